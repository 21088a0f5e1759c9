"""One config value given as text (``floorscan run --set select.k=5``) placed and typed
by the workflow's schemas (:func:`setting`): the config schema
(``workflow/schemas/config.schema.yaml``) and, at a stage's section, the stage's own.

A new option needs nothing here: its schema entry is what types it.
"""

from __future__ import annotations

import os
from typing import Any

from floorscan.core.config import SCHEMA_DIR, ConfigError, error_line, json_value, load_schema


#: The config schema (the whole config; its stage sections have schemas of their own).
CONFIG_SCHEMA = SCHEMA_DIR / "config.schema.yaml"


def _resolve_ref(node: Any, root: dict) -> Any:
    """``node`` with its local ``$ref`` (``#/$defs/...``) followed in ``root``."""
    while isinstance(node, dict) and isinstance(node.get("$ref"), str) and node["$ref"].startswith("#/"):
        target: Any = root
        for part in node["$ref"][2:].split("/"):
            target = target.get(part, {}) if isinstance(target, dict) else {}
        node = target
    return node


def setting(key: str, text: str) -> tuple[list[str], Any]:
    """One config value given as text (``floorscan run --set select.k=5``): where it
    goes in the config and its value, typed by the schemas.

    The dotted ``key`` is walked through the config schema, and into a stage's own
    schema at its section (``select.k``, ``datasets.lab.params.walls.map.support_cell_m``).
    A key of a dataset that is not a top-level key (``scan_topic``, ``pose.source``)
    goes under ``path_options``: the recordings of ``path`` get it. The text is read as
    YAML and taken when the schema allows that value (``5`` an integer, ``true`` a
    boolean, ``[5, all]`` a list), else as the string itself when the schema allows it
    (``scan_topic=/base_scan``, ``k=auto``).

    Parameters
    ----------
    key : str
        Dotted keys, e.g. ``"select.k"``, ``"scan_topic"``, ``"resolution_m"``.
    text : str
        The value as typed.

    Returns
    -------
    keys : list of str
        Where the value goes, from the top of the config.
    value : object

    Raises
    ------
    ConfigError
        An empty or unknown key (naming the known ones at that level), or a value the
        schema rejects (naming the key and what is expected).
    """
    import yaml
    from jsonschema import Draft202012Validator
    from jsonschema.exceptions import best_match

    parts = key.split(".")
    if not key or any(not p for p in parts):
        raise ConfigError(f"{key!r}: expected a key such as select.k or scan_topic")
    root = load_schema(os.path.realpath(CONFIG_SCHEMA))
    dataset = _resolve_ref(root["$defs"]["dataset"], root)
    if parts[0] not in root["properties"] and parts[0] in dataset["properties"]:
        parts = ["path_options", *parts]
    node, walked = root, []
    for part in parts:
        node = _resolve_ref(node, root)
        props = node.get("properties") or {}
        stage_file = SCHEMA_DIR / f"{part}.schema.yaml"
        if part in props:
            node = props[part]
            if walked in ([], ["path_options"]) and part == "path_options":
                node = dataset  # the keys of a dataset
            elif not (node.get("properties") or node.get("$ref")) and stage_file.is_file():
                root = load_schema(os.path.realpath(stage_file))  # a stage section: its schema
                node = root
        elif isinstance(node.get("additionalProperties"), dict):
            node = node["additionalProperties"]
        elif node.get("additionalProperties") is False or props:
            where = ".".join(walked) or "the config"
            raise ConfigError(f"{'.'.join([*walked, part])}: unknown key; expected one of {sorted(props)} ({where})")
        else:  # a free-form mapping: any key, any value
            node = {}
        walked.append(part)
    node = _resolve_ref(node, root)
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        value = text
    validator = Draft202012Validator(root).evolve(schema=node)
    # a mapping is checked by its own keys where it lands (a dataset's `required` aside)
    for candidate in (value, text):
        if not node or validator.is_valid(json_value(candidate)):
            return walked, candidate
    error = best_match(validator.iter_errors(json_value(value)))
    raise ConfigError(error_line(error, key) if error is not None else f"{key}: {text!r} is not a valid value")

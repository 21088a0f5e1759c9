"""Config sections to parameter dataclasses, one rule for every stage."""

from __future__ import annotations

import copy
import dataclasses
import functools
import os
from typing import Any, Mapping, TypeVar

T = TypeVar("T")


def dataclass_from_mapping(cls: type[T], values: Mapping[str, Any] | None, section: str, error=KeyError) -> T:
    """``cls(**values)`` after checking that every key is a field of ``cls``.

    Parameters
    ----------
    cls : dataclass type
    values : mapping or None
        The config section (None: all defaults).
    section : str
        The section's name for the message, e.g. ``"floorplan"`` or ``"register.graph"``.
    error : exception type
        Raised for unknown keys (default ``KeyError``).

    Raises
    ------
    error
        Naming the unknown keys and the known ones.
    """
    values = dict(values or {})
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(values) - names)
    if unknown:
        raise error(f"unknown {section} config keys {unknown}; expected {sorted(names)}")
    return cls(**values)


class ConfigError(ValueError):
    """A config value the schema rejects; the message names the field and the schema."""


@functools.lru_cache(maxsize=None)
def _schema_validator(path: str):
    """The default-filling JSON Schema (draft 2020-12) validator of the YAML schema at
    ``path``, loaded once per process with libyaml when PyYAML has it."""
    import yaml
    from jsonschema import Draft202012Validator, validators

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    with open(path, encoding="utf-8") as f:
        schema = yaml.load(f, Loader=loader)
    if not isinstance(schema, dict):
        raise ConfigError(f"{path}: expected a JSON schema (a mapping), got {type(schema).__name__}")
    Draft202012Validator.check_schema(schema)
    properties = Draft202012Validator.VALIDATORS["properties"]

    def fill_defaults(validator, props, instance, subschema):
        # the jsonschema FAQ's recipe, as snakemake.utils.validate(set_default=True);
        # each default copied, so that no two configs share a mutable default
        if isinstance(instance, dict):
            for name, prop in props.items():
                if isinstance(prop, dict) and "default" in prop:
                    instance.setdefault(name, copy.deepcopy(prop["default"]))
        yield from properties(validator, props, instance, subschema)

    return validators.extend(Draft202012Validator, {"properties": fill_defaults})(schema)


def validate_config(data: dict, schema_path: str | os.PathLike, section: str = "config") -> dict:
    """Validate a config mapping against a JSON schema in YAML and fill its defaults.

    The checks and defaults of ``snakemake.utils.validate(data, schema_path)`` (a
    ``jsonschema`` Draft 2020-12 validator that sets each missing property with a
    ``default``), the schema parsed once per process with libyaml: the workflow
    validates 16 config sections at every start, which took Snakemake's validate
    0.34 s for the 10 schemas (pure-Python YAML, a schema read per call) and this
    0.02 s (issue 8: the start of every run).

    Parameters
    ----------
    data : dict
        The config section; missing properties that have a ``default`` are set in place.
    schema_path : path
        The schema, YAML or JSON.
    section : str
        Where ``data`` sits in the config, for the message (e.g. ``"walls"``).

    Returns
    -------
    dict
        ``data``, with its defaults.

    Raises
    ------
    ConfigError
        The first value the schema rejects, naming its field (``section.key...``), what
        the schema expects and the schema file.
    """
    import jsonschema

    validator = _schema_validator(os.fspath(schema_path))
    try:
        validator.validate(data)
    except jsonschema.ValidationError as e:
        field = ".".join([section, *(str(p) for p in e.absolute_path)])
        raise ConfigError(f"{field}: {e.message} (schema {os.fspath(schema_path)})") from None
    return data


def _same_file(a: str | None, b: str) -> bool:
    """Whether two paths name the same file or folder (resolved against the working
    directory, symbolic links followed)."""
    return a is not None and os.path.realpath(a) == os.path.realpath(b)


def add_path_dataset(config: dict) -> str | None:
    """Make the top-level ``path`` of a config (``--config path=/data/run.bag``) a dataset.

    The dataset is named after the recording (its file or folder name without the
    recording suffixes, other characters than letters, digits and ``_`` replaced by
    ``_``), holds only ``path`` (ingest detects the rest) and becomes the only target.
    A dataset of that name with the same recording (the same path, relative to the
    working directory or absolute) is reused; with another recording the name gets a
    numeric suffix.

    Parameters
    ----------
    config : dict
        The validated workflow config; changed in place (``datasets``, ``target``).

    Returns
    -------
    str or None
        The dataset name, or None when the config has no ``path``.
    """
    import re
    from pathlib import PurePath

    path = config.get("path")
    if not path:
        return None
    name = PurePath(str(path).rstrip("/")).name
    for suffix in (".gz", ".log", ".clf", ".bag", ".db3", ".mcap"):
        if name.lower().endswith(suffix) and len(name) > len(suffix):
            name = name[: -len(suffix)]
    name = re.sub(r"[^A-Za-z0-9_]", "_", name) or "recording"
    if name[0].isdigit():
        name = f"r_{name}"
    datasets = config.setdefault("datasets", {})
    base, n = name, 1
    while name in datasets and not _same_file(datasets[name].get("path"), str(path)):
        n += 1
        name = f"{base}_{n}"
    datasets.setdefault(name, {"description": f"{path} (--config path)", "path": str(path)})
    config["target"] = [name]
    return name

"""The workflow config: validation against the schemas, the checks a schema cannot
make, and config sections to parameter dataclasses (one rule for every stage).

Defaults are written once, in the stage schemas (``workflow/schemas/<stage>.schema.yaml``,
the config a user reads and writes). The Snakefile validates the config before any job
starts (:func:`validate_config`, which fills the defaults, and :func:`check_datasets`)
inside :func:`config_errors_exit`, so that a bad value stops the run with one paragraph
naming the key, not a traceback. The package reads a section through its stage's typed
parameter dataclass: :func:`schema_defaults` gives the dataclass's fields the schema's
defaults, :func:`dataclass_from_mapping` builds it from a section and is the one place
that rejects unknown keys.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import functools
import math
import os
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping, TypeVar

T = TypeVar("T")

#: The stage schemas: ``<SCHEMA_DIR>/<stage>.schema.yaml``.
SCHEMA_DIR = Path(__file__).resolve().parents[2] / "workflow" / "schemas"


def dataclass_from_mapping(cls: type[T], values: Mapping[str, Any] | None, section: str, error=KeyError) -> T:
    """``cls(**values)`` after checking that every key is a field of ``cls``.

    Parameters
    ----------
    cls : dataclass type
    values : mapping, None or cls
        The config section (None: all defaults); an instance of ``cls`` is returned as
        it is.
    section : str
        The section's name for the message, e.g. ``"floorplan"`` or ``"register.graph"``.
    error : exception type
        Raised for unknown keys (default ``KeyError``).

    Raises
    ------
    error
        Naming the unknown keys and the known ones.
    """
    if isinstance(values, cls):
        return values
    values = dict(values or {})
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(values) - names)
    if unknown:
        raise error(f"unknown {section} config keys {unknown}; expected {sorted(names)}")
    return cls(**values)


@functools.lru_cache(maxsize=None)
def _schema(stage: str) -> dict:
    """The parsed schema of ``stage`` (``workflow/schemas/<stage>.schema.yaml``)."""
    return _load_schema(os.path.realpath(SCHEMA_DIR / f"{stage}.schema.yaml"))


@functools.lru_cache(maxsize=None)
def _load_schema(path: str) -> dict:
    """The YAML schema at ``path`` (a resolved path), parsed once per process with libyaml
    when PyYAML has it; shared, not to be changed."""
    import yaml

    loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
    with open(path, encoding="utf-8") as f:
        schema = yaml.load(f, Loader=loader)
    if not isinstance(schema, dict):
        raise ConfigError(f"{path}: expected a JSON schema (a mapping), got {type(schema).__name__}")
    return schema


def _section_properties(section: str) -> dict[str, Any]:
    """The ``properties`` of a section of a stage schema (``"walls"``, ``"walls.ransac"``)."""
    stage, *keys = section.split(".")
    node = _schema(stage)
    for key in keys:
        props = node.get("properties") or {}
        if key not in props:
            raise KeyError(f"{section}: no property {key!r} in {SCHEMA_DIR / (stage + '.schema.yaml')}")
        node = props[key]
    return node.get("properties") or {}


def schema_section_defaults(section: str) -> dict[str, Any]:
    """The defaults the schema gives the properties of a config section.

    Parameters
    ----------
    section : str
        ``"<stage>"`` or ``"<stage>.<key>[.<key>...]"`` for a nested object, e.g.
        ``"walls.ransac"``.

    Returns
    -------
    dict
        Property name to its ``default`` (a deep copy), for the properties that have one.

    Raises
    ------
    KeyError
        ``section`` names no object of the schema.
    """
    props = _section_properties(section)
    return {name: copy.deepcopy(p["default"]) for name, p in props.items() if isinstance(p, dict) and "default" in p}


def schema_defaults(section: str, **derived: Callable[[dict], Any]) -> Callable[[type[T]], type[T]]:
    """Class decorator (under ``@dataclass``): each field without a default in the class
    gets the schema's default of the property of that name in ``section``.

    So a stage's defaults are written once, in its schema, and the parameter dataclass
    the package reads has the same defaults::

        @dataclass(frozen=True)
        @schema_defaults("walls.ransac")
        class RansacParams:
            threshold_m: float
            iterations: int

    A property without a default (``required`` in the schema) stays a field without a
    default. A list or mapping default becomes a ``default_factory`` (each instance its
    own copy).
    ``derived`` gives a field's default as a function of the section's defaults: for a
    field that is not a key of the section (``min_height_m=lambda d:
    d["height_band_m"][0]``), or a key whose default the class holds in another type
    (``icp_distances_m=lambda d: tuple(d["icp_distances_m"])``).

    Raises
    ------
    TypeError
        At import: a field that is not a property of the section has no default in the
        class, or a field has a default both in the class and in the schema or
        ``derived`` (a default written twice).
    """

    def wrap(cls: type[T]) -> type[T]:
        defaults = schema_section_defaults(section)
        properties = _section_properties(section)
        for name in cls.__dict__.get("__annotations__", {}):
            in_class = name in cls.__dict__
            if name in derived:
                if in_class:
                    raise TypeError(f"{cls.__name__}.{name}: default written in the class and derived from {section}")
                setattr(cls, name, derived[name](defaults))
            elif name in defaults:
                if in_class:
                    raise TypeError(f"{cls.__name__}.{name}: default written in the class and in schema {section}")
                value = defaults[name]
                if isinstance(value, (list, dict)):
                    setattr(cls, name, dataclasses.field(default_factory=functools.partial(copy.deepcopy, value)))
                else:
                    setattr(cls, name, value)
            elif not in_class and name not in properties:
                raise TypeError(f"{cls.__name__}.{name}: no default in schema {section}")
        return cls

    return wrap


class ConfigError(ValueError):
    """A config value the schema rejects; the message names the field and the schema."""


#: Where the synthetic buildings live, relative to the working directory (the
#: repository root): ``<BUILDINGS_DIR>/<name>.yaml`` is the building ``name``.
BUILDINGS_DIR = "config/buildings"

#: What a dataset's ``path`` names, for messages.
RECORDING_PATH = (
    "the path of a recording: a ROS1 .bag file, a ROS2 bag folder (or its .db3 / .mcap), "
    "a CARMEN .log or .log.gz, or a folder of .pcd scans with locations.csv"
)


@contextlib.contextmanager
def config_errors_exit() -> Iterator[None]:
    """Stop the program with the message of a :class:`ConfigError` raised inside.

    For the checks of the Snakefile at parse time: Snakemake prints an exception raised
    there with the rule file, line and a traceback; a ``SystemExit`` with a message it
    prints as that message alone, and exits with status 1. Other exceptions (bugs) keep
    their traceback.

    Raises
    ------
    SystemExit
        ``"Config error: <message>"`` for a :class:`ConfigError`.
    """
    try:
        yield
    except ConfigError as e:
        raise SystemExit(f"Config error: {e}") from None


def _non_finite(data: Any, path: tuple = ()) -> tuple[tuple, float] | None:
    """The first float of a nested config (mappings and lists) that is NaN or
    infinite, as (key path, value); None when every number is finite."""
    if isinstance(data, float):
        return None if math.isfinite(data) else (path, data)
    if isinstance(data, Mapping):
        items = data.items()
    elif isinstance(data, (list, tuple)):
        items = enumerate(data)
    else:
        return None
    for key, value in items:
        found = _non_finite(value, (*path, key))
        if found is not None:
            return found
    return None


def _field(section: str, path) -> str:
    """``section.key.key...``; the keys alone for the whole config (section ``config``)."""
    keys = [str(p) for p in path]
    return ".".join(keys if section == "config" and keys else [section, *keys])


def _message(error, section: str) -> str:
    """One line for a jsonschema ``ValidationError``: the field and what is wrong; for
    an unknown key the known ones (``additionalProperties: false``)."""
    field = _field(section, error.absolute_path)
    schema = error.schema if isinstance(error.schema, dict) else {}
    known = schema.get("properties")
    if error.validator == "additionalProperties" and error.validator_value is False and known:
        unknown = sorted(str(k) for k in error.instance if k not in known)
        return f"{field}: unknown keys {unknown}; expected one of {sorted(known)}"
    return f"{field}: {error.message}"


@functools.lru_cache(maxsize=None)
def _schema_validator(path: str):
    """The default-filling JSON Schema (draft 2020-12) validator of the YAML schema at
    ``path`` (:func:`_load_schema`)."""
    from jsonschema import Draft202012Validator, validators

    schema = _load_schema(os.path.realpath(path))
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
    ``default``), each schema parsed once per process with libyaml (the workflow
    validates every stage's section at every start).

    Parameters
    ----------
    data : dict
        The config section; missing properties that have a ``default`` are set in place.
    schema_path : path
        The schema, YAML or JSON.
    section : str
        Where ``data`` sits in the config, for the message (e.g. ``"walls"``);
        ``"config"``, the whole config: the message names the keys alone.

    Returns
    -------
    dict
        ``data``, with its defaults.

    Raises
    ------
    ConfigError
        The first value the schema rejects, naming its field (``section.key...``), what
        the schema expects and the schema file; an unknown key with the known ones. Any
        number that is NaN or infinite (YAML ``.nan``, ``.inf``), wherever it is: a JSON
        schema's ``type: number`` and bounds let them through (NaN compares false with
        every bound).

    Strings where the schema wants a boolean, a number, a list or a mapping (Snakemake's
    ``--config evaluate=true`` and ``poses={'max_gap_s': 0.7}`` arrive as strings) are
    read as YAML first and taken when the result has a type the schema allows
    (:func:`_typed_strings`); a string the schema allows stays a string.
    """
    import jsonschema

    validator = _schema_validator(os.fspath(schema_path))
    schema = _load_schema(os.path.realpath(os.fspath(schema_path)))
    _typed_strings(data, schema, schema)
    try:
        validator.validate(data)
    except jsonschema.ValidationError as e:
        raise ConfigError(f"{_message(e, section)} (schema {os.fspath(schema_path)})") from None
    found = _non_finite(data)
    if found is not None:
        raise ConfigError(f"{_field(section, found[0])}: {found[1]!r}: expected a finite number, not NaN or infinity")
    return data


#: JSON schema types and the Python types of a YAML value that is one.
_SCHEMA_TYPES = {"boolean": (bool,), "integer": (int,), "number": (int, float), "array": (list,), "object": (dict,)}


def _typed_strings(data: Any, schema: dict, root: dict) -> Any:
    """``data`` with its strings read as YAML where ``schema`` (resolved against ``root``'s
    local ``$ref``) wants another type and the YAML value has it; mappings and lists
    changed in place, the (possibly new) value returned."""
    import yaml

    while isinstance(schema, dict) and isinstance(schema.get("$ref"), str) and schema["$ref"].startswith("#/"):
        node: Any = root
        for part in schema["$ref"][2:].split("/"):
            node = node.get(part, {}) if isinstance(node, dict) else {}
        schema = node
    if not isinstance(schema, dict):
        return data
    if isinstance(data, str):
        types = schema.get("type")
        types = [types] if isinstance(types, str) else list(types or [])
        wanted = tuple(t for name in types if name != "string" for t in _SCHEMA_TYPES.get(name, ()))
        if not wanted or "string" in types:
            return data
        try:
            value = yaml.safe_load(data)
        except yaml.YAMLError:
            return data
        if isinstance(value, bool) and bool not in wanted:
            return data
        return _typed_strings(value, schema, root) if isinstance(value, wanted) else data
    if isinstance(data, dict):
        props = schema.get("properties") or {}
        extra = schema.get("additionalProperties")
        for key in list(data):
            sub = props.get(key, extra if isinstance(extra, dict) else None)
            if sub is not None:
                data[key] = _typed_strings(data[key], sub, root)
    elif isinstance(data, list) and isinstance(schema.get("items"), dict):
        for i, item in enumerate(data):
            data[i] = _typed_strings(item, schema["items"], root)
    return data


def known_buildings(buildings_dir: str | os.PathLike = BUILDINGS_DIR) -> list[str]:
    """Names of the synthetic buildings: the ``<name>.yaml`` files of ``buildings_dir``
    (:func:`floorscan.sim.building_file.load_building` reads one), sorted."""
    folder = Path(buildings_dir)
    return sorted(p.stem for p in folder.glob("*.yaml")) if folder.is_dir() else []


def check_datasets(config: Mapping, buildings_dir: str | os.PathLike = BUILDINGS_DIR) -> None:
    """What the schema cannot check of a validated config's recordings.

    Parameters
    ----------
    config : mapping
        The workflow config after :func:`validate_config`.
    buildings_dir : path
        The folder of the synthetic buildings (``<name>.yaml``).

    Raises
    ------
    ConfigError
        A ``path`` (top-level or of a dataset) that is empty, saying what a path names;
        a synthetic dataset's ``building`` without a file in ``buildings_dir``, listing
        the known buildings.
    """
    if "path" in config and not str(config["path"] or "").strip():
        raise ConfigError(f"path (--config path=...) is empty; expected {RECORDING_PATH}")
    for name, ds in (config.get("datasets") or {}).items():
        if ds.get("format") == "synthetic":
            building = str(ds.get("building"))
            if not (Path(buildings_dir) / f"{building}.yaml").is_file():
                raise ConfigError(
                    f"datasets.{name}.building: no building {building!r}; expected one of "
                    f"{known_buildings(buildings_dir)} (the files {os.fspath(buildings_dir)}/<name>.yaml)"
                )
        elif "path" in ds and not str(ds["path"] or "").strip():
            raise ConfigError(f"datasets.{name}.path is empty; expected {RECORDING_PATH}")


def _same_file(a: str | None, b: str) -> bool:
    """Whether two paths name the same file or folder (resolved against the working
    directory, symbolic links followed)."""
    return a is not None and os.path.realpath(a) == os.path.realpath(b)


def dataset_name(path: str | os.PathLike) -> str:
    """The dataset name of a recording: its file or folder name without the recording
    suffixes (``.gz``, ``.log``, ``.clf``, ``.bag``, ``.db3``, ``.mcap``), other
    characters than letters, digits and ``_`` replaced by ``_``, ``r_`` before a
    leading digit."""
    import re
    from pathlib import PurePath

    name = PurePath(os.fspath(path).rstrip("/")).name
    for suffix in (".gz", ".log", ".clf", ".bag", ".db3", ".mcap"):
        if name.lower().endswith(suffix) and len(name) > len(suffix):
            name = name[: -len(suffix)]
    name = re.sub(r"[^A-Za-z0-9_]", "_", name) or "recording"
    return f"r_{name}" if name[0].isdigit() else name


def add_path_datasets(config: dict, recordings: list) -> list[str]:
    """Make the recordings of the top-level ``path`` (``--config path=/data/run.bag``, or
    a folder of recordings) datasets, the run's targets.

    Each dataset is named by :func:`dataset_name`, holds only ``path`` (ingest detects
    the rest). A dataset of that name with the same recording (the same path, relative
    to the working directory or absolute) is reused; with another recording the name
    gets a numeric suffix. The ``building`` section's floors name their recording by
    dataset name or file name; they are resolved to dataset names
    (``building.floors[i].dataset``).

    Parameters
    ----------
    config : dict
        The validated workflow config; changed in place (``datasets``, ``target``,
        ``building``).
    recordings : list of path
        The recordings ``path`` names (:func:`floorscan.ingest.detect.recordings_in`).

    Returns
    -------
    list of str
        The dataset names, in the order of ``recordings``.

    Raises
    ------
    ConfigError
        A floor of ``building`` names no recording of the run or a dataset not
        configured, or two floors name the same recording.
    """
    datasets = config.setdefault("datasets", {})
    names, by_file = [], {}
    for path in recordings:
        base = name = dataset_name(path)
        n = 1
        while (name in datasets and not _same_file(datasets[name].get("path"), os.fspath(path))) or name in names:
            n += 1
            name = f"{base}_{n}"
        datasets.setdefault(name, {"description": f"{os.fspath(path)} (--config path)", "path": os.fspath(path)})
        names.append(name)
        by_file[Path(path).name] = name
    if names:
        config["target"] = names
    resolve_building(config, by_file)
    return names


def resolve_building(config: dict, by_file: Mapping[str, str] | None = None) -> None:
    """Resolve the ``building`` section's floors to datasets, in place: each floor's
    ``recording`` (a dataset name, or the file name of a recording of ``path``) becomes
    ``dataset``; ``storey`` defaults to ``Floor <i>`` and ``elevation_m`` to 0.

    Raises
    ------
    ConfigError
        A floor names no known dataset or recording, or two floors name one.
    """
    building = config.get("building")
    if not building:
        return
    by_file = dict(by_file or {})
    known = set(config.get("datasets") or {})
    seen = {}
    for i, floor in enumerate(building.get("floors") or []):
        ref = str(floor.get("recording", floor.get("dataset", "")))
        name = ref if ref in known else by_file.get(ref)
        if name is None:
            raise ConfigError(
                f"building.floors[{i}].recording: {ref!r} is neither a dataset nor a recording of path; "
                f"expected one of {sorted(known | set(by_file))}"
            )
        if name in seen:
            raise ConfigError(f"building.floors[{i}].recording: {ref!r} is already floor {seen[name]}")
        if name == "building":
            raise ConfigError(f"building.floors[{i}].recording: a dataset named 'building' would write in "
                              "results/building/, the building's folder; rename the recording")
        seen[name] = i
        floor["dataset"] = name
        floor.setdefault("storey", f"Floor {i}")
        floor["elevation_m"] = float(floor.get("elevation_m", 0.0))

"""The workflow config: validation against the schemas, the checks a schema cannot
make, and config sections to parameter dataclasses (one rule for every stage).

Defaults are written once, in the stage schemas (``workflow/schemas/<stage>.schema.yaml``,
the config a user reads and writes). The Snakefile validates the config before any job
starts (:func:`validate_config`, Snakemake's ``validate`` filling the defaults, and
:func:`floorscan.core.datasets.check_datasets`) inside :func:`config_errors_exit`, so that a bad value stops the
run with one paragraph naming the key, not a traceback. The package reads a section
through its stage's typed parameter dataclass, one way for every stage and subsection:
:func:`schema_defaults` gives the dataclass's fields the schema's defaults and names its
section, :func:`stage_params` builds it from a section, checking each key and value
against that section of the schema (:class:`ConfigError` naming the key)::

    support = stage_params(MapParams, config["walls"]["map"])   # "walls.map"

A threshold a user has no reason to set is no option: it is a named constant of the
module that uses it (or of its stage's params module), the default of a field of the
parameter class, with its reason and source beside it. The schema then has no such
key, so a config that sets it stops with the schema's ``unknown key`` message naming it.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import functools
import math
import os
import typing
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping, TypeVar

T = TypeVar("T")

#: The stage schemas: ``<SCHEMA_DIR>/<stage>.schema.yaml``.
SCHEMA_DIR = Path(__file__).resolve().parents[2] / "workflow" / "schemas"


@functools.lru_cache(maxsize=None)
def _schema(stage: str) -> dict:
    """The parsed schema of ``stage`` (``workflow/schemas/<stage>.schema.yaml``)."""
    return load_schema(os.path.realpath(SCHEMA_DIR / f"{stage}.schema.yaml"))


@functools.lru_cache(maxsize=None)
def load_schema(path: str) -> dict:
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
    """The ``properties`` of a section of a stage schema (``"walls"``, ``"walls.map"``)."""
    stage, *keys = section.split(".")
    node = _schema(stage)
    for key in keys:
        props = node.get("properties") or {}
        if key not in props:
            raise KeyError(f"{section}: no property {key!r} in {SCHEMA_DIR / (stage + '.schema.yaml')}")
        node = props[key]
    return node.get("properties") or {}


def schema_enum(section: str, key: str) -> tuple:
    """The values the schema allows a config key (its ``enum``, or its items' for a
    list): the one place an enum is written.

    Parameters
    ----------
    section : str
        A stage schema's section, ``"hulls"``, ``"floorplan.rooms"``.
    key : str
        The property.

    Returns
    -------
    tuple

    Raises
    ------
    KeyError
        When the section has no such property, or it no enum.
    """
    node = _section_properties(section).get(key)
    if node is None:
        raise KeyError(f"{section}: no property {key!r}")
    values = node.get("enum", (node.get("items") or {}).get("enum"))
    if values is None:
        raise KeyError(f"{section}.{key}: no enum in the schema")
    return tuple(values)


def schema_section_defaults(section: str) -> dict[str, Any]:
    """The defaults the schema gives the properties of a config section.

    Parameters
    ----------
    section : str
        ``"<stage>"`` or ``"<stage>.<key>[.<key>...]"`` for a nested object, e.g.
        ``"walls.map"``.

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


#: The parameter dataclasses (:func:`schema_defaults`): class -> (its schema section,
#: its ``derived`` fields).
PARAMS_SECTIONS: dict[type, tuple[str, dict[str, Callable[[dict], Any]]]] = {}


def schema_defaults(section: str, **derived: Callable[[dict], Any]) -> Callable[[type[T]], type[T]]:
    """Class decorator (under ``@dataclass``): each field without a default in the class
    gets the schema's default of the property of that name in ``section``.

    So a stage's defaults are written once, in its schema, and the parameter dataclass
    the package reads has the same defaults::

        @dataclass(frozen=True)
        @schema_defaults("walls.map")
        class MapParams:
            support_cell_m: float
            grid_m: float = MAP_GRID_M   # no option: a constant of the code

    A property without a default (``required`` in the schema) stays a field without a
    default. A list or mapping default becomes a ``default_factory`` (each instance its
    own copy).
    ``derived`` gives a field's default as a function of the section's defaults: for a
    field that is not a key of the section (``min_height_m=lambda d:
    d["height_band_m"][0]``), or a key whose default the class holds in another type
    (``icp_distances_m=lambda d: tuple(d["icp_distances_m"])``); :func:`stage_params`
    applies the same function to a config's section. The class is the one
    :func:`stage_params` builds from ``section``.

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
        PARAMS_SECTIONS[cls] = (section, dict(derived))
        return cls

    return wrap


class ConfigError(ValueError):
    """A config value the schema rejects; the message names the field and the schema."""


def stage_params(cls: type[T], values: "T | Mapping[str, Any] | None", name: str | None = None) -> T:
    """A stage's typed parameters from its config section: the one way the package and
    the scripts read config.

    Parameters
    ----------
    cls : dataclass type
        A parameter class of :func:`schema_defaults` (its section, e.g. ``"walls.map"``),
        or a dataclass whose defaults are constants of the code and no option
        (e.g. :class:`floorscan.walls.params.RansacParams`): built from the keys of
        ``values`` that are its fields, without a schema to check them against.
    values : mapping, None or cls
        The config section (None: the defaults); an instance of ``cls`` is returned as
        it is.
    name : str, optional
        Where the section sits in the config, for messages; default ``cls``'s section.

    Returns
    -------
    cls
        Built from the keys of ``values`` that are its fields (the section's other keys
        belong to other classes or to the workflow), each checked against its property
        of the schema (type, bounds, enum: jsonschema) and for NaN and infinity; a field
        whose type is a parameter class (a subsection such as ``floorplan.structure``)
        built by this function; a ``derived`` field (:func:`schema_defaults`) computed
        from the section.

    Raises
    ------
    ConfigError
        ``<name>.<key>: unknown key; expected one of [...]`` for a key that is neither a
        property of the section nor a field of ``cls``; ``<name>.<key>: <what the
        schema says>`` for a wrong type or value; a field without a default missing.
    """
    if isinstance(values, cls):
        return values
    section, derived = PARAMS_SECTIONS.get(cls, (None, {}))
    name = name or section or cls.__name__
    values = dict(values or {})
    props = _section_properties(section) if section else {}
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init}
    known = sorted(set(props) | {f for f in fields if f not in derived})
    for key in values:
        if key not in props and key not in fields:
            raise ConfigError(f"{name}.{key}: unknown key; expected one of {known}")
    hints = _field_types(cls)
    kwargs = {}
    for key, value in values.items():
        sub = props.get(key)
        nested = _params_class(hints.get(key))
        if nested is not None and isinstance(value, Mapping):
            value = stage_params(nested, value, f"{name}.{key}")
        elif isinstance(sub, dict) and "properties" in sub:  # a subsection: checked by its own class
            nullable = value is None and "null" in (sub["type"] if isinstance(sub.get("type"), list) else [sub.get("type")])
            if not nullable and not isinstance(value, Mapping) and not dataclasses.is_dataclass(value):
                raise ConfigError(f"{name}.{key}: {value!r} is not of type 'object'")
        elif isinstance(sub, dict):
            _check_value(value, sub, section, f"{name}.{key}")
        if key in fields:
            kwargs[key] = value
    if derived:
        merged = {**schema_section_defaults(section), **values}
        kwargs.update({key: fn(merged) for key, fn in derived.items() if key in props or key not in values})
    for f in fields.values():
        if f.name not in kwargs and f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise ConfigError(f"{name}.{f.name}: missing; it has no default")
    return cls(**kwargs)


@functools.lru_cache(maxsize=None)
def _field_types(cls: type) -> dict[str, Any]:
    """The resolved annotations of a parameter class's fields ({} if they do not resolve)."""
    try:
        return typing.get_type_hints(cls)
    except (NameError, TypeError):
        return {}


def _params_class(hint: Any) -> type | None:
    """The parameter class (:data:`PARAMS_SECTIONS`) a field's type names, ``X | None``
    included; None for any other type."""
    for t in (hint, *typing.get_args(hint)):
        if isinstance(t, type) and t in PARAMS_SECTIONS:
            return t
    return None


@functools.lru_cache(maxsize=None)
def _stage_validator(stage: str):
    """A jsonschema (draft 2020-12) validator of the schema of ``stage``, without defaults."""
    from jsonschema import Draft202012Validator

    return Draft202012Validator(_schema(stage))


def _check_value(value: Any, schema: dict, section: str, field: str) -> None:
    """Raise :class:`ConfigError` naming ``field`` when ``value`` breaks ``schema`` (a
    property of the schema of ``section``) or holds a NaN or infinity."""
    from jsonschema.exceptions import best_match

    plain = json_value(value)
    error = best_match(_stage_validator(section.split(".")[0]).evolve(schema=schema).iter_errors(plain))
    if error is not None:
        raise ConfigError(error_line(error, field))
    found = _non_finite(plain)
    if found is not None:
        raise ConfigError(f"{_field(field, found[0])}: {found[1]!r}: expected a finite number, not NaN or infinity")


def json_value(value: Any) -> Any:
    """``value`` with its tuples as lists (JSON arrays, for jsonschema)."""
    if isinstance(value, (list, tuple)):
        return [json_value(v) for v in value]
    if isinstance(value, Mapping):
        return {k: json_value(v) for k, v in value.items()}
    return value


#: Where the synthetic buildings live, relative to the working directory (the
#: repository root): ``<BUILDINGS_DIR>/<name>.yaml`` is the building ``name``.
BUILDINGS_DIR = "config/buildings"

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


def error_line(error, section: str) -> str:
    """One line for a jsonschema ``ValidationError``: the field and what is wrong; for
    an unknown key the known ones (``additionalProperties: false``)."""
    field = _field(section, error.absolute_path)
    schema = error.schema if isinstance(error.schema, dict) else {}
    known = schema.get("properties")
    if error.validator == "additionalProperties" and error.validator_value is False and known:
        unknown = sorted(str(k) for k in error.instance if k not in known)
        return f"{field}: unknown keys {unknown}; expected one of {sorted(known)}"
    alternatives = error.validator_value if error.validator in ("oneOf", "anyOf") else None
    if isinstance(alternatives, list) and alternatives and all(isinstance(a, dict) for a in alternatives):
        said = [alternative_text(a) for a in alternatives]
        expected = said[0] if len(said) == 1 else f"{', '.join(said[:-1])} or {said[-1]}"
        return f"{field}: got {error.instance!r}; expected {expected}"
    return f"{field}: {error.message}"


def alternative_text(schema: dict) -> str:
    """What one schema of a ``oneOf`` / ``anyOf`` accepts, for people: ``'auto'``, ``an
    integer >= 1``, ``a number > 0 and < 1``, ``one of ['a', 'b']``.

    Parameters
    ----------
    schema : dict
        A JSON schema.

    Returns
    -------
    str
    """
    if "const" in schema:
        return repr(schema["const"])
    if "enum" in schema:
        return f"one of {schema['enum']}"
    kind = schema.get("type", "value")
    kind = " or ".join(kind) if isinstance(kind, list) else kind
    article = "an" if str(kind)[:1] in "aeiou" else "a"
    bounds = [f"{op} {schema[key]}" for key, op in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="),
                                                     ("exclusiveMaximum", "<")) if key in schema]  # fmt: skip
    return f"{article} {kind}" + (f" {' and '.join(bounds)}" if bounds else "")


def validate_config(data: dict, schema_path: str | os.PathLike, section: str = "config") -> dict:
    """Validate a config mapping against a JSON schema in YAML and fill its defaults:
    ``snakemake.utils.validate(data, schema_path, set_default=True)``, with what it does
    not do (strings of ``--config`` read as YAML, a message naming the key, NaN and
    infinity refused).

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
    from jsonschema import ValidationError
    from snakemake.exceptions import WorkflowError
    from snakemake.utils import validate

    schema = load_schema(os.path.realpath(os.fspath(schema_path)))
    _typed_strings(data, schema, schema)
    try:
        validate(data, os.fspath(schema_path), set_default=True)
    except WorkflowError as e:  # raised while handling the jsonschema error, its context
        if not isinstance(e.__context__, ValidationError):
            raise
        raise ConfigError(f"{error_line(e.__context__, section)} (schema {os.fspath(schema_path)})") from None
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


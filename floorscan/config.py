"""Config sections to parameter dataclasses, one rule for every stage."""

from __future__ import annotations

import dataclasses
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

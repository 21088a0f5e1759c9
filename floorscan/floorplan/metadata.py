"""What a floor plan is of, written into every one of its exports: :class:`PlanMetadata`
(dataset, ordering, extractor, k, title, time stamp) and the time stamp itself.

The time stamp is never the clock, so the same input gives the same files: the plan's
``timestamp`` (the recording's first scan, :func:`recording_timestamp`), else the
environment's ``SOURCE_DATE_EPOCH``, else 0 (:func:`export_time`; source:
reproducible-builds.org's SOURCE_DATE_EPOCH specification). :func:`floorscan_version`
names the generator.
"""

from __future__ import annotations

import functools
import math
import os
from dataclasses import dataclass
from datetime import datetime, timezone
from typing import TYPE_CHECKING, Mapping

import numpy as np

if TYPE_CHECKING:
    from floorscan.floorplan.georeference import Georeference
    from floorscan.floorplan.plan import FloorPlan


def export_time(timestamp: float | None = None) -> int:
    """Seconds since the epoch (UTC) the exports of a plan are stamped with.

    ``timestamp`` (rounded down: e.g. the recording's first scan stamp) when given,
    else the environment variable ``SOURCE_DATE_EPOCH`` (reproducible-builds.org),
    else 0. Never the clock: the same input gives the same files.

    Parameters
    ----------
    timestamp : float, optional
        Seconds since the epoch.

    Returns
    -------
    int
        Seconds since the epoch.

    Raises
    ------
    ValueError
        For a ``timestamp`` that is not finite, or a ``SOURCE_DATE_EPOCH`` that is
        not an integer.
    """
    if timestamp is not None:
        t = float(timestamp)
        if not math.isfinite(t):
            raise ValueError(f"export timestamp must be finite seconds since the epoch, got {timestamp!r}")
        return math.floor(t)
    env = os.environ.get("SOURCE_DATE_EPOCH", "").strip()
    if not env:
        return 0
    try:
        return int(env)
    except ValueError:
        raise ValueError(f"SOURCE_DATE_EPOCH must be an integer number of seconds, got {env!r}") from None


@functools.lru_cache(maxsize=None)
def floorscan_version() -> str:
    """The installed floorscan's version (``"unknown"`` when not installed), cached.

    Returns
    -------
    str
    """
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("floorscan")
    except PackageNotFoundError:  # pragma: no cover
        return "unknown"


@dataclass(frozen=True)
class PlanMetadata:
    """What a floor plan is of: written into every one of its exports.

    Attributes
    ----------
    dataset, ordering, extractor : str
        The recording, the scan ordering and the wall extractor of the plan.
    k : str
        The number of scans, as in the file names (``"5"``, ``"all"``); an int is
        converted.
    timestamp : float or None
        Seconds since the epoch (UTC) to stamp the exports with, e.g. the
        recording's first scan stamp; None: :func:`export_time`'s fallbacks.
    name : str
        The plan's title (SVG title, IFC project name, from which the IFC GlobalIds
        derive); empty: "``dataset ordering extractor k<k>``" of the fields given.
    """

    dataset: str = ""
    ordering: str = ""
    extractor: str = ""
    k: str = ""
    timestamp: float | None = None
    name: str = ""

    def __post_init__(self):
        for f in ("dataset", "ordering", "extractor", "k", "name"):
            value = getattr(self, f)
            object.__setattr__(self, f, "" if value is None else str(value))

    @property
    def fields(self) -> tuple[tuple[str, str], ...]:
        """``(name, value)`` of dataset, ordering, extractor and k, as every export names them."""
        return ("dataset", self.dataset), ("ordering", self.ordering), ("extractor", self.extractor), ("k", self.k)

    @property
    def title(self) -> str:
        """:attr:`name`, else the fields given joined (``"intel random ransac k5"``),
        else ``"floorscan"``."""
        if self.name:
            return self.name
        parts = [self.dataset, self.ordering, self.extractor, f"k{self.k}" if self.k else ""]
        return " ".join(p for p in parts if p) or "floorscan"

    @property
    def time_stamp(self) -> str:
        """:func:`export_time` of :attr:`timestamp` in ISO 8601, UTC (``1970-01-01T00:00:00+00:00``)."""
        return datetime.fromtimestamp(export_time(self.timestamp), tz=timezone.utc).isoformat()


def table_metadata(meta: PlanMetadata, n_scans: int) -> dict[str, str]:
    """What a plan folder (:func:`floorscan.core.plan_tables.write_plan_tables`) stores of
    what its plan is of: ``dataset``, ``ordering``, ``extractor``, ``k``, ``n_scans`` and,
    when ``meta`` has one, ``timestamp`` (seconds since the epoch); :func:`from_table_metadata`
    reads it back.

    Parameters
    ----------
    meta : PlanMetadata
    n_scans : int
        The scans the plan is of (0 for a map).

    Returns
    -------
    dict of str to str
    """
    out = {"dataset": meta.dataset, "ordering": meta.ordering, "extractor": meta.extractor, "k": meta.k,
           "n_scans": str(int(n_scans))}
    if meta.timestamp is not None:
        out["timestamp"] = repr(float(meta.timestamp))
    return out


def from_table_metadata(stored: Mapping[str, str], source: str = "plan folder") -> PlanMetadata:
    """The :class:`PlanMetadata` of :func:`table_metadata` (a missing field empty, a missing
    time stamp None).

    Parameters
    ----------
    stored : mapping of str to str
    source : str
        What ``stored`` was read from, for the error.

    Returns
    -------
    PlanMetadata

    Raises
    ------
    ValueError
        When the time stamp is not a number.
    """
    stamp = stored.get("timestamp")
    try:
        timestamp = None if stamp is None else float(stamp)
    except ValueError:
        raise ValueError(f"{source}: the plan's timestamp {stamp!r} is not seconds since the epoch") from None
    return PlanMetadata(stored.get("dataset", ""), stored.get("ordering", ""), stored.get("extractor", ""),
                        stored.get("k", ""), timestamp)


def metadata_member(plan: FloorPlan, meta: PlanMetadata, georeference: Georeference | None = None) -> dict:
    """The plan's metadata as the GeoJSON member ``floorscan`` holds it (the DXF's
    metadata are its entries as text, :func:`floorscan.floorplan.dxf._dxf_metadata`).

    Parameters
    ----------
    plan : FloorPlan
    meta : PlanMetadata
    georeference : Georeference, optional
        With one the frame is WGS84 and the units degrees.

    Returns
    -------
    dict
        ``frame``, ``units``, ``crs``, the fields of ``meta``, ``n_walls``,
        ``n_walls_both_faces``, ``n_faces``, ``lengths``, ``time_stamp``, ``generator``,
        ``georeference``; after the structure passes also ``n_clutter`` and
        ``n_junctions``; with rooms or doors also ``n_rooms``, ``n_doors`` and
        ``floor_area_m2`` (:func:`floor_area_m2`).
    """
    return {
        "frame": "map" if georeference is None else "WGS84",
        "units": "metres" if georeference is None else "degrees",
        "crs": "local engineering frame of the recording" if georeference is None else (
            "WGS84 longitude, latitude: the map frame on the local tangent plane of the georeference"),
        **dict(meta.fields),
        "n_walls": len(plan.walls), "n_walls_both_faces": int(plan.walls["paired"].sum()), "n_faces": len(plan.faces),
        "lengths": "metres (thickness_m, height_m, length_m)",
        "time_stamp": meta.time_stamp,
        "generator": f"floorscan {floorscan_version()}",
        "georeference": None if georeference is None else georeference.as_dict(),
        # a plan through the structure passes names its clutter and junctions
        **({"n_clutter": len(plan.clutter), "n_junctions": len(plan.junctions)}
           if len(plan.clutter) or len(plan.junctions) else {}),
        # a plan with rooms names them, its doors and its floor area (the rooms' areas, m2)
        **({"n_rooms": len(plan.rooms), "n_doors": len(plan.doors), "floor_area_m2": floor_area_m2(plan)}
           if len(plan.rooms) or len(plan.doors) else {}),
    }  # fmt: skip


def floor_area_m2(plan: FloorPlan) -> float:
    """The plan's floor area: the sum of its rooms' ``area_m2`` (corridors and open
    spaces included).

    Parameters
    ----------
    plan : FloorPlan

    Returns
    -------
    float
        Square metres, rounded to 4 decimals; 0 without rooms.
    """
    return round(float(plan.rooms["area_m2"].to_numpy(dtype=np.float64).sum()), 4) if len(plan.rooms) else 0.0


def recording_timestamp(index_path: str | os.PathLike) -> int:
    """The exports' time stamp: the recording's first scan stamp; the same recording
    gives the same files.

    Parameters
    ----------
    index_path : path
        ``scan_index.parquet`` (its ``t_ns``, nanoseconds).

    Returns
    -------
    int
        The least ``t_ns`` in whole seconds since the epoch; 0 for an empty index.
    """
    import pyarrow.parquet as pq

    t_ns = pq.read_table(index_path, columns=["t_ns"]).column("t_ns").to_numpy()
    return int(t_ns.min()) // 1_000_000_000 if len(t_ns) else 0

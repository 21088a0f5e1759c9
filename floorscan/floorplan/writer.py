"""Build and write floor plans (stage ``floorplan``): :class:`FloorplanWriter` builds the
plan of a table of wall segments (the one plan builder, :mod:`floorscan.floorplan.scans`)
and writes it in the formats asked for, each by its writer in
:data:`floorscan.floorplan.EXPORT_FORMATS`, with the plan's metadata
(:class:`~floorscan.floorplan.metadata.PlanMetadata`); a plan of the same segments as
one it built before is reused. :func:`write_floorplan` does one plan;
:func:`write_recommended_floorplan` the plan of the selected scans
(``results/<dataset>/floorplan.*``), which :func:`recommended_plan` builds without
writing it (a building's floors, :mod:`floorscan.floorplan.building`). The stage's
scripts call these.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np
import pandas as pd

from floorscan.floorplan import EXPORT_FORMATS, FLOORPLAN_FORMATS
from floorscan.floorplan.footprints import PlanExports
from floorscan.floorplan.metadata import PlanMetadata, export_time, recording_timestamp, table_metadata
from floorscan.core.config import stage_params
from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.plan import FloorPlan, in_scan_order
from floorscan.floorplan.scans import plan_of_scans

if TYPE_CHECKING:
    from floorscan.core.occupancy import OccupancyGrid


class FloorplanWriter:
    """Builds and writes floor plans (stage ``floorplan``); a plan of the same segments
    as one it built before is not built again.

    Many plans of the same segments are the same plan (the plan builder,
    :mod:`floorscan.floorplan.scans`, takes segments in scan order; the evaluation grid,
    :mod:`floorscan.floorplan.grid`, reuses its plans by their scans). The writer keeps
    each plan it built with its footprints and IFC model; for the same segments it
    reuses them and writes the exports with the new plan's metadata (each export
    names its ordering and k): the GeoJSON, SVG and DXF anew (cheap), the IFC model
    renamed (:func:`floorscan.floorplan.ifc._name_ifc`: project name, description,
    GlobalIds) and saved with its header. Every file equals a fresh export of that
    plan and metadata. Each format is written by its writer in
    :data:`floorscan.floorplan.EXPORT_FORMATS`.

    Parameters
    ----------
    cfg : mapping
        The ``floorplan`` config section.

    Raises
    ------
    floorscan.core.config.ConfigError
        For an unknown config key or a wrong value (on construction).
    KeyError
        For an unknown output format (:meth:`write`).
    """

    def __init__(self, cfg: Mapping[str, Any] | None):
        self.params = stage_params(FloorplanParams, cfg)
        self._built: dict[bytes, PlanExports] = {}

    def write(
        self, segments: pd.DataFrame, outputs: Mapping[str, str | os.PathLike], name: str = "", *,
        dataset: str = "", ordering: str = "", extractor: str = "", k: str | int = "",
        timestamp: float | None = None, grid: OccupancyGrid | None = None,
    ) -> tuple[FloorPlan, bool]:  # fmt: skip
        """Build the floor plan of ``segments`` and write it to ``outputs``.

        Parameters
        ----------
        segments : pandas.DataFrame
            Wall segments (``walls/{ordering}/{extractor}/k{k}.parquet``).
        outputs : mapping
            Paths by format: any of :data:`FLOORPLAN_FORMATS`.
        name : str
            Title of the plan (SVG title, IFC project name); empty: made of the
            metadata (:attr:`~floorscan.floorplan.metadata.PlanMetadata.title`).
        dataset, ordering, extractor : str
            What the plan is of, written into every export.
        k : str or int
            Number of scans label (``"5"``, ``"all"``).
        timestamp : float, optional
            Seconds since the epoch to stamp the exports with (e.g. the
            recording's first scan stamp); None: ``SOURCE_DATE_EPOCH``, else 0
            (:func:`~floorscan.floorplan.metadata.export_time`).
        grid : OccupancyGrid, optional
            The free space of the segments' scans: the plan goes through the
            structure passes (:func:`~floorscan.floorplan.plan.build_floorplan`).

        Returns
        -------
        plan : FloorPlan
        reused : bool
            Whether the plan equals one built before (same segments), and so was
            reused rather than built.

        Raises
        ------
        KeyError
            For an unknown output format, or a missing coordinate column.
        """
        _check_formats(outputs)
        meta = PlanMetadata(dataset, ordering, extractor, k, timestamp, name)
        export_time(timestamp)  # a bad SOURCE_DATE_EPOCH fails before anything is built
        segments = in_scan_order(segments)  # as build_floorplan takes them (sorted once)
        key = _segments_key(segments) + (b"" if grid is None else _grid_key(grid))
        built = self._built.get(key)
        reused = built is not None
        if built is None:
            built = self._built[key] = PlanExports(plan_of_scans(segments, None, self.params, grid))
        self.export(built, outputs, meta)
        return built.plan, reused

    def export(self, exports: PlanExports, outputs: Mapping[str, str | os.PathLike], meta: PlanMetadata) -> None:
        """Write a built plan (``exports.plan``) to ``outputs`` (paths by format, any of
        :data:`FLOORPLAN_FORMATS`), named by ``meta``, each format by its writer in
        :data:`floorscan.floorplan.EXPORT_FORMATS` with this writer's params.

        Parameters
        ----------
        exports : PlanExports
        outputs : mapping of str to path
            Format -> output path.
        meta : PlanMetadata

        Raises
        ------
        KeyError
            For an unknown output format.
        """
        _check_formats(outputs)
        for fmt, path in outputs.items():
            EXPORT_FORMATS[fmt].write(exports, path, meta, self.params)


def _check_formats(outputs: Mapping[str, Any]) -> None:
    """Raise ``KeyError`` for a format of ``outputs`` not in :data:`FLOORPLAN_FORMATS`."""
    unknown = sorted(set(outputs) - set(FLOORPLAN_FORMATS))
    if unknown:
        raise KeyError(f"unknown floor plan formats {unknown}; expected {list(FLOORPLAN_FORMATS)}")


def _segments_key(segments: pd.DataFrame) -> bytes:
    """Digest of the segments (in scan order: what :func:`build_floorplan` reads)."""
    h = hashlib.sha256()
    for c in segments.columns:
        h.update(c.encode() + b"\0" + np.ascontiguousarray(segments[c].to_numpy()).tobytes())
    return h.digest()


def _grid_key(grid: OccupancyGrid) -> bytes:
    """Digest of an occupancy grid (origin, resolution, counts)."""
    h = hashlib.sha256(np.r_[grid.origin_xy, grid.resolution_m].tobytes())
    h.update(grid.n_hit_scans.tobytes())
    h.update(grid.n_miss_scans.tobytes())
    return h.digest()


def write_floorplan(
    segments: pd.DataFrame, cfg: Mapping[str, Any] | None, outputs: Mapping[str, str | os.PathLike], name: str = "",
    *, dataset: str = "", ordering: str = "", extractor: str = "", k: str | int = "", timestamp: float | None = None,
) -> FloorPlan:  # fmt: skip
    """Build the floor plan of ``segments`` and write it: ``FloorplanWriter(cfg).write(
    segments, outputs, name, dataset=..., ordering=..., extractor=..., k=...,
    timestamp=...)``.

    Parameters
    ----------
    segments : pandas.DataFrame
        Wall segments ``x0, y0, x1, y1`` (metres), optional ``n_inliers``, ``scan_id``.
    cfg : mapping or None
        The ``floorplan`` config section.
    outputs : mapping of str to path
        Format -> output path.
    name : str
        The plan's title.
    dataset, ordering, extractor : str
    k : str or int
        What the plan is of (its metadata).
    timestamp : float, optional
        The exports' time stamp, seconds since the epoch (:func:`export_time`).

    Returns
    -------
    FloorPlan

    Raises
    ------
    KeyError
        For an unknown output format, or a missing coordinate column.
    floorscan.core.config.ConfigError
        For a config key or value the schema refuses.
    """
    return FloorplanWriter(cfg).write(
        segments, outputs, name, dataset=dataset, ordering=ordering, extractor=extractor, k=k, timestamp=timestamp
    )[0]


@dataclass(frozen=True)
class RecommendedPlan:
    """The recommended floor plan of a recording (:func:`recommended_plan`).

    Attributes
    ----------
    plan : FloorPlan
    metadata : PlanMetadata
        Dataset, ordering, extractor, k (the number of selected scans) and the time
        stamp (the recording's first scan), as its exports name them.
    grid : OccupancyGrid or None
        The free space of the selected scans, when given.
    n_scans, n_segments : int
        The selected scans and their wall segments the plan was built of.
    """

    plan: FloorPlan
    metadata: PlanMetadata
    grid: OccupancyGrid | None
    n_scans: int
    n_segments: int


def recommended_plan(
    scans_path: str | os.PathLike,
    walls_path: str | os.PathLike,
    index_path: str | os.PathLike,
    cfg: Mapping[str, Any] | None,
    dataset: str,
    ordering: str,
    extractor: str,
    grid_path: str | os.PathLike | None = None,
) -> RecommendedPlan:
    """Build the recommended floor plan, the walls of the selected scans, without
    writing it (:func:`write_recommended_floorplan` writes it; a building takes the
    plans of its floors from here).

    Parameters
    ----------
    scans_path : path
        ``selection/scans.parquet``, the selection stage's table
        (:func:`floorscan.select.deliverables.write_scan_table`): its ``scan_id``
        column names the selected scans.
    walls_path : path
        ``walls/<extractor>/per_scan.parquet`` (every kept scan's wall segments, the
        selected scans' are taken) or, for the map extractor,
        ``walls/map/selected.parquet`` (the map of the selected scans, taken whole).
    index_path : path
        ``scan_index.parquet``: the first scan's stamp is the plan's time stamp
        (:func:`~floorscan.floorplan.metadata.recording_timestamp`).
    cfg : mapping
        The ``floorplan`` config section.
    dataset, ordering, extractor : str
        What the plan is of (its metadata).
    grid_path : path, optional
        ``walls/map/selected_grid.parquet``: the free space of the selected scans; with
        it the plan goes through the structure passes (clutter, joins, junctions) and
        gets its rooms and doors.

    Returns
    -------
    RecommendedPlan

    Raises
    ------
    KeyError
        For an unknown config key, or a missing column.
    """
    from floorscan.core.io import read_table
    from floorscan.core.occupancy import read_grid
    from floorscan.floorplan.plan import PLAN_MEMORY
    from floorscan.floorplan.scans import ScanPlans
    from floorscan.core.selection import selected_scan_ids

    ids = selected_scan_ids(scans_path)
    grid = None if grid_path is None else read_grid(grid_path, PLAN_MEMORY, f"the floor plan on the grid {grid_path}")
    meta = PlanMetadata(dataset, ordering, extractor, len(ids), recording_timestamp(index_path))
    plans = ScanPlans(read_table(walls_path), stage_params(FloorplanParams, cfg))
    scans = None if extractor == "map" else ids  # the map extractor's table is the selected scans' map whole
    plan = plans.plan(scans, grid)
    rows = plans.rows(scans)
    return RecommendedPlan(plan, meta, grid, len(ids), int(rows.sum()))


def write_recommended_floorplan(
    scans_path: str | os.PathLike,
    walls_path: str | os.PathLike,
    index_path: str | os.PathLike,
    outputs: Mapping[str, str | os.PathLike],
    cfg: Mapping[str, Any] | None,
    dataset: str,
    ordering: str,
    extractor: str,
    grid_path: str | os.PathLike | None = None,
    map_paths: tuple[str | os.PathLike, str | os.PathLike] | None = None,
    plan_folder: str | os.PathLike | None = None,
) -> dict:
    """Write the recommended floor plan (:func:`recommended_plan`): the walls of the
    selected scans.

    Parameters
    ----------
    scans_path, walls_path, index_path, cfg, dataset, ordering, extractor, grid_path
        As :func:`recommended_plan` (the first scan's stamp is the exports' time stamp:
        the same recording gives the same files).
    outputs : mapping
        Paths by format (any of :data:`FLOORPLAN_FORMATS`); ``cfg``'s ``georeference``
        applies to them.
    map_paths : (path, path), optional
        ``map.pgm``, ``map.yaml``: that grid as a ROS map_server / Nav2 map
        (:func:`floorscan.core.occupancy.write_map_server`); needs ``grid_path``.
    plan_folder : path, optional
        The plan as Parquet tables (:func:`floorscan.floorplan.scans.write_plan`: map
        frame, rooms as WKB), for programs.

    Returns
    -------
    dict
        ``n_scans``, ``n_segments``, ``n_walls``, ``n_faces``, ``n_clutter``,
        ``n_junctions``.

    Raises
    ------
    KeyError
        For an unknown output format or config key.
    ValueError
        For ``map_paths`` without ``grid_path``.
    """
    writer = FloorplanWriter(cfg)
    _check_formats(outputs)
    if map_paths is not None and grid_path is None:
        raise ValueError("an occupancy map needs the grid of the selected scans (grid_path)")
    rec = recommended_plan(scans_path, walls_path, index_path, cfg, dataset, ordering, extractor, grid_path)
    writer.export(PlanExports(rec.plan), outputs, rec.metadata)
    if plan_folder is not None:
        from floorscan.floorplan.scans import write_plan

        write_plan(rec.plan, plan_folder, table_metadata(rec.metadata, rec.n_scans))
    if map_paths is not None:
        from floorscan.core.occupancy import write_map_server

        write_map_server(rec.grid, *map_paths, title=f"occupancy map of the {rec.n_scans} selected scans")
    plan = rec.plan
    return {
        "n_scans": rec.n_scans, "n_segments": rec.n_segments, "n_walls": len(plan.walls), "n_faces": len(plan.faces),
        "n_clutter": len(plan.clutter), "n_junctions": len(plan.junctions),
    }  # fmt: skip


def write_map_floorplan(
    walls_path: str | os.PathLike,
    grid_path: str | os.PathLike,
    outputs: Mapping[str, str | os.PathLike],
    cfg: Mapping[str, Any] | None,
    dataset: str,
    plan_folder: str | os.PathLike | None = None,
) -> FloorPlan:
    """Write the floor plan of an occupancy map given as the recording (rule
    ``map_floorplan``): the map extractor's walls of the map through the structure
    passes and the room step, on the map's grid, as the plan of the selected scans is
    built on theirs (:class:`FloorplanWriter`). A map has no scans: no ordering, no k,
    and no time stamp (the exports take ``SOURCE_DATE_EPOCH``, else 0).

    Parameters
    ----------
    walls_path : path
        ``walls/map/map.parquet`` (:func:`floorscan.walls.map_stage.write_occupancy_map_walls`).
    grid_path : path
        The map's grid (rule ``map_ingest``).
    outputs : mapping
        Paths by format (any of :data:`FLOORPLAN_FORMATS`); ``cfg``'s ``georeference``
        applies to them.
    cfg : mapping
        The ``floorplan`` config section.
    dataset : str
    plan_folder : path, optional
        The plan as Parquet tables (:func:`floorscan.floorplan.scans.write_plan`).

    Returns
    -------
    FloorPlan

    Raises
    ------
    KeyError
        For an unknown output format or config key.
    """
    from floorscan.core.io import read_table
    from floorscan.core.occupancy import read_grid

    plan, _ = FloorplanWriter(cfg).write(
        read_table(walls_path), outputs, f"{dataset} occupancy map", dataset=dataset, extractor="map",
        grid=read_grid(grid_path),
    )  # fmt: skip
    if plan_folder is not None:
        from floorscan.floorplan.scans import write_plan

        write_plan(plan, plan_folder, table_metadata(PlanMetadata(dataset, extractor="map"), 0) | {"source": "map"})
    return plan

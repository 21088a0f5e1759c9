"""The map extractor as a job (rule ``map_walls``): the wall segments of the map of a
set of scans (:func:`floorscan.walls.map_lines.map_segments`) and the occupancy grid of
the same scans (:func:`floorscan.core.occupancy.occupancy_grid`, the free space the
floor plan's structure passes read), for the selected scans (the answer) or all kept
scans (the evaluation; their grid is the reference map's when it has the settings of
:func:`map_grid_params`, so the scans are cast once); or of an occupancy map given as
the recording (:func:`map_of_grid`, rule ``occupancy_map_walls``), whose grid is all
there is.
"""

from __future__ import annotations

import logging
import os
from dataclasses import replace
from typing import Any, Mapping

import numpy as np
import pandas as pd

from floorscan.core.config import schema_section_defaults
from floorscan.core.memory import JobMemory
from floorscan.core.occupancy import OccupancyGrid, OccupancyParams, occupancy_grid
from floorscan.core.ray_casting import COUNTS_BYTES_PER_CELL
from floorscan.walls.map_lines import MapParams, map_segments

log = logging.getLogger(__name__)

#: What the map extractor's job takes a cell of the grid of the scans (the counts being
#: built, :data:`floorscan.core.ray_casting.COUNTS_BYTES_PER_CELL`, and the support
#: test's log-odds, float64) and a wall point (the support test's cells, the thinning's
#: keys and sums: 40 at the job's peak, rounded up, ``benchmarks/README.md``).
MAP_MEMORY = JobMemory(COUNTS_BYTES_PER_CELL + 8, "walls.map.support_cell_m", bytes_per_point=40)


def map_grid_params(cfg: Mapping[str, Any] | None) -> OccupancyParams:
    """The settings of the map extractor's occupancy grid: cells of
    ``map.support_cell_m``, the others the reference map's defaults.

    Parameters
    ----------
    cfg : mapping or None
        The ``walls`` config section.

    Returns
    -------
    OccupancyParams
    """
    from floorscan.core.config import stage_params

    return replace(OccupancyParams(), resolution_m=stage_params(MapParams, (cfg or {}).get("map")).support_cell_m)


def map_of_scans(
    registered_path: str | os.PathLike,
    registration: pd.DataFrame,
    scan_ids: np.ndarray | None,
    cfg: Mapping[str, Any] | None,
    grid: OccupancyGrid | None = None,
) -> tuple[pd.DataFrame, OccupancyGrid]:
    """The map extractor's wall segments and the occupancy grid of a set of scans.

    Parameters
    ----------
    registered_path : path
        ``registered.parquet``: the kept scans' points in the map frame, metres.
    registration : pandas.DataFrame
        ``registration.parquet``: ``scan_id``, ``kept``, ``x_m``, ``y_m`` (the scanner's
        registered position in the map frame, metres: the rays' origin).
    scan_ids : (K,) int ndarray or None
        The scans to use; None: every kept scan.
    cfg : mapping
        The ``walls`` config section (height band, ``map``, ``seed``).
    grid : OccupancyGrid, optional
        The occupancy grid of these scans, already made with :func:`map_grid_params`
        (the reference map of all kept scans, when its settings are those): taken, not
        cast again.

    Returns
    -------
    segments : pandas.DataFrame
        :data:`floorscan.walls.tables.WALLS` columns, ``scan_id`` -1 (a segment of
        many scans).
    grid : OccupancyGrid
        Cells of ``map.support_cell_m``; the other settings the reference map's
        defaults (:func:`map_grid_params`).

    Raises
    ------
    ValueError
        When a scan to use has no kept row, or none of them has a wall point, or
        ``grid`` has other settings than :func:`map_grid_params` or another number of
        scans.
    floorscan.core.io.InputError
        When the grid of the scans' extent would be too large
        (:func:`floorscan.core.grid.check_raster_size`: names the dataset, the extent
        in metres, the cells and the memory), or the job's rasters (:data:`MAP_MEMORY`)
        would not fit in the memory free on the machine, before it is allocated.
    """
    from floorscan.core.io import iter_scans
    from floorscan.core.config import stage_params
    from floorscan.core.wall_points import ScanParams, scan_points_2d

    cfg = cfg or {}
    params = stage_params(MapParams, cfg.get("map"))
    sp = stage_params(ScanParams, cfg)
    reg = registration[registration["kept"]].set_index("scan_id")
    wanted = set(reg.index.tolist() if scan_ids is None else np.asarray(scan_ids).tolist())
    missing = sorted(wanted - set(reg.index.tolist()))
    if missing:
        raise ValueError(f"scans {missing[:5]} are not kept scans of the registration table")
    position = dict(zip(reg.index.tolist(), reg[["x_m", "y_m"]].to_numpy(np.float64)))  # one lookup a scan
    points, origins = [], []
    for sid, xyz in iter_scans(registered_path):
        if sid not in wanted:
            continue
        xy, _ = scan_points_2d(xyz, sp)
        points.append(xy)
        origins.append(position[sid])
    pts = np.concatenate(points) if points else np.empty((0, 2))
    if len(pts) == 0:
        raise ValueError(f"none of the {len(wanted)} scans has a wall point")
    from floorscan.core.io import read_metadata

    dataset = read_metadata(registered_path).get("dataset")
    what = (f"the occupancy grid of {'all kept' if scan_ids is None else 'the selected'} {len(origins)} scans"
            f"{f' of dataset {dataset!r}' if dataset else ''} ({registered_path})")
    settings = map_grid_params(cfg)
    if grid is None:
        grid = occupancy_grid(zip(origins, points), settings, what, MAP_MEMORY)
    elif grid.params != settings or grid.scan_xy is None or len(grid.scan_xy) != len(origins):
        raise ValueError(f"{what}: the grid given is not theirs: {grid.params}, "
                         f"{0 if grid.scan_xy is None else len(grid.scan_xy)} scans; expected {settings}")
    segments = _map_table(pts, grid, params, cfg)
    log.info("map of %d scans (%d wall points): %d wall segments; grid %d x %d cells of %.3f m",
             len(origins), len(pts), len(segments), grid.shape[1], grid.shape[0], grid.resolution_m)
    return segments, grid


#: How far a map's wall may lie from its free space, metres: a map drawn or saved with
#: anti-aliasing has a seam of grey (unknown) pixels between the white floor and the
#: black wall, 2-4 pixels of 5 cm on the benchmark maps of ``room-maps/``; a seam
#: wider than this is unseen space, not a wall's edge.
MAP_SEAM_M = 0.25


def wall_cells(grid: OccupancyGrid, seam_m: float = MAP_SEAM_M) -> np.ndarray:
    """The occupied cells of a map that face its free space: those 8-adjacent to the free
    space grown through non-occupied cells by up to ``seam_m``.

    A map, unlike the grid of scans, may hold occupied cells no ray ever reached: the
    inside of a wall drawn thick, the outside of the building painted black. Only the
    layer of occupied cells the free space looks at are wall points: one face per side
    of a wall, as a scan sees it.

    Parameters
    ----------
    grid : OccupancyGrid
    seam_m : float
        Metres (:data:`MAP_SEAM_M`).

    Returns
    -------
    (H, W) bool ndarray
    """
    from scipy import ndimage

    occupied, free = grid.occupied(), grid.free()
    steps = int(round(seam_m / grid.resolution_m))
    eight = np.ones((3, 3), dtype=bool)
    reach = ndimage.binary_dilation(free, eight, iterations=steps, mask=~occupied) if steps > 0 else free
    return occupied & ndimage.binary_dilation(reach | free, eight)


def map_of_grid(grid: OccupancyGrid, cfg: Mapping[str, Any] | None) -> pd.DataFrame:
    """The map extractor's wall segments of an occupancy map (no scans): RANSAC
    (:func:`floorscan.walls.map_lines.map_segments`) on the centres of its
    :func:`wall_cells`.

    Parameters
    ----------
    grid : OccupancyGrid
        The map (:func:`floorscan.ingest.occupancy_map.read_occupancy_map`).
    cfg : mapping or None
        The ``walls`` config section (``map``, ``seed``).

    Returns
    -------
    pandas.DataFrame
        :data:`floorscan.walls.tables.WALLS` columns, ``scan_id`` -1.
    """
    from floorscan.core.config import stage_params

    cfg = cfg or {}
    params = stage_params(MapParams, cfg.get("map"))
    pts = grid.cell_centres(wall_cells(grid))
    segments = _map_table(pts, grid, params, cfg)
    log.info("map of %d x %d cells of %.3f m: %d wall cells, %d wall segments",
             grid.shape[1], grid.shape[0], grid.resolution_m, len(pts), len(segments))
    return segments


def _map_table(points: np.ndarray, grid: OccupancyGrid, params: MapParams, cfg: Mapping[str, Any]) -> pd.DataFrame:
    """:func:`~floorscan.walls.map_lines.map_segments` seeded by ``cfg``'s ``seed``, as a
    wall table of many scans (``scan_id`` -1)."""
    segments = map_segments(points, grid, params, seed=int(cfg.get("seed", schema_section_defaults("walls")["seed"])))
    segments.insert(0, "scan_id", np.full(len(segments), -1, dtype=np.int32))
    return segments


def write_map_walls(
    registered_path, registration_path, scans_path, cfg, walls_path, grid_path, reference_path=None
) -> dict:
    """Rule ``map_walls``: :func:`map_of_scans` of a set of scans, the segments and the
    grid written.

    Parameters
    ----------
    registered_path : path
        ``registered.parquet``: the kept scans' points in the map frame, metres.
    registration_path : path
        ``registration.parquet`` (``scan_id``, ``kept``, ``x_m``, ``y_m``).
    scans_path : path or None
        ``selection/scans.parquet`` (:func:`floorscan.select.deliverables.write_scan_table`),
        whose ``scan_id`` column names the scans; None: all kept scans.
    cfg : mapping
        The ``walls`` config section.
    walls_path : path
        Output: the segments (:data:`floorscan.walls.tables.WALLS`, metadata
        ``extractor``, ``n_scans``).
    grid_path : path
        Output: the occupancy grid (:func:`floorscan.core.occupancy.write_grid`).
    reference_path : path, optional
        With ``scans_path`` None: the reference map (``reference/occupancy.parquet``),
        whose grid of all kept scans is taken when made with :func:`map_grid_params`
        (the rule passes it only then).

    Returns
    -------
    dict
        ``n_scans`` and ``n_segments`` (int).
    """
    from floorscan.core.io import read_table, write_table
    from floorscan.core.occupancy import write_grid
    from floorscan.core.selection import selected_scan_ids
    from floorscan.walls.tables import WALLS

    registration = read_table(registration_path)
    ids = None if scans_path is None else selected_scan_ids(scans_path)
    given = None
    if reference_path is not None:
        from floorscan.core.occupancy import read_grid

        given = read_grid(reference_path, MAP_MEMORY, f"the map of all kept scans on the reference map {reference_path}")
    segments, grid = map_of_scans(registered_path, registration, ids, cfg, given)
    n_scans = int(registration["kept"].sum()) if ids is None else len(ids)
    write_table(segments, walls_path, WALLS, metadata={"extractor": "map", "n_scans": str(n_scans)})
    write_grid(grid, grid_path, metadata={"n_scans": str(n_scans)})
    return {"n_scans": n_scans, "n_segments": len(segments)}


def write_occupancy_map_walls(grid_path, cfg, walls_path) -> dict:
    """Rule ``occupancy_map_walls``: :func:`map_of_grid` of a map given as the recording,
    the segments written.

    Parameters
    ----------
    grid_path : path
        The map's grid (rule ``map_ingest``, :func:`floorscan.core.occupancy.write_grid`).
    cfg : mapping
        The ``walls`` config section.
    walls_path : path
        Output: the segments (:data:`floorscan.walls.tables.WALLS`, metadata
        ``extractor`` ``map``, ``n_scans`` 0).

    Returns
    -------
    dict
        ``n_segments`` (int).
    """
    from floorscan.core.io import write_table
    from floorscan.core.occupancy import read_grid
    from floorscan.walls.tables import WALLS

    segments = map_of_grid(read_grid(grid_path), cfg)
    write_table(segments, walls_path, WALLS, metadata={"extractor": "map", "n_scans": "0", "source": "map"})
    return {"n_segments": len(segments)}

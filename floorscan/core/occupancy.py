"""Occupancy grids of registered scans: the reference map of a recording (all kept
scans, :mod:`floorscan.score.reference`) and the free space of the selected scans
(the floor plan's structure passes, :mod:`floorscan.floorplan.structure`).

Mapping with known poses (Thrun, Burgard, Fox, *Probabilistic Robotics*, ch. 9,
Table 9.1): every kept scan, at its registered pose, casts a ray from the scanner to
each of its returns; the cells the rays cross are evidence of free space, the cells of
the returns evidence of an obstacle. Each cell's log-odds is the sum of its updates
(prior 0.5, log-odds 0):

- one update per scan and cell (a scan is one measurement of a cell, however many of
  its beams cross it): ``l_hit = logit(prob_hit)`` when a return of the scan falls in
  the cell, else ``l_miss = logit(prob_miss)`` when one of its rays crosses it. Without
  clamping the sum does not depend on the scans' order, so the map is the same for
  any order of the inputs (OctoMap's 0.7 / 0.4 are the defaults; OctoMap clamps for
  a changing world, which an offline reference does not need);
- a cell is occupied when its probability exceeds ``occupied_thresh`` (0.65), free
  below ``free_thresh`` (0.196), unknown between: the thresholds of ROS map_server's
  maps, which :func:`write_map_server` writes (PGM + YAML, ``mode: trinary``) so that
  RViz, nav2 and GIMP open the reference;
- the reference *structure* is the occupied cells hit by at least ``min_scans`` (2)
  scans; occupied cells hit by one scan only (people walking by, a door in motion,
  a stray return) are counted apart and are not structure.

Rays are sampled every ``step_fraction`` of a cell along their length (the cells a
ray crosses, up to a corner clipped by less than a quarter cell); the return's own
cell is not a miss of that scan. 3D scans are cut to the walls' height band first
(:func:`floorscan.core.wall_points.scan_points_2d`), so the grid is the plan view the floor plan
is drawn in.

Usage::

    grid = occupancy_grid(((pose_xy, points_xy) for ...), OccupancyParams())
    write_map_server(grid, "map.pgm", "map.yaml")
    write_grid(grid, "occupancy.parquet")  # read_grid restores it
    structure_xy = grid.cell_centres(grid.structure())

The grids of the first k scans for increasing k, each scan cast once:
:func:`floorscan.core.prefix_grids.prefix_grids`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

import numpy as np
import pandas as pd

from floorscan.core.files import atomic_path
from floorscan.core.config import schema_defaults
from floorscan.core.grid import raster_cells
from floorscan.core.memory import JobMemory
from floorscan.core.ray_casting import CellCounts, GridFrame, check_memory_of_casting, with_returns

#: map_server's PGM values (trinary mode): occupied, free, unknown.
PGM_OCCUPIED, PGM_FREE, PGM_UNKNOWN = 0, 254, 205


def logit(p: float) -> float:
    """Log-odds ``log(p / (1 - p))`` of a probability.

    Parameters
    ----------
    p : float
        In (0, 1).

    Returns
    -------
    float
    """
    return math.log(p / (1.0 - p))


@dataclass(frozen=True)
@schema_defaults("score.reference")
class OccupancyParams:
    """Settings of the reference map (the ``score.reference`` config section).

    Attributes
    ----------
    resolution_m : float
        Cell size, metres.
    prob_hit, prob_miss : float
        Probability of occupancy after one scan's return in the cell / ray through it.
    occupied_thresh, free_thresh : float
        map_server's thresholds on the cell's probability.
    min_scans : int
        Occupied cells hit by fewer scans are not structure.
    step_fraction : float
        Sample spacing along a ray, in cells.
    margin_m : float
        Grid margin around the scans' returns and origins, metres.
    """

    resolution_m: float
    prob_hit: float
    prob_miss: float
    occupied_thresh: float
    free_thresh: float
    min_scans: int
    step_fraction: float
    margin_m: float

    def check(self) -> None:
        """Check every value's range.

        Raises
        ------
        ValueError
            Naming the key (``score.reference.<key>``) when a value is out of range.
        """
        if not self.resolution_m > 0:
            raise ValueError(f"score.reference.resolution_m: expected > 0, got {self.resolution_m}")
        if not 0.5 < self.prob_hit < 1.0:
            raise ValueError(f"score.reference.prob_hit: expected 0.5 < p < 1, got {self.prob_hit}")
        if not 0.0 < self.prob_miss < 0.5:
            raise ValueError(f"score.reference.prob_miss: expected 0 < p < 0.5, got {self.prob_miss}")
        if not 0.0 < self.free_thresh < 0.5 < self.occupied_thresh < 1.0:
            raise ValueError(
                "score.reference: expected 0 < free_thresh < 0.5 < occupied_thresh < 1, got "
                f"{self.free_thresh}, {self.occupied_thresh}"
            )
        if int(self.min_scans) < 1:
            raise ValueError(f"score.reference.min_scans: expected >= 1, got {self.min_scans}")
        if not 0.0 < self.step_fraction <= 1.0:
            raise ValueError(f"score.reference.step_fraction: expected 0 < value <= 1, got {self.step_fraction}")
        if not self.margin_m >= 0:
            raise ValueError(f"score.reference.margin_m: expected >= 0, got {self.margin_m}")


@dataclass
class OccupancyGrid:
    """A 2D occupancy grid in the map frame.

    Attributes
    ----------
    origin_xy : (2,) float ndarray
        Map-frame position of the lower-left corner of cell (row 0, column 0), metres
        (map_server's ``origin``).
    resolution_m : float
        Cell size, metres.
    n_hit_scans, n_miss_scans : (H, W) int32 ndarray
        Scans with a return in the cell / with a ray through it and no return in it;
        row ``i`` at ``y = origin_y + (i + 0.5) r``.
    params : OccupancyParams
    scan_xy : (S, 2) float64 ndarray or None
        Where the scans were taken from (their origins, map frame, metres, in the order
        given): the space the scanner was in. None for a grid written without them.
    """

    origin_xy: np.ndarray
    resolution_m: float
    n_hit_scans: np.ndarray
    n_miss_scans: np.ndarray
    params: OccupancyParams
    scan_xy: np.ndarray | None = None

    @property
    def shape(self) -> tuple[int, int]:
        return self.n_hit_scans.shape

    @property
    def log_odds(self) -> np.ndarray:
        """(H, W) float64 log-odds of occupancy: the sum of the scans' updates."""
        return self.n_hit_scans * logit(self.params.prob_hit) + self.n_miss_scans * logit(self.params.prob_miss)

    def probability(self) -> np.ndarray:
        """(H, W) float64 probability of occupancy."""
        return 1.0 / (1.0 + np.exp(-self.log_odds))

    def occupied(self) -> np.ndarray:
        """(H, W) bool: probability above ``occupied_thresh``."""
        return self._log_odds_beyond(logit(self.params.occupied_thresh), above=True)

    def free(self) -> np.ndarray:
        """(H, W) bool: probability below ``free_thresh``."""
        return self._log_odds_beyond(logit(self.params.free_thresh), above=False)

    def _log_odds_beyond(self, threshold: float, above: bool) -> np.ndarray:
        """``log_odds > threshold`` (``above``) or ``log_odds < threshold``, the log-odds
        summed only where they can pass it: with ``l_hit > 0 > l_miss``, a cell no scan
        hit has log-odds <= 0, one no ray crossed >= 0, so a positive threshold is passed
        only by cells with a hit, a negative one only by cells with a miss. Those cells'
        log-odds are the same floats as :attr:`log_odds`' (the same products and sum)."""
        l_hit, l_miss = logit(self.params.prob_hit), logit(self.params.prob_miss)
        hits, misses = self.n_hit_scans, self.n_miss_scans
        sparse = l_hit > 0 > l_miss and (threshold >= 0 if above else threshold <= 0)
        if not sparse or (hits.size and min(int(hits.min()), int(misses.min())) < 0):
            return self.log_odds > threshold if above else self.log_odds < threshold
        out = np.zeros(hits.shape, dtype=bool)
        hits, misses = hits.reshape(-1), misses.reshape(-1)
        cells = np.flatnonzero(hits if above else misses)
        lo = hits[cells] * l_hit + misses[cells] * l_miss
        out.reshape(-1)[cells] = lo > threshold if above else lo < threshold
        return out

    def structure(self) -> np.ndarray:
        """(H, W) bool: occupied and hit by at least ``min_scans`` scans."""
        return self.occupied() & (self.n_hit_scans >= self.params.min_scans)

    def single_scan(self) -> np.ndarray:
        """(H, W) bool: occupied but hit by fewer than ``min_scans`` scans."""
        return self.occupied() & (self.n_hit_scans < self.params.min_scans)

    def cell_centres(self, mask: np.ndarray) -> np.ndarray:
        """Map-frame centres of the cells where ``mask`` is True.

        Parameters
        ----------
        mask : (H, W) bool ndarray

        Returns
        -------
        (N, 2) float64 ndarray
            ``x, y``, metres, in row-major order of the cells.
        """
        iy, ix = np.nonzero(mask)
        return np.column_stack([ix + 0.5, iy + 0.5]) * self.resolution_m + self.origin_xy

    def cells_of(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The cell of each map-frame point.

        Parameters
        ----------
        xy : (N, 2) float ndarray
            Metres.

        Returns
        -------
        row, col : (N,) int64 ndarray
            Cell indices (may be outside the grid).
        inside : (N,) bool ndarray
            Whether the cell is inside the grid.
        """
        return raster_cells(xy, self.origin_xy, self.resolution_m, self.shape)

    def counts(self) -> dict[str, int]:
        """Cells per class.

        Returns
        -------
        dict of str to int
            ``occupied``, ``structure``, ``single_scan``, ``free``, ``unknown``.
        """
        occ, free = self.occupied(), self.free()
        return {
            "occupied": int(occ.sum()),
            "structure": int(self.structure().sum()),
            "single_scan": int(self.single_scan().sum()),
            "free": int(free.sum()),
            "unknown": int(occ.size - occ.sum() - free.sum()),
        }


def occupancy_grid(scans: Iterable[tuple[np.ndarray, np.ndarray]], params: OccupancyParams = OccupancyParams(),
                   what: str = "occupancy grid", memory: JobMemory | None = None) -> OccupancyGrid:
    """Build the occupancy grid of a set of registered scans (see the module docstring;
    the casting: :mod:`floorscan.core.ray_casting`).

    Parameters
    ----------
    scans : iterable of (origin, points)
        Per scan the scanner's position in the map frame ((2,) float, metres) and its
        returns in the map frame ((M, 2) float, metres, plan view).
    params : OccupancyParams
    what : str
        The grid and whose scans, for the error of a grid too large.
    memory : JobMemory, optional
        What the job's rasters take a cell of the grid: the job stops before the grid
        is allocated when they and the rays of its largest scan would not fit in the
        free memory (:func:`floorscan.core.ray_casting.check_memory_of_casting`).

    Returns
    -------
    OccupancyGrid

    Raises
    ------
    ValueError
        When no scan has a return, or a coordinate is not finite; an ``InputError`` when the
        grid would be too large (:func:`floorscan.core.grid.check_raster_size`) or, with
        ``memory``, need more memory than is free
        (:class:`~floorscan.core.memory.MemoryEstimateError`), before it is allocated.
    """
    params.check()
    scans = with_returns(scans)
    if not scans:
        raise ValueError("occupancy grid: no scan has a return")
    frame = GridFrame.of(scans, params.resolution_m, params.margin_m, what)
    if memory is not None:
        check_memory_of_casting(scans, frame, params.step_fraction, what, memory)
    counts = CellCounts(frame, params.step_fraction)
    for o, p in scans:
        counts.add(*counts.cells(o, p, frame)[:2])
    hits, misses = counts.window(frame)
    return OccupancyGrid(origin_xy=frame.origin, resolution_m=frame.r, n_hit_scans=hits, n_miss_scans=misses,
                         params=params, scan_xy=np.array([o for o, _ in scans], dtype=np.float64).reshape(-1, 2))


def map_image(grid: OccupancyGrid) -> np.ndarray:
    """The grid as a map_server image, row 0 at the top (largest y).

    Parameters
    ----------
    grid : OccupancyGrid

    Returns
    -------
    (H, W) uint8 ndarray
        Occupied 0, free 254, unknown 205.
    """
    img = np.full(grid.shape, PGM_UNKNOWN, dtype=np.uint8)
    img[grid.free()] = PGM_FREE
    img[grid.occupied()] = PGM_OCCUPIED
    return img[::-1]


def write_map_server(
    grid: OccupancyGrid, pgm_path: str | Path, yaml_path: str | Path, title: str = "reference map"
) -> None:
    """Write the grid as a ROS map_server map: a binary PGM (P5) and its YAML.

    The YAML names the image by its file name (map_server resolves it beside the
    YAML), the resolution (m/cell), the origin (x, y, yaw of the lower-left pixel) and
    the thresholds, ``negate: 0``, ``mode: trinary``; ``title`` goes into the PGM's
    comment line.

    Parameters
    ----------
    grid : OccupancyGrid
    pgm_path, yaml_path : path
        Outputs, each written atomically.
    title : str
    """
    img = map_image(grid)
    h, w = img.shape
    with atomic_path(pgm_path) as tmp:
        with open(tmp, "wb") as f:
            f.write(f"P5\n# floorscan {title}, {grid.resolution_m} m/cell\n{w} {h}\n255\n".encode("ascii"))
            f.write(img.tobytes())
    p = grid.params
    text = (
        f"image: {Path(pgm_path).name}\n"
        f"resolution: {grid.resolution_m}\n"
        f"origin: [{float(grid.origin_xy[0])!r}, {float(grid.origin_xy[1])!r}, 0.0]\n"
        f"negate: 0\n"
        f"occupied_thresh: {p.occupied_thresh}\n"
        f"free_thresh: {p.free_thresh}\n"
        f"mode: trinary\n"
    )
    with atomic_path(yaml_path) as tmp:
        Path(tmp).write_text(text)


def grid_table(grid: OccupancyGrid) -> pd.DataFrame:
    """The known cells (hit or crossed by a scan) as a table.

    Parameters
    ----------
    grid : OccupancyGrid

    Returns
    -------
    pandas.DataFrame
        ``row``, ``col``, ``n_hit_scans``, ``n_miss_scans``, all int32.
    """
    known = (grid.n_hit_scans > 0) | (grid.n_miss_scans > 0)
    iy, ix = np.nonzero(known)
    return pd.DataFrame(
        {
            "row": iy.astype(np.int32),
            "col": ix.astype(np.int32),
            "n_hit_scans": grid.n_hit_scans[known].astype(np.int32),
            "n_miss_scans": grid.n_miss_scans[known].astype(np.int32),
        }
    )


def grid_metadata(grid: OccupancyGrid) -> dict[str, str]:
    """Schema metadata that, with :func:`grid_table`, restores the grid.

    Parameters
    ----------
    grid : OccupancyGrid

    Returns
    -------
    dict of str to str
        Origin (metres), resolution (m/cell), height and width (cells), every
        :class:`OccupancyParams` field as ``param_<name>``, and the scans' origins as JSON
        (``scan_xy_m``, metres to 0.1 mm) when the grid has them.
    """
    p = grid.params
    return {
        "origin_x_m": repr(float(grid.origin_xy[0])),
        "origin_y_m": repr(float(grid.origin_xy[1])),
        "resolution_m": repr(grid.resolution_m),
        "height": str(grid.shape[0]),
        "width": str(grid.shape[1]),
        **{f"param_{k}": repr(getattr(p, k)) for k in OccupancyParams.__dataclass_fields__},
        **({} if grid.scan_xy is None else {"scan_xy_m": json.dumps(np.round(grid.scan_xy, 4).tolist())}),
    }


def write_grid(grid: OccupancyGrid, path: str | Path, metadata: dict[str, str] | None = None) -> None:
    """Write the grid as a cell table (:func:`grid_table`) whose schema metadata
    (:func:`grid_metadata`, the cell counts per class and ``metadata``) restores it.

    Parameters
    ----------
    grid : OccupancyGrid
    path : path
        Parquet output, written atomically.
    metadata : dict of str to str, optional
        More key/value strings (they override the grid's on a clash).
    """
    from floorscan.core.io import write_table

    counts = {f"n_{k}_cells": str(v) for k, v in grid.counts().items()}
    write_table(grid_table(grid), path, metadata={**grid_metadata(grid), **counts, **(metadata or {})})


def read_grid(path: str | Path, memory: JobMemory | None = None, what: str | None = None) -> OccupancyGrid:
    """The grid :func:`write_grid` wrote (``reference/occupancy.parquet``).

    Parameters
    ----------
    path : path
    memory : JobMemory, optional
        What the reading job's rasters take a cell of the grid: the job stops before
        the grid is read when they would not fit in the free memory.
    what : str, optional
        What the job makes of the grid, for that message (default: the path).

    Returns
    -------
    OccupancyGrid

    Raises
    ------
    floorscan.core.memory.MemoryEstimateError
        With ``memory``, when the job's rasters would need more memory than is free.
    """
    from floorscan.core.io import read_metadata, read_table

    metadata = read_metadata(path)
    if memory is not None:
        shape = (int(metadata["height"]), int(metadata["width"]))
        memory.check(what or f"the job reading the grid {path}", shape, float(metadata["resolution_m"]))
    return grid_from_table(read_table(path), metadata)


def grid_from_table(table: pd.DataFrame, metadata: dict[str, str]) -> OccupancyGrid:
    """The grid of :func:`grid_table` and :func:`grid_metadata`, exactly.

    Parameters
    ----------
    table : pandas.DataFrame
        ``row``, ``col``, ``n_hit_scans``, ``n_miss_scans``.
    metadata : dict of str to str
        :func:`grid_metadata`'s keys.

    Returns
    -------
    OccupancyGrid

    Raises
    ------
    KeyError
        When a key of :func:`grid_metadata` is missing.
    """
    fields = OccupancyParams.__dataclass_fields__
    params = OccupancyParams(**{k: type(fields[k].default)(float(metadata[f"param_{k}"])) for k in fields})
    h, w = int(metadata["height"]), int(metadata["width"])
    hits = np.zeros((h, w), dtype=np.int32)
    misses = np.zeros((h, w), dtype=np.int32)
    rows, cols = table["row"].to_numpy(), table["col"].to_numpy()
    hits[rows, cols] = table["n_hit_scans"].to_numpy()
    misses[rows, cols] = table["n_miss_scans"].to_numpy()
    scan_xy = metadata.get("scan_xy_m")
    return OccupancyGrid(
        origin_xy=np.array([float(metadata["origin_x_m"]), float(metadata["origin_y_m"])]),
        resolution_m=float(metadata["resolution_m"]),
        n_hit_scans=hits,
        n_miss_scans=misses,
        params=params,
        scan_xy=None if scan_xy is None else np.array(json.loads(scan_xy), dtype=np.float64).reshape(-1, 2),
    )

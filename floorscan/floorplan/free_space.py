"""The free space of a plan's scans, as the structure passes probe it: their parameters
(:class:`StructureParams`, config ``floorplan.structure``), which cells the rover saw
free (:func:`passable`), a mask read at points (:func:`mask_at`) and points along faces
(:func:`segment_samples`). Used by :mod:`~floorscan.floorplan.structure`,
:mod:`~floorscan.floorplan.clutter` and :mod:`~floorscan.floorplan.junctions`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from floorscan.core.config import schema_defaults
from floorscan.core.occupancy import OccupancyGrid


@dataclass(frozen=True)
@schema_defaults("floorplan.structure")
class StructureParams:
    """Parameters of the structure passes (config ``floorplan.structure``; see the
    module docstring). Lengths in metres, angles in degrees."""

    side_offset_m: float
    min_free_side: float
    join_max_gap_m: float
    join_offset_m: float
    join_angle_deg: float
    min_opening_m: float
    snap_m: float
    junction_min_angle_deg: float
    object_free_around: float
    front_min_m: float
    front_max_m: float
    front_overlap: float
    duplicate_angle_deg: float
    clutter_max_length_m: float
    min_wall_length_m: float
    loose_reach_m: float


def passable(grid: OccupancyGrid) -> np.ndarray:
    """Cells the scans' rays crossed more often than they hit them (the free space the
    rover saw; one ray through a doorway makes it passable, where the map_server
    threshold needs four).

    Parameters
    ----------
    grid : OccupancyGrid

    Returns
    -------
    (H, W) bool ndarray
    """
    return (grid.n_miss_scans > grid.n_hit_scans) & (grid.n_miss_scans > 0)


def mask_at(grid: OccupancyGrid, mask: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """``mask`` at the cells of points ``xy``.

    Parameters
    ----------
    grid : OccupancyGrid
    mask : (H, W) bool ndarray
        On the grid's cells.
    xy : (N, 2) float ndarray
        Map metres.

    Returns
    -------
    (N,) bool ndarray
        False outside the grid.
    """
    rows, cols, inside = grid.cells_of(xy)
    out = np.zeros(len(xy), dtype=bool)
    out[inside] = mask[rows[inside], cols[inside]]
    return out


def segment_samples(seg: np.ndarray, step: float, trim: float = 0.0):
    """Points along each segment, at most ``step`` apart: the middles of its
    ``ceil(length / step)`` (at least one) equal pieces, after its ends are trimmed by
    ``trim`` when it is longer than four times that.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    step : float
        Metres.
    trim : float
        Metres.

    Returns
    -------
    points : (S, 2) float64 ndarray
        Metres.
    owner : (S,) int64 ndarray
        The segment of each point.
    normals : (F, 2) float64 ndarray
        Each segment's unit normal (its direction turned a quarter left).
    """
    d = seg[:, 2:] - seg[:, :2]
    length = np.hypot(d[:, 0], d[:, 1])
    u = d / np.maximum(length, 1e-12)[:, None]
    n = np.maximum(np.ceil(length / step).astype(np.int64), 1)
    owner = np.repeat(np.arange(len(seg)), n)
    frac = (np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n) + 0.5) / np.repeat(n, n)
    cut = np.where(length > 4 * trim, trim, 0.0)[owner]
    t = cut + frac * (length[owner] - 2 * cut)
    pts = seg[owner, :2] + u[owner] * t[:, None]
    return pts, owner, np.column_stack([-u[:, 1], u[:, 0]])

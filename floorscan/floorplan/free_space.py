"""The free space of a plan's scans, as the structure passes probe it: their parameters
(:class:`StructureParams`, the constants below), which cells the rover saw
free (:func:`passable`), a mask read at points (:func:`mask_at`) and points along faces
(:func:`segment_samples`). Used by :mod:`~floorscan.floorplan.structure`,
:mod:`~floorscan.floorplan.clutter` and :mod:`~floorscan.floorplan.junctions`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from floorscan.core.grid import ranks_in_runs
from floorscan.core.occupancy import OccupancyGrid


# The structure passes' thresholds (floorscan.floorplan.structure: walls bound the free space the rover saw,
# Bormann et al., ICRA 2016; clutter, thesis section 2.3): sizes of walls and furniture, not a user's choice.
#: Free space is probed this far to each side of a face, metres: past a wall's half thickness and the map's cells.
SIDE_OFFSET_M = 0.15
#: A wall has free space on at least one side over this fraction of its length: the rest may be occluded by furniture.
MIN_FREE_SIDE = 0.3
#: Collinear faces at most this far apart are joined unless free space passes the gap, metres: an occlusion by furniture.
JOIN_MAX_GAP_M = 1.5
#: Collinear: the shorter face's ends lie within this of the longer face's line, metres: two map cells and the noise.
JOIN_OFFSET_M = 0.08
#: Collinear: directions differ by at most this, degrees: one wall seen in pieces by scans of different headings.
JOIN_ANGLE_DEG = 5.0
#: A gap holding a run of free cells this long on the faces' line is an opening, not joined, metres: a narrow door.
MIN_OPENING_M = 0.5
#: Ends within this of a junction with another face move onto it, metres: a wall's own thickness and a missed corner.
SNAP_M = 0.4
#: Faces meet in a junction when their directions differ by at least this, degrees: a corner, not one bent wall.
JUNCTION_MIN_ANGLE_DEG = 30.0
#: A group of returns is an object in free space when at least this fraction of the cells around it are free.
OBJECT_FREE_AROUND = 0.6
#: A short face parallel to a long wall this far or more in front of it (free side), metres: off the wall's face ...
FRONT_MIN_M = 0.2
#: ... and at most this far is a desk, cabinet or shelf against the wall, metres: the depth of a desk or a cabinet ...
FRONT_MAX_M = 0.9
#: ... when it lies along the wall over at least this fraction of its length: furniture stands along the wall.
FRONT_OVERLAP = 0.8
#: Walls lying on each other (within a wall's thickness) whose directions differ by at most this are one wall, degrees.
DUPLICATE_ANGLE_DEG = 20.0
#: Objects in free space shorter than this are furniture, metres: the longest desk, shelf or row of chairs is shorter.
CLUTTER_MAX_LENGTH_M = 2.5
#: The clutter reason of structure step 6's chains of faces standing loose in the free space
#: (:func:`~floorscan.floorplan.clutter.loose_in_free_space`).
LOOSE_IN_FREE_SPACE = "loose_in_free_space"
#: Faces shorter than this without a junction are clutter, metres: a wall that meets no other is at least this long.
MIN_WALL_LENGTH_M = 0.5
#: A face that meets no face, none in its line within this, free at both ends, stands in the room (clutter), metres.
LOOSE_REACH_M = 2.5


@dataclass(frozen=True)
class StructureParams:
    """Parameters of the structure passes (see the module docstring; defaults: the
    module's constants, no config option). Lengths in metres, angles in degrees."""

    side_offset_m: float = SIDE_OFFSET_M
    min_free_side: float = MIN_FREE_SIDE
    join_max_gap_m: float = JOIN_MAX_GAP_M
    join_offset_m: float = JOIN_OFFSET_M
    join_angle_deg: float = JOIN_ANGLE_DEG
    min_opening_m: float = MIN_OPENING_M
    snap_m: float = SNAP_M
    junction_min_angle_deg: float = JUNCTION_MIN_ANGLE_DEG
    object_free_around: float = OBJECT_FREE_AROUND
    front_min_m: float = FRONT_MIN_M
    front_max_m: float = FRONT_MAX_M
    front_overlap: float = FRONT_OVERLAP
    duplicate_angle_deg: float = DUPLICATE_ANGLE_DEG
    clutter_max_length_m: float = CLUTTER_MAX_LENGTH_M
    min_wall_length_m: float = MIN_WALL_LENGTH_M
    loose_reach_m: float = LOOSE_REACH_M


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
    frac = (ranks_in_runs(n) + 0.5) / np.repeat(n, n)
    cut = np.where(length > 4 * trim, trim, 0.0)[owner]
    t = cut + frac * (length[owner] - 2 * cut)
    pts = seg[owner, :2] + u[owner] * t[:, None]
    return pts, owner, np.column_stack([-u[:, 1], u[:, 0]])


def open_run(grid: OccupancyGrid, free: np.ndarray | None = None):
    """``open_run(p, u, t0, t1)``: the longest run of passable cells (``free``, the
    grid's :func:`passable` cells by default) on the stretch ``t0..t1`` (metres,
    ``t0 < t1``) of the line through ``p`` (2,) along the unit vector ``u`` (2,),
    sampled every half cell, metres: the opening test of the structure passes' joins
    and of :func:`~floorscan.floorplan.wall_pieces.piers`."""
    free = passable(grid) if free is None else free
    step = grid.resolution_m / 2

    def open_run(p: np.ndarray, u: np.ndarray, t0: float, t1: float) -> float:
        n = max(int(np.ceil((t1 - t0) / step)), 1)
        t = t0 + (np.arange(n) + 0.5) / n * (t1 - t0)
        return longest_run(mask_at(grid, free, p + u * t[:, None])) * (t1 - t0) / n

    return open_run


def longest_run(flags: np.ndarray) -> int:
    """Length of the longest run of True in a 1D bool array."""
    if not flags.any():
        return 0
    padded = np.r_[False, flags, False].astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return int((edges[1::2] - edges[::2]).max())

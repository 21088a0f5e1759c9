"""Structure step 6's third rule: a short face hanging from the wall graph by one end,
whose free end stands in an object's body, is furniture (a desk or a cabinet pushed
against a wall, seen as a line from the wall to its far side; a line the map extractor
fitted along a row of desks up to a wall).

A wall ends where a person can walk round its end: at a door's jamb the wall is as
thick as a wall, with the free space on its two sides. A face ends in an object when,
across its free end, the cells the scans did not see free form a body

- thicker than the thickest wall (the plan's ``pair_max_m``),
- no deeper than a desk or a cabinet (``front_max_m``, and a cell for the raster's
  rounding), with the free space on its far side,
- whose inside the scans did not see occupied, there or behind the face's middle (a
  desk's outline, its inside unseen; the room benchmarks draw a wall's pier solid),

and the body also lies behind the face's middle (not the unseen beyond a wall, which
runs on past a cabinet's depth). Three kinds of face are walls however thick: one that
another face ends on between its ends (a T: tied into the walls there), one in the
line of a wall beyond its end (:func:`~floorscan.floorplan.wall_pieces.in_wall_lines`:
a piece of a wall with a door between, as a door's jambs stand in one line), and one
whose line meets a face within ``door_max_m`` past its free end (a partition pointing
at the wall across its door).

Bormann et al.'s maps hold no such body (every cell a wall or free); on the real
robot maps of ROSE^2 (Luperto et al., RA-L 2022) desks against the walls part rooms
without this rule (``benchmarks/README.md``).
"""

from __future__ import annotations

import numpy as np

from floorscan.core.geometry import ray_meets_lines
from floorscan.floorplan.free_space import StructureParams
from floorscan.floorplan.wall_pieces import in_wall_lines


def object_ends(seg: np.ndarray, ends: np.ndarray, junctions: np.ndarray, free: np.ndarray, occupied: np.ndarray,
                grid, params: StructureParams = StructureParams(), max_thickness_m: float = 0.4,
                door_max_m: float = 2.0) -> np.ndarray:
    """Which faces end in an object's body (the module docstring).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces ``x0, y0, x1, y1`` after the junction snap, metres.
    ends : (F, 2) bool ndarray
        Whether each end is at a junction
        (:func:`~floorscan.floorplan.junctions.junction_ends`).
    junctions : (P, 5) float ndarray
        ``x, y, i, j, kind`` (:func:`~floorscan.floorplan.junctions.snap_junctions`).
    free, occupied : (H, W) bool ndarray
        The free space (:func:`~floorscan.floorplan.free_space.passable`) and the
        occupied cells on ``grid``.
    grid : OccupancyGrid
    params : StructureParams
        ``clutter_max_length_m``: the longest face judged; ``front_max_m``: the deepest
        object.
    max_thickness_m : float
        The thickest wall, metres.
    door_max_m : float
        The widest door, metres.

    Returns
    -------
    (F,) bool ndarray
        True: furniture.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    ends = np.asarray(ends, dtype=bool)
    out = np.zeros(len(seg), dtype=bool)
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    r = grid.resolution_m
    # a face another face ends on away from its ends (a T) is tied into the walls there
    met = np.zeros(len(seg), dtype=bool)
    tees = np.asarray(junctions, dtype=np.float64).reshape(-1, 5)
    tees = tees[tees[:, 4] == 2]
    for col in (2, 3):
        f = tees[:, col].astype(np.int64)
        met[f[np.hypot(*(seg[f].reshape(-1, 2, 2) - tees[:, None, :2]).transpose(2, 0, 1)).min(axis=1) > 0.02]] = True
    # each face's free end (the end at no junction) and its direction outward there
    e = np.where(ends[:, 0], 1, 0)
    tip = np.where(e[:, None] == 1, seg[:, 2:], seg[:, :2])
    out_u = (seg[:, 2:] - seg[:, :2]) / np.maximum(length, 1e-12)[:, None] * np.where(e == 1, 1.0, -1.0)[:, None]
    # a short face (two cells at least: a cell back from its end is still on it) held at one end
    todo = np.flatnonzero((length < params.clutter_max_length_m) & (length > 2 * r) & (ends.sum(axis=1) == 1) & ~met)
    # a body deeper than a cabinet, and a cell for the raster's rounding, ends beyond the probes
    reach = int(round(params.front_max_m / r)) + 1
    steps = np.arange(-reach, reach + 1) * r
    for i in todo.tolist():
        n = np.array([-out_u[i, 1], out_u[i, 0]])
        at_tip = _body(tip[i] - out_u[i] * r, n, steps, free, occupied, grid)  # a cell back from the end
        if at_tip is None or at_tip[0] <= max_thickness_m:
            continue
        # the object's body lies behind the face along it, not the unseen beyond a wall;
        # its inside, at its end or there, unseen
        mid = _body((seg[i, :2] + seg[i, 2:]) / 2, n, steps, free, occupied, grid)
        out[i] = mid is not None and not (at_tip[1] and mid[1])
    # a face in the line of another beyond its end (a piece of a wall, as a door's jambs
    # stand in one line) or whose line meets another face within a door's width past its
    # free end (a partition pointing at the wall across its door) is a wall
    out &= ~in_wall_lines(seg, out, r, params, door_max_m)
    for i in np.flatnonzero(out).tolist():
        out[i] = not _meets(tip[i], out_u[i], door_max_m, seg[~out], r)
    return out


def _body(at: np.ndarray, n: np.ndarray, steps: np.ndarray, free: np.ndarray, occupied: np.ndarray, grid):
    """The run of cells not seen free through ``at`` along ``n`` ((2,) unit) and back,
    probed at ``steps`` (metres, symmetric about 0): its depth (metres) and whether the
    scans saw all its cells occupied; None where ``at`` is seen free or the run reaches
    no free cell within ``steps`` (or leaves the grid)."""
    xy = at[None] + steps[:, None] * n[None]
    rows, cols, inside = grid.cells_of(xy)
    seen_free = np.zeros(len(xy), dtype=bool)
    seen_free[inside] = free[rows[inside], cols[inside]]
    mid = len(steps) // 2
    lo, hi = np.flatnonzero(seen_free[:mid]), np.flatnonzero(seen_free[mid:])
    if seen_free[mid] or not len(lo) or not len(hi) or not inside[lo[-1]: mid + hi[0] + 1].all():
        return None
    a, b = lo[-1] + 1, mid + hi[0]  # the body's cells
    return (b - a) * (steps[1] - steps[0]), bool(occupied[rows[a:b], cols[a:b]].all())


def _meets(p: np.ndarray, u: np.ndarray, reach_m: float, faces: np.ndarray, tol_m: float) -> bool:
    """Whether the ray from ``p`` along ``u`` (unit) meets one of ``faces`` (K, 4)
    within ``reach_m``, each face taken ``tol_m`` longer at both ends, metres."""
    if not len(faces):
        return False
    d = faces[:, 2:] - faces[:, :2]
    n = np.hypot(d[:, 0], d[:, 1])
    _, t, s, _ = ray_meets_lines(p, u, faces[:, :2], d / np.maximum(n, 1e-12)[:, None])
    with np.errstate(invalid="ignore"):
        return bool(((t >= 0) & (t <= reach_m) & (s >= -tol_m) & (s <= n + tol_m)).any())

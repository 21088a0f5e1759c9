"""The lines of a corridor's sides (:mod:`floorscan.floorplan.corridors`, steps 1-2):
the plan's walls grouped into lines (:func:`wall_lines`), a line joined to the line it
steps out of (:func:`stepped_lines`), the frame of a corridor between two lines
(:func:`corridor_frame`), and how much of a side is bounded along a line
(:func:`bounded`, :func:`walled`).

A corridor is the strip of space between two long parallel lines of wall (Bormann et
al., "Room segmentation: survey, implementation, and analysis", ICRA 2016); its sides
are the walls' lines, as the layouts of Luperto et al. (RA-L 2022, ROSE^2) extend the
walls into lines and cluster the collinear ones.
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.room_space import RoomRaster

#: A corridor's side is bounded along at least this share of the corridor's length:
#: its sides are walls with doors in them, more wall than opening.
SIDE_WALL_SHARE = 0.5
#: A corridor's side steps from its line by at most this, metres, and is still its
#: side: the depth of a column's face, a door's recess or a row of cabinets along it.
SIDE_STEP_M = 0.5


def wall_lines(axes: np.ndarray, thickness: np.ndarray, u: np.ndarray, length: np.ndarray,
               line_offset_m: float, raster: RoomRaster | None = None) -> list[list[int]]:
    """Walls grouped into lines (:mod:`~floorscan.floorplan.corridors`, step 1): a wall
    is on a line when both its ends lie within ``line_offset_m`` plus half the thicker
    wall of the line's longest wall; the walls of each line, its longest first (``axes``
    (N, 4) and ``thickness`` (N,) metres; ``u``, ``length``:
    :func:`~floorscan.floorplan.doors.wall_units`).

    With ``raster``, a line is also more wall than opening, as a corridor's side is: a
    wall joins it only when its walls and the stretches between them that are not space
    (within :data:`SIDE_STEP_M` of the line) cover at least :data:`SIDE_WALL_SHARE` of
    its extent with the wall. A short wall far along a line across open floor is no
    part of it."""
    ends = axes.reshape(-1, 2, 2)
    lines: list[list[int]] = []
    for i in np.argsort(-length, kind="stable"):
        if length[i] <= 0:
            continue
        for line in lines:
            a = line[0]
            n = np.array([-u[a, 1], u[a, 0]])
            off = max(thickness[a], thickness[i]) / 2 + line_offset_m
            if np.abs((ends[i] - ends[a, 0]) @ n).max() <= off and (
                    raster is None or mostly_wall(raster, ends, u[a], n, line + [int(i)])):
                line.append(int(i))
                break
        else:
            lines.append([int(i)])
    return lines


def corridor_frame(ends: np.ndarray, u_all: np.ndarray, wa: list[int], wb: np.ndarray, o: np.ndarray,
                   u: np.ndarray, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The frame of the corridor between the walls ``wa`` and ``wb``
    (:mod:`~floorscan.floorplan.corridors`, step 2): a point on the first side (its
    walls' midpoints' mean) and the mean of both sides' walls' unit directions, each
    turned as ``u`` runs and weighted by the wall's length within the common run.
    Walls fitted each a fraction of a degree off are parallel on average, as ROSE^2
    (Luperto et al., RA-L 2022) takes a cluster of parallel walls' mean direction as
    theirs; one wall's direction carried 40 m along the corridor would put the other
    side 0.3 m off its line at 0.43 degrees.

    Parameters
    ----------
    ends : (N, 2, 2) float ndarray
        The walls' ends, metres.
    u_all : (N, 2) float ndarray
        Their unit directions.
    wa, wb : sequence of int
        The walls of the two sides.
    o, u : (2,) float ndarray
        The first side's line as its longest wall gives it: a point (metres) and the
        unit direction in which ``lo`` and ``hi`` are measured.
    lo, hi : float
        The sides' common run along ``u`` from ``o``, metres.

    Returns
    -------
    origin, direction, normal : (2,) float ndarray
        Metres, and unit vectors; ``o``, ``u`` and its normal when the first side has no
        wall in the run.
    """
    walls = np.r_[np.asarray(wa, dtype=np.int64), np.asarray(wb, dtype=np.int64)]
    t = np.sort((ends[walls] - o) @ u, axis=1)
    w = np.clip(t[:, 1], lo, hi) - np.clip(t[:, 0], lo, hi)  # each wall's length within the run
    w_a = w[: len(wa)]
    if not (w_a > 0).any():
        return o, u, np.array([-u[1], u[0]])
    d = (u_all[walls] * (np.where(u_all[walls] @ u < 0, -1.0, 1.0) * w)[:, None]).sum(axis=0)  # turned as u runs
    d /= np.hypot(*d)
    origin = (ends[wa].mean(axis=1) * w_a[:, None]).sum(axis=0) / w_a.sum()
    return origin, d, np.array([-d[1], d[0]])


def mostly_wall(raster: RoomRaster, ends: np.ndarray, u: np.ndarray, n: np.ndarray, walls: list[int]) -> bool:
    """Whether the walls ``walls`` (``ends`` (N, 2, 2) metres) on the line through the
    first one's start along ``u`` (normal ``n``) and the stretches between them that
    are not space cover at least :data:`SIDE_WALL_SHARE` of their extent."""
    o = ends[walls[0], 0]
    t = np.sort((ends[walls] - o) @ u, axis=1)
    lo, hi = float(t[:, 0].min()), float(t[:, 1].max())
    step = raster.resolution_m
    along = np.arange(lo, hi, step) + step / 2
    on_wall = np.zeros(len(along), dtype=bool)
    for t0, t1 in t.tolist():
        on_wall |= (along >= t0) & (along <= t1)
    gaps = np.flatnonzero(~on_wall)
    if len(gaps):
        on_wall[gaps] = bounded(raster, o, u, n, along[gaps], -SIDE_STEP_M, SIDE_STEP_M)
    return bool(on_wall.mean() >= SIDE_WALL_SHARE) if len(along) else True


def bounded(raster: RoomRaster, o: np.ndarray, u: np.ndarray, n: np.ndarray, t: np.ndarray, a: float,
             b: float) -> np.ndarray:
    """(K,) bool: whether the band from ``a`` to ``b`` metres along ``n`` from the line
    ``o + t u`` holds a cell that is not space (a wall, an obstacle, the unseen), at
    each ``t``."""
    offs = np.arange(a, b + raster.resolution_m / 4, raster.resolution_m / 2)
    pts = o + t[:, None, None] * u + offs[None, :, None] * n
    free = raster.at(raster.space, pts.reshape(-1, 2), outside=False).reshape(len(t), len(offs))
    return ~free.all(axis=1)


def walled(side: np.ndarray, door_cells: int) -> np.ndarray:
    """``side`` ((K,) bool, :func:`bounded` along a side) with each opening of at most
    ``door_cells`` between two bounded stretches bounded too: a door is part of its
    wall."""
    out = side.copy()
    for s, e in runs(~side):
        if s > 0 and e < len(side) and e - s <= door_cells:
            out[s:e] = True
    return out


def sides_walled(side_a: np.ndarray, side_b: np.ndarray, door_cells: int) -> bool:
    """Whether both sides (:func:`bounded` along each) are bounded along at least
    :data:`SIDE_WALL_SHARE` of their length, a door of at most ``door_cells`` part of its
    wall (:func:`walled`)."""
    return min(walled(side_a, door_cells).mean(), walled(side_b, door_cells).mean()) >= SIDE_WALL_SHARE


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Half-open index runs of True in ``mask``."""
    d = np.diff(np.r_[0, mask.astype(np.int8), 0])
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist()))


def stepped_lines(lines: list[list[int]], axes: np.ndarray, u: np.ndarray, cos_par: float,
                  raster: RoomRaster) -> list[list[int]]:
    """``lines`` (:func:`wall_lines`, longest first) with each line joined to an
    earlier one that it runs on from across an opening, stepped out of its line: the
    two parallel (within ``cos_par``, a cosine), their extents along the earlier line
    not overlapping, the later line's wall ends within :data:`SIDE_STEP_M` of the
    earlier line, and the two more wall than opening together (:func:`mostly_wall`).
    A corridor's side that steps out past an opening (the next block's wall) is one
    side, as ROSE^2 (Luperto et al., RA-L 2022) clusters collinear walls into one line.

    Parameters
    ----------
    lines : list of list of int
        Wall indices per line, each line's longest wall first.
    axes : (N, 4) float ndarray
        Wall axes ``x0, y0, x1, y1``, metres.
    u : (N, 2) float ndarray
        Each wall's unit direction.
    cos_par : float
    raster : RoomRaster

    Returns
    -------
    list of list of int
        The lines, joined ones as one list (the earlier line's walls first).
    """
    ends = axes.reshape(-1, 2, 2)
    out = [list(ln) for ln in lines]
    a = 0
    while a < len(out):
        ua, oa = u[out[a][0]], ends[out[a][0], 0]
        na = np.array([-ua[1], ua[0]])
        b = a + 1
        while b < len(out):
            ta, tb = (ends[out[a]] - oa) @ ua, (ends[out[b]] - oa) @ ua
            if (abs(float(u[out[b][0]] @ ua)) >= cos_par and np.abs((ends[out[b]] - oa) @ na).max() <= SIDE_STEP_M
                    and (tb.min() >= ta.max() or ta.min() >= tb.max())
                    and mostly_wall(raster, ends, ua, na, out[a] + out[b])):
                out[a] += out.pop(b)
                continue
            b += 1
        a += 1
    return out

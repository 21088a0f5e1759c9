"""Step 1 of the global layout (:mod:`floorscan.floorplan.layout`): the wall
hypotheses of the cell complex.

The plan's wall axes, turned onto the building's dominant directions (:func:`dominant_axes`,
ROSE^2's first step: Luperto et al., RA-L 2022; a direction few walls share, a curved
wall's pieces, stays as it is), their junctions closed (:func:`snapped_axes`: ends that
nearly meet meet), and each end that meets no wall extended along its own line up to
the first wall it reaches (:func:`layout_lines`). An extension no longer than a door
(``door_max_m``) closes an opening in a wall, a door or a slit: it is evidence of a
boundary, as a wall is (:data:`CLOSED`). A longer one is a hypothesis without evidence
of its own (:data:`OPEN`): whether it divides two rooms is measured on the grid
(:mod:`floorscan.floorplan.arrangement`). The frame closes the complex.
"""

from __future__ import annotations

import numpy as np

from floorscan.core.geometry import axial_mean, ray_meets_lines

#: Coordinates are snapped to this grid before noding and polygonising
#: (:mod:`floorscan.floorplan.arrangement`), metres: far below a map cell (5 cm), far
#: above GEOS's floating-point trouble.
PRECISION_M = 1e-4

#: A wall end this close to another wall's footprint meets that wall (a junction the
#: axes do not quite reach), metres: two 5 cm cells of a map.
JUNCTION_M = 0.1
#: A direction is dominant when its walls hold this share of the walls' length ...
DOMINANT_SHARE = 0.1
#: ... counting the walls within this angle of it, radians (3 degrees: a map's walls
#: drawn by hand or fitted on a warped SLAM map scatter by a degree or two).
DIRECTION_TOLERANCE_RAD = np.deg2rad(3.0)

WALL, CLOSED, OPEN, FRAME = 0, 1, 2, 3


def layout_lines(axes: np.ndarray, thickness: np.ndarray, frame, door_max_m: float):
    """The hypotheses of the cell complex: the wall axes on the dominant directions with
    their junctions closed (:func:`dominant_axes`, :func:`snapped_axes`; the first N
    lines, in the order of ``axes``), the extensions of their free ends and the frame.

    Parameters
    ----------
    axes : (N, 4) float ndarray
        Wall axes ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Metres.
    frame : shapely.Polygon
        The box the complex fills.
    door_max_m : float
        An extension up to this long closes an opening.

    Returns
    -------
    lines : list of shapely.LineString
    kinds : list of int
        :data:`WALL`, :data:`CLOSED` (an opening closed), :data:`OPEN` (an extension
        longer than a door) or :data:`FRAME`.
    gaps : list of tuple
        Each closed opening ``(p, q, wall, width_m)``: from the wall end ``p`` to where
        the ray reaches the next wall's footprint ``q`` ((2,) float ndarrays, metres).
    """
    import shapely
    from shapely.geometry import LineString

    axes, free_end = snapped_axes(dominant_axes(axes), thickness)
    thickness = np.asarray(thickness, dtype=np.float64).reshape(-1)
    lines = [LineString([a[:2], a[2:]]) for a in axes]
    kinds = [WALL] * len(lines)
    gaps = []
    p0, p1 = axes[:, :2], axes[:, 2:]
    length = np.hypot(*(p1 - p0).T)
    dirs = (p1 - p0) / np.maximum(length, 1e-12)[:, None]
    for i in np.flatnonzero(length > 0):
        for k, (end, u) in enumerate(((p0[i], -dirs[i]), (p1[i], dirs[i]))):
            if not free_end[i, k]:
                # a junction: the wall may still go on in its line past an opening (an
                # entrance between two junctions, a door next to a corner)
                ahead = _in_line_ahead(end, u, i, p0, p1, dirs, length, thickness)
                if ahead is not None and JUNCTION_M < ahead <= door_max_m:
                    lines.append(LineString([end, end + u * ahead]))
                    kinds.append(CLOSED)
                    gaps.append((end.copy(), end + u * ahead, int(i), float(ahead)))
                continue
            stop = _first_wall(end, u, i, p0, p1, dirs, length, thickness)
            if stop is None:  # nothing ahead: open to the frame
                ray = LineString([end, end + u * 1e6])
                hit = frame.exterior.intersection(ray)
                t = min((float(np.dot(c - end, u)) for c in shapely.get_coordinates(hit)), default=0.0)
                if t > PRECISION_M:
                    lines.append(LineString([end, end + u * t]))
                    kinds.append(OPEN)
                continue
            t_axis, gap = stop
            lines.append(LineString([end, end + u * (t_axis + JUNCTION_M)]))  # past it: noded at any angle
            if gap <= door_max_m:
                kinds.append(CLOSED)
                gaps.append((end.copy(), end + u * gap, int(i), float(gap)))
            else:
                kinds.append(OPEN)
    lines.append(frame.exterior)
    kinds.append(FRAME)
    return lines, kinds, gaps


def dominant_axes(axes: np.ndarray) -> np.ndarray:
    """Wall axes turned onto the building's dominant directions (ROSE^2's first step,
    without forcing Manhattan; :func:`dominant_directions`): each wall within
    :data:`DIRECTION_TOLERANCE_RAD` of one is turned about its midpoint onto it, the
    others (a curved or oblique wall) stay.

    Parameters
    ----------
    axes : (N, 4) float ndarray
        Metres.

    Returns
    -------
    (N, 4) float64 ndarray
    """
    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4).copy()
    directions, group = dominant_directions(axes)
    d = axes[:, 2:] - axes[:, :2]
    length = np.hypot(*d.T)
    for k, mean in enumerate(directions):
        near = group == k
        u = np.array([np.cos(mean), np.sin(mean)])
        mid = (axes[near, :2] + axes[near, 2:]) / 2
        half = (length[near] / 2)[:, None] * np.sign(d[near] @ u)[:, None]
        axes[near, :2] = mid - half * u
        axes[near, 2:] = mid + half * u
    return axes


def dominant_directions(axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The building's dominant wall directions (ROSE^2's first step, Luperto et al.,
    RA-L 2022, without forcing Manhattan): the directions (mod 180 degrees) that hold
    at least :data:`DOMINANT_SHARE` of the walls' length within
    :data:`DIRECTION_TOLERANCE_RAD`, each the length-weighted mean direction of its
    walls, the strongest first.

    Parameters
    ----------
    axes : (N, 4) float ndarray
        Wall axes ``x0, y0, x1, y1``, metres.

    Returns
    -------
    directions : (D,) float64 ndarray
        Radians, counter-clockwise from +x, in (-pi/2, pi/2].
    group : (N,) int64 ndarray
        Each wall's direction (an index into ``directions``), -1 for none.
    """
    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    group = np.full(len(axes), -1, dtype=np.int64)
    if not len(axes):
        return np.zeros(0), group
    d = axes[:, 2:] - axes[:, :2]
    length = np.hypot(*d.T)
    angle = np.mod(np.arctan2(d[:, 1], d[:, 0]), np.pi)
    remaining = np.ones(len(axes), dtype=bool)
    total = length.sum()
    directions = []
    for _ in range(8):  # a few directions at most
        if not remaining.any():
            break
        diff = np.abs(np.mod(angle[remaining][:, None] - angle[remaining][None, :] + np.pi / 2, np.pi) - np.pi / 2)
        support = (diff <= DIRECTION_TOLERANCE_RAD) @ length[remaining]
        k = int(np.argmax(support))
        if support[k] < DOMINANT_SHARE * total:
            break
        idx = np.flatnonzero(remaining)
        near = idx[diff[k] <= DIRECTION_TOLERANCE_RAD]
        group[near] = len(directions)
        directions.append(axial_mean(angle[near], length[near]))  # the length-weighted mean direction
        remaining[near] = False
    return np.array(directions, dtype=np.float64), group


def snapped_axes(axes: np.ndarray, thickness: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Wall axes whose junctions meet exactly: ends within :data:`JUNCTION_M` of each
    other moved to their mean (a corner), then an end within its reach of another
    wall's footprint moved along its own line onto that wall's axis (a T).

    Parameters
    ----------
    axes : (N, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Metres.

    Returns
    -------
    axes : (N, 4) float64 ndarray
        A new array.
    free_end : (N, 2) bool ndarray
        The ends (start, end) that meet no wall.
    """
    from scipy.spatial import cKDTree

    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4).copy()
    thickness = np.asarray(thickness, dtype=np.float64).reshape(-1)
    n = len(axes)
    free_end = np.ones((n, 2), dtype=bool)
    if n == 0:
        return axes, free_end
    ends = np.r_[axes[:, :2], axes[:, 2:]]  # row r: wall r % n, end r // n
    tree = cKDTree(ends)
    done = np.zeros(2 * n, dtype=bool)
    moved = ends.copy()
    for r in range(2 * n):  # greedy, so that no chain of near ends drifts: each group within JUNCTION_M of its first end
        if done[r]:
            continue
        members, walls = [r], {r % n}
        for q in sorted(tree.query_ball_point(ends[r], JUNCTION_M)):
            if not done[q] and q % n not in walls:
                members.append(q)
                walls.add(q % n)
        if len(members) > 1:
            moved[members] = ends[members].mean(axis=0)
            for q in members:
                free_end[q % n, q // n] = False
        done[members] = True
    ends = moved
    axes = np.c_[ends[:n], ends[n:]]
    p0, p1 = axes[:, :2], axes[:, 2:]
    length = np.hypot(*(p1 - p0).T)
    dirs = (p1 - p0) / np.maximum(length, 1e-12)[:, None]
    for i in range(n):
        for k in (0, 1):
            if not free_end[i, k] or length[i] <= 0:
                continue
            end = axes[i, 2 * k:2 * k + 2]
            u = dirs[i] if k else -dirs[i]
            cross, t, s, _ = ray_meets_lines(end, u, p0, dirs)
            reach = thickness / 2 + JUNCTION_M
            with np.errstate(invalid="ignore"):
                hit = (np.abs(cross) >= 1e-6) & (np.abs(t) * np.abs(cross) <= reach) & (s >= -1e-9) & (s <= length + 1e-9)
            hit &= (np.arange(n) != i) & (length > 0)
            if hit.any():
                best = t[hit][np.argmin(np.abs(t[hit]))]
                axes[i, 2 * k:2 * k + 2] = end + u * (best + 10 * PRECISION_M)  # just past: noded after rounding
                free_end[i, k] = False
    return axes, free_end


def _in_line(end, u, i, p0, p1, dirs, length, thickness) -> tuple[np.ndarray, np.ndarray]:
    """The walls in wall ``i``'s line (parallel, within half the thicker one's thickness
    of it) and how far along ``u`` from ``end`` each one's ends lie: ``(mask (N,),
    (N, 2) metres)``."""
    cross, _, _, off = ray_meets_lines(end, u, p0, dirs)
    same = (np.abs(cross) < 1e-6) & (off <= np.maximum(thickness, thickness[i]) / 2 + PRECISION_M)
    same &= (np.arange(len(p0)) != i) & (length > 0)
    return same, np.c_[(p0 - end) @ u, (p1 - end) @ u]


def _in_line_ahead(end, u, i, p0, p1, dirs, length, thickness) -> float | None:
    """How far ahead of wall ``i``'s end ``end`` along ``u`` the nearest wall in its line
    (parallel, within half a thickness) begins, metres; None when none is ahead."""
    same, ts = _in_line(end, u, i, p0, p1, dirs, length, thickness)
    t = ts.min(axis=1)
    ahead = same & (t > 0)
    return float(t[ahead].min()) if ahead.any() else None


def _first_wall(end, u, i, p0, p1, dirs, length, thickness):
    """The first wall ahead of wall ``i``'s end ``end`` along ``u``: ``(t_axis, gap)``,
    where the ray meets that wall's axis line (metres along the ray) and the opening
    before its face; None when no wall is ahead. A wall counts when the ray meets its
    line within its footprint grown by :data:`JUNCTION_M`; a wall in the same line
    (parallel, within its half thickness) at its nearest end ahead."""
    cross, t, s, _ = ray_meets_lines(end, u, p0, dirs)
    others = (np.arange(len(p0)) != i) & (length > 0)
    reach = thickness / 2 + JUNCTION_M
    with np.errstate(invalid="ignore"):
        crossing = others & (np.abs(cross) >= 1e-6) & (t >= -JUNCTION_M) & (s >= -reach) & (s <= length + reach)
    same, ts = _in_line(end, u, i, p0, p1, dirs, length, thickness)
    same &= (ts.max(axis=1) >= 0) & (ts.min(axis=1) >= -JUNCTION_M)
    cand_t = np.full(len(p0), np.inf)
    cand_gap = np.zeros(len(p0))
    cand_t[crossing] = t[crossing]
    face = thickness[crossing] / 2 / np.abs(cross[crossing])  # from the axis back to the face, along the ray
    cand_gap[crossing] = np.maximum(t[crossing] - face, 0.0)
    cand_t[same] = np.maximum(ts[same].min(axis=1), 0.0)
    cand_gap[same] = cand_t[same]
    if not np.isfinite(cand_t).any():
        return None
    j = int(np.argmin(cand_t))
    return float(cand_t[j]), float(cand_gap[j])

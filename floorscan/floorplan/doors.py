"""Doors of a floor plan: openings in the line of a wall, 0.6 to 2.0 m wide
(``floorplan.rooms.door_min_m``, ``door_max_m``), through which the free space of
two rooms meets (:mod:`floorscan.floorplan.rooms`).

Two ways to find one, both in the wall's line, as a plan drawn by people shows a door:

- :func:`wall_gaps`: the gap between the facing ends of two collinear walls (their
  directions within ``door_angle_deg``, each end within half the thicker wall plus
  ``jamb_m`` of the other's line) when the scans saw free space in it and on both of
  its sides. The rooms are cut along these before they are segmented, so a room seen
  only through its door (a fan of rays) ends at the door.
- where two regions of the segmentation meet between jambs (both ends of the contact
  within ``jamb_m`` of a wall or a seen obstacle, but of no object standing free in
  the room, :func:`~floorscan.floorplan.jambs.jamb_cells`; not from a wall's face to
  an object, :func:`~floorscan.floorplan.jambs.face_to_object`), ``door_min_m``
  to ``door_max_m`` wide, and the persistence of
  :mod:`floorscan.floorplan.persistence` keeps the two regions apart: the door is
  :func:`contact_door` when it lies in the line of a wall whose end is within
  ``jamb_m`` of one of its ends (the opening runs from that end to the other jamb, on
  the line), else :func:`free_door`, the contact as it is (unless it narrows a
  corridor by less than a quarter,
  :func:`~floorscan.floorplan.narrowings.corridor_narrowings`).

A door is kept only when the rooms on its two sides differ.
Source: the door criterion of ipa_room_segmentation's Voronoi segmentation (Bormann et
al., ICRA 2016: a room boundary is a narrow passage between two wall points), here
restricted to openings in a plan wall's line.
"""

from __future__ import annotations

import numpy as np

from floorscan.core.geometry import point_segment_dist2
from floorscan.floorplan.room_space import RoomParams, RoomRaster


def wall_units(axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each wall's unit direction, (N, 2), and length, (N,) metres, of axes ``x0, y0, x1,
    y1`` (N, 4) in metres."""
    d = axes[:, 2:] - axes[:, :2]
    length = np.hypot(d[:, 0], d[:, 1])
    return d / np.maximum(length, 1e-12)[:, None], length


def wall_gaps(axes: np.ndarray, thickness: np.ndarray, params: RoomParams,
              corners: bool = False) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """Door candidates between the facing ends of collinear walls.

    Parameters
    ----------
    axes : (N, 4) float ndarray
        Wall axes ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Metres.
    params : RoomParams
    corners : bool
        False: the gaps between two free ends (an end in an L or T junction is a
        corner, not a jamb). True: the gaps between two corners instead (the mouth of
        a corridor or room whose side walls meet the wall it opens in).

    Returns
    -------
    list of (p, q, wall)
        The opening from ``p`` to ``q`` ((2,) metres, on the line of wall ``wall``,
        the longer of the two), ``door_min_m <= |q - p| <= door_max_m``.
    """
    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    u, length = wall_units(axes)
    cos_max = np.cos(np.radians(params.door_angle_deg))
    ends = axes.reshape(-1, 2, 2)
    out = []
    for i in range(len(axes)):
        for j in range(i + 1, len(axes)):
            if abs(float(u[i] @ u[j])) < cos_max:
                continue
            a, b = (i, j) if length[i] >= length[j] else (j, i)
            n = np.array([-u[a, 1], u[a, 0]])
            off = max(thickness[a], thickness[b]) / 2 + params.line_offset_m
            if np.abs((ends[b] - ends[a, 0]) @ n).max() > off:
                continue
            ta = (ends[a] - ends[a, 0]) @ u[a]
            tb = (ends[b] - ends[a, 0]) @ u[a]
            if tb.min() >= ta.max():  # a's end ka faces b's end kb
                ka, kb = int(np.argmax(ta)), int(np.argmin(tb))
                gap = (ta.max(), tb.min())
            elif tb.max() <= ta.min():
                ka, kb = int(np.argmin(ta)), int(np.argmax(tb))
                gap = (tb.max(), ta.min())
            else:
                continue
            # an end in an L or T junction is a corner, not a jamb: both ends jambs, or
            # with ``corners`` both corners
            if junction_end(axes, thickness, a, ka) != corners or junction_end(axes, thickness, b, kb) != corners:
                continue
            width = gap[1] - gap[0]
            if params.door_min_m <= width <= params.door_max_m:
                p = ends[a, 0] + u[a] * gap[0]
                q = ends[a, 0] + u[a] * gap[1]
                out.append((p, q, a))
    return out


def passes_through(raster: RoomRaster, p: np.ndarray, q: np.ndarray, side_m: float = 0.3,
                   outward: bool = False) -> bool:  # fmt: skip
    """Whether the space holds the middle of the opening ``p``-``q`` and points
    ``side_m`` to each side of it; with ``outward`` also an opening in the building's
    outline: the space holds its middle and the point on one side, and the point on the
    other side lies beyond the building's closed outline (:attr:`RoomRaster.beyond`) or
    off the raster (an entrance, whatever the scans saw through it).

    Parameters
    ----------
    raster : RoomRaster
    p, q : (2,) float ndarray
        The opening's ends, metres.
    side_m : float
        Metres.
    outward : bool
        Also take an opening in the building's outline (above).

    Returns
    -------
    bool
        False when a point is off the raster (but for the outside point of ``outward``).
    """
    mid = (p + q) / 2
    d = q - p
    n = np.array([-d[1], d[0]]) / max(float(np.hypot(*d)), 1e-12)
    pts = np.array([mid, mid + side_m * n, mid - side_m * n])
    inside = raster.at(raster.space, pts, outside=False)
    if inside.all() or not outward or raster.beyond is None:
        return bool(inside.all())
    beyond = raster.at(raster.beyond, pts, outside=True)
    return bool(inside[0] and ((inside[1] and beyond[2]) or (inside[2] and beyond[1])))


def barrier_cells(raster: RoomRaster, p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of an 8-connected line of cells from ``p`` to ``q``, one cell
    longer at each end (it closes the opening to the 4-connected space); scikit-image's
    ``draw.line``.

    Parameters
    ----------
    raster : RoomRaster
    p, q : (2,) float ndarray
        Metres.

    Returns
    -------
    rows, cols : (K,) int ndarray
        Cells on the raster only.
    """
    from skimage.draw import line

    d = q - p
    e = d / max(float(np.hypot(*d)), 1e-12) * raster.resolution_m
    a = np.floor((p - e - raster.origin_xy) / raster.resolution_m).astype(np.int64)
    b = np.floor((q + e - raster.origin_xy) / raster.resolution_m).astype(np.int64)
    rr, cc = line(a[1], a[0], b[1], b[0])
    h, w = raster.space.shape
    ok = (rr >= 0) & (cc >= 0) & (rr < h) & (cc < w)
    return rr[ok], cc[ok]


def contacts(labels: np.ndarray) -> dict[tuple[int, int], list[np.ndarray]]:
    """Where regions touch: for each pair ``(a, b)``, ``a < b``, the places they touch
    (a door and, elsewhere, a missing stretch of wall between the same two regions are
    two places).

    Parameters
    ----------
    labels : (H, W) int ndarray
        Regions 1..R, 0 for none.

    Returns
    -------
    dict of (int, int) to list of (K, 2) float64 ndarray
        Per place, the row, column midpoints (cell units) of the 4-neighbour cell pairs
        of ``a`` and ``b`` that are next to each other; pairs in ascending order.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    out: dict[tuple[int, int], list] = {}
    for axis in (0, 1):
        a = labels[:-1, :] if axis == 0 else labels[:, :-1]
        b = labels[1:, :] if axis == 0 else labels[:, 1:]
        m = (a != b) & (a > 0) & (b > 0)
        if not m.any():
            continue
        rr, cc = np.nonzero(m)
        mid = np.column_stack([rr + (0.5 if axis == 0 else 0.0), cc + (0.5 if axis == 1 else 0.0)])
        lo, hi = np.minimum(a[m], b[m]), np.maximum(a[m], b[m])
        key = lo.astype(np.int64) * (int(labels.max()) + 1) + hi
        order = np.argsort(key, kind="stable")
        key, mid, lo, hi = key[order], mid[order], lo[order], hi[order]
        starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
        for s, e in zip(starts, np.r_[starts[1:], len(key)]):
            out.setdefault((int(lo[s]), int(hi[s])), []).append(mid[s:e])
    pieces: dict[tuple[int, int], list[np.ndarray]] = {}
    for pair, parts in sorted(out.items()):
        pts = np.concatenate(parts)
        ij = cKDTree(pts).query_pairs(1.01, output_type="ndarray")
        graph = coo_matrix((np.ones(len(ij)), (ij[:, 0], ij[:, 1])), shape=(len(pts), len(pts)))
        n, comp = connected_components(graph, directed=False)
        pieces[pair] = [pts[comp == k] for k in range(n)]
    return pieces


def contact_segment(raster: RoomRaster, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The contact of two regions as a segment: the extent of its cell midpoints
    along their principal direction (SVD), half a cell longer at each end.

    Parameters
    ----------
    raster : RoomRaster
    cells : (K, 2) float ndarray
        Row, column midpoints (cell units), from :func:`contacts`.

    Returns
    -------
    p, q : (2,) float64 ndarray
        Map metres.
    """
    xy = (cells[:, ::-1] + 0.5) * raster.resolution_m + raster.origin_xy
    c = xy.mean(axis=0)
    if len(xy) > 1:
        _, _, vt = np.linalg.svd(xy - c, full_matrices=False)
        v = vt[0]
    else:
        v = np.array([1.0, 0.0])
    t = (xy - c) @ v
    h = raster.resolution_m / 2
    return c + v * (t.min() - h), c + v * (t.max() + h)


def junction_end(axes: np.ndarray, thickness: np.ndarray, i: int, k: int, tol_m: float = 0.05) -> bool:
    """Whether end ``k`` of wall ``i`` meets another wall: lies within the two half
    thicknesses and ``tol_m`` of its axis (an L or T junction).

    Parameters
    ----------
    axes : (N, 4) float ndarray
        Wall axes ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Metres.
    i : int
        The wall.
    k : {0, 1}
        Its start or end.
    tol_m : float
        Metres.

    Returns
    -------
    bool
        False when there is no other wall.
    """
    others = np.delete(np.asarray(axes, dtype=np.float64).reshape(-1, 4), i, axis=0)
    if not len(others):
        return False
    end = axes[i, 2 * k : 2 * k + 2]
    gap = footprint_distance(end, others, np.delete(thickness, i))
    return bool(gap.min() <= thickness[i] / 2 + tol_m)


def near_walls(p: np.ndarray, axes: np.ndarray, thickness: np.ndarray, within_m: float) -> bool:
    """Whether the point ``p`` lies within ``within_m`` of a wall's footprint.

    Parameters
    ----------
    p : (2,) float ndarray
        Metres.
    axes : (N, 4) float ndarray
        Wall axes, metres.
    thickness : (N,) float ndarray
        Metres.
    within_m : float
        Metres.

    Returns
    -------
    bool
        False without walls.
    """
    if not len(axes):
        return False
    return bool(footprint_distance(p, axes, thickness).min() <= within_m)


def footprint_distance(p: np.ndarray, axes: np.ndarray, thickness: np.ndarray) -> np.ndarray:
    """(N,) float64: metres from the point ``p`` ((2,) metres) to each wall's footprint,
    its axis (``axes`` (N, 4) metres) less half its thickness (``thickness`` (N,)
    metres); negative inside the footprint."""
    return np.sqrt(point_segment_dist2(p[0], p[1], axes)) - thickness / 2


def contact_door(
    p: np.ndarray, q: np.ndarray, axes: np.ndarray, thickness: np.ndarray, params: RoomParams
) -> tuple[np.ndarray, np.ndarray, int] | None:
    """The door in a wall's line a contact ``p``-``q`` ((2,) metres) between two rooms
    is, or None (module docstring).

    Parameters
    ----------
    p, q : (2,) float ndarray
        The contact's ends, metres.
    axes : (N, 4) float ndarray
        Wall axes, metres.
    thickness : (N,) float ndarray
        Metres.
    params : RoomParams
        ``door_min_m``, ``door_max_m``, ``jamb_m``, ``door_angle_deg``.

    Returns
    -------
    (p, q, wall) or None
        The opening in the line of wall ``wall``: from that wall's end to the other
        jamb's projection on its line, metres.
    """
    if not len(axes):
        return None
    u, _ = wall_units(axes)
    d = q - p
    width = float(np.hypot(*d))
    if not params.door_min_m <= width <= params.door_max_m:
        return None  # a slit, or a passage wider than a door
    if not (near_walls(p, axes, thickness, params.jamb_m) and near_walls(q, axes, thickness, params.jamb_m)):
        return None  # a jamb is missing: the contact ends in open or unseen space
    v = d / width
    mid = (p + q) / 2
    cos_max = np.cos(np.radians(params.door_angle_deg))
    ends = axes.reshape(-1, 2, 2)
    best = None
    for i in np.flatnonzero(np.abs(u @ v) >= cos_max):
        n = np.array([-u[i, 1], u[i, 0]])
        if abs(float((mid - ends[i, 0]) @ n)) > thickness[i] / 2 + params.jamb_m:
            continue
        for k in (0, 1):
            end, away = ends[i, k], ends[i, 1 - k]
            g = (end - away) / max(float(np.hypot(*(end - away))), 1e-12)  # from the wall into the gap
            tp, tq = (p - end) @ g, (q - end) @ g
            t_near, t_far = min(tp, tq), max(tp, tq)
            if not (-params.jamb_m <= t_near <= params.jamb_m and params.door_min_m <= t_far <= params.door_max_m):
                continue
            if best is None or abs(t_near) < best[0]:
                best = (abs(t_near), (end.copy(), end + g * t_far, int(i)))  # to the far jamb, on the line
    return None if best is None else best[1]


def free_door(p: np.ndarray, q: np.ndarray, axes: np.ndarray) -> tuple[np.ndarray, np.ndarray, int] | None:
    """A door where two rooms meet between jambs out of any wall's line (a door between
    a wall's end and a cupboard, or beside a wall the plan lacks): the contact
    ``p``-``q`` ((2,) metres) as it is, in the nearest wall's name; None without walls.

    Returns
    -------
    (p, q, wall) or None
    """
    if not len(axes):
        return None
    m = (p + q) / 2
    return p.copy(), q.copy(), int(np.argmin(point_segment_dist2(m[0], m[1], axes)))


def distinct_doors(doors: list) -> list:
    """One door per opening: of doors ``(p, q, wall, room_a, room_b)`` (``p``, ``q`` (2,)
    metres) between the same rooms whose centres lie within half a metre, the first (the
    room step lists the contacts before the gaps between walls, so a contact found twice
    is kept as its contact)."""
    out: list = []
    for d in doors:
        c = (d[0] + d[1]) / 2
        if any(o[3:] == d[3:] and np.hypot(*((o[0] + o[1]) / 2 - c)) < 0.5 for o in out):
            continue
        out.append(d)
    return out


def distinct_gaps(gaps: list, reach_m: float) -> list:
    """One cut per opening: of the lines ``(p, q, wall)`` (``p``, ``q`` (2,) metres) that
    bound rooms and run along each other, within ``reach_m`` of each other end for end
    (their Hausdorff distance: the same opening found between two walls' ends, as a
    room's open side and on a corridor side's line), the shortest, in the place of the
    first: an opening's width is its narrowest line from jamb to jamb. Two cuts a cell
    or two apart would leave a sliver of space between them, no room, and neither would
    find the rooms on its two sides."""
    import shapely

    out: list = []
    lines: list = []
    for g in gaps:
        line = shapely.LineString([g[0], g[1]])
        same = [k for k, o in enumerate(lines) if shapely.hausdorff_distance(line, o) <= reach_m]
        if not same:
            out.append(g)
            lines.append(line)
        elif line.length < lines[same[0]].length:
            out[same[0]], lines[same[0]] = g, line
    return out

"""Walls that meet and one wall per wall, the structure passes' geometry: ends snapped
into L, T and X junctions (:func:`snap_junctions`), near-parallel duplicates merged
(:func:`merge_parallel_duplicates`), short loose pieces found (:func:`short_loose`).
Sources: the topology of CAD wall graphs (walls meet at their ends or along another);
the tolerances are ours (:class:`~floorscan.floorplan.free_space.StructureParams`).
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.candidates import angle_diff, axial_angle, candidate_pairs
from floorscan.floorplan.free_space import StructureParams


def snap_junctions(seg: np.ndarray, params: StructureParams = StructureParams(), trim_shallow: bool = False):
    """Step 3: ends moved onto the lines of the faces they meet (L, T and X junctions).

    Every end of a face is tested against the faces within ``snap_m`` of it whose
    direction differs by at least ``junction_min_angle_deg``: the point ``X`` where the
    two lines cross is a junction when it lies within ``snap_m`` of the end and within
    the other face extended by ``snap_m``; the end moves to the nearest such ``X``
    (trimming an overshoot, extending a short end). All moves are computed on the
    input, then applied, so an L corner's two ends meet at one point. With
    ``trim_shallow`` (the wall axes), axes that cross at a shallow angle (overlapping
    pieces of a curved wall) are then trimmed to meet where they cross.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces or wall axes, metres.
    params : StructureParams
    trim_shallow : bool

    Returns
    -------
    snapped : (F, 4) float64 ndarray
        Metres.
    junctions : (P, 5) float64 ndarray
        ``x, y, i, j, kind`` of each junction of faces ``i < j``: kind 1 an L (at an end
        of both), 2 a T (an end of one on the other), 3 an X (the two cross away from
        their ends), after the moves.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    out = seg.copy()
    if len(seg) < 2:
        return out, np.empty((0, 5))
    i, j = candidate_pairs(seg, params.snap_m)
    ang = axial_angle(seg)
    ok = angle_diff(ang[i], ang[j]) >= np.radians(params.junction_min_angle_deg)
    i, j = np.r_[i[ok], j[ok]], np.r_[j[ok], i[ok]]  # both directions: the end of i on j
    if len(i) == 0:
        if trim_shallow:
            _trim_shallow_crossings(out, params)
        return out, _junctions(out, params)
    x = line_crossings(seg[i], seg[j])
    lj = np.hypot(seg[j, 2] - seg[j, 0], seg[j, 3] - seg[j, 1])
    uj = (seg[j, 2:] - seg[j, :2]) / np.maximum(lj, 1e-12)[:, None]
    tj = np.einsum("ij,ij->i", x - seg[j, :2], uj)
    on_j = (tj >= -params.snap_m) & (tj <= lj + params.snap_m)
    li = np.hypot(seg[i, 2] - seg[i, 0], seg[i, 3] - seg[i, 1])
    best = np.full((len(seg), 2), np.inf)
    target = np.zeros((len(seg), 2, 2))
    for end in (0, 1):
        e = seg[i, 2 * end : 2 * end + 2]
        other = seg[i, 2 - 2 * end : 4 - 2 * end]
        dist = np.hypot(x[:, 0] - e[:, 0], x[:, 1] - e[:, 1])
        # the end may not cross over its own face's other end
        keeps_length = np.hypot(x[:, 0] - other[:, 0], x[:, 1] - other[:, 1]) >= 0.5 * li
        good = on_j & keeps_length & (dist <= params.snap_m) & np.isfinite(dist)
        for k in np.flatnonzero(good)[np.argsort(dist[good], kind="stable")][::-1].tolist():
            if dist[k] <= best[i[k], end]:
                best[i[k], end] = dist[k]
                target[i[k], end] = x[k]
    moved = np.isfinite(best)
    for end in (0, 1):
        out[moved[:, end], 2 * end : 2 * end + 2] = target[moved[:, end], end]
    if trim_shallow:
        _trim_shallow_crossings(out, params)
    return out, _junctions(out, params)


def _trim_shallow_crossings(seg: np.ndarray, params: StructureParams) -> None:
    """Two faces that cross at less than ``junction_min_angle_deg`` (consecutive pieces
    of a curved wall that overlap) are trimmed, in place, to meet at the crossing: each
    one's end nearer to it moves there when that end lies within half the face's length."""
    import shapely

    if len(seg) < 2:
        return
    lines = shapely.linestrings(seg.reshape(-1, 2, 2))
    i, j = shapely.STRtree(lines).query(lines, predicate="crosses")
    keep = i < j
    i, j = i[keep], j[keep]
    ang = axial_angle(seg)
    shallow = angle_diff(ang[i], ang[j]) < np.radians(params.junction_min_angle_deg)
    for a, b in zip(i[shallow].tolist(), j[shallow].tolist()):
        x = line_crossings(seg[[a]], seg[[b]])[0]
        if not np.isfinite(x).all():
            continue
        for k in (a, b):
            d = np.hypot(*(seg[k].reshape(2, 2) - x).T)
            end = int(np.argmin(d))
            if d[end] <= 0.5 * np.hypot(*(seg[k, 2:] - seg[k, :2])):
                seg[k, 2 * end : 2 * end + 2] = x


def line_crossings(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Where the lines of the matching segments of ``a`` and ``b`` (P, 4) cross, (P, 2)
    metres; NaN for parallel lines."""
    da, db = a[:, 2:] - a[:, :2], b[:, 2:] - b[:, :2]
    den = da[:, 0] * db[:, 1] - da[:, 1] * db[:, 0]
    w = b[:, :2] - a[:, :2]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = (w[:, 0] * db[:, 1] - w[:, 1] * db[:, 0]) / den
        x = a[:, :2] + da * t[:, None]
    x[np.abs(den) < 1e-12] = np.nan
    return x


def _junctions(seg: np.ndarray, params: StructureParams) -> np.ndarray:
    """The junctions of snapped segments (see :func:`snap_junctions`)."""
    tol = 1e-6 + 0.01
    i, j = candidate_pairs(seg, tol)
    ang = axial_angle(seg)
    ok = angle_diff(ang[i], ang[j]) >= np.radians(params.junction_min_angle_deg) * 0.5
    i, j = i[ok], j[ok]
    if len(i) == 0:
        return np.empty((0, 5))
    x = line_crossings(seg[i], seg[j])
    near_end = []
    for s in (i, j):
        d0 = np.hypot(*(x - seg[s, :2]).T)
        d1 = np.hypot(*(x - seg[s, 2:]).T)
        near_end.append(np.minimum(d0, d1) <= tol)
    kind = np.where(near_end[0] & near_end[1], 1, np.where(near_end[0] | near_end[1], 2, 3))
    good = np.isfinite(x).all(axis=1)
    return np.column_stack([x[good], i[good], j[good], kind[good]]).astype(np.float64)


def in_line_pairs(seg: np.ndarray, reach_m: float, offset_m: float, angle_rad: float, cell_m: float,
                  wall_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Pairs of segments within ``reach_m`` of each other whose shorter lies in the
    longer's line: both its ends within ``offset_m`` of that line, its direction within
    ``angle_rad`` of it or, beside a segment at least ``wall_m`` long, within the
    direction a short segment fitted on cells of ``cell_m`` is known to, a cell at each
    end (``atan(2 cell_m / length)``: a 0.5 m piece of a wall fitted on 5 cm cells
    turns by up to 11 degrees from its line).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    reach_m, offset_m, cell_m, wall_m : float
        Metres.
    angle_rad : float
        Radians.

    Returns
    -------
    i, j : (P,) int64 ndarray
        The pairs (``i < j``).
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    i, j = candidate_pairs(seg, reach_m)
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    shorter, longer = np.minimum(length[i], length[j]), np.maximum(length[i], length[j])
    known = np.where(longer >= wall_m, np.maximum(angle_rad, np.arctan2(2 * cell_m, shorter)), angle_rad)
    axial = axial_angle(seg)
    turn = angle_diff(axial[i], axial[j])
    keep = (turn <= known) & (np.abs(shorter_on_longer(seg, i, j)[4]).max(axis=1) <= offset_m)
    return i[keep], j[keep]


def shorter_on_longer(seg: np.ndarray, i: np.ndarray, j: np.ndarray):
    """The ends of the shorter of each pair of segments ``(i, j)`` in the frame of the
    longer one's line.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    i, j : (P,) int ndarray
        Pairs of segments.

    Returns
    -------
    length : (F,) float64 ndarray
        Every segment's length, metres.
    a, b : (P,) int64 ndarray
        The longer and the shorter of each pair.
    t, off : (P, 2) float64 ndarray
        The shorter's two ends along the longer's line from its start, and across it
        (signed, left positive), metres.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    a = np.where(length[i] >= length[j], i, j)
    b = np.where(length[i] >= length[j], j, i)
    t, off = ends_on_line(seg, a, b)
    return length, a, b, t, off


def ends_on_line(seg: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The ends of segments ``b`` in the frame of the lines of segments ``a``.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    a, b : (P,) int ndarray
        Pairs of segments.

    Returns
    -------
    t, off : (P, 2) float64 ndarray
        ``b``'s two ends along ``a``'s line from its start, and across it (signed, left
        of ``x0, y0 -> x1, y1`` positive), metres.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    d = seg[a, 2:] - seg[a, :2]
    u = d / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)[:, None]
    nrm = np.column_stack([-u[:, 1], u[:, 0]])
    rel = [seg[b, k : k + 2] - seg[a, :2] for k in (0, 2)]
    t = np.column_stack([np.einsum("ij,ij->i", r, u) for r in rel])
    off = np.column_stack([np.einsum("ij,ij->i", r, nrm) for r in rel])
    return t, off


def merge_parallel_duplicates(axes: np.ndarray, thickness: np.ndarray, params: StructureParams = StructureParams(),
                              max_distance_m: float = 0.4):  # fmt: skip
    """One wall per wall: near-parallel walls that lie on each other, whatever their
    length, merged into one (duplicate lines a fit left across a thin wall's two faces,
    a skewed copy of a wall).

    Two wall axes are duplicates when their directions differ by at most
    ``duplicate_angle_deg`` and both ends of the shorter lie within ``max_distance_m``
    (the thickest wall, ``floorplan.pair_max_m``) of the longer's axis, between its ends
    (give or take ``max_distance_m``). Groups of duplicates (connected components)
    become one axis: the length-weighted mean line over the extent of all ends; its
    thickness the largest of theirs.

    Parameters
    ----------
    axes : (W, 4) float ndarray
        Wall axes, metres.
    thickness : (W,) float ndarray
        Metres.
    params : StructureParams
    max_distance_m : float

    Returns
    -------
    merged : (M, 4) float64 ndarray
    merged_thickness : (M,) float64 ndarray
    group : (W,) int64 ndarray
        The merged wall of each input wall.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    thickness = np.asarray(thickness, dtype=np.float64).ravel()
    n = len(axes)
    if n < 2:
        return axes.copy(), thickness.copy(), np.arange(n)
    i, j = candidate_pairs(axes, max_distance_m, np.radians(params.duplicate_angle_deg))
    length, a, b, t, off = shorter_on_longer(axes, i, j)
    ok = (
        (np.abs(off) <= max_distance_m).all(axis=1) & (t >= -max_distance_m).all(axis=1)
        & (t <= length[a, None] + max_distance_m).all(axis=1)
    )  # fmt: skip
    graph = coo_matrix((np.ones(int(ok.sum())), (a[ok], b[ok])), shape=(n, n))
    n_groups, group = connected_components(graph, directed=False)
    merged = np.empty((n_groups, 4))
    merged_thickness = np.zeros(n_groups)
    np.maximum.at(merged_thickness, group, thickness)
    for g in range(n_groups):
        members = np.flatnonzero(group == g)
        longest = axes[members[np.argmax(length[members])]]
        u = (longest[2:] - longest[:2]) / max(float(np.hypot(*(longest[2:] - longest[:2]))), 1e-12)
        t = (axes[members].reshape(-1, 2) - longest[:2]) @ u
        merged[g] = np.r_[longest[:2] + t.min() * u, longest[:2] + t.max() * u]
    return merged, merged_thickness, group.astype(np.int64)


def short_loose(seg: np.ndarray, junctions: np.ndarray, min_length: float) -> np.ndarray:
    """Faces shorter than ``min_length`` without a junction at both ends (a short face
    that connects two walls is a wall), or between two walls that meet each other within
    ``min_length`` of its middle (a chord across their corner: the corner's cells traced
    on a slant).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    junctions : (J, 5) float ndarray
        ``x, y, i, j, kind`` (:func:`snap_junctions`); an end of face ``i`` or ``j``
        within 0.02 m of its junction's ``x, y`` (metres) has one.
    min_length : float
        Metres.

    Returns
    -------
    (F,) bool ndarray
    """
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    short = length < min_length
    loose = short & ~junction_ends(seg, junctions).all(axis=1)
    # a short face between two walls that meet each other beside it is a chord across
    # their corner (the corner's own cells, traced on a slant)
    meet: dict[tuple[int, int], np.ndarray] = {}
    partners: dict[int, set[int]] = {}
    for x, y, i, j in junctions[:, :4]:
        i, j = sorted((int(i), int(j)))
        meet[(i, j)] = np.array([x, y])
        partners.setdefault(i, set()).add(j)
        partners.setdefault(j, set()).add(i)
    for f in np.flatnonzero(short & ~loose):
        mid = (seg[f, :2] + seg[f, 2:]) / 2
        others = sorted(partners.get(int(f), set()))
        loose[f] = any((a, b) in meet and np.hypot(*(meet[(a, b)] - mid)) <= min_length
                       for a in others for b in others if a < b)
    return loose


def junction_ends(seg: np.ndarray, junctions: np.ndarray) -> np.ndarray:
    """Which ends of each face are at a junction: an end of face ``i`` or ``j`` within
    0.02 m of its junction's ``x, y``.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    junctions : (J, 5) float ndarray
        ``x, y, i, j, kind`` (:func:`snap_junctions`), metres.

    Returns
    -------
    (F, 2) bool ndarray
        The ``x0, y0`` end, the ``x1, y1`` end.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    ends = np.zeros((len(seg), 2), dtype=bool)
    for col in (2, 3):
        ids = junctions[:, col].astype(np.int64)
        for end in (0, 1):
            at = np.hypot(*(junctions[:, :2] - seg[ids, 2 * end : 2 * end + 2]).T) <= 0.02
            ends[ids[at], end] = True
    return ends

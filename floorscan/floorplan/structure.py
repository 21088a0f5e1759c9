"""The floor plan's structure passes: walls, not furniture; one wall per wall; walls
that meet. They run on the merged faces of a plan when the free space of its scans is
known (an :class:`~floorscan.core.occupancy.OccupancyGrid` of the same scans), in this
order (:func:`structure_passes`):

1. **Structure or clutter** (:func:`border_and_support`). A wall is a boundary of the
   free space seen from more than one position: a face is structure when the cells
   beside it on at least one side are free space (the rover's rays passed there,
   :func:`passable`) over ``min_free_side`` of its length, and its own cells are
   occupied (its returns outweigh the rays of other scans through them: a person
   walking by is seen through by the next scan), and it does not have returns on both
   sides at once ``side_offset_m`` and twice that away (a line through the inside of an
   object, such as a table top in a 3D scanner's height band). Lines through the inside of a piece of furniture (a
   table top in a 3D scanner's height band) and single-scan returns fail it.
2. **Joins** (:func:`join_collinear`). Collinear faces (``join_angle_deg``,
   ``join_offset_m``) less than ``join_max_gap_m`` apart are one face when the rover's
   free space does not pass through the gap: the gap holds no run of free cells
   ``min_opening_m`` long on the faces' line. A gap that free space passes through is an
   opening (a door, a passage) and is kept; an unseen or occluded gap is joined.
3. **Junctions** (:func:`snap_junctions`). An end within ``snap_m`` of where its line
   meets another face's line (at least ``junction_min_angle_deg`` apart) moves there:
   overshoots are trimmed, short ends extended, so faces meet in L, T and X junctions.
4. **Clutter** (:func:`free_standing_objects`). The returns that are not on a long
   face (``clutter_max_length_m``) fall apart into objects; an object smaller than
   ``clutter_max_length_m`` that the free space surrounds (a chair, a desk, a shelf, a
   table top in a 3D scanner's height band) is furniture, and the faces on it are
   clutter. A face shorter than ``min_wall_length_m`` is clutter unless it connects
   two junctions.
5. **In front of a wall** (:func:`in_front_of_walls`). A face shorter than
   ``clutter_max_length_m`` parallel to a long wall face, ``front_min_m`` to
   ``front_max_m`` in front of it on its free side, is the front of a desk, a cabinet
   or a shelf standing against the wall: clutter.

The rule of step 1 and 4 is the issue's (walls are the boundaries of the free space,
long enough and seen from more than one position; short pieces standing inside free
space are furniture), in the sense of the occupancy-grid room and wall work of
Bormann et al., "Room segmentation: survey, implementation, and analysis", ICRA 2016
(free space is what the robot saw, walls bound it); the thresholds are ours. Source of
the duplicate problem it completes: thesis section 5.1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from floorscan.core.config import schema_defaults
from floorscan.core.occupancy import OccupancyGrid
from floorscan.floorplan.candidates import _angle_diff, _axial_angle, _candidate_pairs


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


def passable(grid: OccupancyGrid) -> np.ndarray:
    """(H, W) bool: cells the scans' rays crossed more often than they hit them (the
    free space the rover saw; one ray through a doorway makes it passable, where the
    map_server threshold needs four)."""
    return (grid.n_miss_scans > grid.n_hit_scans) & (grid.n_miss_scans > 0)


def _lookup(grid: OccupancyGrid, mask: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """``mask`` at the cells of points ``xy`` (N, 2); False outside the grid."""
    rows, cols, inside = grid.cells_of(xy)
    out = np.zeros(len(xy), dtype=bool)
    out[inside] = mask[rows[inside], cols[inside]]
    return out


def _samples(seg: np.ndarray, step: float, trim: float = 0.0):
    """Points every ``step`` along each segment (ends trimmed by ``trim`` when the
    segment is long enough), their segment and the segment's unit normal."""
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


def border_and_support(seg: np.ndarray, grid: OccupancyGrid, params: StructureParams = StructureParams()):
    """Step 1: which faces border free space and lie on occupied cells (over half
    their length).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces ``x0, y0, x1, y1``, metres.
    grid : OccupancyGrid
        The free space of the plan's scans.
    params : StructureParams

    Returns
    -------
    structure : (F,) bool ndarray
    free_side : (F,) int8 ndarray
        +1 when the free space lies left of the face (direction x0, y0 -> x1, y1),
        -1 right, 0 both sides or neither.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    if len(seg) == 0:
        return np.zeros(0, bool), np.zeros(0, np.int8)
    free = passable(grid)
    pts, owner, normal = _samples(seg, grid.resolution_m, trim=params.side_offset_m)
    off = params.side_offset_m * normal[owner]
    count = np.bincount(owner, minlength=len(seg)).astype(np.float64)
    left = np.bincount(owner, weights=_lookup(grid, free, pts + off), minlength=len(seg)) / count
    right = np.bincount(owner, weights=_lookup(grid, free, pts - off), minlength=len(seg)) / count
    occupied_cells = grid.occupied()
    on = np.zeros(len(pts), dtype=bool)
    rows, cols, inside = grid.cells_of(pts)
    for dr in (-1, 0, 1):  # the face's own cell or a neighbour (the face lies on a cell edge)
        for dc in (-1, 0, 1):
            r, c = np.clip(rows + dr, 0, grid.shape[0] - 1), np.clip(cols + dc, 0, grid.shape[1] - 1)
            on |= inside & occupied_cells[r, c]
    seen = np.bincount(owner, weights=on, minlength=len(seg)) / count
    hit = grid.n_hit_scans > 0
    # returns on both sides, near and twice as far: a line through the inside of an
    # object (a wall's own far face, or a desk right in front of it, is only near)
    occupied = np.min(
        [np.bincount(owner, weights=_lookup(grid, hit, pts + k * off), minlength=len(seg)) for k in (-2, -1, 1, 2)],
        axis=0,
    ) / count
    structure = (
        (np.maximum(left, right) >= params.min_free_side) & (seen >= 0.5)
        & (occupied < params.min_free_side)
    )  # fmt: skip
    side = np.where(
        (left >= params.min_free_side) & (right < params.min_free_side), 1,
        np.where((right >= params.min_free_side) & (left < params.min_free_side), -1, 0),
    ).astype(np.int8)  # fmt: skip
    return structure, side


def join_collinear(seg: np.ndarray, weights: np.ndarray, grid: OccupancyGrid, params: StructureParams = StructureParams()):
    """Step 2: collinear faces joined across gaps that free space does not pass through.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    weights : (F,) float ndarray
        Their weights (inlier counts); a joined face's is the sum.
    grid : OccupancyGrid
    params : StructureParams

    Returns
    -------
    joined : (J, 4) float64 ndarray
        Metres; a face joined with none is unchanged.
    joined_weights : (J,) float64 ndarray
    group : (F,) int64 ndarray
        The joined face of each input face.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    w = np.asarray(weights, dtype=np.float64).ravel()
    nf = len(seg)
    if nf < 2:
        return seg.copy(), w.copy(), np.arange(nf)
    i, j = _candidate_pairs(seg, params.join_max_gap_m, np.radians(params.join_angle_deg))
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    keep = np.zeros(len(i), dtype=bool)
    if len(i):
        a = np.where(length[i] >= length[j], i, j)  # the longer face's line
        b = np.where(length[i] >= length[j], j, i)
        u = (seg[a, 2:] - seg[a, :2]) / np.maximum(length[a], 1e-12)[:, None]
        nrm = np.column_stack([-u[:, 1], u[:, 0]])
        off0 = np.abs(np.einsum("ij,ij->i", seg[b, :2] - seg[a, :2], nrm))
        off1 = np.abs(np.einsum("ij,ij->i", seg[b, 2:] - seg[a, :2], nrm))
        tb0 = np.einsum("ij,ij->i", seg[b, :2] - seg[a, :2], u)
        tb1 = np.einsum("ij,ij->i", seg[b, 2:] - seg[a, :2], u)
        lo_b, hi_b = np.minimum(tb0, tb1), np.maximum(tb0, tb1)
        gap = np.maximum(lo_b - length[a], -hi_b)
        keep = (np.maximum(off0, off1) <= params.join_offset_m) & (gap <= params.join_max_gap_m)
        free = passable(grid)
        step = grid.resolution_m / 2
        for k in np.flatnonzero(keep & (gap > step)).tolist():
            t0, t1 = (length[a[k]], lo_b[k]) if lo_b[k] > length[a[k]] else (hi_b[k], 0.0)
            n = max(int(np.ceil((t1 - t0) / step)), 1)
            t = t0 + (np.arange(n) + 0.5) / n * (t1 - t0)
            line = seg[a[k], :2] + u[k] * t[:, None]
            open_run = _longest_run(_lookup(grid, free, line)) * (t1 - t0) / n
            keep[k] = open_run < params.min_opening_m
    graph = coo_matrix((np.ones(int(keep.sum())), (i[keep], j[keep])), shape=(nf, nf))
    n_groups, group = connected_components(graph, directed=False)
    joined = np.empty((n_groups, 4))
    for g in range(n_groups):
        joined[g] = _fit_group(seg[group == g], length[group == g])
    return joined, np.bincount(group, weights=w, minlength=n_groups), group.astype(np.int64)


def _longest_run(flags: np.ndarray) -> int:
    """Length of the longest run of True in a 1D bool array."""
    if not flags.any():
        return 0
    padded = np.r_[False, flags, False].astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return int((edges[1::2] - edges[::2]).max())


def _fit_group(seg: np.ndarray, length: np.ndarray) -> np.ndarray:
    """One face for collinear faces: the length-weighted axial mean direction, the
    length-weighted mean offset, the extent of all their ends."""
    if len(seg) == 1:
        return seg[0].copy()
    ang = np.arctan2(seg[:, 3] - seg[:, 1], seg[:, 2] - seg[:, 0])
    phi = 0.5 * np.arctan2((length * np.sin(2 * ang)).sum(), (length * np.cos(2 * ang)).sum())
    u = np.array([np.cos(phi), np.sin(phi)])
    n = np.array([-u[1], u[0]])
    mid = 0.5 * (seg[:, :2] + seg[:, 2:])
    off = float((mid @ n * length).sum() / length.sum())
    t = np.concatenate([seg[:, :2] @ u, seg[:, 2:] @ u])
    return np.r_[off * n + t.min() * u, off * n + t.max() * u]


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
    i, j = _candidate_pairs(seg, params.snap_m)
    ang = _axial_angle(seg)
    ok = _angle_diff(ang[i], ang[j]) >= np.radians(params.junction_min_angle_deg)
    i, j = np.r_[i[ok], j[ok]], np.r_[j[ok], i[ok]]  # both directions: the end of i on j
    if len(i) == 0:
        if trim_shallow:
            _trim_shallow_crossings(out, params)
        return out, _junctions(out, params)
    x = _line_crossings(seg[i], seg[j])
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
    ang = _axial_angle(seg)
    shallow = _angle_diff(ang[i], ang[j]) < np.radians(params.junction_min_angle_deg)
    for a, b in zip(i[shallow].tolist(), j[shallow].tolist()):
        x = _line_crossings(seg[[a]], seg[[b]])[0]
        if not np.isfinite(x).all():
            continue
        for k in (a, b):
            d = np.hypot(*(seg[k].reshape(2, 2) - x).T)
            end = int(np.argmin(d))
            if d[end] <= 0.5 * np.hypot(*(seg[k, 2:] - seg[k, :2])):
                seg[k, 2 * end : 2 * end + 2] = x


def _line_crossings(a: np.ndarray, b: np.ndarray) -> np.ndarray:
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
    i, j = _candidate_pairs(seg, tol)
    ang = _axial_angle(seg)
    ok = _angle_diff(ang[i], ang[j]) >= np.radians(params.junction_min_angle_deg) * 0.5
    i, j = i[ok], j[ok]
    if len(i) == 0:
        return np.empty((0, 5))
    x = _line_crossings(seg[i], seg[j])
    near_end = []
    for s in (i, j):
        d0 = np.hypot(*(x - seg[s, :2]).T)
        d1 = np.hypot(*(x - seg[s, 2:]).T)
        near_end.append(np.minimum(d0, d1) <= tol)
    kind = np.where(near_end[0] & near_end[1], 1, np.where(near_end[0] | near_end[1], 2, 3))
    good = np.isfinite(x).all(axis=1)
    return np.column_stack([x[good], i[good], j[good], kind[good]]).astype(np.float64)


def free_standing_objects(
    grid: OccupancyGrid, params: StructureParams = StructureParams(), walls: np.ndarray | None = None
) -> np.ndarray:
    """Step 4's objects: the cells of things standing in the free space.

    The cells with a return (any scan) but those of ``walls`` (long faces, (A, 4)
    metres, and a cell around them: so a desk or a cabinet in front of a wall comes
    apart from it), grown by one cell so an object's returns hang together, are split into 8-connected components (SciPy's ``ndimage.label``). A
    component is a free-standing object when the free space surrounds it (at least
    ``object_free_around`` of the cells around it are :func:`passable`) and it is small: its
    extent along its principal axis is below ``clutter_max_length_m``. A thin long
    component (its area over its length below ``side_offset_m`` * 2 plus two cells, at
    least ``min_wall_length_m`` long: a wall between two doors) is not an object.

    Returns
    -------
    (H, W) bool ndarray
        The objects' cells (grown by one cell).
    """
    from scipy import ndimage

    hit = grid.n_hit_scans > 0
    if walls is not None and len(walls):
        pts, _, _ = _samples(np.asarray(walls, dtype=np.float64).reshape(-1, 4), grid.resolution_m / 2)
        rows, cols, inside = grid.cells_of(pts)
        on_wall = np.zeros(grid.shape, dtype=bool)
        on_wall[rows[inside], cols[inside]] = True
        hit = hit & ~ndimage.binary_dilation(on_wall, structure=np.ones((3, 3), bool), iterations=2)
    hit = ndimage.binary_dilation(hit, structure=np.ones((3, 3), bool))
    labels, n = ndimage.label(hit, structure=np.ones((3, 3), bool))
    if n == 0:
        return np.zeros(grid.shape, dtype=bool)
    ring = ndimage.binary_dilation(hit, structure=np.ones((3, 3), bool)) & ~hit
    ring_labels = ndimage.grey_dilation(labels, size=(3, 3)) * ring
    free = passable(grid)
    around = np.bincount(ring_labels[ring], minlength=n + 1).astype(np.float64)
    around_free = np.bincount(ring_labels[ring & free], minlength=n + 1)
    surrounded = around_free >= params.object_free_around * np.maximum(around, 1)
    rows, cols = np.nonzero(labels)
    lab = labels[rows, cols]
    r = grid.resolution_m
    x, y = cols * r, rows * r
    cnt = np.bincount(lab, minlength=n + 1).astype(np.float64)
    mx, my = np.bincount(lab, x, n + 1) / np.maximum(cnt, 1), np.bincount(lab, y, n + 1) / np.maximum(cnt, 1)
    dx, dy = x - mx[lab], y - my[lab]
    sxx = np.bincount(lab, dx * dx, n + 1)
    syy = np.bincount(lab, dy * dy, n + 1)
    sxy = np.bincount(lab, dx * dy, n + 1)
    phi = 0.5 * np.arctan2(2 * sxy, sxx - syy)
    u = dx * np.cos(phi[lab]) + dy * np.sin(phi[lab])
    v = -dx * np.sin(phi[lab]) + dy * np.cos(phi[lab])
    length = np.zeros(n + 1)
    width = np.zeros(n + 1)
    for arr, out in ((u, length), (v, width)):
        hi = np.full(n + 1, -np.inf)
        lo = np.full(n + 1, np.inf)
        np.maximum.at(hi, lab, arr)
        np.minimum.at(lo, lab, arr)
        out[:] = np.where(np.isfinite(hi), hi - lo + r, 0.0)
    mean_width = cnt * r * r / np.maximum(length, r)  # area over length: stray returns aside
    wall_like = (mean_width < 2 * params.side_offset_m + 2 * r) & (length >= params.min_wall_length_m)
    is_object = surrounded & (length < params.clutter_max_length_m) & ~wall_like
    is_object[0] = False
    return is_object[labels]


def on_objects(seg: np.ndarray, grid: OccupancyGrid, objects: np.ndarray) -> np.ndarray:
    """Whether most of each face (F, 4) lies on object cells (:func:`free_standing_objects`)."""
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    if len(seg) == 0:
        return np.zeros(0, dtype=bool)
    pts, owner, _ = _samples(seg, grid.resolution_m / 2)
    share = np.bincount(owner, weights=_lookup(grid, objects, pts), minlength=len(seg))
    return share >= 0.5 * np.bincount(owner, minlength=len(seg))


def structure_passes(seg: np.ndarray, weights: np.ndarray, grid: OccupancyGrid, params: StructureParams = StructureParams()):
    """Steps 1 to 4 on the merged faces of a plan (see the module docstring).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Merged faces, metres.
    weights : (F,) float ndarray
        Their weights (inlier counts).
    grid : OccupancyGrid
        The free space of the plan's scans.
    params : StructureParams

    Returns
    -------
    walls : (W, 4) float64 ndarray
        The structure's faces, joined and snapped, metres.
    wall_weights : (W,) float64 ndarray
    free_side : (W,) int8 ndarray
        Which side of each face the free space is on (+1 left, -1 right, 0 both or
        neither; see :func:`border_and_support`).
    clutter : (C, 4) float64 ndarray
        The faces that are not structure (furniture, single-scan returns), metres.
    reason : (C,) object ndarray
        Why each clutter face is clutter: ``not_a_boundary`` (no free space beside it, or returns on both sides, or on cells that are not occupied),
        ``free_standing_object``, ``in_front_of_wall`` or ``short``.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    w = np.asarray(weights, dtype=np.float64).ravel()
    structure, _ = border_and_support(seg, grid, params)
    clutter = [seg[~structure]]
    reason = [np.full(int((~structure).sum()), "not_a_boundary", dtype=object)]
    joined, jw, _ = join_collinear(seg[structure], w[structure], grid, params)
    snapped, junctions = snap_junctions(joined, params)
    length = np.hypot(snapped[:, 2] - snapped[:, 0], snapped[:, 3] - snapped[:, 1])
    anchor = length >= params.clutter_max_length_m
    standing = on_objects(snapped, grid, free_standing_objects(grid, params, snapped[anchor])) & ~anchor
    _, side = border_and_support(snapped, grid, params)
    front = in_front_of_walls(snapped, side, anchor, params) & ~standing
    short = _short_loose(snapped, junctions, params.min_wall_length_m) & ~standing & ~front
    keep = ~standing & ~front & ~short
    clutter += [snapped[standing], snapped[front], snapped[short]]
    reason += [np.full(int(standing.sum()), "free_standing_object", dtype=object),
               np.full(int(front.sum()), "in_front_of_wall", dtype=object),
               np.full(int(short.sum()), "short", dtype=object)]  # fmt: skip
    # the walls meet again without the clutter; a face the new ends left short goes
    walls, junctions = snap_junctions(joined[keep], params)
    still = ~_short_loose(walls, junctions, params.min_wall_length_m)
    clutter.append(walls[~still])
    reason.append(np.full(int((~still).sum()), "short", dtype=object))
    walls, _ = snap_junctions(joined[keep][still], params)
    _, side = border_and_support(walls, grid, params)
    return walls, jw[keep][still], side, np.concatenate(clutter).reshape(-1, 4), np.concatenate(reason)


def in_front_of_walls(seg: np.ndarray, side: np.ndarray, wall: np.ndarray, params: StructureParams = StructureParams()):
    """Step 5: faces shorter than ``clutter_max_length_m`` that stand parallel in front
    of a long wall face, on its free side, between ``front_min_m`` and ``front_max_m``
    from it and along it over ``front_overlap`` of their length: the fronts of desks,
    cabinets and shelves against a wall (the thesis's clutter, sections 1.3 and 2.3).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    side : (F,) int ndarray
        Their free sides (:func:`border_and_support`).
    wall : (F,) bool ndarray
        Which faces are long walls (the candidates behind).
    params : StructureParams

    Returns
    -------
    (F,) bool ndarray
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    out = np.zeros(len(seg), dtype=bool)
    i, j = _candidate_pairs(seg, params.front_max_m, np.radians(params.join_angle_deg))
    if len(i) == 0:
        return out
    i, j = np.r_[i, j], np.r_[j, i]  # face i in front of wall j
    ok = wall[j] & ~wall[i]
    i, j = i[ok], j[ok]
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    u = (seg[j, 2:] - seg[j, :2]) / np.maximum(length[j], 1e-12)[:, None]
    n = np.column_stack([-u[:, 1], u[:, 0]]) * side[j][:, None]  # towards the wall's free side
    mid = 0.5 * (seg[i, :2] + seg[i, 2:])
    dist = np.einsum("ij,ij->i", mid - seg[j, :2], n)
    t0 = np.einsum("ij,ij->i", seg[i, :2] - seg[j, :2], u)
    t1 = np.einsum("ij,ij->i", seg[i, 2:] - seg[j, :2], u)
    overlap = np.minimum(np.maximum(t0, t1), length[j]) - np.maximum(np.minimum(t0, t1), 0.0)
    hit = (side[j] != 0) & (dist >= params.front_min_m) & (dist <= params.front_max_m) & (
        overlap >= params.front_overlap * length[i]
    )
    out[i[hit]] = True
    return out


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
    i, j = _candidate_pairs(axes, max_distance_m, np.radians(params.duplicate_angle_deg))
    length = np.hypot(axes[:, 2] - axes[:, 0], axes[:, 3] - axes[:, 1])
    a = np.where(length[i] >= length[j], i, j)
    b = np.where(length[i] >= length[j], j, i)
    u = (axes[a, 2:] - axes[a, :2]) / np.maximum(length[a], 1e-12)[:, None]
    nrm = np.column_stack([-u[:, 1], u[:, 0]])
    ok = np.ones(len(a), dtype=bool)
    for end in (0, 2):
        rel = axes[b, end : end + 2] - axes[a, :2]
        t = np.einsum("ij,ij->i", rel, u)
        ok &= (np.abs(np.einsum("ij,ij->i", rel, nrm)) <= max_distance_m) & (t >= -max_distance_m) & (
            t <= length[a] + max_distance_m
        )
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


def _short_loose(seg: np.ndarray, junctions: np.ndarray, min_length: float) -> np.ndarray:
    """Faces shorter than ``min_length`` without a junction at both ends (a short face
    that connects two walls is a wall)."""
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    ends = np.zeros((len(seg), 2), dtype=bool)
    for col in (2, 3):
        ids = junctions[:, col].astype(np.int64)
        for end in (0, 1):
            at = np.hypot(*(junctions[:, :2] - seg[ids, 2 * end : 2 * end + 2]).T) <= 0.02
            ends[ids[at], end] = True
    return (length < min_length) & ~ends.all(axis=1)

"""Furniture out of the walls, the structure passes' clutter rules: objects standing in
the free space (:func:`free_standing_objects`, :func:`on_objects`) and fronts of desks,
cabinets and shelves in front of a wall (:func:`in_front_of_walls`) with their sides
(:func:`object_sides`). Source: the
clutter of thesis sections 1.3 and 2.3; the occupancy-grid reading of Bormann et al.,
ICRA 2016 (free space is what the robot saw); the thresholds are ours.
"""

from __future__ import annotations

import numpy as np

from floorscan.core.geometry import OVERLAY_GRID_M, point_segment_dist2
from floorscan.core.grid import square_dilation
from floorscan.core.occupancy import OccupancyGrid
from floorscan.floorplan.candidates import candidate_pairs
from floorscan.floorplan.free_space import StructureParams, mask_at, passable, segment_samples
from floorscan.floorplan.hidden import HIDDEN_MAX_GAP_M, OBJECT_MAX_DEPTH_M, backed, body_seen_free, free_normals
from floorscan.floorplan.junctions import ends_on_line, in_line_pairs, shorter_on_longer


def free_standing_objects(
    grid: OccupancyGrid, params: StructureParams = StructureParams(), walls: np.ndarray | None = None,
    max_thickness_m: float | None = None,
) -> np.ndarray:
    """Step 4's objects: the cells of things standing in the free space.

    The cells with a return (any scan) but those of ``walls`` (long faces, (A, 4)
    metres, and a cell around them: so a desk or a cabinet in front of a wall comes
    apart from it), grown by one cell so an object's returns hang together, are split into 8-connected components (SciPy's ``ndimage.label``). A
    component is a free-standing object when the free space surrounds it (at least
    ``object_free_around`` of the cells around it are :func:`passable`) and it is small: its
    extent along its principal axis is below ``clutter_max_length_m``. A thin long
    component, at least ``min_wall_length_m`` long, is not an object: its area over its
    length below ``side_offset_m`` * 2 plus two cells (a wall between two doors), or,
    in a map (a grid without scan positions, whose obstacles are solid: scans see only
    their outlines) and given ``max_thickness_m``, the largest disc inside it narrower
    than that plus two cells (a partition's stub as thick as a wall, the cross of walls
    between four doors; the local thickness of Hildebrand and Ruegsegger, J. Microscopy
    1997).

    Parameters
    ----------
    grid : OccupancyGrid
        The selected scans' grid.
    params : StructureParams
    walls : (A, 4) float ndarray, optional
        Long wall faces, metres, cut out of the returns first.
    max_thickness_m : float, optional
        The thickest wall, metres (the plan's ``pair_max_m``).

    Returns
    -------
    (H, W) bool ndarray
        The objects' cells (grown by one cell).
    """
    from scipy import ndimage

    hit = grid.n_hit_scans > 0
    if walls is not None and len(walls):
        pts, _, _ = segment_samples(np.asarray(walls, dtype=np.float64).reshape(-1, 4), grid.resolution_m / 2)
        rows, cols, _ = grid.cells_of(pts)
        hit = hit & ~square_dilation(rows, cols, 2, grid.shape)  # a 5 x 5 square
    returns = np.nonzero(hit)
    hit = square_dilation(*returns, 1, grid.shape)
    labels, n = ndimage.label(hit, structure=np.ones((3, 3), bool))
    if n == 0:
        return np.zeros(grid.shape, dtype=bool)
    # each cell of the ring around the components (the returns grown by two cells, a
    # 3 x 3 square of 3 x 3 squares, less the components): the largest label among its
    # 3 x 3 neighbours on the raster (ndimage.grey_dilation of the labels, at the ring's cells)
    ring_r, ring_c = np.nonzero(square_dilation(*returns, 2, grid.shape) & ~hit)
    ring_labels = np.zeros(len(ring_r), dtype=labels.dtype)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            r = np.clip(ring_r + dr, 0, grid.shape[0] - 1)
            c = np.clip(ring_c + dc, 0, grid.shape[1] - 1)
            np.maximum(ring_labels, labels[r, c], out=ring_labels)
    free = passable(grid)
    around = np.bincount(ring_labels, minlength=n + 1).astype(np.float64)
    around_free = np.bincount(ring_labels[free[ring_r, ring_c]], minlength=n + 1)
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
    u = dx * np.cos(phi[lab]) + dy * np.sin(phi[lab])  # along the principal axis
    hi, lo = np.full(n + 1, -np.inf), np.full(n + 1, np.inf)
    np.maximum.at(hi, lab, u)
    np.minimum.at(lo, lab, u)
    length = np.where(np.isfinite(hi), hi - lo + r, 0.0)
    mean_width = cnt * r * r / np.maximum(length, r)  # area over length: stray returns aside
    wall_like = (mean_width < 2 * params.side_offset_m + 2 * r) & (length >= params.min_wall_length_m)
    if max_thickness_m is not None and grid.scan_xy is None:
        # in a map (its obstacles solid, where scans see outlines): thinner than the
        # thickest wall, the diameter of the largest disc inside the component, on each
        # candidate's bounding box (the distance transform's maximum)
        candidate = surrounded & (length < params.clutter_max_length_m) & (length >= params.min_wall_length_m)
        candidate &= ~wall_like
        for k, box in enumerate(ndimage.find_objects(labels), start=1):
            if box is not None and candidate[k]:
                inside = np.pad(labels[box] == k, 1)
                wall_like[k] = 2 * ndimage.distance_transform_edt(inside).max() * r < max_thickness_m + 2 * r
    is_object = surrounded & (length < params.clutter_max_length_m) & ~wall_like
    is_object[0] = False
    return is_object[labels]


def on_objects(seg: np.ndarray, grid: OccupancyGrid, objects: np.ndarray) -> np.ndarray:
    """Whether most of each face lies on object cells (:func:`free_standing_objects`):
    at least half its samples, every half cell.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    grid : OccupancyGrid
    objects : (H, W) bool ndarray
        On ``grid``'s cells.

    Returns
    -------
    (F,) bool ndarray
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    if len(seg) == 0:
        return np.zeros(0, dtype=bool)
    pts, owner, _ = segment_samples(seg, grid.resolution_m / 2)
    share = np.bincount(owner, weights=mask_at(grid, objects, pts), minlength=len(seg))
    return share >= 0.5 * np.bincount(owner, minlength=len(seg))


def in_front_of_walls(seg: np.ndarray, side: np.ndarray, wall: np.ndarray, params: StructureParams = StructureParams(),
                      free_at=None):  # fmt: skip
    """Step 5: faces shorter than ``clutter_max_length_m`` that stand parallel in front
    of a long wall face, on its free side, between ``front_min_m`` and ``front_max_m``
    from it and along it over ``front_overlap`` of their length: the fronts of desks,
    cabinets and shelves against a wall (the thesis's clutter, sections 1.3 and 2.3).
    So is a longer face, up to :data:`~floorscan.floorplan.hidden.HIDDEN_MAX_GAP_M` (a
    row of cabinets), shorter than the wall face behind it and free on the same side
    (the other face of a wall is free on the other side). Where the wall's other face
    runs on behind the front (:func:`~floorscan.floorplan.hidden.backed`), the front
    may stand up to :data:`~floorscan.floorplan.hidden.OBJECT_MAX_DEPTH_M` in front of
    it, when the scans did not see its body free: the wall is a wall's thickness there,
    so what stands deeper is an object.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    side : (F,) int ndarray
        Their free sides (:func:`border_and_support`).
    wall : (F,) bool ndarray
        Which faces are long walls (the candidates behind).
    params : StructureParams
    free_at : callable, optional
        ``free_at(xy)``: (N,) bool, whether the scans saw map points free; a deeper
        front's body must not be (:func:`~floorscan.floorplan.hidden.body_seen_free`).
        None: no front deeper than ``front_max_m``.

    Returns
    -------
    front : (F,) bool ndarray
    behind : (F,) int64 ndarray
        The wall face each front stands against (the nearest), -1 for the others.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    out = np.zeros(len(seg), dtype=bool)
    behind = np.full(len(seg), -1, dtype=np.int64)
    deepest = params.front_max_m if free_at is None else max(params.front_max_m, OBJECT_MAX_DEPTH_M)
    i, j = candidate_pairs(seg, deepest, np.radians(params.join_angle_deg))
    if len(i) == 0:
        return out, behind
    i, j = np.r_[i, j], np.r_[j, i]  # face i in front of wall j
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    # a front shorter than a long wall; or a row of them, up to the longest object
    # against a wall, shorter than the wall face behind it and free on the same side
    _, _, free_n = free_normals(seg, side)
    same_way = np.einsum("ij,ij->i", free_n[i], free_n[j]) > 0
    ok = wall[j] & (~wall[i] | (length[i] < HIDDEN_MAX_GAP_M) & (length[i] < length[j]) & same_way)
    i, j = i[ok], j[ok]
    u = (seg[j, 2:] - seg[j, :2]) / np.maximum(length[j], 1e-12)[:, None]
    n = np.column_stack([-u[:, 1], u[:, 0]]) * side[j][:, None]  # towards the wall's free side
    mid = 0.5 * (seg[i, :2] + seg[i, 2:])
    dist = np.einsum("ij,ij->i", mid - seg[j, :2], n)
    t0 = np.einsum("ij,ij->i", seg[i, :2] - seg[j, :2], u)
    t1 = np.einsum("ij,ij->i", seg[i, 2:] - seg[j, :2], u)
    overlap = np.minimum(np.maximum(t0, t1), length[j]) - np.maximum(np.minimum(t0, t1), 0.0)
    hit = (side[j] != 0) & (dist >= params.front_min_m) & (dist <= deepest)
    hit &= overlap >= params.front_overlap * length[i]
    deep = hit & (dist > params.front_max_m)
    hit &= ~deep | same_way[ok]  # an object's front faces the room the wall's face does
    for k in np.flatnonzero(hit & deep).tolist():  # deeper: the wall's other face behind it
        lo, hi = max(min(t0[k], t1[k]), 0.0), min(max(t0[k], t1[k]), length[j[k]])
        hit[k] = backed(seg, side, int(j[k]), lo, hi, params) and body_seen_free(
            seg[j[k], :2], u[k], n[k], lo, hi, float(dist[k]), free_at, params.side_offset_m
        ) < params.min_free_side
    out[i[hit]] = True
    i, j = i[hit], j[hit]
    order = np.lexsort((j, dist[hit], i))  # by front, the nearest wall first (ties: the lower index)
    first = np.ones(len(order), dtype=bool)
    first[1:] = i[order][1:] != i[order][:-1]
    behind[i[order][first]] = j[order][first]
    return out, behind


def object_sides(seg: np.ndarray, side: np.ndarray, front: np.ndarray, behind: np.ndarray,
                 params: StructureParams = StructureParams()) -> np.ndarray:
    """Step 5, the sides of the objects whose fronts stand against a wall: a face square
    to the wall face behind a front (at least ``junction_min_angle_deg``), from within
    ``snap_m`` of one of the front's ends to within ``snap_m`` of that face's line, no
    longer than the front (furniture stands along the wall, longer than it is deep),
    with the front on its far side from its free side (the object's body is behind it);
    or across the wall's line, to within ``snap_m`` of another front's end (the sides of
    two objects back to back at a partition's end, in one line). It
    closes the object's body against the wall; kept as a wall, it would close the
    front into a closet of three walls that takes the floor under the object from its
    room (:func:`~floorscan.floorplan.structure.floor_under`).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    side : (F,) int ndarray
        Their free sides (:func:`~floorscan.floorplan.structure.border_and_support`).
    front, behind : (F,) ndarray
        :func:`in_front_of_walls`'s fronts and the wall face behind each.
    params : StructureParams

    Returns
    -------
    (F,) bool ndarray
        The sides (never a front).
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    u, length, n = free_normals(seg, side)
    square = np.sin(np.radians(params.junction_min_angle_deg))
    ends = seg.reshape(-1, 2, 2)
    every = np.arange(len(seg))
    out = np.zeros(len(seg), dtype=bool)
    candidate = ~np.asarray(front, dtype=bool) & (np.asarray(side) != 0)
    fronts = np.flatnonzero(front)  # (F, 2) at_any_front: each end within snap_m of any front's end
    to_fronts = np.linalg.norm(ends[:, :, None] - ends[fronts].reshape(1, 1, -1, 2), axis=3)
    at_any_front = to_fronts.min(axis=2, initial=np.inf) <= params.snap_m
    for f in fronts.tolist():
        w = int(behind[f])
        across = candidate & (np.abs(u[:, 0] * u[w, 1] - u[:, 1] * u[w, 0]) >= square) & (length <= length[f])
        body_behind = np.einsum("ij,ij->i", 0.5 * (seg[f, :2] + seg[f, 2:]) - seg[:, :2], n) < 0
        _, off = ends_on_line(seg, np.full(len(seg), w), every)
        on_wall = np.abs(off) <= params.snap_m  # (F, 2): each end on the wall's line
        # (F, 2): each end within snap_m of one of the front's two ends
        at_front = np.linalg.norm(ends[:, :, None, :] - ends[f][None, None], axis=3).min(axis=2) <= params.snap_m
        out |= across & body_behind & ((at_front[:, 0] & on_wall[:, 1]) | (at_front[:, 1] & on_wall[:, 0]))
        # across the wall's line to another front's end: two objects' sides back to back, flush with a partition's end
        to_other = (at_front[:, 0] & at_any_front[:, 1]) | (at_front[:, 1] & at_any_front[:, 0])
        out |= across & body_behind & (off[:, 0] * off[:, 1] < 0) & to_other
    return out


def loose_in_free_space(
    seg: np.ndarray, ends: np.ndarray, side: np.ndarray, grid: OccupancyGrid, params: StructureParams = StructureParams(),
    max_thickness_m: float = 0.4, crossed: np.ndarray | None = None,
) -> np.ndarray:  # fmt: skip
    """Step 6: chains of faces that hold nothing but each other and stand in the free
    space, with a wall behind them or free space on both sides: the fronts (and seen
    ends) of racks, shelves and rows of chairs, however long.

    Faces hold each other at an end: a junction there, another face's end within
    ``snap_m``, or a face at least ``junction_min_angle_deg`` across within ``snap_m``
    (a curved wall's next piece, a rack's end face). A face within ``snap_m`` at both
    ends of one face across it (a piece shorter than ``snap_m``: a chair's seat at its
    back) hangs from it at the nearer end only. Two faces of one group in one
    line hold each other's facing ends across a gap of at most ``join_max_gap_m`` (an
    opening in their wall, which step 2 kept open): a closed loop of walls with doors in
    it (a core of rooms standing free of the outer walls) has no free end. A group of
    faces held together (a face alone, an L, a U; not a closed loop) is loose when

    - no face of it crosses another face away from both their ends (``crossed``, an X
      junction): a partition that crosses a wall, with a door at each of its ends, is
      held by the wall it crosses;
    - no face of it lies in the line of a face outside it within ``loose_reach_m``
      (:func:`~floorscan.floorplan.junctions.in_line_pairs`: within ``2 * side_offset_m``
      of it, and of its direction to ``join_angle_deg`` or, a short face beside one at
      least ``clutter_max_length_m`` long, to a cell at each end): a wall between two
      doors has its wall's other pieces in line across the doors;
    - the cells ``side_offset_m`` to twice that beyond each of its free ends, along
      the face, are free space (:func:`~floorscan.floorplan.free_space.passable`): the
      rover saw past them, so no free end is an occluded continuation;
    - its longest face has free space on both sides, or another face parallel behind
      it (:func:`walls_behind`, walls up to ``max_thickness_m`` thick);
    - it encloses no free space (:func:`_encloses_free_space`): a core of rooms whose
      loop a junction missed by a cell still holds its rooms.

    A building's walls hold each other up: the wall graph is connected, and a wall
    that ends in free space ends at an opening, with the rest of its wall in line. A
    chain loose at its ends in front of a wall stands against it (the clutter of
    thesis sections 1.3 and 2.3); one with free space on both sides stands in the
    room. The second and third conditions keep a wall whose ends were not seen, and a
    wall with windows whose rays pass its ends.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres, after the junction snap.
    ends : (F, 2) bool ndarray
        Whether each end (``x0, y0`` and ``x1, y1``) is at a junction
        (:func:`~floorscan.floorplan.junctions.junction_ends`); a junction holds faces
        through the ends near it.
    side : (F,) int ndarray
        Their free sides (:func:`~floorscan.floorplan.structure.border_and_support`).
    grid : OccupancyGrid
    params : StructureParams
    max_thickness_m : float
        The thickest wall, metres (the plan's ``pair_max_m``).
    crossed : (F,) bool ndarray, optional
        Which faces another face crosses away from both their ends (the X junctions of
        :func:`~floorscan.floorplan.junctions.snap_junctions`, kind 3).

    Returns
    -------
    (F,) bool ndarray
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    side = np.asarray(side)
    nf = len(seg)
    out = np.zeros(nf, dtype=bool)
    if nf == 0:
        return out
    f, g, end = _holds(seg, params)
    n_groups, group = connected_components(coo_matrix((np.ones(len(f)), (f, g)), shape=(nf, nf)), directed=False)
    held = np.zeros((nf, 2), dtype=bool)
    held[f, end] = True
    held |= np.asarray(ends, dtype=bool).reshape(-1, 2)
    i, j = in_line_pairs(seg, params.loose_reach_m, 2 * params.side_offset_m, np.radians(params.join_angle_deg),
                         grid.resolution_m, params.clutter_max_length_m)
    anchored = np.zeros(n_groups, dtype=bool)
    outside = group[i] != group[j]
    anchored[group[i[outside]]] = True
    anchored[group[j[outside]]] = True
    if crossed is not None:
        anchored[group[np.asarray(crossed, dtype=bool)]] = True
    held |= _held_across_openings(seg, i[~outside], j[~outside], params.join_max_gap_m)
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    backed = (side == 0) | walls_behind(seg, side, length >= params.min_wall_length_m, params, max_thickness_m)
    free = passable(grid)
    r = grid.resolution_m
    steps = np.arange(params.side_offset_m, 2 * params.side_offset_m + r / 2, r / 2)
    for k in np.flatnonzero(~anchored).tolist():
        members = np.flatnonzero(group == k)
        free_ends = [(m, e) for m in members.tolist() for e in (0, 1) if not held[m, e]]
        if len(free_ends) < 2 or not backed[members[np.argmax(length[members])]]:
            continue  # a closed loop, or nothing behind its longest face and one side seen
        beyond = []
        for m, e in free_ends:
            p, q = (seg[m, :2], seg[m, 2:]) if e == 0 else (seg[m, 2:], seg[m, :2])
            d = (p - q) / max(float(length[m]), 1e-12)  # outwards from the end
            beyond.append(p + d * steps[:, None])
        out[members] = bool(mask_at(grid, free, np.concatenate(beyond)).all()) and not _encloses_free_space(
            seg[members], grid, free, params.join_max_gap_m
        )
    return out


def _encloses_free_space(seg: np.ndarray, grid: OccupancyGrid, free: np.ndarray, max_gap_m: float) -> bool:
    """Whether faces (``(F, 4)`` metres) enclose seen free space once their gaps up to
    ``max_gap_m`` (openings, junctions missed by a cell) are closed: the union of the faces
    buffered by half of it has a hole holding a passable cell. A core of rooms standing
    free of the outer walls encloses its rooms' floor however its corners fall on the
    cells; a rack, a table or a row of chairs, seen all around, encloses nothing the
    rover saw."""
    import shapely

    lines = shapely.linestrings(seg.reshape(-1, 2, 2))
    union = shapely.union_all(shapely.buffer(lines, max_gap_m / 2, cap_style="square"), grid_size=OVERLAY_GRID_M)
    holes = [shapely.Polygon(ring) for part in shapely.get_parts(union) if part.geom_type == "Polygon"
             for ring in part.interiors]  # fmt: skip
    r = grid.resolution_m
    for hole in holes:
        x0, y0, x1, y1 = hole.bounds
        xs, ys = np.meshgrid(np.arange(x0 + r / 2, x1, r), np.arange(y0 + r / 2, y1, r))
        inside = shapely.contains_xy(hole, xs.ravel(), ys.ravel())
        if inside.any() and mask_at(grid, free, np.column_stack([xs.ravel()[inside], ys.ravel()[inside]])).any():
            return True
    return False


def _held_across_openings(seg: np.ndarray, i: np.ndarray, j: np.ndarray, max_gap_m: float) -> np.ndarray:
    """The ends of faces in line (pairs ``(i, j)``) that face each other across a gap of
    at most ``max_gap_m``: a wall's pieces on the two sides of an opening (step 2 keeps
    such a gap open when free space passes through it) hold each other's ends.

    Returns
    -------
    (F, 2) bool ndarray
        Whether end 0 (``x0, y0``) or 1 (``x1, y1``) of each face is so held.
    """
    out = np.zeros((len(seg), 2), dtype=bool)
    if len(i) == 0:
        return out
    length, a, b, t, _ = shorter_on_longer(seg, i, j)
    after = t.min(axis=1) >= length[a]  # b beyond a's end 1; else before its end 0
    before = t.max(axis=1) <= 0.0
    gap = np.where(after, t.min(axis=1) - length[a], -t.max(axis=1))
    ok = (after | before) & (gap <= max_gap_m)
    out[a[ok & after], 1] = True
    out[a[ok & before], 0] = True
    b_end = np.where(after, np.argmin(t, axis=1), np.argmax(t, axis=1))
    out[b[ok], b_end[ok]] = True
    return out


def _holds(seg: np.ndarray, params: StructureParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which face holds which at which end: ``(f, g, end)``, face ``g`` within
    ``snap_m`` of end ``end`` (0: ``x0, y0``; 1: ``x1, y1``) of face ``f``, by its end, or
    by its body when it lies at least ``junction_min_angle_deg`` across; of a face
    within reach of ``g`` across it at both ends, the nearer end only."""
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    i, j = candidate_pairs(seg, params.snap_m)
    f, g = np.r_[i, j], np.r_[j, i]
    if len(f) == 0:
        return f, g, f.copy()
    angle = np.arctan2(seg[:, 3] - seg[:, 1], seg[:, 2] - seg[:, 0])
    across = np.abs(np.sin(angle[g] - angle[f])) >= np.sin(np.radians(params.junction_min_angle_deg))
    hits, near = [], []
    for e in (0, 1):
        pt = seg[f, 2 * e : 2 * e + 2]
        to_ends = np.minimum(np.hypot(*(pt - seg[g, :2]).T), np.hypot(*(pt - seg[g, 2:]).T))
        to_body = np.sqrt(point_segment_dist2(pt[:, 0], pt[:, 1], seg[g]))
        hits.append(((to_ends <= params.snap_m) | (across & (to_body <= params.snap_m))) & (length[f] > 0))
        near.append(to_body)  # an end of g lies on g, so its body is the nearer
    # a face held at both ends by one face across it (a piece shorter than snap_m)
    # hangs from it at the nearer end only: its far end is free. Two faces alongside
    # each other (the two faces of one wall or object) still hold each other at both
    both = hits[0] & hits[1] & across
    hits[0] &= ~both | (near[0] <= near[1])
    hits[1] &= ~both | (near[1] < near[0])
    rows = [(f[h], g[h], np.full(int(h.sum()), e)) for e, h in enumerate(hits)]
    return tuple(np.concatenate(c) for c in zip(*rows))


def walls_behind(
    seg: np.ndarray, side: np.ndarray, wall: np.ndarray, params: StructureParams = StructureParams(),
    max_thickness_m: float = 0.4,
) -> np.ndarray:  # fmt: skip
    """Faces with a wall face parallel behind them, on the side away from their free
    space: ``front_min_m`` to ``front_max_m + 2 * side_offset_m`` away, along at least
    half of their length. The wall may have been seen on its far face only (its free
    space away from the face): then the face stands a wall's thickness farther,
    ``front_min_m + max_thickness_m`` at least, and a face nearer is that wall's
    other face. Unlike :func:`in_front_of_walls`, whichever sides of the wall were
    seen.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    side : (F,) int ndarray
        Their free sides (:func:`~floorscan.floorplan.structure.border_and_support`);
        a face with 0 has none behind.
    wall : (F,) bool ndarray
        Which faces can stand behind.
    params : StructureParams
    max_thickness_m : float
        The thickest wall, metres (the plan's ``pair_max_m``).

    Returns
    -------
    (F,) bool ndarray
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    side = np.asarray(side)
    out = np.zeros(len(seg), dtype=bool)
    far = params.front_max_m + 2 * params.side_offset_m
    i, j = candidate_pairs(seg, far, np.radians(params.join_angle_deg))
    if len(i) == 0:
        return out
    i, j = np.r_[i, j], np.r_[j, i]  # face j behind face i
    ok = wall[j] & (side[i] != 0)
    i, j = i[ok], j[ok]
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    t, off = ends_on_line(seg, i, j)
    back = -off * side[i][:, None]  # face j's ends behind face i (away from its free side)
    overlap = np.minimum(t.max(axis=1), length[i]) - np.maximum(t.min(axis=1), 0.0)
    # a face behind whose free space lies away from face i is a wall's far face: face
    # i stands a wall's thickness farther from it, else it is that wall's near face
    away = side[j] * np.sign(ends_on_line(seg, j, i)[1].sum(axis=1)) < 0
    near = np.where(away, params.front_min_m + max_thickness_m, params.front_min_m)
    hit = (back.min(axis=1) >= near) & (back.max(axis=1) <= far) & (overlap >= 0.5 * length[i])
    out[i[hit]] = True
    return out

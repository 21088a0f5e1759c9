"""The floor plan's structure passes: walls, not furniture; one wall per wall; walls
that meet (the modules :mod:`~floorscan.floorplan.clutter` and
:mod:`~floorscan.floorplan.junctions` hold the rules of steps 3 to 5). They run on the merged faces of a plan when the free space of its scans is
known (an :class:`~floorscan.core.occupancy.OccupancyGrid` of the same scans), in this
order (:func:`structure_passes`):

0. **Long enough** (:func:`long_enough`). A face shorter than the plan's
   ``min_length_m`` is dropped, its length measured with its ends carried to the corner
   they stop short of by at most :data:`CLAIMED_M` and half a cell: the wall extractor
   gives the points of a corner to the first of its two lines, so the other starts that
   far short of it, more or less as the raster turns (a 0.35 m pier beside a door
   measured 0.27 m on a map turned by 64 degrees and was dropped there).
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
   opening (a door, a passage) and is kept; an unseen or occluded gap is joined. So is a
   longer gap, up to :data:`~floorscan.floorplan.hidden.HIDDEN_MAX_GAP_M`, that objects
   standing against the wall hide (:mod:`floorscan.floorplan.hidden`: their fronts
   parallel in front of it), whose fronts step 5 then makes clutter; and a face that
   ends at an object in a room's corner runs on behind its front to the corner, and a
   partition's faces behind cabinets back to back on its two sides run on to the wall
   (:func:`~floorscan.floorplan.hidden.into_corners`). A face joined across a gap, on
   which the scans saw free space over more than half its length, is parted again: its
   pieces are a row of objects with the floor seen between them (a table's legs, a row
   of chairs), not one wall, as step 1 asks of each face.
3. **Junctions** (:func:`snap_junctions`). An end within ``snap_m`` of where its line
   meets another face's line (at least ``junction_min_angle_deg`` apart) moves there:
   overshoots are trimmed, short ends extended, so faces meet in L, T and X junctions.
4. **Clutter** (:func:`free_standing_objects`). The returns that are not on a long
   face (``clutter_max_length_m``) fall apart into objects; an object smaller than
   ``clutter_max_length_m`` that the free space surrounds (a chair, a desk, a shelf, a
   table top in a 3D scanner's height band) is furniture, and the faces on it are
   clutter, unless the face is a piece of a wall (:func:`in_wall_lines`: in the line of a
   face on no object, a door's width from its end; a partition's piece between two
   doors with a cabinet against it) or, however short, the pier between two doors
   (:func:`piers`: a wall's end in its line a door's width off each of its ends, across
   openings the free space passes) or between a wall it meets and a door
   (:func:`corner_piers`: a wall or another such pier in its line across the door). A
   face shorter than ``min_wall_length_m`` is clutter unless it connects two junctions,
   is a door's jamb (:func:`door_jambs`: in the line of a wall face, ``door_min_m`` to
   ``door_max_m`` beyond its end; the pier between a corner and a door is a wall however
   short) or such a pier. The plan's short-wall rounds keep the piers too.
5. **In front of a wall** (:func:`in_front_of_walls`). A face shorter than
   ``clutter_max_length_m`` (or, free on the same side, shorter than the wall and
   :data:`~floorscan.floorplan.hidden.HIDDEN_MAX_GAP_M`: a row of cabinets) parallel to
   a long wall face, ``front_min_m`` to ``front_max_m`` in front of it on its free
   side, is the front of a desk, a cabinet or a shelf standing against the wall:
   clutter; up to :data:`~floorscan.floorplan.hidden.OBJECT_MAX_DEPTH_M` where the
   wall's other face runs on behind it and the object's body was not seen free
   (:mod:`floorscan.floorplan.hidden`), as in the joins and corners of step 2. So are
   the object's sides, from the wall to the front's ends (:func:`object_sides`). A
   longer face is judged run by run between the partitions that end on it from its
   free side (:mod:`~floorscan.floorplan.partition_fronts`: objects in the two corners
   where a partition meets a wall, their fronts flush with its end): where every run
   is such a front, the face is, and the partition runs on to the wall behind. The
   floor between a front and the wall (:func:`floor_under`) is the room's floor
   (:mod:`floorscan.floorplan.rooms`).
6. **Loose in the free space** (:func:`loose_in_free_space`). A face that meets no
   other face at either end, crosses no face (an X junction: a partition crossing a
   wall between two doors), has no face in its line within ``loose_reach_m``, whose
   ends both stand in free space, and that has free space on both sides or a face
   parallel behind it, is furniture, however long (a 3 m rack in front of a wall, a
   row of chairs): clutter. Walls hold each other up; one that ends in free space ends
   at an opening, with the rest of its wall in line. So is a face shorter than
   ``clutter_max_length_m`` with free space on both sides, held at exactly one end and
   crossed by none, that runs in no direction of the long faces
   (:mod:`~floorscan.floorplan.oblique`: a desk turned in the room against a wall). So
   is a face held at exactly one end and met by no other between its ends whose free
   end lies in a body thicker than a wall and no deeper than a cabinet, its inside not
   seen occupied, that also lies behind the face's middle (:mod:`~floorscan.floorplan.object_ends`:
   a desk's side from the wall it stands against), unless it is in a wall's line or its
   line meets a face within a door's width (a door's jamb).

The rule of step 1 and 4 is the issue's (walls are the boundaries of the free space,
long enough and seen from more than one position; short pieces standing inside free
space are furniture), in the sense of the occupancy-grid room and wall work of
Bormann et al., "Room segmentation: survey, implementation, and analysis", ICRA 2016
(free space is what the robot saw, walls bound it); the thresholds are ours. Source of
the duplicate problem it completes: thesis section 5.1.
"""

from __future__ import annotations

import numpy as np

from floorscan.core.geometry import axial_mean
from floorscan.core.occupancy import OccupancyGrid
from floorscan.floorplan.candidates import candidate_pairs
from floorscan.floorplan.clutter import (
    free_standing_objects, in_front_of_walls, loose_in_free_space, object_sides, on_objects,
)
from floorscan.floorplan.free_space import LOOSE_IN_FREE_SPACE, StructureParams, mask_at, passable, segment_samples
from floorscan.floorplan.free_space import open_run as free_open_run
from floorscan.floorplan.hidden import HIDDEN_MAX_GAP_M, free_normals, hidden_by_objects, into_corners
from floorscan.floorplan.junctions import junction_ends, short_loose, shorter_on_longer, snap_junctions
from floorscan.floorplan.oblique import oblique_in_free_space
from floorscan.floorplan.object_ends import object_ends
from floorscan.floorplan.partition_fronts import fronts_between_partitions
from floorscan.floorplan.wall_pieces import corner_piers, door_jambs, in_wall_lines, piers


def border_and_support(seg: np.ndarray, grid: OccupancyGrid, params: StructureParams = StructureParams(),
                       both_free: bool = False):  # fmt: skip
    """Step 1: which faces border free space and lie on occupied cells (over half
    their length).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces ``x0, y0, x1, y1``, metres.
    grid : OccupancyGrid
        The free space of the plan's scans.
    params : StructureParams
    both_free : bool
        Also return which faces have free space on both sides.

    Returns
    -------
    structure : (F,) bool ndarray
    free_side : (F,) int8 ndarray
        +1 when the free space lies left of the face (direction x0, y0 -> x1, y1),
        -1 right, 0 both sides or neither.
    both : (F,) bool ndarray
        Only with ``both_free``: free space on both sides (``min_free_side`` of the face
        each).
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    if len(seg) == 0:
        return (np.zeros(0, bool), np.zeros(0, np.int8)) + ((np.zeros(0, bool),) if both_free else ())
    free = passable(grid)
    pts, owner, normal = segment_samples(seg, grid.resolution_m, trim=params.side_offset_m)
    off = params.side_offset_m * normal[owner]
    count = np.bincount(owner, minlength=len(seg)).astype(np.float64)
    left = np.bincount(owner, weights=mask_at(grid, free, pts + off), minlength=len(seg)) / count
    right = np.bincount(owner, weights=mask_at(grid, free, pts - off), minlength=len(seg)) / count
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
        [np.bincount(owner, weights=mask_at(grid, hit, pts + k * off), minlength=len(seg)) for k in (-2, -1, 1, 2)],
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
    if both_free:
        return structure, side, (left >= params.min_free_side) & (right >= params.min_free_side)
    return structure, side


def join_collinear(seg: np.ndarray, weights: np.ndarray, grid: OccupancyGrid, params: StructureParams = StructureParams(),
                   side: np.ndarray | None = None, open_run=None, free_at=None):  # fmt: skip
    """Step 2: collinear faces joined across gaps that free space does not pass through:
    up to ``join_max_gap_m``, or up to :data:`~floorscan.floorplan.hidden.HIDDEN_MAX_GAP_M`
    where objects standing against the wall hide the gap
    (:func:`~floorscan.floorplan.hidden.covered_by_fronts`; needs ``side``); a face
    joined across a gap and seen free over more than half its length is parted again
    (:func:`_apart_where_seen_through`: a row of objects).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    weights : (F,) float ndarray
        Their weights (inlier counts); a joined face's is the sum.
    grid : OccupancyGrid
    params : StructureParams
    side : (F,) int ndarray, optional
        The faces' free sides (:func:`border_and_support`); None: no gap is hidden.
    open_run : callable, optional
        :func:`~floorscan.floorplan.free_space.open_run` of ``grid``, when the caller has it.
    free_at : callable, optional
        ``free_at(xy)``: (N,) bool, whether the scans saw map points free: objects up to
        :data:`~floorscan.floorplan.hidden.OBJECT_MAX_DEPTH_M` deep then hide a gap where
        the wall's other face runs on behind it
        (:func:`~floorscan.floorplan.hidden.hidden_by_objects`); None: only ``front_max_m``.

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
    reach = params.join_max_gap_m if side is None else max(params.join_max_gap_m, HIDDEN_MAX_GAP_M)
    i, j = candidate_pairs(seg, reach, np.radians(params.join_angle_deg))
    length, a, b, tb, off = shorter_on_longer(seg, i, j)  # along and across the longer face's line
    keep = np.zeros(len(i), dtype=bool)
    if len(i):
        u = (seg[a, 2:] - seg[a, :2]) / np.maximum(length[a], 1e-12)[:, None]
        lo_b, hi_b = tb.min(axis=1), tb.max(axis=1)
        gap = np.maximum(lo_b - length[a], -hi_b)
        keep = (np.abs(off).max(axis=1) <= params.join_offset_m) & (gap <= reach)
        if side is not None:  # a longer gap: hidden by fronts, both faces free on the same side
            side = np.asarray(side)
            _, _, free_n = free_normals(seg, side)
            for k in np.flatnonzero(keep & (gap > params.join_max_gap_m)).tolist():
                t0, t1 = (length[a[k]], lo_b[k]) if lo_b[k] > length[a[k]] else (hi_b[k], 0.0)
                same_way = free_n[a[k]] @ free_n[b[k]] > 0
                hidden = hidden_by_objects(seg, side, int(a[k]), min(t0, t1), max(t0, t1), params, free_at)
                keep[k] = same_way and hidden
        open_run = free_open_run(grid) if open_run is None else open_run
        for k in np.flatnonzero(keep & (gap > grid.resolution_m / 2)).tolist():
            t0, t1 = (length[a[k]], lo_b[k]) if lo_b[k] > length[a[k]] else (hi_b[k], 0.0)
            keep[k] = open_run(seg[a[k], :2], u[k], t0, t1) < params.min_opening_m
    graph = coo_matrix((np.ones(int(keep.sum())), (i[keep], j[keep])), shape=(nf, nf))
    group = _apart_where_seen_through(seg, connected_components(graph, directed=False)[1], length, grid, free_at)
    n_groups = int(group.max()) + 1
    joined = np.empty((n_groups, 4))
    for g in range(n_groups):
        joined[g] = _fit_group(seg[group == g], length[group == g])
    return joined, np.bincount(group, weights=w, minlength=n_groups), group.astype(np.int64)


def _apart_where_seen_through(seg: np.ndarray, group: np.ndarray, length: np.ndarray, grid: OccupancyGrid,
                              free_at=None) -> np.ndarray:
    """``group`` (:func:`join_collinear`; ``length``: the faces' lengths), with the faces
    of a joined face parted again where the scans saw free space on more than half of
    the joined face's length: the
    pieces are a row of objects with the floor seen between them (a table's legs, a row
    of chairs), not one wall, as a face that is not occupied over half its length is
    not (:func:`border_and_support`). A point of the face is seen free when the cells
    one cell to either side of it are free too. Only a group joined across a gap wider
    than a cell is tested (faces lying over one another are a wall found twice)."""
    if free_at is None:
        free = passable(grid)

        def free_at(xy):
            return mask_at(grid, free, xy)

    out, nxt = group.copy(), int(group.max()) + 1
    for g in np.flatnonzero(np.bincount(group) > 1).tolist():
        members = np.flatnonzero(group == g)
        f = _fit_group(seg[members], length[members])
        total = float(np.hypot(f[2] - f[0], f[3] - f[1]))
        u = (f[2:] - f[:2]) / max(total, 1e-12)
        t = np.sort(seg[members].reshape(-1, 2, 2) @ u - f[:2] @ u, axis=1)
        t = t[np.argsort(t[:, 0])]
        if not (t[1:, 0] - np.maximum.accumulate(t[:-1, 1]) > grid.resolution_m).any():
            continue  # faces one over another (a wall found twice), no gap joined
        n = max(int(np.ceil(total / (grid.resolution_m / 2))), 1)
        on = f[:2] + np.outer((np.arange(n) + 0.5) / n, f[2:] - f[:2])
        across = np.array([-u[1], u[0]]) * grid.resolution_m
        # free across the face's line, a cell to either side too (a face fitted on the
        # returns of a wall lies on the boundary of its cells)
        seen = free_at(on) & free_at(on + across) & free_at(on - across)
        if seen.mean() > 0.5:
            out[members] = nxt + np.arange(len(members))
            nxt += len(members)
    return np.unique(out, return_inverse=True)[1].astype(np.int64)


def _group_sides(seg: np.ndarray, side: np.ndarray, group: np.ndarray, n: int) -> np.ndarray:
    """(n,) int8: each joined face's free side, its longest member's."""
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    out = np.zeros(n, dtype=np.int8)
    for i in np.argsort(length, kind="stable"):  # the longest member written last
        out[group[i]] = side[i]
    return out


def _fit_group(seg: np.ndarray, length: np.ndarray) -> np.ndarray:
    """One face for collinear faces: the length-weighted axial mean direction, the
    length-weighted mean offset, the extent of all their ends."""
    if len(seg) == 1:
        return seg[0].copy()
    phi = axial_mean(np.arctan2(seg[:, 3] - seg[:, 1], seg[:, 2] - seg[:, 0]), length)
    u = np.array([np.cos(phi), np.sin(phi)])
    n = np.array([-u[1], u[0]])
    mid = 0.5 * (seg[:, :2] + seg[:, 2:])
    off = float((mid @ n * length).sum() / length.sum())
    t = np.concatenate([seg[:, :2] @ u, seg[:, 2:] @ u])
    return np.r_[off * n + t.min() * u, off * n + t.max() * u]


#: How far short of the corner it meets a face's end may stop, beyond half a cell of the
#: grid, metres: the map extractor (:mod:`floorscan.walls.map_lines`) gives the points
#: within its inlier distance of a line (0.04 m) to the first line it fits, on
#: thinning cells of 0.03 m, so the line that meets it at a corner starts up to their
#: sum short of it (and a cell's centre lies up to half a cell off the corner).
CLAIMED_M = 0.07


def long_enough(seg: np.ndarray, min_length_m: float, resolution_m: float, params: StructureParams = StructureParams()):
    """Step 0: the faces at least ``min_length_m`` long, a face's ends carried first to
    the corners they stop short of by at most :data:`CLAIMED_M` and half a cell
    (:func:`~floorscan.floorplan.junctions.snap_junctions` with that reach).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Merged faces, metres.
    min_length_m : float
        Metres.
    resolution_m : float
        The grid's cell, metres.
    params : StructureParams
        ``junction_min_angle_deg``.

    Returns
    -------
    keep : (F,) bool ndarray
    faces : (F, 4) float64 ndarray
        ``seg``, with the ends of the faces kept only for their carried ends carried,
        metres.
    """
    from dataclasses import replace

    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    short = length < min_length_m
    if not short.any():
        return ~short, seg
    carried, _ = snap_junctions(seg, replace(params, snap_m=CLAIMED_M + resolution_m / 2))
    carried_length = np.hypot(carried[:, 2] - carried[:, 0], carried[:, 3] - carried[:, 1])
    keep = ~short | (carried_length >= min_length_m)
    return keep, np.where((short & keep)[:, None], carried, seg)


def structure_passes(
    seg: np.ndarray, weights: np.ndarray, grid: OccupancyGrid, params: StructureParams = StructureParams(),
    max_thickness_m: float = 0.4, door_max_m: float = 2.0, door_min_m: float = 0.6, min_length_m: float = 0.0,
):  # fmt: skip
    """Steps 0 to 6 on the merged faces of a plan (see the module docstring).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Merged faces, metres.
    weights : (F,) float ndarray
        Their weights (inlier counts).
    grid : OccupancyGrid
        The free space of the plan's scans.
    params : StructureParams
    max_thickness_m : float
        The thickest wall, metres (the plan's ``pair_max_m``; step 6).
    door_max_m : float
        The widest door, metres (``floorplan.rooms.door_max_m``; step 4's pieces of a
        wall and door jambs).
    door_min_m : float
        The narrowest door, metres (``floorplan.rooms.door_min_m``; step 4's door jambs).
    min_length_m : float
        The shortest face, metres (the plan's ``min_length_m``; step 0); a face dropped
        for it is in no output, as the plan's faces shorter than it are not.

    Returns
    -------
    walls : (W, 4) float64 ndarray
        The structure's faces, joined and snapped, metres.
    wall_weights : (W,) float64 ndarray
    free_side : (W,) int8 ndarray
        Which side of each face the free space is on (+1 left, -1 right, 0 both or
        neither; see :func:`border_and_support`); a face run on behind objects, with
        too little free space beside it to tell, keeps the side of its seen pieces.
    clutter : (C, 4) float64 ndarray
        The faces that are not structure (furniture, single-scan returns), metres.
    reason : (C,) object ndarray
        Why each clutter face is clutter: ``not_a_boundary`` (no free space beside it, or returns on both sides, or on cells that are not occupied),
        ``free_standing_object``, ``in_front_of_wall``, ``short`` or ``loose_in_free_space``.
    under : (K, 4, 2) float64 ndarray
        The floor under each object standing against a wall (step 5): the quadrilateral
        from its front to the wall face behind it, metres (:func:`floor_under`).
    """
    keep, seg = long_enough(seg, min_length_m, grid.resolution_m, params)
    seg, w = seg[keep], np.asarray(weights, dtype=np.float64).ravel()[keep]
    structure, side0 = border_and_support(seg, grid, params)
    clutter = [seg[~structure]]
    reason = [np.full(int((~structure).sum()), "not_a_boundary", dtype=object)]
    free = passable(grid)  # once, for the openings and the objects' bodies
    open_run = free_open_run(grid, free)

    def free_at(xy: np.ndarray) -> np.ndarray:
        return mask_at(grid, free, xy)

    joined, jw, group = join_collinear(seg[structure], w[structure], grid, params, side0[structure], open_run, free_at)
    joined_side = _group_sides(seg[structure], side0[structure], group, len(joined))
    joined = into_corners(joined, joined_side, open_run, params, free_at)
    snapped, junctions = snap_junctions(joined, params)
    length = np.hypot(snapped[:, 2] - snapped[:, 0], snapped[:, 3] - snapped[:, 1])
    anchor = length >= params.clutter_max_length_m
    standing = on_objects(snapped, grid, free_standing_objects(grid, params, snapped[anchor], max_thickness_m)) & ~anchor
    standing &= ~in_wall_lines(snapped, standing, grid.resolution_m, params, door_max_m)
    standing &= ~piers(snapped, standing, grid, params, door_min_m, door_max_m, junctions, open_run)
    standing &= ~corner_piers(snapped, standing, junctions, grid, params, door_min_m, door_max_m, open_run=open_run)
    # a face run on behind objects has too little free space beside it to show a side;
    # it keeps the side its seen pieces had
    _, side, both = border_and_support(snapped, grid, params, both_free=True)
    side = np.where(side != 0, side, joined_side).astype(side.dtype)
    front, behind = in_front_of_walls(snapped, side, anchor, params, free_at)
    whole = front.copy()  # fronts as faces; the others found here run by run
    front, behind, runs, runs_behind, carried = fronts_between_partitions(snapped, side, anchor, junctions, front,
                                                                          behind, params, free_at)  # fmt: skip
    for g, k, xy in carried:  # a partition runs on behind the fronts in its corners to the wall
        joined[g, 2 * k : 2 * k + 2] = xy
    front &= ~standing
    against = front | object_sides(snapped, side, front, behind, params) & ~standing  # fronts and their sides
    short = short_loose(snapped, junctions, params.min_wall_length_m) & ~standing & ~against
    short &= ~door_jambs(snapped, short, params, door_min_m, door_max_m, standing | against)
    short &= ~corner_piers(snapped, short, junctions, grid, params, door_min_m, door_max_m, standing | against, open_run)
    crossed = np.zeros(len(snapped), dtype=bool)
    crossed[junctions[junctions[:, 4] == 3][:, 2:4].astype(np.int64).ravel()] = True  # X junctions
    held = junction_ends(snapped, junctions)
    loose = loose_in_free_space(snapped, held, side, grid, params, max_thickness_m, crossed)
    loose |= oblique_in_free_space(snapped, held, crossed, both, params)
    loose |= object_ends(snapped, held, junctions, free, grid.occupied(), grid, params, max_thickness_m, door_max_m)
    loose &= ~standing & ~against & ~short
    keep = ~standing & ~against & ~short & ~loose
    clutter += [snapped[standing], snapped[against], snapped[short], snapped[loose]]
    reason += [np.full(int(standing.sum()), "free_standing_object", dtype=object),
               np.full(int(against.sum()), "in_front_of_wall", dtype=object),
               np.full(int(short.sum()), "short", dtype=object),
               np.full(int(loose.sum()), LOOSE_IN_FREE_SPACE, dtype=object)]  # fmt: skip
    # the walls meet again without the clutter; a face the new ends left short goes
    walls, junctions = snap_junctions(joined[keep], params)
    still = ~short_loose(walls, junctions, params.min_wall_length_m)
    still |= door_jambs(walls, ~still, params, door_min_m, door_max_m)
    still |= corner_piers(walls, ~still, junctions, grid, params, door_min_m, door_max_m, open_run=open_run)
    clutter.append(walls[~still])
    reason.append(np.full(int((~still).sum()), "short", dtype=object))
    walls, _ = snap_junctions(joined[keep][still], params)
    _, side = border_and_support(walls, grid, params)
    side = np.where(side != 0, side, joined_side[keep][still]).astype(side.dtype)
    whole &= front
    under = np.concatenate([floor_under(snapped[whole], snapped[behind[whole]]), floor_under(runs, runs_behind)])
    return walls, jw[keep][still], side, np.concatenate(clutter).reshape(-1, 4), np.concatenate(reason), under


def floor_under(fronts: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """The floor under objects standing against walls: each front and its ends'
    projections onto the line of the wall face behind it.

    Parameters
    ----------
    fronts, walls : (K, 4) float ndarray
        Each front and its wall face, metres.

    Returns
    -------
    (K, 4, 2) float64 ndarray
        Corners in order (front's first end, front's second end, their projections),
        metres.
    """
    fronts = np.asarray(fronts, dtype=np.float64).reshape(-1, 4)
    walls = np.asarray(walls, dtype=np.float64).reshape(-1, 4)
    d = walls[:, 2:] - walls[:, :2]
    u = d / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)[:, None]

    def onto(p):
        return walls[:, :2] + np.einsum("ij,ij->i", p - walls[:, :2], u)[:, None] * u

    return np.stack([fronts[:, :2], fronts[:, 2:], onto(fronts[:, 2:]), onto(fronts[:, :2])], axis=1)


"""Wall faces hidden behind the objects that stand against them (the structure passes,
:mod:`floorscan.floorplan.structure`, steps 2 and 5).

A cabinet, a shelf or a desk pushed against a wall hides the wall's face: the scans (and
a map's obstacle cells) show the object's front instead, parallel to the wall and
``front_min_m`` to ``front_max_m`` in front of it on its free side, while the wall's face
goes on beside the object, in the same line. A floor plan draws the wall, not the
object: the room's floor runs under its furniture, and its walls are its structure
(issue 44; the thesis's clutter, sections 1.3 and 2.3). So:

two collinear faces whose gap is covered by such fronts (:func:`covered_by_fronts`) are
one face across it, up to :data:`HIDDEN_MAX_GAP_M`
(:func:`floorscan.floorplan.structure.join_collinear`); a face that ends at an object
standing in a corner runs on behind its front to the corner (:func:`into_corners`);
and the fronts, now in front of a wall, are clutter
(:func:`floorscan.floorplan.clutter.in_front_of_walls`). Free space
across the gap still makes it an opening (the joins' own test): a doorway between two
cabinets stays a door. Sides of the objects are left to the other passes: a face that
runs from a wall to the end of a front may be a partition's stub as well.

Deeper objects (a desk with its chair, a bed, cabinets back to back; up to
:data:`OBJECT_MAX_DEPTH_M`) count only where the wall's thickness is seen: its other
face runs on straight behind the stretch (:func:`backed`), and the scans did not see
the object's body free (:func:`body_seen_free`), or, at a partition's end, where
objects as deep stand on its two sides, back to back, from its end on (each face is
then backed by the other side's object, :func:`back_to_back`). From the room alone a
deep object and a step of the wall (a shaft, an alcove, an outer wall's jog) look the same; a wall
that steps moves both its faces, so its other face is not behind the stretch. This is
the thickness evidence of wall detection from both sides (Ochmann et al., "Automatic
reconstruction of fully volumetric 3D building models from oriented point clouds",
ISPRS J. 2019: a wall is two opposite faces a wall's thickness apart).
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.candidates import candidate_pairs
from floorscan.floorplan.free_space import StructureParams

#: The longest object against a wall whose hidden face is joined, metres: a row of
#: cabinets or shelves, two of the longest pieces of furniture (``clutter_max_length_m``).
HIDDEN_MAX_GAP_M = 5.0

#: The deepest object against a wall whose hidden face is restored when the wall's other
#: face is seen running on behind the object (:func:`backed`), metres: a desk with its
#: chair, a bed, two rows of cabinets back to back. Without the other face only
#: ``front_max_m`` (a cabinet): a wall that steps back by more (a shaft, an alcove, an
#: outer wall's jog) looks the same from the room, and only the wall's thickness, seen
#: where its other face runs on straight, tells the object from the structure.
OBJECT_MAX_DEPTH_M = 2.0

#: The thickest wall whose other face backs an object (:func:`backed`), metres: outer
#: and load-bearing walls, and the 0.5 to 1 m strokes of a map drawn by hand. A wall
#: that steps into the room by more than it is thick moves its other face too, in
#: front of the line, so a real step of the structure is not backed.
BACKING_MAX_M = 1.0
#: Passes of :func:`into_corners`: a face carried into its corner behind a shallow object
#: backs the other face of its wall behind a deeper one (cabinets back to back on the two
#: sides of a partition), which the next pass carries in; a third changes nothing more.
INTO_CORNERS_PASSES = 3


def free_normals(seg: np.ndarray, side: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each face's direction, length and the unit normal towards its free side.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    side : (F,) int ndarray
        Free sides (+1 left, -1 right, 0 both or neither;
        :func:`~floorscan.floorplan.structure.border_and_support`).

    Returns
    -------
    u : (F, 2) float64 ndarray
    length : (F,) float64 ndarray
        Metres.
    n : (F, 2) float64 ndarray
        Zero where ``side`` is 0.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    d = seg[:, 2:] - seg[:, :2]
    length = np.hypot(d[:, 0], d[:, 1])
    u = d / np.maximum(length, 1e-12)[:, None]
    n = np.column_stack([-u[:, 1], u[:, 0]]) * np.sign(np.asarray(side, dtype=np.float64))[:, None]
    return u, length, n


def _line_frame(seg: np.ndarray, side: np.ndarray, a: int, params: StructureParams):
    """Face ``a``'s frame: every face's direction ``u``, length and free normal ``n``
    (:func:`free_normals`), whether it is parallel to ``a`` (within ``join_angle_deg``)
    and its ends along ``a``'s line from ``a``'s first end ((F, 2), sorted, metres)."""
    u, length, n = free_normals(seg, side)
    parallel = np.abs(u @ u[a]) >= np.cos(np.radians(params.join_angle_deg))
    along = np.sort(np.column_stack([(seg[:, :2] - seg[a, :2]) @ u[a], (seg[:, 2:] - seg[a, :2]) @ u[a]]), axis=1)
    return u, length, n, parallel, along


def _covers(s: np.ndarray, t0: float, t1: float) -> float:
    """The length of ``t0..t1`` the union of the stretches ``s`` ((K, 2), sorted ends)
    covers, metres."""
    s = np.clip(s, t0, t1)
    s = s[np.argsort(s[:, 0])]
    covered, reach = 0.0, t0
    for lo, hi in s.tolist():
        lo = max(lo, reach)
        if hi > lo:
            covered += hi - lo
            reach = hi
    return covered


def body_seen_free(p: np.ndarray, u: np.ndarray, n: np.ndarray, t0: float, t1: float, depth: float, free_at,
                   step: float) -> float:  # fmt: skip
    """The share of the body of an object against a wall that the scans saw free: the
    rectangle from the wall's line (through ``p``, along the unit ``u``) ``t0..t1``
    along it and up to ``depth`` in front of it (along the unit ``n``), sampled every
    ``step`` (metres) inside its edges; ``free_at(xy)``: (N,) bool of map points
    ((N, 2) metres). A wall's face across a corridor is not an object's front: the
    corridor between is free."""
    along = np.arange(t0 + step, t1 - step / 2, step)
    across = np.arange(step, depth - step / 2, step)
    if not len(along) or not len(across):
        return 0.0
    tt, dd = np.meshgrid(along, across)
    return float(free_at(p + u * tt.reshape(-1, 1) + n * dd.reshape(-1, 1)).mean())


def backed(seg: np.ndarray, side: np.ndarray, a: int, t0: float, t1: float,
           params: StructureParams = StructureParams(), depth_max_m: float = BACKING_MAX_M) -> bool:  # fmt: skip
    """Whether the other face of face ``a``'s wall runs on behind the stretch ``t0..t1``
    of its line: faces parallel to it (within ``join_angle_deg``), free the other way,
    behind its line by at most ``depth_max_m`` (:data:`BACKING_MAX_M`), cover at least
    ``front_overlap`` of the stretch. The wall is then a wall's thickness there, and what
    stands on the free side of ``a``'s line is in front of it. Parameters as
    :func:`covered_by_fronts` (``seg``, ``side``, ``a``, ``t0``, ``t1``, ``params``);
    returns bool."""
    if side[a] == 0 or t1 <= t0:
        return False
    _, s, behind = _behind(seg, side, a, params, depth_max_m)
    return bool(behind.any()) and _covers(s[behind], t0, t1) >= params.front_overlap * (t1 - t0)


def _behind(seg: np.ndarray, side: np.ndarray, a: int, params: StructureParams, depth_max_m: float):
    """Face ``a``'s frame (:func:`_line_frame`: ``u``, the ends along its line ``s``)
    and the faces that may be the other face of its wall: parallel to it, free the other
    way, wholly behind its line by at most ``depth_max_m`` ((F,) bool, ``a`` not)."""
    u, _, n, parallel, s = _line_frame(seg, side, a, params)
    ends = np.stack([(seg[:, :2] - seg[a, :2]) @ n[a], (seg[:, 2:] - seg[a, :2]) @ n[a]], axis=1)
    behind = parallel & ((n @ n[a]) < 0) & (ends.max(axis=1) < 0) & (ends.min(axis=1) >= -depth_max_m)
    behind[a] = False
    return u, s, behind


def back_to_back(seg: np.ndarray, side: np.ndarray, a: int, t0: float, t1: float, params: StructureParams,
                 free_at) -> bool:
    """Whether objects stand back to back on the two sides of face ``a``'s partition
    along the stretch ``t0..t1`` of its line beyond one of its ends: the other face of
    its wall (parallel, free the other way, behind ``a``'s line by at most
    :data:`BACKING_MAX_M`) ends within ``front_min_m`` of where ``a`` ends and the
    stretch begins, and objects up to :data:`OBJECT_MAX_DEPTH_M` deep, whose bodies the
    scans did not see free, cover the stretch on that face's side too
    (:func:`covered_by_fronts`). Neither face then backs the other's objects
    (:func:`backed`), yet the partition's line runs on between them: two cabinets
    1 m deep against its two sides, each deeper than ``front_max_m``. ``free_at`` as
    :func:`covered_by_fronts`; other parameters as :func:`backed`; returns bool."""
    if side[a] == 0 or t1 <= t0:
        return False
    u, s, other = _behind(seg, side, a, params, BACKING_MAX_M)
    # the stretch lies beyond the other face's end, which is where a's end is: past a's
    # far end (t0 at its length) or before its first (t1 at 0)
    beyond_far = t0 >= s[a, 1] - params.front_min_m
    a_end = t0 if beyond_far else t1
    stops = s[:, 1] if beyond_far else s[:, 0]
    other &= (np.abs(stops - a_end) <= params.front_min_m) & (s[:, 1] - s[:, 0] > params.front_min_m)
    p0, p1 = seg[a, :2] + t0 * u[a], seg[a, :2] + t1 * u[a]
    for b in np.flatnonzero(other).tolist():
        b0, b1 = sorted((float((p0 - seg[b, :2]) @ u[b]), float((p1 - seg[b, :2]) @ u[b])))
        if covered_by_fronts(seg, side, b, b0, b1, params, params.front_max_m, OBJECT_MAX_DEPTH_M, free_at):
            return True
    return False


def hidden_by_objects(seg: np.ndarray, side: np.ndarray, a: int, t0: float, t1: float,
                      params: StructureParams = StructureParams(), free_at=None,
                      beside_max_m: float | None = None, shallow: bool = True) -> bool:  # fmt: skip
    """Whether objects against face ``a``'s wall hide the stretch ``t0..t1`` of its line:
    fronts up to ``front_max_m`` deep cover it (:func:`covered_by_fronts`; unless not
    ``shallow``), or, where the wall's other face runs on behind it (:func:`backed`;
    with ``free_at``), fronts up to :data:`OBJECT_MAX_DEPTH_M` deep do. Parameters as
    :func:`covered_by_fronts`; returns bool."""
    if shallow and covered_by_fronts(seg, side, a, t0, t1, params, beside_max_m):
        return True
    return (free_at is not None and backed(seg, side, a, t0, t1, params)
            and covered_by_fronts(seg, side, a, t0, t1, params, beside_max_m, OBJECT_MAX_DEPTH_M, free_at))  # fmt: skip


def covered_by_fronts(seg: np.ndarray, side: np.ndarray, a: int, t0: float, t1: float,
                      params: StructureParams = StructureParams(), beside_max_m: float | None = None,
                      depth_max_m: float | None = None, free_at=None) -> bool:  # fmt: skip
    """Whether the stretch ``t0..t1`` of face ``a``'s line is hidden by objects standing
    against it: faces parallel to it (within ``join_angle_deg``), with their free side
    the same way, ``front_min_m`` to ``front_max_m`` in front of it, cover at least
    ``front_overlap`` of the stretch.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    side : (F,) int ndarray
        Free sides.
    a : int
        The face whose line is tested; its free side must be known (``side[a] != 0``).
    t0, t1 : float
        The stretch along ``a``'s line from its first end, metres, ``t0 < t1``.
    params : StructureParams
    beside_max_m : float, optional
        Fronts that run beside face ``a`` itself for longer than this (metres: the
        other face of its wall) do not count; None: all count.
    depth_max_m : float, optional
        The deepest front, metres; None: ``front_max_m``. A front deeper than
        ``front_max_m`` counts only when the scans saw less than ``min_free_side`` of
        the body between it and the line free (:func:`body_seen_free`, with ``free_at``).
    free_at : callable, optional
        ``free_at(xy)``: (N,) bool, whether the scans saw the map points ``xy`` free.

    Returns
    -------
    bool
    """
    depth_max_m = params.front_max_m if depth_max_m is None else depth_max_m
    if side[a] == 0 or t1 <= t0:
        return False
    u, length, n, parallel, s = _line_frame(seg, side, a, params)
    same_way = (n @ n[a]) > 0
    mid = 0.5 * (seg[:, :2] + seg[:, 2:])
    depth = (mid - seg[a, :2]) @ n[a]
    front = parallel & same_way & (depth >= params.front_min_m) & (depth <= depth_max_m)
    front[a] = False
    if beside_max_m is not None:
        front &= np.minimum(s[:, 1], length[a]) - np.maximum(s[:, 0], 0.0) <= beside_max_m
    for k in np.flatnonzero(front & (depth > params.front_max_m)).tolist():  # deeper: its body not seen free
        front[k] = free_at is not None and body_seen_free(
            seg[a, :2], u[a], n[a], max(s[k, 0], t0), min(s[k, 1], t1), float(depth[k]), free_at, params.side_offset_m
        ) < params.min_free_side
    if not front.any():
        return False
    return _covers(s[front], t0, t1) >= params.front_overlap * (t1 - t0)


def into_corners(seg: np.ndarray, side: np.ndarray, open_run, params: StructureParams = StructureParams(),
                 free_at=None) -> np.ndarray:  # fmt: skip
    """Faces that end at an object standing in a corner, extended to the corner.

    An object in a room's corner (a cabinet, an L of shelves) hides the two walls up to
    their corner: a wall face ends at the object's side, the object's front runs on,
    parallel, in front of the face's line up to the other wall. Face ``a``'s end is
    moved to where its line meets a face square to it (at least
    ``junction_min_angle_deg`` apart) when that point lies at most
    :data:`HIDDEN_MAX_GAP_M` beyond the end and within ``front_max_m`` of that face,
    fronts cover the stretch (:func:`covered_by_fronts`; a face running beside ``a``
    itself for more than ``front_max_m`` is the other face of its wall, not a front)
    and free space does not cross it (``open_run`` shorter than ``min_opening_m``).
    Where the other face of ``a``'s wall runs on behind the stretch (:func:`backed`),
    the object may be :data:`OBJECT_MAX_DEPTH_M` deep, and the square face end as far
    from the corner (the object hides it too). The nearest such face along the line is
    the corner; of the pieces of one wall face on that line (within ``front_min_m`` of
    it), the one the line meets nearest; where that is the front of an object against
    the wall square to ``a`` (an L of desks in the corner: the wall seen past the
    object's far end, ``front_min_m`` to ``front_max_m`` behind the front,
    :func:`_wall_behind`), ``a`` runs on to that wall, the stretch up to the front tested
    as before. A face that ends on a wall square to it (longer
    than :data:`OBJECT_MAX_DEPTH_M`, within ``front_min_m``) is in its corner: it is not
    carried through that wall. The side of an object at ``a``'s end (a square face
    shorter than :data:`OBJECT_MAX_DEPTH_M`, less than ``front_min_m`` beyond it) is no
    corner where a room lies behind ``a``'s wall within :data:`OBJECT_MAX_DEPTH_M` along
    the stretch to the next corner (:func:`backed` that deep): the object stands
    against a partition, whose line runs on behind it; a step of an outer wall has no
    room behind it. A face ``a`` ends on that crosses its wall (``front_min_m`` or more
    on each side of its line), no deeper into the room than an object and no farther
    behind than an object and a wall's thickness, is such a side too (two objects'
    sides flush with a partition's end) where objects stand back to back
    (:func:`back_to_back`) up to a face that looks back at ``a``'s end. Up to
    :data:`INTO_CORNERS_PASSES` passes, each face carried once: a face carried in
    behind a shallow cabinet backs its wall's other face behind a deeper cabinet on the
    partition's other side (cabinets back to back).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    side : (F,) int ndarray
        Free sides.
    open_run : callable
        ``open_run(p, u, t0, t1)``: the longest run of free space on the stretch
        ``t0..t1`` of the line through ``p`` along ``u``, metres
        (:func:`floorscan.floorplan.structure.join_collinear`'s test).
    params : StructureParams
    free_at : callable, optional
        As :func:`covered_by_fronts`; None: no object deeper than ``front_max_m``.

    Returns
    -------
    (F, 4) float64 ndarray
        The faces, some ends moved; metres.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    side = np.asarray(side)
    todo = side != 0
    for _ in range(INTO_CORNERS_PASSES):
        out = _into_corners_once(seg, side, open_run, params, free_at, todo)
        moved = np.any(out != seg, axis=1)
        if not moved.any():
            break
        # a face is carried into its corner once; the next pass tests the faces that a
        # moved face may now back (parallel, within an object's depth)
        i, j = candidate_pairs(out, OBJECT_MAX_DEPTH_M, np.radians(params.join_angle_deg))
        near = np.zeros(len(out), dtype=bool)
        near[i[moved[j]]] = near[j[moved[i]]] = True
        seg, todo = out, todo & ~moved & near
        if not todo.any():
            break
    return out


def _corner(ok: np.ndarray, t: np.ndarray, gap: np.ndarray, same_line_m: float) -> int:
    """Of the faces ``ok``, the corner: the nearest line along ``t`` (metres beyond the
    end); of its faces (pieces of one wall face, within ``same_line_m`` of it), the one
    the line meets nearest (``gap``, metres beyond the face's extent)."""
    first = np.flatnonzero(ok & (t <= t[ok].min() + same_line_m))
    return int(min(first.tolist(), key=lambda c: (gap[c], t[c], c)))


def _wall_behind(seg: np.ndarray, u: np.ndarray, free_n: np.ndarray, length: np.ndarray, ok: np.ndarray, p: int,
                 at: float, beyond: np.ndarray, params: StructureParams) -> int:  # fmt: skip
    """The wall face behind face ``p``, the corner :func:`into_corners` found for a face
    ``a``, when ``p`` is the front of an object standing against it: an L of desks or
    shelves in the room's corner, whose other leg's front ``a``'s stretch runs behind.

    Of the faces ``ok`` (square to ``a``, in the room), one parallel to ``p`` (within
    ``join_angle_deg``) and free the same way, ``front_min_m`` to ``front_max_m``
    beyond it along ``a``'s line (``beyond``, (F,) metres), running on from within
    ``front_max_m`` of ``p``'s end away from ``a``'s line (``at``: where ``a``'s line
    meets ``p``'s, metres along ``p``): the wall seen past the object's far end. The
    nearest; -1 for none.
    """
    along = np.stack([(seg[:, :2] - seg[p, :2]) @ u[p], (seg[:, 2:] - seg[p, :2]) @ u[p]], axis=1)
    apart = np.maximum(np.maximum(along.min(axis=1) - length[p], -along.max(axis=1)), 0.0)
    wall = (ok & (apart <= params.front_max_m) & (beyond >= params.front_min_m) & (beyond <= params.front_max_m)
            & (np.abs(u @ u[p]) >= np.cos(np.radians(params.join_angle_deg))) & (free_n @ free_n[p] > 0)
            & ((along.mean(axis=1) - length[p] / 2) * (at - length[p] / 2) < 0))  # fmt: skip
    wall[p] = False
    if not wall.any():
        return -1
    return int(np.flatnonzero(wall)[np.argmin(beyond[wall])])


def _into_corners_once(seg: np.ndarray, side: np.ndarray, open_run, params: StructureParams, free_at,
                       todo: np.ndarray) -> np.ndarray:  # fmt: skip
    """One pass of :func:`into_corners` over the faces ``todo``, each tested against ``seg``."""
    u, length, free_n = free_normals(seg, side)
    square = np.sin(np.radians(params.junction_min_angle_deg))
    reach = params.front_max_m if free_at is None else OBJECT_MAX_DEPTH_M
    out = seg.copy()
    for a in np.flatnonzero(todo).tolist():
        # a corner's face stands in the room a bounds, on a's free side of its line; a
        # face wholly behind the line is in the wall or beyond it (an object in the next room)
        across = np.stack([(seg[:, :2] - seg[a, :2]) @ free_n[a], (seg[:, 2:] - seg[a, :2]) @ free_n[a]], axis=1)
        in_room = across.max(axis=1) > 0
        # a square face that crosses a's wall, at least front_min_m on each side of its
        # line, no deeper into the room than an object and no farther behind than an
        # object and a wall's thickness: a wall a's end is on, or the sides of two
        # objects back to back, flush with the end of the partition between them
        into, behind = across.max(axis=1), -across.min(axis=1)
        flush = ((np.minimum(into, behind) >= params.front_min_m) & (into <= OBJECT_MAX_DEPTH_M)
                 & (behind <= OBJECT_MAX_DEPTH_M + BACKING_MAX_M))  # fmt: skip
        for k in (0, 1):
            end = seg[a, 2 * k : 2 * k + 2]
            out_dir = u[a] if k == 1 else -u[a]
            # where a's line meets each other face's line, t beyond a's end
            denom = out_dir[0] * u[:, 1] - out_dir[1] * u[:, 0]
            w = seg[:, :2] - end
            with np.errstate(divide="ignore", invalid="ignore"):  # parallel lines: t inf or nan, not ok
                t = (w[:, 0] * u[:, 1] - w[:, 1] * u[:, 0]) / denom
                x = end + t[:, None] * out_dir
                s = np.einsum("ij,ij->i", x - seg[:, :2], u)
                gap = np.maximum(np.maximum(-s, s - length), 0.0)
                ok = (np.abs(denom) >= square) & (t <= HIDDEN_MAX_GAP_M) & (gap <= reach)
                # beyond a's end; or a wall (longer than an object is deep) that a's end
                # is on, within front_min_m: a is in its corner already
                on_wall = (t > -params.front_min_m) & (gap <= params.front_min_m) & (length > OBJECT_MAX_DEPTH_M)
                ok &= ((t > 0) | on_wall) & in_room
            ok[a] = False
            if not ok.any():
                continue
            t0 = float((end - seg[a, :2]) @ u[a])

            def stretch(c: int) -> tuple[float, float]:
                # a's line from its end to where it meets face c, along a
                return (t0, t0 + float(t[c])) if k == 1 else (t0 - float(t[c]), t0)

            p = _corner(ok, t, gap, params.front_min_m)
            paired = False  # back_to_back up to p, when found so on the way
            # the side of an object at a's end (no deeper than an object) is no corner when
            # a room lies behind a's wall within an object's depth along the stretch to the
            # next corner: the object stands against a partition, whose line runs on to it
            # (cabinets back to back); a step of an outer wall has no room behind it
            beyond = ok & ~((t < params.front_min_m) & (length <= OBJECT_MAX_DEPTH_M))
            if t[p] < params.front_min_m and length[p] <= OBJECT_MAX_DEPTH_M and beyond.any():
                q = _corner(beyond, t, gap, params.front_min_m)
                if backed(seg, side, a, *stretch(q), params, OBJECT_MAX_DEPTH_M):
                    p = q
            elif t[p] < params.front_min_m and flush[p] and free_at is not None and (ok & (t >= params.front_min_m)).any():
                # a's end on a face flush across it: the objects back to back beside its
                # wall's end when they hide the stretch on both sides up to the corner
                q = _corner(ok & (t >= params.front_min_m), t, gap, params.front_min_m)
                if float(free_n[q] @ out_dir) < 0 and back_to_back(seg, side, a, *stretch(q), params, free_at):
                    p, paired = q, True
            if t[p] <= 0:  # a ends on a face square to it: in its corner already
                continue
            near = -params.front_max_m <= s[p] <= length[p] + params.front_max_m
            lo, hi = stretch(p)
            t_all, x_all, at = t, x, float(s[p])
            t, x = float(t[p]), x[p]
            # a square face ending farther than front_max_m from the corner: only a
            # deeper object hides it (backed by the wall's other face, or by the objects
            # on the partition's other side, back to back, up to a wall that faces
            # back at a's end: not the objects' own far face)
            covered = hidden_by_objects(seg, side, a, lo, hi, params, free_at, params.front_max_m, shallow=near) or (
                free_at is not None
                and (paired or float(free_n[p] @ out_dir) < 0 and back_to_back(seg, side, a, lo, hi, params, free_at))
                and covered_by_fronts(seg, side, a, lo, hi, params, params.front_max_m, OBJECT_MAX_DEPTH_M, free_at))
            if covered:  # p may be an object's front: a runs on to the wall behind it
                square_in_room = (np.abs(denom) >= square) & in_room
                wall = _wall_behind(seg, u, free_n, length, square_in_room, p, at, t_all - t, params)
                if wall >= 0:
                    t, x = float(t_all[wall]), x_all[wall]
            if covered and open_run(end, out_dir, 0.0, t) < params.min_opening_m:
                out[a, 2 * k : 2 * k + 2] = x
    return out

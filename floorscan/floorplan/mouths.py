"""The open side of a room (:func:`room_mouths`): the line between the ends of two
walls that bound a room on its sides, where the room opens on its whole width onto a
corridor or a hall (an office open to the corridor, a cubicle, a corner room, a short
corridor leading off a hall).

A distance-transform segmentation (:mod:`floorscan.floorplan.persistence`) separates
two spaces only where the space narrows between them; a room open on its whole width
does not narrow, so it joins the corridor. People draw the room's boundary there on the
line that joins the ends of its walls, as they draw a door on the line of its wall
(the room ground truths of Bormann et al., ICRA 2016, and of ROSE^2, Luperto et al.,
RA-L 2022, whose layout extends the walls' lines into the open side of a room). A
mouth is that line, between two wall ends that:

- are free ends (not in an L or T junction, :func:`~floorscan.floorplan.doors.junction_end`),
  or one free end and a corner of the room: the end of its side wall where that wall
  meets another (a room open on its whole width between its side wall and the free end
  of its front wall, Bormann et al.'s lab_a and lab_intel). A line from a corner is
  wider than ``door_max_m`` (a narrower opening is a door, which the persistence
  weighs; across a corridor at its corner it would cut the corridor) and parts the
  space in two (cut, its two sides are no longer connected: from the corner of a block
  that a corridor runs around, the same line crosses the corridor);
- lie ``door_min_m`` to :data:`MOUTH_MAX_M` apart between the side walls' faces (the
  room's clear opening), the line between them in the free space, crossing no wall;
- belong to walls that bound one side of the line: each wall runs from its end square
  to the line into the same side (or along the line, away from it, the line in its
  line within ``line_offset_m`` plus half its thickness: the wall of a corridor going
  on past a room's side wall), within ``door_angle_deg``, and not both
  along the line (that is a gap in one wall, :func:`~floorscan.floorplan.doors.wall_gaps`,
  where no wider than a door; a wider gap between the free ends of two walls at least
  :data:`MOUTH_WALL_M` long is a mouth when it closes a pocket on one side, as below,
  and the space on the other side runs on as far: no recess of the room);
  a corner's wall is a side wall; a side wall is at least as long as the line's clear
  width between the faces of the walls at its ends (the room is as deep as it is
  open: a cubicle, Bormann et al.'s lab_a) and :data:`MOUTH_WALL_M`;
- close a pocket: from the line into that side, the space ends at a wall or at a cell
  outside the space within :data:`MOUTH_DEPTH` times the line's length, at its
  middle and at both quarter points (the back wall of the room), and not before
  :data:`MOUTH_MIN_DEPTH` times its length at its middle (a recess is part of the
  space it opens onto).
- are not both ends of walls that go on: where each side wall's line goes on past its
  end in another wall, beyond a gap at most ``door_max_m`` wide (a door's, or a slit
  narrower than a door where a wall is found in two pieces), the line joins two doors
  or breaks facing each other across a corridor whose walls go on past them, and the
  space on its two sides is one (a corridor's length closes the pocket's depth test
  as a room would).

A mouth cuts the space before it is segmented, as a gap in a wall does; where it is
no wider than a door it is the room's door.

:func:`corner_mouths` are the same line across the missing corner of two walls: the
corner of a corridor (a ring corridor's, Bormann et al.'s office_h) open to the room
beyond it. :func:`dead_end_mouths` are the gaps between two corners in one wall's line
through which a dead end as wide as the gap opens onto a hall (Bormann et al.'s
Freiburg101, its dead-end corridors off the hall).
"""

from __future__ import annotations

import numpy as np

from floorscan.core.geometry import point_segment_dist2
from floorscan.floorplan.doors import barrier_cells, junction_end, wall_units
from floorscan.floorplan.room_space import RoomParams, RoomRaster, wall_footprints

#: The widest open side of a room, metres: two standard office modules (2 x 2.4 m less
#: the walls) open onto a corridor; wider openings join halls that people draw as one
#: space (measured on the room benchmarks: ``benchmarks/README.md``).
MOUTH_MAX_M = 4.0
#: A pocket is at most this many times as deep as its open side is wide (a room, not
#: a corridor running on behind the line).
MOUTH_DEPTH = 4.0
#: A pocket is at least this many times as deep as its open side is wide: a shallower
#: one is a recess of the corridor or hall it opens onto (a niche, the bay of a
#: window), which people draw as part of that space (the niches beside the corridors
#: of Bormann et al.'s NLB).
MOUTH_MIN_DEPTH = 0.5
#: The side walls of a mouth are at least this long, and as long as the mouth is wide
#: (a room's sides, not the stubs of furniture or of a noisy map), metres.
MOUTH_WALL_M = 1.0


def _free_ends(axes: np.ndarray, thickness: np.ndarray) -> list[tuple[int, int]]:
    return [(i, k) for i in range(len(axes)) for k in (0, 1) if not junction_end(axes, thickness, i, k)]


def _in_line(x: np.ndarray, p: np.ndarray, u: np.ndarray, tol_m: float) -> bool:
    """Whether point ``x`` lies within ``tol_m`` of the line through ``p`` along ``u``
    (a unit vector), metres."""
    return abs(float((x - p) @ np.array([-u[1], u[0]]))) <= tol_m


def _ray_hits(raster: RoomRaster, start: np.ndarray, direction: np.ndarray, max_m: float, tree) -> bool:
    """Whether the space ends at a wall (the footprints in ``tree``, a shapely
    STRtree) within ``max_m`` from ``start`` along ``direction``."""
    import shapely

    step = raster.resolution_m / 2
    n = max(2, int(np.ceil(max_m / step)))
    pts = start + np.outer(np.arange(1, n + 1) * step, direction)
    out = np.flatnonzero(~raster.at(raster.space, pts, outside=False))
    if not len(out):
        return False
    hit = shapely.Point(pts[out[0]])
    near = tree.query(hit, predicate="dwithin", distance=2 * raster.resolution_m)
    return bool(len(near))


def sides_apart(raster: RoomRaster, p: np.ndarray, q: np.ndarray):
    """The space cut along the line from ``p`` to ``q`` (metres): its components (an
    ndarray of labels, 0 outside the space) and the components two cells to the left
    and to the right of the line's middle, or None when the line does not part the
    space in two (its two sides still connected, or a side off the raster or outside
    the space)."""
    from scipy import ndimage

    d = q - p
    nrm = np.array([-d[1], d[0]]) / float(np.hypot(*d)) * 2 * raster.resolution_m
    sr, sc, inside = raster.cells_of(np.array([(p + q) / 2 + nrm, (p + q) / 2 - nrm]))
    if not inside.all():
        return None
    cut = raster.space.copy()
    cut[barrier_cells(raster, p, q)] = False
    comp, _ = ndimage.label(cut)
    left, right = int(comp[sr[0], sc[0]]), int(comp[sr[1], sc[1]])
    return (comp, left, right) if left and right and left != right else None


def _goes_on(axes: np.ndarray, thickness: np.ndarray, i: int, k: int, params: RoomParams) -> bool:
    """Whether wall ``i``'s line goes on past its end ``k`` in another wall (parallel
    within ``door_angle_deg``, both its ends within ``line_offset_m`` and half the
    thicker wall of the line), beyond a gap at most ``door_max_m`` wide: the end is a
    door's jamb or the edge of a slit."""
    unit, length = wall_units(axes)
    ends = axes.reshape(-1, 2, 2)
    out = (ends[i, k] - ends[i, 1 - k]) / max(length[i], 1e-12)
    nrm = np.array([-out[1], out[0]])
    rel = ends - ends[i, k]  # (N, 2, 2)
    t, off = rel @ out, np.abs(rel @ nrm)
    in_line = off.max(axis=1) <= params.line_offset_m + np.maximum(thickness, thickness[i]) / 2
    ok = (np.abs(unit @ out) >= np.cos(np.radians(params.door_angle_deg))) & in_line
    ok &= (t.min(axis=1) >= 0) & (t.min(axis=1) <= params.door_max_m)
    ok[i] = False
    return bool(ok.any())


def room_mouths(
    axes: np.ndarray, thickness: np.ndarray, raster: RoomRaster, params: RoomParams
) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """The open sides of rooms (module docstring).

    Parameters
    ----------
    axes : (N, 4) float ndarray
        Wall axes ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Metres.
    raster : RoomRaster
        The space before it is cut.
    params : RoomParams

    Returns
    -------
    list of (p, q, wall)
        Each mouth from ``p`` to ``q`` ((2,) metres, wall ends) and the longer of its
        two walls; no two mouths cross (of two crossing, the shorter is kept).
    """
    import shapely

    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    thickness = np.asarray(thickness, dtype=np.float64).reshape(-1)
    if len(axes) < 2:
        return []
    ends = axes.reshape(-1, 2, 2)
    _, length = wall_units(axes)
    free = _free_ends(axes, thickness)
    if not free:
        return []
    # the ends a mouth joins: the free ends first, then the corners (ends in a junction);
    # every pair (a, b), a < b, has its first end free
    taken = set(free)
    tips = free + [(i, k) for i in range(len(axes)) for k in (0, 1) if (i, k) not in taken]
    is_free = np.arange(len(tips)) < len(free)
    pts = np.array([ends[i, k] for i, k in tips])
    # each wall's direction pointing away from its end (from the end into the wall)
    away = np.array([(ends[i, 1 - k] - ends[i, k]) / max(length[i], 1e-12) for i, k in tips])
    footprints = wall_footprints(axes, thickness)
    tree = shapely.STRtree(footprints)
    # a wall within door_angle_deg of the line's direction runs along it (as a door's
    # walls run along the door), one within it of square to the line bounds a side
    cos_tol = np.cos(np.radians(params.door_angle_deg))

    def closes_pocket(p: np.ndarray, u: np.ndarray, length_m: float, s: float, ends_m: tuple) -> bool:
        """The line from ``p`` along ``u`` runs ``length_m`` in the free space, crosses
        no wall, and the space on side ``s`` (+1 left of ``u``, -1 right) runs on at
        least MOUTH_MIN_DEPTH times its length from its middle and ends at a wall within
        MOUTH_DEPTH times its length at its quarter points and middle. The line is
        tested from ``ends_m`` (the half thickness of the wall at each end, metres) and a
        raster cell past each end, at least 0.15 m: between the walls' faces, clear of
        the cells a face touches."""
        n = s * np.array([-u[1], u[0]])
        step = raster.resolution_m / 2
        t0 = max(0.15, ends_m[0] + raster.resolution_m)
        t1 = max(t0, length_m - max(0.15, ends_m[1] + raster.resolution_m))
        line = shapely.LineString([p + u * t0, p + u * t1])
        if tree.query(line, predicate="intersects").size:
            return False
        t = np.linspace(t0, t1, max(3, int(length_m / raster.resolution_m)))
        if not raster.at(raster.space, p + np.outer(t, u), outside=False).all():
            return False
        if not runs_on(p, u, length_m, s):
            return False  # a recess of the space the line borders, not a room
        starts = [p + u * length_m * f + n * raster.resolution_m for f in (0.25, 0.5, 0.75)]
        return all(_ray_hits(raster, x, n, MOUTH_DEPTH * length_m, tree) for x in starts)

    def runs_on(p: np.ndarray, u: np.ndarray, length_m: float, s: float) -> bool:
        """Whether the space on side ``s`` of the line from ``p`` along ``u`` runs on at
        least MOUTH_MIN_DEPTH times its length ``length_m`` from its middle."""
        n = s * np.array([-u[1], u[0]])
        step = raster.resolution_m / 2
        depth = np.arange(1, int(np.ceil(MOUTH_MIN_DEPTH * length_m / step)) + 1) * step
        start = p + u * length_m / 2 + n * raster.resolution_m
        return bool(raster.at(raster.space, start + np.outer(depth, n), outside=False).all())

    cands = []
    for a in range(len(free)):
        d = pts - pts[a]
        dist = np.hypot(d[:, 0], d[:, 1])
        for b in np.flatnonzero((dist >= params.door_min_m) & (dist <= MOUTH_MAX_M + thickness.max())):
            if b <= a or tips[a][0] == tips[b][0]:
                continue
            corner = not is_free[b]
            if corner and dist[b] <= params.door_max_m:
                continue  # a narrower opening from a corner is a door the persistence weighs
            u = d[b] / dist[b]
            n = np.array([-u[1], u[0]])
            along = np.abs(away[[a, b]] @ u) >= cos_tol
            if along.all():  # a gap in one wall's line: wall_gaps' door up to door_max_m, a mouth beyond
                ia, ib = tips[a][0], tips[b][0]
                width = float(dist[b])
                if (not corner and width > params.door_max_m and away[a] @ u < 0 < away[b] @ u
                        and _in_line(pts[b], pts[a], away[a], params.line_offset_m + thickness[ia] / 2)
                        and length[[ia, ib]].min() >= MOUTH_WALL_M
                        and width - (thickness[ia] + thickness[ib]) / 2 <= MOUTH_MAX_M):
                    # wider: a room's open side in the wall, a room on one side (a
                    # pocket) and on the other no recess of it
                    ends_m = (thickness[ia] / 2, thickness[ib] / 2)
                    if any(closes_pocket(pts[a], u, width, s, ends_m) and runs_on(pts[a], u, width, -s)
                           for s in (1.0, -1.0)):
                        cands.append((width, pts[a].copy(), pts[b].copy(), int(ia if length[ia] >= length[ib] else ib)))
                continue
            if corner and along[1]:
                continue  # a corner bounds a mouth by a side wall only
            side = away[[a, b]] @ n
            # along the line: the wall must run away from the mouth, outward, and the
            # mouth lie in the wall's line (the corridor's wall going on past the room)
            if along[0] and away[a] @ u > 0 or along[1] and away[b] @ u < 0:
                continue
            if along[0] and not _in_line(pts[b], pts[a], away[a], params.line_offset_m + thickness[tips[a][0]] / 2):
                continue
            if along[1] and not _in_line(pts[a], pts[b], away[b], params.line_offset_m + thickness[tips[b][0]] / 2):
                continue
            sides = np.array([tips[a][0], tips[b][0]])[~along]
            if dist[b] - thickness[sides].sum() / 2 > MOUTH_MAX_M:
                continue  # wider than a room's open side, between the side walls' faces
            clear = dist[b] - (thickness[tips[a][0]] + thickness[tips[b][0]]) / 2  # between the end walls' faces
            if length[sides].min() < max(MOUTH_WALL_M, clear):
                continue  # a stub of furniture or noise bounds no room
            into = side[~along]
            if not ((into >= cos_tol).all() or (into <= -cos_tol).all()):
                continue
            ends_m = (thickness[tips[a][0]] / 2, thickness[tips[b][0]] / 2)
            if not closes_pocket(pts[a], u, float(dist[b]), 1.0 if (into > 0).all() else -1.0, ends_m):
                continue
            if not along.any() and all(_goes_on(axes, thickness, *tips[e], params) for e in (a, b)):
                continue  # two doors (or slits) facing each other across a space that goes on past them
            if corner and sides_apart(raster, pts[a], pts[b]) is None:
                continue  # a corner's line across a corridor that goes on around
            wall = tips[a][0] if length[tips[a][0]] >= length[tips[b][0]] else tips[b][0]
            cands.append((float(dist[b]), pts[a].copy(), pts[b].copy(), int(wall)))
    cands.sort(key=lambda c: c[0])
    kept: list = []
    for _, p, q, wall in cands:
        seg = shapely.LineString([p, q])
        if any(shapely.crosses(seg, shapely.LineString([kp, kq])) for kp, kq, _ in kept):
            continue
        kept.append((p, q, wall))
    return kept


def corner_mouths(
    axes: np.ndarray, thickness: np.ndarray, params: RoomParams
) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """The open sides of rooms across the missing corner of two walls.

    Two walls whose free ends (:func:`~floorscan.floorplan.doors.junction_end`) stop
    short of the corner their lines make leave an opening from one end to the other:
    the corner of a corridor open to the room beyond it, which people draw across the
    corner (the chamfered corridor corners of Bormann et al.'s ground truths, ICRA
    2016). Each end lies at most ``door_max_m`` from the corner, on its wall's line
    beyond the wall (a door's width missing from each wall); the opening is at least
    ``door_min_m`` wide, and each wall at least as long as it and :data:`MOUTH_WALL_M`
    (a room's side, not a stub). Where no wider than ``door_max_m`` the opening is the
    room's door, as a mouth's.

    Parameters and returns as :func:`~floorscan.floorplan.doors.wall_gaps`: each
    opening from ``p`` to ``q`` is from one free end to the other, in the name of the
    longer wall, at most ``door_max_m`` times the square root of two wide.
    """
    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    u, length = wall_units(axes)
    cos_max = np.cos(np.radians(params.door_angle_deg))
    ends = axes.reshape(-1, 2, 2)
    free = np.zeros((len(axes), 2), dtype=bool)
    for i, k in _free_ends(axes, thickness):
        free[i, k] = True
    has_free = np.flatnonzero(free.any(axis=1))
    out = []
    for i in has_free.tolist():
        for j in has_free[has_free > i].tolist():
            cross = float(u[i, 0] * u[j, 1] - u[i, 1] * u[j, 0])
            if abs(float(u[i] @ u[j])) >= cos_max or abs(cross) < 1e-9:
                continue  # collinear: :func:`~floorscan.floorplan.doors.wall_gaps`
            for ki in (0, 1):
                if not free[i, ki]:
                    continue
                for kj in (0, 1):
                    if not free[j, kj]:
                        continue
                    a, b = ends[i, ki], ends[j, kj]
                    # the corner c = a + s u_i = b + t u_j
                    rhs = b - a
                    s = float(rhs[0] * u[j, 1] - rhs[1] * u[j, 0]) / cross
                    t = float(rhs[0] * u[i, 1] - rhs[1] * u[i, 0]) / cross
                    out_i = s if ki == 1 else -s  # beyond end ki, away from the wall
                    out_j = t if kj == 1 else -t
                    if not (0 < out_i <= params.door_max_m and 0 < out_j <= params.door_max_m):
                        continue
                    width = float(np.hypot(*(b - a)))
                    side = min(length[i], length[j])
                    if params.door_min_m <= width <= side and side >= MOUTH_WALL_M:
                        out.append((a.copy(), b.copy(), i if length[i] >= length[j] else j))
    return out


def dead_end_mouths(
    axes: np.ndarray, thickness: np.ndarray, raster: RoomRaster, params: RoomParams
) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """The mouths of dead ends off a hall: a corridor or room as wide as its opening,
    closed behind it. The space does not narrow there, so the persistence
    (:mod:`floorscan.floorplan.persistence`) does not part it, and its side walls meet
    the wall it opens in, so it has no free ends for :func:`room_mouths`; people draw
    its boundary on the wall's line (the dead-end corridors off the hall of Bormann et
    al.'s Freiburg101, ICRA 2016). A mouth is a gap ``door_min_m`` to ``door_max_m``
    wide between two corners in one wall's line
    (:func:`~floorscan.floorplan.doors.wall_gaps` with ``corners``) that:

    - parts the space in two (cut, its two sides are no longer connected); the larger
      part is the rest of the space, the other the dead end;
    - no wall at either corner runs on into the rest of the space, in itself or, beyond
      a gap at most ``door_max_m`` wide, in another wall of its line (the walls of a
      corridor going on past the line of a wall that crosses it: that is one
      corridor, not a dead end off it);
    - opens onto a space at least twice as wide as itself: within
      ``corridor_max_width_m`` of the gap's middle and seen from it (the straight line
      in the space), a cell of the rest of the space lies farther than the gap's width
      from every cell outside the space (a hall; a corridor that the dead end meets
      or crosses is not, and keeps it as its arm, as
      :func:`~floorscan.floorplan.corridors.corridor_sides` does).

    Parameters and returns as :func:`room_mouths`.
    """
    from floorscan.floorplan.doors import wall_gaps

    out = []
    clearance = None  # metres from each cell of the space to the nearest cell outside it
    for p, q, wall in wall_gaps(axes, thickness, params, corners=True):
        apart = sides_apart(raster, p, q)
        if apart is None:
            continue
        comp, left, right = apart
        d = q - p
        # the side the rest of the space lies on; no wall at either corner runs into it
        sizes = np.bincount(comp.ravel())
        rest, side = (left, 1.0) if sizes[left] >= sizes[right] else (right, -1.0)
        n = side * np.array([-d[1], d[0]]) / float(np.hypot(*d))
        if any(_runs_into(axes, thickness, c, n, params) for c in (p, q)):
            continue
        # a hall beside the gap: a cell twice the gap's width across, near and seen
        if clearance is None:
            clearance = raster.clearance()
        if hall_beside(raster, clearance, comp == rest, p, q, n, float(np.hypot(*d)), params.corridor_max_width_m):
            out.append((p, q, wall))
    return out


def hall_beside(raster: RoomRaster, clearance: np.ndarray, part: np.ndarray, p: np.ndarray, q: np.ndarray,
                n: np.ndarray, width_m: float, reach_m: float) -> bool:
    """Whether the line from ``p`` to ``q`` ((2,) metres) opens on side ``n`` (a unit
    normal) onto a hall: a cell of ``part`` ((H, W) bool) within ``reach_m`` of the
    line's middle, farther than ``width_m`` from every cell outside the space
    (``clearance``, :meth:`RoomRaster.clearance`: a space at least twice as wide as
    ``width_m``), seen from the line (the straight line from one cell past its middle
    runs in the space)."""
    centre = (p + q) / 2
    rows, cols, _ = raster.cells_of(np.array([centre - reach_m, centre + reach_m]))
    h, w = raster.space.shape
    window = (slice(*np.clip(rows, 0, h - 1) + [0, 1]), slice(*np.clip(cols, 0, w - 1) + [0, 1]))
    rr, cc = np.mgrid[window]
    xy = raster.centres(rr.ravel(), cc.ravel())
    beside = part[window].ravel() & (np.hypot(*(xy - centre).T) <= reach_m) & (clearance[window].ravel() > width_m)
    if not beside.any():
        return False
    mid = centre + n * raster.resolution_m
    cells = xy[beside]
    steps = np.linspace(0.0, 1.0, int(np.ceil(reach_m / (raster.resolution_m / 2))) + 1)
    seen = raster.at(raster.space, (mid + np.einsum("k,nj->nkj", steps, cells - mid)).reshape(-1, 2),
                     outside=False).reshape(len(cells), len(steps)).all(axis=1)
    return bool(seen.any())


def _runs_into(axes: np.ndarray, thickness: np.ndarray, c: np.ndarray, n: np.ndarray, params: RoomParams) -> bool:
    """Whether a wall through the corner ``c`` (its axis within half its thickness and
    ``line_offset_m`` of it) reaches past the corner's line into the side ``n`` (a unit
    normal of the line) by more than half its thickness and ``line_offset_m``, or a wall
    ending at the corner goes on in its line into that side in another wall, beyond a
    gap at most ``door_max_m`` wide (a corridor's wall with a door beside the corner)."""
    tol = thickness / 2 + params.line_offset_m
    near = point_segment_dist2(np.full(len(axes), c[0]), np.full(len(axes), c[1]), axes) <= tol**2
    reach = np.maximum((axes[:, :2] - c) @ n, (axes[:, 2:] - c) @ n)
    if (near & (reach > tol)).any():
        return True
    ends = axes.reshape(-1, 2, 2)
    for i in np.flatnonzero(near):
        k = int(np.argmin(np.hypot(*(ends[i] - c).T)))
        out = ends[i, k] - ends[i, 1 - k]
        length = float(np.hypot(*out))
        if length < 1e-9 or float(out @ n) < np.cos(np.radians(params.door_angle_deg)) * length:
            continue  # not a side wall ending at the corner from the other side
        if _goes_on(axes, thickness, int(i), k, params):
            return True
    return False

"""The sides and ends of corridors (:func:`corridor_sides`, :func:`corridor_ends`): a
corridor is the strip of space between two long parallel lines of wall; an opening in
its sides, however wide, is a room boundary, unless another corridor goes on from it,
and so is its end where it opens onto a hall.

A distance-transform segmentation (:mod:`floorscan.floorplan.persistence`) parts two
spaces only where the space narrows to a door, so an office open onto a corridor
through an opening wider than a door, or through a row of cabinets, is one room with
the corridor. A rule on the opening alone cannot tell it from a widening of the
corridor; the two parallel lines of wall that run past it can. People draw a
corridor from its two walls and its rooms' boundaries on their line, as the layouts of
Luperto et al. ("Robust structure identification and room segmentation of cluttered
indoor environments from occupancy grid maps", RA-L 2022, ROSE^2) extend the walls'
lines across their openings; the corridor as a long, narrow strip is that of Bormann
et al. ("Room segmentation: survey, implementation, and analysis", ICRA 2016).

1. **Lines** (:mod:`floorscan.floorplan.corridor_lines`): the plan's walls grouped
   into lines, each wall in the line of the longest wall whose line holds its ends
   (within half the thicker wall plus ``line_offset_m``, as
   :func:`~floorscan.floorplan.doors.wall_gaps` joins walls), while the line stays more
   wall than opening, as a corridor's side is: its walls and the stretches between
   them that are not space cover at least ``SIDE_WALL_SHARE`` of it. A short wall far
   along the line across open floor is no part of it, and a change to it does not
   reach a corridor's sides.
2. **Corridors**: a line and a parallel one (directions within ``door_angle_deg``;
   the second's walls over their common length within ``2 line_offset_m`` of one
   offset, measured across the corridor's own direction, the mean of both sides'
   walls over that length: a wall fitted half a degree off, carried 35 m along the
   corridor, would put the other side 0.3 m off its line), with a clear width
   between the two of at least :data:`~floorscan.floorplan.room_space.MIN_ROOM_WIDTH_M`
   and at most ``corridor_max_width_m``. The corridor is each run of their common
   length whose middle line lies in the space and crosses no wall across the middle
   half of the strip (rooms in a row with doors between them, or a door across a
   corridor), at least ``corridor_min_length_m`` and ``corridor_elongation`` times its
   width long, and bounded on each side, within ``SIDE_STEP_M`` of the side's line, by
   cells that are not space along at least ``SIDE_WALL_SHARE`` of it, a door no wider than
   ``door_max_m`` between two bounded stretches counting as its wall (its sides are
   walls with doors in them). A run shorter or more open than that is a corridor too
   where one goes on from it past a step of its sides (:func:`_going_on`: both sides'
   lines within ``SIDE_STEP_M`` of the corridor's, bounded together as a corridor's
   sides are). Where a side's line stops and goes on stepped out of it by up to
   ``SIDE_STEP_M`` past an opening (a line joined to the other,
   :func:`~floorscan.floorplan.corridor_lines.stepped_lines`), and no pair of the lines
   themselves makes a run there, the corridor goes on along its own lines as far as the
   run between the joined lines goes, while its sides stay bounded as a corridor's
   (:func:`_past_steps`: a corridor through an open-plan office whose side steps out
   past it, as ROSE^2's layout clusters a stepped wall into one line). Of corridors
   over one another, the narrowest is kept (the inner faces of a stepped side).
3. **Sides**: each opening in a side, at least ``door_min_m`` wide, that leads into
   space, is cut on the side's line, unless the space behind it goes on away from the
   corridor for ``corridor_elongation`` times its width or more, about as wide as the
   opening (the opening's width at its middle at least
   :data:`~floorscan.floorplan.persistence.DOOR_SHARE` of the space's median width along
   the way: a narrower one is a room's entrance, as a door is), from at least two of
   three points across it (a quarter, half and three quarters of it: the ray from one
   point may run up beside a partition that stops short of the side, in a strip of
   space that never ends), or lies in another
   corridor (another corridor meets this one there, and the two stay one room), or
   ends within :data:`~floorscan.floorplan.mouths.MOUTH_MIN_DEPTH` times the opening's
   width (a niche of the corridor, as the open sides of rooms take it; the depth is the
   median of three rays, at a quarter, half and three quarters of the opening, as one
   may meet the end of a partition behind it or pass through a door), or faces, over
   at least half its width, an opening in the other side into another corridor (a
   crossing: that corridor goes on through it, however short its far arm).
4. **Ends** (:func:`corridor_ends`): the line across a corridor's end, from side to
   side, where the corridor opens onto a hall: the line parts the space in two, and
   beyond it lies a space at least twice as wide as the corridor
   (:func:`~floorscan.floorplan.mouths.hall_beside`), looked for within
   ``corridor_max_width_m`` or twice the corridor's clear width, the farther (a hall's
   cells clearer than the corridor lie at least its width in from the hall's wall, and
   the corridor's sides may stop short of its mouth), and reached from the corridor's
   end without a narrowing narrower than the corridor (a hall behind a gap in another
   wall is no end of it).
   This is the dead end of
   :func:`~floorscan.floorplan.mouths.dead_end_mouths` whose side walls end apart
   along it (one side wall goes on beside the hall, the other stops): people draw the
   corridor's end across it where the shorter side ends (Bormann et al.'s Freiburg101,
   its dead-end corridor whose west wall is the hall's). A corridor that joins the
   space at its two ends (a ring, a passage between two blocks) is parted by no single
   line, and stays one room with the space it joins.
5. **Across** (:func:`across_corridor`): a corridor goes on past the ends of the walls
   beside it. The room step's watershed parts a corridor where a partition of the rooms
   beside it, or a room's corner, ends on its side, and the distance-transform
   segmentation keeps such a passage as a door when the basin beside it is the wider
   junction or hall the corridor leads to (:mod:`floorscan.floorplan.persistence`); a
   passage across the corridor from side to side, inside it, at least
   :data:`~floorscan.floorplan.persistence.DOOR_SHARE` of its clear width, is measured
   against the corridor's own width and is no door: the corridor is one room, as people
   draw a ring of corridors (Bormann et al.'s NLB and lab_intel). A door across a
   corridor narrows it by more than a quarter, between jambs, and stays a door.
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.doors import contact_door, wall_units
from floorscan.floorplan.mouths import MOUTH_MIN_DEPTH, hall_beside, sides_apart
from floorscan.floorplan.persistence import DOOR_SHARE
from floorscan.floorplan.corridor_lines import (SIDE_STEP_M, SIDE_WALL_SHARE, bounded, corridor_frame, runs,
                                               sides_walled, stepped_lines, walled, wall_lines)
from floorscan.floorplan.room_space import MIN_ROOM_WIDTH_M, RoomParams, RoomRaster


def corridor_strips(axes: np.ndarray, thickness: np.ndarray, raster: RoomRaster, params: RoomParams) -> list[dict]:
    """The corridors (module docstring, steps 1-2): per corridor, ``polygon`` (between
    the axes of its sides), ``origin``, ``u`` (a point of the first side's line and its
    direction), ``n`` (the unit normal toward the second side), ``sep`` (metres between
    the sides' lines), ``clear`` (metres between the sides' faces), ``t0`` and ``t1``
    (its start and end along ``u``), ``step`` and, per side,
    ``open`` ((K,) bool at ``t0 + (i + 1/2) step``) and ``walls`` (the side's line)."""
    u_all, length = wall_units(axes)
    lines = wall_lines(axes, thickness, u_all, length, params.line_offset_m, raster)
    cos_par = np.cos(np.radians(params.door_angle_deg))
    found, short = _pair_runs(lines, None, axes, thickness, u_all, raster, params)
    stepped = stepped_lines(lines, axes, u_all, cos_par, raster)
    joined = {k for k, ln in enumerate(stepped) if ln not in lines}
    if joined:  # a corridor going on past a step of a side's line, where no run of the lines themselves does
        found = _past_steps(found, short, _pair_runs(stepped, joined, axes, thickness, u_all, raster, params),
                            raster, params)
    found += _going_on(found, short, cos_par, int(params.door_max_m / raster.resolution_m))
    kept: list[dict] = []
    for c in sorted(found, key=lambda c: (c["sep"], -c["polygon"].area)):
        if all(c["polygon"].intersection(k["polygon"]).area < 0.5 * c["polygon"].area for k in kept):
            kept.append(c)
    return kept


def _pair_runs(lines: list[list[int]], must: set[int] | None, axes: np.ndarray, thickness: np.ndarray,
               u_all: np.ndarray, raster: RoomRaster, params: RoomParams) -> tuple[list[dict], list[dict]]:
    """The runs between pairs of ``lines`` (module docstring, step 2): corridors, and
    the runs too short or too open to be one alone. With ``must`` (the indices of
    joined lines, :func:`~floorscan.floorplan.corridor_lines.stepped_lines`), only the
    pairs with such a line, whose walls may lie at two offsets up to ``2 SIDE_STEP_M``
    apart (a stepped side), not ``2 line_offset_m``."""
    import shapely

    line_of = np.full(len(axes), -1)
    for k, ws in enumerate(lines):
        line_of[ws] = k
    ends = axes.reshape(-1, 2, 2)
    cos_par = np.cos(np.radians(params.door_angle_deg))
    step = raster.resolution_m
    door = int(params.door_max_m / step)
    tree = shapely.STRtree(shapely.linestrings(ends))
    found, short = [], []  # corridors, and the runs too short or too open to be one alone
    for ia, wa in enumerate(lines):
        ua, oa = u_all[wa[0]], ends[wa[0], 0]
        ta = np.sort((ends[wa] - oa) @ ua, axis=1)
        lo_a, hi_a = ta[:, 0].min(), ta[:, 1].max()
        if hi_a - lo_a < params.corridor_min_length_m:
            continue
        par = np.flatnonzero((np.abs(u_all @ ua) >= cos_par) & (line_of > ia))
        if not len(par):
            continue
        w_t = np.sort((ends[par] - oa) @ ua, axis=1)
        for ib in np.unique(line_of[par]).tolist():
            if must is not None and ia not in must and ib not in must:
                continue
            in_b = line_of[par] == ib
            lo, hi = max(lo_a, w_t[in_b, 0].min()), min(hi_a, w_t[in_b, 1].max())
            if hi - lo < params.corridor_min_length_m:
                continue
            # the corridor's own frame: its two sides' walls over their common run
            # (corridor_frame), not the first side's longest wall carried along it
            ob, ub, nb = corridor_frame(ends, u_all, wa, par[in_b], oa, ua, lo, hi)
            tb_a = np.sort((ends[wa] - ob) @ ub, axis=1)
            wb_off = ((ends[par[in_b]] - ob) @ nb).mean(axis=1)
            wb_t = np.sort((ends[par[in_b]] - ob) @ ub, axis=1)
            lo, hi = max(tb_a[:, 0].min(), wb_t[:, 0].min()), min(tb_a[:, 1].max(), wb_t[:, 1].max())
            if hi - lo < params.corridor_min_length_m:
                continue
            span = np.clip(wb_t[:, 1], lo, hi) - np.clip(wb_t[:, 0], lo, hi)
            offs = wb_off[span > 0]
            if not len(offs) or np.ptp(offs) > 2 * (params.line_offset_m if must is None else SIDE_STEP_M):
                continue
            sep_signed = float(np.average(offs, weights=span[span > 0]))
            sep = abs(sep_signed)
            clear = sep - (thickness[wa].max() + thickness[lines[ib]].max()) / 2
            if not MIN_ROOM_WIDTH_M <= clear <= params.corridor_max_width_m:
                continue
            n = nb if sep_signed > 0 else -nb
            t = np.arange(lo, hi, step) + step / 2
            free = raster.at(raster.space, ob + t[:, None] * ub + (sep / 2) * n, outside=False).astype(bool)
            middle = shapely.Polygon([ob + lo * ub + sep / 4 * n, ob + hi * ub + sep / 4 * n,
                                      ob + hi * ub + 3 * sep / 4 * n, ob + lo * ub + 3 * sep / 4 * n])
            for j in tree.query(middle, predicate="intersects").tolist():
                if abs(float(u_all[j] @ ub)) < cos_par:  # a wall across the strip
                    tj = (ends[j] - ob) @ ub
                    free &= ~((t >= tj.min() - thickness[j] / 2) & (t <= tj.max() + thickness[j] / 2))
            side_a, side_b = _side_bands(raster, ob, ub, n, t, sep, clear)
            for s, e in runs(free):
                t0, t1 = float(t[s] - step / 2), float(t[e - 1] + step / 2)
                corners = [ob + t0 * ub, ob + t1 * ub, ob + t1 * ub + sep * n, ob + t0 * ub + sep * n]
                sides = ((~side_a[s:e], list(wa), 0.0, -1.0), (~side_b[s:e], list(lines[ib]), sep, 1.0))
                strip = dict(polygon=shapely.Polygon(corners), origin=ob, u=ub, n=n, sep=sep, clear=clear, t0=t0,
                             t1=t1, step=step, sides=sides)
                if ((e - s) * step < max(params.corridor_min_length_m, params.corridor_elongation * clear)
                        or not sides_walled(side_a[s:e], side_b[s:e], door)):
                    short.append(strip)
                    continue
                found.append(strip)
    return found, short


def _side_bands(raster: RoomRaster, o: np.ndarray, u: np.ndarray, n: np.ndarray, t: np.ndarray, sep: float,
                clear: float) -> tuple[np.ndarray, np.ndarray]:
    """Whether each side of the strip from the line ``o + t u`` to ``sep`` metres along
    ``n`` is bounded at each ``t`` (:func:`~floorscan.floorplan.corridor_lines.bounded`):
    within ``SIDE_STEP_M`` of the side's line, and no farther in than half the clear
    width ``clear``; (K,) bool each."""
    side_a = bounded(raster, o, u, n, t, -SIDE_STEP_M, min(SIDE_STEP_M, clear / 2))
    side_b = bounded(raster, o, u, n, t, max(sep - SIDE_STEP_M, sep - clear / 2), sep + SIDE_STEP_M)
    return side_a, side_b


def _past_steps(found: list[dict], short: list[dict], stepped: tuple[list[dict], list[dict]], raster: RoomRaster,
                params: RoomParams) -> list[dict]:
    """``found`` with each corridor going on past a step of a side's line (module
    docstring, step 2): where a run between stepped lines (``stepped``,
    :func:`_pair_runs` of the lines :func:`~floorscan.floorplan.corridor_lines.stepped_lines`
    joined) runs over it (as wide within ``line_offset_m``, over nine tenths of it) and
    on past its ends, over floor no other corridor nor a run going on from it
    (:func:`_going_on`) covers, the corridor goes on along its own lines as far, when
    its sides stay bounded along at least ``SIDE_WALL_SHARE`` of its length (a door
    part of its wall, :func:`~floorscan.floorplan.corridor_lines.walled`)."""
    import shapely

    out = []
    door = int(params.door_max_m / raster.resolution_m)
    cos_par = np.cos(np.radians(params.door_angle_deg))
    for f in found:
        o, u, n, sep, clear, step = f["origin"], f["u"], f["n"], f["sep"], f["clear"], f["step"]
        going = None  # the runs going on from f on lines of their own, once a stepped run is over it
        for c in stepped[0] + stepped[1]:
            if (abs(c["sep"] - sep) > params.line_offset_m or c["polygon"].area <= f["polygon"].area
                    or c["polygon"].intersection(f["polygon"]).area < 0.9 * f["polygon"].area):
                continue
            t0, t1 = sorted(float((c["origin"] + t * c["u"] - o) @ u) for t in (c["t0"], c["t1"]))
            before, after = int(max(0.0, f["t0"] - t0) // step), int(max(0.0, t1 - f["t1"]) // step)
            t = f["t0"] + (np.arange(-before, len(f["sides"][0][0]) + after) + 0.5) * step
            ext = np.r_[np.ones(before, dtype=bool), np.zeros(len(t) - before - after, dtype=bool),
                        np.ones(after, dtype=bool)]  # fmt: skip
            ends = (o + (t[0] - step / 2) * u, o + (t[-1] + step / 2) * u)
            polygon = shapely.Polygon([ends[0], ends[1], ends[1] + sep * n, ends[0] + sep * n])
            beyond = polygon.difference(f["polygon"])
            going = _going_on([f], short, cos_par, door) if going is None else going
            if not ext.any() or any(beyond.intersection(r["polygon"]).area > 0.5 * r["polygon"].area
                                    for r in found + going if r is not f):
                continue  # another corridor is there, or the corridor goes on there on lines of its own
            side_a, side_b = _side_bands(raster, o, u, n, t, sep, clear)
            side_a[~ext], side_b[~ext] = ~f["sides"][0][0], ~f["sides"][1][0]
            if not sides_walled(side_a, side_b, door):
                continue
            sides = ((~side_a,) + tuple(f["sides"][0][1:]), (~side_b,) + tuple(f["sides"][1][1:]))
            f = dict(f, polygon=polygon, t0=float(t[0] - step / 2), t1=float(t[-1] + step / 2), sides=sides)
            break
        out.append(f)
    return out


def _going_on(found: list[dict], short: list[dict], cos_par: float, door_cells: int) -> list[dict]:
    """The runs of ``short`` (strips of :func:`corridor_strips` too short or too open
    to be a corridor alone) where a corridor of ``found`` goes on past a step of its
    sides: parallel to it (within ``cos_par``, the cosine of ``door_angle_deg``), each
    side's line within ``SIDE_STEP_M`` of one of the corridor's, the two overlapping or
    touching along it, and the two together bounded on each side along at least
    ``SIDE_WALL_SHARE`` of their length (an opening of at most ``door_cells`` cells, a
    door, part of its wall). A corridor's side steps where a row of cabinets or the next
    block's wall stands out from its line; the corridor runs on."""
    out = []
    for c in short:
        for f in found:
            if abs(float(c["u"] @ f["u"])) < cos_par:
                continue
            ends = sorted(float((c["origin"] + t * c["u"] - f["origin"]) @ f["u"]) for t in (c["t0"], c["t1"]))
            if ends[0] > f["t1"] + f["step"] or ends[1] < f["t0"] - f["step"]:
                continue
            # each side of the run, on the corridor's side whose line it lies nearest
            pos = [float((c["origin"] + off * c["n"] - f["origin"]) @ f["n"]) for _, _, off, _ in c["sides"]]
            match = [int(abs(p - f["sep"]) < abs(p)) for p in pos]
            if match[0] == match[1] or any(abs(p - (f["sep"] if m else 0.0)) > SIDE_STEP_M for p, m in zip(pos, match)):
                continue
            shares = [(np.sum(walled(~side[0], door_cells)) + np.sum(walled(~f["sides"][m][0], door_cells)))
                      / max(len(side[0]) + len(f["sides"][m][0]), 1) for side, m in zip(c["sides"], match)]
            if min(shares) >= SIDE_WALL_SHARE:
                out.append(c)
                break
    return out


def _walls_and_strips(axes, thickness, raster: RoomRaster, params: RoomParams, strips: list[dict] | None):
    """``axes`` ((N, 4) float64), ``thickness`` ((N,) float64) and the corridor strips:
    ``strips``, or :func:`corridor_strips` when None (none with fewer than two walls)."""
    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    thickness = np.asarray(thickness, dtype=np.float64).reshape(-1)
    if strips is None:
        strips = corridor_strips(axes, thickness, raster, params) if len(axes) >= 2 else []
    return axes, thickness, strips


def corridor_sides(
    axes: np.ndarray, thickness: np.ndarray, raster: RoomRaster, params: RoomParams, strips: list[dict] | None = None
) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """The openings in the sides of the plan's corridors (module docstring).

    Parameters
    ----------
    axes : (N, 4) float ndarray
        Wall axes ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Metres.
    raster : RoomRaster
        The space before it is cut.
    params : RoomParams
    strips : list of dict, optional
        :func:`corridor_strips` of the same walls and raster (computed when None).

    Returns
    -------
    list of (p, q, wall)
        Each opening from ``p`` to ``q`` ((2,) metres, on the side's line) and the
        side's wall nearest to it.
    """
    import shapely

    axes, thickness, strips = _walls_and_strips(axes, thickness, raster, params, strips)
    if not strips:
        return []
    mids = (axes[:, :2] + axes[:, 2:]) / 2
    half_width = raster.clearance()
    strip_tree = shapely.STRtree([s["polygon"] for s in strips])
    out = []
    for k, s in enumerate(strips):
        mouths, cuts = [], []  # per side: the openings into other corridors, the openings to cut
        for side, (opening, walls, off, outward) in enumerate(s["sides"]):
            for a, b in runs(opening):
                g0, g1 = s["t0"] + a * s["step"], s["t0"] + b * s["step"]
                if g1 - g0 < params.door_min_m:
                    continue
                p = s["origin"] + g0 * s["u"] + off * s["n"]
                q = s["origin"] + g1 * s["u"] + off * s["n"]
                mid = (p + q) / 2
                behind = mid + outward * s["n"] * min(s["sep"] / 2, SIDE_STEP_M)
                if not raster.at(raster.space, behind[None], outside=False)[0]:
                    continue
                if any(j != k for j in strip_tree.query(shapely.Point(behind), predicate="within").tolist()):
                    mouths.append((side, g0, g1))  # another corridor's strip
                    continue
                # how far the space goes on away from the corridor, on three rays from a
                # quarter, half and three quarters of the opening (a partition behind one
                # of them turns one ray, not the opening): for corridor_elongation times
                # the mouth's width (at its middle) from two of them, another corridor;
                # for less than MOUTH_MIN_DEPTH times the opening (their median), a
                # recess of this one
                width = 2 * float(raster.at(half_width, behind[None], outside=0.0)[0])
                reach = max(params.corridor_elongation * max(width, MIN_ROOM_WIDTH_M), MOUTH_MIN_DEPTH * (g1 - g0))
                d = np.arange(s["step"] / 2, reach + s["step"], s["step"] / 2)
                away = np.outer(d, outward * s["n"])  # the samples of a ray into the space behind
                starts = [p + f * (q - p) for f in (0.25, 0.5, 0.75)]
                rays = [raster.at(raster.space, x + away, outside=False).astype(bool) for x in starts]
                # another corridor goes on, about as wide as its mouth; a mouth narrower
                # than DOOR_SHARE of the space behind it (the median width along the ray)
                # is the entrance of a room, as a door is
                goes_on = [bool(r.all()) and width >= 2 * DOOR_SHARE * np.median(raster.at(half_width, x + away, 0.0))
                           for x, r in zip(starts, rays)]
                if sum(goes_on) >= 2:
                    mouths.append((side, g0, g1))
                    continue
                depths = [d[-1] if r.all() else d[int(np.argmin(r))] for r in rays]
                if np.median(depths) >= MOUTH_MIN_DEPTH * (g1 - g0):
                    cuts.append((side, g0, g1, p, q, mid, walls))
        for side, g0, g1, p, q, mid, walls in cuts:
            # across from another corridor's mouth, over half its width or more: that
            # corridor crosses this one and goes on through it
            if any(m_side != side and min(g1, m1) - max(g0, m0) >= (g1 - g0) / 2 for m_side, m0, m1 in mouths):
                continue
            # an opening no wider than a door is the door between its jambs, as a
            # contact between two rooms is (the run's ends are whole cells)
            e = s["u"] * s["step"] / 2
            door = contact_door(p - e, q + e, axes, thickness, params)
            if door is None:
                door = (p, q, _nearest_wall(mids, walls, mid))
            out.append(door)
    return out


def corridor_ends(
    axes: np.ndarray, thickness: np.ndarray, raster: RoomRaster, params: RoomParams, strips: list[dict] | None = None
) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """The ends of the plan's corridors that open onto a hall (module docstring, step 4).

    Parameters and returns as :func:`corridor_sides`, except that ``raster`` is the
    space cut along the rooms' other boundaries (the line's parting and the hall beyond
    it are judged there), and each line is a corridor's end from ``p`` to ``q`` ((2,)
    metres, on its sides' lines) with the sides' wall nearest to its middle.
    """
    from scipy import ndimage

    axes, thickness, strips = _walls_and_strips(axes, thickness, raster, params, strips)
    if not strips:
        return []
    mids = (axes[:, :2] + axes[:, 2:]) / 2
    clearance = raster.clearance()
    out = []
    for s in strips:
        for t, outward in ((s["t0"], -1.0), (s["t1"], 1.0)):
            p = s["origin"] + t * s["u"]
            q = p + s["sep"] * s["n"]
            hall = (p, q, outward * s["u"], s["clear"], max(params.corridor_max_width_m, 2 * s["clear"]))
            if not hall_beside(raster, clearance, raster.space, *hall):
                continue  # no hall anywhere beyond: no need to label the space
            apart = sides_apart(raster, p, q)
            if apart is None:
                continue  # the corridor joins the space elsewhere too
            comp = apart[0]
            start = ((p + q) / 2 + outward * s["u"] * 2 * raster.resolution_m)[None]
            beyond = raster.at(comp, start, outside=0)[0]
            if not beyond:
                continue
            # the part beyond the end where a disc as wide as the corridor (less a cell)
            # fits, connected to the end: the hall opens from the corridor, not through a gap
            wide, _ = ndimage.label((comp == beyond) & (clearance >= s["clear"] / 2 - raster.resolution_m))
            k = raster.at(wide, start, outside=0)[0]
            if k and hall_beside(raster, clearance, wide == k, *hall):
                out.append((p, q, _nearest_wall(mids, s["sides"][0][1] + s["sides"][1][1], (p + q) / 2)))
    return out


def across_corridor(p: np.ndarray, q: np.ndarray, strips: list[dict], params: RoomParams) -> bool:
    """Whether the passage from ``p`` to ``q`` crosses a corridor from side to side
    inside it (module docstring, step 5): square to the corridor within
    ``door_angle_deg``, both ends between its ends (``t0``, ``t1``), each within
    ``SIDE_STEP_M`` of a side's face, and at least
    :data:`~floorscan.floorplan.persistence.DOOR_SHARE` of its clear width wide.

    Parameters
    ----------
    p, q : (2,) float ndarray
        The passage's ends, metres.
    strips : list of dict
        :func:`corridor_strips`.
    params : RoomParams

    Returns
    -------
    bool
    """
    d = q - p
    width = float(np.hypot(*d))
    if width == 0.0:
        return False
    for c in strips:
        o, u, n, sep, clear = c["origin"], c["u"], c["n"], c["sep"], c["clear"]
        if width < DOOR_SHARE * clear or abs(float(d @ n)) < width * np.cos(np.radians(params.door_angle_deg)):
            continue
        t = np.array([(p - o) @ u, (q - o) @ u])
        s = np.sort([(p - o) @ n, (q - o) @ n])
        face = (sep - clear) / 2  # from a side's line to its face
        if (t.min() >= c["t0"] and t.max() <= c["t1"]
                and s[0] <= face + SIDE_STEP_M and s[1] >= sep - face - SIDE_STEP_M):
            return True
    return False


def _nearest_wall(mids: np.ndarray, walls: list[int], xy: np.ndarray) -> int:
    """Of ``walls`` (indices), the one whose middle (``mids``, (N, 2) metres) lies
    nearest to ``xy`` ((2,) metres)."""
    return int(walls[int(np.argmin(np.hypot(*(mids[walls] - xy).T)))])

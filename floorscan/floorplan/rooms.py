"""Rooms of a floor plan (:func:`plan_rooms`): the free space the plan's scans saw,
bounded by the plan's walls, segmented into rooms at its doors.

The method is the distance-transform segmentation of Bormann et al., "Room
segmentation: survey, implementation, and analysis" (ICRA 2016; ipa_room_segmentation),
on a map whose obstacles are the plan's walls, not the raw returns, and with doors
taken from the walls:

1. **Space** (:func:`~floorscan.floorplan.room_space.room_space`): the cells the scans
   saw free (:func:`~floorscan.floorplan.free_space.passable`) on a raster of
   ``resolution_m``, opened by a disc of radius ``free_open_m`` (the thin fans
   of rays through windows and doorways into the outside go), minus the plan's wall
   footprints, whose gaps narrower than ``door_min_m`` are closed (nobody passes
   them); closed together with the walls by a disc of ``close_m`` (the unseen strips
   behind furniture along a wall and the shadows of objects join the room; the cells
   that bound the space stay out, so a wall the plan lacks is not bridged: the cells
   the scans saw occupied, and in a map every cell it does not mark free, since a map
   may draw a wall in a shade its thresholds read as unknown) and its
   holes without walls filled (the floor under a table); in a recording, without the
   space outside the building's closed outline (:mod:`floorscan.floorplan.outline`:
   the walls and seen obstacles closed by the smallest disc that holds the rover's
   path), in a map without the space beyond the convex hull of its walls (the rays it
   holds through windows). Furniture and clutter are not obstacles: a room's area is its floor area,
   and the floor under an object standing against a wall (the structure passes' step 5,
   :func:`~floorscan.floorplan.structure.floor_under`) no longer bounds it, and joins
   the room nearest along it, never across a wall, once the rooms are cut (step 5), not
   as a passage between rooms.
2. **Doors between walls** (:func:`~floorscan.floorplan.doors.wall_gaps`): the gap
   between the facing ends of two walls in one line, ``door_min_m`` to ``door_max_m``
   wide, that the scans saw through and that crosses no corridor (step 4), is cut first:
   a room seen only through its door ends at the door, and a room ends at its entrance
   in the building's outline, whatever the scans saw through it (an opening whose one
   side lies beyond the closed outline). So is the open side of a room
   (:func:`~floorscan.floorplan.mouths.room_mouths`): the line between the free ends of
   the walls that bound a room open on its whole width onto a corridor (an office, a
   cubicle), unless it crosses a corridor that goes on past it, or across the missing
   corner of two walls
   (:func:`~floorscan.floorplan.mouths.corner_mouths`: a corridor's corner open to the
   room beyond it), or between two corners in one wall's line where a dead end as wide
   as its opening leaves a hall (:func:`~floorscan.floorplan.mouths.dead_end_mouths`);
   a door where no wider than one. So are the openings, however wide,
   in the sides of a corridor, the strip between two long parallel lines of wall
   (:func:`~floorscan.floorplan.corridors.corridor_sides`), except where another
   corridor goes on from it; and, once these are drawn, the end of a corridor that
   opens onto a hall (:func:`~floorscan.floorplan.corridors.corridor_ends`: a dead end
   whose side walls end apart). The rooms are then segmented again
   (steps 3-5) where a wall stopping short of another, with an opening a door wide or
   wider (a door where no wider), divides a room it bounds for more than the opening
   (:func:`~floorscan.floorplan.extensions.partition_cuts`). An opening found on two
   of these lines within ``jamb_m`` of each other (between two walls' ends and on a
   corridor side's line) is cut once, on the narrower
   (:func:`~floorscan.floorplan.doors.distinct_gaps`).
3. **Regions** (:func:`~floorscan.floorplan.room_space.space_regions`): a watershed
   (scikit-image) of the negated distance to the nearest wall or unseen cell, from the
   maxima of that distance that stand ``marker_depth_m`` above the saddles around them
   (h-maxima): every narrowing of the space is a candidate boundary between two rooms.
4. **Rooms by persistence** (:mod:`floorscan.floorplan.persistence`): the regions
   merged across every passage that is no door (no wider than ``door_max_m``, at most
   three quarters of the width of each region it joins, between jambs, which no
   furniture the structure passes found loose in the space is,
   :func:`~floorscan.floorplan.jambs.loose_furniture`; not from the
   face of a wall to an object wider than a wall,
   :func:`~floorscan.floorplan.jambs.face_to_object`, nor from a column in a
   partition's line past the wall it crosses,
   :func:`~floorscan.floorplan.jambs.stub_past_crossing`, nor across a corridor,
   :func:`~floorscan.floorplan.corridors.across_corridor`): one rule for every passage of
   the plan, in no order. Two rooms that are both corridors and meet through a narrowing
   in no wall's line, at least ``DOOR_SHARE`` of the narrower one's width, are one
   corridor (:func:`~floorscan.floorplan.narrowings.corridor_narrowings`: a corridor
   whose sides bend or step). An opening wider than a door, up to
   :data:`~floorscan.floorplan.mouths.MOUTH_MAX_M` (a room's open side), between
   jambs and ending on no wall's face (:func:`~floorscan.floorplan.jambs.on_wall_face`:
   a passage from a wall's end to the face of a wall across it narrows the space, it
   opens no wall) is weighed as a door is and, where it parts two regions, is an open
   side between two rooms, no door: the layouts of Luperto et al. (ROSE^2, RA-L 2022)
   close a room across its openings, wider than a door too, where walls end on both
   sides. Two regions that also meet through an opening at least
   ``door_min_m`` wide that no jambs frame (one end at a desk or in unseen space) are
   one room, whatever slit or door they meet through besides. Where two rooms
   meet, the contact is their door (:mod:`floorscan.floorplan.doors`), in a wall's
   line when one ends there.
   Groups of regions whose edge runs along walls and seen obstacles for less than
   ``min_enclosure`` of its length, that are reached only through openings no wider
   than a door and where no scan was taken are the outside seen through a window or
   an open door: not rooms; in a recording, nor are the dead ends of unentered space
   (its regions joined through openings no jambs frame, taken together) walled on less
   than half of their edge
   (:data:`~floorscan.floorplan.room_space.MIN_ENCLOSURE_UNENTERED`; its edge along a
   hole in the space counts as walled) that meet one region alone, an entered one,
   through openings no jambs frame (gaps, windows, openings wider than a door); nor
   are the regions lying mostly beyond the closed outline
   (:mod:`floorscan.floorplan.unentered`). In a recording, unentered space walled on at
   least half its edge that meets one entered region alone through an opening wider
   than a door, as a room's open side is (:func:`~floorscan.floorplan.unentered.open_side_rooms`),
   is a room apart from it: a room seen from a hall through its open side.
5. **Rooms**: a region below ``min_room_area_m2`` joins the neighbour it touches most;
   two rooms parted by a row of desks are one
   (:func:`~floorscan.floorplan.desk_rows.join_desk_rows`: a door whose jamb walls are all
   shorter than ``door_min_m`` and tied to no other wall, between two rooms no longer
   together than one office); a room no scan was taken in and no door leads into is dropped unless walls and
   seen obstacles bound it along at least half of its edge
   (:data:`~floorscan.floorplan.room_space.MIN_ENCLOSURE_UNENTERED`): a fan of rays
   seen through an opening wider than a door is bounded at its far end at most, not
   along its two sides. A room is a
   ``corridor`` when it is long for its width (its length, area over width, at least
   ``corridor_elongation`` times its width and ``corridor_min_length_m``, and longer in
   proportion to its width where it is wider than ``corridor_max_width_m``
   (:func:`~floorscan.floorplan.room_tables.is_corridor`); the width, its polygon's
   median local thickness (:func:`~floorscan.floorplan.room_tables.room_width`) with
   its holes smaller than a room filled (an object on its floor, not a core it goes
   around)); in a recording, no room walled on less than half its edge
   (:func:`_unwalled`: the fan of rays through a door, the part of an open office the
   scans reached: an outline that is the reach of the scans). When no door divides
   the space (an open hall, one corridor, a campus), it is one region of kind ``space``
   (or a few, where the seen space falls apart).
6. **Polygons** (:func:`~floorscan.floorplan.room_polygons.room_polygons`): each room's cells, less its strips
   narrower than a walkway that nothing seen bounds (rays through a gap), traced, grown up to the wall faces
   and cut by the wall footprints, simplified by half a cell; a room seen in part, convex between its walls,
   completed up to them (its seen floor's bounding box, square to its longest wall, cut by each nearby wall's
   half-plane); door openings belong to no room; the rooms a coverage
   (:func:`~floorscan.floorplan.room_polygons.disjoint_rooms`: a sliver two rooms grew into is the first's).
   A room mostly narrower than a walkway (:data:`~floorscan.floorplan.room_space.MIN_ROOM_WIDTH_M`, its
   median local thickness: the unseen gap between two walls, a strip beside a corridor) joins the room of its
   widest doors, or goes without one. Valid polygons, holes allowed, in map metres, numbered ``Room 1``,
   ``Corridor 1``, ``Space 1`` in reading order (top to bottom, left to right).

Parameters: :class:`RoomParams` (config ``floorplan.rooms``: the door widths and the smallest
room; the other fields are constants of :mod:`floorscan.floorplan.room_space`).
"""

from __future__ import annotations

import dataclasses
import logging
import time

import numpy as np
import pandas as pd

from floorscan.core.geometry import OVERLAY_GRID_M, minus
from floorscan.core.occupancy import OccupancyGrid
from floorscan.floorplan import doors as D
from floorscan.floorplan.corridors import across_corridor, corridor_ends, corridor_sides, corridor_strips
from floorscan.floorplan.desk_rows import join_desk_rows
from floorscan.floorplan.extensions import partition_cuts
from floorscan.floorplan.jambs import face_to_object, jamb_cells, on_wall_face, stub_past_crossing
from floorscan.floorplan.lone_walls import bounding_no_room
from floorscan.floorplan.mouths import MOUTH_MAX_M, corner_mouths, dead_end_mouths, room_mouths
from floorscan.floorplan.narrowings import corridor_narrowings
from floorscan.floorplan.outline import regions_beyond
from floorscan.floorplan.persistence import persistent_rooms
from floorscan.floorplan.room_polygons import (disjoint_rooms, door_opening, largest_polygon,
                                              narrow_rooms_joined, room_polygons)
from floorscan.floorplan.room_space import (MIN_ENCLOSURE_UNENTERED, RoomParams, RoomRaster, enclosure_cells,
                                            room_space, space_regions)
from floorscan.floorplan.room_tables import room_tables
from floorscan.floorplan.unentered import (enclosure, open_side_rooms, outside_regions, region_sets, set_roots,
                                           visited_regions)

log = logging.getLogger(__name__)

def segment_rooms(
    grid: OccupancyGrid, axes: np.ndarray, thickness: np.ndarray, params: RoomParams = RoomParams(),
    under: np.ndarray | None = None, furniture: np.ndarray | None = None,
) -> tuple[RoomRaster, np.ndarray, list[tuple[np.ndarray, np.ndarray, int, int, int]], bool]:
    """The rooms and doors on the raster (module docstring, steps 1-5).

    Parameters
    ----------
    grid : OccupancyGrid
        The free space of the plan's scans.
    axes : (N, 4) float ndarray
        Wall axes ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Metres.
    params : RoomParams
    under : (K, 4, 2) float ndarray, optional
        The floor under the objects against walls, metres (:func:`plan_rooms`).
    furniture : (F, 4) float ndarray, optional
        Faces of furniture standing loose in the space, metres: no door's jamb
        (:func:`~floorscan.floorplan.jambs.jamb_cells`).

    Returns
    -------
    raster : RoomRaster
    labels : (H, W) int32 ndarray
        0 outside every room, else the room (1..R, in reading order: the first cell
        of each room from the top row down, left to right).
    doors : list of (p, q, wall, room_a, room_b)
        Each door's opening from ``p`` to ``q`` ((2,) metres) in the line of wall
        ``wall`` and the rooms it joins (``room_a < room_b``, labels).
    divided : bool
        Whether a room's open side wider than a door (:mod:`floorscan.floorplan.mouths`)
        divides two rooms (:func:`~floorscan.floorplan.room_tables.room_tables`).
    """

    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    thickness = np.asarray(thickness, dtype=np.float64).reshape(-1)
    raster = room_space(grid, axes, thickness, params, under)
    strips = corridor_strips(axes, thickness, raster, params) if len(axes) >= 2 else []
    # an opening between two walls' ends bounds the rooms on its line, an entrance too
    gaps = [g for g in D.wall_gaps(axes, thickness, params) + corner_mouths(axes, thickness, params)
            if D.passes_through(raster, g[0], g[1], outward=True) and not across_corridor(g[0], g[1], strips, params)]
    gaps += [g for g in room_mouths(axes, thickness, raster, params)
             if not across_corridor(g[0], g[1], strips, params)]
    gaps += dead_end_mouths(axes, thickness, raster, params)
    gaps += [g for g in corridor_sides(axes, thickness, raster, params, strips) if D.passes_through(raster, g[0], g[1])]
    # a corridor's end opens onto a hall once the rooms' other boundaries are drawn
    gaps += [g for g in corridor_ends(axes, thickness, _cut_along(raster, gaps)[0], params, strips)
             if D.passes_through(raster, g[0], g[1])]
    gaps = D.distinct_gaps(gaps, params.jamb_m)
    segmented = _segment(grid, axes, thickness, params, raster, gaps, strips, furniture)
    cuts = partition_cuts(axes, thickness, raster, segmented[1], params)
    if cuts:  # the rooms again, cut where partitions stop short of a wall
        segmented = _segment(grid, axes, thickness, params, raster, D.distinct_gaps(gaps + cuts, params.jamb_m),
                             strips, furniture)
    return segmented


def _cut_along(raster: RoomRaster, gaps: list) -> tuple[RoomRaster, np.ndarray]:
    """``raster`` cut along ``gaps`` ((p, q, wall) lines): the cells of their barriers
    ((H, W) bool, :func:`~floorscan.floorplan.doors.barrier_cells`) are walls, no
    longer space; and the barrier."""
    barrier = np.zeros(raster.space.shape, dtype=bool)
    for p, q, _ in gaps:
        rr, cc = D.barrier_cells(raster, p, q)
        barrier[rr, cc] = True
    return dataclasses.replace(raster, walls=raster.walls | barrier, space=raster.space & ~barrier), barrier


def _segment(grid: OccupancyGrid, axes: np.ndarray, thickness: np.ndarray, params: RoomParams, raster: RoomRaster,
             gaps: list, strips: list, furniture: np.ndarray | None = None,
             ) -> tuple[RoomRaster, np.ndarray, list, bool]:  # fmt: skip
    """:func:`segment_rooms` on ``raster`` cut along ``gaps`` ((p, q, wall) lines that bound
    rooms), with the corridors ``strips`` and the loose ``furniture``; returns as
    :func:`segment_rooms`."""
    cut, barrier = _cut_along(raster, gaps)
    labels, distance = space_regions(cut, params)
    n = int(labels.max())
    # where two regions meet between jambs (jamb_cells: both ends near a wall or a seen
    # obstacle that is no object standing free), no wider than a door: a door, or,
    # narrower than a door, a slit nobody passes, which keeps two regions apart without
    # a door; unless it is no opening in a wall (module docstring, step 4)
    jambs = jamb_cells(cut, params.jamb_m, axes, thickness, params, furniture)
    contacts = D.contacts(labels)
    framed: dict[tuple[int, int], list] = {}
    narrowings: dict[tuple[int, int], float] = {}  # the widest such contact of each pair, metres
    widest: dict[tuple[int, int], float] = {}  # the widest contact of each pair, metres
    passable: set[tuple[int, int]] = set()  # pairs that also meet through an opening no jambs frame
    wide: set[tuple[int, int]] = set()  # pairs that meet through an opening wider than a door, between jambs
    open_wide: set[tuple[int, int]] = set()  # pairs that also meet through a wider opening that is none
    for pair, places in contacts.items():
        for cells in places:
            p, q = D.contact_segment(cut, cells)
            width = float(np.hypot(*(q - p)))
            widest[pair] = max(widest.get(pair, 0.0), width)
            if width > params.door_max_m:
                # an opening in the structure wider than a door and no wider than a
                # room's open side: both ends at jambs, neither on a wall's face (a
                # passage between a wall's face and what stands across it narrows the
                # space, it opens no wall); the saddle weighs it as it weighs a door
                if (width <= MOUTH_MAX_M and cut.at(jambs, np.array([p, q])).all()
                        and not any(on_wall_face(e, axes, thickness, params) for e in (p, q))):
                    wide.add(pair)
                else:
                    open_wide.add(pair)
                continue
            if not cut.at(jambs, np.array([p, q])).all():
                if width >= params.door_min_m:
                    passable.add(pair)
                continue
            if width >= params.door_min_m:
                if (face_to_object(cut, p, q, axes, thickness, params)
                        or stub_past_crossing(cut, p, q, axes, thickness, params)):
                    continue
                if across_corridor(p, q, strips, params):
                    passable.add(pair)  # across a corridor: no opening in a wall
                    continue
            doors_here = framed.setdefault(pair, [])
            if width >= params.door_min_m:
                door = D.contact_door(p, q, axes, thickness, params)
                if door is None:  # in no wall's line: a narrowing (corridor_narrowings), or a free door
                    narrowings[pair] = max(narrowings.get(pair, 0.0), width)
                    door = D.free_door(p, q, axes)
                if door is not None:
                    doors_here.append(door)
    # two regions that meet through an opening a person passes and no jambs frame are
    # one room, whatever slit or door they also meet through; an opening wider than a
    # door parts them only when it is their widest passage
    wide -= open_wide
    root = persistent_rooms(labels, distance, params.door_max_m, (set(framed) | wide) - passable, wide, MOUTH_MAX_M)
    root = corridor_narrowings(labels, root, narrowings, params)
    sets = region_sets(n)
    found = []  # (p, q, wall, a, b)
    open_sides = []  # pairs of regions apart at a room's open side (no door)
    touching: dict[tuple[int, int], float] = {}  # contact length between regions, metres
    kinds: dict[tuple[int, int], str] = {}  # door (apart), narrow or wide (one room)
    for (a, b), places in contacts.items():
        touching[(a, b)] = sum(len(cells) for cells in places) * raster.resolution_m
        if root[a] == root[b]:
            kinds[(a, b)] = "narrow" if widest[(a, b)] <= params.door_max_m else "wide"
        else:
            kinds[(a, b)] = "door"
            found += [(*door, a, b) for door in framed.get((a, b), [])]
            if (a, b) in wide and not framed.get((a, b)):
                open_sides.append((a, b))  # apart at an opening wider than a door, no door
    for p, q, wall in gaps:
        d = q - p
        nrm = np.array([-d[1], d[0]]) / max(float(np.hypot(*d)), 1e-12) * 2 * raster.resolution_m
        a, b = (int(v) for v in raster.at(labels, np.array([(p + q) / 2 + nrm, (p + q) / 2 - nrm])))
        if a and b and a != b:
            pair = (min(a, b), max(a, b))
            if np.hypot(*d) <= params.door_max_m:  # a room's open side wider than a door is no door
                found.append((p, q, wall, *pair))
            else:
                open_sides.append(pair)
            touching[pair] = touching.get(pair, 0.0) + float(np.hypot(*d))
            kinds.setdefault(pair, "door")
    visited = visited_regions(cut, labels, grid.scan_xy, n)
    cells = enclosure_cells(cut)  # the walled cells, for every enclosure below
    outside = outside_regions(cut, labels, kinds, params, visited, grid.scan_xy is not None, cells)
    if grid.scan_xy is not None:  # a room seen through its open side is apart from where it was seen
        for pair in open_side_rooms(cut, labels, kinds, widest, visited, outside, cells):
            kinds[pair] = "door"
            open_sides.append(pair)
    if raster.beyond is not None:  # the regions beyond the building's closed outline
        outside |= regions_beyond(labels, raster.beyond) & ~visited
    for (a, b), kind in kinds.items():
        if kind in ("narrow", "wide") and not (outside[a] or outside[b]):
            sets.merge(a, b)
    found = [d for d in found if not (outside[d[3]] or outside[d[4]])]
    touching = {k: v for k, v in touching.items() if not (outside[k[0]] or outside[k[1]])}
    # regions below the room area join the neighbour they touch most (through a door too)
    area = np.bincount(labels.ravel(), minlength=n + 1) * raster.resolution_m**2
    for _ in range(n):
        roots = set_roots(sets, n)
        room_area = np.bincount(roots, weights=area, minlength=n + 1)
        small = [r for r in np.flatnonzero(room_area > 0) if r and room_area[r] < params.min_room_area_m2]
        best = None
        for r in small:
            links: dict[int, float] = {}
            for (a, b), length in touching.items():
                ra, rb = roots[a], roots[b]
                if ra != rb and r in (ra, rb):
                    other = rb if ra == r else ra
                    links[other] = links.get(other, 0.0) + length
            if links:
                other = max(sorted(links), key=links.get)
                best = (r, other)
                break
        if best is None:
            break
        sets.merge(*best)
    join_desk_rows(found, labels, sets, axes, thickness, cut, params)  # a desk row parts no rooms
    roots = set_roots(sets, n)
    merged = roots[labels]
    merged[outside[labels]] = 0
    # drop what is still below the room area (an isolated scrap of space), and the
    # unentered space that no door joins to a room and walls bound on less than half
    # its edge (a fan seen through a wide opening)
    room_area = np.bincount(merged.ravel(), minlength=n + 1) * raster.resolution_m**2
    merged[room_area[merged] < params.min_room_area_m2] = 0
    with_door = np.zeros(n + 1, dtype=bool)
    for _, _, _, a, b in found:
        if roots[a] != roots[b]:
            with_door[[roots[a], roots[b]]] = True
    unentered = ~with_door & ~visited_regions(cut, merged, grid.scan_xy, n)
    loose = (enclosure(cut, merged, n, cells) < MIN_ENCLOSURE_UNENTERED) & unentered
    loose[0] = False
    if loose.any() and (~loose[1:] & (room_area[1:] > 0)).any():  # never the whole space
        merged[loose[merged]] = 0
    # number the rooms in reading order (first cell from the top row down)
    flat = merged[::-1].ravel()
    ids, first = np.unique(flat, return_index=True)
    order = ids[ids > 0][np.argsort(first[ids > 0], kind="stable")]
    renum = np.zeros(n + 1, dtype=np.int32)
    renum[order] = np.arange(1, len(order) + 1, dtype=np.int32)
    final = renum[merged]
    # a door cell belongs to a room beside it
    from skimage.segmentation import expand_labels, watershed

    grown = expand_labels(final, 1)
    final = np.where(barrier & raster.space, grown, final).astype(np.int32)
    if raster.under is not None:
        # the floor under objects against walls, and the seen floor the walls' closing
        # took: the room nearest along that floor (a breadth-first flood from the
        # rooms), never across a wall
        grow = raster.under & (final == 0)
        flooded = watershed(np.zeros(final.shape, dtype=np.uint8), markers=final, mask=grow | (final > 0),
                            connectivity=1)
        final = np.where(grow, flooded, final).astype(np.int32)
    doors = []
    for p, q, wall, a, b in found:
        ra, rb = renum[roots[a]], renum[roots[b]]
        if ra and rb and ra != rb:
            doors.append((p, q, wall, int(min(ra, rb)), int(max(ra, rb))))
    divided = any(renum[roots[a]] and renum[roots[b]] and renum[roots[a]] != renum[roots[b]] for a, b in open_sides)
    return raster, final, D.distinct_doors(doors), divided


def _unwalled(raster: RoomRaster, labels: np.ndarray, scan_xy: np.ndarray | None, n: int) -> np.ndarray:
    """(n + 1,) bool: the rooms of ``labels`` (1..n) whose outline is the reach of the
    scans, in a recording (``scan_xy`` (S, 2) metres, the scans' origins; None, a map:
    none): walls and seen obstacles bound less than
    :data:`~floorscan.floorplan.room_space.MIN_ENCLOSURE_UNENTERED` of their edge
    (:func:`~floorscan.floorplan.unentered.enclosure`), whether a scan was taken in them
    or not. What the scans saw of such a room is the fan of rays through its door, or
    the part of an open office they reached between its desks; either outline says
    nothing of the room's shape, so its length for its width is no corridor's: a
    corridor runs between walls (:func:`~floorscan.floorplan.room_tables.room_tables`)."""
    if scan_xy is None or n == 0:
        return np.zeros(n + 1, dtype=bool)
    out = enclosure(raster, labels, n) < MIN_ENCLOSURE_UNENTERED
    out[0] = False
    return out


def plan_rooms(
    axes: np.ndarray, thickness: np.ndarray, grid: OccupancyGrid, params: RoomParams = RoomParams(),
    under: np.ndarray | None = None, furniture: np.ndarray | None = None,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The rooms and doors of a plan: :func:`rooms_and_walls` without the walls."""
    return rooms_and_walls(axes, thickness, grid, params, under, furniture)[:2]


def rooms_and_walls(
    axes: np.ndarray, thickness: np.ndarray, grid: OccupancyGrid, params: RoomParams = RoomParams(),
    under: np.ndarray | None = None, furniture: np.ndarray | None = None,
) -> tuple[pd.DataFrame, pd.DataFrame, np.ndarray]:
    """The rooms and doors of a plan (the module docstring): the tables of
    :attr:`~floorscan.floorplan.plan.FloorPlan.rooms` and
    :attr:`~floorscan.floorplan.plan.FloorPlan.doors`, and the walls that bound no room.

    Parameters
    ----------
    axes : (N, 4) float ndarray
        The plan's wall axes ``x0, y0, x1, y1``, metres (a door's ``wall_id`` is a row).
    thickness : (N,) float ndarray
        Metres.
    grid : OccupancyGrid
        The free space of the plan's scans.
    params : RoomParams
    under : (K, 4, 2) float ndarray, optional
        The floor under the objects standing against walls
        (:func:`~floorscan.floorplan.structure.floor_under`), metres: the rooms' floor.
    furniture : (F, 4) float ndarray, optional
        Faces of furniture standing loose in the space
        (:func:`~floorscan.floorplan.jambs.loose_furniture`), metres: it frames no door.

    Returns
    -------
    rooms : pandas.DataFrame
        ``room_id`` (0..R-1), ``name``, ``kind``, ``area_m2``, ``perimeter_m``,
        ``polygon`` (shapely Polygon, map metres).
    doors : pandas.DataFrame
        ``door_id``, ``x0, y0, x1, y1`` (metres), ``width_m``, ``wall_id``, ``room_a``,
        ``room_b`` (room ids).
    lone : (N,) bool ndarray
        The walls no room's cells come near (:func:`~floorscan.floorplan.lone_walls.bounding_no_room`);
        none when there is no room.
    """
    import shapely

    t0 = time.perf_counter()
    raster, labels, doors, divided = segment_rooms(grid, axes, thickness, params, under, furniture)
    n = int(labels.max())
    unwalled = _unwalled(raster, labels, grid.scan_xy, n)
    polys = room_polygons(raster, labels, axes, thickness)
    if doors:  # the opening in the wall belongs to neither room: rooms end at the wall faces
        openings = shapely.union_all([door_opening(p, q, thickness[w], raster.resolution_m) for p, q, w, *_ in doors],
                                     grid_size=OVERLAY_GRID_M)  # fmt: skip
        polys = [largest_polygon(shapely.simplify(minus(p, openings), raster.resolution_m / 4)) for p in polys]
    polys = disjoint_rooms(polys)
    polys, doors = narrow_rooms_joined(polys, doors, thickness, raster.resolution_m)
    keep = [k for k in range(n) if not polys[k].is_empty and polys[k].area >= params.min_room_area_m2]
    new_id = {k + 1: i for i, k in enumerate(keep)}
    polys = [polys[k] for k in keep]
    doors = [(p, q, w, new_id[a], new_id[b]) for p, q, w, a, b in doors if a in new_id and b in new_id]
    rooms, doors_df = room_tables(polys, doors, raster.resolution_m, params, divided,
                                  [bool(unwalled[k + 1]) for k in keep])
    kinds = list(rooms["kind"])
    lone = bounding_no_room(raster, labels > 0, axes, thickness)
    log.info("rooms: %d rooms (%d corridors), %d doors, %.1f m2 in all; %d walls bound none (%.2f s)", len(polys),
             kinds.count("corridor"), len(doors_df), float(rooms["area_m2"].sum()), int(lone.sum()),
             time.perf_counter() - t0)
    return rooms, doors_df, lone


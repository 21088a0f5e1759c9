"""Rooms and doors of a floor plan (floorscan.floorplan.rooms, floorscan.floorplan.doors)
on small buildings scanned by a ray caster: the plan's walls are given (their axes and
thickness), the free space comes from the scans' occupancy grid."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import shapely

from conftest import cast_rays
from floorscan.core.occupancy import OccupancyParams, occupancy_grid
from floorscan.floorplan.doors import distinct_gaps, wall_gaps
from floorscan.floorplan.jambs import jamb_cells
from floorscan.floorplan.room_space import RoomParams, room_space
from floorscan.floorplan.mouths import corner_mouths, room_mouths
from floorscan.floorplan.rooms import plan_rooms, segment_rooms

T = 0.12  # wall thickness, metres


def _wall_faces(walls: list, thickness: float = T) -> list:
    """The two faces ((x0, y0, x1, y1), metres) of each wall of ``walls`` (axes),
    ``thickness`` metres apart."""
    faces = []
    for x0, y0, x1, y1 in walls:
        d = np.array([x1 - x0, y1 - y0]) / np.hypot(x1 - x0, y1 - y0)
        n = np.array([-d[1], d[0]]) * thickness / 2
        faces += [[x0 + n[0], y0 + n[1], x1 + n[0], y1 + n[1]], [x0 - n[0], y0 - n[1], x1 - n[0], y1 - n[1]]]
    return faces


def _grid(walls: list, poses: list, seed: int = 1, objects: list = (), thickness: float = T):
    """The occupancy grid of 360-degree scans from ``poses`` of the wall faces of
    ``walls`` ((x0, y0, x1, y1) axes, ``thickness`` metres) and of the faces ``objects``
    ((x0, y0, x1, y1) each)."""
    rng = np.random.default_rng(seed)
    faces = np.array(_wall_faces(walls, thickness) + [list(f) for f in objects])
    a = np.linspace(-np.pi, np.pi, 1440, endpoint=False)
    scans = []
    for p in poses:
        o = np.asarray(p, dtype=np.float64)
        r = cast_rays(faces, o, a)
        hit = np.isfinite(r) & (r < 12.0)
        r = r[hit] + rng.normal(0, 0.005, int(hit.sum()))
        scans.append((o, o + r[:, None] * np.column_stack([np.cos(a[hit]), np.sin(a[hit])])))
    return occupancy_grid(scans, OccupancyParams())


def _rooms(walls, poses, params=RoomParams()):
    axes = np.array(walls, dtype=np.float64)
    return plan_rooms(axes, np.full(len(axes), T), _grid(walls, poses), params)


# Two rooms 4 x 4 m side by side, joined by a 0.9 m door in the partition (y 1.5..2.4).
BOX = [(0, 0, 8, 0), (8, 0, 8, 4), (8, 4, 0, 4), (0, 4, 0, 0)]
TWO_ROOMS = BOX + [(4, 0, 4, 1.5), (4, 2.4, 4, 4)]


def test_the_floor_under_a_cabinet_against_a_wall_is_the_room_s():
    # one room 4 x 4 m; a cabinet 2 x 0.6 m against its north wall (faces 0.06 m inside);
    # as a map (no scan positions), every cell it does not mark free bounds the space;
    # the floor under the cabinet bounds it no longer, and joins the room once it is cut
    box = [(0, 0, 4, 0), (4, 0, 4, 4), (4, 4, 0, 4), (0, 4, 0, 0)]
    cabinet = [(1, 3.34, 3, 3.34), (1, 3.34, 1, 3.94), (3, 3.34, 3, 3.94)]
    grid = dataclasses.replace(_grid(box, [(1.0, 1.0), (3.0, 1.5), (2.0, 2.5)], objects=cabinet), scan_xy=None)
    axes = np.array(box, dtype=np.float64)
    under = np.array([[[1, 3.34], [3, 3.34], [3, 3.94], [1, 3.94]]], dtype=np.float64)
    without = room_space(grid, axes, np.full(4, T), RoomParams())
    with_floor = room_space(grid, axes, np.full(4, T), RoomParams(), under)
    xy = np.array([[x, y] for x in np.arange(1.15, 2.9, 0.1) for y in (3.45, 3.6, 3.75)])
    assert not without.at(without.space, xy).any()  # the cabinet's cells bound the space
    assert with_floor.at(with_floor.under, xy).all() and not with_floor.at(with_floor.bounds, xy).any()
    # without the cabinet's floor, ``under`` holds only the seen floor the closing of the
    # walls took: none in a box drawn along the cells
    assert not with_floor.at(with_floor.space, xy).any() and not without.under.any()
    assert with_floor.under.sum() * with_floor.resolution_m**2 == pytest.approx(1.2, abs=0.25)
    assert np.array_equal(with_floor.space, without.space)  # elsewhere the same space
    rooms, _ = plan_rooms(axes, np.full(4, T), grid, RoomParams(), under)
    assert len(rooms) == 1 and 14.6 < rooms["area_m2"][0] < 15.3


def test_the_floor_under_a_cabinet_row_across_a_partition_joins_no_two_rooms():
    # two rooms 4 x 4 m; the partition between them (a 0.9 m door at y 1..1.9) ends at
    # the front of a cabinet row (x 2.5..5.5, 0.9 m deep) against the north wall: the
    # floor under the row is no passage (no second door) and each room takes its half
    box = [(0, 0, 8, 0), (8, 0, 8, 4), (8, 4, 0, 4), (0, 4, 0, 0), (4, 0, 4, 1.0), (4, 1.9, 4, 3.04)]
    cabinet = [(2.5, 3.04, 5.5, 3.04), (2.5, 3.04, 2.5, 3.94), (5.5, 3.04, 5.5, 3.94)]
    grid = dataclasses.replace(_grid(box, [(1.5, 1.5), (6.5, 1.5), (2, 2.5), (6, 2.5)], objects=cabinet), scan_xy=None)
    axes = np.array(box, dtype=np.float64)
    under = np.array([[[2.5, 3.04], [5.5, 3.04], [5.5, 3.94], [2.5, 3.94]]], dtype=np.float64)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid, RoomParams(), under)
    assert len(rooms) == 2 and len(doors) == 1
    assert ((doors.x0 + doors.x1) / 2).iloc[0] == pytest.approx(4.0, abs=0.1)
    assert ((doors.y0 + doors.y1) / 2).iloc[0] == pytest.approx(1.45, abs=0.1)
    west, east = sorted(rooms["polygon"], key=lambda p: p.centroid.x)
    assert west.contains(shapely.Point(3.0, 3.5)) and east.contains(shapely.Point(5.0, 3.5))
    assert 14.6 < west.area < 15.6 and 14.6 < east.area < 15.6


def test_the_floor_under_a_deep_cabinet_against_a_partition_is_its_own_room_s_not_the_nearer_one_behind_the_wall():
    # two rooms 4 x 4 m, a 0.9 m door in the partition (y 1.5..2.4); a cabinet 0.9 m deep
    # (x 4.06..4.96, y 2.4..3.9) against the partition in the east room, beside the door:
    # the half of its floor next to the partition lies nearer the west room's floor
    # (0.12 m across the partition) than the east room's (0.9 m along it), and is the
    # east room's, cell for cell
    cabinet = [(4.96, 2.4, 4.96, 3.9), (4.06, 2.4, 4.96, 2.4), (4.06, 3.9, 4.96, 3.9)]
    grid = dataclasses.replace(_grid(TWO_ROOMS, [(2, 2), (6, 1), (6.5, 3)], objects=cabinet), scan_xy=None)
    axes = np.array(TWO_ROOMS, dtype=np.float64)
    under = np.array([[[4.96, 2.4], [4.96, 3.9], [4.06, 3.9], [4.06, 2.4]]], dtype=np.float64)
    raster, labels, doors, _ = segment_rooms(grid, axes, np.full(len(axes), T), RoomParams(), under)
    assert labels.max() == 2 and len(doors) == 1
    west, east = raster.at(labels, np.array([[2.0, 2.0], [6.0, 2.0]]))
    floor = raster.at(labels, raster.centres(*np.nonzero(raster.under)))
    assert raster.under.sum() * raster.resolution_m**2 > 1.0  # most of the cabinet's 1.35 m2
    assert (floor == east).mean() > 0.97 and not (floor == west).any()


def test_loose_furniture_frames_no_door_but_the_wall_it_stands_against_still_does():
    """A room 4 x 8 m with a desk against its west wall and a shelf against its east wall,
    each 1.54 m long and 0.4 m deep, 0.8 m apart across the room: their ends frame a
    door between two rooms, unless the plan calls them loose furniture (the structure
    passes' ``loose_in_free_space`` clutter, :func:`~floorscan.floorplan.jambs.jamb_cells`);
    then the room is one. The cells along the walls stay jambs."""
    box = [(0, 0, 4, 0), (4, 0, 4, 8), (4, 8, 0, 8), (0, 8, 0, 0)]
    desk = [(0.06, 3.8, 1.6, 3.8), (1.6, 3.8, 1.6, 4.2), (1.6, 4.2, 0.06, 4.2)]
    shelf = [(3.94, 3.8, 2.4, 3.8), (2.4, 3.8, 2.4, 4.2), (2.4, 4.2, 3.94, 4.2)]
    grid = _grid(box, [(2, 2), (2, 6), (1.0, 1.5), (3.0, 6.5)], objects=desk + shelf)
    axes = np.array(box, dtype=np.float64)
    rooms, doors = plan_rooms(axes, np.full(4, T), grid, RoomParams())
    assert len(rooms) == 2 and len(doors) == 1  # the desk's and the shelf's ends frame it
    assert doors[["x0", "x1"]].to_numpy().ravel() == pytest.approx([1.6, 2.4], abs=0.1)
    rooms, doors = plan_rooms(axes, np.full(4, T), grid, RoomParams(), None, np.array(desk + shelf, dtype=np.float64))
    assert len(rooms) == 1 and len(doors) == 0 and rooms["area_m2"][0] == pytest.approx(30.6, abs=0.6)
    # the jambs along the walls stay: a desk's cells farther than a jamb's reach and a
    # cell from every wall frame no door, the cells along the wall it stands against do
    raster = room_space(grid, axes, np.full(4, T), RoomParams())
    plain = jamb_cells(raster, RoomParams().jamb_m)
    loose = jamb_cells(raster, RoomParams().jamb_m, furniture=np.array(desk + shelf, dtype=np.float64))
    assert raster.at(plain, np.array([[1.7, 4.0], [2.3, 4.0]])).all()  # the desk's and shelf's ends
    assert not raster.at(loose, np.array([[1.7, 4.0], [2.3, 4.0]])).any()
    along = np.array([[0.1, y] for y in np.arange(3.6, 4.45, 0.1)] + [[3.9, y] for y in np.arange(3.6, 4.45, 0.1)])
    assert raster.at(loose, along).all()


def test_no_room_mouth_runs_diagonally_between_two_perpendicular_walls():
    # a 2 x 2 grid of rooms whose inner walls cross, with a 0.9 m door in each of the
    # four arms; the south arm's free end (2.125, 0.8) and the west arm's (1.59, 2.5) lie
    # 1.78 m apart on a line 17.5 degrees off both walls' directions: no room's open side
    box = [(0, 0, 5.625, 0), (5.625, 0, 5.625, 5.75), (5.625, 5.75, 0, 5.75), (0, 5.75, 0, 0)]
    inner = [(2.125, 0, 2.125, 0.8), (2.125, 1.7, 2.125, 3.67), (2.125, 4.57, 2.125, 5.75),
             (0, 2.5, 0.69, 2.5), (1.59, 2.5, 3.68, 2.5), (4.57, 2.5, 5.625, 2.5)]  # fmt: skip
    walls = box + inner
    poses = [(1.0, 1.2), (3.9, 1.2), (1.0, 4.1), (3.9, 4.1), (2.125, 1.25), (1.14, 2.5), (4.1, 2.5), (2.125, 4.1)]
    grid = _grid(walls, poses)
    axes = np.array(walls, dtype=np.float64)
    mouths = room_mouths(axes, np.full(len(axes), T), room_space(grid, axes, np.full(len(axes), T), RoomParams()),
                         RoomParams())  # fmt: skip
    ends = [{tuple(np.round(p, 2)), tuple(np.round(q, 2))} for p, q, _ in mouths]
    assert {(2.12, 0.8), (1.59, 2.5)} not in ends and {(2.13, 0.8), (1.59, 2.5)} not in ends
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid)
    assert len(rooms) == 4 and len(doors) == 4
    assert sorted(np.round(doors["width_m"], 1).tolist()) == [0.9, 0.9, 0.9, 0.9]


def test_two_rooms_and_their_door():
    rooms, doors = _rooms(TWO_ROOMS, [(2, 2), (6, 2), (3.5, 1.95), (4.5, 1.95)])
    assert len(rooms) == 2 and list(rooms["kind"]) == ["room", "room"]
    assert list(rooms["name"]) == ["Room 1", "Room 2"]
    # floor area of each: 4 x 4 m between wall axes, less half of each wall
    for poly, area in zip(rooms["polygon"], rooms["area_m2"]):
        assert poly.is_valid and poly.geom_type == "Polygon"
        assert area == pytest.approx(poly.area) and 14.5 < area < 15.9
    west = rooms["polygon"][int(np.argmin([p.centroid.x for p in rooms["polygon"]]))]
    assert shapely.box(0.06, 0.06, 3.94, 3.94).difference(west).area < 0.3
    assert len(doors) == 1
    d = doors.iloc[0]
    centre = np.array([(d.x0 + d.x1) / 2, (d.y0 + d.y1) / 2])
    assert np.hypot(*(centre - [4.0, 1.95])) < 0.1 and d.width_m == pytest.approx(0.9, abs=0.1)
    assert {d.room_a, d.room_b} == {0, 1} and d.wall_id in (4, 5)


def test_an_open_hall_is_one_space():
    rooms, doors = _rooms(BOX, [(2, 2), (6, 2)])
    assert list(rooms["kind"]) == ["space"] and list(rooms["name"]) == ["Space 1"] and len(doors) == 0
    assert 30.0 < rooms["area_m2"].iloc[0] < 32.0


def test_an_opening_wider_than_a_door_between_jambs_parts_two_rooms_without_a_door():
    # the partition leaves 2.5 m open between its two pieces: wider than door_max_m
    # (2.0), no wider than a room's open side (MOUTH_MAX_M, 4.0), and narrower than the
    # 4 x 4 m halves: two rooms apart at an open side, no door (before: one room)
    rooms, doors = _rooms(BOX + [(4, 0, 4, 1.0), (4, 3.5, 4, 4)], [(2, 2), (6, 2)])
    assert len(doors) == 0
    assert list(rooms["kind"]) == ["room", "room"]
    assert sorted(rooms["area_m2"]) == pytest.approx([15.1, 15.1], abs=0.5)


def test_a_passage_from_a_wall_s_end_to_a_wall_s_face_parts_no_rooms():
    # a 10 x 4 m room with a 1.5 m pier from its south wall at x = 4: the 2.5 m passage
    # from the pier's end to the north wall's face narrows the space, it opens no wall
    # (without that test: two rooms of 15.3 and 22.9 m2)
    room = [(0, 0, 10, 0), (10, 0, 10, 4), (10, 4, 0, 4), (0, 4, 0, 0), (4, 0, 4, 1.5)]
    rooms, doors = _rooms(room, [(2, 2), (7, 2)])
    assert len(rooms) == 1 and len(doors) == 0
    assert rooms["area_m2"].iloc[0] == pytest.approx(38.2, abs=0.5)


# A corridor 1.9 m wide (y 0..1.9) under two rooms (y 1.9..5.9) parted by a partition at
# x 6, a 0.9 m door from each into the corridor; a column 0.4 m across in the corridor
# against its north wall, in the partition's line, whose side faces the plan took for
# the partition running on 0.56 m past the corridor's wall (the furnished Freiburg52
# and Freiburg79 maps' corridors).
COLUMN_ROOMS = [(0, 0, 12, 0), (12, 0, 12, 5.9), (12, 5.9, 0, 5.9), (0, 5.9, 0, 0), (0, 1.9, 2.5, 1.9),
                (3.4, 1.9, 8.6, 1.9), (9.5, 1.9, 12, 1.9)]  # fmt: skip
COLUMN = [(5.8, 1.34, 6.2, 1.34), (5.8, 1.34, 5.8, 1.8), (6.2, 1.34, 6.2, 1.8), (5.8, 1.8, 6.2, 1.8)]


def test_a_column_in_a_partition_s_line_past_the_corridor_wall_frames_no_door_across_the_corridor():
    # the contact from the partition's end past the wall (y 1.34) to the corridor's south
    # wall is 1.28 m, a door's width, in the partition's line: before, a door there cut
    # the corridor in two; the piece past the wall it crosses is shorter than a door and
    # stands in the space, a column's, no jamb (before: two corridor halves of 10.3 m2,
    # "Room 3" and "Room 4", and a door at x 6 from y 0.1 to 1.34)
    poses = [(3, 0.9), (9, 0.9), (3, 4), (9, 4)]
    grid = dataclasses.replace(_grid(COLUMN_ROOMS + [(6, 5.9, 6, 1.9)], poses, objects=COLUMN), scan_xy=None)
    axes = np.array(COLUMN_ROOMS + [(6, 5.9, 6, 1.34)], dtype=np.float64)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid, RoomParams())
    assert list(rooms["name"]) == ["Room 1", "Room 2", "Corridor 1"]
    assert rooms["area_m2"].to_numpy() == pytest.approx([22.76, 22.76, 20.98], abs=0.3)
    assert sorted(doors["x0"]) == pytest.approx([2.5, 8.6]) and (doors["room_b"] == 2).all()


def test_a_wall_s_piece_past_a_crossing_is_a_jamb_unless_it_stands_in_the_space():
    # a wall at y 3 parts two rooms from one below, a 1 m door in it at x 4.56..5.56; a
    # partition at x 4 meets it from the north, and the plan ran it on to y 2 along the
    # side of a cabinet (x 4..4.5, y 2..2.94) against the wall's south face. The wall's
    # 0.56 m past the crossing runs along the cabinet's top: a pier, whose end frames the
    # door (lab_d_scan's furnished map). Without the cabinet the piece stands in the space
    # on both sides, as a column's faces do: no jamb.
    from floorscan.floorplan.jambs import stub_past_crossing

    walls = [(0, -1, 10, -1), (10, -1, 10, 6), (10, 6, 0, 6), (0, 6, 0, -1), (0, 3, 1, 3), (2, 3, 4.56, 3),
             (5.56, 3, 10, 3)]  # fmt: skip
    cabinet = [(4.06, 2.0, 4.5, 2.0), (4.5, 2.0, 4.5, 2.94)]
    axes = np.array(walls + [(4, 6, 4, 2.0)], dtype=np.float64)
    thickness = np.full(len(axes), T)
    p, q = np.array([4.56, 3.0]), np.array([5.56, 3.0])
    found = []
    for objects in (cabinet, []):
        grid = dataclasses.replace(_grid(walls + [(4, 6, 4, 3)], [(2, 4.5), (7, 4.5), (5, 1)], objects=objects),
                                   scan_xy=None)  # fmt: skip
        raster = room_space(grid, axes, thickness, RoomParams())
        found.append((stub_past_crossing(raster, p, q, axes, thickness, RoomParams()),
                      stub_past_crossing(raster, q, p, axes, thickness, RoomParams())))  # fmt: skip
    assert found == [(False, False), (True, True)]
    # the partition ending at the wall (a T): the wall crosses nothing, its end is a jamb
    tee = np.array(walls + [(4, 6, 4, 3.0)], dtype=np.float64)
    assert not stub_past_crossing(raster, p, q, tee, thickness, RoomParams())


# Two corridors 1.8 m wide crossing two others 12 m apart (a "#" without its top
# bar), their ends closed; the middle stretch's north wall found in two pieces 0.06 m
# apart across, as a map's wall often is.
CROSSINGS = [(-6, 0, 0, 0), (1.8, 0, 12, 0), (13.8, 0, 18, 0), (-6, 1.8, 0, 1.8), (1.8, 1.8, 7, 1.8),
             (7, 1.86, 12, 1.86), (13.8, 1.8, 18, 1.8), (0, -6, 0, 0), (0, 1.8, 0, 7.8), (1.8, -6, 1.8, 0),
             (1.8, 1.8, 1.8, 7.8), (12, -6, 12, 0), (12, 1.8, 12, 7.8), (13.8, -6, 13.8, 0), (13.8, 1.8, 13.8, 7.8),
             (-6, 0, -6, 1.8), (18, 0, 18, 1.8), (0, -6, 1.8, -6), (0, 7.8, 1.8, 7.8), (12, -6, 13.8, -6),
             (12, 7.8, 13.8, 7.8)]  # fmt: skip


def test_a_corridor_s_even_stretch_between_two_crossings_is_no_door():
    # the crossings are wider than the corridors (their largest disc 1.2 m across the
    # diagonal), so the watershed parts the stretch between them where their basins
    # meet, at x 6.9, over 1.6 m, under three quarters of a crossing's width: before,
    # a door there cut the network in two corridors (41.6 and 38.8 m2). The contact
    # runs across the corridor's strip (across_corridor), and the two corridors meet
    # through a narrowing in no wall's line (corridor_narrowings): either keeps it one.
    poses = [(0.9, 0.9), (12.9, 0.9), (7, 0.9), (-4, 0.9), (16, 0.9), (0.9, -4), (0.9, 6), (12.9, -4), (12.9, 6)]
    rooms, doors = _rooms(CROSSINGS, poses)
    assert len(rooms) == 1 and len(doors) == 0
    assert rooms["area_m2"].iloc[0] == pytest.approx(80.8, abs=1.0)


def test_a_gap_narrower_than_a_door_joins_nothing():
    # a 0.4 m slit in the partition is not passable: two rooms, no door between them
    rooms, doors = _rooms(BOX + [(4, 0, 4, 1.8), (4, 2.2, 4, 4)], [(2, 2), (6, 2)])
    assert len(rooms) == 2 and len(doors) == 0
    assert list(rooms["name"]) == ["Space 1", "Space 2"]  # no door divides them: two spaces apart


# A corridor 1.4 m wide (y 0..1.4) under two rooms (y 1.4..4.4) split by a partition at
# x = 4 that meets the corridor wall in a T; a door from the corridor into each room.
CORRIDOR = [
    (0, 0, 8, 0), (8, 0, 8, 4.4), (8, 4.4, 0, 4.4), (0, 4.4, 0, 0),
    (0, 1.4, 1.5, 1.4), (2.4, 1.4, 5.5, 1.4), (6.4, 1.4, 8, 1.4), (4, 1.4, 4, 4.4),
]  # fmt: skip


def test_a_corridor_is_not_cut_where_a_partition_meets_it():
    rooms, doors = _rooms(CORRIDOR, [(1, 0.7), (4, 0.7), (7, 0.7), (2, 3), (6, 3), (1.95, 1.2), (5.95, 1.2)])
    kinds = sorted(rooms["kind"])
    assert kinds == ["corridor", "room", "room"]
    corridor = rooms[rooms["kind"] == "corridor"].iloc[0]
    assert corridor["name"] == "Corridor 1" and 9.5 < corridor["area_m2"] < 11.2
    centres = sorted(((d.x0 + d.x1) / 2, (d.y0 + d.y1) / 2) for d in doors.itertuples())
    assert len(centres) == 2
    assert np.allclose(centres, [(1.95, 1.4), (5.95, 1.4)], atol=0.1)


# A ring of corridor 2 m wide (1.88 m clear) around a 8 m x 4 m core, with a pair of
# wall stubs facing each other across its bottom and top legs at x 6: a door frame.
RING = [(0, 0, 12, 0), (12, 0, 12, 8), (12, 8, 0, 8), (0, 8, 0, 0),
        (2, 2, 10, 2), (10, 2, 10, 6), (10, 6, 2, 6), (2, 6, 2, 2)]  # fmt: skip
RING_POSES = [(1, 1), (6, 1), (11, 1), (11, 4), (11, 7), (6, 7), (1, 7), (1, 4)]


@pytest.mark.parametrize("stub, n_rooms, n_doors", [(0.15, 1, 0), (0.55, 2, 2)])
def test_a_corridor_goes_on_through_a_passage_across_it_unless_a_door_narrows_it(stub, n_rooms, n_doors):
    """corridors.across_corridor: stubs 0.15 m long leave a 1.7 m passage across the
    corridor, 0.9 of its clear width, beside the ring's wider corners: the ring is one;
    stubs 0.55 m long leave a 0.9 m door, under three quarters of the width: two
    corridors and their two doors."""
    walls = RING + [(6, 0, 6, stub), (6, 2, 6, 2 - stub), (6, 8, 6, 8 - stub), (6, 6, 6, 6 + stub)]
    rooms, doors = _rooms(walls, RING_POSES)
    assert len(rooms) == n_rooms and len(doors) == n_doors
    # the floor between the walls' faces, 11.88 m x 7.88 m less 8.12 m x 4.12 m, less the doors
    assert rooms["area_m2"].sum() == pytest.approx(11.88 * 7.88 - 8.12 * 4.12, abs=0.9)
    if n_doors:
        widths = sorted(np.hypot(doors.x1 - doors.x0, doors.y1 - doors.y0))
        assert widths == pytest.approx([0.9, 0.9], abs=0.06)


def _polar(r: float, deg: float) -> tuple[float, float]:
    return r * math.cos(math.radians(deg)), r * math.sin(math.radians(deg))


def _curved_corridor(narrowing: str, tip_r: float) -> tuple[list, list]:
    """A corridor 2 m wide bent through 120 degrees (between radii 10 and 12 m, walls
    every 10 degrees or less: no two straight, parallel lines bound it), with a bay
    0.9 m deep and 2.5 m wide in its outer wall at -30 and +30 degrees (the wider place
    each half's basin holds, as a junction or an alcove beside a real corridor's
    narrowing), and at 0 degrees a narrowing from the outer wall in to radius ``tip_r``:
    a vee of two walls, or a pier; its walls and the poses of its scans."""
    inner = [_polar(10, a) for a in range(-60, 61, 10)]
    walls = [(*inner[k], *inner[k + 1]) for k in range(len(inner) - 1)]
    outer = [-60, -50, -40, -36, -24, -20, -10, -3, 3, 10, 20, 24, 36, 40, 50, 60]
    for a0, a1 in zip(outer[:-1], outer[1:]):
        if (a0, a1) in ((-36, -24), (24, 36)):
            walls += [(*_polar(12, a0), *_polar(12.9, a0)), (*_polar(12.9, a0), *_polar(12.9, a1)),
                      (*_polar(12.9, a1), *_polar(12, a1))]  # fmt: skip
        elif (a0, a1) == (-3, 3) and narrowing == "vee":
            walls += [(*_polar(12, a0), *_polar(tip_r, 0)), (*_polar(tip_r, 0), *_polar(12, a1))]
        else:
            walls.append((*_polar(12, a0), *_polar(12, a1)))
    if narrowing == "pier":
        walls.append((*_polar(12, 0), *_polar(tip_r, 0)))
    walls += [(*_polar(10, -60), *_polar(12, -60)), (*_polar(10, 60), *_polar(12, 60))]
    poses = [_polar(11, a) for a in (-55, -45, -30, -15, -5, 5, 15, 30, 45, 55)] + [_polar(12.4, -30), _polar(12.4, 30)]
    return walls, poses


def _mover(turn_deg: float, shift: tuple[float, float] = (0.0, 0.0)):
    """A point ``(x, y)`` (metres) turned by ``turn_deg`` about the origin, then shifted
    (:func:`floorscan.core.geometry.transform_points`)."""
    from floorscan.core.geometry import transform_points

    def move(x: float, y: float) -> tuple[float, float]:
        px, py, _ = transform_points([[x, y, 0.0]], shift[0], shift[1], 0.0, math.radians(turn_deg))[0]
        return float(px), float(py)

    return move


@pytest.mark.parametrize("turn_deg, shift", [(0.0, (0.0, 0.0)), (128.0, (0.03, 0.03)), (201.0, (0.011, 0.044))])
@pytest.mark.parametrize("narrowing, tip_r, n_rooms", [("vee", 11.73, 1), ("vee", 11.23, 2), ("pier", 11.73, 2)])
def test_a_bent_corridor_narrowed_out_of_any_wall_s_line_by_under_a_quarter_is_one_corridor(
        narrowing, tip_r, n_rooms, turn_deg, shift):  # fmt: skip
    """narrowings.corridor_narrowings: a vee of two walls leaves a 1.6 m passage across
    the bent corridor (clear 1.88 m), under three quarters of each half's basin (its
    bay), so without the rule the corridor is two and a door at the vee, at every pose;
    over three quarters of the corridor's own width, it is one room. A 1.1 m passage
    keeps its door, and so does a pier in whose line the passage lies (a door's frame),
    however the building is turned and shifted."""
    walls, poses = _curved_corridor(narrowing, tip_r)
    move = _mover(turn_deg, shift)
    rooms, doors = _rooms([(*move(x0, y0), *move(x1, y1)) for x0, y0, x1, y1 in walls], [move(*p) for p in poses])
    assert len(rooms) == n_rooms and len(doors) == n_rooms - 1
    assert set(rooms["kind"]) == ({"space"} if n_rooms == 1 else {"corridor"})
    # the floor between the walls' faces (46.9-47.4 m2), less a door's opening and the tracing
    lines = shapely.MultiLineString([[(x0, y0), (x1, y1)] for x0, y0, x1, y1 in walls])
    inside = shapely.union_all(list(shapely.polygonize(list(shapely.node(lines).geoms)).geoms))
    floor = inside.difference(lines.buffer(T / 2, cap_style="flat")).area
    assert floor - 0.8 <= rooms["area_m2"].sum() <= floor


def test_a_region_s_width_is_its_median_local_thickness_on_the_raster():
    """narrowings.raster_width, to half a cell: a strip is as wide as it is across, an L
    of two such strips too, a square as its side (the opening by a disc as wide keeps
    pi / 4 of it)."""
    from floorscan.floorplan.narrowings import raster_width

    strip = np.zeros((240, 240), dtype=bool)
    strip[10:30, 10:230] = True
    ell = strip.copy()
    ell[10:230, 10:30] = True
    square = np.zeros((80, 80), dtype=bool)
    square[10:70, 10:70] = True
    assert raster_width(strip, 0.1) == pytest.approx(2.0, abs=0.06)
    assert raster_width(ell, 0.1) == pytest.approx(2.0, abs=0.06)
    assert raster_width(square, 0.1) == pytest.approx(6.0, abs=0.06)
    assert raster_width(np.zeros((5, 5), dtype=bool), 0.1) == 0.0


def test_a_corridor_joins_no_room_that_is_not_a_corridor_across_a_narrowing():
    """narrowings.corridor_narrowings on hand-made regions (0.1 m cells): a corridor 2 m x
    12 m, a narrower one 1.6 m x 12 m beyond it, and a 6 m x 6 m room beside it; the
    1.3 m narrowing joins the two corridors (over 0.75 of 1.6 m), a 1.1 m one does not,
    and no narrowing joins the room, however wide."""
    from floorscan.floorplan.narrowings import corridor_narrowings

    labels = np.zeros((100, 260), dtype=np.int32)
    labels[0:20, 0:120] = 1
    labels[0:16, 120:240] = 2
    labels[20:80, 0:60] = 3
    root = np.arange(4)
    params = RoomParams()
    joined = corridor_narrowings(labels, root, {(1, 2): 1.3, (1, 3): 1.9}, params)
    assert joined[1] == joined[2] and joined[3] not in (joined[1], joined[0])
    assert corridor_narrowings(labels, root, {(1, 2): 1.1}, params).tolist() == [0, 1, 2, 3]


def test_a_room_seen_only_through_its_door_is_completed_to_its_walls():
    # the scans stay in the corridor: the east room is seen as a fan through its door
    rooms, _ = _rooms(CORRIDOR, [(1, 0.7), (4, 0.7), (7, 0.7), (2, 3), (5.95, 1.0)])
    east = rooms["polygon"][int(np.argmax([p.centroid.x + p.centroid.y for p in rooms["polygon"]]))]
    true_room = shapely.box(4.06, 1.46, 7.94, 4.34)
    assert east.intersection(true_room).area / east.union(true_room).area > 0.9


def _completed(fan, walls):
    """room_polygons._bounded_by_walls of the seen floor ``fan`` among ``walls`` (axes,
    thickness T), no other room."""
    from floorscan.floorplan.room_polygons import _bounded_by_walls
    from floorscan.floorplan.room_space import wall_footprints

    axes = np.array(walls, dtype=np.float64)
    foot = wall_footprints(axes, np.full(len(axes), T))
    return _bounded_by_walls(fan, axes, np.full(len(axes), T), foot, shapely.union_all(foot), shapely.Polygon(), 0.1)


def test_a_room_against_one_wall_line_is_not_completed_to_its_box():
    # the floor seen through a 0.8 m gap in a wall (y 0, in two pieces): a fan of 6.3 m2
    fan = shapely.Polygon([(1.6, 0.06), (2.4, 0.06), (4.0, 3.0), (0.5, 3.0)])
    # one wall's line: the fan as seen, not its 10.3 m2 box
    assert _completed(fan, [(-2, 0, 1.6, 0), (2.4, 0, 6, 0)]).area == pytest.approx(fan.area, abs=0.05)
    # a wall across it at x 4.2 makes a corner: the room is completed up to both walls
    assert _completed(fan, [(-2, 0, 1.6, 0), (2.4, 0, 6, 0), (4.2, 0, 4.2, 4)]).area == pytest.approx(
        3.5 * 2.94, abs=0.05)


@pytest.mark.parametrize("turn_deg", [0.0, 30.0, 117.0, 301.5])
def test_a_room_seen_in_part_is_completed_to_the_same_room_however_the_building_is_turned(turn_deg):
    """room_polygons._bounded_by_walls: the box of the seen floor is taken in the frame of
    the room's longest wall, so the room completed up to its walls is the same whatever
    the building's turn (a box in the map's axes reached past the walls of a turned
    building: the rigid-motion property's room through its entrance)."""
    move = _mover(turn_deg)
    fan = shapely.Polygon([move(*p) for p in [(1.6, 0.06), (2.4, 0.06), (4.0, 3.0), (0.5, 3.0)]])
    walls = [(-2, 0, 1.6, 0), (2.4, 0, 6, 0), (4.2, 0, 4.2, 4)]
    room = _completed(fan, [(*move(x0, y0), *move(x1, y1)) for x0, y0, x1, y1 in walls])
    # the fan's box up to the wall at y 0 (its face at 0.06): x 0.5-4.0, y 0.06-3.0
    box = shapely.Polygon([move(*p) for p in [(0.5, 0.06), (4.0, 0.06), (4.0, 3.0), (0.5, 3.0)]])
    assert room.area == pytest.approx(box.area, abs=0.05)
    assert room.symmetric_difference(box).area < 0.05


def test_wall_gaps_between_collinear_ends():
    params = RoomParams()
    axes = np.array(TWO_ROOMS, dtype=np.float64)
    gaps = wall_gaps(axes, np.full(len(axes), T), params)
    assert len(gaps) == 1
    p, q, wall = gaps[0]
    assert np.allclose(sorted([p[1], q[1]]), [1.5, 2.4]) and np.allclose([p[0], q[0]], 4.0) and wall in (4, 5)
    # ends in a T junction are corners, not jambs: the corridor has no gap at x = 4
    axes = np.array(CORRIDOR, dtype=np.float64)
    widths = sorted(float(np.hypot(*(q - p))) for p, q, _ in wall_gaps(axes, np.full(len(axes), T), params))
    assert np.allclose(widths, [0.9, 0.9])


def test_one_opening_found_on_two_lines_is_cut_once_on_the_narrower():
    """A door found between two walls' ends and again on a corridor side's line, a cell
    or two apart: two cuts would leave a sliver of space between them and find no rooms
    on either side (the rigid-motion property's hallways, furnished, lost a door so)."""
    between_ends = (np.array([-0.77, 9.89]), np.array([-0.23, 9.16]), 10)  # 0.91 m
    on_side_line = (np.array([-0.36, 9.06]), np.array([-0.87, 9.75]), 22)  # 0.86 m, 0.15 m off
    kept = distinct_gaps([between_ends, on_side_line], 0.35)
    assert len(kept) == 1 and kept[0][2] == 22
    assert distinct_gaps([on_side_line, between_ends], 0.35)[0][2] == 22
    # two doors of one wall, side by side, and the same door seen farther off than a jamb's reach
    beside = (np.array([0.6, 0.0]), np.array([1.5, 0.0]), 1)
    door = (np.array([-0.5, 0.0]), np.array([0.4, 0.0]), 2)
    assert len(distinct_gaps([door, beside], 0.35)) == 2
    assert len(distinct_gaps([door, (door[0] + [0, 0.4], door[1] + [0, 0.4], 3)], 0.35)) == 2


def test_the_outside_seen_through_an_opening_is_not_a_room():
    # a room 8 x 4 m with a 1.2 m opening in its south wall; the scans see out through
    # it onto a wall 6 m away: that fan of rays is not walled, not a room, no door
    walls = [(0, 0, 3.4, 0), (4.6, 0, 8, 0), (8, 0, 8, 4), (8, 4, 0, 4), (0, 4, 0, 0)]
    grid = _grid(walls + [(-6, -6, 14, -6)], [(2, 2), (6, 2), (4, 1.0)])
    axes = np.array(walls, dtype=np.float64)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid)
    assert list(rooms["kind"]) == ["space"] and len(doors) == 0
    # the room ends in its opening, within two 0.1 m cells of the wall's outer face (y -0.06)
    assert 29.5 < rooms["area_m2"].iloc[0] < 31.5 and rooms["polygon"].iloc[0].bounds[1] > -0.25


def test_a_fan_seen_through_an_opening_wider_than_a_door_is_no_room_and_a_walled_room_is():
    # an L: a corridor (y 0..2) onto a hall (x 20..26, y 0..10), both scanned; a 2.5 m
    # opening in the corridor's north wall (x 8.75..11.25), wider than a door, shows a
    # fan of rays onto a facade at y 7 that is no wall of the plan's: walled at its far
    # end only (a quarter of its edge), inside the hull of the building's walls
    walls = [(0, 0, 26, 0), (26, 0, 26, 10), (26, 10, 20, 10), (20, 10, 20, 2), (0, 2, 0, 0), (0, 2, 8.75, 2),
             (11.25, 2, 20, 2)]  # fmt: skip
    poses = [(x, 1.0) for x in np.arange(1.0, 19.5, 1.5)] + [(23, 3), (23, 7)]
    axes = np.array(walls, dtype=np.float64)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), _grid(walls + [(4, 7, 18, 7)], poses))
    assert sorted(rooms["kind"]) == ["corridor", "room"] and len(doors) == 1
    assert rooms["area_m2"].sum() == pytest.approx(95.6, abs=1.0)  # the hall and the corridor, no fan
    # the same opening into a room whose walls the plan has (x 6..14, y 2..7): a room
    walled = walls + [(6, 2, 6, 7), (6, 7, 14, 7), (14, 7, 14, 2)]
    axes = np.array(walled, dtype=np.float64)
    rooms, _ = plan_rooms(axes, np.full(len(axes), T), _grid(walled, poses))
    assert sorted(rooms["kind"]) == ["corridor", "room", "room"]
    assert sorted(rooms["area_m2"])[0] == pytest.approx(38.5, abs=1.5)


def test_a_fan_seen_through_gaps_no_jambs_frame_is_not_the_hall_s_floor():
    # a hall 20 x 8 m scanned inside; its west wall stops 1.7 m short of both corners
    # (no jambs: the gaps end at the other walls' faces), its north wall runs on 6 m to
    # the west, and a facade 7 m out stops the rays: the fan between them, walled on
    # just under half its edge, is not the hall's floor (before: 170.3 m2); the gaps
    # are cut as doors beside the corners (extensions.partition_cuts), onto the fan, so
    # no door, and the hall ends on the west wall's line: its floor between the faces,
    # 19.9 x 7.9 m
    walls = [(-6, 8, 20, 8), (20, 8, 20, 0), (20, 0, -0.5, 0), (0, 1.7, 0, 6.3)]
    poses = [(x, 4.0) for x in (1, 3, 5, 8, 11, 14, 17)] + [(1.2, 2), (1.2, 6), (3, 1.5), (3, 6.5)]
    axes = np.array(walls, dtype=np.float64)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), _grid(walls + [(-7, -3, -7, 11)], poses))
    assert len(rooms) == 1 and len(doors) == 0
    assert rooms["area_m2"].iloc[0] == pytest.approx(157.2, abs=1.0)
    beyond = shapely.intersection(rooms["polygon"].iloc[0], shapely.box(-10, -5, -T / 2, 12)).area
    assert beyond < 0.5  # west of the wall's face: a cell's strip (before, the gaps' bulges, 2.7 m2)


def test_a_dead_end_seen_through_an_opening_wider_than_a_door_is_not_the_hall_s_and_a_passage_is():
    # the hall of the test above, its west wall open over 3 m in the middle: the fan
    # beyond is one region with the hall through an opening wider than a door
    # (before: 24.7 m2 of it in the hall)
    walls = [(-6, 8, 20, 8), (20, 8, 20, 0), (20, 0, -0.5, 0), (0, 0, 0, 2.5), (0, 5.5, 0, 8)]
    poses = [(x, 4.0) for x in (1, 3, 5, 8, 11, 14, 17)] + [(1.2, 2), (1.2, 6), (3, 1.5), (3, 6.5)]
    axes = np.array(walls, dtype=np.float64)
    rooms, _ = plan_rooms(axes, np.full(len(axes), T), _grid(walls + [(-7, -3, -7, 11)], poses))
    assert len(rooms) == 1 and rooms["area_m2"].iloc[0] == pytest.approx(157.1, abs=1.5)
    # two halls scanned inside, each open over 4.5 m towards the other (wider than a
    # room's open side, MOUTH_MAX_M): the unentered space between them, walled on less
    # than half its edge, is the passage that joins them, no dead end
    def halls(lo, hi):
        walls = [(0, 0, 10, 0), (0, 8, 10, 8), (0, 0, 0, 8), (10, 0, 10, lo), (10, hi, 10, 8),
                 (16, 0, 26, 0), (16, 8, 26, 8), (26, 0, 26, 8), (16, 0, 16, lo), (16, hi, 16, 8)]  # fmt: skip
        poses = [(x, y) for x in (2, 5, 8, 18, 21, 24) for y in (2, 6)]
        axes = np.array(walls, dtype=np.float64)
        return plan_rooms(axes, np.full(len(axes), T), _grid(walls + [(5, -5, 21, -5), (5, 13, 21, 13)], poses))[0]

    rooms = halls(1.75, 6.25)
    assert len(rooms) == 1
    assert shapely.intersection(rooms["polygon"].iloc[0], shapely.box(10.1, -1, 15.9, 9)).area > 30.0
    # open over 3 m, each hall's opening is its open side: two halls apart, and the
    # unentered space between them, reached through open sides alone, no room (before:
    # one space of 192.5 m2 with it)
    rooms = halls(2.5, 5.5)
    assert sorted(rooms["area_m2"]) == pytest.approx([78.3, 78.3], abs=1.0)


def test_a_room_seen_from_a_hall_through_its_open_side_is_a_room_of_its_own():
    # a hall 20 x 8 m scanned inside; its north wall open over 3.5 m onto a room 5 x 4 m
    # that no scan was taken in, whose east wall the plan holds only a 0.8 m stub of (so
    # no mouth is drawn): walled on most of its edge, it is a room, not the hall's
    # floor (before: one space of 176.0 m2)
    hall = [(0, 0, 20, 0), (20, 0, 20, 8), (0, 8, 0, 0), (0, 8, 8, 8), (11.5, 8, 20, 8)]
    walls = hall + [(7, 8, 7, 12), (7, 12, 12, 12), (12, 8, 12, 8.8)]
    poses = [(x, y) for x in (2, 6, 10, 14, 18) for y in (2.5, 5.5)]
    axes = np.array(walls, dtype=np.float64)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), _grid(walls, poses))
    assert sorted(rooms["kind"]) == ["room", "room"] and len(doors) == 0  # an open side, no door
    small, large = sorted(rooms["polygon"], key=lambda p: p.area)
    assert small.area == pytest.approx(4.9 * 3.9, abs=0.8) and large.area == pytest.approx(19.9 * 7.9, abs=1.0)
    assert shapely.box(7.1, 8.1, 11.9, 11.9).difference(small).area < 0.5
    # the same room entered by the rover: its open side is a gap 3.5 m wide between the
    # free ends of two walls in one line, closing a pocket on the room's side (a mouth,
    # room_mouths); before, the persistence joined the two through it (one room)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), _grid(walls, poses + [(9.5, 10.5)]))
    assert sorted(rooms["kind"]) == ["room", "room"] and len(doors) == 0
    small, large = sorted(rooms["polygon"], key=lambda p: p.area)  # the room and what it saw past its open east side
    assert shapely.box(7.1, 8.1, 11.9, 11.9).difference(small).area < 0.5
    assert large.area == pytest.approx(19.9 * 7.9, abs=1.0)


# A corridor (y 0..2) along four offices (y 2..6, 5 m wide), each open to it through
# a 2.2 m opening, wider than a door and narrower than the office.
OFFICES_ON_A_CORRIDOR = [
    (0, 0, 20, 0), (20, 0, 20, 6), (20, 6, 0, 6), (0, 6, 0, 0), (5, 2, 5, 6), (10, 2, 10, 6), (15, 2, 15, 6),
    (0, 2, 1.4, 2), (3.6, 2, 6.4, 2), (8.6, 2, 11.4, 2), (13.6, 2, 16.4, 2), (18.6, 2, 20, 2),
]  # fmt: skip


def test_offices_open_to_a_corridor_wider_than_a_door_are_rooms():
    """The sides of a corridor (:mod:`floorscan.floorplan.corridors`): the two parallel
    lines of wall at y 0 and 2 make the strip between them a corridor, and its openings
    bound the offices. Without them each office took a part of the corridor: four
    rooms of 28 m2 with three doors across the corridor."""
    from floorscan.floorplan.corridors import corridor_sides
    from floorscan.floorplan.room_space import room_space

    axes = np.array(OFFICES_ON_A_CORRIDOR, dtype=np.float64)
    scans = [(x, 1.0) for x in (2, 6, 10, 14, 18)] + [(x, 4.5) for x in (2.5, 7.5, 12.5, 17.5)]
    grid = _grid(OFFICES_ON_A_CORRIDOR, scans)
    thick = np.full(len(axes), T)
    cuts = corridor_sides(axes, thick, room_space(grid, axes, thick, RoomParams()), RoomParams())
    got = sorted((min(p[0], q[0]), max(p[0], q[0])) for p, q, _ in cuts)
    assert np.allclose(got, [(1.4, 3.6), (6.4, 8.6), (11.4, 13.6), (16.4, 18.6)], atol=0.15)  # 0.1 m cells
    assert all(abs(p[1] - 2) < 0.02 and abs(q[1] - 2) < 0.02 for p, q, _ in cuts)
    rooms, doors = plan_rooms(axes, thick, grid, RoomParams())
    assert sorted(rooms["kind"]) == ["corridor", "room", "room", "room", "room"] and len(doors) == 0
    assert all(18.0 < a < 19.5 for a in rooms[rooms["kind"] == "room"]["area_m2"])  # 5 x 4 m less half walls
    corridor = rooms[rooms["kind"] == "corridor"]["polygon"].iloc[0]
    assert shapely.box(0.1, 0.1, 19.9, 1.9).difference(corridor).area < 0.3


@pytest.mark.parametrize("tilt_deg", [0.0, 0.45])
def test_a_long_corridor_is_found_when_its_side_s_longest_wall_is_fitted_off_its_line(tilt_deg):
    """A corridor 40 m long (y 0..2) under eight offices open to it through 2.2 m
    openings, its first side's longest wall (0.4 m thick, 6 m) fitted 0.45 degrees off:
    carried 40 m, that direction puts the far side's walls 0.30 m apart across it, more
    than the 0.24 m a side's walls may spread (``2 line_offset_m``). Measured across the
    mean direction of both sides' walls (:func:`~floorscan.floorplan.corridor_lines.corridor_frame`)
    the corridor is found, and the offices are rooms; before, each office took its piece
    of the corridor (eight rooms of 26-30 m2, no corridor), as on g4s_y2 at the map
    extractor's seed 5."""
    from floorscan.floorplan.corridors import corridor_strips

    pieces = [(0, 2, 1.4, 2)] + [(5 * k + 3.6, 2, 5 * k + 6.4, 2) for k in range(7)] + [(38.6, 2, 40, 2)]
    partitions = [(5 * k, 2, 5 * k, 6) for k in range(1, 8)]
    outer = [(0, 0, 40, 0), (40, 0, 40, 6), (40, 6, 0, 6), (0, 6, 0, 0)]
    poses = [(x, 1.0) for x in range(2, 40, 4)] + [(5 * k + 2.5, 4.0) for k in range(8)]
    grid = _grid(outer + pieces + partitions, poses)
    a = math.radians(tilt_deg)
    side = [(0, 0, 6 * math.cos(a), 6 * math.sin(a))] + [(6.5 + 5 * k, 0, min(11.0 + 5 * k, 40), 0) for k in range(7)]
    axes = np.array(side + outer[1:] + pieces + partitions, dtype=np.float64)
    th = np.full(len(axes), T)
    th[0] = 0.4
    strips = corridor_strips(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams())
    assert len(strips) == 1 and strips[0]["t1"] - strips[0]["t0"] > 39 and abs(strips[0]["sep"] - 2) < 0.05
    rooms, doors = plan_rooms(axes, th, grid, RoomParams())
    assert sorted(rooms["kind"]) == ["corridor"] + ["room"] * 8 and len(doors) == 0
    assert all(18.5 < x < 19.5 for x in rooms[rooms["kind"] == "room"]["area_m2"])  # 5 x 4 m less half walls


def test_a_corridor_that_another_goes_on_from_stays_one_room():
    """A T junction: the opening in the long corridor's side leads into a corridor 12 m
    long and 2 m wide (more than four times its width), so it is not cut."""
    from floorscan.floorplan.corridors import corridor_sides
    from floorscan.floorplan.room_space import room_space

    walls = [(0, 0, 20, 0), (20, 0, 20, 2), (20, 2, 11, 2), (11, 2, 11, 14), (11, 14, 9, 14), (9, 14, 9, 2),
             (9, 2, 0, 2), (0, 2, 0, 0)]  # fmt: skip
    axes = np.array(walls, dtype=np.float64)
    thick = np.full(len(axes), T)
    grid = _grid(walls, [(x, 1.0) for x in (2, 6, 10, 14, 18)] + [(10, y) for y in (4, 8, 12)])
    assert corridor_sides(axes, thick, room_space(grid, axes, thick, RoomParams()), RoomParams()) == []
    rooms, doors = plan_rooms(axes, thick, grid, RoomParams())
    assert len(rooms) == 1 and len(doors) == 0 and 58 < rooms["area_m2"].iloc[0] < 62


# A corridor (y 0..1.5) along three offices (y 1.5..4.5) open to it on their whole
# width: partitions at x = 3 and 6 end at the corridor, short returns at the ends.
OPEN_OFFICES = [
    (0, 0, 9, 0), (9, 0, 9, 4.5), (9, 4.5, 0, 4.5), (0, 4.5, 0, 0),
    (3, 4.5, 3, 1.5), (6, 4.5, 6, 1.5), (0, 1.5, 0.8, 1.5), (9, 1.5, 8.2, 1.5),
]  # fmt: skip


def _office_row(walls: list, thickness: float):
    """A row of three offices 3 m wide above a corridor (``walls``, ``thickness``
    metres), scanned from the corridor and each office: the x spans of its room mouths
    (sorted), and the plan's rooms and doors."""
    from floorscan.floorplan.mouths import room_mouths
    from floorscan.floorplan.room_space import room_space

    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), thickness)
    grid = _grid(walls, [(1.5, 0.75), (4.5, 0.75), (7.5, 0.75), (1.5, 3), (4.5, 3), (7.5, 3)], thickness=thickness)
    mouths = room_mouths(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams())
    spans = sorted((round(float(min(p[0], q[0])), 2), round(float(max(p[0], q[0])), 2)) for p, q, _ in mouths)
    return spans, *plan_rooms(axes, th, grid, RoomParams())


def test_offices_open_to_a_corridor_on_their_whole_width_are_rooms():
    """The mouths of :mod:`floorscan.floorplan.mouths`: without them the offices and the
    corridor are one space (no narrowing between them)."""
    from floorscan.floorplan.mouths import room_mouths
    from floorscan.floorplan.room_space import room_space

    axes = np.array(OPEN_OFFICES, dtype=np.float64)
    grid = _grid(OPEN_OFFICES, [(1.5, 0.75), (4.5, 0.75), (7.5, 0.75), (1.5, 3), (4.5, 3), (7.5, 3)])
    mouths = room_mouths(axes, np.full(len(axes), T), room_space(grid, axes, np.full(len(axes), T), RoomParams()),
                         RoomParams())  # fmt: skip
    got = sorted((round(float(min(p[0], q[0])), 2), round(float(max(p[0], q[0])), 2)) for p, q, _ in mouths)
    assert got == [(0.8, 3.0), (3.0, 6.0), (6.0, 8.2)]
    assert all(abs(p[1] - 1.5) < 1e-9 and abs(q[1] - 1.5) < 1e-9 for p, q, _ in mouths)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid, RoomParams())
    assert sorted(rooms["kind"]) == ["corridor", "room", "room", "room"] and len(doors) == 0
    offices = rooms[rooms["kind"] == "room"]
    assert all(8.0 < a < 9.0 for a in offices["area_m2"])  # 3 x 3 m less half walls
    corridor = rooms[rooms["kind"] == "corridor"]["polygon"].iloc[0]
    assert shapely.box(0.1, 0.1, 8.9, 1.4).difference(corridor).area < 0.3


def test_offices_between_thick_walls_open_to_a_corridor_are_rooms():
    """The offices of the test above between walls 0.3 m thick: a mouth's line is
    tested between the walls' faces, so the thick walls it joins neither cross it nor
    take its samples of the free space. Tested 0.15 m from each end, the line crossed
    the footprint of the wall at its end, and the offices joined the corridor."""
    spans, rooms, doors = _office_row(OPEN_OFFICES, 0.3)
    assert spans == [(0.8, 3.0), (3.0, 6.0), (6.0, 8.2)]
    assert sorted(rooms["kind"]) == ["corridor", "room", "room", "room"] and len(doors) == 0
    assert all(7.0 < a < 8.5 for a in rooms[rooms["kind"] == "room"]["area_m2"])  # 3 x 3 m less half walls


def test_cubicles_as_deep_as_their_clear_opening_are_rooms():
    """Cubicles 2.9 m deep (to the back wall's axis) whose partitions, 0.2 m thick,
    stand 3 m apart (axis to axis), open onto a corridor: the side walls are shorter
    than the line between their ends but as long as the clear opening between the end
    walls' faces (2.8 m), so they bound rooms (Bormann et al.'s lab_a). The tree before
    took the partitions for stubs: no mouth, one space."""
    walls = [(0, 0, 9, 0), (9, 0, 9, 4.5), (9, 4.5, 0, 4.5), (0, 4.5, 0, 0),
             (3, 4.5, 3, 1.6), (6, 4.5, 6, 1.6), (0, 1.6, 0.8, 1.6), (9, 1.6, 8.2, 1.6)]  # fmt: skip
    spans, rooms, doors = _office_row(walls, 0.2)
    assert spans == [(0.8, 3.0), (3.0, 6.0), (6.0, 8.2)]
    assert sorted(rooms["kind"]) == ["corridor", "room", "room", "room"] and len(doors) == 0
    assert all(7.5 < a < 8.5 for a in rooms[rooms["kind"] == "room"]["area_m2"])  # 3 x 2.9 m less half walls


def test_an_office_open_between_its_side_wall_s_corner_and_its_front_wall_s_free_end_is_a_room():
    """A mouth from a corner: the office (x 4..10, y 0..4) opens onto the corridor above
    it from the corner of its west wall (which meets the corridor's slanted end wall) to
    the free end of its front wall at x 6.5, 2.5 m; a partition with a door parts off
    its east end, so its front wall is not a partition standing in one room. Without the
    mouth the office and the corridor are one room (no narrowing between them)."""
    from floorscan.floorplan.mouths import room_mouths
    from floorscan.floorplan.room_space import room_space

    walls = [(4, 0, 10, 0), (10, 0, 10, 7), (10, 7, 1, 7), (1, 7, 4, 4), (4, 4, 4, 0), (6.5, 4, 10, 4),
             (7.5, 0, 7.5, 1.5), (7.5, 2.4, 7.5, 4)]  # fmt: skip
    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
    grid = _grid(walls, [(5.5, 2), (8.7, 2), (5, 5.5), (8, 5.5), (3, 6)])
    mouths = room_mouths(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams())
    assert [sorted((round(float(p[0]), 2), round(float(q[0]), 2))) for p, q, _ in mouths] == [[4.0, 6.5]]
    assert all(abs(p[1] - 4) < 1e-9 and abs(q[1] - 4) < 1e-9 for p, q, _ in mouths)
    rooms, doors = plan_rooms(axes, th, grid, RoomParams())
    assert len(rooms) == 3 and len(doors) == 1  # corridor, office, east office; the partition's door
    office = [p for p in rooms["polygon"] if p.contains(shapely.Point(5.5, 2))][0]
    assert not office.contains(shapely.Point(5, 5.5)) and 12.5 < office.area < 14.0  # 3.5 x 4 m less half walls


def test_no_mouth_from_a_corner_crosses_a_corridor_that_goes_on_around_a_block():
    """A ring corridor around a block (x 2.5..5, y 2.5..5.5); a stub from the north wall
    ends at (2.5, 7) above the block's corner (2.5, 5.5). The line between them closes a
    pocket by the rays' test, but the corridor goes on around the block: cut, its two
    sides are still connected, so it is no room's open side."""
    from floorscan.floorplan.mouths import room_mouths
    from floorscan.floorplan.room_space import room_space

    walls = [(0, 0, 7.5, 0), (7.5, 0, 7.5, 8), (7.5, 8, 0, 8), (0, 8, 0, 0), (2.5, 2.5, 5, 2.5), (5, 2.5, 5, 5.5),
             (5, 5.5, 2.5, 5.5), (2.5, 5.5, 2.5, 2.5), (2.5, 8, 2.5, 7.0)]  # fmt: skip
    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
    grid = _grid(walls, [(1.2, 1.2), (6.2, 1.2), (6.2, 6.8), (1.2, 6.8), (3.75, 1.2), (3.75, 6.8), (1.2, 4), (6.2, 4)])
    assert room_mouths(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams()) == []
    rooms, doors = plan_rooms(axes, th, grid, RoomParams())
    assert len(rooms) == 1 and len(doors) == 0


def test_a_niche_shallower_than_half_its_width_is_the_corridor_s():
    """A niche 3.1 m wide and 1.3 m deep (x 4..7.1, y 2..3.3) beside a corridor (y 0..2),
    between the corner of a partition and the free end of the corridor's wall: its line
    closes a pocket by the rays' test, but a recess shallower than half its width is
    part of the space it opens onto (the tree before MOUTH_MIN_DEPTH made it a room with
    the room behind it)."""
    from floorscan.floorplan.mouths import room_mouths
    from floorscan.floorplan.room_space import room_space

    walls = [(0, 0, 12, 0), (12, 0, 12, 6), (12, 6, 0, 6), (0, 6, 0, 0), (0, 2, 1.5, 2), (2.4, 2, 4, 2), (4, 2, 4, 6),
             (4, 3.3, 6.0, 3.3), (6.9, 3.3, 12, 3.3), (7, 3.3, 7, 2.3), (7.1, 2, 12, 2)]  # fmt: skip
    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
    grid = _grid(walls, [(2, 1), (6, 1), (10, 1), (5.5, 2.6), (2, 4), (8, 4.5)])
    assert room_mouths(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams()) == []
    rooms, _ = plan_rooms(axes, th, grid, RoomParams())

    def room_of(x, y):
        return [k for k, p in enumerate(rooms["polygon"]) if p.contains(shapely.Point(x, y))]

    assert room_of(5.5, 2.6) == room_of(2, 1) == room_of(10, 1) != []


def test_a_gap_in_one_wall_and_a_short_stub_make_no_mouth():
    """A gap in one wall 2.5 m wide whose one side is a stub of 0.5 m (shorter than
    MOUTH_WALL_M) is no room's open side, nor is the line between two side walls shorter
    than the opening: stubs of furniture."""
    from floorscan.floorplan.mouths import room_mouths
    from floorscan.floorplan.room_space import room_space

    for walls in (BOX + [(4, 0, 4, 1.0), (4, 3.5, 4, 4)], BOX + [(4, 4, 4, 3.0), (6.5, 4, 6.5, 3.0)]):
        axes = np.array(walls, dtype=np.float64)
        grid = _grid(walls, [(2, 2), (6, 2)])
        raster = room_space(grid, axes, np.full(len(axes), T), RoomParams())
        assert room_mouths(axes, np.full(len(axes), T), raster, RoomParams()) == []


def test_a_room_off_a_hall_through_a_gap_in_its_wall_wider_than_a_door_is_a_room_apart():
    """A hall 12 x 8 m whose north wall has a gap 4 m wide (3.88 m between the faces,
    a room's open side) between two free ends; behind it, a room 7 m wide and 4 m deep
    that the rover entered, whose side walls meet the hall's wall beyond the gap. The
    gap is a mouth (a room on one side, and on the other a hall that runs on as far):
    two rooms apart without a door, where the gap in one wall was left to wall_gaps,
    which takes doors alone, and the room and the hall were one space. A recess 1.5 m
    deep behind the same gap (less than MOUTH_MIN_DEPTH times the gap) is part of the
    hall, though the hall closes a pocket on the gap's other side."""
    hall = [(0, 0, 12, 0), (12, 0, 12, 8), (0, 8, 0, 0), (0, 8, 4, 8), (8, 8, 12, 8)]
    plans = {}
    for depth in (4.0, 1.5):
        walls = hall + [(2.5, 8, 2.5, 8 + depth), (9.5, 8, 9.5, 8 + depth), (2.5, 8 + depth, 9.5, 8 + depth)]
        axes = np.array(walls, dtype=np.float64)
        grid = _grid(walls, [(2, 2), (10, 2), (6, 4), (2, 6), (10, 6), (6, 8 + depth / 2)])
        plans[depth] = plan_rooms(axes, np.full(len(axes), T), grid, RoomParams())
    rooms, doors = plans[4.0]
    assert sorted(np.round(rooms["area_m2"]).tolist()) == [27.0, 94.0] and len(doors) == 0
    assert list(rooms["kind"]) == ["room", "room"]
    rooms, doors = plans[1.5]
    assert np.round(rooms["area_m2"]).tolist() == [104.0] and len(doors) == 0


def test_a_room_is_as_wide_as_its_median_local_thickness():
    """room_width: a square is as wide as its side, a corridor as its two walls are
    apart, and a network of 2.5 m corridors around a 7 m round hall as its corridors
    (its largest inscribed circle is the hall's 7 m)."""
    from floorscan.floorplan.room_tables import room_width

    network = shapely.union_all(
        [shapely.box(0, 0, 2.5, 60), shapely.box(-30, 30, 30, 32.5), shapely.Point(1.25, 31.25).buffer(3.5)]
    )
    assert room_width(shapely.box(0, 0, 4, 4), 0.025) == pytest.approx(4.0, abs=0.03)
    assert room_width(shapely.box(0, 0, 2, 20), 0.025) == pytest.approx(2.0, abs=0.03)
    assert room_width(network, 0.025) == pytest.approx(2.5, abs=0.05)
    assert room_width(shapely.Polygon(), 0.025) == 0.0


def test_a_network_of_corridors_is_a_corridor_and_a_hall_is_a_room():
    """room_tables: the kinds of a corridor network with a wide crossing (a corridor),
    a 6 m x 5 m office (a room) and a 2.5 m x 2.5 m closet (a room: not long)."""
    from floorscan.floorplan.room_tables import room_tables

    network = shapely.union_all(
        [shapely.box(0, 0, 2.5, 60), shapely.box(-30, 30, 30, 32.5), shapely.Point(1.25, 31.25).buffer(3.5)]
    )
    polys = [network, shapely.box(3, 0, 9, 5), shapely.box(-3, 0, -0.5, 2.5)]
    doors = [(np.array([2.5, 1.0]), np.array([2.5, 2.0]), 0, 0, 1)]
    rooms, _ = room_tables(polys, doors, 0.05, RoomParams())
    assert list(rooms["kind"]) == ["corridor", "room", "room"]
    assert list(rooms["name"]) == ["Corridor 1", "Room 1", "Room 2"]


def test_a_hallway_wider_than_a_corridor_is_a_corridor_when_longer_in_proportion():
    """is_corridor: a 4.5 m x 50 m hallway (11 widths long, 6 needed at 1.5 times the
    corridor's width) is a corridor; a 4.5 m x 25 m one (5.6 widths) and a 9 m x 50 m
    hall (5.6 widths, 12 needed) are not; a 3 m x 12.5 m corridor (4.2 widths) is, as
    a 3.2 m x 13 m room (4.1 widths, 4.3 needed) is not."""
    from floorscan.floorplan.room_tables import is_corridor

    def kind(w, h):
        return is_corridor(shapely.box(0, 0, w, h), 0.025, RoomParams())

    assert [kind(4.5, 50), kind(4.5, 25), kind(9, 50), kind(3, 12.5), kind(3.2, 13)] == [True, False, False, True, False]


def test_an_office_around_a_table_island_is_a_room_and_a_ring_around_a_core_a_corridor():
    """room_tables: a 5 m x 7 m office around a 0.8 m x 2 m block drawn as walls (a hole
    smaller than the smallest room: its floor's median local thickness without the hole
    is 5 m, with it about 2 m, which reads as a corridor 17 m long) is a room; a 2 m ring
    of corridor around a 10 m x 10 m core of offices (a hole larger than a room) stays a
    corridor."""
    from floorscan.floorplan.room_tables import room_tables, room_width

    office = shapely.box(0, 0, 5, 7).difference(shapely.box(2.1, 2.5, 2.9, 4.5))
    ring = shapely.box(10, 0, 24, 14).difference(shapely.box(12, 2, 22, 12))
    assert room_width(office, 0.025) < 3.0  # what made it a corridor
    doors = [(np.array([5.0, 1.0]), np.array([5.0, 2.0]), 0, 0, 1)]
    rooms, _ = room_tables([office, ring], doors, 0.05, RoomParams())
    assert list(rooms["kind"]) == ["room", "corridor"]
    assert rooms["area_m2"].tolist() == pytest.approx([33.4, 96.0])


# A ring corridor's corner (office_h of Bormann et al.'s benchmark): the corridor, 1.3 m
# wide, runs up along x 3..4.3 and right along y 3.7..5; its two outer walls stop 1 m
# short of the corner (3, 5) their lines make, so the corridor's corner opens 1.41 m
# wide onto the corner room beyond it (x < 3 above y 3, y > 5 left of x 6).
CORNER = [(0, 0, 10, 0), (10, 0, 10, 8), (10, 8, 0, 8), (0, 8, 0, 0),
          (3, 0, 3, 4.0), (0, 3, 3, 3), (4.0, 5, 10, 5), (6, 5, 6, 8),
          (4.3, 0, 4.3, 3.7), (4.3, 3.7, 10, 3.7)]  # fmt: skip
CORNER_POSES = [(3.65, 1.0), (3.65, 4.35), (7.5, 4.35), (1.5, 5.5), (4.5, 6.5), (1.5, 3.8)]


def test_a_corner_mouth_joins_the_free_ends_of_two_walls_across_their_missing_corner():
    axes = np.array(CORNER, dtype=np.float64)
    mouths = corner_mouths(axes, np.full(len(axes), T), RoomParams())
    assert [({tuple(np.round(p, 2)), tuple(np.round(q, 2))}, w) for p, q, w in mouths] == [({(3.0, 4.0), (4.0, 5.0)}, 6)]
    # a wall end whose corner lies more than a door's width beyond it (a partition
    # ending across a corridor from the other wall's jamb) makes none
    far = axes.copy()
    far[4, 3] = 2.8  # the corridor's west wall ends 2.2 m short of the corner
    assert corner_mouths(far, np.full(len(far), T), RoomParams()) == []
    # nor do two walls in one line (a gap in a wall, wall_gaps') or stubs shorter than the opening
    stubs = np.array([(3, 3.2, 3, 4.0), (4.0, 5, 4.9, 5)], dtype=np.float64)
    assert corner_mouths(stubs, np.full(2, T), RoomParams()) == []


def test_a_corridor_corner_open_to_the_room_beyond_it_is_two_rooms_and_their_door():
    rooms, doors = _rooms(CORNER, CORNER_POSES)
    assert len(rooms) == 2
    corridor = rooms["polygon"][int(np.argmax([p.contains(shapely.Point(3.65, 1.0)) for p in rooms["polygon"]]))]
    corner = rooms["polygon"][int(np.argmax([p.contains(shapely.Point(1.5, 5.5)) for p in rooms["polygon"]]))]
    assert not corridor.equals(corner)
    assert corridor.contains(shapely.Point(7.5, 4.35)) and corner.contains(shapely.Point(4.5, 6.5))
    assert len(doors) == 1 and doors["width_m"].iloc[0] == pytest.approx(np.sqrt(2), abs=0.1)
    d = doors.iloc[0]
    assert np.hypot((d.x0 + d.x1) / 2 - 3.5, (d.y0 + d.y1) / 2 - 4.5) < 0.1


def test_a_desk_standing_free_frames_no_door():
    # one room 8 x 4 m with a desk 0.8 x 1.8 m standing free in its middle, 1.04 m from
    # the south and the north wall, its short sides taken for walls (as a map's plan
    # takes a piece of furniture's faces): each narrowing beside it has a wall at one
    # end and the desk at the other. A door is an opening in the building's structure,
    # so the room stays one (a map: no scan positions, every cell not free bounds the
    # space); the tree before the change cut it in two rooms with two doors
    box = [(0, 0, 8, 0), (8, 0, 8, 4), (8, 4, 0, 4), (0, 4, 0, 0)]
    desk = [(3.6, 1.1, 4.4, 1.1), (4.4, 1.1, 4.4, 2.9), (4.4, 2.9, 3.6, 2.9), (3.6, 2.9, 3.6, 1.1)]
    poses = [(1.5, 2.0), (6.5, 2.0), (4.0, 0.55), (4.0, 3.45), (2.5, 1.0), (5.5, 3.0)]
    grid = dataclasses.replace(_grid(box, poses, objects=desk), scan_xy=None)
    axes = np.array(box + [(3.6, 1.1, 4.4, 1.1), (3.6, 2.9, 4.4, 2.9)], dtype=np.float64)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid, RoomParams())
    assert len(rooms) == 1 and len(doors) == 0
    assert 28.5 < rooms["area_m2"].iloc[0] < 30.5


def test_a_piece_of_wall_between_two_doors_in_the_wall_s_line_frames_them():
    """A corridor (y 0..2) and a room (y 2..6) parted by a wall with two doors, 1.0 m
    (x 3..4) and 1.4 m (x 5.8..7.2) wide; the walls beside them end in an L (so no gap
    in one wall's line: corners are no jambs of ``wall_gaps``), and the 1.8 m piece
    between the doors stands free in the space, shorter than a piece of furniture. It
    lies in the wall's line, a door's width from a wall's end on each side: a piece of
    the wall, whose ends frame both doors (the tree before made one space of the two)."""
    walls = [(0, 0, 12, 0), (12, 0, 12, 6), (12, 6, 0, 6), (0, 6, 0, 0), (0, 2, 3, 2), (3, 2, 3, 3.5), (4, 2, 5.8, 2),
             (7.2, 2, 12, 2), (7.2, 2, 7.2, 3.5)]  # fmt: skip
    grid = _grid(walls, [(1.5, 1), (6, 1), (10.5, 1), (1.5, 4), (6, 4.5), (10, 4)])
    for g in (grid, dataclasses.replace(grid, scan_xy=None)):  # a recording, a map
        rooms, doors = plan_rooms(np.array(walls, dtype=np.float64), np.full(len(walls), T), g, RoomParams())
        assert sorted(rooms["kind"]) == ["corridor", "room"] and len(doors) == 2
        assert sorted(round(float(w), 1) for w in doors["width_m"]) == [0.9, 1.3]  # between the walls' faces
        corridor = rooms[rooms["kind"] == "corridor"]["polygon"].iloc[0]
        assert corridor.contains(shapely.Point(6, 1)) and not corridor.contains(shapely.Point(6, 4.5))


def test_a_piece_of_wall_between_a_door_in_its_line_and_a_door_at_a_crossing_wall_frames_them():
    """A corridor (y 0..2) and a room (y 2..6) parted by a wall with two doors: 1.0 m
    (x 3..4) between a wall's corner and the 1.8 m piece, and 1.1 m (x 5.8..6.9) between
    the piece and the outer wall it runs to. The piece stands free in the space, shorter
    than a piece of furniture; with a wall's end in its line a door's width off one end
    and a wall across its line a door's width off the other, it is a piece of the wall
    whose ends frame both doors (the tree before made one space of the two)."""
    walls = [(0, 0, 7, 0), (7, 0, 7, 6), (7, 6, 0, 6), (0, 6, 0, 0), (0, 2, 3, 2), (3, 2, 3, 3.5), (4, 2, 5.8, 2)]
    grid = _grid(walls, [(1.5, 1), (5, 1), (1.5, 4), (5, 4.5)])
    for g in (grid, dataclasses.replace(grid, scan_xy=None)):  # a recording, a map
        rooms, doors = plan_rooms(np.array(walls, dtype=np.float64), np.full(len(walls), T), g, RoomParams())
        assert len(rooms) == 2 and len(doors) == 2
        assert sorted(round(float(w), 1) for w in doors["width_m"]) == [0.9, 1.1]  # between the walls' faces
        south = rooms["polygon"][[p.contains(shapely.Point(5, 1)) for p in rooms["polygon"]]].iloc[0]
        assert not south.contains(shapely.Point(5, 4.5)) and 12.0 < south.area < 14.0
    # a table's edge 0.6 m long in the line, shorter than the openings beside it (1.0 m
    # and 1.2 m to the outer wall at x 5.8): no piece of wall, one room
    walls = [(0, 0, 5.8, 0), (5.8, 0, 5.8, 6), (5.8, 6, 0, 6), (0, 6, 0, 0), (0, 2, 3, 2), (3, 2, 3, 3.5), (4, 2, 4.6, 2)]
    grid = dataclasses.replace(_grid(walls, [(1.5, 1), (4.5, 1), (1.5, 4), (4.5, 4.5)]), scan_xy=None)
    rooms, doors = plan_rooms(np.array(walls, dtype=np.float64), np.full(len(walls), T), grid, RoomParams())
    assert len(rooms) == 1 and len(doors) == 0


def test_a_row_of_desks_standing_free_frames_no_door_however_long():
    # a map of a room 6 x 5 m with a row of two desks (x 0.9..5.0, y 3.4..3.5) standing
    # free 0.84 and 0.94 m from the side walls; the plan took the row's faces for two
    # walls of 2.05 m. The row (4.1 m) is longer than a piece of furniture, but it holds
    # no wall as long as one and encloses nothing: it frames no door, one room
    box = [(0, 0, 6, 0), (6, 0, 6, 5), (6, 5, 0, 5), (0, 5, 0, 0)]
    desks = [(0.9, 3.4, 2.95, 3.4), (2.95, 3.4, 5.0, 3.4), (5.0, 3.4, 5.0, 3.5), (5.0, 3.5, 2.95, 3.5),
             (2.95, 3.5, 0.9, 3.5), (0.9, 3.5, 0.9, 3.4)]  # fmt: skip
    grid = dataclasses.replace(_grid(box, [(3, 1.2), (3, 4.5), (5.5, 3.5), (0.4, 3.5), (2, 2)], objects=desks),
                               scan_xy=None)  # fmt: skip
    axes = np.array(box + [(0.9, 3.45, 2.93, 3.45), (2.97, 3.45, 5.0, 3.45)], dtype=np.float64)
    thickness = np.r_[np.full(4, T), 0.1, 0.1]
    rooms, doors = plan_rooms(axes, thickness, grid)
    assert len(rooms) == 1 and len(doors) == 0
    assert 28.0 < rooms["area_m2"].iloc[0] < 28.6
    # a partition as long as the row, joined to nothing, is a wall that holds its doors
    axes[4:] = [(0.9, 3.45, 5.0, 3.45), (0.9, 3.45, 5.0, 3.45)]
    rooms, doors = plan_rooms(axes[:5], thickness[:5], grid)
    assert len(rooms) == 2 and len(doors) == 2


def _desk_row_office(depth: float, pieces: list, door: tuple = (1.6, 2.6)) -> tuple:
    """The rooms and doors of a map of an office 4 m wide and ``depth`` m deep with a
    row of desks 0.6 m deep across its middle, against both side walls and open between
    x ``door`` (metres), the plan's walls its box and ``pieces`` ((x0, dy, x1): axes at
    ``dy`` off the row's middle line)."""
    box = [(0, 0, 4, 0), (4, 0, 4, depth), (4, depth, 0, depth), (0, depth, 0, 0)]
    y = depth / 2
    desks = []
    for x0, x1 in ((0.0, door[0]), (door[1], 4.0)):
        desks += [(x0, y - 0.3, x1, y - 0.3), (x1, y - 0.3, x1, y + 0.3), (x1, y + 0.3, x0, y + 0.3),
                  (x0, y + 0.3, x0, y - 0.3)]  # fmt: skip
    mid = sum(door) / 2
    poses = [(mid, y), (1.0, y - 1.2), (3.0, y - 1.0), (1.0, y + 1.2), (3.0, y + 1.0), (2.0, 0.6), (2.0, depth - 0.6)]
    grid = dataclasses.replace(_grid(box, poses, objects=desks), scan_xy=None)
    axes = np.array(box + [(x0, y + dy, x1, y + dy) for x0, dy, x1 in pieces], dtype=np.float64)
    return plan_rooms(axes, np.full(len(axes), 0.1), grid, RoomParams())


def test_a_desk_row_with_a_door_s_width_between_its_desks_parts_no_office():
    """The plan took a piece of each desk's face, 0.5 m, for a wall (as a map's plan of
    map15 does): an opening a door wide between walls all shorter than the narrowest
    door, across an office 5 m deep, is a gap between desks and parts no rooms
    (desk_rows); across a hall 12 m deep (longer than one room) it is a door and does;
    so does a door between two walls as long as the desks, beside a corner (a stub
    shorter than a door at one jamb and a wall at the other, or a stub tied to the side
    wall), or with no wall at its jambs."""
    stubs = [(1.1, 0.0, 1.6), (2.6, 0.0, 3.1)]
    rooms, doors = _desk_row_office(5.0, stubs)
    assert len(rooms) == 1 and len(doors) == 0
    assert rooms["polygon"].iloc[0].contains(shapely.MultiPoint([(2, 1), (2, 4), (0.5, 4.5), (3.5, 0.5)]))
    rooms, doors = _desk_row_office(12.0, stubs)
    assert len(rooms) == 2 and len(doors) == 1 and doors["width_m"].iloc[0] == pytest.approx(1.0, abs=0.1)
    rooms, doors = _desk_row_office(5.0, [(0.05, 0.0, 1.6), (2.6, 0.0, 3.95)])
    assert len(rooms) == 2 and len(doors) == 1
    rooms, doors = _desk_row_office(5.0, [(0.05, 0.0, 0.4), (1.4, 0.0, 3.95)], door=(0.4, 1.4))
    assert len(rooms) == 2 and len(doors) == 1 and doors["width_m"].iloc[0] == pytest.approx(1.0, abs=0.1)
    # both jamb walls short, one tied to the side wall: a partition's stub at a corner
    rooms, doors = _desk_row_office(5.0, [(0.05, 0.0, 0.5), (1.5, 0.0, 2.0)], door=(0.5, 1.5))
    assert len(rooms) == 2 and len(doors) == 1
    # no wall at the jambs (the plan lacks the pieces): nothing to weigh, the door stays
    rooms, doors = _desk_row_office(5.0, [])
    assert len(rooms) == 2 and len(doors) == 1


def test_a_cabinet_standing_free_with_a_pocket_of_floor_inside_frames_no_door():
    # a map of a room 7 x 5 m with a cabinet 0.8 x 2.45 m (a little longer than a piece
    # of furniture, so not standing free by its extent) standing 1.24 and 1.19 m from the
    # south and the north wall, its long sides taken for walls; the map marks 0.3 m2
    # inside it free (a shelf seen through). Floor too small for a room makes no core of
    # rooms: the cabinet frames no door and the room stays one (the tree before the
    # change: two rooms and two doors)
    box = [(0, 0, 7, 0), (7, 0, 7, 5), (7, 5, 0, 5), (0, 5, 0, 0)]
    cabinet = [(3.0, 1.3, 3.8, 1.3), (3.8, 1.3, 3.8, 3.75), (3.8, 3.75, 3.0, 3.75), (3.0, 3.75, 3.0, 1.3)]
    poses = [(1.5, 2.5), (5.5, 2.5), (3.4, 0.6), (3.4, 4.4), (1.0, 4.0), (6.0, 1.0)]
    grid = dataclasses.replace(_grid(box, poses, objects=cabinet), scan_xy=None)
    ys, xs = grid.origin_xy[1] + (np.arange(grid.shape[0]) + 0.5) * grid.resolution_m, \
        grid.origin_xy[0] + (np.arange(grid.shape[1]) + 0.5) * grid.resolution_m
    pocket = ((ys > 2.0) & (ys < 2.8))[:, None] & ((xs > 3.2) & (xs < 3.6))[None, :]
    hit, miss = grid.n_hit_scans.copy(), grid.n_miss_scans.copy()
    hit[pocket], miss[pocket] = 0, 5
    grid = dataclasses.replace(grid, n_hit_scans=hit, n_miss_scans=miss)
    axes = np.array(box + [(3.0, 1.3, 3.0, 3.75), (3.8, 1.3, 3.8, 3.75)], dtype=np.float64)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid, RoomParams())
    assert len(rooms) == 1 and len(doors) == 0
    assert 30.5 < rooms["area_m2"].iloc[0] < 32.5  # the floor less the cabinet's


def test_standing_free_is_an_obstacle_apart_shorter_than_a_piece_of_furniture():
    from floorscan.floorplan.jambs import standing_free

    r = 0.05
    solid = np.zeros((200, 200), dtype=bool)
    solid[10, 10:190] = True  # a wall 9 m long
    solid[10:60, 10] = True  # and its L
    solid[100:116, 100:136] = True  # a desk 1.8 x 0.8 m
    solid[185:187, 100:150] = True  # a shelf 2.5 m long: not shorter
    yy, xx = np.mgrid[:200, :200]
    u, v = (xx - 60) + (yy - 140), (xx - 60) - (yy - 140)  # a square 1.5 m a side turned by 45 degrees
    solid |= (np.abs(u) <= 21) & (np.abs(v) <= 21)
    free = standing_free(solid, r)
    assert free[100:116, 100:136].all() and free[140, 60]
    assert not free[10].any() and not free[:, 10].any() and not free[185:187].any()
    assert free.sum() == 16 * 36 + ((np.abs(u) <= 21) & (np.abs(v) <= 21)).sum()
    # the same objects on the raster turned by 90 degrees
    assert np.array_equal(standing_free(np.rot90(solid), r), np.rot90(free))


def test_a_strip_narrower_than_a_walkway_joins_the_room_it_opens_into():
    """A map of 5 cm cells: two rooms (x 0.5..4.5 and 5.55..9.5, y 0.5..6.5) and
    between them a strip 0.75 m wide (x 4.65..5.4) with a door of 0.65 m into each room
    (y 1.0..1.65 and 4.0..4.65). The strip is narrower than the narrowest walkway
    (``MIN_ROOM_WIDTH_M``): no room of its own (the tree before made it a corridor with
    two doors), it joins the room of its wider door (the two are as wide here, up to the
    cells: either); one door is left between the two rooms, and the floor area is the
    same."""
    from floorscan.core.occupancy_classes import grid_of_classes
    from floorscan.floorplan.params import FloorplanParams
    from floorscan.floorplan.room_space import MIN_ROOM_WIDTH_M
    from floorscan.floorplan.scans import plan_of_scans
    from floorscan.walls.map_stage import map_of_grid

    assert 0.75 < MIN_ROOM_WIDTH_M
    r = 0.05
    occ = np.zeros((140, 200), dtype=bool)
    for x0, y0, x1, y1 in [(0.3, 0.3, 9.7, 0.5), (0.3, 6.5, 9.7, 6.7), (0.3, 0.3, 0.5, 6.7), (9.5, 0.3, 9.7, 6.7),
                           (4.5, 0.5, 4.65, 1.0), (4.5, 1.65, 4.65, 6.5), (5.4, 0.5, 5.55, 4.0), (5.4, 4.65, 5.55, 6.5)]:
        occ[round(y0 / r):round(y1 / r), round(x0 / r):round(x1 / r)] = True  # fmt: skip
    free = np.zeros_like(occ)
    free[10:130, 10:190] = True
    grid = grid_of_classes(occ, free & ~occ, origin_xy=(0.0, 0.0), resolution_m=r)
    plan = plan_of_scans(map_of_grid(grid, None), None, FloorplanParams(), grid)
    assert list(plan.rooms["kind"]) == ["room", "room"] and len(plan.doors) == 1
    # the two doors are as wide: the strip joins the room of either, and the other is left
    strip = shapely.box(4.7, 2.0, 5.35, 3.5)
    west, east = plan.rooms["polygon"].iloc[0], plan.rooms["polygon"].iloc[1]
    assert (west.contains(strip) and not east.intersects(strip)) or (east.contains(strip) and not west.intersects(strip))
    left_door_x = 5.475 if west.contains(strip) else 4.575  # the door of the room the strip did not join
    assert abs(plan.doors["width_m"].iloc[0] - 0.65) <= 0.1 and abs(plan.doors["x0"].iloc[0] - left_door_x) < 0.1
    assert 52.0 < plan.rooms["area_m2"].sum() < 54.5


def test_a_dead_end_corridor_off_a_hall_is_a_room_of_its_own():
    """A hall (x 0..20, y 0..8) with a dead-end corridor 1.6 m wide and 7.4 m long off
    its north wall: the space does not narrow at its mouth, which lies between two
    corners, so only the dead end's mouth (:func:`~floorscan.floorplan.mouths.dead_end_mouths`)
    parts it from the hall, at the hall wall's line. Without it, hall and corridor are
    one room."""
    from floorscan.floorplan.mouths import dead_end_mouths
    from floorscan.floorplan.room_space import room_space

    walls = [(0, 0, 20, 0), (20, 0, 20, 8), (20, 8, 10.6, 8), (9, 8, 0, 8), (0, 8, 0, 0),
             (9, 8, 9, 15.4), (10.6, 8, 10.6, 15.4), (9, 15.4, 10.6, 15.4)]  # fmt: skip
    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
    grid = _grid(walls, [(4, 4), (10, 4), (16, 4), (9.8, 10), (9.8, 14)])
    mouths = dead_end_mouths(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams())
    assert [sorted((round(float(p[0]), 2), round(float(q[0]), 2))) for p, q, _ in mouths] == [[9.0, 10.6]]
    assert all(abs(p[1] - 8) < 1e-9 and abs(q[1] - 8) < 1e-9 for p, q, _ in mouths)
    rooms, doors = plan_rooms(axes, th, grid, RoomParams())
    assert sorted(rooms["kind"]) == ["corridor", "room"] and len(doors) == 1
    corridor = rooms[rooms["kind"] == "corridor"]["polygon"].iloc[0]
    assert 10.5 < corridor.area < 11.8 and corridor.bounds[1] > 7.8  # 1.6 x 7.4 m less half walls


def test_a_dead_end_corridor_along_the_hall_s_wall_is_a_corridor_of_its_own():
    """A hall 12 x 8 m and a dead-end corridor 1.8 m wide and 8 m long north of it,
    whose west wall is the hall's west wall going on (Bormann et al.'s Freiburg101):
    its mouth has a corner on one side only, so no gap in a wall's line marks it; the
    corridor's end opens onto the hall (:func:`~floorscan.floorplan.corridors.corridor_ends`)
    and is cut across it. The tree before left one space."""
    from floorscan.floorplan.corridors import corridor_ends, corridor_strips
    from floorscan.floorplan.room_space import room_space

    walls = [(0, 0, 12, 0), (12, 0, 12, 8), (12, 8, 1.8, 8), (1.8, 8, 1.8, 16), (1.8, 16, 0, 16), (0, 16, 0, 0)]
    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
    grid = _grid(walls, [(3, 2), (9, 2), (3, 6), (9, 6), (0.9, 10), (0.9, 14)])
    ends = corridor_ends(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams())
    assert [sorted((round(float(p[0]), 2), round(float(q[0]), 2))) for p, q, _ in ends] == [[0.0, 1.8]]
    assert all(abs(p[1] - 8) < 0.01 and abs(q[1] - 8) < 0.01 for p, q, _ in ends)
    rooms, doors = plan_rooms(axes, th, grid, RoomParams())
    assert sorted(rooms["kind"]) == ["corridor", "room"]
    assert len(doors) == 1 and doors["width_m"].iloc[0] == pytest.approx(1.8, abs=0.15)  # no wider than a door
    corridor = rooms[rooms["kind"] == "corridor"]["polygon"].iloc[0]
    assert 13.0 < corridor.area < 14.5 and corridor.contains(shapely.Point(0.9, 12))  # 1.8 x 8 m less half walls
    # open at its far end onto a room that opens onto the hall too (a ring): no single
    # line parts the space there
    ring = walls[:2] + [(12, 8, 6, 8), (5, 8, 1.8, 8), (1.8, 8, 1.8, 16.2), (1.8, 18, 0, 18), (0, 18, 0, 0),
                        (1.8, 18, 12, 18), (12, 18, 12, 8)]  # fmt: skip
    axes, th = np.array(ring, dtype=np.float64), np.full(len(ring), T)
    grid = _grid(ring, [(3, 2), (9, 2), (3, 6), (9, 6), (0.9, 10), (0.9, 14), (0.9, 17), (6, 17), (10, 12)])
    raster = room_space(grid, axes, th, RoomParams())
    strips = corridor_strips(axes, th, raster, RoomParams())
    assert any(s["polygon"].contains(shapely.Point(0.9, 11)) for s in strips)  # the corridor is still one
    assert corridor_ends(axes, th, raster, RoomParams(), strips) == []


def test_a_wide_corridor_s_end_onto_a_hall_is_found_past_a_recess_at_its_mouth():
    """A corridor 2.4 m wide (x 0..2.4, y 6..19) whose east wall steps 0.6 m out for
    its last 1.5 m, at its mouth onto a 13 m x 6 m hall (orebro's corridor into its
    lab): its strip ends at y 7.5, and the hall's cells clearer than the corridor is
    wide lie over 3.5 m beyond, past ``corridor_max_width_m``; they lie within twice the
    corridor's width, so the end is cut there (before, corridor and hall were one space).
    With a partition across the mouth that leaves a 1 m gap, the hall lies beyond a
    narrowing narrower than the corridor: no end."""
    from floorscan.floorplan.corridors import corridor_ends

    hall = [(-5, 0, 8, 0), (8, 0, 8, 6), (8, 6, 3.0, 6), (0, 6, -5, 6), (-5, 6, -5, 0)]
    corridor = [(0, 6, 0, 19), (2.4, 7.5, 2.4, 19), (0, 19, 2.4, 19), (2.4, 7.5, 3.0, 7.5), (3.0, 7.5, 3.0, 6)]
    poses = [(-3, 3), (3, 3), (6, 3), (1.2, 9), (1.2, 13), (1.2, 17)]
    for walls, found in ((hall + corridor, [[0.0, 2.4]]), (hall + corridor + [(0, 6, 1.4, 6)], [])):
        axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
        grid = _grid(walls, poses)
        ends = corridor_ends(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams())
        assert [sorted((round(float(p[0]), 1), round(float(q[0]), 1))) for p, q, _ in ends] == found
        assert all(abs(p[1] - 7.5) < 0.2 and abs(q[1] - 7.5) < 0.2 for p, q, _ in ends)
    rooms, doors = plan_rooms(np.array(hall + corridor, dtype=np.float64), np.full(len(hall + corridor), T),
                              _grid(hall + corridor, poses), RoomParams())
    assert sorted(rooms["kind"]) == ["corridor", "room"]
    corridor_room = rooms[rooms["kind"] == "corridor"]["polygon"].iloc[0]
    assert corridor_room.contains(shapely.Point(1.2, 12)) and corridor_room.bounds[1] > 6.5


def test_a_corridor_goes_on_past_a_step_of_its_side():
    """A corridor 2 m wide (x 10..24) whose south wall steps 0.4 m out at x 10 and runs
    on to x 3 (the next block's wall): past the step its sides are two other lines, 7 m
    long together, shorter than four widths, and open over 2.5 m to an office below.
    The corridor goes on past the step, so that stretch's openings are cut on its
    sides too (:func:`~floorscan.floorplan.corridors.corridor_strips`); before, only
    the stretch east of the step was a corridor."""
    from floorscan.floorplan.corridors import corridor_sides, corridor_strips
    from floorscan.floorplan.room_space import room_space

    walls = [(3, 2, 5, 2), (6, 2, 24, 2), (3, 2, 3, 6), (3, 6, 8, 6), (8, 6, 8, 2), (24, 0, 24, 2), (10, 0, 24, 0),
             (10, -0.4, 10, 0), (3, -0.4, 5, -0.4), (7.5, -0.4, 10, -0.4), (3, -0.4, 3, 2), (3, -0.4, 3, -4.4),
             (3, -4.4, 10, -4.4), (10, -4.4, 10, -0.4)]  # fmt: skip
    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
    grid = _grid(walls, [(4, 0.8), (8, 0.8), (12, 1), (16, 1), (20, 1), (5.5, 4), (6.5, -2.4)])
    raster = room_space(grid, axes, th, RoomParams())
    strips = corridor_strips(axes, th, raster, RoomParams())
    assert any(s["polygon"].contains(shapely.Point(6.5, 0.8)) for s in strips)
    assert any(s["polygon"].contains(shapely.Point(18, 1)) for s in strips)
    cuts = sorted((round(float(min(p[0], q[0])), 1), round(float(max(p[0], q[0])), 1), round(float(p[1]), 1))
                  for p, q, _ in corridor_sides(axes, th, raster, RoomParams(), strips))  # fmt: skip
    assert cuts == [(5.0, 6.0, 2.0), (5.0, 7.5, -0.4)], cuts



def test_a_corridor_goes_on_through_an_open_office_past_a_step_of_its_side():
    """A corridor (y 0..2, x 0..30) under an office with its door (x 0..18) and an open
    office (x 18..25) open onto it across 7 m; past the open office the corridor's
    north side steps 0.4 m out (the outer wall at y 2.4, x 25..30). The stepped wall
    and the south wall run together for 5 m only, shorter than four widths, and the
    corridor's own north line stops at x 18: the corridor ended there, and the open
    office was one room with its east end. Joined, the two north lines and the south
    wall make one run; the corridor goes on along its own lines to x 30 (its north side
    bounded along 22 of its 30 m), and the open office is parted from it on the
    corridor's line."""
    from floorscan.floorplan.corridors import corridor_strips
    from floorscan.floorplan.room_space import room_space

    walls = [(0, 0, 30, 0), (30, 0, 30, 2.4), (30, 2.4, 25, 2.4), (25, 2.4, 25, 8), (25, 8, 0, 8), (0, 8, 0, 0),
             (0, 2, 8, 2), (9, 2, 18, 2), (18, 2, 18, 8)]  # fmt: skip
    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
    seeds = [(2, 1), (10, 1), (20, 1), (28, 1), (4, 5), (21.5, 5)]
    strips = corridor_strips(axes, th, room_space(_grid(walls, seeds), axes, th, RoomParams()), RoomParams())
    # from the west wall's face to the east wall's
    assert len(strips) == 1 and strips[0]["polygon"].bounds == pytest.approx((0.0, 0.0, 30.0, 2.0), abs=0.25)
    rooms, doors = _rooms(walls, seeds)

    def room_of(x, y):
        return [k for k, p in enumerate(rooms["polygon"]) if p.contains(shapely.Point(x, y))]

    assert len(rooms) == 3 and len(doors) == 1 and room_of(2, 1) == room_of(28, 1) != room_of(21.5, 5) != []
    office = rooms["polygon"].iloc[room_of(21.5, 5)[0]]
    assert office.bounds == pytest.approx((18.0, 2.0, 25.0, 8.0), abs=0.15)


def test_an_opening_whose_middle_faces_a_partition_s_end_is_no_niche():
    """A corridor (y 0..2) open over 4 m (x 8..12) to two rooms below, whose partition
    ends 1.5 m short of the corridor right under the opening's middle. The space behind
    the opening ends there on its middle line only, not across the opening: no niche of
    the corridor, so the opening is cut on the corridor's line. Before, the middle ray
    alone read a niche 1.5 m deep (under half the opening's width)."""
    from floorscan.floorplan.corridors import corridor_sides
    from floorscan.floorplan.room_space import room_space

    walls = [(0, 2, 20, 2), (0, 0, 0, 2), (20, 0, 20, 2), (0, 0, 8, 0), (12, 0, 20, 0), (4, -6, 4, 0),
             (16, -6, 16, 0), (4, -6, 16, -6), (10, -6, 10, -1.5)]  # fmt: skip
    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
    grid = _grid(walls, [(2, 1), (6, 1), (10, 1), (14, 1), (18, 1), (7, -3), (13, -3)])
    cuts = corridor_sides(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams())
    got = sorted((round(float(min(p[0], q[0])), 1), round(float(max(p[0], q[0])), 1), round(float(p[1]), 1))
                 for p, q, _ in cuts)  # fmt: skip
    assert len(got) == 1 and np.allclose(got[0], (8.0, 12.0, 0.0), atol=0.15), got  # 0.1 m cells
    # a niche 2.8 m wide and 1.1 m deep in the corridor's north side, a door at the back
    # of its east part: the ray through the door goes on, the other two end at its back
    niche = [(0, 0, 20, 0), (0, 0, 0, 2), (20, 0, 20, 2), (0, 2, 8, 2), (10.8, 2, 20, 2), (8, 2, 8, 3.1),
             (10.8, 2, 10.8, 3.1), (8, 3.1, 9.6, 3.1), (10.6, 3.1, 12, 3.1), (8, 3.1, 8, 7), (8, 7, 12, 7),
             (12, 7, 12, 3.1)]  # fmt: skip
    axes, th = np.array(niche, dtype=np.float64), np.full(len(niche), T)
    grid = _grid(niche, [(2, 1), (6, 1), (10, 1), (14, 1), (18, 1), (10, 5)])
    assert corridor_sides(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams()) == []


def test_a_passage_into_a_room_wider_than_it_is_no_corridor_going_on():
    """A corridor (y 0..2) with a 1 m opening in its north side into a passage 1 m long
    and a room 5 x 5 m behind it: the space behind goes on for four of the mouth's widths,
    as a corridor going on from the opening would, but it is more than twice as wide as
    the mouth along the way (the median along the ray), so the mouth is the room's
    entrance and is cut as a door on the corridor's line (g4s_y2's room T13). A
    corridor going on from its mouth is as wide as it (test above)."""
    from floorscan.floorplan.corridors import corridor_sides
    from floorscan.floorplan.room_space import room_space

    walls = [(0, 0, 20, 0), (0, 0, 0, 2), (20, 0, 20, 2), (0, 2, 9.5, 2), (10.5, 2, 20, 2), (9.5, 2, 9.5, 3),
             (10.5, 2, 10.5, 3), (7.5, 3, 9.5, 3), (10.5, 3, 12.5, 3), (7.5, 3, 7.5, 8), (12.5, 3, 12.5, 8),
             (7.5, 8, 12.5, 8)]  # fmt: skip
    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
    grid = _grid(walls, [(2, 1), (6, 1), (10, 1), (14, 1), (18, 1), (10, 5.5)])
    cuts = corridor_sides(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams())
    got = sorted((round(float(min(p[0], q[0])), 1), round(float(max(p[0], q[0])), 1), round(float(p[1]), 1))
                 for p, q, _ in cuts)  # fmt: skip
    assert len(got) == 1 and np.allclose(got[0], (9.5, 10.5, 2.0), atol=0.15), got


def test_a_corridor_whose_wall_goes_on_past_a_partition_s_line_is_not_cut_there():
    """A corridor (x 0..20, y 6..7.5) along two closed rooms, a hall (x 8..16, y -2..6)
    open onto it on its whole width. The corridor's part west of the hall is closed
    behind the line of the hall's west wall and the partition above it, and a space
    twice as wide lies beside that line, but the corridor's north wall goes on through
    the line: the corridor crosses it, and no dead end's mouth is cut there. Without
    that test, the corridor's west part is a dead end of its own."""
    from floorscan.floorplan import mouths
    from floorscan.floorplan.room_space import room_space

    walls = [(0, 6, 8, 6), (16, 6, 20, 6), (0, 7.5, 20, 7.5), (0, 6, 0, 11), (20, 6, 20, 11), (8, -2, 8, 6),
             (16, -2, 16, 6), (8, -2, 16, -2), (8, 7.5, 8, 11), (0, 11, 20, 11)]  # fmt: skip
    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
    grid = _grid(walls, [(4, 6.75), (12, 6.75), (12, 2), (4, 9), (14, 9)])
    raster = room_space(grid, axes, th, RoomParams())
    assert mouths.dead_end_mouths(axes, th, raster, RoomParams()) == []
    rooms, _ = plan_rooms(axes, th, grid, RoomParams())
    corridor = [p for p in rooms["polygon"] if p.contains(shapely.Point(12, 6.75))][0]
    assert corridor.contains(shapely.Point(4, 6.75))


def test_a_room_behind_the_corridor_s_wall_is_not_the_hall_a_dead_end_opens_onto():
    """A niche 0.8 m wide and 3 m deep off a corridor 1.2 m wide, and behind the
    corridor's far wall a room 12 x 4 m, whose door lies 4 m away: the room's floor
    within 3 m of the niche's mouth is farther than 0.8 m from its walls, but it is
    not seen from the mouth, so the niche opens onto the corridor, not onto a hall, and
    no dead end's mouth is cut. Measured through the wall, the niche is cut off."""
    from floorscan.floorplan.mouths import dead_end_mouths
    from floorscan.floorplan.room_space import room_space

    walls = [(0, 0, 1, 0), (2, 0, 12, 0), (12, 0, 12, 1.2), (12, 1.2, 6.4, 1.2), (5.6, 1.2, 0, 1.2),
             (0, 1.2, 0, -4), (5.6, 1.2, 5.6, 4.2), (6.4, 1.2, 6.4, 4.2), (5.6, 4.2, 6.4, 4.2), (0, -4, 12, -4),
             (12, -4, 12, 0)]  # fmt: skip
    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
    grid = _grid(walls, [(1.5, 0.6), (6, 0.6), (10, 0.6), (6, 3), (6, -2), (2, -2), (10, -2)])
    assert dead_end_mouths(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams()) == []


def test_a_corridor_crossing_another_keeps_its_short_arm():
    """A crossing: a corridor 12 m long and 2 m wide meets the long corridor from the
    south, and goes on north of it, 2.9 m wide, for 3 m to a wall. The north opening
    faces the south corridor's mouth, so it is that corridor going on through, not a
    room's side: one room. Cut like an office's open side, the 3 m arm was a room of its
    own (its walls are in no line of the south corridor's, so it is no part of that
    corridor's strip)."""
    from floorscan.floorplan.corridors import corridor_sides
    from floorscan.floorplan.room_space import room_space

    walls = [(0, 0, 9, 0), (9, 0, 9, -12), (9, -12, 11, -12), (11, -12, 11, 0), (11, 0, 20, 0), (20, 0, 20, 2),
             (20, 2, 11.6, 2), (11.6, 2, 11.6, 5), (11.6, 5, 8.7, 5), (8.7, 5, 8.7, 2), (8.7, 2, 0, 2),
             (0, 2, 0, 0)]  # fmt: skip
    axes = np.array(walls, dtype=np.float64)
    thick = np.full(len(axes), T)
    grid = _grid(walls, [(x, 1.0) for x in (2, 6, 10, 14, 18)] + [(10, y) for y in (-10, -6, -2, 3.5)])
    assert corridor_sides(axes, thick, room_space(grid, axes, thick, RoomParams()), RoomParams()) == []
    rooms, doors = plan_rooms(axes, thick, grid, RoomParams())
    assert len(rooms) == 1 and len(doors) == 0 and 66 < rooms["area_m2"].iloc[0] < 69


def test_a_door_facing_a_slit_in_the_corridor_wall_does_not_part_the_corridor():
    """A corridor (x 0..12, y 0..2.2) with an office's door in its north wall at x 6..7
    and its south wall broken at x 6.7..7.0 (a slit no one passes, where a map's wall
    is found in two pieces): each wall goes on past its ends, so the line from the
    door's jamb to the slit's edge is no room's open side, and the corridor is one
    room. With only a door-wide gap counting as the wall going on, the corridor parts
    there into two rooms."""
    walls = [(0, 0, 6.7, 0), (7.0, 0, 12, 0), (12, 0, 12, 2.2), (12, 2.2, 7, 2.2), (6, 2.2, 0, 2.2), (0, 2.2, 0, 0),
             (0, 2.2, 0, 6), (0, 6, 12, 6), (12, 6, 12, 2.2)]  # fmt: skip
    poses = [(2.0, 1.1), (9.5, 1.1), (3.0, 4.0), (9.0, 4.0)]
    axes = np.array(walls, dtype=np.float64)
    grid = _grid(walls, poses)
    raster = room_space(grid, axes, np.full(len(axes), T), RoomParams())
    mouths = room_mouths(axes, np.full(len(axes), T), raster, RoomParams())
    assert not any(min(p[1], q[1]) < 0.3 and max(p[1], q[1]) > 1.9 for p, q, _ in mouths)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid, RoomParams())
    assert sorted(rooms["kind"]) == ["corridor", "room"] and len(doors) == 1
    corridor = rooms[rooms["kind"] == "corridor"]["polygon"].iloc[0]
    assert shapely.box(0.2, 0.2, 11.8, 2.0).difference(corridor).area < 0.3
    assert round(float((doors.x0.iloc[0] + doors.x1.iloc[0]) / 2), 1) == 6.5


def test_two_doors_facing_each_other_across_a_corridor_do_not_part_it():
    """A corridor (x 0..10, y 0..2.2) with an office's door on each side at x 4..5, its
    walls going on past the doors: the line between the doors' west jambs is no room's
    open side (the corridor's west part would be a pocket 4 m deep), and the corridor
    is one room. Without the test of :func:`~floorscan.floorplan.mouths.room_mouths`,
    the corridor parts at x 4 into two rooms."""
    walls = [(0, -4, 5, -4), (5, -4, 5, 0), (5, 0, 10, 0), (10, 0, 10, 2.2), (10, 2.2, 5, 2.2), (5, 2.2, 5, 6),
             (5, 6, 0, 6), (0, 6, 0, -4), (0, 2.2, 4, 2.2), (0, 0, 4, 0)]  # fmt: skip
    poses = [(2.0, 1.1), (7.5, 1.1), (2.5, 4.0), (2.5, -2.0)]
    axes = np.array(walls, dtype=np.float64)
    grid = _grid(walls, poses)
    raster = room_space(grid, axes, np.full(len(axes), T), RoomParams())
    mouths = room_mouths(axes, np.full(len(axes), T), raster, RoomParams())
    assert not any(abs(p[0] - 4) < 0.2 and abs(q[0] - 4) < 0.2 for p, q, _ in mouths)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid, RoomParams())
    assert sorted(rooms["kind"]) == ["corridor", "room", "room"] and len(doors) == 2
    corridor = rooms[rooms["kind"] == "corridor"]["polygon"].iloc[0]
    assert shapely.box(0.2, 0.2, 9.8, 2.0).difference(corridor).area < 0.3
    assert sorted(round(float((d.x0 + d.x1) / 2), 1) for d in doors.itertuples()) == [4.5, 4.5]


def test_a_dead_end_of_unentered_space_is_judged_whole():
    """The unentered space beyond a hall's open east side, in two watershed regions: a
    pocket walled on its south and east (walled on all its edge) and a fan beyond it
    walled nowhere. Each meets the hall and the other; as one dead end, walled on about 8
    of its 30 m of edge, both are outside. Judged region by region (before), the fan met
    two regions, so neither was."""
    from floorscan.floorplan.room_space import RoomRaster
    from floorscan.floorplan.unentered import enclosure, outside_regions

    res, m = 0.1, 20  # 10 cm cells, a margin of 2 m of unseen cells around
    h, w = 100 + 2 * m, 200 + 2 * m
    labels = np.zeros((h, w), dtype=np.int32)
    labels[m : m + 100, m : m + 100] = 1  # the hall, x 0..10, y 0..10 (rows up)
    labels[m : m + 40, m + 100 : m + 140] = 2  # the pocket, x 10..14, y 0..4
    labels[m + 40 : m + 100, m + 100 : m + 200] = 3  # the fan, x 10..20, y 4..10
    space = labels > 0
    walls = np.zeros_like(space)
    walls[m - 1, m - 1 : m + 141] = True  # south of the hall and the pocket
    walls[m + 100, m - 1 : m + 101] = True  # north of the hall
    walls[m - 1 : m + 101, m - 1] = True  # west of the hall
    walls[m - 1 : m + 41, m + 140] = True  # east of the pocket
    raster = RoomRaster(np.zeros(2), res, walls, space, walls.copy(), ~space)
    walled = enclosure(raster, labels)
    assert walled[2] == pytest.approx(1.0) and walled[3] < 0.05
    assert enclosure(raster, np.where(labels == 3, 2, labels))[2] == pytest.approx(8 / 30, abs=0.03)
    kinds = {(1, 2): "wide", (1, 3): "wide", (2, 3): "wide"}
    visited = np.array([False, True, False, False])
    out = outside_regions(raster, labels, kinds, RoomParams(), visited, True)
    assert out.tolist() == [False, False, True, True]
    # the same space in a map (no scans: every room is unentered) is not judged so
    assert not outside_regions(raster, labels, kinds, RoomParams(), visited, False).any()


def test_a_short_wall_far_along_a_corridor_side_across_open_floor_is_not_on_its_line():
    """Walls on a line (:func:`floorscan.floorplan.corridors.wall_lines`) with the room
    raster: a 0.6 m wall standing in a hall 30 m beyond a corridor, on the line of the
    corridor's south wall (3 cm off), is not on that line: between them lies the hall's
    floor, and the line would be less wall than opening (15.6 m of 45.6). Drawn from the
    walls alone it joins the line and makes it 45.6 m long, so a change to a wall far
    away reached the corridor's sides (belgioioso's corridor, benchmarks/README.md)."""
    from floorscan.floorplan.corridor_lines import wall_lines
    from floorscan.floorplan.doors import wall_units

    corridor = [(0, 0, 15, 0), (0, 2, 15, 2), (0, 0, 0, 2)]
    hall = [(15, 0, 15, -10), (15, -10, 50, -10), (50, -10, 50, 12), (50, 12, 15, 12), (15, 12, 15, 2)]
    stub = [(45, 0.03, 45.6, 0.03)]
    walls = corridor + hall + stub
    poses = [(2, 1), (7, 1), (12, 1)] + [(x, y) for x in (20, 30, 40) for y in (5, -5)] + [(46, 4), (46, -4)]
    axes = np.array(walls, dtype=np.float64)
    thick = np.full(len(axes), T)
    raster = room_space(_grid(walls, poses), axes, thick, RoomParams())
    u, length = wall_units(axes)
    south, far = 0, len(walls) - 1
    assert [0, far] in wall_lines(axes, thick, u, length, RoomParams().line_offset_m)
    lines = wall_lines(axes, thick, u, length, RoomParams().line_offset_m, raster)
    assert [south] in lines and [far] in lines
    # a door's gap in a line of walls keeps it one line: 2 x 7 m of wall around 1 m
    gap = [(0, 0, 7, 0), (8, 0, 15, 0)] + walls[1:8]
    axes = np.array(gap, dtype=np.float64)
    thick = np.full(len(axes), T)
    raster = room_space(_grid(gap, poses), axes, thick, RoomParams())
    u, length = wall_units(axes)
    assert [0, 1] in wall_lines(axes, thick, u, length, RoomParams().line_offset_m, raster)


def _octagon(cx: float, cy: float, radius: float) -> list:
    a = np.radians(22.5 + 45 * np.arange(9))
    x, y = cx + radius * np.cos(a), cy + radius * np.sin(a)
    return [(x[i], y[i], x[i + 1], y[i + 1]) for i in range(8)]


def test_a_plant_against_a_corridor_wall_frames_no_door_and_a_partition_stub_does():
    """A map of a corridor 16 x 3.5 m. A plant 1.7 m across stands against its north
    wall at x 8, 1.6 m from the south wall's face: the narrowing runs from the middle of
    that wall's face, square to it, to an object wider than any wall, so it is no door
    and the corridor stays one room (the tree before the change: two rooms and a door of
    1.6 m). A partition stub 0.12 m thick hanging 1.6 m from the north wall in its place
    (the plan has it as clutter, not a wall) stands in the opening's line: a door."""
    box = [(0, 0, 16, 0), (16, 0, 16, 3.5), (16, 3.5, 0, 3.5), (0, 3.5, 0, 0)]
    poses = [(2, 1.5), (5, 1), (8, 0.9), (11, 1), (14, 1.5), (4, 2.8), (12, 2.8)]
    axes = np.array(box, dtype=np.float64)
    plant = _octagon(8.0, 3.44 - 0.86, 0.86 / np.cos(np.radians(22.5)))
    grid = dataclasses.replace(_grid(box, poses, objects=plant), scan_xy=None)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid, RoomParams())
    assert len(rooms) == 1 and len(doors) == 0
    assert 51.0 < rooms["area_m2"].iloc[0] < 54.0  # the floor less the plant's
    stub = [(7.94, 3.44, 7.94, 1.84), (7.94, 1.84, 8.06, 1.84), (8.06, 1.84, 8.06, 3.44)]
    grid = dataclasses.replace(_grid(box, poses, objects=stub), scan_xy=None)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid, RoomParams())
    assert len(rooms) == 2 and len(doors) == 1
    assert 1.5 < float(doors["width_m"].iloc[0]) < 1.9


def test_a_plant_against_a_corridor_wall_frames_no_door_on_a_turned_raster():
    """The plant of the test above with the corridor turned by 30 and by 63 degrees: the
    contact between the watershed regions follows the raster's cells, 22 to 25 degrees
    off the wall's normal, and frames no door all the same (the rule's first form asked
    the contact to run within ``door_angle_deg`` of the normal: two rooms and a door)."""
    box = [(0, 0, 16, 0), (16, 0, 16, 3.5), (16, 3.5, 0, 3.5), (0, 3.5, 0, 0)]
    poses = [(2, 1.5), (5, 1), (8, 0.9), (11, 1), (14, 1.5), (4, 2.8), (12, 2.8)]
    plant = _octagon(8.0, 3.44 - 0.86, 0.86 / np.cos(np.radians(22.5)))
    for deg in (30, 63):
        c, s = np.cos(np.radians(deg)), np.sin(np.radians(deg))
        turn = np.array([[c, -s], [s, c]])

        def turned(segs):
            return [(*(turn @ (x0, y0)), *(turn @ (x1, y1))) for x0, y0, x1, y1 in segs]

        axes = np.array(turned(box), dtype=np.float64)
        grid = dataclasses.replace(_grid(turned(box), [tuple(turn @ p) for p in poses], objects=turned(plant)),
                                   scan_xy=None)  # fmt: skip
        rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid, RoomParams())
        assert len(rooms) == 1 and len(doors) == 0, deg
        assert 51.0 < rooms["area_m2"].iloc[0] < 54.0


def test_an_outline_the_scans_reach_is_no_corridor_however_long():
    """What a recording saw of a room through its door and never entered, walled only at
    its far end (a wall 4 m wide, 7 m beyond the door; the building's outer walls run on
    north past it, out of the rays' reach), is the fan of the rays through the door:
    ``_unwalled`` finds it, not the corridor the rover drove along, and nothing in a map
    (no scans). So it does with a scan taken inside the same outline (the part of an open
    office the rover crossed: orebro's 48 m2 of desks south of Room 7 was ``Corridor 3``,
    walled on 0.34 of its edge). Such a room is a room, however long its outline
    (orebro's 4.8 m2 fan through a door was ``Corridor 5``); the same outline is a
    corridor otherwise."""
    from floorscan.floorplan.room_tables import room_tables
    from floorscan.floorplan.rooms import _unwalled

    walls = [(0, 0, 12, 0), (12, 0, 12, 10), (0, 10, 0, 0), (0, 2, 5.5, 2), (6.5, 2, 12, 2), (4, 9, 8, 9)]
    axes = np.array(walls, dtype=np.float64)
    grid = _grid(walls, [(1, 1), (3, 1), (6, 0.4), (9, 1), (11, 1)])
    raster = room_space(grid, axes, np.full(len(axes), T), RoomParams())
    ys = raster.origin_xy[1] + (np.arange(raster.space.shape[0]) + 0.5) * raster.resolution_m
    labels = np.where(raster.space, np.where(ys[:, None] < 2.0, 1, 2), 0).astype(np.int32)
    assert (labels == 2).sum() * raster.resolution_m**2 > 10.0  # the fan was seen
    assert _unwalled(raster, labels, grid.scan_xy, 2).tolist() == [False, False, True]
    entered = np.vstack([grid.scan_xy, [(6.0, 5.0)]])  # a scan taken in the fan
    assert _unwalled(raster, labels, entered, 2).tolist() == [False, False, True]
    assert not _unwalled(raster, labels, None, 2).any()
    strip = shapely.box(0, 0, 1.2, 9.0)  # 1.2 m wide, 9 m long: a corridor's outline
    for unwalled, kind in (([True], "room"), ([False], "corridor"), (None, "corridor")):
        rooms, _ = room_tables([strip], [], 0.05, RoomParams(), True, unwalled)
        assert rooms["kind"].tolist() == [kind]


def test_the_rays_through_a_gap_are_no_room_s_floor_and_a_narrow_passage_between_walls_is():
    """:func:`floorscan.floorplan.room_polygons.without_ray_strips` on a room 4 x 4 m
    walled all round (10 cm cells): a strip of its cells 0.4 m wide runs 2 m out
    through a gap in its north wall into the unseen (the rays through a gap, as orebro's
    corridor had them), and a passage 0.6 m wide runs 2 m out of its east wall between
    two walls. Beyond half a walkway (0.45 m) from the gap's jambs the strip is no floor;
    the passage, near its walls all along, stays whole, and so does the room."""
    from floorscan.floorplan.room_polygons import without_ray_strips
    from floorscan.floorplan.room_space import RoomRaster

    labels = np.zeros((90, 90), dtype=np.int32)
    walls = np.zeros(labels.shape, dtype=bool)
    labels[10:50, 10:50] = 1  # the room, x and y 1..5 m (rows up)
    walls[9, 9:51] = walls[50, 9:51] = walls[9:51, 9] = walls[9:51, 50] = True
    walls[50, 28:32] = False  # the gap in the north wall, x 2.8..3.2
    labels[50:70, 28:32] = 1  # the strip of rays through it, y 5..7
    walls[20:26, 50] = False  # the passage out of the east wall, y 2.0..2.6
    labels[20:26, 50:70] = 1
    walls[19, 50:71] = walls[26, 50:71] = True
    raster = RoomRaster(np.zeros(2), 0.1, walls, labels > 0, walls.copy(), labels == 0)
    out = without_ray_strips(raster, labels)
    gone = (labels == 1) & (out == 0)
    assert not gone[:50].any()  # the room and the passage whole
    # the strip from 0.5 m beyond the wall's row on: 15 of its 20 rows (the first 0.45
    # m lie within half a walkway of the jambs at x 2.7 and 3.2)
    assert gone[50:70, 28:32].sum() == 15 * 4 and gone.sum() == 15 * 4
    # a raster with nothing seen keeps everything (no wall to tell a strip by)
    bare = RoomRaster(np.zeros(2), 0.1, np.zeros_like(walls), labels > 0, np.zeros_like(walls), labels == 0)
    assert (without_ray_strips(bare, labels) == labels).all()


def test_a_wall_that_bounds_no_room_goes_to_the_clutter_layer():
    """The two rooms 4 x 4 m of ``TWO_ROOMS`` with a 1.2 m window in the west room's north
    wall, and through it a facade 3 m long 6 m beyond (a building across the street).
    The rays through the window are outside the building's outline, so no room lies
    beside the facade: it is no wall of the plan but clutter (``bounds_no_room``); the
    building's seven walls, their junctions and the door in the partition stay, their
    ids counted again. Without rooms the facade is a wall."""
    from floorscan.floorplan.params import FloorplanParams
    from floorscan.floorplan.plan import plan_of_segments

    walls = [(0, 0, 8, 0), (8, 0, 8, 4), (8, 4, 2.7, 4), (1.5, 4, 0, 4), (0, 4, 0, 0), (4, 0, 4, 1.5), (4, 2.4, 4, 4)]
    facade = (0.5, 10, 3.5, 10)
    grid = _grid(walls + [facade], [(2, 2), (6, 2)])
    faces = np.array(_wall_faces(walls + [facade]))  # the segments, as a map extractor gives them
    plan = plan_of_segments(faces, None, FloorplanParams(), grid)
    assert len(plan.walls) == 7 and plan.walls["y0"].max() < 4.1 and plan.walls["y1"].max() < 4.1
    lone = plan.clutter[plan.clutter["reason"] == "bounds_no_room"]
    assert len(lone) == 1 and abs(lone["y0"].iloc[0] - (10 - T / 2)) < 0.02 and abs(lone["length_m"].iloc[0] - 3) < 0.05
    assert plan.rooms["area_m2"].round(0).tolist() == [15.0, 15.0]
    door = plan.doors.iloc[0]
    assert len(plan.doors) == 1 and abs(plan.walls.loc[door["wall_id"], "x0"] - 4.0) < 0.02
    assert plan.junctions[["wall_a", "wall_b"]].to_numpy().max() < 7 and len(plan.junctions) >= 6
    assert set(plan.faces["wall_id"]) == set(range(7))
    bare = plan_of_segments(faces, None, FloorplanParams(), grid, with_rooms=False)
    assert len(bare.walls) == 8 and not (bare.clutter["reason"] == "bounds_no_room").any()


def test_a_wall_that_bounds_no_room_is_tied_by_its_line_or_a_junction():
    """:func:`floorscan.floorplan.lone_walls.apart_from_the_rooms` on four walls: a wall
    that bounds a room (0, 0)-(4, 0); a piece in its line beyond a 2 m gap and a wall
    meeting that piece's end, both bounding no room (the far walls of a space seen past
    an obstacle); a wall 5 m away in no line with them (a facade). Only the facade is
    apart: the piece by its line, the other wall by its junction with the piece."""
    from floorscan.floorplan.lone_walls import apart_from_the_rooms

    axes = np.array([(0, 0, 4, 0), (6, 0, 8, 0), (8, 0, 8, 2), (10, 5, 12, 5.5)], dtype=np.float64)
    lone = np.array([False, True, True, True])
    got = apart_from_the_rooms(lone, axes, np.full(4, T), np.array([[1, 2]]), RoomParams())
    assert got.tolist() == [False, False, False, True]
    # without the junction the wall meeting the piece is apart too; with no wall bounding a
    # room, none is (the plan keeps its walls)
    assert apart_from_the_rooms(lone, axes, np.full(4, T), np.empty((0, 2)), RoomParams()).tolist() == [
        False, False, True, True]
    assert not apart_from_the_rooms(np.ones(4, dtype=bool), axes, np.full(4, T), np.array([[1, 2]]),
                                    RoomParams()).any()


def test_a_partition_behind_a_corridor_opening_s_middle_leaves_the_offices_apart_from_the_corridor():
    """A corridor 30 m long (y 0..2.4) under offices 10 m deep; two of them (x 10..14 and
    14..18) open to it through one 6.8 m opening, their partition (x 14.15) stopping 1.5 m
    short of the corridor's side. The ray from the opening's middle runs up beside the
    partition, in a strip a few centimetres wide that never ends, as a corridor going on
    would; from a quarter and three quarters of the opening the space behind is an office,
    wider than the opening's middle, so the opening is cut on the corridor's line: the
    corridor is a room of its own and the offices two rooms. Before, the opening was not
    cut, the corridor took 5 m2 of the offices and the offices were one room of 72 m2 (on
    map_with_clutter at the map extractor's seed 10 the corridor and its offices were one
    room)."""
    from floorscan.floorplan.corridors import corridor_sides

    outer = [(0, 0, 30, 0), (30, 0, 30, 12.4), (30, 12.4, 0, 12.4), (0, 12.4, 0, 0)]
    side = [(0, 2.4, 4, 2.4), (5, 2.4, 10.6, 2.4), (17.4, 2.4, 25, 2.4), (26, 2.4, 30, 2.4)]
    partitions = [(10, 2.4, 10, 12.4), (14.15, 3.9, 14.15, 12.4), (18, 2.4, 18, 12.4)]
    walls = outer + side + partitions
    poses = [(x, 1.2) for x in range(2, 30, 3)] + [(5, 7), (12, 7), (16, 7), (24, 7), (12, 4), (16, 4)]
    axes, th = np.array(walls, dtype=np.float64), np.full(len(walls), T)
    grid = _grid(walls, poses)
    cuts = corridor_sides(axes, th, room_space(grid, axes, th, RoomParams()), RoomParams())
    wide = [(p, q) for p, q, _ in cuts if abs(p[1] - 2.4) < 0.2 and abs(q[0] - p[0]) > 5]
    assert len(wide) == 1 and sorted([wide[0][0][0], wide[0][1][0]]) == pytest.approx([10.6, 17.4], abs=0.15)
    rooms, _ = plan_rooms(axes, th, grid, RoomParams())
    corridor = rooms[rooms["kind"] == "corridor"]
    assert len(corridor) == 1 and 66 < corridor["area_m2"].iloc[0] < 70  # 30 x 2.4 m less half walls
    offices = rooms[(rooms["kind"] == "room") & rooms["area_m2"].between(30, 45)]  # 4 x 10 m less half walls
    assert len(offices) == 2

"""Partitions that stop short of a wall (floorscan.floorplan.extensions)."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from floorscan.floorplan.extensions import wall_extensions
from floorscan.floorplan.room_space import RoomParams, room_space
from floorscan.floorplan.rooms import plan_rooms
from test_rooms import T, _grid, _rooms

# A room 8 x 6 m between wall axes.
HALL = [(0, 0, 8, 0), (8, 0, 8, 6), (8, 6, 0, 6), (0, 6, 0, 0)]


def test_a_partition_that_stops_short_is_extended_to_the_wall_it_points_at():
    walls = HALL + [(4, 0, 4, 3.2)]
    axes = np.array(walls, dtype=np.float64)
    raster = room_space(_grid(walls, [(2, 3), (6, 3)]), axes, np.full(len(axes), T), RoomParams())
    (p, q, wall), = wall_extensions(axes, np.full(len(axes), T), raster, RoomParams())
    assert wall == 4
    # from the partition's end (4, 3.2) up to the north wall's face (y = 6 - T / 2)
    assert p == pytest.approx([4.0, 3.2], abs=0.1) and q == pytest.approx([4.0, 5.94], abs=0.1)


def test_a_room_wrapped_around_a_partition_longer_than_its_opening_is_two_rooms():
    # the partition is 3.2 m long, the opening 2.74 m (wider than door_max_m, 2.0)
    rooms, doors = _rooms(HALL + [(4, 0, 4, 3.2)], [(2, 3), (6, 3)])
    assert len(rooms) == 2 and len(doors) == 0
    west, east = sorted(rooms["polygon"], key=lambda p: p.centroid.x)
    assert west.bounds[2] == pytest.approx(4.0, abs=0.2) and east.bounds[0] == pytest.approx(4.0, abs=0.2)
    assert west.area == pytest.approx(east.area, rel=0.05) and 21.5 < west.area < 24.0


def test_more_opening_than_wall_leaves_one_room():
    # a partition of 2.6 m leaves 3.34 m open
    rooms, doors = _rooms(HALL + [(4, 0, 4, 2.6)], [(2, 3), (6, 3)])
    assert len(rooms) == 1 and len(doors) == 0


@pytest.mark.parametrize("length, n_rooms", [(2.92, 2), (2.85, 1)])
def test_a_partition_as_long_as_its_opening_to_a_cell_at_each_end_divides_the_room(length, n_rooms):
    # 2.92 m of partition against a 3.03 m opening: the room lies along the partition
    # for 2.85 m of cells, less than the opening by two cells (each end anywhere in its
    # cell), and is two rooms; 2.85 m against 3.10 m is more opening than wall
    rooms, doors = _rooms(HALL + [(4, 0, 4, length)], [(2, 3), (6, 3)])
    assert len(rooms) == n_rooms and len(doors) == 0
    if n_rooms == 2:
        west, east = sorted(rooms["polygon"], key=lambda p: p.centroid.x)
        assert west.bounds[2] == pytest.approx(4.0, abs=0.2) and east.bounds[0] == pytest.approx(4.0, abs=0.2)


@pytest.mark.parametrize("return_m, n_rooms", [(0.6, 2), (1.2, 1)])
def test_a_partition_ending_in_a_short_return_is_extended(return_m, n_rooms):
    # the partition (4, 0)-(4, 3.2) turns east at its end: a 0.6 m return (a jamb, a
    # cabinet's side) leaves its end free, and the hall is two rooms; a 1.2 m one is a
    # wall of the L, whose own free end points at the east wall across 2.75 m, more
    # opening than wall: one room
    walls = HALL + [(4, 0, 4, 3.2), (4, 3.2, 4 + return_m, 3.2)]
    rooms, doors = _rooms(walls, [(2, 3), (6, 2)])
    assert len(rooms) == n_rooms and len(doors) == 0
    if n_rooms == 2:
        assert sorted(rooms["area_m2"]) == pytest.approx([22.6, 23.3], abs=0.5)


@pytest.mark.parametrize("height_m, n_rooms", [(8.3, 2), (8.4, 1)])
def test_an_opening_as_wide_as_a_room_s_open_side_to_a_cell_at_each_end_is_cut(height_m, n_rooms):
    # a 4.1 m partition in a hall 8.3 m deep leaves 4.15 m open between the wall faces,
    # MOUTH_MAX_M (4.0 m) to a 0.1 m cell at each end: two rooms; 4.25 m is wider
    hall = [(0, 0, 8, 0), (8, 0, 8, height_m), (8, height_m, 0, height_m), (0, height_m, 0, 0)]
    rooms, doors = _rooms(hall + [(4, 0, 4, 4.1)], [(2, 3), (6, 3)])
    assert len(rooms) == n_rooms and len(doors) == 0


def test_a_door_beside_the_corner_of_two_furnished_rooms_parts_them():
    # a hall 5 x 5 m, a partition (2.5, 0)-(2.5, 3.6) 1.35 m short of the north wall's
    # face, and two desks in each half: the desks keep the distance to the nearest
    # obstacle as low in the rooms as in the opening, so the watershed finds no basin on
    # each side of it; the partition's extension is a door
    hall = [(0, 0, 5, 0), (5, 0, 5, 5), (5, 5, 0, 5), (0, 5, 0, 0)]
    walls = hall + [(2.5, 0, 2.5, 3.6)]

    def desk(x0, y0):
        return [(x0, y0, x0 + 0.8, y0), (x0 + 0.8, y0, x0 + 0.8, y0 + 1), (x0 + 0.8, y0 + 1, x0, y0 + 1),
                (x0, y0 + 1, x0, y0)]  # fmt: skip

    desks = desk(0.8, 1.0) + desk(3.4, 1.0) + desk(0.8, 3.0) + desk(3.4, 3.0)
    axes = np.array(walls, dtype=np.float64)
    grid = _grid(walls, [(1.25, 2.5), (3.75, 2.5)], objects=desks)
    rooms, doors = plan_rooms(axes, np.full(len(axes), T), grid, RoomParams())
    assert len(rooms) == 2 and len(doors) == 1
    door = doors.iloc[0]
    assert door["x0"] == pytest.approx(2.5, abs=0.1) and door["x1"] == pytest.approx(2.5, abs=0.1)
    assert sorted([door["y0"], door["y1"]]) == pytest.approx([3.65, 4.95], abs=0.15)


def test_a_free_standing_wall_does_not_divide_its_hall():
    # both ends stand 2.5 m from the hall's walls: the hall goes on around either end
    walls = [(0, 0, 10, 0), (10, 0, 10, 8), (10, 8, 0, 8), (0, 8, 0, 0), (5, 2.5, 5, 5.5)]
    axes = np.array(walls, dtype=np.float64)
    raster = room_space(_grid(walls, [(2.5, 4), (7.5, 4)]), axes, np.full(len(axes), T), RoomParams())
    assert len(wall_extensions(axes, np.full(len(axes), T), raster, RoomParams())) == 2
    rooms, _ = _rooms(walls, [(2.5, 4), (7.5, 4)])
    assert len(rooms) == 1


def test_a_corridor_is_not_cut_on_the_line_of_a_partition_between_its_offices():
    # a 2.6 m corridor (y 0..2.6) under two offices split at x = 4 by a partition whose
    # end stands free in a 0.6 m slit of the corridor wall; a door into each office
    walls = [(0, 0, 8, 0), (8, 0, 8, 5.6), (8, 5.6, 0, 5.6), (0, 5.6, 0, 0),
             (0, 2.6, 1.5, 2.6), (2.4, 2.6, 3.7, 2.6), (4.3, 2.6, 5.5, 2.6), (6.4, 2.6, 8, 2.6),
             (4, 5.6, 4, 2.6)]  # fmt: skip
    poses = [(1, 1.3), (4, 1.3), (7, 1.3), (2, 4), (6, 4), (1.95, 2.4), (5.95, 2.4)]
    axes = np.array(walls, dtype=np.float64)
    raster = room_space(_grid(walls, poses), axes, np.full(len(axes), T), RoomParams())
    assert [w for _, _, w in wall_extensions(axes, np.full(len(axes), T), raster, RoomParams())] == [8]
    rooms, doors = _rooms(walls, poses)
    assert len(rooms) == 3 and len(doors) == 2
    corridor = next(p for p in rooms["polygon"] if p.contains(shapely.Point(4, 1.3)))
    assert corridor.bounds[0] < 0.2 and corridor.bounds[2] > 7.8 and 18.5 < corridor.area < 20.5


def test_a_corridor_wall_that_stops_short_of_a_room_beside_it_parts_the_room_from_the_corridor():
    # a 2 m corridor (y 0..2) whose north wall (x 3..7) stops 3 m short of the east wall;
    # room A (x 0..5.5) behind it, its door at x 2..3, and an office (x 5.5..10) open
    # onto the corridor from x 7 to 10. The corridor lies along the wall's south face
    # for 4 m, the office on its north face for 1.5 m only: the wall bounds the room
    # more than the opening does, and the office is a room of its own.
    walls = [(0, 0, 10, 0), (10, 0, 10, 6), (10, 6, 0, 6), (0, 6, 0, 0),
             (0, 2, 2, 2), (3, 2, 7, 2), (5.5, 2, 5.5, 6)]  # fmt: skip
    seeds = [(1, 1), (5, 1), (9, 1), (2.5, 4), (8, 4)]
    axes = np.array(walls, dtype=np.float64)
    raster = room_space(_grid(walls, seeds), axes, np.full(len(axes), T), RoomParams())
    exts = wall_extensions(axes, np.full(len(axes), T), raster, RoomParams())
    assert [w for _, _, w in exts] == [5]
    rooms, doors = _rooms(walls, seeds)
    assert len(rooms) == 3 and len(doors) == 1

    def room_of(x, y):
        return [k for k, p in enumerate(rooms["polygon"]) if p.contains(shapely.Point(x, y))]

    assert room_of(8, 4) != room_of(9, 1)
    office = rooms["polygon"].iloc[room_of(8, 4)[0]]
    assert office.bounds == pytest.approx((5.5, 2.0, 10.0, 6.0), abs=0.15)

"""The building's closed outline in a recording (floorscan.floorplan.outline): the
smallest closing that holds the rover's path, on a 20 m x 20 m raster of 0.1 m cells
with a 10 m x 10 m building whose east wall has a gap."""

from __future__ import annotations

import numpy as np
import pytest

from floorscan.floorplan.outline import building_outside, regions_beyond

RES = 0.1


def _building(gap_m: float) -> np.ndarray:
    """(200, 200) bool: the walls (0.2 m) of the box (5, 5)-(15, 15), metres, with a
    gap of ``gap_m`` centred at y = 10 in its east wall."""
    solid = np.zeros((200, 200), dtype=bool)
    solid[49:151, 49:51] = solid[49:151, 149:151] = True  # west, east
    solid[49:51, 49:151] = solid[149:151, 49:151] = True  # south, north
    half = int(round(gap_m / 2 / RES))
    solid[100 - half : 100 + half, 149:151] = False
    return solid


def _at(cells: np.ndarray, x: float, y: float) -> bool:
    return bool(cells[int(y / RES), int(x / RES)])


def test_a_gap_no_wider_than_a_door_is_closed_at_the_door_width():
    solid = _building(1.0)
    outside, beyond, d = building_outside(solid, RES, np.zeros(2), np.array([[10.0, 10.0], [8.0, 12.0]]), 2.0)
    assert d == 2.0
    assert _at(outside, 18.0, 10.0) and _at(outside, 16.6, 10.0)  # beyond the gap, a fan's place
    assert not _at(outside, 10.0, 10.0) and not _at(outside, 14.0, 10.0)
    assert not _at(beyond, 14.5, 10.0) and _at(beyond, 15.6, 10.0)  # grown back to the wall's face
    assert not beyond[55:145, 55:145].any()  # nothing of the room


def test_a_wide_gap_is_closed_by_the_smallest_disc_that_holds_the_path():
    solid = _building(5.0)
    outside, beyond, d = building_outside(solid, RES, np.zeros(2), np.array([[10.0, 10.0]]), 2.0)
    assert 4.9 <= d <= 5.1 + RES  # the gap, within a cell
    assert not _at(outside, 10.0, 10.0) and _at(outside, 19.0, 10.0)
    # the closing's round end reaches into the room at the gap, up to half the diameter
    assert _at(beyond, 14.0, 10.0) and not _at(beyond, 12.0, 10.0)


def test_a_rover_outside_the_building_widens_the_closing_and_a_map_has_none():
    solid = _building(1.0)
    outside, beyond, d = building_outside(solid, RES, np.zeros(2), np.array([[10.0, 10.0], [2.0, 2.0]]), 2.0)
    # (2, 2) is 4.2 m from the building's corner: held once the disc is 8.4 m
    assert 8.0 <= d <= 8.5 and not beyond[50:150, 50:150].any() and not outside[45:155, 45:155].any()
    outside, beyond, d = building_outside(solid, RES, np.zeros(2), None, 2.0)  # a map
    assert d == float("inf") and not outside.any()


def test_regions_beyond_the_outline_by_their_majority():
    labels = np.zeros((4, 10), dtype=np.int32)
    labels[:, :5], labels[:, 5:] = 1, 2
    beyond = np.zeros_like(labels, dtype=bool)
    beyond[:, 3:] = True  # 2 of region 1's 5 columns, all of region 2
    assert regions_beyond(labels, beyond).tolist() == [False, False, True]
    assert regions_beyond(np.zeros((3, 3), dtype=np.int32), np.ones((3, 3), dtype=bool)).tolist() == [False]


@pytest.mark.parametrize("gap_m", [1.0, 3.0])
def test_the_outline_follows_the_building_when_shifted_by_whole_cells(gap_m):
    solid = _building(gap_m)
    shifted = np.roll(solid, (7, -4), axis=(0, 1))
    a = building_outside(solid, RES, np.zeros(2), np.array([[10.0, 10.0]]), 2.0)
    b = building_outside(shifted, RES, np.array([0.4, -0.7]), np.array([[10.0, 10.0]]), 2.0)
    assert a[2] == pytest.approx(b[2], abs=RES)
    assert np.array_equal(np.roll(a[0], (7, -4), axis=(0, 1))[20:180, 20:180], b[0][20:180, 20:180])


def test_a_courtyard_seen_through_windows_is_outside_and_a_room_seen_through_its_door_is_not():
    """A ring building around a 4 m x 4 m courtyard (walls at 8 and 12 m, a 1 m window
    in its east side), and a 3 m x 3 m room (walls at 1 and 4 m) the rover never entered,
    seen whole through its 1 m door: the rover in the ring; of the courtyard the scans
    saw a fan through the window."""
    solid = _building(0.0)
    solid[79:121, 79:81] = solid[79:121, 119:121] = solid[79:81, 79:121] = solid[119:121, 79:121] = True
    solid[95:105, 119:121] = False  # the window
    solid[9:41, 9:11] = solid[9:41, 39:41] = solid[9:11, 9:41] = solid[39:41, 9:41] = True
    solid[39:41, 20:30] = False  # the room's door (north)
    seen = np.zeros_like(solid)
    seen[51:149, 51:149] = True
    seen[81:119, 81:119] = False
    seen[96:104, 100:119] = True  # the fan through the window
    seen[11:39, 11:39] = True  # the room
    outside, beyond, d = building_outside(solid, RES, np.zeros(2), np.array([[6.0, 6.0], [6.0, 14.0]]), 2.0, seen=seen)
    assert d == 2.0
    assert _at(outside, 10.0, 10.0) and _at(outside, 11.0, 10.0)  # the courtyard and its fan
    assert not _at(outside, 2.5, 2.5) and not _at(beyond, 2.5, 2.5)  # the room
    assert not _at(outside, 6.0, 10.0)  # the ring
    outside, _, _ = building_outside(solid, RES, np.zeros(2), np.array([[6.0, 6.0]]), 2.0)
    assert not _at(outside, 10.0, 10.0)  # without what was seen: the courtyard is inside


def test_a_room_seen_through_its_door_whose_far_wall_is_missing_stays_inside_the_walls_hull():
    """The box with an inner wall at y = 12 m (a 1 m door at x = 10 m) and a 4 m gap in
    its north wall; the rover south of the inner wall. The closing holds the rover at
    the door's width and leaks into the north room through the gap: outside, unless the
    convex hull of the walls bounds what the border reaches."""
    solid = _building(0.0)
    solid[119:121, 49:151] = True
    solid[119:121, 95:105] = False  # the door
    solid[149:151, 80:120] = False  # the gap in the north wall
    scans = np.array([[10.0, 8.0], [7.0, 7.0]])
    outside, _, d = building_outside(solid, RES, np.zeros(2), scans, 2.0)
    assert d == 2.0 and _at(outside, 10.0, 13.5) and _at(outside, 10.0, 17.0)
    outside, beyond, d = building_outside(solid, RES, np.zeros(2), scans, 2.0, walls=solid)
    assert d == 2.0 and not _at(outside, 10.0, 13.5) and not _at(beyond, 10.0, 13.5)
    assert _at(outside, 10.0, 17.0) and _at(outside, 2.0, 10.0)  # beyond the hull


def test_beyond_the_walls_hull_the_parts_the_rover_never_entered_are_outside():
    """A 5 m gap and a rover that drove to 1.5 m of it: the closing that holds the rover
    is as wide as the gap, and its round ends leave the mouth of the fan outside the gap
    to the building. Beyond the convex hull of the building's walls the parts the rover
    never entered are outside all the same; where it drove out they stay."""
    solid = _building(5.0)
    walls = solid.copy()
    inside_only = np.array([[10.0, 10.0], [13.5, 10.0]])
    outside, beyond, d = building_outside(solid, RES, np.zeros(2), inside_only, 2.0, walls=walls)
    assert _at(outside, 15.5, 10.0) and _at(outside, 16.0, 12.0)  # just past the gap, in the fan's mouth
    assert not _at(outside, 14.5, 10.0) and not outside[52:148, 52:148].any()  # the building stays
    drove_out = np.array([[10.0, 10.0], [17.0, 10.0]])
    outside, _, _ = building_outside(solid, RES, np.zeros(2), drove_out, 2.0, walls=walls)
    assert not _at(outside, 17.0, 10.0) and not _at(outside, 15.5, 10.0)


def test_a_facade_seen_through_a_window_at_the_raster_s_edge_is_no_wall_of_the_building():
    """The box (its own walls, ``walls``) with a 1.2 m window in its east wall, and
    through it a facade 3 m beyond: a wall 4 m long, two cells from the raster's east
    edge, as a room raster cut to what the scans saw leaves it. The border reaches
    around the facade as around any wall: the facade is no wall of the building, so the
    fan of rays through the window is outside. With a margin of one cell, the cells
    behind the facade were out of the border's reach, so the facade was the building's
    and the fan inside its walls' hull."""
    solid = _building(1.2)[:, :185]  # the raster ends 2 cells east of the facade
    walls = solid.copy()
    solid[80:120, 181:183] = True  # the facade, x 18.1-18.3 m
    seen = np.zeros_like(solid)
    seen[51:149, 51:149] = True
    seen[94:106, 149:181] = True  # the fan through the window
    outside, beyond, d = building_outside(solid, RES, np.zeros(2), np.array([[10.0, 10.0]]), 2.0, seen=seen,
                                          walls=walls | solid)
    assert d == 2.0
    assert _at(outside, 16.5, 10.0) and _at(outside, 17.0, 9.5) and _at(beyond, 17.8, 10.0)  # the fan
    assert not _at(outside, 10.0, 10.0) and not _at(beyond, 14.0, 10.0)  # the room

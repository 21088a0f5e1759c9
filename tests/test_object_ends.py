"""Faces that end in an object's body (:func:`floorscan.floorplan.object_ends.object_ends`)
on hand-made grids of 5 cm: a room 4 m square, its west wall along x = 0."""

from __future__ import annotations

import numpy as np

from floorscan.core.occupancy_classes import grid_of_classes
from floorscan.floorplan.free_space import passable
from floorscan.floorplan.object_ends import object_ends

R = 0.05
#: The room's west wall face (x = 0.05 m), and a face from it into the room along
#: y = 1 m to x = 0.8 m, held by the wall at x = 0.05 m (a T: its end on the wall).
WALL = [0.05, -0.5, 0.05, 3.5]
SIDE = [0.05, 1.0, 0.8, 1.0]


def room(body=None, inside_seen=False, east_wall_x=None, unseen=None):
    """The room's grid: the west wall's cells (0.1 m, about x = 0) occupied, the room
    east of it free, the outside unknown; ``body`` (x0, x1, y0, y1, metres) an object's
    cells, its outline a cell wide occupied, its inside unknown (occupied with
    ``inside_seen``); ``east_wall_x`` a wall's cells across the room at that x;
    ``unseen`` (x0, x1, y0, y1, metres) cells neither free nor occupied."""
    n = int(round(5.0 / R))
    x = (np.arange(n) + 0.5) * R - 0.5  # cell centres, metres, origin at -0.5 m
    xx, yy = np.meshgrid(x, x)
    occupied = (np.abs(xx) <= 0.05) & (yy >= -0.5) & (yy <= 3.5)
    free = (xx > 0.05) & (xx < 4.0) & (yy > -0.5) & (yy < 3.5)
    if east_wall_x is not None:
        occupied |= (np.abs(xx - east_wall_x) <= 0.05) & (yy >= -0.5) & (yy <= 3.5)
        free &= xx < east_wall_x - 0.05
    if body is not None:
        x0, x1, y0, y1 = body
        cells = (xx >= x0) & (xx <= x1) & (yy >= y0) & (yy <= y1)
        inner = (xx >= x0 + R) & (xx <= x1 - R) & (yy >= y0 + R) & (yy <= y1 - R)
        occupied |= cells & ~inner | (cells if inside_seen else False)
        free &= ~cells
    if unseen is not None:
        x0, x1, y0, y1 = unseen
        free &= ~((xx >= x0) & (xx <= x1) & (yy >= y0) & (yy <= y1))
    occupied &= ~free
    return grid_of_classes(occupied, free, origin_xy=(-0.5, -0.5), resolution_m=R)


def judged(grid, faces=(WALL, SIDE), junctions=()):
    """``object_ends`` on ``faces``, the side face held at its first end by the wall,
    with ``junctions`` besides."""
    seg = np.array(faces, dtype=np.float64)
    ends = np.zeros((len(seg), 2), dtype=bool)
    ends[1, 0] = True
    junctions = np.array([[0.05, 1.0, 0, 1, 2], *junctions])  # the side's end on the wall face (a T)
    return object_ends(seg, ends, junctions, passable(grid), grid.occupied(), grid).tolist()


def test_the_side_of_a_desk_against_a_wall_is_furniture():
    """A desk 0.75 m deep from the wall and 0.45 m wide, its outline seen and its inside
    not: the side face ends in a body thicker than a wall, with the room beyond it."""
    assert judged(room(body=(0.05, 0.8, 1.0, 1.45))) == [False, True]


def test_a_body_seen_occupied_throughout_is_a_wall():
    """The same body seen occupied throughout (a pier drawn solid, as the room
    benchmarks draw their walls) is a thick wall's end."""
    assert judged(room(body=(0.05, 0.8, 1.0, 1.45), inside_seen=True)) == [False, False]


def test_a_partition_as_thick_as_a_wall_is_a_wall():
    """A partition 0.2 m thick, seen free on both sides, its inside unseen: its end is a
    wall's."""
    assert judged(room(body=(0.05, 0.8, 0.9, 1.1))) == [False, False]


def test_a_body_deeper_than_a_cabinet_is_no_object():
    """A body 1.2 m wide (deeper than a desk or a cabinet, ``front_max_m``): the unseen
    beyond a wall, not an object."""
    assert judged(room(body=(0.05, 0.8, 1.0, 2.2))) == [False, False]


def test_a_thick_partition_that_points_at_the_wall_across_its_door_is_a_wall():
    """The desk's body and face, with a wall 0.9 m beyond the face's free end: the face
    is the jamb of a door in a partition, however thick."""
    grid = room(body=(0.05, 0.8, 1.0, 1.45), east_wall_x=1.75)
    assert judged(grid, (WALL, SIDE, [1.7, -0.5, 1.7, 3.5])) == [False, False, False]
    # without the wall's face in the plan, the same cells are a desk's
    assert judged(grid) == [False, True]


def test_a_face_along_the_unseen_beyond_a_wall_is_a_wall():
    """The body at the face's free end is a desk's, but behind the rest of the face the
    unseen runs on past a cabinet's depth: the face bounds the unseen beyond a wall (an
    outer wall's step with a column in its corner), not an object."""
    grid = room(body=(0.6, 0.8, 1.0, 1.45), unseen=(0.05, 0.55, 1.0, 3.5))
    assert judged(grid) == [False, False]


def test_a_face_another_wall_ends_on_is_a_wall():
    """The desk's side with a partition ending on it between its ends (a T): tied into
    the walls there."""
    grid = room(body=(0.05, 0.8, 1.0, 1.45))
    got = judged(grid, (WALL, SIDE, [0.4, 1.0, 0.4, 0.2]), [[0.4, 1.0, 1, 2, 2]])
    assert got == [False, False, False]


def test_a_face_in_the_line_of_a_wall_beyond_its_end_is_a_wall():
    """The desk's side with a wall face in its line 1 m past its free end: a piece of a
    wall with a door between, as a door's jambs stand in one line."""
    grid = room(body=(0.05, 0.8, 1.0, 1.45))
    assert judged(grid, (WALL, SIDE, [1.8, 1.0, 3.5, 1.0])) == [False, False, False]

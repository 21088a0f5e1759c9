"""The frames of the openings at the walls' free ends
(:func:`floorscan.floorplan.door_frames.framed_openings`) on hand-made grids of 5 cm."""

from __future__ import annotations

import numpy as np
import pytest

from floorscan.core.occupancy_classes import grid_of_classes
from floorscan.floorplan.door_frames import framed_doors, framed_openings
from floorscan.floorplan.params import FloorplanParams

R = 0.05
PARAMS = FloorplanParams()


def entrance_grid():
    """A south wall along y = 0 (cells 0.1 m thick) from x = 0 to 3 m with an entrance
    from x = 1.1 to 2.0 m; the east wall along x = 3 m; free space north of the south
    wall and in the entrance; the outside unknown."""
    n = int(round(4.0 / R))
    occupied, free = np.zeros((n, n), bool), np.zeros((n, n), bool)
    x = (np.arange(n) + 0.5) * R - 0.5  # cell centres, metres, origin at -0.5 m
    xx, yy = np.meshgrid(x, x)
    wall = (np.abs(yy) <= 0.05) & (xx >= -0.05) & (xx <= 3.05) & ~((xx > 1.1) & (xx < 2.0))
    wall |= (np.abs(xx - 3.0) <= 0.05) & (yy >= -0.05) & (yy <= 3.0)
    wall |= (np.abs(xx) <= 0.05) & (yy >= -0.05) & (yy <= 3.0)
    occupied[wall] = True
    free[~wall & (xx > 0.05) & (xx < 2.95) & (yy > -0.05) & (yy < 3.0)] = True
    return grid_of_classes(occupied, free, origin_xy=(-0.5, -0.5), resolution_m=R)


def test_the_stub_between_an_entrance_and_a_corner_is_a_wall():
    """The south wall's piece west of the entrance is a wall tied to the west wall; the
    1 m piece east of it (cells only, no wall of the plan) is a new wall from the east
    wall's axis to the entrance's jamb."""
    axes = np.array([[0.0, 0.0, 1.1, 0.0], [0.0, 0.0, 0.0, 3.0], [3.0, 0.0, 3.0, 3.0]])
    thickness = np.full(3, 0.1)
    got, stubs, t, meets = framed_openings(axes, thickness, entrance_grid(), PARAMS.rooms, 1.0)
    np.testing.assert_array_equal(got, axes)
    assert stubs.shape == (1, 4) and meets.tolist() == [2] and t.tolist() == [0.1]
    assert stubs[0, :2] == pytest.approx([3.0, 0.0], abs=1e-9)  # on the east wall's axis
    assert stubs[0, 2:] == pytest.approx([2.0, 0.0], abs=R)  # at the jamb


def test_a_collinear_wall_beyond_an_entrance_goes_on_to_its_jamb():
    """With a piece of the south wall east of the entrance shorter than the cells show
    (from x = 2.6 m), that piece goes on to the jamb instead: longer, no new wall."""
    axes = np.array([[0.0, 0.0, 1.1, 0.0], [0.0, 0.0, 0.0, 3.0], [3.0, 0.0, 3.0, 3.0], [2.6, 0.0, 3.0, 0.0]])
    thickness = np.full(4, 0.1)
    got, stubs, _, _ = framed_openings(axes, thickness, entrance_grid(), PARAMS.rooms, 1.0)
    assert len(stubs) == 0
    np.testing.assert_array_equal(got[:3], axes[:3])
    assert got[3, :2] == pytest.approx([2.0, 0.0], abs=R) and got[3, 2:].tolist() == [3.0, 0.0]


def test_a_wall_free_at_both_ends_frames_nothing():
    """The south wall's west piece not tied to any wall (the west wall left out): a
    piece of furniture or a fragment, whose ends frame nothing."""
    axes = np.array([[0.3, 0.0, 1.1, 0.0], [3.0, 0.0, 3.0, 3.0]])
    got, stubs, _, _ = framed_openings(axes, np.full(2, 0.1), entrance_grid(), PARAMS.rooms, 1.0)
    assert len(stubs) == 0
    np.testing.assert_array_equal(got, axes)


def test_a_line_that_meets_a_wall_at_a_slant_frames_nothing():
    """A partition 22 degrees off the east wall's direction, tied to the south wall,
    whose free end is 1 m (along its line) from the east wall's cells, 0.2 m thick
    about an axis of 0.1 m: its line crosses 0.35 m of the east wall's own cells before
    it reaches the wall's footprint. That is no stub: it stands out of the wall by less
    than two cells beyond the wall's face."""
    n = 80
    x = (np.arange(n) + 0.5) * R - 0.5
    xx, yy = np.meshgrid(x, x)
    u = np.array([np.sin(np.radians(22.0)), np.cos(np.radians(22.0))])
    end = np.array([3.0 - 0.1 - 1.0 * u[0], 1.2])
    start = end - u * (end[1] / u[1])  # on the south wall's axis
    occupied = (np.abs(yy) <= 0.05) & (xx >= -0.05) & (xx <= 3.05)
    occupied |= (np.abs(xx - 3.0) <= 0.1) & (yy >= -0.05) & (yy <= 3.3)
    t = np.clip((xx - start[0]) * u[0] + (yy - start[1]) * u[1], 0.0, float(np.hypot(*(end - start))))
    occupied |= np.hypot(xx - start[0] - t * u[0], yy - start[1] - t * u[1]) <= 0.05
    free = ~occupied & (xx > 0.05) & (xx < 2.9) & (yy > 0.05) & (yy < 3.3)
    grid = grid_of_classes(occupied, free, origin_xy=(-0.5, -0.5), resolution_m=R)
    axes = np.array([[0.0, 0.0, 3.0, 0.0], [3.0, 0.0, 3.0, 3.3], [*start, *end]])
    got, stubs, _, _ = framed_openings(axes, np.full(3, 0.1), grid, PARAMS.rooms, 0.5)
    assert len(stubs) == 0
    np.testing.assert_array_equal(got, axes)


def crossing_grid():
    """A wall along x = 2 m (cells 0.1 m thick) from y = 0 to 4 m, crossed along y = 2 m
    by a wall whose cells run from x = 0 to 1 m, from 1.6 to 2.4 m and from 3 to 4 m:
    a door on either side of the crossing, 0.35 m of wall between each door and the
    crossing wall's face; free space around."""
    n = int(round(5.0 / R))
    x = (np.arange(n) + 0.5) * R - 0.5
    xx, yy = np.meshgrid(x, x)
    across = (np.abs(yy - 2.0) <= 0.05) & ((xx <= 1.0) | ((xx >= 1.6) & (xx <= 2.4)) | (xx >= 3.0))
    occupied = ((np.abs(xx - 2.0) <= 0.05) & (yy >= 0.0) & (yy <= 4.0)) | (across & (xx >= 0.0) & (xx <= 4.0))
    free = ~occupied & (xx > -0.4) & (xx < 4.4) & (yy > -0.4) & (yy < 4.4)
    return grid_of_classes(occupied, free, origin_xy=(-0.5, -0.5), resolution_m=R)


@pytest.mark.parametrize("min_wall_length_m", [0.5, 0.3])
def test_the_stubs_of_two_doors_either_side_of_a_crossing_are_one_wall_across_it(min_wall_length_m):
    """The two 0.35 m pieces between the doors and the crossing wall are one wall from
    jamb to jamb across it, as a map turned by another angle traces it, not two walls
    ending at its axis; the doors are cut back to their jambs. So too where the pieces
    are a cell longer than the shortest wall (0.3 m): traced at another pose, they may
    have fallen under it (door_frames.LENGTH_CELLS)."""
    axes = np.array([[0.0, 2.0, 1.0, 2.0], [3.0, 2.0, 4.0, 2.0], [2.0, 0.0, 2.0, 4.0]])
    doors = np.array([[1.0, 2.0, 2.0, 2.0], [3.0, 2.0, 2.0, 2.0]])
    got_doors, got, stubs, t, meets = framed_doors(doors, np.array([0, 1]), axes, np.full(3, 0.1), crossing_grid(),
                                                   PARAMS.rooms, min_wall_length_m)
    np.testing.assert_array_equal(got, axes)
    assert stubs.shape == (1, 4) and meets.tolist() == [2] and t.tolist() == [0.1]
    assert sorted([stubs[0, 0], stubs[0, 2]]) == pytest.approx([1.6, 2.4], abs=R)  # jamb to jamb
    assert stubs[0, [1, 3]] == pytest.approx([2.0, 2.0], abs=1e-9)
    assert got_doors[:, [0, 2]].ravel() == pytest.approx([1.0, 1.6, 3.0, 2.4], abs=R)

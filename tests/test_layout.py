"""The candidate global layout of issue 44 (floorscan.floorplan.layout): the cell complex
of the plan's walls and of the map's own wall lines
(floorscan.floorplan.representative_lines), labelled inside and grouped into rooms by the
evidence of a wall on the boundaries between cells. Measured beside today's room step by ``python -m
benchmarks rooms --rooms layout`` (benchmarks/README.md); here its steps on known
geometry."""

import numpy as np
import pytest
from shapely.geometry import box

from floorscan.core.occupancy_classes import grid_of_classes
from floorscan.floorplan.arrangement import layout_cells
from floorscan.floorplan.hypotheses import CLOSED, OPEN, WALL, dominant_axes, layout_lines, snapped_axes
from floorscan.floorplan.labelling import group_cells
from floorscan.floorplan.layout import layout_rooms
from floorscan.floorplan.room_space import RoomParams

RES = 0.05
T = 0.2


def two_rooms(shift=(0.0, 0.0), door=0.9):
    """Two 5 x 5 m rooms side by side (outer walls 10 x 5 m, axes on the faces' middle),
    a door of ``door`` metres in the middle wall; the map of their free space and walls
    on 5 cm cells; everything moved by ``shift`` metres."""
    sx, sy = shift
    h = T / 2
    axes = np.array([
        [0, 0, 10, 0], [10, 0, 10, 5], [10, 5, 0, 5], [0, 5, 0, 0],   # the outline
        [5, 0, 5, 2.5 - door / 2], [5, 2.5 + door / 2, 5, 5],         # the middle wall, its door
    ], dtype=float) + [sx, sy, sx, sy]  # fmt: skip
    thickness = np.full(len(axes), T)
    ox, oy = -1.0 + sx, -1.0 + sy
    x = ox + (np.arange(240) + 0.5) * RES
    y = oy + (np.arange(140) + 0.5) * RES
    X, Y = np.meshgrid(x - sx, y - sy)
    inside = (X > -h) & (X < 10 + h) & (Y > -h) & (Y < 5 + h)
    wall = inside & ((X < h) | (X > 10 - h) | (Y < h) | (Y > 5 - h) | ((np.abs(X - 5) < h) & (np.abs(Y - 2.5) > door / 2)))
    grid = grid_of_classes(wall, inside & ~wall, (ox, oy), RES)
    return axes, thickness, grid


def test_two_rooms_and_their_door():
    axes, thickness, grid = two_rooms()
    polys, doors = layout_rooms(axes, thickness, grid, RoomParams())
    assert len(polys) == 2 and len(doors) == 1
    np.testing.assert_allclose(sorted(p.area for p in polys), [4.8 * 4.8] * 2, rtol=0.01)  # to the wall faces
    p, q, wall, a, b = doors[0]
    assert (wall, a, b) == (4, 0, 1)
    np.testing.assert_allclose(np.hypot(*(q - p)), 0.9, atol=1e-6)
    assert not polys[0].intersects(polys[1].buffer(-1e-6))  # a coverage: no overlap


def test_a_passage_wider_than_a_door_joins_the_rooms():
    axes, thickness, grid = two_rooms(door=3.5)  # the middle wall is 2 x 0.75 m: more opening than wall
    polys, doors = layout_rooms(axes, thickness, grid, RoomParams())
    assert len(polys) == 1 and doors == []


@pytest.mark.parametrize("shift", [(0.0, 0.0), (0.013, 0.0371), (-0.0249, 0.0117), (1234.567, -89.0123)])
def test_the_same_layout_under_a_shift(shift):
    """A sub-cell (or a large) shift of walls and map gives the same rooms and door, moved:
    the complex is noded on a fixed precision grid."""
    axes, thickness, grid = two_rooms(shift)
    polys, doors = layout_rooms(axes, thickness, grid, RoomParams())
    assert len(polys) == 2 and len(doors) == 1
    c = sorted((p.centroid.x - shift[0], p.centroid.y - shift[1]) for p in polys)
    np.testing.assert_allclose(c, [(2.5, 2.5), (7.5, 2.5)], atol=0.03)


def test_hypotheses_close_gaps_and_extend_free_ends():
    axes, thickness, _ = two_rooms()
    lines, kinds, gaps = layout_lines(axes, thickness, box(-1, -1, 11, 6), door_max_m=2.0)
    assert kinds[:6] == [WALL] * 6
    # each jamb of the door extends across it to the other: a closed opening, 0.9 m
    assert kinds[6:].count(CLOSED) == 2 and kinds.count(OPEN) == 0
    assert sorted(round(g[3], 6) for g in gaps) == [0.9, 0.9]
    cells, edges = layout_cells(lines, kinds)
    assert len(cells) == 3  # two rooms and the outside, within the frame
    assert all(closed == length for a, b, length, closed in edges)  # every edge is wall or closed


def test_junctions_snap_and_directions_turn():
    # an L whose ends stop 4 cm short of each other, a T 6 cm short, one wall 1.5 degrees off
    axes = np.array([[0, 0, 3.96, 0], [4, 0.04, 4, 3], [2, 0.06, 2, 2], [0, 3, 3, 3.0785]], float)
    snapped, free = snapped_axes(axes, np.full(4, 0.1))
    np.testing.assert_allclose(snapped[0, 2:], snapped[1, :2])  # the corner: one point
    assert not free[0, 1] and not free[1, 0] and not free[2, 0] and free[2, 1]
    from shapely.geometry import LineString, Point

    # the T's end moved onto the (moved) wall's axis, a millimetre past it
    assert LineString(snapped[0].reshape(2, 2)).distance(Point(snapped[2, :2])) < 2e-3
    turned = dominant_axes(axes)
    angle = [np.arctan2(*(turned[k, 2:] - turned[k, :2])[::-1]) for k in (0, 3)]
    assert abs(angle[0] - angle[1]) < 1e-9  # the two near-horizontal walls on one direction ...
    assert 0 < angle[0] < np.deg2rad(1.5)  # ... their length-weighted mean
    np.testing.assert_allclose(turned[3, :2] + turned[3, 2:], axes[3, :2] + axes[3, 2:])  # about its midpoint


def test_grouping_by_boundary_evidence():
    # four cells in a row: 0|1 no evidence, 1|2 all wall, 2|3 a third wall; cell 4 outside
    inside = np.array([True, True, True, True, False])
    edges = [(0, 1, 3.0, 0.0), (1, 2, 3.0, 3.0), (2, 3, 3.0, 1.0), (3, 4, 3.0, 3.0)]
    region = group_cells(inside, edges, np.full(5, 10.0), min_area_m2=2.0)
    assert region[0] == region[1] and region[2] == region[3] and region[1] != region[2] and region[4] == -1


def test_an_opening_next_to_a_junction_is_closed():
    """The outer wall's piece that ends where an inner wall meets it still goes on in its
    line past the entrance: the opening between the junction and the next piece is closed."""
    axes = np.array([[0, 0, 6, 0], [6, 0, 6, 5], [6, 5, 0, 5], [0, 5, 0, 3.5], [0, 2.5, 0, 0], [0, 2.5, 4, 2.5]], float)
    lines, kinds, gaps = layout_lines(axes, np.full(6, 0.2), box(-1, -1, 7, 6), door_max_m=2.0)
    entrance = sorted((g[2], round(g[3], 6)) for g in gaps if abs(g[0][0]) < 1e-9 and abs(g[1][0]) < 1e-9)
    assert entrance == [(3, 1.0), (4, 1.0)]  # from each side; a door is taken once (layout_rooms)
    assert [(g[2], round(g[3], 6)) for g in gaps if g[2] == 5] == [(5, 1.9)]  # the inner wall's free end


def test_grouping_joins_the_longest_open_boundary_first():
    """A cell cut out of a corridor by a line (cell 2) whose only boundary with an office
    (cell 3) is the office's door: the corridor's cells join first (their open boundary
    is longer), so the corridor then meets the office along wall and door together
    (3 m wall, 1 m door) and they stay apart; joined by least evidence first, the door
    cell would have joined office and corridor."""
    inside = np.ones(4, dtype=bool)
    edges = [(0, 1, 4.0, 0.0), (1, 2, 2.0, 0.0), (2, 3, 1.0, 0.0), (1, 3, 3.0, 3.0)]
    region = group_cells(inside, edges, np.full(4, 10.0), min_area_m2=2.0)
    assert region[0] == region[1] == region[2] != region[3]


def _grid_of(occupied_cells, shape, free_everywhere_else=True):
    wall = np.zeros(shape, dtype=bool)
    wall[tuple(np.asarray(occupied_cells).T)] = True
    return grid_of_classes(wall, ~wall if free_everywhere_else else np.zeros(shape, bool), (0.0, 0.0), RES)


def test_representative_lines_of_a_dashed_wall_and_clutter():
    """A wall drawn dashed (0.3 m dashes, 0.1 m gaps, 6 m) is one line over its whole
    extent; 300 seeded cells of clutter scattered over 6 x 4 m make none."""
    from floorscan.floorplan.representative_lines import representative_lines

    rows, cols = [], []
    for c in range(0, 120):
        if c % 8 < 6:  # 6 cells on, 2 off
            rows.append(40)
            cols.append(c)
    rng = np.random.default_rng(7)
    clutter = np.c_[rng.integers(50, 80, 300), rng.integers(0, 120, 300)]
    cells = np.r_[np.c_[rows, cols], clutter]
    grid = _grid_of(cells, (80, 120))
    lines, support, openings = representative_lines(grid.cell_centres(grid.occupied()), RES, np.array([0.0, np.pi / 2]))
    assert len(lines) == 1 and len(openings) == 0
    np.testing.assert_allclose(lines[0], [0.0, 2.025, 5.9, 2.025], atol=1e-9)  # cell centres' row, first to last cell
    np.testing.assert_allclose(support[0], 90 * RES)


def test_an_opening_between_two_runs_of_wall_is_closed_and_a_row_of_desks_is_not():
    from floorscan.floorplan.representative_lines import representative_lines

    wall = [(20, c) for c in list(range(0, 40)) + list(range(58, 100))]  # 2 m, a 0.9 m gap, 2.1 m
    desks = [(60, c) for k in range(6) for c in range(16 * k, 16 * k + 12)]  # 0.6 m desks, 0.2 m apart
    grid = _grid_of(wall + desks, (80, 100))
    lines, _, openings = representative_lines(grid.cell_centres(grid.occupied()), RES, np.array([0.0]), door_max_m=2.0)
    assert len(lines) == 2  # the wall's line and the desks' front
    assert len(openings) == 1
    np.testing.assert_allclose(openings[0], [2.0, 1.025, 2.9, 1.025], atol=1e-9)


def test_a_line_along_a_plan_wall_takes_the_wall_s_line():
    from floorscan.floorplan.representative_lines import onto_walls

    lines = np.array([[0.0, 2.08, 6.0, 2.08], [0.0, 3.0, 6.0, 3.0]])
    axes = np.array([[1.0, 2.0, 4.0, 2.0], [0.0, 0.0, 0.0, 5.0]])
    out = onto_walls(lines, axes, np.array([0.1, 0.1]))
    np.testing.assert_allclose(out, [[0.0, 2.0, 6.0, 2.0], [0.0, 3.0, 6.0, 3.0]])


def test_a_wall_the_plan_lacks_still_parts_two_rooms():
    """The map draws the middle wall with its door; the plan has only the outline. The
    map's own line of that wall, and the door between its runs closed, part the rooms."""
    axes, thickness, grid = two_rooms()
    polys, _ = layout_rooms(axes[:4], thickness[:4], grid, RoomParams())
    assert len(polys) == 2
    # each from the outline's wall faces to the middle wall's line (it has no footprint
    # in the plan): 4.9 x 4.8 m, within a cell of the line's place
    np.testing.assert_allclose(sorted(p.area for p in polys), [4.9 * 4.8] * 2, atol=4.8 * RES)
    assert not polys[0].intersects(polys[1].buffer(-1e-6))

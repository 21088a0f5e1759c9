"""The map extractor (floorscan.walls.map_lines), the floor plan's structure passes
(floorscan.floorplan.structure) and the answer's scores (floorscan.score.answer) on a
small room scanned by a ray caster: known walls, a door, an occluded stretch of wall
and a table standing in the room."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
import shapely

from conftest import cast_rays
from floorscan.core.occupancy import OccupancyParams, occupancy_grid
from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.plan import build_floorplan, plan_faces
from floorscan.floorplan.clutter import in_front_of_walls
from floorscan.floorplan.free_space import StructureParams
from floorscan.floorplan.hidden import covered_by_fronts, into_corners
from floorscan.floorplan.junctions import merge_parallel_duplicates, snap_junctions
from floorscan.floorplan.structure import border_and_support, floor_under, join_collinear, structure_passes
from floorscan.score.answer import crossings, true_corners, true_wall_pieces
from floorscan.walls.map_lines import MapParams, map_segments, supported_points

# A room 8 x 5 m (wall faces), a door 0.9 m wide in the south wall at x 2.0..2.9 with a
# corridor behind it, and a table 1.2 x 0.6 m standing free in the room; the cabinet
# in front of the north wall hides a stretch of it from every scan position.
ROOM = [((0, 0), (2.0, 0)), ((2.9, 0), (8, 0)), ((8, 0), (8, 5)), ((8, 5), (0, 5)), ((0, 5), (0, 0))]
CORRIDOR = [((2.0, 0), (2.0, -1.5)), ((2.9, 0), (2.9, -1.5))]
TABLE = shapely.box(5.0, 2.0, 6.2, 2.6).exterior
CABINET = shapely.box(3.0, 4.3, 4.0, 4.6).exterior
POSES = [(1.5, 2.5), (4.0, 1.2), (6.5, 3.8), (2.45, -0.8), (3.0, 2.0), (6.8, 1.0)]


def _scan(origin, rng, segments, n_rays=720, noise=0.005):
    """A 360-degree 2D scan from ``origin``: its returns in the map frame (cast_rays)."""
    o = np.asarray(origin, dtype=np.float64)
    a = np.linspace(-np.pi, np.pi, n_rays, endpoint=False)
    r = cast_rays(segments, o, a)
    hit = np.isfinite(r)
    r = r[hit] + rng.normal(0, noise, int(hit.sum()))
    return o + r[:, None] * np.column_stack([np.cos(a[hit]), np.sin(a[hit])])


@pytest.fixture(scope="module")
def room():
    rng = np.random.default_rng(3)
    rings = [np.asarray(g.coords) for g in (TABLE, CABINET)]
    segments = np.array([[*a, *b] for a, b in ROOM + CORRIDOR] + [[*r[k], *r[k + 1]] for r in rings for k in range(len(r) - 1)])
    scans = [(np.array(p, dtype=np.float64), _scan(p, rng, segments)) for p in POSES]
    pts = np.concatenate([s for _, s in scans])
    sid = np.concatenate([np.full(len(s), i) for i, (_, s) in enumerate(scans)])
    grid = occupancy_grid(scans, OccupancyParams())
    return pts, sid, grid


def _length(seg):
    return np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])


def test_support_drops_a_return_that_other_scans_see_through():
    # a person at (2, 0) seen by the first scan; the second and third see the wall
    # behind through that place; the wall at x = 4 is seen by one scan alone
    o = np.array([0.0, 0.0])
    person = (o, np.array([[2.0, 0.0], [4.0, 1.0]]))
    through = [(o + [0.0, 0.01], np.array([[4.0, 0.0]])), (o - [0.0, 0.01], np.array([[4.0, 0.0]]))]
    grid = occupancy_grid([person, *through], OccupancyParams())
    pts = np.array([[2.0, 0.0], [4.0, 1.0], [4.0, 0.0]])
    assert supported_points(pts, grid).tolist() == [False, True, True]


def test_map_extractor_finds_the_long_walls_and_is_seeded(room):
    pts, _, grid = room
    seg = map_segments(pts, grid, MapParams(), seed=0)
    again = map_segments(pts, grid, MapParams(), seed=0)
    pd.testing.assert_frame_equal(seg, again)
    s = seg[["x0", "y0", "x1", "y1"]].to_numpy()
    # the east wall x = 8 (5 m) is found whole, within 2 cm
    east = s[(np.abs(s[:, 0] - 8) < 0.05) & (np.abs(s[:, 2] - 8) < 0.05)]
    assert len(east) >= 1 and _length(east).max() > 4.8
    with pytest.raises(ValueError, match="finite"):
        map_segments(np.array([[np.nan, 0.0]] * 10), None)


def test_structure_passes_on_the_room(room):
    pts, _, grid = room
    seg = map_segments(pts, grid, MapParams(), seed=0)
    faces, w, _ = plan_faces(seg[["x0", "y0", "x1", "y1"]].to_numpy(), seg["n_inliers"].to_numpy(float))
    walls, ww, side, clutter, reason, _ = structure_passes(faces, w, grid, StructureParams())
    # the table's faces are clutter, no wall lies on it
    table = shapely.box(4.95, 1.95, 6.25, 2.65)
    wall_lines = shapely.linestrings(walls.reshape(-1, 2, 2))
    assert not shapely.intersects(wall_lines, table).any()
    assert shapely.intersects(shapely.linestrings(clutter.reshape(-1, 2, 2)), table).sum() >= 2
    assert set(reason) <= {"not_a_boundary", "free_standing_object", "in_front_of_wall", "short", "loose_in_free_space"}
    # the cabinet's front (y = 4.3, x 3..4) stands in front of the north wall: clutter
    front = clutter[(np.abs(clutter[:, 1] - 4.3) < 0.05) & (np.abs(clutter[:, 3] - 4.3) < 0.05)]
    assert len(front) == 1 and reason[np.flatnonzero((np.abs(clutter[:, 1] - 4.3) < 0.05))[0]] == "in_front_of_wall"
    assert not ((np.abs(walls[:, 1] - 4.3) < 0.05) & (np.abs(walls[:, 3] - 4.3) < 0.05)).any()
    # the north wall behind the cabinet is one face: the occluded stretch is joined
    north = walls[(np.abs(walls[:, 1] - 5) < 0.05) & (np.abs(walls[:, 3] - 5) < 0.05)]
    assert len(north) == 1 and _length(north)[0] > 7.5
    # the door stays open: the south wall is two faces, none across x 2.1..2.8
    south = walls[(np.abs(walls[:, 1]) < 0.05) & (np.abs(walls[:, 3]) < 0.05)]
    assert len(south) == 2
    for s in south:
        lo, hi = sorted((s[0], s[2]))
        assert hi < 2.1 or lo > 2.8
    # the room's four corners are junctions: an end of a wall within 2 cm of each
    ends = walls.reshape(-1, 2)
    for corner in [(0, 0), (8, 0), (8, 5), (0, 5)]:
        assert np.hypot(*(ends - corner).T).min() < 0.03, corner
    # the free space is inside the room for the room's walls
    assert (side != 0).mean() > 0.5


# A hall 10 x 6 m with two doors 1 m wide in its north wall (x 3..4 and 6..7: the wall
# between them is a piece 2 m long, ends free, its wall in line) onto a corridor, and a
# rack 3.2 m long, longer than clutter_max_length_m, 0.6 m deep, 0.45 m in front of the
# south wall: its front is loose in the free space.
HALL = [((0, 0), (10, 0)), ((10, 0), (10, 6)), ((10, 6), (7, 6)), ((6, 6), (4, 6)), ((3, 6), (0, 6)),
        ((0, 6), (0, 0)), ((0, 7.5), (10, 7.5))]  # fmt: skip
RACK = shapely.box(3.4, 0.45, 6.6, 1.05).exterior
HALL_POSES = [(1.5, 3.0), (5.0, 3.0), (8.5, 3.0), (2.0, 1.0), (8.0, 1.0), (5.0, 5.0), (3.5, 6.8), (6.5, 6.8)]


def test_a_rack_in_front_of_a_wall_is_clutter_the_wall_between_two_doors_is_not():
    rng = np.random.default_rng(5)
    r = np.asarray(RACK.coords)
    segments = np.array([[*a, *b] for a, b in HALL] + [[*r[k], *r[k + 1]] for k in range(len(r) - 1)])
    scans = [(np.array(p, dtype=np.float64), _scan(p, rng, segments)) for p in HALL_POSES]
    grid = occupancy_grid(scans, OccupancyParams())
    seg = map_segments(np.concatenate([s for _, s in scans]), grid, MapParams(), seed=0)
    faces, w, _ = plan_faces(seg[["x0", "y0", "x1", "y1"]].to_numpy(), seg["n_inliers"].to_numpy(float))
    walls, _, _, clutter, reason, _ = structure_passes(faces, w, grid, StructureParams())
    rack = shapely.box(3.35, 0.4, 6.65, 1.1)
    assert not shapely.intersects(shapely.linestrings(walls.reshape(-1, 2, 2)), rack).any()
    front = (np.abs(clutter[:, 1] - 1.05) < 0.05) & (np.abs(clutter[:, 3] - 1.05) < 0.05)
    assert front.sum() == 1 and reason[front][0] == "loose_in_free_space"
    assert _length(clutter[front])[0] > 3.0
    # the 2 m wall between the doors stays a wall; the rack's front without the wall
    # behind it and with one side seen stays one too (a wall whose ends were seen free)
    between = walls[(np.abs(walls[:, 1] - 6) < 0.05) & (np.abs(walls[:, 3] - 6) < 0.05)]
    assert any(min(s[0], s[2]) > 3.9 and max(s[0], s[2]) < 6.1 and _length(s[None])[0] > 1.8 for s in between)
    south = walls[(np.abs(walls[:, 1]) < 0.05) & (np.abs(walls[:, 3]) < 0.05)]
    assert len(south) == 1 and _length(south)[0] > 9.5


def test_join_keeps_a_gap_free_space_passes_and_joins_an_unseen_one():
    # two collinear faces with a 1 m gap; free cells fill the gap in one grid only
    faces = np.array([[0.0, 0.0, 3.0, 0.0], [4.0, 0.0, 7.0, 0.0]])
    origin = np.array([3.5, 2.0])
    scans = [(origin, np.array([[x, 0.0] for x in np.arange(0.0, 7.0, 0.05) if not 3.0 < x < 4.0]))]
    unseen = occupancy_grid(scans, OccupancyParams())
    seen = occupancy_grid(scans + [(origin, np.array([[x, -1.0] for x in np.arange(3.1, 3.95, 0.05)]))],
                          OccupancyParams())
    joined, jw, group = join_collinear(faces, np.ones(2), unseen, StructureParams())
    assert len(joined) == 1 and np.allclose(joined[0], [0, 0, 7, 0]) and group.tolist() == [0, 0]
    assert jw.tolist() == [2.0]
    opened, _, _ = join_collinear(faces, np.ones(2), seen, StructureParams())
    assert len(opened) == 2


def test_a_wall_hidden_by_cabinets_is_joined_behind_them_and_their_fronts_are_clutter():
    # a wall at y = 0 seen from the north; two cabinets 1.5 m long and 0.6 m deep stand
    # against it at x 3..4.5 and 4.5..6 (a 3 m gap in the seen face, longer than a join
    # may bridge on its own); their fronts at y = 0.6 hide the wall between the pieces
    pieces = [((0.0, 0.0), (3.0, 0.0)), ((6.0, 0.0), (9.0, 0.0))]
    cabinets = [shapely.box(3.0, 0.0, 4.5, 0.6).exterior, shapely.box(4.5, 0.0, 6.0, 0.6).exterior]
    segments = pieces + [((0.0, 0.0), (0.0, 4.0)), ((9.0, 0.0), (9.0, 4.0)), ((0.0, 4.0), (9.0, 4.0))]
    segments += [tuple(map(tuple, np.asarray(c.coords)[k:k + 2])) for c in cabinets for k in range(4)]
    rng = np.random.default_rng(0)
    scans = [(np.array(p), _scan(p, rng, segments)) for p in [(1.5, 2.0), (4.5, 2.5), (7.5, 2.0)]]
    grid = occupancy_grid(scans, OccupancyParams())
    faces = np.array([[0.0, 0.0, 3.0, 0.0], [6.0, 0.0, 9.0, 0.0], [3.0, 0.6, 6.0, 0.6]])
    side = np.array([1, 1, 1])  # free to the north of all three
    assert covered_by_fronts(faces, side, 0, 3.0, 6.0, StructureParams())
    assert not covered_by_fronts(faces, np.array([1, 1, -1]), 0, 3.0, 6.0, StructureParams())  # a face turned away
    joined, _, group = join_collinear(faces, np.ones(3), grid, StructureParams(), side)
    assert group.tolist() == [0, 0, 1] and np.allclose(joined[0], [0, 0, 9, 0])
    # without the fronts, or without the free sides, the 3 m gap stays open
    assert len(join_collinear(faces[:2], np.ones(2), grid, StructureParams(), side[:2])[0]) == 2
    assert len(join_collinear(faces, np.ones(3), grid, StructureParams())[0]) == 3
    # a gap the free space passes through stays an opening, cabinets beside it or not
    seen = occupancy_grid(scans + [(np.array([4.5, 2.5]), np.array([[x, -1.0] for x in np.arange(3.1, 5.9, 0.05)]))],
                          OccupancyParams())
    assert len(join_collinear(faces, np.ones(3), seen, StructureParams(), side)[0]) == 3
    # the whole pass: the wall is one face from 0 to 9 m, the front is clutter
    walls, _, _, clutter, reason, _ = structure_passes(faces, np.ones(3), grid, StructureParams())
    south = walls[(np.abs(walls[:, 1]) < 0.05) & (np.abs(walls[:, 3]) < 0.05)]
    assert len(south) == 1 and _length(south)[0] > 8.9
    assert not (np.abs(walls[:, 1] - 0.6) < 0.05).any() and (np.abs(clutter[:, 1] - 0.6) < 0.05).sum() == 1


def test_a_wall_hidden_by_a_cabinet_in_a_corner_runs_on_to_the_corner():
    # the room's north wall face (y = 4) is seen from x = 1.5 on; a cabinet 1.5 m long,
    # 0.6 m deep stands in the north-west corner, its front at y = 3.4 (free to the south)
    wall, front, west = [1.5, 4.0, 8.0, 4.0], [0.0, 3.4, 1.5, 3.4], [0.0, 0.0, 0.0, 3.4]
    side = np.array([-1, -1, -1])
    closed = lambda p, u, t0, t1: 0.0  # noqa: E731  (no free space on the stretch)
    out = into_corners(np.array([wall, front, west]), side, closed, StructureParams())
    assert np.allclose(out[0], [0.0, 4.0, 8.0, 4.0]) and np.allclose(out[1:], [front, west])
    # no front, free space across the stretch, or the front facing away: the face stays
    assert np.allclose(into_corners(np.array([wall, west]), side[:2], closed, StructureParams())[0], wall)
    opened = lambda p, u, t0, t1: 1.0  # noqa: E731  (a metre of free space on the stretch)
    assert np.allclose(into_corners(np.array([wall, front, west]), side, opened, StructureParams())[0], wall)
    assert np.allclose(into_corners(np.array([wall, front, west]), np.array([-1, 1, -1]), closed, StructureParams())[0],
                       wall)  # fmt: skip
    # the other face of a thin wall, 0.3 m away, runs beside the face (and on past its
    # end): the wall's own face, no front
    other = [0.0, 3.7, 8.0, 3.7]
    assert np.allclose(into_corners(np.array([wall, other, west]), side, closed, StructureParams())[0], wall)


def test_a_row_of_cabinets_longer_than_a_piece_of_furniture_is_a_front():
    # a wall face 8 m long, free to the north; a row of cabinets 3.4 m long, 0.6 m in front
    # of it, free to the north too: a front; the same face free to the south (the other
    # face of a wall 0.6 m thick) or longer than HIDDEN_MAX_GAP_M (5 m) is not
    wall, row = [0.0, 0.0, 8.0, 0.0], [1.0, 0.6, 4.4, 0.6]
    faces = np.array([wall, row])
    long = np.hypot(faces[:, 2] - faces[:, 0], faces[:, 3] - faces[:, 1]) >= StructureParams().clutter_max_length_m
    front, behind = in_front_of_walls(faces, np.array([1, 1]), long, StructureParams())
    assert front.tolist() == [False, True] and behind.tolist() == [-1, 0]
    assert not in_front_of_walls(faces, np.array([1, -1]), long, StructureParams())[0].any()
    longer = np.array([wall, [1.0, 0.6, 6.6, 0.6]])
    assert not in_front_of_walls(longer, np.array([1, 1]), np.array([True, True]), StructureParams())[0].any()


def test_a_front_stands_against_the_nearest_wall_behind_it():
    from floorscan.floorplan.clutter import in_front_of_walls

    seg = np.array([
        [0.0, 0.0, 6.0, 0.0],    # a wall, free side north
        [0.0, 0.3, 6.0, 0.3],    # a second wall face 0.3 m north of it, free side north
        [2.0, 0.9, 3.5, 0.9],    # a cabinet's front: 0.9 m and 0.6 m in front of them
        [0.0, 5.0, 6.0, 5.0],    # a far wall, free side south: nothing stands against it
    ])  # fmt: skip
    side = np.array([1, 1, 1, -1])
    wall = np.array([True, True, False, True])
    front, behind = in_front_of_walls(seg, side, wall, StructureParams())
    assert front.tolist() == [False, False, True, False] and behind.tolist() == [-1, -1, 1, -1]
    front, behind = in_front_of_walls(seg[:2], side[:2], wall[:2], StructureParams())  # a pair, no front
    assert not front.any() and behind.tolist() == [-1, -1]


def test_the_floor_under_an_object_runs_from_its_front_to_the_wall_behind():
    front = np.array([[1.0, 0.6, 2.5, 0.62]])
    wall = np.array([[0.0, 0.0, 9.0, 0.0]])
    quad = floor_under(front, wall)[0]
    assert np.allclose(quad, [[1.0, 0.6], [2.5, 0.62], [2.5, 0.0], [1.0, 0.0]])
    assert shapely.Polygon(quad).area == pytest.approx(1.5 * 0.61)
    assert floor_under(np.zeros((0, 4)), np.zeros((0, 4))).shape == (0, 4, 2)


def test_a_partition_stub_as_thick_as_a_wall_is_no_free_standing_object():
    # a map of 5 cm cells: a wall 0.3 m thick along y = 1.0..1.3, a stub of the same
    # thickness standing 2 m out of it (x 2.0..2.3), and a desk 0.8 x 1.2 m in the room
    from floorscan.core.occupancy import OccupancyGrid
    from floorscan.floorplan.clutter import free_standing_objects

    r, shape = 0.05, (100, 120)
    hit = np.zeros(shape, dtype=np.int32)
    hit[20:26, :] = 1  # the wall, rows 20..25 (y 1.0..1.3)
    hit[26:66, 40:46] = 1  # the stub, y 1.3..3.3, x 2.0..2.3
    hit[50:66, 80:104] = 1  # the desk, y 2.5..3.3, x 4.0..5.2
    grid = OccupancyGrid(origin_xy=np.zeros(2), resolution_m=r, n_hit_scans=hit, n_miss_scans=np.where(hit > 0, 0, 5),
                         params=OccupancyParams(), scan_xy=None)  # fmt: skip
    wall = np.array([[0.0, 1.3, 6.0, 1.3]])  # the wall's face on the room side
    stub_xy, desk_xy = np.array([[2.15, 2.5]]), np.array([[4.6, 2.9]])

    def on(mask, xy):
        rows, cols, _ = grid.cells_of(xy)
        return bool(mask[rows[0], cols[0]])

    # as thin as a wall by the largest disc inside it (0.3 m, 0.4 m grown by a cell each
    # side), not by its area over its length (0.40 m, not under 2 x side_offset_m + 2 cells)
    thin = free_standing_objects(grid, StructureParams(), wall, max_thickness_m=0.4)
    assert not on(thin, stub_xy) and on(thin, desk_xy)
    old = free_standing_objects(grid, StructureParams(), wall)
    assert on(old, stub_xy) and on(old, desk_xy)


def test_the_dilation_of_the_cells_hit_is_scipys_maximum_filter():
    """free_standing_objects grows the cells hit by squares of cells, in time that
    follows the cells (core.grid.square_dilation): the same cells as SciPy's maximum
    filter of the raster with a False border, for every radius used, on sets that touch
    the raster's edges, sparse (one write per cell and offset) and dense (the filter)."""
    from scipy import ndimage

    from floorscan.core.grid import square_dilation

    rng = np.random.default_rng(5)
    paths = {False: 0, True: 0}
    for _ in range(60):
        shape = tuple(int(v) for v in rng.integers(1, 30, 2))
        mask = rng.random(shape) < rng.uniform(0.0, 0.4)
        mask[0, 0] = mask[-1, -1] = True  # the corners
        for radius in (0, 1, 2):
            dense = mask.sum() * (2 * radius + 1) ** 2 >= mask.size
            paths[dense] += 1
            want = ndimage.maximum_filter(mask, size=2 * radius + 1, mode="constant")
            np.testing.assert_array_equal(square_dilation(*np.nonzero(mask), radius, shape), want)
    assert min(paths.values()) >= 20  # both ways taken
    # cells off the raster (a wall's samples beyond the grid) are ignored
    out = square_dilation(np.array([-1, 2, 9]), np.array([0, 2, 40]), 1, (5, 5))
    assert out.sum() == 9 and out[1:4, 1:4].all()  # (2, 2) alone


def test_snap_makes_l_and_t_junctions_and_trims_an_overshoot():
    seg = np.array([
        [0.0, 0.0, 4.9, 0.0],    # stops 0.1 short of the corner at x = 5
        [5.0, 0.2, 5.0, 4.0],    # stops 0.2 short of it
        [2.0, -0.15, 2.0, 3.0],  # overshoots the first wall by 0.15: a T
    ])  # fmt: skip
    out, junctions = snap_junctions(seg, StructureParams())
    assert np.allclose(out[0], [0, 0, 5, 0]) and np.allclose(out[1], [5, 0, 5, 4])
    assert np.allclose(out[2], [2, 0, 2, 3])
    kinds = sorted(junctions[:, 4].astype(int).tolist())
    assert kinds == [1, 2]  # one L, one T
    assert crossings(out, junctions[:, :2]) == 0
    assert crossings(seg[[0, 2]] + np.array([0, 0, 0, 0]), np.empty((0, 2))) == 1


def test_border_rule_drops_a_line_through_an_object(room):
    _, _, grid = room
    # a line through the middle of the table (returns on both sides) and the east wall
    seg = np.array([[5.1, 2.3, 6.1, 2.3], [8.0, 0.2, 8.0, 4.8]])
    structure, side = border_and_support(seg, grid, StructureParams())
    assert structure.tolist() == [False, True]
    assert side[1] != 0


def test_plan_with_a_grid_has_clutter_and_junctions(room):
    pts, _, grid = room
    seg = map_segments(pts, grid, MapParams(), seed=0)
    plain = build_floorplan(seg)
    plan = build_floorplan(seg, FloorplanParams(), grid)
    assert len(plain.clutter) == 0 and len(plain.junctions) == 0
    assert len(plan.clutter) >= 2 and len(plan.junctions) >= 4
    assert set(plan.junctions["kind"]) <= {"L", "T", "X"}
    assert len(plan.walls) < len(plain.walls)


def test_true_pieces_and_corners():
    truth = {
        "axis": np.array([[0.0, 0.0, 4.0, 0.0], [4.0, 0.0, 4.0, 3.0]]),
        "observed_face": np.array([[0.0, 0.05, 1.0, 0.05], [2.0, 0.05, 3.95, 0.05], [3.95, 0.05, 3.95, 3.0]]),
        "thickness": {},
    }
    pieces = true_wall_pieces(truth)
    assert len(pieces) == 3  # the south wall has an unseen gap of 1 m: two pieces
    corners = true_corners(truth)
    assert corners.tolist() == [[4.0, 0.0]]
    # a T (an end on another axis' middle, within 2 cm) counts; an end 3 cm short does not
    truth["axis"] = np.array([[0.0, 0.0, 4.0, 0.0], [2.0, 0.015, 2.0, 3.0], [3.0, 0.03, 3.0, 3.0]])
    truth["observed_face"] = np.array([[0.0, 0.05, 4.0, 0.05]])
    assert true_corners(truth).tolist() == [[2.0, 0.015]]


def test_duplicates_merge_and_shallow_crossings_meet():
    # a wall and a skewed copy across its 12 cm thickness: one wall; a third wall apart
    axes = np.array([[0.0, 0.0, 4.0, 0.0], [1.0, -0.08, 3.0, 0.1], [0.0, 2.0, 4.0, 2.0]])
    merged, thick, group = merge_parallel_duplicates(axes, np.array([0.1, 0.1, 0.2]))
    assert group.tolist() == [0, 0, 1] and len(merged) == 2
    assert np.allclose(merged[0, [0, 2]], [0.0, 4.0], atol=0.01) and abs(merged[0, 1]) < 0.05
    assert thick.tolist() == [0.1, 0.2]
    # two pieces of a curved wall that overlap at 10 degrees meet where they cross
    a = np.array([0.0, 0.0, 3.0, 0.0])
    d = np.radians(10)
    b = np.array([2.6, -0.2 * np.tan(d) * 0 - 0.05, 2.6 + 3 * np.cos(d), -0.05 + 3 * np.sin(d)])
    out, junctions = snap_junctions(np.array([a, b]), StructureParams(), trim_shallow=True)
    assert crossings(out, np.empty((0, 2))) == 0
    assert np.allclose(out[0, 2:], out[1, :2], atol=1e-9)


def test_answer_curve_grid_and_k_reaching():
    from floorscan.core.selection import curve_ks
    from floorscan.core.score_tables import k_reaching

    assert curve_ks(1) == [1] and curve_ks(0) == []
    ks = curve_ks(100, 10)
    assert ks[0] == 1 and ks[-1] == 100 and ks == sorted(set(ks)) and 8 <= len(ks) <= 11
    curve = pd.DataFrame({"k": [1, 2, 4, 8], "f1_5cm": [0.2, 0.85, 0.95, 0.9]})
    # 95 % and 99 % of the last row's F1 (0.9): 0.855 and 0.891
    assert k_reaching(curve, 0.95) == 4 and k_reaching(curve, 0.99) == 4 and k_reaching(curve, 0.9) == 2


def test_exports_carry_clutter_and_junctions(room, tmp_path):
    """Every export of a plan with structure: GeoJSON kinds clutter and junction, the
    DXF layer CLUTTER (audit clean), the SVG clutter group, IFC path connections per
    junction and furniture per clutter piece (validate clean); the same bytes twice."""
    import json

    import ezdxf
    import ifcopenshell
    import ifcopenshell.validate

    from floorscan.floorplan.writer import FloorplanWriter

    pts, _, grid = room
    plan = build_floorplan(map_segments(pts, grid, MapParams(), seed=0), FloorplanParams(), grid)
    stems = [tmp_path / "a", tmp_path / "b"]
    for stem in stems:
        FloorplanWriter({}).write(map_segments(pts, grid, MapParams(), seed=0), {
            f: f"{stem}.{f}" for f in ("geojson", "svg", "dxf", "ifc")}, dataset="room", grid=grid)
    for f in ("geojson", "svg", "dxf", "ifc"):  # the IFC header names its file
        a, b = ((tmp_path / f"{s}.{f}").read_text().replace(f"{s}.{f}", "") for s in "ab")
        assert a == b, f
    doc = json.loads((tmp_path / "a.geojson").read_text())
    kinds = [feat["properties"]["kind"] for feat in doc["features"]]
    assert kinds.count("clutter") == len(plan.clutter) >= 2 and kinds.count("junction") == len(plan.junctions) >= 4
    assert doc["floorscan"]["n_clutter"] == len(plan.clutter)
    # the scorer's reader takes the faces and counts the walls, not clutter or junctions
    from floorscan.score.geojson import read_floorplan

    faces, n_walls = read_floorplan(tmp_path / "a.geojson")
    assert len(faces) == len(plan.faces) and n_walls == len(plan.walls)
    dxf = ezdxf.readfile(tmp_path / "a.dxf")
    assert len(dxf.modelspace().query('LINE[layer=="CLUTTER"]')) == len(plan.clutter)
    assert not dxf.audit().has_errors
    assert '<g id="clutter"' in (tmp_path / "a.svg").read_text()
    model = ifcopenshell.open(str(tmp_path / "a.ifc"))
    assert len(model.by_type("IfcFurniture")) == len(plan.clutter)
    assert 1 <= len(model.by_type("IfcRelConnectsPathElements")) <= len(plan.junctions)
    logger = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(str(tmp_path / "a.ifc"), logger)
    assert logger.statements == []


def test_answer_line_names_the_plan_counts(tmp_path):
    import json

    from floorscan.figures.answer import plan_counts

    path = tmp_path / "floorplan.geojson"
    path.write_text(json.dumps({"type": "FeatureCollection", "features": [],
                                "floorscan": {"n_walls": 12, "n_junctions": 9, "n_clutter": 3}}))
    assert plan_counts(path) == " (12 walls, 9 junctions, 3 clutter pieces)"
    assert plan_counts(tmp_path / "missing.geojson") == ""


def test_a_piece_of_wall_between_two_doors_with_a_cabinet_against_it_is_a_wall():
    # a map of 5 cm cells: a corridor (y 0.5..2.4) and a room (y 2.55..6.5) parted by a
    # partition 0.15 m thick with two doors (x 3.5..4.5 and 6.3..7.7); a cabinet 1.2 x
    # 0.6 m stands against the 1.8 m piece between them, so piece and cabinet are one
    # object standing free, thicker than a wall. The piece's face lies in the
    # partition's line, a door's width from its ends: a wall, and the doors are doors
    # (the tree before made one space of corridor and room, without a door)
    from floorscan.core.occupancy_classes import grid_of_classes
    from floorscan.floorplan.scans import plan_of_scans
    from floorscan.walls.map_stage import map_of_grid

    r = 0.05
    occ = np.zeros((140, 260), dtype=bool)

    def box(x0, y0, x1, y1):
        occ[round(y0 / r):round(y1 / r), round(x0 / r):round(x1 / r)] = True

    for b in [(0.3, 0.3, 12.5, 0.5), (0.3, 6.5, 12.5, 6.7), (0.3, 0.3, 0.5, 6.7), (12.3, 0.3, 12.5, 6.7),
              (0.5, 2.4, 3.5, 2.55), (4.5, 2.4, 6.3, 2.55), (7.7, 2.4, 12.3, 2.55), (4.8, 2.55, 6.0, 3.15)]:  # fmt: skip
        box(*b)
    free = np.zeros_like(occ)
    free[6:130, 6:250] = True
    grid = grid_of_classes(occ, free & ~occ, origin_xy=(0.0, 0.0), resolution_m=r)
    plan = plan_of_scans(map_of_grid(grid, None), None, FloorplanParams(), grid)
    piece = plan.walls[(plan.walls["y0"].sub(2.475).abs() < 0.1) & (plan.walls["x0"].clip(4.4, 6.4) == plan.walls["x0"])]
    assert len(piece) == 1 and abs(piece["length_m"].iloc[0] - 1.8) < 0.15
    assert sorted(plan.rooms["kind"]) == ["corridor", "room"]
    widths = np.sort(plan.doors["width_m"].to_numpy())
    assert len(widths) == 2 and np.abs(widths - [1.0, 1.4]).max() <= 0.1  # within two cells
    # the cabinet's three other faces stay furniture
    assert (plan.clutter["reason"] == "free_standing_object").sum() == 3


def test_a_chair_standing_free_in_a_hall_is_loose_however_short_its_pieces():
    """A chair's back and seat seen as a V of two faces, 0.85 m and 0.25 m, standing in
    the middle of a hall. The short face is held at the vertex by the long one; its far
    end, shorter than snap_m from the long face, hangs from the same face and is free,
    so the V has two free ends in the free space: loose, clutter. Held at both ends by
    one face, the V was a closed loop and stayed two walls (acapulco's rows of chairs)."""
    from floorscan.floorplan.clutter import loose_in_free_space
    from floorscan.floorplan.junctions import junction_ends

    hall = [((0, 0), (10, 0)), ((10, 0), (10, 6)), ((10, 6), (0, 6)), ((0, 6), (0, 0))]
    chair = [((4.7, 2.2), (5.3, 2.8)), ((5.3, 2.8), (5.55, 2.8))]  # 0.85 m at 45 degrees, 0.25 m
    rng = np.random.default_rng(2)
    segments = np.array([[*a, *b] for a, b in hall + chair], dtype=np.float64)
    scans = [(np.array(p, dtype=np.float64), _scan(p, rng, segments)) for p in [(2, 1.5), (8, 1.5), (2, 4.5), (8, 4.5), (5, 5)]]
    grid = occupancy_grid(scans, OccupancyParams())
    snapped, junctions = snap_junctions(segments, StructureParams())
    _, side = border_and_support(snapped, grid, StructureParams())
    loose = loose_in_free_space(snapped, junction_ends(snapped, junctions), side, grid, StructureParams())
    assert loose.tolist() == [False, False, False, False, True, True]


def test_a_row_of_table_legs_with_the_floor_seen_between_them_is_no_wall():
    """Eight legs 0.12 m square, 0.45 m apart on a line (x 1.0 .. 4.27, y 2.44 .. 2.56),
    in a room scanned from both sides of the row: the gaps between the legs (0.33 m,
    narrower than an opening, 71 % of the row's length) are seen free, so their faces
    are no joined wall: they stay eight faces. Without the test of
    :func:`~floorscan.floorplan.structure.join_collinear`, they are joined into one face
    3.27 m long, longer than any piece of furniture."""
    room = [((0, 0), (6, 0)), ((6, 0), (6, 5)), ((6, 5), (0, 5)), ((0, 5), (0, 0))]
    legs = [shapely.box(x, 2.44, x + 0.12, 2.56).exterior for x in 1.0 + 0.45 * np.arange(8)]
    rng = np.random.default_rng(4)
    rings = [np.asarray(g.coords) for g in legs]
    segments = np.array([[*a, *b] for a, b in room] + [[*r[k], *r[k + 1]] for r in rings for k in range(len(r) - 1)])
    poses = [(1.2, 1.0), (3.0, 1.2), (4.8, 0.8), (1.5, 4.0), (3.2, 3.9), (5.0, 4.2)]
    grid = occupancy_grid([(np.array(p, dtype=np.float64), _scan(p, rng, segments)) for p in poses], OccupancyParams())
    faces = np.array([[x, 2.44, x + 0.12, 2.44] for x in 1.0 + 0.45 * np.arange(8)])
    joined, _, group = join_collinear(faces, np.ones(8), grid, StructureParams())
    assert len(joined) == 8 and sorted(group.tolist()) == list(range(8))
    # the north wall's face found in two pieces 0.33 m apart, its cells between them
    # occupied, is still one face
    wall = np.array([[0.0, 5.0, 2.0, 5.0], [2.33, 5.0, 6.0, 5.0]])
    one, _, _ = join_collinear(wall, np.ones(2), grid, StructureParams())
    assert len(one) == 1 and np.allclose(one[0], [0, 5, 6, 5], atol=1e-9)


def test_the_map_extractor_cuts_a_segment_where_the_floor_is_seen_between_table_legs():
    """Eight legs 0.12 m square, 0.35 m apart (gaps of 0.23 m, which RANSAC's
    ``max_gap_m`` of 0.3 m bridges), scanned from both sides of the row: the cells
    between the legs were seen free and never hit, so no map segment runs along the row
    for more than one leg and its neighbourhood. Without the cut
    (:func:`floorscan.walls.map_lines.map_segments`) one segment spans the row's 2.57 m.
    The room's walls are whole."""
    room = [((0, 0), (6, 0)), ((6, 0), (6, 5)), ((6, 5), (0, 5)), ((0, 5), (0, 0))]
    xs = 1.0 + 0.35 * np.arange(8)
    legs = [shapely.box(x, 2.44, x + 0.12, 2.56).exterior for x in xs]
    rng = np.random.default_rng(5)
    rings = [np.asarray(g.coords) for g in legs]
    segments = np.array([[*a, *b] for a, b in room] + [[*r[k], *r[k + 1]] for r in rings for k in range(len(r) - 1)])
    poses = [(1.2, 1.0), (2.4, 0.9), (3.6, 1.1), (4.8, 0.8), (1.5, 4.0), (2.6, 4.1), (3.7, 3.9), (5.0, 4.2)]
    scans = [(np.array(p, dtype=np.float64), _scan(p, rng, segments, n_rays=1440)) for p in poses]
    grid = occupancy_grid(scans, OccupancyParams())
    seg = map_segments(np.concatenate([s for _, s in scans]), grid, MapParams(), seed=0)
    xy = seg[["x0", "y0", "x1", "y1"]].to_numpy()
    along_row = (np.abs(xy[:, [1, 3]] - 2.5).max(axis=1) < 0.1) & (np.abs(xy[:, 3] - xy[:, 1]) < 0.05)
    assert along_row.any() and _length(xy[along_row]).max() < 0.6
    walls = np.abs(xy[:, [1, 3]]).max(axis=1) < 0.05  # the south wall, y = 0
    assert _length(xy[walls]).max() > 5.5


def test_a_door_jamb_is_a_face_in_a_wall_line_a_door_s_width_beyond_its_end():
    """door_jambs: of the short faces, the 0.45 m pier 0.85 m before a wall in its line
    (a door between them) is a jamb; a face 0.2 m before the wall (a slit, no door),
    one 2.5 m beyond it (wider than a door), one 2 m beside its line (a desk's side)
    and one across it are not, nor is the pier when the long face is no wall."""
    from floorscan.floorplan.wall_pieces import door_jambs

    faces = np.array([
        [1.3, 0.0, 6.0, 0.0],    # the wall
        [0.0, 0.0, 0.45, 0.0],   # the pier between the corner and the door
        [6.2, 0.0, 6.5, 0.0],    # 0.2 m past the wall's end
        [8.5, 0.0, 8.9, 0.0],    # 2.5 m past it
        [3.0, 2.0, 3.4, 2.0],    # parallel, 2 m off its line
        [7.0, -0.2, 7.0, 0.2],   # across its line
    ])  # fmt: skip
    short = np.array([False, True, True, True, True, True])
    assert door_jambs(faces, short, StructureParams(), 0.6, 2.0).tolist() == [False, True, False, False, False, False]
    assert not door_jambs(faces, short, StructureParams(), 0.9, 2.0)[1]  # a door narrower than the narrowest
    # the long face a furniture front, no wall: no jamb
    assert not door_jambs(faces, short, StructureParams(), 0.6, 2.0, not_walls=np.arange(6) == 0).any()



def _map_plan(boxes, shape):
    """The plan of a map of 5 cm cells: ``boxes`` (x0, y0, x1, y1 metres) occupied, the
    rest of the frame one cell in free."""
    from floorscan.core.occupancy_classes import grid_of_classes
    from floorscan.floorplan.scans import plan_of_scans
    from floorscan.walls.map_stage import map_of_grid

    r = 0.05
    occ = np.zeros(shape, dtype=bool)
    for x0, y0, x1, y1 in boxes:
        occ[round(y0 / r):round(y1 / r), round(x0 / r):round(x1 / r)] = True
    free = np.zeros_like(occ)
    free[6:shape[0] - 6, 6:shape[1] - 6] = True
    grid = grid_of_classes(occ, free & ~occ, origin_xy=(0.0, 0.0), resolution_m=r)
    return plan_of_scans(map_of_grid(grid, None), None, FloorplanParams(), grid)


def test_the_pier_between_two_doors_is_a_wall_and_parts_two_rooms():
    # two rooms 2.5 m wide (x 0.5..3.0 and 3.15..5.65, y 0.5..4.5) parted by a
    # partition with two doors (y 1.6..2.8 and 3.2..3.9) and a 0.4 m pier between
    # them, standing free in the space the doors let through (map15's two west rooms).
    # Without the pier the opening is 2.3 m: wider than a door, and nearly as wide as
    # the rooms, so they were one space (the tree before: one space of 20.9 m2, no door)
    outer = [(0.3, 0.3, 5.85, 0.5), (0.3, 4.5, 5.85, 4.7), (0.3, 0.3, 0.5, 4.7), (5.65, 0.3, 5.85, 4.7)]
    partition = [(3.0, 0.5, 3.15, 1.6), (3.0, 2.8, 3.15, 3.2), (3.0, 3.9, 3.15, 4.5)]
    plan = _map_plan(outer + partition, (100, 124))
    pier = plan.walls[(plan.walls[["y0", "y1"]].min(axis=1) > 2.7) & (plan.walls[["y0", "y1"]].max(axis=1) < 3.4)
                      & (plan.walls[["x0", "x1"]].min(axis=1) > 2.9) & (plan.walls[["x0", "x1"]].max(axis=1) < 3.3)]  # fmt: skip
    assert len(pier) == 1 and abs(pier["length_m"].iloc[0] - 0.4) <= 0.1
    assert len(plan.rooms) == 2
    assert sorted(plan.rooms["area_m2"]) == pytest.approx([10.0, 10.0], abs=0.5)
    widths = np.sort(plan.doors["width_m"].to_numpy())
    assert len(widths) == 2 and np.abs(widths - [0.7, 1.2]).max() <= 0.1  # within two cells


def _wall_line_grid(openings):
    """A map of 5 cm cells, 4 x 4 m, all free but a wall line at y 1.9..2.05 with the
    openings ``(x0, x1)`` (metres) cut out of it."""
    from floorscan.core.occupancy_classes import grid_of_classes

    r = 0.05
    occ = np.zeros((80, 80), dtype=bool)
    occ[38:41, :] = True
    for x0, x1 in openings:
        occ[38:41, round(x0 / r):round(x1 / r)] = False
    return grid_of_classes(occ, ~occ, origin_xy=(0.0, 0.0), resolution_m=r)


def test_a_pier_is_free_standing_between_two_openings_the_free_space_passes():
    """piers: the 0.3 m piece between two walls in its line, 1.2 and 0.7 m off their
    ends across free space, is a pier; not with one of the walls gone, nor across a
    gap the scans saw closed, nor when another face meets it at an end (the end face
    of a wall stopping at the line)."""
    from floorscan.floorplan.wall_pieces import piers

    faces = np.array([[0.0, 2.0, 1.0, 2.0], [2.2, 2.0, 2.5, 2.0], [3.2, 2.0, 4.0, 2.0]])
    which = np.array([False, True, False])
    params, doors = StructureParams(), _wall_line_grid([(1.0, 2.2), (2.5, 3.2)])
    assert piers(faces, which, doors, params).tolist() == [False, True, False]
    assert not piers(faces[:2], which[:2], doors, params).any()  # a wall on one side only
    at_end = np.array([[2.2, 2.0, 1, 0, 2]], dtype=np.float64)  # x, y, i, j, kind: a face meets the piece's end
    assert not piers(faces, which, doors, params, junctions=at_end).any()
    assert not piers(faces, which, _wall_line_grid([(2.5, 3.2)]), params).any()  # the west opening seen closed


def test_a_pier_is_a_wall_by_its_faces_when_its_axis_lies_a_thickness_off_the_line():
    """loose_walls: the axis of a pier seen from both sides lies in its middle, those of
    the walls in its line, seen from one side, half a default thickness behind their
    faces: 0.2 m apart, beyond side_offset_m, while all faces lie on one line (map15's
    corridor wall between two doors at one seed of the map extractor). Its faces in the
    line of the walls' faces make it a pier; not with one of the walls gone."""
    from floorscan.floorplan.wall_pieces import loose_walls

    axes = np.array([[0.0, 1.9, 1.0, 1.9], [2.2, 2.1, 2.5, 2.1], [3.2, 1.9, 4.0, 1.9]])
    faces = np.array([[0.0, 2.0, 1.0, 2.0], [2.2, 2.0, 2.5, 2.0], [2.2, 2.2, 2.5, 2.2], [3.2, 2.0, 4.0, 2.0]])
    wall_of_face, none = np.array([0, 1, 1, 2]), np.zeros((0, 5))
    params, doors = StructureParams(), _wall_line_grid([(1.0, 2.2), (2.5, 3.2)])
    assert loose_walls(axes, faces, wall_of_face, none, doors, params).tolist() == [False, False, False]
    assert loose_walls(axes, axes, np.arange(3), none, doors, params).tolist() == [False, True, False]  # axes alone
    assert loose_walls(axes[:2], faces[:3], wall_of_face[:3], none, doors, params).tolist() == [False, True]


def test_the_pier_between_a_wall_and_a_door_is_a_wall_however_short():
    # two rooms 2.5 m wide parted by a partition with a door (y 0.9..1.8) 0.4 m from the
    # south wall: the 0.4 m stub between the wall and the door, cut from the south wall
    # by the free-standing objects' cut, stood free and was furniture (the tree before:
    # two faces of clutter, free_standing_object); it meets the south wall and has the
    # partition in its line across the door
    outer = [(0.3, 0.3, 5.85, 0.5), (0.3, 4.5, 5.85, 4.7), (0.3, 0.3, 0.5, 4.7), (5.65, 0.3, 5.85, 4.7)]
    plan = _map_plan(outer + [(3.0, 0.5, 3.15, 0.9), (3.0, 1.8, 3.15, 4.5)], (100, 124))
    stub = plan.walls[(plan.walls[["x0", "x1"]].sub(3.08).abs().max(axis=1) < 0.1) & (plan.walls[["y0", "y1"]].max(axis=1) < 1.2)]
    assert len(stub) == 1 and abs(stub["length_m"].iloc[0] - 0.4) <= 0.1
    assert not (plan.clutter["reason"] == "free_standing_object").any()
    assert len(plan.rooms) == 2 and len(plan.doors) == 1 and abs(plan.doors["width_m"].iloc[0] - 0.9) <= 0.1


def test_a_corner_pier_meets_a_wall_and_has_a_wall_or_a_pier_across_a_door():
    """corner_piers: a 0.3 m stub that meets a wall at an end and has a wall in its line
    0.8 m beyond its other end, across free space, is such a pier; so are two stubs facing
    each other across a door (a partition's two pieces); not a stub that meets no wall,
    or only another stub (the corner of an object), nor across a gap the scans saw closed,
    nor one with nothing in its line."""
    from floorscan.floorplan.wall_pieces import corner_piers

    # the stub (0), the wall across the door (1), the wall the stub meets (2), a short
    # piece square to the stub at its end (3)
    faces = np.array([[0.0, 2.0, 0.3, 2.0], [1.1, 2.0, 3.5, 2.0], [0.0, 0.5, 0.0, 3.5], [0.0, 2.0, 0.0, 2.3]])
    at_wall = np.array([[0.0, 2.0, 0, 2, 2]], dtype=np.float64)  # x, y, i, j, kind (a T)
    at_piece = np.array([[0.0, 2.0, 0, 3, 1]], dtype=np.float64)  # an L with the short piece
    standing, params, door = np.array([True, False, False, True]), StructureParams(), _wall_line_grid([(0.3, 1.1)])
    assert corner_piers(faces, standing, at_wall, door, params).tolist() == [True, False, False, False]
    assert not corner_piers(faces, standing, np.zeros((0, 5)), door, params).any()
    assert not corner_piers(faces, standing, at_piece, door, params).any()
    assert not corner_piers(faces, standing, at_wall, _wall_line_grid([]), params).any()
    lone = [0, 2, 3]  # no wall in the stub's line
    assert not corner_piers(faces[lone], standing[lone], np.array([[0.0, 2.0, 0, 1, 2]]), door, params).any()
    two = np.array([[0.0, 2.0, 0.3, 2.0], [1.1, 2.0, 1.4, 2.0], [0.0, 0.5, 0.0, 3.5], [1.4, 0.5, 1.4, 3.5]])
    ends = np.array([[0.0, 2.0, 0, 2, 2], [1.4, 2.0, 1, 3, 2]], dtype=np.float64)
    assert corner_piers(two, np.array([True, True, False, False]), ends, door, params).tolist() == [True, True, False, False]


def test_a_short_face_is_measured_from_the_corner_it_stops_short_of():
    """long_enough: a 0.26 m face ending 0.06 m short of a wall's line reaches 0.32 m
    from the corner and is kept, carried there; 0.15 m short it is not, nor is a 0.26 m
    face that meets nothing; a face at least the shortest length is kept as it is."""
    from floorscan.floorplan.structure import long_enough

    wall = [0.0, -1.0, 0.0, 3.0]
    faces = np.array([wall, [0.06, 0.0, 0.32, 0.0], [0.15, 1.0, 0.41, 1.0], [1.0, 2.0, 1.26, 2.0], [0.5, 2.5, 1.0, 2.5]])
    keep, carried = long_enough(faces, 0.3, 0.05)
    assert keep.tolist() == [True, True, False, False, True]
    assert carried[1] == pytest.approx([0.0, 0.0, 0.32, 0.0], abs=1e-9)
    assert np.array_equal(carried[[0, 2, 3, 4]], faces[[0, 2, 3, 4]])


def test_the_corner_reach_is_what_the_map_extractor_claims():
    """CLAIMED_M is the map extractor's inlier distance and thinning cell, which the
    floor plan package cannot import (ARCHITECTURE.md: no stage imports another)."""
    from floorscan.floorplan.structure import CLAIMED_M
    from floorscan.walls.map_lines import MAP_GRID_M, MAP_THRESHOLD_M

    assert CLAIMED_M == pytest.approx(MAP_THRESHOLD_M + MAP_GRID_M)


def test_parallel_lines_cross_nowhere_without_a_warning():
    """line_crossings of parallel and of crossing pairs: NaN for the parallel ones (and
    no RuntimeWarning from their infinite parameter), the crossing point for the others."""
    import warnings

    from floorscan.floorplan.junctions import line_crossings

    a = np.array([[0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
    b = np.array([[0.0, 1.0, 1.0, 1.0], [0.5, -1.0, 0.5, 1.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        x = line_crossings(a, b)
    assert np.isnan(x[0]).all()
    assert np.allclose(x[1], [0.5, 0.0])


@pytest.mark.parametrize("turned", [True, False])
def test_a_short_face_hanging_from_a_wall_turned_from_every_long_face_is_furniture(turned):
    """A hall 10 x 6 m with a partition 2.5 m long down from its north wall, scanned
    from both sides of three short faces: one held at one end by the east wall (its end
    0.1 m short of it: a junction), one standing free, one held at both ends between the
    partition and the east wall. Turned 32 degrees from the hall's walls, the one held
    at one end is furniture (a desk turned against the wall); the free one is step 6's
    first rule's, the one held at both ends is in the wall graph. Turned 9 degrees
    (under OBLIQUE_MIN_DEG, 15), none is. Seen from its north side only, the first is a
    wall (a room's wall seen from the room)."""
    from floorscan.floorplan.junctions import junction_ends
    from floorscan.floorplan.oblique import oblique_in_free_space

    hall = [((0, 0), (10, 0)), ((10, 0), (10, 6)), ((10, 6), (0, 6)), ((0, 6), (0, 0)), ((8.5, 6), (8.5, 3.5))]
    rise = np.tan(np.radians(32.0 if turned else 9.0))
    faces = [((8.3, 2.5 - 1.6 * rise), (9.9, 2.5)),  # held by the east wall at one end
             ((3.0, 3.0), (4.2, 3.0 + 1.2 * rise)),  # held at neither end
             ((8.6, 4.2), (9.9, 4.2 + 1.3 * rise))]  # held by the partition and the east wall
    segments = np.array([[*a, *b] for a, b in hall + faces], dtype=np.float64)
    snapped, junctions = snap_junctions(segments, StructureParams())
    held = junction_ends(snapped, junctions)
    crossed = np.zeros(len(snapped), dtype=bool)
    assert held[5:].sum(axis=1).tolist() == [1, 0, 2]
    poses = [(8.6, 0.7), (9.3, 3.3), (9.3, 5.6), (2.5, 1.5), (4.5, 4.5), (6.5, 2.0)]
    for seen_south in (True, False):  # without the scan south of the first face, its south side is unseen
        rng = np.random.default_rng(5)
        scans = [(np.array(p, dtype=np.float64), _scan(p, rng, segments)) for p in poses[not seen_south:]]
        _, _, both = border_and_support(snapped, occupancy_grid(scans, OccupancyParams()), both_free=True)
        out = oblique_in_free_space(snapped, held, crossed, both)
        assert out.tolist() == [False] * 5 + [turned and seen_south, False, False]


def test_a_short_face_across_the_corner_of_two_walls_that_meet_is_loose():
    """A 0.35 m face from a wall to the wall it meets at an L, beside that corner, is the
    corner's cells traced on a slant (a chord), not a wall; the same face between two
    walls that meet nowhere, or meet 2 m away, connects them and is a wall."""
    from floorscan.floorplan.junctions import short_loose

    seg = np.array([[0.0, 0.0, 2.0, 0.0], [2.0, 0.0, 2.0, 2.0], [1.75, 0.0, 2.0, 0.25]])
    chord = np.array([[1.75, 0.0, 0, 2, 0], [2.0, 0.25, 1, 2, 0]], dtype=np.float64)
    corner = np.array([[2.0, 0.0, 0, 1, 0]], dtype=np.float64)
    assert short_loose(seg, np.vstack([chord, corner]), 0.5).tolist() == [False, False, True]
    assert short_loose(seg, chord, 0.5).tolist() == [False, False, False]
    far = np.array([[0.0, 2.0, 0, 1, 0]], dtype=np.float64)  # the two walls meet 2 m from the face
    assert short_loose(seg, np.vstack([chord, far]), 0.5).tolist() == [False, False, False]


def test_a_wall_in_line_with_a_short_wall_piece_fitted_a_few_degrees_off_is_no_loose_furniture():
    """A corridor's north wall, 4 m (x 2..6, y 3), seen from both sides and past both
    ends, and 1.3 m beyond its east end a 0.53 m piece of the wall held at a corner,
    fitted 6.5 degrees off its line (a short face is fitted on few cells: its direction
    is known to a cell at each end, atan(0.1 / 0.53) = 10.7 degrees). The piece lies in
    the long wall's line, so the long wall is held up and stays a wall; compared with
    join_angle_deg (5 degrees) alone it was in no line, and the wall was loose furniture
    (map_with_clutter at the map extractor's seed 6: the corridor's north wall, 58.4-62.4
    m, clutter, and the corridor one room with the hall and the offices north of it). A
    piece as short in line with a face shorter than a wall holds nothing more: the zigzag
    of a row of chairs stays loose."""
    from floorscan.floorplan.clutter import loose_in_free_space
    from floorscan.floorplan.junctions import junction_ends

    a = np.radians(6.5)
    piece = (7.3, 3.0, 7.3 + 0.53 * np.cos(a), 3.0 - 0.53 * np.sin(a))
    box = [(0, 0, 12, 0), (12, 0, 12, 6), (12, 6, 0, 6), (0, 6, 0, 0)]
    corner = [(piece[2], piece[3], piece[2], 6.0)]  # the wall the piece meets at its east end
    segments = np.array(box + corner + [(2, 3, 6, 3), piece], dtype=np.float64)
    poses = [(1, 1.5), (4, 1.5), (7, 1.5), (1, 4.5), (4, 4.5), (6.5, 4.5)]
    rng = np.random.default_rng(4)

    def loose_faces(segments):
        scans = [(np.array(p, dtype=np.float64), _scan(p, rng, segments)) for p in poses]
        grid = occupancy_grid(scans, OccupancyParams())
        snapped, junctions = snap_junctions(segments, StructureParams())
        _, side = border_and_support(snapped, grid, StructureParams())
        ends = junction_ends(snapped, junctions)
        return ends, loose_in_free_space(snapped, ends, side, grid, StructureParams())

    ends, loose = loose_faces(segments)
    assert ends[-1].tolist() == [False, True] and not ends[-2].any()  # the piece held at its corner only
    assert loose.tolist() == [False] * 7
    # a 2 m face (a rack's front, shorter than a wall, clutter_max_length_m) is no wall
    # for the piece to be in line with: loose
    segments[-2] = (4, 3, 6, 3)
    assert loose_faces(segments)[1].tolist() == [False] * 5 + [True, False]

"""Properties of the plan on small generated buildings (issue 44, item 4).

The buildings are rectangles of 1-3 x 1-2 rooms of 2-3.5 m with a door in every inner
wall (:func:`floorscan.sim.generated.room_grid_building`): a plan of one takes about
0.1 s, so the suite's 500 cases (:data:`INPUT_EXAMPLES` + :data:`JITTER_CASES` +
:data:`POSES`) cost a minute or two.

- No input raises anything but a documented error (Hypothesis, every example; the
  examples are derandomized by profile ``ci`` of ``tests/conftest.py``,
  ``FLOORSCAN_HYPOTHESIS_PROFILE=dev`` asks for fresh ones).
- A millimetre of jitter on the scan points gives the same counts of walls, rooms and
  doors, and a rigid motion (a sub-cell shift of the map's cells, a turn by any angle,
  mirroring) the same counts as the building at its own pose with each room within
  :data:`ROOM_TOLERANCE_M` of its room there. Issue 44 wants every case to pass; the
  plan does not get there yet, so these two run seeded cases (``numpy.random``, seed
  44) and allow the wrong ones measured today (:data:`WRONG_JITTER`,
  :data:`WRONG_POSES`; ``benchmarks/README.md``, seventh, tenth, thirty-sixth,
  thirty-seventh, fifty-third, fifty-fourth and fifty-sixth sessions): a change that makes the plan
  less stable fails here, one that makes it more stable lowers the numbers. The same
  rigid-motion cases drawn from other seeds (``python -m benchmarks properties``) tell
  whether a change is more stable beyond these poses.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from benchmarks.bench_properties import (ROOM_TOLERANCE_M, TEST_SEED, back, counts, map_plan, pose_errors, quiet,
                                         seeded_building)
from floorscan.core.occupancy import occupancy_grid
from floorscan.core.occupancy_classes import grid_of_classes
from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.scans import plan_of_scans
from floorscan.sim.generated import moved, room_grid_building, scans_2d
from floorscan.sim.ground_truth import true_rooms
from floorscan.sim.occupancy_map import MAP_RESOLUTION_M
from floorscan.walls.map_lines import map_segments

#: Hypothesis examples of the input property.
INPUT_EXAMPLES = 250
#: Seeded buildings of the jitter property, and of them how many may change a count
#: today.
JITTER_CASES = 100
WRONG_JITTER = 0
#: Seeded poses of the rigid-motion property, and of them how many may change a count
#: or move a room farther than :data:`ROOM_TOLERANCE_M` today.
POSES = 150
WRONG_POSES = 2


def scan_plan(origins, scans):
    """The plan of scans: their occupancy grid and map walls, as the answer's."""
    grid = occupancy_grid(zip(origins, scans))
    return quiet(plan_of_scans, map_segments(np.concatenate(scans), grid, seed=0), None, FloorplanParams(), grid)


@pytest.mark.slow
def test_a_millimetre_of_jitter_keeps_the_counts():
    rng = np.random.default_rng(TEST_SEED)
    wrong = []
    for _ in range(JITTER_CASES):
        key = seeded_building(rng)
        b = room_grid_building(*key)
        origins = np.array([p.representative_point().coords[0] for p in true_rooms(b)["polygon"]])
        scans = scans_2d(b, origins)
        jittered = [s + rng.uniform(-1e-3, 1e-3, s.shape) for s in scans]
        before, after = counts(scan_plan(origins, scans)), counts(scan_plan(origins, jittered))
        if before != after:
            wrong.append((key, before, after))
    print(f"{len(wrong)} of {JITTER_CASES} buildings change a count: {wrong}")
    assert len(wrong) <= WRONG_JITTER, wrong


COORD = st.floats(-3.0, 3.0, allow_nan=False)
SEGMENTS = st.lists(
    st.one_of(
        st.tuples(COORD, COORD, COORD, COORD),
        st.tuples(COORD, COORD).map(lambda p: (*p, *p)),  # zero length
        st.just((math.nan, 0.0, 1.0, 1.0)),  # a non-finite row: dropped
    ),
    max_size=30,
)


@settings(max_examples=INPUT_EXAMPLES)
@given(segments=SEGMENTS, seed=st.integers(0, 2**32 - 1), inliers=st.integers(1, 50))
def test_no_input_raises_but_a_documented_error(segments, seed, inliers):
    """Any segments (repeated, zero length, crossing, not finite) on a random map of
    free and occupied cells: a plan, or a documented error (KeyError, ValueError)."""
    rng = np.random.default_rng(seed)
    shape = tuple(rng.integers(1, 80, 2))
    occupied = rng.random(shape) < rng.uniform(0, 0.5)
    free = ~occupied & (rng.random(shape) < rng.uniform(0, 1))
    grid = grid_of_classes(occupied, free, origin_xy=tuple(rng.uniform(-3, 0, 2)), resolution_m=MAP_RESOLUTION_M)
    table = pd.DataFrame(np.array(segments, dtype=np.float64).reshape(-1, 4), columns=["x0", "y0", "x1", "y1"])
    table["n_inliers"] = inliers
    try:
        plan = quiet(plan_of_scans, table, None, FloorplanParams(), grid)
    except (KeyError, ValueError):
        return
    assert len(plan.rooms) == 0 or all(p.is_valid for p in plan.rooms["polygon"])


def wall_lines(plan, theta: float) -> list:
    """The plan's wall axes as shapely lines, turned back by ``theta`` (radians, no
    mirror) to the building's own pose."""
    return [back(shapely.LineString([(w.x0, w.y0), (w.x1, w.y1)]), theta, False) for w in plan.walls.itertuples()]


def stubs_at(plan, theta: float, xy: tuple) -> list:
    """The lengths (metres) of the plan's walls shorter than 0.5 m within 0.1 m of the
    point ``xy`` (metres) at the building's own pose (:func:`wall_lines`)."""
    point = shapely.Point(*xy)
    return [g.length for g in wall_lines(plan, theta) if g.length < 0.5 and g.distance(point) < 0.1]


@pytest.mark.slow
def test_a_rigid_motion_keeps_the_plan():
    rng = np.random.default_rng(TEST_SEED)
    miscounted, far = [], []
    for _ in range(POSES):
        case, d = pose_errors(rng)
        if math.isnan(d):
            miscounted.append(case)
        elif d > ROOM_TOLERANCE_M:
            far.append((case, round(d, 3)))
    print(f"{len(miscounted)} of {POSES} poses change a count: {miscounted}; "
          f"{len(far)} move a room farther than {ROOM_TOLERANCE_M:.2f} m: {far}")
    assert len(miscounted) + len(far) <= WRONG_POSES, (miscounted, far)


def test_the_pier_between_a_corner_and_a_door_is_a_wall_at_any_pose():
    """A room of 2.25 m x 2.625 m whose entrance leaves a pier of 0.5 m between the
    room's corner and the door: traced on the turned map its face is 0.49 m, shorter
    than the shortest wall (``min_wall_length_m``), and was clutter there and a wall at
    the building's own pose. As a door's jamb it is a wall at both."""
    b = room_grid_building((2.25,), (2.625,), (0.375, 0.75, 0.75, 0.5, 0.5, 0.125, 0.25))
    ref = map_plan(b)
    got = map_plan(moved(b, 4.01867355926839, True), (0.02261687410704572, 0.006834559085400038))
    assert counts(ref) == counts(got) == (5, 1, 0)
    pier = [w for w in ref.walls.itertuples() if max(w.x0, w.x1) < 0.7 and abs(w.y0 - w.y1) < 0.01]
    assert len(pier) == 1 and 0.45 <= pier[0].length_m <= 0.6


def test_a_partition_that_crosses_a_wall_between_two_doors_is_a_wall_at_any_pose():
    """Six rooms in 3 x 2: the partition between the east column and the middle one
    runs from a door at the south wall to a door at the north wall and crosses the
    middle wall on its way (an X). Nothing holds it at its ends and no wall lies in its
    line, so structure pass 6 made it loose furniture, at every pose; the turned map
    then lost two rooms and two doors. The wall it crosses holds it. The three stubs
    between a door and the outer wall (0.3 m each) are walls at both poses
    (:mod:`floorscan.floorplan.door_frames`)."""
    b = room_grid_building((3.378844928076694, 3.1159663035004495, 2.2250816650429117),
                           (2.949597245345187, 3.29417872724858),
                           (0.8867359057224617, 0.7174189717885862, 0.5604296378053996, 0.04957731665663201,
                            0.9605012498543829, 0.9509421760857373, 0.5511455054204821))  # fmt: skip
    ref = map_plan(b)
    got = map_plan(moved(b, 2.4039311077780257, False), (0.013292708029456047, 0.03558873557284543))
    assert counts(ref) == counts(got) == (15, 6, 7)
    partition = ref.walls[(ref.walls["x0"].sub(6.5).abs() < 0.1) & (ref.walls["x1"].sub(6.5).abs() < 0.1)]
    lengths = np.sort(partition["length_m"].to_numpy())  # the two stubs and the partition
    assert len(lengths) == 3 and 3.5 <= lengths[2] <= 3.8 and lengths[:2] == pytest.approx([0.325, 0.325], abs=0.05)
    assert not (ref.clutter["reason"] == "loose_in_free_space").any()


def test_the_pier_at_a_corner_measures_its_length_from_the_corner_at_any_pose():
    """A room of 2.75 m x 3.375 m whose entrance leaves a 0.4 m pier between the
    room's south-west corner and the door. On the map turned by 64 degrees the wall
    extractor gives the corner's points to the west wall, and the pier's faces start
    0.09 m short of it: 0.27 and 0.29 m, shorter than the plan's shortest face, so the
    plan had five walls at the building's own pose and four turned. Measured from the
    corner (structure step 0) the inner face is 0.35 m at its own pose, 0.34 m turned."""
    b = room_grid_building((2.75,), (3.375,), (0.125, 0.875, 0.125, 1.0, 0.625, 0.0, 0.125))
    ref = map_plan(b)
    got = map_plan(moved(b, 1.111111702894065, True), (0.009389356648595687, 0.024633285831915375))
    assert counts(ref) == counts(got) == (5, 1, 0)
    for plan in (ref, got):
        assert np.sort(plan.walls["length_m"].to_numpy())[0] == pytest.approx(0.375, abs=0.05)


def test_a_stub_beside_a_door_is_a_wall_at_any_pose():
    """Four rooms; the partition between the west rooms leaves a 0.3 m stub between the
    west wall and its door. On the map turned by 0.17 rad one of the stub's two faces
    goes missing and the structure passes drop the other, so the door ran on over the
    stub's cells to the wall's face (1.18 m wide) and the plan had a wall fewer than at
    the building's own pose. The door is cut back to the cells the free space crosses,
    and the occupied cells between its jamb and the west wall are the stub
    (:mod:`floorscan.floorplan.door_frames`)."""
    b = room_grid_building((2.9535072013701673, 2.201263147255986), (3.373116976641538, 2.2672596287166145),
                           (0.26565109926507813, 0.23272839541600399, 0.724749025220941, 0.05343823121230651,
                            0.048434427279979486, 0.295684094661784, 0.5710266406850021))  # fmt: skip
    theta = 0.1725822519681962
    ref = map_plan(b)
    got = map_plan(moved(b, theta, False), (0.005239093268128709, 0.006146615578175658))
    assert counts(ref) == counts(got) == (11, 4, 4)
    for plan, turned in ((ref, 0.0), (got, theta)):
        assert plan.doors["width_m"].between(0.85, 1.0).all()
        stub = stubs_at(plan, turned, (0.2, 3.37))
        assert len(stub) == 1 and stub[0] == pytest.approx(0.35, abs=0.06)


def test_the_stub_beside_an_entrance_is_a_wall_at_any_pose():
    """One room of 2.5 m x 2.875 m whose entrance leaves a 0.35 m stub of the south wall
    between the entrance and the east wall. The entrance is no door between two rooms;
    on the map turned by 4.69 rad the stub lost a face, the structure passes dropped it
    and the plan had four walls where the building's own pose has five. The occupied
    cells between the entrance's jamb and the east wall are a wall, as beside a door
    (:mod:`floorscan.floorplan.door_frames`)."""
    b = room_grid_building((2.5,), (2.875,), (0.875, 0.375, 0.75, 0.25, 0.875, 0.125, 0.25))
    theta = 4.686453841821435
    ref = map_plan(b)
    got = map_plan(moved(b, theta, False), (0.04964027429297932, 0.02097405343285666))
    assert counts(ref) == counts(got) == (5, 1, 0)
    for plan, turned in ((ref, 0.0), (got, theta)):
        stub = stubs_at(plan, turned, (2.25, 0.03))
        assert len(stub) == 1 and stub[0] == pytest.approx(0.37, abs=0.05)


def test_a_room_reaches_its_corners_on_a_map_turned_45_degrees():
    """Three rooms in a row, the map turned by 45 degrees: the walls drawn in steps of
    cells leave pockets of seen floor in the rooms' corners that the closing of the
    walls takes from the space (:func:`~floorscan.floorplan.room_space.room_space`).
    They join the room beside them, so each room lies within three cells of its room at
    the building's own pose (0.26 m when they were no room's)."""
    b = room_grid_building((2.1114626076983574, 3.381191928050069, 3.1833274730621053), (2.247368581191461,),
                           (0.0794980640451326, 0.2138843157643392, 0.5862703134319163, 0.2939242629719411,
                            0.1680193395571592, 0.38050761457499316, 0.8469106918271858))  # fmt: skip
    theta = 0.7854987174932325
    ref = map_plan(b)
    got = map_plan(moved(b, theta, False), (0.02248280948774209, 0.02709127470123573))
    assert counts(ref) == counts(got) == (9, 3, 2)
    rooms = list(ref.rooms["polygon"])
    far = max(min(back(p, theta, False).hausdorff_distance(r) for r in rooms) for p in got.rooms["polygon"])
    assert far <= 3 * MAP_RESOLUTION_M

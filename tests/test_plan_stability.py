"""The plan stands still under shifts, rotations and mirroring of the input (issue 44,
item 4): a synthetic building drawn as a map at any origin a fraction of a cell away,
turned by any angle and mirrored, gives the same rooms and doors, with and without its
furniture, each room within about a cell of the true room.

The origins are Hypothesis examples, derandomized (profile ``ci`` of
``tests/conftest.py``: the same examples on every run) unless
``FLOORSCAN_HYPOTHESIS_PROFILE=dev`` asks for fresh ones. Before the enclosure test of
``loose_in_free_space``, hallways with furniture lost its core's three rooms (11 rooms,
10 doors) in 10 of 30 such shifts: a corner of the core missed by a cell left its loop
of walls open, and the loop was taken for a rack.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.scans import plan_of_scans
from floorscan.sim.building_file import load_building
from floorscan.sim.footprint import building_outline
from floorscan.sim.generated import moved
from floorscan.sim.ground_truth import true_doors, true_rooms
from floorscan.sim.occupancy_map import MAP_RESOLUTION_M, building_map
from floorscan.walls.map_stage import map_of_grid


BUILDINGS = Path(__file__).resolve().parents[1] / "config" / "buildings"
#: The corner of the map before the shift, metres: no whole number of cells from the
#: buildings' own origin.
CORNER = (-3.0, -2.0)
#: Examples per building and furniture: four cases make 80 plans, about 25 s.
EXAMPLES = 20
#: A plan room and its true room overlap at least this much (intersection over union):
#: a room of 3 m x 3 m whose outline lies a 5 cm cell off all round has 0.94; hallways'
#: room C2 with its furniture has 0.87 at any pose, its rack drawn as a closet (the
#: expected failure of tests/test_building_map.py).
MIN_ROOM_IOU = 0.85


@pytest.fixture(scope="module", params=["demo", "hallways"])
def building(request):
    b = load_building(BUILDINGS / f"{request.param}.yaml")
    n_doors = int((~true_doors(b)["exterior"].to_numpy(bool)).sum())
    return b, len(true_rooms(b)), n_doors


@pytest.mark.slow
@pytest.mark.parametrize("furniture", [False, True], ids=["empty", "furnished"])
@settings(max_examples=EXAMPLES)
@given(dx=st.floats(0.0, MAP_RESOLUTION_M, exclude_max=True), dy=st.floats(0.0, MAP_RESOLUTION_M, exclude_max=True))
def test_a_sub_cell_shift_keeps_every_room_and_door(building, furniture, dx, dy):
    b, n_rooms, n_doors = building
    logging.disable(logging.INFO)
    try:
        grid = building_map(b, furniture=furniture, origin_xy=(CORNER[0] + dx, CORNER[1] + dy))
        plan = plan_of_scans(map_of_grid(grid, None), None, FloorplanParams(), grid)
    finally:
        logging.disable(logging.NOTSET)
    assert (len(plan.rooms), len(plan.doors)) == (n_rooms, n_doors), (dx, dy)


#: Poses per building and furniture, drawn from a seeded generator.
POSES = 30
#: The most poses of :data:`POSES` on which the plan may lose or gain a room or door
#: (measured: the docstring of the test). Issue 44 wants none; a change that makes the
#: plan less stable fails here.
WRONG_POSES = {("demo", False): 0, ("demo", True): 0, ("hallways", False): 0, ("hallways", True): 0}


@pytest.mark.slow
@pytest.mark.parametrize("furniture", [False, True], ids=["empty", "furnished"])
def test_a_rigid_motion_keeps_every_room_and_door(building, furniture):
    """Any rotation, mirroring and sub-cell shift (:data:`POSES` seeded poses) gives the
    true rooms and doors, each plan room within :data:`MIN_ROOM_IOU` of a true room, on
    all but :data:`WRONG_POSES` poses (none of these 30). On 120 seeded poses, hallways
    empty and demo are right on all; hallways furnished is wrong on 5: on four its room
    C2, its rack drawn as a closet, falls just under :data:`MIN_ROOM_IOU` (the expected
    failure of tests/test_building_map.py), and on one the ring corridor is parted at
    the furniture standing in it (15 rooms, 15 doors). Before the room step cut each
    opening once (:func:`~floorscan.floorplan.doors.distinct_gaps`), 9 were wrong, 5 of
    them a door short: the door found between two walls' ends and again on the
    corridor side's line, whose two cuts left a sliver between them."""
    b0, n_rooms, n_doors = building
    rng = np.random.default_rng(44)
    wrong = []
    for _ in range(POSES):
        theta, mirror = float(rng.uniform(0, 2 * math.pi)), bool(rng.integers(2))
        dx, dy = (float(v) for v in rng.uniform(0, MAP_RESOLUTION_M, 2))
        b = moved(b0, theta, mirror)
        x0, y0 = (math.floor(v / MAP_RESOLUTION_M) * MAP_RESOLUTION_M - 1.0 for v in building_outline(b).bounds[:2])
        logging.disable(logging.INFO)
        try:
            grid = building_map(b, furniture=furniture, origin_xy=(x0 + dx, y0 + dy))
            plan = plan_of_scans(map_of_grid(grid, None), None, FloorplanParams(), grid)
        finally:
            logging.disable(logging.NOTSET)
        truth = list(true_rooms(b)["polygon"])
        iou = min((max(r.intersection(t).area / r.union(t).area for t in truth) for r in plan.rooms["polygon"]), default=0)
        if (len(plan.rooms), len(plan.doors)) != (n_rooms, n_doors) or iou < MIN_ROOM_IOU:
            wrong.append((round(theta, 3), mirror, len(plan.rooms), len(plan.doors), round(iou, 2)))
    print(b0.name, furniture, len(wrong), wrong)
    assert len(wrong) <= WRONG_POSES[(b0.name, furniture)], wrong

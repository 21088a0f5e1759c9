"""The benchmark's large synthetic building (issue 46, item 3): a valid building file of
200 m x 200 m, its rooms and doors as the simulator's ground truth counts them, and a
rover path of about 20 000 scans."""

from __future__ import annotations

import numpy as np

from benchmarks.campus import CAMPUS_SPEED_MPS, write_campus
from floorscan.sim.building_file import load_building
from floorscan.sim.ground_truth import true_doors, true_rooms
from floorscan.sim.trajectory import rover_trajectory


def test_the_campus_is_a_200_m_building_of_240_rooms_and_20000_scans(tmp_path):
    path = tmp_path / "campus200.yaml"
    mapping = write_campus(path)
    building = load_building(path)  # checks the walls, the openings and the rover's path
    assert mapping["walls"][0]["points"] == [[0, 0], [200, 0], [200, 200], [0, 200]]
    rooms = true_rooms(building)
    assert len(rooms) == 241  # 240 rooms and the corridors' space
    assert len(true_doors(building, rooms)) == 240
    wp = np.array(mapping["waypoints"])
    assert np.ptp(wp, axis=0).min() > 150
    trajectory = rover_trajectory(wp, CAMPUS_SPEED_MPS, 1.0)
    assert 19_000 <= trajectory.duration_s * 10 <= 22_000  # scans at 10 Hz

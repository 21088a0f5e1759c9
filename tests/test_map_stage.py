"""The map extractor of all kept scans on the reference map's grid (issue 46): the grid
of the same scans with the same settings is not cast again, and gives the same files."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from floorscan.core.io import REGISTERED, write_table
from floorscan.core.occupancy import OccupancyParams, occupancy_grid, write_grid
from floorscan.score.reference import reference_of_recording
from floorscan.walls.map_stage import map_grid_params, map_of_scans, write_map_walls


@pytest.fixture
def room(tmp_path):
    """Four scans of a 6 m x 4 m room, taken at four places inside it."""
    rng = np.random.default_rng(0)
    ang = np.linspace(-math.pi, math.pi, 720, endpoint=False)
    rows, reg = [], []
    for sid, (ox, oy) in enumerate([(1.0, 1.0), (4.5, 1.2), (2.5, 3.0), (5.0, 3.1)]):
        d = np.column_stack([np.cos(ang), np.sin(ang)])
        # distance to the walls x = 0, 6 and y = 0, 4 along each ray
        with np.errstate(divide="ignore"):
            tx = np.where(d[:, 0] > 0, (6.0 - ox) / d[:, 0], np.where(d[:, 0] < 0, -ox / d[:, 0], np.inf))
            ty = np.where(d[:, 1] > 0, (4.0 - oy) / d[:, 1], np.where(d[:, 1] < 0, -oy / d[:, 1], np.inf))
        r = np.minimum(tx, ty) + rng.normal(0.0, 0.005, len(ang))
        rows.append(pd.DataFrame({"scan_id": sid, "x": ox + r * d[:, 0], "y": oy + r * d[:, 1], "z": 0.0}))
        reg.append((sid, True, ox, oy))
    path = tmp_path / "registered.parquet"
    write_table(pd.concat(rows, ignore_index=True), path, schema=REGISTERED, metadata={"dataset": "room"})
    return path, pd.DataFrame(reg, columns=["scan_id", "kept", "x_m", "y_m"])


def test_the_map_of_all_kept_scans_on_the_reference_grid_writes_the_same_files(room, tmp_path, monkeypatch):
    import floorscan.walls.map_stage as map_stage

    path, registration = room
    reg_path = tmp_path / "registration.parquet"
    registration.to_parquet(reg_path)
    cast = write_map_walls(path, reg_path, None, {}, tmp_path / "cast.parquet", tmp_path / "cast_grid.parquet")
    reference = reference_of_recording(path, registration, {}, OccupancyParams())
    assert reference.params == map_grid_params({})
    write_grid(reference, tmp_path / "reference.parquet", {"against_ground_truth_x": "1.0"})

    def cast_again(*args, **kwargs):
        raise AssertionError("the scans were cast again")

    monkeypatch.setattr(map_stage, "occupancy_grid", cast_again)
    taken = write_map_walls(path, reg_path, None, {}, tmp_path / "taken.parquet", tmp_path / "taken_grid.parquet",
                            tmp_path / "reference.parquet")
    assert cast == taken and cast["n_segments"] >= 4
    for a, b in (("cast.parquet", "taken.parquet"), ("cast_grid.parquet", "taken_grid.parquet")):
        assert (tmp_path / a).read_bytes() == (tmp_path / b).read_bytes(), a


def test_a_grid_of_other_settings_or_other_scans_is_refused(room):
    path, registration = room
    coarse = reference_of_recording(path, registration, {}, replace(OccupancyParams(), resolution_m=0.1))
    with pytest.raises(ValueError, match="the grid given is not theirs"):
        map_of_scans(path, registration, None, {}, coarse)
    from floorscan.core.io import iter_scans

    origins = dict(zip(registration["scan_id"], registration[["x_m", "y_m"]].to_numpy()))
    three = occupancy_grid([(origins[sid], xyz[:, :2]) for sid, xyz in iter_scans(path) if sid < 3], OccupancyParams())
    with pytest.raises(ValueError, match="3 scans; expected"):
        map_of_scans(path, registration, None, {}, three)
    # the map's own cell setting is the grid's
    assert map_grid_params({"map": {"support_cell_m": 0.1}}) == coarse.params

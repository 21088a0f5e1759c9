"""The memory a run will need, known before it runs out (issue 46, item 4): the estimate
of a grid sized by the site, checked against the machine's free memory before the grid
is allocated."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from floorscan.core.memory import JobMemory, MemoryEstimateError, check_memory, free_memory_bytes
from floorscan.core.occupancy import OccupancyParams, occupancy_grid
from floorscan.core.prefix_grids import prefix_grids
from floorscan.core.ray_casting import (
    COUNTS_BYTES_PER_CELL, RAY_SAMPLE_BYTES, GridFrame, check_memory_of_casting, ray_samples,
)


def _hall(width_m: float, depth_m: float, n_scans: int = 4, seed: int = 0):
    """Scans of a hall's four walls from points inside it (returns sampled along the walls)."""
    rng = np.random.default_rng(seed)
    t = rng.uniform(0, 1, (400, 1))
    walls = np.vstack([np.hstack([t * width_m, 0 * t]), np.hstack([t * width_m, 0 * t + depth_m]),
                       np.hstack([0 * t, t * depth_m]), np.hstack([0 * t + width_m, t * depth_m])])
    return [(np.array([width_m, depth_m]) * rng.uniform(0.2, 0.8, 2), walls + rng.normal(0, 0.01, walls.shape))
            for _ in range(n_scans)]


def test_the_machine_has_free_memory():
    free = free_memory_bytes()
    assert free is not None and 10e6 < free < 2**50


def test_the_estimate_of_a_grid_is_its_cells_times_bytes():
    """A hall of 100 m x 45 m at 5 cm with the 0.5 m margin: 2021 x 921 cells (both
    extents + 1 cell); the counts being built take 24 bytes a cell: 44.7 MB, and the
    job's other parts add up."""
    scans = [(np.array([50.0, 22.5]), np.array([[0.0, 0.0], [100.0, 45.0]]))]
    frame = GridFrame.of(scans, 0.05, 0.5)
    assert (frame.width, frame.height) == (2021, 921)
    job = JobMemory(COUNTS_BYTES_PER_CELL, "walls.map.support_cell_m")
    assert job.check("a hall", (frame.height, frame.width), 0.05, {"points": 1e6}, free=10**9) == 2021 * 921 * 24 + 1e6
    assert check_memory("a hall", {"a": 1.0, "b": 2.0}, "x", free=3) == 3.0
    # a job working on the scans' points: 11.2 M wall points x 40 bytes beside the grid
    job = JobMemory(32, "walls.map.support_cell_m", bytes_per_point=40)
    assert job.check("a hall", (921, 2021), 0.05, free=10**10, points=11_166_312) == 921 * 2021 * 32 + 11_166_312 * 40


def test_the_estimate_covers_what_building_the_grid_takes():
    """Building the occupancy grid of a hall (60 m x 30 m: 0.74 M cells, its largest
    scan 1.85 M ray samples; 20 m x 10 m: 0.09 M cells, 0.62 M samples) allocates at
    most the estimate (24 bytes a cell, 40 a ray sample) and at least two thirds of it:
    the estimate is of the arrays, not a guess."""
    params = OccupancyParams()
    for width, depth in [(60.0, 30.0), (20.0, 10.0)]:
        scans = _hall(width, depth)
        frame = GridFrame.of(scans, params.resolution_m, params.margin_m)
        samples = max(ray_samples(o, p, frame.r, params.step_fraction) for o, p in scans)
        estimate = check_memory_of_casting(scans, frame, params.step_fraction, "a hall",
                                           JobMemory(COUNTS_BYTES_PER_CELL, "walls.map.support_cell_m"))
        assert estimate == frame.width * frame.height * COUNTS_BYTES_PER_CELL + samples * RAY_SAMPLE_BYTES
        tracemalloc.start()
        try:
            occupancy_grid(scans, params)
            _, peak = tracemalloc.get_traced_memory()
        finally:
            tracemalloc.stop()
        assert 2 / 3 * estimate < peak <= estimate, (width, peak, estimate)


def test_a_grid_larger_than_the_free_memory_stops_before_it_is_allocated(monkeypatch):
    """With 50 MB free, the grid of a 300 m x 200 m site at 5 cm (6021 x 4021 cells,
    0.58 GB of counts) stops before a byte of it is allocated, with one message: the
    estimate, the memory free and the setting to change."""
    import floorscan.core.memory as memory

    monkeypatch.setattr(memory, "free_memory_bytes", lambda: 50_000_000)
    scans = [(np.array([150.0, 100.0]), np.array([[0.0, 0.0], [300.0, 200.0]]))]
    job = JobMemory(COUNTS_BYTES_PER_CELL, "walls.map.support_cell_m")
    tracemalloc.start()
    try:
        with pytest.raises(MemoryEstimateError) as err:
            occupancy_grid(scans, OccupancyParams(), "the occupancy grid of 1 scan of dataset 'site'", job)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 1_000_000
    msg = str(err.value)
    assert msg.startswith("the occupancy grid of 1 scan of dataset 'site' would need about 0.58 GB more memory")
    assert "(6021 x 4021 cells of 0.05 m x 24 bytes 0.58 GB, the rays of the largest scan" in msg
    assert "more than the 0.05 GB free" in msg
    assert "walls.map.support_cell_m (now 0.05 m)" in msg and "\n" not in msg
    with pytest.raises(MemoryEstimateError):  # the same scans' prefix grids: before the first grid
        next(prefix_grids(scans, [1], OccupancyParams(), "grids", job))
    monkeypatch.setattr(memory, "free_memory_bytes", lambda: None)  # unknown: no check
    assert job.check("a site", (4021, 6021), 0.05) == 6021 * 4021 * 24


def test_the_map_extractor_and_the_scoring_jobs_stop_before_their_rasters(monkeypatch, tmp_path):
    """The jobs whose rasters are sized by the site check before they allocate them:
    the map extractor's grid (map_walls: walls.map.support_cell_m), and a grid read by
    a scoring job (the reference map: score.reference.resolution_m), whose check reads
    the file's metadata only."""
    import floorscan.core.memory as memory
    from floorscan.core.occupancy import write_grid
    from floorscan.score.against_reference import SCORING_MEMORY, read_reference
    from floorscan.walls.map_stage import MAP_MEMORY

    scans = _hall(60.0, 30.0)
    grid = occupancy_grid(scans)
    write_grid(grid, tmp_path / "occupancy.parquet")
    assert read_reference(tmp_path / "occupancy.parquet").shape == grid.shape
    cells = grid.shape[0] * grid.shape[1]
    monkeypatch.setattr(memory, "free_memory_bytes", lambda: int(cells * SCORING_MEMORY.bytes_per_cell) - 1)
    with pytest.raises(MemoryEstimateError, match=r"scoring against the reference map .* score.reference.resolution_m \(now 0.05 m\)"):
        read_reference(tmp_path / "occupancy.parquet")
    monkeypatch.setattr(memory, "free_memory_bytes", lambda: int(cells * MAP_MEMORY.bytes_per_cell) - 1)
    with pytest.raises(MemoryEstimateError, match=r"walls.map.support_cell_m \(now 0.05 m\)"):
        occupancy_grid(scans, OccupancyParams(), "the map", MAP_MEMORY)

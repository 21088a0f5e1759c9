"""No raster sized by the data without a bound (issue 45, item 4): the occupancy grid of
the walls stage (and of the reference), the selection's coverage raster and the scoring
grid are refused before they are allocated when they would take more than
:data:`floorscan.core.grid.MAX_RASTER_BYTES` (half of a job's 2 GB), naming the extent in
metres, the cells and the memory (:func:`floorscan.core.grid.check_raster_size`).

Before, a PCD folder in millimetres ended in a ``MemoryError`` traceback in ``map_walls``:
its occupancy grid asked for 26 GiB. The units check at ingest
(tests/test_bad_input_units.py) now stops such a folder first; this is the backstop.
"""

import math
import tracemalloc

import numpy as np
import pandas as pd
import pytest

from floorscan.core.grid import MAX_RASTER_BYTES, check_raster_size
from floorscan.core.io import REGISTERED, InputError, write_table
from floorscan.core.occupancy import occupancy_grid


def test_an_occupancy_grid_too_large_is_refused_before_it_is_allocated():
    """Two scans 40 km apart (a pose in millimetres): 4.8e11 cells, 10 TiB, were asked of numpy."""
    scans = [(np.zeros(2), np.array([[1.0, 0.0], [0.0, 1.0]])),
             (np.array([40_000.0, 0.0]), np.array([[40_001.0, 0.0], [40_000.0, 30_000.0]]))]
    tracemalloc.start()
    try:
        with pytest.raises(InputError) as info:
            occupancy_grid(scans, what="the occupancy grid of 2 scans")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 10_000_000  # refused before any array of the grid's size
    msg = str(info.value)
    assert msg.startswith("the occupancy grid of 2 scans: the data spans 40001 m x 30000 m, which at 0.05 m cells "
                          "needs 800041 x 600021 = 4.8e+11 cells, 1.07e+04 GiB (24 bytes a cell), more than the 1 GB a "
                          "raster may take (half of a job's 2 GB)"), msg
    assert "in millimetres" in msg


def test_map_walls_of_scans_in_millimetres_names_the_dataset_extent_cells_and_memory(tmp_path):
    """The issue's case: the registered scans of a PCD folder in millimetres reached
    ``map_walls``, whose occupancy grid asked for 26 GiB."""
    from floorscan.walls.map_stage import map_of_scans

    ang = np.linspace(-math.pi / 2, math.pi / 2, 181)
    rows, reg = [], []
    for sid in range(3):
        ox, oy = 2000.0 + 500.0 * sid, 3000.0  # millimetres
        r = 4000.0 + 100.0 * sid
        rows.append(pd.DataFrame({"scan_id": sid, "x": ox + r * np.cos(ang), "y": oy + r * np.sin(ang), "z": 0.0}))
        reg.append((sid, True, ox, oy))
    path = tmp_path / "registered.parquet"
    write_table(pd.concat(rows, ignore_index=True), path, schema=REGISTERED, metadata={"dataset": "pcd_mm"})
    registration = pd.DataFrame(reg, columns=["scan_id", "kept", "x_m", "y_m"])
    with pytest.raises(InputError) as info:
        map_of_scans(path, registration, None, {})
    msg = str(info.value)
    assert msg.startswith(f"the occupancy grid of all kept 3 scans of dataset 'pcd_mm' ({path}): the data spans "), msg
    assert " m x " in msg and "cells, " in msg and " GiB (24 bytes a cell)" in msg, msg
    assert "expected a building's extent in metres, at most about 323 m square at 0.05 m" in msg


def test_the_raster_bound_passes_the_largest_shared_grid():
    """acapulco's grid of the walls stage, 2798 x 963 cells of 5 cm, the largest of the
    shared recordings, is far inside the bound; a building 2 km square is not."""
    check_raster_size("grid", (0.0, 0.0), (139.9, 48.15), 0.05, (963, 2798), 24)
    assert 2798 * 963 * 24 < MAX_RASTER_BYTES / 10
    with pytest.raises(InputError, match="needs 40000 x 40000 = 1.6e[+]09 cells"):
        check_raster_size("grid", (0.0, 0.0), (2000.0, 2000.0), 0.05, (40000, 40000), 24)


def test_the_scoring_grid_is_bounded_too_and_the_coverage_raster_needs_no_bound():
    """The scoring grid is sized by the walls' extent: bounded. The selection's coverage
    raster holds only the tiles its scans touch (issue 46): two scans 300 km apart take
    two tiles, not the extent between them."""
    import shapely

    from floorscan.core.segment_raster import grid_for
    from floorscan.select.raster import RasterCoverage

    far = [shapely.box(0, 0, 1, 1), shapely.box(3e5, 3e5, 3e5 + 1, 3e5 + 1)]
    cov = RasterCoverage(far)
    assert cov.covered.size <= 2 * 4 * 128 * 128 and list(cov.counts) == [400, 400]
    with pytest.raises(InputError, match=r"^scoring grid of the reference walls \(score.cell_m\): the data spans "
                                         r"300000 m x 1 m, which at 0.05 m cells needs 6000040 x 60"):
        grid_for([[0.0, 0.0, 3e5, 0.0], [3e5, 0.0, 3e5, 1.0]])

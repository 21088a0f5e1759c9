"""The reference map of a recording: the occupancy grid of all its kept scans
(:func:`reference_of_recording`; the grid itself, its parameters and files are
:mod:`floorscan.core.occupancy`, shared with the floor plan's structure passes).

Usage::

    grid = reference_of_recording("registered.parquet", registration, walls_config)
    floorscan.core.occupancy.write_map_server(grid, "map.pgm", "map.yaml")
    structure_xy = grid.cell_centres(grid.structure())
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from floorscan.core.memory import JobMemory
from floorscan.core.occupancy import OccupancyGrid, OccupancyParams, occupancy_grid
from floorscan.core.ray_casting import COUNTS_BYTES_PER_CELL

#: What a cell of the reference map takes the job that makes it: the counts being built
#: (:data:`floorscan.core.ray_casting.COUNTS_BYTES_PER_CELL`) and the figure of the
#: whole grid drawn by the same job (its RGBA image and matplotlib's copies of it: 56
#: bytes a cell at the job's peak, rounded up, ``benchmarks/README.md``).
REFERENCE_MEMORY = JobMemory(COUNTS_BYTES_PER_CELL + 56, "score.reference.resolution_m")


def reference_of_recording(
    registered_path: str | Path,
    registration: pd.DataFrame,
    walls_config: dict | None = None,
    params: OccupancyParams = OccupancyParams(),
) -> OccupancyGrid:
    """The occupancy grid of a recording's kept scans.

    Parameters
    ----------
    registered_path : path
        ``registered.parquet``: the kept scans' points in the map frame (streamed
        scan by scan).
    registration : pandas.DataFrame
        ``registration.parquet``: ``scan_id``, ``kept``, ``x_m``, ``y_m`` (the scanner's
        registered position, the rays' origin).
    walls_config : mapping, optional
        The ``walls`` config section: its height band cuts 3D scans
        (:func:`floorscan.core.wall_points.scan_points_2d`), as for the walls themselves.
    params : OccupancyParams

    Returns
    -------
    OccupancyGrid

    Raises
    ------
    ValueError
        When a scan of ``registered_path`` has no kept row with a pose, or none has a
        return in the height band.
    floorscan.core.io.InputError
        When the grid would be too large, or the job's rasters (:data:`REFERENCE_MEMORY`)
        would not fit in the memory free on the machine, before it is allocated.
    """
    from floorscan.core.io import iter_scans
    from floorscan.core.config import stage_params
    from floorscan.core.wall_points import ScanParams, scan_points_2d

    scan_params = stage_params(ScanParams, walls_config)
    reg = registration[registration["kept"]].set_index("scan_id")
    origin = dict(zip(reg.index.tolist(), reg[["x_m", "y_m"]].to_numpy(np.float64)))  # one lookup a scan

    def scans():
        for sid, pts in iter_scans(registered_path):
            if sid not in origin:
                raise ValueError(f"{registered_path}: scan {sid} has no kept row in the registration table")
            xy, _ = scan_points_2d(pts, scan_params)
            yield origin[sid], xy

    what = f"the reference map of the {len(origin)} kept scans of {registered_path}"
    return occupancy_grid(scans(), params, what, REFERENCE_MEMORY)

"""An occupancy grid whose classes are given, not measured: a map (what a ROS map_server
map holds, :mod:`floorscan.ingest.occupancy_map`; the simulator's plan view of its own
building, :mod:`floorscan.sim.occupancy_map`) as the grid the walls and rooms read
(:class:`~floorscan.core.occupancy.OccupancyGrid`).

The grid holds each class as scan counts: an occupied cell as hit by ``min_scans``
scans (and by enough to pass ``occupied_thresh``), a free cell as crossed by the fewest
scans that put it under ``free_thresh``, an unknown cell as neither; so every consumer
of the grid (``occupied()``, ``free()``, ``structure()``) reads the given classes
unchanged. A map has no scan positions: ``scan_xy`` is None.

Usage::

    grid = grid_of_classes(occupied, free, origin_xy=(x0, y0), resolution_m=0.05)
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from floorscan.core.occupancy import OccupancyGrid, OccupancyParams, logit


def grid_of_classes(
    occupied: np.ndarray, free: np.ndarray, origin_xy, resolution_m: float, params: OccupancyParams = OccupancyParams()
) -> OccupancyGrid:  # fmt: skip
    """An occupancy grid whose classes are given: each occupied cell hit by
    ``params.min_scans`` scans (and at least enough to pass ``occupied_thresh``), each
    free cell crossed by the fewest scans that put it under ``free_thresh``.

    Parameters
    ----------
    occupied, free : (H, W) bool ndarray
        Row 0 at the bottom (the grid's ``y = origin_y + (i + 0.5) r``); disjoint.
    origin_xy : (2,) float
        The corner of cell (0, 0), metres.
    resolution_m : float
        Cell size, metres.
    params : OccupancyParams
        Its ``resolution_m`` is replaced by ``resolution_m``.

    Returns
    -------
    OccupancyGrid
        ``occupied()`` and ``free()`` equal ``occupied`` and ``free``; ``structure()``
        equals ``occupied``; ``scan_xy`` None.

    Raises
    ------
    ValueError
        When the masks differ in shape or overlap.
    """
    occupied, free = np.asarray(occupied, bool), np.asarray(free, bool)
    if occupied.shape != free.shape or occupied.ndim != 2:
        raise ValueError(f"occupied and free must be (H, W) of one shape, got {occupied.shape} and {free.shape}")
    if (occupied & free).any():
        raise ValueError("a cell cannot be both occupied and free")
    p = replace(params, resolution_m=float(resolution_m))
    n_hit = max(int(p.min_scans), math.floor(logit(p.occupied_thresh) / logit(p.prob_hit)) + 1)
    n_miss = math.floor(logit(p.free_thresh) / logit(p.prob_miss)) + 1
    return OccupancyGrid(
        origin_xy=np.asarray(origin_xy, dtype=np.float64).reshape(2), resolution_m=float(resolution_m),
        n_hit_scans=np.where(occupied, n_hit, 0).astype(np.int32), n_miss_scans=np.where(free, n_miss, 0).astype(np.int32),
        params=p,
    )  # fmt: skip

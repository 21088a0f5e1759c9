"""The occupancy grids of the first k scans of a sequence, for increasing k, each scan cast
once (:func:`prefix_grids`): the grid of the first k + dk scans is the counts of the
first k plus those of the next dk. The answer's plans of the first k scans
(:mod:`floorscan.floorplan.answer_plans`) are built on them.

Every grid equals :func:`floorscan.core.occupancy.occupancy_grid` of the same scans:
origin, shape, counts and scan positions. The counts are held in the frame of the grid
of all the scans (:mod:`floorscan.core.ray_casting`), and a grid is their window over
its own extent. A cell is measured from the frame's origin, which can round a point
lying on a cell's edge (a pose logged to the centimetre on a 5 cm grid) into the cell
beside: a scan with a return or ray sample on an edge is counted apart, cast again for
each origin the grids take, in that origin's frame, as ``occupancy_grid`` casts it.

Usage::

    for k, grid in prefix_grids(scans, [1, 2, 4, 8], OccupancyParams()):
        ...  # grid: OccupancyGrid of scans[:k], or None when none of them has a return
"""

from __future__ import annotations

from typing import Iterable, Iterator, Sequence

import numpy as np

from floorscan.core.memory import JobMemory
from floorscan.core.occupancy import OccupancyGrid, OccupancyParams
from floorscan.core.ray_casting import CellCounts, GridFrame, check_memory_of_casting, with_returns


def prefix_grids(
    scans: Sequence[tuple[np.ndarray, np.ndarray]], ks: Iterable[int], params: OccupancyParams = OccupancyParams(),
    what: str = "occupancy grid", memory: JobMemory | None = None,
) -> Iterator[tuple[int, OccupancyGrid | None]]:
    """The occupancy grids of the first k scans, for increasing k (see the module docstring).

    Parameters
    ----------
    scans : sequence of (origin, points)
        Per scan the scanner's position in the map frame ((2,) float, metres) and its
        returns in the map frame ((M, 2) float, metres, plan view), in order; a scan
        without a return counts in k.
    ks : iterable of int
        Increasing numbers of scans, each from 1 to ``len(scans)``.
    params : OccupancyParams
    what : str
        The grids and whose scans, for the error of a grid too large.
    memory : JobMemory, optional
        What the job's rasters take a cell of the grid of all the scans: the job stops
        before it is allocated when they and the rays of the largest scan would not fit
        in the free memory (:func:`floorscan.core.ray_casting.check_memory_of_casting`).

    Yields
    ------
    (k, OccupancyGrid or None)
        Per k its grid (its own arrays: the later scans leave it as it is), None when
        none of the first k scans has a return.

    Raises
    ------
    ValueError
        When the ks do not increase within 1 .. ``len(scans)``, or a coordinate is not
        finite; an ``InputError`` when the grid of all the scans would be too large
        (:func:`floorscan.core.grid.check_raster_size`) or, with ``memory``, need more
        memory than is free, before it is allocated.
    """
    params.check()
    scans = [(np.asarray(o, dtype=np.float64)[:2], np.asarray(p, dtype=np.float64)[:, :2]) for o, p in scans]
    ks = [int(k) for k in ks]
    if any(b <= a for a, b in zip(ks, ks[1:])) or (ks and not 1 <= ks[0] <= ks[-1] <= len(scans)):
        raise ValueError(f"prefix grids: expected increasing k from 1 to {len(scans)}, got {ks}")
    returns = with_returns(scans)
    if returns:
        frame = GridFrame.of(returns, params.resolution_m, params.margin_m, what)
        if memory is not None:
            check_memory_of_casting(returns, frame, params.step_fraction, what, memory)
        counts = CellCounts(frame, params.step_fraction)
    done, origins, on_edge = 0, [], []
    cast: list[list] = []  # per scan of on_edge: [hit, missed, width] from the origin `origin`
    origin = None
    for k in ks:
        for o, p in scans[done:k]:
            if not len(p):
                continue
            hit, missed, edge = counts.cells(o, p, counts.frame, edges=True)
            if edge:
                on_edge.append((o, p))
            else:
                counts.add(hit, missed)
            origins.append(o)
        done = k
        if not origins:
            yield k, None
            continue
        frame = GridFrame.of(with_returns(scans[:k]), params.resolution_m, params.margin_m)
        hits, misses = counts.window(frame)
        if origin is None or origin.tobytes() != frame.origin.tobytes():
            origin, cast = frame.origin, []
        for o, p in on_edge[len(cast):]:  # cast from the grid's own origin, as occupancy_grid casts them
            cast.append([*counts.cells(o, p, frame)[:2], frame.width])
        for c in cast:
            if c[2] != frame.width:  # the same origin, more columns
                c[:] = [*((i // c[2]) * frame.width + i % c[2] for i in c[:2]), frame.width]
            hits.reshape(-1)[c[0]] += 1
            misses.reshape(-1)[c[1]] += 1
        yield k, OccupancyGrid(origin_xy=frame.origin, resolution_m=frame.r, n_hit_scans=hits, n_miss_scans=misses,
                               params=params, scan_xy=np.array(origins, dtype=np.float64).reshape(-1, 2))

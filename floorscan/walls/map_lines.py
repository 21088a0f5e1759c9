"""The map extractor: wall segments fitted on the registered points of many scans
together (the answer's floor plan), not scan by scan.

The thesis extracts walls scan by scan (sections 3.4 and 5.3) because its subject is
the ordering; it leaves the extraction open ("any wall extraction can be put in
place", section 5.1). A wall that many scans each see sparsely, at range or at a
grazing angle, is found in no single scan; fitted on the map of the selected scans it
is. The per-scan extractors (:mod:`~floorscan.walls.ransac`,
:mod:`~floorscan.walls.cluster`) stay: they drive the orderings and the quality curves.

:func:`map_segments` works on the union of the scans' 2D wall points
(:func:`floorscan.core.wall_points.scan_points_2d`, in the map frame):

1. **Support** (:func:`supported_points`). A point counts when its cell of the
   occupancy grid of the same scans (:mod:`floorscan.core.occupancy`, cells of
   ``support_cell_m``) is occupied: its returns outweigh the rays of the other scans
   that passed through it (log-odds, Thrun et al., *Probabilistic Robotics*, ch. 9). A
   person walking by, seen by one scan and seen through by the next, is not; a wall
   seen by one selected scan and contradicted by none is (the selection keeps few scans
   per wall, so a count of scans would drop it).
2. **Thinning** to one mean point per ``grid_m`` cell
   (:func:`floorscan.core.grid.cell_means`), so a wall seen by many scans weighs as
   much as one seen by few, and the cost follows the map's size, not the scan count.
3. **Iterative RANSAC** (thesis section 5.3, Algorithm 4; Fischler and Bolles 1981),
   :func:`floorscan.walls.ransac.ransac_rows` with the map's settings: the line with
   most inliers, refit by total least squares, cut into pieces at gaps wider than
   ``max_gap_m``; a piece with ``min_inliers`` points and ``min_length_m`` of length is
   a wall segment. No coverage test: a wall seen sparsely at range is sampled every
   few decimetres. But a segment is cut where the grid saw its line free and no scan
   hit it, a cell to either side too, over more than two cells
   (:func:`_apart_where_seen_free`): the floor seen between the legs of a row of tables
   or chairs, which ``max_gap_m`` bridges, is no wall's. A cell some scans hit and
   others saw through (a wall smeared by drifting poses) is not cut.

Which segments are walls and which are furniture, which gaps are openings and which
are occlusions, and where walls meet are the floor plan's passes
(:mod:`floorscan.floorplan.structure`), which know the free space.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from floorscan.core.config import schema_defaults
from floorscan.core.occupancy import OccupancyGrid
from floorscan.core.grid import cell_means
from floorscan.walls.params import RansacParams
from floorscan.walls.ransac import ransac_rows
from floorscan.walls.tables import segments_frame


#: Thinning cell, metres: finer than the inlier distance, so thinning moves no wall off its line.
MAP_GRID_M = 0.03
#: RANSAC inlier distance on the map, metres: the scans' registration error adds to the range noise of one scan.
MAP_THRESHOLD_M = 0.04
#: RANSAC hypotheses per line: a map's wall holds a far smaller share of its points than a scan's wall.
MAP_ITERATIONS = 1000
#: Inliers of a line and points of a piece, at least: five thinned points span a 0.12 m piece.
MAP_MIN_INLIERS = 5
#: A line's points split into pieces at gaps wider than this, metres (the floor plan joins what free space does not cross).
MAP_MAX_GAP_M = 0.3
#: Pieces shorter than this are no wall segment, metres: the floor plan's passes judge the short ones by the free space.
MAP_MIN_LENGTH_M = 0.1
#: RANSAC lines, at most: a bound far above the wall lines of a floor of hundreds of rooms.
MAP_MAX_LINES = 5000


@dataclass(frozen=True)
@schema_defaults("walls.map")
class MapParams:
    """Parameters of the map extractor (config ``walls.map``: ``support_cell_m``; the
    others are the module's constants; see the module docstring).

    Attributes
    ----------
    support_cell_m : float
        Cell of the occupancy grid of the support test, metres.
    grid_m : float
        Thinning cell, metres.
    threshold_m : float
        RANSAC inlier distance, metres.
    iterations : int
        RANSAC hypotheses per line.
    min_inliers : int
        Inliers of a line, and points of a piece, at least.
    max_gap_m : float
        A line's points split into pieces at gaps wider than this, metres.
    min_length_m : float
        Length of a wall segment, at least, metres.
    max_lines : int
        RANSAC lines, at most.
    """

    support_cell_m: float
    grid_m: float = MAP_GRID_M
    threshold_m: float = MAP_THRESHOLD_M
    iterations: int = MAP_ITERATIONS
    min_inliers: int = MAP_MIN_INLIERS
    max_gap_m: float = MAP_MAX_GAP_M
    min_length_m: float = MAP_MIN_LENGTH_M
    max_lines: int = MAP_MAX_LINES

    def ransac(self) -> RansacParams:
        """The :class:`~floorscan.walls.params.RansacParams` of the map's RANSAC (two
        refits, no coverage test).

        Returns
        -------
        RansacParams
            ``threshold_m``, ``iterations``, ``min_inliers``, ``max_lines``, ``min_length_m``
            and ``max_gap_m`` from this; ``refine_iterations`` 2, ``min_coverage`` 0.
        """
        return RansacParams(
            threshold_m=self.threshold_m, iterations=self.iterations, refine_iterations=2,
            min_points=self.min_inliers, max_lines=self.max_lines, min_inliers=self.min_inliers,
            min_length_m=self.min_length_m, max_gap_m=self.max_gap_m, min_coverage=0.0,
            coverage_gap_m=self.max_gap_m,
        )  # fmt: skip


def supported_points(points: np.ndarray, grid: OccupancyGrid) -> np.ndarray:
    """Which points lie in an occupied cell of ``grid`` (the occupancy grid of their
    scans; outside it, none).

    Parameters
    ----------
    points : (N, 2) float ndarray
        Wall points of many scans in the map frame, metres.
    grid : OccupancyGrid

    Returns
    -------
    (N,) bool ndarray
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    rows, cols, inside = grid.cells_of(pts)
    out = np.zeros(len(pts), dtype=bool)
    out[inside] = grid.occupied()[rows[inside], cols[inside]]
    return out


def map_points(points: np.ndarray, grid: OccupancyGrid | None, params: MapParams = MapParams()) -> np.ndarray:
    """Steps 1 and 2 of :func:`map_segments`: the supported points (all of them without
    a grid) thinned to one mean point per ``grid_m`` cell.

    Parameters
    ----------
    points : (N, 2) float ndarray
        Wall points of the scans in the map frame, metres. Not modified.
    grid : OccupancyGrid or None
        Occupancy grid of the same scans (:func:`supported_points`); None keeps every point.
    params : MapParams

    Returns
    -------
    (M, 2) float64 ndarray
        Cell means, metres, cells in lexicographic order; (0, 2) when no point is left.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if grid is not None:
        pts = pts[supported_points(pts, grid)]
    return cell_means(pts, params.grid_m)[0] if len(pts) else np.empty((0, 2))


def map_segments(points: np.ndarray, grid: OccupancyGrid | None, params: MapParams = MapParams(), seed=0) -> pd.DataFrame:
    """Wall segments of the map of many registered scans (see the module docstring).

    Parameters
    ----------
    points : (N, 2) float ndarray
        The scans' 2D wall points in the map frame, metres. Not modified.
    grid : OccupancyGrid or None
        The occupancy grid of the same scans (the support test); None: every point
        counts.
    params : MapParams
    seed : int, sequence of int or numpy.random.Generator
        Seeds RANSAC (``numpy.random.default_rng(seed)``); same seed, same walls.

    Returns
    -------
    pandas.DataFrame
        One row per wall segment: ``x0, y0, x1, y1`` (metres), ``n_inliers`` (thinned
        points of the segment, int32), ``rmse_m`` (their RMS distance to it, metres),
        in order of discovery.

    Raises
    ------
    ValueError
        When ``points`` is not (N, 2) or has a non-finite coordinate.
    """
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"map points must be (N, 2), got shape {pts.shape}")
    if not np.isfinite(pts).all():
        raise ValueError("map points: a coordinate is not finite")
    q = map_points(pts, grid, params)
    if len(q) < params.min_inliers:
        return segments_frame([])
    rows = ransac_rows(q, params.ransac(), seed)
    if grid is not None:
        free = grid.free() & (grid.n_hit_scans == 0)
        rows = [piece for row in rows for piece in _apart_where_seen_free(row, grid, free, params)]
    return segments_frame(rows)


def _apart_where_seen_free(row: tuple, grid: OccupancyGrid, free: np.ndarray, params: MapParams) -> list[tuple]:
    """A segment ``(x0, y0, x1, y1, n_inliers, rmse_m)`` cut where the grid saw its line
    free (``free``: the grid's :meth:`~floorscan.core.occupancy.OccupancyGrid.free`
    cells that no scan hit), a cell to either side too, over more than two cells: the
    floor seen between the legs of a row of tables, which RANSAC's ``max_gap_m``
    bridges. The inliers are shared by length; a piece shorter than ``min_length_m`` or
    with fewer than ``min_inliers`` goes."""
    from scipy import ndimage

    x0, y0, x1, y1, n, rmse = row
    a, b = np.array([x0, y0]), np.array([x1, y1])
    length = float(np.hypot(*(b - a)))
    res = grid.resolution_m
    if length < 2 * res:
        return [row]
    m = int(np.ceil(length / (res / 2)))
    t = (np.arange(m) + 0.5) / m
    on = a + np.outer(t, b - a)
    across = np.array([a[1] - b[1], b[0] - a[0]]) / length * res

    def at(xy):
        r, c, inside = grid.cells_of(xy)
        out = np.zeros(len(xy), dtype=bool)
        out[inside] = free[r[inside], c[inside]]
        return out

    runs, _ = ndimage.label(at(on) & at(on + across) & at(on - across))
    cut = (runs > 0) & (np.bincount(runs)[runs] * length / m > 2 * res)
    if not cut.any():
        return [row]
    pieces, _ = ndimage.label(~cut)
    out = []
    for (span,) in ndimage.find_objects(pieces):
        p, q = a + (b - a) * (span.start / m), a + (b - a) * (span.stop / m)
        piece = float(np.hypot(*(q - p)))
        share = int(round(n * piece / length))
        if piece >= params.min_length_m and share >= params.min_inliers:
            out.append((float(p[0]), float(p[1]), float(q[0]), float(q[1]), share, rmse))
    return out

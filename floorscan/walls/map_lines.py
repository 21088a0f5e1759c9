"""The map extractor: wall segments fitted on the registered points of many scans
together (the answer's floor plan), not scan by scan.

The thesis extracts walls scan by scan (sections 3.4 and 5.3) because its subject is
the ordering; it leaves the extraction open ("any wall extraction can be put in
place", section 5.1). A wall that many scans each see sparsely, at range or at a
grazing angle, is found in no single scan; fitted on the map of the selected scans it
is. The per-scan extractors (:mod:`~floorscan.walls.ransac`,
:mod:`~floorscan.walls.cluster`) stay: they drive the orderings and the quality curves.

:func:`map_segments` works on the union of the scans' 2D wall points
(:func:`floorscan.walls.points.scan_points_2d`, in the map frame):

1. **Support** (:func:`supported_points`). A point counts when its ``support_cell_m``
   cell is hit by at least ``min_scans`` scans: structure is seen from more than one
   position, people walking by and stray returns are not (the structure rule of the
   reference map, :mod:`floorscan.core.occupancy`).
2. **Thinning** to one mean point per ``grid_m`` cell
   (:func:`floorscan.core.grid.cell_means`), so a wall seen by many scans weighs as
   much as one seen by few, and the cost follows the map's size, not the scan count.
3. **Iterative RANSAC** (thesis section 5.3, Algorithm 4; Fischler and Bolles 1981),
   :func:`floorscan.walls.ransac._ransac_rows` with the map's settings: the line with
   most inliers, refit by total least squares, cut into pieces at gaps wider than
   ``max_gap_m``; a piece with ``min_inliers`` points and ``min_length_m`` of length is
   a wall segment. No coverage test: a wall seen sparsely at range is sampled every
   few decimetres.

Which segments are walls and which are furniture, which gaps are openings and which
are occlusions, and where walls meet are the floor plan's passes
(:mod:`floorscan.floorplan.structure`), which know the free space.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from floorscan.core.config import schema_defaults
from floorscan.core.grid import cell_means
from floorscan.walls.params import RansacParams
from floorscan.walls.ransac import _ransac_rows
from floorscan.walls.tables import segments_frame


@dataclass(frozen=True)
@schema_defaults("walls.map")
class MapParams:
    """Parameters of the map extractor (config ``walls.map``; see the module docstring).

    Attributes
    ----------
    support_cell_m : float
        Cell of the support test, metres.
    min_scans : int
        Scans that must hit a point's support cell.
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
    min_scans: int
    grid_m: float
    threshold_m: float
    iterations: int
    min_inliers: int
    max_gap_m: float
    min_length_m: float
    max_lines: int

    def ransac(self) -> RansacParams:
        """The :class:`~floorscan.walls.params.RansacParams` of the map's RANSAC (two
        refits, no coverage test)."""
        return RansacParams(
            threshold_m=self.threshold_m, iterations=self.iterations, refine_iterations=2,
            min_points=self.min_inliers, max_lines=self.max_lines, min_inliers=self.min_inliers,
            min_length_m=self.min_length_m, max_gap_m=self.max_gap_m, min_coverage=0.0,
            coverage_gap_m=self.max_gap_m,
        )  # fmt: skip


def supported_points(points: np.ndarray, scan_of_point: np.ndarray, params: MapParams = MapParams()) -> np.ndarray:
    """Which points lie in a ``support_cell_m`` cell hit by at least ``min_scans``
    scans (every point when fewer scans than that are given).

    Parameters
    ----------
    points : (N, 2) float ndarray
        Wall points of many scans in the map frame, metres.
    scan_of_point : (N,) int ndarray
        The scan of each point.
    params : MapParams

    Returns
    -------
    (N,) bool ndarray
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    _, scan_index = np.unique(np.asarray(scan_of_point).ravel(), return_inverse=True)
    if len(pts) == 0:
        return np.zeros(0, dtype=bool)
    n_scans = int(scan_index.max()) + 1
    need = min(int(params.min_scans), n_scans)
    if need <= 1:
        return np.ones(len(pts), dtype=bool)
    cell = np.floor(pts / params.support_cell_m).astype(np.int64)
    _, cell_index = np.unique(cell, axis=0, return_inverse=True)
    cell_index = cell_index.ravel()
    pairs = np.unique(cell_index * n_scans + scan_index.ravel())
    scans_per_cell = np.bincount(pairs // n_scans, minlength=int(cell_index.max()) + 1)
    return scans_per_cell[cell_index] >= need


def map_points(points: np.ndarray, scan_of_point: np.ndarray, params: MapParams = MapParams()) -> np.ndarray:
    """Steps 1 and 2 of :func:`map_segments`: the supported points thinned to one mean
    point per ``grid_m`` cell, (M, 2) float64, metres (cells in lexicographic order)."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    pts = pts[supported_points(pts, scan_of_point, params)]
    return cell_means(pts, params.grid_m)[0] if len(pts) else np.empty((0, 2))


def map_segments(points: np.ndarray, scan_of_point: np.ndarray, params: MapParams = MapParams(), seed=0) -> pd.DataFrame:
    """Wall segments of the map of many registered scans (see the module docstring).

    Parameters
    ----------
    points : (N, 2) float ndarray
        The scans' 2D wall points in the map frame, metres. Not modified.
    scan_of_point : (N,) int ndarray
        The scan of each point (the support test counts distinct scans).
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
        When ``points`` is not (N, 2), has a non-finite coordinate, or its length
        differs from ``scan_of_point``'s.
    """
    pts = np.asarray(points, dtype=np.float64)
    scans = np.asarray(scan_of_point).ravel()
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"map points must be (N, 2), got shape {pts.shape}")
    if len(pts) != len(scans):
        raise ValueError(f"{len(pts)} map points but {len(scans)} scan ids")
    if not np.isfinite(pts).all():
        raise ValueError("map points: a coordinate is not finite")
    q = map_points(pts, scans, params)
    if len(q) < params.min_inliers:
        return segments_frame([])
    return segments_frame(_ransac_rows(q, params.ransac(), seed))

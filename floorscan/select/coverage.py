"""Orderings by what each scan adds to the walls: ``wall_coverage`` and ``surface_coverage``.

The thesis orders scans by the floor area their hulls cover (Algorithm 1) and names
its limits (chapter 6): area is a surrogate, point density should count, and "the
loop between the line extraction and scan selection should be closed". These two
orderings rank scans by the structure they see instead, without a reference: each
is the lazy greedy (:func:`floorscan.core.greedy.lazy_greedy`) on a coverage of grid
cells of side ``cell_m`` in the map frame,

    f(S) = sum over cells c of v(c) * max over scans s in S of q(s, c)

- ``wall_coverage``: a scan covers the cells its own wall segments (the walls stage's
  per-scan segments of one extractor) pass through, sampled every half cell. ``q`` is
  1, or with ``wall_quality`` the fit quality of the segment: ``n / (n + n_min)``
  (``n`` inliers, ``n_min`` the RANSAC minimum: a segment at the minimum counts half)
  times ``1 - rmse / threshold`` (a line whose inliers spread to the RANSAC threshold
  counts nothing), at least ``min_quality``; the best segment of the scan in the cell.
  The weighting is off by default: against the reference map it lowered the area
  under the F1 curve on most recordings (``benchmarks/README.md``).
- ``surface_coverage``: a scan covers the cells its points fall in (3D scans cut to
  the walls' height band first, as the walls stage cuts them). ``q`` is the point
  density the scan gives the cell, ``min(1, points / (cell_m / full_spacing_m))``:
  the spacing of returns on a surface, ``r dtheta / cos(incidence)``, grows with range
  and incidence, so near, head-on views fill a cell and far, grazing ones do not
  (the thesis's point-density term, measured rather than modelled).

In both, ``v(c)`` is 1 for a cell that at least ``min_scans`` scans cover and 0
otherwise: what only one scan sees (a person walking by, a door in motion, a
spurious line) is not structure, as the reference map counts it
(:mod:`floorscan.score.reference`). Scans that add nothing follow in scan id order.

The two are entries of :data:`floorscan.select.registry.COVERAGE_SETS`;
:func:`floorscan.select.orderings.coverage_orderings` runs them (the ``select_coverage``
job). Usage::

    cover, quality, value = wall_cells(per_scan, CoverageParams())
    order = lazy_greedy(cover, scan_ids, quality, value)
"""

from __future__ import annotations

from typing import Iterable

import numpy as np
import pandas as pd
import pyarrow as pa

from floorscan.core.geometry import sample_segments, samples_per_segment
from floorscan.select.params import CoverageParams
#: Column of a coverage ordering's table: the ordering's own objective ``f`` of its
#: first rank + 1 scans (weighted cells), which ``select.k: auto`` reads.
OBJECTIVE_COLUMN = "covered_objective"
#: ``orderings/{wall,surface}_coverage.parquet``: the lazy greedy's ``rank, scan_id,
#: gain`` and the objective along the way (the hull orderings' tables have hull areas
#: instead, :data:`floorscan.select.orderings.ORDERING`).
COVERAGE_ORDERING = pa.schema(
    [("rank", pa.int32()), ("scan_id", pa.int32()), ("gain", pa.float64()), (OBJECTIVE_COLUMN, pa.float64())]
)


def _cell_sets(scan: np.ndarray, ij: np.ndarray, quality: np.ndarray, min_scans: int):
    """Per scan its distinct cells (indices 0 .., from the (N, 2) integer cell
    coordinates ``ij``) with the best quality among its entries there, and the value of
    each cell (1 when >= ``min_scans`` scans cover it)."""
    if len(ij) == 0:
        return {}, {}, np.zeros(0)
    ij = ij - ij.min(axis=0)
    key = ij[:, 0] * (int(ij[:, 1].max()) + 1) + ij[:, 1]
    cell_key, cell = np.unique(key, return_inverse=True)
    # one row per (scan, cell): the best quality first, then the first of them kept
    order = np.lexsort((-quality, cell, scan))
    s, c, q = scan[order], cell.reshape(-1)[order], quality[order]
    first = np.r_[True, (s[1:] != s[:-1]) | (c[1:] != c[:-1])]
    s, c, q = s[first], c[first], q[first]
    value = (np.bincount(c, minlength=len(cell_key)) >= min_scans).astype(np.float64)
    bounds = np.flatnonzero(np.diff(s)) + 1
    cover, best = {}, {}
    for cs, cc, cq in zip(np.split(s, bounds), np.split(c, bounds), np.split(q, bounds)):
        cover[int(cs[0])], best[int(cs[0])] = cc, cq
    return cover, best, value


def segment_quality(n_inliers: np.ndarray, rmse_m: np.ndarray, min_inliers: int, threshold_m: float,
                    min_quality: float = 0.05) -> np.ndarray:
    """Fit quality of wall segments in [``min_quality``, 1): ``n / (n + min_inliers)``
    times ``1 - rmse / threshold`` (module docstring).

    Parameters
    ----------
    n_inliers : (F,) int ndarray
    rmse_m : (F,) float ndarray
        Inlier RMS distance to the line, metres.
    min_inliers : int
        RANSAC's fewest inliers of a segment (:attr:`~floorscan.walls.params.RansacParams.min_inliers`).
    threshold_m : float
        RANSAC's inlier distance, metres (:attr:`~floorscan.walls.params.RansacParams.threshold_m`).
    min_quality : float

    Returns
    -------
    (F,) float64 ndarray
        In [``min_quality``, 1]; a NaN ``rmse_m`` counts as ``threshold_m`` (fit 0).
    """
    n = np.asarray(n_inliers, dtype=np.float64)
    fit = 1.0 - np.nan_to_num(np.asarray(rmse_m, dtype=np.float64), nan=threshold_m) / threshold_m
    return np.clip(n / (n + max(int(min_inliers), 1)) * fit, min_quality, 1.0)


def wall_cells(per_scan: pd.DataFrame, params: CoverageParams, min_inliers: int = 15, threshold_m: float = 0.03):
    """The ``wall_coverage`` sets: per scan the cells its segments pass through.

    Parameters
    ----------
    per_scan : pandas.DataFrame
        ``scan_id, x0, y0, x1, y1, n_inliers, rmse_m`` (metres), the walls stage's
        ``walls/<extractor>/per_scan.parquet``.
    params : CoverageParams
    min_inliers, threshold_m : int, float
        The extractor's RANSAC settings (:func:`segment_quality`).

    Returns
    -------
    cover : dict of int to (M_s,) int64 ndarray
        Cell indices per scan (scans without segments are absent).
    quality : dict of int to (M_s,) float64 ndarray
    value : (N,) float64 ndarray
        Per cell, 1 when at least ``min_scans`` scans cover it, else 0.
    """
    params.check()
    seg = per_scan[["x0", "y0", "x1", "y1"]].to_numpy(np.float64)
    finite = np.isfinite(seg).all(axis=1)
    seg, rows = seg[finite], per_scan[finite]
    if params.wall_quality:
        q = segment_quality(rows["n_inliers"].to_numpy(), rows["rmse_m"].to_numpy(), min_inliers, threshold_m,
                            params.min_quality)
    else:
        q = np.ones(len(rows))
    n = samples_per_segment(seg, 0.5 * params.cell_m)
    xy = sample_segments(seg, 0.5 * params.cell_m)
    ij = np.floor(xy / params.cell_m).astype(np.int64)
    return _cell_sets(np.repeat(rows["scan_id"].to_numpy(np.int64), n), ij, np.repeat(q, n), params.min_scans)


def surface_cells(scans: Iterable[tuple[int, np.ndarray]], params: CoverageParams):
    """The ``surface_coverage`` sets: per scan the cells its points fall in.

    Parameters
    ----------
    scans : iterable of (scan_id, (M, 2) float ndarray)
        Each scan's plan-view points in the map frame, metres (for 3D scans the
        walls' height band, :func:`floorscan.core.wall_points.scan_points_2d`).
    params : CoverageParams

    Returns
    -------
    As :func:`wall_cells`; the quality is the density the scan gives the cell.
    """
    params.check()
    full = params.cell_m / params.full_spacing_m
    ids, cells, counts = [], [], []
    for sid, xy in scans:
        xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
        xy = xy[np.isfinite(xy).all(axis=1)]
        if len(xy) == 0:
            continue
        # the scan's cells and its returns in each
        ij, count = np.unique(np.floor(xy / params.cell_m).astype(np.int64), axis=0, return_counts=True)
        ids.append(np.full(len(ij), int(sid), dtype=np.int64))
        cells.append(ij)
        counts.append(count)
    if not ids:
        return {}, {}, np.zeros(0)
    quality = np.clip(np.concatenate(counts) / full, params.min_quality, 1.0)
    return _cell_sets(np.concatenate(ids), np.concatenate(cells), quality, params.min_scans)

"""Greedy maximum coverage: thesis Algorithm 1, the ``cluster_hull`` and ``convex_hull``
orderings (thesis section 3.3).

Round ``t`` adds the scan ``j`` maximising ``area(U_t ∪ c_j)``, i.e. the gain
``area(c_j \\ U_t)``, where ``U_t`` is the union of the chosen scans' coverage ``c``
(:func:`floorscan.select.hulls.scan_coverage`). Ties go to the lowest ``scan_id``
(Algorithm 1's strict ``>`` keeps the first index). Scans with zero coverage area
(fewer than 3 points, collinear, empty) never enter the greedy: they are ranked last,
in ``scan_id`` order. Areas are counted on the coverage raster
(:mod:`floorscan.select.raster`), so gains are exact integers.

- :func:`greedy_reference` is the plain Algorithm 1: every round recomputes every
  remaining candidate's gain against the current union.
- :func:`greedy_coverage` is the production greedy, lazy evaluation (Minoux 1978):
  coverage is monotone submodular, so a gain computed in an earlier round is an upper
  bound of the current one. It returns the reference's ordering and gains.
- :func:`greedy_exact` is Algorithm 1 literally on Shapely unions (validation only).

A gain is a sum over the scan's runs of cells (:class:`~floorscan.select.raster.RasterCoverage`),
not over its cells, so neither greedy holds the scans' cells.

Usage::

    ids, geoms = scan_coverage(hulls)
    table = greedy_coverage(ids, geoms, raster_m=0.05)   # rank, scan_id, covered_area_m2, gain_m2
"""

from __future__ import annotations

import heapq
from typing import Sequence

import numpy as np
import pandas as pd
import shapely

from floorscan.select.raster import RasterCoverage, ordering_table, raster_for


def _zero_tail(ids: np.ndarray, cov: RasterCoverage) -> list[int]:
    zero = np.flatnonzero(cov.counts == 0)
    return zero[np.argsort(ids[zero], kind="stable")].tolist()


def greedy_reference(scan_ids: Sequence[int], geometries: Sequence, raster_m: float = 0.05) -> pd.DataFrame:
    """Plain greedy maximum coverage (thesis Algorithm 1): the reference.

    Every round recomputes, for every remaining candidate, the area of the union
    of the chosen scans and the candidate (as the candidate's gain over the union)
    and takes the largest; ties go to the lowest scan_id. O(S^2) evaluations.

    Parameters
    ----------
    scan_ids : (S,) int
        Unique scan ids.
    geometries : (S,) Shapely Polygon / MultiPolygon
        Coverage of each scan (map frame, metres). Scans with no covered cell
        (empty, < 3 points, collinear, smaller than a cell) are ranked last by id.
    raster_m : float
        Coverage raster cell side, metres.

    Returns
    -------
    DataFrame
        ``rank`` int32, ``scan_id`` int32, ``covered_area_m2`` (cumulative) and
        ``gain_m2`` float64: all S scans.
    """
    ids, cov = raster_for(scan_ids, geometries, raster_m)
    cand = np.flatnonzero(cov.counts > 0)
    cand = cand[np.argsort(ids[cand], kind="stable")]  # ascending id
    order, gains = [], []
    while len(cand):
        g = cov.gains(cand)
        i = int(np.argmax(g))  # first maximum = lowest scan_id (ascending order)
        j = int(cand[i])
        order.append(j)
        gains.append(int(g[i]))
        cov.add(j)
        cand = np.delete(cand, i)
    zero = _zero_tail(ids, cov)
    return ordering_table(ids, order + zero, gains + [0] * len(zero), raster_m**2)


def greedy_coverage(
    scan_ids: Sequence[int],
    geometries: Sequence,
    raster_m: float = 0.05,
    stats: dict | None = None,
    raster: RasterCoverage | None = None,
) -> pd.DataFrame:
    """Greedy maximum coverage with lazy evaluation: the ordering of
    :func:`greedy_reference` (thesis Algorithm 1), far faster (production greedy of the
    ``select`` stage).

    Parameters
    ----------
    scan_ids : (S,) sequence of int
        Unique scan ids.
    geometries : (S,) sequence of shapely Polygon / MultiPolygon
        Coverage of each scan (map frame, metres).
    raster_m : float
        Coverage raster cell side, metres.
    stats : dict, optional
        Filled with ``evaluations`` (candidate gains computed) and ``rounds``.
    raster : RasterCoverage, optional
        The raster of ``geometries`` at ``raster_m``, reused instead of rasterising
        again (its union is emptied first).

    Returns
    -------
    pandas.DataFrame
        As :func:`greedy_reference`: ``rank`` int32, ``scan_id`` int32,
        ``covered_area_m2`` (cumulative) and ``gain_m2`` float64, all S scans.

    Notes
    -----
    Lazy greedy (Minoux 1978; Krause and Golovin 2014): coverage is monotone
    submodular, so a gain computed in an earlier round bounds the current gain from
    above. Candidates sit in a heap keyed by (-bound, scan_id). The top is popped;
    if its bound was computed in this round it is chosen, else its gain is
    recomputed and it is pushed back. A chosen top has gain >= every other bound,
    and on equal gain a lower scan_id would sit above it, so the choice is the
    reference's (maximum gain, lowest scan_id). Gains are integer cell counts, so
    the comparison is exact and the two greedies return identical orderings and
    gains.
    """
    ids, cov = raster_for(scan_ids, geometries, raster_m, raster)
    active = np.flatnonzero(cov.counts > 0)
    heap = [(-int(cov.counts[j]), int(ids[j]), int(j), 0) for j in active]  # round-0 gains are exact
    heapq.heapify(heap)
    order, gains = [], []
    evaluations, rnd = len(active), 0
    while heap:
        neg, sid, j, stamp = heap[0]
        if stamp == rnd:
            heapq.heappop(heap)
            order.append(j)
            gains.append(-neg)
            cov.add(j)
            rnd += 1
            continue
        evaluations += 1
        heapq.heapreplace(heap, (-cov.gain(j), sid, j, rnd))
    zero = _zero_tail(ids, cov)
    if stats is not None:
        stats.update(evaluations=evaluations, rounds=rnd)
    return ordering_table(ids, order + zero, gains + [0] * len(zero), raster_m**2)


def greedy_exact(
    scan_ids: Sequence[int], geometries: Sequence, max_scans: int | None = None, tie_tol_m2: float = 1e-9
) -> pd.DataFrame:
    """Thesis Algorithm 1 literally, on exact Shapely polygon unions (validation only).

    Every round computes ``area(U ∪ c_j)`` with Shapely for every remaining
    candidate; the largest wins, candidates within ``tie_tol_m2`` of it are tied and
    the lowest scan_id wins. Slow (overlays of a union that grows to thousands of
    vertices); used to check that the raster greedy picks the same scans.

    Parameters
    ----------
    scan_ids, geometries
        As :func:`greedy_reference`.
    max_scans : int, optional
        Stop after this many picks (default: all scans with positive area).
    tie_tol_m2 : float
        Tie tolerance, m^2.

    Returns
    -------
    DataFrame
        ``rank, scan_id, covered_area_m2, gain_m2`` of the picked scans only.
    """
    ids = np.asarray(scan_ids, dtype=np.int64)
    geoms = np.asarray(geometries, dtype=object)
    area = shapely.area(geoms)
    remaining = np.flatnonzero(area > 0)
    remaining = remaining[np.argsort(ids[remaining], kind="stable")]
    limit = len(remaining) if max_scans is None else min(max_scans, len(remaining))
    union = shapely.Polygon()
    covered = 0.0
    order, gains = [], []
    while len(order) < limit:
        pot = shapely.area(shapely.union(union, geoms[remaining]))
        i = int(np.flatnonzero(pot >= pot.max() - tie_tol_m2)[0])
        j = int(remaining[i])
        union = shapely.union(union, geoms[j])
        order.append(j)
        gains.append(float(pot[i]) - covered)
        covered = float(pot[i])
        remaining = np.delete(remaining, i)
    g = np.asarray(gains)
    return pd.DataFrame(
        {
            "rank": np.arange(len(order), dtype=np.int32),
            "scan_id": ids[np.asarray(order, dtype=np.int64)].astype(np.int32),
            "covered_area_m2": np.cumsum(g),
            "gain_m2": g,
        }
    )

"""Floor-plan quality against the number of scans, and the bound of any selection.

For an ordering of the kept scans, the floor plan of its first k scans (the walls
stage's per-scan segments of those scans, merged by the one plan builder,
:class:`floorscan.floorplan.scans.ScanPlans`, as the evaluation grid's and the answer's
plans are; the stage's script hands it to :func:`score_curves`) is scored against the reference map
(:func:`floorscan.score.against_reference.plan_against_reference`) at every k of a
grid (:func:`k_grid`: a step of at most 2 % of the kept scans, so that the k reaching a
level is read to within 2 %). Orderings scored:

- the workflow's orderings (``orderings/<ordering>.parquet``; thesis Algorithm 1 and
  the baselines);
- ``random`` as several seeded permutations (``random_seeds``, seeds 0, 1, ...): its
  mean curve and the spread of the seeds;
- ``oracle``: a greedy that maximises completeness itself (:func:`oracle_ordering`).
  It knows the reference, so no user can run it: it is the limit a reference-free
  ordering is measured against.

The summary of the curves (k95, k99, area under the curve, the ratio to the oracle's
k95) and its tables are :mod:`floorscan.score.curve_summary`.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
import pandas as pd

from floorscan.core.geometry import sample_segments, samples_per_segment
from floorscan.core.greedy import lazy_greedy
from floorscan.core.grid import unique_ints
from floorscan.core.score_tables import ORACLE, RANDOM
from floorscan.score.against_reference import Structure, plan_against_reference, within_bound
from floorscan.score.structure_grid import nearest_sample_d2


def k_grid(n_kept: int, step_fraction: float = 0.02) -> list[int]:
    """The k at which curves are scored: every ``step`` scans, ``step`` =
    ``max(1, floor(step_fraction * n_kept))``, and ``n_kept`` itself.

    Parameters
    ----------
    n_kept : int
        Kept scans of the recording.
    step_fraction : float
        The step as a fraction of ``n_kept`` (config ``score.curve_step_fraction``).

    Returns
    -------
    list of int
        ``step, 2 step, ...`` below ``n_kept``, then ``n_kept``: increasing, the last
        gap at most ``step``.

    Raises
    ------
    ValueError
        When ``n_kept`` < 1 or ``step_fraction`` is not in (0, 1].
    """
    if n_kept < 1:
        raise ValueError(f"k grid: no kept scan (n_kept {n_kept})")
    if not 0.0 < step_fraction <= 1.0:
        raise ValueError(f"score.curve_step_fraction: expected 0 < value <= 1, got {step_fraction}")
    step = max(1, int(math.floor(step_fraction * n_kept)))
    return list(range(step, n_kept, step)) + [n_kept]


def oracle_ordering(
    per_scan: pd.DataFrame, scan_ids: list[int], structure: Structure, tau_m: float, sample_m: float = 0.05
) -> pd.DataFrame:
    """The greedy ordering that maximises the reference structure its walls reach.

    Each scan covers the structure cells within ``tau_m`` of its own wall segments;
    the ordering takes at each step the scan that adds the most uncovered cells
    (:func:`floorscan.core.greedy.lazy_greedy`; ties go to the smaller scan_id). Scans
    that add nothing follow in scan_id order.

    Parameters
    ----------
    per_scan : pandas.DataFrame
        Per-scan wall segments: ``scan_id, x0, y0, x1, y1`` (metres, map frame).
    scan_ids : list of int
        The kept scans to order.
    structure : Structure
    tau_m : float
        Tolerance, metres.
    sample_m : float
        Spacing of the segment samples, metres: a cell within
        :func:`floorscan.score.against_reference.within_bound` of a sample counts
        (5 cm: up to 6 mm beyond tau at tau 5 cm; a bound needs no finer cover).

    Returns
    -------
    pandas.DataFrame
        ``rank, scan_id, gain_cells, covered_cells``, one row per scan of ``scan_ids``.
    """
    order = lazy_greedy(scan_cover(per_scan, scan_ids, structure, tau_m, sample_m), scan_ids)
    return pd.DataFrame({
        "rank": order["rank"], "scan_id": order["scan_id"],
        "gain_cells": order["gain"].round().astype(np.int64), "covered_cells": order["covered"].round().astype(np.int64),
    })  # fmt: skip


def scan_cover(
    per_scan: pd.DataFrame, scan_ids: list[int], structure: Structure, tau_m: float, sample_m: float = 0.05
) -> dict[int, np.ndarray]:
    """Per scan, the indices of the structure cells within ``tau_m`` of its wall
    segments (sorted int64; empty for a scan without walls).

    The segments are sampled every ``sample_m``
    (:func:`floorscan.core.geometry.sample_segments`); a cell counts when it lies
    within :func:`floorscan.score.against_reference.within_bound` of a sample.

    Parameters
    ----------
    per_scan : pandas.DataFrame
        Per-scan wall segments: ``scan_id, x0, y0, x1, y1`` (metres, map frame). Rows of
        scans not in ``scan_ids`` are ignored.
    scan_ids : list of int
        The scans to cover.
    structure : Structure
        The reference map's structure cells (``structure.xy``, ``structure.cells``).
    tau_m : float
        Tolerance, metres.
    sample_m : float
        Spacing of the segment samples, metres.

    Returns
    -------
    dict of int to (C,) int64 ndarray
        One entry per scan of ``scan_ids``: the indices into ``structure.xy`` of the
        cells it covers, distinct and sorted.
    """
    cover = {int(s): np.empty(0, dtype=np.int64) for s in scan_ids}
    if len(per_scan) == 0:
        return cover
    seg = per_scan[["x0", "y0", "x1", "y1"]].to_numpy(np.float64)
    samples = sample_segments(seg, sample_m)
    starts = np.r_[0, np.cumsum(samples_per_segment(seg, sample_m))]
    scan_ids_of_rows, scan_of_row = np.unique(per_scan["scan_id"].to_numpy(np.int64), return_inverse=True)
    # every (segment, structure cell) pair with a sample within the bound: the pairs of
    # cKDTree.sparse_distance_matrix (squared distance at most the bound squared)
    bound = within_bound(tau_m, sample_m)
    cells, rows = structure.cells.segment_cells(seg, bound)
    d2 = nearest_sample_d2(structure.xy[cells, 0], structure.xy[cells, 1], rows, seg, samples, starts)
    near = d2 <= bound * bound
    n_cells = len(structure.xy)
    keys = scan_of_row[rows[near]] * n_cells + cells[near]
    if len(scan_ids_of_rows) * n_cells <= _MARK_CELLS:  # distinct and sorted, by scan then cell
        mark = np.zeros(len(scan_ids_of_rows) * n_cells, dtype=bool)
        mark[keys] = True
        keys = np.flatnonzero(mark)
    else:  # increasing runs (a segment's cells), by scan when the rows are: a merge sort joins them
        keys = unique_ints(keys, kind="stable")
    scans, cells = scan_ids_of_rows[keys // n_cells], keys % n_cells
    bounds = np.flatnonzero(np.diff(scans)) + 1
    for chunk_scans, chunk_cells in zip(np.split(scans, bounds), np.split(cells, bounds)):
        if len(chunk_scans) and int(chunk_scans[0]) in cover:
            cover[int(chunk_scans[0])] = chunk_cells
    return cover


#: Largest scans x structure cells for which :func:`scan_cover` marks its pairs in one
#: boolean array (one byte each) rather than sorting them.
_MARK_CELLS = 1 << 28


def random_orderings(scan_ids: list[int], seeds: list[int]) -> dict[int, pd.DataFrame]:
    """Seeded random permutations of the kept scans, ``{seed: (rank, scan_id)}``
    (``numpy.random.default_rng(seed).permutation`` of the sorted scan ids).

    Parameters
    ----------
    scan_ids : list of int
        The kept scans, in any order.
    seeds : list of int
        One permutation per seed; the same seed gives the same permutation.

    Returns
    -------
    dict of int to pandas.DataFrame
        Seed -> ``rank`` (0, 1, ...) and ``scan_id`` (int64), a row per scan.
    """
    ids = np.sort(np.asarray(scan_ids, dtype=np.int64))
    return {
        int(seed): pd.DataFrame({"rank": np.arange(len(ids)), "scan_id": np.random.default_rng(seed).permutation(ids)})
        for seed in seeds
    }


def adaptive_curve(
    evaluate: Callable[[int], dict],
    n_kept: int,
    step_fraction: float = 0.02,
    dense_fraction: float = 0.2,
    coarse_factor: int = 5,
    targets: tuple[float, ...] = (),
    tau_key: str = "f1_5cm",
    exact_targets: tuple[float, ...] = (),
) -> pd.DataFrame:
    """A quality-vs-k curve read to within one step where it matters, at a fraction
    of the plans of the full grid.

    Every k of :func:`k_grid` up to ``dense_fraction`` of the kept scans (where the
    area under the curve is taken); beyond, every ``coarse_factor``-th k of the grid,
    in order, until every target is reached, and the kept scans themselves; then, for
    each target F1 that no dense k reaches,
    every k of the grid between the last coarse k below it and the first that reaches
    it. So the first k reaching a target is read to within one step of the grid, as on
    the full grid, unless the curve reached it before and dropped below it again
    between two coarse k (F1 is not monotone in k). Last, for each of
    ``exact_targets`` first reached at a dense k, the k between the evaluated k before
    it (or 0) and it are bisected: the first k reaching it to one scan where the curve
    is monotone between them (k95 of the good orderings lies there, a step or two in:
    a step of 2 % would make a k95 of 8 against the oracle's 4 a ratio of 2).

    Parameters
    ----------
    evaluate : callable
        k -> the metrics of the plan of the first k scans (a dict with ``tau_key``).
    n_kept : int
    step_fraction, dense_fraction : float
    coarse_factor : int
    targets : tuple of float
        F1 values whose first k is wanted (levels times the all-scan F1).
    tau_key : str
        The F1 column the targets refer to.

    Returns
    -------
    pandas.DataFrame
        ``k`` and the metrics, a row per evaluated k, by k.
    """
    grid = k_grid(n_kept, step_fraction)
    dense = [k for k in grid if k <= dense_fraction * n_kept] or grid[:1]
    rest = [k for k in grid if k > dense[-1]]
    coarse = rest[coarse_factor - 1 :: coarse_factor]
    if rest and (not coarse or coarse[-1] != rest[-1]):
        coarse.append(rest[-1])
    rows = {k: evaluate(k) for k in dense}

    def reached_all() -> bool:
        return all(
            any(r[tau_key] >= t - 1e-12 for r in rows.values()) for t in targets if np.isfinite(t)
        )

    for k in coarse[:-1]:  # in order, until every target is reached
        if reached_all():
            break
        rows[k] = evaluate(k)
    if coarse:
        rows[coarse[-1]] = evaluate(coarse[-1])  # all kept scans
    for target in targets:
        if not np.isfinite(target):
            continue
        reached = [k for k in sorted(rows) if rows[k][tau_key] >= target - 1e-12]
        if not reached or reached[0] in dense:
            continue
        below = max(k for k in rows if k < reached[0])
        for k in grid:
            if below < k < reached[0] and k not in rows:
                rows[k] = evaluate(k)
                if rows[k][tau_key] >= target - 1e-12:
                    break
    for target in exact_targets:
        if not np.isfinite(target):
            continue
        reached = [k for k in sorted(rows) if rows[k][tau_key] >= target - 1e-12]
        if not reached or reached[0] > dense[-1]:
            continue
        lo, hi = max([k for k in rows if k < reached[0]], default=0), reached[0]
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if mid not in rows:
                rows[mid] = evaluate(mid)
            if rows[mid][tau_key] >= target - 1e-12:
                hi = mid
            else:
                lo = mid
    return pd.DataFrame([{"k": k, **rows[k]} for k in sorted(rows)])


def score_curves(
    per_scan: pd.DataFrame,
    orderings: dict[str, pd.DataFrame],
    reference_path,
    plan_faces: Callable[[tuple[int, ...]], np.ndarray],
    taus_m: tuple[float, ...] = (0.05, 0.10),
    oracle_tau_m: float = 0.05,
    step_fraction: float = 0.02,
    random_seeds: int = 10,
    dense_fraction: float = 0.2,
    levels: tuple[float, ...] = (0.95, 0.99),
    exact_levels: tuple[float, ...] = (0.95,),
    log=None,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The curves of one extractor (stage ``score_curves``).

    Parameters
    ----------
    per_scan : pandas.DataFrame
        The extractor's per-scan wall segments (``walls/<extractor>/per_scan.parquet``).
    orderings : dict of str to pandas.DataFrame
        The workflow's orderings (``rank, scan_id``); ``random`` among them is
        replaced by ``random_seeds`` seeded permutations.
    reference_path : path
        ``reference/occupancy.parquet``.
    plan_faces : callable
        ``plan_faces(scan_ids) -> (F, 4) float64 ndarray``: the merged wall faces
        (``x0, y0, x1, y1``, metres) of the floor plan of those scans' segments of
        ``per_scan``, scan ids sorted: the one plan builder's
        (:meth:`floorscan.floorplan.scans.ScanPlans.faces`, prepared for ``per_scan``
        with the ``floorplan`` config section; ``scripts/score_curves.py`` makes it).
    taus_m : tuple of float
    oracle_tau_m : float
        Tolerance of the completeness the oracle maximises.
    step_fraction : float
        :func:`k_grid`'s step.
    random_seeds : int
    dense_fraction : float
        Every k of the grid up to this fraction of the kept scans
        (:func:`adaptive_curve`).
    levels : tuple of float
        Fractions of the all-scan F1 whose first k is read to within a step.
    exact_levels : tuple of float
        Those read to one scan where a dense k reaches them (:func:`adaptive_curve`).
    log : logging.Logger, optional

    Returns
    -------
    curves : pandas.DataFrame
        ``ordering, seed`` (-1 unless random), ``n_kept``, ``k`` and the metrics of
        :func:`plan_against_reference`, a row per ordering (seed) and k.
    oracle : pandas.DataFrame
        The oracle ordering (:func:`oracle_ordering`).
    """
    from floorscan.score.against_reference import read_reference

    structure = Structure(read_reference(reference_path))
    cache: dict[tuple, dict] = {}

    def score_scans(scan_ids) -> dict:
        """The plan of these scans' segments against the reference, once per set of
        scans (the same scans give the same plan: k = all of every ordering)."""
        key = tuple(sorted(int(s) for s in scan_ids))
        if key not in cache:
            cache[key] = plan_against_reference(plan_faces(key), structure, taus_m)
        return cache[key]

    any_ordering = next(iter(orderings.values()))
    scan_ids = sorted(int(s) for s in any_ordering["scan_id"])
    n_kept = len(scan_ids)
    tau_key = f"f1_{round(oracle_tau_m * 100):d}cm"
    f1_all = score_scans(scan_ids)[tau_key]
    targets = tuple(level * f1_all for level in levels)
    exact = tuple(level * f1_all for level in exact_levels)
    oracle = oracle_ordering(per_scan, scan_ids, structure, oracle_tau_m)
    runs = [(name, -1, o) for name, o in orderings.items() if name != RANDOM]
    runs += [(RANDOM, seed, o) for seed, o in random_orderings(scan_ids, list(range(random_seeds))).items()]
    runs.append((ORACLE, -1, oracle))
    parts = []
    for name, seed, ordering in runs:
        parts.append(_curve_of(name, seed, ordering, n_kept, score_scans, step_fraction, dense_fraction,
                               targets, tau_key, exact))
        if log is not None:
            c = parts[-1]
            log.info("%s%s: %d k from %d to %d, F1 %.3f .. %.3f", name, f" seed {seed}" if seed >= 0 else "",
                     len(c), c["k"].iloc[0], c["k"].iloc[-1], float(c[tau_key].min()), float(c[tau_key].max()))
    return pd.concat(parts, ignore_index=True), oracle


def _curve_of(name, seed, ordering, n_kept, score_scans, step_fraction, dense_fraction, targets,
              tau_key, exact=()) -> pd.DataFrame:
    ranked = ordering.sort_values("rank", kind="stable")["scan_id"].to_numpy(np.int64)

    def evaluate(k: int) -> dict:
        return score_scans(ranked[: int(k)])

    c = adaptive_curve(evaluate, n_kept, step_fraction, dense_fraction, targets=targets, tau_key=tau_key,
                       exact_targets=exact)
    c.insert(0, "ordering", name)
    c.insert(1, "seed", seed)
    c.insert(2, "n_kept", n_kept)
    return c

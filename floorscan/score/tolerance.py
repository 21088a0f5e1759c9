"""Tolerance metrics of walls, in the style of the ISPRS benchmark on indoor modelling
(Khoshelham et al. 2017, "The ISPRS benchmark on indoor modelling", and Khoshelham et
al. 2018, "An evaluation framework for benchmarking indoor modelling methods"), applied
to 2D wall segments; thesis Chapter 6 asks for "more robust error metrics".

- *precision* (the benchmark's *correctness*): the fraction of inferred wall length
  lying within ``tau`` of a ground-truth segment, computed exactly
  (:func:`floorscan.score.capsule.length_within`);
- *recall* (*completeness*): the fraction of the ground truth within ``tau`` of an
  inferred segment, measured on ground-truth samples every ``sample_step_m`` (default
  1 cm) deduplicated on a grid of the same size
  (:func:`floorscan.score.segments.gt_samples`), with exact sample-to-segment distances
  (:func:`floorscan.score.nearest.nearest_below`);
- *F1*: the harmonic mean; *median distance*: the median (and mean) of the same
  samples' distances to the nearest inferred segment, over the samples within
  :data:`DISTANCE_CUTOFF_M` of one (the benchmark's *accuracy*: the distances within a
  cut-off, so that walls no scan has seen yet do not swamp it).

Columns are named by the tolerance (:func:`~floorscan.core.score_tables.tau_label`): ``precision_5cm``,
``recall_5cm``, ``f1_5cm``, ...

On real recordings the reference is the union of the walls of all kept scans, and the
walls of the first k scans are a subset of it: precision is 1 there by construction;
recall and F1 carry the comparison.

Empty inputs never raise: with no inferred wall, precision is NaN (0/0, undefined),
recall is 0 and F1 is 0 (a floor plan without walls is worthless, and 0 keeps the
metric-against-k curves continuous); with no ground-truth wall, recall is NaN and F1 is
0 if walls were inferred (all of them false positives), NaN if neither set has walls.
"""

from __future__ import annotations

import math

import numpy as np

from floorscan.core.score_tables import tau_label
from floorscan.score.capsule import lengths_within, length_within
from floorscan.score.nearest import SegmentIndex, nearest_below, pairs_within
from floorscan.score.segments import row_keys, gt_samples
from floorscan.core.segments import MIN_SEGMENT_M, as_segments, segment_lengths

#: The median and mean distance count the ground-truth samples within this of an
#: inferred wall, metres: ten times the largest default tolerance, the cut-off of the
#: plans' distances to the reference map
#: (:mod:`floorscan.score.against_reference`).
DISTANCE_CUTOFF_M = 1.0


def distance_bound(taus) -> float:
    """How far the samples' distances are measured, metres: the cut-off, and twice the
    largest tolerance when that is farther (a sample at the bound is beyond every
    tolerance, so recall needs no farther distance)."""
    return max(DISTANCE_CUTOFF_M, 2 * max(taus, default=0.0))


def _f1(p: float, r: float, has_inferred: bool, has_gt: bool) -> float:
    if not has_inferred and not has_gt:
        return math.nan
    if not has_inferred or not has_gt:
        return 0.0
    return 2 * p * r / (p + r) if (p + r) > 0 else 0.0


def tolerance_metrics(
    inferred, ground_truth, taus=(0.05, 0.10), sample_step_m: float = 0.01, samples=None
) -> dict[str, float]:
    """Precision (correctness), recall (completeness) and F1 of wall length within
    each tolerance, and the median distance from the ground truth to the inferred walls.

    Style of the ISPRS benchmark on indoor modelling (Khoshelham et al. 2017, 2018),
    applied to 2D wall segments; thesis Chapter 6 asks for "more robust error metrics".

    - precision at tau: inferred wall length within tau of a ground-truth segment over
      the inferred wall length, computed exactly
      (:func:`floorscan.score.capsule.length_within`); overlapping inferred segments
      (the same wall seen by several scans) each count.
    - recall at tau: the ground truth is sampled every ``sample_step_m`` and the samples
      deduplicated on a ``sample_step_m`` grid
      (:func:`floorscan.score.segments.dedupe_samples`), so that a place
      of a wall counts once however many reference segments overlap there (real
      recordings' references are the overlapping walls of all scans; on the simulator's
      ground truth this changes nothing but the corners); recall is the fraction of
      these samples within tau of an inferred segment (exact distances).
    - median (mean) distance: over the same samples, metres.

    Parameters
    ----------
    inferred : (M, 4) array_like or DataFrame
        Inferred wall segments, metres.
    ground_truth : (K, 4) array_like or DataFrame
        Ground-truth (or reference) wall segments, metres.
    taus : sequence of float
        Tolerances in metres.
    sample_step_m : float
        Spacing and deduplication cell of the ground-truth samples, metres.
    samples : (S, 2) ndarray, optional
        ``gt_samples(ground_truth, sample_step_m)``, when already computed.

    Returns
    -------
    dict
        ``precision_<tau>``, ``recall_<tau>``, ``f1_<tau>`` for each tau (suffix from
        :func:`~floorscan.core.score_tables.tau_label`, e.g. ``f1_5cm``); ``median_distance_m`` and
        ``mean_distance_m`` over the samples within :data:`DISTANCE_CUTOFF_M` of an
        inferred wall (NaN without inferred or ground-truth walls, or without such a
        sample);
        ``inferred_length_m``, ``gt_length_m`` (sums of segment lengths) and
        ``n_gt_samples``. Empty sets: see the module docstring (precision NaN and F1 0
        with nothing inferred).
    """
    inf = as_segments(inferred)
    gt = as_segments(ground_truth)
    len_i = float(segment_lengths(inf).sum())
    len_g = float(segment_lengths(gt).sum())
    has_i, has_g = len_i > MIN_SEGMENT_M, len_g > MIN_SEGMENT_M
    pts = gt_samples(gt, sample_step_m) if samples is None else samples
    d = (nearest_below(pts, SegmentIndex(inf), np.full(len(pts), distance_bound(taus))) if has_i
         else np.full(len(pts), np.inf))
    covered = {tau: float(length_within(inf, gt, tau).sum()) if has_i and has_g else 0.0 for tau in taus}
    return tolerance_from(len_i, len_g, len(pts), d, covered, taus)


def tolerance_from(len_i: float, len_g: float, n_pts: int, d: np.ndarray, covered: dict, taus) -> dict:
    """:func:`tolerance_metrics` from its parts.

    Parameters
    ----------
    len_i, len_g : float
        Inferred and ground-truth lengths, metres.
    n_pts : int
        Ground-truth samples.
    d : (n_pts,) float ndarray
        The samples' distances to the inferred walls, metres.
    covered : dict of float to float
        Inferred length within each tau of the ground truth, metres.
    taus : iterable of float
        Metres.

    Returns
    -------
    dict of str to float
        As :func:`tolerance_metrics`.
    """
    has_i, has_g = len_i > MIN_SEGMENT_M, len_g > MIN_SEGMENT_M
    out: dict[str, float] = {
        "inferred_length_m": len_i,
        "gt_length_m": len_g,
        "n_gt_samples": float(n_pts),
    }
    for tau in taus:
        r = float(np.mean(d <= tau)) if has_g and n_pts else math.nan
        _set_prf(out, tau, covered[tau], len_i, r, has_i, has_g)
    near = d[d < DISTANCE_CUTOFF_M]
    if has_i and has_g and len(near):
        out["median_distance_m"] = float(np.median(near))
        out["mean_distance_m"] = float(np.mean(near))
    else:
        out["median_distance_m"] = math.nan
        out["mean_distance_m"] = math.nan
    return out


def _set_prf(out: dict, tau: float, covered_m: float, len_i: float, recall: float, has_i: bool, has_g: bool) -> None:
    """Set ``precision_<tau>`` (inferred length within tau of the ground truth over the
    inferred length; NaN without inferred walls, 0 without ground truth), ``recall_<tau>``
    and ``f1_<tau>`` in ``out``."""
    lab = tau_label(tau)
    p = (float(covered_m / len_i) if has_g else 0.0) if has_i else math.nan
    out[f"precision_{lab}"] = p
    out[f"recall_{lab}"] = recall
    out[f"f1_{lab}"] = _f1(p, recall, has_i, has_g)


def recall_precision(inferred, gt, taus, samples, pairs=None) -> dict[str, float]:
    """``precision_<tau>``, ``recall_<tau>`` and ``f1_<tau>`` of :func:`tolerance_metrics`
    (same values), without the distances of the samples that tau does not need.

    Parameters
    ----------
    inferred : (M, 4) array_like
        Inferred walls, metres.
    gt : (K, 4) float ndarray
        Ground-truth walls, metres.
    taus : sequence of float
        Metres.
    samples : (S, 2) float ndarray
        Ground-truth samples (:func:`floorscan.score.segments.gt_samples`).
    pairs : SamplePairs, optional
        Cached sample pairs of ``samples``, used when its reach covers every tau.

    Returns
    -------
    dict of str to float
    """
    inf = as_segments(inferred)
    len_i = float(segment_lengths(inf).sum())
    len_g = float(segment_lengths(gt).sum())
    has_i, has_g = len_i > MIN_SEGMENT_M, len_g > MIN_SEGMENT_M
    hit = np.zeros((len(taus), len(samples)), dtype=bool)
    if has_i:
        if pairs is not None and pairs.samples is samples and max(taus) <= pairs.reach:
            # The samples near each face (floorscan.score.growing.SamplePairs; faces of
            # plans of several k recur): the same test as pairs_within.
            si, d = pairs.of(inf, row_keys(inf))
            for t, tau in enumerate(taus):
                hit[t, si[d <= tau]] = True
        else:
            hit = pairs_within(samples, SegmentIndex(inf), taus, hit)
    out: dict[str, float] = {}
    covs = lengths_within(inf, as_segments(gt), taus) if has_i and has_g else None
    for t, tau in enumerate(taus):
        covered = float(covs[t].sum()) if has_i and has_g else 0.0
        r = float(np.mean(hit[t])) if has_g and len(samples) else math.nan
        _set_prf(out, tau, covered, len_i, r, has_i, has_g)
    return out

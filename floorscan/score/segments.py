"""Points along wall segments: what the scores of walls measure on.

Wall segments are ``(M, 4)`` float64 arrays ``x0, y0, x1, y1`` in metres
(:mod:`floorscan.core.segments`: :func:`~floorscan.core.segments.as_segments`,
:func:`~floorscan.core.segments.segment_lengths`).

Recall (the ISPRS benchmark's *completeness*; Khoshelham et al. 2017, 2018) is measured
on points along the ground truth: :func:`sample_segments` cuts each segment into equal
pieces of at most ``step_m`` and samples their centres (the weights sum to the length
exactly), :func:`dedupe_samples` keeps one sample per grid cell so that a place of a
wall counts once however many overlapping segments describe it (real recordings'
references are the overlapping walls of all scans), and :func:`gt_samples` does both.
"""

from __future__ import annotations

import numpy as np

from floorscan.core.grid import ranks_in_runs
from floorscan.core.segments import MIN_SEGMENT_M, as_segments, segment_lengths


def sample_segments(segments, step_m: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """Points along segments at most ``step_m`` apart, with the length each stands for.

    Each segment of length L is cut into ``n = ceil(L / step_m)`` equal pieces and
    sampled at the pieces' centres, so the weights ``L / n`` sum to L exactly.

    Parameters
    ----------
    segments : (M, 4) array_like
        ``x0, y0, x1, y1``, metres; non-finite rows and segments of at most
        :data:`MIN_SEGMENT_M` are left out.
    step_m : float
        Metres.

    Returns
    -------
    points : (S, 2) float64 ndarray
        Sample positions, metres.
    weights : (S,) float64 ndarray
        Length in metres represented by each sample.

    Raises
    ------
    ValueError
        When ``step_m`` is not positive.
    """
    if not step_m > 0:
        raise ValueError(f"step_m must be > 0; got {step_m}")
    seg = as_segments(segments)
    lengths = segment_lengths(seg)
    keep = lengths > MIN_SEGMENT_M
    seg, lengths = seg[keep], lengths[keep]
    if len(seg) == 0:
        return np.zeros((0, 2)), np.zeros(0)
    n = np.maximum(1, np.ceil(lengths / step_m - 1e-9).astype(np.int64))
    idx = np.repeat(np.arange(len(seg)), n)
    k = ranks_in_runs(n)
    t = (k + 0.5) / n[idx]
    pts = seg[idx, :2] + t[:, None] * (seg[idx, 2:] - seg[idx, :2])
    return pts, (lengths / n)[idx]


def dedupe_samples(points: np.ndarray, cell_m: float) -> np.ndarray:
    """Keep one sample per ``cell_m`` square cell (the first in input order).

    Walls from many scans overlap: a wall seen by 100 scans is 100 near-identical
    segments. Deduplicating the samples on a grid makes each place of the wall count
    once (up to the width of the stack of duplicates, a few cells).

    Parameters
    ----------
    points : (S, 2) float ndarray
        Metres.
    cell_m : float
        Metres.

    Returns
    -------
    (S', 2) float64 ndarray
        The kept samples, in input order.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(pts) == 0:
        return pts.copy()
    key = np.floor(pts / cell_m).astype(np.int64)
    key -= key.min(axis=0)
    flat = key[:, 0] * (int(key[:, 1].max()) + 1) + key[:, 1]
    _, first = np.unique(flat, return_index=True)
    return pts[np.sort(first)]


def gt_samples(ground_truth, sample_step_m: float = 0.01) -> np.ndarray:
    """The deduplicated ground-truth samples of
    :func:`floorscan.score.tolerance.tolerance_metrics`: :func:`sample_segments` then
    :func:`dedupe_samples`, both at ``sample_step_m``.

    Parameters
    ----------
    ground_truth : (M, 4) array_like
        Segments, metres.
    sample_step_m : float
        Metres.

    Returns
    -------
    (S, 2) float64 ndarray
        Metres.
    """
    return dedupe_samples(sample_segments(ground_truth, sample_step_m)[0], sample_step_m)


def densify(seg: np.ndarray, step: float) -> np.ndarray:
    """Points along each segment, both ends included, at most ``step`` apart.

    Parameters
    ----------
    seg : (M, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    step : float
        Metres.

    Returns
    -------
    (Q, 2) float64 ndarray
        Metres, segment after segment.
    """
    n = np.maximum(1, np.ceil(segment_lengths(seg) / step).astype(np.int64))
    idx = np.repeat(np.arange(len(seg)), n + 1)
    k = ranks_in_runs(n + 1)
    t = k / n[idx]
    return seg[idx, :2] + t[:, None] * (seg[idx, 2:] - seg[idx, :2])


def row_keys(seg: np.ndarray) -> list[bytes]:
    """The bytes of each row: equal rows, equal keys.

    Parameters
    ----------
    seg : (M, 4) float ndarray

    Returns
    -------
    list of bytes
        32 bytes per row (float64).
    """
    return np.ascontiguousarray(seg, dtype=np.float64).view(np.dtype((np.void, 32))).ravel().tolist()

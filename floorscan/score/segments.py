"""Wall segments as arrays, and points along them: what every score of walls starts from.

A set of wall segments is a ``(M, 4)`` float64 array ``x0, y0, x1, y1`` in metres (map
frame). :func:`as_segments` makes one from an array or a walls table (columns ``x0, y0,
x1, y1``) and drops non-finite rows; :func:`segment_lengths` measures them.

Recall (the ISPRS benchmark's *completeness*; Khoshelham et al. 2017, 2018) is measured
on points along the ground truth: :func:`sample_segments` cuts each segment into equal
pieces of at most ``step_m`` and samples their centres (the weights sum to the length
exactly), :func:`dedupe_samples` keeps one sample per grid cell so that a place of a
wall counts once however many overlapping segments describe it (real recordings'
references are the overlapping walls of all scans), and :func:`gt_samples` does both.
"""

from __future__ import annotations

import numpy as np

#: Segments shorter than this (metres) have no length and are ignored.
MIN_SEGMENT_M = 1e-9


def as_segments(segments) -> np.ndarray:
    """Return wall segments as a new ``(M, 4)`` float64 array ``x0, y0, x1, y1``.

    Parameters
    ----------
    segments : array_like, shape (M, 4), or pandas.DataFrame with columns x0, y0, x1, y1
        Segment end points in metres (map frame).

    Returns
    -------
    (M, 4) float64 ndarray
        A copy; rows with a NaN or infinite coordinate are dropped.

    Raises
    ------
    ValueError
        When the input does not have 4 columns.
    """
    if hasattr(segments, "columns"):
        missing = [c for c in ("x0", "y0", "x1", "y1") if c not in segments.columns]
        if missing:
            raise ValueError(f"wall table lacks columns {missing}; expected x0, y0, x1, y1")
        arr = segments[["x0", "y0", "x1", "y1"]].to_numpy(dtype=np.float64, copy=True)
    else:
        arr = np.array(segments, dtype=np.float64, copy=True)
        if arr.size == 0:
            return np.zeros((0, 4))
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise ValueError(f"segments must have shape (M, 4) (x0, y0, x1, y1); got {arr.shape}")
    return arr[np.isfinite(arr).all(axis=1)]


def segment_lengths(segments: np.ndarray) -> np.ndarray:
    """Lengths of segments.

    Parameters
    ----------
    segments : (M, 4) float ndarray
        ``x0, y0, x1, y1``, metres.

    Returns
    -------
    (M,) float64 ndarray
        Metres.
    """
    s = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    return np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1])


def split_long(seg: np.ndarray, max_len: float, return_owner: bool = False):
    """Cut segments into equal collinear pieces no longer than ``max_len`` (same union).

    Parameters
    ----------
    seg : (M, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    max_len : float
        Metres.
    return_owner : bool

    Returns
    -------
    pieces : (P, 4) float64 ndarray
        Metres, segment after segment.
    owner : (P,) int64 ndarray
        With ``return_owner`` only: the row of ``seg`` of each piece.
    """
    lengths = segment_lengths(seg)
    n = np.maximum(1, np.ceil(lengths / max_len).astype(np.int64))
    idx = np.repeat(np.arange(len(seg)), n)
    start = np.arange(len(idx)) - np.repeat(np.cumsum(n) - n, n)
    t0 = start / n[idx]
    t1 = (start + 1) / n[idx]
    p = seg[idx, :2]
    d = seg[idx, 2:] - seg[idx, :2]
    pieces = np.column_stack([p + t0[:, None] * d, p + t1[:, None] * d])
    return (pieces, idx) if return_owner else pieces


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
    k = np.arange(len(idx)) - np.repeat(np.cumsum(n) - n, n)
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
    k = np.arange(len(idx)) - np.repeat(np.cumsum(n + 1) - (n + 1), n + 1)
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

"""Wall segments as arrays: what every stage that reads walls starts from (the scores,
the scoring raster, the figures).

A set of wall segments is a ``(M, 4)`` float64 array ``x0, y0, x1, y1`` in metres (map
frame). :func:`as_segments` makes one from an array or a walls table (columns ``x0, y0,
x1, y1``) and drops non-finite rows; :func:`segment_lengths` measures them;
:func:`split_long` cuts them into collinear pieces of bounded length (the same union),
as the scoring raster (:mod:`floorscan.core.segment_raster`) and the distance scores
(:mod:`floorscan.score.nearest`) do.
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

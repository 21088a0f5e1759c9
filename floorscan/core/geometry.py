"""Plane geometry shared by the stages: points along wall segments.

Usage::

    samples = sample_segments(segments, 0.02)        # (N, 2), segment after segment
    per_segment = samples_per_segment(segments, 0.02)
"""

from __future__ import annotations

import numpy as np


def samples_per_segment(segments: np.ndarray, sample_m: float) -> np.ndarray:
    """(F,) int64: how many samples :func:`sample_segments` puts on each segment
    (``ceil(length / sample_m) + 1``, at least 2: its ends)."""
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    return np.maximum(np.ceil(length / sample_m).astype(np.int64), 1) + 1


def sample_segments(segments: np.ndarray, sample_m: float) -> np.ndarray:
    """Points every ``sample_m`` (at most) along each segment, ends included.

    Parameters
    ----------
    segments : (F, 4) float ndarray
        x0, y0, x1, y1 per segment, metres.
    sample_m : float
        Largest spacing, metres.

    Returns
    -------
    (N, 2) float64 ndarray
        The samples, segment after segment (:func:`samples_per_segment` of each),
        each standing for ``length / n`` metres of its segment (equal weights within a
        segment); see :func:`segment_weights`.
    """
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    if len(seg) == 0:
        return np.empty((0, 2))
    n = samples_per_segment(seg, sample_m)
    which = np.repeat(np.arange(len(seg)), n)
    t = (np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)) / np.repeat(n - 1, n)
    a, b = seg[which, :2], seg[which, 2:]
    return a + (b - a) * t[:, None]


def segment_weights(segments: np.ndarray, sample_m: float) -> np.ndarray:
    """Length in metres each sample of :func:`sample_segments` stands for."""
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    if len(seg) == 0:
        return np.empty(0)
    n = samples_per_segment(seg, sample_m)
    return np.repeat(np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]) / n, n)

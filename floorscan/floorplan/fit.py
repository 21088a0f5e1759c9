"""One segment fitted to several (:func:`fit_segments`; :func:`fit_groups` fits many
groups at once): the merged face of the segments of one wall face
(:mod:`floorscan.floorplan.merge`).

Each segment counts as its weight spread evenly along it; the line is the weighted
total least squares line of those masses (the major axis of their second moments, a
segment of length L adding L^2 / 12 along its direction), the extent the union of the
segments' projections on it.
"""

from __future__ import annotations

import numpy as np


def fit_segments(seg: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """One segment fitted to several (weighted total least squares over their lengths).

    Each segment counts as its weight spread evenly along it: the line minimises the
    weighted sum of squared distances of those masses (centroid ``m = sum w_i m_i /
    sum w_i``; direction the major axis of ``sum w_i [(m_i - m)(m_i - m)^T + L_i^2 / 12
    d_i d_i^T]``). The extent is the union of the segments' projections on it.

    Parameters
    ----------
    seg : (M, 4) float ndarray
        Segments ``x0, y0, x1, y1``, metres.
    weights : (M,) float ndarray
        Positive weights (e.g. inlier counts).

    Returns
    -------
    (4,) float64 ndarray
        The merged segment, metres.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    if len(seg) == 1:
        return seg[0].copy()
    return fit_groups(seg, weights, np.zeros(len(seg), dtype=np.int64), 1)[0]


def fit_groups(seg: np.ndarray, weights: np.ndarray, group: np.ndarray, n_groups: int) -> np.ndarray:
    """:func:`fit_segments` of every group at once.

    Parameters
    ----------
    seg : (M, 4) float ndarray
        Segments ``x0, y0, x1, y1``, metres.
    weights : (M,) float ndarray
        Positive weights.
    group : (M,) int ndarray
        Group of each segment, 0 .. ``n_groups`` - 1; every group has a member.
    n_groups : int

    Returns
    -------
    (n_groups, 4) float64 ndarray
        The fitted segment of each group, metres (a group of one: its segment's line
        and extent, up to rounding).
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    w = np.asarray(weights, dtype=np.float64).reshape(-1)
    g = np.asarray(group, dtype=np.int64).reshape(-1)

    def total(values):
        return np.bincount(g, weights=values, minlength=n_groups)

    mid = 0.5 * (seg[:, :2] + seg[:, 2:])
    vec = seg[:, 2:] - seg[:, :2]
    length = np.hypot(vec[:, 0], vec[:, 1])
    d = vec / np.maximum(length, 1e-12)[:, None]
    w_sum = total(w)
    m = np.stack([total(w * mid[:, 0]), total(w * mid[:, 1])], axis=1) / w_sum[:, None]
    r = mid - m[g]
    wl = w * length**2 / 12.0
    cxx = total(w * r[:, 0] * r[:, 0] + wl * d[:, 0] * d[:, 0])
    cyy = total(w * r[:, 1] * r[:, 1] + wl * d[:, 1] * d[:, 1])
    cxy = total(w * r[:, 0] * r[:, 1] + wl * d[:, 0] * d[:, 1])
    phi = 0.5 * np.arctan2(2.0 * cxy, cxx - cyy)
    u = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    t0 = np.einsum("ij,ij->i", seg[:, :2] - m[g], u[g])
    t1 = np.einsum("ij,ij->i", seg[:, 2:] - m[g], u[g])
    lo = np.full(n_groups, np.inf)
    hi = np.full(n_groups, -np.inf)
    np.minimum.at(lo, g, np.minimum(t0, t1))
    np.maximum.at(hi, g, np.maximum(t0, t1))
    a, b = m + lo[:, None] * u, m + hi[:, None] * u
    return np.concatenate([a, b], axis=1)

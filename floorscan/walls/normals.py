"""In-plane normals of 2D points from their neighbourhood covariances.

:func:`point_normals` gives each point of a scan the normal of its neighbourhood: the
eigenvector of the smallest eigenvalue of the 2x2 covariance
(:func:`neighbourhood_covariances`) of its ``max_nn`` nearest points within
``radius_m``, as Open3D's hybrid search finds them. Step 1 of
:func:`floorscan.walls.cluster.cluster_ransac` (thesis section 3.4).

The covariances are Open3D's ``estimate_covariances`` computed with SciPy's k-d tree
(the same floats, tested against Open3D), so that a job does not import Open3D, whose
import is slow (it imports scikit-learn); Open3D's own ``estimate_normals`` is of no
use here, as it returns the z axis for points in a plane.
"""

from __future__ import annotations

import numpy as np


def point_normals(points: np.ndarray, radius_m: float = 0.25, max_nn: int = 20) -> np.ndarray:
    """In-plane unit normals of 2D points from their neighbourhoods.

    Open3D's ``estimate_normals`` on points embedded at z = 0 returns the z axis for
    every point (for planar data the smallest-variance direction is always z; checked
    with Open3D 0.19 and tested). So the normal comes from the neighbourhood
    covariance of Open3D's ``estimate_covariances`` with ``KDTreeSearchParamHybrid(
    radius_m, max_nn)`` (:func:`neighbourhood_covariances`, the same numbers computed
    with SciPy's k-d tree, so that a job does not import Open3D) and is the
    eigenvector of the smallest eigenvalue of the 2x2 covariance (closed form).

    Normals are axial (a line has no preferred side): they are folded into the
    canonical half-plane, angle in [0, pi). The clustering of
    :func:`floorscan.walls.cluster.cluster_ransac` only uses sign-free quantities, so
    no scanner position is needed.

    Parameters
    ----------
    points : (N, 2) float ndarray
        Points, metres.
    radius_m : float
        Neighbourhood radius, metres.
    max_nn : int
        At most this many neighbours.

    Returns
    -------
    (N, 2) float64 ndarray
        Unit normals with angle in [0, pi); NaN for points with fewer than 3
        neighbours or an isotropic neighbourhood.
    """
    sxx, syy, sxy = neighbourhood_covariances(points, radius_m, max_nn)
    # Major axis angle phi of the 2x2 covariance; the normal is perpendicular to it.
    phi = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)
    theta = np.mod(phi + 0.5 * np.pi, np.pi)
    normals = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    spread = np.hypot(sxx - syy, 2.0 * sxy)  # eigenvalue difference
    normals[spread <= 1e-12] = np.nan
    return normals


def neighbourhood_covariances(
    points: np.ndarray, radius_m: float = 0.25, max_nn: int = 20
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Covariance of each point's neighbourhood, as Open3D's ``estimate_covariances``.

    The neighbourhood of a point is its ``max_nn`` nearest points (itself included)
    closer than ``radius_m`` (squared distance ``< radius_m**2``), nearest first, as
    Open3D's hybrid search; the covariance is Open3D's ``ComputeCovariance``: sums
    of x, y, x*x, x*y, y*y accumulated neighbour by neighbour in that order, divided
    by the count, ``E[xy] - E[x] E[y]``; with fewer than 3 neighbours it is the
    identity. The same floats as Open3D 0.19 (tested), without importing it.

    Parameters
    ----------
    points : (N, 2) float ndarray
        Points, metres.
    radius_m : float
        Neighbourhood radius, metres.
    max_nn : int
        At most this many neighbours.

    Returns
    -------
    sxx, syy, sxy : (N,) float64 ndarray
        Covariance entries, square metres.
    """
    from scipy.spatial import cKDTree

    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    if n == 0:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    k = int(min(max_nn, n))
    # slightly wider bound, then the exact rule on squared distances
    # an unbalanced tree (split at the midpoint of the cell, not the median) is quicker
    # to build and to search here; the neighbours and their order are the same but for
    # distinct points at exactly equal distances (lattices)
    _, idx = cKDTree(pts, balanced_tree=False).query(pts, k=k, distance_upper_bound=radius_m * (1 + 1e-9))
    # (k, N) layout: a sum over axis 0 adds neighbour after neighbour for every point,
    # in order, as Open3D does (no pairwise summation: that is for the inner axis);
    # "+ 0.0" as Open3D's sums start from +0.0 (only the sign of a zero sum differs)
    idx = np.ascontiguousarray(np.asarray(idx).reshape(n, k).T)
    ok = idx < n
    idx *= ok  # missing neighbours (index n) -> 0
    px, py = pts[:, 0].copy(), pts[:, 1].copy()
    x, y = px[idx], py[idx]
    d2, dy = x - px, y - py  # dx * dx + dy * dy in place
    d2 *= d2
    dy *= dy
    d2 += dy
    ok &= d2 < radius_m * radius_m
    cnt = ok.view(np.uint8).sum(axis=0, dtype=np.int64)
    # the points that are no neighbours become zeros (-0.0 for a negative coordinate:
    # no matter, a non-zero sum is unchanged by it and the "+ 0.0" makes a zero sum +0.0)
    x *= ok
    y *= ok
    sxy = np.multiply(x, y, out=d2).sum(axis=0) + 0.0  # x * y into a dead buffer
    sx, sy = x.sum(axis=0) + 0.0, y.sum(axis=0) + 0.0
    x *= x
    y *= y
    sxx, syy = x.sum(axis=0) + 0.0, y.sum(axis=0) + 0.0
    m = np.maximum(cnt, 1).astype(np.float64)
    sx, sy, sxx, sxy, syy = sx / m, sy / m, sxx / m, sxy / m, syy / m
    cxx, cyy, cxy = sxx - sx * sx, syy - sy * sy, sxy - sx * sy
    few = cnt < 3
    cxx[few], cyy[few], cxy[few] = 1.0, 1.0, 0.0
    return cxx, cyy, cxy

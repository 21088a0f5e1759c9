"""MeanShift clustering of the normal directions and of the offsets along a normal.

Steps 2 and 3 of :func:`floorscan.walls.cluster.cluster_ransac` (thesis section 3.4):
flat-kernel MeanShift with bin seeding (Comaniciu and Meer 2002), by default
:func:`mean_shift`, scikit-learn's algorithm step for step, vectorised over the seeds;
:func:`mean_shift_labels` picks it or :class:`sklearn.cluster.MeanShift`
(:attr:`floorscan.walls.params.ClusterParams.meanshift`) and estimates a missing bandwidth.

MeanShift stays custom because scikit-learn's moves one seed and queries one
neighbourhood at a time, about 30x slower on the small 1D and 2D projections of a
scan; a test checks that both give the same clusters.
"""

from __future__ import annotations

import warnings

import numpy as np

from floorscan.core.grid import cell_groups


def mean_shift(x: np.ndarray, bandwidth: float, min_bin_freq: int = 1, max_iter: int = 300) -> np.ndarray:
    """Flat-kernel mean shift with bin seeding, vectorised over the seeds.

    The algorithm of :class:`sklearn.cluster.MeanShift` with ``bin_seeding=True,
    cluster_all=True`` (Comaniciu and Meer 2002), step for step: seeds are the grid
    cells of size ``bandwidth`` holding at least ``min_bin_freq`` points (all points
    when every point has its own cell); each seed moves to the mean of the points
    within ``bandwidth`` until it moves less than ``1e-3 * bandwidth``; the modes,
    by decreasing number of points within, drop any later mode within ``bandwidth``;
    each point gets the label of its nearest mode. scikit-learn does the same one
    seed and one neighbour query at a time, each with its input validation, much
    slower on the small projections of a scan (benchmarks/bench_walls.py); a test
    checks that both give the same clusters.

    Parameters
    ----------
    x : (N, d) float ndarray
    bandwidth : float
        Kernel radius, in the units of ``x``.
    min_bin_freq : int
    max_iter : int

    Returns
    -------
    (N,) int64 ndarray
        Cluster labels 0.. (most populated mode first); all -1 when no cell holds
        ``min_bin_freq`` points.
    """
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    if len(x) == 0:
        return np.empty(0, dtype=np.int64)
    means = _bin_seeds(x, bandwidth, min_bin_freq)
    if len(means) == len(x):
        means = x.copy()
    if len(means) == 0:
        return np.full(len(x), -1, dtype=np.int64)
    r2, stop = bandwidth**2, 1e-3 * bandwidth
    within = np.zeros(len(means), dtype=np.int64)
    n, dim = x.shape
    # Squared distances of seeds m to points x, (m**2).sum(1)[:, None] - 2.0 * m @ x.T
    # + (x**2).sum(1)[None, :], as one BLAS product of rows (-2 m, (m**2).sum(), 1) with
    # columns (x, 1, (x**2).sum()): the kernel accumulates the terms in this order with
    # fused multiply-adds, so it rounds as the three steps (scaling by -2 is exact; the
    # tests check it bit for bit).
    xa = np.empty((dim + 2, n))
    xa[:dim] = x.T
    xa[dim] = 1.0
    xa[dim + 1] = _row_squares(x)
    act = np.arange(len(means))  # the seeds still moving, in seed order
    m = means.copy()  # their means
    for _ in range(max_iter):
        if len(act) == 0:
            break
        ma = np.empty((len(m), dim + 2))
        np.multiply(m, -2.0, out=ma[:, :dim])
        ma[:, dim] = _row_squares(m)
        ma[:, dim + 1] = 1.0
        # the flat kernel's weights (d2 <= r2) written as 1.0 / 0.0, and their counts
        # (sums of ones: exact integers, as w.sum(axis=1))
        w = ma @ xa
        np.less_equal(w, r2, out=w)  # in place: one (seeds, points) temporary fewer
        cnt = w.sum(axis=1)
        within[act] = cnt
        moved = cnt > 0
        if moved.all():  # the usual case: no boolean indexing
            new = (w @ x) / cnt[:, None]
            shift = np.sqrt(_row_squares(new - m))
            means[act] = new
            going = shift > stop
            if going.all():
                m = new
                continue
        else:
            new = (w[moved] @ x) / cnt[moved, None]
            shift = np.sqrt(_row_squares(new - m[moved]))
            means[act[moved]] = new
            going = np.zeros(len(act), dtype=bool)
            going[np.flatnonzero(moved)[shift > stop]] = True
        act = act[going]
        m = means[act]
    keep = within > 0
    if not keep.any():
        return np.full(len(x), -1, dtype=np.int64)
    centers, n_in = means[keep], within[keep]
    # Decreasing (points within, centre) as sklearn sorts its (centre, count) items.
    order = np.lexsort(tuple(centers[:, k] for k in range(centers.shape[1] - 1, -1, -1)) + (n_in,))[::-1]
    centers = centers[order]
    nc = len(centers)
    # row i: ((centers - centers[i]) ** 2).sum(axis=1) <= r2, for all i at once when few
    near = _pair_squares(centers, centers) <= r2 if nc <= 256 else None
    unique = np.ones(nc, dtype=bool)
    for i in range(nc):
        if unique[i]:
            unique[_row_squares(centers - centers[i]) <= r2 if near is None else near[i]] = False
            unique[i] = True
    centers = centers[unique]
    if len(centers) == 1:  # every point is nearest to it
        return np.zeros(n, dtype=np.int64)
    return np.argmin(_pair_squares(x, centers), axis=1).astype(np.int64)


def _bin_seeds(x: np.ndarray, bandwidth: float, min_bin_freq: int) -> np.ndarray:
    """MeanShift's bin seeds of (N, d) ``x``: the grid cells ``round(x / bandwidth)``
    holding at least ``min_bin_freq`` points, times ``bandwidth``, in lexicographic
    order of the cells, (S, d). In 1D (the offsets: most calls) by a sort and a
    comparison of neighbours instead of :func:`floorscan.core.grid.cell_groups` (same
    cells, fewer calls)."""
    cells = np.round(x / bandwidth)
    if x.shape[1] == 1:
        c = np.sort(cells[:, 0])
        new = np.empty(len(c), dtype=bool)
        new[0] = True
        np.not_equal(c[1:], c[:-1], out=new[1:])
        start = np.flatnonzero(new)
        counts = np.empty(len(start), dtype=np.intp)  # numpy.diff(start, append=len(c))
        np.subtract(start[1:], start[:-1], out=counts[:-1])
        counts[-1] = len(c) - start[-1]
        return c[start[counts >= min_bin_freq], None] * bandwidth
    counts, first = cell_groups(cells, first=True, inverse=False)
    return cells[first[counts >= min_bin_freq]] * bandwidth


def _row_squares(a: np.ndarray) -> np.ndarray:
    """``(a**2).sum(axis=1)`` of (N, d) ``a``, for d <= 2 without the reduction (slow on
    a short axis): a sum of one or two terms is the same float whatever the order."""
    if a.shape[1] == 1:
        return a[:, 0] * a[:, 0]
    if a.shape[1] == 2:
        return a[:, 0] * a[:, 0] + a[:, 1] * a[:, 1]
    return (a**2).sum(axis=1)


def _pair_squares(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Squared distances (N, M) of the rows of (N, d) ``a`` to those of (M, d) ``b``,
    ``((a[:, None, :] - b[None, :, :]) ** 2).sum(axis=2)``; for d <= 2 term by term (the
    same floats, without the 3D temporary and the reduction over a short axis)."""
    if a.shape[1] > 2:
        return ((a[:, None, :] - b[None, :, :]) ** 2).sum(axis=2)
    d = a[:, 0, None] - b[:, 0]
    out = d * d
    if a.shape[1] == 2:
        d = a[:, 1, None] - b[:, 1]
        out += d * d
    return out


def mean_shift_labels(
    x: np.ndarray, bandwidth: float | None, bin_seeding: bool, min_bin_freq: int, backend: str = "numpy"
) -> np.ndarray:
    """MeanShift labels of the rows of ``x`` (flat kernel, every point labelled;
    Comaniciu and Meer 2002).

    ``backend`` "numpy" is :func:`mean_shift` (needs ``bin_seeding``), "sklearn" is
    :class:`sklearn.cluster.MeanShift`.

    Parameters
    ----------
    x : (N, d) float ndarray
        Points to cluster (radians for the normal embedding, metres for offsets).
    bandwidth : float or None
        Flat-kernel radius, units of ``x``; None estimates it with
        ``sklearn.cluster.estimate_bandwidth(quantile=0.1)``.
    bin_seeding : bool
        Seeds are the grid cells (size ``bandwidth``) holding at least ``min_bin_freq``
        points; otherwise every point is a seed.
    min_bin_freq : int
    backend : {"numpy", "sklearn"}
        "numpy" is used only with ``bin_seeding``; otherwise scikit-learn.

    Returns
    -------
    (N,) int ndarray
        Cluster label per row; all -1 when no bin holds ``min_bin_freq`` points; all 0
        when the estimated bandwidth is not positive.
    """
    # scikit-learn only when used: its import is slow
    if bandwidth is None:
        from sklearn.cluster import estimate_bandwidth

        bandwidth = float(estimate_bandwidth(x, quantile=0.1)) if len(x) > 1 else 0.0
        if not bandwidth > 0:
            return np.zeros(len(x), dtype=np.int64)
    if backend == "numpy" and bin_seeding:
        return mean_shift(x, bandwidth, min_bin_freq)
    from sklearn.cluster import MeanShift, get_bin_seeds
    from threadpoolctl import threadpool_limits

    # One thread: the nearest-neighbour queries of MeanShift on a few hundred points
    # are much slower with a thread pool on a shared machine.
    with warnings.catch_warnings(), threadpool_limits(1):
        warnings.simplefilter("ignore")  # "binning data failed ... using all points"
        seeds = None
        if bin_seeding:
            # sklearn's MeanShift fails ("max() arg is an empty sequence") when no bin
            # holds min_bin_freq points: then no cluster is dense enough.
            seeds = get_bin_seeds(x, bandwidth, min_bin_freq)
            if len(seeds) == 0:
                return np.full(len(x), -1, dtype=np.int64)
        return MeanShift(bandwidth=bandwidth, seeds=seeds, cluster_all=True).fit_predict(x)

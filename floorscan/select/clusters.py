"""The clusters of a scan and their outliers (thesis section 3.3.2, Algorithm 2 steps 1-3).

Per scan, on the map-frame floor coordinates (x, y) only:

1. KMeans (scikit-learn's :class:`~sklearn.cluster.KMeans`: Lloyd with k-means++
   seeding, ``n_init`` fixed) with ``k_clusters`` centres on a seeded random
   subsample of at most ``sample_size`` points ("KMeans cannot be performed on all the
   points in a reasonable time. A small subset of those points is used for the
   clustering", section 3.3.2). The seed of scan ``s`` is derived from ``(seed, s)``,
   so a scan's clusters do not depend on which other scans are processed.
2. Every point of the scan is assigned to its nearest centre.
3. Outlier rule ("points around each cluster are selected, based on the minimum
   distance between all the cluster centers"): a point assigned to centre ``c`` is
   kept when its distance to ``c`` is at most ``radius_factor * d``, where ``d`` is

   - ``radius_rule="nearest_centre"`` (default): the distance from ``c`` to the
     nearest other centre (each cluster's own minimum centre distance), or
   - ``radius_rule="global_min"``: the minimum distance over all pairs of centres
     of the scan (the thesis sentence read literally).

   With a single centre (``k_clusters=1``, or a scan with one distinct point) there
   is no centre distance and every point is kept, so ``k_clusters=1`` gives the
   plain convex hull of the scan.

:func:`cluster_labels` does the three steps on one scan. The hulls stage
(:func:`floorscan.select.hulls.scan_hulls`) calls :func:`kmeans_sample` and
:func:`labels_from_sample` instead, so that parameter sets differing only in
``k_clusters`` (Fig. 5.7) share a scan's sample.

scikit-learn is imported where KMeans runs, not with this module: the jobs that only
merge or read hulls (select) need not import it. Its fits run under
:func:`kmeans_context`: many small fits on one thread, without scikit-learn's
per-call input and parameter checks (:func:`cluster_labels` and the hulls stage
check the scan, :class:`HullParams` its values).
"""

from __future__ import annotations

import contextlib
from typing import Iterator

import numpy as np

from floorscan.select.params import HullParams


def _scan_seed(seed: int, scan_id: int) -> np.random.Generator:
    return np.random.default_rng([int(seed), int(scan_id) & 0xFFFFFFFF])


def _n_distinct(xy: np.ndarray) -> int:
    """Number of distinct rows of an (N, 2) array (``len(np.unique(xy, axis=0))``)."""
    if len(xy) < 2:
        return len(xy)
    # as complex numbers (exact copies of x, y; -0.0 == 0.0 as floats), one sort
    # orders the rows as lexsort does
    c = np.empty(len(xy), dtype=np.complex128)
    c.real = xy[:, 0]
    c.imag = xy[:, 1]
    c.sort()
    return 1 + int(np.count_nonzero(c[1:] != c[:-1]))


@contextlib.contextmanager
def kmeans_context(clustering: bool = True) -> Iterator[None]:
    """The context of the hulls stage's KMeans fits: scikit-learn (and its OpenMP and
    BLAS) loaded, then limited to one thread; no per-call input finiteness check
    (:func:`cluster_labels` checks the scan) and no parameter validation
    (:class:`HullParams` checks them). Nothing when ``clustering`` is false.

    threadpoolctl limits only the libraries already loaded, hence scikit-learn is
    imported before the limit. One fit per scan on <= ``sample_size`` points gains
    nothing from threads, which would oversubscribe a shared machine, and on one
    thread the fits do not depend on the number of cores.

    Parameters
    ----------
    clustering : bool
        False: a context that does nothing (no scikit-learn import).

    Yields
    ------
    None
    """
    if not clustering:
        yield
        return
    import sklearn
    import sklearn.cluster  # noqa: F401  (loads its OpenMP runtime before the limit)
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1), sklearn.config_context(assume_finite=True, skip_parameter_validation=True):
        yield


def cluster_labels(points_xy: np.ndarray, params: HullParams = HullParams(), scan_id: int = 0) -> np.ndarray:
    """Cluster of every point of one scan, -1 for points dropped as outliers (thesis
    section 3.3.2, Algorithm 2; the radius rule is in the module docstring).

    Parameters
    ----------
    points_xy : (N, 2) float ndarray
        Scan points on the floor plane (map frame x, y), metres. Not modified.
    params : HullParams
        Clustering parameters (``k_clusters``, ``sample_size``, radius rule, seed).
    scan_id : int
        Mixed into the seed so each scan has its own reproducible random stream.

    Returns
    -------
    labels : (N,) int64 ndarray
        In ``0 .. k-1`` with ``k = min(k_clusters, distinct points)``, or -1 for a
        point outside its cluster's radius. All -1 for an empty scan.

    Raises
    ------
    ValueError
        When ``points_xy`` is not (N, 2), or holds NaN or inf.
    """
    xy = np.asarray(points_xy, dtype=np.float64)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise ValueError(f"points_xy must have shape (N, 2), got {xy.shape}")
    if len(xy) == 0:
        return np.zeros(0, dtype=np.int64)
    if not np.isfinite(xy).all():
        raise ValueError(f"scan {scan_id}: points_xy contains NaN or inf")
    with kmeans_context():
        return labels_from_sample(xy, params, kmeans_sample(xy, params, scan_id))


def kmeans_sample(xy: np.ndarray, params: HullParams, scan_id: int) -> tuple[np.ndarray, int, int | None]:
    """The KMeans input of a non-empty scan.

    Parameters
    ----------
    xy : (N, 2) float64 ndarray
        The scan's points, metres, N >= 1, finite.
    params : HullParams
        Only ``seed`` and ``sample_size`` are used.
    scan_id : int

    Returns
    -------
    sample : (min(N, sample_size), 2) float64 ndarray
        The points KMeans is fitted on, in scan order.
    distinct : int
        Distinct points in ``sample``.
    random_state : int or None
        KMeans' seed, drawn from the scan's stream after the subsample; None when the
        sample has at most one distinct point (no fit).

    Notes
    -----
    The three depend only on the scan, ``seed`` and ``sample_size``, so parameter sets
    differing in other fields (Fig. 5.7's ``k_clusters``) share them.
    """
    n = len(xy)
    rng = _scan_seed(params.seed, scan_id)
    sample = xy if n <= params.sample_size else np.take(xy, np.sort(rng.choice(n, params.sample_size, replace=False)), axis=0)
    distinct = _n_distinct(sample)
    state = int(rng.integers(2**31 - 1)) if distinct > 1 else None
    return sample, distinct, state


def labels_from_sample(xy: np.ndarray, params: HullParams, drawn: tuple[np.ndarray, int, int | None]) -> np.ndarray:
    """:func:`cluster_labels` of a non-empty, finite scan from its :func:`kmeans_sample`
    (run inside :func:`kmeans_context`; thesis Algorithm 2).

    Parameters
    ----------
    xy : (N, 2) float64 ndarray
        Scan points, metres, N > 0, finite.
    params : HullParams
    drawn : tuple
        :func:`kmeans_sample`'s ``(sample, distinct, random_state)``: the (M, 2) points
        KMeans fits, the number of distinct points, KMeans' seed.

    Returns
    -------
    (N,) int64 ndarray
        Cluster in ``0 .. k-1``, or -1 outside its cluster's radius; all 0 when
        ``k <= 1``.
    """
    sample, distinct, state = drawn
    n = len(xy)
    k = min(params.k_clusters, distinct)
    if k <= 1:
        return np.zeros(n, dtype=np.int64)
    from sklearn.cluster import KMeans

    centres = KMeans(
        n_clusters=k,
        n_init=params.n_init,
        max_iter=params.max_iter,
        random_state=state,
        algorithm="lloyd",
    ).fit(sample).cluster_centers_
    labels, d2min = _nearest_centre(xy, centres)
    cc = np.sqrt(((centres[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2))
    np.fill_diagonal(cc, np.inf)
    nearest = cc.min(axis=1)
    radius = params.radius_factor * (nearest if params.radius_rule == "nearest_centre" else np.full(k, nearest.min()))
    keep = d2min <= radius[labels] ** 2
    labels[~keep] = -1
    return labels


def _nearest_centre(xy: np.ndarray, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index of the nearest centre of every point and its squared distance.

    One pass per centre over (N,) arrays kept in the CPU cache, instead of (N, k)
    temporaries; the distances are the same floats (``dx*dx + dy*dy``, as
    ``((p - c) ** 2).sum(axis=1)``), and a tie goes to the lower centre index, as
    ``argmin``.
    """
    x, y = np.ascontiguousarray(xy[:, 0]), np.ascontiguousarray(xy[:, 1])
    dx, dy = x - centres[0, 0], y - centres[0, 1]
    best = dx * dx
    dy *= dy
    best += dy
    labels = np.zeros(len(x), dtype=np.int64)
    closer = np.empty(len(x), dtype=bool)
    for j in range(1, len(centres)):
        np.subtract(x, centres[j, 0], out=dx)
        np.subtract(y, centres[j, 1], out=dy)
        dx *= dx
        dy *= dy
        dx += dy
        np.less(dx, best, out=closer)
        np.copyto(best, dx, where=closer)
        np.copyto(labels, j, where=closer)
    return labels, best

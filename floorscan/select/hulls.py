"""Coverage hulls of scans on the floor plane (thesis section 3.3.2, Algorithm 2).

A scan's coverage is the area of the floor it sees. A single convex hull of the scan
overestimates it (thesis Fig. 3.2a: no measurement inside the hull's middle, and one
outlier inflates it), so Algorithm 2 splits each scan into clusters and takes the
union of one convex hull per cluster (Fig. 3.2b).

Per scan, on the map-frame floor coordinates (x, y) only:

1. KMeans (Lloyd with k-means++ seeding, ``n_init`` fixed; :func:`kmeans`, which
   gives scikit-learn's centres bit for bit) with ``k_clusters`` centres on a
   seeded random subsample of at most ``sample_size`` points ("KMeans cannot be
   performed on all the points in a reasonable time. A small subset of those points is
   used for the clustering", section 3.3.2). The seed of scan ``s`` is derived from
   ``(seed, s)``, so a scan's hulls do not depend on which other scans are processed.
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
4. The convex hull of each cluster's kept points (Shapely/GEOS, vectorised over all
   clusters of all scans at once). A cluster with fewer than 3 kept points or only
   collinear points has no area: it is stored as an empty polygon with
   ``area_m2 = 0``.

The scan's coverage is the union of its cluster hulls (:func:`scan_coverage`).

Speed (issue 8). Exact shortcuts, giving the same hulls bit for bit:

- the distinct points of the KMeans sample are counted with one sort of complex
  numbers instead of ``numpy.unique(axis=0)``;
- the points of a cluster go to GEOS as one LineString (one coordinate sequence)
  instead of a MultiPoint of point geometries: the convex hull of the same
  coordinates without a geometry object per point (GEOS's convex hull then costs
  ~0.1 us a point; creating the point objects cost ~1 us a point). A pre-filter
  of the points inside the octagon of extreme points (Akl-Toussaint) was measured
  slower than GEOS's own;
- KMeans distances as ``dx*dx + dy*dy`` without an (N, k, 2) temporary;
- the convex hull of a scan is that of its cluster hulls' vertices and of its
  points in no cluster hull (outliers): ~20 points a cluster instead of every point
  through GEOS a second time (a vertex of the scan's hull is a vertex of its
  cluster's hull, and GEOS gives the same ring for any point set with the same
  hull: its vertices without collinear points, from the lowest point);
- KMeans is :func:`kmeans`, scikit-learn's algorithm in NumPy with the same
  floating-point operations: the same centres bit for bit (tested; on the samples
  of all 1017 kept scans of hallways3d at k = 2, 10 and 20 too), without importing
  scikit-learn (1.4-1.7 CPU-s a job) or its per-fit checks: hallways3d's hulls
  stage took 4.6-5.5 CPU-s against 7.3-8.7 with scikit-learn, the same hulls. With
  ``kmeans: sklearn``, scikit-learn is imported before limiting its OpenMP/BLAS
  threads to one (threadpoolctl limits only loaded libraries: imported later,
  KMeans ran two OpenMP threads whose spinning cost +30 % CPU, several times more
  on a busy machine), and its per-call input and parameter validation is switched off
  (``sklearn.config_context``): the inputs are checked here;
- several parameter sets in one pass (Fig. 5.7's cluster counts) share each scan's
  KMeans sample, distinct-point count and ``random_state`` when their ``seed`` and
  ``sample_size`` agree (they depend on nothing else);
- rows gathered with ``np.take`` / ``np.compress`` (5-7x faster than ``xy[idx]`` /
  ``xy[mask]`` on (n, 2) arrays) and cluster sizes from the sorted labels.

:func:`scan_hulls` runs the stage scan by scan over any iterable of scans (e.g.
:func:`floorscan.core.io.iter_scans` streaming ``registered.parquet``), so memory follows
the largest scan, not the recording.
"""

from __future__ import annotations

import contextlib
import numbers
from dataclasses import asdict, dataclass, fields
from typing import Iterable, Iterator, Mapping, Sequence

import numpy as np
import pandas as pd
import pyarrow as pa
import shapely

from floorscan.core.io import split_by_scan

# scikit-learn (KMeans, hulls.kmeans: sklearn) and threadpoolctl are imported where
# used: importing scikit-learn costs 1.4-1.7 CPU-s, which the stages that only merge
# or read hulls (select) need not pay (issue 8).

#: ``hulls.parquet`` and ``convex_hulls.parquet``: a row per (scan, cluster); the
#: geometry is WKB (little endian, 2D) of a Polygon, empty when the hull has no area.
HULLS = pa.schema(
    [
        ("scan_id", pa.int32()),
        ("cluster", pa.int32()),
        ("geometry", pa.binary()),
        ("area_m2", pa.float64()),
    ]
)

#: ``cluster`` value of the rows of the single convex hull per scan.
CONVEX_CLUSTER = -1

RADIUS_RULES = ("nearest_centre", "global_min")
KMEANS_BACKENDS = ("numpy", "sklearn")


@dataclass(frozen=True)
class HullParams:
    """Parameters of the ``hulls`` stage (``workflow/schemas/hulls.schema.yaml``).

    Attributes
    ----------
    k_clusters : int
        KMeans clusters per scan (thesis: 10).
    sample_size : int
        Points per scan drawn (seeded, without replacement) for KMeans.
    radius_factor : float
        A point is kept when within ``radius_factor * d`` of its centre (see
        ``radius_rule``).
    radius_rule : {"nearest_centre", "global_min"}
        What ``d`` is: the centre's distance to its nearest other centre, or the
        minimum distance between any two centres of the scan.
    n_init : int
        KMeans initialisations (k-means++), fixed for determinism.
    max_iter : int
        KMeans Lloyd iterations at most.
    seed : int
        Base seed of the subsample and KMeans.
    kmeans : {"numpy", "sklearn"}
        KMeans implementation: :func:`kmeans` (default) or scikit-learn's
        ``KMeans``, the reference it reproduces bit for bit.
    """

    k_clusters: int = 10
    sample_size: int = 1000
    radius_factor: float = 1.0
    radius_rule: str = "nearest_centre"
    n_init: int = 1
    max_iter: int = 100
    seed: int = 0
    kmeans: str = "numpy"

    def __post_init__(self) -> None:
        # scikit-learn's parameter validation is off in the loop (_kmeans_config)
        for name in ("k_clusters", "sample_size", "n_init", "max_iter", "seed"):
            value = getattr(self, name)
            if not isinstance(value, numbers.Integral) or isinstance(value, bool):
                raise ValueError(f"hulls.{name} must be an integer, got {value!r}")
        if self.k_clusters < 1:
            raise ValueError(f"hulls.k_clusters must be >= 1, got {self.k_clusters}")
        if self.sample_size < 1:
            raise ValueError(f"hulls.sample_size must be >= 1, got {self.sample_size}")
        if not self.radius_factor > 0:
            raise ValueError(f"hulls.radius_factor must be > 0, got {self.radius_factor}")
        if self.radius_rule not in RADIUS_RULES:
            raise ValueError(f"hulls.radius_rule must be one of {RADIUS_RULES}, got {self.radius_rule!r}")
        if self.n_init < 1 or self.max_iter < 1:
            raise ValueError("hulls.n_init and hulls.max_iter must be >= 1")
        if self.kmeans not in KMEANS_BACKENDS:
            raise ValueError(f"hulls.kmeans must be one of {KMEANS_BACKENDS}, got {self.kmeans!r}")

    @classmethod
    def from_config(cls, cfg: Mapping | None) -> "HullParams":
        """Build from the stage's config dict; unknown keys raise ``ValueError``."""
        cfg = dict(cfg or {})
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(cfg) - names)
        if unknown:
            raise ValueError(f"unknown hulls config keys {unknown}; expected {sorted(names)}")
        return cls(**cfg)

    def as_dict(self) -> dict:
        return asdict(self)


def _scan_seed(seed: int, scan_id: int) -> np.random.Generator:
    return np.random.default_rng([int(seed), int(scan_id) & 0xFFFFFFFF])


def _n_distinct(xy: np.ndarray) -> int:
    """Number of distinct rows of an (N, 2) array (``len(np.unique(xy, axis=0))``)."""
    if len(xy) < 2:
        return len(xy)
    # as complex numbers (exact copies of x, y; -0.0 == 0.0 as floats), one sort
    # orders the rows as lexsort does, 4x faster
    c = np.empty(len(xy), dtype=np.complex128)
    c.real = xy[:, 0]
    c.imag = xy[:, 1]
    c.sort()
    return 1 + int(np.count_nonzero(c[1:] != c[:-1]))


def cluster_labels(points_xy: np.ndarray, params: HullParams = HullParams(), scan_id: int = 0) -> np.ndarray:
    """Cluster of every point of one scan, -1 for points dropped as outliers.

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

    Notes
    -----
    Thesis section 3.3.2 / Algorithm 2; the radius rule is documented in the module
    docstring. Raises ``ValueError`` when ``points_xy`` is not (N, 2) or not finite.
    """
    xy = np.asarray(points_xy, dtype=np.float64)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise ValueError(f"points_xy must have shape (N, 2), got {xy.shape}")
    if len(xy) == 0:
        return np.zeros(0, dtype=np.int64)
    if not np.isfinite(xy).all():
        raise ValueError(f"scan {scan_id}: points_xy contains NaN or inf")
    return _labels(xy, params, _kmeans_sample(xy, params, scan_id))


def _kmeans_sample(xy: np.ndarray, params: HullParams, scan_id: int) -> tuple[np.ndarray, int, int | None]:
    """The KMeans input of a non-empty scan: (sample, distinct points in it, the
    KMeans ``random_state``). They depend only on the scan, ``seed`` and
    ``sample_size``, so parameter sets differing in other fields (Fig. 5.7's
    ``k_clusters``) share them. The ``random_state`` is drawn from the scan's stream
    after the subsample; None when the scan has at most one distinct point (no fit)."""
    n = len(xy)
    rng = _scan_seed(params.seed, scan_id)
    sample = xy if n <= params.sample_size else np.take(xy, np.sort(rng.choice(n, params.sample_size, replace=False)), axis=0)
    distinct = _n_distinct(sample)
    state = int(rng.integers(2**31 - 1)) if distinct > 1 else None
    return sample, distinct, state


def _labels(xy: np.ndarray, params: HullParams, drawn: tuple[np.ndarray, int, int | None]) -> np.ndarray:
    """:func:`cluster_labels` of a non-empty, finite scan from its :func:`_kmeans_sample`."""
    sample, distinct, state = drawn
    n = len(xy)
    k = min(params.k_clusters, distinct)
    if k <= 1:
        return np.zeros(n, dtype=np.int64)
    if params.kmeans == "numpy":
        centres, _ = kmeans(sample, k, n_init=params.n_init, max_iter=params.max_iter, random_state=state)
    else:
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


def kmeans(
    points: np.ndarray,
    k: int,
    n_init: int = 1,
    max_iter: int = 300,
    random_state: int = 0,
    tol: float = 1e-4,
    init: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """KMeans (k-means++ seeding, Lloyd iterations): the centres of
    :class:`sklearn.cluster.KMeans` bit for bit, without importing scikit-learn.

    The algorithm of scikit-learn 1.9's ``KMeans(n_clusters=k, n_init=n_init,
    max_iter=max_iter, tol=tol, random_state=random_state, algorithm="lloyd")`` run
    on one thread, step for step and with the same floating-point operations: the
    data centred on its mean; greedy k-means++ (Arthur and Vassilvitskii 2007) with
    ``2 + int(log k)`` local trials drawn from ``numpy.random.RandomState(
    random_state)``; Lloyd steps that stop when no label changes or when the
    squared centre shifts sum to at most ``tol`` times the mean variance of the
    coordinates; an empty cluster moves to the point farthest from its centre;
    of ``n_init`` runs the lowest inertia wins. A stage makes ~1000 fits on ~1000
    points each (thesis Algorithm 2, one fit per scan): importing scikit-learn costs
    1.4-1.7 CPU-s a job, and its fits 1.3-1.6x the CPU time of these (``python -m
    benchmarks selection``). Tests check the same centres and labels, bit for bit,
    against scikit-learn on one thread, in 2D (``hulls.kmeans: sklearn`` runs
    scikit-learn instead).

    Parameters
    ----------
    points : (N, d) float ndarray
        Points to cluster, metres. Not modified.
    k : int
        Clusters, ``1 <= k <= N``.
    n_init : int
        Runs from different seedings; the one with the lowest inertia is returned.
    max_iter : int
        Lloyd steps at most per run.
    random_state : int
        Seed of the ``numpy.random.RandomState`` of the seeding.
    tol : float
        Relative tolerance on the centre shift (scikit-learn's ``tol``).
    init : (k, d) float ndarray, optional
        Initial centres instead of k-means++ (then ``n_init`` must be 1).

    Returns
    -------
    centres : (k, d) float64 ndarray
        Metres.
    labels : (N,) int64 ndarray
        Nearest centre of each point, ``0 .. k-1``.

    Raises
    ------
    ValueError
        When ``points`` is not (N, d) with ``1 <= k <= N``, or ``init`` is not (k, d).
    """
    x = np.array(points, dtype=np.float64, order="C")  # a copy: centred in place
    if x.ndim != 2 or not 1 <= int(k) <= len(x):
        raise ValueError(f"kmeans: points must be (N, d) with 1 <= k <= N, got shape {x.shape} and k={k}")
    k = int(k)
    tol_abs = np.mean(np.var(x, axis=0)) * tol  # scikit-learn: before centring
    mean = x.mean(axis=0)
    x -= mean  # "for more accurate distance computations" (scikit-learn)
    if init is not None:
        init = np.array(init, dtype=np.float64, order="C")
        if init.shape != (k, x.shape[1]) or n_init != 1:
            raise ValueError(f"kmeans: init must be ({k}, {x.shape[1]}) with n_init 1, got {init.shape}, {n_init}")
        init -= mean
    rng = np.random.RandomState(random_state)
    x_sq = np.einsum("ij,ij->i", x, x)
    cols = [np.ascontiguousarray(x[:, f]) for f in range(x.shape[1])]
    best = None
    for _ in range(int(n_init)):
        start = _kmeans_plusplus(x, x_sq, k, rng) if init is None else init
        centres, labels = _lloyd(x, cols, start, int(max_iter), tol_abs)
        if n_init == 1:  # nothing to compare (the stage's default: one fit per scan)
            best = (None, centres, labels)
            break
        d = x - centres[labels]
        d *= d
        # scikit-learn's inertia: point after point, as the cumulative sum
        inertia = np.cumsum(d.sum(axis=1))[-1]
        if best is None or (inertia < best[0] and not _same_clustering(labels, best[2], k)):
            best = (inertia, centres, labels)
    return best[1] + mean, best[2].astype(np.int64)


def _kmeans_plusplus(x: np.ndarray, x_sq: np.ndarray, k: int, rng: np.random.RandomState) -> np.ndarray:
    """scikit-learn's ``_kmeans_plusplus`` (unit weights): the same draws, the same
    distance expressions (``-2 c.x + |c|^2 + |x|^2``, clipped at 0)."""
    n = len(x)
    w = np.ones(n)
    trials = 2 + int(np.log(k))
    centres = np.empty((k, x.shape[1]))
    centres[0] = x[rng.choice(n, p=w / w.sum())]
    c0 = centres[0, np.newaxis]
    closest = -2 * (c0 @ x.T)
    closest += np.einsum("ij,ij->i", c0, c0)[:, None]
    closest += x_sq[None, :]
    np.maximum(closest, 0, out=closest)
    potential = closest @ w
    for c in range(1, k):
        draws = rng.uniform(size=trials) * potential
        candidates = np.searchsorted(np.cumsum(w * closest), draws)
        np.minimum(candidates, closest.size - 1, out=candidates)
        xc = x[candidates]
        d = -2 * (xc @ x.T)
        d += np.einsum("ij,ij->i", xc, xc)[:, None]
        d += x_sq[None, :]
        np.maximum(d, 0, out=d)
        np.minimum(closest, d, out=d)
        potentials = d @ w.reshape(-1, 1)
        pick = np.argmin(potentials)
        potential, closest = potentials[pick], d[pick]
        centres[c] = x[candidates[pick]]
    return centres


def _lloyd(x: np.ndarray, cols: list, centres: np.ndarray, max_iter: int, tol_abs: float):
    """scikit-learn's ``_kmeans_single_lloyd`` on one thread: (centres, labels)."""
    k = len(centres)
    labels_old = None
    converged = False  # strictly: no label changed
    for _ in range(max_iter):
        labels = _assign(x, centres)
        # sums point after point in order, as scikit-learn's loop (bincount adds in order)
        counts = np.bincount(labels, minlength=k).astype(np.float64)
        new = np.empty_like(centres)
        for f, col in enumerate(cols):
            new[:, f] = np.bincount(labels, weights=col, minlength=k)
        if not counts.all():
            _relocate_empty(x, centres, new, counts, labels)
        if counts.all():
            new *= (1.0 / counts)[:, None]
        else:  # scikit-learn's _average_centers, cluster by cluster
            largest = int(np.argmax(counts))
            for j in range(k):
                if counts[j] > 0:
                    new[j] *= 1.0 / counts[j]
                else:
                    new[j] = new[largest]
        shift = new - centres
        shift *= shift
        shift = np.sqrt(shift.sum(axis=1))
        centres = new
        if labels_old is not None and np.array_equal(labels, labels_old):
            converged = True
            break
        if (shift**2).sum() <= tol_abs:
            break
        labels_old = labels
    if not converged:
        labels = _assign(x, centres)
    return centres, labels


def _assign(x: np.ndarray, centres: np.ndarray) -> np.ndarray:
    """Nearest centre by ``|c|^2 - 2 c.x`` (scikit-learn's BLAS expression; the
    factor -2 is exact, so scaling the centres first gives the same floats)."""
    d = x @ (-2.0 * centres).T
    d += np.einsum("ij,ij->i", centres, centres)
    return d.argmin(axis=1)


def _relocate_empty(x, centres, new, counts, labels) -> None:
    """scikit-learn's ``_relocate_empty_clusters_dense``: each empty cluster takes
    the point farthest from its centre (in place on ``new`` and ``counts``)."""
    empty = np.flatnonzero(counts == 0)
    dist = ((x - centres[labels]) ** 2).sum(axis=1)
    far = np.argpartition(dist, -len(empty))[: -len(empty) - 1 : -1]
    if np.max(dist) == 0:  # fewer distinct points than clusters
        return
    for e, i in zip(empty, far):
        old = labels[i]
        new[old] -= x[i]
        new[e] = x[i]
        counts[e] = 1.0
        counts[old] -= 1.0


def _same_clustering(a: np.ndarray, b: np.ndarray, k: int) -> bool:
    """Whether labels ``a`` and ``b`` are the same partition up to a renaming."""
    first = np.full(k, -1, dtype=np.int64)
    idx = np.unique(a, return_index=True)
    first[idx[0]] = b[idx[1]]
    return bool(np.array_equal(first[a], b))


def _nearest_centre(xy: np.ndarray, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Index of the nearest centre of every point and its squared distance.

    One pass per centre over (N,) arrays kept in the CPU cache, instead of (N, k)
    temporaries (2x faster at k = 20); the distances are the same floats
    (``dx*dx + dy*dy``, as ``((p - c) ** 2).sum(axis=1)``), and a tie goes to the
    lower centre index, as ``argmin``.
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


class _HullBuilder:
    """Collects the points of groups (scan clusters) and makes their convex
    hulls with GEOS in batches: one LineString per group (the group's points as one
    coordinate sequence; its convex hull is that of the points).

    With ``convex=True`` it also makes the convex hull of every scan added, from the
    vertices of the scan's group hulls and the points in no group hull (outliers,
    groups of one point): a vertex of the scan's hull is a vertex of the hull of the
    group holding it, so these few points have the same hull as the whole scan
    (GEOS keeps the hull's vertices, without collinear points, and starts the ring
    at the lowest point: the same polygon bit for bit).
    """

    def __init__(self, batch_points: int = 1 << 20, convex: bool = False):
        self.batch_points = batch_points
        self.convex = convex
        self._xy: list[np.ndarray] = []
        self._n: list[np.ndarray] = []
        self._out: list[np.ndarray] = []
        self._pending = 0
        self.geoms: list[np.ndarray] = []
        self.convex_geoms: list[np.ndarray] = []

    def add(self, xy: np.ndarray, labels: np.ndarray, k: int) -> None:
        """Add the ``k`` groups of one scan: points ``xy`` with ``labels`` in 0..k-1,
        or -1 (ignored, but inside the scan's convex hull)."""
        ok = labels >= 0
        if ok.all():
            keep = None
            lab = labels
        else:
            keep = np.flatnonzero(ok)
            lab = labels[keep]
        # stable sort of small ints: radix sort for int16 (timsort for int64)
        order = np.argsort(lab.astype(np.int16) if k < 2**15 else lab, kind="stable")
        # np.take: row gathers 5-7x faster than xy[idx] / xy[mask] on (n, 2) arrays
        pts = np.take(xy, order if keep is None else np.take(keep, order), axis=0)
        counts = np.diff(np.searchsorted(np.take(lab, order), np.arange(k + 1)))  # bincount
        self._xy.append(pts)
        self._n.append(counts)
        if self.convex:
            self._out.append(np.zeros((0, 2)) if keep is None else np.compress(~ok, xy[:, :2], axis=0))
        self._pending += len(pts)
        if self._pending >= self.batch_points:
            self._flush()

    @staticmethod
    def _hulls(xy: np.ndarray, counts: np.ndarray) -> np.ndarray:
        """Convex hull of each run of ``counts`` rows of ``xy`` (GEOS geometry: Polygon,
        or LineString/Point when degenerate); an empty Polygon for a run of < 2 rows."""
        geoms = np.full(len(counts), shapely.Polygon(), dtype=object)
        line = counts >= 2  # fewer than 2 points: no LineString, and no area anyway
        n_line = int(line.sum())
        if n_line == len(counts):
            geoms[:] = shapely.convex_hull(shapely.linestrings(xy, indices=np.repeat(np.arange(n_line), counts)))
        elif n_line:
            # points of the groups with a line, and the line's number among them
            sel = np.repeat(line, counts)
            idx = np.repeat(np.arange(n_line), counts[line])
            geoms[line] = shapely.convex_hull(shapely.linestrings(np.compress(sel, xy, axis=0), indices=idx))
        return geoms

    def _flush(self) -> None:
        if not self._n:
            return
        counts = np.concatenate(self._n)
        xy = np.concatenate(self._xy) if len(self._xy) > 1 else self._xy[0]
        geoms = self._hulls(xy, counts)
        self.geoms.append(geoms)
        if self.convex:
            k = np.array([len(n) for n in self._n])
            scan = np.repeat(np.arange(len(k)), k)  # the scan (in this batch) of each group
            line = counts >= 2
            hull_xy, hull_i = shapely.get_coordinates(geoms[line], return_index=True)
            single = counts == 1
            n_out = np.array([len(o) for o in self._out])
            pts = np.concatenate([hull_xy, np.compress(np.repeat(single, counts), xy, axis=0), *self._out])
            sid = np.concatenate([scan[line][hull_i], scan[single], np.repeat(np.arange(len(k)), n_out)])
            order = np.argsort(sid, kind="stable")
            self.convex_geoms.append(self._hulls(np.take(pts, order, axis=0), np.bincount(sid, minlength=len(k))))
        self._xy, self._n, self._out, self._pending = [], [], [], 0

    @staticmethod
    def _polygons(parts: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        geoms = np.concatenate(parts) if parts else np.zeros(0, dtype=object)
        areas = shapely.area(geoms) if len(geoms) else np.zeros(0)
        poly = (shapely.get_type_id(geoms) == 3) & (areas > 0) if len(geoms) else np.zeros(0, bool)
        geoms = np.where(poly, geoms, shapely.Polygon())
        return geoms, np.where(poly, areas, 0.0).astype(np.float64)

    def finish(self) -> tuple[np.ndarray, np.ndarray]:
        """(geometries, areas) of every group added, in order; a hull without area
        (fewer than 3 points, collinear) is an empty Polygon with area 0."""
        self._flush()
        out = self._polygons(self.geoms)
        self.geoms = []
        return out

    def finish_convex(self) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`finish`, for the convex hull of every scan added (``convex=True``)."""
        self._flush()
        out = self._polygons(self.convex_geoms)
        self.convex_geoms = []
        return out


def _kmeans_config(clustering: bool):
    """scikit-learn's configuration for many small KMeans fits: no input finiteness
    check (:func:`cluster_labels` checks the scan) and no parameter validation
    (:class:`HullParams` checks them), which are per-call overhead, not results."""
    if not clustering:
        return contextlib.nullcontext()
    import sklearn

    return sklearn.config_context(assume_finite=True, skip_parameter_validation=True)


def _frame(scan_rows: list, cluster_rows: list, geoms: np.ndarray, areas: np.ndarray) -> pd.DataFrame:
    sid = np.concatenate(scan_rows).astype(np.int32) if scan_rows else np.zeros(0, np.int32)
    cl = np.concatenate(cluster_rows).astype(np.int32) if cluster_rows else np.zeros(0, np.int32)
    order = np.argsort(sid, kind="stable")  # scans in id order, clusters in order
    return pd.DataFrame(
        {"scan_id": sid[order], "cluster": cl[order], "geometry": geoms[order], "area_m2": areas[order]}
    )


def scan_hulls(
    scans: Iterable[tuple[int, np.ndarray]],
    params: Sequence[HullParams] = (HullParams(),),
    scan_ids: Iterable[int] | None = None,
    convex: bool = True,
    batch_points: int = 1 << 20,
) -> tuple[list[pd.DataFrame], pd.DataFrame | None, dict]:
    """Cluster hulls (one table per parameter set) and convex hulls, scan by scan.

    Parameters
    ----------
    scans : iterable of (int, (n, >=2) float ndarray)
        ``(scan_id, points)`` of each scan, map frame, metres; only columns 0 and 1
        (x, y) are used. Consumed once, one scan at a time (e.g.
        :func:`floorscan.core.io.iter_scans` or :func:`floorscan.core.io.split_by_scan`), so memory holds
        one scan plus up to ``batch_points`` points waiting for GEOS.
    params : sequence of HullParams
        One cluster-hull table per entry (Fig. 5.7 needs several ``k_clusters``).
    scan_ids : iterable of int, optional
        The scans to report; a listed scan without points gets one empty row
        (``cluster=0`` / ``-1``, area 0); points of unlisted scans are ignored.
        Default: every scan with points.
    convex : bool
        Also make the single convex hull per scan (:func:`convex_hulls`).
    batch_points : int
        Points handed to GEOS at once.

    Returns
    -------
    cluster : list of DataFrame
        Per entry of ``params``, as :func:`cluster_hulls`.
    convex : DataFrame or None
        As :func:`convex_hulls`.
    counts : dict
        ``n_scans`` (reported), ``n_points`` (of reported scans), ``n_points_ignored``,
        ``n_no_points`` (reported scans without points).

    Raises
    ------
    ValueError
        When a scan id comes twice (its points must come together), points are not
        (n, >=2), or (clustering) not finite.
    """
    params = list(params)
    wanted = None if scan_ids is None else set(int(s) for s in np.asarray(list(scan_ids), dtype=np.int64))
    # the convex hulls come from the first cluster hulls' vertices (see _HullBuilder)
    builders = [_HullBuilder(batch_points, convex=convex and i == 0) for i in range(len(params))]
    rows = [([], []) for _ in params]
    cbuilder = _HullBuilder(batch_points) if convex and not params else None
    crows: tuple[list, list] = ([], [])
    seen: set[int] = set()
    n_points = n_ignored = 0
    # one KMeans per scan on <= sample_size points: threads only add overhead and
    # oversubscribe a shared machine, so run BLAS/OpenMP single-threaded.
    # threadpoolctl limits only the libraries already loaded: load scikit-learn's
    # OpenMP and BLAS first when it is used (imported at the first scan instead, its
    # KMeans ran on every core, its idle threads spinning: +30 % CPU, and up to 5x on
    # a busy machine)
    from threadpoolctl import threadpool_limits

    use_sklearn = any(p.kmeans == "sklearn" for p in params)
    if use_sklearn:
        from sklearn.cluster import KMeans  # noqa: F401

    with threadpool_limits(limits=1), _kmeans_config(use_sklearn):
        for sid, pts in scans:
            sid = int(sid)
            if sid in seen:
                raise ValueError(f"scan {sid}: its points come in two separate runs; expected them together")
            seen.add(sid)
            pts = np.asarray(pts)
            if pts.ndim != 2 or pts.shape[1] < 2:
                raise ValueError(f"scan {sid}: points must have shape (n, 2) or (n, 3), got {pts.shape}")
            if wanted is not None and sid not in wanted:
                n_ignored += len(pts)
                continue
            xy = np.ascontiguousarray(pts[:, :2], dtype=np.float64)
            n_points += len(xy)
            if params and len(xy) and not np.isfinite(xy).all():
                raise ValueError(f"scan {sid}: points_xy contains NaN or inf")
            drawn: dict = {}  # (seed, sample_size) -> the KMeans sample, shared by params
            for p, b, (rs, rc) in zip(params, builders, rows):
                if len(xy) == 0:
                    lab = np.zeros(0, dtype=np.int64)
                else:
                    key = (p.seed, p.sample_size)
                    if key not in drawn:
                        drawn[key] = _kmeans_sample(xy, p, sid)
                    lab = _labels(xy, p, drawn[key])
                k = max(int(lab.max()) + 1, 1) if len(lab) else 1
                b.add(xy, lab, k)
                rs.append(np.full(k, sid))
                rc.append(np.arange(k))
            if convex:
                if cbuilder is not None:
                    cbuilder.add(xy, np.zeros(len(xy), dtype=np.int64), 1)
                crows[0].append(np.array([sid]))
                crows[1].append(np.array([CONVEX_CLUSTER]))
    missing = sorted(wanted - seen) if wanted is not None else []

    def table(finish, rs, rc, cluster_id):  # a scan without points gets one empty hull
        geoms, areas = finish()
        return _frame(rs + [np.array([s]) for s in missing], rc + [np.array([cluster_id]) for _ in missing],
                      np.r_[geoms, np.full(len(missing), shapely.Polygon(), dtype=object)],
                      np.r_[areas, np.zeros(len(missing))])

    out = [table(b.finish, rs, rc, 0) for b, (rs, rc) in zip(builders, rows)]
    conv = None
    if convex:
        conv = table(builders[0].finish_convex if params else cbuilder.finish, crows[0], crows[1], CONVEX_CLUSTER)
    counts = {"n_scans": len(seen) if wanted is None else len(wanted), "n_points": int(n_points), "n_points_ignored": int(n_ignored),
              "n_no_points": int(len(missing))}
    return out, conv, counts


def cluster_hulls(
    registered: pd.DataFrame,
    params: HullParams = HullParams(),
    scan_ids: Iterable[int] | None = None,
) -> pd.DataFrame:
    """Cluster hulls of every scan (thesis Algorithm 2 with the section 3.3.2 detail).

    Parameters
    ----------
    registered : DataFrame
        Map-frame points ``scan_id, x, y[, z]`` (metres), e.g. ``registered.parquet``.
        Only x and y are used. Not modified.
    params : HullParams
        Clustering parameters.
    scan_ids : iterable of int, optional
        The scans to report (e.g. the kept scans of ``registration.parquet``). A scan
        listed here without points gets one row ``cluster=0`` with an empty polygon
        and zero area; points of scans not listed are ignored. Default: every scan
        with points.

    Returns
    -------
    DataFrame
        ``scan_id`` int32, ``cluster`` int32 (``0..k-1``), ``geometry`` (Shapely
        Polygon, empty for a cluster with < 3 kept or collinear points), ``area_m2``
        float64, sorted by (scan_id, cluster). ``k`` is ``k_clusters``, or fewer for
        a scan with fewer distinct points.
    """
    out, _, _ = scan_hulls(split_by_scan(registered, ("x", "y")).items(), [params], scan_ids, convex=False)
    return out[0]


def convex_hulls(registered: pd.DataFrame, scan_ids: Iterable[int] | None = None) -> pd.DataFrame:
    """One convex hull per scan (the naive coverage of thesis Fig. 3.2a).

    Same columns as :func:`cluster_hulls`, ``cluster = -1`` (:data:`CONVEX_CLUSTER`),
    one row per scan; no outlier removal.
    """
    _, conv, _ = scan_hulls(split_by_scan(registered, ("x", "y")).items(), [], scan_ids, convex=True)
    return conv


def scan_coverage(hulls: pd.DataFrame, scan_ids: Iterable[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The coverage of each scan: the union of its hulls (thesis Algorithm 1 input).

    Parameters
    ----------
    hulls : DataFrame
        ``scan_id``, ``geometry`` (Shapely geometries or WKB bytes), as written by the
        hulls stage.
    scan_ids : iterable of int, optional
        Scans to return, in this order; a scan without rows gets an empty polygon.
        Default: the scans of ``hulls`` in ascending id.

    Returns
    -------
    scan_ids : (S,) int64 ndarray
    geometries : (S,) object ndarray of Shapely Polygon / MultiPolygon
        Vectorised: one ``union_all`` over a padded (S, k) array.
    """
    sid = hulls["scan_id"].to_numpy(dtype=np.int64)
    geom = hulls["geometry"].to_numpy()
    if len(geom) and isinstance(geom[0], (bytes, bytearray, memoryview)):
        geom = shapely.from_wkb(geom)
    ids = np.unique(sid) if scan_ids is None else np.asarray(list(scan_ids), dtype=np.int64)
    if len(ids) == 0:
        return ids, np.zeros(0, dtype=object)
    order = np.argsort(sid, kind="stable")
    sid, geom = sid[order], geom[order]
    uniq, starts, counts = np.unique(sid, return_index=True, return_counts=True)
    width = int(counts.max()) if len(counts) else 1
    padded = np.full((len(uniq), width), None, dtype=object)
    col = np.arange(len(sid)) - np.repeat(starts, counts)
    padded[np.repeat(np.arange(len(uniq)), counts), col] = geom
    unions = shapely.union_all(padded, axis=1)
    unions = np.where(shapely.is_empty(unions), shapely.Polygon(), unions)
    out = np.full(len(ids), shapely.Polygon(), dtype=object)
    pos = np.searchsorted(uniq, ids)
    hit = (pos < len(uniq)) & (uniq[np.minimum(pos, len(uniq) - 1)] == ids)
    out[hit] = unions[pos[hit]]
    return ids, out


def to_table(hulls: pd.DataFrame) -> pa.Table:
    """The hulls frame as a :data:`HULLS` table (WKB little endian, 2D)."""
    wkb = shapely.to_wkb(hulls["geometry"].to_numpy(), output_dimension=2, byte_order=1)
    return pa.table(
        {
            "scan_id": pa.array(hulls["scan_id"].to_numpy(np.int32), pa.int32()),
            "cluster": pa.array(hulls["cluster"].to_numpy(np.int32), pa.int32()),
            "geometry": pa.array(list(wkb), pa.binary()),
            "area_m2": pa.array(hulls["area_m2"].to_numpy(np.float64), pa.float64()),
        },
        schema=HULLS,
    )


def from_table(df: pd.DataFrame, path: str = "hulls") -> pd.DataFrame:
    """Parse a hulls table read from Parquet: geometry WKB -> Shapely.

    Raises ``KeyError`` naming ``path`` when a column is missing.
    """
    missing = [c for c in HULLS.names if c not in df.columns]
    if missing:
        raise KeyError(f"{path}: columns {missing} missing; expected {HULLS.names}")
    out = df[HULLS.names].copy()
    out["geometry"] = shapely.from_wkb(out["geometry"].to_numpy())
    return out


def kept_scan_ids(registration: pd.DataFrame, path: str = "registration.parquet") -> np.ndarray:
    """Scan ids with ``kept`` true in a registration table, ascending (int64).

    Raises ``KeyError`` naming ``path`` when ``scan_id`` or ``kept`` is missing.
    """
    missing = [c for c in ("scan_id", "kept") if c not in registration.columns]
    if missing:
        raise KeyError(f"{path}: columns {missing} missing; expected scan_id, kept, ...")
    kept = registration["kept"].to_numpy(dtype=bool)
    return np.unique(registration["scan_id"].to_numpy(dtype=np.int64)[kept])


def compute_hulls(
    registered: pd.DataFrame | Iterable[tuple[int, np.ndarray]],
    registration: pd.DataFrame,
    params: HullParams = HullParams(),
) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """The ``hulls`` stage: cluster hulls and convex hulls of every kept scan.

    Parameters
    ----------
    registered : DataFrame or iterable of (int, (n, >=2) ndarray)
        ``registered.parquet``: map-frame points ``scan_id, x, y, z`` (metres), as a
        frame, or streamed scan by scan (:func:`floorscan.core.io.iter_scans`), which
        keeps memory to one scan.
    registration : DataFrame
        ``registration.parquet``: one row per scan with ``scan_id`` and ``kept``.
    params : HullParams

    Returns
    -------
    cluster : DataFrame
        :func:`cluster_hulls` of the kept scans (a kept scan without points gets one
        empty row).
    convex : DataFrame
        :func:`convex_hulls` of the kept scans.
    counts : dict
        ``n_scans``, ``n_points``, ``n_points_ignored`` (points of scans not kept),
        ``n_no_points`` (kept scans without points), ``n_zero_area`` (kept scans whose
        cluster hulls have no area: < 3 points, collinear), ``n_clusters_zero_area``.

    Raises
    ------
    KeyError
        When ``registration`` lacks ``scan_id`` or ``kept``, or the frame lacks
        ``scan_id, x, y``.
    """
    ids = kept_scan_ids(registration)
    scans = split_by_scan(registered, ("x", "y")).items() if isinstance(registered, pd.DataFrame) else registered
    (cluster,), convex, counts = scan_hulls(scans, [params], ids, convex=True)
    per_scan = cluster.groupby("scan_id")["area_m2"].sum()
    counts["n_zero_area"] = int((per_scan <= 0).sum())
    counts["n_clusters_zero_area"] = int((cluster["area_m2"] <= 0).sum())
    return cluster, convex, counts

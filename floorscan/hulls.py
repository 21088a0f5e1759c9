"""Coverage hulls of scans on the floor plane (thesis section 3.3.2, Algorithm 2).

A scan's coverage is the area of the floor it sees. A single convex hull of the scan
overestimates it (thesis Fig. 3.2a: no measurement inside the hull's middle, and one
outlier inflates it), so Algorithm 2 splits each scan into clusters and takes the
union of one convex hull per cluster (Fig. 3.2b).

Per scan, on the map-frame floor coordinates (x, y) only:

1. KMeans (scikit-learn, Lloyd, ``n_init`` fixed) with ``k_clusters`` centres on a
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
4. The convex hull of each cluster's kept points (Shapely, vectorised over all
   clusters of all scans at once). A cluster with fewer than 3 kept points or only
   collinear points has no area: it is stored as an empty polygon with
   ``area_m2 = 0``.

The scan's coverage is the union of its cluster hulls (:func:`scan_coverage`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import Iterable, Mapping

import numpy as np
import pandas as pd
import pyarrow as pa
import shapely
from sklearn.cluster import KMeans
from threadpoolctl import threadpool_limits

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
    """

    k_clusters: int = 10
    sample_size: int = 1000
    radius_factor: float = 1.0
    radius_rule: str = "nearest_centre"
    n_init: int = 1
    max_iter: int = 100
    seed: int = 0

    def __post_init__(self) -> None:
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
    n = len(xy)
    if n == 0:
        return np.zeros(0, dtype=np.int64)
    if not np.isfinite(xy).all():
        raise ValueError(f"scan {scan_id}: points_xy contains NaN or inf")
    rng = _scan_seed(params.seed, scan_id)
    sample = xy if n <= params.sample_size else xy[np.sort(rng.choice(n, params.sample_size, replace=False))]
    n_distinct = len(np.unique(sample, axis=0))
    k = min(params.k_clusters, n_distinct)
    if k <= 1:
        return np.zeros(n, dtype=np.int64)
    km = KMeans(
        n_clusters=k,
        n_init=params.n_init,
        max_iter=params.max_iter,
        random_state=int(rng.integers(2**31 - 1)),
        algorithm="lloyd",
    ).fit(sample)
    centres = km.cluster_centers_
    # nearest centre of every point: (N, k) squared distances
    d2 = ((xy[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2)
    labels = d2.argmin(axis=1)
    cc = np.sqrt(((centres[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2))
    np.fill_diagonal(cc, np.inf)
    nearest = cc.min(axis=1)
    radius = params.radius_factor * (nearest if params.radius_rule == "nearest_centre" else np.full(k, nearest.min()))
    keep = d2[np.arange(n), labels] <= radius[labels] ** 2
    return np.where(keep, labels, -1).astype(np.int64)


def _hull_geometries(xy: np.ndarray, group: np.ndarray, n_groups: int) -> tuple[np.ndarray, np.ndarray]:
    """Convex hull per group (vectorised); degenerate hulls become empty polygons.

    ``group`` in ``0..n_groups-1`` (or -1 = ignore). Returns (geometries, areas).
    """
    ok = group >= 0
    geoms = np.full(n_groups, shapely.Polygon(), dtype=object)
    if ok.any():
        g = group[ok]
        order = np.argsort(g, kind="stable")
        present = np.unique(g)
        mp = shapely.multipoints(xy[ok][order], indices=np.searchsorted(present, g[order]))
        hulls = shapely.convex_hull(mp)
        geoms[present] = hulls
    areas = shapely.area(geoms)
    poly = (shapely.get_type_id(geoms) == 3) & (areas > 0)
    geoms = np.where(poly, geoms, shapely.Polygon())
    areas = np.where(poly, areas, 0.0)
    return geoms, areas


def _split(registered: pd.DataFrame) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """scan ids (sorted unique), start offsets, xy sorted by scan (stable)."""
    for col in ("scan_id", "x", "y"):
        if col not in registered.columns:
            raise KeyError(f"registered points: column {col!r} missing; expected scan_id, x, y, z")
    ids = registered["scan_id"].to_numpy()
    order = np.argsort(ids, kind="stable")
    ids = ids[order]
    xy = registered[["x", "y"]].to_numpy(dtype=np.float64)[order]
    uniq, starts = np.unique(ids, return_index=True)
    return uniq, np.r_[starts, len(ids)], xy


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
    uniq, bounds, xy = _split(registered)
    wanted = uniq if scan_ids is None else np.unique(np.asarray(list(scan_ids), dtype=np.int64))
    index = {int(s): i for i, s in enumerate(uniq)}
    group = np.full(len(xy), -1, dtype=np.int64)
    rows_scan, rows_cluster = [], []
    offset = 0
    # one KMeans per scan on <= sample_size points: threads only add overhead and
    # oversubscribe a shared machine, so run BLAS/OpenMP single-threaded
    with threadpool_limits(limits=1):
        labels = {int(sid): cluster_labels(xy[bounds[index[int(sid)]] : bounds[index[int(sid)] + 1]], params, scan_id=int(sid))
                  for sid in wanted if int(sid) in index}
    for sid in wanted:
        i = index.get(int(sid))
        if i is None:
            k = 1  # no points: one empty row
        else:
            a, b = bounds[i], bounds[i + 1]
            lab = labels[int(sid)]
            k = max(int(lab.max()) + 1, 1) if len(lab) else 1
            group[a:b] = np.where(lab >= 0, lab + offset, -1)
        rows_scan.append(np.full(k, sid))
        rows_cluster.append(np.arange(k))
        offset += k
    geoms, areas = _hull_geometries(xy, group, offset)
    return pd.DataFrame(
        {
            "scan_id": np.concatenate(rows_scan).astype(np.int32) if rows_scan else np.zeros(0, np.int32),
            "cluster": np.concatenate(rows_cluster).astype(np.int32) if rows_cluster else np.zeros(0, np.int32),
            "geometry": geoms,
            "area_m2": areas.astype(np.float64),
        }
    )


def convex_hulls(registered: pd.DataFrame, scan_ids: Iterable[int] | None = None) -> pd.DataFrame:
    """One convex hull per scan (the naive coverage of thesis Fig. 3.2a).

    Same columns as :func:`cluster_hulls`, ``cluster = -1`` (:data:`CONVEX_CLUSTER`),
    one row per scan; no outlier removal. Vectorised over all scans.
    """
    uniq, bounds, xy = _split(registered)
    wanted = uniq if scan_ids is None else np.unique(np.asarray(list(scan_ids), dtype=np.int64))
    pos = np.searchsorted(wanted, uniq)
    listed = (pos < len(wanted)) & (wanted[np.minimum(pos, len(wanted) - 1)] == uniq)
    counts = np.diff(bounds)
    group = np.repeat(np.where(listed, pos, -1), counts)
    geoms, areas = _hull_geometries(xy, group, len(wanted))
    return pd.DataFrame(
        {
            "scan_id": wanted.astype(np.int32),
            "cluster": np.full(len(wanted), CONVEX_CLUSTER, dtype=np.int32),
            "geometry": geoms,
            "area_m2": areas.astype(np.float64),
        }
    )


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
    registered: pd.DataFrame, registration: pd.DataFrame, params: HullParams = HullParams()
) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """The ``hulls`` stage: cluster hulls and convex hulls of every kept scan.

    Parameters
    ----------
    registered : DataFrame
        ``registered.parquet``: map-frame points ``scan_id, x, y, z`` (metres).
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
    """
    ids = kept_scan_ids(registration)
    present = np.isin(registered["scan_id"].to_numpy(), ids)
    cluster = cluster_hulls(registered, params, scan_ids=ids)
    convex = convex_hulls(registered, scan_ids=ids)
    per_scan = cluster.groupby("scan_id")["area_m2"].sum()
    with_points = np.unique(registered["scan_id"].to_numpy()[present])
    counts = {
        "n_scans": int(len(ids)),
        "n_points": int(present.sum()),
        "n_points_ignored": int((~present).sum()),
        "n_no_points": int(len(ids) - len(with_points)),
        "n_zero_area": int((per_scan <= 0).sum()),
        "n_clusters_zero_area": int((cluster["area_m2"] <= 0).sum()),
    }
    return cluster, convex, counts

"""Coverage hulls of scans on the floor plane: the ``hulls`` stage (thesis section 3.3.2,
Algorithm 2).

A scan's coverage is the area of the floor it sees. A single convex hull of the scan
overestimates it (thesis Fig. 3.2a: no measurement inside the hull's middle, and one
outlier inflates it), so Algorithm 2 splits each scan into clusters and takes the
union of one convex hull per cluster (Fig. 3.2b):

1-3. KMeans clusters of a seeded subsample, every point assigned to its nearest
     centre, points beyond a radius dropped as outliers (:mod:`floorscan.select.clusters`);
4.   the convex hull of each cluster's kept points (:mod:`floorscan.select.convex`,
     vectorised over all clusters of all scans at once). A cluster with fewer than 3
     kept points or only collinear points has no area: it is stored as an empty
     polygon with ``area_m2 = 0``.

The scan's coverage is the union of its cluster hulls (:func:`scan_coverage`), the
input of thesis Algorithm 1 (:mod:`floorscan.select.greedy`).

:func:`scan_hulls` runs the stage scan by scan over any iterable of scans (e.g.
:func:`floorscan.core.io.iter_scans` streaming ``registered.parquet``), so memory follows
the largest scan, not the recording; several parameter sets in one pass (Fig. 5.7's
cluster counts) share each scan's KMeans sample when their ``seed`` and
``sample_size`` agree. :func:`compute_hulls` is the stage on a shard of the kept scans
(``scripts/hulls.py``); :func:`merge_hull_shards` concatenates the shards into
``hulls.parquet`` and ``convex_hulls.parquet`` (the first step of the select job,
``scripts/select.py``).
"""

from __future__ import annotations

import logging
import os
from typing import Iterable, Sequence

import numpy as np
import pandas as pd
import pyarrow as pa
import shapely

from floorscan.core.grid import unique_ints
from floorscan.core.io import split_by_scan, write_table
from floorscan.core.shards import plan_from_files, read_shards
from floorscan.select.clusters import kmeans_context, kmeans_sample, labels_from_sample
from floorscan.select.convex import HullBuilder
from floorscan.select.params import HullParams

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
    # the convex hulls come from the first cluster hulls' vertices (see HullBuilder)
    builders = [HullBuilder(batch_points, convex=convex and i == 0) for i in range(len(params))]
    rows = [([], []) for _ in params]
    cbuilder = HullBuilder(batch_points) if convex and not params else None
    crows: tuple[list, list] = ([], [])
    seen: set[int] = set()
    n_points = n_ignored = 0
    # one KMeans per scan, on one thread (floorscan.select.clusters.kmeans_context)
    with kmeans_context(bool(params)):
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
                        drawn[key] = kmeans_sample(xy, p, sid)
                    lab = labels_from_sample(xy, p, drawn[key])
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
    """One convex hull per scan (the naive coverage of thesis Fig. 3.2a); no outlier
    removal.

    Parameters
    ----------
    registered : pandas.DataFrame
        Points table ``scan_id``, ``x``, ``y`` (map frame, metres).
    scan_ids : iterable of int, optional
        The scans to hull (default: every scan of ``registered``).

    Returns
    -------
    pandas.DataFrame
        The columns of :func:`cluster_hulls`, ``cluster = -1`` (:data:`CONVEX_CLUSTER`),
        one row per scan.
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
    ids = unique_ints(sid) if scan_ids is None else np.asarray(list(scan_ids), dtype=np.int64)
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
    """The hulls frame as a :data:`HULLS` table.

    Parameters
    ----------
    hulls : pandas.DataFrame
        ``scan_id``, ``cluster``, ``geometry`` (shapely), ``area_m2``.

    Returns
    -------
    pyarrow.Table
        ``scan_id``, ``cluster`` int32, ``geometry`` WKB (little endian, 2D),
        ``area_m2`` float64.
    """
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

    Parameters
    ----------
    df : pandas.DataFrame
        The :data:`HULLS` columns.
    path : str
        The file's name in error messages.

    Returns
    -------
    pandas.DataFrame
        A copy with the :data:`HULLS` columns, ``geometry`` as shapely geometries.

    Raises
    ------
    KeyError
        Naming ``path``, when a column is missing.
    """
    missing = [c for c in HULLS.names if c not in df.columns]
    if missing:
        raise KeyError(f"{path}: columns {missing} missing; expected {HULLS.names}")
    out = df[HULLS.names].copy()
    out["geometry"] = shapely.from_wkb(out["geometry"].to_numpy())
    return out


def kept_scan_ids(registration: pd.DataFrame, path: str = "registration.parquet") -> np.ndarray:
    """Scan ids with ``kept`` true in a registration table.

    Parameters
    ----------
    registration : pandas.DataFrame
        ``scan_id`` and ``kept``.
    path : str
        The file's name in error messages.

    Returns
    -------
    (K,) int64 ndarray
        Unique, ascending.

    Raises
    ------
    KeyError
        Naming ``path``, when ``scan_id`` or ``kept`` is missing.
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


def merge_hull_shards(
    shard_hulls: Sequence[str | os.PathLike],
    shard_convex: Sequence[str | os.PathLike],
    registration: str | os.PathLike,
    registered: str | os.PathLike,
    shard_scans: int,
    out_hulls: str | os.PathLike,
    out_convex: str | os.PathLike,
    dataset: str,
    log: logging.Logger | None = None,
) -> tuple[pd.DataFrame, pd.DataFrame, dict]:
    """The hull shards concatenated in scan order: ``hulls.parquet`` and
    ``convex_hulls.parquet``, exactly the tables of one unsharded job.

    Parameters
    ----------
    shard_hulls, shard_convex : sequence of path
        The shards' ``hulls.parquet`` and ``convex_hulls.parquet``
        (:func:`compute_hulls` of each scan range), each in a folder named by its
        shard label, in plan order.
    registration, registered : path
        The register stage's files the workflow made the shard plan from
        (:func:`floorscan.core.shards.plan_from_files`); the shards are checked against
        that plan.
    shard_scans : int
        ``hulls.shard_scans`` of the plan.
    out_hulls, out_convex : path
        Where the merged tables are written (atomically), with the metadata of the
        unsharded stage.
    dataset : str
        Dataset name, stored in the files' metadata.
    log : logging.Logger, optional
        Gets one line: the summed drop counts of the shards and their number.

    Returns
    -------
    cluster, convex : DataFrame
        The merged tables as written (geometry as WKB bytes; :func:`from_table`
        parses them).
    counts : dict
        The shards' ``counts`` (:func:`compute_hulls`) summed, without the per-scan
        area counts.

    Raises
    ------
    ValueError
        When the files are not the plan's shards (a stale plan or shard) or overlap
        (:func:`floorscan.core.shards.read_shards`).
    """
    # the plan the workflow named the shards by, from the register stage's files
    plan = plan_from_files(registration, registered, shard_scans)
    cluster, counts = read_shards(shard_hulls, plan, "hulls shards")
    convex, _ = read_shards(shard_convex, plan, "convex hull shards")
    if log is not None:
        log.info("hulls: %s from %d shards", counts, len(plan["shards"]))
    meta = {"stage": "hulls", "dataset": dataset, "units": "metres, m2"}
    cluster, convex = cluster.cast(HULLS), convex.cast(HULLS)  # the frames the files read back as
    write_table(cluster, out_hulls, metadata=meta)
    write_table(convex, out_convex, metadata=meta)
    return cluster.to_pandas(), convex.to_pandas(), counts

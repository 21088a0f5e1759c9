"""The select stage's orderings of the kept scans (thesis section 3.3), run from the
registry (:mod:`floorscan.select.registry`).

- :func:`select_stage` / :func:`select_orderings`: the ``select`` job, every ordering of
  :data:`~floorscan.select.registry.RANKERS` (thesis Algorithm 1 on cluster and convex
  hulls, and the baselines) and their summary. Along each ordering the covered area
  is measured the same way, the union of the scans' cluster hulls on the coverage
  raster (:func:`coverage_along`), so the orderings are comparable (thesis Fig. 5.6);
- :func:`coverage_orderings`: the ``select_coverage`` job, every ordering of
  :data:`~floorscan.select.registry.COVERAGE_SETS` (the lazy greedy on cell sets,
  :mod:`floorscan.select.coverage`), tables of their own objective;
- :func:`with_hull_coverage`: the hull area along the orderings that lack it (the
  coverage orderings), for the figures.

Usage (the ``select`` job, ``scripts/select.py``)::

    orderings, summary = select_stage(hulls, convex, registration, SelectParams())
    write_table(orderings["cluster_hull"], path, schema=ORDERING)
"""

from __future__ import annotations

import time
from typing import Iterable, Mapping, Sequence

import numpy as np
import pandas as pd
import pyarrow as pa
import shapely

from floorscan.core.greedy import lazy_greedy
from floorscan.select.hulls import kept_scan_ids, scan_coverage
from floorscan.select.params import CoverageParams, SelectParams
from floorscan.select.raster import RasterCoverage, ordering_table, raster_for
from floorscan.select.registry import COVERAGE_SETS, RANKERS, CoverageInputs, HullInputs
from floorscan.select.summary import summarize

#: ``orderings/{ordering}.parquet`` of the ``select`` job's orderings.
ORDERING = pa.schema(
    [
        ("rank", pa.int32()),
        ("scan_id", pa.int32()),
        ("covered_area_m2", pa.float64()),
        ("gain_m2", pa.float64()),
    ]
)


def coverage_along(
    scan_ids: Sequence[int],
    geometries: Sequence,
    order: Sequence[int],
    raster_m: float = 0.05,
    raster: RasterCoverage | None = None,
) -> pd.DataFrame:
    """Cumulative covered area along a given ordering.

    Parameters
    ----------
    scan_ids : (S,) int
        Unique scan ids.
    geometries : (S,) Shapely geometries
        Coverage of each scan, metres.
    order : (S,) int
        A permutation of ``scan_ids`` (ids, not positions).
    raster_m : float
        Coverage raster cell side, metres.
    raster : RasterCoverage, optional
        The raster of ``geometries`` at ``raster_m`` to reuse (its union is emptied).

    Returns
    -------
    DataFrame
        ``rank, scan_id, covered_area_m2, gain_m2``.

    Raises
    ------
    ValueError
        When ``order`` is not a permutation of ``scan_ids``, or ``raster`` is of other
        scans or another cell size.
    """
    ids, cov = raster_for(scan_ids, geometries, raster_m, raster)
    order = np.asarray(order, dtype=np.int64)
    pos = np.searchsorted(np.sort(ids), order)
    srt = np.argsort(ids, kind="stable")
    if len(order) != len(ids) or np.any(pos >= len(ids)) or not np.array_equal(np.sort(order), np.sort(ids)):
        raise ValueError("order must be a permutation of scan_ids")
    positions = srt[pos]
    gains = []
    for j in positions.tolist():
        gains.append(cov.gain(j))
        cov.add(j)
    return ordering_table(ids, positions, gains, raster_m**2)


def with_hull_coverage(orderings: Mapping[str, pd.DataFrame], hulls: pd.DataFrame, scan_ids, raster_m: float) -> dict:
    """The orderings with the hull area they cover along the way (``covered_area_m2``,
    ``gain_m2`` of :func:`coverage_along`), for the orderings whose tables lack it (the
    coverage orderings, which rank by their own objective), so that every ordering is
    compared on the same curve (thesis Fig. 5.6).

    Parameters
    ----------
    orderings : mapping of str to DataFrame
        Ordering tables (``rank, scan_id``, ...).
    hulls : DataFrame
        ``hulls.parquet`` (the cluster hulls of the kept scans).
    scan_ids : (S,) int
        The kept scans.
    raster_m : float
        Coverage raster cell side, metres.

    Returns
    -------
    dict of str to DataFrame
        The same tables; those without ``covered_area_m2`` get both columns (the other
        columns kept, rows in rank order).
    """
    missing = [name for name, o in orderings.items() if "covered_area_m2" not in o.columns]
    out = dict(orderings)
    if not missing:
        return out
    ids, geoms = scan_coverage(hulls, scan_ids)
    raster = RasterCoverage(geoms, raster_m)
    for name in missing:
        o = orderings[name].sort_values("rank", kind="stable").reset_index(drop=True)
        along = coverage_along(ids, geoms, o["scan_id"].to_numpy(), raster_m, raster=raster)
        out[name] = o.assign(covered_area_m2=along["covered_area_m2"].to_numpy(), gain_m2=along["gain_m2"].to_numpy())
    return out


def select_orderings(
    cluster_geometries: tuple[np.ndarray, np.ndarray],
    convex_geometries: tuple[np.ndarray, np.ndarray],
    poses: pd.DataFrame,
    params: SelectParams = SelectParams(),
) -> tuple[dict[str, pd.DataFrame], pd.DataFrame]:
    """Every ordering of :data:`~floorscan.select.registry.RANKERS` of the kept scans and
    their summary.

    Parameters
    ----------
    cluster_geometries : (scan_ids, geometries)
        Cluster-hull coverage per scan (:func:`floorscan.select.hulls.scan_coverage`).
    convex_geometries : (scan_ids, geometries)
        Convex-hull coverage per scan, the same scan ids.
    poses : DataFrame
        ``scan_id, t_ns, x_m, y_m, yaw_rad`` of at least these scans (registration).
    params : SelectParams

    Returns
    -------
    orderings : dict name -> DataFrame (``rank, scan_id, covered_area_m2, gain_m2``),
        covered area always of the cluster-hull union, so orderings are comparable.
    summary : DataFrame of the :data:`~floorscan.select.summary.SUMMARY` columns and
        ``seconds``, the time of each ranking (:func:`~floorscan.select.summary.summarize`).

    Raises
    ------
    ValueError
        When the convex and cluster scan ids differ or a scan has no pose row.
    """
    ids, geoms = (np.asarray(a) for a in cluster_geometries)
    cids, cgeoms = (np.asarray(a) for a in convex_geometries)
    if not np.array_equal(np.sort(ids), np.sort(cids)):
        raise ValueError("hulls and convex hulls cover different scans")
    cg = dict(zip(cids.tolist(), cgeoms))
    cgeoms = np.array([cg[int(s)] for s in ids], dtype=object)
    p = poses.set_index("scan_id")
    missing = sorted(set(ids.tolist()) - set(p.index.tolist()))
    if missing:
        raise ValueError(f"registration: no row for scans {missing[:10]} (of {len(missing)})")
    inputs = HullInputs(ids, geoms, cgeoms, p.loc[ids].reset_index(), params)
    order, secs = {}, {}
    for name, rank in RANKERS.items():
        t0 = time.perf_counter()
        order[name] = rank(inputs)  # the first to use inputs.raster makes it (in its time)
        secs[name] = time.perf_counter() - t0
    # every ordering's covered area is that of the cluster hulls, on one raster
    out = {name: coverage_along(ids, geoms, o, params.raster_m, raster=inputs.raster) for name, o in order.items()}
    area = shapely.area(geoms) if len(geoms) else np.zeros(0)
    return out, summarize(out, secs, zero_area=int((area <= 0).sum()))


def select_stage(
    hulls: pd.DataFrame, convex: pd.DataFrame, registration: pd.DataFrame, params: SelectParams = SelectParams()
) -> tuple[dict[str, pd.DataFrame], pd.DataFrame]:
    """The ``select`` stage on its input tables.

    Parameters
    ----------
    hulls, convex : DataFrame
        ``hulls.parquet`` and ``convex_hulls.parquet`` (geometry as WKB or Shapely).
    registration : DataFrame
        ``registration.parquet`` (``scan_id, t_ns, kept, x_m, y_m, yaw_rad``).
    params : SelectParams

    Returns
    -------
    As :func:`select_orderings`: every kept scan ranked in each ordering.

    Raises
    ------
    KeyError
        When a required column is missing (the message names the table).
    """
    need = ("scan_id", "t_ns", "kept", "x_m", "y_m", "yaw_rad")
    missing = [c for c in need if c not in registration.columns]
    if missing:
        raise KeyError(f"registration.parquet: columns {missing} missing; expected {list(need)}")
    for name, df in (("hulls.parquet", hulls), ("convex_hulls.parquet", convex)):
        miss = [c for c in ("scan_id", "geometry") if c not in df.columns]
        if miss:
            raise KeyError(f"{name}: columns {miss} missing; expected scan_id, cluster, geometry, area_m2")
    ids = kept_scan_ids(registration)
    cluster_geoms = scan_coverage(hulls, ids)
    convex_geoms = scan_coverage(convex, ids)
    poses = registration[registration["kept"].to_numpy(dtype=bool)]
    return select_orderings(cluster_geoms, convex_geoms, poses, params)


def coverage_orderings(
    per_scan: pd.DataFrame,
    scans: Iterable[tuple[int, np.ndarray]],
    scan_ids,
    params: CoverageParams = CoverageParams(),
    min_inliers: int = 15,
    threshold_m: float = 0.03,
    log=None,
) -> dict[str, pd.DataFrame]:
    """Every ordering of :data:`~floorscan.select.registry.COVERAGE_SETS` of the kept
    scans (the ``select_coverage`` job).

    Parameters
    ----------
    per_scan : pandas.DataFrame
        ``walls/<wall_extractor>/per_scan.parquet``.
    scans : iterable of (scan_id, (M, 2) float ndarray)
        Plan-view points of the kept scans, metres
        (:func:`floorscan.select.coverage.surface_cells`).
    scan_ids : sequence of int
        The kept scans.
    params : CoverageParams
    min_inliers, threshold_m : int, float
        The extractor's RANSAC settings.
    log : logging.Logger, optional

    Returns
    -------
    dict of str to pandas.DataFrame
        Per name (``wall_coverage``, ``surface_coverage``): ``rank, scan_id, gain,
        covered``.
    """
    ids = [int(s) for s in scan_ids]
    keep = set(ids)
    inputs = CoverageInputs(per_scan[per_scan["scan_id"].isin(keep)], ((s, xy) for s, xy in scans if int(s) in keep),
                            ids, params, min_inliers, threshold_m)
    out = {}
    for name, cells in COVERAGE_SETS.items():
        cover, quality, value = cells(inputs)
        out[name] = lazy_greedy(cover, ids, quality, value)
        if log is not None:
            adds = out[name][out[name]["gain"] > 0]
            covered = out[name]["covered"].to_numpy()
            k95 = int(np.searchsorted(covered, 0.95 * covered[-1] - 1e-9) + 1) if len(adds) else 0
            log.info("%s: %d cells of %.2f m, %d of them covered by >= %d scans; %d of %d scans add to them, "
                     "95 %% of the coverage from %d scans", name, len(value), params.cell_m, int(value.sum()),
                     params.min_scans, len(adds), len(ids), k95)
    return out

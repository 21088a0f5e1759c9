"""The data of the select stage's figures (thesis Figs 5.6, 5.7, 5.8), which
:mod:`floorscan.figures.selection` draws (rule ``selection_figures``; its script hands
this over):

- :func:`k99`: the fewest scans reaching 99 % of each ordering's final covered area,
  marked on the covered area against the number of scans (Fig. 5.6);
- :func:`coverage_vs_clusters`: the greedy ``cluster_hull`` coverage curve for several
  numbers of KMeans clusters (Fig. 5.7);
- :func:`selection_timing`: time to order n scans, the lazy greedy against the
  reference Algorithm 1 (Fig. 5.8). The reference is O(n^2) and is timed only up to
  ``reference_max_scans`` (default 150), so that the figure job stays short;
- :func:`selection_figure_data`: all three for a dataset, with the ``figure_*`` keys
  of the ``select`` section (:class:`FigureParams`).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from typing import Iterable, Mapping, Sequence

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from floorscan.core.config import schema_defaults
from floorscan.core.io import iter_scans, split_by_scan
from floorscan.select.greedy import greedy_coverage, greedy_reference
from floorscan.select.hulls import kept_scan_ids, scan_coverage, scan_hulls
from floorscan.select.params import HullParams, SelectParams
from floorscan.select.summary import k_for_fraction


@dataclass(frozen=True)
@schema_defaults("select", figure_k_clusters=lambda d: tuple(int(k) for k in d["figure_k_clusters"]))
class FigureParams:
    """The ``figure_*`` keys of the ``select`` config section
    (``stage_params(FigureParams, config["select"])``: the section's other keys are
    other classes', an unknown key a :class:`~floorscan.core.config.ConfigError`).

    Attributes
    ----------
    figure_k_clusters : tuple of int
        Cluster counts of Fig. 5.7 (1 = convex hull).
    figure_max_scans : int
        Figs 5.7/5.8 use at most this many scans, evenly spaced in recording order.
    figure_reference_max_scans : int
        Fig. 5.8 times the reference greedy only up to this many scans.
    """

    figure_k_clusters: tuple[int, ...]
    figure_max_scans: int
    figure_reference_max_scans: int


def _spaced(ids: np.ndarray, max_scans: int) -> np.ndarray:
    if len(ids) <= max_scans:
        return ids
    return ids[np.unique(np.linspace(0, len(ids) - 1, max_scans).round().astype(int))]


def coverage_vs_clusters(
    registered: pd.DataFrame | str | os.PathLike | Iterable[tuple[int, np.ndarray]],
    scan_ids: Sequence[int],
    k_values: Sequence[int],
    hull_params: HullParams = HullParams(),
    raster_m: float = 0.05,
    hulls: pd.DataFrame | None = None,
    convex: pd.DataFrame | None = None,
) -> dict[int, pd.DataFrame]:
    """Greedy ``cluster_hull`` ordering for each number of clusters (Fig. 5.7).

    Parameters
    ----------
    registered : DataFrame, path or iterable of (int, (n, >=2) ndarray)
        Map-frame points ``scan_id, x, y`` (metres): a frame, ``registered.parquet``
        (streamed scan by scan, :func:`floorscan.core.io.iter_scans`), or the scans.
        Read once for all ``k_values``.
    scan_ids : sequence of int
        The scans to order.
    k_values : sequence of int
        KMeans cluster counts; 1 gives the convex hull.
    hull_params : HullParams
        The other hull parameters (``k_clusters`` is replaced).
    raster_m : float
        Coverage raster cell, metres.
    hulls : DataFrame, optional
        The hulls stage's table (made with ``hull_params``): its rows are used for
        ``k = hull_params.k_clusters`` instead of clustering again (the same hulls:
        a scan's hulls depend only on the scan, the parameters and the seed).
    convex : DataFrame, optional
        The hulls stage's convex hulls (``convex_hulls.parquet``): used for ``k = 1``,
        whose cluster hull is the convex hull of the scan (one cluster, every point
        kept), instead of hulling every scan again.

    Returns
    -------
    dict k -> ordering frame (``rank, scan_id, covered_area_m2, gain_m2``).
    """
    return _coverage_curves(registered, scan_ids, k_values, hull_params, raster_m, hulls, convex)[0]


def _coverage_curves(registered, scan_ids, k_values, hull_params, raster_m, hulls, convex):
    """:func:`coverage_vs_clusters` and, per k, the scans' coverage (ids, geometries)
    that the curves ordered (Fig. 5.8 times the greedy on those of the stage's k)."""
    ids = np.asarray(scan_ids, dtype=np.int64)
    known = {}
    if hulls is not None:
        known[int(hull_params.k_clusters)] = hulls[np.isin(hulls["scan_id"].to_numpy(), ids)]
    if convex is not None:
        known[1] = convex[np.isin(convex["scan_id"].to_numpy(), ids)]
    todo = [int(k) for k in dict.fromkeys(int(k) for k in k_values) if int(k) not in known]
    if todo:
        if isinstance(registered, pd.DataFrame):
            scans = split_by_scan(registered[np.isin(registered["scan_id"].to_numpy(), ids)], ("x", "y")).items()
        elif isinstance(registered, (str, os.PathLike)):
            # float32 as stored (the registered.parquet contract): the scans not drawn
            # are skipped without a float64 copy, scan_hulls widens the drawn ones exactly
            schema = pq.read_schema(registered)
            f32 = all(schema.field(c).type == pa.float32() for c in ("x", "y") if c in schema.names)
            scans = iter_scans(registered, ("x", "y"), dtype=np.float32 if f32 else np.float64)
        else:
            scans = registered
        params = [HullParams(**{**hull_params.as_dict(), "k_clusters": k}) for k in todo]
        made, _, _ = scan_hulls(scans, params, scan_ids=ids, convex=False)
        known.update(zip(todo, made))
    out, coverage = {}, {}
    for k in k_values:
        if int(k) not in coverage:
            coverage[int(k)] = scan_coverage(known[int(k)], ids)
        out[int(k)] = greedy_coverage(*coverage[int(k)], raster_m)
    return out, coverage


def selection_timing(
    scan_ids: Sequence[int],
    geometries: Sequence,
    sizes: Sequence[int],
    reference_max_scans: int = 150,
    raster_m: float = 0.05,
) -> pd.DataFrame:
    """Time the lazy and the reference greedy on the first n scans (Fig. 5.8).

    Parameters
    ----------
    scan_ids : (S,) sequence of int
    geometries : (S,) sequence of shapely geometry
        Coverage of each scan, metres.
    sizes : sequence of int
        The n to time (capped at S).
    reference_max_scans : int
    raster_m : float
        Metres.

    Returns
    -------
    DataFrame
        ``n_scans``, ``fast_s``, ``reference_s`` (NaN above ``reference_max_scans``),
        ``identical`` (bool, orderings equal; NA when the reference was not run).
    """
    ids = np.asarray(scan_ids, dtype=np.int64)
    geoms = np.asarray(geometries, dtype=object)
    rows = []
    for n in sizes:
        n = int(min(n, len(ids)))
        t0 = time.perf_counter()
        fast = greedy_coverage(ids[:n], geoms[:n], raster_m)
        fast_s = time.perf_counter() - t0
        ref_s, same = np.nan, pd.NA
        if n <= reference_max_scans:
            t0 = time.perf_counter()
            ref = greedy_reference(ids[:n], geoms[:n], raster_m)
            ref_s = time.perf_counter() - t0
            same = bool(np.array_equal(fast["scan_id"].to_numpy(), ref["scan_id"].to_numpy()))
        rows.append({"n_scans": n, "fast_s": fast_s, "reference_s": ref_s, "identical": same})
    return pd.DataFrame(rows)


def k99(orderings: Mapping[str, pd.DataFrame]) -> dict[str, int]:
    """The fewest scans reaching 99 % of each ordering's final covered area (Fig. 5.6,
    :func:`floorscan.select.summary.k_for_fraction`).

    Parameters
    ----------
    orderings : mapping of str to pandas.DataFrame
        Ordering name -> ``rank``, ``covered_area_m2`` (square metres).

    Returns
    -------
    dict of str to int
        0 for an empty ordering or one of no area.
    """
    return {name: k_for_fraction(o.sort_values("rank"), 0.99) for name, o in orderings.items()}


@dataclass
class SelectionFigureData:
    """What the three selection figures draw.

    Attributes
    ----------
    k99 : dict of str to int
        :func:`k99` of the orderings (Fig. 5.6).
    clusters : dict of int to pandas.DataFrame
        :func:`coverage_vs_clusters` (Fig. 5.7).
    timing : pandas.DataFrame
        :func:`selection_timing` (Fig. 5.8).
    """

    k99: dict
    clusters: dict
    timing: pd.DataFrame


def selection_figure_data(
    registered: pd.DataFrame | str | os.PathLike,
    registration: pd.DataFrame,
    hulls: pd.DataFrame,
    orderings: Mapping[str, pd.DataFrame],
    hull_params: HullParams,
    select_params: SelectParams,
    params: FigureParams,
    convex_hulls: pd.DataFrame | None = None,
) -> SelectionFigureData:
    """The data of the three selection figures (thesis Figs. 5.6 to 5.8).

    Parameters
    ----------
    registered : pandas.DataFrame or path
        The points frame or ``registered.parquet`` (streamed scan by scan: memory
        follows the largest scan).
    registration : pandas.DataFrame
        ``registration.parquet``.
    hulls : pandas.DataFrame
        The hulls stage's table, made with ``hull_params``: the Fig. 5.7 curve of
        ``hull_params.k_clusters`` without clustering again.
    orderings : mapping of str to pandas.DataFrame
        Ordering name -> ``rank``, ``covered_area_m2`` (Fig. 5.6).
    hull_params : HullParams
    select_params : SelectParams
    params : FigureParams
    convex_hulls : pandas.DataFrame, optional
        The stage's ``convex_hulls.parquet``: the curve of k = 1.

    Returns
    -------
    SelectionFigureData
    """
    ids = _spaced(kept_scan_ids(registration), params.figure_max_scans)
    curves, coverage = _coverage_curves(
        registered, ids, params.figure_k_clusters, hull_params, select_params.raster_m, hulls, convex_hulls
    )
    # the coverage of the stage's hulls: the same unions as scan_coverage(hulls, ids)
    sid, geoms = coverage.get(int(hull_params.k_clusters)) or scan_coverage(hulls, ids)
    sizes = sorted({int(s) for s in np.unique(np.geomspace(10, max(len(ids), 10), 8).round())} | {len(ids)})
    sizes = [s for s in sizes if 0 < s <= len(ids)]
    timing = selection_timing(sid, geoms, sizes, params.figure_reference_max_scans, select_params.raster_m)
    return SelectionFigureData(k99(orderings), curves, timing)

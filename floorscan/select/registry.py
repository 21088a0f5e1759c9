"""The registry of scan orderings: every ordering the select stage makes, by name.

An ordering ranks every kept scan. There are two kinds, one per job of the stage:

- :data:`RANKERS`, the orderings of the ``select`` job (thesis section 3.3, Fig. 5.6):
  ``rank(inputs: HullInputs) -> (S,) int64 scan ids`` in rank order, a permutation
  of ``inputs.scan_ids``. The job measures the cluster-hull area along each
  (:func:`floorscan.select.orderings.select_orderings`), writes
  ``orderings/<name>.parquet`` and a row of ``orderings/summary.parquet``.
- :data:`COVERAGE_SETS`, the orderings of the ``select_coverage`` job (after the
  walls stage's per-scan segments, :mod:`floorscan.select.coverage`):
  ``cells(inputs: CoverageInputs) -> (cover, quality, value)``, the cell sets the
  lazy greedy (:func:`floorscan.core.greedy.lazy_greedy`) ranks the scans by
  (:func:`floorscan.select.orderings.coverage_orderings`).

:data:`ORDERINGS` and :data:`COVERAGE_ORDERINGS` (their names, in this order) are what
the workflow's rules (``workflow/rules/select.smk``) and the figures read.

To add an ordering: write its function (a module of this package by what it does,
e.g. :mod:`floorscan.select.baselines`), add one entry to :data:`RANKERS` or
:data:`COVERAGE_SETS` here, and add its name to the ``enum`` of
``select.default_ordering`` (``workflow/schemas/select.schema.yaml``) and of
``walls.orderings`` (``workflow/schemas/walls.schema.yaml``). The rules, scripts,
summary and figures follow the registry.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Callable, Iterable

import numpy as np
import pandas as pd

from floorscan.select.baselines import motion_filter_order, random_order, sequential_order
from floorscan.select.coverage import surface_cells, wall_cells
from floorscan.select.greedy import greedy_coverage
from floorscan.select.params import CoverageParams, SelectParams
from floorscan.select.raster import RasterCoverage


@dataclass
class HullInputs:
    """What the ``select`` job's orderings rank the kept scans from.

    Attributes
    ----------
    scan_ids : (S,) int64 ndarray
        The kept scans.
    cluster : (S,) object ndarray of Shapely geometries
        Cluster-hull coverage of each scan (:func:`floorscan.select.hulls.scan_coverage`),
        in ``scan_ids`` order, metres.
    convex : (S,) object ndarray of Shapely geometries
        Convex-hull coverage of each scan, in ``scan_ids`` order.
    poses : DataFrame
        ``scan_id, t_ns, x_m, y_m, yaw_rad``, a row per scan in ``scan_ids`` order.
    params : SelectParams
    """

    scan_ids: np.ndarray
    cluster: np.ndarray
    convex: np.ndarray
    poses: pd.DataFrame
    params: SelectParams

    @cached_property
    def raster(self) -> RasterCoverage:
        """The coverage raster of ``cluster`` at ``params.raster_m``, made once: the
        ``cluster_hull`` greedy and the hull area along every ordering use it."""
        return RasterCoverage(self.cluster, self.params.raster_m)


@dataclass
class CoverageInputs:
    """What the ``select_coverage`` job's orderings rank the kept scans from.

    Attributes
    ----------
    per_scan : DataFrame
        The kept scans' rows of ``walls/<wall_extractor>/per_scan.parquet``.
    scans : iterable of (int, (M, 2) float ndarray)
        Plan-view points of the kept scans, metres; consumed once.
    scan_ids : list of int
        The kept scans.
    params : CoverageParams
    min_inliers, threshold_m : int, float
        The wall extractor's RANSAC settings.
    """

    per_scan: pd.DataFrame
    scans: Iterable[tuple[int, np.ndarray]]
    scan_ids: list
    params: CoverageParams
    min_inliers: int = 15
    threshold_m: float = 0.03


def _cluster_hull(inputs: HullInputs) -> np.ndarray:
    """Thesis Algorithm 1 on the cluster hulls (:func:`greedy_coverage`)."""
    p = inputs.params
    return greedy_coverage(inputs.scan_ids, inputs.cluster, p.raster_m, raster=inputs.raster)["scan_id"].to_numpy()


def _convex_hull(inputs: HullInputs) -> np.ndarray:
    """The same greedy on one convex hull per scan (the naive coverage, Fig. 3.2a)."""
    return greedy_coverage(inputs.scan_ids, inputs.convex, inputs.params.raster_m)["scan_id"].to_numpy()


def _random(inputs: HullInputs) -> np.ndarray:
    return random_order(inputs.scan_ids, inputs.params.seed)


def _sequential(inputs: HullInputs) -> np.ndarray:
    return sequential_order(inputs.poses["scan_id"], inputs.poses["t_ns"])


def _motion_filter(inputs: HullInputs) -> np.ndarray:
    p = inputs.params
    return motion_filter_order(
        inputs.poses,
        max_distance_m=p.motion_max_distance_m,
        max_angle_rad=np.deg2rad(p.motion_max_angle_deg),
        max_time_s=p.motion_max_time_s,
    )


#: The ``select`` job's orderings: name -> ``rank(HullInputs)`` (scan ids in rank order).
RANKERS: dict[str, Callable[[HullInputs], np.ndarray]] = {
    "cluster_hull": _cluster_hull,
    "convex_hull": _convex_hull,
    "random": _random,
    "sequential": _sequential,
    "motion_filter": _motion_filter,
}

#: The ``select_coverage`` job's orderings: name -> ``cells(CoverageInputs)``, the
#: ``(cover, quality, value)`` of :func:`floorscan.core.greedy.lazy_greedy`.
COVERAGE_SETS: dict[str, Callable[[CoverageInputs], tuple]] = {
    "wall_coverage": lambda i: wall_cells(i.per_scan, i.params, i.min_inliers, i.threshold_m),
    "surface_coverage": lambda i: surface_cells(i.scans, i.params),
}

#: Names of the ``select`` job's orderings (``orderings/<name>.parquet``, the summary rows).
ORDERINGS = tuple(RANKERS)
#: Names of the ``select_coverage`` job's orderings.
COVERAGE_ORDERINGS = tuple(COVERAGE_SETS)

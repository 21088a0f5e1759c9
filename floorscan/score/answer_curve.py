"""The quality curve of the answer's floor plan: the plan the answer is made with (the
map extractor and the structure passes) of the first k scans of the default ordering,
against the reference map, for k on a geometric grid (rule ``answer_curve``).

The thesis's quality curves (thesis Fig. 5.8; :mod:`floorscan.score.curves`) score the
per-scan extractors' plans of every ordering on a dense grid; this curve scores the plan
a user gets, so its k95 and k99 (the first k whose plan reaches 95 / 99 % of the F1 of
the plan of all kept scans) are what the automatic k (``select.k: auto``) is measured
against. The plan of a set of scans is made by the walls and floorplan stages'
functions, which the stage's script hands to :func:`answer_curve` (``plan_of``).
"""

from __future__ import annotations

import os
from typing import Any, Callable

import numpy as np
import pandas as pd

from floorscan.core.occupancy import OccupancyGrid, OccupancyParams, occupancy_grid
from floorscan.core.wall_points import ScanParams, scan_points_2d


def curve_ks(n_kept: int, n_points: int = 24) -> list[int]:
    """About ``n_points`` values of k from 1 to ``n_kept``, geometrically spaced.

    Parameters
    ----------
    n_kept : int
        Kept scans.
    n_points : int

    Returns
    -------
    list of int
        Distinct, increasing, ``n_kept`` last; empty when ``n_kept`` < 1.
    """
    if n_kept < 1:
        return []
    ks = np.unique(np.round(np.geomspace(1, n_kept, max(2, n_points))).astype(np.int64))
    return sorted(set(ks.tolist()) | {int(n_kept)})


def answer_curve(
    registered_path: str | os.PathLike,
    registration: pd.DataFrame,
    ordering: pd.DataFrame,
    reference,
    plan_of: Callable[[np.ndarray, OccupancyGrid], Any],
    scan_params: ScanParams,
    grid_params: OccupancyParams,
    n_points: int = 24,
) -> pd.DataFrame:
    """F1, completeness and correctness at 5 cm against the reference map of the
    answer's plan of the first k scans of ``ordering``, for k in :func:`curve_ks`.

    Parameters
    ----------
    registered_path : path
        ``registered.parquet`` (kept scans' points in the map frame, metres).
    registration : pandas.DataFrame
        ``registration.parquet`` (``scan_id``, ``kept``, ``x_m``, ``y_m``).
    ordering : pandas.DataFrame
        ``orderings/<ordering>.parquet``: ``rank`` and ``scan_id``.
    reference : OccupancyGrid or Structure
        The reference map.
    plan_of : callable
        ``plan_of(points, grid)``: the answer's floor plan of the wall points of a set
        of scans (``(N, 2)`` float64, map metres) on their occupancy grid, with the
        tables ``walls`` and ``faces`` (``x0, y0, x1, y1``, metres): the map
        extractor's segments (:func:`floorscan.walls.map_lines.map_segments`) made a
        plan (:func:`floorscan.floorplan.plan.build_floorplan`), as the answer's plan
        is made; ``scripts/answer_curve.py`` makes it of the ``walls`` and
        ``floorplan`` config sections.
    scan_params : ScanParams
        How a scan becomes wall points (the ``walls`` section's height band and grid).
    grid_params : OccupancyParams
        The occupancy grid of the scans (the map extractor's: cells of
        ``walls.map.support_cell_m``).
    n_points : int
        Grid size (:func:`curve_ks`).

    Returns
    -------
    pandas.DataFrame
        ``k``, ``n_walls``, ``completeness_5cm``, ``correctness_5cm``, ``f1_5cm``, one row
        per k.
    """
    from floorscan.core.io import iter_scans
    from floorscan.score.against_reference import Structure, plan_against_reference

    structure = reference if isinstance(reference, Structure) else Structure(reference)
    reg = registration[registration["kept"]].set_index("scan_id")
    order = ordering.sort_values("rank")["scan_id"].to_numpy(np.int64)
    points = {}
    for sid, xyz in iter_scans(registered_path):
        if sid in reg.index:
            points[sid] = scan_points_2d(xyz, scan_params)[0]
    order = order[np.isin(order, list(points))]
    rows = []
    for k in curve_ks(len(order), n_points):
        ids = order[:k]
        scans = [(reg.loc[s, ["x_m", "y_m"]].to_numpy(np.float64), points[s]) for s in ids]
        pts = np.concatenate([p for _, p in scans]) if scans else np.empty((0, 2))
        if not any(len(p) for _, p in scans):
            rows.append({"k": k, "n_walls": 0, "completeness_5cm": 0.0, "correctness_5cm": np.nan, "f1_5cm": 0.0})
            continue
        grid = occupancy_grid(scans, grid_params)
        plan = plan_of(pts, grid)
        m = plan_against_reference(plan.faces[["x0", "y0", "x1", "y1"]].to_numpy(np.float64), structure, (0.05,))
        rows.append({"k": k, "n_walls": len(plan.walls), "completeness_5cm": m["completeness_5cm"],
                     "correctness_5cm": m["correctness_5cm"], "f1_5cm": m["f1_5cm"]})  # fmt: skip
    return pd.DataFrame(rows)

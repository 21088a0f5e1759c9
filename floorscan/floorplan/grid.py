"""The evaluation grid (stage ``floorplan``, rule ``floorplan``): the floor plan of the
first k scans of every ordering and k of the walls stage's grid, for one extractor.

Every plan is built by the one plan builder (:class:`~floorscan.floorplan.scans.ScanPlans`,
prepared once for the extractor's per-scan walls) and written as Parquet tables
(:func:`~floorscan.floorplan.scans.write_plan`, ``evaluation/plans/<ordering>_<extractor>_k<k>/``),
which the score stage reads, and in the formats of :data:`floorscan.floorplan.EVALUATION_FORMATS`
for people (``evaluation/floorplan/<ordering>_<extractor>_k<k>.*``). A plan of the
same scans as an earlier one (every ordering's ``k = all``) is built once and written
again with its own metadata (:class:`~floorscan.floorplan.writer.FloorplanWriter`).
"""

from __future__ import annotations

import logging
import os
from typing import Any, Mapping, Sequence

import pandas as pd

from floorscan.floorplan.footprints import PlanExports
from floorscan.floorplan.metadata import PlanMetadata, table_metadata
from floorscan.floorplan.scans import ScanPlans, write_plan
from floorscan.floorplan.writer import FloorplanWriter
from floorscan.core.selection import first_k_scans

log = logging.getLogger(__name__)


def write_plan_grid(
    walls: pd.DataFrame,
    orderings: Mapping[str, pd.DataFrame],
    runs: Sequence[tuple[str, str]],
    plan_folders: Sequence[str | os.PathLike],
    exports: Sequence[Mapping[str, str | os.PathLike]],
    cfg: Mapping[str, Any] | None,
    dataset: str,
    extractor: str,
    timestamp: float | None = None,
) -> list[dict]:
    """Build and write the plan of the first k scans of each run.

    Parameters
    ----------
    walls : pandas.DataFrame
        The extractor's per-scan wall segments (``walls/<extractor>/per_scan.parquet``,
        schema :data:`floorscan.walls.tables.WALLS`).
    orderings : mapping of str to pandas.DataFrame
        The orderings by name (``rank``, ``scan_id``).
    runs : sequence of (ordering, k label)
        The plans, e.g. ``("cluster_hull", "10")``, ``("random", "all")``.
    plan_folders : sequence of path
        Per run, its Parquet plan folder.
    exports : sequence of mapping
        Per run, its export paths by format (any of
        :data:`floorscan.floorplan.FLOORPLAN_FORMATS`; may be empty).
    cfg : mapping
        The ``floorplan`` config section (not georeferenced: the grid is in the map frame).
    dataset, extractor : str
        What the plans are of (their metadata).
    timestamp : float, optional
        The exports' time stamp, seconds since the epoch (the recording's first scan).

    Returns
    -------
    list of dict
        Per run: ``ordering``, ``k``, ``n_scans``, ``n_walls``, ``n_faces`` and
        ``reused`` (the same scans as an earlier run's plan).

    Raises
    ------
    KeyError
        For an ordering not in ``orderings``, an unknown export format, or a missing column.
    ValueError
        When the runs, folders and exports differ in length, or for a bad k label.
    """
    if not len(runs) == len(plan_folders) == len(exports):
        raise ValueError(f"{len(runs)} runs, {len(plan_folders)} plan folders, {len(exports)} export sets")
    writer = FloorplanWriter(cfg)
    builder = ScanPlans(walls, writer.params, prepared=True)
    built: dict[tuple[int, ...], PlanExports] = {}
    done = []
    for (ordering, k), folder, outputs in zip(runs, plan_folders, exports):
        ids = first_k_scans(orderings[ordering], k)
        key = tuple(sorted(ids))
        reused = key in built
        if not reused:
            built[key] = PlanExports(builder.plan(ids))
        plan = built[key].plan
        meta = PlanMetadata(dataset, ordering, extractor, k, timestamp)
        write_plan(plan, folder, table_metadata(meta, len(ids)))
        writer.export(built[key], outputs, meta)
        done.append({"ordering": ordering, "k": k, "n_scans": len(ids), "n_walls": len(plan.walls),
                     "n_faces": len(plan.faces), "reused": reused})
        log.info("%s k=%s: %d scans, %d walls, %d faces (%s)", ordering, k, len(ids), len(plan.walls),
                 len(plan.faces), "reused: same scans as an earlier plan" if reused else "built")
    return done

"""The recommended selection (rule ``selection``): the answer a user came for.

From the default ordering (``select.default_ordering``) it takes the first k scans
(``select.k``: ``auto`` by default, :func:`floorscan.select.deliverables.recommended_k`)
and writes, under ``results/<dataset>/selection/``:

- ``scans.csv``: rank, scan id, stamp (ns and ISO 8601), registered pose, gain;
- ``scans.parquet``: the same table for the later stages (the recommended plan,
  the map extractor's walls of the selected scans);
- ``points.ply``, ``points.pcd``: the selected scans' points in the map frame;
- ``recording/``: the recording cut to the selected scans, in its own format (written
  by the ingest stage's writer, :mod:`floorscan.ingest.reduced`, which the stage's
  script hands to :func:`write_selection`);
- ``selection.json``: k and the reason for it, the counts, and the size of the
  recording before and after (what :func:`floorscan.figures.answer.answer_lines` prints at the end of a run).

The recommended floor plan (``results/<dataset>/floorplan.*``) is made of the walls of
these scans by the floorplan stage.
"""

from __future__ import annotations

import logging
import os
from typing import Any, Callable, Mapping

import numpy as np
import pandas as pd

from floorscan.core.io import read_table
from floorscan.core.files import write_json
from floorscan.select.coverage import OBJECTIVE_COLUMN
from floorscan.select.deliverables import recommended_k, scan_list, write_scan_list, write_scan_table, write_selected_points

log = logging.getLogger(__name__)


def objective_of(ordering):
    """The cumulative objective of an ordering's table in rank order, and its unit:
    the coverage orderings' own objective (:data:`OBJECTIVE_COLUMN`, weighted cells),
    else the covered hull area (m2).

    Parameters
    ----------
    ordering : pandas.DataFrame
        An ordering table: ``rank`` and ``covered_objective`` or ``covered_area_m2``.

    Returns
    -------
    covered : (n,) float64 ndarray
    unit : str
        ``"cells"`` or ``"m2"``.
    """
    table = ordering.sort_values("rank", kind="stable")
    if OBJECTIVE_COLUMN in table.columns:
        return table[OBJECTIVE_COLUMN].to_numpy(dtype="float64"), "cells"
    return table["covered_area_m2"].to_numpy(dtype="float64"), "m2"


def write_selection(
    ordering_path: str | os.PathLike,
    ordering_name: str,
    index_path: str | os.PathLike,
    registration_path: str | os.PathLike,
    registered_path: str | os.PathLike,
    dataset: Mapping[str, Any],
    select_cfg: Mapping[str, Any],
    outputs: Mapping[str, str | os.PathLike],
    reduce_recording: Callable[[list[int]], dict],
) -> dict:
    """Pick k, write the scan list, the points and the reduced recording.

    Parameters
    ----------
    ordering_path : path
        ``orderings/<ordering_name>.parquet``.
    ordering_name : str
        ``select.default_ordering``.
    index_path, registration_path, registered_path : path
        ``scan_index.parquet``, ``registration.parquet``, ``registered.parquet``.
    dataset : mapping
        The dataset as ingest read it (``name``).
    select_cfg : mapping
        The ``select`` config section as the schema fills it (``k``, ``k_coverage``).
    outputs : mapping
        Paths ``scans`` (CSV), ``table`` (the same, Parquet), ``ply``, ``pcd`` and ``summary`` (JSON).
    reduce_recording : callable
        ``reduce_recording(scan_ids) -> dict``: writes the recording cut to the selected
        scans (ingest's ``scan_id``, rank order) and returns what it wrote, the
        ``recording`` of ``selection.json``
        (:func:`floorscan.ingest.reduced.write_selected_recording`).

    Returns
    -------
    dict
        The content of ``selection.json``.

    Raises
    ------
    ValueError
        From :func:`recommended_k` (a bad rule, an empty ordering).
    floorscan.core.io.InputError
        When the recording no longer holds the scans ingest numbered
        (``reduce_recording``).
    """
    ordering = read_table(ordering_path)
    covered, unit = objective_of(ordering)
    k, reason = recommended_k(covered, select_cfg["k"], float(select_cfg["k_coverage"]), objective=ordering_name,
                              unit=unit)
    log.info("%s", reason)
    stamps = read_table(index_path, columns=["scan_id", "t_ns"])  # ingest's scan index
    t_ns = stamps["t_ns"].to_numpy(np.int64)
    index = pd.DataFrame({"scan_id": stamps["scan_id"].to_numpy(np.int64), "t_ns": t_ns})
    table = scan_list(ordering, k, index, read_table(registration_path))
    write_scan_list(table, outputs["scans"])
    write_scan_table(table, outputs["table"], {"ordering": ordering_name, "k": str(int(k))})
    ids = table["scan_id"].astype(int).tolist()
    n_points = write_selected_points(registered_path, ids, outputs["ply"], outputs["pcd"])
    log.info("scan list %s; %d points of the %d scans in %s and %s", outputs["scans"], n_points, k,
             outputs["ply"], outputs["pcd"])
    rec = reduce_recording(ids)
    summary = {
        "dataset": str(dataset.get("name", "")),
        "ordering": ordering_name,
        "k": int(k),
        "k_rule": select_cfg["k"],
        "k_coverage": float(select_cfg["k_coverage"]),
        "reason": reason,
        "n_kept": int(len(ordering)),
        "n_recorded": int(len(t_ns)),
        "n_points": int(n_points),
        "scans": str(outputs["scans"]),
        "points": [str(outputs["ply"]), str(outputs["pcd"])],
        "recording": rec,
    }
    write_json(summary, outputs["summary"])
    return summary

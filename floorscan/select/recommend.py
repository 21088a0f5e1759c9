"""The recommended selection (rule ``selection``): the answer a user came for.

From the default ordering (``select.default_ordering``) it takes the first k scans
(``select.k``: ``auto`` by default, :func:`floorscan.select.deliverables.recommended_k`)
and writes, under ``results/<dataset>/selection/``:

- ``scans.csv``: rank, scan id, stamp (ns and ISO 8601), registered pose, gain;
- ``scans.parquet``: the same table for the later stages (the recommended plan,
  the map extractor's walls of the selected scans);
- ``points.ply``, ``points.pcd``: the selected scans' points in the map frame;
- ``recording/``: the recording cut to the selected scans, in its own format
  (:mod:`floorscan.select.recording`);
- ``selection.json``: k and the reason for it, the counts, and the size of the
  recording before and after (what :func:`floorscan.figures.answer.answer_lines` prints at the end of a run).

The recommended floor plan (``results/<dataset>/floorplan.*``) is made of the walls of
these scans by the floorplan stage.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pandas as pd

from floorscan.ingest.detect import bag_path
from floorscan.core.io import read_table
from floorscan.core.files import write_json
from floorscan.select.coverage import OBJECTIVE_COLUMN
from floorscan.select.deliverables import recommended_k, scan_list, write_scan_list, write_scan_table, write_selected_points
from floorscan.select.recording import read_detection, write_reduced_recording

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
    recording_path: str | os.PathLike,
    dataset: Mapping[str, Any],
    select_cfg: Mapping[str, Any],
    outputs: Mapping[str, str | os.PathLike],
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
    recording_path : path
        The recording ingest read.
    dataset : mapping
        The dataset as ingest read it (``format``, ``path``, ``locations``).
    select_cfg : mapping
        The ``select`` config section as the schema fills it (``k``, ``k_coverage``).
    outputs : mapping
        Paths ``scans`` (CSV), ``table`` (the same, Parquet), ``ply``, ``pcd``, ``recording`` (a folder, made here) and
        ``summary`` (JSON).

    Returns
    -------
    dict
        The content of ``selection.json``.

    Raises
    ------
    ValueError
        From :func:`recommended_k` (a bad rule, an empty ordering).
    floorscan.core.io.InputError
        When the recording no longer holds the scans ingest numbered.
    """
    ordering = read_table(ordering_path)
    covered, unit = objective_of(ordering)
    k, reason = recommended_k(covered, select_cfg["k"], float(select_cfg["k_coverage"]), objective=ordering_name,
                              unit=unit)
    log.info("%s", reason)
    detection = read_detection(index_path, dataset)  # checks scan_id is 0..N-1: t_ns[i] is scan i's
    t_ns = detection["t_ns"]
    index = pd.DataFrame({"scan_id": np.arange(len(t_ns), dtype=np.int64), "t_ns": t_ns})
    table = scan_list(ordering, k, index, read_table(registration_path))
    write_scan_list(table, outputs["scans"])
    write_scan_table(table, outputs["table"], {"ordering": ordering_name, "k": str(int(k))})
    ids = table["scan_id"].astype(int).tolist()
    n_points = write_selected_points(registered_path, ids, outputs["ply"], outputs["pcd"])
    log.info("scan list %s; %d points of the %d scans in %s and %s", outputs["scans"], n_points, k,
             outputs["ply"], outputs["pcd"])
    # the recording's own name (a ROS2 bag given by its .db3 / .mcap file: its folder's)
    out = Path(outputs["recording"]) / bag_path(recording_path).name
    rec = write_reduced_recording(recording_path, detection.get("format") or dataset.get("format"), ids, out,
                                  detection)
    log.info("reduced recording %s: %d of %d messages, %d bytes of %d (%.1f %%)", out, rec["messages_out"],
             rec["messages_in"], rec["bytes_out"], rec["bytes_in"], 100.0 * rec["bytes_out"] / max(rec["bytes_in"], 1))
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

"""Write a recording's tables: ``scans.parquet``, ``scan_index.parquet``, ``pose_stream.parquet``.

:func:`write_recording` streams the points of each scan to ``scans.parquet`` one batch
at a time (row groups written in a thread by :class:`floorscan.core.io.ScanRowGroups`),
so memory grows with the largest scan, not with the recording. The three files are
written atomically, and what the reader detected goes into the schema metadata of the
scan index and the pose stream. Scans whose ranges are not metres (millimetres,
centimetres: :func:`floorscan.ingest.units.range_units_problem`) are refused, after
:data:`~floorscan.ingest.units.EARLY_CHECK_SCANS` scans or at the end.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Mapping

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from floorscan.core.runtime import progress
from floorscan.core.io import (
    POSE_STREAM,
    SCAN_INDEX,
    SCANS,
    InputError,
    parquet_options,
    ScanRowGroups,
    write_table,
)
from floorscan.core.files import atomic_path
from floorscan.ingest.recording import Recording, pose_stream_frame
from floorscan.ingest.units import EARLY_CHECK_SCANS, MedianReturn, range_units_problem

log = logging.getLogger(__name__)


def write_recording(
    recording: Recording,
    scans_path: str | Path,
    index_path: str | Path,
    pose_stream_path: str | Path,
    sensor_height_m: float = 0.0,
    metadata: Mapping[str, str] | None = None,
) -> pd.DataFrame:
    """Stream a recording's scans to Parquet and write its index and pose stream.

    Scans get ``scan_id`` 0..N-1 in recording order, and ``source_ordinal`` their
    frame's ordinal in the recording (:attr:`floorscan.ingest.recording.Scan.source_ordinal`;
    null when the reader does not number its frames): the select stage finds a scan in
    the recording by it, whatever ingest skipped or sorted. ``sensor_height_m`` is added to
    the pose stream's z. All three files are written atomically: on any error none
    of them is left behind. ``recording.detected`` (string values, read once the scans
    are exhausted: the loss counts are complete then) and ``metadata`` are stored in the
    schema metadata of the scan index and the pose stream; the register stage reads
    ``pose_kind`` and ``stamps`` from the scan index's.

    Parameters
    ----------
    recording : Recording
        Consumed: its scans are iterated once.
    scans_path, index_path, pose_stream_path : path
        Outputs: ``scans.parquet``, ``scan_index.parquet``, ``pose_stream.parquet``.
    sensor_height_m : float
        Added to the pose stream's z, metres.
    metadata : mapping of str to str, optional
        More schema metadata (e.g. ``dataset``, ``source``).

    Returns
    -------
    pandas.DataFrame
        The scan index (columns of :data:`floorscan.core.io.SCAN_INDEX`).

    Raises
    ------
    InputError
        No scans, scan timestamps going backwards, no poses while the pose kind is
        not ``none`` (a map pose source was found or set but has no poses), or scans
        whose ranges are not metres (names the recording and its scans).
    """
    rows: list[tuple[int, int, int, int, str, int | None]] = []
    meta = {k.encode(): str(v).encode() for k, v in (metadata or {}).items()}
    with atomic_path(scans_path) as tmp:
        with pq.ParquetWriter(tmp, SCANS.with_metadata(meta), **parquet_options(SCANS, ["scan_id"])) as writer:
            with ScanRowGroups(writer) as batch:  # row groups written in a thread
                last_t = None
                median = MedianReturn()
                for scan_id, scan in enumerate(progress(recording.scans, log, what="scans read")):
                    if last_t is not None and scan.t_ns < last_t:
                        raise InputError(
                            f"{recording.source}: scan timestamps go backwards at scan {scan_id} "
                            f"({scan.t_ns} ns after {last_t} ns); expected non-decreasing stamps"
                        )
                    last_t = scan.t_ns
                    pts = np.asarray(scan.points, dtype=np.float32).reshape(-1, 3)
                    n = len(pts)
                    ordinal = None if scan.source_ordinal is None else int(scan.source_ordinal)
                    rows.append((scan_id, int(scan.t_ns), n, int(scan.n_dropped), scan.frame, ordinal))
                    if n:
                        batch.add(scan_id, pts)
                    median.add(pts)
                    if median.n_scans == EARLY_CHECK_SCANS:
                        _check_range_units(recording, median)
        if not rows:
            raise InputError(f"{recording.source}: no scans found")
        index = pd.DataFrame(rows, columns=["scan_id", "t_ns", "n_points", "n_dropped", "frame", "source_ordinal"])
        _check_range_units(recording, median)
        if index["source_ordinal"].isna().any():  # a reader that does not number its frames: all null
            index["source_ordinal"] = None
        else:
            index["source_ordinal"] = index["source_ordinal"].astype(np.int64)
        # after the scans: a lazy reader adds what it skipped to ``detected`` as it reads
        table_meta = {**{k: str(v) for k, v in recording.detected.items()}, **(metadata or {})}
        stream = recording.pose_stream
        if stream is None or stream.empty:
            if recording.detected.get("pose_kind") != "none":
                what = recording.detected.get("pose_source", "the pose source")
                raise InputError(f"{recording.source}: no poses found for the pose source ({what})")
            stream = pose_stream_frame([], [], [], [], [])  # no map pose: LIDAR odometry
        stream = stream.copy()
        stream["z"] = stream["z"].astype(np.float64) + float(sensor_height_m)
        write_table(index, index_path, schema=SCAN_INDEX, metadata=table_meta)
        write_table(stream, pose_stream_path, schema=POSE_STREAM, metadata=table_meta)
    return index


def _check_range_units(recording: Recording, median: MedianReturn) -> None:
    """Refuse scans whose ranges are not metres (:func:`floorscan.ingest.units.range_units_problem`),
    naming the recording and its scans (a bag's topic, a CARMEN log's lines, a PCD
    folder's files)."""
    problem = range_units_problem(median.value, median.n_scans)
    if not problem:
        return
    topic = recording.detected.get("scan_topic", "")
    if recording.detected.get("format") == "pcd" or topic == "pcd files":
        what = "the points of the .pcd files (their distance from the scan locations of the locations CSV)"
    elif recording.detected.get("format") == "carmen":
        what = f"the ranges of the {topic} lines"
    else:
        what = f"the ranges of the scans on {topic!r}" if topic else "the ranges of the scans"
    raise InputError(f"{recording.source}: {what} {problem}")

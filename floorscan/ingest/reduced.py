"""The reduced recording: the user's recording with only the selected scans and the
messages needed to use them, in the recording's own format.

The selected scans are found exactly where ingest read them: by the scan index's
``source_ordinal``, the ordinal of each scan's frame in the recording (a bag's message
on the scan topic, a CARMEN log's laser line, a PCD folder's locations row;
:data:`floorscan.core.io.SCAN_INDEX`), never by a stamp lookup that rounded or spread
stamps would break, nor by ``scan_id``, which skipped frames and re-sorted stamps move.
An index written before that column existed is read as ingest numbered scans then: the
frames in reading order without the ``skipped_frames``
(:func:`floorscan.ingest.reduced_checks.scan_frames`). The count of frames and the
stamps are checked (:mod:`floorscan.ingest.reduced_checks`). What is kept depends on
the format, one module each:

- ROS1 ``.bag`` and ROS2 bag folders: :mod:`floorscan.ingest.reduced_bag` (the
  selected scan messages, static and latched topics, pose messages near a selected
  scan);
- CARMEN ``.log`` / ``.log.gz``: :mod:`floorscan.ingest.reduced_carmen` (comments and
  parameters, the selected laser lines, pose lines near a selected scan);
- PCD folders: :mod:`floorscan.ingest.reduced_pcd` (the selected ``.pcd`` files and
  their rows of the locations CSV).

Outputs are written under a temporary name beside the target and renamed
(:func:`floorscan.core.files.atomic_path`, :func:`floorscan.core.files.staged_path`).

Usage (the workflow's rule ``selection``, for the select stage's scans:
:func:`write_selected_recording`)::

    detection = read_detection("results/trace0/scan_index.parquet")
    info = write_reduced_recording(dataset_path, detection["format"], table["scan_id"],
                                   "results/trace0/selection/recording/trace0.bag", detection)

To add a format: a module ``reduced_<format>.py`` with a function
``reduce_<format>(source, ids, out_path, detection, t_ns, window_s)`` returning the
dict of :func:`write_reduced_recording`, and its entry in :data:`REDUCERS`.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np

from floorscan.core.io import InputError, read_metadata
from floorscan.ingest.reduced_bag import reduce_bag
from floorscan.ingest.reduced_carmen import reduce_carmen
from floorscan.ingest.reduced_pcd import reduce_pcd

log = logging.getLogger(__name__)

#: ``fmt`` values read as a bag (``synthetic``: the simulator's ROS1 bag).
BAG_FORMATS = ("rosbag", "synthetic")
#: The writer of each format (ingest's ``format``):
#: ``reduce(source, ids, out_path, detection, t_ns, window_s) -> dict``.
REDUCERS = {**dict.fromkeys(BAG_FORMATS, reduce_bag), "carmen": reduce_carmen, "pcd": reduce_pcd}


def read_detection(index_path: str | os.PathLike, dataset: Mapping[str, Any] | None = None) -> dict:
    """The ``detection`` of :func:`write_reduced_recording` from ``scan_index.parquet``.

    Parameters
    ----------
    index_path : path
        The ingest stage's ``scan_index.parquet``: its ``t_ns`` and ``source_ordinal``
        columns and the schema metadata ingest stored (``format``, ``scan_topic``,
        ``stamps``, a CARMEN log's ``max_range_m``, ``n_frames_read``,
        ``skipped_frames``; :attr:`floorscan.ingest.recording.Recording.detected`).
    dataset : mapping, optional
        The dataset's config entry; its ``locations`` (PCD folders) is passed on.

    Returns
    -------
    dict
        ``format``, ``scan_topic``, ``stamps``, ``n_frames_read``, ``skipped_frames``
        (str, when stored), ``max_range_m`` (str, CARMEN), ``locations`` (str, PCD, when
        the dataset names it), ``t_ns`` ((N,) int64 ndarray, the stamp of scan ``i`` at
        ``i``) and ``source_ordinal`` ((N,) int64 ndarray, the frame of scan ``i`` at
        ``i``; only when the index has the column, without nulls).

    Raises
    ------
    InputError
        The index's ``scan_id`` is not ``0..N-1`` in order (not an ingest output), or
        its ``source_ordinal`` repeats a frame or is negative.
    """
    import pyarrow.parquet as pq

    meta = read_metadata(index_path)
    has_ordinal = "source_ordinal" in pq.read_schema(index_path).names
    table = pq.read_table(index_path, columns=["scan_id", "t_ns"] + (["source_ordinal"] if has_ordinal else []))
    ids = table.column("scan_id").to_numpy()
    if not np.array_equal(ids, np.arange(len(ids))):
        raise InputError(f"{index_path}: scan_id is not 0..{len(ids) - 1} in order; expected ingest's scan index")
    keys = ("format", "scan_topic", "stamps", "max_range_m", "n_frames_read", "skipped_frames")
    det = {k: meta[k] for k in keys if k in meta}
    if dataset is not None and dataset.get("locations"):
        det["locations"] = str(dataset["locations"])
    det["t_ns"] = table.column("t_ns").to_numpy().astype(np.int64)
    ordinal = table.column("source_ordinal") if has_ordinal else None
    if ordinal is not None and ordinal.null_count == 0:  # else written before ingest numbered frames
        ordinal = ordinal.to_numpy().astype(np.int64)
        if len(ordinal) and (ordinal.min() < 0 or np.unique(ordinal).size != len(ordinal)):
            raise InputError(
                f"{index_path}: source_ordinal repeats a frame or is negative; expected each scan's own frame "
                "in the recording (ingest's scan index)"
            )
        det["source_ordinal"] = ordinal
    return det


def write_reduced_recording(
    source: str | os.PathLike,
    fmt: str | None,
    scan_ids: Iterable[int],
    out_path: str | os.PathLike,
    detection: Mapping[str, Any],
    window_s: float = 0.5,
) -> dict:
    """Write the recording ``source`` reduced to the scans ``scan_ids`` (see the module
    docstring for what each format keeps).

    Parameters
    ----------
    source : path
        The recording ingest read: a ROS1 ``.bag``, a ROS2 bag folder or its ``.db3`` /
        ``.mcap`` file, a CARMEN ``.log`` / ``.log.gz``, a PCD folder.
    fmt : str or None
        ``rosbag`` (or ``synthetic``), ``carmen`` or ``pcd`` (ingest's ``format``);
        None: detected from ``source`` (:func:`floorscan.ingest.detect.detect_format`).
    scan_ids : iterable of int
        The selected scans, ingest's ``scan_id`` (duplicates ignored).
    out_path : path
        Output: a ``.bag`` file (ROS1), a bag folder (ROS2), a ``.log`` / ``.log.gz``
        file (CARMEN, gzip when the input is), a folder (PCD). Replaced when it exists.
    detection : mapping
        What ingest found (:func:`read_detection` builds it from ``scan_index.parquet``):

        - ``scan_topic`` (str, bags: required): the topic ingest read the scans from;
        - ``t_ns`` ((N,) int array_like, recommended): ``scan_index``'s stamps in
          ``scan_id`` order. The recording must still hold the frames ingest read
          (``n_frames_read``, else N and the ``skipped_frames``), and each selected
          scan's stamp must be ``t_ns[scan_id]`` (bags: the header stamp, or the log
          time when it is 0; CARMEN with recorded or spread stamps; PCD with a ``t_ns``
          column); without it only the range of the ids is checked;
        - ``source_ordinal`` ((N,) int array_like, recommended): ``scan_index``'s
          column, the frame of each scan in the recording (a bag's message on the scan
          topic, a CARMEN log's laser line in file order, the locations CSV's row).
          Without it the scans are the frames in ingest's reading order without the
          ``skipped_frames`` (str ``"0,5-6"`` as ingest stores it, or ordinals; none when
          absent); a bag whose stamps ingest sorted then fails the stamp check;
        - ``n_frames_read`` (str or int, optional): the frames ingest read;
        - ``stamps`` (str, CARMEN, optional): ingest's stamp class; the log must still
          have it (the scan numbering depends on it);
        - ``locations`` (str, PCD, optional): the locations CSV in the folder
          (default ``locations.csv``).
    window_s : float
        Pose messages within this many seconds of a selected scan are kept, >= 0.

    Returns
    -------
    dict
        ``format`` (``rosbag1``, ``rosbag2``, ``carmen``, ``pcd``), ``path`` (str, the
        output), ``bytes_in`` / ``bytes_out`` (int, a folder's: the sum of its files),
        ``messages_in`` / ``messages_out`` (int: bag messages, CARMEN non-blank lines,
        PCD scans), ``scan_messages_out`` (int, = the number of selected scans),
        ``topics`` (dict topic -> messages written; CARMEN: line type, ``#`` for
        comments; PCD: ``pcd files``).

    Raises
    ------
    InputError (a ValueError)
        An unknown format; no scan selected; a selected scan_id that is not in the
        recording, a scan count or a selected scan's stamp that differs from
        ``detection`` (the recording changed since ingest: the message names the file
        and what was expected); a bag without the scan topic; a malformed CARMEN laser
        line; a PCD folder without its locations CSV or with a file outside it.
    """
    source = Path(source)
    if not source.exists():
        raise InputError(f"{source}: recording not found")
    if window_s < 0 or not np.isfinite(window_s):
        raise InputError(f"window_s {window_s!r}: expected a finite number of seconds >= 0")
    if fmt is None:
        from floorscan.ingest.detect import detect_format

        fmt = detect_format(source)
    ids = np.unique(np.asarray([int(s) for s in scan_ids], dtype=np.int64))
    if ids.size == 0:
        raise InputError(f"{source}: no scans selected; expected at least one scan_id")
    if ids[0] < 0:
        raise InputError(f"{source}: scan_id {int(ids[0])} is negative; expected ingest's ids 0..N-1")
    t_ns = detection.get("t_ns")
    t_ns = None if t_ns is None else np.asarray(t_ns, dtype=np.int64)
    if t_ns is not None and ids[-1] >= len(t_ns):
        raise InputError(
            f"{source}: selected scan_id {int(ids[-1])} is not in the recording's scan index "
            f"(0..{len(t_ns) - 1}); expected ids of this recording's ingest"
        )
    ordinals = detection.get("source_ordinal")
    if ordinals is not None and t_ns is not None and len(ordinals) != len(t_ns):
        raise InputError(
            f"{source}: detection has {len(ordinals)} source_ordinal for {len(t_ns)} stamps; expected one of each "
            "per scan of the scan index"
        )
    reduce = REDUCERS.get(fmt)
    if reduce is None:
        names = list(REDUCERS)
        raise InputError(f"{source}: unsupported format {fmt!r}; expected {', '.join(names[:-1])} or {names[-1]}")
    return reduce(source, ids, Path(out_path), detection, t_ns, window_s)


def write_selected_recording(
    recording_path: str | os.PathLike,
    index_path: str | os.PathLike,
    dataset: Mapping[str, Any],
    scan_ids: Iterable[int],
    folder: str | os.PathLike,
) -> dict:
    """The recording cut to the selected scans (rule ``selection``): what ingest found
    (:func:`read_detection`) and :func:`write_reduced_recording` into ``folder``, under
    the recording's own name (a ROS2 bag given by its ``.db3`` / ``.mcap`` file: its
    folder's).

    Parameters
    ----------
    recording_path : path
        The recording ingest read.
    index_path : path
        Its ``scan_index.parquet``.
    dataset : mapping
        The dataset as ingest read it (``format``, ``locations``).
    scan_ids : iterable of int
        The selected scans, ingest's ``scan_id``.
    folder : path
        Output folder (``selection/recording/``).

    Returns
    -------
    dict
        As :func:`write_reduced_recording`.

    Raises
    ------
    InputError
        As :func:`read_detection` and :func:`write_reduced_recording`.
    """
    from floorscan.ingest.detect import bag_path

    detection = read_detection(index_path, dataset)  # checks scan_id is 0..N-1: t_ns[i] is scan i's
    out = Path(folder) / bag_path(recording_path).name
    rec = write_reduced_recording(recording_path, detection.get("format") or dataset.get("format"), scan_ids, out,
                                  detection)
    log.info("reduced recording %s: %d of %d messages, %d bytes of %d (%.1f %%)", out, rec["messages_out"],
             rec["messages_in"], rec["bytes_out"], rec["bytes_in"], 100.0 * rec["bytes_out"] / max(rec["bytes_in"], 1))
    return rec

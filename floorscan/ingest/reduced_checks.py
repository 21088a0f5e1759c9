"""Checks shared by the reduced-recording writers (:mod:`floorscan.ingest.reduced`):
where each selected scan is in the recording, that it still holds the frames ingest
read, with the stamps it recorded; the size of what was read and written.

A scan is found by its frame's ordinal in the recording (:func:`scan_frames`): the scan
index's ``source_ordinal`` (:data:`floorscan.core.io.SCAN_INDEX`), not its ``scan_id``:
ingest skips bad frames and sorts stamps a little out of order.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import numpy as np

from floorscan.core.io import InputError
from floorscan.core.messages import quoted


def size_of(path: Path) -> int:
    """Bytes of a file, or of every file under a folder.

    Parameters
    ----------
    path : Path

    Returns
    -------
    int
    """
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return path.stat().st_size


def skipped_frames(source: Path, detection: Mapping[str, Any]) -> np.ndarray:
    """The frames ingest skipped, ``detection["skipped_frames"]`` (text as ingest stores
    it, ``"0,5-6"``, or ordinals).

    Parameters
    ----------
    source : Path
        The recording, for messages.
    detection : mapping

    Returns
    -------
    (K,) int64 ndarray
        Sorted, unique; empty when none.

    Raises
    ------
    InputError
        The text is not ranges of ordinals.
    """
    from floorscan.ingest.points import parse_ordinal_ranges

    value = detection.get("skipped_frames")
    if value is None:
        return np.zeros(0, dtype=np.int64)
    if isinstance(value, str):
        try:
            value = parse_ordinal_ranges(value)
        except ValueError as e:
            raise InputError(f"{source}: scan index metadata skipped_frames: {e}; expected ingest's ranges") from None
    return np.unique(np.asarray(value, dtype=np.int64))


def scan_frames(
    source: Path, ids: np.ndarray, detection: Mapping[str, Any], order: np.ndarray | None = None
) -> np.ndarray:
    """The frame (0-based ordinal in the recording) of each selected scan, as ingest read it.

    ``detection["source_ordinal"]`` (the scan index's column: the frame of scan ``i`` at
    ``i``) when given; else, for an index written before that column existed, the
    frames ingest read into scans in ``order``, without the ones it skipped
    (``detection["skipped_frames"]``): scan ``i`` is the ``i``-th of them.

    Parameters
    ----------
    source : path
        The recording, for messages.
    ids : (S,) int64 ndarray
        The selected scan_ids, sorted, unique, >= 0.
    detection : mapping
        See :func:`floorscan.ingest.reduced.write_reduced_recording`.
    order : (n,) int ndarray, optional
        Without ``source_ordinal``: the recording's n frames in the order ingest turns
        them into scans (a CARMEN log's laser lines sorted by stamp); default file order.

    Returns
    -------
    frames : (S,) int64 ndarray
        The frame of ``ids[j]`` at ``j``; a scan beyond the frames of ``order`` gets an
        ordinal beyond them too (:func:`check_count` refuses it).

    Raises
    ------
    InputError
        A selected scan_id beyond the scan index's ``source_ordinal``.
    """
    ordinals = detection.get("source_ordinal")
    if ordinals is not None:
        ordinals = np.asarray(ordinals, dtype=np.int64)
        if ids[-1] >= len(ordinals):
            raise InputError(
                f"{source}: selected scan_id {int(ids[-1])} is not in the recording's scan index "
                f"(0..{len(ordinals) - 1}); expected ids of this recording's ingest"
            )
        return ordinals[ids]
    skipped = skipped_frames(source, detection)
    if order is None:  # enough frames for the largest id
        order = np.arange(int(ids[-1]) + 1 + skipped.size, dtype=np.int64)
    order = np.asarray(order, dtype=np.int64)
    read = order[~np.isin(order, skipped)]
    if ids[-1] >= len(read):  # beyond the recording: ordinals it does not hold
        read = np.r_[read, len(order) + np.arange(int(ids[-1]) + 1 - len(read), dtype=np.int64)]
    return read[ids]


def check_count(
    source: Path,
    n: int,
    ids: np.ndarray,
    t_ns: np.ndarray | None,
    what: str,
    frames: np.ndarray | None = None,
    detection: Mapping[str, Any] | None = None,
) -> None:
    """Check that the recording still holds the frames ingest read and the selected scans.

    Parameters
    ----------
    n : int
        Frames the recording holds (``what``: messages on the scan topic, laser lines,
        scan locations).
    ids : (S,) int64 ndarray
        The selected scan_ids, sorted.
    t_ns : (N,) int64 ndarray or None
        The scan index's stamps.
    frames : (S,) int64 ndarray, optional
        The selected scans' frames (:func:`scan_frames`); default ``ids``.
    detection : mapping, optional
        ``n_frames_read`` (the frames ingest read) and ``skipped_frames``.

    Raises
    ------
    InputError
        When the recording holds another number of frames than ingest read
        (``n_frames_read``, else the scan index's scans (``t_ns``) and the frames it
        skipped), or a selected scan's frame is not among its ``n``.
    """
    detection = detection or {}
    frames = ids if frames is None else np.asarray(frames, dtype=np.int64)
    n_skipped = skipped_frames(source, detection).size
    n_read = detection.get("n_frames_read")
    if n_read is not None:
        try:
            n_read = int(n_read)
        except (TypeError, ValueError):
            raise InputError(
                f"{source}: scan index metadata n_frames_read is {quoted(n_read, 40)}; expected a count of frames"
            ) from None
    elif t_ns is not None:
        n_read = len(t_ns) + n_skipped
    if n_read is not None and n != n_read:
        if t_ns is not None and n_read == len(t_ns):  # nothing skipped
            read = f"the scan index {len(t_ns)}"
        else:
            read = f"ingest read {n_read}" + (
                "" if t_ns is None else f" (the scan index's {len(t_ns)} scans and {n_skipped} skipped)"
            )
        raise InputError(
            f"{source}: holds {n} {what}, {read}; expected the recording ingest read "
            "(it changed since ingest: rerun ingest)"
        )
    j = int(np.argmax(frames))
    if frames[j] >= n:
        i, f = int(ids[j]), int(frames[j])
        where = f"ids 0..{n - 1}" if i == f else f"scan {i} is frame {f}"
        raise InputError(
            f"{source}: selected scan_id {i} is not in the recording ({n} {what}, {where}); "
            "expected ids of this recording's ingest"
        )


def check_stamps(source: Path, ids: np.ndarray, got: np.ndarray, t_ns: np.ndarray | None) -> None:
    """Check that the selected scans' stamps ``got`` (in the order of ``ids``) are the
    scan index's ``t_ns[ids]``.

    Parameters
    ----------
    source : Path
        The recording, for messages.
    ids : (S,) int ndarray
        The selected scan ids.
    got : (S,) int64 ndarray
        Their stamps in the recording, nanoseconds.
    t_ns : (N,) int64 ndarray or None
        The scan index's stamps in ``scan_id`` order, nanoseconds; None: nothing checked.

    Raises
    ------
    InputError
        Naming the first scan whose stamp differs (the recording changed since ingest).
    """
    if t_ns is None:
        return
    bad = np.flatnonzero(got != t_ns[ids])
    if bad.size:
        i = int(ids[bad[0]])
        raise InputError(
            f"{source}: scan {i} is stamped {int(got[bad[0]])} ns, the scan index says {int(t_ns[i])} ns "
            f"({bad.size} of {len(ids)} selected scans differ); expected the recording ingest read "
            "(it changed since ingest: rerun ingest)"
        )

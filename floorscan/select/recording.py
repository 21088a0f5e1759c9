"""The reduced recording: the user's recording with only the selected scans and the
messages needed to use them (issue 23), in the recording's own format.

The selected scans are found exactly as ingest numbered them (``scan_id`` = the
position of the scan in ingest's reading order, :mod:`floorscan.ingest`), never by a
stamp lookup that rounded or spread stamps would break; the stamps are only checked.
What is kept, per format:

- ROS1 ``.bag`` -> ROS1 ``.bag`` (``rosbags.rosbag1.Writer``, the input's chunk
  compression); ROS2 bag folder (or its ``.db3`` / ``.mcap`` file) -> ROS2 bag folder
  (``rosbags.rosbag2.Writer``, the input's storage plugin). The synthetic datasets'
  recording (``results/<dataset>/sim/recording.bag``) is a ROS1 bag. Kept: the selected
  messages of the scan topic (the ``n``-th message of the topic in the order rosbags'
  ``AnyReader`` yields them, as ingest reads it, is scan ``n``); every message of
  ``/tf_static`` and of latched topics (ROS1 ``latching=1``, ROS2 durability
  ``transient_local``); the messages of pose topics (types :data:`POSE_MSGTYPES`:
  ``/tf``, ``/amcl_pose``, ``/odom``, ...) whose log time lies within ``window_s`` of a
  selected scan's log time. Other topics are dropped. The serialized bytes are copied
  (no deserialize/serialize round trip) with each connection's metadata (type,
  message definition and hash, caller id and latching, serialization format and QoS);
  a ROS2 bag that stores no message definitions gets those of the ROS2 Humble
  typestore, as floorscan reads it.
- CARMEN ``.log`` / ``.log.gz`` -> the same compression (gzip with mtime 0, so the
  same selection gives the same bytes). Kept: comment (``#``) and ``PARAM`` lines; the
  selected laser lines (``FLASER`` / ``ROBOTLASER1``, numbered as
  :mod:`floorscan.ingest.carmen` numbers them: file order, stable-sorted by stamp
  when some lines step back in time, unless the stamps are made up); pose lines
  (:data:`CARMEN_POSE_LINES`) whose ``ipc_timestamp`` lies within ``window_s`` of a
  selected scan's, or, when their stamp is unusable (0, or the log's stamps are made
  up), that sit next to a selected laser line (no other laser line between them).
  Other lines (other laser types, ``NEFF``, ``SYNC``, ...) are dropped. Re-ingesting
  the reduced log gives the same points when ``ingest.carmen_max_range_m`` is set to
  the original's detected ``max_range_m`` (the no-return range is detected from the
  log's readings, and fewer readings may detect another).
- PCD folder (``*.pcd`` + locations CSV) -> a folder with the selected ``.pcd`` files
  copied and the CSV reduced to their rows (field text as it was).

Outputs are written under a temporary name beside the target and renamed
(:func:`floorscan.core.files.atomic_path`, :func:`floorscan.core.files.staged_path`).

Usage (the workflow)::

    detection = read_detection("results/trace0/scan_index.parquet")
    info = write_reduced_recording(dataset_path, detection["format"], table["scan_id"],
                                   "results/trace0/deliverables/recording.bag", detection)

To add a format: a ``_reduce_<format>`` function returning the same dict, and a branch
in :func:`write_reduced_recording`.
"""

from __future__ import annotations

import gzip
import hashlib
import io
import logging
import os
import shutil
from collections import Counter
from pathlib import Path
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd

from floorscan.core.io import InputError, read_metadata
from floorscan.core.files import atomic_path, staged_path

log = logging.getLogger(__name__)

#: Message types of the pose topics kept within the window of a selected scan
#: (rosbags' names; ``tf/msg/tfMessage`` is the old ROS1 TF type).
POSE_MSGTYPES = (
    "tf2_msgs/msg/TFMessage",
    "tf/msg/tfMessage",
    "geometry_msgs/msg/PoseWithCovarianceStamped",
    "geometry_msgs/msg/PoseStamped",
    "geometry_msgs/msg/TransformStamped",
    "nav_msgs/msg/Odometry",
)
#: Topics kept whole whatever their QoS or latching.
STATIC_TOPICS = ("/tf_static",)
#: CARMEN pose lines kept within the window. Their ``ipc_timestamp`` is the third field
#: from the end (``ODOM x y theta tv rv accel ipc_timestamp host logger_timestamp``), as
#: in every CARMEN message, the laser lines too (:data:`floorscan.ingest.carmen_lines.LAYOUTS`).
CARMEN_POSE_LINES = ("ODOM", "TRUEPOS")
#: CARMEN lines always kept (besides ``#`` comments).
CARMEN_KEPT_LINES = ("PARAM",)
#: ``fmt`` values read as a bag (``synthetic``: the simulator's ROS1 bag).
BAG_FORMATS = ("rosbag", "synthetic")


def read_detection(index_path: str | os.PathLike, dataset: Mapping[str, Any] | None = None) -> dict:
    """The ``detection`` of :func:`write_reduced_recording` from ``scan_index.parquet``.

    Parameters
    ----------
    index_path : path
        The ingest stage's ``scan_index.parquet``: its ``t_ns`` column and the schema
        metadata ingest stored (``format``, ``scan_topic``, ``stamps``, a CARMEN log's
        ``max_range_m``; :attr:`floorscan.ingest.recording.Recording.detected`).
    dataset : mapping, optional
        The dataset's config entry; its ``locations`` (PCD folders) is passed on.

    Returns
    -------
    dict
        ``format``, ``scan_topic``, ``stamps`` (str, when stored), ``max_range_m``
        (str, CARMEN), ``locations`` (str, PCD, when the dataset names it) and ``t_ns``
        ((N,) int64 ndarray, the stamp of scan ``i`` at ``i``).

    Raises
    ------
    InputError
        The index's ``scan_id`` is not ``0..N-1`` in order (not an ingest output).
    """
    import pyarrow.parquet as pq

    meta = read_metadata(index_path)
    table = pq.read_table(index_path, columns=["scan_id", "t_ns"])
    ids = table.column("scan_id").to_numpy()
    if not np.array_equal(ids, np.arange(len(ids))):
        raise InputError(f"{index_path}: scan_id is not 0..{len(ids) - 1} in order; expected ingest's scan index")
    det = {k: meta[k] for k in ("format", "scan_topic", "stamps", "max_range_m") if k in meta}
    if dataset is not None and dataset.get("locations"):
        det["locations"] = str(dataset["locations"])
    det["t_ns"] = table.column("t_ns").to_numpy().astype(np.int64)
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
          ``scan_id`` order. The recording must still hold N scans, and each selected
          scan's stamp must be ``t_ns[scan_id]`` (bags: the header stamp, or the log
          time when it is 0; CARMEN with recorded or spread stamps; PCD with a ``t_ns``
          column); without it only the range of the ids is checked;
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
    if fmt in BAG_FORMATS:
        return _reduce_bag(source, ids, Path(out_path), detection, t_ns, window_s)
    if fmt == "carmen":
        return _reduce_carmen(source, ids, Path(out_path), detection, t_ns, window_s)
    if fmt == "pcd":
        return _reduce_pcd(source, ids, Path(out_path), detection, t_ns)
    raise InputError(f"{source}: unsupported format {fmt!r}; expected rosbag, synthetic, carmen or pcd")


def _size(path: Path) -> int:
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file())
    return path.stat().st_size


def _check_count(source: Path, n: int, ids: np.ndarray, t_ns: np.ndarray | None, what: str) -> None:
    if t_ns is not None and n != len(t_ns):
        raise InputError(
            f"{source}: holds {n} {what}, the scan index {len(t_ns)}; expected the recording ingest read "
            "(it changed since ingest: rerun ingest)"
        )
    if ids[-1] >= n:
        raise InputError(
            f"{source}: selected scan_id {int(ids[-1])} is not in the recording ({n} {what}, ids 0..{n - 1}); "
            "expected ids of this recording's ingest"
        )


def _check_stamps(source: Path, ids: np.ndarray, got: np.ndarray, t_ns: np.ndarray | None) -> None:
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


# ----------------------------------------------------------------------------------
# ROS1 and ROS2 bags
# ----------------------------------------------------------------------------------
def _digest(raw) -> bytes:
    return hashlib.blake2b(raw, digest_size=16).digest()


def _latched(c) -> bool:
    ext = c.ext
    if hasattr(ext, "latching"):
        try:
            return bool(int(ext.latching or 0))
        except (TypeError, ValueError):
            return False
    from rosbags.interfaces import QosDurability

    return any(q.durability == QosDurability.TRANSIENT_LOCAL for q in ext.offered_qos_profiles)


def _stamp_ns(msg, bag_t: int) -> int:
    """The scan's stamp as ingest takes it: the header stamp, the log time when 0."""
    t = int(msg.header.stamp.sec) * 1_000_000_000 + int(msg.header.stamp.nanosec)
    return t if t > 0 else int(bag_t)


def _ros1_compression(reader):
    """The chunk compression of a ROS1 bag (``Writer.CompressionFormat``), or None."""
    try:
        from rosbags.rosbag1 import Writer
        from rosbags.rosbag1.reader import decompressors

        names = {v: k for k, v in decompressors.items()}
        found = {names.get(ch.decompressor) for r in reader.readers for ch in r.chunks.values()}
    except (ImportError, AttributeError):
        return None
    for name in ("lz4", "bz2"):
        if name in found:
            return Writer.CompressionFormat[name.upper()]
    return None


def _reduce_bag(source: Path, ids, out_path: Path, detection, t_ns, window_s: float) -> dict:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    from floorscan.ingest.detect import bag_path

    path = bag_path(source)
    ros2 = path.is_dir()
    topic = detection.get("scan_topic")
    if not topic:
        raise InputError(f"{path}: detection has no scan_topic; expected the topic ingest read the scans from")
    typestore = get_typestore(Stores.ROS2_HUMBLE)  # as ingest reads bags (floorscan.ingest.rosbag)
    selected = set(ids.tolist())
    try:
        with AnyReader([path], default_typestore=typestore) as reader:
            scan_conns = [c for c in reader.connections if c.topic == topic]
            if not scan_conns:
                listing = ", ".join(sorted({f"{c.topic} ({c.msgtype})" for c in reader.connections}))
                raise InputError(f"{path}: no topic {topic!r} (the scan topic ingest read); topics in the bag: {listing}")
            # pass 1: ingest's numbering of the scans (floorscan.ingest.rosbag.open_bag)
            want: Counter = Counter()
            times, stamps = [], []
            n = 0
            for i, (c, t, raw) in enumerate(reader.messages(connections=scan_conns)):
                n += 1
                if i in selected:
                    want[(c.id, t, _digest(raw))] += 1
                    times.append(t)
                    if t_ns is not None:
                        stamps.append(_stamp_ns(reader.deserialize(raw, c.msgtype), t))
            _check_count(path, n, ids, t_ns, f"messages on {topic}")
            if t_ns is not None:
                _check_stamps(path, ids, np.asarray(stamps, dtype=np.int64), t_ns)
            times = np.sort(np.asarray(times, dtype=np.int64))
            kind = {}
            for c in reader.connections:
                if c.topic == topic:
                    kind[c.id] = "scan"
                elif c.topic in STATIC_TOPICS or _latched(c):
                    kind[c.id] = "static"
                elif c.msgtype in POSE_MSGTYPES:
                    kind[c.id] = "pose"
            kept = [c for c in reader.connections if c.id in kind]
            messages_in = sum(int(c.msgcount) for c in reader.connections)
            pairs = {(cid, t) for cid, t, _ in want}
            window_ns = int(round(window_s * 1e9))
            counts: Counter = Counter()
            n_scans = 0
            with staged_path(out_path) as tmp:
                writer = _bag_writer(tmp, path, reader, ros2)
                with writer:
                    out_conns: list = []  # (key, output connection)
                    by_id: dict = {}
                    for c, t, raw in reader.messages(connections=kept):
                        k = kind[c.id]
                        if k == "scan":
                            if (c.id, t) not in pairs:
                                continue
                            key = (c.id, t, _digest(raw))
                            if want[key] <= 0:
                                continue
                            want[key] -= 1
                            n_scans += 1
                        elif k == "pose" and not _near(times, t, window_ns):
                            continue
                        wc = by_id.get(c.id)
                        if wc is None:
                            wc = by_id[c.id] = _out_connection(writer, c, out_conns, ros2)
                        writer.write(wc, t, raw)
                        counts[c.topic] += 1
                if n_scans != len(ids):
                    raise InputError(
                        f"{path}: found {n_scans} of the {len(ids)} selected scans on the second read; "
                        "expected the same messages (is the bag being written?)"
                    )
    except InputError:
        raise
    except Exception as e:  # rosbags raises several reader/writer errors
        raise InputError(f"{path}: cannot reduce the bag ({type(e).__name__}: {e})") from e
    return {
        "format": "rosbag2" if ros2 else "rosbag1",
        "path": str(out_path),
        "bytes_in": _size(path),
        "bytes_out": _size(out_path),
        "messages_in": messages_in,
        "messages_out": int(sum(counts.values())),
        "scan_messages_out": n_scans,
        "topics": dict(sorted(counts.items())),
    }


def _near(times: np.ndarray, t: int, window_ns: int) -> bool:
    """Whether ``t`` lies within ``window_ns`` of one of the sorted ``times``."""
    j = int(np.searchsorted(times, t))
    if j < len(times) and times[j] - t <= window_ns:
        return True
    return j > 0 and t - times[j - 1] <= window_ns


def _bag_writer(tmp: Path, path: Path, reader, ros2: bool):
    if ros2:
        from rosbags.rosbag2 import StoragePlugin, Writer

        mcap = any(p.suffix.lower() == ".mcap" for p in path.iterdir())
        return Writer(tmp, version=Writer.VERSION_LATEST, storage_plugin=StoragePlugin.MCAP if mcap else StoragePlugin.SQLITE3)
    from rosbags.rosbag1 import Writer

    writer = Writer(tmp)
    compression = _ros1_compression(reader)
    if compression is not None:
        writer.set_compression(compression)
    return writer


def _out_connection(writer, c, out_conns: list, ros2: bool):
    """The output connection of input connection ``c``: its topic, type, definition,
    hash and extension (ROS1 caller id and latching; ROS2 format and QoS); input
    connections that agree on all of them share one."""
    key = (c.topic, c.msgtype, c.msgdef.data, c.digest, c.ext)
    for k, wc in out_conns:
        if k == key:
            return wc
    has_def = bool(c.msgdef.data) and bool(c.digest)
    if ros2:
        from rosbags.typesys import Stores, get_typestore

        kwargs = (
            {"msgdef": c.msgdef.data, "rihs01": c.digest}
            if has_def
            else {"typestore": get_typestore(Stores.ROS2_HUMBLE)}  # a bag without stored definitions
        )
        wc = writer.add_connection(
            c.topic, c.msgtype, serialization_format=c.ext.serialization_format,
            offered_qos_profiles=c.ext.offered_qos_profiles, **kwargs,
        )
    else:
        from rosbags.typesys import Stores, get_typestore

        kwargs = (
            {"msgdef": c.msgdef.data, "md5sum": c.digest}
            if has_def
            else {"typestore": get_typestore(Stores.ROS1_NOETIC)}
        )
        wc = writer.add_connection(c.topic, c.msgtype, callerid=c.ext.callerid, latching=c.ext.latching, **kwargs)
    out_conns.append((key, wc))
    return wc


# ----------------------------------------------------------------------------------
# CARMEN logs
# ----------------------------------------------------------------------------------
def _read_lines(path: Path) -> tuple[list[str], bool]:
    """The log's lines with their line ends, as latin-1 text (byte for byte), split as
    ingest splits them (universal newlines); and whether it is gzip."""
    with open(path, "rb") as f:
        gz = f.read(2) == b"\x1f\x8b"
    import zlib

    try:
        raw = gzip.open(path, "rb") if gz else open(path, "rb")
        with io.TextIOWrapper(raw, encoding="latin-1", newline="") as f:
            return f.readlines(), gz
    except (EOFError, OSError, zlib.error) as e:
        raise InputError(f"{path}: cannot read the log, truncated or corrupt ({e})") from None


def _reduce_carmen(source: Path, ids, out_path: Path, detection, t_ns, window_s: float) -> dict:
    from floorscan.ingest.carmen_lines import LASER_TYPES
    from floorscan.ingest.carmen_stamps import classify_stamps, spread_stamps

    lines, gz = _read_lines(source)
    tokens = [ln.encode("latin-1").decode("ascii", errors="replace").split() for ln in lines]
    laser_line, t_s = [], []  # laser ordinal -> line index, ipc stamp
    for i, tok in enumerate(tokens):
        if tok and tok[0] in LASER_TYPES:
            # ingest checked each laser line's layout; a log changed since fails the count
            # and stamp checks against the scan index below
            try:
                t_s.append(float(tok[-3]))
            except (ValueError, IndexError) as e:
                raise InputError(f"{source}:{i + 1}: malformed {tok[0]} line ({e}); expected ingest's field layout") from None
            laser_line.append(i)
    n = len(laser_line)
    _check_count(source, n, ids, t_ns, "laser lines")
    t = np.asarray(t_s, dtype=np.float64)
    try:
        stamps, _ = classify_stamps(t)
    except ValueError:
        raise InputError(f"{source}: laser lines with timestamp 0 among stamped ones; expected the log ingest read") from None
    if detection.get("stamps") not in (None, stamps):
        raise InputError(
            f"{source}: its laser stamps are now {stamps!r}, ingest found {detection['stamps']!r}; "
            "expected the log ingest read (it changed since ingest: rerun ingest)"
        )
    # ingest's numbering (floorscan.ingest.carmen.open_carmen)
    order = np.arange(n)
    if stamps != "made_up":
        stamp_ns = np.round(t * 1e9).astype(np.int64)
        if np.any(np.diff(stamp_ns) < 0):
            order = np.argsort(stamp_ns, kind="stable")
        stamp_ns = stamp_ns[order]
        if stamps == "spread":
            stamp_ns = spread_stamps(stamp_ns)
        _check_stamps(source, ids, stamp_ns[ids], t_ns)
    chosen = np.zeros(n, dtype=bool)
    chosen[order[ids]] = True
    sel_t = np.sort(t[chosen])
    # laser ordinal of the last laser line at or before each line (-1: none yet)
    is_laser = np.zeros(len(lines), dtype=bool)
    is_laser[laser_line] = True
    before = np.cumsum(is_laser) - 1
    usable = stamps != "made_up"
    keep, counts, n_in = [], Counter(), 0
    for i, tok in enumerate(tokens):
        if not tok:
            continue
        n_in += 1
        head = tok[0]
        if head.startswith("#") or head in CARMEN_KEPT_LINES:
            ok = True
        elif is_laser[i]:
            ok = bool(chosen[before[i]])
        elif head in CARMEN_POSE_LINES:
            try:
                ts = float(tok[-3])
            except (ValueError, IndexError):
                ts = 0.0
            if usable and np.isfinite(ts) and ts > 0:
                j = int(np.searchsorted(sel_t, ts))
                ok = (j < len(sel_t) and sel_t[j] - ts <= window_s) or (j > 0 and ts - sel_t[j - 1] <= window_s)
            else:  # no usable stamp: the pose lines between a selected laser line and its neighbours
                b = int(before[i])
                ok = (b >= 0 and chosen[b]) or (b + 1 < n and chosen[b + 1])
        else:
            ok = False
        if ok:
            keep.append(lines[i])
            counts["#" if head.startswith("#") else head] += 1
    data = "".join(keep).encode("latin-1")
    with atomic_path(out_path) as tmp:
        if gz:
            with open(tmp, "wb") as f, gzip.GzipFile(filename="", mode="wb", fileobj=f, mtime=0) as g:
                g.write(data)
        else:
            tmp.write_bytes(data)
    return {
        "format": "carmen",
        "path": str(out_path),
        "bytes_in": _size(source),
        "bytes_out": _size(out_path),
        "messages_in": n_in,
        "messages_out": len(keep),
        "scan_messages_out": int(sum(counts[k] for k in LASER_TYPES)),
        "topics": dict(sorted(counts.items())),
    }


# ----------------------------------------------------------------------------------
# PCD folders
# ----------------------------------------------------------------------------------
def _reduce_pcd(source: Path, ids, out_path: Path, detection, t_ns) -> dict:
    if not source.is_dir():
        raise InputError(f"{source}: expected a folder of .pcd files")
    name = str(detection.get("locations") or "locations.csv")
    csv = source / name
    if not csv.is_file():
        raise InputError(f"{csv}: scan locations CSV not found (dataset option 'locations')")
    try:  # the same parser as ingest (floorscan.ingest.pcd.read_locations), the fields as text
        loc = pd.read_csv(csv, dtype=str, keep_default_na=False)
    except Exception as e:
        raise InputError(f"{csv}: cannot read the CSV ({e})") from None
    if "file" not in loc.columns:
        raise InputError(f"{csv}: no 'file' column; expected file,t_ns,x,y,z,yaw")
    _check_count(csv, len(loc), ids, t_ns, "scan locations")
    rows = loc.iloc[ids]
    if "t_ns" in loc.columns:
        got = pd.to_numeric(rows["t_ns"], errors="coerce").to_numpy(dtype=np.float64)
        _check_stamps(csv, ids, np.nan_to_num(got, nan=-1).astype(np.int64), t_ns)
    files = []
    for f in rows["file"]:
        rel = Path(str(f))
        if rel.is_absolute() or ".." in rel.parts:
            raise InputError(f"{csv}: names {f!r}; expected a path inside {source}")
        if not (source / rel).is_file():
            raise InputError(f"{csv}: names {f!r}, which is not in {source}")
        files.append(rel)
    with staged_path(out_path) as tmp:
        tmp.mkdir()
        for rel in files:
            (tmp / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(source / rel, tmp / rel)
        (tmp / name).parent.mkdir(parents=True, exist_ok=True)
        rows.to_csv(tmp / name, index=False, lineterminator="\n")
    return {
        "format": "pcd",
        "path": str(out_path),
        "bytes_in": _size(source),
        "bytes_out": _size(out_path),
        "messages_in": len(loc),
        "messages_out": len(rows),
        "scan_messages_out": len(rows),
        "topics": {"pcd files": len(rows)},
    }

"""The reduced recording of a ROS1 ``.bag`` or a ROS2 bag folder.

ROS1 ``.bag`` -> ROS1 ``.bag`` (``rosbags.rosbag1.Writer``, the input's chunk
compression); ROS2 bag folder (or its ``.db3`` / ``.mcap`` file) -> ROS2 bag folder
(``rosbags.rosbag2.Writer``, the input's storage plugin). The synthetic datasets'
recording (``results/<dataset>/sim/recording.bag``) is a ROS1 bag. Kept:

- the selected messages of the scan topic: scan ``i`` is the message of the topic the
  scan index's ``source_ordinal[i]`` counts, in the order rosbags' ``AnyReader`` yields
  them, as ingest reads it (:func:`floorscan.ingest.reduced_checks.scan_frames`;
  the messages ingest skipped or sorted by stamp are not counted by ``scan_id``);
- every message of ``/tf_static`` (:data:`STATIC_TOPICS`) and of latched topics (ROS1
  ``latching=1``, ROS2 durability ``transient_local``);
- the messages of pose topics (types :data:`POSE_MSGTYPES`: ``/tf``, ``/amcl_pose``,
  ``/odom``, ...) whose log time lies within ``window_s`` of a selected scan's log time.

Other topics are dropped. The serialized bytes are copied (no deserialize/serialize
round trip) with each connection's metadata (type, message definition and hash,
caller id and latching, serialization format and QoS); a ROS2 bag that stores no
message definitions gets those of the ROS2 Humble typestore, as floorscan reads it.
"""

from __future__ import annotations

import hashlib
from collections import Counter
from pathlib import Path

import numpy as np

from floorscan.core.io import InputError
from floorscan.core.files import staged_path
from floorscan.ingest.reduced_checks import check_count, check_stamps, scan_frames, size_of

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


def reduce_bag(source: Path, ids, out_path: Path, detection, t_ns, window_s: float) -> dict:
    """The reduced copy of a ROS1 or ROS2 bag (module docstring).

    Parameters
    ----------
    source : Path
        The recording ingest read.
    ids : (S,) int ndarray
        The selected scans, ingest's ``scan_id``, unique and ascending.
    out_path : Path
        Output, replaced when it exists.
    detection : mapping
        What ingest found (``write_reduced_recording``'s ``detection``).
    t_ns : (N,) int64 ndarray or None
        ``scan_index``'s stamps in ``scan_id`` order, nanoseconds; None skips the stamp
        check.
    window_s : float
        Pose messages within this many seconds of a selected scan are kept.

    Returns
    -------
    dict
        As :func:`floorscan.ingest.reduced.write_reduced_recording`, ``format``
        ``rosbag1`` or ``rosbag2``.

    Raises
    ------
    InputError
        No ``scan_topic`` in ``detection``, or no such topic in the bag; the message
        count or a stamp differs from ingest's; rosbags fails to read or write.
    """
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    from floorscan.ingest.detect import bag_path
    from floorscan.ingest.ros_messages import bag_messages

    path = bag_path(source)
    ros2 = path.is_dir()
    topic = detection.get("scan_topic")
    if not topic:
        raise InputError(f"{path}: detection has no scan_topic; expected the topic ingest read the scans from")
    typestore = get_typestore(Stores.ROS2_HUMBLE)  # as ingest reads bags (floorscan.ingest.rosbag)
    frames = scan_frames(path, ids, detection)
    selected = {int(f): j for j, f in enumerate(frames)}  # message ordinal -> position in ids
    try:
        with AnyReader([path], default_typestore=typestore) as reader:
            scan_conns = [c for c in reader.connections if c.topic == topic]
            if not scan_conns:
                listing = ", ".join(sorted({f"{c.topic} ({c.msgtype})" for c in reader.connections}))
                raise InputError(f"{path}: no topic {topic!r} (the scan topic ingest read); topics in the bag: {listing}")
            # pass 1: the messages ingest numbered (floorscan.ingest.rosbag.open_bag)
            want: Counter = Counter()
            times = []
            stamps = np.zeros(len(ids), dtype=np.int64)  # in the order of ids
            n = 0
            for i, (c, t, raw) in enumerate(bag_messages(reader, scan_conns)):
                n += 1
                j = selected.get(i)
                if j is not None:
                    want[(c.id, t, _digest(raw))] += 1
                    times.append(t)
                    if t_ns is not None:
                        stamps[j] = _stamp_ns(reader.deserialize(raw, c.msgtype), t)
            check_count(path, n, ids, t_ns, f"messages on {topic}", frames, detection)
            if t_ns is not None:
                check_stamps(path, ids, stamps, t_ns)
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
                    for c, t, raw in bag_messages(reader, kept):
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
        "bytes_in": size_of(path),
        "bytes_out": size_of(out_path),
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

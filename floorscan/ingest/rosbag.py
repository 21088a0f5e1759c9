"""ROS1 and ROS2 bag reader (rosbags ``AnyReader``).

Scans come from one topic carrying ``sensor_msgs/LaserScan`` or
``sensor_msgs/PointCloud2``, stamped with their header stamp (the bag's receive time
when the stamp is zero). Poses come from one of (dataset option ``pose.source``):

- ``topic``: ``geometry_msgs/PoseWithCovarianceStamped`` (``/amcl_pose``, the thesis's
  case, section 3.5), ``geometry_msgs/PoseStamped`` or ``nav_msgs/Odometry``: the pose of
  ``pose.base_frame``; a static transform from it to the scan frame found on
  ``/tf_static`` (or a constant one on ``/tf``) is applied;
- ``tf``: the chain of transforms from ``pose.fixed_frame`` to the scan frame on ``/tf``
  and ``/tf_static`` (several publishers), each link interpolated at the union of the
  moving links' stamps, linearly in translation and by slerp in rotation, as tf2 does.

The scan topic and the pose source are detected when the dataset does not name them
(:mod:`floorscan.ingest.rosbag_detect`); the messages are decoded and checked by
:mod:`floorscan.ingest.ros_messages`, the TF chains by :mod:`floorscan.ingest.tf_chains` and
:mod:`floorscan.ingest.tf_poses`.

Scans of the topic in several frames (two scanners, a renamed frame) are each placed by
their own frame's pose when static TF links the frames, else refused naming the frames
(:mod:`floorscan.ingest.scan_frames`).

ROS2 bags that store no message definitions are read with the Humble typestore. A
``.db3`` / ``.mcap`` file is read as its folder's bag.

A scan message with broken geometry, that cannot be decoded or without a valid return
is skipped and counted (:class:`~floorscan.ingest.points.ScanLosses`: ``lost_bad_frames``,
``lost_no_points`` in ``Recording.detected``, the first named in a note and a warning);
more than half of them broken, or none usable, is an ``InputError`` naming the first.
Header stamps a little out of order (a message earlier than the one before it, at most
:data:`MAX_OUT_OF_ORDER_FRACTION` of the messages, each within
:data:`REORDER_WINDOW` messages of its place and at most
:data:`~floorscan.ingest.recording.MAX_STEP_BACK_S` back) are sorted, as a CARMEN log's lines are,
for the scans and for a pose topic, and noted; more is an ``InputError``.
"""

from __future__ import annotations

import dataclasses
import heapq
import logging
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np
from scipy.spatial.transform import Rotation

from floorscan.core.io import InputError
from floorscan.core.messages import MAX_QUOTE
from floorscan.ingest.params import PosesParams
from floorscan.ingest.points import FrameError, ScanLosses, filter_points, no_point_reason, no_return_reason
from floorscan.ingest.recording import MAX_STEP_BACK_S, Recording, Scan, pose_stream_frame
from floorscan.ingest.ros2_metadata import ros2_folder_check
from floorscan.ingest.ros_messages import (
    bag_messages,
    laser_scan_limits,
    laser_scan_problem,
    laser_scan_xyz,
    message_label,
    pointcloud2_xyz,
    pose_problem,
    stamp_ns,
)
from floorscan.ingest.scan_frames import ScanFrames
from floorscan.ingest.rosbag_detect import (
    MAP_FRAME,
    MAP_POSE_TYPES,
    POSE_TYPES,
    SCAN_TYPES,
    detect_pose_source,
    detect_scan_topic,
    short_type,
)
from floorscan.ingest.tf_chains import TfLink, read_tf
from floorscan.ingest.tf_poses import is_upside_down, planar_pose_stream, static_transform, tf_pose_stream, turn_over

log = logging.getLogger(__name__)

#: Scan or pose messages stamped earlier than the message before them are sorted by
#: stamp when they are at most this fraction of the topic's messages (two swapped
#: stamps, a publisher's jitter); more means the stamps are not the acquisition times.
MAX_OUT_OF_ORDER_FRACTION = 0.1
#: A scan may be this many messages away from its place in stamp order (the scans are
#: streamed: this many are held back to sort them).
REORDER_WINDOW = 16


def _reader(path: Path):
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    return AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))


def _topics(reader) -> dict[str, str]:
    out: dict[str, str] = {}
    for c in reader.connections:
        out.setdefault(c.topic, c.msgtype)
    return out


def _connections(reader, path: Path, topic: str, allowed: tuple[str, ...], what: str):
    topics = _topics(reader)
    if topic not in topics:
        listing = ", ".join(f"{t} ({m})" for t, m in sorted(topics.items()))
        raise InputError(f"{path}: no topic {topic!r} for {what}; topics in the bag: {listing}")
    conns = [c for c in reader.connections if c.topic == topic]
    bad = sorted({c.msgtype for c in conns if c.msgtype not in allowed})
    if bad:
        raise InputError(
            f"{path}: topic {topic!r} carries {', '.join(bad)}; expected one of {', '.join(allowed)} for {what}"
        )
    return conns


def open_bag(path: Path, dataset: Mapping[str, Any], max_gap_s: float | None = None) -> Recording:
    """Open a ROS1 ``.bag`` or ROS2 bag folder as a :class:`~floorscan.ingest.recording.Recording`.

    Parameters
    ----------
    path : Path
        The bag file (ROS1), folder (ROS2) or a ROS2 bag's ``.db3`` / ``.mcap`` file.
    dataset : mapping
        Optional ``scan_topic`` and ``pose`` (``source``, ``topic``, ``fixed_frame``,
        ``base_frame``), detected when absent (:mod:`floorscan.ingest.rosbag_detect`); optional
        ``range_min_m`` / ``range_max_m`` (tighten the message's limits).
    max_gap_s : float, optional
        TF chains: samples inside a gap longer than this in any moving link are left
        out of the pose stream, so the pose stage sees the gap; None: ``poses.max_gap_s``'s
        default.

    Returns
    -------
    Recording
        ``detected`` holds ``scan_topic``, ``pose_source``, ``pose_kind`` (``map``, or
        ``none`` with an empty pose stream) and ``stamps`` (``recorded``: header stamps).

    Raises
    ------
    InputError
        Unreadable/corrupt bag, missing topic (the message lists the bag's topics),
        unsupported message type, no path between the TF frames, pose stamps unsorted
        or duplicated; without ``scan_topic``, several or no scan topics; without
        ``pose``, several map pose topics and none of them ``/amcl_pose``.
    """
    if max_gap_s is None:
        max_gap_s = PosesParams().max_gap_s
    from floorscan.ingest.detect import bag_path

    path = bag_path(path)
    ros2_folder_check(path)
    rmin_cfg = dataset.get("range_min_m")
    rmax_cfg = dataset.get("range_max_m")
    notes: list[str] = []
    try:
        with _reader(path) as reader:
            topics = {t: (info.msgtype, info.msgcount) for t, info in reader.topics.items()}
            scan_topic = dataset.get("scan_topic")
            if scan_topic is None:
                scan_topic, note = detect_scan_topic(topics, path)
                notes.append(note)
            scan_conns = _connections(reader, path, scan_topic, SCAN_TYPES, "scans")
            scan_frame = _scan_frame(reader, path, scan_topic, scan_conns)
            tf = _LazyTF(reader, path)
            pose_cfg = dataset.get("pose")
            if pose_cfg is None:
                pose_cfg, phrase, note = detect_pose_source(topics, tf.edges, scan_frame, path,
                                                            _pose_frames(reader, topics))
                notes.append(note)
            else:
                phrase = None
            if pose_cfg is None:
                stream, pose_kind = pose_stream_frame([], [], [], [], []), "none"
                stream.attrs["upside_down"] = _mount_upside_down(tf.edges, scan_frame)
            else:
                pose_kind = "map"
                source = pose_cfg["source"]
                if source == "topic":
                    if "topic" not in pose_cfg:
                        raise InputError(f"{path}: pose.source 'topic' needs pose.topic (e.g. /amcl_pose)")
                    stream = _pose_topic_stream(reader, path, pose_cfg, scan_frame, tf, notes)
                    described = f"topic {pose_cfg['topic']} ({short_type(topics[pose_cfg['topic']][0])})"
                elif source == "tf":
                    fixed = pose_cfg.get("fixed_frame", MAP_FRAME)
                    stream, chain = tf_pose_stream(tf.edges, path, fixed, scan_frame, max_gap_s)
                    described = "TF " + " -> ".join([fixed] + [e.child for e in chain])
                else:
                    raise InputError(f"{path}: pose.source {source!r} is not available for bags; use topic or tf")
                if phrase is None:
                    phrase = f"{described} (set in the dataset)"
                    notes.append(f"pose source {phrase}: used as the map pose")
            edges = tf.edges  # read by every pose source above (and by detection)
            upside_down = bool(stream.attrs.pop("upside_down", False))
            if upside_down:
                note = (f"scanner frame {scan_frame!r} is mounted upside down (its TF turns it half a turn about a "
                        "level axis): its scans are turned over (y and z negated) to lie level under its pose")
                notes.append(note)
                log.info("%s: %s", path, note)
    except InputError:
        raise
    except Exception as e:  # rosbags raises several reader/deserialization errors
        raise InputError(f"{path}: cannot read the bag, truncated or corrupt ({type(e).__name__}: {e})") from None

    n_total = int(topics[scan_topic][1] or 0)
    detected = {"scan_topic": scan_topic, "pose_source": phrase, "pose_kind": pose_kind, "stamps": "recorded"}

    def _scans() -> Iterator[Scan]:
        losses = ScanLosses(f"scans on {scan_topic!r}")
        order = _StampOrder(path, scan_topic)
        frames = ScanFrames(path, scan_topic, scan_frame, edges)
        try:
            with _reader(path) as reader:
                conns = [c for c in reader.connections if c.topic == scan_topic]
                for i, (c, bag_t, raw) in enumerate(bag_messages(reader, conns)):
                    losses.n_read += 1
                    try:
                        scan = frames.place(_scan(reader, c, bag_t, raw, path, scan_topic, i, rmin_cfg, rmax_cfg))
                        if scan is None:  # a frame TF does not place: counted, refused below
                            continue
                        if upside_down:
                            scan = dataclasses.replace(scan, points=turn_over(scan.points))
                    except FrameError as e:
                        losses.skip(i, e)
                        if losses.too_many_bad(max(n_total, losses.n_read)):
                            raise losses.refusal(max(n_total, losses.n_read)) from None
                        continue
                    yield from order.push(i, scan)
        except InputError:
            raise
        except Exception as e:
            raise InputError(
                f"{path}: cannot read scans on {scan_topic!r}, truncated or corrupt bag "
                f"({type(e).__name__}: {str(e)[:MAX_QUOTE]})"
            ) from None
        losses.report(detected, notes, str(path))
        frames.finish(notes, detected)
        yield from order.flush(losses.n_read)
        note = order.note()
        if note:
            notes.append(note)
            log.warning("%s", note)

    return Recording(
        scans=_scans(), pose_stream=stream, source=f"{path} {scan_topic}", notes=notes, detected=detected
    )


def _pose_frames(reader, topics) -> dict[str, str]:
    """Pose topic -> the ``header.frame_id`` of its first message that decodes (detection
    leaves a topic in an odometry frame out of the map poses)."""
    out = {}
    for topic, (msgtype, n) in topics.items():
        if msgtype not in MAP_POSE_TYPES or not n:
            continue
        for c, _, raw in bag_messages(reader, [c for c in reader.connections if c.topic == topic]):
            try:
                out[topic] = reader.deserialize(raw, c.msgtype).header.frame_id
                break
            except Exception:  # noqa: BLE001 - a broken message is read (and refused) later
                continue
    return out


def _mount_upside_down(edges, scan_frame: str) -> bool:
    """Whether the static mount ``base_link`` -> the scanner (when the bag has one) turns
    the scanner upside down; a broken TF tree is no mount (without a pose source the
    scans are registered by LIDAR odometry, in the scanner's frame)."""
    if not edges:
        return False
    try:
        mount = static_transform(edges, "base_link", scan_frame)
    except InputError:
        return False
    return mount is not None and is_upside_down(mount[0])


def _scan_frame(reader, path: Path, topic: str, conns) -> str:
    """The frame of the first scan message that can be decoded (a broken one is skipped
    later, as the scans are read)."""
    error = None
    for c, _, raw in bag_messages(reader, conns):
        try:
            return reader.deserialize(raw, c.msgtype).header.frame_id.lstrip("/")
        except Exception as e:  # rosbags raises several deserialization errors
            error = error or f"{type(e).__name__}: {str(e)[:MAX_QUOTE]}"
    if error is None:
        from floorscan.ingest.rosbag_detect import metadata_hint

        raise InputError(f"{path}: topic {topic!r} has no messages{metadata_hint(path)}")
    raise InputError(f"{path}: no message on {topic!r} can be decoded (the first: {error}); truncated or corrupt bag")


class _LazyTF:
    """The bag's TF links, read once on first use (detection and the pose source share them)."""

    def __init__(self, reader, path: Path):
        self._reader, self._path, self._edges = reader, path, None

    @property
    def edges(self) -> dict[tuple[str, str], TfLink]:
        if self._edges is None:
            self._edges = read_tf(self._reader, self._path)
        return self._edges


def _pose_topic_stream(
    reader, path: Path, pose_cfg: Mapping[str, Any], scan_frame: str, tf: "_LazyTF", notes: list[str]
):
    topic = pose_cfg["topic"]
    conns = _connections(reader, path, topic, POSE_TYPES, "poses")
    t, xyz, quat = [], [], []
    for i, (c, bag_t, raw) in enumerate(bag_messages(reader, conns)):
        msg = reader.deserialize(raw, c.msgtype)
        stamped = c.msgtype.endswith("/PoseStamped")
        pose = msg.pose if stamped else msg.pose.pose
        t.append(stamp_ns(msg.header, bag_t))
        v, q = pose.position, pose.orientation
        xyz.append((v.x, v.y, v.z))
        quat.append((q.x, q.y, q.z, q.w))
        bad = pose_problem(xyz[-1], quat[-1], "pose" if stamped else "pose.pose")
        if bad:
            raise InputError(f"{message_label(path, topic, i, t[-1])}: {short_type(c.msgtype)} {bad}")
    if not t:
        raise InputError(f"{path}: pose topic {topic!r} has no messages")
    t = np.asarray(t, dtype=np.int64)
    what = f"{path}: pose topic {topic!r} header stamps"
    order, note = _sort_few(t, what)
    if note:
        notes.append(note)
        log.warning("%s", note)
    t = t[order]
    _check_sorted(t, what)
    rot = Rotation.from_quat(np.asarray(quat, dtype=np.float64)[order])
    trans = np.asarray(xyz, dtype=np.float64)[order]
    # mount of the scanner on the base: a constant transform base_frame -> scan_frame
    base = pose_cfg.get("base_frame", "base_link")
    mount = static_transform(tf.edges, base, scan_frame)
    if mount is not None:
        m_rot, m_t = mount
        trans = trans + rot.apply(m_t)
        rot = rot * m_rot
    else:
        log.info("%s: no static transform %s -> %s; the scanner is taken to be at the pose", path, base, scan_frame)
    return planar_pose_stream(t, rot, trans, f"{path}: pose of {scan_frame!r} from {topic!r}")


def _check_sorted(t: np.ndarray, what: str) -> None:
    d = np.diff(t)
    if np.any(d < 0):
        i = int(np.flatnonzero(d < 0)[0]) + 1
        raise InputError(f"{what} are not sorted (message {i}: {t[i]} ns after {t[i - 1]} ns); expected increasing stamps")
    if np.any(d == 0):
        i = int(np.flatnonzero(d == 0)[0]) + 1
        raise InputError(f"{what} have a duplicate stamp {t[i]} ns (message {i}); expected strictly increasing stamps")


def _sort_few(t: np.ndarray, what: str) -> tuple[np.ndarray, str | None]:
    """The stable order that sorts stamps ``t`` when only a few step back, and a note.

    Returns
    -------
    order : (N,) int ndarray
        Indices sorting ``t`` (identity when it is sorted).
    note : str or None
        What was sorted, or None.

    Raises
    ------
    InputError
        More than :data:`MAX_OUT_OF_ORDER_FRACTION` of the stamps step back.
    """
    back = np.flatnonzero(np.diff(t) < 0) + 1
    if back.size == 0:
        return np.arange(t.size), None
    if back.size > MAX_OUT_OF_ORDER_FRACTION * t.size:
        i = int(back[0])
        raise InputError(
            f"{what} are not sorted: {back.size} of {t.size} messages are stamped earlier than the message before "
            f"them (the first: message {i}, {t[i]} ns after {t[i - 1]} ns), more than "
            f"{100 * MAX_OUT_OF_ORDER_FRACTION:g} %; expected increasing stamps"
        )
    note = (
        f"{what}: {back.size} of {t.size} messages stamped earlier than the message before them "
        f"(messages {back[:5].tolist()}{'...' if back.size > 5 else ''}): sorted by header stamp"
    )
    return np.argsort(t, kind="stable"), note


class _StampOrder:
    """Scans streamed in header-stamp order: a few messages out of order are held back
    (at most :data:`REORDER_WINDOW`) and sorted, as a CARMEN log's lines are."""

    def __init__(self, path: Path, topic: str):
        self.path, self.topic = path, topic
        self.heap: list[tuple[int, int, Scan]] = []
        self.last_in: int | None = None
        self.last_out: int | None = None
        self.back: list[int] = []

    def push(self, index: int, scan: Scan) -> Iterator[Scan]:
        t = scan.t_ns
        if self.last_in is not None and t < self.last_in - MAX_STEP_BACK_S * 1e9:
            raise InputError(
                f"{message_label(self.path, self.topic, index, t)}: header stamp is {(self.last_in - t) * 1e-9:.1f} s "
                f"earlier than the scan before it ({self.last_in} ns); scans a little out of order (up to "
                f"{MAX_STEP_BACK_S:g} s back) are sorted by stamp, one this far back is a clock reset or a second "
                "recording in the bag: expected stamps in recording order (split the bag where the other recording "
                "starts)"
            )
        if self.last_in is not None and t < self.last_in:
            self.back.append(index)
            if self.last_out is not None and t < self.last_out:
                raise InputError(
                    f"{message_label(self.path, self.topic, index, t)}: header stamp is earlier than a scan "
                    f"{REORDER_WINDOW} or more messages before it ({self.last_out} ns); expected stamps in "
                    f"recording order, give or take {REORDER_WINDOW} messages"
                )
        self.last_in = t
        heapq.heappush(self.heap, (t, index, scan))
        while len(self.heap) > REORDER_WINDOW:
            yield self._pop()

    def _pop(self) -> Scan:
        t, _, scan = heapq.heappop(self.heap)
        self.last_out = t
        return scan

    def flush(self, n_read: int) -> Iterator[Scan]:
        """The scans held back; refuses stamps that step back too often (``n_read`` read)."""
        if len(self.back) > MAX_OUT_OF_ORDER_FRACTION * n_read:
            i = self.back[0]
            raise InputError(
                f"{self.path}: header stamps on {self.topic!r} are not sorted: {len(self.back)} of {n_read} messages "
                f"are stamped earlier than the message before them (the first: message {i}), more than "
                f"{100 * MAX_OUT_OF_ORDER_FRACTION:g} %; expected increasing stamps"
            )
        while self.heap:
            yield self._pop()

    def note(self) -> str | None:
        if not self.back:
            return None
        b = self.back
        return (
            f"{len(b)} scans on {self.topic!r} stamped earlier than the message before them "
            f"(messages {b[:5]}{'...' if len(b) > 5 else ''}): scans sorted by header stamp"
        )


def _scan(reader, c, bag_t: int, raw, path: Path, topic: str, i: int, rmin_cfg, rmax_cfg) -> Scan:
    """Scan message ``i`` (its ``source_ordinal``) read and checked.

    Raises
    ------
    FrameError
        It cannot be decoded, its geometry or layout is broken, or it has no valid return.
    """
    try:
        msg = reader.deserialize(raw, c.msgtype)
        t_ns = stamp_ns(msg.header, bag_t)
        frame = msg.header.frame_id.lstrip("/")
    except Exception as e:  # rosbags raises several deserialization errors
        raise FrameError(
            message_label(path, topic, i, bag_t),
            f"{short_type(c.msgtype)} cannot be decoded ({type(e).__name__}: {str(e)[:MAX_QUOTE]}); expected a message "
            "of its connection's type",
        ) from None
    where = message_label(path, topic, i, t_ns)
    if c.msgtype.endswith("LaserScan"):
        bad = laser_scan_problem(msg)
        if bad:
            raise FrameError(where, bad)
        pts, dropped = laser_scan_xyz(msg, path, topic, i, t_ns, rmin_cfg, rmax_cfg)
        if not len(pts):
            rmin, rmax = laser_scan_limits(msg, rmin_cfg, rmax_cfg)
            raise FrameError(
                where, f"LaserScan has no valid return: {no_return_reason(msg.ranges, rmin, rmax)}", loss="no_points"
            )
    else:
        xyz = pointcloud2_xyz(msg, path, topic, index=i, t_ns=t_ns)
        pts, dropped = filter_points(xyz, rmin_cfg, rmax_cfg)
        if not len(pts):
            what = f"PointCloud2 has no valid return: {no_point_reason(xyz, rmin_cfg, rmax_cfg)}"
            raise FrameError(where, what, loss="no_points")
    return Scan(t_ns, frame, pts, dropped, i)

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
:mod:`floorscan.ingest.ros_messages`, the TF chains by :mod:`floorscan.ingest.tf_chains`.

ROS2 bags that store no message definitions are read with the Humble typestore. A
``.db3`` / ``.mcap`` file is read as its folder's bag.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np
from scipy.spatial.transform import Rotation

from floorscan.core.io import InputError
from floorscan.ingest.params import PosesParams
from floorscan.ingest.points import filter_points
from floorscan.ingest.recording import Recording, Scan, pose_stream_frame
from floorscan.ingest.ros_messages import laser_scan_xyz, message_label, pointcloud2_xyz, pose_problem, stamp_ns
from floorscan.ingest.rosbag_detect import (
    MAP_FRAME,
    POSE_TYPES,
    SCAN_TYPES,
    detect_pose_source,
    detect_scan_topic,
    short_type,
)
from floorscan.ingest.tf_chains import TfLink, planar_pose_stream, read_tf, static_transform, tf_pose_stream

log = logging.getLogger(__name__)


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
            first = next(reader.messages(connections=scan_conns), None)
            if first is None:
                raise InputError(f"{path}: topic {scan_topic!r} has no messages")
            c0, _, raw0 = first
            scan_frame = reader.deserialize(raw0, c0.msgtype).header.frame_id.lstrip("/")
            tf = _LazyTF(reader, path)
            pose_cfg = dataset.get("pose")
            if pose_cfg is None:
                pose_cfg, phrase, note = detect_pose_source(topics, tf.edges, scan_frame, path)
                notes.append(note)
            else:
                phrase = None
            if pose_cfg is None:
                stream, pose_kind = pose_stream_frame([], [], [], [], []), "none"
            else:
                pose_kind = "map"
                source = pose_cfg["source"]
                if source == "topic":
                    if "topic" not in pose_cfg:
                        raise InputError(f"{path}: pose.source 'topic' needs pose.topic (e.g. /amcl_pose)")
                    stream = _pose_topic_stream(reader, path, pose_cfg, scan_frame, tf)
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
    except InputError:
        raise
    except Exception as e:  # rosbags raises several reader/deserialization errors
        raise InputError(f"{path}: cannot read the bag, truncated or corrupt ({type(e).__name__}: {e})") from None

    def _scans() -> Iterator[Scan]:
        try:
            with _reader(path) as reader:
                conns = [c for c in reader.connections if c.topic == scan_topic]
                for i, (c, bag_t, raw) in enumerate(reader.messages(connections=conns)):
                    msg = reader.deserialize(raw, c.msgtype)
                    t_ns = stamp_ns(msg.header, bag_t)
                    frame = msg.header.frame_id.lstrip("/")
                    if c.msgtype.endswith("LaserScan"):
                        pts, dropped = laser_scan_xyz(msg, path, scan_topic, i, t_ns, rmin_cfg, rmax_cfg)
                    else:
                        xyz = pointcloud2_xyz(msg, path, scan_topic, index=i, t_ns=t_ns)
                        pts, dropped = filter_points(xyz, rmin_cfg, rmax_cfg)
                    yield Scan(t_ns, frame, pts, dropped)
        except InputError:
            raise
        except Exception as e:
            raise InputError(
                f"{path}: cannot read scans on {scan_topic!r}, truncated or corrupt bag ({type(e).__name__}: {e})"
            ) from None

    detected = {"scan_topic": scan_topic, "pose_source": phrase, "pose_kind": pose_kind, "stamps": "recorded"}
    return Recording(
        scans=_scans(), pose_stream=stream, source=f"{path} {scan_topic}", notes=notes, detected=detected
    )


class _LazyTF:
    """The bag's TF links, read once on first use (detection and the pose source share them)."""

    def __init__(self, reader, path: Path):
        self._reader, self._path, self._edges = reader, path, None

    @property
    def edges(self) -> dict[tuple[str, str], TfLink]:
        if self._edges is None:
            self._edges = read_tf(self._reader, self._path)
        return self._edges


def _pose_topic_stream(reader, path: Path, pose_cfg: Mapping[str, Any], scan_frame: str, tf: "_LazyTF"):
    topic = pose_cfg["topic"]
    conns = _connections(reader, path, topic, POSE_TYPES, "poses")
    t, xyz, quat = [], [], []
    for i, (c, bag_t, raw) in enumerate(reader.messages(connections=conns)):
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
    _check_sorted(t, f"{path}: pose topic {topic!r} header stamps")
    rot = Rotation.from_quat(np.asarray(quat, dtype=np.float64))
    trans = np.asarray(xyz, dtype=np.float64)
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

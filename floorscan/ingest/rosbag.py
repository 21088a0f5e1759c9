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

Detection (issue 20), when the dataset does not name them:

- scan topic (:func:`detect_scan_topic`): the bag's one topic of LaserScan or
  PointCloud2 messages; with several or none, an ``InputError`` lists the candidates
  (or the bag's topics) and asks for ``scan_topic``;
- pose source (:func:`detect_pose_source`), in this order: (a) a
  PoseWithCovarianceStamped or PoseStamped topic (with several, ``/amcl_pose``); (b) the
  TF chain from ``map`` to the scan frame; (c) none. Wheel odometry (nav_msgs/Odometry
  topics, TF chains from ``odom``) drifts and is never taken for the map pose: without
  (a) or (b) the pose stream is empty, the pose kind ``none``, and the register stage
  runs LIDAR odometry. A pose source set in the dataset is used as given (pose kind
  ``map``: the user's choice).

ROS2 bags that store no message definitions are read with the Humble typestore. A
``.db3`` / ``.mcap`` file is read as its folder's bag.

Bad values (issue 24) are an ``InputError`` naming the file, the topic, the message and
the field, never a wrong pose or point: a LaserScan's ``angle_min``,
``angle_increment``, ``range_min`` or ``range_max`` not finite; a pose message's position
or orientation not finite, or its quaternion not a unit one (``|q|^2`` off 1 by more than
:data:`QUATERNION_TOLERANCE`, the bound tf2 applies to the transforms it accepts); a TF
transform the same, when its link is in the chain the poses come from (a broken link
elsewhere in the tree is not read); a PointCloud2 whose layout does not hold its points
(a field beyond ``point_step``, ``row_step`` short of a row, data not ``row_step x
height`` bytes) or with no finite point at all. Non-finite *ranges* and single
non-finite *points* are not errors: they are "no return", dropped and counted.
"""

from __future__ import annotations

import logging
import math
from collections import defaultdict
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from floorscan.ingest import (
    Recording,
    Scan,
    filter_points,
    laser_scan_points,
    pose_stream_frame,
)
from floorscan.core.io import InputError

log = logging.getLogger(__name__)

SCAN_TYPES = ("sensor_msgs/msg/LaserScan", "sensor_msgs/msg/PointCloud2")
POSE_TYPES = (
    "geometry_msgs/msg/PoseWithCovarianceStamped",
    "geometry_msgs/msg/PoseStamped",
    "nav_msgs/msg/Odometry",
)
#: Pose topics detection takes for map poses (a localizer's output); odometry is not one.
MAP_POSE_TYPES = POSE_TYPES[:2]
ODOMETRY_TYPE = "nav_msgs/msg/Odometry"
#: The pose topic detection prefers among several (AMCL's output).
PREFERRED_POSE_TOPIC = "/amcl_pose"
#: The map frame of a TF chain detection looks for.
MAP_FRAME = "map"
TF_TOPICS = ("/tf", "/tf_static")
#: A scanner tilted more than this (degrees) cannot be treated as planar.
MAX_TILT_DEG = 10.0
#: A quaternion whose squared norm is off 1 by more than this is not a rotation (tf2's
#: ``BufferCore::setTransform`` rejects such transforms with the same bound).
QUATERNION_TOLERANCE = 0.01


def _reader(path: Path):
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    return AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE))


def _stamp_ns(header, bag_t: int) -> int:
    t = int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)
    return t if t > 0 else int(bag_t)


def _topics(reader) -> dict[str, str]:
    out: dict[str, str] = {}
    for c in reader.connections:
        out.setdefault(c.topic, c.msgtype)
    return out


def _short(msgtype: str) -> str:
    return msgtype.rsplit("/", 1)[-1]


def _listing(topics: Mapping[str, tuple[str, int]]) -> str:
    return ", ".join(f"{t} ({m}, {n} messages)" for t, (m, n) in sorted(topics.items()))


def detect_scan_topic(topics: Mapping[str, tuple[str, int]], path: Path | str = "") -> tuple[str, str]:
    """The bag's one scan topic.

    Parameters
    ----------
    topics : mapping of str to (str, int)
        Topic -> (message type, message count), as rosbags names the types
        (``sensor_msgs/msg/LaserScan``).

    Returns
    -------
    topic : str
    note : str
        Why it was chosen, for the stage log.

    Raises
    ------
    InputError
        Several topics with LaserScan or PointCloud2 messages (listed with their type
        and message count; set the dataset's ``scan_topic``), or none (the bag's topics
        are listed).
    """
    scans = {t: (m, n) for t, (m, n) in topics.items() if m in SCAN_TYPES and n > 0}
    if len(scans) == 1:
        (topic, (msgtype, n)), = scans.items()
        return topic, f"scan topic {topic} (detected: the bag's one {_short(msgtype)} topic, {n} messages)"
    if scans:
        raise InputError(
            f"{path}: several scan topics: {_listing(scans)}; set the dataset's 'scan_topic' to one of them"
        )
    raise InputError(
        f"{path}: no topic with sensor_msgs/LaserScan or sensor_msgs/PointCloud2 messages; "
        f"topics in the bag: {_listing(topics) or 'none'}"
    )


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


def open_bag(path: Path, dataset: Mapping[str, Any], max_gap_s: float = 0.5) -> Recording:
    """Open a ROS1 ``.bag`` or ROS2 bag folder as a :class:`~floorscan.ingest.Recording`.

    Parameters
    ----------
    path : Path
        The bag file (ROS1), folder (ROS2) or a ROS2 bag's ``.db3`` / ``.mcap`` file.
    dataset : mapping
        Optional ``scan_topic`` and ``pose`` (``source``, ``topic``, ``fixed_frame``,
        ``base_frame``), detected when absent (see the module docstring); optional
        ``range_min_m`` / ``range_max_m`` (tighten the message's limits).
    max_gap_s : float
        TF chains: samples inside a gap longer than this in any moving link are left
        out of the pose stream, so the pose stage sees the gap.

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
                    described = f"topic {pose_cfg['topic']} ({_short(topics[pose_cfg['topic']][0])})"
                elif source == "tf":
                    fixed = pose_cfg.get("fixed_frame", MAP_FRAME)
                    stream, chain = _tf_stream(tf.edges, path, fixed, scan_frame, max_gap_s)
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
                    t_ns = _stamp_ns(msg.header, bag_t)
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
    def edges(self) -> dict[tuple[str, str], "_Edge"]:
        if self._edges is None:
            self._edges = _read_tf(self._reader, self._path)
        return self._edges


def detect_pose_source(
    topics: Mapping[str, tuple[str, int]],
    edges: Mapping[tuple[str, str], "_Edge"],
    scan_frame: str,
    path: Path | str = "",
) -> tuple[dict | None, str, str]:
    """The map pose source of a bag, or none (see the module docstring for the order).

    Parameters
    ----------
    topics : mapping of str to (str, int)
        Topic -> (message type, message count).
    edges : mapping
        The bag's TF links (parent, child) -> link, as :func:`_read_tf` returns them.
    scan_frame : str
        Frame of the scans (no leading slash).

    Returns
    -------
    pose : dict or None
        A dataset ``pose`` entry (``{source: topic, topic, base_frame}`` or
        ``{source: tf, fixed_frame: map}``), or None: no map pose (pose kind ``none``).
    phrase : str
        The pose source for people, e.g. ``topic /amcl_pose (PoseWithCovarianceStamped)``,
        ``TF map -> odom -> base_link -> laser`` or ``none: wheel odometry only (TF odom ->
        base_link -> laser); LIDAR odometry``.
    note : str
        Why, for the stage log.

    Raises
    ------
    InputError
        Several PoseWithCovarianceStamped / PoseStamped topics, none of them
        ``/amcl_pose`` (they are listed; set the dataset's ``pose``).
    """
    poses = {t: (m, n) for t, (m, n) in topics.items() if m in MAP_POSE_TYPES and n > 0}
    if len(poses) > 1 and PREFERRED_POSE_TOPIC in poses:
        poses = {PREFERRED_POSE_TOPIC: poses[PREFERRED_POSE_TOPIC]}
        why = f"{PREFERRED_POSE_TOPIC} among several pose topics"
    else:
        why = "the bag's one map pose topic"
    if len(poses) > 1:
        raise InputError(
            f"{path}: several pose topics: {_listing(poses)}; set the dataset's "
            f"'pose' (e.g. {{source: topic, topic: {sorted(poses)[0]}}})"
        )
    if poses:
        (topic, (msgtype, n)), = poses.items()
        phrase = f"topic {topic} ({_short(msgtype)})"
        note = f"pose source {phrase} (detected: {why}, {n} messages)"
        return {"source": "topic", "topic": topic, "base_frame": "base_link"}, phrase, note
    chain = _chain_or_none(edges, MAP_FRAME, scan_frame)
    if chain is not None:
        phrase = "TF " + " -> ".join([MAP_FRAME] + [e.child for e in chain])
        note = f"pose source {phrase} (detected: no pose topic, and the TF chain from {MAP_FRAME!r} to the scan frame)"
        return {"source": "tf", "fixed_frame": MAP_FRAME}, phrase, note
    wheel = []
    root_chain = _chain_from_root(edges, scan_frame)
    if len(root_chain) > 1:
        wheel.append("TF " + " -> ".join(root_chain))
    odom = sorted(t for t, (m, n) in topics.items() if m == ODOMETRY_TYPE and n > 0)
    if odom:
        wheel.append(f"Odometry on {', '.join(odom)}")
    if wheel:
        phrase = f"none: wheel odometry only ({'; '.join(wheel)}); LIDAR odometry"
    else:
        phrase = "none: no pose topic and no TF; LIDAR odometry"
    note = (
        f"pose source none (detected: no PoseWithCovarianceStamped or PoseStamped topic and no TF chain "
        f"from {MAP_FRAME!r} to {scan_frame!r}; wheel odometry drifts and is never taken for the map pose): "
        "the pose stream is empty (pose kind none) and the register stage runs LIDAR odometry"
    )
    return None, phrase, note


def _message(path: Path | str, topic: str, index: int, t_ns: int) -> str:
    """How an error names one message: ``file: 'topic' message i (t ... ns)``."""
    return f"{path}: {topic!r} message {index} (t {t_ns} ns)"


def laser_scan_xyz(
    msg,
    path: Path | str = "",
    topic: str = "",
    index: int = 0,
    t_ns: int = 0,
    range_min_m: float | None = None,
    range_max_m: float | None = None,
) -> tuple[np.ndarray, int]:
    """Points of a ``sensor_msgs/LaserScan`` in the scanner frame.

    Beam ``i`` points at ``angle_min + i * angle_increment``; returns are kept in
    ``[max(range_min, range_min_m), min(range_max, range_max_m))``
    (:func:`floorscan.ingest.laser_scan_points`).

    Parameters
    ----------
    msg : sensor_msgs/LaserScan
        ``angle_min``, ``angle_increment``, ``range_min``, ``range_max`` (radians,
        metres) and ``ranges`` ((B,) float32, metres).
    path, topic, index, t_ns
        The bag, topic, message index and stamp, for error messages.
    range_min_m, range_max_m : float, optional
        The dataset's limits, metres: they only tighten the message's.

    Returns
    -------
    points : (N, 3) float32 ndarray
        Valid returns, z = 0, metres.
    n_dropped : int
        Beams dropped: NaN, inf (no return) or out of the range limits.

    Raises
    ------
    InputError
        ``angle_min``, ``angle_increment``, ``range_min`` or ``range_max`` is not finite
        (names the file, topic, message and field).
    """
    values = (float(msg.angle_min), float(msg.angle_increment), float(msg.range_min), float(msg.range_max))
    for name, v in zip(("angle_min", "angle_increment", "range_min", "range_max"), values):
        if not math.isfinite(v):
            raise InputError(f"{_message(path, topic, index, t_ns)}: LaserScan {name} is {v}; expected a finite number")
    angle_min, angle_increment, range_min, range_max = values
    rmin = max(range_min, range_min_m if range_min_m is not None else 0.0)
    rmax = min(range_max, range_max_m if range_max_m is not None else math.inf)
    return laser_scan_points(np.asarray(msg.ranges), angle_min, angle_increment, rmin, rmax)


_PC2_DTYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}


def pointcloud2_xyz(msg, path: Path | str = "", topic: str = "", index: int | None = None, t_ns: int = 0) -> np.ndarray:
    """The ``x, y, z`` fields of a ``sensor_msgs/PointCloud2`` as an (N, 3) array.

    float32 when the three fields are little-endian float32 (the usual LIDAR driver
    layout: the values as they are, without a float64 copy that the float32 scan table
    would round back), else float64. Handles any point step, field offsets, endianness,
    row padding (``row_step`` beyond ``width x point_step``; 0 is taken as unpadded) and
    organised clouds (height > 1). Non-finite points are returned as they are (the
    caller drops and counts them).

    Parameters
    ----------
    index, t_ns : int, optional
        The message's index on the topic and stamp, named in error messages.

    Raises
    ------
    InputError
        The message has no x, y or z field, one of unknown datatype or ending beyond
        ``point_step``; ``row_step`` is short of ``width x point_step``; the data is not
        ``row_step x height`` bytes; or no point is finite (the cloud holds nothing).
    """
    what = f"{path}: PointCloud2 on {topic!r}" if index is None else f"{_message(path, topic, index, t_ns)}: PointCloud2"
    fields = {f.name: f for f in msg.fields}
    missing = [n for n in "xyz" if n not in fields]
    if missing:
        raise InputError(
            f"{what} lacks fields {missing}; expected x, y, z "
            f"(fields: {sorted(fields)})"
        )
    order = ">" if msg.is_bigendian else "<"
    step, width, height, row_step = int(msg.point_step), int(msg.width), int(msg.height), int(msg.row_step)
    names, formats, offsets = [], [], []
    for n in "xyz":
        f = fields[n]
        if f.datatype not in _PC2_DTYPES:
            raise InputError(f"{what} field {n!r} has unknown datatype {f.datatype}")
        size = np.dtype(_PC2_DTYPES[f.datatype]).itemsize
        if not 0 <= int(f.offset) <= step - size:
            raise InputError(
                f"{what} field {n!r} (offset {int(f.offset)}, {size} bytes) ends beyond point_step {step}"
            )
        names.append(n)
        formats.append(order + _PC2_DTYPES[f.datatype])
        offsets.append(int(f.offset))
    if row_step and row_step < width * step:
        raise InputError(
            f"{what} row_step {row_step} is less than width x point_step = {width} x {step} = {width * step}"
        )
    rs = row_step or width * step  # 0: a driver that left it unset, rows packed
    data = np.asarray(msg.data, dtype=np.uint8)
    if data.size != rs * height:
        raise InputError(
            f"{what} has {data.size} bytes of data; "
            f"expected row_step x height = {rs} x {height} = {rs * height}"
        )
    n_points = width * height
    out_dtype = np.float32 if all(f == "<f4" for f in formats) else np.float64
    if n_points == 0:
        return np.zeros((0, 3), dtype=out_dtype)
    if rs != width * step:
        data = np.ascontiguousarray(data.reshape(height, rs)[:, : width * step]).reshape(-1)
    dt = np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": step})
    arr = np.frombuffer(data, dtype=dt, count=n_points)  # a view: count bounds it
    out = np.empty((n_points, 3), dtype=out_dtype)
    for i, n in enumerate("xyz"):
        out[:, i] = arr[n]
    if not (np.isfinite(out[:, 0]) & np.isfinite(out[:, 1]) & np.isfinite(out[:, 2])).any():
        raise InputError(
            f"{what} has no finite point ({n_points} points); expected a cloud with at least one return"
        )
    return out


def _pose_problem(
    position: tuple[float, float, float],
    quat: tuple[float, float, float, float],
    prefix: str,
    parts: tuple[str, str] = ("position", "orientation"),
) -> str | None:
    """What is wrong with a pose's values (``prefix.position.x is nan; ...``), or None:
    a non-finite component of ``position`` (x, y, z) or ``quat`` (x, y, z, w), or a
    quaternion off unit length by more than :data:`QUATERNION_TOLERANCE` (in ``|q|^2``).

    Called for every pose and TF message: a good pose costs one test (a NaN or inf
    component fails it); the loops below only explain a bad one.
    """
    n2 = quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]
    if abs(n2 - 1.0) <= QUATERNION_TOLERANCE and math.isfinite(position[0] + position[1] + position[2]):
        return None
    (p_name, q_name) = parts
    for part, values in ((p_name, position), (q_name, quat)):
        for c, v in zip("xyzw", values):
            if not math.isfinite(v):
                return f"{prefix}.{part}.{c} is {float(v)}; expected a finite number"
    if abs(n2 - 1.0) > QUATERNION_TOLERANCE:
        return (
            f"{prefix}.{q_name} is {tuple(map(float, quat))}, |q|^2 = {n2:g}; expected a unit quaternion "
            f"(|q|^2 within {QUATERNION_TOLERANCE} of 1, as tf2 requires)"
        )
    return None  # finite values whose sum overflowed


def _pose_topic_stream(reader, path: Path, pose_cfg: Mapping[str, Any], scan_frame: str, tf: "_LazyTF"):
    topic = pose_cfg["topic"]
    conns = _connections(reader, path, topic, POSE_TYPES, "poses")
    t, xyz, quat = [], [], []
    for i, (c, bag_t, raw) in enumerate(reader.messages(connections=conns)):
        msg = reader.deserialize(raw, c.msgtype)
        stamped = c.msgtype.endswith("/PoseStamped")
        pose = msg.pose if stamped else msg.pose.pose
        t.append(_stamp_ns(msg.header, bag_t))
        v, q = pose.position, pose.orientation
        xyz.append((v.x, v.y, v.z))
        quat.append((q.x, q.y, q.z, q.w))
        bad = _pose_problem(xyz[-1], quat[-1], "pose" if stamped else "pose.pose")
        if bad:
            raise InputError(f"{_message(path, topic, i, t[-1])}: {_short(c.msgtype)} {bad}")
    if not t:
        raise InputError(f"{path}: pose topic {topic!r} has no messages")
    t = np.asarray(t, dtype=np.int64)
    _check_sorted(t, f"{path}: pose topic {topic!r} header stamps")
    rot = Rotation.from_quat(np.asarray(quat, dtype=np.float64))
    trans = np.asarray(xyz, dtype=np.float64)
    # mount of the scanner on the base: a constant transform base_frame -> scan_frame
    base = pose_cfg.get("base_frame", "base_link")
    mount = _static_chain(tf.edges, base, scan_frame)
    if mount is not None:
        m_rot, m_t = mount
        trans = trans + rot.apply(m_t)
        rot = rot * m_rot
    else:
        log.info("%s: no static transform %s -> %s; the scanner is taken to be at the pose", path, base, scan_frame)
    return _planar(t, rot, trans, f"{path}: pose of {scan_frame!r} from {topic!r}")


def _check_sorted(t: np.ndarray, what: str) -> None:
    d = np.diff(t)
    if np.any(d < 0):
        i = int(np.flatnonzero(d < 0)[0]) + 1
        raise InputError(f"{what} are not sorted (message {i}: {t[i]} ns after {t[i - 1]} ns); expected increasing stamps")
    if np.any(d == 0):
        i = int(np.flatnonzero(d == 0)[0]) + 1
        raise InputError(f"{what} have a duplicate stamp {t[i]} ns (message {i}); expected strictly increasing stamps")


def _planar(t, rot: Rotation, trans, what: str):
    """Pose stream of a chain of 3D poses, refusing a tilted scanner."""
    mat = rot.as_matrix()
    tilt = np.degrees(np.arccos(np.clip(mat[:, 2, 2], -1.0, 1.0)))
    if np.max(tilt) > MAX_TILT_DEG:
        raise InputError(
            f"{what}: the scanner is tilted {np.max(tilt):.1f} deg from level; floorscan expects a level "
            f"scanner (tilt under {MAX_TILT_DEG} deg)"
        )
    yaw = np.arctan2(mat[:, 1, 0], mat[:, 0, 0])
    return pose_stream_frame(t, trans[:, 0], trans[:, 1], trans[:, 2], yaw)


class _Edge:
    """Samples of one TF link parent -> child: stamps, translations, rotations."""

    def __init__(self, parent: str, child: str):
        self.parent, self.child = parent, child
        self.t: list[int] = []
        self.trans: list[tuple[float, float, float]] = []
        self.quat: list[tuple[float, float, float, float]] = []
        self.static = False
        #: The first bad sample (file, topic, message, field), left out; the link is
        #: refused when a chain uses it (:func:`_check_links`).
        self.bad: str | None = None

    def finish(self) -> None:
        if not self.t:  # every sample was bad
            self.t_arr, self.trans_arr, self.rot = np.zeros(0, np.int64), np.zeros((0, 3)), None
            return
        t = np.asarray(self.t, dtype=np.int64)
        order = np.argsort(t, kind="stable")
        t, trans, quat = t[order], np.asarray(self.trans)[order], np.asarray(self.quat)[order]
        keep = np.r_[t[1:] != t[:-1], True]  # duplicate stamps: the last one wins, as in tf2
        self.t_arr, self.trans_arr = t[keep], trans[keep]
        self.rot = Rotation.from_quat(quat[keep])
        # a link that never changes is static, whichever topic carried it
        if not self.static and len(self.t_arr) > 0:
            same = np.allclose(self.trans_arr, self.trans_arr[0], atol=1e-9) and np.allclose(
                (self.rot * self.rot[0].inv()).magnitude(), 0.0, atol=1e-9
            )
            self.static = bool(same)
        if self.static:
            self.t_arr, self.trans_arr, self.rot = self.t_arr[-1:], self.trans_arr[-1:], self.rot[-1:]

    def at(self, t: np.ndarray) -> tuple[Rotation, np.ndarray]:
        if self.static:
            return Rotation.from_quat(np.repeat(self.rot.as_quat(), len(t), axis=0)), np.repeat(
                self.trans_arr, len(t), axis=0
            )
        tt = t.astype(np.float64)
        ts = self.t_arr.astype(np.float64)
        trans = np.stack([np.interp(tt, ts, self.trans_arr[:, k]) for k in range(3)], axis=1)
        rot = Slerp(ts, self.rot)(np.clip(tt, ts[0], ts[-1])) if len(ts) > 1 else self.rot
        return rot, trans


def _read_tf(reader, path: Path) -> dict[tuple[str, str], _Edge]:
    conns = [c for c in reader.connections if c.topic in TF_TOPICS]
    edges: dict[tuple[str, str], _Edge] = {}
    seen: dict[str, int] = defaultdict(int)
    for c, bag_t, raw in reader.messages(connections=conns):
        msg = reader.deserialize(raw, c.msgtype)
        index = seen[c.topic]
        seen[c.topic] += 1
        for tr in msg.transforms:
            key = (tr.header.frame_id.lstrip("/"), tr.child_frame_id.lstrip("/"))
            e = edges.get(key)
            if e is None:
                e = edges[key] = _Edge(*key)
            e.static |= c.topic == "/tf_static"
            t_ns = _stamp_ns(tr.header, bag_t)
            v, q = tr.transform.translation, tr.transform.rotation
            trans, quat = (v.x, v.y, v.z), (q.x, q.y, q.z, q.w)
            bad = _pose_problem(trans, quat, "transform", ("translation", "rotation"))
            if bad:
                if e.bad is None:
                    e.bad = f"{_message(path, c.topic, index, t_ns)}: TransformStamped {key[0]} -> {key[1]}: {bad}"
                continue
            e.t.append(t_ns)
            e.trans.append(trans)
            e.quat.append(quat)
    for e in edges.values():
        e.finish()
    return edges


def _chain(edges: dict[tuple[str, str], _Edge], fixed: str, frame: str, path: Path) -> list[_Edge]:
    parents: dict[str, list[_Edge]] = defaultdict(list)
    for e in edges.values():
        parents[e.child].append(e)
    chain, cur, seen = [], frame, set()
    while cur != fixed:
        ps = parents.get(cur, [])
        if len(ps) > 1:
            raise InputError(
                f"{path}: TF frame {cur!r} has several parents {[p.parent for p in ps]}; expected a tree"
            )
        if not ps or cur in seen:
            frames = sorted({f for k in edges for f in k})
            raise InputError(
                f"{path}: no TF chain from {fixed!r} to the scan frame {frame!r} (stops at {cur!r}); "
                f"frames on /tf and /tf_static: {frames}"
            )
        seen.add(cur)
        chain.append(ps[0])
        cur = ps[0].parent
    return chain[::-1]


def _chain_or_none(edges, fixed: str, frame: str) -> list[_Edge] | None:
    """The chain of links from ``fixed`` to ``frame``, or None when there is none."""
    if fixed == frame:
        return None
    try:
        return _chain(edges, fixed, frame, Path())
    except InputError:
        return None


def _chain_from_root(edges, frame: str) -> list[str]:
    """Frames from the root of ``frame``'s TF tree down to ``frame`` (first parent each)."""
    parents: dict[str, str] = {}
    for parent, child in edges:
        parents.setdefault(child, parent)
    out = [frame]
    while out[-1] in parents and parents[out[-1]] not in out:
        out.append(parents[out[-1]])
    return out[::-1]


def _check_links(chain: list[_Edge]) -> None:
    """Refuse a chain with a link that had a bad sample (its message names it)."""
    for e in chain:
        if e.bad is not None:
            raise InputError(e.bad)


def _static_chain(edges, base: str, frame: str):
    if base == frame:
        return Rotation.identity(), np.zeros(3)
    try:
        chain = _chain(edges, base, frame, Path())
    except InputError:
        return None
    _check_links(chain)
    if not all(e.static for e in chain):
        return None
    rot, trans = Rotation.identity(), np.zeros(3)
    for e in chain:
        trans = trans + rot.apply(e.trans_arr[0])
        rot = rot * e.rot[0]
    return rot, trans


def _tf_stream(edges, path: Path, fixed: str, frame: str, max_gap_s: float):
    """Pose stream of the TF chain ``fixed`` -> ``frame`` and the chain's links."""
    if not edges:
        raise InputError(f"{path}: pose.source is 'tf' but the bag has no /tf or /tf_static messages")
    chain = _chain(edges, fixed, frame, path)
    _check_links(chain)
    moving = [e for e in chain if not e.static]
    if not moving:
        raise InputError(f"{path}: the TF chain {fixed!r} -> {frame!r} never changes; the scanner does not move")
    lo = max(e.t_arr[0] for e in moving)
    hi = min(e.t_arr[-1] for e in moving)
    t = np.unique(np.concatenate([e.t_arr for e in moving]))
    keep = (t >= lo) & (t <= hi)
    gap_ns = int(max_gap_s * 1e9)
    for e in moving:
        d = np.diff(e.t_arr)
        for i in np.flatnonzero(d > gap_ns):
            keep &= ~((t > e.t_arr[i]) & (t < e.t_arr[i + 1]))
    t = t[keep]
    if t.size == 0:
        raise InputError(f"{path}: the moving TF links {[(e.parent, e.child) for e in moving]} do not overlap in time")
    rot, trans = Rotation.identity(len(t)), np.zeros((len(t), 3))
    for e in chain:
        r_e, t_e = e.at(t)
        trans = trans + rot.apply(t_e)
        rot = rot * r_e
    return _planar(t, rot, trans, f"{path}: TF chain {fixed!r} -> {frame!r}"), chain

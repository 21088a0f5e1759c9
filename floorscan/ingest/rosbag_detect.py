"""Which topics of a bag carry its scans and its map poses, when the dataset does not say.

Detection:

- scan topic (:func:`detect_scan_topic`): the bag's one topic of LaserScan or
  PointCloud2 messages; with several or none, an ``InputError`` lists the candidates
  (or the bag's topics) and asks for ``scan_topic``;
- pose source (:func:`detect_pose_source`), in this order: (a) a
  PoseWithCovarianceStamped or PoseStamped topic (with several, ``/amcl_pose``); (b) the
  TF chain from ``map`` to the scan frame; (c) none. Wheel odometry (nav_msgs/Odometry
  topics, TF chains from ``odom``) drifts and is never taken for the map pose: without
  (a) or (b) the pose stream is empty, the pose kind ``none``, and the register stage
  runs LIDAR odometry (its verdict says why). A pose source set in the dataset is used
  as given (pose kind ``map``: the user's choice).

A bag whose TF has a ``map`` frame but no chain from it to the scan frame (the scan's
frame_id misspelt, empty or missing from TF; a loop; a frame with two parents) is an
error, not LIDAR odometry: the map frame says the recording has map poses, and placing
the scans by LIDAR odometry would silently move the map (issue 35).
"""

from __future__ import annotations

from pathlib import Path
from typing import Mapping

from floorscan.core.io import InputError
from floorscan.ingest.tf_chains import TfChainError, TfLink, tf_chain, tf_chain_from_root, tf_frames, walk_up


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


def short_type(msgtype: str) -> str:
    """A message type's last part: ``sensor_msgs/msg/LaserScan`` -> ``LaserScan``.

    Parameters
    ----------
    msgtype : str

    Returns
    -------
    str
    """
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
        return topic, f"scan topic {topic} (detected: the bag's one {short_type(msgtype)} topic, {n} messages)"
    if scans:
        raise InputError(
            f"{path}: several scan topics: {_listing(scans)}; set the dataset's 'scan_topic' to one of them"
        )
    raise InputError(
        f"{path}: no topic with sensor_msgs/LaserScan or sensor_msgs/PointCloud2 messages; "
        f"topics in the bag: {_listing(topics) or 'none'}{metadata_hint(path)}"
    )


def metadata_hint(path: Path | str) -> str:
    """For a ROS2 bag, where its topics' types and message counts come from: its
    ``metadata.yaml`` (rosbags reads them there), and what to do when it disagrees with
    the storage file.

    Parameters
    ----------
    path : path
        The bag folder or its storage file.

    Returns
    -------
    str
        A parenthesis to append to a message (leading space); empty when there is no
        ``metadata.yaml`` (a ROS1 bag).
    """
    p = Path(path)
    meta = p / "metadata.yaml" if p.is_dir() else p.parent / "metadata.yaml"
    if not meta.is_file():
        return ""
    return (f" (a ROS2 bag's topic types and message counts are those of its {meta}: when they disagree with "
            f"the storage file, regenerate it with `ros2 bag reindex {meta.parent}`)")


def is_odometry_frame(frame: str) -> bool:
    """Whether a pose's ``header.frame_id`` is an odometry frame (``odom``,
    ``odom_combined``, ``wheel_odom``, ...; REP 105): wheel odometry drifts, it is no map
    pose."""
    return "odom" in frame.lstrip("/").lower()


def detect_pose_source(
    topics: Mapping[str, tuple[str, int]],
    edges: Mapping[tuple[str, str], TfLink],
    scan_frame: str,
    path: Path | str = "",
    frames: Mapping[str, str] | None = None,
) -> tuple[dict | None, str, str]:
    """The map pose source of a bag, or none (see the module docstring for the order).

    Parameters
    ----------
    topics : mapping of str to (str, int)
        Topic -> (message type, message count).
    edges : mapping
        The bag's TF links (parent, child) -> link, as :func:`floorscan.ingest.tf_chains.read_tf` returns them.
    scan_frame : str
        Frame of the scans (no leading slash).
    frames : mapping of str to str, optional
        Pose topic -> its first message's ``header.frame_id``: a topic in an odometry
        frame (:func:`is_odometry_frame`) is not a map pose, and is named in the note.

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
        ``/amcl_pose`` (they are listed; set the dataset's ``pose``); or no pose topic
        and a ``map`` frame in TF without a chain to ``scan_frame`` (the message names
        the scan frame, why there is no chain, the frames TF has and its chains).
    """
    poses = {t: (m, n) for t, (m, n) in topics.items() if m in MAP_POSE_TYPES and n > 0}
    in_odom = sorted(t for t in poses if is_odometry_frame((frames or {}).get(t, "")))
    poses = {t: v for t, v in poses.items() if t not in in_odom}
    skipped = "".join(
        f"; {t} skipped: its frame_id is {(frames or {})[t]!r}, wheel odometry, not a map pose" for t in in_odom
    )
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
        phrase = f"topic {topic} ({short_type(msgtype)})"
        note = f"pose source {phrase} (detected: {why}, {n} messages{skipped})"
        return {"source": "topic", "topic": topic, "base_frame": "base_link"}, phrase, note
    if MAP_FRAME in tf_frames(edges) and scan_frame != MAP_FRAME:
        try:
            chain = tf_chain(edges, MAP_FRAME, scan_frame, path)
        except TfChainError as e:
            raise InputError(f"{e} {_no_fallback(e, edges, scan_frame)}") from None
        phrase = "TF " + " -> ".join([MAP_FRAME] + [e.child for e in chain])
        note = (f"pose source {phrase} (detected: no map pose topic, and the TF chain from {MAP_FRAME!r} to the scan "
                f"frame{skipped})")
        return {"source": "tf", "fixed_frame": MAP_FRAME}, phrase, note
    wheel = []
    root_chain = tf_chain_from_root(edges, scan_frame)
    if len(root_chain) > 1:
        wheel.append("TF " + " -> ".join(root_chain))
    odom = sorted([t for t, (m, n) in topics.items() if m == ODOMETRY_TYPE and n > 0] + in_odom)
    if odom:
        wheel.append(f"Odometry on {', '.join(odom)}")
    if wheel:
        phrase = f"none: wheel odometry only ({'; '.join(wheel)}); LIDAR odometry"
    else:
        phrase = "none: no pose topic and no TF; LIDAR odometry"
    _, kind, problem = walk_up(edges, scan_frame)
    broken = f"; the TF tree is broken: {problem}" if kind else ""
    note = (
        f"pose source none (detected: no PoseWithCovarianceStamped or PoseStamped topic and no {MAP_FRAME!r} "
        f"frame in TF{broken}{skipped}; wheel odometry drifts and is never taken for the map pose): "
        "the pose stream is empty (pose kind none) and the register stage runs LIDAR odometry"
    )
    if kind:
        phrase += f" ({problem})"
    return None, phrase, note


def _no_fallback(error: TfChainError, edges, scan_frame: str) -> str:
    """Why ingest stops on a bag with a map frame but no chain to the scan frame, and
    what the user can do."""
    how = "correct the frames in the bag (the scan's frame_id, or the TF links)"
    if error.kind == "elsewhere":
        root = tf_chain_from_root(edges, scan_frame)[0]
        how += (
            f", or name a pose source by hand in the dataset's 'pose': {{source: tf, fixed_frame: {root}}} "
            f"takes the chain from {root!r} for the map pose"
        )
    return (
        f"The bag has a {MAP_FRAME!r} frame, so it was recorded with map poses: ingest does not fall back "
        f"to LIDAR odometry on its own. To go on, {how}."
    )

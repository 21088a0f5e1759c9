"""Shared fixtures: tiny recordings written in every format floorscan reads.

The reference trajectory: the base drives along +x at ``SPEED`` m/s while turning at
``YAW_RATE`` rad/s, from (1, 2) with yaw 0.2 rad, for ``DURATION`` s. The laser sits
``MOUNT_X`` m ahead of and ``MOUNT_Z`` m above ``base_link``. Scans at 10 Hz; poses at
10 Hz with a phase offset (not synchronized with the scans, as AMCL in thesis 3.5).
"""

from __future__ import annotations

import functools
import gzip
import inspect
import math
import re
from pathlib import Path

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

REPO = Path(__file__).resolve().parents[1]

# Hypothesis runs derandomized (profile ``ci``: the same examples on every run, no example
# database) unless ``FLOORSCAN_HYPOTHESIS_PROFILE=dev`` asks for fresh random examples.
settings.register_profile(
    "ci", derandomize=True, deadline=None, database=None, print_blob=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
settings.register_profile("dev", deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
settings.load_profile(os.environ.get("FLOORSCAN_HYPOTHESIS_PROFILE", "ci"))
SHARED_DATA = (REPO / ".." / "shared" / "data").resolve()
needs_shared = pytest.mark.skipif(
    not SHARED_DATA.is_dir(), reason=f"real recordings not found at {SHARED_DATA} (../shared/data)"
)

T0_NS = 1_700_000_000_000_000_000
SPEED = 0.5
YAW_RATE = 0.1
YAW0 = 0.2
X0, Y0 = 1.0, 2.0
DURATION = 2.0
MOUNT_X, MOUNT_Z = 0.1, 0.3
N_BEAMS = 181


def base_pose(t_s):
    """Exact base_link pose (x, y, yaw) at time t_s seconds after T0: constant speed and turn rate."""
    t = np.asarray(t_s, dtype=np.float64)
    yaw = YAW0 + YAW_RATE * t
    # integral of v*(cos, sin)(yaw0 + w t)
    x = X0 + SPEED / YAW_RATE * (np.sin(yaw) - math.sin(YAW0))
    y = Y0 - SPEED / YAW_RATE * (np.cos(yaw) - math.cos(YAW0))
    return x, y, yaw


def laser_pose(t_s):
    x, y, yaw = base_pose(t_s)
    return x + MOUNT_X * np.cos(yaw), y + MOUNT_X * np.sin(yaw), yaw


def scan_ranges(i: int) -> np.ndarray:
    """Ranges of scan i: 181 beams over 180 deg with a NaN, an inf and two out-of-range beams."""
    r = np.linspace(1.0, 3.0, N_BEAMS).astype(np.float32) + 0.01 * i
    r[0] = np.nan
    r[1] = np.inf
    r[2] = 0.01  # below range_min 0.05
    r[3] = 40.0  # above range_max 30
    return r


def _time(ts, t_ns):
    Time = ts.types["builtin_interfaces/msg/Time"]
    return Time(sec=int(t_ns // 1_000_000_000), nanosec=int(t_ns % 1_000_000_000))


def _header(ts, t_ns, frame, ros1):
    Header = ts.types["std_msgs/msg/Header"]
    if ros1:
        return Header(seq=0, stamp=_time(ts, t_ns), frame_id=frame)
    return Header(stamp=_time(ts, t_ns), frame_id=frame)


def _quat(yaw):
    return 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


def _bag_writer(path: Path, ros2: bool):
    """(typestore, its types, serializer, writer) of a ROS1 bag or ROS2 bag folder."""
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE if ros2 else Stores.ROS1_NOETIC)
    if "tf2_msgs/msg/TFMessage" not in ts.types:  # the Noetic store lacks tf2_msgs
        from rosbags.typesys import get_types_from_msg

        ts.register(get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage"))
    if ros2:
        from rosbags.rosbag2 import Writer

        return ts, ts.types, ts.serialize_cdr, Writer(path, version=9)
    from rosbags.rosbag1 import Writer

    return ts, ts.types, ts.serialize_ros1, Writer(path)


def _scan_message(ts, t_ns: int, frame: str, r: np.ndarray, ros2: bool, cloud: bool, z: float = 0.0):
    """A LaserScan of ranges ``r`` over 180 degrees (range 0.05-30 m), or the same beams
    as a PointCloud2 of float32 x, y, z (z = ``z``)."""
    T = ts.types
    header = _header(ts, t_ns, frame, not ros2)
    if cloud:
        ang = -math.pi / 2 + np.arange(r.size) * math.pi / (r.size - 1)
        xyz = np.stack([r * np.cos(ang), r * np.sin(ang), np.full(r.size, z, np.float32)], 1).astype("<f4")
        fields = [T["sensor_msgs/msg/PointField"](name=n, offset=4 * k, datatype=7, count=1) for k, n in enumerate("xyz")]
        return T["sensor_msgs/msg/PointCloud2"](
            header=header, height=1, width=r.size, fields=fields, is_bigendian=False, point_step=12,
            row_step=12 * r.size, data=np.frombuffer(xyz.tobytes(), np.uint8), is_dense=False,
        )
    return T["sensor_msgs/msg/LaserScan"](
        header=header, angle_min=-math.pi / 2, angle_max=math.pi / 2, angle_increment=math.pi / (r.size - 1),
        time_increment=0.0, scan_time=0.1, range_min=0.05, range_max=30.0, ranges=r,
        intensities=np.zeros(0, np.float32),
    )


def _write_messages(writer, ts, ser, msgs) -> None:
    """Write (t_ns, topic, message) tuples in time order, a connection per topic; a
    tuple (t_ns, topic, message, data) writes the bytes ``data`` instead of the
    message's serialization, unless ``data`` is None (an undecodable message)."""
    msgs.sort(key=lambda m: m[0])
    with writer:
        conns = {}
        for t, topic, msg, *data in msgs:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msg.__msgtype__, typestore=ts)
            raw = data[0] if data and data[0] is not None else ser(msg, msg.__msgtype__)
            writer.write(conns[topic], t, raw)


def write_bag(
    path: Path,
    ros2: bool = False,
    pointcloud: bool = False,
    pose_offset_s: float = 0.05,
    pose_shift_s: float = 0.0,
    n_scans: int = 20,
    amcl_order: str = "sorted",
) -> Path:
    """Write a tiny bag: /scan, /amcl_pose, /odom, /tf (map->odom, odom->base_link), /tf_static.

    ``pose_shift_s`` moves every pose stamp (to build non-overlapping streams);
    ``amcl_order`` "duplicate" or "unsorted" breaks the /amcl_pose stamps.
    """
    ts, T, ser, writer = _bag_writer(path, ros2)
    msgs = []  # (t_ns, topic, msg)
    for i in range(n_scans):
        t = T0_NS + int(i * 0.1e9)
        msgs.append((t, "/scan", _scan_message(ts, t, "laser", scan_ranges(i), ros2, pointcloud, z=0.5)))
    n_pose = int(round(DURATION / 0.1)) + 2
    stamps = [T0_NS + int((pose_offset_s - 0.1 + k * 0.1 + pose_shift_s) * 1e9) for k in range(n_pose)]
    header_stamps = list(stamps)  # /amcl_pose header stamps; the bag's own times stay sorted
    if amcl_order == "duplicate":
        header_stamps[5] = header_stamps[4]
    elif amcl_order == "unsorted":
        header_stamps[5], header_stamps[6] = header_stamps[6], header_stamps[5]
    Pose, Point, Q = T["geometry_msgs/msg/Pose"], T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Quaternion"]
    Vec = T["geometry_msgs/msg/Vector3"]
    for k, t in enumerate(stamps):
        x, y, yaw = base_pose((t - T0_NS) / 1e9)
        pose = Pose(position=Point(x=float(x), y=float(y), z=0.0), orientation=Q(*_quat(float(yaw))))
        cov = np.zeros(36)
        msgs.append((t, "/amcl_pose", T["geometry_msgs/msg/PoseWithCovarianceStamped"](
            header=_header(ts, header_stamps[k], "map", not ros2),
            pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=cov))))
        msgs.append((t, "/odom", T["nav_msgs/msg/Odometry"](
            header=_header(ts, t, "odom", not ros2), child_frame_id="base_link",
            pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=cov),
            twist=T["geometry_msgs/msg/TwistWithCovariance"](
                twist=T["geometry_msgs/msg/Twist"](linear=Vec(x=0.0, y=0.0, z=0.0), angular=Vec(x=0.0, y=0.0, z=0.0)),
                covariance=cov))))
        tf = []
        for parent, child, (tx, ty, tyaw) in (("map", "odom", (0.0, 0.0, 0.0)), ("odom", "base_link", (x, y, yaw))):
            tf.append(T["geometry_msgs/msg/TransformStamped"](
                header=_header(ts, t, parent, not ros2), child_frame_id=child,
                transform=T["geometry_msgs/msg/Transform"](
                    translation=Vec(x=float(tx), y=float(ty), z=0.0), rotation=Q(*_quat(float(tyaw))))))
        msgs.append((t, "/tf", T["tf2_msgs/msg/TFMessage"](transforms=tf)))
    static = T["tf2_msgs/msg/TFMessage"](transforms=[T["geometry_msgs/msg/TransformStamped"](
        header=_header(ts, T0_NS, "base_link", not ros2), child_frame_id="laser",
        transform=T["geometry_msgs/msg/Transform"](
            translation=Vec(x=MOUNT_X, y=0.0, z=MOUNT_Z), rotation=Q(0.0, 0.0, 0.0, 1.0)))])
    msgs.append((T0_NS - 1, "/tf_static", static))
    _write_messages(writer, ts, ser, msgs)
    return path


@pytest.fixture(scope="session")
def ros1_bag(tmp_path_factory) -> Path:
    return write_bag(tmp_path_factory.mktemp("bags") / "tiny.bag")


@pytest.fixture(scope="session")
def ros2_bag(tmp_path_factory) -> Path:
    return write_bag(tmp_path_factory.mktemp("bags2") / "tiny_ros2", ros2=True)


def cast_rays(segments: np.ndarray, origin, angles: np.ndarray) -> np.ndarray:
    """The range of each ray from ``origin`` (x, y) at ``angles`` (radians, map frame) to
    the nearest of ``segments`` ((S, 2, 2) or (S, 4), metres); inf where it hits none.
    The tests' 2D ray caster (the simulator's is floorscan.sim.raycast, in 3D)."""
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    d = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    a, e = seg[:, :2], seg[:, 2:] - seg[:, :2]
    w = a[None] - np.asarray(origin, dtype=np.float64)[:2]
    den = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (w[..., 0] * e[None, :, 1] - w[..., 1] * e[None, :, 0]) / den
        u = (w[..., 0] * d[:, None, 1] - w[..., 1] * d[:, None, 0]) / den
    t = np.where((np.abs(den) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1), t, np.inf)
    return t.min(axis=1) if len(seg) else np.full(len(d), np.inf)


def write_room_bag(
    path: Path,
    ranges,
    n: int = 30,
    ros2: bool = False,
    cloud: bool = False,
    change=None,
    raw=None,
    stamps: list[int] | None = None,
    scan_frame: str = "laser",
    links: tuple[tuple[str, str], ...] = (("map", "odom"), ("odom", "base_link")),
    static: tuple[tuple[str, str], ...] = (("base_link", "laser"),),
    map_until_s: float | None = None,
    pose_topic: bool = False,
    still: bool = False,
    mount_roll: float = 0.0,
    pose_frame: str = "map",
    mounts: dict[str, tuple[float, float, float]] | None = None,
    map_jump: tuple[float, float] | None = None,
) -> Path:
    """A bag (ROS1 file, or ROS2 folder with ``ros2``) of ``n`` scans on ``/scan`` at
    10 Hz along :func:`base_pose`: LaserScans of ``ranges(i)`` (181 beams over 180
    degrees, range 0.05-30 m), or the same beams as PointCloud2 (``cloud``), frame
    ``scan_frame``.

    TF: the ``links`` on /tf at 10 Hz, half a period off the scans (``map -> odom`` a slow
    drift correction, so it is no static link, ending after ``map_until_s`` seconds (the
    localizer stopped); any other link the base pose), the ``static`` links (the laser's
    mount) on /tf_static (no /tf_static topic when there are none, no /tf when ``links``
    is empty). ``pose_topic``: the base pose on /amcl_pose as well (in ``pose_frame``). ``still``:
    the robot never moves (every link sends one pose over and over). ``mount_roll``: the
    static links' roll, radians (pi: the scanner mounted upside down, whose ranges are
    then the level scanner's in reverse order). ``change(i, msg)``
    edits scan ``i``'s message; ``raw(i)`` gives bytes stored instead of its
    serialization (or None); ``stamps``: the scans' header stamps (the bag's own times
    stay in order). ``mounts``: child frame -> (x, y, yaw) of its static link (metres,
    radians; the others at ``MOUNT_X``). ``map_jump``: (t_s, dx): ``map -> odom`` jumps
    ``dx`` metres along x from ``t_s`` seconds on and stays there (a localizer that
    relocalises).
    """
    ts, T, ser, writer = _bag_writer(path, ros2)
    mounts = mounts or {}
    Vec, Q = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]

    def transform(parent, child, t, x, y, yaw, z=0.0, roll=0.0):
        q = _quat(float(yaw)) if roll == 0.0 else (math.sin(roll / 2.0), 0.0, 0.0, math.cos(roll / 2.0))
        return T["geometry_msgs/msg/TransformStamped"](
            header=_header(ts, t, parent, not ros2), child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](
                translation=Vec(x=float(x), y=float(y), z=float(z)), rotation=Q(*q)))

    msgs = [(T0_NS - 1, "/tf_static", T["tf2_msgs/msg/TFMessage"](
        transforms=[transform(p, c, T0_NS, *mounts.get(c, (MOUNT_X, 0.0, 0.0)), MOUNT_Z, mount_roll) for p, c in static]))] if static else []
    for i in range(n):
        t = T0_NS + int(i * 0.1e9)
        msg = _scan_message(ts, t if stamps is None else stamps[i], scan_frame, ranges(i), ros2, cloud)
        if change is not None:
            change(i, msg)
        msgs.append((t, "/scan", msg, raw(i) if raw is not None else None))
    for k in range(n + 2):
        t_s = k * 0.1 - 0.05
        t = T0_NS + int(t_s * 1e9)
        x, y, yaw = base_pose(0.0 if still else t_s)
        tf = []
        for p, c in links:
            if (p, c) == ("map", "odom"):
                if map_until_s is None or t_s <= map_until_s:
                    jump = map_jump[1] if map_jump is not None and t_s >= map_jump[0] else 0.0
                    tf.append(transform(p, c, t, (0.0 if still else 1e-4 * k) + jump, 0.0, 0.0))
            else:
                tf.append(transform(p, c, t, x, y, yaw))
        if tf:
            msgs.append((t, "/tf", T["tf2_msgs/msg/TFMessage"](transforms=tf)))
        if pose_topic:
            pose = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=float(x), y=float(y), z=0.0),
                                               orientation=Q(*_quat(float(yaw))))
            msgs.append((t, "/amcl_pose", T["geometry_msgs/msg/PoseWithCovarianceStamped"](
                header=_header(ts, t, pose_frame, not ros2),
                pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)))))
    _write_messages(writer, ts, ser, msgs)
    return path


def write_carmen(path: Path, lines: list[str]) -> Path:
    data = "\n".join(lines) + "\n"
    if path.suffix == ".gz":
        with gzip.open(path, "wt") as f:
            f.write(data)
    else:
        path.write_text(data)
    return path


def flaser_line(ranges, pose, t_s) -> str:
    r = " ".join(f"{v:.3f}" for v in ranges)
    x, y, th = pose
    return f"FLASER {len(ranges)} {r} {x} {y} {th} {x} {y} {th} {t_s} pippo {t_s}"


def robotlaser_line(ranges, pose, t_s, start=-math.pi / 2, fov=math.pi, res=None) -> str:
    """A ROBOTLASER1 line (CARMEN layout, no remissions); ``res`` defaults to fov / (n - 1)."""
    n = len(ranges)
    res = fov / (n - 1) if res is None else res
    r = " ".join(f"{v:.3f}" for v in ranges)
    x, y, th = pose
    return (f"ROBOTLASER1 0 {start} {fov} {res} 30.0 0.01 0 {n} {r} 0 {x} {y} {th} {x} {y} {th} "
            f"0 0 0.5 0.3 0 {t_s} host {t_s}")


def write_detection_bag(
    path: Path,
    scan_topics: tuple[str, ...] = ("/scan",),
    pose_topics: tuple[str, ...] = (),
    tf_links: tuple[tuple[str, str], ...] = (("odom", "base_link"),),
    odom_topics: tuple[str, ...] = ("/odom",),
    frame_prefix: str = "",
    ranges=None,
    n_scans: int = 10,
    ros2: bool = False,
) -> Path:
    """Write a bag for detecting the scan topic and pose source.

    Parameters
    ----------
    scan_topics : tuple of str
        Topics carrying the LaserScan of each scan (frame ``laser``, 181 beams,
        range 0.05-30 m); topics ending in ``_cloud`` carry a PointCloud2 instead.
    pose_topics : tuple of str
        PoseWithCovarianceStamped topics (frame ``map``) with the base pose at 10 Hz.
    tf_links : tuple of (str, str)
        Moving /tf links at 10 Hz: ``("map", "odom")`` is the identity, any other link
        carries the base pose. A static ``base_link -> laser`` mount is on /tf_static.
    odom_topics : tuple of str
        nav_msgs/Odometry topics (frame ``odom``) with the base pose.
    frame_prefix : str
        Put before every TF and header frame name (``"/"`` as old ROS1 bags do).
    ranges : callable, optional
        ``ranges(i)`` -> (181,) float32 ranges of scan ``i``; default :func:`scan_ranges`.
    """
    ts, T, ser, writer = _bag_writer(path, ros2)
    ranges = ranges or scan_ranges

    def f(name):
        return frame_prefix + name

    Pose, Point, Q = T["geometry_msgs/msg/Pose"], T["geometry_msgs/msg/Point"], T["geometry_msgs/msg/Quaternion"]
    Vec, cov = T["geometry_msgs/msg/Vector3"], np.zeros(36)

    def transform(parent, child, t, x, y, yaw, z=0.0):
        return T["geometry_msgs/msg/TransformStamped"](
            header=_header(ts, t, f(parent), not ros2), child_frame_id=f(child),
            transform=T["geometry_msgs/msg/Transform"](
                translation=Vec(x=float(x), y=float(y), z=float(z)), rotation=Q(*_quat(float(yaw)))))

    msgs = [(T0_NS - 1, "/tf_static", T["tf2_msgs/msg/TFMessage"](
        transforms=[transform("base_link", "laser", T0_NS, MOUNT_X, 0.0, 0.0, MOUNT_Z)]))]
    for i in range(n_scans):
        t = T0_NS + int(i * 0.1e9)
        r = np.asarray(ranges(i), dtype=np.float32)
        for topic in scan_topics:
            msgs.append((t, topic, _scan_message(ts, t, f("laser"), r, ros2, topic.endswith("_cloud"))))
    for k in range(n_scans + 2):
        t = T0_NS + int((k * 0.1 - 0.05) * 1e9)
        x, y, yaw = base_pose((t - T0_NS) / 1e9)
        pose = Pose(position=Point(x=float(x), y=float(y), z=0.0), orientation=Q(*_quat(float(yaw))))
        for topic in pose_topics:
            msgs.append((t, topic, T["geometry_msgs/msg/PoseWithCovarianceStamped"](
                header=_header(ts, t, f("map"), not ros2),
                pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=cov))))
        for topic in odom_topics:
            msgs.append((t, topic, T["nav_msgs/msg/Odometry"](
                header=_header(ts, t, f("odom"), not ros2), child_frame_id=f("base_link"),
                pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=cov),
                twist=T["geometry_msgs/msg/TwistWithCovariance"](
                    twist=T["geometry_msgs/msg/Twist"](
                        linear=Vec(x=0.0, y=0.0, z=0.0), angular=Vec(x=0.0, y=0.0, z=0.0)),
                    covariance=cov))))
        if tf_links:
            msgs.append((t, "/tf", T["tf2_msgs/msg/TFMessage"](transforms=[
                transform(p, c, t, 0.0, 0.0, 0.0) if (p, c) == ("map", "odom") else transform(p, c, t, x, y, yaw)
                for p, c in tf_links])))
    _write_messages(writer, ts, ser, msgs)
    return path


# The whole workflow in a copy of its files (tests/test_workflow.py, test_reproducible.py,
# test_cluster.py): the repository's results/ is never touched.
SNAKEMAKE = Path(__import__("sys").executable).with_name("snakemake")


def copy_workflow(dest: Path) -> Path:
    """Copy the Snakefile, workflow/, config/ and scripts/ to ``dest`` (made), with
    ``../shared`` beside it when the shared recordings exist."""
    import shutil

    dest.mkdir(parents=True)
    for name in ("Snakefile", "workflow", "config", "scripts"):
        src = REPO / name
        if src.is_dir():
            shutil.copytree(src, dest / name)
        else:
            shutil.copy2(src, dest / name)
    # keep the shipped relative paths to ../shared/data valid from the copy
    if SHARED_DATA.is_dir() and not (dest.parent / "shared").exists():
        (dest.parent / "shared").symlink_to(SHARED_DATA.parent)
    return dest


def snakemake(workdir: Path, *args, timeout=900):
    """``snakemake --cores 2 *args`` in ``workdir``; the CompletedProcess."""
    import subprocess

    return subprocess.run(
        [str(SNAKEMAKE), "--cores", "2", *args], cwd=workdir, capture_output=True, text=True, timeout=timeout
    )


@pytest.fixture(scope="session")
def demo_run(tmp_path_factory):
    """The demo's default target run once for the session, in a copy of the workflow;
    the workflow folder. Tests may run more targets in it, not delete its files."""
    wd = copy_workflow(tmp_path_factory.mktemp("wf") / "floorscan")
    res = snakemake(wd)
    assert res.returncode == 0, res.stderr[-4000:]
    return wd


@pytest.fixture(scope="session")
def survey_run(demo_run):
    """A folder of recordings run once for the session in the demo's workflow copy, as
    the README's folder commands (docs/running.md) run it: ``survey/`` holds the demo's recording twice
    (``ground.bag``, ``first.bag``), a truncated copy (``broken.bag``) and a text file,
    run with ``--config path=<survey>/ --configfile house.yaml`` (the docs'
    house.yaml block: the two good recordings are the floors of one building) and the
    repository's default profile (keep-going). Then ``broken.bag`` is moved out, so the
    README's commands on the folder (tests/test_readme.py) find its two recordings
    built (the same paths: the same datasets) and succeed.

    Returns (workflow folder, the run's CompletedProcess, the dry-run job graph of the
    folder with broken.bag in it as ``snakemake --dag`` prints it, the folder)."""
    import re
    import shutil

    wd = demo_run
    folder = wd / "survey"
    folder.mkdir()
    bag = wd / "results" / "demo" / "sim" / "recording.bag"
    for name in ("ground.bag", "first.bag"):
        shutil.copy2(bag, folder / name)
    (folder / "broken.bag").write_bytes(bag.read_bytes()[:300_000])
    (folder / "notes.txt").write_text("taken on Tuesday")
    pages = [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]  # where tests/test_readme.py reads commands
    house = next(b for page in pages for b in re.findall(r"```yaml\n(.*?)```", page.read_text(), re.S)
                 if b.startswith("# house.yaml\n"))
    (wd / "house.yaml").write_text(house)
    path = f"path={folder}/"
    res = snakemake(wd, "--workflow-profile", "workflow/profiles/default", "--config", path, "--configfile", "house.yaml")
    dag = snakemake(wd, "-n", "--forceall", "--dag", "--config", path)
    (folder / "broken.bag").rename(wd / "broken.bag")
    return wd, res, dag, folder


# Test tiers: the markers of pyproject.toml, set here from what a test uses, so that a new
# test lands in its tier by itself (`make test-fast` runs -m "not workflow and not
# realdata and not slow"; `make test` runs everything).
#   workflow: a fixture of the session's demo run (WORKFLOW_FIXTURES), or a call of
#             snakemake() or copy_workflow(), or SNAKEMAKE, in the test's own body;
#   realdata: the needs_shared skip marker (any skipif naming ../shared/data), or
#             SHARED_DATA in the test's own body.
# A test that runs Snakemake or reads ../shared through a helper of its module carries the
# marker in its file, as does a slow test (measured by pytest --durations: 2.5 s or more
# on 2 idle cores, which is 4 s or more while the machine is shared).
WORKFLOW_FIXTURES = {"demo_run", "default_run", "survey_run"}
_RUNS_WORKFLOW = re.compile(r"\b(?:snakemake|copy_workflow)\(|\bSNAKEMAKE\b")
_READS_SHARED = re.compile(r"\bSHARED_DATA\b")


@functools.cache
def _source(function) -> str:
    try:
        return inspect.getsource(function)
    except (OSError, TypeError):
        return ""


def _needs_shared(item) -> bool:
    return any("../shared/data" in str(m.kwargs.get("reason", "")) for m in item.iter_markers("skipif"))


@pytest.hookimpl(tryfirst=True)  # before -m deselects by these markers
def pytest_collection_modifyitems(items):
    for item in items:
        body = _source(getattr(item, "function", None))
        if WORKFLOW_FIXTURES & set(item.fixturenames) or _RUNS_WORKFLOW.search(body):
            item.add_marker(pytest.mark.workflow)
        if _needs_shared(item) or _READS_SHARED.search(body):
            item.add_marker(pytest.mark.realdata)

import gzip
import math
import shutil

import numpy as np
import pytest

from conftest import (
    DURATION,
    MOUNT_Z,
    N_BEAMS,
    SHARED_DATA,
    T0_NS,
    flaser_line,
    laser_pose,
    needs_shared,
    scan_ranges,
    write_bag,
    write_carmen,
)
from floorscan.ingest.readers import open_recording
from floorscan.ingest.writer import write_recording
from floorscan.core.io import InputError, read_table
from floorscan.ingest.poses import scan_poses


def ingest(ds, out, cfg=None, max_gap_s=0.5, sensor_height_m=0.0):
    """Run ingest + poses like the workflow does; return (index, stream, scans, poses)."""
    rec = open_recording(ds, cfg or {}, max_gap_s=max_gap_s)
    index = write_recording(
        rec, out / "scans.parquet", out / "scan_index.parquet", out / "pose_stream.parquet", sensor_height_m
    )
    stream = read_table(out / "pose_stream.parquet")
    poses = scan_poses(index, stream, max_gap_s, "stream")
    return index, stream, read_table(out / "scans.parquet"), poses


def assert_poses_match_truth(index, poses, n_expected):
    assert poses["valid"].sum() == n_expected
    v = poses[poses["valid"]]
    x, y, yaw = laser_pose((v["t_ns"].to_numpy() - T0_NS) / 1e9)
    # linear interpolation of a 0.1 rad/s arc between 0.1 s samples: chord error < 1e-4 m
    np.testing.assert_allclose(v["x"], x, atol=2e-4)
    np.testing.assert_allclose(v["y"], y, atol=2e-4)
    np.testing.assert_allclose(v["yaw"], yaw, atol=1e-6)


BAG_DS = {"format": "rosbag", "scan_topic": "/scan"}


@pytest.mark.parametrize(
    "pose",
    [
        {"source": "topic", "topic": "/amcl_pose", "base_frame": "base_link"},
        {"source": "tf", "fixed_frame": "map"},
        {"source": "topic", "topic": "/odom", "base_frame": "base_link"},
    ],
    ids=["amcl_pose", "tf_chain", "odometry"],
)
def test_ros1_bag_scans_and_poses(ros1_bag, tmp_path, pose):
    index, stream, scans, poses = ingest({**BAG_DS, "path": str(ros1_bag), "pose": pose}, tmp_path)
    assert len(index) == 20
    # NaN, inf, 0.01 m (< range_min) and 40 m (> range_max) are dropped and counted
    assert index["n_dropped"].tolist() == [4] * 20
    assert index["n_points"].tolist() == [N_BEAMS - 4] * 20
    assert len(scans) == 20 * (N_BEAMS - 4)
    assert index["frame"].unique().tolist() == ["laser"]
    assert np.all(np.diff(index["t_ns"]) == int(0.1e9))
    # the laser's mount (0.1 m ahead, 0.3 m up) comes from /tf_static
    np.testing.assert_allclose(stream["z"], MOUNT_Z)
    # amcl/odom stamps start 0.05 s before the first scan and go on past the last
    assert_poses_match_truth(index, poses, 20)
    # beam 90 of scan 0 points straight ahead at 2.0 m
    s0 = scans[scans["scan_id"] == 0]
    ahead = s0.iloc[90 - 4]
    assert ahead["x"] == pytest.approx(scan_ranges(0)[90], abs=1e-5)
    assert ahead["y"] == pytest.approx(0.0, abs=1e-5)


def test_ros2_bag_with_tf_and_odometry(ros2_bag, tmp_path):
    ds = {**BAG_DS, "path": str(ros2_bag), "pose": {"source": "tf", "fixed_frame": "odom"}}
    index, stream, scans, poses = ingest(ds, tmp_path)
    assert len(index) == 20 and index["n_dropped"].sum() == 80
    assert_poses_match_truth(index, poses, 20)


def test_pointcloud2_scans(tmp_path):
    bag = write_bag(tmp_path / "pc2.bag", pointcloud=True, n_scans=5)
    pose = {"source": "topic", "topic": "/amcl_pose"}
    index, _, scans, _ = ingest({**BAG_DS, "path": str(bag), "pose": pose}, tmp_path)
    assert index["n_dropped"].tolist() == [2] * 5  # NaN and inf; no range limits set
    np.testing.assert_allclose(scans["z"], 0.5)
    out2 = tmp_path / "limited"
    out2.mkdir()
    # range limits apply to the 3D distance: the 0.01 m beam sits 0.5 m below the scanner
    index2, *_ = ingest({**BAG_DS, "path": str(bag), "pose": pose, "range_min_m": 0.6, "range_max_m": 30.0}, out2)
    assert index2["n_dropped"].tolist() == [4] * 5


def test_carmen_flaser_geometry_and_poses(tmp_path):
    log = write_carmen(
        tmp_path / "a.log.gz",
        [
            "# comment",
            "PARAM robot_frontlaser_offset 0.0 nohost 0",
            flaser_line([1.0] * 180, (1.0, 2.0, 0.5), 10.0),
            "ODOM 0 0 0 0 0 0 10.05 pippo 10.05",
            flaser_line([2.0] * 90 + [81.83] * 90, (1.5, 2.0, 0.6), 10.2),
            flaser_line([1.0] * 181, (2.0, 2.0, 0.7), 10.4),
        ],
    )
    index, stream, scans, poses = ingest({"format": "carmen", "path": str(log)}, tmp_path, {"carmen_max_range_m": 50.0})
    assert index["n_points"].tolist() == [180, 90, 181]
    assert index["n_dropped"].tolist() == [0, 90, 0]
    assert index["t_ns"].tolist() == [10_000_000_000, 10_200_000_000, 10_400_000_000]
    np.testing.assert_allclose(poses["x"], [1.0, 1.5, 2.0])
    np.testing.assert_allclose(poses["yaw"], [0.5, 0.6, 0.7])
    s0 = scans[scans.scan_id == 0][["x", "y"]].to_numpy()
    # 180 beams over 180 deg: -90 deg, then 1 deg steps; beam 90 straight ahead
    np.testing.assert_allclose(s0[0], [0.0, -1.0], atol=1e-6)
    np.testing.assert_allclose(s0[90], [1.0, 0.0], atol=1e-6)
    s2 = scans[scans.scan_id == 2][["x", "y"]].to_numpy()
    # 181 beams: both ends included
    np.testing.assert_allclose(s2[-1], [0.0, 1.0], atol=1e-6)


def test_carmen_all_zero_stamps_and_out_of_order_lines(tmp_path):
    log = write_carmen(tmp_path / "z.log", [flaser_line([1.0] * 180, (i, 0, 0), 0) for i in range(3)])
    index, *_ = ingest({"format": "carmen", "path": str(log)}, tmp_path, {"missing_time_period_s": 0.2})
    assert index["t_ns"].tolist() == [0, 200_000_000, 400_000_000]
    out = tmp_path / "o"
    out.mkdir()
    log2 = write_carmen(tmp_path / "o.log", [flaser_line([1.0] * 180, (i, 0, 0), t) for i, t in enumerate([1.0, 1.5, 1.2])])
    index2, _, _, poses2 = ingest({"format": "carmen", "path": str(log2)}, out)
    assert index2["t_ns"].tolist() == [1_000_000_000, 1_200_000_000, 1_500_000_000]
    assert poses2["x"].tolist() == [0.0, 2.0, 1.0]  # each scan keeps its own pose


def test_pcd_folder_round_trip(tmp_path):
    import open3d as o3d

    folder = tmp_path / "pcd"
    folder.mkdir()
    rng = np.random.default_rng(0)
    local = [rng.uniform(-3, 3, (50, 3)) for _ in range(3)]
    locs = [(0.0, 0.0, 0.4, 0.0), (1.0, 2.0, 0.4, math.pi / 2), (2.0, -1.0, 0.4, -3.0)]
    rows = ["file,t_ns,x,y,z,yaw"]
    for i, (p, (x, y, z, yaw)) in enumerate(zip(local, locs)):
        c, s = math.cos(yaw), math.sin(yaw)
        world = np.c_[c * p[:, 0] - s * p[:, 1] + x, s * p[:, 0] + c * p[:, 1] + y, p[:, 2] + z]
        if i == 1:
            world[0] = np.nan
        pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(world))
        o3d.io.write_point_cloud(str(folder / f"{i:04d}.pcd"), pc)
        rows.append(f"{i:04d}.pcd,{1000 + i * 100},{x},{y},{z},{yaw}")
    (folder / "locations.csv").write_text("\n".join(rows) + "\n")
    index, stream, scans, poses = ingest({"format": "pcd", "path": str(folder)}, tmp_path)
    assert index["n_points"].tolist() == [50, 49, 50]
    assert index["n_dropped"].tolist() == [0, 1, 0]
    got = scans[scans.scan_id == 2][["x", "y", "z"]].to_numpy()
    np.testing.assert_allclose(got, local[2], atol=1e-5)
    np.testing.assert_allclose(poses["yaw"], [0.0, math.pi / 2, -3.0], atol=1e-12)


# --- bad input: one clear message, no output left behind -------------------------------


def ingest_fails(ds, tmp_path, match, cfg=None):
    out = tmp_path / "out"
    out.mkdir(exist_ok=True)
    with pytest.raises(InputError, match=match):
        ingest(ds, out, cfg)
    assert list(out.iterdir()) == [], "a failed ingest must leave no file behind"


def test_missing_file(tmp_path):
    ingest_fails({"format": "carmen", "path": str(tmp_path / "nope.log")}, tmp_path, r"nope.log: recording not found")


def test_bag_without_the_topic_lists_topics(ros1_bag, tmp_path):
    ds = {"format": "rosbag", "path": str(ros1_bag), "scan_topic": "/base_scan", "pose": {"source": "tf"}}
    ingest_fails(ds, tmp_path, r"no topic '/base_scan' for scans; topics in the bag: .*/amcl_pose \(geometry_msgs/msg/PoseWithCovarianceStamped\).*/scan \(sensor_msgs/msg/LaserScan\)")


def test_unsupported_message_type(ros1_bag, tmp_path):
    ds = {"format": "rosbag", "path": str(ros1_bag), "scan_topic": "/odom", "pose": {"source": "tf", "fixed_frame": "map"}}
    ingest_fails(ds, tmp_path, r"topic '/odom' carries nav_msgs/msg/Odometry; expected one of sensor_msgs/msg/LaserScan")
    ds = {"format": "rosbag", "path": str(ros1_bag), "scan_topic": "/scan", "pose": {"source": "topic", "topic": "/scan"}}
    ingest_fails(ds, tmp_path, r"topic '/scan' carries sensor_msgs/msg/LaserScan; expected one of geometry_msgs")


def test_truncated_bag(ros1_bag, tmp_path):
    data = ros1_bag.read_bytes()
    bad = tmp_path / "truncated.bag"
    bad.write_bytes(data[: len(data) // 2])
    ds = {"format": "rosbag", "path": str(bad), "scan_topic": "/scan", "pose": {"source": "topic", "topic": "/amcl_pose"}}
    ingest_fails(ds, tmp_path, r"truncated.bag: cannot read .*truncated or corrupt")


def test_corrupt_and_empty_carmen_logs(tmp_path):
    good = write_carmen(tmp_path / "g.log.gz", [flaser_line([1.0] * 180, (0, 0, 0), t) for t in range(200)])
    data = good.read_bytes()
    (tmp_path / "cut.log.gz").write_bytes(data[: len(data) // 2])
    ingest_fails({"format": "carmen", "path": str(tmp_path / "cut.log.gz")}, tmp_path, r"cut.log.gz: cannot read the log, truncated or corrupt")
    write_carmen(tmp_path / "odom.log", ["ODOM 0 0 0 0 0 0 1.0 pippo 1.0"] * 3)
    ingest_fails({"format": "carmen", "path": str(tmp_path / "odom.log")}, tmp_path, r"odom.log: no laser lines; expected FLASER or ROBOTLASER1 lines \(message types found: ODOM \(3\)\)")
    write_carmen(tmp_path / "short.log", ["FLASER 180 1.0 1.0 1.0"])
    ingest_fails({"format": "carmen", "path": str(tmp_path / "short.log")}, tmp_path, r"short.log:1: malformed FLASER line")


def test_pose_stream_not_overlapping_scans(tmp_path):
    bag = write_bag(tmp_path / "late.bag", pose_shift_s=100.0, n_scans=5)
    ds = {"format": "rosbag", "path": str(bag), "scan_topic": "/scan", "pose": {"source": "topic", "topic": "/amcl_pose"}}
    out = tmp_path / "o"
    out.mkdir()
    with pytest.raises(InputError, match="does not overlap the scans"):
        ingest(ds, out)


def test_duplicate_pose_stamps(tmp_path):
    bag = write_bag(tmp_path / "duplicate.bag", amcl_order="duplicate", n_scans=5)
    ds = {"format": "rosbag", "path": str(bag), "scan_topic": "/scan", "pose": {"source": "topic", "topic": "/amcl_pose"}}
    ingest_fails(ds, tmp_path, r"pose topic '/amcl_pose' header stamps have a.*duplicate stamp")


def test_two_swapped_pose_stamps_are_sorted(tmp_path):
    """Issue 35: two swapped stamps are sorted with a note, as a CARMEN log's lines are
    (they aborted the bag before); tests/test_bad_input_frames.py has more."""
    bag = write_bag(tmp_path / "unsorted.bag", amcl_order="unsorted", n_scans=5)
    ds = {"format": "rosbag", "path": str(bag), "scan_topic": "/scan", "pose": {"source": "topic", "topic": "/amcl_pose"}}
    rec = open_recording(ds, {}, 0.5)
    assert any("1 of 22 messages stamped earlier than the message before them (messages [6])" in n for n in rec.notes)
    assert np.all(np.diff(rec.pose_stream["t_ns"].to_numpy()) > 0)


def test_tf_chain_missing_frame(ros1_bag, tmp_path):
    ds = {"format": "rosbag", "path": str(ros1_bag), "scan_topic": "/scan", "pose": {"source": "tf", "fixed_frame": "world"}}
    ingest_fails(ds, tmp_path, r"no TF chain from 'world' to the scan frame 'laser' \(stops at 'map'\)")


# --- real recordings ------------------------------------------------------------------

REAL = {
    "intel": ({"format": "carmen", "path": "radish/intel-corrected.log.gz"}, {}, 910, 910),
    "aces": ({"format": "carmen", "path": "radish/aces-corrected.log.gz"}, {}, 440, 440),
    "freiburg101": ({"format": "carmen", "path": "radish/freiburg-101-corrected.log.gz"}, {}, 292, 292),
    "orebro": ({"format": "carmen", "path": "radish/orebro-corrected.log.gz"}, {"carmen_max_range_m": 32.0}, 237, 237),
    "trace0": (
        {"format": "rosbag", "path": "uob-pioneer/trace0.bag", "scan_topic": "/base_scan",
         "pose": {"source": "tf", "fixed_frame": "map"}}, {}, 958, 957),
    "mac_ros2": (
        {"format": "rosbag", "path": "comprobo-mac/macfirst_floor_take_2", "scan_topic": "/scan",
         "pose": {"source": "tf", "fixed_frame": "odom"}}, {}, 357, 356),
}


@needs_shared
@pytest.mark.realdata
@pytest.mark.parametrize("name", list(REAL))
def test_real_recordings(name, tmp_path):
    ds, cfg, n_scans, n_posed = REAL[name]
    ds = {**ds, "path": str(SHARED_DATA / ds["path"])}
    index, stream, scans, poses = ingest(ds, tmp_path, cfg)
    assert len(index) == n_scans
    assert poses["valid"].sum() == n_posed
    assert set(poses.loc[~poses["valid"], "reason"]) <= {"after_pose_stream", "before_pose_stream", "pose_gap"}
    assert index["n_points"].sum() == len(scans)
    assert scans["scan_id"].nunique() == (index["n_points"] > 0).sum()
    assert np.isfinite(scans[["x", "y", "z"]].to_numpy()).all()


def test_filter_points_float32_input_keeps_the_same_points_as_float64():
    from floorscan.ingest.points import filter_points

    rng = np.random.default_rng(3)
    p = rng.uniform(-10, 10, (2000, 3)).astype(np.float32)
    p[::97, 1] = np.nan
    p[::89, 2] = np.inf
    for rmin, rmax in ((None, None), (0.5, 12.0)):
        a, na = filter_points(p, rmin, rmax)
        b, nb = filter_points(p.astype(np.float64), rmin, rmax)
        assert a.dtype == np.float32 and na == nb and na > 0
        np.testing.assert_array_equal(a, b)
    clean = p[np.isfinite(p).all(axis=1)]
    out, n = filter_points(clean)
    assert n == 0 and out is not clean and np.array_equal(out, clean)


def _pc2(points, fmt, point_step, offsets=(0, 4, 8), bigendian=False):
    """A stand-in PointCloud2 message (the attributes pointcloud2_xyz reads)."""
    from types import SimpleNamespace

    datatype = {"f4": 7, "f8": 8}[fmt]
    order = ">" if bigendian else "<"
    dt = np.dtype({"names": list("xyz"), "formats": [order + fmt] * 3, "offsets": list(offsets), "itemsize": point_step})
    rec = np.zeros(len(points), dtype=dt)
    for i, n in enumerate("xyz"):
        rec[n] = points[:, i]
    fields = [SimpleNamespace(name=n, datatype=datatype, offset=o) for n, o in zip("xyz", offsets)]
    return SimpleNamespace(fields=fields, is_bigendian=bigendian, point_step=point_step, width=len(points), height=1,
                           row_step=point_step * len(points), data=np.frombuffer(rec.tobytes(), np.uint8))


def test_pointcloud2_xyz_keeps_float32_fields_and_widens_the_others():
    from floorscan.ingest.ros_messages import pointcloud2_xyz

    pts = np.array([[1.5, -2.25, 0.125], [3.1, 4.2, np.nan], [0.1, 0.2, 0.3]])
    little = pointcloud2_xyz(_pc2(pts, "f4", 16))  # x y z + 4 bytes of intensity
    assert little.dtype == np.float32 and little.shape == (3, 3)
    np.testing.assert_array_equal(little, pts.astype(np.float32))  # NaN kept for the caller to count
    big = pointcloud2_xyz(_pc2(pts, "f4", 12, bigendian=True))
    assert big.dtype == np.float64
    np.testing.assert_array_equal(big, pts.astype(np.float32).astype(np.float64))
    double = pointcloud2_xyz(_pc2(pts, "f8", 32, offsets=(0, 8, 16)))
    assert double.dtype == np.float64
    np.testing.assert_array_equal(double, pts)


# --- issue 20: one range rule for every reader ----------------------------------------


def test_laser_scan_returns_at_range_max_are_no_return():
    from floorscan.ingest.points import laser_scan_points

    r = np.array([0.04, 0.05, 1.0, 29.999, 30.0, 30.5, np.nan, np.inf])
    pts, dropped = laser_scan_points(r, 0.0, 0.0, 0.05, 30.0)  # all beams along +x
    # kept: 0.05 (range_min is valid), 1.0 and 29.999; dropped: below min, at max, beyond, NaN, inf
    np.testing.assert_allclose(pts[:, 0], [0.05, 1.0, 29.999], rtol=1e-6)
    assert dropped == 5


def test_filter_points_upper_bound_is_strict_too():
    from floorscan.ingest.points import filter_points

    p = np.array([[3.0, 4.0, 0.0], [0.6, 0.8, 0.0], [0.0, 0.0, 4.999], [6.0, 8.0, 0.0], [0.1, 0.0, 0.0]])
    kept, dropped = filter_points(p, 0.5, 5.0)  # distances 5, 1, 4.999, 10, 0.1
    np.testing.assert_allclose(kept, p[[1, 2]])
    assert dropped == 3


def test_bag_returns_at_range_max_dropped_and_counted(tmp_path):
    from conftest import write_detection_bag

    def ranges(i):
        r = scan_ranges(i)
        r[10:30] = 30.0  # exactly range_max: 20 "no return" beams
        return r

    bag = write_detection_bag(tmp_path / "max.bag", pose_topics=("/amcl_pose",), ranges=ranges, n_scans=4)
    index, *_ = ingest({"path": str(bag)}, tmp_path)
    # NaN, inf, 0.01 m (< range_min), 40 m (> range_max) and the 20 beams at range_max
    assert index["n_dropped"].tolist() == [24] * 4
    assert index["n_points"].tolist() == [N_BEAMS - 24] * 4


# --- CARMEN: no-return range detected --------------------------------------------------


def _carmen_scans(n_scans, far, n_far_per_scan, t0=10.0):
    """FLASER lines of 180 beams at 2 m with ``n_far_per_scan`` beams at ``far`` m."""
    lines = []
    for i in range(n_scans):
        r = [2.0] * 180
        for k in range(n_far_per_scan):
            r[k] = far
        lines.append(flaser_line(r, (0.1 * i, 0.0, 0.0), t0 + 0.2 * i))
    return lines


def test_no_return_range_rules():
    from floorscan.ingest.carmen_ranges import no_return_range

    # 50 readings at 32.767 m among 20 000 (0.25 %), codes a few mm below, a real wall at 32.6 m
    r = np.r_[np.full(19_930, 2.0), np.full(50, 32.767), np.full(15, 32.763), [32.6] * 5]
    nr = no_return_range([r])
    assert (nr.how, nr.value_m, nr.count) == ("detected", 32.767, 50)
    assert nr.fraction == pytest.approx(50 / 20_000)
    assert nr.max_range_m == pytest.approx(32.667)
    assert nr.n_dropped == 65  # 32.767 and 32.763; 32.6 m is kept
    # the farthest wall read 3 times in 20 000: not a no-return value; the SICK limit 80 m
    far = no_return_range([np.r_[np.full(19_997, 2.0), [45.0] * 3]])
    assert (far.how, far.max_range_m, far.count, far.n_dropped) == ("fallback", 80.0, 3, 0)
    # frequent enough as a fraction but under 10 readings
    few = no_return_range([np.r_[np.full(100, 2.0), [81.91] * 9]])
    assert few.how == "fallback" and few.n_dropped == 9
    # a number given by the user wins
    given = no_return_range([r], max_range_m=32.0)
    assert (given.how, given.max_range_m, given.n_dropped) == ("configured", 32.0, 70)


def test_carmen_max_range_detected_and_stored(tmp_path):
    # 10 scans x 180 beams, 12 of each scan at 32.767 m (6.7 %)
    log = write_carmen(tmp_path / "d.log", _carmen_scans(10, 32.767, 12))
    index, *_ = ingest({"path": str(log)}, tmp_path)  # format detected too
    assert index["n_dropped"].tolist() == [12] * 10
    meta = _meta(tmp_path / "scan_index.parquet")
    assert meta["max_range_m"] == "32.667" and meta["format"] == "carmen" and meta["scan_topic"] == "FLASER"
    out = tmp_path / "given"
    out.mkdir()
    index2, *_ = ingest({"path": str(log)}, out, {"carmen_max_range_m": 40.0})
    assert index2["n_dropped"].tolist() == [0] * 10
    assert _meta(out / "scan_index.parquet")["max_range_m"] == "40"


def _meta(path):
    from floorscan.core.io import read_metadata

    return read_metadata(path)


# --- CARMEN: stamps classified ---------------------------------------------------------


def _stamped_log(path, stamps):
    return write_carmen(path, [flaser_line([1.0] * 180, (float(i), 0.0, 0.0), t) for i, t in enumerate(stamps)])


def test_carmen_spread_stamps_keep_line_order(tmp_path, caplog):
    # 7 lines, 3 repeat the stamp before them (at most half): spread
    log = _stamped_log(tmp_path / "s.log", [10.0, 10.0, 10.2, 10.3, 10.3, 10.3, 10.6])
    rec = open_recording({"path": str(log)}, {}, 0.5)
    assert rec.detected["stamps"] == "spread"
    assert any("3 of 7 laser lines repeat" in n and "2 runs, the longest 3 lines" in n for n in rec.notes)
    index, stream, _, poses = ingest({"path": str(log)}, tmp_path)
    assert index["t_ns"].tolist() == [10_000_000_000, 10_100_000_000, 10_200_000_000, 10_300_000_000,
                                      10_400_000_000, 10_500_000_000, 10_600_000_000]
    assert poses["x"].tolist() == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0]  # line order, each its own pose
    assert _meta(tmp_path / "scan_index.parquet")["stamps"] == "spread"


def test_carmen_last_run_spread_over_the_median_step(tmp_path):
    log = _stamped_log(tmp_path / "l.log", [1.0, 1.5, 2.0, 2.5, 2.5])
    index, *_ = ingest({"path": str(log)}, tmp_path)
    assert index["t_ns"].tolist() == [1_000_000_000, 1_500_000_000, 2_000_000_000, 2_500_000_000, 2_750_000_000]


def test_carmen_mostly_repeated_stamps_are_made_up(tmp_path):
    # 3 of 5 lines repeat an earlier stamp (more than half): index x period from the first stamp
    log = _stamped_log(tmp_path / "m.log", [5.0, 5.0, 5.0, 5.0, 5.1])
    rec = open_recording({"path": str(log)}, {"missing_time_period_s": 0.2}, 0.5)
    assert rec.detected["stamps"] == "made_up"
    assert any("3 of 5 laser lines repeat an earlier timestamp" in n for n in rec.notes)
    index, *_ = ingest({"path": str(log)}, tmp_path, {"missing_time_period_s": 0.2})
    assert index["t_ns"].tolist() == [5_000_000_000, 5_200_000_000, 5_400_000_000, 5_600_000_000, 5_800_000_000]
    assert _meta(tmp_path / "pose_stream.parquet")["stamps"] == "made_up"


def test_carmen_all_zero_stamps_made_up_and_mixed_zero_rejected(tmp_path):
    log = _stamped_log(tmp_path / "z.log", [0, 0, 0])
    assert open_recording({"path": str(log)}, {}, 0.5).detected["stamps"] == "made_up"
    mixed = _stamped_log(tmp_path / "x.log", [1.0, 0, 1.2])
    ingest_fails({"path": str(mixed)}, tmp_path, r"x.log: laser lines with timestamp 0 among stamped ones \(lines \[2\]\)")


def test_carmen_lines_out_of_order_are_recorded_stamps(tmp_path):
    log = _stamped_log(tmp_path / "o.log", [1.0, 1.5, 1.2])
    rec = open_recording({"path": str(log)}, {}, 0.5)
    assert rec.detected["stamps"] == "recorded"
    assert any("1 laser lines earlier than the line before them" in n for n in rec.notes)


# --- format detection ------------------------------------------------------------------


def test_detect_format_of_each_kind(ros1_bag, ros2_bag, tmp_path):
    from floorscan.ingest.detect import bag_path, detect_format

    assert detect_format(ros1_bag) == "rosbag"
    assert detect_format(ros2_bag) == "rosbag"  # folder with metadata.yaml and a .db3
    db3 = next(ros2_bag.glob("*.db3"))
    assert detect_format(db3) == "rosbag" and bag_path(db3) == ros2_bag
    magic = tmp_path / "recording"  # no suffix: the ROS1 magic says it
    shutil.copy(ros1_bag, magic)
    assert detect_format(magic) == "rosbag"
    lines = ["PARAM robot_frontlaser_offset 0.0 nohost 0"] * 50 + [flaser_line([1.0] * 180, (0, 0, 0), 1.0)]
    for name in ("a.log", "a.log.gz", "a.clf", "a.gz"):
        assert detect_format(write_carmen(tmp_path / name, lines)) == "carmen", name
    pcd = tmp_path / "pcd"
    pcd.mkdir()
    (pcd / "0000.pcd").write_text("")
    assert detect_format(pcd) == "pcd"


def test_detect_format_errors_name_the_path_and_what_is_expected(tmp_path):
    from floorscan.ingest.detect import detect_format

    expected = r"expected a ROS1 \.bag file, a ROS2 bag folder .* a CARMEN log .* a folder of \.pcd files"
    (tmp_path / "notes.txt").write_text("hello\n")
    with pytest.raises(InputError, match=rf"notes.txt: unknown recording format \(suffix '.txt'\); {expected}"):
        detect_format(tmp_path / "notes.txt")
    write_carmen(tmp_path / "server.log", ["GET /index.html 200"] * 10)
    with pytest.raises(InputError, match=rf"server.log: no FLASER or ROBOTLASER1 line in its first .*; {expected}"):
        detect_format(tmp_path / "server.log")
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "readme.md").write_text("")
    with pytest.raises(InputError, match=rf"empty: a folder with neither a ROS2 bag nor \.pcd files \(it holds: readme.md\); {expected}"):
        detect_format(empty)
    # through open_recording: nothing written
    ingest_fails({"path": str(tmp_path / "notes.txt")}, tmp_path, "unknown recording format")


def test_explicit_format_wins_over_the_path(tmp_path):
    # a CARMEN log under a bag's name
    log = write_carmen(tmp_path / "looks_like.bag", [flaser_line([1.0] * 180, (i, 0, 0), 1.0 + i) for i in range(3)])
    index, *_ = ingest({"format": "carmen", "path": str(log)}, tmp_path)
    assert len(index) == 3
    assert _meta(tmp_path / "scan_index.parquet")["format"] == "carmen"


# --- bags: scan topic and pose source detected -----------------------------------------


def test_scan_topic_detected_and_several_refused(tmp_path):
    from conftest import write_detection_bag

    one = write_detection_bag(tmp_path / "one.bag", scan_topics=("/front_cloud",), pose_topics=("/amcl_pose",), n_scans=3)
    rec = open_recording({"path": str(one)}, {}, 0.5)
    assert rec.detected["scan_topic"] == "/front_cloud"
    two = write_detection_bag(tmp_path / "two.bag", scan_topics=("/front", "/rear"), n_scans=3)
    ingest_fails(
        {"path": str(two)}, tmp_path,
        r"two.bag: several scan topics: /front \(sensor_msgs/msg/LaserScan, 3 messages\), "
        r"/rear \(sensor_msgs/msg/LaserScan, 3 messages\); set the dataset's 'scan_topic'",
    )
    none = write_detection_bag(tmp_path / "none.bag", scan_topics=(), n_scans=3)
    ingest_fails({"path": str(none)}, tmp_path, r"none.bag: no topic with sensor_msgs/LaserScan .*topics in the bag: /odom \(nav_msgs/msg/Odometry, 5 messages\)")
    # a scan topic set in the dataset picks one of several
    rec2 = open_recording({"path": str(two), "scan_topic": "/rear"}, {}, 0.5)
    assert rec2.detected["scan_topic"] == "/rear"


def test_pose_source_amcl_topic_detected(ros1_bag, tmp_path):
    index, stream, _, poses = ingest({"path": str(ros1_bag)}, tmp_path)
    meta = _meta(tmp_path / "scan_index.parquet")
    assert {k: meta[k] for k in ("format", "scan_topic", "pose_source", "pose_kind", "stamps")} == {
        "format": "rosbag", "scan_topic": "/scan", "pose_source": "topic /amcl_pose (PoseWithCovarianceStamped)",
        "pose_kind": "map", "stamps": "recorded",
    }
    assert _meta(tmp_path / "pose_stream.parquet")["pose_source"] == meta["pose_source"]
    assert_poses_match_truth(index, poses, 20)


def test_several_pose_topics(tmp_path):
    from conftest import write_detection_bag

    with_amcl = write_detection_bag(tmp_path / "a.bag", pose_topics=("/amcl_pose", "/slam_pose"), n_scans=3)
    assert open_recording({"path": str(with_amcl)}, {}, 0.5).detected["pose_source"].startswith("topic /amcl_pose")
    without = write_detection_bag(tmp_path / "b.bag", pose_topics=("/pose_a", "/pose_b"), n_scans=3)
    ingest_fails({"path": str(without)}, tmp_path, r"b.bag: several pose topics: /pose_a .*/pose_b .*set the dataset's 'pose'")


def test_pose_source_tf_map_detected(tmp_path):
    from conftest import write_detection_bag

    bag = write_detection_bag(tmp_path / "tf.bag", tf_links=(("map", "odom"), ("odom", "base_link")), odom_topics=())
    index, stream, _, poses = ingest({"path": str(bag)}, tmp_path)
    meta = _meta(tmp_path / "scan_index.parquet")
    assert (meta["pose_source"], meta["pose_kind"]) == ("TF map -> odom -> base_link -> laser", "map")
    assert_poses_match_truth(index, poses, 10)


@pytest.mark.parametrize("prefix", ["", "/"], ids=["frames", "slashed_frames"])
def test_odometry_only_bag_has_no_map_pose(tmp_path, prefix):
    from conftest import write_detection_bag

    bag = write_detection_bag(tmp_path / "odom.bag", frame_prefix=prefix)  # /odom and TF odom -> base_link
    index, stream, _, poses = ingest({"path": str(bag)}, tmp_path)
    assert len(index) == 10 and stream.empty
    meta = _meta(tmp_path / "scan_index.parquet")
    assert meta["pose_kind"] == "none"
    assert meta["pose_source"] == "none: wheel odometry only (TF odom -> base_link -> laser; Odometry on /odom); LIDAR odometry"
    assert _meta(tmp_path / "pose_stream.parquet")["pose_kind"] == "none"
    assert not poses["valid"].any() and set(poses["reason"]) == {"no_pose_source"}


def test_odometry_given_as_pose_is_used_as_the_map_pose(tmp_path):
    from conftest import write_detection_bag

    bag = write_detection_bag(tmp_path / "odom.bag")
    for pose in ({"source": "topic", "topic": "/odom"}, {"source": "tf", "fixed_frame": "odom"}):
        out = tmp_path / pose["source"]
        out.mkdir()
        index, _, _, poses = ingest({"path": str(bag), "pose": pose}, out)
        meta = _meta(out / "scan_index.parquet")
        assert meta["pose_kind"] == "map" and meta["pose_source"].endswith("(set in the dataset)")
        assert_poses_match_truth(index, poses, 10)


def test_empty_pose_stream_is_an_error_for_a_map_pose_source(tmp_path):
    from floorscan.ingest.recording import Recording, Scan, pose_stream_frame

    def scans():
        yield Scan(0, "laser", np.zeros((1, 3), np.float32), 0)

    empty = pose_stream_frame([], [], [], [], [])
    out = tmp_path / "out"
    out.mkdir()
    rec = Recording(scans(), empty, "rec", detected={"pose_kind": "map", "pose_source": "topic /amcl_pose"})
    with pytest.raises(InputError, match=r"rec: no poses found for the pose source \(topic /amcl_pose\)"):
        write_recording(rec, out / "s.parquet", out / "i.parquet", out / "p.parquet")
    assert list(out.iterdir()) == []
    rec = Recording(scans(), empty, "rec", detected={"pose_kind": "none", "pose_source": "none"})
    write_recording(rec, out / "s.parquet", out / "i.parquet", out / "p.parquet")
    assert read_table(out / "p.parquet").empty


# --- real recordings: what is detected -------------------------------------------------

# path: (scan topic, pose source, pose kind)
REAL_BAGS = {
    "uob-pioneer/trace0.bag": ("/base_scan", "TF map -> odom -> base_link -> laser", "map"),
    "uob-pioneer/lgfloor2.bag": (
        "/base_scan", "none: wheel odometry only (TF odom -> base_link -> laser); LIDAR odometry", "none"),
    "stage-sim/simpath2.bag": (
        "/base_scan",
        "none: wheel odometry only (TF odom -> base_footprint -> base_link -> base_laser_link; "
        "Odometry on /base_pose_ground_truth, /odom); LIDAR odometry",
        "none",
    ),
    "comprobo-mac/macfirst_floor_take_2": (
        "/scan", "none: wheel odometry only (TF odom -> base_link -> rplidar_link; Odometry on /odom); LIDAR odometry",
        "none"),
}


@needs_shared
@pytest.mark.realdata
@pytest.mark.parametrize("name", list(REAL_BAGS))
def test_real_bags_detected(name):
    topic, source, kind = REAL_BAGS[name]
    rec = open_recording({"path": str(SHARED_DATA / name)}, {}, 0.5)
    assert rec.detected == {"format": "rosbag", "scan_topic": topic, "pose_source": source, "pose_kind": kind,
                            "stamps": "recorded"}
    assert rec.pose_stream.empty == (kind == "none")


@needs_shared
@pytest.mark.realdata
@pytest.mark.parametrize(
    "name, stamps, max_range_m",
    [("belgioioso", "made_up", "81.81"), ("orebro", "made_up", "32.667"), ("intel", "recorded", "81.73"),
     ("aces", "recorded", "49.9"), ("freiburg-101", "recorded", "81.81")],
)
def test_real_carmen_logs_detected(name, stamps, max_range_m):
    rec = open_recording({"path": str(SHARED_DATA / "radish" / f"{name}-corrected.log.gz")}, {}, 0.5)
    why = {"belgioioso": {"stamps_reason": "394 of 395 laser lines repeat an earlier timestamp (1 distinct values), "
                                           "more than half"},
           "orebro": {"stamps_reason": "every laser timestamp is 0"}}.get(name, {})
    assert rec.detected == {"format": "carmen", "scan_topic": "FLASER",
                            "pose_source": "embedded (corrected pose on each FLASER line)", "pose_kind": "map",
                            "stamps": stamps, **why, "max_range_m": max_range_m,
                            "n_frames_read": {"belgioioso": "395", "orebro": "237", "intel": "910", "aces": "440",
                                              "freiburg-101": "292"}[name]}


@needs_shared
@pytest.mark.realdata
def test_real_orebro_no_return_readings_all_dropped():
    rec = open_recording({"path": str(SHARED_DATA / "radish" / "orebro-corrected.log.gz")}, {}, 0.5)
    # 463 readings at 32.767 m and 505 at 32.759-32.765 m (its no-return codes)
    assert any("largest reading 32.767 m carries 463" in n and "968 readings dropped" in n for n in rec.notes)
    assert sum(s.n_dropped for s in rec.scans) == 968


@needs_shared
@pytest.mark.realdata
def test_real_simpath2_returns_at_range_max_dropped():
    rec = open_recording({"path": str(SHARED_DATA / "stage-sim" / "simpath2.bag")}, {}, 0.5)
    kept = dropped = 0
    for s in rec.scans:
        kept, dropped = kept + len(s.points), dropped + s.n_dropped
    # 634 scans x 500 beams; 56 454 at range_max (5.6 m), 17.8 %: none were dropped before
    assert (kept + dropped, dropped) == (317_000, 56_454)


def test_pcd_folder_detected_with_made_up_stamps(tmp_path):
    folder = tmp_path / "pcd"
    folder.mkdir()
    header = "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
    for i in range(3):
        (folder / f"{i}.pcd").write_text(header + f"{i + 1.0} 0 0\n{i + 1.0} 1 0\n")
    (folder / "locations.csv").write_text("file,x,y,z\n" + "".join(f"{i}.pcd,{i}.0,0.0,0.0\n" for i in range(3)))
    index, *_ = ingest({"path": str(folder)}, tmp_path, {"missing_time_period_s": 0.5})
    assert index["t_ns"].tolist() == [0, 500_000_000, 1_000_000_000]
    meta = _meta(tmp_path / "scan_index.parquet")
    assert {k: meta[k] for k in ("format", "scan_topic", "pose_source", "pose_kind", "stamps")} == {
        "format": "pcd", "scan_topic": "pcd files", "pose_source": "embedded (scan locations in locations.csv)",
        "pose_kind": "map", "stamps": "made_up",
    }


# --- issue 24: bad input never becomes a wrong result ----------------------------------


def _robotlaser1_line(ranges, pose, t_s, remissions=(), start=-1.5, res=0.01, max_range=30.0):
    """A ROBOTLASER1 line (CARMEN layout: 24 + n + m fields); ``pose`` is the laser pose."""
    x, y, th = pose
    r = " ".join(f"{v:.3f}" for v in ranges)
    m = " ".join(f"{v:.1f}" for v in remissions)
    return (f"ROBOTLASER1 0 {start} 3.1416 {res} {max_range} 0.01 0 {len(ranges)} {r} {len(remissions)} {m} "
            f"{x} {y} {th} {x} {y} {th} 0.1 0.0 0.5 0.3 0.2 {t_s} pippo {t_s}").replace("  ", " ")


def _one_line_log(tmp_path, line, name="bad.log"):
    good = [flaser_line([1.0] * 4, (0.0, 0.0, 0.0), 1.0 + i) for i in range(2)]
    return write_carmen(tmp_path / name, [*good, line])  # the bad line is line 3


@pytest.mark.parametrize(
    "line, match",
    [
        # a range missing: the pose would have been read from x..theta shifted by one
        ("FLASER 4 1.0 1.0 1.0 0.5 0.6 0.7 0.5 0.6 0.7 3.0 pippo 3.0",
         r"bad.log:3: malformed FLASER line: 14 fields for n = 4 beams; expected 2 \+ n \+ 9 = 15"),
        # a field too many inside the ranges: x would be read from the last range
        ("FLASER 4 1.0 1.0 1.0 1.0 1.0 0.5 0.6 0.7 0.5 0.6 0.7 3.0 pippo 3.0",
         r"bad.log:3: malformed FLASER line: 16 fields for n = 4 beams; expected 2 \+ n \+ 9 = 15"),
        ("FLASER 4 1.0 1.0 1.0 1.0 0.5 0.6 0.7 0.5 0.6 0.7 3.0 pippo 3.0 extra",
         r"bad.log:3: malformed FLASER line: 16 fields"),
        ("FLASER 2.5 1.0 1.0 0.5 0.6 0.7 0.5 0.6 0.7 3.0 pippo 3.0",
         r"bad.log:3: malformed FLASER line: field 2 \(n, the beam count\) is '2.5'; expected an integer >= 1"),
        ("FLASER 4 1.0 1.0 1.0 1.0 0.5 north 0.7 0.5 0.6 0.7 3.0 pippo 3.0",
         r"bad.log:3: malformed FLASER line: field 8 \(y\) is 'north'; expected a number"),
        ("FLASER 4 1.0 1.0 1.0 1.0 0.5 0.6 0.7 0.5 0.6 0.7 3.0 pippo 3,5",
         r"bad.log:3: malformed FLASER line: field 15 \(logger_timestamp\) is '3,5'; expected a number"),
    ],
    ids=["range_missing", "range_extra", "trailing_field", "beam_count", "pose_word", "logger_stamp"],
)
def test_carmen_flaser_field_count_is_exact(tmp_path, line, match):
    log = _one_line_log(tmp_path, line)
    ingest_fails({"format": "carmen", "path": str(log)}, tmp_path, match)


def test_carmen_robotlaser1_field_count_is_exact(tmp_path):
    from floorscan.ingest.carmen import parse_carmen

    ok = _robotlaser1_line([1.0, 2.0, 3.0], (0.5, 0.6, 0.7), 3.0, remissions=(10.0, 20.0))
    assert len(ok.split()) == 24 + 3 + 2
    log = write_carmen(tmp_path / "ok.log", [ok])
    (scan,), _ = parse_carmen(log, max_range_m=50.0)
    assert scan["pose"].tolist() == [0.5, 0.6, 0.7] and scan["t_s"] == 3.0
    np.testing.assert_allclose(scan["points"][:, 0], [1.0 * math.cos(-1.5), 2.0 * math.cos(-1.49), 3.0 * math.cos(-1.48)], rtol=1e-6)
    tok = ok.split()
    for bad, match in [
        # tok: 0 type, 8 n = 3, 9-11 ranges, 12 m = 2, 13-14 remissions, 15-17 laser pose
        (tok[:13] + tok[14:], r"28 fields for n = 3 beams and m = 2 remissions; expected 24 \+ n \+ m = 29"),
        (tok[:10] + tok[11:], r"field 13 \(m, the remission count\) is '10.0'; expected an integer >= 0"),
        (tok[:10] + ["1.5"] + tok[10:], r"field 13 \(m, the remission count\) is '3.000'"),
        (tok + ["0"], r"30 fields for n = 3 beams and m = 2 remissions"),
        (tok[:9], r"9 fields for n = 3 beams; expected 24 \+ n \+ m, at least 27"),
        (tok[:8] + ["-3"] + tok[9:], r"field 9 \(n, the beam count\) is '-3'; expected an integer >= 1"),
        (tok[:13] + ["x"] + tok[14:], r"field 14 \(remission 1\) is 'x'; expected a number"),
    ]:
        write_carmen(tmp_path / "bad.log", [ok, ok.replace(" 3.0 pippo 3.0", " 4.0 pippo 4.0"), " ".join(bad)])
        with pytest.raises(InputError, match=rf"bad.log:3: malformed ROBOTLASER1 line: {match}"):
            parse_carmen(tmp_path / "bad.log")


@pytest.mark.parametrize("stamp", ["nan", "inf", "-inf", "-1.5", "1e10"])
def test_carmen_bad_stamp_names_its_own_line(tmp_path, stamp):
    lines = [flaser_line([1.0] * 4, (float(i), 0.0, 0.0), t) for i, t in enumerate(["1.0", "1.1", stamp, "1.3", "1.4"])]
    log = write_carmen(tmp_path / "s.log", lines)
    ingest_fails(
        {"format": "carmen", "path": str(log)}, tmp_path,
        rf"s.log:3: malformed FLASER line: field 13 \(ipc_timestamp\) is {stamp}; expected a finite time in seconds",
    )


@pytest.mark.parametrize("kind", ["FLASER", "ROBOTLASER1"])
@pytest.mark.parametrize("field, value", [(0, "nan"), (1, "inf"), (2, "-inf")])
def test_carmen_non_finite_pose_is_an_error_naming_line_and_field(tmp_path, kind, field, value):
    pose = [0.5, 0.6, 0.7]
    pose[field] = value
    line = (flaser_line([1.0] * 4, pose, 3.0) if kind == "FLASER" else _robotlaser1_line([1.0] * 4, pose, 3.0))
    log = _one_line_log(tmp_path, line)
    name = ("x", "y", "theta")[field] if kind == "FLASER" else ("laser_x", "laser_y", "laser_theta")[field]
    ingest_fails({"format": "carmen", "path": str(log)}, tmp_path,
                 rf"bad.log:3: malformed {kind} line: field \d+ \({name}\) is {value}; expected a finite number")


def test_carmen_non_finite_ranges_stay_no_return(tmp_path):
    from floorscan.ingest.carmen import parse_carmen

    log = write_carmen(tmp_path / "r.log", [flaser_line([1.0, float("nan"), float("inf"), -1.0], (0, 0, 0), 1.0)])
    (scan,), _ = parse_carmen(log, max_range_m=50.0)
    assert len(scan["points"]) == 1 and scan["n_dropped"] == 3


@pytest.mark.parametrize(
    "field, name, value", [(3, "start_angle", "nan"), (5, "angular_resolution", "inf"), (6, "maximum_range", "nan")]
)
def test_carmen_robotlaser1_non_finite_angles_and_range_are_errors(tmp_path, field, name, value):
    tok = _robotlaser1_line([1.0] * 4, (0.5, 0.6, 0.7), 3.0).split()
    tok[field - 1] = value  # field k (1-based, the type is field 1) is tok[k - 1]
    log = _one_line_log(tmp_path, " ".join(tok))
    ingest_fails({"format": "carmen", "path": str(log)}, tmp_path,
                 rf"bad.log:3: malformed ROBOTLASER1 line: field {field} \({name}\) is {value}; expected a finite number")


def _pcd_header(fields="x y z", size="4 4 4", type_="F F F", count="1 1 1", width=2, height=1, points=2, data="ascii"):
    return (f"VERSION .7\nFIELDS {fields}\nSIZE {size}\nTYPE {type_}\nCOUNT {count}\nWIDTH {width}\nHEIGHT {height}\n"
            f"VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {points}\nDATA {data}\n")


@pytest.mark.parametrize(
    "header, body, match",
    [
        (dict(points="abc"), "1 2 3\n4 5 6\n", r"PCD header POINTS is 'abc'; expected a non-negative integer"),
        (dict(size="2"), "1 2 3\n4 5 6\n", r"PCD header SIZE has 1 values for 3 FIELDS \(x y z\); expected one per field"),
        (dict(size="2 2 2"), "1 2 3\n4 5 6\n", r"PCD field 'x' is TYPE F SIZE 2; expected F 4 or F 8"),
        (dict(type_="I F F"), "1 2 3\n4 5 6\n", r"PCD field 'x' is TYPE I SIZE 4; expected F 4 or F 8"),
        (dict(type_="F F Q"), "1 2 3\n4 5 6\n", r"PCD field 'z' is TYPE Q SIZE 4; expected F 4 or F 8"),
        (dict(count="2 1 1"), "1 2 3 4\n4 5 6 7\n", r"PCD field 'x' has COUNT 2; expected 1"),
        (dict(width=3), "1 2 3\n4 5 6\n", r"PCD header POINTS 2 but WIDTH x HEIGHT = 3 x 1 = 3"),
        (dict(fields="x y"), "1 2 3\n4 5 6\n", r"PCD header FIELDS x y; expected the fields x, y and z"),
        (dict(), "1 2 3\n", r"1 rows stored, the header says POINTS 2"),
        (dict(), "1 2 3\n4 5 6\n7 8 9\n", r"3 rows stored, the header says POINTS 2"),
        (dict(), "1 2\n4 5 6\n", r"p.pcd:11: row of 2 values; expected 3 \(FIELDS x y z, COUNT 1 1 1\)"),
        (dict(), "1 2 3\n4 5 6 7\n", r"p.pcd:12: row of 4 values; expected 3"),
        (dict(), "1 a 3\n4 5 6\n", r"p.pcd:11: field 'y' is 'a'; expected a number"),
        (dict(), "1 2 3\n4 5 1e39\n", r"p.pcd:12: field 'z' is 1e\+39, beyond the range of its TYPE F SIZE 4"),
    ],
    ids=["points_abc", "size_2", "size_2_each", "int_x", "type_q", "count_2", "width_x_height", "no_z",
         "fewer_rows", "more_rows", "short_row", "long_row", "word", "f4_overflow"],
)
def test_pcd_header_checked_against_the_data(tmp_path, header, body, match):
    from floorscan.ingest.pcd_file import read_pcd_xyz

    p = tmp_path / "p.pcd"
    p.write_text(_pcd_header(**header) + body)
    with pytest.raises(InputError, match=rf"p.pcd:?\d*: .*{match}" if not match.startswith("p.pcd") else match):
        read_pcd_xyz(p)


@pytest.mark.parametrize("extra", [-4, 4, 1])
def test_pcd_binary_size_must_match_points(tmp_path, extra):
    from floorscan.ingest.pcd_file import read_pcd_xyz

    pts = np.array([[1.5, 2.0, 3.0], [4.0, 5.0, 6.0]], "<f4")
    data = pts.tobytes()
    data = data[:extra] if extra < 0 else data + b"\0" * extra
    p = tmp_path / "b.pcd"
    p.write_bytes(_pcd_header(data="binary").encode() + data)
    with pytest.raises(InputError, match=rf"b.pcd: {len(data)} bytes of binary data; expected POINTS x 12 bytes a point = 24"):
        read_pcd_xyz(p)
    p.write_bytes(_pcd_header(data="binary").encode() + pts.tobytes())
    np.testing.assert_array_equal(read_pcd_xyz(p), pts)


def test_pcd_f8_and_padding_fields_and_compressed_read_exactly(tmp_path):
    import open3d as o3d

    from floorscan.ingest.pcd_file import read_pcd_xyz

    rng = np.random.default_rng(5)
    pts = rng.uniform(-10, 10, (7, 3))
    rec = np.zeros(7, dtype=[("i", "<u2"), ("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("rgb", "<f4", (2,))])
    rec["x"], rec["y"], rec["z"] = pts.T
    p = tmp_path / "f8.pcd"
    p.write_bytes(_pcd_header("intensity x y z rgb", "2 8 8 8 4", "U F F F F", "1 1 1 1 2", 7, 1, 7, "binary").encode()
                  + rec.tobytes())
    np.testing.assert_array_equal(read_pcd_xyz(p), pts)
    c = tmp_path / "c.pcd"
    o3d.t.io.write_point_cloud(str(c), o3d.t.geometry.PointCloud(o3d.core.Tensor(pts.astype(np.float32))), compressed=True)
    np.testing.assert_array_equal(read_pcd_xyz(c), pts.astype(np.float32))
    raw = c.read_bytes()
    c.write_bytes(raw[:-3])
    with pytest.raises(InputError, match=r"c.pcd: \d+ bytes of compressed data; the header of the data says \d+"):
        read_pcd_xyz(c)


@pytest.mark.parametrize(
    "csv, match",
    [
        ("file,t_ns,x,y,z,yaw\n0.pcd,1000,0,0,0,nan\n", r"column 'yaw' row 1 is 'nan'; expected a finite number"),
        ("file,t_ns,x,y,z,yaw\n0.pcd,1000,inf,0,0,0\n", r"column 'x' row 1 is 'inf'; expected a finite number"),
        ("file,t_ns,x,y,z,yaw\n0.pcd,1000.5,0,0,0,0\n", r"column 't_ns' row 1 is '1000.5'; expected an integer"),
        ("file,t_ns,x,y,z,yaw\n0.pcd,-5,0,0,0,0\n", r"column 't_ns' row 1 is '-5'; expected an integer"),
        ("file,t_ns,x,y,z,yaw\n0.pcd,99999999999999999999,0,0,0,0\n", r"column 't_ns' row 1 is '99999999999999999999'"),
        ("file,t_ns,x,y,z,yaw\n0.pcd,1e21,0,0,0,0\n", r"column 't_ns' row 1 is '1e21'; expected an integer"),
    ],
    ids=["nan_yaw", "inf_x", "fractional_t_ns", "negative_t_ns", "t_ns_beyond_int64", "t_ns_float"],
)
def test_pcd_locations_fields_checked(tmp_path, csv, match):
    from floorscan.ingest.pcd import read_locations

    (tmp_path / "0.pcd").write_text(_pcd_header(width=1, points=1) + "1 2 3\n")
    (tmp_path / "locations.csv").write_text(csv)
    with pytest.raises(InputError, match=rf"locations.csv: {match}"):
        read_locations(tmp_path, "locations.csv", 0.1)


def _set(msg, dotted, value):
    *head, last = dotted.split(".")
    for name in head:
        msg = getattr(msg, name)
    setattr(msg, last, value)


def _bag_with_bad_value(path, scan=None, pose_type="geometry_msgs/msg/PoseWithCovarianceStamped", pose=None,
                        tf=None, tf_link=("odom", "base_link"), n=5):
    """A ROS1 bag: /scan (LaserScan, 181 beams), /pose (``pose_type``), /tf map -> odom ->
    base_link and base_link -> camera, /tf_static base_link -> laser. ``scan``, ``pose``,
    ``tf`` ({dotted attribute: value}) are set on message 2 of /scan, /pose and on the
    ``tf_link`` transform of /tf message 2."""
    import dataclasses

    from conftest import _bag_writer, _header, _quat, _scan_message, _write_messages

    ts, T, ser, writer = _bag_writer(path, False)
    Vec, Q = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    P = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=1.0, y=2.0, z=0.0), orientation=Q(*_quat(0.3)))

    def transform(parent, child, t, x=0.0):
        return T["geometry_msgs/msg/TransformStamped"](
            header=_header(ts, t, parent, True), child_frame_id=child,
            transform=T["geometry_msgs/msg/Transform"](translation=Vec(x=x, y=0.0, z=0.0), rotation=Q(*_quat(0.0))))

    msgs = [(T0_NS - 1, "/tf_static", T["tf2_msgs/msg/TFMessage"](transforms=[transform("base_link", "laser", T0_NS)]))]
    cov = np.zeros(36)
    for i in range(n):
        t = T0_NS + int(i * 0.1e9)
        s = _scan_message(ts, t, "laser", scan_ranges(i), False, False)
        if pose_type.endswith("PoseStamped") and not pose_type.endswith("CovarianceStamped"):
            p = T[pose_type](header=_header(ts, t - 1000, "map", True), pose=dataclasses.replace(P, position=dataclasses.replace(P.position), orientation=dataclasses.replace(P.orientation)))
        else:
            pp = T["geometry_msgs/msg/PoseWithCovariance"](
                pose=dataclasses.replace(P, position=dataclasses.replace(P.position), orientation=dataclasses.replace(P.orientation)),
                covariance=cov)
            if pose_type.endswith("Odometry"):
                p = T[pose_type](header=_header(ts, t - 1000, "map", True), child_frame_id="base_link", pose=pp,
                                 twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=T["geometry_msgs/msg/Twist"](
                                     linear=Vec(x=0.0, y=0.0, z=0.0), angular=Vec(x=0.0, y=0.0, z=0.0)), covariance=cov))
            else:
                p = T[pose_type](header=_header(ts, t - 1000, "map", True), pose=pp)
        links = [transform("map", "odom", t), transform("odom", "base_link", t, x=0.1 * i),
                 transform("base_link", "camera", t)]
        if i == 2:
            for k, v in (scan or {}).items():
                _set(s, k, v)
            for k, v in (pose or {}).items():
                _set(p, k, v)
            link = next(tr for tr in links if (tr.header.frame_id, tr.child_frame_id) == tf_link)
            for k, v in (tf or {}).items():
                _set(link, k, v)
        msgs += [(t, "/scan", s), (t - 1000, "/pose", p), (t, "/tf", T["tf2_msgs/msg/TFMessage"](transforms=links))]
    _write_messages(writer, ts, ser, msgs)
    return path


@pytest.mark.parametrize("field", ["angle_min", "angle_increment", "range_min", "range_max"])
@pytest.mark.parametrize("value", [float("nan"), float("inf")])
def test_laser_scan_non_finite_header_fields_are_skipped_and_named(tmp_path, field, value):
    """One broken scan of five is skipped and counted, named in a note (issue 35; it was
    an error before); more than half broken is an error: tests/test_bad_input_frames.py."""
    bag = _bag_with_bad_value(tmp_path / "s.bag", scan={field: value})
    ds = {"path": str(bag), "scan_topic": "/scan", "pose": {"source": "topic", "topic": "/pose"}}
    rec = open_recording(ds, {}, 0.5)
    index = write_recording(rec, tmp_path / "scans.parquet", tmp_path / "scan_index.parquet",
                            tmp_path / "pose_stream.parquet")
    assert len(index) == 4 and rec.detected["lost_bad_frames"] == "1"
    assert any(f"s.bag: '/scan' message 2 (t {T0_NS + 200_000_000} ns): LaserScan {field} is {value}; "
               "expected a finite number" in n for n in rec.notes)


def test_laser_scan_non_finite_ranges_stay_no_return(tmp_path):
    bag = _bag_with_bad_value(tmp_path / "r.bag")
    index, *_ = ingest({"path": str(bag), "scan_topic": "/scan", "pose": {"source": "topic", "topic": "/pose"}}, tmp_path)
    assert index["n_dropped"].tolist() == [4] * 5  # NaN, inf, below range_min, beyond range_max


POSE_FIELDS = {
    "geometry_msgs/msg/PoseWithCovarianceStamped": "pose.pose",
    "geometry_msgs/msg/PoseStamped": "pose",
    "nav_msgs/msg/Odometry": "pose.pose",
}


@pytest.mark.parametrize("pose_type", list(POSE_FIELDS))
@pytest.mark.parametrize("field, value", [("position.x", float("nan")), ("position.z", float("inf")),
                                          ("orientation.w", float("nan"))])
def test_pose_topic_non_finite_fields_are_errors(tmp_path, pose_type, field, value):
    prefix = POSE_FIELDS[pose_type]
    bag = _bag_with_bad_value(tmp_path / "p.bag", pose_type=pose_type, pose={f"{prefix}.{field}": value})
    ds = {"path": str(bag), "scan_topic": "/scan", "pose": {"source": "topic", "topic": "/pose"}}
    ingest_fails(ds, tmp_path, rf"p.bag: '/pose' message 2 \(t {T0_NS + 200_000_000 - 1000} ns\): "
                               rf"{pose_type.rsplit('/', 1)[-1]} {prefix}.{field} is {value}; expected a finite number")


def test_pose_topic_zero_quaternion_is_an_error(tmp_path):
    zero = {f"pose.pose.orientation.{c}": 0.0 for c in "xyzw"}
    bag = _bag_with_bad_value(tmp_path / "q.bag", pose=zero)
    ds = {"path": str(bag), "scan_topic": "/scan", "pose": {"source": "topic", "topic": "/pose"}}
    ingest_fails(ds, tmp_path, r"q.bag: '/pose' message 2 .*: PoseWithCovarianceStamped pose.pose.orientation is "
                               r"\(0.0, 0.0, 0.0, 0.0\), \|q\|\^2 = 0; expected a unit quaternion")


@pytest.mark.parametrize("field, value", [("transform.translation.x", float("nan")),
                                          ("transform.rotation.z", float("inf")), ("transform.rotation.w", 0.0)])
def test_tf_non_finite_transform_in_the_chain_is_an_error(tmp_path, field, value):
    bag = _bag_with_bad_value(tmp_path / "t.bag", tf={field: value})
    ds = {"path": str(bag), "scan_topic": "/scan", "pose": {"source": "tf", "fixed_frame": "map"}}
    what = r"transform.rotation is \(0.0, 0.0, 0.0, 0.0\), \|q\|\^2 = 0; expected a unit quaternion" if value == 0.0 else (
        f"{field} is {value}; expected a finite number")
    ingest_fails(ds, tmp_path, rf"t.bag: '/tf' message 2 \(t {T0_NS + 200_000_000} ns\): TransformStamped odom -> base_link: "
                               rf"{what}")


def test_tf_bad_link_outside_the_chain_is_not_used(tmp_path):
    bag = _bag_with_bad_value(tmp_path / "c.bag", tf={"transform.translation.x": float("nan")},
                              tf_link=("base_link", "camera"))
    index, stream, *_ = ingest({"path": str(bag), "scan_topic": "/scan", "pose": {"source": "tf", "fixed_frame": "map"}},
                               tmp_path)
    assert len(index) == 5 and np.isfinite(stream[["x", "y", "z", "yaw"]].to_numpy()).all()


def test_pointcloud2_every_point_non_finite_is_an_error():
    from floorscan.ingest.ros_messages import pointcloud2_xyz

    pts = np.array([[np.nan, 1.0, 2.0], [1.0, np.inf, 0.0]])
    with pytest.raises(InputError, match=r"c.bag: PointCloud2 on '/cloud' has no finite point \(2 points\)"):
        pointcloud2_xyz(_pc2(pts, "f4", 16), "c.bag", "/cloud")
    # one finite point is enough: the others are dropped and counted by ingest
    assert len(pointcloud2_xyz(_pc2(np.r_[pts, [[1.0, 2.0, 3.0]]], "f4", 16))) == 3


@pytest.mark.parametrize(
    "change, match",
    [
        (dict(point_step=10), r"field 'z' \(offset 8, 4 bytes\) ends beyond point_step 10"),
        (dict(row_step=8), r"row_step 8 is less than width x point_step = 3 x 16 = 48"),
        (dict(height=2, width=2, row_step=32), r"has 48 bytes of data; expected row_step x height = 32 x 2 = 64"),
        (dict(data_cut=4), r"has 44 bytes of data; expected row_step x height = 48 x 1 = 48"),
        (dict(data_extra=16), r"has 64 bytes of data; expected row_step x height = 48 x 1 = 48"),
    ],
    ids=["field_beyond_point", "row_step_short", "rows_missing", "data_cut", "data_extra"],
)
def test_pointcloud2_layout_checked(change, match):
    from floorscan.ingest.ros_messages import pointcloud2_xyz

    msg = _pc2(np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]]), "f4", 16)
    cut, extra = change.pop("data_cut", 0), change.pop("data_extra", 0)
    for k, v in change.items():
        setattr(msg, k, v)
    if cut or extra:
        msg.data = np.r_[msg.data[: len(msg.data) - cut], np.zeros(extra, np.uint8)]
    with pytest.raises(InputError, match=rf"c.bag: PointCloud2 on '/cloud' {match}"):
        pointcloud2_xyz(msg, "c.bag", "/cloud")


def test_carmen_log_with_a_byte_order_mark_keeps_its_first_scan(tmp_path):
    """Issue 35: a log saved by an editor with a UTF-8 byte-order mark lost its first
    scan (its line type read as unknown); the mark is dropped, plain or gzip."""
    lines = [flaser_line([1.0] * 180, (1.0, 2.0, 0.5), 10.0), flaser_line([1.0] * 180, (1.5, 2.0, 0.5), 10.2)]
    for name in ("bom.log", "bom.log.gz"):
        log = write_carmen(tmp_path / name, lines)
        raw = log.read_bytes() if name.endswith(".log") else gzip.decompress(log.read_bytes())
        data = b"\xef\xbb\xbf" + raw
        log.write_bytes(data if name.endswith(".log") else gzip.compress(data))
        out = tmp_path / name.replace(".", "_")
        out.mkdir()
        index, _, _, poses = ingest({"format": "carmen", "path": str(log)}, out, {})
        assert len(index) == 2 and poses["x"].tolist() == [1.0, 1.5]


def test_a_locations_csv_with_spaces_after_its_commas_reads_as_without(tmp_path):
    """'file, t_ns, x, y, z, yaw' (as people and spreadsheets write it) was refused as
    'columns ['x', 'y', 'z'] missing' (issue 45, item 6); a header that lacks a column
    now shows the columns it has."""
    from floorscan.core.io import InputError
    from floorscan.ingest.pcd import read_locations

    rows = ["a.pcd,1600000000000000000,0.5,1.25,0.3,0.1", "b.pcd,1600000000100000000,0.75,1.5,0.3,0.2"]
    for sub in ("plain", "spaced"):
        (tmp_path / sub).mkdir()
        for name in ("a.pcd", "b.pcd"):
            (tmp_path / sub / name).write_text("")
    (tmp_path / "plain" / "locations.csv").write_text("\n".join(["file,t_ns,x,y,z,yaw", *rows]) + "\n")
    (tmp_path / "spaced" / "locations.csv").write_text(
        "\n".join(["file, t_ns, x, y, z, yaw", *[r.replace(",", ", ") for r in rows]]) + "\n")
    plain = read_locations(tmp_path / "plain", "locations.csv", 0.1)
    spaced = read_locations(tmp_path / "spaced", "locations.csv", 0.1)
    import pandas as pd

    pd.testing.assert_frame_equal(plain, spaced)
    assert list(spaced["file"]) == ["a.pcd", "b.pcd"] and spaced["t_ns"].iloc[1] == 1600000000100000000
    (tmp_path / "spaced" / "locations.csv").write_text("name, t_ns, x, y, z\n" + rows[0][:-4] + "\n")
    with pytest.raises(InputError, match=r"columns \['file'\] missing \(the header has \['name', 't_ns', 'x', 'y', 'z'\]\)"):
        read_locations(tmp_path / "spaced", "locations.csv", 0.1)


def test_a_ros2_folder_rosbags_cannot_open_is_said_as_such(tmp_path):
    """Without metadata.yaml, or declaring a storage or serialization rosbags does not
    read: each named, not 'cannot read the bag, truncated or corrupt' (issue 45, item 6)."""
    import yaml

    from floorscan.core.io import InputError
    from floorscan.ingest.rosbag import open_bag

    bag = tmp_path / "run2"
    bag.mkdir()
    (bag / "run2_0.db3").write_bytes(b"")
    with pytest.raises(InputError, match=r"run2: a ROS2 bag folder without its metadata.yaml \(it holds run2_0.db3\); "
                                         r".*'ros2 bag reindex .*run2'"):
        open_bag(bag, {})

    def meta(store, fmt):
        topic = {"topic_metadata": {"name": "/scan", "type": "sensor_msgs/msg/LaserScan", "serialization_format": fmt}}
        info = {"version": 4, "storage_identifier": store, "relative_file_paths": ["run2_0.db3"],
                "topics_with_message_count": [topic]}
        (bag / "metadata.yaml").write_text(yaml.safe_dump({"rosbag2_bagfile_information": info}))

    meta("rocksdb", "cdr")
    with pytest.raises(InputError, match=r"metadata.yaml: storage_identifier 'rocksdb'; expected one of sqlite3, mcap"):
        open_bag(bag, {})
    meta("sqlite3", "json")
    with pytest.raises(InputError, match=r"metadata.yaml: topics /scan are not serialized as 'cdr'"):
        open_bag(bag, {})


def test_a_pcd_folder_whose_scans_sit_in_a_sub_folder_is_one_recording(tmp_path):
    """locations.csv beside a 'scans/' folder was taken as a folder of recordings, and
    the error pointed at scans/locations.csv (issue 45, item 5): the locations CSV makes
    it one PCD recording."""
    from floorscan.ingest.detect import detect_format, is_one_recording, recordings_in

    rec = tmp_path / "survey"
    (rec / "scans").mkdir(parents=True)
    (rec / "scans" / "a.pcd").write_text("")
    (rec / "locations.csv").write_text("file,x,y,z\nscans/a.pcd,0,0,0\n")
    assert detect_format(rec) == "pcd" and is_one_recording(rec)
    assert recordings_in(rec) == ([rec], [])
    assert recordings_in(tmp_path) == ([rec], [])  # in a folder of recordings: one of them

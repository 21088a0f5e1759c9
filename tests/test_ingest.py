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
from floorscan.ingest import open_recording, write_recording
from floorscan.io import InputError, read_table
from floorscan.poses import scan_poses


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
    ingest_fails({"format": "carmen", "path": str(tmp_path / "odom.log")}, tmp_path, r"odom.log: no laser lines; expected FLASER or ROBOTLASER1 lines \(message types found: \{'ODOM': 3\}\)")
    write_carmen(tmp_path / "short.log", ["FLASER 180 1.0 1.0 1.0"])
    ingest_fails({"format": "carmen", "path": str(tmp_path / "short.log")}, tmp_path, r"short.log:1: malformed FLASER line")


def test_pose_stream_not_overlapping_scans(tmp_path):
    bag = write_bag(tmp_path / "late.bag", pose_shift_s=100.0, n_scans=5)
    ds = {"format": "rosbag", "path": str(bag), "scan_topic": "/scan", "pose": {"source": "topic", "topic": "/amcl_pose"}}
    out = tmp_path / "o"
    out.mkdir()
    with pytest.raises(InputError, match="does not overlap the scans"):
        ingest(ds, out)


@pytest.mark.parametrize("order", ["duplicate", "unsorted"])
def test_unsorted_or_duplicate_pose_stamps(tmp_path, order):
    bag = write_bag(tmp_path / f"{order}.bag", amcl_order=order, n_scans=5)
    ds = {"format": "rosbag", "path": str(bag), "scan_topic": "/scan", "pose": {"source": "topic", "topic": "/amcl_pose"}}
    match = "duplicate stamp" if order == "duplicate" else "are not sorted"
    ingest_fails(ds, tmp_path, rf"pose topic '/amcl_pose' header stamps {'have a' if order == 'duplicate' else ''}.*{match}")


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
    from floorscan.ingest import filter_points

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
    from floorscan.ingest.rosbag import pointcloud2_xyz

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

"""Synthetic recordings: rover path, pose error, and the bag/PCD/ground-truth outputs."""

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from floorscan.sim.building_file import parse_building
from floorscan.sim.params import SimParams
from floorscan.sim.recording import gauss_markov, simulate_recording
from floorscan.sim.scanners import Scanner2D, Scanner3D, scanner_from_config
from floorscan.sim.simulate import run_simulation
from floorscan.sim.trajectory import rover_trajectory
from floorscan.core.io import InputError, read_table

REPO = Path(__file__).resolve().parents[1]
SCHEMA = REPO / "workflow" / "schemas" / "simulate.schema.yaml"

# A 4 x 3 m room with a door, a window and a box; the rover drives 1.2 m, turns, 0.6 m.
ROOM = {
    "name": "tiny",
    "height_m": 2.5,
    "wall_thickness_m": 0.1,
    "walls": [
        {
            "id": "room",
            "closed": True,
            "points": [[-2.05, -1.55], [2.05, -1.55], [2.05, 1.55], [-2.05, 1.55]],
            "openings": [
                {"id": "door", "kind": "door", "segment": 0, "offset_m": 2.5, "width_m": 0.9},
                {"id": "win", "kind": "window", "segment": 2, "offset_m": 1.0, "width_m": 1.0,
                 "sill_m": 0.9, "head_m": 2.0},
            ],
        }
    ],
    "furniture": [{"id": "box", "center": [1.4, 0.9], "size": [0.5, 0.5, 0.8]}],
    "waypoints": [[-1.0, 0.0], [0.2, 0.0], [0.2, -0.6]],
}
CFG = {"scanners": {"2d": {}, "3d": {"horizontal_resolution_deg": 3.0}}}
OUTS = {"bag": "recording.bag", "pcd": "pcd", "true_poses": "true_poses.parquet",
        "stl": "building.stl", "walls": "walls.geojson"}


def run(tmp: Path, scanner="2d", seed=1, cfg=CFG, building=ROOM):
    tmp.mkdir(parents=True, exist_ok=True)
    byaml = tmp / "tiny.yaml"
    byaml.write_text(yaml.safe_dump(building))
    outs = {k: tmp / "sim" / v for k, v in OUTS.items()}
    counts = run_simulation(byaml, {"name": "tiny", "scanner": scanner, "seed": seed}, cfg, outs)
    return outs, counts


@pytest.fixture(scope="module")
def rec2d(tmp_path_factory):
    return run(tmp_path_factory.mktemp("sim2d"))


@pytest.fixture(scope="module")
def rec3d(tmp_path_factory):
    return run(tmp_path_factory.mktemp("sim3d"), scanner="3d")


def read_bag(path):
    from rosbags.highlevel import AnyReader

    out = {}
    with AnyReader([Path(path)]) as r:
        out["connections"] = {c.topic: (c.msgtype, c.msgcount) for c in r.connections}
        for con, t, raw in r.messages():
            out.setdefault(con.topic, []).append((t, r.deserialize(raw, con.msgtype)))
    return out


def stamp_ns(header):
    return header.stamp.sec * 1_000_000_000 + header.stamp.nanosec


def read_pcd(path):
    import open3d as o3d

    return np.asarray(o3d.io.read_point_cloud(str(path)).points)


def to_map(p, pose):
    c, s = math.cos(pose["yaw"]), math.sin(pose["yaw"])
    return np.column_stack([c * p[:, 0] - s * p[:, 1] + pose["x"], s * p[:, 0] + c * p[:, 1] + pose["y"],
                            p[:, 2] + pose["z"]])


def check_pcd_equals_bag(outs, scan_points):
    bag = read_bag(outs["bag"])
    truth = read_table(outs["true_poses"]).set_index("t_ns")
    locs = pd.read_csv(outs["pcd"] / "locations.csv")
    assert list(locs.columns) == ["file", "t_ns", "x", "y", "z", "yaw"]
    assert len(bag["/scan"]) == len(locs) == len(truth)
    n_total = 0
    for (t, msg), row in zip(bag["/scan"], locs.itertuples()):
        assert stamp_ns(msg.header) == t == row.t_ns
        assert msg.header.frame_id == "laser"
        pose = truth.loc[row.t_ns]
        assert (pose.x, pose.y, pose.z, pose.yaw) == (row.x, row.y, row.z, row.yaw)
        expected = to_map(scan_points(msg), pose)
        got = read_pcd(outs["pcd"] / row.file)
        assert got.shape == expected.shape
        np.testing.assert_allclose(got, expected, rtol=0, atol=2e-6)  # float32 precision
        n_total += len(got)
    return n_total


def laserscan_points(msg):
    r = np.asarray(msg.ranges, dtype=np.float64)
    a = msg.angle_min + np.arange(len(r)) * msg.angle_increment
    ok = np.isfinite(r)
    return np.column_stack([r[ok] * np.cos(a[ok]), r[ok] * np.sin(a[ok]), np.zeros(ok.sum())])


def cloud_points(msg):
    assert [f.name for f in msg.fields] == ["x", "y", "z"] and msg.point_step == 12
    return np.frombuffer(bytes(msg.data), dtype="<f4").reshape(-1, 3).astype(np.float64)


def test_pcd_folder_and_bag_agree_point_for_point_2d(rec2d):
    outs, counts = rec2d
    assert 30 <= counts["n_scans"] <= 90  # a tiny recording
    n = check_pcd_equals_bag(outs, laserscan_points)
    assert n == counts["n_points"]
    assert counts["n_no_return"] > 0  # beams out through the door


def test_pcd_folder_and_bag_agree_point_for_point_3d(rec3d):
    outs, counts = rec3d
    n = check_pcd_equals_bag(outs, cloud_points)
    assert n == counts["n_points"]
    assert n > counts["n_scans"] * 120 * 16 * 0.8


def test_same_seed_gives_byte_identical_files(rec2d, tmp_path):
    outs, _ = rec2d
    again, _ = run(tmp_path / "again")
    for key in ["bag", "true_poses", "stl", "walls"]:
        assert Path(again[key]).read_bytes() == Path(outs[key]).read_bytes(), key
    files = sorted(p.name for p in Path(outs["pcd"]).iterdir())
    assert files == sorted(p.name for p in Path(again["pcd"]).iterdir())
    for f in files:
        assert (Path(again["pcd"]) / f).read_bytes() == (Path(outs["pcd"]) / f).read_bytes(), f
    other, _ = run(tmp_path / "other", seed=2)
    assert Path(other["bag"]).read_bytes() != Path(outs["bag"]).read_bytes()
    assert Path(other["stl"]).read_bytes() == Path(outs["stl"]).read_bytes()


def test_bag_topics_frames_and_static_transform(rec2d):
    outs, counts = rec2d
    bag = read_bag(outs["bag"])
    conns = bag["connections"]
    assert conns["/scan"] == ("sensor_msgs/msg/LaserScan", counts["n_scans"])
    assert conns["/amcl_pose"][0] == "geometry_msgs/msg/PoseWithCovarianceStamped"
    assert conns["/odom"][0] == "nav_msgs/msg/Odometry"
    assert conns["/tf_static"] == ("tf2_msgs/msg/TFMessage", 1)
    (tf,) = [m.transforms[0] for _, m in bag["/tf_static"]]
    assert (tf.header.frame_id, tf.child_frame_id) == ("base_link", "laser")
    assert (tf.transform.translation.x, tf.transform.translation.z) == (0.0, 0.3)
    assert {m.header.frame_id for _, m in bag["/amcl_pose"]} == {"map"}
    assert {(m.header.frame_id, m.child_frame_id) for _, m in bag["/odom"]} == {("odom", "base_link")}
    scan = bag["/scan"][0][1]
    assert len(scan.ranges) == 1081 and scan.range_max == 20.0
    assert scan.angle_min == pytest.approx(-3 * math.pi / 4, abs=1e-6)
    # messages are in time order and every stamp equals its record time
    for topic in ["/scan", "/amcl_pose", "/odom"]:
        times = np.array([t for t, _ in bag[topic]])
        assert np.all(np.diff(times) > 0), topic
        assert all(t == stamp_ns(m.header) for t, m in bag[topic]), topic
    # the AMCL stream brackets the scans, is not synchronized with them, about 10 Hz
    pose_t = np.array([t for t, _ in bag["/amcl_pose"]])
    scan_t = np.array([t for t, _ in bag["/scan"]])
    assert pose_t[0] < scan_t[0] and pose_t[-1] > scan_t[-1]
    assert not set(pose_t) & set(scan_t)
    assert np.median(np.diff(pose_t)) == pytest.approx(1e8, rel=0.05)
    cov = np.asarray(bag["/amcl_pose"][0][1].pose.covariance)
    assert cov[0] == cov[7] == pytest.approx(0.05**2) and cov[35] == pytest.approx(0.02**2)


def test_amcl_pose_is_the_true_pose_plus_the_recorded_error(tmp_path):
    b = parse_building(ROOM, "tiny.yaml")
    rec = simulate_recording(b, scanner_from_config("2d", {}), SimParams(), seed=4)
    traj = rover_trajectory(b.waypoints, 0.3, 1.0)
    truth = traj.at((rec.pose_t_ns - SimParams().start_time_ns) / 1e9)
    d = rec.amcl - truth
    d[:, 2] = (d[:, 2] + np.pi) % (2 * np.pi) - np.pi
    np.testing.assert_allclose(d, rec.amcl_error, atol=1e-9)
    assert np.abs(rec.amcl_error[:, :2]).max() > 0.005  # there is an error


def test_gauss_markov_std_and_correlation():
    rng = np.random.default_rng(0)
    e = gauss_markov(200_000, 0.1, 0.05, 2.0, rng)
    assert e.std() == pytest.approx(0.05, rel=0.05)
    lag1 = np.corrcoef(e[:-1], e[1:])[0, 1]
    assert lag1 == pytest.approx(math.exp(-0.1 / 2.0), abs=0.005)
    lag20 = np.corrcoef(e[:-20], e[20:])[0, 1]  # 2 s = one correlation time
    assert lag20 == pytest.approx(math.exp(-1), abs=0.03)
    white = gauss_markov(100_000, 0.1, 1.0, 0.0, np.random.default_rng(1))
    assert abs(np.corrcoef(white[:-1], white[1:])[0, 1]) < 0.01
    again = gauss_markov(200_000, 0.1, 0.05, 2.0, np.random.default_rng(0))
    np.testing.assert_array_equal(e, again)


def test_trajectory_drives_the_waypoints_at_speed_and_turns_smoothly():
    wps = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 2.0], [0.0, 2.0]])
    tr = rover_trajectory(wps, 0.3, 1.0)
    for w in wps:
        assert np.hypot(*(tr.xy - w).T).min() < 0.021
    step = np.hypot(*np.diff(tr.xy, axis=0).T) / np.diff(tr.t)
    assert step.max() == pytest.approx(0.3, rel=1e-6)
    assert np.median(step) == pytest.approx(0.3, rel=0.01)
    assert np.abs(np.diff(tr.yaw)).max() <= 1.0 * 0.01 + 1e-12  # yaw rate limit
    assert tr.yaw[-1] - tr.yaw[0] == pytest.approx(math.pi, abs=0.05)  # two left turns
    # 8 m at 0.3 m/s plus two 90 degree turns of about 2 s each
    assert 27 < tr.duration_s < 34


def test_true_poses_and_scan_count(rec2d):
    outs, counts = rec2d
    tp = read_table(outs["true_poses"])
    assert list(tp.columns) == ["t_ns", "x", "y", "z", "yaw"]
    assert tp["t_ns"].dtype == np.int64
    assert np.all(np.diff(tp["t_ns"]) == 100_000_000)  # 10 Hz
    assert np.all(tp["z"] == 0.3)
    assert tp[["x", "y"]].iloc[0].tolist() == [-1.0, 0.0]
    assert np.hypot(tp["x"].iloc[-1] - 0.2, tp["y"].iloc[-1] + 0.6) < 0.021 + 0.03  # last scan <= 0.1 s early
    tr = rover_trajectory(np.array(ROOM["waypoints"]), 0.3, 1.0)
    assert len(tp) == math.floor(tr.duration_s * 10) + 1


def test_odometry_drifts_by_its_scale_error(tmp_path):
    straight = dict(ROOM, waypoints=[[-1.5, 0.0], [1.5, 0.0]])
    b = parse_building(straight, "tiny.yaml")
    p = SimParams(odom_scale_error=0.05, odom_yaw_drift_rad_s=0.0)
    rec = simulate_recording(b, scanner_from_config("2d", {}), p, seed=0)
    assert rec.odom[0, :3].tolist() == [0.0, 0.0, 0.0]
    assert rec.odom[-1, 0] == pytest.approx(3.0 * 1.05, abs=0.03)
    assert abs(rec.odom[-1, 1]) < 0.02


def test_walls_geojson_is_the_ground_truth(rec2d):
    import json

    outs, _ = rec2d
    gt = json.loads(Path(outs["walls"]).read_text())
    assert gt["slice_height_m"] == 0.3
    kinds = [f["properties"]["kind"] for f in gt["features"]]
    assert kinds.count("axis") == 4 and kinds.count("footprint") >= 1
    faces = [np.array(f["geometry"]["coordinates"]) for f in gt["features"]
             if f["properties"]["kind"] == "face"]
    # inner perimeter 2 * (4 + 3) = 14 m, minus the 0.9 m door, plus two 0.1 m jambs
    assert sum(np.hypot(*(f[1] - f[0])) for f in faces) == pytest.approx(14 - 0.9 + 0.2)


# ----------------------------------------------------------------------- bad input


def test_unknown_scanner_and_bad_seed(tmp_path):
    with pytest.raises(InputError, match=r"datasets\.tiny\.scanner: 'lidar9'"):
        run(tmp_path, scanner="lidar9")
    with pytest.raises(InputError, match=r"datasets\.tiny\.seed"):
        run(tmp_path, seed=-1)


def test_negative_noise_is_rejected(tmp_path):
    from floorscan.core.config import ConfigError

    with pytest.raises(ConfigError, match=r"simulate\.pose_position_std_m: -0\.1 is less than the minimum of 0"):
        run(tmp_path, cfg=dict(CFG, pose_position_std_m=-0.1))
    with pytest.raises(InputError, match=r"scanners\.2d\.range_noise_std_m"):
        run(tmp_path, cfg={"scanners": {"2d": {"range_noise_std_m": -0.01}}})
    assert not (tmp_path / "sim" / "recording.bag").exists()


def test_zero_beam_scanner_is_rejected(tmp_path):
    with pytest.raises(InputError, match=r"scanners\.3d\.n_beams"):
        run(tmp_path, scanner="3d", cfg={"scanners": {"3d": {"n_beams": 0}}})


def test_waypoint_in_a_wall_names_the_building_file(tmp_path):
    bad = dict(ROOM, waypoints=[[0.0, 0.0], [2.04, 0.0]])
    with pytest.raises(InputError, match=r"tiny\.yaml: waypoints\[1\].*wall 'room'"):
        run(tmp_path, building=bad)


def test_schema_defaults_equal_the_dataclass_defaults():
    from dataclasses import fields

    schema = yaml.safe_load(SCHEMA.read_text())
    props = schema["properties"]
    for f in fields(SimParams):
        assert props[f.name]["default"] == f.default, f.name
    assert set(props) == {f.name for f in fields(SimParams)} | {"scanners"}
    for cls, key in [(Scanner2D, "scanner2d"), (Scanner3D, "scanner3d")]:
        sprops = schema["$defs"][key]["properties"]
        assert set(sprops) == {f.name for f in fields(cls)}
        for f in fields(cls):
            assert sprops[f.name]["default"] == f.default, (key, f.name)


def test_observed_faces_are_the_seen_parts_of_the_faces(rec2d):
    import json

    outs, _ = rec2d
    gt = json.loads(Path(outs["walls"]).read_text())

    def total(kind):
        return sum(np.hypot(*np.subtract(*np.array(f["geometry"]["coordinates"])))
                   for f in gt["features"] if f["properties"]["kind"] == kind)

    # the rover drives inside the 4 x 3 m room: it sees most of it, not the box's shadow
    assert 0.8 * total("face") < total("observed_face") < total("face")

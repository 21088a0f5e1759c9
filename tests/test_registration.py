"""Tests of the register stage's registration (floorscan.register: pipeline, stream,
icp, prepare and the strategies; thesis 3.2.2, 3.5, Algorithm 3): exact synthetic
geometry, drop reasons, and checks on the real recordings in ../shared/data."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from conftest import cast_rays
from floorscan.core.geometry import transform_points
from floorscan.register.icp import fitness_against, icp_planar
from floorscan.register.params import RegistrationConfig
from floorscan.register.pipeline import register_scans
from floorscan.register.prepare import normals_2d
from floorscan.register.result import RegistrationError

REPO = Path(__file__).resolve().parents[1]
SHARED_DATA = (REPO / ".." / "shared" / "data").resolve()
needs_shared = pytest.mark.skipif(
    not SHARED_DATA.is_dir(), reason=f"real recordings not found at {SHARED_DATA} (../shared/data)"
)

# A 10 m x 6 m room with a 2 m x 1.5 m notch and a free-standing 1.5 m pillar wall, so
# that no translation or rotation leaves it unchanged.
ROOM = np.array([[0, 0], [10, 0], [10, 6], [4, 6], [4, 4.5], [2, 4.5], [2, 6], [0, 6], [0, 0]], float)
PILLAR = np.array([[6.0, 2.0], [6.0, 3.5]])
SEGMENTS = np.concatenate(
    [np.stack([ROOM[:-1], ROOM[1:]], axis=1), PILLAR[None]], axis=0
)  # (S, 2, 2)


def ray_cast(pose, n_beams=360, fov=2 * np.pi, max_range=20.0, noise=0.0, rng=None, z_beams=(0.0,)):
    """Points (scanner frame) of a scanner at pose (x, y, yaw) in ROOM, one ring per z_beam
    elevation (radians) for 3D scans (walls are vertical; floor and ceiling not modelled)."""
    x, y, yaw = pose
    ang = yaw - fov / 2 + np.arange(n_beams) * fov / n_beams
    r = cast_rays(SEGMENTS, (x, y), ang)
    ok = r < max_range
    if noise and rng is not None:
        r = r + rng.normal(0, noise, len(r))
    local = np.stack([r * np.cos(ang - yaw), r * np.sin(ang - yaw)], axis=1)[ok]
    rings = []
    for el in z_beams:
        horiz = local * 1.0
        rings.append(np.column_stack([horiz, np.linalg.norm(horiz, axis=1) * math.tan(el)]))
    return np.concatenate(rings)


def trajectory(n=30, speed=0.3, dt=0.5):
    """A path through the room: along the lower part, turning slowly. (x, y, yaw), t_ns."""
    s = np.arange(n) * speed * dt
    x = 1.5 + s
    y = 1.5 + 0.5 * np.sin(s / 2.0)
    yaw = 0.3 * np.sin(s / 3.0)
    t_ns = 1_700_000_000_000_000_000 + (np.arange(n) * dt * 1e9).astype(np.int64)
    return np.stack([x, y, yaw], axis=1), t_ns


def recording(poses_true, t_ns, pose_error=None, seed=0, noise=0.0, **kw):
    """scans, scan_index, poses tables of a simulated 2D recording."""
    rng = np.random.default_rng(seed)
    rows, idx, pr = [], [], []
    for i, (p, t) in enumerate(zip(poses_true, t_ns)):
        pts = ray_cast(p, noise=noise, rng=rng, **kw)
        rows.append(pd.DataFrame({"scan_id": i, "x": pts[:, 0], "y": pts[:, 1], "z": pts[:, 2]}))
        idx.append((i, int(t)))
        e = pose_error[i] if pose_error is not None else (0.0, 0.0, 0.0)
        pr.append((i, int(t), p[0] + e[0], p[1] + e[1], 0.0, p[2] + e[2], True, ""))
    scans = pd.concat(rows, ignore_index=True).astype({"scan_id": np.int32, "x": np.float32, "y": np.float32, "z": np.float32})
    index = pd.DataFrame(idx, columns=["scan_id", "t_ns"])
    poses = pd.DataFrame(pr, columns=["scan_id", "t_ns", "x", "y", "z", "yaw", "valid", "reason"])
    return scans, index, poses


def tree_of(points):
    from scipy.spatial import cKDTree

    return cKDTree(points)


# --------------------------------------------------------------------------- geometry


@pytest.mark.parametrize("method", ["point_to_point", "point_to_plane"])
def test_icp_recovers_known_offset_exactly(method):
    true = (3.0, 2.0, 0.0, 0.4)
    src = ray_cast((true[0], true[1], true[3]), n_beams=720)
    target = transform_points(src, *true)
    tree = tree_of(target)
    nrm = normals_2d(target, tree, 10) if method == "point_to_plane" else None
    init = (true[0] + 0.12, true[1] - 0.08, 0.0, true[3] + math.radians(3))
    pose, n = icp_planar(src, target, tree, init, 0.5, method=method, normals=nrm, max_iterations=100, tolerance=1e-9)
    assert n == len(src)
    assert abs(pose[0] - true[0]) < 1e-3 and abs(pose[1] - true[1]) < 1e-3
    assert abs(pose[3] - true[3]) < math.radians(0.1)
    assert pose[2] == 0.0


def test_icp_between_two_viewpoints_within_mm():
    """Different beams hit the walls from two poses 0.4 m apart: ICP against the first
    scan still recovers the second pose within a few mm and 0.1 degree."""
    a, b = (3.0, 2.0, 0.2), (3.4, 2.1, 0.3)
    target = transform_points(ray_cast(a, n_beams=1440), a[0], a[1], 0.0, a[2])
    src = ray_cast(b, n_beams=1440)
    tree = tree_of(target)
    init = (b[0] + 0.1, b[1] - 0.1, 0.0, b[2] - math.radians(2))
    pose = init
    for d in (0.3, 0.1):
        pose, _ = icp_planar(src, target, tree, pose, d, method="point_to_plane",
                             normals=normals_2d(target, tree, 10), max_iterations=100, tolerance=1e-9)
    assert math.hypot(pose[0] - b[0], pose[1] - b[1]) < 0.005
    assert abs(pose[3] - b[2]) < math.radians(0.1)


def test_icp_matches_open3d_point_to_point_on_2d_scans():
    o3d = pytest.importorskip("open3d")
    a, b = (3.0, 2.0, 0.2), (3.3, 2.1, 0.25)
    target = transform_points(ray_cast(a, n_beams=720), a[0], a[1], 0.0, a[2])
    src = ray_cast(b, n_beams=720)
    init = (b[0] + 0.05, b[1] - 0.05, 0.0, b[2] + 0.02)
    pose, _ = icp_planar(src, target, tree_of(target), init, 0.2, max_iterations=200, tolerance=1e-10)
    T0 = np.eye(4)
    c, s = math.cos(init[3]), math.sin(init[3])
    T0[:2, :2] = [[c, -s], [s, c]]
    T0[:2, 3] = init[:2]
    pc = lambda p: o3d.geometry.PointCloud(o3d.utility.Vector3dVector(p))  # noqa: E731
    res = o3d.pipelines.registration.registration_icp(
        pc(src), pc(target), 0.2, T0,
        o3d.pipelines.registration.TransformationEstimationPointToPoint(),
        o3d.pipelines.registration.ICPConvergenceCriteria(1e-12, 1e-12, 200),
    )
    T = res.transformation
    assert abs(T[0, 3] - pose[0]) < 1e-4 and abs(T[1, 3] - pose[1]) < 1e-4
    assert abs(math.atan2(T[1, 0], T[0, 0]) - pose[3]) < 1e-5
    assert abs(T[2, 3]) < 1e-9  # 2D point-to-point stays planar in Open3D too


def test_fitness_identical_is_one_and_matches_open3d():
    o3d = pytest.importorskip("open3d")
    pts = ray_cast((3.0, 2.0, 0.1))
    f, rmse, n = fitness_against(pts, tree_of(pts), 0.05)
    assert f == 1.0 and rmse == 0.0 and n == len(pts)
    rng = np.random.default_rng(3)
    src, tgt = rng.uniform(0, 2, (500, 3)), rng.uniform(0, 2, (400, 3))
    f, rmse, _ = fitness_against(src, tree_of(tgt), 0.1)
    pc = lambda p: o3d.geometry.PointCloud(o3d.utility.Vector3dVector(p))  # noqa: E731
    ref = o3d.pipelines.registration.evaluate_registration(pc(src), pc(tgt), 0.1, np.eye(4))
    assert 0.1 < f < 0.9
    assert f == pytest.approx(ref.fitness, abs=1e-12)
    assert rmse == pytest.approx(ref.inlier_rmse, rel=1e-9)


def test_transform_points_does_not_mutate():
    p = np.array([[1.0, 0.0, 0.5]])
    q = transform_points(p, 1.0, 2.0, 0.2, math.pi / 2)
    np.testing.assert_allclose(q, [[1.0, 3.0, 0.7]], atol=1e-12)
    np.testing.assert_array_equal(p, [[1.0, 0.0, 0.5]])


# --------------------------------------------------------------------------- pipeline


def test_registration_corrects_a_pose_error_and_keeps_good_scans():
    true, t = trajectory(30)
    err = np.zeros((30, 3))
    err[10] = (0.10, -0.06, math.radians(2.0))  # AMCL-like error on one scan
    scans, index, poses = recording(true, t, err)
    r = register_scans(scans, index, poses, {"every_n": 1, "reference": "previous"})
    tb = r.table.set_index("scan_id")
    assert tb["kept"].all()
    assert tb.loc[0, "reason"] == "anchor" and (tb["reason"].iloc[1:] == "").all()
    # the bad scan is pulled back onto its neighbours: correction ~ -error
    assert tb.loc[10, "dx_m"] == pytest.approx(-0.10, abs=0.01)
    assert tb.loc[10, "dy_m"] == pytest.approx(0.06, abs=0.01)
    assert tb.loc[10, "dyaw_rad"] == pytest.approx(-math.radians(2.0), abs=math.radians(0.2))
    assert tb.loc[10, "fitness_icp"] > tb.loc[10, "fitness_prior"]
    assert tb.loc[10, "fitness_icp"] > 0.95
    # registered points are the kept scans in the map frame
    reg = r.registered
    assert reg["scan_id"].nunique() == 30 and len(reg) == len(scans)
    assert reg.dtypes["x"] == np.float32
    p10 = reg[reg["scan_id"] == 10][["x", "y"]].to_numpy()
    want = transform_points(scans[scans["scan_id"] == 10][["x", "y", "z"]].to_numpy(), true[10, 0], true[10, 1], 0, true[10, 2])
    assert np.median(np.linalg.norm(p10 - want[:, :2], axis=1)) < 0.01


def test_every_nth_and_not_sampled():
    true, t = trajectory(23)
    scans, index, poses = recording(true, t)
    r = register_scans(scans, index, poses, {"every_n": 5, "reference": "previous"})
    tb = r.table
    assert list(tb.index[tb["kept"]]) == [0, 5, 10, 15, 20]
    assert (tb.loc[~tb["kept"], "reason"] == "not_sampled").all()
    assert r.summary["counts"] == {"": 4, "anchor": 1, "not_sampled": 18}
    assert tb.loc[~tb["kept"], ["x_m", "y_m"]].notna().all().all()  # localizer pose kept


def test_drop_reasons_too_few_duplicate_pose_jump_no_pose():
    true, t = trajectory(20)
    scans, index, poses = recording(true, t)
    # scan 3: only 10 points; scan 6: same stamp as scan 5; scan 9: same points as 8
    scans = scans[(scans["scan_id"] != 3) | (scans.groupby("scan_id").cumcount() < 10)]
    index.loc[6, "t_ns"] = index.loc[5, "t_ns"]
    p8 = scans[scans["scan_id"] == 8].assign(scan_id=np.int32(9))
    scans = pd.concat([scans[scans["scan_id"] != 9], p8]).sort_values("scan_id", kind="stable")
    # scan 12: pose 3 m off (a jump); scan 15: no pose
    poses.loc[12, "x"] += 3.0
    poses.loc[15, ["x", "y", "yaw"]] = np.nan
    poses.loc[15, ["valid", "reason"]] = (False, "pose_gap")
    r = register_scans(scans, index, poses, {"every_n": 1})
    reason = r.table.set_index("scan_id")["reason"]
    assert reason[3] == "too_few_points"
    assert reason[6] == "duplicate" and reason[9] == "duplicate"
    assert reason[12] == "pose_jump" and reason[13] == ""  # only the outlier is dropped
    assert reason[15] == "no_pose:pose_gap"
    assert r.summary["counts"]["pose_jump"] == 1
    assert set(r.registered["scan_id"]) == set(range(20)) - {3, 6, 9, 12, 15}
    assert np.isnan(r.table.loc[15, "x_m"])


def test_low_prior_fitness_drops_a_bad_pose():
    true, t = trajectory(20)
    err = np.zeros((20, 3))
    err[8] = (0.0, 0.0, math.radians(60))  # within the turn-rate limit, far off
    scans, index, poses = recording(true, t, err)
    r = register_scans(scans, index, poses, {"every_n": 1, "max_turn_rate_rad_s": 10, "reference": "previous"})
    row = r.table.loc[8]
    assert row["reason"] == "low_prior_fitness" and not row["kept"]
    assert row["fitness_prior"] < 0.15
    assert r.summary["fraction_of_checked"]["low_prior_fitness"] == pytest.approx(1 / 19)


def test_all_dropped_error_names_the_threshold():
    true, t = trajectory(10)
    scans, index, poses = recording(true, t)
    with pytest.raises(RegistrationError, match=r"too_few_points.*min_points"):
        register_scans(scans, index, poses, {"min_points": 100000})
    rng = np.random.default_rng(1)
    err = np.column_stack([np.zeros(10), np.zeros(10), rng.choice([-1, 1], 10) * 0.5])
    scans, index, poses = recording(true, t, err)
    with pytest.raises(RegistrationError, match=r"low_prior_fitness': 9.*register.min_prior_fitness=0.9"):
        register_scans(scans, index, poses, {"every_n": 1, "min_prior_fitness": 0.9, "max_turn_rate_rad_s": 100,
                                             "pose_jump_slack_rad": 2, "reference": "previous"})


def test_deterministic_same_input_same_output():
    true, t = trajectory(15)
    rng = np.random.default_rng(7)
    err = rng.normal(0, [0.03, 0.03, 0.01], (15, 3))
    scans, index, poses = recording(true, t, err, seed=5, noise=0.01)
    a = register_scans(scans, index, poses, {"every_n": 1})
    b = register_scans(scans.copy(), index.copy(), poses.copy(), {"every_n": 1})
    pd.testing.assert_frame_equal(a.table, b.table)
    pd.testing.assert_frame_equal(a.registered, b.registered)
    c = recording(true, t, err, seed=6, noise=0.01)[0]  # other seed, other noise
    assert not register_scans(c, index, poses, {"every_n": 1}).table["dx_m"].equals(a.table["dx_m"])


def test_registration_reduces_noisy_pose_error():
    """AMCL-like independent errors (3 cm, 1 deg): aligning each scan to its neighbours
    lowers the RMS position error against the truth (measured 4.4 -> 3.5 cm)."""
    true, t = trajectory(40, dt=0.3)
    rng = np.random.default_rng(11)
    err = rng.normal(0, [0.03, 0.03, math.radians(1)], (40, 3))
    scans, index, poses = recording(true, t, err, seed=1, noise=0.005)
    r = register_scans(scans, index, poses, {"every_n": 1})
    tb = r.table[r.table["kept"]]
    before = np.sqrt(np.mean(np.sum(err[tb.index, :2] ** 2, axis=1)))
    after = np.sqrt(np.mean((tb["x_m"] - true[tb.index, 0]) ** 2 + (tb["y_m"] - true[tb.index, 1]) ** 2))
    assert len(tb) == 40
    assert after < 0.85 * before


def test_3d_scans_keep_z_and_recover_planar_pose():
    true, t = trajectory(12)
    err = np.zeros((12, 3))
    err[6] = (0.08, 0.05, math.radians(1.5))
    el = np.radians(np.linspace(-15, 15, 16))
    scans, index, poses = recording(true, t, err, n_beams=360, z_beams=el)
    poses["z"] = 0.4
    r = register_scans(scans, index, poses, {"every_n": 1, "voxel_size_m": 0.05, "reference": "previous"})
    tb = r.table.set_index("scan_id")
    assert tb["kept"].all() and (tb["z_m"] == 0.4).all()
    assert tb.loc[6, "x_m"] == pytest.approx(true[6, 0], abs=0.01)
    assert tb.loc[6, "y_m"] == pytest.approx(true[6, 1], abs=0.01)
    assert tb.loc[6, "yaw_rad"] == pytest.approx(true[6, 2], abs=math.radians(0.2))
    z = r.registered.loc[r.registered["scan_id"] == 6, "z"].to_numpy()
    assert z.min() == pytest.approx(0.4 + scans.loc[scans["scan_id"] == 6, "z"].min(), abs=1e-5)


def _relative_to_first(poses_xy_yaw):
    """(x, y, yaw) rows expressed in the frame of the first row (the odometry map frame)."""
    p = np.asarray(poses_xy_yaw, dtype=np.float64)
    c, s = math.cos(-p[0, 2]), math.sin(-p[0, 2])
    d = p[:, :2] - p[0, :2]
    yaw = (p[:, 2] - p[0, 2] + np.pi) % (2 * np.pi) - np.pi
    return np.column_stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1], yaw])


@pytest.mark.parametrize("rings", [1, 16], ids=["2d", "3d"])
def test_odometry_mode_follows_the_true_path(rings):
    """Pose-free mode: the first scan defines the map frame; the poses of the others
    relative to it come out within mm (measured max 2.4 mm 2D, 1.8 mm 3D)."""
    true, t = trajectory(25, dt=0.4)
    z_beams = (0.0,) if rings == 1 else tuple(np.radians(np.linspace(-15, 15, rings)))
    scans, index, _ = recording(true, t, z_beams=z_beams)
    r = register_scans(scans, index, None, {"mode": "odometry", "every_n": 1})
    tb = r.table[r.table["kept"]]
    assert len(tb) == 25
    rel = _relative_to_first(true)
    np.testing.assert_allclose(tb[["x_m", "y_m"]].to_numpy(), rel[:, :2], atol=0.01)
    np.testing.assert_allclose(tb["yaw_rad"], rel[:, 2], atol=math.radians(0.2))
    assert (tb["z_m"] == 0.0).all()
    # fitness at the constant-velocity prediction (no localizer to screen by): high here
    assert np.isnan(tb["fitness_prior"].iloc[0]) and (tb["fitness_prior"].iloc[1:] > 0.9).all()
    assert tb["reason"].iloc[0] == "anchor"

def test_odometry_restarts_from_rest_after_a_stop():
    """A rover that stands still repeats its scan exactly (a simulator, a paused
    bag): those scans are duplicates, and the next moving scan is predicted from rest,
    not by carrying the velocity from before the stop across it (which put it 2.5 m
    ahead here, beyond the ICP's reach). Poses after the stop within 1 cm."""
    dt, speed = 0.1, 0.5
    moving = np.arange(12) * speed * dt
    s = np.concatenate([moving, np.full(50, moving[-1]), moving[-1] + np.arange(1, 13) * speed * dt])
    true = np.stack([1.0 + s, np.full_like(s, 1.5), np.zeros_like(s)], axis=1)
    t = 1_700_000_000_000_000_000 + (np.arange(len(s)) * dt * 1e9).astype(np.int64)
    scans, index, _ = recording(true, t)
    r = register_scans(scans, index, None, {"mode": "odometry", "every_n": 1, "loop_closure": False})
    tb = r.table
    assert r.summary["counts"]["duplicate"] == 50
    ok = tb["x_m"].notna().to_numpy()
    assert ok.sum() == len(s) - 50
    rel = _relative_to_first(true)
    err = np.hypot(tb["x_m"].to_numpy()[ok] - rel[ok, 0], tb["y_m"].to_numpy()[ok] - rel[ok, 1])
    assert err.max() < 0.01


def test_constant_velocity_prediction_keeps_turning():
    """The motion between the last two poses, in the first one's frame, is repeated
    (scaled by the time ratio): 1 m ahead then a quarter turn -> another metre along
    the new heading and another quarter turn."""
    from floorscan.register.odometry import predict_constant_velocity

    p = predict_constant_velocity((0.0, 0.0, 0.5, 0.0), 0, (1.0, 0.0, 0.5, math.pi / 2), 10**9, 2 * 10**9)
    np.testing.assert_allclose(p[:3], (1.0, 1.0, 0.5), atol=1e-12)
    assert abs(abs(p[3]) - math.pi) < 1e-12
    half = predict_constant_velocity((0.0, 0.0, 0.0, 0.0), 0, (0.2, 0.0, 0.0, 0.0), 10**9, 15 * 10**8)
    np.testing.assert_allclose(half, (0.3, 0.0, 0.0, 0.0), atol=1e-12)
    assert predict_constant_velocity((0, 0, 0, 0), 5, (1.0, 2.0, 0.0, 0.3), 5, 9) == (1.0, 2.0, 0.0, 0.3)


def test_odometry_drops_a_failed_scan_and_goes_on_from_the_prediction():
    """A scan that matches nothing (its points 100 m away) is dropped as icp_failed and
    has no pose; the chain continues from the constant-velocity prediction, so the
    scans after it are still registered within 1 cm. every_n=3: all usable scans feed
    the odometry, only every third is kept, the others still get their pose."""
    true, t = trajectory(25, dt=0.4)
    scans, index, _ = recording(true, t)
    far = scans["scan_id"] == 12
    scans.loc[far, "x"] += 100.0
    r = register_scans(scans, index, None, {"mode": "odometry", "every_n": 3})
    tb = r.table.set_index("scan_id")
    assert tb.loc[12, "reason"] == "icp_failed" and not tb.loc[12, "kept"] and np.isnan(tb.loc[12, "x_m"])
    assert r.summary["counts"] == {"": 7, "anchor": 1, "icp_failed": 1, "not_sampled": 16}
    assert list(tb.index[tb["kept"]]) == [0, 3, 6, 9, 15, 18, 21, 24]
    rel = _relative_to_first(true)
    ok = tb["x_m"].notna().to_numpy()
    assert ok.sum() == 24  # every scan but the failed one has a pose
    err = np.hypot(tb["x_m"].to_numpy()[ok] - rel[ok, 0], tb["y_m"].to_numpy()[ok] - rel[ok, 1])
    assert err.max() < 0.01


def test_scan_clouds_drop_floor_and_ceiling_from_3d_icp():
    """3D scans: the ICP cloud keeps the walls (vertical normals) on the coarse grid and
    none of the floor; 2D scans keep every point for fitness."""
    from floorscan.register.prepare import graph_cloud, scan_clouds

    g = np.arange(-3.0, 3.0, 0.05)
    gx, gy = np.meshgrid(g, g)
    floor = np.column_stack([gx.ravel(), gy.ravel(), np.full(gx.size, -0.4)])
    h = np.arange(-0.4, 2.0, 0.05)
    wx, wz = np.meshgrid(g, h)
    wall = np.column_stack([wx.ravel(), np.full(wx.size, 3.0), wz.ravel()])
    cfg = RegistrationConfig()
    c = scan_clouds(np.concatenate([floor, wall]), cfg)
    assert len(c.icp) > 100
    assert np.all(np.abs(c.icp[:, 1] - 3.0) < 0.1)  # wall points only
    assert np.isclose(c.fit_source[:, 2], -0.4, atol=0.15).sum() > 100  # fitness keeps the floor
    assert len(c.fit_target) > len(c.fit_source)  # finer reference grid
    flat = np.column_stack([np.arange(50.0), np.zeros(50), np.zeros(50)])
    c2 = scan_clouds(flat, cfg)
    np.testing.assert_array_equal(c2.fit_source, flat)
    # the pose graph gets the wall projected to the xy plane on a 5 cm 2D grid: one
    # point per 5 cm of wall (120 columns of 6 m; the grid cuts one column in two
    # halves at most), none of the floor or the ceiling (each cell of them holds
    # points of one height, with 1 cm of noise), a 0.3 m box side (0.2 m extent) kept
    rng = np.random.default_rng(0)
    ceiling = floor + [0.0, 0.0, 2.4]
    box = np.column_stack([np.full(7, -2.0), np.full(7, 0.0), np.linspace(-0.4, -0.1, 7)])
    noisy = np.concatenate([floor, ceiling]) + rng.normal(0.0, 0.01, (2 * len(floor), 3)) * [0, 0, 1]
    g3 = graph_cloud(np.concatenate([noisy, wall, box]), cfg)
    on_wall = np.isclose(g3[:, 1], 3.0)
    assert 115 <= on_wall.sum() <= 125 and np.all(g3[:, 2] == 0.0)
    np.testing.assert_allclose(g3[~on_wall], [[-2.0, 0.0, 0.0]], atol=0.05)  # the box side (its cell mean), only
    assert len(graph_cloud(np.concatenate([noisy, wall]), RegistrationConfig(graph={"vertical_extent_m": 2.5}))) == 0
    # no gap limit: floor and ceiling (2.4 m apart) make every cell a wall
    loose = graph_cloud(np.concatenate([noisy, wall]), RegistrationConfig(graph={"max_height_gap_m": 3.0}))
    assert len(loose) > 14000
    np.testing.assert_array_equal(graph_cloud(flat, cfg), flat)


@pytest.mark.parametrize("z_beams", [(0.0,), tuple(np.radians([-10.0, 0.0, 10.0]))], ids=["2d", "3d"])
def test_streamed_registration_matches_the_in_memory_one(tmp_path, z_beams):
    """register_recording (points streamed from a file, written scan by scan) gives the
    table and points of register_scans, and the figure's density raster of the file
    counts every point."""
    from floorscan.core.io import SCANS, read_table, write_table
    from floorscan.register.stream import register_recording

    true, t = trajectory(16)
    rng = np.random.default_rng(2)
    err = rng.normal(0, [0.03, 0.03, 0.01], (16, 3))
    scans, index, poses = recording(true, t, err, seed=3, noise=0.005, z_beams=z_beams)
    scans = scans[scans["scan_id"] != 4]  # a scan without points: too_few_points
    write_table(scans, tmp_path / "scans.parquet", schema=SCANS)
    cfg = {"every_n": 2}
    a = register_scans(scans, index, poses, cfg)
    b = register_recording(tmp_path / "scans.parquet", index, poses, cfg, tmp_path / "reg.parquet",
                           metadata={"dataset": "t"})
    pd.testing.assert_frame_equal(a.table, b.table)
    reg = read_table(tmp_path / "reg.parquet")
    pd.testing.assert_frame_equal(reg, a.registered)
    assert b.table.loc[4, "reason"] == "too_few_points"
    assert b.registered is None
    assert not list(tmp_path.glob(".reg.parquet*"))  # the temporary file of the sampled scans is gone
    # the figure job's raster, streamed from the file, counts every point
    from floorscan.figures.registration import density_of_file

    f = density_of_file(tmp_path / "reg.parquet", 0.05)
    assert f.grid()[2].sum() == len(reg)
    # its extent comes from the x, y statistics, the only float ones written
    import pyarrow.parquet as pq

    group = pq.ParquetFile(tmp_path / "reg.parquet").metadata.row_group(0)
    assert [group.column(i).is_stats_set for i in range(4)] == [True, True, True, False]  # scan_id x y z
    xy = reg[["x", "y"]].to_numpy(np.float64)
    np.testing.assert_allclose(f.lo, xy.min(axis=0), atol=1e-6)


def test_registered_map_figure_sums_cells_into_blocks(tmp_path):
    """A map wider than the figure is drawn on blocks of cells, their counts summed
    (a one-point cell of a far wall stays visible instead of being skipped)."""
    from floorscan.figures.registration import coarsen_counts, plot_registered_map

    h = np.arange(35, dtype=float).reshape(5, 7)
    ex, ey = np.arange(8) * 0.05, 1.0 + np.arange(6) * 0.05
    ex2, ey2, h2, factor = coarsen_counts(ex, ey, h, 3)
    assert factor == 3 and h2.shape == (2, 3)
    assert h2[0, 0] == h[:3, :3].sum() and h2[1, 2] == h[3:, 6:].sum() and h2.sum() == h.sum()
    np.testing.assert_allclose(ex2, [0.0, 0.15, 0.3, 0.45])
    np.testing.assert_allclose(ey2, [1.0, 1.15, 1.3])
    assert coarsen_counts(ex, ey, h, 7)[3] == 1
    # a 150 m wide map of 5 cm cells: drawn, on 30 cm blocks
    xy = np.c_[np.linspace(0, 150, 2000), np.zeros(2000)]
    table = pd.DataFrame({"kept": [True], "x_m": [0.0], "y_m": [0.0]})
    plot_registered_map(pd.DataFrame({"x": xy[:, 0], "y": xy[:, 1]}), table, tmp_path / "map.png")
    assert (tmp_path / "map.png").stat().st_size > 10_000


@pytest.mark.slow
def test_edges_aligned_while_reading_are_the_edges(tmp_path, caplog):
    """With edge workers the pose graph's pairs are aligned while the scans are read,
    for the scans the index and poses say will be sampled; a scan the points drop
    (scan 5: no points) shifts the sampling after it, and the pairs not expected are
    aligned afterwards. Same table and points as without workers, in memory."""
    import logging

    from floorscan.core.io import SCANS, read_table, write_table
    from floorscan.register.stream import register_recording

    true, t = trajectory(16)
    err = np.random.default_rng(2).normal(0, [0.03, 0.03, 0.01], (16, 3))
    scans, index, poses = recording(true, t, err, seed=3, noise=0.005)
    scans = scans[scans["scan_id"] != 5]
    write_table(scans, tmp_path / "scans.parquet", schema=SCANS)
    a = register_scans(scans, index, poses, {"every_n": 1})
    with caplog.at_level(logging.INFO, logger="floorscan.register.edges"):
        b = register_recording(tmp_path / "scans.parquet", index, poses, {"every_n": 1, "graph": {"workers": 2}},
                               tmp_path / "reg.parquet")
    pd.testing.assert_frame_equal(a.table, b.table)
    pd.testing.assert_frame_equal(read_table(tmp_path / "reg.parquet"), a.registered)
    assert b.table.loc[5, "reason"] == "too_few_points"
    # pairs with scan 5 were expected and never sent; the pairs across the gap were not expected
    line = [r.getMessage() for r in caplog.records if "aligned while the scans were read" in r.getMessage()]
    done, total = map(int, re.match(r"edges: (\d+) of (\d+) pairs", line[0]).groups())
    assert 0 < done < total and total - done <= 4


def test_bad_input_errors():
    true, t = trajectory(5)
    scans, index, poses = recording(true, t)
    from floorscan.core.io import InputError

    with pytest.raises(InputError, match="poses.parquet.*no row for 1 scans"):
        register_scans(scans, index, poses.iloc[:4], {})
    with pytest.raises(InputError, match=r"scans.parquet: columns \['z'\] missing"):
        register_scans(scans.drop(columns="z"), index, poses, {})
    with pytest.raises(InputError, match="mode 'pose' needs poses"):
        register_scans(scans, index, None, {})
    from floorscan.core.config import ConfigError

    with pytest.raises(ConfigError, match=r"register\.icp_method: 'gicp' is not one of"):
        register_scans(scans, index, poses, {"icp_method": "gicp"})


def test_schema_defaults_match_dataclass():
    schema = yaml.safe_load((REPO / "workflow/schemas/register.schema.yaml").read_text())
    defaults = {k: v["default"] for k, v in schema["properties"].items()}
    import dataclasses

    code = {f.name: f.default if f.default is not dataclasses.MISSING else f.default_factory()
            for f in dataclasses.fields(RegistrationConfig)}
    code["icp_max_correspondence_m"] = list(code["icp_max_correspondence_m"])
    assert defaults == code
    assert schema["additionalProperties"] is False


# --------------------------------------------------------------------------- real data


def _ingest(tmp_path, ds, cfg=None):
    readers = pytest.importorskip("floorscan.ingest.readers")
    writer = pytest.importorskip("floorscan.ingest.writer")
    from floorscan.core.io import read_table
    from floorscan.ingest.poses import scan_poses

    rec = readers.open_recording(ds, cfg or {}, max_gap_s=0.5)
    index = writer.write_recording(rec, tmp_path / "s.parquet", tmp_path / "i.parquet", tmp_path / "p.parquet")
    poses = scan_poses(index, read_table(tmp_path / "p.parquet"), 0.5, "stream")
    return read_table(tmp_path / "s.parquet"), index, poses


RADISH = {"intel": "intel-corrected.log.gz", "aces": "aces-corrected.log.gz",
          "orebro": "orebro-corrected.log.gz"}


@needs_shared
@pytest.mark.realdata
@pytest.mark.slow
@pytest.mark.parametrize("name", list(RADISH))
def test_radish_icp_corrections_are_small(name, tmp_path):
    """SLAM-corrected poses: the ICP corrections have median < 2 cm and < 0.5 degree."""
    ingest_cfg = {"carmen_max_range_m": 32.0} if name == "orebro" else {}
    scans, index, poses = _ingest(tmp_path, {"format": "carmen", "path": str(SHARED_DATA / "radish" / RADISH[name])}, ingest_cfg)
    # as in config/config.yaml: the logs are thinned SLAM keyframes whose poses are
    # already corrected, so the thesis's sequential references
    cfg = {"every_n": 1, "reference": "previous"}
    if name == "orebro":  # stamps are synthetic (scan index x 0.1 s): no speed check
        cfg.update(max_speed_m_s=100.0, max_turn_rate_rad_s=100.0)
    r = register_scans(scans, index, poses, cfg)
    s = r.summary
    assert s["median_correction_m"] < 0.02
    assert math.degrees(s["median_correction_rad"]) < 0.5
    # orebro's scans are up to 3 m apart: 11 % fall below the fitness thresholds
    assert s["n_kept"] >= (0.85 if name == "orebro" else 0.95) * len(index)


@needs_shared
@pytest.mark.realdata
@pytest.mark.slow
def test_freiburg101_corrections_fix_the_logs_own_pose_error(tmp_path):
    """freiburg101 is the Radish log whose median correction misses the issue's 2 cm
    (2.15 cm with ``previous``; 1.89 cm with ``graph``, which instead gives intel 2.27 cm).
    The corrections are the log's own pose error, not ICP noise: they make the map
    crisper. Mean thinness of the eight longest walls (see :func:`_straight_walls`), all
    292 scans: log poses 0.628, ``previous`` 0.683. On the 290 scans both references keep:
    log 0.633, ``previous`` 0.723, ``graph`` 0.619; on intel, aces and orebro, where the
    corrections are at the noise floor, the three differ by <= 0.03."""
    scans, index, poses = _ingest(
        tmp_path, {"format": "carmen", "path": str(SHARED_DATA / "radish" / "freiburg-101-corrected.log.gz")}
    )
    r = register_scans(scans, index, poses, {"every_n": 1, "reference": "previous"})
    s = r.summary
    assert 0.015 < s["median_correction_m"] < 0.025
    assert math.degrees(s["median_correction_rad"]) < 0.5
    assert s["n_kept"] == len(index)
    from floorscan.core.io import split_by_scan

    by = split_by_scan(scans)
    t = r.table.set_index("scan_id")
    p = poses.set_index("scan_id")

    def mapxy(x, y, yaw):
        out = []
        for i in t.index:
            c, sn = math.cos(yaw[i]), math.sin(yaw[i])
            out.append(by[int(i)][:, :2] @ np.array([[c, sn], [-sn, c]]) + [x[i], y[i]])
        return np.concatenate(out)

    thin_log = np.mean([w for _, w in _straight_walls(mapxy(p.x, p.y, p.yaw), n_lines=8)])
    thin_reg = np.mean([w for _, w in _straight_walls(mapxy(t.x_m, t.y_m, t.yaw_rad), n_lines=8)])
    assert thin_reg > thin_log + 0.03


def _straight_walls(points_xy, seed=0, n_lines=6, band=0.15):
    """The n_lines longest walls by sequential RANSAC (3 cm inliers) on a 2 cm grid of the
    map, refitted by PCA; per wall its length (m) and the fraction of the grid cells within
    `band` of the line that lie within 5 cm of it (1.0: a perfectly thin wall)."""
    rng = np.random.default_rng(seed)
    p = np.unique(np.round(points_xy / 0.02), axis=0) * 0.02
    out = []
    for _ in range(n_lines):
        best = None
        for _ in range(400):
            a, b = p[rng.choice(len(p), 2, replace=False)]
            d = b - a
            if np.hypot(*d) < 0.5:
                continue
            nrm = np.array([-d[1], d[0]]) / np.hypot(*d)
            inl = np.abs((p - a) @ nrm) < 0.03
            if best is None or inl.sum() > best.sum():
                best = inl
        c = p[best].mean(axis=0)
        _, _, vt = np.linalg.svd(p[best] - c)
        dist = (p - c) @ vt[1]
        near = np.abs(dist) < band
        out.append((float(np.ptp((p[near] - c) @ vt[0])), float(np.mean(np.abs(dist[near]) < 0.05))))
        p = p[~near]
    return out


@needs_shared
@pytest.mark.realdata
@pytest.mark.slow
def test_trace0_registered_walls_are_straight(tmp_path):
    """trace0 (poses via TF): the six longest walls of the registered map are straight:
    five are longer than 7 m and, on average, >= 60 % of the map within 15 cm of a wall
    lies within 5 cm of its line (measured with reference: graph 0.67; map 0.54;
    previous 0.49; the localizer poses alone 0.46; a smeared map with 0.3 m position
    noise 0.37)."""
    ds = {"format": "rosbag", "path": str(SHARED_DATA / "uob-pioneer/trace0.bag"), "scan_topic": "/base_scan",
          "pose": {"source": "tf", "fixed_frame": "map"}}
    scans, index, poses = _ingest(tmp_path, ds)
    r = register_scans(scans, index, poses, {})
    xy = r.registered[["x", "y"]].to_numpy(np.float64)
    walls = _straight_walls(xy)
    assert sum(length > 7.0 for length, _ in walls) >= 5
    assert np.mean([thin for _, thin in walls]) >= 0.60
    assert r.summary["n_kept"] >= 0.95 * r.summary["n_sampled"]


def _simulated_demo(seed=1, every=5):
    """The demo building driven by the simulator (AMCL-like Gauss-Markov pose error: 5 cm,
    0.02 rad, 2 s correlation time), every ``every``-th scan: scans, index, the
    localizer's poses interpolated at the scans, and the true scanner poses (~2 s)."""
    from floorscan.sim.building_file import load_building
    from floorscan.sim.params import SimParams
    from floorscan.sim.raycast import scanner_points
    from floorscan.sim.recording import simulate_recording
    from floorscan.sim.scanners import Scanner2D

    b = load_building(REPO / "config" / "buildings" / "demo.yaml")
    rec = simulate_recording(b, Scanner2D(), SimParams(), seed=seed)
    rows, ks = [], []
    for k, rng in rec.iter_scans():
        if k % every == 0:
            pts, _ = scanner_points(rec.scanner, rng)
            rows.append(pd.DataFrame({"scan_id": np.int32(len(ks)), "x": pts[:, 0], "y": pts[:, 1], "z": pts[:, 2]}))
            ks.append(k)
    ks = np.asarray(ks)
    t = rec.scan_t_ns[ks]
    amcl_yaw = np.unwrap(rec.amcl[:, 2])
    loc = np.column_stack([np.interp(t, rec.pose_t_ns, rec.amcl[:, 0]), np.interp(t, rec.pose_t_ns, rec.amcl[:, 1]),
                           np.interp(t, rec.pose_t_ns, amcl_yaw)])
    poses = pd.DataFrame({"scan_id": np.arange(len(ks), dtype=np.int32), "t_ns": t, "x": loc[:, 0], "y": loc[:, 1],
                          "z": rec.scan_poses[ks, 2], "yaw": loc[:, 2], "valid": True, "reason": ""})
    index = pd.DataFrame({"scan_id": np.arange(len(ks), dtype=np.int32), "t_ns": t})
    return pd.concat(rows, ignore_index=True), index, poses, rec.scan_poses[ks]


def _rms_errors(table, true):
    """RMS position (m) and yaw (rad) error of the kept scans' final poses."""
    k = table["kept"].to_numpy()
    d = table[["x_m", "y_m"]].to_numpy()[k] - true[k, :2]
    dyaw = (table["yaw_rad"].to_numpy()[k] - true[k, 3] + np.pi) % (2 * np.pi) - np.pi
    return float(np.sqrt(np.mean(np.sum(d**2, axis=1)))), float(np.sqrt(np.mean(dyaw**2)))


def test_map_registration_reduces_amcl_like_pose_error():
    """Issue 4 check: on a synthetic recording with AMCL-like (time-correlated) pose
    error, registration against the map of the whole recording lowers the RMS error
    against the simulator's true poses (measured on demo, every 5th scan: position
    7.6 -> 4.3 cm, yaw 1.08 -> 0.82 degree; the sequential variant only 7.6 -> 7.4 cm,
    since the previous scans carry nearly the same error)."""
    scans, index, poses, true = _simulated_demo()
    before = _rms_errors(pd.DataFrame({"kept": True, "x_m": poses["x"], "y_m": poses["y"], "yaw_rad": poses["yaw"]}), true)
    r = register_scans(scans, index, poses, {"every_n": 1, "reference": "map"})
    assert r.summary["n_kept"] == len(index)
    after = _rms_errors(r.table, true)
    assert 0.06 < before[0] < 0.09
    assert after[0] < 0.65 * before[0]
    assert after[1] < 0.85 * before[1]
    # the gauge is anchored: the mean correction over all scans is zero
    assert abs(r.table["dx_m"].mean()) < 1e-9 and abs(r.table["dy_m"].mean()) < 1e-9
    assert abs(r.table["dyaw_rad"].mean()) < 1e-9
    seq = _rms_errors(register_scans(scans, index, poses, {"every_n": 1, "reference": "previous"}).table, true)
    assert seq[0] > 0.9 * before[0]  # why the thesis's variant is not the default


def test_pose_graph_registration_halves_amcl_like_pose_error():
    """reference: graph (default): ICP edges keep the scans' relative geometry to
    millimetres, the localizer's priors place the whole (measured on demo, every 5th
    scan: 7.6 -> 3.1 cm, 1.08 -> 0.56 degree; the rest is the mean of the localizer's
    error over a 32 s drive, a rigid offset of 2.5 cm and 0.5 degree)."""
    scans, index, poses, true = _simulated_demo()
    before = _rms_errors(pd.DataFrame({"kept": True, "x_m": poses["x"], "y_m": poses["y"], "yaw_rad": poses["yaw"]}), true)
    r = register_scans(scans, index, poses, {"every_n": 1})
    assert r.summary["n_kept"] == len(index)
    after = _rms_errors(r.table, true)
    assert after[0] < 0.5 * before[0]
    assert after[1] < 0.65 * before[1]
    assert r.table["fitness_icp"].median() > 0.7


def test_map_references_exclude_the_correlation_window():
    """The references of a scan are >= exclude_window_s away in time and spread by
    reference_spacing_s; with none outside the window it falls back to the nearest."""
    from floorscan.register.scan_to_map import _select_references

    t = np.arange(10) * 0.5
    pose = np.column_stack([np.arange(10) * 0.1, np.zeros(10), np.zeros(10), np.zeros(10)])
    cfg = RegistrationConfig(exclude_window_s=3.0, reference_spacing_s=1.0, n_references=8)
    refs, n_fallback = _select_references(pose, t, np.ones(10, bool), cfg)
    assert list(refs[0]) == [6, 8]
    assert list(refs[9]) == [3, 1]
    assert n_fallback == 2  # scans 4 and 5: every other scan is within 3 s
    assert list(refs[4][:2]) in ([3, 5], [5, 3])


def _drift(table, reference):
    """Position error (m) of the kept scans' poses against ``reference`` poses
    (x, y, yaw per table row) after aligning the first kept pose of each, and the
    reference's path length (m)."""
    k = table["kept"].to_numpy() & np.isfinite(reference[:, 0])
    a = _relative_to_first(table[["x_m", "y_m", "yaw_rad"]].to_numpy()[k])
    b = _relative_to_first(reference[k])
    path = float(np.sum(np.hypot(*np.diff(reference[k][:, :2], axis=0).T)))
    return np.hypot(a[:, 0] - b[:, 0], a[:, 1] - b[:, 1]), path


ODOMETRY_DATA = {
    # measured: kept 192/192, median 0.23 m, final 0.19 m of 32.8 m (0.6 %; without loop
    # closure 0.25 m, 0.32 m) against the
    # localizer (AMCL-like, map -> odom; its own yaw is off by up to 5 degrees between
    # scans 2 s apart, by pairwise ICP, so part of this is the reference's error)
    "trace0": ({"format": "rosbag", "path": "uob-pioneer/trace0.bag", "scan_topic": "/base_scan",
                "pose": {"source": "tf", "fixed_frame": "map"}}, 0.40, 0.55, 100),
    # measured: kept 72/72, median 0.09 m, final 0.22 m of 8.3 m against wheel odometry
    # (without loop closure 0.11 m, 0.20 m)
    "mac_ros2": ({"format": "rosbag", "path": "comprobo-mac/macfirst_floor_take_2", "scan_topic": "/scan",
                  "pose": {"source": "tf", "fixed_frame": "odom"}}, 0.20, 0.35, 55),
}


@needs_shared
@pytest.mark.realdata
@pytest.mark.slow
@pytest.mark.parametrize("name", list(ODOMETRY_DATA))
def test_odometry_mode_on_real_recordings(name, tmp_path):
    """Pose-free mode on real recordings (issue 4): every sampled scan kept (>= 95 %),
    and the path stays close to the recording's own poses, which the odometry never
    reads (bounds: measured figures plus margin, see ODOMETRY_DATA)."""
    ds, max_median, max_final, min_sampled = ODOMETRY_DATA[name]
    ds = dict(ds, path=str(SHARED_DATA / ds["path"]))
    scans, index, poses = _ingest(tmp_path, ds)
    r = register_scans(scans, index, None, {"mode": "odometry"})
    print(name, r.summary["n_sampled"], r.summary["verdict"])
    s = r.summary
    # the motion filter samples on the odometry's poses: consecutive sampled scans are
    # keep_distance_m or keep_angle_rad apart (measured: trace0 %s, mac_ros2 61 of 357)
    assert s["n_kept"] >= 0.95 * s["n_sampled"] and s["n_sampled"] >= min_sampled
    cfg = s["config"]
    p = r.table.loc[r.table["kept"], ["x_m", "y_m", "yaw_rad"]].to_numpy(float)
    step = np.hypot(*np.diff(p[:, :2], axis=0).T)
    turn = np.abs((np.diff(p[:, 2]) + np.pi) % (2 * np.pi) - np.pi)
    # loop closure moves the poses after sampling by a few cm
    assert np.all((step >= cfg["keep_distance_m"] - 0.1) | (turn >= cfg["keep_angle_rad"] - 0.05))
    ref = poses.set_index("scan_id").reindex(r.table["scan_id"])
    ref = np.where(ref["valid"].fillna(False).to_numpy(bool)[:, None], ref[["x", "y", "yaw"]].to_numpy(float), np.nan)
    err, path = _drift(r.table, ref)
    assert path > 5.0
    assert np.median(err) < max_median
    assert err[-1] < max_final



def test_graph_cloud_one_sort_equals_the_grouped_path(monkeypatch):
    """graph_cloud sorts once by (cell key, height); the same cloud as grouping the
    cells first (its path for extents beyond the int64 key), bit for bit."""
    import floorscan.register.prepare as R
    from floorscan.core.grid import cell_keys

    rng = np.random.default_rng(5)
    wall = np.column_stack([rng.uniform(-3, 3, 3000), np.full(3000, 2.0) + rng.normal(0, 0.01, 3000),
                            rng.uniform(-0.4, 2.0, 3000)])
    floor = np.column_stack([rng.uniform(-3, 3, (3000, 2)), rng.normal(-0.4, 0.01, 3000)])
    pts = np.concatenate([wall, floor])
    cfg = RegistrationConfig()
    fast = R.graph_cloud(pts, cfg)
    monkeypatch.setattr(R, "cell_keys", lambda cells: None)
    np.testing.assert_array_equal(fast, R.graph_cloud(pts, cfg))
    assert 100 < len(fast) <= 240 and np.all(np.abs(fast[:, 1] - 2.0) < 0.05)  # the wall: 120 cells a row, no floor
    c = rng.integers(-50, 50, (500, 2))
    np.testing.assert_array_equal(np.argsort(cell_keys(c), kind="stable"), np.lexsort(c.T[::-1]))


def test_cell_height_order_is_lexsort_by_cell_then_height():
    """The one-key sort of graph_cloud orders as numpy.lexsort((z, key)) (equal
    heights in a cell may swap): float32 heights of both signs, -0.0 and ties; keys
    past 2**31 or float64 heights take the lexsort itself."""
    from floorscan.register.prepare import _cell_height_order

    rng = np.random.default_rng(3)
    for n in (1, 2, 50, 3000):
        key = rng.integers(0, 40, n)
        z = rng.normal(0.0, 2.0, n).astype(np.float32).astype(np.float64)
        z[rng.random(n) < 0.1], z[rng.random(n) < 0.05], z[rng.random(n) < 0.1] = 0.0, -0.0, 1.5
        want = np.lexsort((z, key))
        got = _cell_height_order(key, z)
        assert np.array_equal(key[got], key[want]) and np.array_equal(z[got], z[want])
    key = np.array([2**31, 5, 5])
    z64 = np.array([0.1, 0.3, 0.2])  # not float32 values
    assert _cell_height_order(key, z64).tolist() == [2, 1, 0]


def _absolute_trajectory_error(table, truth):
    """RMS position (m) and yaw (rad) error of the kept scans' poses against ``truth``
    (x, y, yaw per table row) after the least-squares rigid alignment of the two
    trajectories (the absolute trajectory error, Sturm et al., IROS 2012; Horn's closed
    form in 2D), so that neither a frame choice nor the first pose's error counts."""
    k = table["kept"].to_numpy() & np.isfinite(truth[:, 0])
    a = table[["x_m", "y_m", "yaw_rad"]].to_numpy(np.float64)[k]
    b = np.asarray(truth, dtype=np.float64)[k]
    ca, cb = a[:, :2].mean(axis=0), b[:, :2].mean(axis=0)
    da, db = a[:, :2] - ca, b[:, :2] - cb
    theta = math.atan2(np.sum(da[:, 0] * db[:, 1] - da[:, 1] * db[:, 0]), np.sum(da * db))
    c, s = math.cos(theta), math.sin(theta)
    moved = np.column_stack([c * da[:, 0] - s * da[:, 1], s * da[:, 0] + c * da[:, 1]]) + cb
    dyaw = (a[:, 2] + theta - b[:, 2] + np.pi) % (2 * np.pi) - np.pi
    return float(np.sqrt(np.mean(np.sum((moved - b[:, :2]) ** 2, axis=1)))), float(np.sqrt(np.mean(dyaw**2)))


@needs_shared
@pytest.mark.realdata
@pytest.mark.slow
def test_simpath2_registration_error_against_the_simulators_truth(tmp_path):
    """Issue 20: the Stage bag carries the simulator's true pose (/base_pose_ground_truth).
    Absolute trajectory error of each mode against it (RMS position / yaw of the kept
    scans after rigid alignment), measured: prior poses = truth + an AMCL-like
    Gauss-Markov error (5 cm, 0.02 rad, 2 s, seed 7) 6.8 cm / 1.25 deg -> pose mode
    3.2 cm / 0.34 deg; odometry mode (no poses) 5.4 cm / 0.55 deg; the bag's wheel
    odometry taken as the map pose 5.9 cm / 2.38 deg, registered in pose mode 4.2 cm /
    1.14 deg. Odometry mode restarts its motion model after a stop (the simulator's
    identical scans while the robot stands); carrying the velocity across the stops
    gave 3.2 m / 34 deg."""
    from floorscan.sim.recording import gauss_markov

    ds = {"path": str(SHARED_DATA / "stage-sim" / "simpath2.bag"),
          "pose": {"source": "topic", "topic": "/base_pose_ground_truth"}}
    scans, index, truth_poses = _ingest(tmp_path, ds)
    truth = truth_poses[["x", "y", "yaw"]].to_numpy(float)
    assert truth_poses["valid"].mean() > 0.99
    rng = np.random.default_rng(7)
    n = len(truth)
    noisy = truth_poses.copy()
    noisy["x"] += gauss_markov(n, 0.1, 0.05, 2.0, rng)
    noisy["y"] += gauss_markov(n, 0.1, 0.05, 2.0, rng)
    noisy["yaw"] += gauss_markov(n, 0.1, 0.02, 2.0, rng)
    rows = {}
    prior = pd.DataFrame({"kept": noisy["valid"], "x_m": noisy["x"], "y_m": noisy["y"], "yaw_rad": noisy["yaw"]})
    rows["prior"] = _absolute_trajectory_error(prior, truth)
    pose = register_scans(scans, index, noisy, {"mode": "pose"}, recording={"pose_kind": "map"})
    rows["pose"] = _absolute_trajectory_error(pose.table, truth)
    odo = register_scans(scans, index, None, {"mode": "odometry"}, recording={"pose_kind": "none"})
    rows["odometry"] = _absolute_trajectory_error(odo.table, truth)
    wheel_ds = dict(ds, pose={"source": "topic", "topic": "/odom"})
    (tmp_path / "wheel").mkdir()
    wheel = _ingest(tmp_path / "wheel", wheel_ds)[2]
    w = pd.DataFrame({"kept": wheel["valid"], "x_m": wheel["x"], "y_m": wheel["y"], "yaw_rad": wheel["yaw"]})
    rows["wheel"] = _absolute_trajectory_error(w, truth)
    rows["wheel_pose"] = _absolute_trajectory_error(register_scans(scans, index, wheel, {"mode": "pose"}).table, truth)
    for k, (e, y) in rows.items():
        print(f"simpath2 {k}: RMS {100 * e:.1f} cm, {np.degrees(y):.2f} deg")
    assert pose.summary["n_kept"] >= 0.95 * pose.summary["n_sampled"] >= 100
    assert odo.summary["n_kept"] >= 0.95 * odo.summary["n_sampled"] >= 100
    assert rows["pose"][0] < 0.6 * rows["prior"][0] and rows["pose"][0] < 0.04
    assert rows["pose"][1] < 0.5 * rows["prior"][1]
    assert rows["odometry"][0] < 0.07 and np.degrees(rows["odometry"][1]) < 0.8
    assert rows["wheel_pose"][0] < rows["wheel"][0] and rows["wheel_pose"][1] < 0.6 * rows["wheel"][1]

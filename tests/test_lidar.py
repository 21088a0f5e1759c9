"""LIDAR models against known geometry: an empty 4 x 6 m room (thesis 4.1)."""

import numpy as np
import pytest

from floorscan.sim.building_file import parse_building
from floorscan.sim.mesh import building_mesh
from floorscan.sim.raycast import RayCaster, iter_scan_batches, measure_ranges, scanner_points, to_map
from floorscan.sim.scanners import scanner_from_config
from floorscan.core.io import InputError

HALF_X, HALF_Y, HEIGHT = 2.0, 3.0, 2.5  # inner faces x = +-2, y = +-3, ceiling 2.5 m


def room(openings=()):
    t = 0.1
    hx, hy = HALF_X + t / 2, HALF_Y + t / 2
    return parse_building(
        {
            "height_m": HEIGHT,
            "walls": [{"id": "room", "closed": True, "thickness_m": t,
                       "points": [[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]],
                       "openings": list(openings)}],
            "waypoints": [[0, 0], [0, 1]],
        },
        "room.yaml",
    )


@pytest.fixture(scope="module")
def caster():
    return RayCaster.from_mesh(building_mesh(room()))


def exact_2d(x, y, yaw, angles):
    """Distance from (x, y) along yaw + angles to the inner faces of the room."""
    a = yaw + np.asarray(angles)
    c, s = np.cos(a), np.sin(a)
    with np.errstate(divide="ignore"):
        tx = np.where(c > 0, (HALF_X - x) / c, np.where(c < 0, (-HALF_X - x) / c, np.inf))
        ty = np.where(s > 0, (HALF_Y - y) / s, np.where(s < 0, (-HALF_Y - y) / s, np.inf))
    return np.minimum(tx, ty)


def test_2d_scanner_beams_match_a_laserscan():
    sc = scanner_from_config("2d", {})
    assert sc.n_beams == 1081
    assert sc.angle_min == pytest.approx(-3 * np.pi / 4, abs=1e-7)
    assert sc.angle_max == pytest.approx(3 * np.pi / 4, abs=1e-6)
    assert np.float32(sc.angle_increment) == sc.angle_increment  # float32, as in the message
    full = scanner_from_config("lidar360", {"kind": "2d", "fov_deg": 360, "angular_resolution_deg": 1})
    assert full.n_beams == 360  # -180 and +180 are the same beam


def test_exact_distances_and_range_noise_std_is_1cm(caster):
    sc = scanner_from_config("2d", {})
    rng = np.random.default_rng(7)
    xs = np.linspace(-1.0, 1.0, 8)
    poses = np.column_stack([xs, xs * 1.2, np.full(8, 0.3), np.linspace(0, 3, 8)])
    poses = np.repeat(poses, 6, axis=0)  # 48 scans, 51888 beams
    ranges, exact = measure_ranges(caster, sc, poses, rng, return_exact=True)
    truth = np.stack([exact_2d(p[0], p[1], p[3], sc.angles()) for p in poses])
    # Embree's hit distances are the analytic ones (float32)
    assert np.abs(exact - truth).max() < 2e-5
    err = (ranges - truth)[np.isfinite(ranges)]
    assert err.size > 50_000
    assert err.std() == pytest.approx(0.01, rel=0.10)
    assert err.std() == pytest.approx(0.01, rel=0.03)  # 52k samples: a 0.3 % sampling error
    assert abs(err.mean()) < 3e-4


def fit_line(p):
    """Total least squares line through (N, 2) points: (unit normal, offset, rms)."""
    c = p.mean(axis=0)
    _, s, vt = np.linalg.svd(p - c, full_matrices=False)
    n = vt[1]
    return n, float(n @ c), float(s[1] / np.sqrt(len(p)))


def test_single_scan_from_the_centre_recovers_the_four_walls(caster):
    sc = scanner_from_config("2d", {})
    pose = np.array([0.0, 0.0, 0.3, 0.4])
    ranges = measure_ranges(caster, sc, pose[None], np.random.default_rng(3))[0]
    pts, valid = scanner_points(sc, ranges)
    assert valid.all()  # closed room, all within 20 m
    m = to_map(pts, pose)
    assert np.allclose(m[:, 2], 0.3)
    xy = m[:, :2]
    # assign each point to the wall it is nearest to, fit a line to each group
    d = np.stack([HALF_X - xy[:, 0], xy[:, 0] + HALF_X, HALF_Y - xy[:, 1], xy[:, 1] + HALF_Y], 1)
    wall = d.argmin(axis=1)
    expected = [(np.array([1.0, 0.0]), HALF_X), (np.array([1.0, 0.0]), -HALF_X),
                (np.array([0.0, 1.0]), HALF_Y), (np.array([0.0, 1.0]), -HALF_Y)]
    for k, (normal, offset) in enumerate(expected):
        group = xy[wall == k]
        assert len(group) > 60
        n, off, rms = fit_line(group)
        if n @ normal < 0:
            n, off = -n, -off
        assert abs(off - offset) < 0.01  # position of the wall within 1 cm
        assert np.degrees(np.arccos(min(1.0, n @ normal))) < 0.5  # its direction
        assert rms == pytest.approx(0.01, rel=0.35)  # the points scatter by the range noise


def test_no_return_beyond_max_range(caster):
    sc = scanner_from_config("short", {"kind": "2d", "range_max_m": 2.5, "range_noise_std_m": 0.0})
    pose = np.array([0.5, 0.0, 0.3, 0.0])
    ranges = measure_ranges(caster, sc, pose[None], np.random.default_rng(0))[0]
    truth = exact_2d(0.5, 0.0, 0.0, sc.angles())
    assert np.all(np.isposinf(ranges[truth > 2.5 + 1e-4]))
    near = truth < 2.5 - 1e-4
    assert near.sum() > 100
    np.testing.assert_allclose(ranges[near], truth[near], atol=2e-5)


def test_rays_pass_through_a_door_but_not_a_window_above_the_scanner():
    door = {"id": "door", "kind": "door", "segment": 0, "offset_m": 1.05, "width_m": 2.0}  # x -1..1, y = -3
    window = {"id": "win", "kind": "window", "segment": 2, "offset_m": 1.05, "width_m": 2.0,
              "sill_m": 0.9, "head_m": 2.0}  # x 1..-1 on y = +3
    c = RayCaster.from_mesh(building_mesh(room([door, window])))
    sc = scanner_from_config("lidar360", {"kind": "2d", "fov_deg": 360, "angular_resolution_deg": 0.5,
                                                "range_noise_std_m": 0.0})
    ranges = measure_ranges(c, sc, np.array([[0.0, 0.0, 0.3, 0.0]]), np.random.default_rng(0))[0]
    a = sc.angles()
    # beams toward the door gap leave the building: no return (the door jambs are 0.1 m deep)
    through_door = (np.sin(a) < 0) & (np.abs(3.1 * np.cos(a) / np.sin(a)) < 0.99)
    assert through_door.sum() > 20
    assert np.all(np.isposinf(ranges[through_door]))
    # toward the window (sill 0.9 m, scanner at 0.3 m) the wall returns
    toward_window = (np.sin(a) > 0) & (np.abs(3 * np.cos(a) / np.sin(a)) < 0.99)
    np.testing.assert_allclose(ranges[toward_window], exact_2d(0, 0, 0, a[toward_window]), atol=2e-5)


def test_3d_scan_points_lie_on_walls_floor_and_ceiling(caster):
    sc = scanner_from_config("3d", {"horizontal_resolution_deg": 2.0})
    assert len(sc.directions()) == 180 * 16
    assert np.degrees(sc.elevations()).tolist() == pytest.approx(np.arange(-15, 16, 2).tolist())
    pose = np.array([0.3, -0.2, 0.3, 1.0])
    ranges = measure_ranges(caster, sc, pose[None], np.random.default_rng(5))[0]
    pts, valid = scanner_points(sc, ranges)
    assert valid.all()
    m = to_map(pts, pose)
    dist = np.stack([np.abs(np.abs(m[:, 0]) - HALF_X), np.abs(np.abs(m[:, 1]) - HALF_Y),
                     np.abs(m[:, 2]), np.abs(m[:, 2] - HEIGHT)], 1).min(axis=1)
    assert np.quantile(dist, 0.99) < 0.03 and dist.max() < 0.06  # 1 cm noise
    on_floor = np.abs(m[:, 2]) < 0.04
    # beams at -15..-5 deg from 0.3 m reach the floor 1.1..3.4 m away: inside the room
    assert on_floor.sum() > 180 * 3


def test_noise_is_seeded_and_independent_of_batching(caster):
    sc = scanner_from_config("2d", {})
    poses = np.column_stack([np.zeros(10), np.linspace(-1, 1, 10), np.full(10, 0.3), np.zeros(10)])
    a = measure_ranges(caster, sc, poses, np.random.default_rng(11))
    b = measure_ranges(caster, sc, poses, np.random.default_rng(11))
    rng = np.random.default_rng(11)
    batches = iter_scan_batches(10, sc.n_beams, max_rays=3000)
    parts = [measure_ranges(caster, sc, poses[s], rng) for s in batches]
    assert len(parts) == 5  # 2 scans per call
    np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(a, np.concatenate(parts))
    c = measure_ranges(caster, sc, poses, np.random.default_rng(12))
    assert not np.array_equal(a, c)


def test_inputs_are_not_mutated(caster):
    sc = scanner_from_config("2d", {})
    pose = np.array([0.0, 0.0, 0.3, 0.2])
    before = pose.copy()
    r = measure_ranges(caster, sc, pose[None], np.random.default_rng(0))[0]
    r0 = r.copy()
    to_map(scanner_points(sc, r)[0], pose)
    np.testing.assert_array_equal(pose, before)
    np.testing.assert_array_equal(r, r0)


@pytest.mark.parametrize(
    "name, cfg, match",
    [
        ("3d", {"n_beams": 0}, r"simulate\.scanners\.3d\.n_beams.*at least one beam"),
        ("3d", {"elevations_deg": []}, r"simulate\.scanners\.3d\.elevations_deg.*at least one beam"),
        ("2d", {"range_noise_std_m": -0.01}, r"simulate\.scanners\.2d\.range_noise_std_m.*>= 0"),
        ("2d", {"angular_resolution_deg": 0}, r"simulate\.scanners\.2d\.angular_resolution_deg"),
        ("2d", {"range_min_m": 5, "range_max_m": 1}, r"simulate\.scanners\.2d\.range_max_m"),
        ("velo", {"kind": "4d"}, r"simulate\.scanners\.velo\.kind"),
        ("2d", {"fov": 180}, r"unknown keys \['fov'\]"),
    ],
)
def test_bad_scanner_config(name, cfg, match):
    with pytest.raises(InputError, match=match):
        scanner_from_config(name, cfg)

"""Pose-graph registration (floorscan.posegraph): ICP edges and Open3D optimisation."""

import math

import numpy as np
import pandas as pd
import pytest

from floorscan import posegraph as G

# An L-shaped room (metres): walls as segments, so every scan constrains x, y and yaw.
ROOM = np.array(
    [
        [0, 0, 8, 0], [8, 0, 8, 3], [8, 3, 3, 3], [3, 3, 3, 7], [3, 7, 0, 7], [0, 7, 0, 0],
        [5, 1, 6, 1.6],  # a pillar-like oblique wall
    ],
    dtype=float,
)


def _scan(pose, rng, step=0.02, max_range=7.0, noise=0.003):
    """Wall points within range of ``pose`` (no occlusion), in the scanner frame."""
    pts = []
    for x0, y0, x1, y1 in ROOM:
        n = int(math.hypot(x1 - x0, y1 - y0) / step) + 1
        s = np.linspace(0, 1, n)[:, None]
        pts.append(np.c_[x0 + s * (x1 - x0), y0 + s * (y1 - y0)])
    p = np.vstack(pts)
    p = p[np.hypot(p[:, 0] - pose[0], p[:, 1] - pose[1]) < max_range]
    p = p + rng.normal(0, noise, p.shape)
    c, s = math.cos(pose[3]), math.sin(pose[3])
    d = p - pose[:2]
    local = np.c_[c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], np.zeros(len(d))]
    return local


def _path(n=40):
    """A drive along the L and back (so the path revisits: loop closures)."""
    out = np.r_[np.linspace([1.0, 1.5], [7.0, 1.5], n // 2), np.linspace([1.5, 2.0], [1.5, 6.0], n // 2)]
    yaw = np.r_[np.zeros(n // 2), np.full(n // 2, math.pi / 2)]
    return np.c_[out, np.zeros(n), yaw]


def _rms(p, q):
    return float(np.sqrt(np.mean(np.sum((p[:, :2] - q[:, :2]) ** 2, axis=1))))


@pytest.fixture(scope="module")
def recording():
    rng = np.random.default_rng(7)
    truth = _path()
    clouds = [_scan(p, rng) for p in truth]
    t = np.arange(len(truth)) * 0.5
    # localizer-like priors: 5 cm / 1 degree errors, independent per scan
    priors = truth.copy()
    priors[:, :2] += rng.normal(0, 0.05, (len(truth), 2))
    priors[:, 3] += rng.normal(0, math.radians(1.0), len(truth))
    return truth, clouds, t, priors


@pytest.fixture(scope="module")
def edges(recording):
    truth, clouds, t, priors = recording
    return G.scan_pair_edges(clouds, priors, t)


def test_candidate_pairs_sequential_and_loops():
    pos = np.array([[0, 0], [1, 0], [2, 0], [2, 1], [0.2, 0.1]], dtype=float)
    t = np.array([0.0, 1.0, 2.0, 3.0, 10.0])
    p = G.GraphParams(sequential_neighbours=1, loop_radius_m=0.5, loop_min_separation_s=3.0)
    assert G.candidate_pairs(pos, t, p) == [
        (0, 1, "sequential"), (0, 4, "loop"), (1, 2, "sequential"),
        (2, 3, "sequential"), (3, 4, "sequential"),
    ]
    # a loop closer in time than loop_min_separation_s is not a loop
    t2 = np.array([0.0, 1.0, 2.0, 3.0, 2.5])
    assert (0, 4, "loop") not in G.candidate_pairs(pos, t2, p)
    # loop_max_per_scan 0: sequential only
    p0 = G.GraphParams(sequential_neighbours=2, loop_max_per_scan=0)
    assert {k for *_, k in G.candidate_pairs(pos, t, p0)} == {"sequential"}


def test_edges_match_the_true_relative_poses(recording, edges):
    truth, clouds, t, priors = recording
    assert len(edges) >= len(truth) - 1
    assert set(edges["kind"]) == {"sequential", "loop"}
    err_xy, err_yaw = [], []
    for e in edges[edges["fitness"] >= 0.6].itertuples():
        dx, dy, dyaw = G.se2_between(truth[e.i], truth[e.j])
        err_xy.append(math.hypot(e.dx_m - dx, e.dy_m - dy))
        err_yaw.append(abs(e.dyaw_rad - dyaw))
    # priors are 5 cm / 1 degree off; ICP edges are millimetre-accurate
    assert np.median(err_xy) < 0.004
    assert np.median(np.degrees(err_yaw)) < 0.1
    assert (edges["fitness"] >= 0.6).mean() > 0.9


def test_graph_keeps_icp_geometry_and_localizer_placement(recording, edges):
    truth, clouds, t, priors = recording
    out, info = G.optimize_pose_graph(priors, edges, priors=priors)
    before, after = _rms(priors, truth), _rms(out, truth)
    assert before > 0.06
    # 40 independent 5 cm priors on a rigid trajectory: placement error ~ 5 / sqrt(40) cm
    assert after < 0.3 * before
    assert info["n_edges"] == (edges["fitness"] >= 0.6).sum() and info["n_isolated"] == 0
    yaw_err = np.degrees(np.abs(np.angle(np.exp(1j * (out[:, 3] - truth[:, 3])))))
    assert np.sqrt(np.mean(yaw_err**2)) < 0.3


def test_without_priors_the_first_scan_is_held(recording, edges):
    truth, clouds, t, _ = recording
    start = truth.copy()
    start[1:, :2] += 0.03  # a wrong initial guess for all but the first scan
    out, info = G.optimize_pose_graph(start, edges, priors=None)
    np.testing.assert_allclose(out[0], start[0], atol=1e-9)
    assert _rms(out, truth) < 0.005


def test_same_input_same_output(recording):
    truth, clouds, t, priors = recording
    a = G.scan_pair_edges(clouds[:10], priors[:10], t[:10])
    b = G.scan_pair_edges(clouds[:10], priors[:10], t[:10])
    pd.testing.assert_frame_equal(a, b)
    pa, _ = G.optimize_pose_graph(priors[:10], a, priors=priors[:10])
    pb, _ = G.optimize_pose_graph(priors[:10], b, priors=priors[:10])
    np.testing.assert_array_equal(pa, pb)


def test_edge_icp_in_worker_processes_gives_the_same_edges(recording, edges, monkeypatch):
    """``workers`` splits the pairs over processes (the register rule's threads); every
    edge is the single-process one, in the same order."""
    truth, clouds, t, priors = recording
    monkeypatch.setattr(G, "_MIN_PAIRS_PER_WORKER", 10)
    assert len(G._chunks(list(range(len(edges))), 3)) == 3
    par = G.scan_pair_edges(clouds, priors, t, G.GraphParams(workers=3))
    assert len(par) == len(edges) > 30
    pd.testing.assert_frame_equal(par, edges)


def test_bad_input():
    poses = np.zeros((3, 4))
    edges = pd.DataFrame([(0, 5, "sequential", 0.0, 0.0, 0.0, 1.0, 1.0, 0.0)], columns=G.EDGE_COLUMNS)
    with pytest.raises(ValueError, match="outside 0..2"):
        G.optimize_pose_graph(poses, edges)
    with pytest.raises(ValueError, match="priors"):
        G.optimize_pose_graph(poses, edges.iloc[:0], priors=np.zeros((2, 4)))
    with pytest.raises(KeyError, match="unknown register.graph config keys"):
        G.GraphParams.from_mapping({"loop_radius": 3})


def test_refine_poses_reports_fitness_per_scan(recording):
    truth, clouds, t, priors = recording
    poses, fit0, fitness, rmse, info = G.refine_poses(clouds[:12], priors[:12], t[:12], priors[:12])
    assert np.all(fit0 < fitness)  # the priors are 5 cm / 1 degree off
    assert poses.shape == (12, 4)
    # nearest-neighbour distances between 5 cm voxel means: about 1 cm on a wall
    assert np.all(fitness > 0.6) and np.all(rmse < 0.015)
    assert info["n_pairs"] >= 11
    assert _rms(poses, truth[:12]) < _rms(priors[:12], truth[:12])

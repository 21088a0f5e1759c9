"""Pose-graph registration (floorscan.register.posegraph, edges, solver): ICP edges and the
sparse planar optimiser."""

import math

import numpy as np
import pandas as pd
import pytest

from floorscan.core.geometry import se2_between
from floorscan.register import edges as E
from floorscan.register.edges import EDGE_COLUMNS, candidate_pairs, scan_pair_edges
from floorscan.register.params import GraphParams
from floorscan.register.posegraph import refine_poses
from floorscan.register.solver import optimize_pose_graph

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
    return scan_pair_edges(clouds, priors, t)


def test_candidate_pairs_sequential_and_loops():
    pos = np.array([[0, 0], [1, 0], [2, 0], [2, 1], [0.2, 0.1]], dtype=float)
    t = np.array([0.0, 1.0, 2.0, 3.0, 10.0])
    p = GraphParams(sequential_neighbours=1, loop_radius_m=0.5, loop_min_separation_s=3.0)
    assert candidate_pairs(pos, t, p) == [
        (0, 1, "sequential"), (0, 4, "loop"), (1, 2, "sequential"),
        (2, 3, "sequential"), (3, 4, "sequential"),
    ]
    # a loop closer in time than loop_min_separation_s is not a loop
    t2 = np.array([0.0, 1.0, 2.0, 3.0, 2.5])
    assert (0, 4, "loop") not in candidate_pairs(pos, t2, p)
    # loop_max_per_scan 0: sequential only
    p0 = GraphParams(sequential_neighbours=2, loop_max_per_scan=0)
    assert {k for *_, k in candidate_pairs(pos, t, p0)} == {"sequential"}


def test_edges_match_the_true_relative_poses(recording, edges):
    truth, clouds, t, priors = recording
    assert len(edges) >= len(truth) - 1
    assert set(edges["kind"]) == {"sequential", "loop"}
    err_xy, err_yaw = [], []
    for e in edges[edges["fitness"] >= 0.6].itertuples():
        dx, dy, dyaw = se2_between(truth[e.i], truth[e.j])
        err_xy.append(math.hypot(e.dx_m - dx, e.dy_m - dy))
        err_yaw.append(abs(e.dyaw_rad - dyaw))
    # priors are 5 cm / 1 degree off; ICP edges are millimetre-accurate
    assert np.median(err_xy) < 0.004
    assert np.median(np.degrees(err_yaw)) < 0.1
    assert (edges["fitness"] >= 0.6).mean() > 0.9


def test_graph_keeps_icp_geometry_and_localizer_placement(recording, edges):
    truth, clouds, t, priors = recording
    out, info = optimize_pose_graph(priors, edges, priors=priors)
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
    out, info = optimize_pose_graph(start, edges, priors=None)
    np.testing.assert_allclose(out[0], start[0], atol=1e-9)
    assert _rms(out, truth) < 0.005


def test_same_input_same_output(recording):
    truth, clouds, t, priors = recording
    a = scan_pair_edges(clouds[:10], priors[:10], t[:10])
    b = scan_pair_edges(clouds[:10], priors[:10], t[:10])
    pd.testing.assert_frame_equal(a, b)
    pa, _ = optimize_pose_graph(priors[:10], a, priors=priors[:10])
    pb, _ = optimize_pose_graph(priors[:10], b, priors=priors[:10])
    np.testing.assert_array_equal(pa, pb)


@pytest.mark.slow
def test_edge_icp_in_worker_processes_gives_the_same_edges(recording, edges, monkeypatch):
    """``workers`` splits the pairs over processes (the register rule's threads); every
    edge is the single-process one, in the same order."""
    truth, clouds, t, priors = recording
    monkeypatch.setattr(E, "_MIN_PAIRS_PER_WORKER", 10)
    assert len(E._chunks(list(range(len(edges))), 3)) == 3
    par = scan_pair_edges(clouds, priors, t, GraphParams(workers=3))
    assert len(par) == len(edges) > 30
    pd.testing.assert_frame_equal(par, edges)


def test_bad_input():
    poses = np.zeros((3, 4))
    edges = pd.DataFrame([(0, 5, "sequential", 0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 1.0)], columns=EDGE_COLUMNS)
    with pytest.raises(ValueError, match="outside 0..2"):
        optimize_pose_graph(poses, edges)
    with pytest.raises(ValueError, match="priors"):
        optimize_pose_graph(poses, edges.iloc[:0], priors=np.zeros((2, 4)))
    from floorscan.core.config import ConfigError, stage_params

    with pytest.raises(ConfigError, match=r"register\.graph\.loop_radius: unknown key"):
        stage_params(GraphParams, {"loop_radius": 3})


def test_refine_poses_reports_fitness_per_scan(recording):
    truth, clouds, t, priors = recording
    poses, fit0, fitness, rmse, info = refine_poses(clouds[:12], priors[:12], t[:12], priors[:12])
    assert np.all(fit0 < fitness)  # the priors are 5 cm / 1 degree off
    assert poses.shape == (12, 4)
    # nearest-neighbour distances between 5 cm voxel means: about 1 cm on a wall
    assert np.all(fitness > 0.6) and np.all(rmse < 0.015)
    assert info["n_pairs"] >= 11
    assert _rms(poses, truth[:12]) < _rms(priors[:12], truth[:12])


def _diff(a, b):
    """Largest position (m) and yaw (rad) difference between two pose arrays."""
    return (float(np.max(np.hypot(a[:, 0] - b[:, 0], a[:, 1] - b[:, 1]))),
            float(np.max(np.abs(np.angle(np.exp(1j * (a[:, 3] - b[:, 3])))))))


@pytest.mark.parametrize("with_priors", [True, False])
def test_solver_reaches_the_optimum(recording, edges, with_priors):
    """From the priors (or, in odometry mode, a wrong start for all but the held first
    scan) the solver ends nearer the truth, at a stationary point: started again from its
    answer it does not move. (Open3D's 6-DoF optimiser found the same poses: hallways
    0.07 mm, benchmarks/README.md.)"""
    truth, clouds, t, priors = recording
    start = priors.copy()
    if not with_priors:
        start = truth.copy()
        start[1:] += [0.03, -0.02, 0.0, 0.01]
    pr = priors if with_priors else None
    a, ia = optimize_pose_graph(start, edges, pr)
    b, ib = optimize_pose_graph(a, edges, pr)
    d_xy, d_yaw = _diff(a, b)
    assert d_xy < 1e-7 and d_yaw < 1e-8
    assert ia == ib and ia["n_pruned"] == 0
    assert _rms(a, truth) < 0.5 * _rms(start, truth)
    np.testing.assert_array_equal(a[:, 2], start[:, 2])  # z passes through
    assert np.all(np.abs(a[:, 3]) <= math.pi)


def test_a_wrong_loop_edge_is_pruned(recording, edges):
    """A loop edge 2 m off is switched off by the line process and the poses are those
    of the graph without that edge."""
    truth, clouds, t, priors = recording
    bad = edges.copy()
    k = bad.index[(bad["kind"] == "loop") & (bad["fitness"] >= 0.6)][0]
    bad.loc[k, "dx_m"] += 2.0
    before, prior_before = bad.copy(), priors.copy()
    out, info = optimize_pose_graph(priors, bad, priors)
    pd.testing.assert_frame_equal(bad, before)  # the caller's arrays are not changed
    np.testing.assert_array_equal(priors, prior_before)
    without, info0 = optimize_pose_graph(priors, edges.drop(k), priors)
    assert info["n_pruned"] == 1 and info0["n_pruned"] == 0
    assert info["n_edges"] == info0["n_edges"] + 1
    d_xy, d_yaw = _diff(out, without)
    assert d_xy < 1e-7 and d_yaw < 1e-8
    assert _rms(out, truth) < 0.012  # the clean graph's 0.88 cm
    # a sequential edge is not robust: it is never pruned
    seq = edges.copy()
    k = seq.index[(seq["kind"] == "sequential") & (seq["fitness"] >= 0.6)][0]
    seq.loc[k, "dx_m"] += 2.0
    _, info_seq = optimize_pose_graph(priors, seq, priors)
    assert info_seq["n_pruned"] == 0


def test_long_path_is_sparse():
    """6000 scans (Open3D's dense 36000 x 36000 normal matrix would need 10 GB): exact
    odometry edges along a known path and 5 cm / 1 degree priors give the path back
    to within the priors' averaged error; a scan without edges keeps its prior."""
    rng = np.random.default_rng(3)
    n = 6000
    s = np.arange(n) * 0.2
    yaw = (s / 20 + math.pi / 2 + math.pi) % (2 * math.pi) - math.pi
    truth = np.c_[20 * np.cos(s / 20), 20 * np.sin(s / 20), np.full(n, 0.4), yaw]
    rel = [se2_between(truth[k], truth[k + 1]) for k in range(n - 1)]
    edges = pd.DataFrame(
        [(k, k + 1, "sequential", *r, 1.0, 1.0, 0.001, 1.0, 1.0) for k, r in enumerate(rel) if k not in (2999, 3000)],
        columns=EDGE_COLUMNS,
    )  # scan 3000 has no edge
    priors = truth.copy()
    priors[:, :2] += rng.normal(0, 0.05, (n, 2))
    priors[:, 3] += rng.normal(0, math.radians(1.0), n)
    out, info = optimize_pose_graph(priors, edges, priors)
    assert info["n_isolated"] == 1 and info["n_edges"] == n - 3
    np.testing.assert_allclose(out[3000, :3], priors[3000, :3], atol=1e-9)
    assert abs(math.remainder(out[3000, 3] - priors[3000, 3], 2 * math.pi)) < 1e-9
    keep = np.arange(n) != 3000
    assert _rms(priors[keep], truth[keep]) > 0.06
    assert _rms(out[keep], truth[keep]) < 0.02


def test_candidate_pairs_out_and_back():
    """A rover driving 9 m out and back along a line (1 m, 1 s between scans): each
    scan pairs with its successor, and with the scan at its place on the way back
    once the two are 3 s apart; the nearest loop per scan is kept."""
    x = np.r_[np.arange(10.0), np.arange(9.0, -1.0, -1.0)]
    poses = np.c_[x, np.zeros(20), np.zeros(20), np.zeros(20)]
    t = np.arange(20.0)
    params = GraphParams(sequential_neighbours=1, loop_radius_m=0.5, loop_min_separation_s=3.0, loop_max_per_scan=1)
    pairs = candidate_pairs(poses, t, params)
    assert [p for p in pairs if p[2] == "sequential"] == [(i, i + 1, "sequential") for i in range(19)]
    assert [p for p in pairs if p[2] == "loop"] == [(k, 19 - k, "loop") for k in range(9)]
    # within 1.5 m the neighbours 1 m away compete; the nearest (0 m) wins with one loop per scan
    wide = candidate_pairs(poses, t, GraphParams(**{**params.__dict__, "loop_radius_m": 1.5}))
    assert [p for p in wide if p[2] == "loop"] == [(k, 19 - k, "loop") for k in range(9)]
    # two loops a scan, however close the partners: 9 at 0 m, then 8 at 1 m on the same pass
    two = candidate_pairs(poses, t, GraphParams(**{**params.__dict__, "loop_radius_m": 1.5, "loop_max_per_scan": 2,
                                                   "loop_partner_separation_m": 0.0}))
    loops = [(i, j) for i, j, kind in two if kind == "loop"]
    assert all(j - i > 1 for i, j in loops) and len(loops) == 17
    # partners 6 m apart along the path: the second (1 m from the first) is left out
    apart = candidate_pairs(poses, t, GraphParams(**{**params.__dict__, "loop_radius_m": 1.5, "loop_max_per_scan": 2}))
    assert [p for p in apart if p[2] == "loop"] == [(k, 19 - k, "loop") for k in range(9)]


def test_loop_partners_come_from_different_passes():
    """Three passes along x (1 m, 1 s between scans) at y = 0, 0.1 and 1.2 m. The two
    nearest candidates of a first-pass scan both lie on the second pass (0.1 and
    1.005 m away), so with the nearest two the third pass gets no loop at all; with
    partners 6 m apart along the path each scan is tied to both other passes."""
    x = np.tile(np.arange(30.0), 3)
    y = np.repeat([0.0, 0.1, 1.2], 30)
    poses, t = np.c_[x, y], np.arange(90.0)

    def partners(sep):
        p = GraphParams(sequential_neighbours=1, loop_radius_m=1.5, loop_min_separation_s=3.0,
                          loop_max_per_scan=2, loop_partner_separation_m=sep)
        out = {a: [] for a in range(90)}
        for i, j, kind in candidate_pairs(poses, t, p):
            if kind == "loop":
                out[i].append(j)
                out[j].append(i)
        return out

    nearest = partners(0.0)
    assert sorted(nearest[10]) == [40, 41] and sorted(nearest[40]) == [10, 11]
    assert not any(nearest[a] for a in range(60, 90))
    apart = partners(6.0)
    assert all(sorted(apart[k]) == [k + 30, k + 60] for k in range(30))  # first pass: one partner on each other
    assert all(sorted(apart[k + 60]) == [k, k + 30] for k in range(30))
    assert sum(len(v) for v in apart.values()) == 2 * 90


def test_coarse_icp_stage_keeps_edges_accurate(recording):
    """coarse_voxel_size_m: the first ICP stage on 0.1 m clouds; 0, or a size not above
    voxel_size_m, is plain two-stage ICP on the full clouds (the same edges)."""
    truth, clouds, t, priors = recording
    n = 14
    off = scan_pair_edges(clouds[:n], priors[:n], t[:n], GraphParams(coarse_voxel_size_m=0.0))
    same = scan_pair_edges(clouds[:n], priors[:n], t[:n], GraphParams(coarse_voxel_size_m=0.05))
    pd.testing.assert_frame_equal(off, same)
    on = scan_pair_edges(clouds[:n], priors[:n], t[:n], GraphParams(coarse_voxel_size_m=0.1))
    assert len(on) == len(off) and (on["fitness"] >= 0.6).sum() == (off["fitness"] >= 0.6).sum()
    for e in (off, on):
        err = [
            math.hypot(r.dx_m - dx, r.dy_m - dy)
            for r in e.itertuples()
            for dx, dy, _ in [se2_between(truth[r.i], truth[r.j])]
        ]
        assert np.median(err) < 0.004  # the priors are 5 cm off
    assert not np.array_equal(on[["dx_m", "dy_m"]].to_numpy(), off[["dx_m", "dy_m"]].to_numpy())


@pytest.mark.parametrize("n", [1, 2])
def test_a_graph_with_nothing_to_move_returns_the_poses(n):
    """One scan (held) or scans without an edge, by odometry: the poses as given, not a
    ValueError of an empty normal matrix (a 3-scan recording placed by LIDAR odometry
    whose sampling kept one scan stopped the register stage)."""
    poses = np.zeros((n, 4))
    poses[:, 0] = np.arange(n, dtype=np.float64)
    edges = pd.DataFrame({c: pd.Series(dtype=np.float64) for c in EDGE_COLUMNS}).astype({"i": np.int64, "j": np.int64})
    out, info = optimize_pose_graph(poses, edges)
    assert np.array_equal(out, poses) and info["n_edges"] == 0 and info["n_isolated"] == n

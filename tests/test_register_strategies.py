"""The registration strategies (``reference: graph``, ``previous``, ``map``, ``mode:
odometry`` and its loop closure) return a :class:`ScanRegistration` and change nothing
they are given."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest

from floorscan.core.io import split_by_scan
from floorscan.register.odometry import register_odometry
from floorscan.register.params import RegistrationConfig
from floorscan.register.posegraph import register_graph
from floorscan.register.prepare import ScanStore
from floorscan.register.result import ScanRegistration
from floorscan.register.scan_to_map import register_map
from floorscan.register.sequential import register_sequential
from test_registration import recording, trajectory

N = 12
DUPLICATE = 3  # a scan the screening dropped


def _inputs(mode="pose"):
    """Scan ids, times, config, clouds, the initial result and the sampled positions of
    a clean simulated recording of ``N`` scans, one of them screened out."""
    true, t = trajectory(N)
    scans, index, poses = recording(true, t)
    cfg = RegistrationConfig(every_n=1, mode=mode)
    reason = np.full(N, "", dtype=object)
    reason[DUPLICATE] = "duplicate"
    initial = ScanRegistration.before_registration(reason, poses[["x", "y", "z", "yaw"]].to_numpy(np.float64))
    sampled = np.flatnonzero(reason == "")
    return index["scan_id"].to_numpy(), t, cfg, ScanStore(cfg, split_by_scan(scans)), initial, sampled


def _run(strategy, sampled, clouds, sids, t, cfg, initial):
    if strategy == "graph":
        return register_graph(sampled, clouds, sids, t, cfg, initial, priors=True)
    if strategy == "previous":
        return register_sequential(sampled, clouds, sids, t, cfg, initial)
    if strategy == "map":
        return register_map(sampled, clouds, sids, t, cfg, initial)
    return register_odometry(sampled, sampled, clouds, sids, t, cfg, initial)


def _assert_same(a: ScanRegistration, b: ScanRegistration) -> None:
    for f in dataclasses.fields(ScanRegistration):
        np.testing.assert_array_equal(getattr(a, f.name), getattr(b, f.name), err_msg=f.name)


def test_before_registration_copies_its_inputs():
    reason = np.array(["", "duplicate"], dtype=object)
    pose = np.zeros((2, 4))
    r = ScanRegistration.before_registration(reason, pose)
    r.reason[0], r.pose[0, 0] = "anchor", 1.0
    assert reason[0] == "" and pose[0, 0] == 0.0
    assert not r.kept.any() and np.isnan(r.fitness_prior).all() and np.isnan(r.pose_correction).all()
    assert r.pose_correction.shape == (2, 3) and len(r.sampled) == 0 and r.n_anchors == 0


@pytest.mark.parametrize("strategy", ["graph", "previous", "map", "odometry"])
def test_strategy_returns_a_scan_registration_and_changes_nothing_given(strategy):
    sids, t, cfg, clouds, initial, sampled = _inputs("odometry" if strategy == "odometry" else "pose")
    if strategy in ("previous", "map"):
        cfg = cfg.replace(reference=strategy)
    given, given_sampled = copy.deepcopy(initial), sampled.copy()

    res = _run(strategy, sampled, clouds, sids, t, cfg, initial)

    _assert_same(initial, given)
    np.testing.assert_array_equal(sampled, given_sampled)
    assert isinstance(res, ScanRegistration)
    for f in ("kept", "reason", "fitness_prior", "fitness_icp", "inlier_rmse_m", "pose_correction", "pose"):
        assert not np.shares_memory(getattr(res, f), getattr(initial, f)), f
    assert res.kept.shape == res.fitness_icp.shape == res.inlier_rmse_m.shape == (N,)
    assert res.pose.shape == (N, 4) and res.pose_correction.shape == (N, 3)
    np.testing.assert_array_equal(res.sampled, sampled)
    # a clean recording: every sampled scan kept, the screened one untouched
    assert res.kept[sampled].all() and not res.kept[DUPLICATE]
    assert res.reason[DUPLICATE] == "duplicate" and np.isnan(res.fitness_icp[DUPLICATE])
    assert set(res.reason[sampled]) <= {"", "anchor"}
    assert np.isfinite(res.pose[sampled]).all()
    # anchors: the first scan (previous, odometry); in the pose graph every scan has edges
    assert res.n_anchors == {"graph": 0, "map": 0, "previous": 1, "odometry": 1}[strategy]
    if strategy != "graph":
        assert res.n_anchors == int((res.reason == "anchor").sum())
    if strategy != "odometry":  # the localizer's pose was nearly right
        assert np.abs(res.pose_correction[sampled, :2]).max() < 0.02


def test_loop_closure_changes_only_the_poses_of_the_odometry_result():
    sids, t, cfg, clouds, initial, sampled = _inputs("odometry")
    odo = register_odometry(sampled, sampled, clouds, sids, t, cfg, initial)
    given = copy.deepcopy(odo)

    closed = register_graph(np.flatnonzero(odo.kept), clouds, sids, t, cfg, odo, priors=False)

    _assert_same(odo, given)
    for f in dataclasses.fields(ScanRegistration):
        if f.name != "pose":
            np.testing.assert_array_equal(getattr(closed, f.name), getattr(odo, f.name), err_msg=f.name)
    assert np.isfinite(closed.pose[odo.kept]).all()
    np.testing.assert_array_equal(closed.pose[~odo.kept], odo.pose[~odo.kept])

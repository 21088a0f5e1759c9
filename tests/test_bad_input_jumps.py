"""Every scan dropped before registration is in the verdict (issue 45 item 3): the
screening's ``pose_jump`` and ``too_few_points`` drops are losses by reason, beside
ingest's and the scans without a pose; a jump of the localizer's pose is a warning that
says where (scan, seconds into the scans) and by how much
(:mod:`floorscan.register.losses`)."""

import numpy as np
import pandas as pd

from benchmarks.bench_bad_input import cases, run_corpus
from floorscan.register.consistency import verdict
from floorscan.register.losses import (
    Losses,
    describe_jumps,
    ingest_losses,
    pose_jump_episodes,
    with_pose_losses,
    with_screening_losses,
)

T = 1_700_000_000_000_000_000 + np.arange(10, dtype=np.int64) * 100_000_000


def test_carmen_poses_500_m_off_are_a_warning_naming_the_jumps(tmp_path):
    """Three lines of a CARMEN log 500 m off: the verdict was ``kept 4 of 4 sampled scans
    (100 %)`` with nothing of the three scans; now it counts them and names the jumps."""
    case = next(c for c in cases() if c.name == "carmen_three_poses_500_m_off")
    (o,) = run_corpus(tmp_path, [case], echo=None)
    assert o.outcome == "warning", o.detail


def _poses(jump_at=(), dx=500.0):
    x = np.arange(10) * 0.05
    x[list(jump_at)] += dx
    return pd.DataFrame({"x": x, "y": 0.0, "yaw": 0.0})


def test_jumps_are_grouped_by_the_last_plausible_pose_and_say_where_and_how_far():
    reasons = np.array(["", "", "", "pose_jump", "pose_jump", "", "duplicate", "pose_jump", "", ""])
    poses = _poses(jump_at=(3, 4, 7))
    jumps = pose_jump_episodes(reasons, T, poses[["x", "y", "yaw"]].to_numpy())
    assert [(j.first, j.n_scans, j.last, j.back) for j in jumps] == [(3, 2, 2, 5), (7, 1, 5, 8)]
    assert abs(jumps[0].distance_m - 500.05) < 1e-9 and abs(jumps[0].dt_s - 0.1) < 1e-9
    assert abs(jumps[1].distance_m - 500.10) < 1e-9  # from scan 5 (6 is a duplicate), 0.2 s
    text = describe_jumps(jumps, np.arange(100, 110), T, "register.max_speed_m_s 2")
    assert text == (
        "2 jumps: at scan 107 (0.7 s into the scans) 500.10 m and 0 deg in 0.20 s, 1 scan until the pose came "
        "back; at scan 103 (0.3 s into the scans) 500.05 m and 0 deg in 0.10 s, 2 scans until the pose came back; "
        "faster than register.max_speed_m_s 2"
    )
    # a relocalisation: the poses never come back within the recording
    reasons = np.array([""] * 6 + ["pose_jump"] * 4)
    (j,) = pose_jump_episodes(reasons, T, _poses(jump_at=range(6, 10), dx=3.0)[["x", "y", "yaw"]].to_numpy())
    assert (j.first, j.n_scans, j.back) == (6, 4, -1)
    assert "to the end of the recording (the poses never came back)" in describe_jumps([j], np.arange(10), T)


def test_screening_losses_count_jumps_and_thin_scans_not_duplicates_nor_empty_scans_twice():
    index = pd.DataFrame({"scan_id": np.arange(10), "n_points": [50] * 9 + [0]})
    losses = ingest_losses(index, {"n_frames_read": "10"})
    assert losses.counts == {"lost_no_points": 1}
    reasons = np.array(["", "pose_jump", "duplicate", "too_few_points", "", "", "no_pose:gap", "", "",
                        "too_few_points"])
    out = with_screening_losses(losses, np.arange(10), T, reasons, _poses(jump_at=(1,)), "register.max_speed_m_s 2", 30)
    out = with_pose_losses(out, np.arange(10), T, reasons)
    assert out.counts == {"no_pose": 1, "pose_jump": 1, "too_few_points": 1, "lost_no_points": 1}
    assert list(out.counts) == ["no_pose", "pose_jump", "too_few_points", "lost_no_points"]
    w = out.warnings()
    assert w[1].startswith("1 of the recording's 10 scans (10 %) were dropped where the localizer's pose jumped "
                           "(pose_jump: 1 jump: at scan 1 (0.1 s into the scans) 500.05 m")
    assert w[2] == "1 of the recording's 10 scans (10 %) have too few points (too_few_points: fewer than register.min_points 30)"
    # odometry mode: no poses, the jumps counted without detail
    bare = with_screening_losses(Losses(10), np.arange(10), T, reasons, None)
    assert bare.counts == {"pose_jump": 1, "too_few_points": 2}
    none = Losses(10)
    assert with_screening_losses(none, np.arange(10), T, np.array([""] * 9 + ["duplicate"]), None) is none


def test_the_verdict_line_counts_the_jumps_and_too_many_stop_the_stage():
    reasons = np.array([""] * 7 + ["pose_jump"] * 3)
    losses = with_screening_losses(Losses(10), np.arange(10), T, reasons, _poses(jump_at=(7, 8, 9)))
    v = verdict(20, 20, 0.9, 1000, 0.2, 0.3, losses=losses, max_lost_fraction=0.5)
    # one cause (the jumps): its line gives the count, the head does not say it again
    assert v.line().startswith("WARNING: kept 20 of 20 sampled scans (100 %); map consistency 0.90")
    assert v.line().count("3 of the recording's 10 scans (30 %)") == 1
    assert ("pose_jump: 1 jump: at scan 7 (0.7 s into the scans) 500.05 m and 0 deg in 0.10 s, 3 scans to the end "
            "of the recording (the poses never came back))") in v.line()
    v = verdict(20, 20, 0.9, 1000, 0.2, 0.3, losses=losses, max_lost_fraction=0.2)
    assert not v.ok and "never reached registration (3 pose jumps), more than register.max_lost_fraction 0.2" in v.line()


def test_a_localizer_that_relocalises_is_a_warning_naming_the_scan_and_the_metres(tmp_path):
    """``map -> odom`` jumps 3 m at 5 s and stays (issue 45 item 2): the scans after it
    were placed 3 m from those before, and the verdict named one scan without a pose.
    Now it says where the map pose jumped, by how much, and that it stayed."""
    case = next(c for c in cases() if c.name == "bag_localizer_relocalises")
    (o,) = run_corpus(tmp_path, [case], echo=None)
    assert o.outcome == "warning", o.detail
    assert "at scan 50 (5.0 s into the scans) the map pose jumped 2.9" in o.detail, o.detail
    assert "relocalisation" in o.detail


def test_a_jump_that_stays_is_a_relocalisation_and_one_that_comes_back_is_not():
    t = 1_700_000_000_000_000_000 + np.arange(12, dtype=np.int64) * 100_000_000
    x = np.arange(12) * 0.05  # 0.5 m/s along x
    x[5:] += 3.0  # relocalised at scan 5: the poses stay 3 m on
    reasons = np.array([""] * 5 + ["pose_jump"] * 3 + [""] * 4)
    xyyaw = np.c_[x, np.zeros(12), np.zeros(12)]
    (j,) = pose_jump_episodes(reasons, t, xyyaw)
    assert (j.first, j.n_scans, j.last, j.back) == (5, 3, 4, 8)
    assert j.relocalised and abs(j.offset_m - 3.0) < 1e-9 and abs(j.size_m - 3.0) < 1e-9
    text = describe_jumps([j], np.arange(12), t)
    assert text.startswith("1 jump: at scan 5 (0.5 s into the scans) the map pose jumped 3.00 m and stayed there "
                           "(a relocalisation: walls seen before and after it may be doubled)"), text
    assert "3 scans dropped until the new pose fit the speed limit" in text
    # the same jump, but the poses come back: an outlier, not a relocalisation
    x2 = np.arange(12) * 0.05
    x2[5:8] += 3.0
    (k,) = pose_jump_episodes(reasons, t, np.c_[x2, np.zeros(12), np.zeros(12)])
    assert not k.relocalised and abs(k.offset_m) < 1e-9
    assert "3.05 m and 0 deg in 0.10 s, 3 scans until the pose came back" in describe_jumps([k], np.arange(12), t)


def test_a_pause_in_the_scans_is_a_warning_naming_where_and_how_long():
    """Two recordings in one file whose stamps go on forward (the second a day later)
    were merged silently; a pause longer than a minute and than 20 of the scans' periods
    is named. The shared logs' pauses (aces: up to 38 s, a scan every 2.2 s) are not."""
    from floorscan.register.consistency import PAUSE_S, pause_warning

    t = (np.arange(50) * 100_000_000).astype(np.int64)
    assert pause_warning(t) == ""
    t2 = t.copy()
    t2[30:] += 86_400 * 10**9  # the second recording, a day later
    text = pause_warning(t2)
    assert text.startswith("the scans pause for 24.0 h after scan 29 (2.9 s into the scans): two recordings in one"), text
    assert "split the file where the second starts" in text
    aces_like = np.cumsum(np.r_[0, np.full(99, 2.2), 37.7, np.full(50, 2.2)]) * 1e9
    assert pause_warning(aces_like.astype(np.int64)) == "" and 37.7 < PAUSE_S
    slow = (np.arange(20) * 10 * 10**9).astype(np.int64)  # a scan every 10 s: 20 periods is 200 s
    slow[10:] += 150 * 10**9
    assert pause_warning(slow) == ""  # 160 s, under 20 of its periods
    slow[10:] += 100 * 10**9
    assert "for 4.3 min after scan 9" in pause_warning(slow)


def test_two_logs_a_day_apart_are_a_warning(tmp_path):
    case = next(c for c in cases() if c.name == "carmen_two_logs_a_day_apart")
    (o,) = run_corpus(tmp_path, [case], echo=None)
    assert o.outcome == "warning", o.detail
    assert "the scans pause for 24.0 h after scan 29" in o.detail

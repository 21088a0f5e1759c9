"""Issue 35, items 2 and 3: TF problems are errors, never a silent switch to LIDAR
odometry; the scans lost before registration (without a pose, or at ingest) are counted
against all the recording's scans, warned about one by one, and stop the register stage
above ``register.max_lost_fraction``.

The bags are written here, in a room that registers (``test_registration.SEGMENTS``),
with the writers of ``conftest``: LaserScans on ``/scan`` at 10 Hz along
``conftest.base_pose``, TF links chosen per test.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from conftest import MOUNT_X, base_pose, cast_rays, laser_pose, write_room_bag
from floorscan.core.io import POSES, SCAN_INDEX, SCANS, InputError, read_metadata, read_table, write_table
from floorscan.ingest.poses import missing_poses_line, scan_poses
from floorscan.ingest.readers import open_recording
from floorscan.ingest.writer import write_recording
from floorscan.register.consistency import verdict
from floorscan.register.losses import Losses, ingest_losses
from floorscan.register.params import RegistrationConfig
from floorscan.register.pipeline import register_scans
from floorscan.register.result import RegistrationError
from floorscan.register.stream import register_recording
from test_registration import SEGMENTS, recording, trajectory

N_BEAMS = 181


def room_ranges(t_s: float) -> np.ndarray:
    """The LaserScan ranges (181 beams over 180 degrees) of the laser at ``laser_pose(t_s)`` in the room."""
    x, y, yaw = laser_pose(t_s)
    ang = float(yaw) + np.linspace(-math.pi / 2, math.pi / 2, N_BEAMS)
    return cast_rays(SEGMENTS, (float(x), float(y)), ang).astype(np.float32)


def write_tf_bag(
    path: Path,
    moving: tuple[tuple[str, str], ...] = (("map", "odom"), ("odom", "base_link")),
    static: tuple[tuple[str, str], ...] = (("base_link", "laser"),),
    scan_frame: str = "laser",
    n_scans: int = 30,
    map_until_s: float | None = None,
    pose_topic: bool = False,
    still: bool = False,
) -> Path:
    """A ROS1 bag (:func:`conftest.write_room_bag`): ``n_scans`` LaserScans of the room
    on ``/scan`` (frame ``scan_frame``), the ``moving`` links on /tf, the ``static`` ones
    on /tf_static."""
    return write_room_bag(path, lambda i: room_ranges(i * 0.1), n=n_scans, scan_frame=scan_frame, links=moving,
                          static=static, map_until_s=map_until_s, pose_topic=pose_topic, still=still)


def ingest_bag(bag: Path, out: Path, dataset: dict | None = None):
    """Ingest (open_recording + write_recording) and the poses stage, in ``out``:
    (scan index, its metadata, poses)."""
    out.mkdir(parents=True, exist_ok=True)
    rec = open_recording({"path": str(bag), **(dataset or {})}, {}, max_gap_s=0.5)
    write_recording(rec, out / "scans.parquet", out / "scan_index.parquet", out / "pose_stream.parquet")
    index = read_table(out / "scan_index.parquet")
    poses = scan_poses(index, read_table(out / "pose_stream.parquet"), 0.5, str(bag))
    write_table(poses, out / "poses.parquet", schema=POSES)
    return index, read_metadata(out / "scan_index.parquet"), poses


def ingest_error(bag: Path, tmp_path: Path, dataset: dict | None = None) -> str:
    out = tmp_path / "out"
    with pytest.raises(InputError) as info:
        ingest_bag(bag, out, dataset)
    assert not list(out.glob("*.parquet")), "a failed ingest leaves no table"
    message = str(info.value)
    assert "\n" not in message  # one paragraph
    return message


# --- item 2: TF problems are errors ---------------------------------------------------------


def test_the_good_bag_reads_its_map_poses_from_tf(tmp_path):
    """The reference: the full chain map -> odom -> base_link -> laser gives map poses."""
    index, meta, poses = ingest_bag(write_tf_bag(tmp_path / "good.bag"), tmp_path / "out")
    assert (meta["pose_kind"], meta["pose_source"]) == ("map", "TF map -> odom -> base_link -> laser")
    assert len(index) == 30 and poses["valid"].all()
    x, y, _ = laser_pose(0.0)
    assert (poses.loc[0, "x"], poses.loc[0, "y"]) == pytest.approx((x, y), abs=1e-3)


def test_a_robot_that_never_moves_reads_its_one_pose_from_tf(tmp_path):
    """A stationary robot's TF chain never changes (every link static): each scan gets
    the chain's one pose, as a stationary CARMEN log's scans do (it was refused)."""
    index, _, poses = ingest_bag(write_tf_bag(tmp_path / "still.bag", still=True), tmp_path / "out")
    x, y, yaw = base_pose(0.0)
    assert len(index) == len(poses) == 30 and poses["valid"].all()
    assert np.ptp(poses["x"]) == 0.0 and np.ptp(poses["yaw"]) == 0.0
    assert poses["x"].iloc[0] == pytest.approx(x + MOUNT_X * np.cos(yaw), abs=1e-6)
    assert poses["y"].iloc[0] == pytest.approx(y + MOUNT_X * np.sin(yaw), abs=1e-6)


def test_a_misspelt_scan_frame_is_an_error_naming_the_frame_the_frames_and_the_chains(tmp_path):
    """The scan's frame_id 'lasr' is not in TF, which has map -> odom -> base_link -> laser:
    an error, not LIDAR odometry (before: pose kind none, the map frame moved)."""
    bag = write_tf_bag(tmp_path / "misspelt.bag", scan_frame="lasr")
    message = ingest_error(bag, tmp_path)
    assert message.startswith(f"{bag}: no TF chain from 'map' to the scan frame 'lasr': 'lasr' is not a frame on /tf")
    assert "Frames on /tf and /tf_static: 'base_link', 'laser', 'map', 'odom'." in message
    assert "Chains: map -> odom -> base_link -> laser." in message
    assert "does not fall back to LIDAR odometry on its own" in message


def test_an_empty_scan_frame_is_an_error(tmp_path):
    message = ingest_error(write_tf_bag(tmp_path / "empty.bag", scan_frame=""), tmp_path)
    assert "no TF chain from 'map' to the scan frame '': the scan's frame_id is empty." in message
    assert "Chains: map -> odom -> base_link -> laser." in message


def test_a_tf_loop_is_an_error_naming_the_loop(tmp_path):
    """base_link -> laser on /tf_static and laser -> base_link on /tf: each frame has one
    parent, and the way up from the laser comes back to it."""
    bag = write_tf_bag(tmp_path / "loop.bag", moving=(("map", "odom"), ("laser", "base_link")))
    message = ingest_error(bag, tmp_path)
    assert "no TF chain from 'map' to the scan frame 'laser': the TF tree has a loop: 'laser' -> 'base_link' -> 'laser'." in message
    assert "Chains: laser -> base_link -> laser (a loop); map -> odom." in message


def test_a_frame_with_two_parents_is_an_error_naming_both(tmp_path):
    bag = write_tf_bag(tmp_path / "two.bag", moving=(("map", "odom"), ("odom", "base_link"), ("world", "base_link")))
    message = ingest_error(bag, tmp_path)
    assert "TF frame 'base_link' has several parents ('odom', 'world'); a TF tree gives each frame one." in message
    assert "Chains: map -> odom -> base_link -> laser; world -> base_link -> laser." in message


def test_a_map_frame_under_another_root_names_the_way_out(tmp_path):
    """map -> odom exists, but the laser's chain starts at 'odom2': the message says
    where it stops and which pose source the user can name by hand."""
    bag = write_tf_bag(tmp_path / "apart.bag", moving=(("map", "odom"), ("odom2", "base_link")))
    message = ingest_error(bag, tmp_path)
    assert "no TF chain from 'map' to the scan frame 'laser' (stops at 'odom2'): its chain starts at 'odom2'" in message
    assert "{source: tf, fixed_frame: odom2}" in message
    # named by hand, it is used
    _, meta, poses = ingest_bag(bag, tmp_path / "by_hand", {"pose": {"source": "tf", "fixed_frame": "odom2"}})
    assert meta["pose_kind"] == "map" and meta["pose_source"] == "TF odom2 -> base_link -> laser (set in the dataset)"
    assert poses["valid"].all()


def test_a_pose_source_set_by_hand_reads_a_bag_with_a_misspelt_scan_frame(tmp_path):
    """The user named the pose topic: ingest does not need the TF chain to the scans."""
    bag = write_tf_bag(tmp_path / "misspelt.bag", scan_frame="lasr", pose_topic=True)
    _, meta, poses = ingest_bag(bag, tmp_path / "out", {"pose": {"source": "topic", "topic": "/amcl_pose"}})
    assert meta["pose_kind"] == "map" and poses["valid"].all()


def test_two_parents_on_the_mount_are_not_swallowed(tmp_path):
    """With a pose topic the mount base_link -> laser is looked up in TF; a frame with two
    parents on the way is an error, not "no mount" (the scanner taken to be at the base)."""
    bag = write_tf_bag(tmp_path / "two.bag", moving=(("map", "odom"), ("odom", "base_link"), ("world", "base_link")),
                       static=(("base_link", "laser"), ("odom", "laser")), pose_topic=True)
    message = ingest_error(bag, tmp_path)
    assert "TF frame 'laser' has several parents ('base_link', 'odom')" in message


def test_without_a_map_frame_the_fallback_to_lidar_odometry_is_a_verdict_warning(tmp_path):
    """Wheel odometry only (odom -> base_link -> laser, no map frame): ingest goes on
    with pose kind none, and the register verdict says why it used LIDAR odometry."""
    bag = write_tf_bag(tmp_path / "odom.bag", moving=(("odom", "base_link"),))
    _, meta, _ = ingest_bag(bag, tmp_path / "out")
    assert (meta["pose_kind"], meta["pose_source"]) == ("none", "none: wheel odometry only (TF odom -> base_link -> laser); LIDAR odometry")
    true, t = trajectory(12)
    scans, index, _ = recording(true, t)
    r = register_scans(scans, index, None, {"every_n": 1, "loop_closure": False}, recording=meta)
    v = r.summary["verdict"]
    assert r.summary["config"]["mode"] == "odometry" and v["ok"]
    assert v["warnings"][0] == (
        "no map poses in the recording (pose source: none: wheel odometry only (TF odom -> base_link -> laser); "
        "LIDAR odometry), so the scans were placed by LIDAR odometry (register.mode auto) and the map frame is "
        "the first scan's"
    )
    assert v["line"].startswith("WARNING: kept 12 of 12 sampled scans (100 %);")
    # asked for by the user: no warning about it
    r = register_scans(scans, index, None, {"mode": "odometry", "every_n": 1, "loop_closure": False}, recording=meta)
    assert not any("LIDAR odometry" in w for w in r.summary["verdict"]["warnings"])


# --- the localizer stops part-way --------------------------------------------------------------


def test_a_localizer_that_stops_part_way_stops_the_register_stage(tmp_path, caplog):
    """map -> odom ends after 0.95 s of a 3 s bag: 20 of the 30 scans get no pose. The
    verdict counts them against all 30 scans (before: "kept 10 of 10 sampled scans
    (100 %)"); above register.max_lost_fraction 0.2 the stage stops naming them, with
    the option at 1 it goes on with a warning."""
    bag = write_tf_bag(tmp_path / "stops.bag", map_until_s=1.0)
    index, meta, poses = ingest_bag(bag, tmp_path / "out")
    assert meta["pose_kind"] == "map"
    assert poses["valid"].tolist() == [True] * 10 + [False] * 20
    assert set(poses.loc[~poses["valid"], "reason"]) == {"after_pose_stream"}
    assert missing_poses_line(poses) == (
        "20 of 30 scans have no pose (after_pose_stream 20); the register stage counts them as lost "
        "(register.max_lost_fraction)"
    )
    scans = read_table(tmp_path / "out" / "scans.parquet")
    cfg = {"every_n": 1, "reference": "previous"}
    with pytest.raises(RegistrationError) as info:
        register_scans(scans, index, poses, cfg, recording=meta)
    message = str(info.value)
    # one cause: its own lines give the count, the verdict's head does not repeat it
    assert message.startswith("register: the result is poor: POOR: kept 10 of 10 sampled scans (100 %); map consistency")
    assert (
        "20 of the recording's 30 scans (67 %) never reached registration (20 without a pose), more than "
        "register.max_lost_fraction 0.2" in message
    )
    assert (
        "20 of the recording's 30 scans (67 %) have no pose (after_pose_stream 20: after the last pose; "
        "the poses end 0.9 s into the 2.9 s of scans)" in message
    )
    r = register_scans(scans, index, poses, {**cfg, "max_lost_fraction": 1.0}, recording=meta)
    v = r.summary["verdict"]
    assert v["ok"] and v["n_kept"] == 10
    assert v["losses"] == {"n_recording": 30, "counts": {"no_pose": 20}, "fraction": pytest.approx(2 / 3)}
    assert v["line"].startswith("WARNING: kept 10 of 10 sampled scans (100 %); map consistency")
    assert v["line"].count("20 of the recording's 30 scans") == 1


def test_a_few_scans_without_a_pose_are_a_warning_only():
    """3 of 30 scans (10 %) in a gap: within register.max_lost_fraction 0.2, a warning."""
    true, t = trajectory(30)
    scans, index, poses = recording(true, t)
    poses.loc[[10, 11, 12], ["valid", "reason"]] = (False, "pose_gap")
    poses.loc[[10, 11, 12], ["x", "y", "yaw"]] = np.nan
    r = register_scans(scans, index, poses, {"every_n": 1, "reference": "previous"})
    v = r.summary["verdict"]
    assert v["ok"]
    assert "3 of the recording's 30 scans (10 %) have no pose (pose_gap 3: in a gap between poses longer than poses.max_gap_s)" in v["warnings"]
    assert "lost before registration" not in v["line"] and v["line"].count("3 of the recording's 30 scans") == 1


# --- item 3: ingest's losses, from the scan index's metadata ------------------------------


def _write_recording_tables(tmp_path: Path, meta: dict[str, str], n: int = 30):
    """scans.parquet and scan_index.parquet (with ``meta`` as its metadata) of the room
    recording, and its poses: the register stage's inputs."""
    true, t = trajectory(n)
    scans, index, poses = recording(true, t)
    index = index.assign(n_points=scans.groupby("scan_id").size().to_numpy(), n_dropped=0, frame="laser")
    write_table(scans, tmp_path / "scans.parquet", schema=SCANS)
    write_table(index, tmp_path / "scan_index.parquet", schema=SCAN_INDEX, metadata=meta)
    return index, poses


def test_ingest_losses_are_warnings_with_their_numbers(tmp_path):
    """40 frames read, 3 bad and 2 without points (the 35 scans in the index), one unknown
    line: 6 of 41 lost (15 %), each a warning; the streamed stage reads them from the
    scan index's metadata."""
    meta = {"pose_kind": "map", "n_frames_read": "40", "lost_bad_frames": "3", "lost_no_points": "2",
            "lost_unknown_lines": "1"}
    _, poses = _write_recording_tables(tmp_path, meta, n=35)
    recorded = read_metadata(tmp_path / "scan_index.parquet")
    r = register_recording(tmp_path / "scans.parquet", read_table(tmp_path / "scan_index.parquet"), poses,
                           {"every_n": 1, "reference": "previous"}, tmp_path / "registered.parquet", recording=recorded)
    v = r.summary["verdict"]
    assert v["ok"]
    assert v["warnings"][:3] == [
        "3 of the recording's 41 scans (7 %) were bad frames, skipped at ingest (lost_bad_frames)",
        "2 of the recording's 41 scans (5 %) have no valid point (every return invalid or out of range) (lost_no_points)",
        "1 of the recording's 41 scans (2 %) are lines of an unknown type, never read (lost_unknown_lines)",
    ]
    assert ", 6 of the recording's 41 scans (15 %) lost before registration;" in v["line"]
    assert not any("lost_unlisted_files" in w for w in v["warnings"])  # 0: no warning


def test_ingest_losses_above_the_threshold_stop_the_stage_naming_them(tmp_path):
    """A PCD folder with 20 of its 40 files not in the locations CSV (issue 35): 20 of 40
    scans lost (50 %), above register.max_lost_fraction 0.2."""
    _, poses = _write_recording_tables(tmp_path, {"pose_kind": "map", "n_frames_read": "20",
                                                  "lost_unlisted_files": "20"}, n=20)
    index = read_table(tmp_path / "scan_index.parquet")
    recorded = read_metadata(tmp_path / "scan_index.parquet")
    cfg = {"every_n": 1, "reference": "previous"}
    with pytest.raises(RegistrationError) as info:
        register_recording(tmp_path / "scans.parquet", index, poses, cfg, tmp_path / "registered.parquet",
                           recording=recorded)
    message = str(info.value)
    assert (
        "20 of the recording's 40 scans (50 %) never reached registration (20 files not in the locations CSV), "
        "more than register.max_lost_fraction 0.2: the plan would show only part of what was recorded "
        "(register.max_lost_fraction 1 accepts it)" in message
    )
    assert "20 of the recording's 40 scans (50 %) are files not in the locations CSV, never read (lost_unlisted_files)" in message
    assert not (tmp_path / "registered.parquet").exists()
    # the threshold is the option's: at 0.6 the same recording is registered, with the warning
    r = register_recording(tmp_path / "scans.parquet", index, poses, {**cfg, "max_lost_fraction": 0.6},
                           tmp_path / "registered.parquet", recording=recorded)
    assert r.summary["verdict"]["ok"] and r.summary["verdict"]["losses"]["counts"] == {"lost_unlisted_files": 20}


def test_losses_count_scans_without_a_pose_and_ingest_losses_together():
    """Neither alone is above 20 %, together they are: 4 without a pose + 3 bad frames of
    30 scans = 23 %."""
    true, t = trajectory(27)
    scans, index, poses = recording(true, t)
    poses.loc[[0, 1, 2, 3], ["valid", "reason"]] = (False, "before_pose_stream")
    poses.loc[[0, 1, 2, 3], ["x", "y", "yaw"]] = np.nan
    with pytest.raises(RegistrationError, match=re.escape(
        "7 of the recording's 30 scans (23 %) never reached registration (4 without a pose, 3 bad frames)"
    )) as info:
        register_scans(scans, index, poses, {"every_n": 1, "reference": "previous"},
                       recording={"pose_kind": "map", "lost_bad_frames": "3"})
    assert "(before_pose_stream 4: before the first pose; the poses start 2.0 s into the 13.0 s of scans)" in str(info.value)


def test_missing_loss_keys_count_zero_and_bad_ones_are_refused():
    index = pd.DataFrame({"scan_id": np.arange(5), "t_ns": np.arange(5), "n_points": [10, 0, 10, 10, 10]})
    none = ingest_losses(index.drop(columns="n_points"), {"pose_kind": "map"})
    assert (none.n_recording, none.counts, none.n_lost) == (5, {}, 0)
    # a scan of the index without points is a loss, on top of those ingest skipped
    empty = ingest_losses(index, {"lost_no_points": "2", "n_frames_read": "7"})
    assert (empty.n_recording, empty.counts) == (7, {"lost_no_points": 3})
    with pytest.raises(InputError, match=r"metadata lost_bad_frames='three' is not a count of scans"):
        ingest_losses(index, {"lost_bad_frames": "three"})
    with pytest.raises(InputError, match=r"metadata n_frames_read='-1' is not a count"):
        ingest_losses(index, {"n_frames_read": "-1"})


def test_verdict_judges_losses_by_the_option():
    losses = Losses(300, {"no_pose": 201}, "after_pose_stream 201: after the last pose")
    v = verdict(14, 14, math.nan, 0, 0.2, 0.3, losses=losses, max_lost_fraction=0.2)
    assert not v.ok
    assert v.line().startswith("POOR: kept 14 of 14 sampled scans (100 %); map consistency undefined")
    assert v.problems == [
        "201 of the recording's 300 scans (67 %) never reached registration (201 without a pose), more than "
        "register.max_lost_fraction 0.2: the plan would show only part of what was recorded "
        "(register.max_lost_fraction 1 accepts it)"
    ]
    assert verdict(14, 14, math.nan, 0, 0.2, 0.3, losses=losses, max_lost_fraction=0.7).ok
    # exactly at the threshold is not above it
    assert verdict(14, 14, math.nan, 0, 0.2, 0.3, losses=Losses(10, {"no_pose": 2}), max_lost_fraction=0.2).ok
    assert RegistrationConfig().max_lost_fraction == 0.2  # the schema's default
    from floorscan.core.config import ConfigError, stage_params

    with pytest.raises(ConfigError, match=r"register.max_lost_fraction: 1.5 is greater than the maximum of 1"):
        stage_params(RegistrationConfig, {"max_lost_fraction": 1.5})

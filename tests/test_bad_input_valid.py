"""Valid recordings that were refused (issue 45 item 1): each runs to registration with
what its class needs, made by the bad-input corpus's tools
(``benchmarks/bench_bad_input.py``: the tiny-recording writers of ``conftest.py``).

- A bag without ``/tf`` or ``/tf_static`` (only a scan topic, or one with ``/amcl_pose``):
  rosbags' ``messages(connections=[])`` yields *every* message of the bag, so the TF
  reader decoded the scans as transforms ("truncated or corrupt"). Every read of a bag's
  messages goes through :func:`floorscan.ingest.ros_messages.bag_messages`.
- A PCD folder with epoch stamps (``t_ns`` ~1.6e18, every digit set): the reduced
  recording read them as float64 and lost the last digits; they are int64 everywhere.
- A 360 degree scanner whose span is a little over 2 pi, and a scanner mounted upside
  down (roll 180 degrees in its TF): valid scans, the second turned over by its mount.
"""

import ast
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.spatial.transform import Rotation

from benchmarks.bench_bad_input import cases, run_corpus
from floorscan.core.io import InputError

PACKAGE = Path(__file__).resolve().parents[1] / "floorscan"

#: The corpus's cases of this item, and what each gives.
VALID = {
    "bag_no_tf_scan_only_ros1": "warning",  # LIDAR odometry, said in the verdict
    "bag_no_tf_scan_only_ros2": "warning",
    "bag_no_tf_pose_topic_ros1": "correct",
    "bag_no_tf_pose_topic_ros2": "correct",
    "pcd_epoch_stamps": "correct",
    "scan_360_span_a_little_over_two_pi": "correct",
    "scan_upside_down_tf": "correct",
    "scan_upside_down_pose_topic": "correct",
}


def test_the_refused_classes_run(tmp_path):
    """Ingest, poses and register on each case (about 2 s): the bags without TF run on
    their pose topic (the first pose the base's) or by LIDAR odometry (the verdict says
    so); the PCD folder's stamps are the CSV's to the nanosecond and its reduced
    recording is written; the 360 and upside-down scans' points lie on the room's walls
    at their poses."""
    selected = [c for c in cases() if c.name in VALID]
    assert len(selected) == len(VALID)
    outcomes = run_corpus(tmp_path, selected, echo=None)
    got = {o.case.name: (o.outcome, o.detail) for o in outcomes}
    wrong = {k: v for k, v in got.items() if v[0] != VALID[k]}
    assert not wrong, wrong


class _Reader:
    """A stand-in for rosbags' AnyReader: messages(connections=[]) yields every message."""

    def __init__(self):
        self.all = [("c", 1, b"scan"), ("c", 2, b"scan")]

    def messages(self, connections=()):
        return iter(self.all if not connections else [m for m in self.all if m[0] in connections])


def test_bag_messages_of_no_connection_are_none():
    from floorscan.ingest.ros_messages import bag_messages

    reader = _Reader()
    assert list(bag_messages(reader, [])) == []
    assert list(bag_messages(reader, iter(()))) == []
    assert len(list(bag_messages(reader, ["c"]))) == 2


def test_no_module_reads_a_bags_messages_but_through_bag_messages():
    """The class, not the call site: a new ``reader.messages(...)`` would bring the
    empty-list trap back."""
    calls = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "messages":
                calls.append(str(path.relative_to(PACKAGE)))
    assert calls == ["ingest/ros_messages.py"], calls


def test_the_reduced_bag_of_a_bag_without_tf(tmp_path):
    """The select stage's copy of a bag with only a scan topic: the selected scans."""
    from benchmarks.bench_bad_input import room_bag
    from floorscan.ingest.readers import open_recording
    from floorscan.ingest.reduced import write_reduced_recording

    src = room_bag(tmp_path / "scan_only.bag", n=12, links=(), static=())
    rec = open_recording({"path": str(src)}, {}, 0.5)
    t = [s.t_ns for s in rec.scans]
    info = write_reduced_recording(src, "rosbag", [2, 7], tmp_path / "reduced.bag", {"scan_topic": "/scan", "t_ns": t})
    assert info["topics"] == {"/scan": 2}
    again = [s.t_ns for s in open_recording({"path": str(tmp_path / "reduced.bag")}, {}, 0.5).scans]
    assert again == [t[2], t[7]]


def test_epoch_stamps_are_read_as_integers_to_the_nanosecond(tmp_path):
    from floorscan.ingest.pcd import stamp_column

    col = pd.Series(["1612345678123456789", "1612345678223456906", "9223372036854775807"])
    got = stamp_column(tmp_path / "locations.csv", col)
    assert got.dtype == np.int64
    assert got.tolist() == [1612345678123456789, 1612345678223456906, 2**63 - 1]
    assert int(float(got[0])) != int(got[0])  # what a float64 would have made of it
    with pytest.raises(InputError, match=r"locations.csv: column 't_ns' row 2 is '1.6e18'"):
        stamp_column(tmp_path / "locations.csv", pd.Series(["1", "1.6e18"]))


def test_a_span_a_little_over_a_full_turn_is_radians_and_degrees_are_still_refused():
    from floorscan.ingest.points import ANGLE_SPAN_TOLERANCE_RAD, angle_span_problem

    assert angle_span_problem(2 * math.pi + math.radians(3), "span") is None  # 3 beams past the turn
    assert angle_span_problem(2 * math.pi + 0.9 * ANGLE_SPAN_TOLERANCE_RAD, "span") is None
    assert "degrees" in angle_span_problem(2 * math.pi + 1.1 * ANGLE_SPAN_TOLERANCE_RAD, "span")
    for degrees in (90.0, 180.0, 270.0, 360.0):
        assert "degrees" in angle_span_problem(degrees, "span")


def _stream(rot: Rotation, n: int = 3):
    from floorscan.ingest.tf_poses import planar_pose_stream

    t = np.arange(n, dtype=np.int64) * 100_000_000
    rots = Rotation.from_quat(np.repeat(rot.as_quat()[None], n, axis=0)) if len(rot.as_quat().shape) == 1 else rot
    return planar_pose_stream(t, rots, np.zeros((n, 3)), "chain")


def test_an_upside_down_scanner_is_level_turned_over_and_a_tilted_one_refused():
    from floorscan.ingest.tf_poses import turn_over

    for euler in ("xyz", "yxz"):  # rolled or pitched half a turn, heading 30 deg
        r = Rotation.from_euler("z", 30, degrees=True) * Rotation.from_euler(euler[0], 180, degrees=True)
        s = _stream(r)
        assert s.attrs["upside_down"] is True
        p = np.array([[2.0, 1.0, 0.5]])
        # the stream's level pose places the turned-over points where the mount puts them
        yaw = float(s["yaw"].iloc[0])
        level = Rotation.from_euler("z", yaw).apply(turn_over(p))
        np.testing.assert_allclose(level, r.apply(p), atol=1e-9)
    assert _stream(Rotation.from_euler("z", 30, degrees=True)).attrs["upside_down"] is False
    with pytest.raises(InputError, match=r"chain: the scanner is tilted 45.0 deg from level"):
        _stream(Rotation.from_euler("x", 45, degrees=True))
    with pytest.raises(InputError, match=r"tilted 45.0 deg from level"):
        _stream(Rotation.from_euler("x", 135, degrees=True))
    mixed = Rotation.from_euler("x", [[0], [0], [180]], degrees=True)
    with pytest.raises(InputError, match=r"level at first and upside down from pose 2"):
        _stream(mixed)


def test_a_pose_topic_in_the_odometry_frame_is_no_map_pose(tmp_path):
    """Issue 45 item 4: /amcl_pose whose header.frame_id is 'odom' was taken as "the
    bag's one map pose topic"; it is wheel odometry, so the scans run by LIDAR odometry
    and the note names the topic and its frame."""
    from floorscan.ingest.rosbag_detect import is_odometry_frame

    (o,) = run_corpus(tmp_path, [c for c in cases() if c.name == "bag_pose_topic_in_odom_frame"], echo=None)
    assert o.outcome == "warning", o.detail
    assert [is_odometry_frame(f) for f in ("odom", "/odom", "odom_combined", "map", "world", "")] == [
        True, True, True, False, False, False]

"""Two sources in one recording (issue 45, item 2): two frames on one scan topic, two
CARMEN logs in one file. Each used to run to a wrong map with exit 0.

- Scans of one topic in two frames are each placed by their own frame's pose when TF
  links the frames by static mounts (:mod:`floorscan.ingest.scan_frames`), else ingest
  stops naming the topic and both frames with their counts.
- A CARMEN log whose stamps step back by more than
  :data:`floorscan.ingest.recording.MAX_STEP_BACK_S` is never sorted into one
  trajectory: two logs in one file are refused naming the lines where each starts and
  their scans; a single line stamped far back is refused naming it.

The relocalising localizer (the third class) is in ``tests/test_bad_input_jumps.py``.
The recordings are the bad-input corpus's (``benchmarks/bench_bad_input.py``), made from
the test room; none needs ``../shared``.
"""

import math

import numpy as np
import pytest

from benchmarks.bench_bad_input import REAR_MOUNT, cases, run_corpus, run_stages
from floorscan.core.io import InputError, read_table
from floorscan.ingest.tf_chains import TfLink
from floorscan.ingest.tf_poses import static_between


def _case(name):
    return next(c for c in cases() if c.name == name)


def _run(tmp_path, name):
    case = _case(name)
    folder = tmp_path / "in"
    folder.mkdir()
    ds = case.build(folder)
    return case, ds, run_stages(ds, tmp_path / "out")


def test_two_scanners_on_one_topic_are_each_placed_by_their_own_mount(tmp_path):
    """A front and a rear scanner (turned half a turn, 0.3 m apart) on /scan: the rear
    scans used to be placed with the front scanner's pose, 1.4 m off the walls."""
    case, ds, run = _run(tmp_path, "bag_two_scanners_one_topic")
    assert run.error is None, run.message
    assert run.detected["scan_frames"] == "laser 15, rear 15"
    assert any("'laser' (15 scans), 'rear' (15 scans): each placed by its own frame's pose" in n for n in run.notes)
    from benchmarks.bench_bad_input import judge

    outcome, detail = judge(case, run)
    assert outcome == "correct", detail  # the rear scans' points lie on the room's walls
    index = read_table(tmp_path / "out" / "scan_index.parquet")
    assert set(index["frame"]) == {"laser"}  # every scan's points are in the posed frame


def test_a_scan_frame_without_tf_is_refused_naming_the_topic_and_both_frames(tmp_path):
    """The scan frame renamed after 18 scans, TF only for the old name: every scan was
    placed with the first frame's TF and the other frame never mentioned."""
    (o,) = run_corpus(tmp_path, [_case("bag_scan_frame_renamed_midway")], echo=None)
    assert o.outcome == "clear", o.detail
    msg = o.detail
    assert "renamed.bag: topic '/scan' carries scans in 2 frames, 'laser' (18 scans), 'laser_link' (12 scans)" in msg
    assert "no static transform links 'laser' to 'laser_link'" in msg
    assert not list((tmp_path / "out" / o.case.name).glob("*.parquet"))  # nothing half-written


def _link(parent, child, x, yaw):
    e = TfLink(parent, child)
    e.t, e.trans, e.quat = [0], [(x, 0.0, 0.0)], [(0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))]
    e.static = True
    e.finish()
    return e


def test_static_between_two_mounts_maps_points_of_one_scanner_into_the_other():
    edges = {("base_link", "laser"): _link("base_link", "laser", 0.1, 0.0),
             ("base_link", "rear"): _link("base_link", "rear", REAR_MOUNT[0], REAR_MOUNT[2])}
    rot, trans = static_between(edges, "laser", "rear")
    # a point 1 m ahead of the rear scanner is 1.2 m behind the base, 1.3 m behind the laser
    assert np.allclose(rot.apply([1.0, 0.0, 0.0]) + trans, [-1.3, 0.0, 0.0])
    assert static_between(edges, "laser", "laser_link") is None  # not in the tree
    assert static_between({}, "laser", "rear") is None


def test_a_second_frame_in_a_bag_without_tf_is_refused(tmp_path):
    """LIDAR odometry (no TF at all) cannot place a second frame either."""
    from benchmarks.bench_bad_input import _frame_of, room_bag

    path = room_bag(tmp_path / "no_tf_two.bag", links=(), static=(), change=_frame_of("b", lambda i: i % 3 == 0))
    run = run_stages({"name": path.name, "path": str(path)}, tmp_path / "out")
    assert isinstance(run.error, InputError)
    assert "carries scans in 2 frames, 'b' (10 scans), 'laser' (20 scans)" in str(run.error)
    assert "the bag has no TF" in str(run.error)

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
the test room; the real logs concatenated come from ``../shared/data/radish`` (skipped
without it).
"""

import gzip
import math

import numpy as np
import pytest

from conftest import SHARED_DATA, needs_shared
from benchmarks.bench_bad_input import REAR_MOUNT, cases, run_corpus, run_stages
from floorscan.core.io import InputError, read_table
from floorscan.ingest.carmen import open_carmen
from floorscan.ingest.carmen_stamps import log_starts
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


def test_two_carmen_logs_in_one_file_are_refused_naming_where_the_second_starts(tmp_path):
    """Two logs of the test room concatenated, the second stamped before the first: they
    used to be sorted by stamp into one trajectory (the verdict GOOD)."""
    (o,) = run_corpus(tmp_path, [_case("carmen_two_logs_concatenated")], echo=None)
    assert o.outcome == "clear", o.detail
    assert "two_logs.log: holds 2 logs, not one: at line 35 the laser stamps step back 10.9 s" in o.detail
    assert "lines 3-32 hold 30 scans, lines 35-54 hold 20 scans" in o.detail
    assert not list((tmp_path / "out" / o.case.name).glob("*.parquet"))


@pytest.mark.parametrize("name, words", [
    ("carmen_one_line_a_minute_early", "early_line.log:12: FLASER line stamped 59.9 s earlier than the laser line "
                                       "before it (line 11, 101.000 s)"),
    ("bag_one_scan_stamped_a_minute_early", "early.bag: '/scan' message 5 (t 1699999940500000000 ns): header stamp "
                                            "is 59.9 s earlier than the scan before it"),
])
def test_a_scan_stamped_far_back_is_never_sorted_into_the_trajectory(tmp_path, name, words):
    """One line (CARMEN) or message (bag) stamped a minute back used to be sorted to its
    stamp's place, silently in a bag (within the reordering window)."""
    (o,) = run_corpus(tmp_path, [_case(name)], echo=None)
    assert o.outcome == "clear" and words in o.detail, o.detail


def test_log_starts_splits_concatenated_logs_only():
    t = np.r_[200.0 + np.arange(30) * 0.1, 100.0 + np.arange(20) * 0.1]
    assert log_starts(t).tolist() == [30]
    assert log_starts(np.r_[t, 2.0 + np.arange(12) * 0.1]).tolist() == [30, 50]  # three logs
    one_stray = 100.0 + np.arange(50) * 0.1
    one_stray[20] = 3.0  # a single broken stamp: not a log
    assert log_starts(one_stray).size == 0
    short = np.r_[100.0 + np.arange(30) * 0.1, 2.0 + np.arange(5) * 0.1]  # 5 lines: no recording
    assert log_starts(short).size == 0
    junk = np.random.default_rng(0).uniform(0, 1000, 200)  # stamps stepping back everywhere: the stamp class decides
    assert log_starts(junk).size == 0
    jitter = 100.0 + np.arange(50) * 0.1
    jitter[[10, 30]] -= 0.86  # as intel's worst line: sorted, no second log
    assert log_starts(jitter).size == 0


def _laser_lines(text: str) -> list[int]:
    return [i for i, line in enumerate(text.splitlines(), 1) if line.split()[:1] in (["FLASER"], ["ROBOTLASER1"])]


@needs_shared
def test_two_real_logs_concatenated_are_refused_and_intel_still_opens(tmp_path):
    """acapulco and aces concatenated (the issue's case: their stamps overlap, 19-1383 s
    and 21-1339 s, so sorting interleaved two buildings); intel's lines written up to
    0.86 s late are still sorted."""
    radish = SHARED_DATA / "radish"
    first = gzip.decompress((radish / "acapulco-corrected.log.gz").read_bytes()).decode()
    second = gzip.decompress((radish / "aces-corrected.log.gz").read_bytes()).decode()
    if not first.endswith("\n"):
        first += "\n"
    path = tmp_path / "acapulco_then_aces.log"
    path.write_text(first + second)
    n_first_lines = len(first.splitlines())
    a, b = _laser_lines(first), _laser_lines(second)
    start = n_first_lines + b[0]
    with pytest.raises(InputError) as info:
        open_carmen(path, {}, None)
    msg = str(info.value)
    assert msg.startswith(f"{path}: holds 2 logs, not one: at line {start} the laser stamps step back"), msg
    assert (f"lines {a[0]}-{a[-1]} hold {len(a)} scans, lines {start}-{n_first_lines + b[-1]} hold {len(b)} scans"
            in msg), msg
    assert f"split the file before line {start}" in msg
    rec = open_carmen(radish / "intel-corrected.log.gz", {}, None)
    assert rec.detected["stamps"] == "recorded"
    assert any("4 laser lines earlier than the line before them" in n for n in rec.notes)

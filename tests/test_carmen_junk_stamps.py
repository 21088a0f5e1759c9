"""CARMEN logs whose stamps are junk for the whole recording (issue 36, item 3): read in
line order with made-up stamps, said in the ingest notes and the verdict; one bad stamp
in a good log stays an error naming its line."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import flaser_line, needs_shared, robotlaser_line, write_carmen

from floorscan.core.io import InputError, read_metadata
from floorscan.ingest.carmen_stamps import (
    WRAP_S, StampsOutOfRange, made_up_stamps_ns, n_out_of_time_order, out_of_range, stamp_class,
)
from floorscan.ingest.readers import open_recording
from floorscan.ingest.writer import write_recording
from floorscan.register.consistency import stamps_warning, verdict

N = 12
RANGES = [1.0, 2.0, 3.0, 2.5]
REASON = f"{N} of {N} laser stamps out of range (negative or past the 32-bit wrap)"


def _junk_stamps(n: int = N) -> list[str]:
    """The public log's stamps: -0.45 s, then the unsigned 32-bit wrap on every line."""
    return ["-0.45"] + [f"4294967295.{i:02d}" for i in range(1, n)]


def _log(path, stamps, kind="FLASER"):
    """A log with one laser line per stamp, pose x = line index, and an ODOM line
    (stamped like the laser) between every two laser lines."""
    lines = []
    for i, t in enumerate(stamps):
        pose = (float(i), 0.5, 0.0)
        lines.append(flaser_line(RANGES, pose, t) if kind == "FLASER" else robotlaser_line(RANGES, pose, t))
        lines.append(f"ODOM {float(i)} 0.5 0.0 0 0 0 {t} pippo {t}")
    return write_carmen(path, ["# junk stamps", *lines])


@pytest.mark.parametrize("kind", ["FLASER", "ROBOTLASER1"])
def test_every_stamp_junk_is_read_in_line_order_with_made_up_stamps(tmp_path, kind):
    log = _log(tmp_path / "junk.log", _junk_stamps(), kind)
    rec = open_recording({"path": str(log)}, {"missing_time_period_s": 0.25}, 0.5)
    assert rec.detected["stamps"] == "made_up"
    assert rec.detected["stamps_reason"] == REASON
    note = [n for n in rec.notes if "stamps made up" in n]
    assert note == [
        f"{log}: stamps made up: {REASON}; scans in line order stamped at index x 0.25 s "
        "(ingest.missing_time_period_s) from 0 s"
    ]
    out = tmp_path / "out"
    out.mkdir()
    index = write_recording(rec, out / "scans.parquet", out / "scan_index.parquet", out / "pose_stream.parquet")
    assert len(index) == N  # every laser line is a scan
    assert index["source_ordinal"].tolist() == list(range(N))  # line order
    assert index["t_ns"].tolist() == [i * 250_000_000 for i in range(N)]
    meta = read_metadata(out / "scan_index.parquet")
    assert (meta["stamps"], meta["stamps_reason"], meta["n_frames_read"]) == ("made_up", REASON, str(N))
    # the pose stream: each line's own pose at the same made-up stamps
    poses = rec.pose_stream
    assert poses["t_ns"].tolist() == index["t_ns"].tolist()
    assert poses["x"].tolist() == [float(i) for i in range(N)]


def test_junk_stamps_after_a_good_first_stamp_count_from_it(tmp_path):
    # 10 of 12 out of range: the first stamp (5 s) is usable, so the made-up ones start there
    stamps = ["5.0", "5.1"] + [f"4.29497e+09"] * (N - 2)
    rec = open_recording({"path": str(_log(tmp_path / "j.log", stamps))}, {"missing_time_period_s": 0.1}, 0.5)
    assert rec.detected["stamps_reason"] == "10 of 12 laser stamps out of range (past the 32-bit wrap), more than half"
    assert [s.t_ns for s in rec.scans] == [5_000_000_000 + i * 100_000_000 for i in range(N)]


@pytest.mark.parametrize("bad, text", [("-0.45", "-0.45"), ("4294967295.5", "4294967295.5"), ("nan", "nan")])
def test_one_bad_stamp_among_good_ones_names_its_line(tmp_path, bad, text):
    stamps = [f"{10.0 + 0.1 * i:.1f}" for i in range(N)]
    stamps[4] = bad
    log = _log(tmp_path / "one.log", stamps)  # laser line 5 is file line 2 + 2 x 4 = 10
    with pytest.raises(InputError) as e:
        open_recording({"path": str(log)}, {}, 0.5)
    msg = str(e.value)
    assert msg.startswith(
        f"{log}:10: malformed FLASER line: field 13 (ipc_timestamp) is {text}; expected a finite time in seconds, "
        "0 or more and below 2147483648 (2^31 s, the 32-bit wrap)"
    )
    assert f"1 of the {N} laser stamps are out of range" in msg


def test_a_stamp_that_is_not_a_number_stays_a_malformed_line(tmp_path):
    log = _log(tmp_path / "w.log", ["junk"] * N)
    with pytest.raises(InputError, match=r"w.log:2: malformed FLASER line: field 13 \(ipc_timestamp\) is 'junk'; "
                                         r"expected a number"):
        open_recording({"path": str(log)}, {}, 0.5)


def test_half_out_of_range_is_still_an_error_more_than_half_is_made_up():
    t = np.array([1.0, 2.0, 3.0, -1.0, -1.0, -1.0])  # 3 of 6: not more than half
    with pytest.raises(StampsOutOfRange) as e:
        stamp_class(t)
    assert (e.value.index, e.value.n_bad, e.value.n) == (3, 3, 6)
    c = stamp_class(np.r_[t, math.inf])  # 4 of 7
    assert (c.kind, c.n_out_of_range, c.n_out_of_order) == ("made_up", 4, 0)
    assert c.why == "4 of 7 laser stamps out of range (negative or infinite), more than half"


def test_stamps_scrambled_beyond_repair_are_made_up_a_few_swaps_are_sorted():
    scrambled = np.array([5.0, 1.0, 9.0, 3.0, 7.0, 2.0, 8.0, 4.0, 6.0])  # longest in-order run 1, 3, 4, 6: 4
    assert n_out_of_time_order(scrambled) == 5
    c = stamp_class(scrambled)
    assert (c.kind, c.n_out_of_order) == ("made_up", 5)
    assert c.why == "5 of 9 laser stamps out of time order (off the longest run of non-decreasing stamps), more than half"
    swapped = np.array([1.0, 2.0, 4.0, 3.0, 5.0, 6.0])
    c = stamp_class(swapped)
    assert (c.kind, c.n_out_of_order, c.why) == ("recorded", 1, "")


def test_out_of_range_bounds_and_made_up_start():
    t = np.array([0.0, 1.5, WRAP_S - 1.0, WRAP_S, 4294967295.55, -0.45, math.nan, math.inf])
    assert out_of_range(t).tolist() == [False, False, False, True, True, True, True, True]
    assert made_up_stamps_ns(np.array([-0.45, 4294967295.1, 4294967295.2]), 0.5).tolist() == [0, 500_000_000, 1_000_000_000]
    assert made_up_stamps_ns(np.array([2.0, 4294967295.1]), 0.5).tolist() == [2_000_000_000, 2_500_000_000]


def test_the_verdict_names_made_up_stamps_as_a_warning(tmp_path):
    rec = open_recording({"path": str(_log(tmp_path / "junk.log", _junk_stamps()))}, {}, 0.5)
    warning = stamps_warning(rec.detected)
    assert warning == (
        f"stamps made up: {REASON}; the scans keep the recording's order, ingest.missing_time_period_s apart, "
        "so the checks on speed and turn rate are off"
    )
    v = verdict(N, N, 0.9, 500, 0.5, 0.5, stamps=warning)
    assert v.ok and v.warnings == [warning]
    assert v.line() == (
        f"WARNING: kept {N} of {N} sampled scans (100 %); map consistency 0.90 (500 revisited points); {warning}"
    )
    # recorded stamps: no such warning
    assert stamps_warning({"stamps": "recorded"}) == "" and stamps_warning(None) == ""
    # made-up stamps without a reason (a PCD folder without stamps): still named
    assert stamps_warning({"stamps": "made_up"}).startswith("stamps made up; the scans keep")


def test_reduced_junk_log_keeps_the_odometry_beside_the_selected_scans(tmp_path):
    from floorscan.ingest.reduced import write_reduced_recording

    src = _log(tmp_path / "junk.log", _junk_stamps())
    lines = src.read_text().splitlines()  # comment, then laser i at 1 + 2i and its ODOM at 2 + 2i
    out = tmp_path / "junk_out.log"
    info = write_reduced_recording(src, "carmen", [5], out, {"stamps": "made_up"})
    # no usable stamp to window by: the ODOM lines next to laser line 5 (after 4, after 5)
    assert out.read_text().splitlines() == [lines[0], lines[10], lines[11], lines[12]]
    assert info["topics"] == {"#": 1, "FLASER": 1, "ODOM": 2}


@needs_shared
@pytest.mark.realdata
@pytest.mark.workflow
def test_a_shared_log_with_junk_stamps_runs_to_its_plan(tmp_path):
    """orebro's log with the public log's junk stamps on every laser line (-0.45 s, then
    the 32-bit wrap): a bare path runs to its plan, and the verdict says the stamps are
    made up."""
    import gzip
    import json

    from conftest import SHARED_DATA, copy_workflow, snakemake

    wd = copy_workflow(tmp_path / "floorscan")
    out, n = [], 0
    with gzip.open(SHARED_DATA / "radish" / "orebro-corrected.log.gz", "rt") as f:
        for line in f:
            tok = line.split()
            if tok and tok[0] == "FLASER":
                tok[-3] = tok[-1] = "-0.45" if n == 0 else f"4294967295.{n:03d}"
                n += 1
                line = " ".join(tok) + "\n"
            out.append(line)
    (tmp_path / "junk.log").write_text("".join(out))
    res = snakemake(wd, "--config", f"path={tmp_path / 'junk.log'}")
    assert res.returncode == 0, res.stderr[-3000:]
    assert (wd / "results" / "junk" / "floorplan.svg").is_file()
    verdict = json.loads(read_metadata(wd / "results" / "junk" / "registration.parquet")["verdict"])
    assert verdict["line"].startswith("WARNING")
    assert f"stamps made up: {n} of {n} laser stamps out of range (negative or past the 32-bit wrap)" in verdict["line"]
    assert n == 237 and "stamps made up" in res.stdout

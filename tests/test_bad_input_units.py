"""Units (issue 45, item 4): ranges in millimetres or centimetres and headings in degrees
are refused at ingest naming the file and the field (:mod:`floorscan.ingest.units`).

Before, registration failed with advice about fitness thresholds (ranges in
millimetres, a CARMEN theta in degrees, a PCD yaw in degrees), a CARMEN log in
millimetres lost every reading to its no-return limit, and a PCD folder in millimetres
ended in a ``MemoryError`` in ``map_walls`` (its backstop: tests/test_bad_input_rasters.py).
The recordings are the bad-input corpus's
(``benchmarks/bench_bad_input.py``); the shared recordings must pass the checks
(``../shared/data``, skipped without it).
"""

import math

import numpy as np
import pytest

from conftest import SHARED_DATA, needs_shared
from benchmarks.bench_bad_input import cases, run_corpus
from floorscan.core.io import InputError
from floorscan.ingest import units
from floorscan.ingest.recording import Recording, Scan
from floorscan.ingest.writer import write_recording


def _outcome(tmp_path, name):
    (o,) = run_corpus(tmp_path, [next(c for c in cases() if c.name == name)], echo=None)
    assert o.outcome == "clear", o.detail
    assert not list((tmp_path / "out" / name).glob("*.parquet")), "ingest left a table behind"
    return o.detail


@pytest.mark.parametrize("name, start", [
    ("bag_ranges_in_millimetres",
     "ranges_mm.bag /scan: the ranges of the scans on '/scan' look like millimetres (median return 3858.08 m over "
     "30 scans: 3.86 m in millimetres, 38.6 m in centimetres); expected metres"),
    ("bag_ranges_in_centimetres_ros2",
     "ranges_cm_ros2 /scan: the ranges of the scans on '/scan' look like centimetres (median return 385.808 m over "
     "30 scans: 0.386 m in millimetres, 3.86 m in centimetres); expected metres"),
    ("carmen_ranges_in_millimetres",
     "ranges_mm.log: the ranges r1..rn of the FLASER lines look like millimetres (median return 3851.58 m over 30 "
     "scans: 3.85 m in millimetres"),
    ("carmen_ranges_in_centimetres_robotlaser1",
     "ranges_cm.log: the ranges r1..rn of the ROBOTLASER1 lines look like centimetres (median return 385.808 m"),
    ("pcd_folder_in_millimetres",
     "pcd_mm: the points of the .pcd files (their distance from the scan locations of the locations CSV) look like "
     "millimetres (median return 4068.79 m over 40 scans: 4.07 m in millimetres"),
])
def test_ranges_not_in_metres_are_refused_at_ingest_naming_the_field(tmp_path, name, start):
    detail = _outcome(tmp_path, name)
    assert detail.startswith("ingest failed: "), detail
    assert start in detail, detail
    assert f"no LIDAR's median return over a recording is beyond {units.MAX_MEDIAN_RANGE_M:g} m" in detail


@pytest.mark.parametrize("name, start", [
    ("carmen_theta_in_degrees",
     "theta_deg.log: the laser heading (theta of the FLASER lines) looks like degrees (values up to 28.07, the "
     "first 11.46); expected radians"),
    ("pcd_yaw_in_degrees",
     "pcd_yaw_deg/locations.csv: column 'yaw' looks like degrees (values up to 33.8, the first 11.46); expected "
     "radians"),
])
def test_headings_in_degrees_are_refused_at_ingest_naming_the_field(tmp_path, name, start):
    detail = _outcome(tmp_path, name)
    assert detail.startswith("ingest failed: ") and start in detail, detail


T_10HZ = np.arange(200, dtype=np.int64) * 100_000_000


def test_a_heading_turning_in_degrees_is_told_by_its_steps():
    """The issue's example: a robot turning 100 deg/s, the heading in degrees wrapping at 180."""
    yaw = (np.arange(200) * 10.0 + 180.0) % 360.0 - 180.0 + 0.5
    msg = units.yaw_units_problem(T_10HZ, yaw)
    assert msg.startswith("looks like degrees (values up to 179.5, steps of 10 between poses 0.1 s apart at 199 of "
                          "199 steps, a turn of 25.7 rad/s if radians); expected radians"), msg
    assert msg.endswith("Convert the headings to radians")


def test_a_heading_in_degrees_starting_near_zero_is_told_by_its_wrap():
    """Degrees from 0, turning 5 deg/s (too slow for the turn rate), wrapping at 180 once."""
    t = np.arange(800, dtype=np.int64) * 100_000_000
    yaw = (np.arange(800) * 0.5 + 180.0) % 360.0 - 180.0  # 0 .. 179.5, then -180 ..
    assert units.yaw_units_problem(t[:300], yaw[:300]) is None  # 0 to 149.5 deg at 5 deg/s: can be unwrapped radians
    msg = units.yaw_units_problem(t, yaw)
    assert msg is not None and msg.startswith(
        "looks like degrees (values up to 180, a step of -359.5 between poses 359 and 360, 0.1 s apart); expected radians"
    ), msg


@pytest.mark.parametrize("yaw", [
    0.3 * np.sin(np.arange(200) * 0.05),  # wrapped radians
    np.mod(0.1 * np.arange(200) - 0.4, 2 * math.pi),  # [0, 2 pi) convention: jumps, but within a turn
    0.5 * np.arange(200) * 0.1 + 0.2,  # unwrapped: 0.2 to 10.1 rad by turning at 0.5 rad/s
])
def test_headings_in_radians_pass(yaw):
    assert units.yaw_units_problem(T_10HZ, yaw) is None


def test_a_few_steps_faster_than_a_robot_turns_are_stamps_not_degrees():
    """intel's corrected log: 8 of 909 steps 'turn' 59 rad/s (lines written late, 0.01 s
    apart after sorting); a localizer that relocalises turns its heading at a stroke."""
    yaw = 0.3 * np.sin(np.arange(200) * 0.05)
    t = T_10HZ.copy()
    for k in (20, 60, 100, 140):
        t[k] = t[k - 1] + 10_000_000
        yaw[k] = yaw[k - 1] + 0.5
    assert units.yaw_units_problem(t, yaw) is None
    yaw[::5] += 2.0  # a fifth of the steps: degrees, or a broken heading
    assert "at 79 of 199 steps" in units.yaw_units_problem(t, yaw)


@pytest.mark.parametrize("median, unit", [(51.0, "centimetres"), (999.0, "centimetres"), (1000.0, "millimetres"),
                                          (1800.0, "millimetres")])
def test_the_median_return_names_the_unit(median, unit):
    msg = units.range_units_problem(median, 30)
    assert msg.startswith(f"look like {unit} (median return {median:.6g} m over 30 scans: "), msg
    assert units.range_units_problem(units.MAX_MEDIAN_RANGE_M, 30) is None
    assert units.range_units_problem(math.nan, 0) is None


def test_a_long_recording_in_millimetres_is_refused_without_reading_all_of_it(tmp_path):
    read = []

    def scans():
        for i in range(5000):
            read.append(i)
            ang = np.linspace(-1.5, 1.5, 181)
            yield Scan(i * 100_000_000, "laser", np.c_[3000 * np.cos(ang), 3000 * np.sin(ang), np.zeros(181)]
                       .astype(np.float32), 0, i)

    rec = Recording(scans=scans(), source="long_mm.bag /scan",
                    detected={"format": "rosbag", "scan_topic": "/scan", "pose_kind": "none"})
    with pytest.raises(InputError, match=r"^long_mm.bag /scan: the ranges of the scans on '/scan' look like "
                                         r"millimetres \(median return 3000 m over 200 scans"):
        write_recording(rec, tmp_path / "scans.parquet", tmp_path / "index.parquet", tmp_path / "stream.parquet")
    assert len(read) == units.EARLY_CHECK_SCANS
    assert not list(tmp_path.iterdir())


# --- the shared recordings pass ----------------------------------------------------------


@needs_shared
@pytest.mark.parametrize("log", ["intel", "aces", "freiburg-101", "orebro", "belgioioso", "acapulco"])
def test_the_shared_carmen_logs_are_metres_and_radians(log):
    """Median returns 1.97 (intel) to 7.95 m (acapulco), headings within [-3.25, 3.25]."""
    from floorscan.ingest.carmen import open_carmen

    rec = open_carmen(SHARED_DATA / "radish" / f"{log}-corrected.log.gz", {}, None)
    median = units.MedianReturn()
    for s in rec.scans:
        median.add(s.points)
    assert 1.0 < median.value < 10.0
    yaw = rec.pose_stream["yaw"].to_numpy()
    assert np.abs(yaw).max() < 3.3
    assert units.yaw_units_problem(rec.pose_stream["t_ns"].to_numpy(), yaw) is None


@needs_shared
@pytest.mark.parametrize("rel", ["uob-pioneer/trace0.bag", "uob-pioneer/lgfloor2.bag", "stage-sim/simpath2.bag",
                                 "comprobo-mac/macfirst_floor_take_2"])
def test_the_shared_bags_are_metres(tmp_path, rel):
    """Median returns 1.77 (simpath2) to 2.46 m (mac_ros2): ingest writes them."""
    from floorscan.ingest.readers import open_recording

    path = SHARED_DATA / rel
    rec = open_recording({"name": path.name, "path": str(path)}, {}, max_gap_s=0.5)
    index = write_recording(rec, tmp_path / "scans.parquet", tmp_path / "index.parquet", tmp_path / "stream.parquet")
    assert len(index) > 300

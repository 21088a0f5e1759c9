"""Bad frames in otherwise good recordings (issue 35, items 1 and 4; loss counts of item 3).

Scan geometry is checked at ingest: a LaserScan's angles, ranges count and range limits,
a ROBOTLASER1 line's field of view and resolution. One bad frame (broken geometry, no
valid return, undecodable) is skipped, counted in ``Recording.detected`` and named in a
note; more than half broken, or none usable, is an ``InputError`` naming the file, the
message (topic and index, or line) and the field. Swapped stamps and a robot that never
moves behave the same in a bag as in a CARMEN log.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from conftest import (
    T0_NS,
    _bag_writer,
    _header,
    _quat,
    _scan_message,
    _write_messages,
    flaser_line,
    robotlaser_line,
    scan_ranges,
    write_carmen,
)
from floorscan.core.io import InputError, read_metadata, read_table
from floorscan.ingest.readers import open_recording
from floorscan.ingest.writer import write_recording


def _ingest(ds, out: Path, cfg=None):
    """open_recording + write_recording, as the ingest stage runs them: (recording, index)."""
    out.mkdir(parents=True, exist_ok=True)
    rec = open_recording(ds, cfg or {}, max_gap_s=0.5)
    index = write_recording(rec, out / "scans.parquet", out / "scan_index.parquet", out / "pose_stream.parquet")
    return rec, index


def _fails(ds, out: Path, cfg=None) -> str:
    with pytest.raises(InputError) as info:
        _ingest(ds, out, cfg)
    assert not list(out.glob("*.parquet"))  # nothing left behind
    return str(info.value)


def _bag(path: Path, n=20, change=None, raw=None, stamps=None, cloud=False, ros2=False, moving=True) -> Path:
    """A bag of ``n`` scans on /scan (LaserScan of 181 beams over 180 degrees, range
    0.05-30 m, or a PointCloud2 of the same beams) at 10 Hz, /amcl_pose at 10 Hz and a
    static base_link -> laser mount.

    ``change(i, msg)`` edits scan message ``i`` in place; ``raw(i)`` returns bytes to
    store instead of scan ``i``'s serialization (or None); ``stamps`` the header stamps
    (the bag's own times stay in order); ``moving`` False: the pose never changes.
    """
    ts, T, ser, writer = _bag_writer(path, ros2)
    Vec, Q = T["geometry_msgs/msg/Vector3"], T["geometry_msgs/msg/Quaternion"]
    mount = T["geometry_msgs/msg/TransformStamped"](
        header=_header(ts, T0_NS, "base_link", not ros2), child_frame_id="laser",
        transform=T["geometry_msgs/msg/Transform"](translation=Vec(x=0.1, y=0.0, z=0.0), rotation=Q(0.0, 0.0, 0.0, 1.0)))
    msgs = [(T0_NS - 1, "/tf_static", T["tf2_msgs/msg/TFMessage"](transforms=[mount]))]
    for i in range(n):
        t = T0_NS + int(i * 0.1e9)
        stamp = t if stamps is None else stamps[i]
        msg = _scan_message(ts, stamp, "laser", scan_ranges(i), ros2, cloud)
        if change is not None:
            change(i, msg)
        msgs.append((t, "/scan", msg, raw(i) if raw is not None else None))
        x = 1.0 + (0.05 * i if moving else 0.0)
        pose = T["geometry_msgs/msg/Pose"](position=T["geometry_msgs/msg/Point"](x=x, y=2.0, z=0.0),
                                           orientation=Q(*_quat(0.3)))
        msgs.append((t - 1000, "/amcl_pose", T["geometry_msgs/msg/PoseWithCovarianceStamped"](
            header=_header(ts, t - 1000, "map", not ros2),
            pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=np.zeros(36)))))
    msgs.append((T0_NS + int(n * 0.1e9), "/amcl_pose", dataclasses.replace(msgs[-1][2], header=_header(
        ts, T0_NS + int(n * 0.1e9), "map", not ros2))))
    _write_messages(writer, ts, ser, msgs)
    return path


BAG = {"scan_topic": "/scan", "pose": {"source": "topic", "topic": "/amcl_pose"}}


def _ds(path: Path) -> dict:
    return {"path": str(path), **BAG}


# --- LaserScan geometry -------------------------------------------------------------------


def test_laser_scan_angle_increment_zero_in_every_scan_is_an_error_naming_the_field(tmp_path):
    bag = _bag(tmp_path / "inc0.bag", change=lambda i, m: setattr(m, "angle_increment", 0.0))
    msg = _fails(_ds(bag), tmp_path / "out")
    assert msg.startswith(f"{bag}: '/scan' message 0 (t {T0_NS} ns): LaserScan angle_increment is 0; "
                          "expected a non-zero step with the sign of angle_max - angle_min = 3.14159 rad")
    assert "more than half" in msg and "\n" not in msg


def test_laser_scan_increment_against_the_angles_in_one_scan_is_skipped_and_named(tmp_path):
    def change(i, m):
        if i == 7:
            m.angle_increment = -m.angle_increment

    rec, index = _ingest(_ds(_bag(tmp_path / "neg.bag", change=change)), tmp_path / "out")
    assert len(index) == 19
    assert (rec.detected["n_frames_read"], rec.detected["lost_bad_frames"]) == ("20", "1")
    assert "lost_no_points" not in rec.detected and rec.detected["skipped_frames"] == "7"
    note = [n for n in rec.notes if "lost_bad_frames" in n]
    assert len(note) == 1 and "skipped 1 of 20 scans on '/scan'" in note[0]
    assert f"'/scan' message 7 (t {T0_NS + 700_000_000} ns): LaserScan angle_increment is -0.0174533" in note[0]
    # the scan before and after it are there, at their stamps
    assert T0_NS + 700_000_000 not in index["t_ns"].tolist() and T0_NS + 800_000_000 in index["t_ns"].tolist()


def test_laser_scan_with_twice_the_ranges_of_its_angles_is_an_error(tmp_path):
    """The issue's silent case: 362 ranges for 181 angles wrapped round the full circle."""
    bag = _bag(tmp_path / "twice.bag", change=lambda i, m: setattr(m, "ranges", np.r_[m.ranges, m.ranges]))
    msg = _fails(_ds(bag), tmp_path / "out")
    assert f"{bag}: '/scan' message 0 (t {T0_NS} ns): LaserScan ranges has 362 values; expected " in msg
    assert "(angle_max - angle_min) / angle_increment + 1 = 3.14159 / 0.0174533 + 1 = 181, within one" in msg


def test_laser_scan_one_range_more_than_the_angles_is_read(tmp_path):
    """Drivers differ by one beam on whether angle_max is included: within one is fine."""
    rec, index = _ingest(_ds(_bag(tmp_path / "plus1.bag", change=lambda i, m: setattr(
        m, "ranges", np.r_[m.ranges, np.float32(2.0)]))), tmp_path / "out")
    assert len(index) == 20 and "lost_bad_frames" not in rec.detected


def test_laser_scan_angles_in_degrees_are_refused(tmp_path):
    def change(i, m):
        m.angle_min, m.angle_max, m.angle_increment = -90.0, 90.0, 1.0

    bag = _bag(tmp_path / "deg.bag", change=change)
    msg = _fails(_ds(bag), tmp_path / "out")
    assert f"{bag}: '/scan' message 0 (t {T0_NS} ns): LaserScan angle_max - angle_min = 90 - -90 is 180; " in msg
    assert "expected at most 2 pi = 6.2832 rad (angles in degrees? 180 degrees would be 3.1416 rad)" in msg


def test_laser_scan_range_min_not_below_range_max_in_three_scans_is_skipped(tmp_path):
    def change(i, m):
        if i in (0, 5, 6):
            m.range_min, m.range_max = 30.0, 0.05

    rec, index = _ingest(_ds(_bag(tmp_path / "rng.bag", change=change)), tmp_path / "out")
    assert len(index) == 17 and rec.detected["lost_bad_frames"] == "3" and rec.detected["skipped_frames"] == "0,5-6"
    assert any("message 0 (t " in n and "LaserScan range_min is 30 m, range_max 0.05 m; expected range_min < range_max"
               in n for n in rec.notes)


def test_eleven_broken_scans_of_twenty_are_an_error_naming_the_first(tmp_path):
    def change(i, m):
        if i >= 9:
            m.angle_increment = 0.0

    bag = _bag(tmp_path / "most.bag", change=change)
    msg = _fails(_ds(bag), tmp_path / "out")
    assert msg.startswith(f"{bag}: '/scan' message 9 (t {T0_NS + 900_000_000} ns): LaserScan angle_increment is 0")
    assert "At least 11 of the 20 scans on '/scan' have broken geometry or cannot be decoded, more than half" in msg


def test_ten_broken_scans_of_twenty_are_skipped(tmp_path):
    def change(i, m):
        if i >= 10:
            m.angle_increment = 0.0

    rec, index = _ingest(_ds(_bag(tmp_path / "half.bag", change=change)), tmp_path / "out")
    assert len(index) == 10 and rec.detected["lost_bad_frames"] == "10"


# --- no valid return ------------------------------------------------------------------------


def test_one_laser_scan_without_a_valid_return_is_skipped_and_counted_in_the_index_metadata(tmp_path):
    def change(i, m):
        if i == 4:
            m.ranges = np.full(181, np.nan, np.float32)

    out = tmp_path / "out"
    rec, index = _ingest(_ds(_bag(tmp_path / "nan.bag", change=change)), out)
    assert len(index) == 19 and (index["n_points"] > 0).all()
    meta = read_metadata(out / "scan_index.parquet")
    assert (meta["n_frames_read"], meta["lost_no_points"], meta["skipped_frames"]) == ("20", "1", "4")
    assert "lost_bad_frames" not in meta
    assert any("no valid return (lost_no_points)" in n and "message 4" in n and "of its 181 ranges, 181 NaN" in n
               for n in rec.notes)
    # the poses of the other scans are unchanged
    assert len(read_table(out / "pose_stream.parquet")) == 21


def test_every_laser_scan_without_a_valid_return_is_an_error_that_says_why(tmp_path):
    bag = _bag(tmp_path / "far.bag", change=lambda i, m: setattr(m, "ranges", np.full(181, 30.0, np.float32)))
    msg = _fails(_ds(bag), tmp_path / "out")
    assert msg.startswith(f"{bag}: '/scan' message 0 (t {T0_NS} ns): LaserScan has no valid return: of its 181 "
                          "ranges, 181 at or beyond range_max 30 m are invalid")
    assert f"All 20 scans on '/scan' of {bag} have no valid return: the recording has no usable data" in msg


def test_one_all_nan_pointcloud2_frame_is_skipped_ros2(tmp_path):
    """It aborted the whole ingest before (issue 35)."""
    def change(i, m):
        if i == 12:
            m.data = np.frombuffer(np.full(3 * m.width, np.nan, "<f4").tobytes(), np.uint8)

    rec, index = _ingest(_ds(_bag(tmp_path / "cloud", change=change, cloud=True, ros2=True)), tmp_path / "out")
    assert len(index) == 19 and rec.detected["lost_no_points"] == "1" and "lost_bad_frames" not in rec.detected
    assert any("'/scan' message 12" in n and "PointCloud2 has no finite point (181 points)" in n for n in rec.notes)


# --- undecodable frames ---------------------------------------------------------------------


def test_one_undecodable_scan_message_is_skipped_and_named(tmp_path):
    rec, index = _ingest(_ds(_bag(tmp_path / "garbled.bag", raw=lambda i: b"\x01\x02\x03" if i == 3 else None)),
                         tmp_path / "out")
    assert len(index) == 19 and rec.detected["lost_bad_frames"] == "1" and rec.detected["skipped_frames"] == "3"
    note = next(n for n in rec.notes if "lost_bad_frames" in n)
    assert f"'/scan' message 3 (t {T0_NS + 300_000_000} ns): LaserScan cannot be decoded" in note


# --- stamps and stationary recordings, bag and CARMEN alike ----------------------------------


def test_two_swapped_scan_stamps_are_sorted_in_a_bag_as_in_a_carmen_log(tmp_path):
    stamps = [T0_NS + int(i * 0.1e9) for i in range(20)]
    stamps[5], stamps[6] = stamps[6], stamps[5]
    rec, index = _ingest(_ds(_bag(tmp_path / "swap.bag", stamps=stamps)), tmp_path / "bag")
    assert index["t_ns"].tolist() == sorted(stamps)
    assert any("1 scans on '/scan' stamped earlier than the message before them (messages [6])" in n for n in rec.notes)
    scans = read_table(tmp_path / "bag" / "scans.parquet")
    # scan 5 (t 0.5 s) holds message 6's points: scan_ranges(6), 0.01 m farther than message 5's
    r5 = np.hypot(scans[scans.scan_id == 5].x, scans[scans.scan_id == 5].y).min()
    r6 = np.hypot(scans[scans.scan_id == 6].x, scans[scans.scan_id == 6].y).min()
    assert r5 == pytest.approx(r6 + 0.01, abs=1e-5)
    # the same swap in a CARMEN log: sorted too
    t = [10.0 + 0.1 * i for i in range(20)]
    t[5], t[6] = t[6], t[5]
    log = write_carmen(tmp_path / "swap.log", [flaser_line(np.linspace(1, 3, 180), (0.1 * i, 0, 0), f"{s:.1f}")
                                               for i, s in enumerate(t)])
    rec2, index2 = _ingest({"path": str(log)}, tmp_path / "carmen")
    assert np.all(np.diff(index2["t_ns"].to_numpy()) > 0) and len(index2) == len(index) == 20
    assert any("1 laser lines earlier than the line before them" in n for n in rec2.notes)


def test_scan_stamps_out_of_order_too_often_are_an_error(tmp_path):
    stamps = [T0_NS + int(i * 0.1e9) for i in range(20)]
    for i in (2, 6, 10, 14):  # four swapped pairs: 4 of 20 messages step back, more than 10 %
        stamps[i], stamps[i + 1] = stamps[i + 1], stamps[i]
    bag = _bag(tmp_path / "scrambled.bag", stamps=stamps)
    msg = _fails(_ds(bag), tmp_path / "out")
    assert msg == (f"{bag}: header stamps on '/scan' are not sorted: 4 of 20 messages are stamped earlier than the "
                   "message before them (the first: message 3), more than 10 %; expected increasing stamps")


def test_a_robot_that_never_moves_runs_in_a_bag_as_in_a_carmen_log(tmp_path):
    rec, index = _ingest(_ds(_bag(tmp_path / "still.bag", moving=False)), tmp_path / "bag")
    stream = read_table(tmp_path / "bag" / "pose_stream.parquet")
    assert len(index) == 20 and np.ptp(stream["x"]) == 0.0 and stream["x"].iloc[0] == pytest.approx(1.0 + 0.1 * math.cos(0.3))
    log = write_carmen(tmp_path / "still.log", [flaser_line(np.linspace(1, 3, 180), (1.0, 2.0, 0.3), 10.0 + 0.1 * i)
                                                for i in range(20)])
    rec2, index2 = _ingest({"path": str(log)}, tmp_path / "carmen")
    assert len(index2) == 20 and np.ptp(read_table(tmp_path / "carmen" / "pose_stream.parquet")["x"]) == 0.0


# --- CARMEN ----------------------------------------------------------------------------------


def _robotlaser_log(path, n=10, bad=None):
    lines = []
    for i in range(n):
        kw = bad(i) if bad else {}
        lines.append(robotlaser_line(np.linspace(1.0, 3.0, 181), (0.1 * i, 0.0, 0.0), 10.0 + 0.1 * i, **(kw or {})))
    return write_carmen(path, lines)


def test_robotlaser1_resolution_zero_on_every_line_is_an_error_naming_line_and_field(tmp_path):
    log = _robotlaser_log(tmp_path / "res0.log", bad=lambda i: {"res": 0.0})
    msg = _fails({"path": str(log)}, tmp_path / "out")
    assert msg.startswith(f"{log}:1: ROBOTLASER1 line field 5 (angular_resolution) is 0; expected the non-zero angle "
                          "between beams, radians")
    assert "At least 10 of the 10 laser lines have broken geometry" in msg


def test_robotlaser1_fov_against_its_beams_on_one_line_is_skipped_and_its_pose_kept(tmp_path):
    log = _robotlaser_log(tmp_path / "fov.log", bad=lambda i: {"fov": 2 * math.pi, "res": math.pi / 180} if i == 2 else None)
    rec, index = _ingest({"path": str(log)}, tmp_path / "out")
    assert len(index) == 9 and rec.detected["lost_bad_frames"] == "1" and rec.detected["n_frames_read"] == "10"
    assert any(f"{log}:3: ROBOTLASER1 line field 4 (fov) is 6.28319 rad, but n x angular_resolution = 181 x "
               "0.0174533 = 3.15905 rad; expected them within one beam" in n for n in rec.notes)
    assert len(read_table(tmp_path / "out" / "pose_stream.parquet")) == 10


def test_robotlaser1_fov_of_n_or_n_minus_1_steps_is_read(tmp_path):
    log = _robotlaser_log(tmp_path / "ok.log", bad=lambda i: {"res": math.pi / 181} if i % 2 else None)
    rec, index = _ingest({"path": str(log)}, tmp_path / "out")
    assert len(index) == 10 and "lost_bad_frames" not in rec.detected


def test_carmen_lines_of_an_unknown_type_are_counted_and_named(tmp_path):
    good = [flaser_line(np.linspace(1, 3, 180), (0.1 * i, 0, 0), 10.0 + 0.1 * i) for i in range(6)]
    lines = ["PARAM robot_front_laser_max 81.9 nohost 0", good[0], "FLASR 180 " + " ".join(["1.0"] * 180), good[1],
             "ODOM 0 0 0 0 0 0 10.1 host 10.1", "NEFF 12.5 10.1 host 10.1", good[2], "XYZZY 1 2 3", *good[3:]]
    log = write_carmen(tmp_path / "unknown.log", lines)
    rec, index = _ingest({"path": str(log)}, tmp_path / "out")
    assert len(index) == 6 and rec.detected["lost_unknown_lines"] == "2"
    meta = read_metadata(tmp_path / "out" / "scan_index.parquet")
    assert meta["lost_unknown_lines"] == "2" and meta["n_frames_read"] == "6"
    assert any("2 lines of a message type CARMEN does not define were not read (lost_unknown_lines; line 3 'FLASR', "
               "line 8 'XYZZY')" in n for n in rec.notes)


def test_carmen_line_without_a_valid_return_is_skipped(tmp_path):
    lines = [flaser_line(np.linspace(1, 3, 180) if i != 4 else np.full(180, np.nan), (0.1 * i, 0, 0), 10.0 + 0.1 * i)
             for i in range(10)]
    rec, index = _ingest({"path": str(write_carmen(tmp_path / "nan.log", lines))}, tmp_path / "out")
    assert len(index) == 9 and rec.detected["lost_no_points"] == "1" and rec.detected["skipped_frames"] == "4"
    assert any(":5: FLASER line has no valid return: of its 180 ranges, 180 NaN are invalid" in n for n in rec.notes)


# --- PCD folders -------------------------------------------------------------------------------


def _pcd_folder(folder: Path, n=6, listed=None, nan_at=()) -> Path:
    folder.mkdir()
    rows = ["file,t_ns,x,y,z,yaw"]
    for i in range(n):
        pts = np.c_[np.linspace(1, 3, 50) + i, np.linspace(-1, 1, 50), np.zeros(50)]
        if i in nan_at:
            pts[:] = np.nan
        body = "\n".join(" ".join(f"{v:.4f}" for v in p) for p in pts)
        (folder / f"s{i:02d}.pcd").write_text(
            f"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 50\nHEIGHT 1\nPOINTS 50\n"
            f"DATA ascii\n{body}\n")
        if listed is None or i in listed:
            rows.append(f"s{i:02d}.pcd,{1000 + 100 * i},{float(i)},0,0,0")
    (folder / "locations.csv").write_text("\n".join(rows) + "\n")
    return folder


def test_pcd_files_not_in_the_locations_csv_are_counted_and_named(tmp_path):
    folder = _pcd_folder(tmp_path / "pcd", n=8, listed=(0, 1, 2, 4, 6))
    rec, index = _ingest({"path": str(folder), "format": "pcd"}, tmp_path / "out")
    assert len(index) == 5 and rec.detected["lost_unlisted_files"] == "3" and rec.detected["n_frames_read"] == "5"
    assert any("3 .pcd files are not listed in locations.csv and were not read (lost_unlisted_files; s03.pcd, "
               "s05.pcd, s07.pcd)" in n for n in rec.notes)
    assert read_metadata(tmp_path / "out" / "scan_index.parquet")["lost_unlisted_files"] == "3"


def test_pcd_file_without_a_finite_point_is_skipped(tmp_path):
    folder = _pcd_folder(tmp_path / "pcd", n=6, nan_at=(2,))
    rec, index = _ingest({"path": str(folder), "format": "pcd"}, tmp_path / "out")
    assert len(index) == 5 and rec.detected["lost_no_points"] == "1" and "lost_unlisted_files" not in rec.detected
    assert any("s02.pcd (locations.csv row 3): no valid point: of its 50 points, 50 are not finite" in n
               for n in rec.notes)


def test_pcd_folder_of_only_nan_files_is_an_error(tmp_path):
    folder = _pcd_folder(tmp_path / "pcd", n=3, nan_at=(0, 1, 2))
    msg = _fails({"path": str(folder), "format": "pcd"}, tmp_path / "out")
    assert msg.startswith(f"{folder / 's00.pcd'} (locations.csv row 1): no valid point")
    assert f"All 3 listed PCD files of {folder} have no valid return" in msg


def test_a_good_recording_reports_its_frames_and_no_losses(tmp_path):
    rec, index = _ingest(_ds(_bag(tmp_path / "good.bag")), tmp_path / "out")
    meta = read_metadata(tmp_path / "out" / "scan_index.parquet")
    assert len(index) == 20 and meta["n_frames_read"] == "20"
    assert not [k for k in meta if k.startswith("lost_") or k == "skipped_frames"]

"""The reduced recording after ingest skipped bad frames or sorted stamps (issue 35).

Ingest skips a bad scan frame (no valid return, broken geometry, undecodable) and sorts
scan stamps a little out of order, so ``scan_id`` is no longer the frame's ordinal in
the recording. The scan index's ``source_ordinal`` says which frame each scan is; the
select stage's writer cuts the recording by it. Each case: ingest, select scans on
both sides of the skipped (or swapped) frame, write the reduced recording, read it
back: it holds exactly the selected scans, stamped as the index says.
"""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import numpy as np
import pytest

from conftest import T0_NS, flaser_line, robotlaser_line, write_carmen
from floorscan.core.io import SCAN_INDEX, InputError, read_metadata, read_table, write_table
from floorscan.ingest.readers import open_recording
from floorscan.ingest.reduced import read_detection, write_reduced_recording
from test_bad_input_frames import _bag, _ds, _ingest


def _reduce(src: Path, out_dir: Path, ids, ds: dict | None = None, name: str = "reduced"):
    """Ingest ``src`` (dataset ``ds``), reduce it to ``ids`` from the scan index as the
    workflow does: (scan index, detection, output path, writer's info)."""
    rec, index = _ingest(ds or {"path": str(src)}, out_dir / "ingest")
    det = read_detection(out_dir / "ingest" / "scan_index.parquet")
    out = out_dir / name
    info = write_reduced_recording(src, det["format"], ids, out, det)
    return index, det, out, info


def _scan_messages(path: Path) -> list[tuple[int, bytes, int]]:
    """(log time, raw bytes, header stamp ns or None: undecodable) of each /scan message, in reading order."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    out = []
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as r:
        conns = [c for c in r.connections if c.topic == "/scan"]
        for c, t, raw in r.messages(connections=conns):
            try:
                s = r.deserialize(raw, c.msgtype).header.stamp
            except Exception:  # the test's undecodable message
                out.append((t, bytes(raw), None))
                continue
            out.append((t, bytes(raw), s.sec * 1_000_000_000 + s.nanosec))
    return out


def _same_points(out_dir: Path, again, ids) -> None:
    """Scans ``again`` (re-ingested) hold the points of the selected scans ``ids``."""
    scans = read_table(out_dir / "ingest" / "scans.parquet")
    for s, i in zip(again, ids):
        mine = scans[scans.scan_id == i][["x", "y", "z"]].to_numpy(np.float32)
        np.testing.assert_array_equal(s.points, mine)


def _text(path: Path) -> str:
    """A CARMEN log's text, gzip or not."""
    data = path.read_bytes()
    return (gzip.decompress(data) if data[:2] == b"\x1f\x8b" else data).decode()


def _drop_ordinals(index_path: Path) -> None:
    """Rewrite a scan index as one written before ``source_ordinal`` existed (its metadata kept)."""
    meta = read_metadata(index_path)
    index = read_table(index_path).drop(columns="source_ordinal")
    write_table(index, index_path, schema=SCAN_INDEX, metadata=meta)


# --- bags ---------------------------------------------------------------------------------


def _nan_laser_scan(i, m):
    if i == 4:
        m.ranges = np.full(181, np.nan, np.float32)


def _nan_cloud(i, m):
    if i == 4:
        m.data = np.frombuffer(np.full(3 * m.width, np.nan, "<f4").tobytes(), np.uint8)


def _range_min_above_max(i, m):
    if i == 4:
        m.range_min, m.range_max = 30.0, 0.05


@pytest.mark.parametrize(
    "kind", ["no_valid_return_ros1", "all_nan_cloud_ros2", "broken_geometry_ros1", "undecodable_ros1"]
)
def test_reduced_bag_after_a_skipped_scan_holds_the_selected_scans(kind, tmp_path):
    ros2 = kind.endswith("ros2")
    src = tmp_path / ("in" if ros2 else "in.bag")
    if kind == "no_valid_return_ros1":
        _bag(src, change=_nan_laser_scan)
    elif kind == "all_nan_cloud_ros2":
        _bag(src, change=_nan_cloud, cloud=True, ros2=True)
    elif kind == "broken_geometry_ros1":
        _bag(src, change=_range_min_above_max)
    else:
        _bag(src, raw=lambda i: b"\x01\x02\x03" if i == 4 else None)
    ids = [2, 4, 10, 18]  # scan 4 is message 5: the one after the skipped message 4
    index, det, out, info = _reduce(src, tmp_path, ids, _ds(src), "reduced" if ros2 else "reduced.bag")
    assert len(index) == 19 and det["skipped_frames"] == "4" and det["n_frames_read"] == "20"
    assert det["source_ordinal"].tolist() == [0, 1, 2, 3, *range(5, 20)]
    assert info["scan_messages_out"] == 4 and info["topics"]["/scan"] == 4
    got = _scan_messages(out)
    t_ns = index["t_ns"].to_numpy()
    assert [s for _, _, s in got] == t_ns[ids].tolist() == [T0_NS + k * 100_000_000 for k in (2, 5, 11, 19)]
    source = _scan_messages(src)
    assert [m[:2] for m in got] == [source[k][:2] for k in (2, 5, 11, 19)]  # the input's bytes
    again = list(open_recording({**_ds(src), "path": str(out)}, {}, 0.5).scans)
    assert [s.t_ns for s in again] == t_ns[ids].tolist()
    _same_points(tmp_path, again, ids)


def test_reduced_bag_with_a_scan_selected_past_the_index_is_refused(tmp_path):
    src = _bag(tmp_path / "in.bag", change=_nan_laser_scan)
    _ingest(_ds(src), tmp_path / "ingest")
    det = read_detection(tmp_path / "ingest" / "scan_index.parquet")
    with pytest.raises(InputError, match=r"in.bag: selected scan_id 19 is not in the recording's scan index \(0..18\)"):
        write_reduced_recording(src, "rosbag", [3, 19], tmp_path / "r.bag", det)
    # the bag lost a message since ingest: 19 messages, ingest read 20 (19 scans, 1 skipped)
    short = _bag(tmp_path / "short.bag", n=19)
    with pytest.raises(InputError, match=r"short.bag: holds 19 messages on /scan, ingest read 20 \(the scan index's "
                                         r"19 scans and 1 skipped\); .* rerun ingest"):
        write_reduced_recording(short, "rosbag", [3], tmp_path / "r.bag", det)
    assert not (tmp_path / "r.bag").exists()


def test_reduced_bag_with_two_swapped_stamps_holds_the_selected_scans(tmp_path):
    """Messages 5 and 6 carry each other's stamps: ingest sorts them, so scan 5 is message 6."""
    stamps = [T0_NS + i * 100_000_000 for i in range(20)]
    stamps[5], stamps[6] = stamps[6], stamps[5]
    src = _bag(tmp_path / "swap.bag", stamps=stamps)
    ids = [1, 5, 9, 17]
    index, det, out, info = _reduce(src, tmp_path, ids, _ds(src), "reduced.bag")
    assert "skipped_frames" not in det and det["source_ordinal"][[4, 5, 6, 7]].tolist() == [4, 6, 5, 7]
    t_ns = index["t_ns"].to_numpy()
    got = _scan_messages(out)
    assert [s for _, _, s in got] == t_ns[ids].tolist() == [T0_NS + k * 100_000_000 for k in (1, 5, 9, 17)]
    source = _scan_messages(src)
    assert [m[:2] for m in got] == [source[k][:2] for k in (1, 6, 9, 17)]  # scan 5 is message 6
    again = list(open_recording({"path": str(out), "scan_topic": "/scan"}, {}, 0.5).scans)
    assert [s.t_ns for s in again] == t_ns[ids].tolist()
    _same_points(tmp_path, again, ids)
    # both swapped scans: the reduced bag keeps the messages in the input's order
    out2 = tmp_path / "both.bag"
    write_reduced_recording(src, "rosbag", [5, 6], out2, det)
    assert [s for _, _, s in _scan_messages(out2)] == [stamps[5], stamps[6]]
    assert sorted(s for _, _, s in _scan_messages(out2)) == t_ns[[5, 6]].tolist()


def test_reduced_bag_from_an_index_without_source_ordinal_falls_back_to_skipped_frames(tmp_path):
    src = _bag(tmp_path / "in.bag", change=_nan_laser_scan)
    ids = [2, 4, 10, 18]
    index, det, out, _ = _reduce(src, tmp_path, ids, _ds(src), "new.bag")
    _drop_ordinals(tmp_path / "ingest" / "scan_index.parquet")
    old = read_detection(tmp_path / "ingest" / "scan_index.parquet")
    assert "source_ordinal" not in old and old["skipped_frames"] == "4"
    write_reduced_recording(src, "rosbag", ids, tmp_path / "old.bag", old)
    assert [m[2] for m in _scan_messages(tmp_path / "old.bag")] == index["t_ns"].to_numpy()[ids].tolist()
    assert _scan_messages(tmp_path / "old.bag") == _scan_messages(out)
    # sorted stamps cannot be re-derived from skipped_frames: the stamp check says so
    stamps = [T0_NS + i * 100_000_000 for i in range(20)]
    stamps[5], stamps[6] = stamps[6], stamps[5]
    swap = _bag(tmp_path / "swap.bag", stamps=stamps)
    _ingest(_ds(swap), tmp_path / "swap")
    _drop_ordinals(tmp_path / "swap" / "scan_index.parquet")
    with pytest.raises(InputError, match=r"swap.bag: scan 5 is stamped 1700000000600000000 ns, the scan index says "
                                         r"1700000000500000000 ns .* rerun ingest"):
        write_reduced_recording(swap, "rosbag", [5], tmp_path / "s.bag",
                                read_detection(tmp_path / "swap" / "scan_index.parquet"))


# --- CARMEN -------------------------------------------------------------------------------


def _carmen_lines(bad_line: int, kind: str) -> list[str]:
    """Ten laser lines at 10 Hz from 10.0 s, the 8th and 9th swapped, an ODOM line after
    each; laser line ``bad_line`` (0-based) broken: ROBOTLASER1 with a field of view of
    a full turn for 181 beams of one degree, or FLASER without a valid return."""
    stamps = [10.0 + 0.1 * i for i in range(10)]
    stamps[7], stamps[8] = stamps[8], stamps[7]
    lines = ["PARAM robot_front_laser_max 30.0 nohost 0"]
    for i, t in enumerate(stamps):
        ranges = np.linspace(1.0, 3.0, 181) + 0.01 * i
        if kind == "ROBOTLASER1":
            geometry = {"fov": 2 * math.pi, "res": math.pi / 180} if i == bad_line else {}
            lines.append(robotlaser_line(ranges, (0.1 * i, 0.0, 0.0), f"{t:.1f}", **geometry))
        else:
            r = np.full(180, np.nan) if i == bad_line else ranges[:180]
            lines.append(flaser_line(r, (0.1 * i, 0, 0), f"{t:.1f}"))
        lines.append(f"ODOM {0.1 * i:.1f} 0 0 0 0 0 {t + 0.01:.2f} host {t + 0.01:.2f}")
    return lines


@pytest.mark.parametrize("kind", ["ROBOTLASER1", "FLASER"])
@pytest.mark.parametrize("name", ["skip.log", "skip.log.gz"])
def test_reduced_carmen_log_after_a_skipped_line_holds_the_selected_scans(kind, name, tmp_path):
    src = write_carmen(tmp_path / name, _carmen_lines(3, kind))
    ids = [1, 3, 6, 7, 8]  # scan 3 is laser line 4; scans 6 and 7 are lines 8 and 7 (swapped stamps)
    index, det, out, info = _reduce(src, tmp_path, ids, None, "out_" + name)
    assert len(index) == 9 and det["skipped_frames"] == "3" and det["n_frames_read"] == "10"
    assert det["source_ordinal"].tolist() == [0, 1, 2, 4, 5, 6, 8, 7, 9]
    assert info["scan_messages_out"] == 5 and info["topics"][kind] == 5
    t_ns = index["t_ns"].to_numpy()
    laser = [ln for ln in _text(out).splitlines() if ln.startswith(kind)]
    assert sorted(round(float(ln.split()[-3]) * 1e9) for ln in laser) == t_ns[ids].tolist()
    assert [round(float(ln.split()[-3]) * 10) for ln in laser] == [101, 104, 108, 107, 109]  # in file order
    src_laser = [ln for ln in _text(src).splitlines() if ln.startswith(kind)]
    assert laser == [src_laser[k] for k in (1, 4, 7, 8, 9)]  # the input's lines, as they were
    cfg = {"carmen_max_range_m": float(read_metadata(tmp_path / "ingest" / "scan_index.parquet")["max_range_m"])}
    again = list(open_recording({"path": str(out)}, cfg, 0.5).scans)
    assert [s.t_ns for s in again] == t_ns[ids].tolist()
    _same_points(tmp_path, again, ids)
    # an index written before source_ordinal existed: the same log from skipped_frames
    _drop_ordinals(tmp_path / "ingest" / "scan_index.parquet")
    old = read_detection(tmp_path / "ingest" / "scan_index.parquet")
    assert "source_ordinal" not in old
    write_reduced_recording(src, "carmen", ids, tmp_path / ("old_" + name), old)
    assert (tmp_path / ("old_" + name)).read_bytes() == out.read_bytes()


# --- PCD ----------------------------------------------------------------------------------


def _pcd_folder(folder: Path, n: int = 6, empty: int = 2) -> Path:
    """``n`` ascii PCD scans listed in locations.csv; scan ``empty`` holds no point (POINTS 0)."""
    folder.mkdir()
    rows = ["file,t_ns,x,y,z,yaw"]
    for i in range(n):
        pts = np.zeros((0, 3)) if i == empty else np.c_[np.linspace(1, 3, 20) + i, np.linspace(-1, 1, 20), np.zeros(20)]
        body = "".join(" ".join(f"{v:.4f}" for v in p) + "\n" for p in pts)
        (folder / f"s{i:02d}.pcd").write_text(
            f"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {len(pts)}\nHEIGHT 1\n"
            f"POINTS {len(pts)}\nDATA ascii\n{body}")
        rows.append(f"s{i:02d}.pcd,{1000 + 100 * i},{float(i)},0,0,0")
    (folder / "locations.csv").write_text("\n".join(rows) + "\n")
    return folder


def test_reduced_pcd_folder_after_an_empty_file_holds_the_selected_scans(tmp_path):
    src = _pcd_folder(tmp_path / "pcd")
    ids = [1, 2, 4]  # scan 2 is s03.pcd, after the empty s02.pcd
    index, det, out, info = _reduce(src, tmp_path, ids, {"path": str(src), "format": "pcd"})
    assert len(index) == 5 and det["skipped_frames"] == "2" and det["source_ordinal"].tolist() == [0, 1, 3, 4, 5]
    assert sorted(p.name for p in out.iterdir()) == ["locations.csv", "s01.pcd", "s03.pcd", "s05.pcd"]
    assert (out / "locations.csv").read_text() == (
        "file,t_ns,x,y,z,yaw\ns01.pcd,1100,1.0,0,0,0\ns03.pcd,1300,3.0,0,0,0\ns05.pcd,1500,5.0,0,0,0\n"
    )
    assert info["scan_messages_out"] == 3
    again = list(open_recording({"path": str(out), "format": "pcd"}, {}, 0.5).scans)
    assert [s.t_ns for s in again] == index["t_ns"].to_numpy()[ids].tolist() == [1100, 1300, 1500]
    _same_points(tmp_path, again, ids)
    _drop_ordinals(tmp_path / "ingest" / "scan_index.parquet")
    old = read_detection(tmp_path / "ingest" / "scan_index.parquet")
    write_reduced_recording(src, "pcd", ids, tmp_path / "old", old)
    assert (tmp_path / "old" / "locations.csv").read_text() == (out / "locations.csv").read_text()


def test_reduced_carmen_gzip_with_trailing_garbage_is_read_as_ingest_reads_it(tmp_path):
    """Ingest reads a gzip log with trailing garbage (with a warning, as ``gzip -d``);
    the reduced recording reads it the same way (before: "cannot read the log,
    truncated or corrupt (Not a gzipped file)")."""
    lines = [flaser_line(np.linspace(1.0, 3.0, 180), (0.1 * i, 0.0, 0.0), f"{10.0 + 0.1 * i:.1f}") for i in range(10)]
    src = write_carmen(tmp_path / "lab.log.gz", lines)
    src.write_bytes(src.read_bytes() + b"\x00\x00junk appended by a copy tool\n")
    index, det, out, info = _reduce(src, tmp_path, np.array([1, 4, 7]))
    assert len(index) == 10 and info["scan_messages_out"] == 3
    assert gzip.decompress(out.read_bytes()).decode().splitlines() == [lines[1], lines[4], lines[7]]


def test_reduced_carmen_with_a_byte_order_mark_keeps_the_first_scan(tmp_path):
    """A log that starts with a UTF-8 byte-order mark: ingest drops the mark and reads
    its first laser line; the reduced recording counts that line too (before: one laser
    line fewer than ingest, and the reduction stopped on the count)."""
    lines = [flaser_line(np.linspace(1.0, 3.0, 180), (0.1 * i, 0.0, 0.0), f"{10.0 + 0.1 * i:.1f}") for i in range(10)]
    src = tmp_path / "bom.log"
    src.write_bytes(b"\xef\xbb\xbf" + ("\n".join(lines) + "\n").encode())
    index, det, out, info = _reduce(src, tmp_path, np.array([0, 4, 9]))
    assert len(index) == 10 and info["scan_messages_out"] == 3
    assert out.read_bytes().decode("utf-8-sig").splitlines() == [lines[0], lines[4], lines[9]]


# --- the scan index -----------------------------------------------------------------------


def test_scan_index_source_ordinal_is_int64_and_null_when_written_without_it(tmp_path):
    import pyarrow.parquet as pq

    src = _bag(tmp_path / "in.bag", change=_nan_laser_scan)
    _ingest(_ds(src), tmp_path / "ingest")
    path = tmp_path / "ingest" / "scan_index.parquet"
    table = pq.read_table(path)
    assert table.schema.field("source_ordinal").type == "int64" and table.column("source_ordinal").null_count == 0
    _drop_ordinals(path)
    assert pq.read_table(path).column("source_ordinal").null_count == 19
    # only source_ordinal may be absent from a frame written as a scan index
    with pytest.raises(KeyError, match=r"columns \['frame'\] missing"):
        write_table(read_table(path).drop(columns=["frame", "source_ordinal"]), tmp_path / "x.parquet",
                    schema=SCAN_INDEX)

"""The select stage's deliverables (issue 23): recommended k, the scan list, the selected
points, and the reduced recording in each format read back and re-ingested."""

import gzip
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from conftest import SHARED_DATA, T0_NS, flaser_line, needs_shared, scan_ranges, write_carmen
from floorscan.ingest.readers import open_recording
from floorscan.ingest.writer import write_recording
from floorscan.core.io import REGISTERED, InputError, write_table
from floorscan.core.files import staged_path
from floorscan.select.deliverables import recommended_k, scan_list, write_scan_list, write_selected_points
from floorscan.ingest.reduced import read_detection, write_reduced_recording

# --- recommended k --------------------------------------------------------------------

CURVE = [50.0, 80.0, 95.0, 99.0, 100.0]  # cumulative cells of 5 scans


def test_recommended_k_auto_is_the_smallest_k_reaching_the_fraction():
    k, why = recommended_k(CURVE, objective="wall_coverage", unit="cells")
    assert k == 4
    assert why == (
        "k = 4 of 5 kept scans: the smallest k whose wall_coverage reaches 99 % of what all scans cover "
        "(99 of 100 cells)"
    )
    assert recommended_k(CURVE, fraction=0.95)[0] == 3
    assert recommended_k(CURVE, fraction=0.9)[0] == 3
    assert recommended_k(CURVE, fraction=0.5)[0] == 1
    assert recommended_k(CURVE, fraction=1.0)[0] == 5
    # thousands separators and areas
    k, why = recommended_k(np.array([2500.0, 5013.0, 5063.0]), objective="wall_coverage", unit="cells")
    assert (k, why.endswith("(5,013 of 5,063 cells)")) == (2, True)
    k, why = recommended_k([1.25, 2.5, 2.525], fraction=0.98, objective="cluster_hull", unit="m2")
    assert k == 2 and why.endswith("reaches 98 % of what all scans cover (2.50 of 2.52 m2)")


def test_recommended_k_auto_edge_cases():
    # a cumulative sum in floating point: 1.0 of the total is reached at the last scan, not missed
    cov = np.cumsum([0.1] * 10)
    assert recommended_k(cov, fraction=1.0)[0] == 10
    assert recommended_k([10.0, 10.0, 10.0])[0] == 1  # the first scan covers everything
    assert recommended_k([7.0])[0] == 1
    k, why = recommended_k([0.0, 0.0, 0.0], objective="wall_coverage", unit="cells")
    assert k == 1
    assert why == "k = 1 of 3 kept scans: wall_coverage is 0 cells for every k, so the smallest k reaching 99 % of it is 1"


def test_recommended_k_count_and_fraction_rules():
    cov = np.arange(1.0, 11.0) * 10  # 10 scans, 10 cells each
    k, why = recommended_k(cov, 3, objective="wall_coverage", unit="cells")
    assert k == 3
    assert why == (
        "k = 3 of 10 kept scans: 3 asked (its wall_coverage reaches 30 % of what all scans cover, 30 of 100 cells)"
    )
    k, why = recommended_k(cov, 25)
    assert k == 10 and "25 asked, clipped to [1, 10]" in why
    assert recommended_k(cov, 0)[0] == 1
    assert recommended_k(cov, np.int64(4))[0] == 4
    assert recommended_k(cov, 0.3)[0] == 3  # 0.3 * 10 is 3.0000000000000004 in floating point: still 3
    assert recommended_k(cov, 0.25)[0] == 3  # 2.5 rounded up
    assert recommended_k(cov, 0.01)[0] == 1
    k, why = recommended_k(cov, 1.0)
    assert k == 10 and "100 % of the scans, rounded up" in why


@pytest.mark.parametrize(
    "covered, rule, fraction, message",
    [
        ([], "auto", 0.99, r"empty ordering: no scans to recommend"),
        ([1.0, 2.0], "best", 0.99, r"rule 'best': expected 'auto', an int count of scans or a float fraction in \(0, 1\]"),
        ([1.0, 2.0], 1.5, 0.99, r"rule 1.5: expected 'auto', an int .* \(for a count, give an int\)"),
        ([1.0, 2.0], -0.2, 0.99, r"rule -0.2"),
        ([1.0, 2.0], True, 0.99, r"rule True"),
        ([1.0, 2.0], "auto", 0.0, r"fraction 0.0: expected a number in \(0, 1\]"),
        ([1.0, 2.0], "auto", 1.5, r"fraction 1.5"),
        ([1.0, 3.0, 2.0], "auto", 0.99, r"non-decreasing .* rank 3 \(2\) is below rank 2 \(3\)"),
        ([1.0, np.nan], "auto", 0.99, r"1 values are not finite"),
        ([[1.0, 2.0]], "auto", 0.99, r"expected a 1-D array"),
    ],
)
def test_recommended_k_rejects_bad_input(covered, rule, fraction, message):
    with pytest.raises(ValueError, match=message):
        recommended_k(covered, rule, fraction)


# --- scan list --------------------------------------------------------------------------


def _tiny_tables(gain_column="gain_m2"):
    ordering = pd.DataFrame(  # rows out of rank order, ranks 0-based as the select stage writes them
        {"rank": [1, 0, 2], "scan_id": [7, 3, 5], "covered_area_m2": [3.0, 2.0, 3.5], gain_column: [1.0, 2.0, 0.5]}
    )
    t = np.array([1682942400123456789, 1682942400500000000, 1682942401000000999, 1682942401999999999], np.int64)
    scan_index = pd.DataFrame({"scan_id": [3, 5, 7, 9], "t_ns": t})
    registration = pd.DataFrame({
        "scan_id": [3, 5, 7, 9], "kept": [True, True, True, False],
        "x_m": [1.0, 2.5, -0.125, np.nan], "y_m": [2.0, 0.0, 1.0 / 3.0, np.nan],
        "yaw_rad": [0.5, -math.pi, 1e-7, np.nan],
    })
    return ordering, scan_index, registration


def test_scan_list_of_a_tiny_table(tmp_path):
    ordering, scan_index, registration = _tiny_tables()
    df = scan_list(ordering, 2, scan_index, registration)
    assert list(df.columns) == ["rank", "scan_id", "t_ns", "time_iso", "x_m", "y_m", "yaw_rad", "gain"]
    assert df["rank"].tolist() == [1, 2]
    assert df["scan_id"].tolist() == [3, 7]
    assert df["t_ns"].dtype == np.int64
    assert df["t_ns"].tolist() == [1682942400123456789, 1682942401000000999]
    assert df["time_iso"].tolist() == ["2023-05-01T12:00:00.123456Z", "2023-05-01T12:00:01.000000Z"]
    assert df["x_m"].tolist() == [1.0, -0.125]
    assert df["yaw_rad"].tolist() == [0.5, 1e-7]
    assert df["gain"].tolist() == [2.0, 1.0]
    path = tmp_path / "out" / "scans.csv"
    write_scan_list(df, path)
    assert path.read_text() == (
        "rank,scan_id,t_ns,time_iso,x_m,y_m,yaw_rad,gain\n"
        "1,3,1682942400123456789,2023-05-01T12:00:00.123456Z,1.000000,2.000000,0.500000,2.000000\n"
        "2,7,1682942401000000999,2023-05-01T12:00:01.000000Z,-0.125000,0.333333,0.000000,1.000000\n"
    )
    first = path.read_bytes()
    write_scan_list(scan_list(ordering, 2, scan_index, registration), path)
    assert path.read_bytes() == first
    assert [p.name for p in path.parent.iterdir()] == ["scans.csv"]  # no temporary left
    # a coverage ordering's `gain` column
    df = scan_list(_tiny_tables("gain")[0], 3, scan_index, registration)
    assert df["gain"].tolist() == [2.0, 1.0, 0.5]
    assert df["yaw_rad"].tolist()[2] == -math.pi


def test_scan_list_rejects_mismatched_tables():
    ordering, scan_index, registration = _tiny_tables()
    with pytest.raises(ValueError, match=r"k 0: expected an int in \[1, 3\]"):
        scan_list(ordering, 0, scan_index, registration)
    with pytest.raises(ValueError, match=r"k 4: expected an int in \[1, 3\]"):
        scan_list(ordering, 4, scan_index, registration)
    with pytest.raises(ValueError, match=r"scan_index: selected scans \[5\] are not in it"):
        scan_list(ordering, 3, scan_index[scan_index.scan_id != 5], registration)
    rejected = registration.assign(kept=registration.scan_id != 7)
    with pytest.raises(ValueError, match=r"registration: selected scans \[7\] are not kept there"):
        scan_list(ordering, 2, scan_index, rejected)
    with pytest.raises(ValueError, match=r"ordering: no gain column; expected one of \['gain', 'gain_m2'\]"):
        scan_list(ordering.drop(columns="gain_m2"), 2, scan_index, registration)
    with pytest.raises(ValueError, match=r"registration: columns \['yaw_rad'\] missing"):
        scan_list(ordering, 2, scan_index, registration.drop(columns="yaw_rad"))


# --- selected points -------------------------------------------------------------------


def test_selected_points_as_ply_and_pcd(tmp_path):
    import open3d as o3d

    rng = np.random.default_rng(3)
    sizes = {0: 5, 1: 7, 2: 11, 4: 3}
    pts = {s: rng.uniform(-10, 10, (n, 3)).astype(np.float32) for s, n in sizes.items()}
    df = pd.concat([pd.DataFrame({"scan_id": s, "x": p[:, 0], "y": p[:, 1], "z": p[:, 2]}) for s, p in pts.items()])
    registered = tmp_path / "registered.parquet"
    write_table(df, registered, schema=REGISTERED)
    ply, pcd = tmp_path / "out" / "selected.ply", tmp_path / "out" / "selected.pcd"
    n = write_selected_points(registered, [4, 1], ply, pcd)
    assert n == 10
    expected = np.concatenate([pts[1], pts[4]])  # scan id order
    for path in (ply, pcd):
        cloud = o3d.t.io.read_point_cloud(str(path))
        got = cloud.point.positions.numpy()
        assert got.shape == (10, 3)
        np.testing.assert_array_equal(got.astype(np.float32), expected)
    assert b"binary" in pcd.read_bytes()[:300].split(b"DATA")[1][:10]
    assert b"format binary_little_endian" in ply.read_bytes()[:200]
    assert sorted(p.name for p in ply.parent.iterdir()) == ["selected.pcd", "selected.ply"]
    with pytest.raises(ValueError, match=r"registered.parquet: selected scans \[3\] have no points in it"):
        write_selected_points(registered, [1, 3], tmp_path / "a.ply", tmp_path / "a.pcd")
    with pytest.raises(ValueError, match="no scans selected"):
        write_selected_points(registered, [], tmp_path / "a.ply", tmp_path / "a.pcd")
    assert not (tmp_path / "a.ply").exists()


def test_staged_path_replaces_a_folder_and_leaves_it_on_error(tmp_path):
    out = tmp_path / "bag"
    out.mkdir()
    (out / "old.txt").write_text("old")
    with staged_path(out) as tmp:
        tmp.mkdir()
        (tmp / "new.txt").write_text("new")
    assert [p.name for p in out.iterdir()] == ["new.txt"]
    with pytest.raises(RuntimeError):
        with staged_path(out) as tmp:
            tmp.mkdir()
            (tmp / "half.txt").write_text("half")
            raise RuntimeError("writer failed")
    assert [p.name for p in out.iterdir()] == ["new.txt"]
    assert [p.name for p in tmp_path.iterdir()] == ["bag"]


# --- reduced recording: bags -------------------------------------------------------------

POSE_TOPICS = ("/amcl_pose", "/odom", "/tf")


def _bag_messages(path):
    """{topic: [(log time, raw bytes)]} and the connections of a bag, read as floorscan reads bags."""
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    out = {}
    with AnyReader([Path(path)], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as r:
        conns = {c.topic: c for c in r.connections}
        for c, t, raw in r.messages():
            out.setdefault(c.topic, []).append((t, bytes(raw)))
        stamps = [
            r.deserialize(raw, c.msgtype).header.stamp
            for c, _, raw in r.messages(connections=[c for c in r.connections if c.topic == "/scan"])
        ]
    return out, conns, [s.sec * 1_000_000_000 + s.nanosec for s in stamps]


@pytest.mark.parametrize("bag", ["ros1_bag", "ros2_bag"])
def test_reduced_bag_keeps_selected_scans_static_tf_and_poses_in_the_window(bag, request, tmp_path):
    src = request.getfixturevalue(bag)
    ids = [15, 2]
    t_ns = T0_NS + np.arange(20, dtype=np.int64) * 100_000_000
    out = tmp_path / ("reduced.bag" if bag == "ros1_bag" else "reduced")
    info = write_reduced_recording(src, "rosbag", ids, out, {"scan_topic": "/scan", "t_ns": t_ns}, window_s=0.22)
    # poses every 0.1 s at -0.05 s + k 0.1 s: 4 within 0.22 s of scan 2 (0.2 s) and 4 of scan 15 (1.5 s)
    assert info["topics"] == {"/amcl_pose": 8, "/odom": 8, "/scan": 2, "/tf": 8, "/tf_static": 1}
    assert (info["messages_in"], info["messages_out"], info["scan_messages_out"]) == (87, 27, 2)
    assert info["format"] == ("rosbag1" if bag == "ros1_bag" else "rosbag2")
    assert info["bytes_out"] == sum(p.stat().st_size for p in [out, *out.rglob("*")] if p.is_file())
    assert 0 < info["bytes_out"] < info["bytes_in"]
    src_msgs, src_conns, _ = _bag_messages(src)
    got, conns, stamps = _bag_messages(out)
    assert stamps == [T0_NS + 200_000_000, T0_NS + 1_500_000_000]  # the selected scans' header stamps
    # the scans' and every kept message's bytes are the input's
    for topic, msgs in got.items():
        assert set(msgs) <= set(src_msgs[topic]), topic
        assert (conns[topic].msgtype, conns[topic].digest) == (src_conns[topic].msgtype, src_conns[topic].digest)
    assert got["/scan"] == [m for i, m in enumerate(src_msgs["/scan"]) if i in ids]
    assert got["/tf_static"] == src_msgs["/tf_static"]
    scan_t = np.array([t for t, _ in got["/scan"]])
    for topic in POSE_TOPICS:
        expected = [m for m in src_msgs[topic] if np.min(np.abs(scan_t - m[0])) <= 220_000_000]
        assert got[topic] == expected, topic


def test_reduced_bag_from_the_scan_index_reingests_to_the_same_scans(ros1_bag, tmp_path):
    """The workflow's path: ingest, read_detection from scan_index.parquet, reduce, ingest again."""
    ds = {"path": str(ros1_bag)}
    rec = open_recording(ds, {}, 0.5)
    write_recording(rec, tmp_path / "scans.parquet", tmp_path / "scan_index.parquet", tmp_path / "pose_stream.parquet")
    det = read_detection(tmp_path / "scan_index.parquet")
    assert {k: v for k, v in det.items() if k not in ("t_ns", "source_ordinal")} == {
        "format": "rosbag", "scan_topic": "/scan", "stamps": "recorded", "n_frames_read": "20"}
    assert det["t_ns"].tolist() == (T0_NS + np.arange(20) * 100_000_000).tolist()
    assert det["source_ordinal"].tolist() == list(range(20))  # nothing skipped: message i is scan i
    out = tmp_path / "reduced.bag"
    write_reduced_recording(ros1_bag, det["format"], [4, 9, 17], out, det)
    again = list(open_recording({"path": str(out)}, {}, 0.5).scans)
    assert [s.t_ns for s in again] == [T0_NS + i * 100_000_000 for i in (4, 9, 17)]
    originals = list(open_recording(ds, {}, 0.5).scans)
    for s, i in zip(again, (4, 9, 17)):
        np.testing.assert_array_equal(s.points, originals[i].points)
    assert len(again[0].points) == 177  # 181 beams, 4 invalid (scan_ranges)


def test_reduced_bag_keeps_latched_topics_and_drops_others(tmp_path):
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    T = ts.types
    src = tmp_path / "latched.bag"
    with Writer(src) as w:
        scan = w.add_connection("/scan", "sensor_msgs/msg/LaserScan", typestore=ts)
        latched = w.add_connection("/floor_name", "std_msgs/msg/String", typestore=ts, latching=1)
        chatter = w.add_connection("/chatter", "std_msgs/msg/String", typestore=ts)
        w.write(latched, T0_NS - 5, ts.serialize_ros1(T["std_msgs/msg/String"](data="lower ground"), "std_msgs/msg/String"))
        for i in range(3):
            t = T0_NS + i * 1_000_000_000
            header = T["std_msgs/msg/Header"](seq=i, stamp=T["builtin_interfaces/msg/Time"](sec=t // 10**9, nanosec=0), frame_id="laser")
            msg = T["sensor_msgs/msg/LaserScan"](
                header=header, angle_min=-1.0, angle_max=1.0, angle_increment=0.5, time_increment=0.0, scan_time=0.1,
                range_min=0.1, range_max=10.0, ranges=scan_ranges(i)[:5], intensities=np.zeros(0, np.float32))
            w.write(scan, t, ts.serialize_ros1(msg, "sensor_msgs/msg/LaserScan"))
            w.write(chatter, t + 1, ts.serialize_ros1(T["std_msgs/msg/String"](data=f"hello {i}"), "std_msgs/msg/String"))
    out = tmp_path / "out.bag"
    info = write_reduced_recording(src, None, [1], out, {"scan_topic": "/scan"})
    assert info["topics"] == {"/floor_name": 1, "/scan": 1}
    assert (info["messages_in"], info["messages_out"]) == (7, 2)
    from rosbags.rosbag1 import Reader

    with Reader(out) as r:
        (c,) = [c for c in r.connections if c.topic == "/floor_name"]
        assert c.ext.latching == 1
        assert [t for _, t, _ in r.messages()] == [T0_NS - 5, T0_NS + 1_000_000_000]


def test_reduced_ros2_bag_keeps_the_mcap_storage(ros2_bag, tmp_path):
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import StoragePlugin, Writer
    from rosbags.typesys import Stores, get_typestore

    src = tmp_path / "mcap_bag"
    with AnyReader([ros2_bag], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as r, Writer(
        src, version=9, storage_plugin=StoragePlugin.MCAP
    ) as w:
        conns = {c.id: w.add_connection(c.topic, c.msgtype, msgdef=c.msgdef.data, rihs01=c.digest) for c in r.connections}
        for c, t, raw in r.messages():
            w.write(conns[c.id], t, raw)
    out = tmp_path / "reduced"
    info = write_reduced_recording(next(src.glob("*.mcap")), "rosbag", [0, 19], out, {"scan_topic": "/scan"})
    assert sorted(p.suffix for p in out.iterdir()) == [".mcap", ".yaml"]
    assert info["topics"]["/scan"] == 2 and info["topics"]["/tf_static"] == 1
    got, _, stamps = _bag_messages(out)
    assert stamps == [T0_NS, T0_NS + 1_900_000_000]


def test_reduced_bag_refuses_a_recording_that_changed(ros1_bag, tmp_path):
    t_ns = T0_NS + np.arange(20, dtype=np.int64) * 100_000_000
    out = tmp_path / "r.bag"
    with pytest.raises(InputError, match=r"tiny.bag: selected scan_id 20 is not in the recording's scan index \(0..19\)"):
        write_reduced_recording(ros1_bag, "rosbag", [3, 20], out, {"scan_topic": "/scan", "t_ns": t_ns})
    with pytest.raises(InputError, match=r"tiny.bag: selected scan_id 20 is not in the recording \(20 messages on /scan, ids 0..19\)"):
        write_reduced_recording(ros1_bag, "rosbag", [20], out, {"scan_topic": "/scan"})
    with pytest.raises(InputError, match=r"tiny.bag: holds 20 messages on /scan, the scan index 21; .* changed since ingest"):
        write_reduced_recording(ros1_bag, "rosbag", [3], out, {"scan_topic": "/scan", "t_ns": np.r_[t_ns, t_ns[-1] + 1]})
    moved = t_ns.copy()
    moved[3] += 1
    with pytest.raises(InputError, match=r"tiny.bag: scan 3 is stamped 1700000000300000000 ns, the scan index says 1700000000300000001 ns"):
        write_reduced_recording(ros1_bag, "rosbag", [3, 4], out, {"scan_topic": "/scan", "t_ns": moved})
    with pytest.raises(InputError, match=r"tiny.bag: no topic '/base_scan' \(the scan topic ingest read\); topics in the bag: /amcl_pose"):
        write_reduced_recording(ros1_bag, "rosbag", [3], out, {"scan_topic": "/base_scan"})
    with pytest.raises(InputError, match="no scans selected"):
        write_reduced_recording(ros1_bag, "rosbag", [], out, {"scan_topic": "/scan"})
    with pytest.raises(InputError, match="unsupported format 'laz'"):
        write_reduced_recording(ros1_bag, "laz", [1], out, {"scan_topic": "/scan"})
    assert not out.exists()
    assert list(tmp_path.iterdir()) == []


# --- reduced recording: CARMEN and PCD ------------------------------------------------------


def _carmen_log(path):
    """Five FLASER lines, the fourth earlier than the third (ingest sorts it before it), with
    ODOM lines between them, one with stamp 0; a NEFF and a RAWLASER1 line (dropped)."""
    stamps = [10.0, 10.5, 11.5, 11.0, 12.0]
    lines = ["# message formats defined: PARAM SYNC ODOM FLASER", "PARAM robot_frontlaser_offset 0.0 nohost 0"]
    for i, t in enumerate(stamps):
        lines.append(flaser_line(np.linspace(1.0, 3.0, 180) + 0.01 * i, (float(i), 2.0, 0.1 * i), t))
        lines.append("ODOM 0 0 0 0 0 0 0 pippo 0")
        lines.append("NEFF 15")
        lines.append(f"ODOM {i} 0 0 0 0 0 {t + 0.1:.3f} pippo {t + 0.1:.3f}")
        lines.append(f"ODOM {i} 0 0 0 0 0 {t + 0.25:.3f} pippo {t + 0.25:.3f}")
    lines.append("RAWLASER1 0 0 0 0 0 0 0 0 0 13.0 pippo 13.0")
    return write_carmen(path, lines)


@pytest.mark.parametrize("name", ["a.log", "a.log.gz"])
def test_reduced_carmen_log_keeps_ingest_numbering_and_odometry_in_the_window(name, tmp_path):
    src = _carmen_log(tmp_path / name)
    rec = open_recording({"path": str(src)}, {}, 0.5)
    originals = list(rec.scans)
    det = {"stamps": rec.detected["stamps"], "t_ns": [s.t_ns for s in originals]}
    assert det["t_ns"] == [10_000_000_000, 10_500_000_000, 11_000_000_000, 11_500_000_000, 12_000_000_000]
    out = tmp_path / "out" / name
    info = write_reduced_recording(src, "carmen", [2, 4], out, det, window_s=0.2)
    assert info["topics"] == {"#": 1, "FLASER": 2, "ODOM": 5, "PARAM": 1}
    assert (info["messages_in"], info["messages_out"], info["scan_messages_out"]) == (28, 9, 2)
    data = out.read_bytes()
    assert (data[:2] == b"\x1f\x8b") == name.endswith(".gz")
    text = (gzip.decompress(data) if name.endswith(".gz") else data).decode()
    kept = [ln.split()[0] + " " + ln.split()[-1] for ln in text.splitlines()]
    # scan 2 is the fourth FLASER line (stamp 11.0); the zero-stamped ODOM lines on either side
    # of it are kept (no laser line between them and it), its ODOM at 11.1 within 0.2 s, the
    # one at 11.25 not; scan 4 (12.0) likewise; the ODOM lines of the other scans are out of
    # the windows (10.75 and 11.75 are 0.25 s away)
    assert kept == [
        "# FLASER", "PARAM 0", "ODOM 0", "FLASER 11.0", "ODOM 0", "ODOM 11.100", "FLASER 12.0", "ODOM 0", "ODOM 12.100",
    ]
    assert text.splitlines()[3] == flaser_line(np.linspace(1.0, 3.0, 180) + 0.03, (3.0, 2.0, 0.1 * 3), 11.0)
    again = list(open_recording({"path": str(out)}, {"carmen_max_range_m": float(rec.detected["max_range_m"])}, 0.5).scans)
    assert [s.t_ns for s in again] == [11_000_000_000, 12_000_000_000]
    for s, i in zip(again, (2, 4)):
        np.testing.assert_array_equal(s.points, originals[i].points)
    first = out.read_bytes()
    write_reduced_recording(src, "carmen", [2, 4], out, det, window_s=0.2)
    assert out.read_bytes() == first  # gzip without a time stamp: the same bytes
    with pytest.raises(InputError, match=r"a.log(.gz)?: its laser stamps are now 'recorded', ingest found 'spread'"):
        write_reduced_recording(src, "carmen", [2], out, {**det, "stamps": "spread"})
    with pytest.raises(InputError, match=r"holds 5 laser lines, the scan index 6"):
        write_reduced_recording(src, "carmen", [2], out, {"t_ns": det["t_ns"] + [13]})
    with pytest.raises(InputError, match=r"scan 2 is stamped 11000000000 ns, the scan index says 11500000000 ns"):
        write_reduced_recording(src, "carmen", [2], out, {"t_ns": sorted(det["t_ns"][:2] + [11_500_000_000] * 3)})


def test_reduced_carmen_log_with_made_up_stamps_keeps_odometry_beside_the_scans(tmp_path):
    lines = []
    for i in range(4):
        lines += [flaser_line([1.0 + i] * 180, (float(i), 0.0, 0.0), 0), f"ODOM {i} 0 0 0 0 0 0 pippo 0"]
    src = write_carmen(tmp_path / "z.log", lines)
    out = tmp_path / "z_out.log"
    info = write_reduced_recording(src, "carmen", [2], out, {"stamps": "made_up"})
    # the ODOM lines after scan 1 and after scan 2 (beside scan 2), no stamp to window by
    assert out.read_text().splitlines() == [lines[3], lines[4], lines[5]]
    assert info["topics"] == {"FLASER": 1, "ODOM": 2}


def _pcd_folder(folder, n=4):
    import open3d as o3d

    folder.mkdir()
    rng = np.random.default_rng(1)
    rows = ["file,t_ns,x,y,z,yaw"]
    for i in range(n):
        pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(rng.uniform(-3, 3, (20 + i, 3))))
        o3d.io.write_point_cloud(str(folder / f"scan_{i:02d}.pcd"), pc)
        rows.append(f"scan_{i:02d}.pcd,{1000 + i * 100},{0.5 * i},1.25,0.4,{0.1 * i:.1f}")
    (folder / "locations.csv").write_text("\n".join(rows) + "\n")
    (folder / "README.txt").write_text("not a scan\n")
    return folder


def test_reduced_pcd_folder_copies_the_selected_scans_and_their_rows(tmp_path):
    src = _pcd_folder(tmp_path / "pcd")
    rec = open_recording({"path": str(src)}, {}, 0.5)
    originals = list(rec.scans)
    det = {"t_ns": [s.t_ns for s in originals]}
    out = tmp_path / "reduced"
    info = write_reduced_recording(src, "pcd", [3, 1], out, det)
    assert sorted(p.name for p in out.iterdir()) == ["locations.csv", "scan_01.pcd", "scan_03.pcd"]
    assert (out / "locations.csv").read_text() == (
        "file,t_ns,x,y,z,yaw\nscan_01.pcd,1100,0.5,1.25,0.4,0.1\nscan_03.pcd,1300,1.5,1.25,0.4,0.3\n"
    )
    for name in ("scan_01.pcd", "scan_03.pcd"):
        assert (out / name).read_bytes() == (src / name).read_bytes()
    assert info["topics"] == {"pcd files": 2}
    assert (info["messages_in"], info["messages_out"], info["scan_messages_out"]) == (4, 2, 2)
    assert info["bytes_out"] == sum(p.stat().st_size for p in out.iterdir())
    again = list(open_recording({"path": str(out)}, {}, 0.5).scans)
    assert [len(s.points) for s in again] == [21, 23]
    for s, i in zip(again, (1, 3)):
        np.testing.assert_array_equal(s.points, originals[i].points)
    with pytest.raises(InputError, match=r"locations.csv: selected scan_id 4 is not in the recording \(4 scan locations, ids 0..3\)"):
        write_reduced_recording(src, "pcd", [4], tmp_path / "r2", {})


# --- the real recordings ------------------------------------------------------------------

REAL = {
    # name: (path, output name, topics written for the 10 scans, window 0.5 s)
    "trace0": ("uob-pioneer/trace0.bag", "trace0.bag", {"/base_scan": 10, "/odom": 97, "/tf": 292}),
    "mac_ros2": ("comprobo-mac/macfirst_floor_take_2", "mac", {"/odom": 190, "/scan": 10, "/tf": 223, "/tf_static": 2}),
    "intel": ("radish/intel-corrected.log.gz", "intel.log.gz", {"#": 2, "FLASER": 10, "ODOM": 84, "PARAM": 2}),
}


@needs_shared
@pytest.mark.realdata
@pytest.mark.parametrize("name", list(REAL))
def test_reduced_real_recording_reingests_to_the_same_scans(name, tmp_path):
    rel, out_name, topics = REAL[name]
    src = SHARED_DATA / rel
    rec = open_recording({"path": str(src)}, {}, 0.5)
    originals = list(rec.scans)
    n = len(originals)
    ids = np.linspace(3, n - 4, 10).round().astype(int)
    det = {**rec.detected, "t_ns": [s.t_ns for s in originals]}
    out = tmp_path / out_name
    info = write_reduced_recording(src, rec.detected["format"], ids, out, det, window_s=0.5)
    assert info["topics"] == topics
    assert info["scan_messages_out"] == 10
    assert info["bytes_out"] < info["bytes_in"] / 10
    cfg = {"carmen_max_range_m": float(rec.detected["max_range_m"])} if "max_range_m" in rec.detected else {}
    again_rec = open_recording({"path": str(out)}, cfg, 0.5)
    again = list(again_rec.scans)
    assert again_rec.detected["scan_topic"] == rec.detected["scan_topic"]
    assert again_rec.detected["pose_kind"] == rec.detected["pose_kind"]
    assert len(again) == 10
    for s, i in zip(again, ids):
        assert (s.t_ns, s.frame, s.n_dropped) == (originals[i].t_ns, originals[i].frame, originals[i].n_dropped)
        np.testing.assert_array_equal(s.points, originals[i].points)

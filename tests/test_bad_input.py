"""A stage that fails on bad input says so once, as one paragraph naming the user's
file; a bug keeps its traceback (issue 24 item 5).

floorscan.core.stage.stage_log logs the failure to the stage's log file only (Snakemake
prints that file when a job fails: ``show-failed-logs`` of the default profile) and
ends the script with status 1 without a traceback; Snakemake removes the job's outputs.
"""

import runpy
import shutil
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest

from conftest import REPO
from floorscan.core.config import ConfigError
from floorscan.core.io import POSE_STREAM, SCAN_INDEX, InputError, write_table
from floorscan.core.stage import stage_log

SNAKEMAKE = Path(sys.executable).with_name("snakemake")


def _smk(tmp_path, rule="ingest"):
    return SimpleNamespace(rule=rule, log=[str(tmp_path / f"{rule}.log")], wildcards={"dataset": "lab"})


@pytest.mark.parametrize("error", [InputError, ConfigError])
def test_an_expected_error_is_one_paragraph_in_the_log_and_exit_status_1(tmp_path, capsys, error):
    message = "/data/lab.bag: cannot read the bag, truncated or corrupt"
    with pytest.raises(SystemExit) as exit_info:
        with stage_log(_smk(tmp_path)):
            raise error(message)
    assert exit_info.value.code == 1
    assert isinstance(exit_info.value.__cause__, error)  # for a caller in the same process
    log = (tmp_path / "ingest.log").read_text()
    assert "Traceback" not in log
    errors = [line for line in log.splitlines() if " ERROR " in line]
    assert len(errors) == 1 and errors[0].endswith(f"ERROR floorscan.ingest: ingest failed: {message}")
    # not on stderr as well: Snakemake prints the failed job's log
    assert message not in capsys.readouterr().err


def test_a_bug_keeps_its_traceback_and_is_reraised(tmp_path, capsys):
    with pytest.raises(ZeroDivisionError):
        with stage_log(_smk(tmp_path, "hulls_shard")):
            1 / 0
    log = (tmp_path / "hulls_shard.log").read_text()
    assert "stage hulls_shard failed" in log and "Traceback" in log and "ZeroDivisionError" in log
    assert "Traceback" not in capsys.readouterr().err  # Python prints it once, as it ends


def test_a_later_stage_names_the_recording_not_an_intermediate_table(tmp_path):
    """The message of a stage after ingest names the recording (and its topic) that
    ingest read, from the metadata of its tables."""
    from floorscan.core.stage import failure_message

    index = tmp_path / "scan_index.parquet"
    meta = {"source": "/data/lab.bag /scan"}
    write_table(pd.DataFrame({"scan_id": [0, 1], "t_ns": [10, 20], "n_points": [5, 5], "n_dropped": [0, 0],
                              "frame": ["laser", "laser"]}), index, schema=SCAN_INDEX, metadata=meta)
    msg = failure_message("register", ValueError("register: the result is poor: kept 1 of 40 sampled scans"), index)
    assert msg == "register failed on /data/lab.bag /scan: register: the result is poor: kept 1 of 40 sampled scans"
    # a message that names the recording already is left as it is
    assert failure_message("ingest", InputError("/data/lab.bag: corrupt"), index) == "ingest failed: /data/lab.bag: corrupt"
    assert failure_message("x", InputError("bad"), tmp_path / "missing.parquet") == "x failed: bad"


class _Named(dict):
    """Stand-in for Snakemake's named lists: items by key and by attribute."""

    __getattr__ = dict.__getitem__


def test_the_poses_stage_names_the_recording_and_its_pose_source(tmp_path):
    """A pose stream that does not overlap the scans: the message names the bag, the
    scan topic and the pose topic, not pose_stream.parquet."""
    meta = {"source": "/data/lab.bag /scan", "pose_source": "topic /amcl_pose (PoseWithCovarianceStamped)"}
    t = 1_700_000_000_000_000_000 + np.arange(5, dtype=np.int64) * 100_000_000
    write_table(pd.DataFrame({"scan_id": np.arange(5), "t_ns": t, "n_points": 5, "n_dropped": 0, "frame": "laser"}),
                tmp_path / "scan_index.parquet", schema=SCAN_INDEX, metadata=meta)
    later = t + 3_600_000_000_000  # an hour after the last scan
    write_table(pd.DataFrame({"t_ns": later, "x": 0.0, "y": 0.0, "z": 0.0, "yaw": 0.0}),
                tmp_path / "pose_stream.parquet", schema=POSE_STREAM, metadata=meta)
    log = tmp_path / "poses.log"
    smk = _Named(
        input=_Named(index=str(tmp_path / "scan_index.parquet"), pose_stream=str(tmp_path / "pose_stream.parquet")),
        output=_Named(poses=str(tmp_path / "poses.parquet")), params=_Named(cfg={"max_gap_s": 0.5}),
        wildcards=_Named(dataset="lab"), log=[str(log)], rule="poses",
    )
    with pytest.raises(SystemExit) as exit_info:
        runpy.run_path(str(REPO / "scripts" / "poses.py"), init_globals={"snakemake": smk}, run_name="__main__")
    assert exit_info.value.code == 1
    error = [line for line in log.read_text().splitlines() if " ERROR " in line]
    assert len(error) == 1
    assert "/data/lab.bag /scan" in error[0] and "/amcl_pose" in error[0] and "does not overlap the scans" in error[0]
    assert "pose_stream.parquet" not in error[0]
    assert not (tmp_path / "poses.parquet").exists()


@pytest.mark.workflow
def test_a_corrupt_bag_is_reported_once_without_a_traceback(tmp_path, ros1_bag):
    """The whole workflow on a truncated bag: the job fails (status 1, no outputs) and
    the error is printed once, as one paragraph naming the bag (measured: 110 lines
    with the error three times and two tracebacks before; 75 lines after, most of them
    Snakemake's banner and job table)."""
    wd = tmp_path / "floorscan"
    wd.mkdir()
    for name in ("Snakefile", "workflow", "config", "scripts"):
        src = REPO / name
        shutil.copytree(src, wd / name) if src.is_dir() else shutil.copy2(src, wd / name)
    (wd / "profiles").symlink_to("workflow/profiles")  # the repository's default profile, as a user runs
    bag = tmp_path / "lab.bag"  # the tiny recording of conftest, cut short
    data = ros1_bag.read_bytes()
    bag.write_bytes(data[: len(data) // 2])
    res = subprocess.run([str(SNAKEMAKE), "--cores", "2", "--config", f"path={bag}"], cwd=wd,
                         capture_output=True, text=True, timeout=300)
    out = res.stdout + res.stderr
    assert res.returncode == 1, out[-3000:]
    assert "Error in rule ingest" in out
    lines = [line for line in out.splitlines() if "ingest failed:" in line]
    assert len(lines) == 1, out
    assert str(bag) in lines[0] and "cannot read the bag" in lines[0]
    assert "Traceback" not in out and "InputError" not in out
    assert not list((wd / "results" / "lab").glob("*.parquet"))


def _bad_recordings(root: Path, ros1_bag: Path, ros2_bag: Path) -> dict[str, Path]:
    """A corpus of bad recordings as users bring them, each in its own file or folder:
    truncated and corrupted bags, CARMEN logs with broken lines, PCD folders whose
    headers, data or locations disagree."""
    from conftest import flaser_line, write_carmen

    corpus: dict[str, Path] = {}
    data = ros1_bag.read_bytes()
    for frac in (0.05, 0.2, 0.5, 0.8, 0.97):  # truncated ROS1 bags
        p = root / f"truncated_{int(frac * 100)}.bag"
        p.write_bytes(data[: int(len(data) * frac)])
        corpus[p.name] = p
    for at in (0.1, 0.4, 0.7):  # a run of zeros over the middle of the bag
        p = root / f"zeroed_{int(at * 100)}.bag"
        b = bytearray(data)
        i = int(len(b) * at)
        b[i : i + 4096] = bytes(4096)
        p.write_bytes(bytes(b))
        corpus[p.name] = p
    p = root / "empty.bag"
    p.write_bytes(b"")
    corpus[p.name] = p
    p = root / "not_a_bag.bag"
    p.write_bytes(b"#ROSBAG V2.0\n" + bytes(range(256)) * 8)
    corpus[p.name] = p
    # ROS2: a bag folder without its storage file, or with a truncated one
    db3 = next(ros2_bag.glob("*.db3"))
    for frac in (0.0, 0.3):
        folder = root / f"ros2_truncated_{int(frac * 100)}"
        shutil.copytree(ros2_bag, folder)
        (folder / db3.name).write_bytes(db3.read_bytes()[: int(db3.stat().st_size * frac)])
        corpus[folder.name] = folder
    folder = root / "ros2_no_metadata"
    shutil.copytree(ros2_bag, folder)
    (folder / "metadata.yaml").unlink()
    corpus[folder.name] = folder
    # CARMEN logs: a good line with a broken one among them
    good = [flaser_line(np.full(180, 2.0), (1.0, 2.0, 0.1), 100.0 + 0.1 * i) for i in range(5)]
    broken = {
        "short": "FLASER 180 " + " ".join(["2.0"] * 179) + " 1 2 0.1 1 2 0.1 100.9 host 100.9",
        "long": "FLASER 180 " + " ".join(["2.0"] * 181) + " 1 2 0.1 1 2 0.1 100.9 host 100.9",
        "count_word": "FLASER abc 2.0 2.0 1 2 0.1 1 2 0.1 100.9 host 100.9",
        "count_float": "FLASER 2.5 2.0 2.0 1 2 0.1 1 2 0.1 100.9 host 100.9",
        "nan_pose": "FLASER 2 2.0 2.0 nan 2 0.1 1 2 0.1 100.9 host 100.9",
        "inf_theta": "FLASER 2 2.0 2.0 1 2 inf 1 2 0.1 100.9 host 100.9",
        "nan_stamp": "FLASER 2 2.0 2.0 1 2 0.1 1 2 0.1 nan host 100.9",
        "negative_stamp": "FLASER 2 2.0 2.0 1 2 0.1 1 2 0.1 -5 host 100.9",
        "word_range": "FLASER 2 2.0 two 1 2 0.1 1 2 0.1 100.9 host 100.9",
        "robotlaser_short": "ROBOTLASER1 0 -1.5 3.14 0.01 30 0.1 0 3 2.0 2.0 2.0 0",
    }
    for name, line in broken.items():
        corpus[f"carmen_{name}.log"] = write_carmen(root / f"carmen_{name}.log", good[:3] + [line] + good[3:])
    p = root / "carmen_no_laser.log"
    p.write_text("# a log without laser lines\nODOM 1 2 0.1 0 0 0 100.0 host 100.0\n")
    corpus[p.name] = p
    p = root / "carmen_gzip_truncated.log.gz"
    import gzip

    p.write_bytes(gzip.compress(("\n".join(good) + "\n").encode())[:-20])
    corpus[p.name] = p
    # PCD folders
    header = "VERSION 0.7\nFIELDS x y z\nSIZE {size}\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {w}\nHEIGHT 1\nPOINTS {n}\nDATA {data}\n"
    pcd_cases = {
        "points_word": (header.format(size="4 4 4", w=2, n="abc", data="ascii") + "1 2 3\n4 5 6\n", None),
        "size_2": (header.format(size="2 4 4", w=2, n=2, data="ascii") + "1 2 3\n4 5 6\n", None),
        "rows_missing": (header.format(size="4 4 4", w=3, n=3, data="ascii") + "1 2 3\n4 5 6\n", None),
        "row_short": (header.format(size="4 4 4", w=2, n=2, data="ascii") + "1 2 3\n4 5\n", None),
        "word_in_data": (header.format(size="4 4 4", w=2, n=2, data="ascii") + "1 2 3\n4 five 6\n", None),
        "width_mismatch": (header.format(size="4 4 4", w=5, n=2, data="ascii") + "1 2 3\n4 5 6\n", None),
        "binary_short": (header.format(size="4 4 4", w=2, n=2, data="binary"), bytes(20)),
        "compressed_sizes": (header.format(size="4 4 4", w=2, n=2, data="binary_compressed"), bytes([9, 0, 0, 0, 24, 0, 0, 0, 1])),
        "unknown_data": (header.format(size="4 4 4", w=2, n=2, data="zip") + "1 2 3\n4 5 6\n", None),
        "integer_x": (header.format(size="4 4 4", w=2, n=2, data="ascii").replace("TYPE F F F", "TYPE I F F")
                      + "1 2 3\n4 5 6\n", None),
        "x_count_2": (header.format(size="4 4 4", w=2, n=2, data="ascii").replace("COUNT 1 1 1", "COUNT 2 1 1")
                      + "1 1 2 3\n4 4 5 6\n", None),
        "no_z": (header.format(size="4 4 4", w=2, n=2, data="ascii").replace("FIELDS x y z", "FIELDS x y w")
                 + "1 2 3\n4 5 6\n", None),
    }
    good_pcd = header.format(size="4 4 4", w=2, n=2, data="ascii") + "1 2 3\n4 5 6\n"
    for name, (text, blob) in pcd_cases.items():
        folder = root / f"pcd_{name}"
        folder.mkdir()
        (folder / "a.pcd").write_text(good_pcd)
        (folder / "b.pcd").write_bytes(text.encode() + (blob or b""))
        (folder / "locations.csv").write_text("file,t_ns,x,y,z,yaw\na.pcd,0,0,0,0,0\nb.pcd,100,1,0,0,0\n")
        corpus[folder.name] = folder
    for name, rows in {
        "nan_x": "a.pcd,0,nan,0,0,0\nb.pcd,100,1,0,0,0\n",
        "fraction_stamp": "a.pcd,0.5,0,0,0,0\nb.pcd,100,1,0,0,0\n",
        "missing_file": "a.pcd,0,0,0,0,0\nc.pcd,100,1,0,0,0\n",
        "word_yaw": "a.pcd,0,0,0,0,north\nb.pcd,100,1,0,0,0\n",
    }.items():
        folder = root / f"pcd_locations_{name}"
        folder.mkdir()
        (folder / "a.pcd").write_text(good_pcd)
        (folder / "b.pcd").write_text(good_pcd)
        (folder / "locations.csv").write_text("file,t_ns,x,y,z,yaw\n" + rows)
        corpus[folder.name] = folder
    folder = root / "pcd_no_locations"
    folder.mkdir()
    (folder / "a.pcd").write_text(good_pcd)
    corpus[folder.name] = folder
    return corpus


def test_a_corpus_of_bad_recordings_gives_one_input_error_each_and_leaves_nothing(tmp_path, ros1_bag, ros2_bag):
    """Issue 24: at least 40 bad recordings through the ingest stage (open_recording
    and write_recording, what scripts/ingest.py runs): each ends in the project's
    InputError naming the recording, never another exception or a table written from
    a misread, and no output or hidden temporary is left behind."""
    from floorscan.ingest.readers import open_recording
    from floorscan.ingest.writer import write_recording

    (tmp_path / "in").mkdir()
    corpus = _bad_recordings(tmp_path / "in", ros1_bag, ros2_bag)
    assert len(corpus) >= 40
    outcomes = {}
    for name, path in corpus.items():
        out = tmp_path / "out" / name
        out.mkdir(parents=True)
        try:
            rec = open_recording({"name": name, "path": str(path)}, {}, max_gap_s=0.5)
            write_recording(rec, out / "scans.parquet", out / "scan_index.parquet", out / "pose_stream.parquet")
            outcomes[name] = "read"
        except InputError as e:
            assert path.name in str(e) or str(path) in str(e), (name, str(e))
            outcomes[name] = "InputError"
        left = sorted(p.name for p in out.iterdir())
        assert outcomes[name] == "read" or left == [], (name, left)
    wrong = {k: v for k, v in outcomes.items() if v != "InputError"}
    assert wrong == {}, f"{len(wrong)} of {len(corpus)} bad recordings were read: {sorted(wrong)}"

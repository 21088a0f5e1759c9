"""A stage that fails on bad input says so once, as one paragraph naming the user's
file; a bug keeps its traceback (issue 24 item 5).

floorscan.workflow.stage_log logs the failure to the stage's log file only (Snakemake
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
from floorscan.config import ConfigError
from floorscan.io import POSE_STREAM, SCAN_INDEX, InputError, write_table
from floorscan.workflow import stage_log

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
    from floorscan.workflow import failure_message

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

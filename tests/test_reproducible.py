"""The same input gives the same files (issue 24 item 7).

Timing lives in the logs, the benchmarks folder and the timing figures only: the
tables the stages exchange and the answer (floor plans, scan list, reduced recording,
points) hold none, so two runs of the demo from scratch give byte-identical files
outside ``logs/`` and ``benchmarks/``, the timing figures aside. The PNG figures are
compared too: matplotlib writes no creation time into a PNG (its ``Software`` entry
names the version only).
"""

import re
import sys
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from benchmarks.compare_results import TIMING_FIGURES, digests
from floorscan.core.io import POSE_STREAM, POSES, SCAN_INDEX, SCANS, write_table
from floorscan.select.summary import SUMMARY, summarize
from floorscan.walls.tables import SCAN_STATUS

SNAKEMAKE = Path(sys.executable).with_name("snakemake")

#: A column name that says it is a duration.
TIMING_COLUMN = re.compile(r"(^|_)(s|ms|sec|secs|seconds|time_s|time_ms)$")


def timing_columns(schema: pa.Schema) -> list[str]:
    return [name for name in schema.names if TIMING_COLUMN.search(name) and not name.endswith("_m_s")]


def test_the_tables_of_the_stages_hold_no_timing(tmp_path):
    """Not in the schemas of the tables, nor in the summary as written."""
    for name, schema in {"SCANS": SCANS, "SCAN_INDEX": SCAN_INDEX, "POSE_STREAM": POSE_STREAM, "POSES": POSES,
                         "SCAN_STATUS": SCAN_STATUS, "SUMMARY": SUMMARY}.items():
        assert timing_columns(schema) == [], name
    o = pd.DataFrame({"rank": [1, 2], "scan_id": [4, 2], "covered_area_m2": [1.0, 2.0], "gain_m2": [1.0, 1.0]})
    summary = summarize({"cluster_hull": o}, {"cluster_hull": 0.25})
    assert summary["seconds"].tolist() == [0.25]  # for the log
    write_table(summary, tmp_path / "summary.parquet", schema=SUMMARY)
    assert timing_columns(pq.read_schema(tmp_path / "summary.parquet")) == []


@pytest.mark.workflow
@pytest.mark.slow
def test_two_runs_of_the_demo_give_the_same_bytes(tmp_path, demo_run):
    """The demo from scratch in a copy of the workflow (~1 min on 2 cores) against the
    session's run of it (conftest.demo_run; other tests rerun stages in it, which must
    not change a byte either); every file of results/demo compared byte for byte."""
    from conftest import copy_workflow, snakemake

    wd = copy_workflow(tmp_path / "again" / "floorscan")
    res = snakemake(wd)
    assert res.returncode == 0, res.stderr[-4000:]
    runs = [demo_run / "results", wd / "results"]
    a, b = (digests(r / "demo") for r in runs)
    assert len(a) > 500  # the whole evaluation of the demo
    assert sorted(set(a) ^ set(b)) == []
    differ = sorted(k for k in a if a[k] != b[k])
    assert differ == [], f"{len(differ)} files differ between two runs: {differ}"
    # the timing figures' data: one time per kept scan and extractor
    status = pd.read_parquet(runs[0] / "demo" / "walls" / "ransac" / "scan_status.parquet")
    for extractor in ("ransac", "cluster_ransac"):
        times = pd.read_parquet(runs[0] / "demo" / "benchmarks" / f"scan_walls_{extractor}_times.parquet")
        assert times["scan_id"].tolist() == status["scan_id"].tolist() and (times["time_s"] > 0).all()
    for figure in TIMING_FIGURES:
        assert (runs[0] / "demo" / figure).stat().st_size > 200, figure

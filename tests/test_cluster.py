"""Stages share nothing but files (issue 8 item 4).

The per-scan stages of the demo run twice from the same registered scans: once with
the local executor, one job per stage, and once in shards through the cluster-generic
executor (``workflow/profiles/local-cluster``: ``submit.sh`` starts every shard job as
a separate background process running its own Snakemake, as are select and walls,
which merge the shards; the cheap plan jobs are local rules of the submitting
process). The outputs must be the same bytes.
"""

import hashlib
import re
import shutil
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from conftest import snakemake

pytestmark = [pytest.mark.workflow, pytest.mark.slow]

OUT = "results/demo"
TABLES = ["hulls.parquet", "convex_hulls.parquet", "walls/ransac/per_scan.parquet"]
STATUS = "walls/ransac/scan_status.parquet"


def copy_demo_without(src, dest, names):
    """The workflow folder ``src`` with its demo built (the session's demo run) copied to
    ``dest`` (Snakemake's records and the file times kept), without ``names`` under
    results/demo (the outputs under test) and without the other datasets' results."""
    def ignore(folder, entries):
        if Path(folder) == Path(src) / "results":
            return [e for e in entries if e != "demo"]
        return []

    shutil.copytree(src, dest, symlinks=True, ignore=ignore)
    for name in names:
        path = dest / OUT / name
        if path.is_dir():
            shutil.rmtree(path)
        elif path.exists():
            path.unlink()
    return dest


@pytest.fixture(scope="module")
def runs(tmp_path_factory, demo_run):
    root = tmp_path_factory.mktemp("cluster")
    # the session's demo run without the outputs under test: only these stages run again
    local = copy_demo_without(demo_run, root / "local", ("hulls.parquet", "convex_hulls.parquet", "walls", "shards"))
    targets = [f"{OUT}/{t}" for t in TABLES + [STATUS]]
    (local / "config" / "one_job.yaml").write_text("hulls: {shard_scans: 0}\nwalls: {shard_scans: 0}\n")
    res = snakemake(local, *targets, "--configfile", "config/one_job.yaml")
    assert res.returncode == 0, res.stderr[-4000:]
    assert "rule register" not in res.stdout + res.stderr
    # the same registered scans (and Snakemake's records of them) without the outputs under test
    cluster = copy_demo_without(local, root / "cluster", ("hulls.parquet", "convex_hulls.parquet", "walls", "shards"))
    # 65 kept scans: 2 shards per stage
    (cluster / "config" / "shards.yaml").write_text("hulls: {shard_scans: 40}\nwalls: {shard_scans: 40}\n")
    res = snakemake(cluster, *targets, "--profile", "workflow/profiles/local-cluster", "--configfile", "config/shards.yaml")
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-4000:]
    assert "rule register" not in res.stdout + res.stderr  # only the stages under test ran
    return local / OUT, cluster / OUT, res.stdout + res.stderr


def md5(path):
    return hashlib.md5(path.read_bytes()).hexdigest()


def test_cluster_shards_give_the_local_files(runs):
    local, cluster, _ = runs
    for name in TABLES:
        assert md5(local / name) == md5(cluster / name), name
        assert pq.read_table(local / name).equals(pq.read_table(cluster / name))
    a, b = pq.read_table(local / STATUS), pq.read_table(cluster / STATUS)
    keep = [c for c in a.column_names if c != "time_s"]  # the wall-clock time of each scan
    assert a.select(keep).equals(b.select(keep))
    # real numbers: every kept scan has 10 cluster hulls and walls
    kept = pq.read_table(local / "registration.parquet").to_pandas().query("kept")["scan_id"]
    hulls = pq.read_table(cluster / "hulls.parquet").to_pandas()
    assert len(kept) == 76 and hulls.groupby("scan_id").size().eq(10).all()
    assert hulls["scan_id"].drop_duplicates().tolist() == sorted(kept)
    status = b.to_pandas()
    assert status["scan_id"].tolist() == sorted(kept) and (status["n_walls"] > 0).mean() > 0.9


def test_every_shard_was_a_separate_submitted_process(runs):
    local, cluster, log = runs
    for stage, folder in (("hulls", "hulls"), ("scan_walls", "walls/ransac")):
        shards = sorted(p.name for p in (cluster / "shards" / folder).iterdir() if p.is_dir())
        assert shards == ["scans_000000-000136", "scans_000137-000320"], stage
        # submit.sh writes one output file per job script it starts
        outs = list((cluster.parents[1] / ".snakemake" / "local-cluster").glob(f"snakejob.{stage}_shard.*.sh.out"))
        assert len(outs) == 2, stage
        assert [p.name for p in (local / "shards" / folder).iterdir() if p.is_dir()] == ["scans_000000-000320"]
    pids = re.findall(r"Submitted job \d+ with external jobid '(\d+)'", log)
    # the 4 shard jobs, and select and walls, which merge them (per_scan.parquet is
    # written by walls, which needs the orderings); the plans are local rules
    assert len(pids) == 6 and len(set(pids)) == 6

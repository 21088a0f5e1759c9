"""Shards of the per-scan stages (floorscan.core.shards; issue 8 item 3).

The hulls and scan_walls stages run as shard jobs over scan ranges and a merge. Here
the real stage scripts run in-process (a stand-in for the ``snakemake`` object) on a
small input, both sharded and as one job, and the merged files must be the very bytes
the unsharded stage writes (``time_s``, the per-scan wall-clock time, aside).
"""

import hashlib
import itertools
import math
import runpy
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from conftest import REPO, SHARED_DATA, needs_shared
from floorscan.select.hulls import compute_hulls, to_table
from floorscan.core.io import InputError, REGISTERED, write_table
from floorscan.select.params import HullParams
from floorscan.select.registry import ORDERINGS
from floorscan.core.shards import (
    concat_shards,
    parse_shard_label,
    plan_from_files,
    plan_shards,
    read_scan_range,
    read_shards,
    scan_id_bounds,
    shard_label,
    shard_ranges,
)
from floorscan.walls.extract import extract_walls
from floorscan.walls.tables import SCAN_STATUS, WALLS

SCRIPTS = REPO / "scripts"
WALLS_CFG = {"seed": 3}  # the rest are the package defaults


# --------------------------------------------------------------------- shard ranges


def test_fewer_kept_scans_than_a_shard_is_one_range_over_all_scans():
    assert shard_ranges([3, 5, 8], 500, first=0, last=20) == [(0, 20)]
    assert shard_ranges([3, 5, 8], 0, first=0, last=20) == [(0, 20)]  # 0 = no sharding
    assert shard_ranges([4], 1) == [(4, 4)]


def test_exact_multiple_gives_full_shards():
    assert shard_ranges(range(100), 25) == [(0, 24), (25, 49), (50, 74), (75, 99)]
    assert shard_ranges(range(6), 1) == [(i, i) for i in range(6)]


def test_ranges_are_balanced_contiguous_and_start_at_kept_scans():
    kept = [2, 3, 7, 11, 12, 13, 20, 31, 40, 41]  # 10 kept of scans 0..45
    r = shard_ranges(kept, 4, first=0, last=45)
    assert r == [(0, 11), (12, 30), (31, 45)]  # ceil(10/4) = 3 shards of 4, 3, 3 kept
    n_kept = [sum(a <= k <= b for k in kept) for a, b in r]
    assert n_kept == [4, 3, 3]
    # unsorted, duplicated ids: the same ranges
    assert shard_ranges(kept[::-1] + [7], 4, first=0, last=45) == r


@pytest.mark.parametrize("n_kept,size", [(1, 1), (7, 3), (1017, 500), (1017, 250), (999, 1000)])
def test_number_and_size_of_shards(n_kept, size):
    kept = np.arange(n_kept) * 5 + 2
    r = shard_ranges(kept, size, first=0, last=int(kept[-1]) + 4)
    assert len(r) == math.ceil(n_kept / size)
    counts = [int(((kept >= a) & (kept <= b)).sum()) for a, b in r]
    assert sum(counts) == n_kept and max(counts) <= size and max(counts) - min(counts) <= 1
    assert r[0][0] == 0 and r[-1][1] == kept[-1] + 4
    assert all(b + 1 == a for (_, b), (a, _) in zip(r, r[1:]))


def test_bad_shard_requests_raise():
    with pytest.raises(ValueError, match="no kept scans"):
        shard_ranges([], 10)
    with pytest.raises(ValueError, match=">= 0"):
        shard_ranges([1, 2], -1)
    with pytest.raises(ValueError, match="does not contain every kept scan"):
        shard_ranges([1, 9], 1, first=2, last=9)


def test_labels_round_trip_and_reject_garbage():
    assert shard_label(120, 239) == "scans_000120-000239"
    assert parse_shard_label("scans_000120-000239") == (120, 239)
    assert parse_shard_label(shard_label(5, 1234567)) == (5, 1234567)
    for bad in ("scans_9-3", "scans_1_2", "hulls.parquet", "scans_-1-3"):
        with pytest.raises(ValueError):
            parse_shard_label(bad)
    with pytest.raises(ValueError):
        shard_label(4, 3)


def registration_table(n_scans: int, kept: set) -> pd.DataFrame:
    """A registration table: the rover drives along x at 0.5 m/s, a scan every 0.2 s."""
    ids = np.arange(n_scans, dtype=np.int32)
    return pd.DataFrame({
        "scan_id": ids, "t_ns": ids.astype(np.int64) * 200_000_000, "kept": [i in kept for i in range(n_scans)],
        "x_m": 0.1 * ids, "y_m": np.zeros(n_scans), "yaw_rad": np.zeros(n_scans),
    })  # fmt: skip


def test_plan_covers_registration_and_points():
    reg = registration_table(30, {4, 5, 9, 17, 25})
    plan = plan_shards(reg, np.array([4, 5, 9, 17, 25, 33]), 2)  # a point of scan 33
    assert [(s["start"], s["stop"], s["n_kept"]) for s in plan["shards"]] == [(0, 8, 2), (9, 24, 2), (25, 33, 1)]
    assert (plan["first"], plan["last"], plan["n_kept"], plan["shard_scans"]) == (0, 33, 5, 2)
    assert plan["shards"][1]["label"] == "scans_000009-000024"
    # plan_from_files passes the file as a pyarrow Table: same plan
    assert plan_shards(pa.Table.from_pandas(reg), np.array([4, 5, 9, 17, 25, 33]), 2) == plan


def test_plan_without_kept_scans_is_a_clear_error():
    reg = registration_table(12, set()).assign(reason="pose_gap")
    with pytest.raises(InputError, match=r"reg\.parquet: no kept scan \(of 12\).*'pose_gap': 12"):
        plan_shards(reg, [], 10, path="reg.parquet")
    with pytest.raises(InputError, match=r"no kept scan \(of 12\).*'pose_gap': 12"):
        plan_shards(pa.Table.from_pandas(reg), [], 10, path="reg.parquet")
    with pytest.raises(InputError, match="columns \\['kept'\\] missing"):
        plan_shards(pd.DataFrame({"scan_id": [0, 1]}), [], 10, path="reg.parquet")


def test_plan_from_files_reads_bounds_from_statistics(tmp_path):
    reg = registration_table(30, {4, 5, 9, 17, 25})
    write_table(reg, tmp_path / "registration.parquet")
    ids = np.repeat(np.array([4, 5, 9, 17, 25, 33], np.int32), 3)  # a point of scan 33
    pts = pd.DataFrame({"scan_id": ids, "x": np.zeros(len(ids), np.float32)})
    # three row groups: the bounds come from their statistics (min 4, max 33)
    pq.write_table(pa.Table.from_pandas(pts, preserve_index=False), tmp_path / "registered.parquet", row_group_size=7)
    assert pq.ParquetFile(tmp_path / "registered.parquet").metadata.num_row_groups == 3
    assert scan_id_bounds(tmp_path / "registered.parquet") == (4, 33)
    plan = plan_from_files(tmp_path / "registration.parquet", tmp_path / "registered.parquet", 2)
    assert plan == plan_shards(reg, ids, 2)
    assert [s["label"] for s in plan["shards"]] == ["scans_000000-000008", "scans_000009-000024", "scans_000025-000033"]
    # without statistics the column is read: the same bounds
    pq.write_table(pa.Table.from_pandas(pts, preserve_index=False), tmp_path / "nostats.parquet",
                   row_group_size=7, write_statistics=False)
    assert scan_id_bounds(tmp_path / "nostats.parquet") == (4, 33)
    # no points: the registration alone (0..29)
    pq.write_table(pa.Table.from_pandas(pts.iloc[:0], preserve_index=False), tmp_path / "empty.parquet")
    assert scan_id_bounds(tmp_path / "empty.parquet") is None
    assert plan_from_files(tmp_path / "registration.parquet", tmp_path / "empty.parquet", 0)["last"] == 29
    pq.write_table(pa.table({"x": [1.0]}), tmp_path / "x.parquet")
    with pytest.raises(InputError, match=r"x\.parquet: no scan_id column"):
        scan_id_bounds(tmp_path / "x.parquet")
    # nothing kept: the error names the file and the drop reasons (read for the message)
    write_table(registration_table(12, set()).assign(reason="pose_gap"), tmp_path / "none.parquet")
    with pytest.raises(InputError, match=r"none\.parquet: no kept scan \(of 12\).*'pose_gap': 12"):
        plan_from_files(tmp_path / "none.parquet", tmp_path / "registered.parquet", 2)


def test_read_scan_range_keeps_file_order(tmp_path):
    df = pd.DataFrame({"scan_id": np.array([0, 0, 1, 2, 2, 2, 3], np.int32), "v": np.arange(7.0)})
    write_table(df, tmp_path / "t.parquet")
    got = read_scan_range(tmp_path / "t.parquet", 1, 2)
    assert got["scan_id"].tolist() == [1, 2, 2, 2] and got["v"].tolist() == [2.0, 3.0, 4.0, 5.0]
    assert read_scan_range(tmp_path / "t.parquet", 5, 9).empty
    write_table(pd.DataFrame({"x": [1.0]}), tmp_path / "bad.parquet")
    with pytest.raises(InputError, match="bad.parquet: no scan_id column"):
        read_scan_range(tmp_path / "bad.parquet", 0, 1)


def test_concat_checks_order_and_ranges():
    t = lambda ids: pa.table({"scan_id": pa.array(ids, pa.int32())})  # noqa: E731
    merged = concat_shards([t([0, 1, 1]), t([]), t([7, 9])], ["scans_0-3", "scans_4-5", "scans_6-9"])
    assert merged.column("scan_id").to_pylist() == [0, 1, 1, 7, 9]
    assert merged.column("scan_id").num_chunks == 1
    with pytest.raises(ValueError, match="not contiguous"):
        concat_shards([t([0]), t([7])], ["scans_0-3", "scans_5-9"])
    with pytest.raises(ValueError, match="outside its range"):
        concat_shards([t([0, 4]), t([7])], ["scans_0-3", "scans_4-9"])
    with pytest.raises(ValueError, match="not ascending"):
        concat_shards([t([2, 1]), t([7])], ["scans_0-3", "scans_4-9"])
    with pytest.raises(ValueError, match="do not match the plan"):
        read_shards(["a/scans_0-3/x.parquet"], {"shards": [{"label": "scans_0-9"}]})


# ------------------------------------------------- sharded == unsharded, real scripts


class _Named(dict):
    """Stand-in for Snakemake's named lists: items by key and by attribute."""

    __getattr__ = dict.__getitem__


_JOB = itertools.count()


def run_script(name: str, tmp: Path, rule: str, input, output, params=None, wildcards=None):
    """Run scripts/<name> as Snakemake would (its ``snakemake`` object); its log text."""
    log = tmp / "logs" / f"{rule}_{next(_JOB)}.log"
    log.parent.mkdir(parents=True, exist_ok=True)
    smk = _Named(input=_Named(input), output=_Named(output), params=_Named(params or {}),
                 wildcards=_Named(wildcards or {}), log=[str(log)], rule=rule)
    runpy.run_path(str(SCRIPTS / name), init_globals={"snakemake": smk}, run_name="__main__")
    return log.read_text()


def unsharded(registered, registration, out: Path, extractor: str):
    """What the stages wrote before sharding: one job over every scan."""
    cluster, convex, counts = compute_hulls(pq.read_table(registered).to_pandas(),
                                            pq.read_table(registration).to_pandas(), HullParams())
    meta = {"stage": "hulls", "dataset": "t", "units": "metres, m2"}
    write_table(to_table(cluster), out / "hulls.parquet", metadata=meta)
    write_table(to_table(convex), out / "convex_hulls.parquet", metadata=meta)
    walls, status = extract_walls(pq.read_table(registered).to_pandas(), extractor, WALLS_CFG)
    meta = {"dataset": "t", "extractor": extractor, "units": "metres, map frame"}
    write_table(walls, out / "per_scan.parquet", schema=WALLS, metadata=meta)
    write_table(status, out / "scan_status.parquet", schema=SCAN_STATUS, metadata=meta)
    return counts


def sharded(registered, registration, out: Path, shard_scans: int, extractor: str):
    """The workflow's jobs: the plan (what the Snakefile computes once the register
    checkpoint has ended), one job per shard, merge (hulls; walls, with its k tables);
    real scripts."""
    res = {"registered": str(registered), "registration": str(registration)}
    merge_logs = {}
    labels = [s["label"] for s in plan_from_files(registration, registered, shard_scans)["shards"]]
    shard = lambda stage, lb, name: str(out / "shards" / stage / lb / f"{name}.parquet")  # noqa: E731
    for lb in labels:
        run_script("hulls_shard.py", out, "hulls_shard", res,
                   {"hulls": shard("hulls", lb, "hulls"), "convex": shard("hulls", lb, "convex_hulls")},
                   {"cfg": {}}, {"dataset": "t", "shard": lb})
        run_script("scan_walls_shard.py", out, "scan_walls_shard", {"points": str(registered)},
                   {"walls": shard("scan_walls", lb, "per_scan"), "status": shard("scan_walls", lb, "scan_status")},
                   {"cfg": WALLS_CFG}, {"dataset": "t", "extractor": extractor, "shard": lb})
    # rule select merges the hull shards and orders the scans
    orderings = [str(out / "orderings" / f"{o}.parquet") for o in ORDERINGS]
    merge_logs["hulls"] = run_script(
        "select.py", out, "select",
        {"shard_hulls": [shard("hulls", lb, "hulls") for lb in labels],
         "shard_convex": [shard("hulls", lb, "convex_hulls") for lb in labels], **res},
        {"hulls": str(out / "hulls.parquet"), "convex": str(out / "convex_hulls.parquet"),
         "orderings": orderings, "summary": str(out / "orderings" / "summary.parquet")},
        params={"cfg": {}, "shard_scans": shard_scans}, wildcards={"dataset": "t"})
    # rule scan_walls merges the wall shards; rule walls cuts the first k scans of each ordering
    merge_logs["scan_walls"] = run_script(
        "scan_walls.py", out, "scan_walls",
        {"shard_walls": [shard("scan_walls", lb, "per_scan") for lb in labels],
         "shard_status": [shard("scan_walls", lb, "scan_status") for lb in labels], **res},
        {"walls": str(out / "per_scan.parquet"), "status": str(out / "scan_status.parquet")},
        params={"shard_scans": shard_scans}, wildcards={"dataset": "t", "extractor": extractor})
    ordering = out / "orderings" / "sequential.parquet"  # select's: the kept scans in id order
    tables = [str(out / "walls" / "sequential" / extractor / f"k{k}.parquet") for k in ("5", "all")]
    run_script(
        "walls.py", out, "walls", {"walls": str(out / "per_scan.parquet"), "orderings": [str(ordering)]},
        {"tables": tables}, params={"run": {"orderings": ["sequential"], "k": ["5", "all"]}},
        wildcards={"dataset": "t", "extractor": extractor})
    return labels, merge_logs


def md5(path: Path) -> str:
    return hashlib.md5(path.read_bytes()).hexdigest()


def assert_identical(a: Path, b: Path):
    for name in ("hulls.parquet", "convex_hulls.parquet", "per_scan.parquet"):
        assert md5(a / name) == md5(b / name), name
    sa, sb = pq.read_table(a / "scan_status.parquet"), pq.read_table(b / "scan_status.parquet")
    cols = [c for c in sa.column_names if c != "time_s"]  # wall-clock time of each scan
    assert sa.select(cols).equals(sb.select(cols))
    assert sa.schema.equals(sb.schema, check_metadata=True)


def write_inputs(tmp: Path, points: pd.DataFrame, registration: pd.DataFrame):
    write_table(points, tmp / "registered.parquet", schema=REGISTERED)
    write_table(registration, tmp / "registration.parquet")
    return tmp / "registered.parquet", tmp / "registration.parquet"


def rooms_recording(seed=0):
    """40 scans of a 6 m x 4 m room with a 2 m x 2 m alcove, 2D (z = 0), map frame.

    Scans 3, 11 and 30 are dropped by "registration" (30's points are still in the
    points table: hulls ignores them), 17 is kept without points, 25 has 8 points.
    """
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 1, 150)
    walls = [((0, 0), (6, 0)), ((6, 0), (6, 4)), ((6, 4), (2, 4)), ((2, 4), (2, 6)), ((2, 6), (0, 6)), ((0, 6), (0, 0))]
    room = np.vstack([np.outer(1 - t, a) + np.outer(t, b) for a, b in walls])
    parts = []
    for s in range(40):
        if s in (3, 11, 17):
            continue
        view = room[rng.random(len(room)) < 0.6]
        view = view + rng.normal(0, 0.01, (1, 2)) + rng.normal(0, 0.005, view.shape)  # pose error, noise
        if s == 25:
            view = view[:8]
        parts.append(pd.DataFrame({"scan_id": s, "x": view[:, 0], "y": view[:, 1], "z": 0.0}))
    points = pd.concat(parts, ignore_index=True)
    return points, registration_table(40, set(range(40)) - {3, 11, 30})


@pytest.mark.parametrize("shard_scans", [0, 7, 13])
def test_sharded_scripts_write_the_unsharded_files(tmp_path, shard_scans):
    points, registration = rooms_recording()
    registered, reg = write_inputs(tmp_path, points, registration)
    (tmp_path / "one").mkdir()
    counts = unsharded(registered, reg, tmp_path / "one", "ransac")
    labels, logs = sharded(registered, reg, tmp_path / "many", shard_scans, "ransac")
    assert len(labels) == (1 if shard_scans == 0 else math.ceil(37 / shard_scans))
    assert_identical(tmp_path / "one", tmp_path / "many")
    # the drop counts of hulls survive the merge: kept scan 17 without points, the 150-odd
    # points of dropped scan 30 ignored; scan 25's 8 points give no wall (reason kept)
    assert counts["n_no_points"] == 1 and counts["n_points_ignored"] > 50 and counts["n_scans"] == 37
    assert f"hulls: {counts} from {len(labels)} shards" in logs["hulls"]
    status = pq.read_table(tmp_path / "many" / "scan_status.parquet").to_pandas().set_index("scan_id")
    assert status.loc[25, "reason"] == "too_few_points" and status.loc[25, "n_walls"] == 0
    assert "'too_few_points': 1" in logs["scan_walls"]
    walls = pq.read_table(tmp_path / "many" / "per_scan.parquet").to_pandas()
    assert len(walls) > 4 * 35 and walls.groupby("scan_id").size().index.is_monotonic_increasing
    # the walls job's k tables: all kept scans in the sequential ordering are the walls
    # of the kept scans (dropped scan 30's points, in the points table, have walls too)
    k_dir = tmp_path / "many" / "walls" / "sequential" / "ransac"
    kall = pq.read_table(k_dir / "kall.parquet").to_pandas()
    assert (walls["scan_id"] == 30).sum() > 0
    assert kall.equals(walls[walls["scan_id"] != 30].reset_index(drop=True))
    first5 = sorted(status.index)[:5]
    assert pq.read_table(k_dir / "k5.parquet").to_pandas()["scan_id"].unique().tolist() == [
        s for s in first5 if (walls["scan_id"] == s).any()
    ]


@needs_shared
@pytest.mark.realdata
def test_sharded_equals_unsharded_on_a_real_recording(tmp_path):
    """Orebro (Radish), first 30 scans in the map frame of the log's corrected poses,
    every fifth scan dropped; both extractors."""
    from floorscan.ingest.carmen import parse_carmen

    scans, _ = parse_carmen(SHARED_DATA / "radish" / "orebro-corrected.log.gz", max_range_m=32.0)
    parts = []
    for s, scan in enumerate(scans[:30]):
        x, y, th = scan["pose"]
        p = scan["points"].astype(np.float64)
        c, si = np.cos(th), np.sin(th)
        parts.append(pd.DataFrame({"scan_id": s, "x": x + c * p[:, 0] - si * p[:, 1],
                                   "y": y + si * p[:, 0] + c * p[:, 1], "z": 0.0}))
    points = pd.concat(parts, ignore_index=True)
    kept = {s for s in range(30) if s % 5 != 4}
    points = points[points["scan_id"].isin(kept)]
    registered, reg = write_inputs(tmp_path, points, registration_table(30, kept))
    for extractor in ("ransac", "cluster_ransac"):
        out = tmp_path / extractor
        (out / "one").mkdir(parents=True)
        unsharded(registered, reg, out / "one", extractor)
        labels, _ = sharded(registered, reg, out / "many", 10, extractor)
        assert len(labels) == 3  # 24 kept scans
        assert_identical(out / "one", out / "many")
    assert len(pq.read_table(tmp_path / "ransac" / "one" / "per_scan.parquet")) > 24

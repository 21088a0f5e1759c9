"""floorscan.core.io: the points writer (row groups written in a thread) and reader."""

import numpy as np
import pyarrow.parquet as pq
import pytest

from floorscan.core.io import SCANS, ScanRowGroups, iter_scans, parquet_options


def _scans(n=7, seed=0):
    rng = np.random.default_rng(seed)
    return [(sid, rng.normal(size=(int(rng.integers(1, 9)), 3))) for sid in range(n)]


def test_row_groups_written_in_a_thread_read_back_in_order(tmp_path):
    scans = _scans()
    path = tmp_path / "s.parquet"
    with pq.ParquetWriter(path, SCANS, **parquet_options(SCANS)) as writer:
        with ScanRowGroups(writer, rows=10) as out:
            for sid, pts in scans:
                out.add(sid, pts)
    meta = pq.ParquetFile(path).metadata
    assert meta.num_rows == sum(len(p) for _, p in scans)
    assert meta.num_row_groups == 3  # 10+ points per group, the rest last
    back = list(iter_scans(path))
    assert [s for s, _ in back] == [s for s, _ in scans]
    for (_, a), (_, b) in zip(back, scans):
        np.testing.assert_array_equal(a, b.astype(np.float32))


def test_points_tables_without_float_statistics_keep_those_of_scan_id(tmp_path):
    """parquet_options(schema, ["scan_id"]), as the ingest stage writes scans.parquet:
    no min/max for x, y, z (40 % of the writing); scan_id keeps them, which scan
    ranges use to skip row groups."""
    scans = _scans(12, seed=1)
    path = tmp_path / "s.parquet"
    with pq.ParquetWriter(path, SCANS, **parquet_options(SCANS, ["scan_id"])) as writer:
        with ScanRowGroups(writer, rows=10) as out:
            for sid, pts in scans:
                out.add(sid, pts)
    meta = pq.ParquetFile(path).metadata
    assert meta.num_row_groups > 3
    assert [meta.row_group(0).column(i).is_stats_set for i in range(4)] == [True, False, False, False]
    first = meta.row_group(0).column(0).statistics.max
    back = list(iter_scans(path, scan_range=(first + 1, 11)))
    assert [s for s, _ in back] == list(range(first + 1, 12))
    for (_, a), (_, b) in zip(back, scans[first + 1:]):
        np.testing.assert_array_equal(a, b.astype(np.float32))


class _FailingWriter:
    schema = SCANS

    def __init__(self):
        self.calls = 0

    def write_table(self, table, row_group_size):
        self.calls += 1
        raise OSError("disk full")


def test_a_failed_background_write_is_raised_at_the_next_row_group_or_the_end():
    w = _FailingWriter()
    with pytest.raises(OSError, match="disk full"):
        with ScanRowGroups(w, rows=4) as out:
            for sid, pts in _scans(50):
                out.add(sid, pts)
    assert w.calls == 1  # nothing written after the failure
    with pytest.raises(OSError, match="disk full"):
        with ScanRowGroups(_FailingWriter(), rows=1000) as out:
            out.add(0, np.zeros((3, 3)))


def test_an_error_of_the_caller_waits_for_the_row_group_in_the_thread(tmp_path):
    path = tmp_path / "s.parquet"
    with pytest.raises(ValueError, match="bad scan"):
        with pq.ParquetWriter(path, SCANS, **parquet_options(SCANS)) as writer:
            with ScanRowGroups(writer, rows=4) as out:
                for sid, pts in _scans(20):
                    out.add(sid, pts)
                raise ValueError("bad scan")
    # the writer closed after the thread's last row group: a readable file
    assert pq.ParquetFile(path).metadata.num_rows > 0


# ------------------------------------- issue 24: temporaries left by a killed run


def _stale(folder, *names):
    for name in names:
        p = folder / name
        if name.endswith("/"):
            p.mkdir()
            (p / "half.bag").write_bytes(b"half")
        else:
            p.write_bytes(b"half a file")
    return [folder / n.rstrip("/") for n in names]


def test_a_writer_removes_the_temporaries_a_killed_writer_left(tmp_path):
    """SIGKILL leaves atomic_path's `.<name>.<8 characters>.tmp`: the next write of the
    same file removes it; another file's temporaries and other names stay (the register
    stage's `.registered.parquet.sampled.parquet` is in use while registered.parquet
    is written)."""
    import pandas as pd

    from floorscan.core.io import write_table

    stale, other, sampled = _stale(tmp_path, ".t.parquet.k3x_9a0q.tmp", ".u.parquet.k3x_9a0q.tmp",
                                   ".t.parquet.sampled.parquet")
    write_table(pd.DataFrame({"a": [1, 2]}), tmp_path / "t.parquet")
    assert not stale.exists() and other.exists() and sampled.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == [".t.parquet.sampled.parquet", ".u.parquet.k3x_9a0q.tmp", "t.parquet"]


def test_a_stage_removes_the_temporaries_of_its_outputs_before_it_runs(tmp_path):
    """Every temporary name a writer of the outputs uses (atomic_path's files, the
    staged folders of the deliverables and the simulator, the register stage's copy of
    the sampled scans) is removed when the stage starts, and logged; the temporaries of
    other files stay."""
    from types import SimpleNamespace

    from floorscan.core.files import stale_temporaries
    from floorscan.core.stage import stage_log

    gone = _stale(tmp_path, ".registered.parquet.sampled.parquet", ".registered.parquet.0a1b2c3d.tmp",
                  ".recording.abcdefgh.tmp/", ".pcd.zz_yy_xx.old/")
    kept = _stale(tmp_path, ".registration.parquet.x.tmp", ".other.parquet.0a1b2c3d.tmp", ".registered.parquetx.tmp")
    outputs = {"registered": str(tmp_path / "registered.parquet"), "recording": str(tmp_path / "recording"),
               "pcd": str(tmp_path / "pcd")}
    smk = SimpleNamespace(rule="register", log=[str(tmp_path / "register.log")], wildcards={}, output=outputs)
    assert stale_temporaries(tmp_path / "registered.parquet") == sorted(gone[:2])
    with stage_log(smk):
        assert not any(p.exists() for p in gone)
    assert all(p.exists() for p in kept)
    log = (tmp_path / "register.log").read_text()
    assert log.count("left by an earlier run that was killed") == 4

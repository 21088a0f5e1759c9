"""floorscan.io: the points writer (row groups written in a thread) and reader."""

import numpy as np
import pyarrow.parquet as pq
import pytest

from floorscan.io import SCANS, ScanRowGroups, iter_scans, parquet_options


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

"""The pipeline benchmark's account of how many jobs ran at once (benchmarks/bench_pipeline.py)."""

from __future__ import annotations

import pytest

from benchmarks.bench_pipeline import concurrency


def test_seconds_with_no_job_one_and_two_and_the_stretches_of_one_alone():
    # a runs 0-5 s, b 2-8 s, c 10-12 s, the run 13 s: none 8-10 and 12-13, one 0-2, 5-8
    # and 10-12, two 2-5
    got = concurrency([["a", 0.0, 5.0], ["b", 2.0, 8.0], ["c", 10.0, 12.0]], 13.0, longest=2)
    assert got["seconds"] == pytest.approx({0: 3.0, 1: 7.0, 2: 3.0})
    assert got["alone"] == [(5.0, 8.0, "b"), (0.0, 2.0, "a")]


def test_two_jobs_of_one_script_in_a_row_are_one_stretch_and_no_job_is_all_idle():
    got = concurrency([["score", 0.0, 4.0], ["score", 4.0, 6.0]], 6.0)
    assert got["seconds"] == pytest.approx({0: 0.0, 1: 6.0, 2: 0.0})
    assert got["alone"] == [(0.0, 6.0, "score")]
    assert concurrency([], 3.0) == {"seconds": {0: 3.0, 1: 0.0, 2: 0.0}, "alone": []}

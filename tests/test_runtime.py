"""Progress lines of long stages (floorscan.core.runtime.progress)."""

import logging

from floorscan.core.runtime import progress


class FakeClock:
    def __init__(self, step):
        self.t, self.step = 0.0, step

    def __call__(self):
        self.t += self.step
        return self.t


def test_progress_logs_every_interval_with_count_rate_and_percentage(caplog):
    log = logging.getLogger("test.progress")
    with caplog.at_level(logging.INFO, logger="test.progress"):
        # the clock advances 1 s a call: one call at the start, one per item, one at the end
        out = list(progress(range(12), log, total=12, what="scans", every_s=5.0, clock=FakeClock(1.0)))
    assert out == list(range(12))
    lines = [r.getMessage() for r in caplog.records]
    # lines at items 5 and 10 (5 s and 10 s after the start), then the closing line at 13 s
    assert lines == [
        "progress: 5 of 12 scans (42 %) in 5.0 s, 1.0 scans/s",
        "progress: 10 of 12 scans (83 %) in 10.0 s, 1.0 scans/s",
        "progress: 12 of 12 scans (100 %) in 13.0 s, 0.9 scans/s, done",
    ]


def test_progress_is_silent_for_short_loops_and_without_a_logger(caplog):
    log = logging.getLogger("test.progress")
    with caplog.at_level(logging.INFO, logger="test.progress"):
        assert list(progress(iter("abc"), log, what="plans", clock=FakeClock(0.1))) == ["a", "b", "c"]
        assert list(progress([1, 2], None)) == [1, 2]
    assert caplog.records == []

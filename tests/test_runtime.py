"""Progress lines of long stages (floorscan.core.runtime.progress) and the allocator's
freed memory kept (floorscan.core.runtime.keep_freed_memory)."""

import logging
import sys
from pathlib import Path

import pytest

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


#: Run in a fresh interpreter: the test process's heap holds the free memory of the tests
#: before it, where a 48 MB array may fit whatever the setting.
_KEPT = """
import ctypes, sys
import numpy as np
from floorscan.core.runtime import keep_freed_memory

class MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in
                ("arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks", "fordblks",
                 "keepcost")]

libc = ctypes.CDLL("libc.so.6")
libc.mallinfo2.restype = MallInfo2
if sys.argv[1] == "keep":
    assert keep_freed_memory()
size = 48 * 2**20
a = np.ones(size, dtype=np.uint8)
own = libc.mallinfo2().hblkhd >= size  # a block of its own
del a
print(own, libc.mallinfo2().fordblks >= size)  # kept, free
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt: Linux only")
def test_freed_large_arrays_stay_in_the_heap_for_the_next_ones():
    """After :func:`keep_freed_memory`, a freed 48 MB array (above glibc's largest
    default mapping threshold, 32 MB) stays in the heap as free memory, where the next
    array of its size is taken from, instead of going back to the kernel; without it,
    the array is a mapping of its own and goes back."""
    import subprocess

    def run(how: str) -> str:
        return subprocess.run([sys.executable, "-c", _KEPT, how], capture_output=True, text=True, check=True,
                              cwd=Path(__file__).resolve().parents[1]).stdout

    assert run("keep") == "False True\n"
    assert run("default") == "True False\n"

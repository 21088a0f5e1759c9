"""Run-time helpers shared by the stages: progress lines in a stage's log.

A stage that takes more than a few seconds wraps its main loop in :func:`progress`, so
its log (and the terminal, through :func:`floorscan.core.stage.stage_log`) says how far it
is and how fast it goes, at most every ``every_s`` seconds::

    for scan_id, xyz in progress(iter_scans(path), log, total=n, what="scans"):
        ...
"""

from __future__ import annotations

import logging
import time
from typing import Callable, Iterable, Iterator, TypeVar

T = TypeVar("T")

#: Seconds between two progress lines of a stage.
PROGRESS_EVERY_S = 5.0


def progress(
    items: Iterable[T],
    log: logging.Logger | None,
    total: int | None = None,
    what: str = "scans",
    every_s: float = PROGRESS_EVERY_S,
    clock: Callable[[], float] = time.monotonic,
) -> Iterator[T]:
    """Yield ``items`` unchanged, logging ``done / total what (percent), rate`` at most
    every ``every_s`` seconds, and a last line with the count and rate when the items
    end after at least one progress line.

    Parameters
    ----------
    items : iterable
        The work items (scans, plans, ...), consumed lazily.
    log : logging.Logger or None
        Where the lines go; None yields the items without logging.
    total : int, optional
        The number of items, when known (the line then gives the percentage).
    what : str
        The items' name in the line ("scans").
    every_s : float
        Least seconds between two lines.
    clock : callable
        Seconds, monotonic (tests pass a fake clock).

    Yields
    ------
    The items of ``items``, in order.
    """
    if log is None:
        yield from items
        return
    t0 = last = clock()
    done = 0
    lines = 0
    for item in items:
        yield item
        done += 1
        now = clock()
        if now - last >= every_s:
            last = now
            lines += 1
            log.info("progress: %s", _line(done, total, what, now - t0))
    if lines:
        log.info("progress: %s, done", _line(done, total, what, clock() - t0))


def _line(done: int, total: int | None, what: str, seconds: float) -> str:
    rate = done / seconds if seconds > 0 else float("inf")
    of = f" of {total} {what} ({100.0 * done / total:.0f} %)" if total else f" {what}"
    return f"{done}{of} in {seconds:.1f} s, {rate:.1f} {what}/s"

"""Run-time helpers shared by the stages: progress lines in a stage's log, worker
processes, Open3D's OpenMP threads, and how the C allocator hands back freed memory
(:func:`keep_freed_memory`).

A stage that takes more than a few seconds wraps its main loop in :func:`progress`, so
its log (and the terminal, through :func:`floorscan.core.stage.stage_log`) says how far it
is and how fast it goes, at most every ``every_s`` seconds::

    for scan_id, xyz in progress(iter_scans(path), log, total=n, what="scans"):
        ...

A stage runs independent calls in the processes its Snakemake rule's ``threads`` give
it with the standard library's :class:`concurrent.futures.ProcessPoolExecutor`::

    rows = map_in_processes(fn, calls, workers)        # a pool for this one map
    with process_pool(workers, preload=("open3d",)) as pool:
        start_workers(pool, workers)                   # their imports overlap our work
        future = pool.submit(fn, *args)                # ... one pool for the whole job

The workers are spawned, not forked: Open3D's and scikit-learn's OpenMP runtimes are not
safe across ``fork``. A spawned worker imports the parent's main module again (as
``__mp_main__``), so a stage script that reaches a pool keeps its work under
``if __name__ == "__main__":`` (Snakemake runs a ``script:`` as ``__main__``). A worker
takes about a second to start (interpreter and imports): start one pool per job and give
each call at least a second of work.
"""

from __future__ import annotations

import functools
import importlib
import logging
import multiprocessing
import time
from concurrent.futures import Executor, ProcessPoolExecutor
from typing import Any, Callable, Iterable, Iterator, Sequence, TypeVar

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


# --------------------------------------------------------------------------- memory

#: glibc's ``mallopt`` parameters (``malloc.h``): ``M_TRIM_THRESHOLD`` and ``M_MMAP_THRESHOLD``.
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
#: Blocks at least this large are mapped from the kernel on their own, bytes: the
#: temporaries of one scan's rays and a plan's rasters of a large site (a 200 m x 200 m
#: floor at 5 cm is 16 M cells, 128 MB in float64) come from the heap.
MMAP_THRESHOLD_BYTES = 256 * 2**20
#: Free memory at the top of the heap is handed back to the kernel above this, bytes:
#: what one such raster and its temporaries need stays for the next plan.
TRIM_THRESHOLD_BYTES = 256 * 2**20


def keep_freed_memory() -> bool:
    """Keep the memory of freed large arrays in the process for the next ones (glibc).

    By default glibc maps each block above a threshold (128 kB, raised to the size of
    each larger block freed, up to 32 MB) from the kernel on its own, and hands free
    memory at the top of its heap back above twice that; a loop that allocates and
    frees the same large NumPy temporaries on every pass (the ray casting of each scan,
    each plan's rasters) then has the kernel map and zero their pages anew each time.
    With blocks up to :data:`MMAP_THRESHOLD_BYTES` taken from the heap, and up to
    :data:`TRIM_THRESHOLD_BYTES` of its free top kept, the pages are reused
    (measured in ``benchmarks/README.md``). The results are the same bytes. The cost
    is memory: a job keeps up to :data:`TRIM_THRESHOLD_BYTES` of freed memory at the
    top of its heap, and the blocks freed below it, for its next arrays. Called at the
    start of every stage (:func:`floorscan.core.stage.stage_log`) and of every worker
    process (:func:`process_pool`).

    Source: glibc's ``mallopt(3)``.

    Returns
    -------
    bool
        Whether both settings took (False off glibc: another C library keeps its own
        policy).
    """
    import ctypes
    import sys

    if not sys.platform.startswith("linux"):
        return False
    try:
        mallopt = ctypes.CDLL("libc.so.6").mallopt
    except (OSError, AttributeError):  # musl and others: no glibc
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    return bool(mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES)) & bool(mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD_BYTES))


# --------------------------------------------------------------------------- processes


def process_pool(workers: int, preload: Sequence[str] = ()) -> ProcessPoolExecutor:
    """A pool of ``workers`` spawned worker processes, each importing the ``preload``
    modules before its first call (the pool starts a worker at a call that finds none
    idle; :func:`start_workers` starts them ahead).

    Parameters
    ----------
    workers : int
        Worker processes (at least 1).
    preload : sequence of str
        Module names each worker imports when it starts.

    Returns
    -------
    concurrent.futures.ProcessPoolExecutor
        To be shut down by the caller (``with`` block or ``shutdown()``).
    """
    return ProcessPoolExecutor(
        max_workers=max(1, int(workers)),
        mp_context=multiprocessing.get_context("spawn"),
        initializer=_import_modules,
        initargs=(tuple(preload),),
    )


def _import_modules(names: tuple[str, ...]) -> None:
    keep_freed_memory()
    for name in names:
        importlib.import_module(name)


def _nothing() -> None:
    return None


def start_workers(pool: ProcessPoolExecutor, n: int) -> None:
    """Start ``n`` workers of ``pool`` now, so that their start-up (interpreter, main
    module, ``preload``) overlaps the caller's work instead of delaying the first
    results: ``n`` empty calls, each finding no idle worker, start one each.

    Parameters
    ----------
    pool : concurrent.futures.ProcessPoolExecutor
    n : int
        Workers to start; 0 or less starts none.
    """
    for _ in range(max(0, int(n))):
        pool.submit(_nothing)


def map_in_processes(fn: Callable, calls: Sequence[tuple], workers: int = 1,
                     pool: Executor | None = None) -> list[Any]:
    """``[fn(*args) for args in calls]`` in worker processes.

    With ``pool``, every call runs in it. Without, the first call runs here and the
    others in a pool of ``min(workers, len(calls)) - 1`` processes made for this map (a
    process fewer to start); with one worker or one call, every call runs here.

    Parameters
    ----------
    fn : callable
        A module-level function (the workers import it by module and name); its
        arguments and result must pickle.
    calls : sequence of tuple
        Positional arguments of each call.
    workers : int
        Processes to use, this one included (the rule's ``threads``).
    pool : concurrent.futures.Executor, optional
        A pool to run every call in (:func:`process_pool`).

    Returns
    -------
    list
        The results, in the order of ``calls``.

    Raises
    ------
    Exception
        The first failed call's exception, raised again here with its message (a
        worker's traceback is attached as its ``__cause__``);
        :class:`concurrent.futures.process.BrokenProcessPool` when a worker died.
    """
    calls = list(calls)
    if pool is not None:
        futures = [pool.submit(fn, *args) for args in calls]
        return [f.result() for f in futures]
    n = min(int(workers), len(calls)) - 1
    if n < 1:
        return [fn(*args) for args in calls]
    with process_pool(n) as own:
        futures = [own.submit(fn, *args) for args in calls[1:]]
        try:
            first = fn(*calls[0])
            return [first] + [f.result() for f in futures]
        except BaseException:
            own.shutdown(wait=True, cancel_futures=True)
            raise


# --------------------------------------------------------------------------- threads


def one_openmp_thread():
    """Context: Open3D's OpenMP loops on one thread (threadpoolctl, a scikit-learn
    dependency). Its multi-threaded reductions sum in varying order, so results (the
    pose graph) would differ from run to run in the last bits (same input, same output
    is a house rule); and on the 2-core target one thread costs less CPU. The
    controller is made once: ``threadpool_limits`` scans the loaded libraries on every
    call.

    Returns
    -------
    context manager
        threadpoolctl's limit; leaving it restores the thread count.
    """
    return _openmp_controller().limit(limits=1, user_api="openmp")


@functools.lru_cache(maxsize=1)
def _openmp_controller():
    import open3d as o3d  # noqa: F401  (its OpenMP runtime must be loaded before the scan)
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()

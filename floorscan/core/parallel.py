"""Independent calls of one function in worker processes (issue 8: a stage uses the
cores its Snakemake rule's ``threads`` give it).

Each worker is a fresh interpreter (``python -c ...``) that reads one pickled call on
stdin and writes its pickled result on stdout. Not ``fork``: Open3D's and
scikit-learn's OpenMP runtimes are not safe across fork. Not ``multiprocessing``'s
``spawn`` either: it re-runs the parent's main script in every worker, and a Snakemake
stage script has no ``if __name__ == "__main__"`` guard. A worker costs ~1 s to start
(interpreter and imports), so callers give each at least a second of work, or start
it ahead with :func:`prestart`.
"""

from __future__ import annotations

import atexit
import importlib
import pickle
import subprocess
import sys
import tempfile
from typing import Any, Callable, Sequence

_WORKER = "from floorscan.core.parallel import _worker; _worker()"

#: Workers started ahead by :func:`prestart`, waiting for their call on stdin.
_READY: list[tuple[subprocess.Popen, Any]] = []


def prestart(n: int, preload: Sequence[str] = ()) -> int:
    """Start ``n`` workers now, importing ``preload`` modules, for the next
    :func:`map_in_processes` call, so their start-up (~1-3 s with Open3D) overlaps
    the caller's work instead of delaying the results.

    Workers not used by the time the interpreter exits are stopped. Returns the
    number of workers waiting.

    Parameters
    ----------
    n : int
        Workers to start (none when ``n <= 0``).
    preload : sequence of str
        Module names each worker imports before it waits for its call.
    """
    for _ in range(max(0, int(n))):
        _READY.append(_spawn(preload))
    return len(_READY)


def ready() -> int:
    """Workers started by :func:`prestart` and not used yet."""
    return len(_READY)


def _spawn(preload: Sequence[str] = ()) -> tuple[subprocess.Popen, Any]:
    err = tempfile.TemporaryFile()  # a file, not a pipe: it never fills up
    code = "".join(f"import {m}; " for m in preload) + _WORKER
    proc = subprocess.Popen(
        [sys.executable, "-c", code], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=err,
    )
    return proc, err


@atexit.register
def _stop_ready() -> None:
    while _READY:
        proc, err = _READY.pop()
        proc.kill()
        proc.wait()
        err.close()


def map_in_processes(fn: Callable, calls: Sequence[tuple], local_first: bool | None = None) -> list[Any]:
    """``[fn(*args) for args in calls]``, the first call here and the others each in a
    worker process, all at once.

    Parameters
    ----------
    fn : callable
        A module-level function (found again by module and name in the worker); its
        arguments and result must pickle.
    calls : sequence of tuple
        Positional arguments of each call.
    local_first : bool, optional
        Run the first call in this process (True) or every call in a worker (False).
        Default: in workers when workers started ahead (:func:`prestart`) wait for
        all the calls (they have imported what the calls need; this process may
        not have), else the first call here.

    Returns
    -------
    list
        The results, in the order of ``calls``.

    Raises
    ------
    RuntimeError
        A worker failed (its exit status and the last lines of its stderr).
    """
    calls = list(calls)
    if local_first is None:
        local_first = len(_READY) < len(calls)
    if len(calls) == 0 or (len(calls) == 1 and local_first):
        return [fn(*args) for args in calls]
    remote = calls[1:] if local_first else calls
    stream = CallStream(len(remote))  # a worker per call, started ahead ones first
    try:
        for w, args in enumerate(remote):
            stream.submit(w, fn, args)
        results = [fn(*calls[0])] if local_first else []
        return results + stream.results()
    finally:
        stream.close()


class CallStream:
    """Calls sent to worker processes as the caller produces them, each worker taking
    many calls in turn (:func:`map_in_processes` needs every call at once).

    :meth:`submit` returns at once: a thread per worker writes the calls to it and
    another reads its results, so the caller keeps working while the workers run
    (the register stage reads and screens scans while the pose graph's edges are
    aligned). Workers started ahead by :func:`prestart` are used first. A worker
    keeps its module state between calls (a cache of inputs sent before, say).

    Parameters
    ----------
    n : int
        Worker processes (at least 1).

    Raises
    ------
    RuntimeError
        From :meth:`results`: a worker failed (its exit status and the last lines
        of its stderr).
    """

    def __init__(self, n: int):
        import queue
        import threading

        self._n = max(1, int(n))
        self._procs: list[tuple[subprocess.Popen, Any]] = []
        self._outbox: list[Any] = []
        self._threads: list[threading.Thread] = []
        self._results: dict[int, Any] = {}
        self._submitted = 0
        self._what = "a call"  # the function last submitted, for error messages
        self.pending = [0] * self._n  # calls sent to each worker and not yet answered
        self._lock = threading.Lock()
        for w in range(self._n):
            proc, err = _READY.pop(0) if _READY else _spawn()
            self._procs.append((proc, err))
            box: queue.Queue = queue.Queue()
            self._outbox.append(box)
            order: queue.Queue = queue.Queue()  # call numbers, in the order this worker answers
            self._threads.append(threading.Thread(target=self._send, args=(proc, box, order), daemon=True))
            self._threads.append(threading.Thread(target=self._receive, args=(w, proc, order), daemon=True))
        for t in self._threads:
            t.start()

    def submit(self, worker: int, fn: Callable, args: tuple) -> int:
        """Queue ``fn(*args)`` for worker ``worker`` (0 .. n - 1); returns the call number.
        ``fn`` is module-level; arguments and result must pickle."""
        number = self._submitted
        self._submitted += 1
        self._what = f"{fn.__module__}.{fn.__qualname__}"
        with self._lock:
            self.pending[worker] += 1
        self._outbox[worker].put((number, pickle.dumps((fn.__module__, fn.__qualname__, args))))
        return number

    def least_busy(self) -> int:
        """The worker with the fewest unanswered calls."""
        with self._lock:
            return min(range(self._n), key=lambda w: self.pending[w])

    def _send(self, proc, box, order) -> None:
        while True:
            item = box.get()
            if item is None:
                break
            number, data = item
            order.put(number)
            try:
                proc.stdin.write(data)
                proc.stdin.flush()
            except (BrokenPipeError, ValueError):  # it died: reported by results()
                break
        try:
            proc.stdin.close()
        except (BrokenPipeError, ValueError):
            pass
        order.put(None)

    def _receive(self, w: int, proc, order) -> None:
        while True:
            number = order.get()
            if number is None:
                return
            try:
                result = pickle.load(proc.stdout)
            except Exception:  # EOF or garbage: the worker failed; results() reports it
                return
            self._results[number] = result
            with self._lock:
                self.pending[w] -= 1

    def results(self) -> list[Any]:
        """Wait for every call; their results in submission order. Ends the workers."""
        try:
            for box in self._outbox:
                box.put(None)
            for t in self._threads:
                t.join()
            for (proc, err), box in zip(self._procs, self._outbox):
                if proc.wait() != 0:
                    err.seek(0)
                    tail = "\n".join(err.read().decode(errors="replace").strip().splitlines()[-5:])
                    raise RuntimeError(f"{self._what} in a worker process exited with {proc.returncode}:\n{tail}")
            missing = self._submitted - len(self._results)
            if missing:
                raise RuntimeError(f"{missing} of {self._submitted} calls got no result from the worker processes")
            return [self._results[k] for k in range(self._submitted)]
        finally:
            self.close()

    def close(self) -> None:
        """Stop the workers (results not collected are lost)."""
        for proc, err in self._procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
            err.close()
        self._procs = []


def _worker() -> None:
    """Worker entry point: pickled ``(module, name, args)`` calls on stdin, one after
    the other until it closes, each call's pickled result on stdout."""
    stdin, stdout = sys.stdin.buffer, sys.stdout.buffer
    while True:
        try:
            module, name, args = pickle.load(stdin)
        except EOFError:
            return
        fn = importlib.import_module(module)
        for part in name.split("."):
            fn = getattr(fn, part)
        stdout.write(pickle.dumps(fn(*args)))
        stdout.flush()

"""Independent calls of one function in worker processes (issue 8: a stage uses the
cores its Snakemake rule's ``threads`` give it).

Each worker is a fresh interpreter (``python -c ...``) that reads one pickled call on
stdin and writes its pickled result on stdout. Not ``fork``: Open3D's and
scikit-learn's OpenMP runtimes are not safe across fork. Not ``multiprocessing``'s
``spawn`` either: it re-runs the parent's main script in every worker, and a Snakemake
stage script has no ``if __name__ == "__main__"`` guard. A worker costs ~1 s to start
(interpreter and imports), so callers give each at least a second of work.
"""

from __future__ import annotations

import importlib
import pickle
import subprocess
import sys
import tempfile
from typing import Any, Callable, Sequence

_WORKER = "from floorscan.parallel import _worker; _worker()"


def map_in_processes(fn: Callable, calls: Sequence[tuple]) -> list[Any]:
    """``[fn(*args) for args in calls]``, the first call here and the others each in a
    worker process, all at once.

    Parameters
    ----------
    fn : callable
        A module-level function (found again by module and name in the worker); its
        arguments and result must pickle.
    calls : sequence of tuple
        Positional arguments of each call.

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
    if len(calls) <= 1:
        return [fn(*args) for args in calls]
    procs, errs = [], []
    try:
        for args in calls[1:]:
            errs.append(tempfile.TemporaryFile())  # a file, not a pipe: it never fills up
            proc = subprocess.Popen(
                [sys.executable, "-c", _WORKER], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=errs[-1],
            )
            proc.stdin.write(pickle.dumps((fn.__module__, fn.__qualname__, args)))
            proc.stdin.close()
            procs.append(proc)
        results = [fn(*calls[0])]
        for proc, err in zip(procs, errs):
            out = proc.stdout.read()
            if proc.wait() != 0:
                err.seek(0)
                tail = "\n".join(err.read().decode(errors="replace").strip().splitlines()[-5:])
                raise RuntimeError(f"{fn.__module__}.{fn.__qualname__} in a worker process exited with "
                                   f"{proc.returncode}:\n{tail}")
            results.append(pickle.loads(out))
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        for err in errs:
            err.close()
    return results


def _worker() -> None:
    """Worker entry point: one pickled ``(module, name, args)`` call on stdin, its
    pickled result on stdout."""
    module, name, args = pickle.load(sys.stdin.buffer)
    fn = importlib.import_module(module)
    for part in name.split("."):
        fn = getattr(fn, part)
    sys.stdout.buffer.write(pickle.dumps(fn(*args)))
    sys.stdout.buffer.flush()

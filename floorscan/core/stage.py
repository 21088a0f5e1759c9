"""Glue between Snakemake stage scripts and the package: logging and error reporting.

A stage script is thin::

    from floorscan.core.stage import stage_log
    with stage_log(snakemake) as log:
        ...  # read snakemake.input / params, call one package function, write outputs

Everything logged through :mod:`logging` goes to the rule's ``log:`` file and to
stderr. A failure goes to the log file alone, which Snakemake prints when the job
fails (``show-failed-logs`` of the default profile), so it is printed once:

- an expected error (:data:`EXPECTED_ERRORS`: bad input, a bad config value, a
  recording too poor to register) as one paragraph that names the user's recording,
  without a traceback; the script then exits with status 1 (``SystemExit``, which
  Python ends without a traceback);
- an error of the machine (:func:`floorscan.core.messages.system_error`: no space left
  on the device, a read-only file system, permission denied) as one paragraph that
  names the path and what to do, without a traceback, and exit status 1 likewise; when
  the log file cannot be written (the disk is full) the paragraph goes to stderr;
- any other exception (a bug) with its traceback, and re-raised: Python prints it.

A message quotes at most :data:`floorscan.core.messages.MAX_QUOTE` characters of a run
of the user's data (:func:`floorscan.core.messages.shorten_message`).

Either way the job fails and Snakemake removes its outputs. Before the stage runs,
temporaries of its outputs that a killed run left are removed
(:func:`floorscan.core.files.remove_stale_temporaries`), and the C allocator is told to
keep freed large arrays for the next ones (:func:`floorscan.core.runtime.keep_freed_memory`).

Profiling: with the environment variable ``FLOORSCAN_PROFILE`` set to a directory, each
stage's body runs under :mod:`cProfile` and its statistics are written there as
``<rule>[_<wildcard values>].prof`` (read them with :mod:`pstats` or snakeviz), e.g.
``FLOORSCAN_PROFILE=/tmp/prof snakemake --cores 2 --forcerun floorplan``.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
import time
from pathlib import Path
from typing import Any, Iterator

LOG_FORMAT = "%(asctime)s %(levelname)s %(name)s: %(message)s"

#: Exceptions that report bad input or a bad config, not a bug, as (module, class):
#: :class:`floorscan.core.io.InputError`, :class:`floorscan.core.config.ConfigError`,
#: :class:`floorscan.register.result.RegistrationError` (a recording too poor to
#: register). Looked up among the modules already imported, so none is imported here.
EXPECTED_ERRORS = (
    ("floorscan.core.io", "InputError"),
    ("floorscan.core.config", "ConfigError"),
    ("floorscan.register.result", "RegistrationError"),
)

#: ``extra`` of the failure record: the stderr handler leaves it to the log file.
_FAILURE = {"floorscan_failure": True}


class Interrupted(BaseException):
    """A stage stopped by SIGTERM (Snakemake stopping its jobs, a cluster's time limit),
    raised where it runs so that its log says so (:func:`stage_log`)."""


def _raise_on_sigterm():
    """Make SIGTERM raise :class:`Interrupted` in the main thread until the returned
    function restores the previous handler (a no-op off the main thread)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return lambda: None

    def handler(signum, frame):
        raise Interrupted(signal.Signals(signum).name)

    previous = signal.signal(signal.SIGTERM, handler)
    return lambda: signal.signal(signal.SIGTERM, previous)


def is_expected_error(exc: BaseException) -> bool:
    """Whether ``exc`` is one of :data:`EXPECTED_ERRORS` (or a subclass): an error of
    the input or config, reported without a traceback.

    Parameters
    ----------
    exc : BaseException

    Returns
    -------
    bool
    """
    classes = [getattr(sys.modules.get(module), cls, None) for module, cls in EXPECTED_ERRORS]
    return isinstance(exc, tuple(c for c in classes if isinstance(c, type)))


def failure_message(rule: str, exc: BaseException, source: str | os.PathLike | None = None) -> str:
    """The paragraph printed for an expected error of stage ``rule``.

    Parameters
    ----------
    rule : str
    exc : BaseException
        The error; its message names the file, topic or key and what was expected.
    source : path, optional
        An ingest table (``scan_index.parquet``, ...) whose metadata names the user's
        recording (:func:`floorscan.core.io.recording_source`): named in the paragraph when
        the message does not name it, so that a later stage's error points at the
        recording, not at an intermediate table.

    Returns
    -------
    str
        ``"<rule> failed: <message>"`` or ``"<rule> failed on <recording>: <message>"``.
    """
    from floorscan.core.messages import shorten_message

    message = shorten_message(str(exc).strip()) or type(exc).__name__
    recording = None
    if source is not None:
        from floorscan.core.io import recording_source

        recording = recording_source(source)
    if recording and recording.split()[0] not in message:
        return f"{rule} failed on {recording}: {message}"
    return f"{rule} failed: {message}"


def _outputs(smk: Any, what: str = "output") -> list[str]:
    """The job's output (or ``what``: input) paths (a Snakemake named list, or a mapping
    of names to paths)."""
    output = getattr(smk, what, None) or []
    values = output.values() if isinstance(output, dict) else output
    return [str(v) for v in values if isinstance(v, (str, os.PathLike))]


class _LogFile(logging.FileHandler):
    """The rule's log file; a record it cannot write (no space left) sets ``failed``
    instead of printing logging's own traceback, and the failure goes to stderr."""

    failed = False

    def handleError(self, record: logging.LogRecord) -> None:
        self.failed = True

    def close(self) -> None:
        try:
            super().close()
        except OSError:  # flushing to a full disk
            self.failed = True


def _log_file(path: str) -> _LogFile | None:
    """The handler of the rule's log file; None when it cannot be opened (a read-only
    or full disk): the stage then logs to stderr alone and its error says why."""
    try:
        return _LogFile(path, mode="w")
    except OSError:
        return None


@contextlib.contextmanager
def stage_log(smk: Any, name: str | None = None, source: str | os.PathLike | None = None) -> Iterator[logging.Logger]:
    """Route logging of a stage script to its Snakemake log file.

    Parameters
    ----------
    smk : snakemake.script.Snakemake
        The ``snakemake`` object of the script; ``smk.log[0]`` is the log file,
        ``smk.output`` the job's outputs (their stale temporaries are removed first).
    name : str, optional
        Logger name; defaults to ``floorscan.<rule>``.
    source : path, optional
        An ingest table whose metadata names the recording, for the message of an
        expected error (:func:`failure_message`).

    Yields
    ------
    logging.Logger
        The stage's logger.

    Raises
    ------
    SystemExit
        Status 1, for an error of :data:`EXPECTED_ERRORS` inside the block, logged as
        one paragraph (:func:`failure_message`) to the log file only (to stderr when
        there is none); the error is its ``__cause__``. Likewise for a system error
        (:func:`floorscan.core.messages.system_error`: no space left, a read-only file
        system, permission denied; raised, or the cause or context of the error
        raised), whose paragraph names the path (the ``OSError``'s
        file, else the folder of ``smk.output``) and what to do
        (:func:`floorscan.core.messages.system_error_message`), to stderr when the log
        file cannot take it.
    Exception
        Any other exception inside the block, logged with its traceback to the log file
        only (likewise), and re-raised. Either way Snakemake marks the job failed and
        removes its outputs.
    """
    from floorscan.core.files import remove_stale_temporaries
    from floorscan.core.runtime import keep_freed_memory

    keep_freed_memory()
    rule = getattr(smk, "rule", "stage")
    logger = logging.getLogger(name or f"floorscan.{rule}")
    root = logging.getLogger()
    root.setLevel(logging.INFO)
    stderr = logging.StreamHandler(sys.stderr)
    handlers: list[logging.Handler] = []
    if len(smk.log) > 0:
        log_file = _log_file(smk.log[0])
        if log_file is not None:
            handlers.append(log_file)
            # the failure goes to the log file alone, which Snakemake prints when the job
            # fails; to stderr when the file could not take it (handlers run in order)
            stderr.addFilter(lambda record: not getattr(record, "floorscan_failure", False) or log_file.failed)
    handlers.append(stderr)
    for h in handlers:
        h.setFormatter(logging.Formatter(LOG_FORMAT))
        root.addHandler(h)
    wildcards = dict(getattr(smk, "wildcards", {}).items()) if hasattr(smk, "wildcards") else {}
    # CPU time so far: the interpreter start and the script's imports
    logger.info("start %s %s (%.2f s CPU before the stage: start-up and imports)", rule, wildcards, time.process_time())
    for tmp, out in remove_stale_temporaries(_outputs(smk)):
        logger.info("removed %s, a temporary of %s left by an earlier run that was killed", tmp, out)
    t0, c0 = time.perf_counter(), time.process_time()
    profile_dir = os.environ.get("FLOORSCAN_PROFILE")
    profiler = None
    if profile_dir:
        import cProfile

        profiler = cProfile.Profile()
        profiler.enable()
    on_term = _raise_on_sigterm()
    try:
        yield logger
        logger.info("done %s in %.2f s (%.2f s CPU)", rule, time.perf_counter() - t0, time.process_time() - c0)
    except (KeyboardInterrupt, Interrupted) as e:
        how = "SIGINT (Ctrl-C)" if isinstance(e, KeyboardInterrupt) else "SIGTERM"
        logger.error("%s interrupted by %s after %.1f s: its outputs are not written; run the workflow again to go "
                     "on from here", rule, how, time.perf_counter() - t0, extra=_FAILURE)
        raise
    except Exception as e:
        from floorscan.core.messages import system_error, system_error_message

        # the machine's error, raised or wrapped (a reader's "cannot read the log" raised
        # from a PermissionError): named as such, not as bad input
        oserror = system_error(e)
        if oserror is not None:
            message = system_error_message(oserror, _outputs(smk, "input"), _outputs(smk))
            logger.error("%s failed: %s", rule, message, extra=_FAILURE)
            raise SystemExit(1) from e
        if not is_expected_error(e):
            logger.exception("stage %s failed", rule, extra=_FAILURE)
            raise
        logger.error("%s", failure_message(rule, e, source), extra=_FAILURE)
        raise SystemExit(1) from e
    finally:
        on_term()
        if profiler is not None:
            profiler.disable()
            stem = "_".join([str(rule), *(str(v) for v in wildcards.values())])
            Path(profile_dir).mkdir(parents=True, exist_ok=True)
            profiler.dump_stats(str(Path(profile_dir) / f"{stem}.prof"))
        for h in handlers:
            root.removeHandler(h)
            h.close()

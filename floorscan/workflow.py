"""Glue between Snakemake stage scripts and the package: logging and error reporting.

A stage script is thin::

    from floorscan.workflow import stage_log
    with stage_log(snakemake) as log:
        ...  # read snakemake.input / params, call one package function, write outputs

Everything logged through :mod:`logging` (and any exception with its traceback) goes
to the rule's ``log:`` file and to stderr.

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


@contextlib.contextmanager
def stage_log(smk: Any, name: str | None = None) -> Iterator[logging.Logger]:
    """Route logging of a stage script to its Snakemake log file.

    Parameters
    ----------
    smk : snakemake.script.Snakemake
        The ``snakemake`` object of the script; ``smk.log[0]`` is the log file.
    name : str, optional
        Logger name; defaults to ``floorscan.<rule>``.

    Yields
    ------
    logging.Logger
        The stage's logger. An exception inside the block is logged with its
        traceback and re-raised, so Snakemake marks the job failed and removes
        its outputs.
    """
    rule = getattr(smk, "rule", "stage")
    logger = logging.getLogger(name or f"floorscan.{rule}")
    root = logging.getLogger()
    root.setLevel(logging.INFO)
    handlers: list[logging.Handler] = [logging.StreamHandler(sys.stderr)]
    if len(smk.log) > 0:
        handlers.append(logging.FileHandler(smk.log[0], mode="w"))
    for h in handlers:
        h.setFormatter(logging.Formatter(LOG_FORMAT))
        root.addHandler(h)
    wildcards = dict(getattr(smk, "wildcards", {}).items()) if hasattr(smk, "wildcards") else {}
    # CPU time so far: the interpreter start and the script's imports
    logger.info("start %s %s (%.2f s CPU before the stage: start-up and imports)", rule, wildcards, time.process_time())
    t0, c0 = time.perf_counter(), time.process_time()
    profile_dir = os.environ.get("FLOORSCAN_PROFILE")
    profiler = None
    if profile_dir:
        import cProfile

        profiler = cProfile.Profile()
        profiler.enable()
    try:
        yield logger
        logger.info("done %s in %.2f s (%.2f s CPU)", rule, time.perf_counter() - t0, time.process_time() - c0)
    except Exception:
        logger.exception("stage %s failed", rule)
        raise
    finally:
        if profiler is not None:
            profiler.disable()
            stem = "_".join([str(rule), *(str(v) for v in wildcards.values())])
            Path(profile_dir).mkdir(parents=True, exist_ok=True)
            profiler.dump_stats(str(Path(profile_dir) / f"{stem}.prof"))
        for h in handlers:
            root.removeHandler(h)
            h.close()

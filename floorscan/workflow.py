"""Glue between Snakemake stage scripts and the package: logging and error reporting.

A stage script is thin::

    from floorscan.workflow import stage_log
    with stage_log(snakemake) as log:
        ...  # read snakemake.input / params, call one package function, write outputs

Everything logged through :mod:`logging` (and any exception with its traceback) goes
to the rule's ``log:`` file and to stderr.
"""

from __future__ import annotations

import contextlib
import logging
import sys
import time
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
    logger.info("start %s %s", rule, wildcards)
    t0 = time.perf_counter()
    try:
        yield logger
        logger.info("done %s in %.2f s", rule, time.perf_counter() - t0)
    except Exception:
        logger.exception("stage %s failed", rule)
        raise
    finally:
        for h in handlers:
            root.removeHandler(h)
            h.close()

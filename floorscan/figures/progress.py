"""What the ``floorscan`` command (:mod:`floorscan.cli`) shows while Snakemake runs, read
from Snakemake's output line by line: a line per finished job (n of N, its rule and
dataset, the time since the start), a failed job's own paragraph (the error its stage
wrote to its log, :func:`floorscan.figures.index_page.log_error`) and the workflow's
own messages; everything else stays in the run's log file. :func:`jobs_to_run` reads
the job table of a dry run.

Snakemake's output is text for people, not an interface: the patterns below are the
lines of Snakemake 9 (``rule x:`` with its ``jobid`` / ``wildcards`` / ``log`` fields,
``Finished jobid: 3 (Rule: x)``, ``4 of 12 steps (33%) done``, ``Error in rule x:``).
A line they do not match is kept in the log, not shown. The answer reads the run's files
(:mod:`floorscan.figures.run_end`); only a failed job whose stage logged no error is
named from these lines.
"""

from __future__ import annotations

import os
import re
import sys
import time
from pathlib import Path


def elapsed(seconds: float) -> str:
    """``7.3 s``, ``2 min 05 s``."""
    if seconds < 60:
        return f"{seconds:.1f} s"
    m, s = divmod(int(round(seconds)), 60)
    return f"{m} min {s:02d} s"


_JOB = re.compile(r"^(?:local)?(?:rule|checkpoint) (\w+):$")
_FIELD = re.compile(r"^    (jobid|wildcards|log): (.*)$")
_FINISHED = re.compile(r"^Finished jobid: (\d+) \(Rule: (\w+)\)")
_STEPS = re.compile(r"^(\d+) of (\d+) steps \(.*\) done")
_ERROR = re.compile(r"^Error in rule (\w+):$")
#: The workflow's own lines to the user (the Snakefile's, not Snakemake's).
_OWN = re.compile(r"^(Config error: |Cannot run: |.*: (?:\d+ recordings, one dataset each|1 recording, one dataset): )")


class Progress:
    """Reads Snakemake's log, line by line: prints a line per finished job, the failed
    jobs' own paragraphs and the workflow's messages; keeps the rest for the log file."""

    def __init__(self, repo: Path, out=None, start: float | None = None):
        self.repo, self.out = repo, out
        self.start = time.monotonic() if start is None else start
        self.jobs: dict[str, dict] = {}
        self.block: dict | None = None
        self.finished: str | None = None
        self.failures: list[dict] = []
        self.shown = 0  # lines shown besides progress: the workflow's messages, failures

    def _print(self, line: str) -> None:
        print(line, file=self.out or sys.stdout, flush=True)

    def feed(self, line: str) -> None:
        line = line.rstrip("\n")
        field = _FIELD.match(line)
        if field and self.block is not None:
            name, value = field.groups()
            if name == "jobid":
                self.block["jobid"] = value
                self.jobs[value] = self.block
            elif name == "wildcards":
                self.block["wildcards"] = dict(w.split("=", 1) for w in value.split(", ") if "=" in w)
            else:
                self.block["log"] = value.replace(" (check log file(s) for error details)", "").split(", ")
            return
        if line.startswith("    ") and self.block is not None:
            return
        self._end_block()
        m = _JOB.match(line)
        if m:
            self.block = {"rule": m.group(1)}
            return
        m = _ERROR.match(line)
        if m:
            self.block = {"rule": m.group(1), "error": True}
            return
        m = _FINISHED.match(line)
        if m:
            self.finished = m.group(1)
            self.jobs.setdefault(m.group(1), {"rule": m.group(2)})
            return
        m = _STEPS.match(line)
        if m and self.finished is not None:
            job = self.jobs.get(self.finished, {})
            self.finished = None
            ds = job_dataset(job)
            label = job.get("rule", "?") + (f" ({ds})" if ds else "")
            self._print(f"{m.group(1):>4} of {m.group(2):<4} {label:<44} {elapsed(time.monotonic() - self.start):>10}")
            return
        if _OWN.match(line):
            self.shown += 1
            self._print(line)

    def _end_block(self) -> None:
        block, self.block = self.block, None
        if block and block.get("error"):
            self.failures.append(block)
            self.shown += 1
            self._print(self.failure_text(block))

    def close(self) -> None:
        self._end_block()

    def failure_text(self, block: dict) -> str:
        """The failed job's paragraph from its log (the stage's own error)."""
        from floorscan.figures.index_page import log_error

        ds = job_dataset(block)
        head = f"FAILED {block['rule']}" + (f" ({ds})" if ds else "")
        for log in block.get("log") or []:
            path = self.repo / log
            text = log_error(path) if path.is_file() else None
            if text:
                return f"{head}: {text}\n  its log: {path}"
        logs = ", ".join(os.fspath(self.repo / p) for p in block.get("log") or [])
        return f"{head}" + (f"; its log: {logs}" if logs else "")


def job_dataset(job: dict) -> str | None:
    """A job's dataset: its wildcard, else the results/<dataset>/ of its log (an
    error's block names no wildcards)."""
    ds = (job.get("wildcards") or {}).get("dataset")
    for log in job.get("log") or [] if ds is None else []:
        m = re.match(r"^(?:\./)?results/([^/]+)/", log)
        if m:
            return m.group(1)
    return ds


#: The workflow's target rules: they run a command that does nothing (the Snakefile), not work.
TARGET_RULES = ("all", "plan", "evaluation")


def jobs_to_run(log_text: str) -> int:
    """The jobs of a dry run's last job table (Snakemake's ``Job stats``), the target
    rules' left out; 0 when it has none ("Nothing to be done")."""
    tables = re.findall(r"^Job stats:\n.*?\n-+\s+-+\n(.*?)^total\s+\d+$", log_text, re.M | re.S)
    if not tables:
        return 0
    rows = [line.split() for line in tables[-1].splitlines() if line.strip()]
    return sum(int(n) for rule, n in rows if rule not in TARGET_RULES)

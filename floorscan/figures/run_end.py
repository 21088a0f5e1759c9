"""The end of a run, from the run's files: which datasets it was about, which of them
failed, ``results/index.html`` rewritten, and the lines of the answer.

Two callers, one path through this module:

- the Snakefile's ``onsuccess`` / ``onerror`` handlers (a run of ``snakemake``): they
  know the run's targets (config ``target``) and the time the Snakefile was read;
- the ``floorscan`` command (:mod:`floorscan.cli`), after its Snakemake process has
  ended, in every case, a run with nothing to be done included: it reads the run's
  manifest (:func:`write_manifest`, written by the Snakefile when the command asks for
  it by :data:`MANIFEST_ENV`) and its own start time.

Both read only files: a dataset ran in the run when a log of ``results/<dataset>/logs/``
was written since the run started (every stage writes one), and failed when such a log
holds an error (:func:`floorscan.figures.index_page.log_error`, the paragraph the stage
wrote). Nothing here reads Snakemake's internals (its scheduler, DAG or targets), which
a minor release may change.

Snakemake runs neither handler when it has nothing to do (``workflow.py`` returns after
"Nothing to be done" before ``onsuccess``): a run of ``snakemake`` then ends without the
answer, a run of ``floorscan run`` with it.
"""

from __future__ import annotations

import json
import os
import shlex
from collections.abc import Callable
from pathlib import Path

from floorscan.core.files import atomic_path

#: The environment variable by which the ``floorscan`` command asks the Snakefile for the
#: run's manifest (its value: where to write it); the Snakefile's handlers then print
#: nothing, the command prints the answer.
MANIFEST_ENV = "FLOORSCAN_RUN_MANIFEST"


def write_manifest(path: str | os.PathLike, datasets: list[str], building: dict | None = None) -> None:
    """The run's manifest: its target datasets and its building, for the command that
    prints the answer after Snakemake has ended. Written once (the Snakefile is read
    again by each job's process, with the same config): an existing file is kept.

    Parameters
    ----------
    path : path
        The file (JSON), written atomically.
    datasets : list of str
        The run's target datasets, in order.
    building : dict, optional
        ``page``, ``ifc`` (paths) and ``storeys`` (int) of the run's building.
    """
    path = Path(path)
    if path.exists():
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps({"datasets": list(datasets), "building": building}, indent=1) + "\n",
                       encoding="utf-8")


def read_manifest(path: str | os.PathLike) -> dict | None:
    """The manifest :func:`write_manifest` wrote, or None (the Snakefile stopped before
    it: a config error, a missing input)."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) and isinstance(data.get("datasets"), list) else None


def _logs_since(dataset: str, start_ns: int, results: str | os.PathLike) -> list[Path]:
    """The stage logs of ``results/<dataset>/logs`` written at or after ``start_ns``,
    newest first."""
    folder = Path(results) / dataset / "logs"
    found = []
    for p in folder.glob("*.log") if folder.is_dir() else []:
        try:
            t = p.stat().st_mtime_ns
        except OSError:
            continue
        if t >= start_ns:
            found.append((t, p.name, p))
    return [p for *_, p in sorted(found, reverse=True)]


def ran_since(dataset: str, start_ns: int, results: str | os.PathLike = "results") -> bool:
    """Whether a job of ``dataset`` ran since ``start_ns`` (time.time_ns()): a stage log
    of it was written since."""
    return bool(_logs_since(dataset, start_ns, results))


def failed_since(dataset: str, start_ns: int, results: str | os.PathLike = "results") -> str | None:
    """The error a job of ``dataset`` logged since ``start_ns``: the paragraph of the
    newest log written since that holds one (:func:`floorscan.figures.index_page.log_error`),
    or None."""
    found = _failed_log_since(dataset, start_ns, results)
    return found[1] if found else None


def _failed_log_since(dataset: str, start_ns: int, results: str | os.PathLike) -> tuple[Path, str] | None:
    from floorscan.figures.index_page import log_error

    for log in _logs_since(dataset, start_ns, results):
        text = log_error(log)
        if text:
            return log, text
    return None


def run_datasets(targets: list[str], datasets, start_ns: int, results: str | os.PathLike = "results") -> list[str]:
    """The datasets a run was about, for its answer.

    The run's targets when a job of one of them ran, or when no job of any dataset ran
    (nothing to be done, the building alone); then each other dataset a job ran for (a
    file of it asked for: ``snakemake results/intel/floorplan.svg``).

    Parameters
    ----------
    targets : list of str
        The config's ``target`` datasets (the paths' datasets of ``--config path``).
    datasets : iterable of str
        Every configured dataset.
    start_ns : int
        When the run started, ``time.time_ns()``.
    results : path

    Returns
    -------
    list of str
        Targets first, then the others in the order of ``datasets``.
    """
    ran = [d for d in dict.fromkeys([*targets, *datasets]) if ran_since(d, start_ns, results)]
    others = [d for d in ran if d not in targets]
    return (list(targets) if set(ran) & set(targets) or not ran else []) + others


def results_datasets(results: str | os.PathLike = "results") -> list[str]:
    """Every dataset ``results/`` holds: a folder with a front page or stage logs (the
    building's folder is not a dataset), sorted."""
    root = Path(results)
    if not root.is_dir():
        return []
    return sorted(p.name for p in root.iterdir()
                  if p.is_dir() and p.name != "building" and ((p / "front.html").is_file() or (p / "logs").is_dir()))


def write_results_index(datasets: list[str], failed: dict | None = None, results: str | os.PathLike = "results") -> Path:
    """Rewrite ``results/index.html``: the run's datasets first (a failed one with the
    error of this run), then every other dataset ``results/`` holds.

    Parameters
    ----------
    datasets : list of str
    failed : dict, optional
        ``{dataset: error paragraph}`` of the run.
    results : path

    Returns
    -------
    Path
        The page.
    """
    from floorscan.figures.index_page import dataset_status, write_index

    failed = dict(failed or {})
    statuses = [{**dataset_status(ds, results), "failed": failed[ds]} if ds in failed else dataset_status(ds, results)
                for ds in datasets]
    statuses += [dataset_status(ds, results) for ds in results_datasets(results) if ds not in datasets]
    page = Path(results) / "index.html"
    page.parent.mkdir(parents=True, exist_ok=True)
    write_index(statuses, page)
    return page


def finish_run(datasets: list[str], results: str | os.PathLike = "results", failed: dict | None = None,
               report: str | Callable[[list[str] | None], str] = "", building: dict | None = None) -> list[str]:
    """Rewrite the index and give the run's last lines: the answer of each dataset
    (:func:`floorscan.figures.answer.answer_lines`), the building, and which recordings
    failed.

    Parameters
    ----------
    datasets : list of str
        :func:`run_datasets`.
    results : path
        The results folder, as the lines name it (relative to where they are read).
    failed : dict, optional
        ``{dataset: error paragraph}``.
    report : str or callable
        The command that makes the report of these datasets, or empty; or a function
        of the datasets with a front page (None when every dataset has one) that gives
        it (:func:`report_command`).
    building : dict, optional
        ``page``, ``ifc`` (relative to the results folder's parent) and ``storeys``.

    Returns
    -------
    list of str
    """
    from floorscan.figures.answer import answer_lines

    failed = {ds: text for ds, text in (failed or {}).items() if ds in datasets}
    write_results_index(datasets, failed, results)
    if callable(report):  # the report of the datasets with an answer, or of the run
        complete = [ds for ds in datasets if ds not in failed and (Path(results) / ds / "front.html").is_file()]
        report = report(complete if len(complete) < len(datasets) else None) if complete else ""
    lines = answer_lines(datasets, results, failed=failed, report=report)
    base = Path(results).parent
    if building and (base / building["page"]).is_file():
        lines.append(f"building: {base / building['page']}, {base / building['ifc']} ({building['storeys']} storeys)")
    if failed:
        lines.append(f"{len(failed)} of {len(datasets)} recordings failed: {', '.join(failed)}")
    return lines


def run_answer(targets: list[str], datasets, start_ns: int, results: str | os.PathLike = "results",
               failed_jobs=(), report: str | Callable[[list[str] | None], str] = "",
               building: dict | None = None) -> list[str]:
    """The end of a run, as both callers make it: the run's datasets
    (:func:`run_datasets`), the failed ones' errors from their stage logs
    (:func:`failed_since`), else from ``failed_jobs``, then :func:`finish_run`. A run
    of one dataset names the log of its error, not the paragraph again: the command
    printed it when the job failed, and Snakemake shows the failed job's log
    (``show-failed-logs`` in the default profile), just above.

    Parameters
    ----------
    targets : list of str
        The run's target datasets (the manifest's).
    datasets : iterable of str
        The datasets a job may have run for.
    start_ns : int
        When the run started, ``time.time_ns()``.
    results : path
        The results folder, as the lines name it.
    failed_jobs : iterable of (str, str)
        ``(dataset, text)`` of each job Snakemake said failed (the command reads them
        from its output): the text stands for a dataset whose stage logs hold no error
        (a job killed, an output missing).
    report, building
        As :func:`finish_run`.

    Returns
    -------
    list of str
    """
    runs = run_datasets(targets, datasets, start_ns, results)
    failed = {}
    for ds in runs:
        found = _failed_log_since(ds, start_ns, results)
        if found:  # one recording: its paragraph is right above (the command's, or the log Snakemake shows)
            failed[ds] = f"its error is the paragraph above; its log: {found[0]}" if len(runs) == 1 else found[1]
    for ds, text in failed_jobs:
        if ds in runs:
            failed.setdefault(ds, text)
    return finish_run(runs, results, failed, report, building)


def report_command(argv: list[str], only: list[str] | None = None) -> str:
    """The ``snakemake`` command that makes the report of a run, quoted for a shell: the
    run's program, its ``--config`` entries, config files, Snakefile and working
    directory (read from its own command line ``argv``), ``--report
    results/report.html``, and with ``only`` the front pages of those datasets as
    targets (a run in which other datasets failed: the report of all of them would
    stop at the first missing figure).

    Parameters
    ----------
    argv : list of str
        ``sys.argv`` of the Snakemake process.
    only : list of str, optional
        The datasets of the run that have an answer, when some of its datasets have none.

    Returns
    -------
    str
    """
    kept, i = [], 1
    while i < len(argv):
        word = argv[i]
        if word in ("--config", "-C", "--configfile", "--configfiles"):
            values = []
            i += 1
            while i < len(argv) and not argv[i].startswith("-") and (word.startswith("--configfile") or "=" in argv[i]):
                values.append(argv[i])
                i += 1
            kept += [word, *values] if values else []
            continue
        if word in ("--snakefile", "-s", "--directory", "-d") and i + 1 < len(argv):
            kept += [word, argv[i + 1]]
            i += 2
            continue
        if word.startswith(("--configfile=", "--snakefile=", "--directory=")):
            kept.append(word)
        i += 1
    targets = [f"results/{ds}/front.html" for ds in only or []]
    return shlex.join([argv[0], "--cores", "2", *kept, "--report", "results/report.html", *targets])

"""The run's last lines, from the run's files (floorscan.figures.answer,
floorscan.figures.run_end): which datasets a run is about, which failed, the index and
the manifest the `floorscan` command reads (issue 47, item 2: no Snakemake internals)."""

import json
import os
import shlex

from floorscan.figures.answer import answer_lines
from floorscan.figures.run_end import (
    failed_since, finish_run, read_manifest, report_command, results_datasets, run_answer, run_datasets,
    write_manifest,
)

T0 = 1_700_000_000 * 10**9  # the run's start, ns
ERROR = "2026-01-01 00:00:00,000 ERROR floorscan.ingest: ingest failed: x.bag: truncated\n"
INFO = "2026-01-01 00:00:00,000 INFO floorscan.poses: done poses\n"


def _log(results, dataset, stage, text, t_ns):
    log = results / dataset / "logs" / f"{stage}.log"
    log.parent.mkdir(parents=True, exist_ok=True)
    log.write_text(text)
    os.utime(log, ns=(t_ns, t_ns))
    return log


def test_the_datasets_of_a_run_are_its_targets_and_those_a_job_ran_for(tmp_path):
    known = ["demo", "intel", "orebro"]
    for ds in known:  # an earlier run of each
        _log(tmp_path, ds, "ingest", INFO, T0 - 10**9)
    assert run_datasets(["demo"], known, T0, tmp_path) == ["demo"]  # nothing ran: the targets
    _log(tmp_path, "intel", "poses", INFO, T0 + 10**9)  # `snakemake results/intel/...`
    assert run_datasets(["demo"], known, T0, tmp_path) == ["intel"]
    _log(tmp_path, "demo", "poses", INFO, T0 + 2 * 10**9)  # a job of a target ran: every target
    assert run_datasets(["orebro", "demo"], known, T0, tmp_path) == ["orebro", "demo", "intel"]


def test_a_failure_is_an_error_logged_in_this_run(tmp_path):
    _log(tmp_path, "a", "ingest", ERROR, T0 - 10**9)  # an earlier run's
    assert failed_since("a", T0, tmp_path) is None
    _log(tmp_path, "a", "poses", INFO, T0 + 10**9)
    assert failed_since("a", T0, tmp_path) is None
    _log(tmp_path, "a", "register", ERROR.replace("ingest", "register"), T0 + 10**9)
    assert failed_since("a", T0, tmp_path) == "register failed: x.bag: truncated"
    assert failed_since("missing", T0, tmp_path) is None


def test_a_failed_dataset_gets_its_error_not_an_older_answer(tmp_path):
    (tmp_path / "a" / "selection").mkdir(parents=True)
    (tmp_path / "a" / "selection" / "selection.json").write_text("{}")  # an older answer: not read
    lines = answer_lines(["a", "b"], tmp_path, failed={"a": "ingest failed: x.bag: truncated"})
    assert lines == [
        "a: FAILED: ingest failed: x.bag: truncated",
        f"b: not finished: no answer yet ({tmp_path}/b/selection/selection.json is not made: the run stopped before "
        "it, or its targets do not include the plan); run it again to go on",
    ]


def test_the_end_of_a_run_rewrites_the_index_of_every_dataset(tmp_path):
    """finish_run: the run's datasets in the index first, then every other dataset
    results/ holds (one that failed earlier and has no front page included, the
    building's folder not); the last lines say which recordings failed."""
    results = tmp_path / "results"
    _log(results, "broken", "ingest", ERROR, T0 + 10**9)
    _log(results, "old_failure", "ingest", ERROR, T0 - 10**9)
    (results / "earlier").mkdir()
    (results / "earlier" / "front.html").write_text("<html></html>")
    (results / "building" / "logs").mkdir(parents=True)
    assert results_datasets(results) == ["broken", "earlier", "old_failure"]
    failed = {"broken": failed_since("broken", T0, results)}
    lines = finish_run(["broken", "lab"], results, failed, report="floorscan report")
    assert lines[0] == "broken: FAILED: ingest failed: x.bag: truncated"
    assert lines[1].startswith("lab: not finished: no answer yet")
    # no report: none of the run's datasets has an answer to report
    assert lines[2:] == [f"index: {results / 'index.html'}", "1 of 2 recordings failed: broken"]
    index = (results / "index.html").read_text()
    assert "4 recordings: 0 with a plan, 4 failed" in index  # broken, lab, then earlier, old_failure: no plan
    order = [index.index(f'id="{ds}"') for ds in ("broken", "lab", "earlier", "old_failure")]
    assert order == sorted(order) and 'id="building"' not in index


def test_one_failed_recording_points_at_its_paragraph_several_repeat_theirs(tmp_path):
    """run_answer: a run of one recording that failed names the log of the paragraph
    printed just above (the error once, tests/test_bad_input.py); of several, each
    paragraph again at the end; a job Snakemake said failed whose stage logged no
    error gets the text its caller gives."""
    log = _log(tmp_path, "lab", "ingest", ERROR, T0 + 10**9)
    lines = run_answer(["lab"], [], T0, tmp_path)
    assert lines[0] == f"lab: FAILED: its error is the paragraph above; its log: {log}"
    assert lines[-1] == "1 of 1 recordings failed: lab"
    _log(tmp_path, "other", "poses", INFO, T0 + 10**9)  # ran, logged no error: killed
    lines = run_answer(["lab", "other"], [], T0, tmp_path, failed_jobs=[("other", "poses failed; its log: x")])
    assert lines[:2] == ["lab: FAILED: ingest failed: x.bag: truncated", "other: FAILED: poses failed; its log: x"]
    assert lines[-1] == "2 of 2 recordings failed: lab, other"


def test_the_answer_says_when_the_summary_holds_the_evaluation(tmp_path):
    """What --evaluate adds is said on the answer's summary line: only when summary.md
    ends with the evaluation's part (a plan-only summary beside an older evaluation
    does not)."""
    from floorscan.figures.answer import evaluation_note

    folder = tmp_path / "lab"
    (folder / "evaluation").mkdir(parents=True)
    assert evaluation_note(folder) == ""
    (folder / "evaluation" / "summary.md").write_text("## Floor plans against the reference map\n")
    (folder / "summary.md").write_text("# Scan reduction summary: lab\n")
    assert evaluation_note(folder) == ""
    (folder / "summary.md").write_text("# Scan reduction summary: lab\n\n## Floor plans against the reference map\n")
    assert evaluation_note(folder) == f" (with the evaluation: every plan and score in {folder}/evaluation/)"


def test_the_manifest_is_written_once(tmp_path):
    """The Snakefile is read again by every job's process: the first manifest stays."""
    path = tmp_path / "state" / "manifest.json"
    assert read_manifest(path) is None
    building = {"page": "results/building/index.html", "ifc": "results/building/building.ifc", "storeys": 2}
    write_manifest(path, ["ground", "first"], building)
    write_manifest(path, ["other"])
    assert read_manifest(path) == {"datasets": ["ground", "first"], "building": building}
    path.write_text(json.dumps({"datasets": "x"}))
    assert read_manifest(path) is None


def test_the_report_command_of_a_run_is_its_own_quoted():
    """The run's program, config entries, config files, Snakefile and folder, quoted
    (issue 47: a path with spaces, a dropped --configfile); its targets and other
    options not; with the datasets that have an answer, their front pages."""
    argv = ["/v/bin/snakemake", "--cores", "2", "plan", "--config", "path=/d/my run.bag", "resolution_m=0.1",
            "--configfile", "my.yaml", "x y.yaml", "-n", "--configfile=z.yaml", "-d", "/w d", "--keep-going"]
    command = report_command(argv)
    assert shlex.split(command) == ["/v/bin/snakemake", "--cores", "2", "--config", "path=/d/my run.bag",
                                    "resolution_m=0.1", "--configfile", "my.yaml", "x y.yaml", "--configfile=z.yaml",
                                    "-d", "/w d", "--report", "results/report.html"]
    assert shlex.split(report_command(["snakemake", "--cores", "2"], only=["a", "b"])) == [
        "snakemake", "--cores", "2", "--report", "results/report.html", "results/a/front.html", "results/b/front.html"]


def test_the_report_named_is_of_the_datasets_with_an_answer(tmp_path):
    """finish_run with report_command: every dataset answered, the run's report; one
    failed, the front pages of the others (a report of all would stop at the failed
    one's missing figures); all failed, no report (an older results/report.html is not
    named either)."""
    import functools

    results = tmp_path / "results"
    for ds in ("a", "b"):
        (results / ds).mkdir(parents=True)
        (results / ds / "front.html").write_text("<html></html>")
    (results / "report.html").write_text("an older report")
    command = functools.partial(report_command, ["snakemake", "--cores", "2"])

    def report_line(datasets, failed):
        return [l for l in finish_run(datasets, results, failed, report=command) if l.startswith("report: ")]

    assert report_line(["a"], {}) == []  # a has no answer (no selection.json): nothing to report
    (results / "a" / "map").mkdir()
    (results / "a" / "map" / "map.json").write_text(json.dumps({"width": 2, "height": 2, "resolution_m": 0.05}))
    (results / "b" / "map").mkdir()
    (results / "b" / "map" / "map.json").write_text(json.dumps({"width": 2, "height": 2, "resolution_m": 0.05}))
    assert report_line(["a", "b"], {}) == ["report: snakemake --cores 2 --report results/report.html"]
    assert report_line(["a", "b"], {"b": "ingest failed"}) == [
        "report: snakemake --cores 2 --report results/report.html results/a/front.html"]
    assert report_line(["a", "b"], {"a": "x", "b": "y"}) == []


def test_the_workflow_reads_no_snakemake_internals():
    """Issue 47, item 2: the Snakefile and its rule files use of Snakemake's `workflow`
    object only what Snakemake documents for Snakefiles (its folder), and no exit
    handler (the answer came from workflow.scheduler, workflow.dag,
    workflow.dag_settings.targets and an atexit hook on workflow.exec_mode)."""
    import re
    from pathlib import Path

    repo = Path(__file__).resolve().parents[1]
    used = {}
    for path in [repo / "Snakefile", *sorted((repo / "workflow" / "rules").glob("*.smk"))]:
        text = path.read_text()
        for attr in re.findall(r"(?<![\w/])workflow\.(\w+)(?!\w*\.rst)", text):
            used.setdefault(attr, []).append(path.name)
        for internal in ("atexit", "snakemake_interface_executor_plugins", "ExecMode"):
            assert internal not in text, (path.name, internal)
    assert set(used) <= {"basedir", "current_basedir", "source_path"}, used

"""The floorscan command (floorscan/cli.py, issue 47 item 1): its arguments, every
misuse as one line, the config it writes for Snakemake, its progress lines, and one run
of the demo in a copy of the workflow."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from conftest import REPO, copy_workflow
from floorscan import cli
from floorscan.core.datasets import add_path_datasets, check_datasets
from floorscan.core.config import ConfigError


def run_args(*argv):
    own, extra = cli.split_passthrough(["run", *argv])
    return cli.parser().parse_args(own), extra


def test_help_says_it_all(capsys):
    with pytest.raises(SystemExit) as e:
        cli.main(["--help"])
    assert e.value.code == 0
    top = capsys.readouterr().out
    assert "run" in top and "report" in top and "--" in top
    with pytest.raises(SystemExit):
        cli.main(["run", "--help"])
    text = capsys.readouterr().out
    for word in ("PATH", "--evaluate", "--cores", "--config", "--set", "select.k=5", "scan_topic", "resolution_m", "-- -n"):
        assert word in text, word


@pytest.mark.parametrize(
    "argv, message",
    [
        ([], "expected a command, run or report"),
        (["bogus"], "invalid choice: 'bogus'"),
        (["run", "--cores", "0"], "--cores: 0 is not at least 1"),
        (["run", "--cores", "two"], "'two' is not a whole number"),
        (["run", "/no/such/run.bag"], "/no/such/run.bag: no such file or folder"),
        (["run", "--set", "select.k"], "expected KEY=VALUE"),
        (["run", "--set", "select.kk=5"], "select.kk: unknown key; expected one of ["),
        (["run", "--set", "select.k=five"], "select.k: got 'five'; expected 'auto', an integer >= 1 or a number > 0 and < 1"),
        (["run", "--set", "resolution_m=-1"], "resolution_m: -1 is less than or equal to the minimum of 0"),
        (["run", "--set", "nosuch=1"], "nosuch: unknown key"),
        (["run", "--set", "scan_topic=/base_scan"], "scan_topic is a key of a dataset"),
        (["run", "--set", "path=/data/run.bag"], "give recordings as PATH arguments"),
        (["run", "--config", "/no/such.yaml"], "/no/such.yaml: no such file"),
        (["run", "--frobnicate"], "unrecognized arguments: --frobnicate"),
        (["report", "extra"], "unrecognized arguments: extra"),
    ],
)
def test_every_misuse_is_one_line(argv, message, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert message in err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_a_config_file_that_is_not_a_mapping_is_one_line(tmp_path, capsys):
    (tmp_path / "list.yaml").write_text("- a\n- b\n")
    (tmp_path / "bad.yaml").write_text("a: [\n")
    for name, message in (("list.yaml", "expected a YAML mapping"), ("bad.yaml", "not a YAML config file")):
        assert cli.main(["run", "--config", str(tmp_path / name)]) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1


def test_passthrough_after_double_dash():
    args, extra = run_args("a.bag", "--cores", "3", "--", "-n", "--forceall", "plan")
    assert args.paths == ["a.bag"] and args.cores == 3 and extra == ["-n", "--forceall", "plan"]
    cmd = cli.snakemake_command(Path("/repo"), [Path("/x/run.yaml")], 3, extra)
    assert cmd[1:] == ["--snakefile", "/repo/Snakefile", "--directory", "/repo", "--configfile", "/x/run.yaml",
                       "--cores", "3", "-n", "--forceall", "plan"]


def test_the_config_it_writes(tmp_path, monkeypatch):
    """--set typed by the schemas, nested keys, a dataset key for the PATHs'
    recordings; the paths absolute (spaces kept), several a list; plan only unless
    --evaluate or the config file says so."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my data").mkdir()
    (tmp_path / "my data" / "lab run.bag").write_bytes(b"")
    (tmp_path / "floor.png").write_bytes(b"")
    args, _ = run_args("my data/lab run.bag", "--set", "select.k=5", "--set", "scan_topic=/base_scan",
                       "--set", "resolution_m=0.1", "--set", "walls.k=[5, all]", "--set", "select.k_coverage=0.95",
                       "--set", "pose.source=tf", "--set", "walls.map.support_cell_m=0.04",
                       "--set", "datasets.lab.params.select.k=auto")
    config = cli.run_config(args)
    assert config == {
        "path": str(tmp_path / "my data" / "lab run.bag"),
        "evaluate": False,
        "select": {"k": 5, "k_coverage": 0.95},
        "path_options": {"scan_topic": "/base_scan", "pose": {"source": "tf"}},
        "resolution_m": 0.1,
        "walls": {"k": [5, "all"], "map": {"support_cell_m": 0.04}},
        "datasets": {"lab": {"params": {"select": {"k": "auto"}}}},
    }
    args, _ = run_args("my data/", "../" + tmp_path.name + "/floor.png", "--evaluate")  # normalised
    config = cli.run_config(args)
    assert config == {"path": [str(tmp_path / "my data"), str(tmp_path / "floor.png")], "evaluate": True}
    (tmp_path / "eval.yaml").write_text("evaluate: true\n")
    assert "evaluate" not in cli.run_config(run_args("--config", "eval.yaml")[0])  # the file decides


def test_path_options_and_several_paths_make_the_datasets(tmp_path):
    """The Snakefile's side: path_options on every recording of path (a reused
    dataset too), a list of paths checked for empty ones."""
    config = {"datasets": {"lab": {"path": "/d/lab.bag"}}, "path_options": {"scan_topic": "/base_scan"}}
    names = add_path_datasets(config, [Path("/d/lab.bag"), Path("/e/my run.bag")])
    assert names == ["lab", "my_run"] and config["target"] == names
    assert config["datasets"]["lab"]["scan_topic"] == config["datasets"]["my_run"]["scan_topic"] == "/base_scan"
    check_datasets({"path": ["/a.bag", "/b.bag"], "datasets": {}})
    with pytest.raises(ConfigError, match="path .* is empty"):
        check_datasets({"path": ["/a.bag", " "], "datasets": {}})


def test_the_report_has_every_file_of_the_complete_datasets():
    """floorscan report's targets: the inputs of `all` in the dry run's job list that
    belong to the complete datasets (their figures with them), not the others' nor the
    building's; their front pages when the list names no `all`."""
    dry_run = ("[Wed Nov 25 14:00:27 2026]\nrule front_page:\n    input: results/a/x.png\n    jobid: 4\n"
               "[Wed Nov 25 14:00:27 2026]\nlocalrule all:\n    input: results/a/poses.parquet, results/b/poses.parquet, "
               "results/a/figures/registered_map.png, results/building/building.ifc, results/a/front.html, "
               "results/b/front.html\n    jobid: 0\n    resources: tmpdir=/tmp\n")
    assert cli.report_targets(dry_run, ["a"]) == ["results/a/poses.parquet", "results/a/figures/registered_map.png",
                                                  "results/a/front.html"]
    assert cli.report_targets("Nothing to be done", ["a", "b"]) == ["results/a/front.html", "results/b/front.html"]


def test_progress_lines_and_a_failed_jobs_paragraph(tmp_path):
    """One line per finished job (n of N, rule, dataset, elapsed); a failed job's own
    paragraph from its log; the workflow's messages; Snakemake's other lines not."""
    log = tmp_path / "results" / "broken" / "logs" / "ingest.log"
    log.parent.mkdir(parents=True)
    log.write_text("2026-01-01 00:00:00,000 INFO floorscan.ingest: start ingest\n"
                   "2026-01-01 00:00:00,100 ERROR floorscan.ingest: ingest failed: broken.bag: truncated\n")
    lines = []

    class Out:
        def write(self, text):
            lines.append(text)

        def flush(self):
            pass

    p = cli.Progress(tmp_path, out=Out(), start=0.0)
    for line in [
        "Config file config/config.yaml is extended by additional config specified via the command line.",
        "/d/survey: 2 recordings, one dataset each: broken, lab",
        "Building DAG of jobs...", "[Wed Nov 25 07:36:43 2026]", "localrule ingest:", "    jobid: 3",
        "    wildcards: dataset=lab", "    log: results/lab/logs/ingest.log", "some stage output",
        "[Wed Nov 25 07:36:45 2026]", "Finished jobid: 3 (Rule: ingest)", "1 of 12 steps (8%) done",
        "Error in rule ingest:", "    message: None", "    jobid: 2",
        "    log: results/broken/logs/ingest.log (check log file(s) for error details)",
        "RuleException:", "CalledProcessError in file ...",
    ]:
        p.feed(line)
    p.close()
    text = "".join(lines).splitlines()
    assert text[0] == "/d/survey: 2 recordings, one dataset each: broken, lab"
    assert text[1].split()[:4] == ["1", "of", "12", "ingest"] and "(lab)" in text[1] and text[1].endswith(" s")
    assert text[2] == "FAILED ingest (broken): ingest failed: broken.bag: truncated"
    assert text[3] == f"  its log: {log}"
    assert len(text) == 4


def test_run_prints_progress_and_the_answer_from_anywhere(tmp_path):
    """One real run of the demo's plan (~20 s) in a copy of the workflow, from another
    folder; a dry run of two paths, one with spaces; the report of what exists."""
    wd = copy_workflow(tmp_path / "floorscan")
    (wd / "profiles").symlink_to("workflow/profiles")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {**os.environ, "FLOORSCAN_REPOSITORY": str(wd),
           "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))}

    def floorscan(*argv):
        return subprocess.run([sys.executable, "-m", "floorscan.cli", *argv], cwd=elsewhere, env=env,
                              capture_output=True, text=True, timeout=600)

    res = floorscan("run")
    assert res.returncode == 0, res.stdout + res.stderr
    lines = res.stdout.splitlines()
    progress = [l for l in lines if re.match(r"^\s*\d+ of \d+ ", l)]
    assert any(l.split()[3] == "register" and "(demo)" in l for l in progress), res.stdout
    assert progress[-1].split()[0] == progress[-1].split()[2]  # n of N: the last is N
    answer = lines[lines.index(next(l for l in lines if l.startswith("demo: "))):]
    assert answer[0].startswith("demo: 10 of 76 kept scans")
    # all it prints: the progress, then the answer (`make run`, with the evaluation: 45 lines)
    assert lines == progress + answer and len(lines) < 60
    assert f"{wd}/results/demo/floorplan.{{geojson,svg,dxf,ifc}}" in res.stdout  # from the repository, not cwd
    assert "Building DAG" not in res.stdout + res.stderr and "SNAKEMAKE" not in res.stdout
    assert "Building DAG of jobs" in (wd / ".snakemake" / "floorscan" / "run.log").read_text()
    # one dataset's run writes the index too: the front page's link back to it resolves
    index = (wd / "results" / "index.html").read_text()
    assert 'href="demo/front.html"' in index and 'href="../index.html"' in (wd / "results" / "demo" / "front.html").read_text()
    # again, nothing to be done (a file target: Snakemake runs no handler): the answer still, read from the files
    again = floorscan("run", "--", "results/demo/front.html")
    assert again.returncode == 0, again.stdout + again.stderr
    assert "Nothing to be done" in (wd / ".snakemake" / "floorscan" / "run.log").read_text()
    lines = again.stdout.splitlines()
    assert lines[0].startswith("demo: 10 of 76 kept scans") and "no answer yet" not in again.stdout, again.stdout
    assert lines[-1] == "report: floorscan report" and f"  front page:         {wd}/results/demo/front.html" in lines
    assert "dry run: 0 jobs to run" in floorscan("run", "--", "-n").stdout  # the target rule is no work

    (elsewhere / "my data").mkdir()
    bag = wd / "results" / "demo" / "sim" / "recording.bag"
    (elsewhere / "my data" / "lab run.bag").write_bytes(bag.read_bytes())
    (elsewhere / "second.bag").write_bytes(bag.read_bytes())
    res = floorscan("run", "my data/lab run.bag", "second.bag", "--set", "select.k=5", "--", "-n")
    assert res.returncode == 0, res.stdout + res.stderr
    assert "2 recordings, one dataset each: lab_run, second" in res.stdout
    assert "dry run: 20 jobs to run" in res.stdout, res.stdout  # 10 a recording before register
    written = yaml.safe_load((wd / ".snakemake" / "floorscan" / "run.yaml").read_text())
    assert written["path"] == [str(elsewhere / "my data" / "lab run.bag"), str(elsewhere / "second.bag")]
    assert written["select"] == {"k": 5} and written["evaluate"] is False

    res = floorscan("report")  # of the last run: lab_run and second are not made, skipped
    assert "skipped lab_run: not made yet" in res.stdout and res.returncode == 1

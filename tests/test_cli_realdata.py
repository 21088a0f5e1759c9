"""Issue 47's "done when", on real recordings: the `floorscan` command as a newcomer
types it after `make run`, on ../shared/data (skipped, with the reason, without it).

One copy of the workflow for the module (the shared recordings beside it as
``../shared``, its default profile as ``profiles/``), in which the tests run in order:
trace0's plan from the bare path (progress, the answer, the verdict of a recording with
a scan or two without a pose, the front page's links); ``--set`` of a dataset key and a
nested option in a real run; the smallest real recording with ``--evaluate``; a folder
with spaces in its path holding an occupancy map and a broken recording, then
``floorscan report``; and misuses, one line each. ``results/index.html`` is checked
after every run. About 100 s on 2 cores, most of it the one evaluation (orebro, 45 s)
and the two plans of trace0 (15 to 20 s each).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
from html.parser import HTMLParser
from pathlib import Path

import pytest

from conftest import REPO, SHARED_DATA, copy_workflow, needs_shared

pytestmark = [needs_shared, pytest.mark.realdata, pytest.mark.workflow, pytest.mark.slow]

TRACE0 = "../shared/data/uob-pioneer/trace0.bag"  # as the issue types it, from the workflow's folder
OREBRO = "../shared/data/radish/orebro-corrected.log.gz"  # the smallest real recording: 237 scans, stamps all 0
MAP = SHARED_DATA / "room-maps" / "bormann" / "lab_ipa.png"
#: Snakemake's own lines, which go to the run's log only.
BOILERPLATE = ("Building DAG", "RuleException", "CalledProcessError", "Traceback", "Error in rule", "localrule all",
               "jobid:", "SNAKEMAKE")


class Run:
    """The module's copy of the workflow and the command run in it."""

    def __init__(self, wd: Path):
        self.wd = wd
        self.env = {**os.environ, "FLOORSCAN_REPOSITORY": str(wd),
                    "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))}

    def __call__(self, *argv, cwd: Path | None = None) -> subprocess.CompletedProcess:
        """``floorscan *argv`` from ``cwd`` (the workflow's folder); the index page is
        checked to be rewritten by every run that loads the workflow."""
        start = time.time()
        res = subprocess.run([sys.executable, "-m", "floorscan.cli", *argv], cwd=cwd or self.wd, env=self.env,
                             capture_output=True, text=True, timeout=900)
        if argv[0] == "run" and "--" not in argv and res.returncode in (0, 1):
            check_index(self.wd / "results", start)
        return res


@pytest.fixture(scope="module")
def floorscan(tmp_path_factory) -> Run:
    wd = copy_workflow(tmp_path_factory.mktemp("cli_realdata") / "floorscan")
    (wd / "profiles").symlink_to("workflow/profiles")  # the repository's default profile (keep-going)
    assert (wd.parent / "shared" / "data").is_dir()
    return Run(wd)


def check_index(results: Path, since: float) -> None:
    """Issue 47, item 3: ``results/index.html`` is rewritten at the end of the run and
    has a card for every dataset ``results/`` holds."""
    index = results / "index.html"
    assert index.stat().st_mtime >= since - 1, "index.html not rewritten by the run"
    held = {p.name for p in results.iterdir() if p.is_dir() and (p / "logs").is_dir()}
    cards = set(re.findall(r'<section class="card" id="([^"]+)"', index.read_text()))
    assert cards == held, (cards, held)


def progress_lines(stdout: str) -> list[str]:
    return [l for l in stdout.splitlines() if re.match(r"^\s*\d+ of \d+ ", l)]


def answer(stdout: str, dataset: str) -> list[str]:
    """The answer's lines: from the dataset's head line on."""
    lines = stdout.splitlines()
    return lines[next(i for i, l in enumerate(lines) if l.startswith(f"{dataset}: ")):]


class Links(HTMLParser):
    """A page's links, and the files it names without a link (``<code class="missing">``)."""

    def __init__(self, text: str):
        super().__init__()
        self.hrefs, self.missing, self._missing = [], [], False
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "a":
            self.hrefs.append(a["href"])
        self._missing = tag == "code" and a.get("class") == "missing"

    def handle_data(self, data):
        if self._missing:
            self.missing.append(data)
            self._missing = False


def svg_subtitle(path: Path) -> str:
    return re.search(r'<text id="subtitle"[^>]*>([^<]*)</text>', path.read_text()).group(1)


def test_a_recording_prints_progress_and_the_answer(floorscan):
    """`floorscan run ../shared/data/uob-pioneer/trace0.bag`: a line per finished job,
    then the answer (at most 10 lines), nothing of Snakemake's; the plan alone. Its
    verdict is GOOD with 1 of 958 scans without a pose (under 1 %: said, not a
    warning); its plan is dated (a ROS bag has absolute time); every file its front
    page names is a link that resolves."""
    res = floorscan("run", TRACE0)
    assert res.returncode == 0, res.stdout + res.stderr
    progress = progress_lines(res.stdout)
    assert [l.split()[3] for l in progress if "(trace0)" in l][:3] == ["ingest", "poses", "register"], res.stdout
    last = progress[-1].split()
    assert last[0] == last[2] and last[3] == "all"
    lines = answer(res.stdout, "trace0")
    assert re.fullmatch(r"trace0: \d+ of 221 kept scans \(958 recorded\), wall_coverage", lines[0]), lines[0]
    assert lines[1].startswith("  verdict:            GOOD: ") and "1 of the recording's 958 scans (<1 %) have no pose" in lines[1]
    assert "  front page:         results/trace0/front.html" in lines and lines[-1] == "report: floorscan report"
    assert len(lines) <= 10 and res.stdout.splitlines() == progress + lines  # progress, then the answer, no more
    assert not [w for w in BOILERPLATE if w in res.stdout + res.stderr]
    out = floorscan.wd / "results" / "trace0"
    assert not (out / "evaluation").exists()  # a bare path: the plan alone
    assert re.search(r"metres \u00b7 20\d\d-\d\d-\d\dT", svg_subtitle(out / "floorplan.svg"))
    page = (out / "front.html").read_text()
    links = Links(page)
    assert links.missing == ["../report.html"]  # no report made yet: named, not linked
    for name in ("../index.html", "floorplan.geojson", "floorplan.svg", "floorplan.dxf", "floorplan.ifc", "map.pgm",
                 "map.yaml", "selection/scans.csv", "selection/recording/trace0.bag", "selection/points.ply",
                 "selection/points.pcd", "summary.md"):  # fmt: skip
        assert name in links.hrefs, name
    assert all((out / h).exists() for h in links.hrefs), [h for h in links.hrefs if not (out / h).exists()]
    assert "Not evaluated in this run" in page


def test_set_reaches_the_stages_in_a_real_run(floorscan):
    """`--set scan_topic=...` and `--set select.k=5` in a real run of trace0: a topic
    the bag lacks fails in ingest with the stage's own paragraph (so the setting
    reached it) and no Snakemake boilerplate; the bag's own topic and k = 5 give the
    plan of 5 scans."""
    wrong = floorscan("run", TRACE0, "--set", "scan_topic=/scan")
    assert wrong.returncode == 1
    assert wrong.stdout.startswith("FAILED ingest (trace0): ingest failed: ")
    assert "no topic '/scan' for scans; topics in the bag: /base_scan (sensor_msgs/msg/LaserScan)" in wrong.stdout
    assert "trace0: FAILED: its error is the paragraph above" in wrong.stdout
    assert "report:" not in wrong.stdout  # nothing to report
    assert not [w for w in BOILERPLATE if w in wrong.stdout + wrong.stderr]

    res = floorscan("run", TRACE0, "--set", "scan_topic=/base_scan", "--set", "select.k=5")
    assert res.returncode == 0, res.stdout + res.stderr
    lines = answer(res.stdout, "trace0")
    assert re.fullmatch(r"trace0: 5 of 221 kept scans \(958 recorded\), wall_coverage", lines[0]), lines[0]
    assert next(l for l in lines if l.startswith("  reduced recording:")).endswith(", 5 scans)")
    summary = (floorscan.wd / "results" / "trace0" / "summary.md").read_text()
    assert "scan_topic /base_scan" in summary


def test_evaluate_adds_the_evaluation(floorscan):
    """`--evaluate` on the smallest real recording (orebro, 237 scans): the evaluation's
    files, its tables on the front page and in summary.md, said in the answer; a CARMEN
    log's stamps count from 0, so its plan and page show no date."""
    res = floorscan("run", OREBRO, "--evaluate")
    assert res.returncode == 0, res.stdout + res.stderr
    ds = "orebro-corrected"
    out = floorscan.wd / "results" / ds
    rules = {l.split()[3] for l in progress_lines(res.stdout)}
    assert {"reference", "score_curves", "score", "score_figures"} <= rules, rules
    lines = answer(res.stdout, ds)
    assert f"  summary:            results/{ds}/summary.md (with the evaluation: every plan and score in results/{ds}/evaluation/)" in lines
    for name in ("evaluation/summary.md", "summary.parquet", "figures/floorplan_f1_vs_k.png", "evaluation/plans"):
        assert (out / name).exists(), name
    assert "## Floor plans against the reference map" in (out / "summary.md").read_text()
    page = (out / "front.html").read_text()
    assert "How few scans give the floor plan of all scans" in page and "Not evaluated in this run" not in page
    assert svg_subtitle(out / "floorplan.svg").endswith("map frame of the recording, metres")
    assert "1970" not in page


def test_a_folder_with_spaces_a_map_and_a_broken_recording_then_the_report(floorscan, tmp_path):
    """`floorscan run "my survey/"` (a space in the folder's and a file's name) holding
    an occupancy map and a truncated bag: the map's plan, the bag's own paragraph, the
    others go on; then `floorscan report` writes the report of the good ones with every
    figure, naming the one it skips."""
    folder = tmp_path / "my survey"
    folder.mkdir()
    shutil.copy(MAP, folder / "lab ipa.png")
    (folder / "broken.bag").write_bytes((SHARED_DATA / "uob-pioneer" / "trace0.bag").read_bytes()[:300_000])
    res = floorscan("run", "my survey/", cwd=tmp_path)
    assert res.returncode == 1, res.stdout + res.stderr
    assert f"{folder}: 2 recordings, one dataset each: broken, lab_ipa" in res.stdout
    assert "FAILED ingest (broken): ingest failed: " in res.stdout and "truncated or corrupt" in res.stdout
    assert not [w for w in BOILERPLATE if w in res.stdout + res.stderr]
    results = floorscan.wd / "results"
    lines = res.stdout.splitlines()
    assert re.fullmatch(r"lab_ipa: floor plan of an occupancy map, 864 x 768 cells of 0\.05 m \(\d+ walls, .*\); "
                        + re.escape(f"{results}/lab_ipa/front.html"), next(l for l in lines if l.startswith("lab_ipa: ")))
    assert lines[-2:] == ["report: floorscan report", "1 of 2 recordings failed: broken"]
    for name in ("floorplan.geojson", "floorplan.svg", "floorplan.dxf", "floorplan.ifc", "map.pgm", "front.html"):
        assert (results / "lab_ipa" / name).is_file(), name
    assert svg_subtitle(results / "lab_ipa" / "floorplan.svg").endswith("metres")  # a map: no date
    index = (results / "index.html").read_text()
    assert "4 recordings: 3 with a plan, 1 failed" in index  # broken, lab_ipa, then orebro-corrected and trace0

    rep = floorscan("report", cwd=tmp_path)
    assert rep.returncode == 0, rep.stdout + rep.stderr
    assert "skipped broken: its run failed: ingest failed: " in rep.stdout
    assert f"report: {results}/report.html (lab_ipa)" in rep.stdout
    report = (results / "report.html").read_text()
    assert "Datasets in this report: lab_ipa." in report


@pytest.mark.parametrize("argv, message", [
    (["run", TRACE0, "--evalute"], "floorscan: unrecognized arguments: --evalute (see floorscan --help)"),
    (["run", TRACE0, "--set", "select.kk=5"], "floorscan run: --set select.kk=5: select.kk: unknown key"),
    (["run", TRACE0, "--cores", "two"], "argument --cores: 'two' is not a whole number"),
])
def test_a_mistyped_option_is_one_line(floorscan, argv, message):
    res = floorscan(*argv)
    assert res.returncode == 2 and res.stdout == ""
    assert message in res.stderr and res.stderr.count("\n") == 1, res.stderr

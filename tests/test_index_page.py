"""The index page of a run over several recordings (floorscan.figures.index_page), from
fake results folders: two datasets with a plan, one whose ingest failed."""

import json
import os
import types
from html.parser import HTMLParser
from pathlib import Path

import pandas as pd
import pytest

from floorscan.core.io import InputError, write_table
from floorscan.core.stage import stage_log
from floorscan.figures import index_page as I

GOOD = {
    "ok": True, "line": "GOOD: kept 76 of 76 sampled scans (100 %); map consistency 0.88 (1764 revisited points)",
    "problems": [], "warnings": [],
}  # fmt: skip
WARN = {
    "ok": True,
    "line": "WARNING: kept 9 of 12 sampled scans (75 %); map consistency 0.71 (40 revisited points); "
            "only 9 scans kept: scores from so few scans mean little",
    "problems": [], "warnings": ["only 9 scans kept: scores from so few scans mean little"],
}  # fmt: skip
INGEST_ERROR = "bad <run>.log:1: malformed FLASER line: field 2 is 'x'; expected an integer & >= 1"
SVG = '<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10"><rect width="10" height="5"/></svg>\n'


def _dataset(results: Path, name: str, verdict: dict, k: int, n_kept: int, n_recorded: int,
             counts: dict, front: bool) -> None:
    """The files dataset_status reads, for a dataset whose run made a plan."""
    d = results / name
    (d / "selection").mkdir(parents=True)
    (d / "logs").mkdir()
    (d / "selection" / "selection.json").write_text(json.dumps(
        {"dataset": name, "k": k, "n_kept": n_kept, "n_recorded": n_recorded, "ordering": "wall_coverage"}))
    write_table(pd.DataFrame({"scan_id": [0]}), d / "registration.parquet",
                metadata={"dataset": name, "verdict": json.dumps(verdict), "mode": "poses"})
    (d / "floorplan.geojson").write_text(json.dumps(
        {"type": "FeatureCollection", "features": [], "floorscan": {"dataset": name, **counts}}))
    (d / "logs" / "select.log").write_text("2026-01-01 00:00:00,000 INFO floorscan.select: done select\n")
    os.utime(d / "logs" / "select.log", ns=(1_000_000_000, 1_000_000_000))
    (d / "floorplan.svg").write_text(SVG)
    if front:
        (d / "front.html").write_text("<html><body>front</body></html>\n")


def _failed_ingest(results: Path, name: str, message: str = INGEST_ERROR) -> Path:
    """A dataset whose ingest failed: only its log, written by the stage's own logging."""
    log = results / name / "logs" / "ingest.log"
    log.parent.mkdir(parents=True)
    smk = types.SimpleNamespace(rule="ingest", log=[str(log)], output=[], input=[], wildcards={"dataset": name})
    with pytest.raises(SystemExit):
        with stage_log(smk) as logger:
            logger.info("reading the recording")
            raise InputError(message)
    return log


@pytest.fixture
def results(tmp_path):
    root = tmp_path / "results"
    _dataset(root, "alpha", GOOD, k=10, n_kept=76, n_recorded=321,
             counts={"n_walls": 14, "n_rooms": 5, "n_doors": 1}, front=True)
    _dataset(root, "beta", WARN, k=4, n_kept=9, n_recorded=12,
             counts={"n_walls": 6, "n_rooms": 1, "n_doors": 0}, front=False)
    _failed_ingest(root, "gamma")
    return root


class _Links(HTMLParser):
    def __init__(self):
        super().__init__()
        self.links, self.imgs = [], []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "a":
            self.links.append(a["href"])
        elif tag == "img":
            self.imgs.append((a["src"], a.get("width")))


def test_status_of_a_dataset_with_a_plan(results):
    assert I.dataset_status("alpha", results) == {
        "name": "alpha", "verdict_class": "GOOD", "verdict": GOOD["line"],
        "k": 10, "n_kept": 76, "n_recorded": 321, "n_walls": 14, "n_rooms": 5, "n_doors": 1,
        "floorplan": "alpha/floorplan.svg", "front": "alpha/front.html", "failed": None,
    }  # fmt: skip
    beta = I.dataset_status("beta", results)
    assert (beta["verdict_class"], beta["k"], beta["n_doors"], beta["front"], beta["failed"]) == (
        "WARNING", 4, 0, None, None)


def test_status_of_a_failed_dataset_carries_its_error(results):
    s = I.dataset_status("gamma", results)
    assert s["failed"] == f"ingest failed: {INGEST_ERROR}"
    assert s["floorplan"] is None and s["verdict"] is None and s["k"] is None and s["n_walls"] is None
    assert I.failure_text("gamma", results) == f"ingest failed: {INGEST_ERROR}"


def test_index_lists_every_dataset_and_the_failed_ones_error(results):
    page = results / "index.html"
    statuses = [I.dataset_status(d, results) for d in ("alpha", "beta", "gamma")]
    I.write_index(statuses, page)
    text = page.read_text(encoding="utf-8")
    assert "<p class=\"counts\">3 recordings: 2 with a plan, 1 failed</p>" in text
    for name in ("alpha", "beta", "gamma"):
        assert f'<section class="card" id="{name}">' in text
    assert '<p class="verdict good"><b>GOOD</b>kept 76 of 76 sampled scans (100 %)' in text
    assert '<p class="verdict warning"><b>WARNING</b>kept 9 of 12 sampled scans (75 %)' in text
    assert "10 of 76 kept of 321 recorded scans" in text and "4 of 9 kept of 12 recorded scans" in text
    assert "14 walls, 5 rooms, 1 door" in text and "6 walls, 1 room, 0 doors" in text
    # the error, escaped, in the red block
    assert ('<div class="error"><b>Failed:</b> ingest failed: bad &lt;run&gt;.log:1: malformed FLASER line: '
            "field 2 is &#39;x&#39;; expected an integer &amp; &gt;= 1</div>") in text
    assert "<run>" not in text
    assert "<script" not in text


def test_index_links_point_to_existing_files(results):
    page = results / "index.html"
    I.write_index([I.dataset_status(d, results) for d in ("alpha", "beta", "gamma")], page)
    parser = _Links()
    parser.feed(page.read_text(encoding="utf-8"))
    # alpha's thumbnail and name open its front page; beta has none, its thumbnail opens the plan
    assert parser.links == ["alpha/front.html", "alpha/front.html", "beta/floorplan.svg"]
    assert parser.imgs == [("alpha/floorplan.svg", str(I.THUMB_WIDTH)), ("beta/floorplan.svg", str(I.THUMB_WIDTH))]
    for rel in parser.links + [src for src, _ in parser.imgs]:
        assert (page.parent / rel).is_file(), rel


def test_index_is_the_same_bytes_when_written_again(results, tmp_path):
    page = results / "index.html"
    statuses = [I.dataset_status(d, results) for d in ("alpha", "beta", "gamma")]
    I.write_index(statuses, page)
    first = page.read_bytes()
    os.utime(results / "alpha" / "floorplan.svg", ns=(5_000_000_000, 5_000_000_000))
    I.write_index([I.dataset_status(d, results) for d in ("alpha", "beta", "gamma")], page)
    assert page.read_bytes() == first
    assert not [p.name for p in results.iterdir() if p.name.endswith(".tmp")]


def test_a_name_and_paths_are_escaped_and_quoted(tmp_path):
    page = tmp_path / "index.html"
    I.write_index([{"name": "a&b <1>", "floorplan": "a&b <1>/floorplan.svg", "front": None, "failed": None}], page)
    text = page.read_text(encoding="utf-8")
    assert "<h2>a&amp;b &lt;1&gt;</h2>" in text
    assert 'src="a%26b%20%3C1%3E/floorplan.svg"' in text
    assert "1 recording: 1 with a plan, 0 failed" in text


def test_failure_text_of_a_bug_is_its_exception_line(tmp_path):
    log = tmp_path / "delta" / "logs" / "register.log"
    log.parent.mkdir(parents=True)
    smk = types.SimpleNamespace(rule="register", log=[str(log)], output=[], input=[], wildcards={})
    with pytest.raises(ZeroDivisionError):
        with stage_log(smk):
            1 / 0
    assert I.failure_text("delta", tmp_path) == "stage register failed: ZeroDivisionError: division by zero"


def test_failure_text_without_an_error_names_the_newest_log(tmp_path):
    logs = tmp_path / "eps" / "logs"
    logs.mkdir(parents=True)
    for i, stage in enumerate(("ingest", "poses", "register")):
        (logs / f"{stage}.log").write_text(f"2026-01-01 00:00:0{i},000 INFO floorscan.{stage}: start {stage}\n")
        os.utime(logs / f"{stage}.log", ns=((i + 1) * 10**9, (i + 1) * 10**9))
    assert I.failure_text("eps", tmp_path) == f"failed at register; see {logs / 'register.log'}"
    assert I.failure_text("zeta", tmp_path) is None
    assert I.dataset_status("zeta", tmp_path)["failed"] == f"no floor plan and no log in {tmp_path / 'zeta'}"


def test_an_error_logged_after_the_plan_marks_the_dataset_failed(results):
    plan = results / "alpha" / "floorplan.svg"
    os.utime(plan, ns=(2 * 10**9, 2 * 10**9))
    log = results / "alpha" / "logs" / "front_page.log"
    log.write_text("2026-01-01 00:00:00,000 INFO floorscan.front_page: start\n"
                   "2026-01-01 00:00:01,000 ERROR floorscan.front_page: front_page failed: summary.parquet: no rows\n")
    os.utime(log, ns=(3 * 10**9, 3 * 10**9))
    assert I.dataset_status("alpha", results)["failed"] == "front_page failed: summary.parquet: no rows"
    os.utime(log, ns=(1 * 10**9, 1 * 10**9))  # older than the plan: a stage of an earlier run
    assert I.dataset_status("alpha", results)["failed"] is None


def test_a_poor_verdict_is_read_from_the_register_log(tmp_path):
    line = ("POOR: kept 3 of 40 sampled scans (8 %); map consistency undefined (no place passed twice) "
            "(0 revisited points)")
    log = tmp_path / "eta" / "logs" / "register.log"
    log.parent.mkdir(parents=True)
    log.write_text(f"2026-01-01 00:00:00,000 WARNING floorscan.register: verdict: {line}\n"
                   f"2026-01-01 00:00:01,000 ERROR floorscan.register: register failed: register: the result is poor: "
                   f"{line}\n")
    s = I.dataset_status("eta", tmp_path)
    assert (s["verdict_class"], s["verdict"]) == ("POOR", line)
    assert s["failed"] == f"register failed: register: the result is poor: {line}"
    assert I.counts_line([s]) == "1 recording: 0 with a plan, 1 failed"

"""Issue 36: a folder of recordings in one run (one answer each, one index page, a bad
recording's error without stopping the others), and the answer printed wherever the
run starts (a no-op rerun, a one-file build)."""

from __future__ import annotations

import json

import pytest

from conftest import snakemake


@pytest.fixture(scope="module")
def folder_run(survey_run):
    """The demo's recording twice (the README's two floors, ground.bag and first.bag)
    and a truncated copy of it in one folder, and a text file that is no recording, run
    with `--config path=<folder>/ --configfile house.yaml` (conftest.survey_run)."""
    wd, res, _, _ = survey_run
    return wd, res


def test_a_folder_gives_one_answer_per_recording_and_names_the_bad_one(folder_run):
    wd, res = folder_run
    assert res.returncode != 0  # one recording failed
    assert "survey/: 3 recordings, one dataset each: broken, first, ground (not recordings, left out: notes.txt)" in res.stderr
    lines = res.stdout.strip().splitlines()
    assert lines[0].startswith("broken: FAILED: ingest failed: ")
    assert "survey/broken.bag: cannot read the bag, truncated or corrupt" in lines[0]
    for i, ds in ((1, "first"), (2, "ground")):
        assert lines[i] == f"{ds}: 10 of 76 kept scans (321 recorded), wall_coverage; GOOD; results/{ds}/front.html"
        for name in ("floorplan.ifc", "map.pgm", "summary.md", "front.html", "selection/scans.csv"):
            assert (wd / "results" / ds / name).is_file(), (ds, name)
    assert lines[-1] == "1 of 3 recordings failed: broken"
    assert "index: results/index.html" in lines
    # nothing half-written for the bad one: its log alone
    assert sorted(p.relative_to(wd / "results" / "broken").as_posix() for p in (wd / "results" / "broken").rglob("*")) == [
        "logs", "logs/ingest.log"]
    index = (wd / "results" / "index.html").read_text()
    # the run's three first, then the dataset an earlier run left in results/ (the fixture's demo)
    assert "4 recordings: 3 with a plan, 1 failed" in index
    assert index.index('href="first/front.html"') < index.index('href="demo/front.html"')
    assert 'src="ground/floorplan.svg"' in index and 'href="first/front.html"' in index
    assert "truncated or corrupt" in index


def test_the_printed_report_command_makes_the_report_of_the_good_recordings(folder_run):
    """Issue 47, item 1: the `report:` line of a folder run in which a recording
    failed, pasted as it is, makes the report (of the good recordings' front pages,
    with the run's config file), instead of stopping at the failed one's figures."""
    import shlex
    import subprocess

    wd, res = folder_run
    line = next(l for l in res.stdout.splitlines() if l.startswith("report: "))
    words = shlex.split(line[len("report: "):])
    assert words[-4:] == ["--report", "results/report.html", "results/first/front.html", "results/ground/front.html"]
    assert "house.yaml" in words
    try:
        made = subprocess.run(words, cwd=wd, capture_output=True, text=True, timeout=600)
        assert made.returncode == 0, made.stderr[-2000:]
        report = (wd / "results" / "report.html").read_text()
        assert "Datasets in this report: first, ground." in report
    finally:  # the session's demo run stays as it was: its front page, made again later, links a report that exists
        (wd / "results" / "report.html").unlink(missing_ok=True)


def test_floors_of_one_building_give_one_ifc_with_a_storey_each(folder_run):
    import ifcopenshell
    import ifcopenshell.validate
    from ifcopenshell.util.element import get_decomposition

    wd, res = folder_run
    assert "building: results/building/index.html, results/building/building.ifc (2 storeys)" in res.stdout
    model = ifcopenshell.open(str(wd / "results" / "building" / "building.ifc"))
    storeys = {s.Name: s for s in model.by_type("IfcBuildingStorey")}
    assert sorted(storeys) == ["First floor", "Ground floor"] and storeys["First floor"].Elevation == pytest.approx(3.2)
    for name, storey in storeys.items():  # each holds its own floor's walls and rooms (the demo's: 14 and 5)
        parts = get_decomposition(storey)
        assert sum(e.is_a("IfcWall") for e in parts) == 14 and sum(e.is_a("IfcSpace") for e in parts) == 5, name
    logger = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(model, logger, express_rules=True)
    assert logger.statements == []
    for ds in ("ground", "first"):  # each floor stamped as its own answer is: the plan tables keep the stamp
        floor = json.loads((wd / "results" / "building" / f"{ds}.geojson").read_text())["floorscan"]
        own = json.loads((wd / "results" / ds / "floorplan.geojson").read_text())["floorscan"]
        assert floor["time_stamp"] == own["time_stamp"] != "1970-01-01T00:00:00+00:00", ds
    assert "no time stamp" not in (wd / "results" / "building" / "logs" / "building.log").read_text()
    page = (wd / "results" / "building" / "index.html").read_text()
    assert "Main building" in page and "../first/front.html" in page


def test_the_answer_is_printed_wherever_the_run_starts(demo_run):
    """A rerun with nothing else to do (the target rule alone runs, and onsuccess prints)
    and a one-file build each end with their own dataset's answer, in at most 10 lines,
    naming map.pgm, summary.md and the front page. A file target that is up to date is
    Snakemake's "Nothing to be done", which runs no handler (`floorscan run` prints the
    answer then: tests/test_cli.py)."""
    for args in ((), ("results/demo/front.html", "--forcerun", "front_page")):
        res = snakemake(demo_run, *args)
        assert res.returncode == 0, res.stderr[-2000:]
        assert "1 of 1 steps (100%) done" in res.stderr  # all; front_page
        lines = res.stdout.strip().splitlines()
        assert lines[0].startswith("demo: 10 of 76 kept scans (321 recorded)") and len(lines) <= 10
        text = "\n".join(lines)
        for name in ("results/demo/map.pgm", "results/demo/summary.md", "results/demo/front.html"):
            assert name in text
        assert "(with the evaluation: every plan and score in results/demo/evaluation/)" in text  # the demo's default
    md = (demo_run / "results" / "demo" / "summary.md").read_text()
    assert md.startswith("# Scan reduction summary: demo") and "## The answer" in md
    assert "## Floor plans against the reference map" in md  # the evaluation's part


def test_a_wrong_path_is_one_line(demo_run):
    res = snakemake(demo_run, "--config", "path=no/such/run.bag")
    assert res.returncode != 0
    # relative: read from the working directory, which the line names (`-d` from elsewhere)
    assert (f"path: no/such/run.bag: no such file or folder in {demo_run} (a relative path is read from the working "
            "directory); expected a ROS1 .bag file") in res.stderr
    assert "Traceback" not in res.stderr and "MissingInputException" not in res.stderr
    assert not (demo_run / "results" / "run").exists()


def test_the_recordings_of_a_folder_are_independent_jobs(survey_run):
    """Issue 36, item 6: the job graph of a folder run, without the `all` target that
    gathers them, falls apart into one part per recording, so any executor (the
    cluster profile: tests/test_cluster.py) runs the recordings side by side."""
    import re

    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    _, _, res, _ = survey_run  # the dry run's job graph of the folder with its three recordings
    assert res.returncode == 0, res.stderr[-2000:]
    nodes = dict(re.findall(r"^\s*(\d+)\[label = \"([^\"]*)\"", res.stdout, re.M))
    edges = [(a, b) for a, b in re.findall(r"^\s*(\d+) -> (\d+)$", res.stdout, re.M)
             if "all" not in (nodes[a], nodes[b])]  # fmt: skip
    ids = {n: i for i, n in enumerate(n for n in nodes if nodes[n] != "all")}
    graph = coo_matrix(([1] * len(edges), ([ids[a] for a, _ in edges], [ids[b] for _, b in edges])), (len(ids),) * 2)
    n_parts, part = connected_components(graph, directed=False)
    ingests = [ids[n] for n, label in nodes.items() if label.startswith("ingest")]
    assert n_parts == 3 and len(ingests) == 3  # broken, first, ground
    assert len({part[i] for i in ingests}) == 3


def test_a_folder_of_one_recording_names_what_it_left_out(demo_run, tmp_path):
    """What a folder holds that is no recording (a text file, a subfolder) is named
    however few recordings it holds (issue 45, item 5: it was said only for several)."""
    import shutil

    folder = tmp_path / "one"
    (folder / "day2").mkdir(parents=True)
    shutil.copy(demo_run / "results" / "demo" / "sim" / "recording.bag", folder / "ground.bag")
    (folder / "notes.txt").write_text("the survey\n")
    res = snakemake(demo_run, "-n", "--config", f"path={folder}/")
    assert res.returncode == 0, res.stderr[-2000:]
    assert f"{folder}/: 1 recording, one dataset: ground (not recordings, left out: day2, notes.txt)" in res.stderr

"""Issues 36 and 47: every command of the README and of the pages of docs/ works as
written, and the pages hold together.

Each command of their ``bash`` blocks is checked here (a test fails on a command it
does not know):

- ``make <target>``: ``make -n <target>`` (the recipe exists; ``make test`` is what CI
  runs);
- ``.venv/bin/floorscan ...``: in the copy of the workflow below, run for real, except
  those that build an evaluation or set the pages' example scan topic, which are dry
  runs (``-- -n``); ``--help`` exits 0;
- ``.venv/bin/python -m benchmarks <name> [options]``: the options parse, and the run
  stops there (a run takes minutes to hours: ``benchmarks/README.md``);
- ``.venv/bin/snakemake ...``: in a copy of the workflow with the demo built, as
  written and run for real, except those that redo the demo's stages, build a whole
  evaluation or need a cluster (``-R``, ``--forcerun``, the target ``evaluation``,
  ``--profile``), which are dry runs (``-n``); the pages' example paths
  (``/data/lab_run.bag``, ``/data/survey/``, ``/data/floor/map.yaml``,
  ``/data/floor.png``) stand for the demo's recording, a folder of two copies of it and
  the demo building rasterised as a map (the map_server yaml, and its image alone), the
  example recording's folder ``results/lab_run/`` for the demo recording's
  ``results/recording/``, and the example config files (``my.yaml``, ``house.yaml``)
  are the pages' own YAML blocks.

A command written inline in the prose is one of the blocks' commands, so that it is
tested too; the pages' links and anchors resolve, the README stays short and links
every page, and a stage option a page names exists in its schema.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from conftest import REPO, SHARED_DATA, SNAKEMAKE

README = REPO / "README.md"
#: The README and the reference pages it links: every command in them is tested here.
PAGES = [README, *sorted((REPO / "docs").glob("*.md"))]
#: What a command of the pages starts with: the checks below know these.
KNOWN = ("make ", ".venv/bin/snakemake ", ".venv/bin/python -m benchmarks", "FLOORSCAN_PROFILE=", ".venv/bin/floorscan ")


def blocks(lang: str, pages=PAGES) -> list[str]:
    """The fenced blocks of one language in ``pages`` (an indented fence included)."""
    return [b for page in pages for b in re.findall(rf"```{lang}\n(.*?)```", page.read_text(), re.S)]


def readme_blocks(lang: str) -> list[str]:
    return blocks(lang, [README])


def commands(pages=PAGES) -> list[str]:
    """The commands of the pages' bash blocks (comments and blank lines left out)."""
    out = []
    for block in blocks("bash", pages):
        for line in block.splitlines():
            line = re.sub(r"\s+#.*$", "", line).strip()
            if line and not line.startswith("#"):
                out.append(line)
    return out


def readme_commands() -> list[str]:
    """The commands of the README and of docs/, each once (the name of issue 36's test)."""
    return list(dict.fromkeys(commands()))


def test_the_readme_has_the_commands_this_test_knows():
    cmds = readme_commands()
    assert len(cmds) >= 15 and "make test" in cmds
    assert all(c.startswith(KNOWN) for c in cmds), [c for c in cmds if not c.startswith(KNOWN)]
    assert not [c for c in cmds if c.startswith("snakemake")]  # without .venv/bin: "command not found"
    # the README's own: the two set-up commands and the one command for a recording, both forms
    own = commands([README])
    assert own[:2] == ["make run", "make test"], own
    assert ".venv/bin/floorscan run /data/lab_run.bag" in own
    assert ".venv/bin/snakemake --cores 2 --config path=/data/lab_run.bag" in own


@pytest.mark.parametrize("cmd", [c for c in readme_commands() if c.startswith("make ")])
def test_make_targets_exist(cmd):
    res = subprocess.run(["make", "-n", *shlex.split(cmd)[1:]], cwd=REPO, capture_output=True, text=True)
    assert res.returncode == 0, res.stderr


@pytest.mark.parametrize("cmd", [c for c in readme_commands() if c.startswith(".venv/bin/python -m benchmarks")])
def test_benchmark_commands_parse(cmd):
    """The benchmark's options parse as written (its argparse parser runs, then the run
    stops before the benchmark does; a misspelt option exits 2); a benchmark named
    without options is one the runner knows."""
    args = shlex.split(cmd)[3:]
    assert parse_benchmark_args(args).returncode == 0


def parse_benchmark_args(args: list[str]):
    """``python -m benchmarks <args>`` stopped right after its options parse."""
    code = (
        "import argparse, sys\n"
        "parse = argparse.ArgumentParser.parse_args\n"
        "def parse_only(self, args=None, namespace=None):\n"
        "    parse(self, args, namespace)\n"
        "    sys.exit(0)\n"
        "argparse.ArgumentParser.parse_args = parse_only\n"
        "import benchmarks.__main__ as m\n"
        "known = sorted(p.stem[len('bench_'):] for p in m.Path(m.__file__).parent.glob('bench_*.py'))\n"
        f"runs = m.split_args({args!r}, known)\n"
        "name, opts = runs[0]\n"
        "sys.exit(m.main([name, *opts]) if opts else 0)\n"
    )
    return subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=120)


def test_a_misspelt_benchmark_option_fails_the_check():
    """The check above can fail: an option the benchmark does not have exits 2, an
    unknown benchmark exits non-zero."""
    assert parse_benchmark_args(["pipeline", "--datasetz", "hallways"]).returncode == 2
    assert parse_benchmark_args(["pipeline", "--datasets", "hallways", "--target", "plan"]).returncode == 0
    assert parse_benchmark_args(["selectionz"]).returncode != 0


def test_the_benchmarks_have_a_help():
    res = subprocess.run([sys.executable, "-m", "benchmarks", "--help"], cwd=REPO, capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 0 and "benchmarks: " in res.stdout and "pipeline" in res.stdout, res.stderr


@pytest.fixture(scope="module")
def readme_workdir(survey_run):
    """The demo's workflow copy with the README's example files: my.yaml, house.yaml
    (its YAML blocks, their paths the demo's) and the folder of two recordings that
    conftest.survey_run built with that house.yaml (so the README's folder commands
    find their datasets built: the same paths)."""
    wd, _, _, survey = survey_run
    bag = wd / "results" / "demo" / "sim" / "recording.bag"
    for block in blocks("yaml"):
        m = re.match(r"# (\S+\.yaml)\n", block)
        if m:
            (wd / m.group(1)).write_text(block.replace("/data/lab_run.bag", str(bag)))
    # the README's map examples: the demo building rasterised as a map_server map, and its image alone
    from floorscan.sim.building_file import load_building
    from floorscan.sim.occupancy_map import write_building_map

    (wd / "maps" / "floor").mkdir(parents=True, exist_ok=True)
    write_building_map(load_building(wd / "config" / "buildings" / "demo.yaml"), wd / "maps" / "floor" / "map.yaml")
    from PIL import Image

    Image.open(wd / "maps" / "floor" / "map.pgm").save(wd / "maps" / "floor.png")
    return wd, {"/data/lab_run.bag": str(bag), "/data/survey/": str(survey) + "/",
                "/data/floor/map.yaml": str(wd / "maps" / "floor" / "map.yaml"), "/data/floor.png": str(wd / "maps" / "floor.png"),
                "results/lab_run/": "results/recording/"}


@pytest.mark.workflow
@pytest.mark.parametrize(
    "cmd", [c for c in readme_commands() if ".venv/bin/snakemake" in c and "profiles/slurm" not in c]
)
def test_snakemake_commands_work_as_written(readme_workdir, cmd):
    wd, paths = readme_workdir
    for example, real in paths.items():
        cmd = cmd.replace(example, real)
    env = dict(os.environ)
    words = shlex.split(cmd)
    while "=" in words[0]:  # FLOORSCAN_PROFILE=/tmp/prof
        key, value = words.pop(0).split("=", 1)
        env[key] = value
    assert words[0] == ".venv/bin/snakemake"
    shared = [name for name, d in yaml.safe_load((REPO / "config" / "config.yaml").read_text())["datasets"].items()
              if "../shared/" in str(d.get("path", "")) and re.search(rf"\b{re.escape(name)}\b", cmd)]
    if shared and not SHARED_DATA.is_dir():
        pytest.skip(f"{', '.join(shared)}: real recordings not found at {SHARED_DATA} (../shared/data)")
    heavy = any(w in ("-R", "--forcerun", "--profile", "evaluation") for w in words)
    args = [*words[1:], "-n"] if heavy else words[1:]
    res = subprocess.run([str(SNAKEMAKE), *args], cwd=wd, capture_output=True, text=True, env=env, timeout=600)
    assert res.returncode == 0, res.stderr[-3000:]
    assert "Error" not in res.stderr, res.stderr[-3000:]
    # every run ends with the answer of its datasets; but a file target or an --until
    # with nothing to do is Snakemake's "Nothing to be done", which runs no handler
    # (docs/running.md says so)
    restricted = "--until" in words or any(w.startswith("results/") for w in words)
    if not heavy and "--unlock" not in words and not (restricted and "Nothing to be done" in res.stderr):
        answers = (" kept scans (", ": no answer yet (", ": floor plan of an occupancy map, ")
        assert any(a in res.stdout for a in answers), res.stdout[-2000:]


@pytest.mark.workflow
@pytest.mark.parametrize("cmd", [c for c in readme_commands() if c.startswith(".venv/bin/floorscan ")])
def test_floorscan_commands_work_as_written(readme_workdir, cmd):
    """The `floorscan` commands, run in the same copy of the workflow
    (``FLOORSCAN_REPOSITORY``), in the pages' order: a plan is run for real, a run
    with ``--evaluate`` or with the pages' example scan topic (``/base_scan``; the demo
    recording's is ``/scan``) as a dry run (``-- -n``), the report of the last run for
    real, the help as it is. The real runs of trace0, a folder, a map, --set and
    --evaluate: tests/test_cli_realdata.py."""
    wd, paths = readme_workdir
    paths = {**paths, "run.bag": paths["/data/lab_run.bag"]}
    words = shlex.split(cmd)
    words = [paths.get(w, w) for w in words]
    assert words[0] == ".venv/bin/floorscan"
    env = {**os.environ, "FLOORSCAN_REPOSITORY": str(wd),
           "PYTHONPATH": os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")]))}

    def floorscan(*argv):
        return subprocess.run([sys.executable, "-m", "floorscan.cli", *argv], cwd=wd, capture_output=True,
                              text=True, env=env, timeout=600)

    args = words[1:]
    if "--help" in args:
        res = floorscan(*args)
        assert res.returncode == 0 and res.stdout.startswith("usage: floorscan"), res.stderr
        return
    dry = "--" in args and "-n" in args[args.index("--"):]
    if args[0] == "run" and not dry and ("--evaluate" in args or "--set" in args):
        args, dry = [*args, "--", "-n"], True
    if args == ["report"] and not (wd / ".snakemake" / "floorscan" / "configfiles").is_file():
        assert floorscan("run", paths["/data/lab_run.bag"]).returncode == 0  # a run to report on
    try:
        res = floorscan(*args)
    finally:  # the session's demo run stays as it was: its front page, made again later, links a report that exists
        (wd / "results" / "report.html").unlink(missing_ok=True)
    assert res.returncode == 0, res.stdout[-2000:] + res.stderr[-2000:]
    assert "Traceback" not in res.stdout + res.stderr
    if dry:
        assert re.search(r"^dry run: \d+ jobs to run", res.stdout, re.M), res.stdout[-2000:]
    elif args[0] == "run":
        assert re.search(r"^recording: \d+ of \d+ kept scans \(\d+ recorded\)", res.stdout, re.M), res.stdout[-2000:]
    else:
        assert re.search(r"^report: .*results/report\.html \(", res.stdout, re.M), res.stdout[-2000:]


def test_the_slurm_profile_names_an_installed_executor():
    """``--profile workflow/profiles/slurm`` needs a SLURM cluster; its executor plugin
    is installed and its profile names it."""
    import importlib.util

    assert "executor: slurm" in (REPO / "workflow" / "profiles" / "slurm" / "config.yaml").read_text()
    assert importlib.util.find_spec("snakemake_executor_plugin_slurm") is not None


# ------------------------------------------------------------------ the pages hold together (issue 47, item 5)

#: The stage sections of the config, each with its schema (workflow/schemas/<section>.schema.yaml).
SECTIONS = ("ingest", "poses", "simulate", "register", "hulls", "select", "walls", "floorplan", "score")
#: A file's suffix, not an option (`floorplan.svg`, `select.schema.yaml`).
SUFFIXES = {"geojson", "svg", "dxf", "ifc", "smk", "py", "yaml", "parquet", "png", "pgm", "log", "tsv", "csv", "json", "md"}


def slug(heading: str) -> str:
    """A heading's anchor as GitHub makes it: lower case, code marks and punctuation
    dropped, spaces to hyphens."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower().replace("`", ""))
    return text.replace(" ", "-")


def prose(text: str) -> str:
    """A page without its fenced blocks."""
    return re.sub(r"```.*?```", "", text, flags=re.S)


def broken_links(page: Path, text: str) -> list[str]:
    """The relative links of a page whose file, or whose anchor in that file, is missing."""
    bad = []
    for target in re.findall(r"\]\(([^)\s]+)\)|<img src=\"([^\"]+)\"", prose(text)):
        target = next(t for t in target if t)
        if re.match(r"[a-z]+:", target):  # https:, mailto:
            continue
        file, _, anchor = target.partition("#")
        path = (page.parent / file).resolve() if file else page
        if not path.exists():
            bad.append(target)
        elif anchor and path.suffix == ".md":
            headings = re.findall(r"^#+ (.+)$", prose(path.read_text()), re.M)
            if anchor not in {slug(h) for h in headings}:
                bad.append(target)
    return bad


def inline_commands(text: str) -> list[str]:
    """The code spans of a page's prose written as a command of KNOWN's kinds."""
    spans = re.findall(r"`([^`\n]+(?:\n[^`\n]+)?)`", prose(text))
    return [" ".join(s.split()) for s in spans if s.startswith(KNOWN)]


def unknown_options(text: str) -> list[str]:
    """The ``<section>.<key>[.<key>...]`` a page's code spans name that its section's
    schema does not have (``--set select.k=5``, ``register.graph.agreement_m``)."""
    bad = []
    for span in re.findall(r"`([^`]+)`", prose(text)):
        for section, keys in re.findall(rf"(?<![\w./-])({'|'.join(SECTIONS)})\.([A-Za-z0-9_.]+)", span):
            keys = keys.rstrip(".").removesuffix(".*").split(".")
            if keys[-1] in SUFFIXES or keys == ["{geojson,svg,dxf,ifc}"]:
                continue
            node = yaml.safe_load((REPO / "workflow" / "schemas" / f"{section}.schema.yaml").read_text())
            for key in keys:
                node = (node.get("properties") or {}).get(key) if isinstance(node, dict) else None
                if node is None:
                    bad.append(f"{section}.{'.'.join(keys)}")
                    break
    return bad


def test_the_readme_is_short_and_links_every_page():
    text = README.read_text()
    assert len(text.splitlines()) <= 150
    assert max(len(line) for line in text.splitlines()) <= 300
    linked = {Path(t).name for t in re.findall(r"\]\(docs/([^)#]+)", text)}
    assert linked == {p.name for p in PAGES[1:]}, linked
    assert "[LICENSE](LICENSE)" in text and (REPO / "LICENSE").read_text().startswith("MIT License")


def test_the_readme_shows_a_small_picture_of_a_real_plan():
    text = README.read_text()
    first_screen = "\n".join(text.splitlines()[:20])
    images = re.findall(r"<img src=\"([^\"]+)\"|!\[[^]]*\]\(([^)]+)\)", first_screen)
    assert len(images) == 1, images
    image = REPO / next(i for i in images[0] if i)
    assert image.parent == REPO / "docs" / "images" and image.suffix == ".png"
    assert image.stat().st_size < 300_000
    assert "intel-corrected.log.gz" in first_screen  # which recording it is


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_links_and_anchors_resolve(page):
    assert broken_links(page, page.read_text()) == []


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_a_command_in_the_prose_is_a_tested_command(page):
    cmds = {" ".join(c.split()) for c in readme_commands()}
    assert [c for c in inline_commands(page.read_text()) if c not in cmds] == []


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_the_options_a_page_names_exist(page):
    assert unknown_options(page.read_text()) == []


def test_the_page_checks_can_fail(tmp_path):
    """Each check above finds a planted defect."""
    page = tmp_path / "page.md"
    (tmp_path / "there.md").write_text("# Here\n")
    assert broken_links(page, "[a](nowhere.md) [b](there.md#here) [c](there.md#gone) [d](https://x.org)") == [
        "nowhere.md", "there.md#gone"]
    assert inline_commands("run `.venv/bin/snakemake --cores 2 plan`, not `--cores`") == [
        ".venv/bin/snakemake --cores 2 plan"]
    assert unknown_options("`select.k`, `--set select.kk=5`, `register.graph.agreement_m`, `floorplan.svg`, "
                           "`floorplan.rooms.door_width_m`") == ["select.kk", "floorplan.rooms.door_width_m"]
    assert slug("The `floorscan` command") == "the-floorscan-command"

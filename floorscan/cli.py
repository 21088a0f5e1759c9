"""The ``floorscan`` command: runs the repository's Snakemake workflow on recordings,
maps or folders, prints one line per finished job and then the run's answer.

Snakemake stays the engine: the command runs it as a subprocess on the Snakefile of
the repository this package lives in (``--snakefile``, ``--directory``: it works from
any folder), with a config file it writes from its options
(``.snakemake/floorscan/run.yaml`` in the repository; ``--set`` typed by the schemas,
:func:`floorscan.core.settings.setting`). It holds no stage logic: the answer is read
from the run's files once Snakemake has ended (the datasets of the manifest the
Snakefile writes, their results and stage logs: :mod:`floorscan.figures.run_end`), a
failed job's paragraph the one its stage wrote to its log
(:func:`floorscan.figures.index_page.log_error`), and everything else Snakemake says
goes to ``.snakemake/floorscan/run.log``::

    floorscan run /data/lab_run.bag                      # the plan
    floorscan run /data/survey/ /data/floor/map.yaml --evaluate --set select.k=5
    floorscan run --config house.yaml -- -n              # a dry run of a config file
    floorscan report                                     # the report of the last run

To add an option: add it to :func:`parser` and turn it into config (``run_config``) or
Snakemake arguments (``snakemake_command``); what a stage does belongs in the workflow.
``FLOORSCAN_REPOSITORY`` names another copy of the workflow (the tests run one).
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import subprocess
import sys
import threading
import time
from pathlib import Path

from floorscan.figures.progress import Progress, job_dataset, jobs_to_run

#: The folder that holds the package, the Snakefile and config/ (a git checkout).
PACKAGE_ROOT = Path(__file__).resolve().parents[1]

#: Where the command keeps the last run's config and Snakemake's output (in the repository).
STATE_DIR = Path(".snakemake") / "floorscan"

_EPILOG = """\
A PATH is a recording (.bag, ROS2 bag folder, .db3, .mcap, CARMEN .log/.log.gz, a folder
of .pcd scans), an occupancy map (a map_server .yaml, a .pgm/.png image) or a folder of
them; several PATHs are one run whose datasets are all their recordings. Without PATH the
datasets of the config's `target` run (the shipped synthetic demo, or those of --config).

Outputs land in results/<dataset>/ of the repository ({repo}); Snakemake's own output
in {log}.
"""


class UsageError(Exception):
    """A misuse of the command: one line, exit status 2."""


class _Parser(argparse.ArgumentParser):
    """argparse with a misuse as one line (its usage is in --help)."""

    def error(self, message):
        raise UsageError(f"{self.prog}: {message} (see {self.prog} --help)")


def repository() -> Path:
    """The workflow's folder: ``FLOORSCAN_REPOSITORY``, else the package's parent folder."""
    return Path(os.environ.get("FLOORSCAN_REPOSITORY") or PACKAGE_ROOT).resolve()


def parser() -> argparse.ArgumentParser:
    """The command line: ``floorscan run`` and ``floorscan report``."""
    repo = repository()
    epilog = _EPILOG.format(repo=repo, log=repo / STATE_DIR / "run.log")
    top = _Parser(
        prog="floorscan",
        description="Floor plans from rover LIDAR recordings and occupancy maps (a Snakemake workflow).",
        epilog="floorscan run --help: the options of a run. Anything after `--` goes to Snakemake as it is.",
    )
    sub = top.add_subparsers(dest="command", metavar="{run,report}", parser_class=_Parser)
    run = sub.add_parser(
        "run",
        help="make the floor plan of recordings, maps or folders (and with --evaluate the evaluation)",
        description="Make the floor plan of each recording or map; print one line per finished job, then the answer.",
        epilog=epilog + "\nExamples:\n  floorscan run /data/lab_run.bag\n"
        "  floorscan run /data/survey/ --evaluate --cores 4\n"
        "  floorscan run run.bag --set scan_topic=/base_scan --set select.k=5\n"
        "  floorscan run floor.png --set resolution_m=0.1\n"
        "  floorscan run --config house.yaml /data/survey/ -- -n      (a dry run)\n",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    run.add_argument("paths", nargs="*", metavar="PATH", help="recordings, maps or folders of them")
    run.add_argument("--evaluate", action="store_true",
                     help="also build the evaluation (plans of every ordering, extractor and k, scores, figures); "
                          "default: the plan alone, unless the --config file sets `evaluate: true`")
    run.add_argument("--cores", type=_positive_int, default=2, metavar="N", help="cores Snakemake may use (default 2)")
    run.add_argument("--config", metavar="FILE", type=_config_file,
                     help="a config file (as snakemake --configfile): datasets, a building, any stage's options")
    run.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", dest="settings",
                     help="set one option, nested keys dotted and typed by the schema: select.k=5, walls.k='[5, all]', "
                          "resolution_m=0.1; a dataset key (scan_topic=/base_scan, pose.source=tf) applies to "
                          "the PATHs' recordings. Repeatable. The options: workflow/schemas/*.schema.yaml")
    report = sub.add_parser(
        "report",
        help="build the HTML report of the last run's datasets (snakemake --report)",
        description="Build the report of what the last `floorscan run` made: a dataset whose run failed or did not "
                    "finish is left out, with a line that says so.",
        epilog=epilog,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    report.add_argument("--output", "-o", metavar="FILE", help="the report (default results/report.html in the repository)")
    return top


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} is not at least 1")
    return value


def _config_file(text: str) -> Path:
    import yaml

    path = Path(text).expanduser().absolute()
    if not path.is_file():
        raise argparse.ArgumentTypeError(f"{text}: no such file")
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else type(e).__name__
        raise argparse.ArgumentTypeError(f"{text}: not a YAML config file ({first})") from None
    if not isinstance(data, dict):
        raise argparse.ArgumentTypeError(f"{text}: expected a YAML mapping of config keys, got {type(data).__name__}")
    return path


def split_passthrough(argv: list[str]) -> tuple[list[str], list[str]]:
    """The command's own arguments and those after the first ``--`` (for Snakemake)."""
    if "--" in argv:
        i = argv.index("--")
        return argv[:i], argv[i + 1:]
    return list(argv), []


def _set_nested(config: dict, keys: list[str], value) -> None:
    node = config
    for key in keys[:-1]:
        if not isinstance(node.get(key), dict):
            node[key] = {}
        node = node[key]
    node[keys[-1]] = value


def run_config(args: argparse.Namespace) -> dict:
    """The config the run passes to Snakemake (its last config file, over
    config/config.yaml and ``--config``): the PATHs as absolute paths (one: a string,
    several: a list), ``evaluate``, and each ``--set`` typed by the schemas.

    Raises
    ------
    UsageError
        A PATH that does not exist, a ``--set`` that is not KEY=VALUE, names an unknown
        key or a value the schema rejects, sets ``path`` or a dataset key without PATH.
    """
    import yaml

    from floorscan.core.config import ConfigError
    from floorscan.core.settings import setting

    config: dict = {}
    paths = []
    for p in args.paths:
        path = Path(p).expanduser()
        if not path.exists():
            raise UsageError(f"floorscan run: {p}: no such file or folder")
        paths.append(os.path.abspath(path))  # absolute and normal (`../my data/` has no `..` left)
    if paths:
        config["path"] = paths[0] if len(paths) == 1 else paths
    user = yaml.safe_load(args.config.read_text(encoding="utf-8")) if args.config else {}
    if args.evaluate or "evaluate" not in user:
        config["evaluate"] = bool(args.evaluate)
    for item in args.settings:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise UsageError(f"floorscan run: --set {item}: expected KEY=VALUE, e.g. --set select.k=5")
        if key == "path" or key.startswith("path."):
            raise UsageError("floorscan run: --set path: give recordings as PATH arguments")
        try:
            keys, value = setting(key, text)
        except ConfigError as e:
            raise UsageError(f"floorscan run: --set {item}: {e}") from None
        if keys[0] == "path_options" and not paths:
            raise UsageError(f"floorscan run: --set {item}: {key} is a key of a dataset, applied to the PATHs' "
                             f"recordings; without PATH set datasets.<name>.{key}")
        _set_nested(config, keys, value)
    return config


def snakemake_executable() -> list[str]:
    """Snakemake beside this Python (its venv), else ``python -m snakemake``."""
    exe = Path(sys.executable).with_name("snakemake")
    return [os.fspath(exe)] if exe.is_file() else [sys.executable, "-m", "snakemake"]


def snakemake_command(repo: Path, configfiles: list[Path], cores: int, extra: list[str]) -> list[str]:
    """The Snakemake command line of a run of the repository's workflow."""
    cmd = [*snakemake_executable(), "--snakefile", os.fspath(repo / "Snakefile"), "--directory", os.fspath(repo)]
    if configfiles:
        cmd += ["--configfile", *map(os.fspath, configfiles)]
    return [*cmd, "--cores", str(cores), *extra]


def _environment() -> dict:
    """The jobs import this package: its folder first on PYTHONPATH."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (os.fspath(PACKAGE_ROOT), env.get("PYTHONPATH")) if p)
    return env


def print_answer(repo: Path, manifest: dict, start_ns: int, progress: Progress) -> None:
    """The run's answer, read from its files (:func:`floorscan.figures.run_end.run_answer`),
    its paths from the repository when the user is elsewhere; a failed job whose stage
    logged no error is named by its rule and log, as Snakemake said them."""
    from floorscan.figures.run_end import run_answer

    root = Path("results") if Path.cwd().resolve() == repo else repo / "results"
    failed = [(job_dataset(b), f"{b['rule']} failed; its log: {', '.join(os.fspath(repo / p) for p in b.get('log') or [])}")
              for b in progress.failures]
    program = shlex.quote(sys.argv[0]) if Path(sys.argv[0]).name == "floorscan" else "floorscan"  # as typed (make)
    ran = [ds for ds in map(job_dataset, progress.jobs.values()) if ds]  # the target rule's job has none
    for line in run_answer(manifest["datasets"], ran, start_ns, root, failed, f"{program} report", manifest.get("building")):
        print(line, flush=True)


def _stream(proc: subprocess.Popen, progress: Progress, log, dry_run: bool, repo: Path) -> None:
    """Read the run's two streams: stdout is the answer (a dry run's stdout is
    Snakemake's log), stderr Snakemake's log."""
    lock = threading.Lock()

    def answer():
        for line in proc.stdout:
            with lock:
                log.write(line)
                if dry_run:
                    progress.feed(line)
                else:  # Snakemake's own stdout (a passed-through --list-rules, --summary, ...)
                    print(line.rstrip("\n"), flush=True)

    reader = threading.Thread(target=answer, daemon=True)
    reader.start()
    for line in proc.stderr:
        with lock:
            log.write(line)
            progress.feed(line)
    reader.join()
    with lock:
        progress.close()


def _state(repo: Path) -> Path:
    state = repo / STATE_DIR
    try:
        state.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise UsageError(f"floorscan: cannot write {state}: {e.strerror}") from None
    return state


def run_snakemake(cmd: list[str], repo: Path, log_path: Path, dry_run: bool = False,
                  env: dict | None = None) -> tuple[int, Progress]:
    """Run Snakemake, showing progress; its output saved to ``log_path``."""
    progress = Progress(repo)
    with open(log_path, "w", encoding="utf-8") as log:
        log.write("$ " + shlex.join(cmd) + "\n")
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, bufsize=1,
                                env=env or _environment(), errors="replace")
        try:
            _stream(proc, progress, log, dry_run, repo)
            code = proc.wait()
        except KeyboardInterrupt:
            proc.wait()  # Snakemake got the same interrupt: let it end its jobs
            print("floorscan: interrupted", file=sys.stderr)
            return 130, progress
    return code, progress


def _tail(log_path: Path, n: int = 1) -> str:
    lines = [l for l in log_path.read_text(encoding="utf-8", errors="replace").splitlines() if l.strip()]
    return "\n".join(lines[-n:])


def command_run(args: argparse.Namespace, extra: list[str]) -> int:
    import yaml

    repo = repository()
    config = run_config(args)
    state = _state(repo)
    run_yaml = state / "run.yaml"
    run_yaml.write_text("# written by `floorscan run` (the last run's options; `floorscan report` reads it)\n"
                        + yaml.safe_dump(config, sort_keys=False), encoding="utf-8")
    configfiles = [*([args.config] if args.config else []), run_yaml]
    (state / "configfiles").write_text("\n".join(map(os.fspath, configfiles)) + "\n", encoding="utf-8")
    dry_run = any(a in ("-n", "--dry-run", "--dryrun") for a in extra)
    log_path = state / "run.log"
    # the Snakefile writes the run's datasets to the manifest; the answer is printed here,
    # from the run's files, once Snakemake has ended (nothing to be done included)
    from floorscan.figures.run_end import MANIFEST_ENV, read_manifest

    manifest = state / "manifest.json"
    manifest.unlink(missing_ok=True)
    env = {**_environment(), MANIFEST_ENV: os.fspath(manifest)}
    start_ns = time.time_ns()
    code, progress = run_snakemake(snakemake_command(repo, configfiles, args.cores, extra), repo, log_path, dry_run, env)
    run = None if dry_run or code == 130 else read_manifest(manifest)
    if run is not None:
        print_answer(repo, run, start_ns, progress)
    if dry_run and code == 0:
        print(f"dry run: {jobs_to_run(log_path.read_text(encoding='utf-8'))} jobs to run (the job table: {log_path})")
    elif code not in (0, 130) and not progress.shown:
        print(f"floorscan run: Snakemake stopped (exit status {code}): {_tail(log_path)}\n  its output: {log_path}",
              file=sys.stderr)
    elif code not in (0, 130):
        print(f"Snakemake's output: {log_path}", file=sys.stderr)
    return code


_DATASET = re.compile(r"^\s+wildcards: (?:.*, )?dataset=([^,\s]+)", re.M)
#: The inputs of the target rule ``all`` in a dry run's job list (Snakemake 9's text).
_ALL_INPUT = re.compile(r"^(?:local)?rule all:\n(?:    .*\n)*?    input: (.*)$", re.M)


def report_targets(dry_run: str, datasets: list[str]) -> list[str]:
    """The files of the target rule ``all`` that belong to ``datasets``
    (``results/<dataset>/...``), read from a dry run's job list: as targets of
    ``snakemake --report`` they give the report every figure the run made of those
    datasets and nothing of the others (a failed one's figures do not exist). Their
    front pages when the dry run names no inputs of ``all``.

    Parameters
    ----------
    dry_run : str
        The output of ``snakemake -n --forceall``.
    datasets : list of str

    Returns
    -------
    list of str
        Paths relative to the workflow's folder.
    """
    wanted = set(datasets)
    m = _ALL_INPUT.search(dry_run)
    files = [f for f in (m.group(1).split(", ") if m else []) if f.split("/")[:1] == ["results"]
             and len(f.split("/")) > 2 and f.split("/")[1] in wanted]
    return files or [f"results/{ds}/front.html" for ds in datasets]


def command_report(args: argparse.Namespace, extra: list[str]) -> int:
    """The report of the last run's datasets that are complete (a dry run has nothing
    to do for them); each other one named with why it is left out."""
    from floorscan.figures.index_page import failure_text

    repo = repository()
    state = _state(repo)
    listed = state / "configfiles"
    if not listed.is_file():
        raise UsageError("floorscan report: no run to report on yet; run `floorscan run PATH` first")
    configfiles = [Path(p) for p in listed.read_text(encoding="utf-8").split("\n") if p]
    missing = [p for p in configfiles if not p.is_file()]
    if missing:
        raise UsageError(f"floorscan report: the last run's config file {missing[0]} is gone; run `floorscan run` again")
    base = snakemake_command(repo, configfiles, 1, [])

    def dry_run(*flags) -> str:
        res = subprocess.run([*base, "-n", *flags], capture_output=True, text=True, env=_environment())
        if res.returncode != 0:
            raise UsageError(f"floorscan report: the last run's workflow does not load: {_tail_text(res)}")
        return res.stdout + res.stderr

    def datasets(text: str) -> list[str]:
        return list(dict.fromkeys(_DATASET.findall(text)))

    jobs = dry_run("--forceall")
    every = datasets(jobs)
    pending = set(datasets(dry_run()))
    complete = [d for d in every if d not in pending]
    for ds in every:
        if ds in pending:
            why = failure_text(ds, repo / "results")
            print(f"skipped {ds}: " + (f"its run failed: {why}" if why else "not made yet (floorscan run makes it)"))
    if not complete:
        print("floorscan report: no dataset of the last run is complete; nothing to report", file=sys.stderr)
        return 1
    out = Path(args.output).expanduser().absolute() if args.output else repo / "results" / "report.html"
    targets = report_targets(jobs, complete)
    log_path = state / "report.log"
    code, _ = run_snakemake([*base, "--report", os.fspath(out), *extra, *targets], repo, log_path)
    if code == 0:
        print(f"report: {out} ({', '.join(complete)})")
    else:
        print(f"floorscan report: Snakemake stopped (exit status {code}): {_tail(log_path)}\n  its output: {log_path}",
              file=sys.stderr)
    return code


def _tail_text(res: subprocess.CompletedProcess) -> str:
    lines = [l for l in (res.stderr + res.stdout).splitlines() if l.strip()]
    return lines[-1] if lines else f"exit status {res.returncode}"


def main(argv: list[str] | None = None) -> int:
    """The ``floorscan`` console script; the exit status."""
    own, extra = split_passthrough(list(sys.argv[1:] if argv is None else argv))
    try:
        args = parser().parse_args(own)
        if args.command is None:
            raise UsageError("floorscan: expected a command, run or report (see floorscan --help)")
        if not (repository() / "Snakefile").is_file():
            raise UsageError(f"floorscan: no Snakefile in {repository()}: the command runs the workflow of the "
                             "repository its package is in (pip install -e <repository>)")
        if args.command == "run":
            return command_run(args, extra)
        return command_report(args, extra)
    except UsageError as e:
        print(e, file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

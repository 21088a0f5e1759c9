"""End to end: wall-clock time against the recording's duration (the real-time factor),
and time and peak memory of every stage (issue 8; thesis Table 5.1).

Run: ``.venv/bin/python -m benchmarks pipeline [--datasets hallways hallways3d
hallways3d_6000 campus200] [--cores 2] [--target all|plan|evaluation ...] [--workdir DIR]
[--keep] [--snakemake-args '...']``

For each dataset the workflow runs in a copy of the repository (so ``results/`` of
the checkout is never touched; ``PYTHONPATH`` points at the copy): first the
simulate stage alone (it makes the input recording; it is not processing, so it is
not timed), then everything from ingest to the final outputs, timed. Printed per
dataset:

- the recording's duration (first to last scan stamp, s), its scans, the largest
  scan (points) as recorded and as registered, and the bag's size;
- the end-to-end wall time and the real-time factor = duration / wall time (target
  on 2 cores: >= 10 on the 3D recordings);
- a row per stage: jobs, summed and slowest job time from Snakemake's benchmark
  files (``results/<ds>/benchmarks/*.tsv``), and peak resident memory (RSS) of a
  job both from those files and from polling every job's process here every 0.2 s
  (Snakemake samples every 0.5 s for the first 15 s of a job, then every 30 s, so
  its figure can miss the peak of a long job), and the CPU seconds of its jobs
  (polled; they do not count other processes' time, but they too grow when the VM
  is slow: 88 to 122 CPU-s for the same hallways3d run).

Around every timed run a speed probe (:func:`speed_probe`: the same fixed
single-threaded NumPy and Python work) is timed: a hint of the machine's speed at the
run's start and end (a shared VM's speed drifts: up to 1.6x within an hour on the
project's). Only a hint: it cannot see the drift during a run (measured 30-46 ms around
hallways3d runs of 52-74 s; the fastest run had the fastest probe, but one at 34 ms
took 74 s).

``hallways3d_6000`` and ``campus200`` are not in ``config/config.yaml``: the benchmark
adds them with a ``--configfile`` overlay (:data:`EXTRA_DATASETS`). ``hallways3d_6000``:
the hallways floor, 3D scanner, the rover at 0.248 m/s instead of 0.3, so ~6000 scans
over ~600 s. ``campus200``: a 200 m x 200 m floor of 240 rooms on a grid of corridors
(:mod:`benchmarks.campus`, its building file written into the copy), 2D scanner, the
rover at 1.5 m/s: ~20 000 scans over ~2100 s.

With several ``--target`` values each dataset runs each target in turn, from its
recording (everything but the simulation rebuilt), and the table of each is printed.

``--workdir DIR`` keeps the copy in DIR and reuses its simulated recordings (only
``results/<ds>/sim`` is kept between runs; everything else is rebuilt).
"""

from __future__ import annotations

import argparse
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import yaml

from benchmarks.campus import CAMPUS_SPEED_MPS, write_campus
from floorscan.figures.stage_times import read_benchmark

REPO = Path(__file__).resolve().parents[1]
DEFAULT_DATASETS = ("hallways", "hallways3d", "hallways3d_6000")
#: The building of the ``campus200`` dataset (config/buildings/<name>.yaml in the copy).
CAMPUS = "campus200"
#: Datasets the benchmark adds to the config (a --configfile overlay).
EXTRA_DATASETS = {
    "hallways3d_6000": {
        "description": "hallways floor, 3D scanner, slower rover (0.248 m/s): ~6000 scans (benchmark)",
        "format": "synthetic",
        "building": "hallways",
        "scanner": "3d",
        "seed": 1,
        "params": {"simulate": {"speed_mps": 0.248}},
    },
    "campus200": {
        "description": "200 m x 200 m campus floor, corridors every 40 m, 240 rooms, 2D scanner: ~20 000 scans (benchmark)",
        "format": "synthetic",
        "building": CAMPUS,
        "scanner": "2d",
        "seed": 1,
        "params": {"simulate": {"speed_mps": CAMPUS_SPEED_MPS}},
    },
}
_IGNORE = shutil.ignore_patterns("results", ".snakemake", ".git", ".venv", "__pycache__", ".pytest_cache")
_SCRIPT = re.compile(r"\.snakemake/scripts/tmp[^./]*\.([A-Za-z0-9_]+)\.py")


def prepare_copy(workdir: Path) -> Path:
    """Copy the repository's code and config into ``workdir/repo`` (results kept)."""
    dst = workdir / "repo"
    dst.mkdir(parents=True, exist_ok=True)
    for item in REPO.iterdir():
        if item.name in ("results", ".snakemake", ".git", ".venv", "__pycache__", ".pytest_cache"):
            continue
        target = dst / item.name
        if target.is_dir() and not target.is_symlink():
            shutil.rmtree(target)
        elif target.exists() or target.is_symlink():
            target.unlink()
        if item.is_dir():
            shutil.copytree(item, target, ignore=_IGNORE)
        else:
            shutil.copy2(item, target)
    venv = dst / ".venv"
    if not venv.exists():  # a worktree has no .venv of its own: the environment running this
        venv.symlink_to(REPO / ".venv" if (REPO / ".venv").exists() else Path(sys.prefix))
    shared = workdir / "shared"  # datasets refer to ../shared/data
    if not shared.exists() and (REPO.parent / "shared").exists():
        shared.symlink_to(REPO.parent / "shared")
    (dst / "config" / "bench_pipeline.yaml").write_text(yaml.safe_dump({"datasets": EXTRA_DATASETS}))
    write_campus(dst / "config" / "buildings" / f"{CAMPUS}.yaml", name=CAMPUS)
    return dst


class RssPoller:
    """Peak RSS (MB) and CPU time (s) of the Snakemake script jobs under a process, by
    script name (CPU time as last seen, up to ``interval_s`` short of a job's end). A
    job's worker processes (edge ICP, scoring) count toward its script: CPU summed,
    the peak RSS of the largest process."""

    def __init__(self, pid: int, interval_s: float = 0.2):
        import psutil

        self._psutil = psutil
        self.root = psutil.Process(pid)
        self.interval_s = interval_s
        self.peak: dict[str, float] = {}
        self._cpu: dict[int, tuple[str, float]] = {}
        self._job: dict[int, str] = {}  # pid -> script of the job it belongs to
        #: pid -> [script, first seen, last seen] (s since the poller started)
        self.spans: dict[int, list] = {}
        self.total_peak = 0.0
        #: CPU seconds of the Snakemake process itself (DAG, scheduling, file checks)
        self.snakemake_cpu = 0.0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()

    @property
    def cpu(self) -> dict[str, float]:
        """CPU seconds (user + system) summed over the jobs of each script."""
        out: dict[str, float] = {}
        for name, sec in self._cpu.values():
            out[name] = out.get(name, 0.0) + sec
        return out

    def _run(self):
        ps = self._psutil
        t0 = time.perf_counter()
        while not self._stop.is_set():
            now = time.perf_counter() - t0
            try:
                procs = [self.root, *self.root.children(recursive=True)]
            except ps.Error:
                break
            total = 0.0
            try:
                t = self.root.cpu_times()
                self.snakemake_cpu = t.user + t.system
            except (ps.Error, OSError):
                pass
            for p in procs:
                try:
                    rss = p.memory_info().rss / 2**20
                    cmd = " ".join(p.cmdline())
                    t = p.cpu_times()
                    ppid = p.ppid()
                except (ps.Error, OSError):
                    continue
                total += rss
                m = _SCRIPT.search(cmd)
                name = m.group(1) if m else self._job.get(ppid)  # a job's worker process
                if name:
                    self._job[p.pid] = name
                    self.peak[name] = max(self.peak.get(name, 0.0), rss)
                    self._cpu[p.pid] = (name, t.user + t.system)
                    if m:
                        self.spans.setdefault(p.pid, [name, now, now])[2] = now
            self.total_peak = max(self.total_peak, total)
            self._stop.wait(self.interval_s)


def snakemake(repo: Path, dataset: str, cores: int, targets: list[str], poll: bool = False, extra: tuple = ()):
    """Run Snakemake in ``repo`` for ``dataset``; returns (seconds, RssPoller or None).

    With ``poll`` (the timed run) only modification times trigger reruns, so a kept
    simulation is not redone; without it (the simulation), changed parameters or
    code of the simulate stage do."""
    cmd = [
        str(repo / ".venv" / "bin" / "snakemake"), "--cores", str(cores),
        "--configfile", "config/config.yaml", "config/bench_pipeline.yaml",
        "--config", f"target=[{dataset}]", "--quiet", *extra, "all",
        *(["--rerun-triggers", "mtime"] if poll else []),
        *([] if not targets else ["--", *targets]),
    ]  # fmt: skip
    env = {**os.environ, "PYTHONPATH": str(repo)}
    log = repo / f"bench_pipeline_{dataset}.log"
    t0 = time.perf_counter()
    with open(log, "w") as fh:
        proc = subprocess.Popen(cmd, cwd=repo, env=env, stdout=fh, stderr=subprocess.STDOUT)
        poller = RssPoller(proc.pid) if poll else None
        if poller:
            with poller:
                rc = proc.wait()
        else:
            rc = proc.wait()
    seconds = time.perf_counter() - t0
    if rc != 0:
        tail = "\n".join(log.read_text().splitlines()[-30:])
        raise RuntimeError(f"snakemake failed for {dataset} (exit {rc}); log {log}:\n{tail}")
    return seconds, poller


#: Stages of the table: a benchmark file or script is counted under the longest of
#: these that its name starts with (``hulls_shard_scans_0-99`` -> ``hulls``).
STAGES = (
    "simulate", "ingest", "poses", "register", "register_figure", "hulls", "select", "selection_figures",
    "scan_walls", "walls", "map_walls", "floorplan", "answer_floorplans", "score_runs", "score", "score_walls_figures",
    "score_figures",
)  # fmt: skip


#: The score stage as ARCHITECTURE.md draws it (config section ``score``): the
#: reference map, the metrics of the evaluation grid, the curves (counted under
#: ``score``) and the summary.
SCORE_STAGES = ("reference", "score_runs", "score")
#: The scoring figures: the figures stage's, printed beside the score stage (issue 21
#: measured the two together).
SCORE_FIGURES = ("score_walls_figures", "score_figures")


def stage_of(name: str) -> str:
    """Stage of a benchmark file name (``floorplan_random_ransac`` -> ``floorplan``) or a
    script name (``hulls_shard`` -> ``hulls``); the name itself when none matches."""
    hits = [st for st in STAGES if name == st or name.startswith(st + "_")]
    return max(hits, key=len) if hits else name


def stage_table(
    bench_dir: Path, polled: dict[str, float], cpu: dict[str, float] | None = None, spans: dict | None = None
) -> pd.DataFrame:
    """A row per stage from the benchmark TSVs: jobs, s_total, s_max, rss_mb (TSV),
    the polled peak RSS of the stage's jobs (MB), their polled CPU seconds, and when
    the stage's first job was first seen and its last job last seen (``start``,
    ``end``: s since Snakemake started; from ``RssPoller.spans``)."""
    rows = []
    for p in sorted(bench_dir.rglob("*.tsv")):
        b = read_benchmark(p)
        name = p.relative_to(bench_dir).with_suffix("").as_posix().replace("/", "_")
        rows.append({"job": name, "stage": stage_of(name), "s": float(b["s"].mean()),
                     "rss_mb": float(pd.to_numeric(b["max_rss"], errors="coerce").max())})
    jobs = pd.DataFrame(rows)
    t = jobs.groupby("stage", sort=False).agg(
        jobs=("job", "size"), s_total=("s", "sum"), s_max=("s", "max"), rss_mb=("rss_mb", "max")
    )
    t["rss_polled_mb"] = [
        max([v for k, v in polled.items() if stage_of(k) == st], default=np.nan) for st in t.index
    ]
    cpu = cpu or {}
    t["cpu_s"] = [sum(v for k, v in cpu.items() if stage_of(k) == st) if cpu else np.nan for st in t.index]
    for k, v in polled.items():  # scripts of no stage above (e.g. the shard plans)
        if stage_of(k) not in t.index:
            t.loc[stage_of(k)] = [0, np.nan, np.nan, np.nan, v, cpu.get(k, np.nan)]
    spans = list((spans or {}).values())
    t["start"] = [min([a for n, a, _ in spans if stage_of(n) == st], default=np.nan) for st in t.index]
    t["end"] = [max([b for n, _, b in spans if stage_of(n) == st], default=np.nan) for st in t.index]
    order = {st: i for i, st in enumerate(STAGES)}
    return t.iloc[sorted(range(len(t)), key=lambda i: (order.get(t.index[i], len(STAGES)), t.index[i]))]


def largest_scan(path: Path) -> tuple[int, int, int]:
    """(scans, largest scan's points, total points) of a points table (scan_id column only)."""
    ids = pq.read_table(path, columns=["scan_id"])["scan_id"].to_numpy()
    counts = np.bincount(ids - ids.min()) if len(ids) else np.zeros(0, int)
    counts = counts[counts > 0]
    return len(counts), int(counts.max(initial=0)), len(ids)


def speed_probe(repeats: int = 3) -> float:
    """CPU milliseconds of a fixed single-threaded workload (the least of ``repeats``):
    sorting 10**6 random floats and a Python loop of 3 * 10**5 steps, the two kinds of
    work the stages do. Lower is faster; the same machine at the same speed gives
    the same figure within a few percent."""
    rng = np.random.default_rng(0)
    x = rng.random(1_000_000)
    best = np.inf
    for _ in range(repeats):
        t = time.process_time()
        np.sort(x)
        acc = 0
        for i in range(300_000):
            acc += i * i % 7
        best = min(best, time.process_time() - t)
    return best * 1e3


def run_dataset(repo: Path, dataset: str, cores: int, extra: tuple = (), target: str = "all") -> dict:
    res = repo / "results" / dataset
    if res.exists():  # keep the simulated recording only
        for item in res.iterdir():
            if item.name != "sim":
                shutil.rmtree(item) if item.is_dir() else item.unlink()
    synthetic = (yaml.safe_load((repo / "config/config.yaml").read_text())["datasets"].get(dataset)
                 or EXTRA_DATASETS.get(dataset, {})).get("format") == "synthetic"
    t_sim = None
    if synthetic:
        t_sim, _ = snakemake(repo, dataset, cores, [f"results/{dataset}/sim/recording.bag"])
        (res / "benchmarks" / "simulate.tsv").unlink(missing_ok=True)
    load_before, probe_before = os.getloadavg()[0], speed_probe()
    wall, poller = snakemake(repo, dataset, cores, [] if target == "all" else [target], poll=True, extra=extra)
    load_after, probe_after = os.getloadavg()[0], speed_probe()
    index = pq.read_table(res / "scan_index.parquet", columns=["t_ns", "n_points"]).to_pandas()
    duration = (index["t_ns"].max() - index["t_ns"].min()) / 1e9
    bag = res / "sim" / "recording.bag"
    kept, largest_reg, reg_points = largest_scan(res / "registered.parquet")
    return {
        "dataset": dataset, "target": target, "duration_s": duration, "scans": len(index),
        "largest_scan": int(index["n_points"].max()), "points": int(index["n_points"].sum()),
        "kept": kept, "largest_registered": largest_reg, "registered_points": reg_points,
        "bag_mb": bag.stat().st_size / 2**20 if bag.exists() else np.nan,
        "wall_s": wall, "rtf": duration / wall, "simulate_s": t_sim,
        "stages": stage_table(res / "benchmarks", poller.peak, poller.cpu, poller.spans), "peak_all_jobs_mb": poller.total_peak,
        "concurrency": concurrency(list(poller.spans.values()), wall),
        "snakemake_cpu_s": poller.snakemake_cpu,
        "load": (load_before, load_after), "probe_ms": (probe_before, probe_after),
    }  # fmt: skip


def concurrency(spans: list, wall_s: float, longest: int = 4) -> dict:
    """How many jobs ran at once over a run, from the poller's job spans.

    Parameters
    ----------
    spans : list of [script, start_s, end_s]
        :attr:`RssPoller.spans`' values, seconds since the poller started.
    wall_s : float
        The run's wall time, seconds.
    longest : int
        How many of the longest stretches with one job alone to name.

    Returns
    -------
    dict
        ``seconds``: {0: s, 1: s, 2: s} with no job, one, two or more running;
        ``alone``: the ``longest`` stretches of one job alone, ``(start_s, end_s,
        script)``, longest first.
    """
    events = sorted([(a, 1, n) for n, a, _ in spans] + [(b, -1, n) for n, _, b in spans], key=lambda e: (e[0], -e[1]))
    seconds = {0: 0.0, 1: 0.0, 2: 0.0}
    alone, running, t_prev = [], {}, 0.0
    for t, step, name in events + [(max(wall_s, events[-1][0] if events else 0.0), 0, "")]:
        n = sum(running.values())
        seconds[min(n, 2)] += max(t - t_prev, 0.0)
        if n == 1 and t > t_prev:
            job = next(k for k, v in running.items() if v)
            if alone and alone[-1][2] == job and abs(alone[-1][1] - t_prev) < 1e-9:
                alone[-1] = (alone[-1][0], t, job)
            else:
                alone.append((t_prev, t, job))
        if step:
            running[name] = running.get(name, 0) + step
        t_prev = max(t_prev, t)
    alone.sort(key=lambda a: a[0] - a[1])
    return {"seconds": seconds, "alone": alone[:longest]}


def report(r: dict, cores: int) -> None:
    print(f"\n### {r['dataset']} (target {r['target']}, --cores {cores})")
    print(f"recording: {r['duration_s']:.1f} s, {r['scans']} scans, {r['points'] / 1e6:.1f} M points, "
          f"largest scan {r['largest_scan']} points" + (f", bag {r['bag_mb']:.0f} MB" if np.isfinite(r["bag_mb"]) else ""))
    print(f"registered: {r['kept']} kept scans, {r['registered_points'] / 1e6:.2f} M points, "
          f"largest {r['largest_registered']} points")
    sim = "" if r["simulate_s"] is None else f", it took {r['simulate_s']:.0f} s"
    print(f"end to end (ingest .. figures; simulate excluded{sim}): "
          f"{r['wall_s']:.1f} s; real-time factor {r['rtf']:.2f}x (target >= 10x on 3D)")
    t = r["stages"]
    cpu = t["cpu_s"].sum()
    print(f"CPU time of all jobs {cpu:.0f} s (wall x cores = {r['wall_s'] * cores:.0f} s); load average "
          f"{r['load'][0]:.1f} before, {r['load'][1]:.1f} after: other processes on the machine slow "
          "every job; the CPU seconds leave their time out, but grow too when the VM is slow")
    print(f"speed probe (fixed single-threaded work, lower is faster): {r['probe_ms'][0]:.0f} ms before, "
          f"{r['probe_ms'][1]:.0f} ms after")
    print(f"CPU time of the Snakemake process itself (DAG, scheduling, checks): {r['snakemake_cpu_s']:.1f} s")
    print(f"peak RSS of all running jobs together: {r['peak_all_jobs_mb']:.0f} MB")
    print(f"{'stage':<18}{'jobs':>5}{'s total':>10}{'s max':>9}{'CPU s':>8}{'RSS MB':>9}{'polled':>9}"
          f"{'from s':>8}{'to s':>7}")
    for st, row in t.iterrows():
        print(f"{st:<18}{int(row['jobs']):>5d}{row['s_total']:>10.1f}{row['s_max']:>9.1f}{row['cpu_s']:>8.1f}"
              f"{row['rss_mb']:>9.0f}{row['rss_polled_mb']:>9.0f}{row['start']:>8.1f}{row['end']:>7.1f}")
    print(f"{'sum of jobs':<18}{int(t['jobs'].sum()):>5d}{t['s_total'].sum():>10.1f}{'':>9}{cpu:>8.1f}")
    scoring = [st for st in SCORE_STAGES if st in t.index]
    if scoring:
        score_cpu = t.loc[scoring, "cpu_s"].sum()
        figures = [st for st in SCORE_FIGURES if st in t.index]
        with_figures = score_cpu + t.loc[figures, "cpu_s"].sum()
        print(f"score stage ({', '.join(scoring)}; score counts score_curves): {score_cpu:.1f} of {cpu:.1f} CPU-s "
              f"({100 * score_cpu / cpu:.1f} %); with the scoring figures ({', '.join(figures)}): "
              f"{with_figures:.1f} CPU-s ({100 * with_figures / cpu:.1f} %)")
    print("from s / to s: when the stage's first job started and its last job ended, seconds after Snakemake "
          "started (polled every 0.2 s)")
    c = r.get("concurrency")
    if c:
        sec = c["seconds"]
        print(f"jobs running at once (polled): none {sec[0]:.1f} s, one {sec[1]:.1f} s, two or more {sec[2]:.1f} s; "
              "the longest stretches of one job alone: "
              + ", ".join(f"{job} {a:.1f}-{b:.1f} s" for a, b, job in c["alone"]))


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--datasets", nargs="+", default=list(DEFAULT_DATASETS))
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--workdir", type=Path, help="keep the copy here and reuse its simulated recordings")
    ap.add_argument("--keep", action="store_true", help="do not delete the temporary copy")
    ap.add_argument("--target", nargs="+", default=["all"], choices=("all", "plan", "evaluation"),
                    help="the workflow targets timed, each in turn: all (default), plan (the recommended plan "
                         "alone), evaluation")
    ap.add_argument("--snakemake-args", default="", help="more Snakemake options for the timed run, e.g. '--scheduler greedy'")
    args = ap.parse_args(argv)
    extra = tuple(shlex.split(args.snakemake_args))
    workdir = args.workdir or Path(tempfile.mkdtemp(prefix="floorscan-bench-pipeline-"))
    repo = prepare_copy(workdir)
    print(f"bench_pipeline: workflow copy {repo}, --cores {args.cores}, datasets {args.datasets}")
    try:
        results = []
        for ds in args.datasets:
            for target in args.target:
                r = run_dataset(repo, ds, args.cores, extra, target)
                report(r, args.cores)
                results.append(r)
        print("\n### summary")
        print(f"{'dataset':<18}{'target':>11}{'duration s':>11}{'scans':>7}{'largest':>9}{'wall s':>9}{'RTF':>7}"
              f"{'CPU s':>8}{'RTF/CPU':>9}{'max job RSS MB':>16}{'probe ms':>10}")
        for r in results:
            cpu = r["stages"]["cpu_s"].sum()
            print(f"{r['dataset']:<18}{r['target']:>11}{r['duration_s']:>11.1f}{r['scans']:>7d}{r['largest_scan']:>9d}"
                  f"{r['wall_s']:>9.1f}{r['rtf']:>7.2f}{cpu:>8.0f}{r['duration_s'] / cpu:>9.2f}"
                  f"{r['stages']['rss_polled_mb'].max():>16.0f}{max(r['probe_ms']):>10.0f}")
        print("RTF = recording duration / end-to-end wall time; RTF/CPU = duration / CPU seconds of all jobs "
              f"(the wall time on an idle machine is at least CPU s / {args.cores}); probe ms: the slower "
              "of the speed probes around the run (lower is faster)")
    finally:
        if args.workdir is None and not args.keep:
            shutil.rmtree(workdir, ignore_errors=True)


if __name__ == "__main__":
    main(sys.argv[1:])

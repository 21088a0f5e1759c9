"""Stability of the plan under micrometre changes of a recording's ranges (issue 44, item 4).

Run: ``.venv/bin/python -m benchmarks stability [--dataset intel] [--seeds 1 2 3]
[--amplitude-um 10] [--cores 2] [--workdir DIR] [--keep]``

A CARMEN recording (default the ``intel`` dataset of ``config/config.yaml``) is written
again, outside the repository (a temporary folder, or ``--workdir``), once per seed: every
range of every ``FLASER`` line plus a uniform draw in [-a, +a] (``--amplitude-um``, default
10 um) from ``numpy.random.default_rng(seed)``, printed with 6 decimals (1 um). Seed 0
writes the ranges unchanged (only their printing differs): a control, whose plan must be
the recording's own. Each copy is a dataset of its own (``<dataset>_s<seed>``, a
``--configfile`` overlay) and the workflow's ``plan`` target runs on the recording and on
every copy in a copy of the repository (:func:`benchmarks.bench_pipeline.prepare_copy`;
the checkout's ``results/`` is never touched).

Printed per dataset, so that a change of the plan can be traced to the stage where it
starts:

- register: the largest change of a kept scan's pose against the recording's (m, rad),
  and the scans kept;
- select: the selected scans (how many differ from the recording's);
- map walls: the segments of the selected scans' map and the occupancy cells whose
  hit / miss class differs;
- plan: walls, faces, rooms, doors, clutter (:func:`floorscan.core.plan_tables.read_plan_tables`).

The same seed writes the same copy; the measurements are in ``benchmarks/README.md``.
"""

from __future__ import annotations

import argparse
import gzip
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from benchmarks.bench_pipeline import REPO, prepare_copy
from floorscan.core.plan_tables import read_plan_tables

DEFAULT_SEEDS = (0, 1, 2, 3)


def perturb_carmen(src: Path, dst: Path, seed: int, amplitude_m: float) -> int:
    """Write ``src`` (a CARMEN log, gzip or plain) to ``dst`` (gzip) with each range of its
    ``FLASER`` lines changed by a uniform draw in [-amplitude_m, +amplitude_m].

    Parameters
    ----------
    src, dst : Path
        The recording read, and the copy written (gzip, any suffix).
    seed : int
        Seed of ``numpy.random.default_rng``; 0 changes nothing (the control).
    amplitude_m : float
        Largest change of a range, metres.

    Returns
    -------
    int
        The ranges changed.
    """
    rng = np.random.default_rng(seed)
    opener = gzip.open if src.suffix == ".gz" else open
    n_changed = 0
    with opener(src, "rt") as fin, gzip.open(dst, "wt") as fout:
        for line in fin:
            tok = line.split()
            if tok[:1] != ["FLASER"]:
                fout.write(line)
                continue
            n = int(tok[1])
            r = np.array(tok[2 : 2 + n], dtype=np.float64)
            if seed != 0:
                r = r + rng.uniform(-amplitude_m, amplitude_m, n)
                n_changed += n
            tok[2 : 2 + n] = [f"{v:.6f}" for v in r]
            fout.write(" ".join(tok) + "\n")
    return n_changed


def run_plans(repo: Path, datasets: list[str], cores: int) -> None:
    """The ``plan`` target of ``datasets`` in the workflow copy ``repo``, under ``nice``."""
    cmd = [
        "nice", "-n", "10", str(repo / ".venv" / "bin" / "snakemake"), "--cores", str(cores),
        "--configfile", "config/config.yaml", "config/bench_stability.yaml",
        "--config", f"target=[{','.join(datasets)}]", "--quiet", "--", "plan",
    ]  # fmt: skip
    log = repo / "bench_stability.log"
    with open(log, "w") as fh:
        rc = subprocess.run(cmd, cwd=repo, env={**os.environ, "PYTHONPATH": str(repo)},
                            stdout=fh, stderr=subprocess.STDOUT).returncode
    if rc != 0:
        tail = "\n".join(log.read_text().splitlines()[-30:])
        raise RuntimeError(f"snakemake failed (exit {rc}); log {log}:\n{tail}")


def plan_counts(results: Path) -> dict[str, int]:
    """Walls, faces, rooms, doors and clutter of ``results/plan_tables``."""
    t = read_plan_tables(results / "plan_tables")
    return {name: len(t[name]) for name in ("walls", "faces", "rooms", "doors", "clutter")}


def stage_changes(base: Path, other: Path) -> dict[str, float]:
    """How far each stage's output of ``other`` lies from ``base`` (two results folders)."""
    a = pd.read_parquet(base / "registration.parquet").set_index("scan_id")
    b = pd.read_parquet(other / "registration.parquet").set_index("scan_id")
    both = a.index[a["kept"] & b["kept"]]
    dxy = np.hypot(a.loc[both, "x_m"] - b.loc[both, "x_m"], a.loc[both, "y_m"] - b.loc[both, "y_m"])
    dyaw = np.abs(np.angle(np.exp(1j * (a.loc[both, "yaw_rad"] - b.loc[both, "yaw_rad"]))))
    sa = set(pd.read_parquet(base / "selection" / "scans.parquet")["scan_id"])
    sb = set(pd.read_parquet(other / "selection" / "scans.parquet")["scan_id"])
    ga = pd.read_parquet(base / "walls" / "map" / "selected_grid.parquet")
    gb = pd.read_parquet(other / "walls" / "map" / "selected_grid.parquet")
    cells = ga.merge(gb, on=["row", "col"], how="outer", suffixes=("_a", "_b")).fillna(0)
    hit = (cells["n_hit_scans_a"] > 0) != (cells["n_hit_scans_b"] > 0)
    counts = (cells["n_hit_scans_a"] != cells["n_hit_scans_b"]) | (cells["n_miss_scans_a"] != cells["n_miss_scans_b"])
    return {
        "kept": int(b["kept"].sum()),
        "max_dxy_m": float(dxy.max()),
        "max_dyaw_rad": float(dyaw.max()),
        "selected_differ": len(sa ^ sb) // 2,
        "cells_hit_differ": int(hit.sum()),
        "cells_counts_differ": int(counts.sum()),
        "map_segments": len(pd.read_parquet(other / "walls" / "map" / "selected.parquet")),
    }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", default="intel", help="a CARMEN dataset of config/config.yaml (default intel)")
    ap.add_argument("--seeds", type=int, nargs="+", default=list(DEFAULT_SEEDS),
                    help="one copy per seed; seed 0 is the unchanged control (default 0 1 2 3)")
    ap.add_argument("--amplitude-um", type=float, default=10.0, help="largest change of a range, micrometres")
    ap.add_argument("--cores", type=int, default=2)
    ap.add_argument("--workdir", type=Path, help="keep the copy and its results here")
    ap.add_argument("--keep", action="store_true", help="do not delete the temporary copy")
    args = ap.parse_args(argv)
    workdir = args.workdir or Path(tempfile.mkdtemp(prefix="floorscan-bench-stability-"))
    repo = prepare_copy(workdir)
    try:
        cfg = yaml.safe_load((REPO / "config" / "config.yaml").read_text())["datasets"][args.dataset]
        src = (REPO / cfg["path"]).resolve()
        if not src.is_file():
            print(f"skipped: {src} is absent (the shared recordings, ../shared/data)")
            return
        data = workdir / "perturbed"
        data.mkdir(exist_ok=True)
        overlay = {}
        for seed in args.seeds:
            name = f"{args.dataset}_s{seed}"
            dst = data / f"{name}.log.gz"
            n = perturb_carmen(src, dst, seed, args.amplitude_um * 1e-6)
            print(f"{name}: {n} ranges changed by up to {args.amplitude_um:g} um (seed {seed}) -> {dst}")
            overlay[name] = {"description": f"{args.dataset}, ranges +- {args.amplitude_um:g} um, seed {seed}",
                             "path": str(dst)}
        (repo / "config" / "bench_stability.yaml").write_text(yaml.safe_dump({"datasets": overlay}))
        names = [args.dataset, *overlay]
        run_plans(repo, names, args.cores)
        res = repo / "results"
        base = plan_counts(res / args.dataset)
        rows = []
        for name in names:
            row = {"dataset": name, **plan_counts(res / name)}
            if name != args.dataset:
                row.update(stage_changes(res / args.dataset, res / name))
            row["same_counts"] = all(row[k] == base[k] for k in ("walls", "rooms", "doors"))
            rows.append(row)
        table = pd.DataFrame(rows).set_index("dataset")
        with pd.option_context("display.width", 200, "display.max_columns", 20):
            print(table)
        changed = [f"{args.dataset}_s{seed}" for seed in args.seeds if seed != 0]
        same = int(table.loc[changed, "same_counts"].sum())
        print(f"{same} of {len(changed)} changed copies give {args.dataset}'s counts of walls, rooms and doors "
              f"({base['walls']} walls, {base['rooms']} rooms, {base['doors']} doors)"
              + ("" if 0 not in args.seeds else
                 f"; the control (seed 0) {'does' if table.loc[f'{args.dataset}_s0', 'same_counts'] else 'does NOT'}"))
    finally:
        if args.workdir is None and not args.keep:
            shutil.rmtree(workdir, ignore_errors=True)


if __name__ == "__main__":
    main(sys.argv[1:])

"""Time and memory per stage (thesis Table 5.1) from the Snakemake benchmark files of a
dataset (``results/<dataset>/benchmarks``).

:func:`stage_times` sums the jobs of each stage (a job's stage from its benchmark
file's name, :func:`stage_of`; a new stage is added to :data:`STAGES`);
:func:`plot_stage_times` draws the table.
"""

from __future__ import annotations

import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from floorscan.figures.style import save_figure  # noqa: E402

#: Stage names recognised in benchmark file names (first token otherwise).
STAGES = (
    "ingest", "poses", "simulate", "register", "hulls", "select", "walls",
    "floorplan", "score",
)  # fmt: skip


def read_benchmark(path) -> pd.DataFrame:
    """A Snakemake benchmark TSV, with "NA"/"-" as missing.

    Parameters
    ----------
    path : path

    Returns
    -------
    pandas.DataFrame
        Columns ``s``, ``h:m:s``, ``max_rss``, ...; one row per repeat.
    """
    return pd.read_csv(path, sep="\t", na_values=["NA", "-", ""])


def stage_of(name: str) -> str:
    """Stage of a benchmark file's name relative to the benchmarks folder, e.g.
    ``walls/sequential/ransac/k5`` or ``walls_sequential_ransac_k5`` -> ``walls``.

    Parameters
    ----------
    name : str

    Returns
    -------
    str
        A name of :data:`STAGES`, else the name's first part.
    """
    for st in STAGES:
        if name == st or re.match(rf"^{st}[/_.\-]", name):
            return st
    return re.split(r"[/_.\-]", name)[0]


def stage_times(bench_dir) -> pd.DataFrame:
    """Table 5.1 from the benchmark files present under ``bench_dir`` (recursive).

    Parameters
    ----------
    bench_dir : path

    Returns
    -------
    pandas.DataFrame
        A row per stage in pipeline order (unknown stages after, by name): ``stage``,
        ``n_jobs`` (benchmark files), ``s_total`` (sum over jobs of the mean over
        repeats, seconds), ``s_max`` (slowest job, seconds), ``max_rss_mb`` (largest
        resident memory of any job, MB; NaN when not measured). Empty when no file.
    """
    bench_dir = Path(bench_dir)
    rows = []
    for p in sorted(bench_dir.rglob("*.tsv")) if bench_dir.exists() else []:
        try:
            b = read_benchmark(p)
        except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError):
            continue
        if "s" not in b.columns or b.empty:
            continue
        name = p.relative_to(bench_dir).with_suffix("").as_posix()
        rss = pd.to_numeric(b.get("max_rss"), errors="coerce") if "max_rss" in b else None
        rows.append(
            {
                "stage": stage_of(name),
                "job": name,
                "s": float(pd.to_numeric(b["s"], errors="coerce").mean()),
                "max_rss_mb": float(rss.max()) if rss is not None else np.nan,
            }
        )
    cols = ["stage", "n_jobs", "s_total", "s_max", "max_rss_mb"]
    if not rows:
        return pd.DataFrame(columns=cols)
    jobs = pd.DataFrame(rows)
    agg = jobs.groupby("stage", sort=False).agg(
        n_jobs=("job", "size"), s_total=("s", "sum"), s_max=("s", "max"),
        max_rss_mb=("max_rss_mb", "max"),
    ).reset_index()
    rank = {s: i for i, s in enumerate(STAGES)}
    agg["_o"] = [rank.get(s, len(STAGES)) for s in agg["stage"]]
    return agg.sort_values(["_o", "stage"]).drop(columns="_o").reset_index(drop=True)[cols]


def plot_stage_times(table: pd.DataFrame, out, title: str = "") -> None:
    """Bar charts of total time and peak memory per stage (thesis Table 5.1).

    Parameters
    ----------
    table : pandas.DataFrame
        :func:`stage_times`.
    out : path
        PNG output.
    title : str
    """
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.8))
    if len(table):
        y = np.arange(len(table))
        axes[0].barh(y, table["s_total"], color="tab:blue")
        axes[0].set_yticks(y, [f"{s} ({n})" for s, n in zip(table["stage"], table["n_jobs"])])
        axes[0].invert_yaxis()
        axes[1].barh(y, table["max_rss_mb"].fillna(0), color="tab:orange")
        axes[1].set_yticks(y, table["stage"])
        axes[1].invert_yaxis()
    else:
        for ax in axes:
            ax.text(0.5, 0.5, "no benchmark files", ha="center", transform=ax.transAxes)
    axes[0].set_xlabel("time, all jobs of the stage (s)")
    axes[1].set_xlabel("peak resident memory of a job (MB)")
    axes[0].set_title("time per stage (number of jobs)", fontsize=10)
    axes[1].set_title("memory per stage", fontsize=10)
    fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, out)

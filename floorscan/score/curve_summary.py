"""The summary of the quality-vs-k curves (:mod:`floorscan.score.curves`) and its tables.

:func:`curve_summary` reads, per ordering, the k reaching 95 % and 99 % of the
all-scan plan's F1 (:func:`first_k_reaching`), the area under the F1-vs-k curve up to
20 % of the kept scans (:func:`area_under_curve`), and the ratio of k95 to the
oracle's. :func:`curve_summary_markdown` writes it as the Markdown table of
``summary.md``, headed by the line of
:func:`~floorscan.core.score_tables.beats_random_line`; its columns and cells
(:data:`~floorscan.core.score_tables.SUMMARY_COLUMNS`,
:func:`~floorscan.core.score_tables.summary_cell`) are those the HTML pages show
(:mod:`floorscan.core.score_tables`).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from floorscan.core.score_tables import ORACLE, SUMMARY_COLUMNS, summary_cell


def first_k_reaching(k: np.ndarray, f1: np.ndarray, target: float) -> float:
    """The first k of the curve whose F1 reaches ``target`` (NaN when none does).

    Parameters
    ----------
    k : (N,) int ndarray
        Numbers of scans of the curve's points, increasing.
    f1 : (N,) float ndarray
        F1 at each k (a NaN never reaches the target).
    target : float
        F1 to reach; reached at ``f1 >= target - 1e-12``.

    Returns
    -------
    float
        The first such k, as a float; NaN when no point reaches ``target``.
    """
    hit = np.flatnonzero(np.asarray(f1) >= target - 1e-12)
    return float(np.asarray(k)[hit[0]]) if len(hit) else math.nan


def area_under_curve(k: np.ndarray, f1: np.ndarray, n_kept: int, up_to: float = 0.2) -> float:
    """Mean F1 over k from 0 to ``up_to`` of the kept scans (trapezoids on k /
    n_kept, F1 0 at k 0, the curve linearly interpolated at the end): 1 for a curve at
    F1 1 from the first scan.

    Parameters
    ----------
    k : (N,) int ndarray
        Numbers of scans of the curve's points, increasing.
    f1 : (N,) float ndarray
        F1 at each k; NaN counts as 0.
    n_kept : int
        Kept scans of the recording.
    up_to : float
        Fraction of the kept scans the mean is taken over.

    Returns
    -------
    float
        The area under F1 against ``k / n_kept`` from 0 to ``up_to``, divided by
        ``up_to`` (a curve ending before ``up_to`` adds nothing beyond its end).
    """
    x = np.concatenate([[0.0], np.asarray(k, dtype=np.float64) / n_kept])
    y = np.concatenate([[0.0], np.nan_to_num(np.asarray(f1, dtype=np.float64))])
    end = min(up_to, float(x[-1]))
    keep = x < end
    xs = np.concatenate([x[keep], [end]])
    ys = np.concatenate([y[keep], [np.interp(end, x, y)]])
    return float(np.trapezoid(ys, xs) / up_to)


def curve_summary(
    curves: pd.DataFrame, n_kept: int, n_recorded: int, tau_m: float = 0.05, levels=(0.95, 0.99), up_to: float = 0.2
) -> pd.DataFrame:
    """Per ordering and extractor: k reaching each level of the all-scan F1, the area
    under the curve up to ``up_to`` of the kept scans, and k95 against the oracle's.

    Parameters
    ----------
    curves : pandas.DataFrame
        ``extractor, ordering, seed, k`` and ``f1_<tau>`` (``seed`` -1 for a
        deterministic ordering). With several seeds (random) each figure is the mean of
        the seeds' own (each seed's curve read on its own k), with their spread.
    n_kept, n_recorded : int
        Kept and recorded scans of the recording.
    tau_m : float
    levels : sequence of float
    up_to : float

    Returns
    -------
    pandas.DataFrame
        ``extractor, ordering, n_seeds, f1_all`` and per level p: ``k_p``,
        ``fraction_kept_p``, ``fraction_recorded_p``; ``k_p_seed_sd`` (random: the
        seeds' spread); ``auc``, ``auc_seed_sd``; ``k95_over_oracle``.
    """
    col = f"f1_{round(tau_m * 100):d}cm"
    rows = []
    for (extractor, ordering), g in curves.groupby(["extractor", "ordering"], sort=True):
        at_all = g.loc[g["k"] == n_kept, col]
        f1_all = float(at_all.iloc[0]) if len(at_all) else math.nan
        seeds = [s.sort_values("k") for _, s in g.groupby("seed", sort=True)]
        row = {"extractor": extractor, "ordering": ordering, "n_seeds": len(seeds), "f1_all": f1_all}
        for level in levels:
            p = f"{round(level * 100):d}"
            per_seed = [first_k_reaching(s["k"].to_numpy(), s[col].to_numpy(), level * f1_all) for s in seeds]
            kk = float(np.mean(per_seed))
            row[f"k_{p}"] = kk
            row[f"fraction_kept_{p}"] = kk / n_kept
            row[f"fraction_recorded_{p}"] = kk / n_recorded if n_recorded else math.nan
            row[f"k_{p}_seed_sd"] = float(np.std(per_seed)) if len(seeds) > 1 else math.nan
        aucs = [area_under_curve(s["k"].to_numpy(), s[col].to_numpy(), n_kept, up_to) for s in seeds]
        row["auc"] = float(np.mean(aucs))
        row["auc_seed_sd"] = float(np.std(aucs)) if len(seeds) > 1 else math.nan
        rows.append(row)
    out = pd.DataFrame(rows)
    if out.empty:
        return out
    oracle = out[out["ordering"] == ORACLE].set_index("extractor")["k_95"]
    out["k95_over_oracle"] = [
        r["k_95"] / oracle[r["extractor"]] if r["extractor"] in oracle.index and oracle[r["extractor"]] > 0 else math.nan
        for _, r in out.iterrows()
    ]
    return out


def curve_summary_markdown(summary: pd.DataFrame, tau_m: float, n_kept: int, n_recorded: int, line: str) -> str:
    """The curve summary (:func:`curve_summary`) as a Markdown table for ``summary.md``,
    headed by ``line`` (:func:`floorscan.core.score_tables.beats_random_line`).

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`curve_summary`'s table; the columns of
        :data:`~floorscan.core.score_tables.SUMMARY_COLUMNS` are shown.
    tau_m : float
        The tolerance of the F1, metres (shown in cm).
    n_kept, n_recorded : int
        Kept and recorded scans of the recording.
    line : str
        The sentence heading the table.

    Returns
    -------
    str
        A paragraph saying what the columns mean, ``line``, and the table (a row per
        row of ``summary``), ending with a newline.
    """
    lines = [
        f"Floor plans against the reference map at tau = {tau_m * 100:.0f} cm; {n_kept} kept of {n_recorded} "
        "recorded scans. k95 / k99: the first k whose plan reaches 95 / 99 % of the all-scan plan's F1; "
        "AUC 20 %: mean F1 up to 20 % of the kept scans; random: mean of its seeds (+- their spread).",
        "",
        line,
        "",
        "| " + " | ".join(h for _, h in SUMMARY_COLUMNS) + " |",
        "|" + "---|" * len(SUMMARY_COLUMNS),
    ]
    for r in summary.to_dict("records"):
        lines.append("| " + " | ".join(summary_cell(r, c, n_kept, pm="+-") for c, _ in SUMMARY_COLUMNS) + " |")
    return "\n".join(lines) + "\n"

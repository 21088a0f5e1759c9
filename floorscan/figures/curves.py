"""Scoring curves: the quality of the walls and floor plans of the first k scans against
k, a line per ordering.

- :func:`plot_metrics_vs_k`: correct match, false positive, false negative (thesis
  section 5.1), wall-cell correct match and F1 against the number of scans, per
  extractor (Fig. 5.4), from ``metrics.parquet``;
- :func:`plot_quality_vs_k`: the floor plan's F1 against the reference map (ISPRS
  benchmark terms) against k / kept scans, every ordering, random's seeds as a band and
  the oracle dashed, from the curves of :mod:`floorscan.score.curves`.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pandas as pd  # noqa: E402

from floorscan.figures.style import ORDERING_COLOURS, reference_name, save_figure  # noqa: E402
from floorscan.core.score_tables import GROUND_TRUTH, tau_label  # noqa: E402


def plot_metrics_vs_k(metrics: pd.DataFrame, out, tau: float = 0.05) -> None:
    """Fig. 5.4: metrics against the number of scans, a line per ordering.

    Columns: the thesis's correct match, false positive and false negative (fractions
    of the map area), the wall-cell correct match (IoU of wall cells) and F1 at ``tau``;
    a row per extractor. Correct match over the map area stays near 1 because empty
    cells dominate it, hence the wall-cell version beside it.

    Parameters
    ----------
    metrics : pandas.DataFrame
        ``metrics.parquet`` (:func:`floorscan.score.runs.score_dataset`).
    out : path
        PNG to write.
    tau : float
        Tolerance of the F1 column, metres.
    """
    f1 = f"f1_{tau_label(tau)}"
    cols = [
        ("correct_match", "correct match\n(fraction of map)"),
        ("false_positive", "false positive\n(fraction of map)"),
        ("false_negative", "false negative\n(fraction of map)"),
        ("wall_correct_match", "correct match\n(fraction of wall cells)"),
        (f1, f"F1 at {tau_label(tau)}"),
    ]
    extractors = sorted(metrics["extractor"].unique()) if len(metrics) else [""]
    fig, axes = plt.subplots(
        len(extractors), len(cols), figsize=(3.2 * len(cols), 2.8 * len(extractors)),
        squeeze=False,
    )
    kind = metrics["reference_kind"].iloc[0] if len(metrics) else GROUND_TRUTH
    for r, ext in enumerate(extractors):
        sub = metrics[metrics["extractor"] == ext]
        for c, (col, label) in enumerate(cols):
            ax = axes[r, c]
            for ordering, g in sub.groupby("ordering", sort=True):
                g = g.sort_values("n_scans")
                ax.plot(
                    g["n_scans"], g[col], marker="o", ms=3,
                    color=ORDERING_COLOURS.get(ordering), label=ordering,
                )
            ax.set_xscale("log")
            ticks = sorted(sub["n_scans"].unique())
            ax.set_xticks(ticks, [str(t) for t in ticks], fontsize=7)
            ax.minorticks_off()
            ax.set_title(f"{ext}: {label}" if c == 0 else label, fontsize=9)
            ax.grid(alpha=0.3)
            if r == len(extractors) - 1:
                ax.set_xlabel("number of scans k")
    axes[0, -1].legend(fontsize=7, loc="lower right")
    ds = metrics["dataset"].iloc[0] if len(metrics) else ""
    fig.suptitle(f"{ds}: walls of the first k scans against the {reference_name(kind)}")
    fig.tight_layout()
    save_figure(fig, out)


def plot_quality_vs_k(curves: pd.DataFrame, out, tau: float = 0.05, up_to: float = 0.2, title: str = "") -> None:
    """F1 of the plan of the first k scans against the reference map, per extractor:
    every ordering, random's mean with a one-sd band over its seeds, the oracle dashed.

    Parameters
    ----------
    curves : pandas.DataFrame
        :func:`floorscan.score.curves.score_curves`' table with an ``extractor`` column.
    out : path
        PNG output.
    tau : float
        The F1's tolerance, metres.
    up_to : float
        The AUC's range, a fraction of the kept scans (shaded).
    title : str
    """
    col = f"f1_{round(tau * 100):d}cm"
    extractors = sorted(curves["extractor"].unique())
    fig, axes = plt.subplots(1, len(extractors), figsize=(6.5 * len(extractors), 5), squeeze=False)
    for ax, extractor in zip(axes[0], extractors):
        c = curves[curves["extractor"] == extractor]
        n_kept = int(c["n_kept"].iloc[0])
        f1_all = float(c.loc[c["k"] == n_kept, col].iloc[0])
        ax.axvspan(0, up_to, color="0.92", zorder=0)
        for ordering, g in c.groupby("ordering", sort=True):
            n_seeds = g["seed"].nunique()
            stats = g.groupby("k", sort=True)[col].agg(["mean", "std", "count"])
            stats = stats[stats["count"] == n_seeds]  # the k every seed was scored at
            x = stats.index.to_numpy() / n_kept
            colour = ORDERING_COLOURS.get(ordering, "black")
            style = "--" if ordering == "oracle" else "-"
            label = f"{ordering} (mean of {g['seed'].nunique()} seeds)" if g["seed"].nunique() > 1 else ordering
            ax.plot(x, stats["mean"], style, color=colour, lw=1.4, label=label)
            if g["seed"].nunique() > 1:
                ax.fill_between(x, stats["mean"] - stats["std"], stats["mean"] + stats["std"], color=colour, alpha=0.2)
        ax.axhline(0.95 * f1_all, color="0.3", ls=":", lw=1, label="95 % of the all-scan F1")
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1)
        ax.set_xlabel(f"k / kept scans ({n_kept} kept)")
        ax.set_ylabel(f"F1 against the reference map, tau {tau * 100:.0f} cm")
        ax.set_title(f"{extractor}", fontsize=10)
        ax.legend(fontsize=8, loc="lower right")
    fig.suptitle(title or "Floor-plan F1 against the number of scans", fontsize=11)
    save_figure(fig, out)

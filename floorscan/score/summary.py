"""The scan-reduction summary of the walls on the configured k grid: the smallest k whose
F1 reaches a fraction of the all-scan F1 (:func:`summarize`; the thesis claims a
tenfold reduction), and its Markdown (:func:`grid_summary_markdown`, in the evaluation's
``summary.md``).

The floor plans' curves against the reference map have their own summary and Markdown
(:func:`floorscan.score.curve_summary.curve_summary`, :func:`~floorscan.score.curve_summary.curve_summary_markdown`).
"""

from __future__ import annotations

import math

from floorscan.core.score_tables import FEW_SCANS, GROUND_TRUTH, tau_label


def summarize(metrics, tau: float = 0.05, levels=(0.95, 0.99)):
    """The smallest k reaching a fraction of the all-scan F1, per ordering and extractor.

    For each ordering and extractor, with ``F1_all`` the F1 at ``tau`` of ``k = all``,
    the first k of the configured grid (in increasing number of scans) whose F1 is at
    least ``level * F1_all``; the number of scans behind it, that number as a fraction
    of the scans kept and the reduction factor ``n_scans_kept / n_scans`` (the thesis's
    claim is a tenfold reduction). F1 is not monotone in k: this is the first k that
    reaches the level, not a k after which it stays above.

    Parameters
    ----------
    metrics : pandas.DataFrame
        Output of :func:`floorscan.score.runs.score_dataset`.
    tau : float
        Tolerance of the F1 used, metres.
    levels : sequence of float
        Fractions of the all-scan F1.

    Returns
    -------
    pandas.DataFrame
        Columns ``dataset, reference_kind, ordering, extractor, n_scans_kept, f1_all``
        and per level L (as a percentage p): ``k_p``, ``n_scans_p``, ``fraction_p``,
        ``reduction_p`` (``k_p`` empty, the others NaN, when F1_all is NaN or 0);
        with the ``map_*`` columns of the reference map in ``metrics``, also
        ``map_completeness_all``, ``map_correctness_all``, ``map_f1_all``: the all-scan
        floor plan against the reference map at ``tau``.

    Raises
    ------
    ValueError
        When ``metrics`` has no ``f1_<tau>`` column.
    """
    import pandas as pd

    col = f"f1_{tau_label(tau)}"
    if col not in metrics.columns:
        raise ValueError(f"metrics lack column {col!r}; is tau {tau} in score.taus_m?")
    rows = []
    for (ordering, extractor), g in metrics.groupby(["ordering", "extractor"], sort=True):
        g = g.sort_values("n_scans", kind="stable")
        all_rows = g[g["k"] == "all"]
        f1_all = float(all_rows[col].iloc[0]) if len(all_rows) else math.nan
        n_kept = int(g["n_scans_kept"].iloc[0])
        row = {
            "dataset": g["dataset"].iloc[0],
            "reference_kind": g["reference_kind"].iloc[0],
            "ordering": ordering,
            "extractor": extractor,
            "n_scans_kept": n_kept,
            "f1_all": f1_all,
        }
        # the all-scan floor plan against the reference map (occupancy grid), when scored
        for m in ("completeness", "correctness", "f1"):
            c = f"map_{m}_{tau_label(tau)}"
            if c in g.columns:
                row[f"map_{m}_all"] = float(all_rows[c].iloc[0]) if len(all_rows) else math.nan
        for level in levels:
            p = f"{round(level * 100, 6):g}"
            hit = g[g[col] >= level * f1_all - 1e-12] if f1_all > 0 else g.iloc[0:0]
            if len(hit):
                n = int(hit["n_scans"].iloc[0])
                row[f"k_{p}"] = str(hit["k"].iloc[0])
                row[f"n_scans_{p}"] = n
                row[f"fraction_{p}"] = n / n_kept if n_kept else math.nan
                row[f"reduction_{p}"] = n_kept / n if n else math.nan
            else:
                row[f"k_{p}"] = ""
                row[f"n_scans_{p}"] = -1
                row[f"fraction_{p}"] = math.nan
                row[f"reduction_{p}"] = math.nan
        rows.append(row)
    return pd.DataFrame(rows)


def grid_summary_markdown(summary, tau: float = 0.05, levels=(0.95, 0.99)) -> str:
    """The table of :func:`summarize` (the k of the configured grid) as Markdown, after
    what F1 is measured against, and the all-scan plans against the reference map. An
    F1 from fewer than :data:`floorscan.core.score_tables.FEW_SCANS` kept scans is
    marked.

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`summarize`, non-empty.
    tau : float
        Metres.
    levels : sequence of float

    Returns
    -------
    str
    """
    kind = summary["reference_kind"].iloc[0]
    against = (
        "the simulator's ground-truth walls"
        if kind == GROUND_TRUTH
        else "the reference: walls of the same extractor from all kept scans (not ground truth)"
    )
    lines = [
        f"F1 at tau = {tau_label(tau)} against {against}. For each level, the smallest k "
        "of the configured grid whose F1 reaches that fraction of the all-scan F1, the "
        "scans it uses as a fraction of the scans kept, and the reduction factor.",
        "",
    ]
    head = ["ordering", "extractor", "scans kept", "F1 all"]
    for level in levels:
        p = f"{round(level * 100, 6):g}"
        head += [f"k {p}%", f"fraction {p}%", f"reduction {p}%"]
    lines.append("| " + " | ".join(head) + " |")
    lines.append("|" + "---|" * len(head))
    for _, r in summary.iterrows():
        f1_all = f"{r['f1_all']:.3f}"
        if int(r["n_scans_kept"]) < FEW_SCANS:
            f1_all += f" (warning: from {int(r['n_scans_kept'])} scans)"
        cells = [r["ordering"], r["extractor"], str(r["n_scans_kept"]), f1_all]
        for level in levels:
            p = f"{round(level * 100, 6):g}"
            k = r[f"k_{p}"] or "-"
            if k not in ("-", "all"):
                k = f"{k} ({r[f'n_scans_{p}']})" if str(r[f"n_scans_{p}"]) != k else k
            cells += [k, f"{r[f'fraction_{p}']:.3f}", f"{r[f'reduction_{p}']:.1f}x"]
        lines.append("| " + " | ".join(cells) + " |")
    if "map_f1_all" in summary.columns:
        lines += [
            "",
            f"The floor plan from all kept scans against the reference map (occupancy grid of all kept "
            f"scans, its structure cells; `reference/map.pgm`), at tau = {tau_label(tau)}: completeness "
            "(structure within tau of a plan face), correctness (plan face length within tau of structure), F1.",
            "",
            "| ordering | extractor | completeness | correctness | F1 |",
            "|---|---|---|---|---|",
        ]
        for _, r in summary.iterrows():
            lines.append(
                f"| {r['ordering']} | {r['extractor']} | {r['map_completeness_all']:.3f} | "
                f"{r['map_correctness_all']:.3f} | {r['map_f1_all']:.3f} |"
            )
    return "\n".join(lines) + "\n"

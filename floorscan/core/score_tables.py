"""What the score stage's tables hold, as the stages and pages that read them need it:
the values of their columns, their column names, and their cells for people.

The score stage writes them (:mod:`floorscan.score`); the figures and pages read them
(:mod:`floorscan.figures`), never the stage's functions; what both need is here:

- :data:`GROUND_TRUTH`, :data:`REFERENCE`: the values of the ``reference_kind`` column
  (what the walls are scored against);
- :data:`RANDOM`, :data:`ORACLE`: the ``ordering`` of the curves' random seeds and of
  the completeness bound (:mod:`floorscan.score.curves`);
- :func:`tau_label`: the suffix of a tolerance's columns (``f1_5cm``);
- :data:`FEW_SCANS`: below it a result is flagged (the registration's verdict, the
  summaries);
- ``summary.parquet`` for people (:mod:`floorscan.score.curve_summary`): its columns
  (:data:`SUMMARY_COLUMNS`), a cell (:func:`summary_cell`), whether an ordering beats
  random (:func:`beats_random_line`);
- :func:`k_reaching`: the k95 / k99 of the answer's curve
  (``evaluation/answer_curve.csv``, :mod:`floorscan.score.answer_curve`).

A new column of a table that a page shows gets its header and cell here.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    import pandas as pd

#: Values of the ``reference_kind`` column: what the inferred walls are scored against.
GROUND_TRUTH = "ground_truth"
REFERENCE = "reference"
#: Ordering name of the completeness-maximising bound.
ORACLE = "oracle"
#: Ordering name of the seeded random permutations.
RANDOM = "random"
#: A result from fewer kept scans than this is flagged in the summary and report.
FEW_SCANS = 10


def tau_label(tau: float) -> str:
    """Column suffix for a tolerance: 0.05 -> ``"5cm"``, 0.025 -> ``"2.5cm"``.

    Parameters
    ----------
    tau : float
        Metres.

    Returns
    -------
    str
    """
    return f"{round(tau * 100, 6):g}cm"


#: Columns of the summary tables (``summary.md``, ``summary.html``, the report's front
#: page): ``summary.parquet`` column and header.
SUMMARY_COLUMNS = (
    ("extractor", "extractor"),
    ("ordering", "ordering"),
    ("f1_all", "F1 all"),
    ("k_95", "k95"),
    ("fraction_kept_95", "k95 / kept"),
    ("fraction_recorded_95", "k95 / recorded"),
    ("k_99", "k99"),
    ("fraction_kept_99", "k99 / kept"),
    ("fraction_recorded_99", "k99 / recorded"),
    ("auc", "AUC 20 %"),
    ("k95_over_oracle", "k95 / oracle's"),
)


def summary_cell(row, col: str, n_kept: int | None = None, pm: str = "±") -> str:
    """One cell of a summary table: k as a count with random's seed spread (``pm``),
    the AUC likewise, fractions and F1 to 3 decimals, k95 / oracle's to 2; ``-`` for a
    missing value; an F1 from fewer than ``FEW_SCANS`` kept scans (``n_kept``) marked.

    Parameters
    ----------
    row : mapping
        A row of ``summary.parquet`` (:func:`floorscan.score.curve_summary.curve_summary`;
        column -> value; a ``*_seed_sd`` column is read when present).
    col : str
        A column of :data:`SUMMARY_COLUMNS`.
    n_kept : int, optional
        Kept scans; with fewer than :data:`FEW_SCANS` the ``f1_all`` cell says so.
    pm : str
        The plus-minus sign (``"+-"`` in Markdown).

    Returns
    -------
    str
        The cell's text (not escaped); ``-`` for a missing or non-finite value.
    """
    v = row.get(col)
    if col in ("extractor", "ordering"):
        return str(v)
    if v is None or not np.isfinite(float(v)):
        return "-"
    if col in ("k_95", "k_99", "auc"):
        sd = row.get(f"{col}_seed_sd" if col != "auc" else "auc_seed_sd")
        digits = 3 if col == "auc" else 0
        return f"{v:.{digits}f}" + (f" {pm} {sd:.{digits}f}" if sd is not None and np.isfinite(sd) else "")
    if col == "k95_over_oracle":
        return f"{v:.2f}"
    text = f"{v:.3f}"
    if col == "f1_all" and n_kept is not None and n_kept < FEW_SCANS:
        text += f" (warning: from {n_kept} scans)"
    return text


def beats_random_line(summary: pd.DataFrame, ordering: str, extractor: str) -> str:
    """One sentence: does ``ordering`` beat random (area under the curve and k95).

    Parameters
    ----------
    summary : pandas.DataFrame
        ``summary.parquet`` (:func:`floorscan.score.curve_summary.curve_summary`;
        ``extractor, ordering, auc, auc_seed_sd, k_95, k_95_seed_sd`` read).
    ordering : str
        The ordering compared with ``random``.
    extractor : str
        The wall extractor whose rows are compared.

    Returns
    -------
    str
        ``<ordering> beats random with <extractor>: ...`` (or ``does not beat``: by the
        area under the curve), with both areas and their difference (random's seed
        spread when finite) and both k95 (or that one of them does not reach it); or
        ``<ordering> or random was not scored for <extractor>.``
    """
    s = summary[summary["extractor"] == extractor].set_index("ordering")
    if ordering not in s.index or RANDOM not in s.index:
        return f"{ordering} or {RANDOM} was not scored for {extractor}."
    a, r = s.loc[ordering], s.loc[RANDOM]
    d_auc = a["auc"] - r["auc"]
    verb = "beats" if d_auc > 0 else "does not beat"
    spread = f" +- {r['auc_seed_sd']:.3f}" if np.isfinite(r["auc_seed_sd"]) else ""
    k_text = (
        f"k95 {a['k_95']:.0f} against {r['k_95']:.0f} (random's seeds +- {r['k_95_seed_sd']:.0f})"
        if np.isfinite(a["k_95"]) and np.isfinite(r["k_95"])
        else "k95 not reached by one of them"
    )
    return (
        f"{ordering} {verb} random with {extractor}: area under the F1 curve up to 20 % of the kept scans "
        f"{a['auc']:.3f} against {r['auc']:.3f}{spread} ({d_auc:+.3f}); {k_text}."
    )


def k_reaching(curve: pd.DataFrame, level: float) -> int | None:
    """The first k of ``curve`` whose ``f1_5cm`` reaches ``level`` times the F1 of its
    last row (all kept scans).

    Parameters
    ----------
    curve : pandas.DataFrame
        ``evaluation/answer_curve.csv`` (:func:`floorscan.score.answer_curve.answer_curve`):
        ``k`` and ``f1_5cm`` in increasing k.
    level : float
        Fraction, e.g. 0.99.

    Returns
    -------
    int or None
        None for an empty curve; the last k when none reaches it (a NaN target).
    """
    if curve.empty:
        return None
    target = level * float(curve["f1_5cm"].iloc[-1])
    hit = curve["f1_5cm"].to_numpy() >= target
    return int(curve["k"].to_numpy()[int(np.argmax(hit))]) if hit.any() else int(curve["k"].iloc[-1])

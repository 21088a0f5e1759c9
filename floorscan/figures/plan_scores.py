"""The table "How good the plan is" on the front page (:mod:`floorscan.figures.report`): the
recommended plan beside the plan of all kept scans, as :mod:`floorscan.score.answer`
scores them (``evaluation/answer_scores.csv``, the room scores joined:
:func:`floorscan.figures.room_table.with_room_scores`), and the scans its plan needs.
"""

from __future__ import annotations


#: Rows of the answer's table: the column of ``answer_scores.csv`` and its label.
ANSWER_ROWS = (
    ("n_walls", "walls"), ("n_junctions", "junctions"), ("n_clutter", "clutter pieces (furniture)"),
    ("short_wall_share", "walls under 0.5 m"), ("n_crossings", "walls crossing away from a junction"),
    ("map_completeness_5cm", "completeness at 5 cm (reference map)"),
    ("map_completeness_all_5cm", "... with the clutter"), ("map_correctness_5cm", "correctness at 5 cm (reference map)"),
    ("gt_precision_5cm", "precision at 5 cm (true walls)"), ("gt_recall_5cm", "recall at 5 cm (observed true walls)"),
    ("gt_corners_as_junctions", "true corners that are junctions"),
    ("room_precision", "rooms that match a true room (IoU 0.5)"), ("room_recall", "true rooms matched (IoU 0.5)"),
    ("room_mean_iou", "mean IoU of the matched rooms"),
    ("door_recall", "true doors found (0.2 m)"), ("door_precision", "doors that are true doors"),
)  # fmt: skip


def answer_table(answer, curve=None) -> dict | None:
    """"How good the plan is": the recommended plan beside the plan of all kept scans
    and how many scans of the default ordering its plan needs (k95 and k99), as cells
    for the front page's template.

    Parameters
    ----------
    answer : pandas.DataFrame or path
        ``answer_scores.csv``.
    curve : pandas.DataFrame or path, optional
        ``answer_curve.csv``.

    Returns
    -------
    dict or None
        ``header`` (list of str), ``rows`` (list of (label, list of cell texts)),
        ``k95`` and ``k99`` (int or None: the curve's); None when neither plan was
        scored.
    """
    import pandas as pd

    table = answer if isinstance(answer, pd.DataFrame) else pd.read_csv(answer)
    by_plan = {row["plan"]: row for row in table.to_dict("records")}
    plans = [p for p in ("recommended", "all_scans_map") if p in by_plan]
    if not plans:
        return None
    rows = []
    for col, label in ANSWER_ROWS:
        values = [by_plan[p].get(col) for p in plans]
        if all(v is None or (isinstance(v, float) and v != v) for v in values):
            continue
        rows.append((label, [_answer_cell(col, v) for v in values]))
    ks = answer_curve_k(curve)
    for level, k in ks.items():
        if k is not None:
            rows.append((f"scans for {level} % of the all-scan plan's F1 (k{level})", [f"{k}"]))
    return {"header": ["", "this plan", "all kept scans"][: len(plans) + 1], "rows": rows,
            "k95": ks.get(95), "k99": ks.get(99)}  # fmt: skip


def answer_curve_k(curve) -> dict:
    """k95 and k99 of the answer's curve.

    Parameters
    ----------
    curve : pandas.DataFrame, path or None
        ``answer_curve.csv``.

    Returns
    -------
    dict
        ``{95: k or None, 99: k or None}``; empty for no curve.
    """
    if curve is None:
        return {}
    import pandas as pd

    from floorscan.core.score_tables import k_reaching

    c = curve if isinstance(curve, pd.DataFrame) else pd.read_csv(curve)
    return {round(level * 100): k_reaching(c, level) for level in (0.95, 0.99)}


def _answer_cell(col: str, value) -> str:
    if value is None or (isinstance(value, float) and value != value):
        return "\u2013"
    if col.startswith("n_"):
        return f"{int(value)}"
    return f"{100 * float(value):.0f} %"

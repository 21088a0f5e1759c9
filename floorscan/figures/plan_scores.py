"""The table "How good the plan is" on the front page (:mod:`floorscan.figures.report`): the
recommended plan beside the plan of all kept scans, as :mod:`floorscan.score.answer`
scores them (``evaluation/answer_scores.csv``, the room scores joined:
:func:`floorscan.figures.room_table.with_room_scores`), and the scans its plan needs.
"""

from __future__ import annotations

import html


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


def answer_html(answer, curve=None) -> list[str]:
    """"How good the plan is": the recommended plan beside the plan of all kept scans
    and how many scans of the default ordering its plan needs (k95 and k99).

    Parameters
    ----------
    answer : pandas.DataFrame or path
        ``answer_scores.csv``.
    curve : pandas.DataFrame or path, optional
        ``answer_curve.csv``.

    Returns
    -------
    list of str
        HTML pieces; empty when neither plan was scored.
    """
    import pandas as pd

    from floorscan.score.answer_curve import k_reaching

    table = answer if isinstance(answer, pd.DataFrame) else pd.read_csv(answer)
    by_plan = {row["plan"]: row for row in table.to_dict("records")}
    plans = [p for p in ("recommended", "all_scans_map") if p in by_plan]
    if not plans:
        return []
    head = "".join(f"<th>{html.escape(h)}</th>" for h in ("", "this plan", "all kept scans")[: len(plans) + 1])
    rows = []
    for col, label in ANSWER_ROWS:
        values = [by_plan[p].get(col) for p in plans]
        if all(v is None or (isinstance(v, float) and v != v) for v in values):
            continue
        cells = "".join(f'<td class="num">{_answer_cell(col, v)}</td>' for v in values)
        rows.append(f"<tr><th>{html.escape(label)}</th>{cells}</tr>")
    if curve is not None:
        c = curve if isinstance(curve, pd.DataFrame) else pd.read_csv(curve)
        for level in (0.95, 0.99):
            k = k_reaching(c, level)
            if k is not None:
                label = f"scans for {round(level * 100)} % of the all-scan plan's F1 (k{round(level * 100)})"
                rows.append(f'<tr><th>{html.escape(label)}</th><td class="num">{k}</td></tr>')
    return ["<h4>How good the plan is</h4>", f'<table class="facts-table"><tr>{head}</tr>{"".join(rows)}</table>']


def _answer_cell(col: str, value) -> str:
    if value is None or (isinstance(value, float) and value != value):
        return "&ndash;"
    if col.startswith("n_"):
        return f"{int(value)}"
    return f"{100 * float(value):.0f} %"

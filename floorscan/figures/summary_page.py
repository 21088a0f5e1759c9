"""The scan-reduction summary of a dataset as HTML: the table the front page shows and
``summary.html``, a page of its own (the same cells as ``summary.md``,
:func:`floorscan.score.curve_summary.summary_cell`)."""

from __future__ import annotations

import html
import os
from typing import TYPE_CHECKING

from floorscan.core.files import atomic_path
from floorscan.core.score_tables import SUMMARY_COLUMNS, summary_cell

if TYPE_CHECKING:
    import pandas as pd


def write_summary_page(path: str | os.PathLike, dataset: str, summary: "pd.DataFrame", n_kept: int,
                       beats_random: str, verdict: dict | None, ordering: str) -> None:
    """``summary.html``: the verdict, the beats-random line and :func:`summary_table_html`
    of one dataset, a page of its own (the front page includes the same table).

    Parameters
    ----------
    path : path
        Output, written atomically.
    dataset : str
    summary : pandas.DataFrame
        :func:`floorscan.score.curve_summary.curve_summary`.
    n_kept : int
    beats_random : str
        :func:`floorscan.score.curve_summary.beats_random_line`.
    verdict : dict or None
    ordering : str
        Highlighted.
    """
    with atomic_path(path) as tmp:
        tmp.write_text(
            f"<html><head><meta charset='utf-8'><title>{dataset} summary</title></head><body>"
            f"<h1>{dataset}</h1>"
            + (f"<p><b>Verdict: {verdict['line']}</b></p>" if verdict else "")
            + f"<p>{beats_random}</p>"
            + summary_table_html(summary, n_kept, ordering)
            + "</body></html>\n"
        )


def summary_table_html(
    summary: "pd.DataFrame", n_kept: int | None = None, ordering: str = "", extractor: str = ""
) -> str:
    """The summary as an HTML table, the cells as in ``summary.md`` (random's k and AUC
    with their seeds' spread); the rows of ``ordering`` (with ``extractor``, when given:
    the recommended plan) highlighted, the oracle's in grey. An F1 from fewer than
    :data:`floorscan.register.consistency.FEW_SCANS` kept scans is marked.

    Parameters
    ----------
    summary : pandas.DataFrame
        :func:`floorscan.score.curve_summary.curve_summary`.
    n_kept : int, optional
    ordering, extractor : str

    Returns
    -------
    str
    """
    esc = html.escape
    table = summary_rows(summary, n_kept, ordering, extractor)
    out = [
        "<table>",
        "<thead><tr>" + "".join(f"<th>{esc(h)}</th>" for h in table["header"]) + "</tr></thead>",
        "<tbody>",
    ]
    for cls, cells in table["rows"]:
        tds = "".join(f'<td class="num">{esc(c)}</td>' if numeric else f"<td>{esc(c)}</td>" for numeric, c in cells)
        attr = f' class="{cls}"' if cls else ""
        out.append(f"<tr{attr}>{tds}</tr>")
    out += ["</tbody>", "</table>"]
    return "\n".join(out)


def summary_rows(
    summary: "pd.DataFrame", n_kept: int | None = None, ordering: str = "", extractor: str = ""
) -> dict:
    """The cells of :func:`summary_table_html`, for a template: the header, and per row
    its classes (``recommended``, ``bound``) and its cells (numeric or not, text).

    Parameters
    ----------
    summary : pandas.DataFrame
    n_kept : int, optional
    ordering, extractor : str

    Returns
    -------
    dict
        ``header``: list of str; ``rows``: list of (str, list of (bool, str)).
    """
    rows = []
    for r in summary.to_dict("records"):
        cls = []
        if ordering and r.get("ordering") == ordering and (not extractor or r.get("extractor") == extractor):
            cls.append("recommended")
        if r.get("ordering") == "oracle":
            cls.append("bound")
        cells = [(col not in ("extractor", "ordering"), summary_cell(r, col, n_kept)) for col, _ in SUMMARY_COLUMNS]
        rows.append((" ".join(cls), cells))
    return {"header": [h for _, h in SUMMARY_COLUMNS], "rows": rows}

"""The scan-reduction summary of a dataset as HTML: the cells of the table the front
page shows (:func:`summary_rows`, the same cells as ``summary.md``,
:func:`floorscan.core.score_tables.summary_cell`) and ``summary.html``, a page of its
own rendered from ``templates/summary_page.html.j2`` (:class:`SummaryPage`) in the front
page's frame (``_front_base.html.j2``: its style and the links to the index and to the
report); the table and its note are the macros ``summary_table`` and ``summary_note`` of
``templates/_macros.html.j2``, which the front page uses too."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from floorscan.core.files import atomic_path
from floorscan.core.score_tables import SUMMARY_COLUMNS, summary_cell
from floorscan.figures.front_parts import verdict_lines
from floorscan.figures.pages import INDEX, OutputFile, render, report_file

if TYPE_CHECKING:
    import pandas as pd


@dataclass(frozen=True)
class SummaryPage:
    """What ``summary.html`` shows: given to its template
    (``templates/summary_page.html.j2``) as one object.

    Attributes
    ----------
    dataset : str
    table : dict
        :func:`summary_rows`.
    verdict_line : str
        The registration's verdict line, or empty.
    beats_random : str
        :func:`floorscan.core.score_tables.beats_random_line`, or empty.
    index : OutputFile
        The index of every dataset (``results/index.html``), linked at the top.
    report : OutputFile or None
        Snakemake's report of the run, linked at the top when it exists.
    description : str
        A line under the title (the frame's; none here).
    """

    dataset: str
    table: dict
    verdict_line: str = ""
    beats_random: str = ""
    index: OutputFile = field(default_factory=lambda: INDEX)
    report: OutputFile | None = None
    description: str = ""

    @property
    def head(self) -> str:
        """The title: ``demo: how few scans the floor plan needs``."""
        return f"{self.dataset}: how few scans the floor plan needs"

    @property
    def verdict_cls(self) -> str:
        """The verdict's class (``good``, ``warning``, ``poor`` or empty), as the front
        page colours it."""
        return verdict_lines(self.verdict_line)["cls"]


def summary_page_html(page: SummaryPage) -> str:
    """``summary.html`` as text, rendered from its template.

    Parameters
    ----------
    page : SummaryPage

    Returns
    -------
    str
    """
    return render("summary_page.html.j2", page)


def write_summary_page(path: str | os.PathLike, dataset: str, summary: "pd.DataFrame", n_kept: int,
                       beats_random: str, verdict: dict | None, ordering: str) -> None:
    """``summary.html``: the verdict, the beats-random line and the summary table
    (:func:`summary_rows`) of one dataset, a page of its own (the front page shows the
    same table).

    Parameters
    ----------
    path : path
        Output, written atomically.
    dataset : str
    summary : pandas.DataFrame
        :func:`floorscan.score.curve_summary.curve_summary`.
    n_kept : int
    beats_random : str
        :func:`floorscan.core.score_tables.beats_random_line`.
    verdict : dict or None
    ordering : str
        Highlighted.
    """
    page = SummaryPage(dataset, summary_rows(summary, n_kept, ordering), str((verdict or {}).get("line") or ""),
                       beats_random or "", report=report_file(Path(path).parent))
    with atomic_path(path) as tmp:
        tmp.write_text(summary_page_html(page), encoding="utf-8")


def summary_rows(
    summary: "pd.DataFrame", n_kept: int | None = None, ordering: str = "", extractor: str = ""
) -> dict:
    """The summary table's cells, for a template (macro ``summary_table``): the header,
    and per row its classes (``recommended``, ``bound``: the rows of ``ordering``, with
    ``extractor`` when given, highlighted; the oracle's in grey) and its cells (numeric
    or not, text, as in ``summary.md``; an F1 from fewer than
    :data:`floorscan.core.score_tables.FEW_SCANS` kept scans is marked).

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

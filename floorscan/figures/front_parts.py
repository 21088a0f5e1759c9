"""The parts of a recording's front page (:mod:`floorscan.figures.report`) that its
template shows: the plan's SVG made fit to inline (:func:`inline_svg`), the quality
figure as a data URI (:func:`png_data_uri`), the plan's caption, the compact table of
the scans needed (:func:`quality_table`), the verdict's lines (:func:`verdict_lines`).
"""

from __future__ import annotations

import base64
import os
import re
from pathlib import Path
from typing import TYPE_CHECKING, Mapping

from floorscan.core.score_tables import summary_cell

if TYPE_CHECKING:  # pandas is imported by the functions that use it
    import pandas as pd

#: The thesis's ordering (Algorithm 1), compared with random beside the recommended one.
THESIS_ORDERING = "cluster_hull"


def inline_svg(svg: str) -> str:
    """SVG text made fit to inline in HTML: no XML declaration, doctype or comments,
    and no fixed ``width`` / ``height`` on the root element (its ``viewBox`` scales it
    to the page).

    Parameters
    ----------
    svg : str

    Returns
    -------
    str

    Raises
    ------
    ValueError
        Not an SVG, or it holds a ``<script>`` (the page is included in the report's
        own page, inside a script string).
    """
    text = re.sub(r"<\?xml[^>]*\?>|<!DOCTYPE[^>]*>|<!--.*?-->", "", svg, flags=re.S | re.I).strip()
    m = re.search(r"<svg\b[^>]*>", text, flags=re.I)
    if m is None:
        raise ValueError("floorplan_svg: no <svg> element")
    if re.search(r"<\s*/?\s*script", text, flags=re.I):
        raise ValueError("floorplan_svg: holds a <script>, which the report page cannot include")
    root = re.sub(r'\s(width|height)="[^"]*"', "", m.group(0))
    return text[: m.start()] + root + text[m.end():]


def png_data_uri(path: "str | os.PathLike") -> str:
    """``data:image/png;base64,...`` of a PNG file.

    Parameters
    ----------
    path : path

    Returns
    -------
    str
    """
    return "data:image/png;base64," + base64.b64encode(Path(path).read_bytes()).decode("ascii")


def plan_caption(k=None, ordering: str = "", extractor: str = "", n_walls=None) -> str:
    """The caption of the recommended plan: what it is made of and where its files are
    (the drawing carries its own title, legend and scale bar).

    Parameters
    ----------
    k : int, optional
        Scans of the plan.
    ordering, extractor : str
    n_walls : int, optional

    Returns
    -------
    str
    """
    text = "The recommended floor plan"
    if n_walls is not None:
        text += f", {n_walls} walls"
    if k is not None:
        text += f", from the first {k} scans of the {ordering} ordering" if ordering else f", from {k} scans"
    if extractor:
        text += f", walls by {extractor}"
    return text + "; its files (SVG, GeoJSON, DXF, IFC) are under Files."


#: Rows of the compact quality table beside the plan (the full table is below it).
QUALITY_ROWS = ("oracle", THESIS_ORDERING, "random")
#: Its columns: summary column and header.
QUALITY_COLUMNS = (("ordering", "ordering"), ("k_95", "k95"), ("k_99", "k99"), ("auc", "AUC 20 %"))


def quality_table(summary: "pd.DataFrame", ordering: str, extractor: str) -> dict:
    """The compact table beside the plan (:attr:`FrontPage.quality_table`): the
    extractor shown, the header and per row its class and cells (the summary's).

    Parameters
    ----------
    summary : pandas.DataFrame
    ordering, extractor : str
        The recommended plan's.

    Returns
    -------
    dict
        ``extractor`` (str), ``header`` (list of str), ``rows`` (list of (class, cells)).
    """
    if extractor and "extractor" in summary and not (summary["extractor"] == extractor).any():
        # the answer's extractor has no curves of every ordering (the map extractor: its
        # own curve is in the answer table); show the thesis's per-scan extractor's
        extractor = "ransac" if (summary["extractor"] == "ransac").any() else str(summary["extractor"].iloc[0])
    rows = summary[summary["extractor"] == extractor] if extractor and "extractor" in summary else summary
    order = [ordering] + [o for o in QUALITY_ROWS if o != ordering]
    records = {r["ordering"]: r for r in rows.to_dict("records")}
    out = []
    for name in order:
        r = records.get(name)
        if r is None:
            continue
        cls = "recommended" if name == ordering else ("bound" if name == "oracle" else "")
        out.append((cls, [name] + [summary_cell(r, col) for col, _ in QUALITY_COLUMNS[1:]]))
    return {"extractor": extractor, "header": [h for _, h in QUALITY_COLUMNS], "rows": out}


def read_summary(summary) -> "pd.DataFrame | None":
    """The summary table itself: ``summary`` when a table or None, read when the path of a Parquet file."""
    if summary is None or not isinstance(summary, (str, os.PathLike)):
        return summary
    if Path(summary).suffix != ".parquet":
        raise ValueError(f"summary {summary}: expected summary.parquet (a table), not {Path(summary).suffix!r}")
    from floorscan.core.io import read_table

    return read_table(summary)


def beats_random_lines(table: "pd.DataFrame", ordering: str) -> list[str]:
    """Does the recommended ordering, and the thesis's, beat random, per extractor."""
    from floorscan.core.score_tables import RANDOM, beats_random_line

    present = set(table["ordering"])
    if RANDOM not in present:
        return []
    shown = [o for o in dict.fromkeys([ordering, THESIS_ORDERING]) if o and o in present]
    return [beats_random_line(table, o, e) for o in shown for e in sorted(set(table["extractor"]))]


def verdict_lines(verdict) -> dict:
    """The registration's verdict as the page shows it.

    Parameters
    ----------
    verdict : mapping, str, sequence of str or None
        As :attr:`FrontPage.verdict`.

    Returns
    -------
    dict
        ``first`` (the first line, or "no verdict recorded."), ``cls`` (``good``,
        ``warning``, ``poor`` or empty: the first word) and ``rest`` (the other lines).
    """
    if not verdict:
        return {"first": "no verdict recorded.", "cls": "", "rest": []}
    if isinstance(verdict, Mapping):
        lines = [str(verdict["line"])]
    elif isinstance(verdict, str):
        lines = [verdict]
    else:
        lines = [str(v) for v in verdict]
    word = lines[0].split(":", 1)[0].strip().lower()
    return {"first": lines[0], "cls": word if word in ("good", "warning", "poor") else "", "rest": lines[1:]}


def int_or_none(text: str) -> int | None:
    """The k of a summary cell (``"10"``, ``"10 ± 4"``), None for none."""
    m = re.match(r"\s*(\d+)", str(text))
    return int(m.group(1)) if m else None

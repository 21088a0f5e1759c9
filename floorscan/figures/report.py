"""The front page of a dataset's result: what the report opens on.

:func:`front_page` renders one self-contained HTML page per dataset from plain inputs:
the recommended floor plan (its SVG inlined), how few scans it took (k of the kept and
recorded scans and why, the scan list, the reduced recording's size), the
registration's verdict, what ingest detected in the recording, the scan-reduction
summary table and the quality-vs-k figure (a PNG as a data URI).
:func:`write_front_page` writes it atomically; :func:`write_front_page_of_files` reads
the stage outputs it is made of and writes it (the stage script's one call).

Snakemake 9.27's report opens on its workflow description
(``workflow/report/workflow.rst``) and lets that description include a file verbatim
(docutils' ``raw`` directive with ``:file:``), so ``workflow.rst`` includes each
dataset's front page there; the page is also a result of the report (shown in a frame).
The description travels inside a ``<script>`` string of the report, so the page holds
no script and no HTML comment, and its links are not relative; its style is scoped to
``.floorscan-front`` and changes nothing else on the report's page.
"""

from __future__ import annotations

import base64
import html
import json
import os
import re
from pathlib import Path
from typing import TYPE_CHECKING, Mapping, Sequence

from floorscan.core.files import atomic_path
from floorscan.figures.answer import format_bytes
from floorscan.figures.plan_scores import answer_html
from floorscan.figures.room_table import read_plan_rooms, rooms_table_html, with_room_scores
from floorscan.figures.summary_page import summary_table_html
from floorscan.score.curve_summary import summary_cell

if TYPE_CHECKING:  # pandas is imported by the functions that use it
    import pandas as pd

#: Class of the page's outer element; every style rule of the page is under it.
ROOT_CLASS = "floorscan-front"

#: What ingest detected (keys of the scan index's metadata) and how the page names them.
DETECTED_FIELDS = (
    ("format", "format"),
    ("scan_topic", "scan topic"),
    ("pose_source", "pose source"),
    ("stamps", "stamps"),
    ("source", "read from"),
)

#: The thesis's ordering (Algorithm 1), compared with random beside the recommended one.
THESIS_ORDERING = "cluster_hull"

FRONT_STYLE = """
.floorscan-front { font-family: system-ui, -apple-system, "Segoe UI", sans-serif; color: #1e293b;
  font-size: 14px; line-height: 1.45; max-width: 70rem; }
.floorscan-front h2 { font-size: 1.35em; margin: 0.2em 0 0.4em; }
.floorscan-front h3 { font-size: 1.05em; margin: 1.1em 0 0.4em; }
.floorscan-front p, .floorscan-front ul { margin: 0.35em 0; }
.floorscan-front li { margin: 0.1em 0; }
.floorscan-front .top { display: flex; flex-wrap: wrap; gap: 1.2em; align-items: flex-start; }
.floorscan-front figure { margin: 0; }
.floorscan-front .plan { flex: 1 1 26rem; }
.floorscan-front .plan svg { display: block; width: 100%; height: auto; max-height: 34rem;
  background: #fff; border: 1px solid #cbd5e1; }
.floorscan-front figcaption { font-size: 0.85em; color: #475569; margin-top: 0.3em; }
.floorscan-front .facts { flex: 1 1 20rem; }
.floorscan-front .verdict { padding: 0.4em 0.6em; border-left: 4px solid #64748b;
  background: #f1f5f9; font-weight: 600; }
.floorscan-front .verdict.good { border-color: #16a34a; background: #f0fdf4; }
.floorscan-front .verdict.warning { border-color: #d97706; background: #fffbeb; }
.floorscan-front .verdict.poor { border-color: #dc2626; background: #fef2f2; }
.floorscan-front table { border-collapse: collapse; font-size: 0.85em; margin: 0.4em 0; width: auto; }
.floorscan-front th, .floorscan-front td { border: 1px solid #cbd5e1; padding: 0.15em 0.45em;
  text-align: left; vertical-align: top; }
.floorscan-front td.num { text-align: right; white-space: nowrap; font-variant-numeric: tabular-nums; }
.floorscan-front thead th { background: #e2e8f0; }
.floorscan-front table.facts-table th { background: #f8fafc; font-weight: 600; white-space: nowrap; }
.floorscan-front tr.recommended td { background: #fef9c3; font-weight: 600; }
.floorscan-front tr.bound td { color: #64748b; font-style: italic; }
.floorscan-front .note { font-size: 0.85em; color: #475569; }
.floorscan-front .quality img { max-width: 100%; height: auto; }
.floorscan-front code { font-size: 0.9em; }
.floorscan-front code::before, .floorscan-front code::after { content: none; }
"""


def front_page(
    dataset: str,
    *,
    floorplan_svg: str,
    summary: "pd.DataFrame | str | os.PathLike | None" = None,
    verdict: "Mapping | str | Sequence[str] | None" = None,
    detected: Mapping[str, str] | None = None,
    mode: str = "",
    quality_png: "str | os.PathLike | None" = None,
    scan_list: "str | os.PathLike | None" = None,
    k: int | None = None,
    n_kept: int | None = None,
    n_recorded: int | None = None,
    bytes_in: int | None = None,
    bytes_out: int | None = None,
    k_reason: str = "",
    ordering: str = "",
    extractor: str = "",
    n_walls: int | None = None,
    description: str = "",
    answer: "pd.DataFrame | str | os.PathLike | None" = None,
    answer_curve: "pd.DataFrame | str | os.PathLike | None" = None,
    rooms: "list[dict] | None" = None,
) -> str:
    """The front page of a dataset's result as one self-contained HTML document.

    Parameters
    ----------
    dataset : str
        Dataset name (title).
    floorplan_svg : str
        The recommended floor plan as SVG text (``results/<dataset>/floorplan.svg``,
        :func:`floorscan.floorplan.svg.write_svg`), inlined by :func:`inline_svg`.
    summary : pandas.DataFrame or path, optional
        The scan-reduction summary (:func:`floorscan.score.curve_summary.curve_summary`), or
        the path of ``summary.parquet``. None: the run did not evaluate (config
        ``evaluate``); the page says so.
    verdict : mapping, str or sequence of str, optional
        The registration's verdict: the dict of
        :meth:`floorscan.register.consistency.Verdict.as_dict` (its ``line``), or the
        line(s) themselves. The first word (GOOD, WARNING, POOR) colours it.
    detected : mapping, optional
        What ingest detected: the scan index's schema metadata
        (:func:`floorscan.core.io.read_metadata` of ``scan_index.parquet``); the keys of
        :data:`DETECTED_FIELDS` are shown.
    mode : str
        The register mode used (``pose`` or ``odometry``; empty: ``pose``).
    quality_png : path, optional
        The quality-vs-k figure (PNG), embedded as a data URI.
    scan_list : path, optional
        The list of the selected scans (``selection/scans.csv``), named on the page.
    k, n_kept, n_recorded : int, optional
        Scans selected, kept by the registration and recorded.
    bytes_in, bytes_out : int, optional
        Size of the recording and of the reduced recording, bytes.
    k_reason : str
        Why k (:func:`floorscan.select.deliverables.recommended_k`'s sentence).
    ordering, extractor : str
        The ordering and the wall extractor of the recommended plan: named in its
        caption, highlighted in the summary table; the ordering and the thesis's
        (:data:`THESIS_ORDERING`) are compared with random
        (:func:`floorscan.score.curve_summary.beats_random_line`).
    n_walls : int, optional
        Walls of the recommended plan.
    description : str
        The dataset's description (config ``datasets.<name>.description``).
    answer : pandas.DataFrame or path, optional
        The scores of the recommended plan and of the all-scan map plan
        (``evaluation/answer_scores.csv``, :func:`floorscan.score.answer.score_answer`),
        shown as "How good the plan is".
    answer_curve : pandas.DataFrame or path, optional
        The answer's quality curve (``evaluation/answer_curve.csv``,
        :func:`floorscan.score.answer_curve.answer_curve`): its k95 and k99 join that table.
    rooms : list of dict, optional
        The plan's rooms (:func:`floorscan.figures.room_table.read_plan_rooms`): a
        table of name, kind and area, and the floor area
        (:func:`~floorscan.figures.room_table.rooms_table_html`).

    Returns
    -------
    str
        The HTML document.

    Raises
    ------
    ValueError
        ``floorplan_svg`` is not an SVG or holds a script, or ``summary`` is a path
        that is not a Parquet table.
    """
    table = _read_summary(summary)
    esc = html.escape
    head = f"{dataset}: floor plan"
    if k is not None and n_recorded:
        head += f" from {k} of {n_recorded} recorded scans"
    parts = [f'<div class="{ROOT_CLASS}" id="front-{esc(dataset, quote=True)}">', f"<h2>{esc(head)}</h2>"]
    if description:
        parts.append(f"<p>{esc(description)}</p>")
    parts.append('<div class="top">')
    parts.append(
        f'<figure class="plan">{inline_svg(floorplan_svg)}<figcaption>'
        f"{esc(plan_caption(k, ordering, extractor, n_walls))}</figcaption></figure>"
    )
    parts.append('<div class="facts">')
    parts += _verdict_html(verdict)
    parts += _scans_html(k, n_kept, n_recorded, bytes_in, bytes_out, scan_list, k_reason)
    if answer is not None:
        parts += answer_html(answer, answer_curve)
    parts += rooms_table_html(rooms)
    if table is not None:
        parts += _quality_html(table, ordering, extractor)
    parts += _detected_html(detected, mode)
    parts.append("</div></div>")

    parts.append("<h3>How few scans give the floor plan of all scans</h3>")
    if table is None:
        parts.append("<p>Not evaluated in this run (config <code>evaluate</code>): no summary.</p>")
    else:
        sentences = _beats_random(table, ordering)
        if sentences:
            parts.append("<ul>" + "".join(f"<li>{esc(s)}</li>" for s in sentences) + "</ul>")
        parts.append(summary_table_html(table, n_kept, ordering, extractor))
        parts.append(
            '<p class="note">Every floor plan is scored against the reference map (the occupancy grid of all '
            "kept scans). k95 / k99: the first k whose plan reaches 95 / 99 % of the all-scan plan's F1; "
            "AUC 20 %: mean F1 up to 20 % of the kept scans; random: mean of its seeds (&plusmn; their "
            "spread); oracle (grey): knows the reference, the bound no ordering can pass.</p>"
        )
    if quality_png is not None:
        parts.append(
            f'<figure class="quality"><img alt="floor-plan F1 against the number of scans" '
            f'src="{png_data_uri(quality_png)}"><figcaption>Floor-plan F1 against the number of scans k: every '
            "ordering, random's seeds and the oracle.</figcaption></figure>"
        )
    parts.append("</div>")
    body = "\n".join(parts)
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f"<title>{esc(head)}</title>\n<style>{FRONT_STYLE}</style>\n</head>\n<body>\n{body}\n</body>\n</html>\n"
    )


def write_front_page(path: "str | os.PathLike", dataset: str, **kwargs) -> str:
    """Write :func:`front_page` to ``path`` atomically.

    Parameters
    ----------
    path : path
    dataset : str
    **kwargs
        As :func:`front_page`.

    Returns
    -------
    str
        The page.
    """
    text = front_page(dataset, **kwargs)
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return text


def write_front_page_of_files(
    path: "str | os.PathLike",
    dataset: str,
    *,
    floorplan_svg: "str | os.PathLike",
    plan: "str | os.PathLike",
    selection: "str | os.PathLike",
    registration: "str | os.PathLike",
    index: "str | os.PathLike",
    summary: "str | os.PathLike | None" = None,
    quality_png: "str | os.PathLike | None" = None,
    extractor: str = "",
    description: str = "",
    answer: "str | os.PathLike | None" = None,
    answer_curve: "str | os.PathLike | None" = None,
    room_scores: "str | os.PathLike | None" = None,
) -> str:
    """:func:`write_front_page` of a dataset's stage outputs (rule ``front_page``).

    Parameters
    ----------
    path : path
        ``results/<dataset>/front.html``.
    floorplan_svg, plan : path
        The recommended floor plan: ``floorplan.svg``, and its Parquet tables
        ``plan_tables/`` (:mod:`floorscan.core.plan_tables`) for its wall count and rooms.
    selection : path
        ``selection/selection.json`` (:func:`floorscan.select.recommend.write_selection`):
        k and why, the counts, the scan list and the reduced recording's size.
    registration : path
        ``registration.parquet``: its metadata holds the verdict and the mode.
    index : path
        ``scan_index.parquet``: its metadata holds what ingest detected.
    summary, quality_png : path, optional
        ``summary.parquet`` and ``figures/quality_vs_k.png`` (None: not evaluated).
    extractor, description : str
        As :func:`front_page`.
    answer, answer_curve : path, optional
        ``evaluation/answer_scores.csv`` and ``evaluation/answer_curve.csv`` (None: not
        evaluated).
    room_scores : path, optional
        ``evaluation/room_scores.csv`` (:mod:`floorscan.score.rooms`): its rooms and
        doors against the truth join the answer's table, by plan.

    Returns
    -------
    str
        The page.
    """
    from floorscan.core.plan_tables import plan_faces_and_walls
    from floorscan.core.io import read_metadata
    from floorscan.select.recommend import read_selection

    sel = read_selection(selection)
    reg = read_metadata(registration)
    rec = sel.get("recording") or {}
    return write_front_page(
        path, dataset,
        floorplan_svg=Path(floorplan_svg).read_text(encoding="utf-8"),
        summary=summary,
        verdict=json.loads(reg["verdict"]) if "verdict" in reg else None,
        detected=read_metadata(index),
        mode=reg.get("mode", ""),
        quality_png=quality_png,
        scan_list=sel.get("scans"),
        k=sel.get("k"), n_kept=sel.get("n_kept"), n_recorded=sel.get("n_recorded"),
        bytes_in=rec.get("bytes_in"), bytes_out=rec.get("bytes_out"),
        k_reason=sel.get("reason", ""),
        ordering=sel.get("ordering", ""),
        extractor=extractor,
        n_walls=plan_faces_and_walls(plan)[1],
        description=description,
        answer=with_room_scores(answer, room_scores), answer_curve=answer_curve,
        rooms=read_plan_rooms(plan),
    )  # fmt: skip


# ------------------------------------------------------------------------ parts


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
    return text + ": floorplan.svg, also as GeoJSON, DXF and IFC."


#: Rows of the compact quality table beside the plan (the full table is below it).
QUALITY_ROWS = ("oracle", THESIS_ORDERING, "random")
#: Its columns: summary column and header.
QUALITY_COLUMNS = (("ordering", "ordering"), ("k_95", "k95"), ("k_99", "k99"), ("auc", "AUC 20 %"))


def _quality_html(summary: "pd.DataFrame", ordering: str, extractor: str) -> list[str]:
    """The recommended ordering against the thesis's, random and the oracle, for the
    recommended plan's extractor: k95, k99 and the AUC (the summary's cells), so the
    page's first screen says how few scans the plan needs."""
    esc = html.escape
    if extractor and "extractor" in summary and not (summary["extractor"] == extractor).any():
        # the answer's extractor has no curves of every ordering (the map extractor: its
        # own curve is in the answer table); show the thesis's per-scan extractor's
        extractor = "ransac" if (summary["extractor"] == "ransac").any() else str(summary["extractor"].iloc[0])
    rows = summary[summary["extractor"] == extractor] if extractor and "extractor" in summary else summary
    order = [ordering] + [o for o in QUALITY_ROWS if o != ordering]
    records = {r["ordering"]: r for r in rows.to_dict("records")}
    out = [f"<h3>Scans needed ({esc(extractor)} walls)</h3>" if extractor else "<h3>Scans needed</h3>", "<table>",
           "<thead><tr>" + "".join(f"<th>{esc(h)}</th>" for _, h in QUALITY_COLUMNS) + "</tr></thead><tbody>"]
    for name in order:
        r = records.get(name)
        if r is None:
            continue
        cls = "recommended" if name == ordering else ("bound" if name == "oracle" else "")
        cells = [f"<td>{esc(name)}</td>"] + [
            f'<td class="num">{esc(summary_cell(r, col))}</td>' for col, _ in QUALITY_COLUMNS[1:]
        ]
        out.append(f'<tr class="{cls}">' + "".join(cells) + "</tr>")
    out.append("</tbody></table>")
    return out


def _read_summary(summary) -> "pd.DataFrame | None":
    if summary is None or not isinstance(summary, (str, os.PathLike)):
        return summary
    if Path(summary).suffix != ".parquet":
        raise ValueError(f"summary {summary}: expected summary.parquet (a table), not {Path(summary).suffix!r}")
    from floorscan.core.io import read_table

    return read_table(summary)


def _beats_random(table: "pd.DataFrame", ordering: str) -> list[str]:
    """Does the recommended ordering, and the thesis's, beat random, per extractor."""
    from floorscan.score.curve_summary import beats_random_line
    from floorscan.score.curves import RANDOM

    present = set(table["ordering"])
    if RANDOM not in present:
        return []
    shown = [o for o in dict.fromkeys([ordering, THESIS_ORDERING]) if o and o in present]
    return [beats_random_line(table, o, e) for o in shown for e in sorted(set(table["extractor"]))]


def _verdict_html(verdict) -> list[str]:
    if not verdict:
        return ['<p class="verdict">Registration: no verdict recorded.</p>']
    if isinstance(verdict, Mapping):
        lines = [str(verdict["line"])]
    elif isinstance(verdict, str):
        lines = [verdict]
    else:
        lines = [str(v) for v in verdict]
    word = lines[0].split(":", 1)[0].strip().lower()
    cls = f" {word}" if word in ("good", "warning", "poor") else ""
    return [f'<p class="verdict{cls}">Registration: {html.escape(lines[0])}</p>'] + [
        f"<p>{html.escape(line)}</p>" for line in lines[1:]
    ]


def facts_table(rows: list[tuple[str, str]]) -> str:
    body = "".join(f"<tr><th>{html.escape(a)}</th><td>{b}</td></tr>" for a, b in rows)
    return f'<table class="facts-table">{body}</table>'


def _scans_html(k, n_kept, n_recorded, bytes_in, bytes_out, scan_list, k_reason: str) -> list[str]:
    esc = html.escape
    rows = []
    if k is not None:
        of = []
        if n_kept is not None:
            of.append(f"{n_kept} kept")
        if n_recorded:
            of.append(f"{n_recorded} recorded ({100 * k / n_recorded:.1f} %)")
        rows.append(("scans used", esc(f"{k}" + (" of " + ", ".join(of) if of else ""))))
    if bytes_in is not None and bytes_out is not None:
        frac = f" ({100 * bytes_out / bytes_in:.1f} %)" if bytes_in else ""
        rows.append(("recording", esc(f"{format_bytes(bytes_in)} → {format_bytes(bytes_out)}{frac}")))
    if scan_list is not None:
        rows.append(("scan list", f"<code>{esc(Path(scan_list).as_posix())}</code>"))
    out = ["<h3>Scans</h3>", facts_table(rows)] if rows else []
    if k_reason:
        out.append(f'<p class="note">{esc(k_reason)}</p>')
    return out


def _detected_html(detected, mode: str) -> list[str]:
    detected = dict(detected or {})
    rows = [(label, html.escape(str(detected[key]))) for key, label in DETECTED_FIELDS if detected.get(key)]
    rows.append(("registered in", html.escape(f"{mode or 'pose'} mode")))
    return ["<h3>What ingest detected</h3>", facts_table(rows)]

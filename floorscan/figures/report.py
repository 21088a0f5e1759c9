"""The front page of a dataset's result: what the report opens on.

:class:`FrontPage` holds what the page shows: the recommended floor plan (its SVG
inlined), the answer's files (links relative to the page's folder, a missing file named
and not linked: :class:`floorscan.figures.pages.OutputFile`) and the link back to the
index, how few scans it took (k of the kept and recorded scans, and why k is what it is
beside the curve's k95 and k99), the scan list, the reduced recording's size, the
registration's verdict, what ingest detected, the scan-reduction summary table and the
quality-vs-k figure (a PNG as a data URI). :func:`front_page` renders it with the
template ``templates/front_page.html.j2`` (:mod:`floorscan.figures.pages`, autoescaped);
:func:`write_front_page` writes it atomically; :func:`write_front_page_of_files` reads
the stage outputs it is made of and writes it (the stage script's one call).

Snakemake 9.27's report opens on its workflow description
(``workflow/report/workflow.rst``) and lets that description include a file verbatim
(docutils' ``raw`` directive with ``:file:``), so ``workflow.rst`` includes each
dataset's front page there; the page is also a result of the report (shown in a frame).
The description travels inside a ``<script>`` string of the report, so the page holds
no script and no HTML comment; its style is scoped to ``.floorscan-front`` and changes
nothing else on the report's page. Its links are relative to ``results/<dataset>/``,
where the page is written: ``workflow.rst`` makes them plain text inside the report,
where they would resolve elsewhere.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Mapping, Sequence

from floorscan.core.files import atomic_path
from floorscan.figures.answer import format_bytes
from floorscan.figures.front_parts import (  # noqa: F401 (QUALITY_*: the page's tables, for tests)
    QUALITY_COLUMNS, QUALITY_ROWS, THESIS_ORDERING, beats_random_lines, int_or_none, read_summary, inline_svg,
    plan_caption, png_data_uri, quality_table, verdict_lines,
)
from floorscan.figures.pages import INDEX, OutputFile, output_file, render, report_file
from floorscan.figures.plan_scores import answer_table
from floorscan.figures.room_table import read_plan_rooms, with_room_scores
from floorscan.figures.summary_page import summary_rows

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




@dataclass
class FrontPage:
    """What the front page of a recording's result shows: given to its template as one
    object (:func:`front_page`). Fields are plain inputs; the properties are what the
    template shows of them.

    Attributes
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
    scan_list : OutputFile, optional
        The list of the selected scans (``selection/scans.csv``), linked in the scans' table.
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
        (:func:`floorscan.core.score_tables.beats_random_line`).
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
        table of name, kind and area, and the floor area.
    files : list of OutputFile
        The answer's files (:func:`answer_files`), listed under "Files".
    index : OutputFile
        The index of every dataset (``results/index.html``), linked at the top.
    report : OutputFile, optional
        Snakemake's report (``results/report.html``), linked at the top when it exists.
    """

    dataset: str
    floorplan_svg: str
    summary: "pd.DataFrame | str | os.PathLike | None" = None
    verdict: "Mapping | str | Sequence[str] | None" = None
    detected: Mapping[str, str] | None = None
    mode: str = ""
    quality_png: "str | os.PathLike | None" = None
    scan_list: OutputFile | None = None
    k: int | None = None
    n_kept: int | None = None
    n_recorded: int | None = None
    bytes_in: int | None = None
    bytes_out: int | None = None
    k_reason: str = ""
    ordering: str = ""
    extractor: str = ""
    n_walls: int | None = None
    description: str = ""
    answer: "pd.DataFrame | str | os.PathLike | None" = None
    answer_curve: "pd.DataFrame | str | os.PathLike | None" = None
    rooms: "list[dict] | None" = None
    files: list[OutputFile] = field(default_factory=list)
    index: OutputFile = field(default_factory=lambda: INDEX)
    report: OutputFile | None = None

    def __post_init__(self):
        self.summary = read_summary(self.summary)

    # ------------------------------------------------------------ what the page shows

    @property
    def head(self) -> str:
        """The title: ``demo: floor plan from 10 of 321 recorded scans``."""
        head = f"{self.dataset}: floor plan"
        if self.k is not None and self.n_recorded:
            head += f" from {self.k} of {self.n_recorded} recorded scans"
        return head

    @property
    def plan_svg(self):
        """The plan's SVG, checked and made fit to inline (:func:`inline_svg`)."""
        from markupsafe import Markup

        return Markup(inline_svg(self.floorplan_svg))

    @property
    def caption(self) -> str:
        return plan_caption(self.k, self.ordering, self.extractor, self.n_walls)

    @property
    def verdict_lines(self) -> dict:
        """The verdict's first line, its class (``good``, ``warning``, ``poor`` or
        empty) and the lines after it."""
        return verdict_lines(self.verdict)

    @property
    def scan_rows(self) -> list[tuple[str, str, OutputFile | None]]:
        """The scans' table: (label, text, file to link or None)."""
        rows = []
        if self.k is not None:
            of = []
            if self.n_kept is not None:
                of.append(f"{self.n_kept} kept")
            if self.n_recorded:
                of.append(f"{self.n_recorded} recorded ({100 * self.k / self.n_recorded:.1f} %)")
            rows.append(("scans used", f"{self.k}" + (" of " + ", ".join(of) if of else ""), None))
        if self.bytes_in is not None and self.bytes_out is not None:
            frac = f" ({100 * self.bytes_out / self.bytes_in:.1f} %)" if self.bytes_in else ""
            rows.append(("recording", f"{format_bytes(self.bytes_in)} → {format_bytes(self.bytes_out)}{frac}", None))
        if self.scan_list is not None:
            rows.append(("scan list", self.scan_list.name, self.scan_list))
        return rows

    @property
    def answer_table(self) -> dict | None:
        """"How good the plan is" (:func:`floorscan.figures.plan_scores.answer_table`)."""
        return None if self.answer is None else answer_table(self.answer, self.answer_curve)

    @property
    def quality_table(self) -> dict | None:
        """The recommended ordering against the thesis's, random and the oracle, for the
        recommended plan's extractor: k95, k99 and the AUC (the summary's cells), so the
        page's first screen says how few scans the plan needs."""
        if self.summary is None:
            return None
        return quality_table(self.summary, self.ordering, self.extractor)

    @property
    def k_figures(self) -> tuple[int | None, int | None, str]:
        """The k95 and k99 the page shows beside k, and whose they are: the answer's
        curve (the recommended plan's own), else the recommended ordering's row of the
        summary."""
        table = self.answer_table
        if table and table["k95"] is not None and table["k99"] is not None:
            return table["k95"], table["k99"], "this plan's curve"
        quality = self.quality_table
        if quality:
            for cls, cells in quality["rows"]:
                if "recommended" in cls.split():
                    return int_or_none(cells[1]), int_or_none(cells[2]), f"the {self.ordering} curve"
        return None, None, ""

    @property
    def k_explanation(self) -> str:
        """Why k is what it is, beside the curve's k95 and k99, when k differs from
        them: k is chosen by the selection's rule before any plan is scored (its
        reason); k95 and k99 are measured afterwards, on the F1 of the plans."""
        k95, k99, whose = self.k_figures
        if self.k is None or k95 is None or k99 is None or self.k in (k95, k99):
            return ""
        if self.k > k99:
            rel, so = "more than", "so the extra scans are a margin"
        elif self.k < k95:
            rel, so = "fewer than", "so the plan of k scans on that curve is below 95 % of the all-scan plan's F1"
        else:
            rel, so = "between", "so the plan of k scans on that curve is below 99 % of the all-scan plan's F1"
        reason = f" ({self.k_reason})" if self.k_reason else ""
        return (
            f"k = {self.k} is {rel} the k95 = {k95} and k99 = {k99} of {whose} because the selection chose k "
            f"before any plan was scored, by its own rule{reason}; k95 and k99 are measured afterwards, on the F1 "
            f"of the plans of the first k scans against the reference map, {so}."
        )

    @property
    def beats_random(self) -> list[str]:
        return [] if self.summary is None else beats_random_lines(self.summary, self.ordering)

    @property
    def summary_table(self) -> dict:
        """The full summary (:func:`floorscan.figures.summary_page.summary_rows`)."""
        return summary_rows(self.summary, self.n_kept, self.ordering, self.extractor)

    @property
    def detected_rows(self) -> list[tuple[str, str]]:
        """What ingest detected (:data:`DETECTED_FIELDS`) and the register mode."""
        detected = dict(self.detected or {})
        rows = [(label, str(detected[key])) for key, label in DETECTED_FIELDS if detected.get(key)]
        rows.append(("registered in", f"{self.mode or 'pose'} mode"))
        return rows

    @property
    def quality_png_uri(self) -> str:
        return "" if self.quality_png is None else png_data_uri(self.quality_png)


def answer_files(page_dir: "str | os.PathLike", selection: Mapping | None = None) -> list[OutputFile]:
    """The answer's files a front page in ``page_dir`` names, each a link when it exists.

    Parameters
    ----------
    page_dir : path
        The page's folder, ``results/<dataset>``.
    selection : mapping, optional
        ``selection/selection.json`` (:func:`floorscan.core.selection.read_selection`):
        where the scan list, the reduced recording and the points are; None for a map.

    Returns
    -------
    list of OutputFile
        The floor plan (SVG, GeoJSON, DXF, IFC), the occupancy map (PGM, YAML), the scan
        list, the reduced recording, the points (PLY, PCD) and ``summary.md``.
    """
    d = Path(page_dir)
    named = [
        ("floor plan, SVG", d / "floorplan.svg"),
        ("floor plan, GeoJSON", d / "floorplan.geojson"),
        ("floor plan, DXF (CAD)", d / "floorplan.dxf"),
        ("floor plan, IFC (BIM)", d / "floorplan.ifc"),
        ("occupancy map, PGM", d / "map.pgm"),
        ("occupancy map, YAML (ROS map_server, Nav2)", d / "map.yaml"),
    ]
    if selection is not None:
        rec = selection.get("recording") or {}
        points = list(selection.get("points") or [])
        named += [("scan list", selection.get("scans")), ("reduced recording", rec.get("path"))]
        named += [(f"points, {Path(p).suffix[1:].upper()}", p) for p in points]
    named.append(("summary", d / "summary.md"))
    return [output_file(label, p, d) for label, p in named if p]


def front_page(page: FrontPage) -> str:
    """The front page of a dataset's result as one self-contained HTML document: the
    template ``front_page.html.j2`` given ``page``.

    Parameters
    ----------
    page : FrontPage

    Returns
    -------
    str
        The HTML document.

    Raises
    ------
    ValueError
        ``page.floorplan_svg`` is not an SVG or holds a script, or ``page.summary`` is a
        path that is not a Parquet table.
    """
    return render("front_page.html.j2", page)


def write_front_page(path: "str | os.PathLike", page: FrontPage) -> str:
    """Write :func:`front_page` to ``path`` atomically.

    Parameters
    ----------
    path : path
    page : FrontPage

    Returns
    -------
    str
        The page.
    """
    text = front_page(page)
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
        ``results/<dataset>/front.html``; the answer's files are linked relative to its
        folder, those that exist now (:func:`answer_files`).
    floorplan_svg, plan : path
        The recommended floor plan: ``floorplan.svg``, and its Parquet tables
        ``plan_tables/`` (:mod:`floorscan.core.plan_tables`) for its wall count and rooms.
    selection : path
        ``selection/selection.json`` (:func:`floorscan.select.recommend.write_selection`):
        k and why, the counts, the scan list, the reduced recording and the points.
    registration : path
        ``registration.parquet``: its metadata holds the verdict and the mode.
    index : path
        ``scan_index.parquet``: its metadata holds what ingest detected.
    summary, quality_png : path, optional
        ``summary.parquet`` and ``figures/quality_vs_k.png`` (None: not evaluated).
    extractor, description : str
        As :class:`FrontPage`.
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
    from floorscan.core.selection import read_selection

    page_dir = Path(path).parent
    sel = read_selection(selection)
    reg = read_metadata(registration)
    rec = sel.get("recording") or {}
    page = FrontPage(
        dataset,
        floorplan_svg=Path(floorplan_svg).read_text(encoding="utf-8"),
        summary=summary,
        verdict=json.loads(reg["verdict"]) if "verdict" in reg else None,
        detected=read_metadata(index),
        mode=reg.get("mode", ""),
        quality_png=quality_png,
        scan_list=output_file("scan list", sel["scans"], page_dir) if sel.get("scans") else None,
        k=sel.get("k"), n_kept=sel.get("n_kept"), n_recorded=sel.get("n_recorded"),
        bytes_in=rec.get("bytes_in"), bytes_out=rec.get("bytes_out"),
        k_reason=sel.get("reason", ""),
        ordering=sel.get("ordering", ""),
        extractor=extractor,
        n_walls=plan_faces_and_walls(plan)[1],
        description=description,
        answer=with_room_scores(answer, room_scores), answer_curve=answer_curve,
        rooms=read_plan_rooms(plan),
        files=answer_files(page_dir, sel),
        report=report_file(page_dir),
    )  # fmt: skip
    return write_front_page(path, page)

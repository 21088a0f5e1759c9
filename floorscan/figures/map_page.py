"""The answer of an occupancy map given as the recording (:mod:`floorscan.ingest.occupancy_map`):
its front page (:func:`write_map_front_page`) and ``summary.md`` (:func:`write_map_summary`);
the run's last lines are :func:`floorscan.figures.answer.map_answer_lines`.

A map gives the plan (walls, clutter, junctions, rooms, doors, every export) and the map
as read (``map.pgm``, ``map.yaml``); it holds no scans, so nothing that needs them is
made: no registration and its verdict, no selection, scan list, reduced recording or
points, no evaluation against the scans' reference.
:data:`floorscan.figures.answer.NOT_FROM_A_MAP` says so wherever the answer of a
recording would list them.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

from floorscan.core.files import atomic_path
from floorscan.figures.answer import NOT_FROM_A_MAP, plan_counts
from floorscan.figures.pages import INDEX, OutputFile, render, report_file
from floorscan.figures.report import answer_files, inline_svg
from floorscan.figures.room_table import read_plan_rooms

def write_map_summary(
    path: str | os.PathLike, dataset: str, info: str | os.PathLike, floorplan_geojson: str | os.PathLike
) -> str:
    """Write ``summary.md`` of a map dataset: what was read of the map, where the plan
    is, and what a map does not give.

    Parameters
    ----------
    path : path
        ``results/<dataset>/summary.md``.
    dataset : str
    info : path
        ``map/map.json``.
    floorplan_geojson : path
        The plan's GeoJSON (its counts).

    Returns
    -------
    str
        The Markdown written.
    """
    from floorscan.core.map_info import map_line, read_map_info

    root = Path(path).parent
    lines = [
        f"# Floor plan of an occupancy map: {dataset}", "",
        f"Recording: {map_line(read_map_info(info))}.", "",
        "## The answer", "",
        f"- floor plan: `{root}/floorplan.{{geojson,svg,dxf,ifc}}`{plan_counts(floorplan_geojson)}, in the map's own "
        "frame (map_server's: metres from its origin)",
        f"- occupancy map as read: `{root}/map.pgm`, `map.yaml` (ROS map_server, Nav2)",
        f"- front page: `{root}/front.html`", "",
        f"Not from a map: {NOT_FROM_A_MAP}.", "",
    ]  # fmt: skip
    text = "\n".join(lines)
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return text


@dataclass
class MapFrontPage:
    """What the front page of a map's plan shows, in the style of a recording's
    (:class:`floorscan.figures.report.FrontPage`): given to its template as one object
    (:func:`map_front_page`).

    Attributes
    ----------
    dataset : str
    floorplan_svg : str
        The plan as SVG text, inlined.
    info : dict
        :meth:`floorscan.core.map_info.MapInfo.as_dict`.
    rooms : list of dict, optional
        :func:`floorscan.figures.room_table.read_plan_rooms`.
    n_walls : int, optional
    description : str
    files : list of OutputFile
        The plan's files and the map as read
        (:func:`floorscan.figures.report.answer_files` without a selection).
    index : OutputFile
        The index of every dataset.
    report : OutputFile, optional
        Snakemake's report, linked when it exists.
    """

    dataset: str
    floorplan_svg: str
    info: dict
    rooms: list[dict] | None = None
    n_walls: int | None = None
    description: str = ""
    files: list[OutputFile] = field(default_factory=list)
    index: OutputFile = field(default_factory=lambda: INDEX)
    report: OutputFile | None = None

    @property
    def head(self) -> str:
        return f"{self.dataset}: floor plan of an occupancy map"

    @property
    def plan_svg(self):
        """The plan's SVG, checked and made fit to inline (:func:`inline_svg`)."""
        from markupsafe import Markup

        return Markup(inline_svg(self.floorplan_svg))

    @property
    def caption(self) -> str:
        caption = "The plan of the map's walls and free space (walls, clutter dashed, rooms, doors)"
        return caption + (f": {self.n_walls} walls." if self.n_walls is not None else ".")

    @property
    def read_rows(self) -> list[tuple[str, str, bool]]:
        """What was read of the map: (label, text, shown as code)."""
        info = self.info
        kind = "ROS map_server map" if Path(info["image"]).name != Path(info["path"]).name else "map image"
        return [
            ("format", kind, False),
            ("read from", str(info["path"]), True),
            ("cells", f"{info['width']} x {info['height']} of {info['resolution_m']:g} m", False),
            ("origin", f"({info['origin_x_m']:g}, {info['origin_y_m']:g}) m", False),
            ("mode", f"{info['mode']}{', negated' if info['negate'] else ''}; occupied above "
                     f"{info['occupied_thresh']:g}, free below {info['free_thresh']:g}", False),
            ("occupied / free / unknown", f"{info['n_occupied']} / {info['n_free']} / {info['n_unknown']} cells", False),
        ]  # fmt: skip

    @property
    def not_from_a_map(self) -> str:
        return NOT_FROM_A_MAP[0].upper() + NOT_FROM_A_MAP[1:]


def map_front_page(page: MapFrontPage) -> str:
    """The front page of a map's plan as one self-contained HTML document: the template
    ``map_front_page.html.j2`` given ``page``.

    Parameters
    ----------
    page : MapFrontPage

    Returns
    -------
    str

    Raises
    ------
    ValueError
        ``page.floorplan_svg`` is not an SVG or holds a script.
    """
    return render("map_front_page.html.j2", page)


def write_map_front_page(
    path: str | os.PathLike, dataset: str, *, floorplan_svg: str | os.PathLike, plan: str | os.PathLike,
    info: str | os.PathLike, description: str = "",
) -> str:  # fmt: skip
    """:func:`map_front_page` of a map dataset's files, written atomically (rule
    ``map_front_page``).

    Parameters
    ----------
    path : path
        ``results/<dataset>/front.html``; the plan's files and the map are linked
        relative to its folder, those that exist now.
    dataset : str
    floorplan_svg : path
        ``floorplan.svg``.
    plan : path
        ``plan_tables/`` (its rooms and wall count).
    info : path
        ``map/map.json``.
    description : str

    Returns
    -------
    str
        The page.
    """
    from floorscan.core.plan_tables import plan_faces_and_walls
    from floorscan.core.map_info import read_map_info

    page_dir = Path(path).parent
    text = map_front_page(MapFrontPage(
        dataset, floorplan_svg=Path(floorplan_svg).read_text(encoding="utf-8"), info=read_map_info(info),
        rooms=read_plan_rooms(plan), n_walls=plan_faces_and_walls(plan)[1], description=description,
        files=answer_files(page_dir), report=report_file(page_dir),
    ))  # fmt: skip
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return text

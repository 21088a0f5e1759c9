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

import html
import os
from pathlib import Path

from floorscan.core.files import atomic_path
from floorscan.figures.answer import NOT_FROM_A_MAP, plan_counts
from floorscan.figures.report import FRONT_STYLE, ROOT_CLASS, facts_table, inline_svg
from floorscan.figures.room_table import read_plan_rooms, rooms_table_html

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
    from floorscan.ingest.occupancy_map import map_line, read_map_info

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


def map_front_page(dataset: str, *, floorplan_svg: str, info: dict, rooms: list[dict] | None = None,
                   n_walls: int | None = None, description: str = "") -> str:  # fmt: skip
    """The front page of a map's plan as one self-contained HTML document, in the
    style of a recording's (:func:`floorscan.figures.report.front_page`).

    Parameters
    ----------
    dataset : str
    floorplan_svg : str
        The plan as SVG text, inlined.
    info : dict
        :meth:`floorscan.ingest.occupancy_map.MapInfo.as_dict`.
    rooms : list of dict, optional
        :func:`floorscan.figures.room_table.read_plan_rooms`.
    n_walls : int, optional
    description : str

    Returns
    -------
    str

    Raises
    ------
    ValueError
        ``floorplan_svg`` is not an SVG or holds a script.
    """
    esc = html.escape
    head = f"{dataset}: floor plan of an occupancy map"
    parts = [f'<div class="{ROOT_CLASS}" id="front-{esc(dataset, quote=True)}">', f"<h2>{esc(head)}</h2>"]
    if description:
        parts.append(f"<p>{esc(description)}</p>")
    caption = "The plan of the map's walls and free space (walls, clutter dashed, rooms, doors)"
    caption += f": {n_walls} walls." if n_walls is not None else "."
    parts += ['<div class="top">', f'<figure class="plan">{inline_svg(floorplan_svg)}<figcaption>{esc(caption)}</figcaption></figure>',
              '<div class="facts">']  # fmt: skip
    rows = [
        ("format", esc("ROS map_server map" if Path(info["image"]).name != Path(info["path"]).name else "map image")),
        ("read from", f"<code>{esc(info['path'])}</code>"),
        ("cells", esc(f"{info['width']} x {info['height']} of {info['resolution_m']:g} m")),
        ("origin", esc(f"({info['origin_x_m']:g}, {info['origin_y_m']:g}) m")),
        ("mode", esc(f"{info['mode']}{', negated' if info['negate'] else ''}; occupied above "
                     f"{info['occupied_thresh']:g}, free below {info['free_thresh']:g}")),
        ("occupied / free / unknown", esc(f"{info['n_occupied']} / {info['n_free']} / {info['n_unknown']} cells")),
    ]  # fmt: skip
    parts += ["<h3>What was read</h3>", facts_table(rows)]
    parts += rooms_table_html(rooms)
    parts += ["<h3>What a map does not give</h3>", f"<p>{esc(NOT_FROM_A_MAP[0].upper() + NOT_FROM_A_MAP[1:])}.</p>"]
    parts += ["</div></div>", "</div>"]
    body = "\n".join(parts)
    return (
        '<!DOCTYPE html>\n<html lang="en">\n<head>\n<meta charset="utf-8">\n'
        f"<title>{esc(head)}</title>\n<style>{FRONT_STYLE}</style>\n</head>\n<body>\n{body}\n</body>\n</html>\n"
    )


def write_map_front_page(
    path: str | os.PathLike, dataset: str, *, floorplan_svg: str | os.PathLike, plan: str | os.PathLike,
    info: str | os.PathLike, description: str = "",
) -> str:  # fmt: skip
    """:func:`map_front_page` of a map dataset's files, written atomically (rule
    ``map_front_page``).

    Parameters
    ----------
    path : path
        ``results/<dataset>/front.html``.
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
    from floorscan.ingest.occupancy_map import read_map_info

    text = map_front_page(
        dataset, floorplan_svg=Path(floorplan_svg).read_text(encoding="utf-8"), info=read_map_info(info),
        rooms=read_plan_rooms(plan), n_walls=plan_faces_and_walls(plan)[1], description=description,
    )  # fmt: skip
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return text

"""The SVG export of a floor plan (:func:`write_svg`; a browser): a plain SVG (no
scripts) that scales to any window (``viewBox``, width and height 100 %), with a title,
the wall polygons (walls of which one face was seen drawn lighter and dashed), axes,
the clutter (thin dashed lines under the walls, when the plan has some), the rooms
(a light fill per kind under everything, holes left empty, a label with the name and
area inside each) and the doors (the opening cleared across its wall and drawn as a
coloured line), a scale bar of a round length in metres, a legend and the map frame's
x (right) and y (up) axes; the map's y is up, SVG's down: the drawing is flipped. With
a georeference (:class:`~floorscan.floorplan.georeference.Georeference`), a north
arrow. The file is written atomically and is byte-identical when written again from
the same input.
Source: SVG 1.1 (W3C).
"""

from __future__ import annotations

import math
import os
from typing import TYPE_CHECKING, Mapping, Sequence
from xml.sax.saxutils import escape

import numpy as np

from floorscan.core.files import atomic_path
from floorscan.floorplan.footprints import PlanExports
from floorscan.floorplan.georeference import Georeference, as_georeference
from floorscan.floorplan.metadata import PlanMetadata, export_time, floor_area_m2, floorscan_version
from floorscan.core.messages import count_text

if TYPE_CHECKING:
    from floorscan.floorplan.params import FloorplanParams
    from floorscan.floorplan.plan import FloorPlan


#: Size of the text and of the marks around the plan (title, legend, scale bar, axes)
#: against the 12 px they were laid out for: the plan's longer side is 1000 px of the
#: viewBox, so a page that shows the drawing 600 to 900 px wide shows 12 px text at 7 to
#: 11 px; 1.6 times it is 11 to 17 px, readable at 100 % zoom.
SVG_TEXT_SCALE = 1.6
#: Room labels: the name and the area under it, px of the viewBox (inside the plan,
#: where a larger label no longer fits a small room).
SVG_ROOM_LABEL_PX, SVG_ROOM_AREA_PX = 18.0, 15.0
#: The gap between a room label's two lines, and the height of a line's capitals above its
#: baseline (em; DejaVu Sans' and Helvetica's are 0.73 em), px of the viewBox and em.
SVG_ROOM_LINE_GAP_PX, SVG_ASCENT_EM = 3.0, 0.73
#: SVG layout, pixels of the viewBox (the SVG scales to the window): the plan's longer
#: side, the least canvas width (title, scale bar and legend fit), margins and bands.
SVG_PLAN_PX, SVG_MARGIN_PX = 1000.0, 20.0
SVG_MIN_WIDTH_PX, SVG_HEAD_PX, SVG_FOOT_PX = 720.0 * SVG_TEXT_SCALE, 56.0 * SVG_TEXT_SCALE, 84.0 * SVG_TEXT_SCALE
#: A legend row of a kind of room or of doors, pixels: the foot band grows by one each.
SVG_LEGEND_ROW_PX = 19.0 * SVG_TEXT_SCALE
#: Seconds since the epoch from which a time stamp is a date (2000-01-01): below it the
#: stamps count from the recording's start or from nothing (a CARMEN log, a map).
ABSOLUTE_TIME_S = 946_684_800
#: Room fills by kind (light, under the walls), the fill of another kind, and how the
#: legend names each kind.
SVG_ROOM_FILLS = {"room": "#fbefc4", "corridor": "#d3e8f5", "space": "#dff0d8"}
SVG_ROOM_FILL_OTHER = "#eeeeee"
#: Colour of a room's outline.
SVG_ROOM_OUTLINE = "#a8946a"
SVG_ROOM_LABELS = {"room": "room", "corridor": "corridor", "space": "open space (not closed by walls)"}
#: Colour of a door: its opening, leaf and swing (apart from the red wall axes).
SVG_DOOR_COLOUR = "#2b8a3e"


def _scale_bar_length(max_m: float) -> float:
    """The longest of 1, 2 and 5 x 10^n metres not above ``max_m`` (> 0), metres."""
    e = math.floor(math.log10(max_m))
    for m in (5, 2, 1):
        length = float(f"{m}e{e}")
        if length <= max_m * (1 + 1e-12):
            return length
    return float(f"1e{e - 1}")  # pragma: no cover (rounding of log10)


def write_svg(
    plan: FloorPlan, path: str | os.PathLike, metadata: PlanMetadata | None = None,
    georeference: Georeference | Mapping | None = None,
) -> None:  # fmt: skip
    """Write the floor plan as a plain SVG that fits any browser window.

    The viewBox is in pixels: the plan's longer side :data:`SVG_PLAN_PX`, a title
    band above (the plan's title and the number of walls), a band below with a
    scale bar (a round length in metres, :func:`_scale_bar_length`), the map frame's
    x (right) and y (up) axes (with a georeference also north) and a legend (wall;
    wall of which one face was seen, whose thickness is assumed: lighter, dashed;
    wall axis). ``width`` and ``height`` are 100 %: a browser scales the drawing to
    its window, aspect kept. The plan is drawn in map metres inside a group whose
    transform ``matrix(s 0 0 -s tx ty)`` flips y (the map's y is up, SVG's down);
    ``s`` is pixels per metre. Each axis line has a tooltip (length x thickness).
    With rooms: a fill per room under the walls (:data:`SVG_ROOM_FILLS`; holes by
    ``fill-rule="evenodd"``), its name and area (``"12.4 m²"``) at its label point
    (:attr:`~floorscan.floorplan.footprints.PlanExports.room_labels`), the counts and
    floor area right of the title; with doors: the opening as a coloured line over a
    white gap across its wall; a legend row per kind of room and one for doors.

    Parameters
    ----------
    plan : FloorPlan
    path : path
        Output, written atomically.
    metadata : PlanMetadata, optional
    georeference : Georeference or mapping, optional
        Only draws north; coordinates stay map metres.
    """
    _write_svg(PlanExports(plan), path, metadata or PlanMetadata(), as_georeference(georeference))


def _write_svg(
    exports: PlanExports, path: str | os.PathLike, meta: PlanMetadata, georeference: Georeference | None
) -> None:
    """:func:`write_svg` of a plan's :class:`~floorscan.floorplan.footprints.PlanExports`."""
    plan = exports.plan
    walls = plan.walls
    n = len(walls)
    kinds = _room_kinds(plan.rooms)
    n_extra = len(kinds) + (1 if len(plan.doors) else 0)  # legend rows of rooms and doors
    if exports.has_extent:
        lo, hi = exports.extent
        (xmin, ymin), (xmax, ymax) = (lo - 0.5).tolist(), (hi + 0.5).tolist()  # a margin, metres
    else:
        xmin, ymin, xmax, ymax = 0.0, 0.0, 1.0, 1.0
    s = SVG_PLAN_PX / max(xmax - xmin, ymax - ymin)  # pixels per metre
    pw, ph = (xmax - xmin) * s, (ymax - ymin) * s
    m = SVG_MARGIN_PX
    width = max(pw + 2 * m, SVG_MIN_WIDTH_PX)
    height = SVG_HEAD_PX + ph + SVG_FOOT_PX + SVG_LEGEND_ROW_PX * n_extra
    tx, ty = (width - pw) / 2 - s * xmin, SVG_HEAD_PX + s * ymax
    paired = walls["paired"].to_numpy(dtype=bool)
    n_paired = int(paired.sum())
    title = meta.title
    # the date only when the recording has one: stamps counted from 0 (a CARMEN log, a
    # map) are no date a person would read
    dated = export_time(meta.timestamp) >= ABSOLUTE_TIME_S
    sub = (
        f"{n} walls ({n_paired} with both faces seen, {n - n_paired} with one)"
        f" \u00b7 map frame of the recording, metres" + (f" \u00b7 {meta.time_stamp}" if dated else "")
    )
    about = "; ".join(f"{k}: {v or '-'}" for k, v in meta.fields)
    desc = (
        f"floorscan {floorscan_version()} floor plan. {about}; walls: {n}. "
        "Coordinates: map frame of the recording (x right, y up), metres."
    )
    if len(plan.rooms) or len(plan.doors):
        desc += f" Rooms: {len(plan.rooms)} ({floor_area_m2(plan):.1f} m2 floor area); doors: {len(plan.doors)}."
    if georeference is not None:
        desc += (
            f" Georeference: origin lat {georeference.lat}, lon {georeference.lon} (WGS84), "
            f"+x axis at {georeference.heading_deg} degrees clockwise from north."
        )
    px = 1.0 / s  # one pixel, metres
    T = SVG_TEXT_SCALE
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="100%" height="100%" '
        f'viewBox="0 0 {width:.2f} {height:.2f}" preserveAspectRatio="xMidYMid meet" '
        'font-family="sans-serif">',
        f"<title>{_xml(title)}</title>",
        f"<desc>{_xml(desc)}</desc>",
        f'<rect id="background" width="{width:.2f}" height="{height:.2f}" fill="#ffffff"/>',
        f'<text id="title" x="{m:.2f}" y="{26 * T:g}" font-size="{18 * T:g}" font-weight="bold">{_xml(title)}</text>',
        f'<text id="subtitle" x="{m:.2f}" y="{45 * T:g}" font-size="{12 * T:g}" fill="#444444">{_xml(sub)}</text>',
    ]
    if len(plan.rooms) or len(plan.doors):
        rooms, doors = count_text(len(plan.rooms), "room"), count_text(len(plan.doors), "door")
        summary = f"{rooms}, {floor_area_m2(plan):.1f} m\u00b2 \u00b7 {doors}"
        out.append(f'<text id="rooms-summary" x="{width - m:.2f}" y="{26 * T:g}" font-size="{12 * T:g}" text-anchor="end" '
                   f'fill="#444444">{_xml(summary)}</text>')
    out.append(f'<g id="plan" transform="matrix({s:.10g} 0 0 {-s:.10g} {tx:.6f} {ty:.6f})">')
    out += _svg_rooms(exports, px)
    clutter = plan.clutter
    if len(clutter):  # under the walls: thin, dashed, light
        out.append(f'<g id="clutter" stroke="#9aa5b1" stroke-width="{1.2 * px:.6g}" '
                   f'stroke-dasharray="{4 * px:.6g} {3 * px:.6g}" fill="none">')
        for cid, x0, y0, x1, y1, reason in zip(*(clutter[c].tolist() for c in ("clutter_id", "x0", "y0", "x1", "y1", "reason"))):
            out.append(f'<line x1="{x0:.4f}" y1="{y0:.4f}" x2="{x1:.4f}" y2="{y1:.4f}"><title>clutter {cid}: '
                       f"{_xml(str(reason))}</title></line>")
        out.append("</g>")
    groups = (
        ("walls", paired, f'fill="#8c8c8c" stroke="#333333" stroke-width="{0.6 * px:.6g}"'),
        ("walls-one-face", ~paired, f'fill="#dddddd" stroke="#333333" stroke-width="{0.6 * px:.6g}" '
         f'stroke-dasharray="{3 * px:.6g} {2 * px:.6g}"'),
    )  # fmt: skip
    for gid, which, style in groups:
        out.append(f'<g id="{gid}" {style}>')
        for ring, keep in zip(exports.rings, which.tolist()):
            if ring is not None and keep:
                pts = " ".join(f"{x:.4f},{y:.4f}" for x, y in ring[:-1])
                out.append(f'<polygon points="{pts}"/>')
        out.append("</g>")
    out.append(f'<g id="axes" stroke="#cc0000" stroke-width="{1.0 * px:.6g}" fill="none">')
    for wall_id, x0, y0, x1, y1, length, thickness in zip(
        *(walls[c].tolist() for c in ("wall_id", "x0", "y0", "x1", "y1", "length_m", "thickness_m"))
    ):
        out.append(
            f'<line x1="{x0:.4f}" y1="{y0:.4f}" x2="{x1:.4f}" y2="{y1:.4f}">'
            f"<title>wall {wall_id}: {length:.2f} m x {thickness:.2f} m</title></line>"
        )
    out.append("</g>")
    leaves = door_leaves(plan)
    out += _svg_doors(plan, px, leaves)
    out.append("</g>")
    out += _svg_room_labels(exports, s, tx, ty, door_swings(leaves))
    out += _svg_scale_bar(s, m, height - 30 * T)
    out += _svg_frame_axes(m + 250 * T, height - 30 * T, georeference)
    legend_y = height - (80 if len(clutter) else 74) * T - SVG_LEGEND_ROW_PX * n_extra
    out += _svg_legend(width - m - 300 * T, legend_y, with_clutter=bool(len(clutter)), room_kinds=kinds,
                       with_doors=bool(len(plan.doors)))
    out.append("</svg>")
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(out) + "\n", encoding="utf-8")


def _svg_scale_bar(s: float, x: float, y: float) -> list[str]:
    """A scale bar of a round length (at most 200 px) at ``(x, y)`` px, ``s`` px a metre."""
    length = _scale_bar_length(200.0 / s)
    bar = length * s
    t = 5 * SVG_TEXT_SCALE  # half a tick
    return [
        f'<g id="scale-bar" transform="translate({x:.2f} {y:.2f})" stroke="#000000" stroke-width="{2 * SVG_TEXT_SCALE:g}">',
        f'<line x1="0" y1="0" x2="{bar:.4f}" y2="0"/>',
        f'<line x1="0" y1="{-t:g}" x2="0" y2="{t:g}"/>',
        f'<line x1="{bar:.4f}" y1="{-t:g}" x2="{bar:.4f}" y2="{t:g}"/>',
        f'<text x="{bar / 2:.4f}" y="{-8 * SVG_TEXT_SCALE:g}" font-size="{12 * SVG_TEXT_SCALE:g}" text-anchor="middle" '
        f'stroke="none">{length:g} m</text>',
        "</g>",
    ]


def _svg_arrow(dx: float, dy: float, label: str, colour: str) -> list[str]:
    """An arrow from the origin to ``(dx, dy)`` px with ``label`` beyond its head."""
    norm = math.hypot(dx, dy)
    ux, uy = dx / norm, dy / norm
    bx, by = dx - 7 * ux, dy - 7 * uy  # base of the head
    head = f"{dx:.2f},{dy:.2f} {bx - 4 * uy:.2f},{by + 4 * ux:.2f} {bx + 4 * uy:.2f},{by - 4 * ux:.2f}"
    lx, ly = dx + 9 * ux, dy + 9 * uy + 4
    return [
        f'<line x1="0" y1="0" x2="{bx:.2f}" y2="{by:.2f}" stroke="{colour}" stroke-width="2"/>',
        f'<polygon points="{head}" fill="{colour}"/>',
        f'<text x="{lx:.2f}" y="{ly:.2f}" font-size="12" text-anchor="middle" fill="{colour}">{label}</text>',
    ]


def _svg_frame_axes(x: float, y: float, georeference: Georeference | None) -> list[str]:
    """The map frame's x (right) and y (up) axes at ``(x, y)`` px, and with a
    georeference the direction of true north in the map frame (``(cos h, sin h)``,
    ``h`` the heading; flipped to SVG's y down)."""
    out = [f'<g id="frame-axes" transform="translate({x:.2f} {y:.2f}) scale({SVG_TEXT_SCALE:g})">']
    out += _svg_arrow(32.0, 0.0, "x", "#000000")
    out += _svg_arrow(0.0, -32.0, "y", "#000000")
    if georeference is not None:
        h = math.radians(georeference.heading_deg)
        out.append('<g id="north" transform="translate(96 -16)">')
        out += _svg_arrow(26.0 * math.cos(h), -26.0 * math.sin(h), "N", "#1f4e9c")
        out.append("</g>")
    out.append('<text x="0" y="22" font-size="11" fill="#444444">map frame (m)</text>')
    out.append("</g>")
    return out


def _room_kinds(rooms) -> list[str]:
    """The kinds of room the plan has, in the order of :data:`SVG_ROOM_FILLS` (others
    after, sorted)."""
    present = {str(k) for k in rooms["kind"].tolist()}
    return [k for k in SVG_ROOM_FILLS if k in present] + sorted(present - set(SVG_ROOM_FILLS))


def _svg_path(poly) -> str:
    """SVG path data of a polygon, map metres: ``M x,y L ... Z`` per ring (exterior,
    then holes; drawn with ``fill-rule="evenodd"`` the holes stay empty)."""
    rings = [poly.exterior, *poly.interiors]
    return " ".join("M " + " L ".join(f"{x:.4f},{y:.4f}" for x, y in ring.coords[:-1]) + " Z" for ring in rings)


def _svg_rooms(exports: PlanExports, px: float) -> list[str]:
    """The rooms under everything else in the plan group (map metres, ``px`` metres a
    pixel): a light fill per kind (:data:`SVG_ROOM_FILLS`) with a thin outline, so that
    two rooms side by side read as two, holes by ``fill-rule="evenodd"``, a tooltip
    with the name, kind and area."""
    r = exports.plan.rooms
    if not len(r):
        return []
    out = [f'<g id="rooms" stroke="{SVG_ROOM_OUTLINE}" stroke-width="{1.0 * px:.6g}" stroke-linejoin="round" '
           'fill-rule="evenodd">']
    for room_id, name, kind, area, poly in zip(
        r["room_id"].tolist(), r["name"].tolist(), r["kind"].tolist(), r["area_m2"].tolist(),
        exports.room_polys.tolist(),
    ):  # fmt: skip
        if poly is None or poly.is_empty:
            continue
        fill = SVG_ROOM_FILLS.get(str(kind), SVG_ROOM_FILL_OTHER)
        out.append(f'<path id="room-{int(room_id)}" d="{_svg_path(poly)}" fill="{fill}"><title>'
                   f"{_xml(str(name))} ({_xml(str(kind))}): {float(area):.1f} m\u00b2</title></path>")
    out.append("</g>")
    return out


def door_leaves(plan: FloorPlan) -> list[tuple]:
    """Each door's opening, width and leaf, as :func:`_svg_doors` draws them: ``(door_id,
    x0, y0, x1, y1, width_m, wall_id, room_a, room_b, leaf, sweep)``, the leaf hinged at
    ``(x0, y0)``, as wide as the opening, at right angles to it into the first of the two
    rooms that is not a corridor (``leaf`` its free end, (2,) metres; ``sweep`` the SVG
    arc flag from the leaf back to ``(x1, y1)``)."""
    import shapely

    d = plan.doors
    polys = dict(zip(plan.rooms["room_id"].tolist(), plan.rooms["polygon"].tolist())) if len(plan.rooms) else {}
    corridor = set(plan.rooms.loc[plan.rooms["kind"] == "corridor", "room_id"].tolist()) if len(plan.rooms) else set()
    out = []
    for door_id, x0, y0, x1, y1, width, wall_id, a, b in zip(
        *(d[c].tolist() for c in ("door_id", "x0", "y0", "x1", "y1", "width_m", "wall_id", "room_a", "room_b"))
    ):
        w = float(np.hypot(x1 - x0, y1 - y0))
        n = np.array([-(y1 - y0), x1 - x0]) / max(w, 1e-12)
        mid = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
        room = polys.get(b if a in corridor and b not in corridor else a)
        if room is not None and not shapely.contains_xy(room, *(mid + 0.25 * w * n)) and shapely.contains_xy(room, *(mid - 0.25 * w * n)):
            n = -n  # the leaf opens into that room
        leaf = np.array([x0, y0]) + w * n
        sweep = 1 if (leaf[0] - x0) * (y1 - y0) - (leaf[1] - y0) * (x1 - x0) > 0 else 0
        out.append((door_id, x0, y0, x1, y1, width, wall_id, a, b, leaf, sweep))
    return out


def door_swings(leaves: list[tuple]):
    """The quarter discs the doors' leaves (:func:`door_leaves`) swing through, one
    shapely geometry in map metres (empty without doors): what a room's label keeps
    clear of where it can (:func:`_svg_room_labels`)."""
    import shapely

    sectors = []
    for _, x0, y0, x1, y1, _, _, _, _, leaf, _ in leaves:
        hinge = np.array([x0, y0])
        a0 = math.atan2(leaf[1] - y0, leaf[0] - x0)
        a1 = math.atan2(y1 - y0, x1 - x0)
        turn = (a1 - a0 + math.pi) % (2 * math.pi) - math.pi  # a quarter turn, either way
        t = a0 + turn * np.linspace(0.0, 1.0, 9)
        w = float(np.hypot(leaf[0] - x0, leaf[1] - y0))
        sectors.append(shapely.Polygon(np.vstack([hinge, hinge + w * np.c_[np.cos(t), np.sin(t)]])))
    return shapely.union_all(sectors) if sectors else shapely.GeometryCollection()


def _svg_doors(plan: FloorPlan, px: float, leaves: list[tuple]) -> list[str]:
    """The doors above the walls (map metres, ``px`` metres a pixel), drawn as a plan
    drawn by people draws them: the opening cleared to white across its wall's
    thickness, a thin line across it, and the leaf, as wide as the opening, swung a
    quarter turn into the first of the two rooms that is not a corridor, with its arc (:data:`SVG_DOOR_COLOUR`;
    a tooltip gives the width and the rooms joined); ``leaves``: :func:`door_leaves`."""
    if not len(plan.doors):
        return []
    thick = dict(zip(plan.walls["wall_id"].tolist(), plan.walls["thickness_m"].tolist()))
    out = [f'<g id="doors" fill="none" stroke="{SVG_DOOR_COLOUR}" stroke-linecap="butt">']
    for door_id, x0, y0, x1, y1, width, wall_id, a, b, leaf, sweep in leaves:
        xy = f'x1="{x0:.4f}" y1="{y0:.4f}" x2="{x1:.4f}" y2="{y1:.4f}"'
        if wall_id in thick:
            out.append(f'<line {xy} stroke="#ffffff" stroke-width="{float(thick[wall_id]) + 2 * px:.6g}"/>')
        w = float(np.hypot(x1 - x0, y1 - y0))
        out.append(
            f'<g><title>door {int(door_id)}: {float(width):.2f} m, rooms {int(a)} and {int(b)}</title>'
            f'<line {xy} stroke-width="{1.0 * px:.6g}"/>'
            f'<line x1="{x0:.4f}" y1="{y0:.4f}" x2="{leaf[0]:.4f}" y2="{leaf[1]:.4f}" stroke-width="{2.0 * px:.6g}"/>'
            f'<path d="M {leaf[0]:.4f} {leaf[1]:.4f} A {w:.4f} {w:.4f} 0 0 {sweep} {x1:.4f} {y1:.4f}" '
            f'stroke-width="{0.8 * px:.6g}" stroke-dasharray="{3 * px:.6g} {2 * px:.6g}"/></g>'
        )
    out.append("</g>")
    return out


def _svg_room_labels(exports: PlanExports, s: float, tx: float, ty: float, swings) -> list[str]:
    """A label per room, in pixels (outside the flipped plan group, so the text stands
    upright): the name, and the area in m\u00b2 below it, placed inside the room and
    clear of the other labels at the largest size that fits, level or along the room, off
    the doors' swings (``swings``, :func:`door_swings`) where it can
    (:func:`~floorscan.floorplan.labels.place_room_labels`, from the room's label point
    :attr:`~floorscan.floorplan.footprints.PlanExports.room_labels`); the name alone
    where two lines do not fit."""
    from floorscan.floorplan.labels import place_room_labels, room_label_boxes

    r = exports.plan.rooms
    if not len(r):
        return []
    name_px, area_px = SVG_ROOM_LABEL_PX, SVG_ROOM_AREA_PX
    names, areas, full, alone = room_label_boxes(r, name_px, area_px, SVG_ROOM_LINE_GAP_PX)
    xy, scale, with_area, angle = place_room_labels(exports.room_polys, exports.room_labels, full / s, alone / s,
                                                    np.full(len(names), name_px / s), swings)
    out = [f'<g id="room-labels" font-size="{name_px:g}" text-anchor="middle" fill="#333333">']
    for name, area, (x, y), f, both, turn in zip(names, areas, xy.tolist(), scale.tolist(), with_area.tolist(),
                                                angle.tolist()):
        if x != x:  # NaN: no polygon
            continue
        lx, ly = tx + s * x, ty - s * y
        height = f * (name_px + SVG_ROOM_LINE_GAP_PX + area_px if both else name_px)
        top = ly - height / 2
        size = "" if f == 1.0 else f' font-size="{f * name_px:.4g}"'
        if turn:  # along the room; the drawing's y runs down, so a turn to the left is negative
            size += f' transform="rotate({-math.degrees(turn):.2f} {lx:.2f} {ly:.2f})"'
        text = f'<text x="{lx:.2f}" y="{top + SVG_ASCENT_EM * f * name_px:.2f}"{size}>{_xml(name)}'
        if both:
            second = top + f * (name_px + SVG_ROOM_LINE_GAP_PX + SVG_ASCENT_EM * area_px)  # its baseline
            text += f'<tspan x="{lx:.2f}" y="{second:.2f}" font-size="{f * area_px:.4g}">{area}</tspan>'
        out.append(text + "</text>")
    out.append("</g>")
    return out


def _svg_legend(
    x: float, y: float, with_clutter: bool = False, room_kinds: Sequence[str] = (), with_doors: bool = False
) -> list[str]:
    """The legend at ``(x, y)`` px, scaled by :data:`SVG_TEXT_SCALE`: the kinds of things the plan draws (clutter only
    when the plan has some; a row per kind of room and one for doors only when the
    plan has them, :data:`SVG_LEGEND_ROW_PX` apart)."""
    clutter = [
        '<line x1="0" y1="64" x2="22" y2="64" stroke="#9aa5b1" stroke-width="1.2" stroke-dasharray="4 3"/>',
        '<text x="30" y="69">clutter (furniture, not a wall)</text>',
    ] if with_clutter else []  # fmt: skip
    rows, base = [], (69.0 if with_clutter else 50.0)
    row = SVG_LEGEND_ROW_PX / SVG_TEXT_SCALE  # the group is scaled by SVG_TEXT_SCALE
    for kind in room_kinds:
        base += row
        fill = SVG_ROOM_FILLS.get(kind, SVG_ROOM_FILL_OTHER)
        rows += [f'<rect x="0" y="{base - 10:g}" width="22" height="10" fill="{fill}" stroke="#bbbbbb" '
                 'stroke-width="0.6"/>', f'<text x="30" y="{base:g}">{_xml(SVG_ROOM_LABELS.get(kind, kind))}</text>']
    if with_doors:
        base += row
        rows += [f'<path d="M 2 {base:g} L 2 {base - 12:g} A 12 12 0 0 1 14 {base:g} Z" fill="none" '
                 f'stroke="{SVG_DOOR_COLOUR}" stroke-width="1.2"/>', f'<text x="30" y="{base:g}">door (opening in a wall, its leaf)</text>']
    return [
        f'<g id="legend" transform="translate({x:.2f} {y:.2f}) scale({SVG_TEXT_SCALE:g})" font-size="12">',
        '<rect x="0" y="0" width="22" height="10" fill="#8c8c8c" stroke="#333333" stroke-width="0.6"/>',
        '<text x="30" y="10">wall (both faces seen)</text>',
        '<rect x="0" y="20" width="22" height="10" fill="#dddddd" stroke="#333333" stroke-width="0.6" '
        'stroke-dasharray="3 2"/>',
        '<text x="30" y="30">wall, one face seen (thickness assumed)</text>',
        '<line x1="0" y1="45" x2="22" y2="45" stroke="#cc0000" stroke-width="1"/>',
        '<text x="30" y="50">wall axis</text>',
        *clutter,
        *rows,
        "</g>",
    ]


def _xml(s: str) -> str:
    """``s`` escaped for XML text and attribute values (``xml.sax.saxutils.escape``,
    and ``"``)."""
    return escape(s, {'"': "&quot;"})


def export(exports: PlanExports, path: str | os.PathLike, meta: PlanMetadata, params: FloorplanParams) -> None:
    """The SVG writer of :data:`floorscan.floorplan.EXPORT_FORMATS`: :func:`write_svg`
    of a plan's exports, with north when ``params.georeference`` is set.

    Parameters as every writer of :data:`~floorscan.floorplan.EXPORT_FORMATS` (the
    package docstring's "add an export format": ``exports``, ``path``, ``meta``,
    ``params``).
    """
    _write_svg(exports, path, meta, params.georeference)

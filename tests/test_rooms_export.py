"""Rooms and doors in every export of a floor plan: GeoJSON, SVG, DXF, IFC, the front page.

The plan, built by hand: a 6 m x 4 m box of 20 cm walls (axes on the box) split at
x = 3 m by a 10 cm partition with a 0.9 m door gap (y 1.0 to 1.9 m), a room left of
it and a corridor right of it around a 1 m x 1 m block (a polygon with a hole).
"""

import json
import xml.etree.ElementTree as ET

import numpy as np
import pandas as pd
import pytest
import shapely

from floorscan.floorplan import EXPORT_FORMATS, FLOORPLAN_FORMATS
from floorscan.floorplan.footprints import PlanExports
from floorscan.floorplan.metadata import PlanMetadata
from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.plan import DOOR_COLUMNS, ROOM_COLUMNS
from test_floorplan import SVG_NS, plan_of, signed_area

T, H = 0.2, 2.7  # outer wall thickness and every wall's height, metres
WALLS = [
    (0.0, 0.0, 6.0, 0.0, T, H, True), (6.0, 0.0, 6.0, 4.0, T, H, True), (6.0, 4.0, 0.0, 4.0, T, H, True),
    (0.0, 4.0, 0.0, 0.0, T, H, True),
    (3.0, 0.0, 3.0, 1.0, 0.1, H, True), (3.0, 1.9, 3.0, 4.0, 0.1, H, False),  # the partition, a 0.9 m gap
]  # fmt: skip
ROOM = shapely.box(0.1, 0.1, 2.95, 3.9)  # 2.85 x 3.8 = 10.83 m2
BLOCK = shapely.box(4.0, 1.5, 5.0, 2.5)
CORRIDOR = shapely.Polygon(shapely.box(3.05, 0.1, 5.9, 3.9).exterior.coords, [BLOCK.exterior.coords])  # 9.83 m2
META = PlanMetadata(dataset="box", ordering="random", extractor="ransac", k="all")


def rooms_plan(door_wall: int = 4):
    """The box plan with its two rooms and one door in the line of wall ``door_wall``."""
    plan = plan_of(WALLS)
    polys = [ROOM, CORRIDOR]
    plan.rooms = pd.DataFrame({
        "room_id": [1, 2], "name": ["Room 1", "Corridor 1"], "kind": ["room", "corridor"],
        "area_m2": [p.area for p in polys], "perimeter_m": [p.length for p in polys], "polygon": polys,
    })[ROOM_COLUMNS]  # fmt: skip
    plan.doors = pd.DataFrame({
        "door_id": [0], "x0": [3.0], "y0": [1.9], "x1": [3.0], "y1": [1.0], "width_m": [0.9],
        "wall_id": [door_wall], "room_a": [1], "room_b": [2],
    })[DOOR_COLUMNS]  # fmt: skip
    return plan


def write(plan, tmp_path, fmt, params=FloorplanParams(), meta=META, exports=None, name="p"):
    path = tmp_path / f"{name}{EXPORT_FORMATS[fmt].suffix}"
    EXPORT_FORMATS[fmt].write(exports or PlanExports(plan), path, meta, params)
    return path


# ------------------------------------------------------------------------------ GeoJSON


def test_geojson_rooms_are_rfc7946_polygons_with_their_areas_and_the_door_a_line(tmp_path):
    doc = json.loads(write(rooms_plan(), tmp_path, "geojson").read_text())
    rooms = [f for f in doc["features"] if f["properties"]["kind"] == "room"]
    doors = [f for f in doc["features"] if f["properties"]["kind"] == "door"]
    assert [f["geometry"]["type"] for f in rooms] == ["Polygon", "Polygon"] and len(doors) == 1
    assert [f["properties"]["name"] for f in rooms] == ["Room 1", "Corridor 1"]
    assert [f["properties"]["room_kind"] for f in rooms] == ["room", "corridor"]
    assert [f["properties"]["room_id"] for f in rooms] == [1, 2]
    for f, want in zip(rooms, (ROOM, CORRIDOR)):
        rings = f["geometry"]["coordinates"]
        assert len(rings) == 1 + len(want.interiors)  # the corridor keeps its hole
        assert all(r[0] == r[-1] for r in rings)  # closed
        assert signed_area(rings[0]) > 0 and all(signed_area(r) < 0 for r in rings[1:])  # RFC 7946 7.1.6
        poly = shapely.Polygon(rings[0], rings[1:])
        assert poly.is_valid and poly.area == pytest.approx(want.area, abs=1e-9)
        assert f["properties"]["area_m2"] == pytest.approx(want.area, abs=1e-4)
        assert f["properties"]["perimeter_m"] == pytest.approx(want.length, abs=1e-4)
    assert [round(a, 4) for a in (rooms[0]["properties"]["area_m2"], rooms[1]["properties"]["area_m2"])] == [
        10.83, 9.83]  # fmt: skip
    assert doors[0]["geometry"] == {"type": "LineString", "coordinates": [[3.0, 1.9], [3.0, 1.0]]}
    assert doors[0]["properties"] == {
        "kind": "door", "door_id": 0, "width_m": 0.9, "wall_id": 4, "room_a": 1, "room_b": 2}  # fmt: skip
    member = doc["floorscan"]
    assert (member["n_rooms"], member["n_doors"]) == (2, 1)
    assert member["floor_area_m2"] == pytest.approx(10.83 + 9.83, abs=1e-9)


def test_georeferenced_room_rings_keep_their_orientation(tmp_path):
    params = FloorplanParams(georeference={"lat": 47.37, "lon": 8.54, "heading_deg": 200.0})
    doc = json.loads(write(rooms_plan(), tmp_path, "geojson", params).read_text())
    (corridor,) = [f for f in doc["features"] if f["properties"].get("name") == "Corridor 1"]
    outer, hole = corridor["geometry"]["coordinates"]
    assert signed_area(outer) > 0 and signed_area(hole) < 0
    assert 8.5 < outer[0][0] < 8.6 and 47.3 < outer[0][1] < 47.4  # lon, lat degrees


def test_plan_readers_ignore_rooms_and_doors(tmp_path):
    """The readers of a plan's GeoJSON and the scorer's of its Parquet tables count
    walls, faces, axes and junctions as before: rooms and doors are not walls."""
    from floorscan.figures.floorplans import read_geojson_geometries
    from floorscan.floorplan.scans import write_plan
    from floorscan.score.answer import plan_parts
    from floorscan.score.geojson import read_floorplan

    path = write(rooms_plan(), tmp_path, "geojson")
    faces, n_walls = read_floorplan(path)
    assert (len(faces), n_walls) == (0, len(WALLS))
    write_plan(rooms_plan(), tmp_path / "plan")
    parts = plan_parts(tmp_path / "plan")
    assert len(parts["axes"]) == len(WALLS) and len(parts["clutter"]) == 0 and len(parts["junctions"]) == 0
    assert len(read_geojson_geometries(path)) == len(WALLS)


# ------------------------------------------------------------------------------ SVG


def test_svg_fills_rooms_labels_them_and_draws_the_door(tmp_path):
    root = ET.parse(write(rooms_plan(), tmp_path, "svg")).getroot()
    paths = root.findall(".//s:g[@id='rooms']/s:path", SVG_NS)
    assert root.find(".//s:g[@id='rooms']", SVG_NS).get("fill-rule") == "evenodd"
    assert [p.get("d").count("M") for p in paths] == [1, 2]  # the corridor's hole is a second ring
    assert paths[0].get("fill") != paths[1].get("fill")  # a fill per kind
    # rooms under the walls, doors above them
    order = [g.get("id") for g in root.find(".//s:g[@id='plan']", SVG_NS)]
    assert order.index("rooms") < order.index("walls") < order.index("doors")
    # labels: name and area, at a point inside the room (pixels back to metres)
    s, _, _, _, tx, ty = (float(v) for v in root.find(".//s:g[@id='plan']", SVG_NS).get("transform")[7:-1].split())
    labels = root.findall(".//s:g[@id='room-labels']/s:text", SVG_NS)
    assert ["".join(t.itertext()) for t in labels] == ["Room 110.8 m\u00b2", "Corridor 19.8 m\u00b2"]
    for text, poly in zip(labels, (ROOM, CORRIDOR)):
        x, y = (float(text.get("x")) - tx) / s, (ty - (float(text.get("y")) + 2)) / s
        assert poly.contains(shapely.Point(x, y))
    # the door: a white gap across the wall, a line on the opening, the leaf (as wide as
    # the opening, at right angles to it from its first end) and its swing
    doors = root.find(".//s:g[@id='doors']", SVG_NS)
    assert doors.get("stroke") not in ("#ffffff", None)
    gap = doors.find("s:line", SVG_NS)
    assert gap.get("stroke") == "#ffffff"
    opening, leaf = doors.findall("s:g/s:line", SVG_NS)
    assert [float(opening.get(a)) for a in ("x1", "y1", "x2", "y2")] == [3.0, 1.9, 3.0, 1.0]
    x1, y1, x2, y2 = (float(leaf.get(a)) for a in ("x1", "y1", "x2", "y2"))
    assert (x1, y1) == (3.0, 1.9) and y2 == pytest.approx(1.9) and abs(x2 - 3.0) == pytest.approx(0.9)
    # it opens into the room, not the corridor
    assert ROOM.contains(shapely.Point((x1 + x2) / 2, y2 - 0.1))
    swing = doors.find("s:g/s:path", SVG_NS).get("d")
    assert swing.startswith(f"M {x2:.4f} 1.9000 A 0.9000 0.9000 0 0 ") and swing.endswith("3.0000 1.0000")
    legend = [t.text for t in root.findall(".//s:g[@id='legend']/s:text", SVG_NS)]
    assert legend[3:] == ["room", "corridor", "door (opening in a wall, its leaf)"]
    assert root.find(".//s:text[@id='rooms-summary']", SVG_NS).text == "2 rooms, 20.7 m\u00b2 \u00b7 1 door"


# ------------------------------------------------------------------------------ DXF


@pytest.mark.parametrize("version", ["R2010", "R12"])
def test_dxf_room_rings_labels_and_door_line_audit_clean(tmp_path, version):
    from ezdxf import recover

    path = write(rooms_plan(), tmp_path, "dxf", FloorplanParams(dxf_version=version))
    doc, auditor = recover.readfile(path)
    assert len(auditor.errors) == 0 and len(doc.audit().errors) == 0
    msp = doc.modelspace()
    outline = "POLYLINE" if version == "R12" else "LWPOLYLINE"
    rings = msp.query(f'{outline}[layer=="ROOM"]')
    assert len(rings) == 3 and all(p.is_closed for p in rings)  # two exteriors, the corridor's hole
    pts = [[(v.x, v.y) for v in p.points_in_wcs()] if version == "R12" else p.get_points("xy") for p in rings]
    areas = sorted(signed_area(list(p) + [p[0]]) for p in pts)
    np.testing.assert_allclose(areas, [-BLOCK.area, ROOM.area, shapely.Polygon(CORRIDOR.exterior).area], atol=1e-9)
    if version == "R12":
        assert not msp.query("MTEXT")
        texts = [t.dxf.text for t in msp.query('TEXT[layer=="ROOM"]')]
        assert texts == ["Room 1", "10.8 m\u00b2", "Corridor 1", "9.8 m\u00b2"]
    else:
        labels = msp.query('MTEXT[layer=="ROOM"]')
        assert [m.plain_text() for m in labels] == ["Room 1\n10.8 m\u00b2", "Corridor 1\n9.8 m\u00b2"]
        assert ROOM.contains(shapely.Point(labels[0].dxf.insert.x, labels[0].dxf.insert.y))
    (door,) = msp.query('LINE[layer=="DOOR"]')
    assert (door.dxf.start.x, door.dxf.start.y, door.dxf.end.x, door.dxf.end.y) == (3.0, 1.9, 3.0, 1.0)
    assert doc.ezdxf_metadata()["floorscan_n_rooms"] == "2"


def test_dxf_of_a_plan_without_rooms_has_the_empty_layers(tmp_path):
    from ezdxf import recover

    doc, auditor = recover.readfile(write(plan_of(WALLS), tmp_path, "dxf"))
    assert len(auditor.errors) == 0 and {"ROOM", "DOOR"} <= {layer.dxf.name for layer in doc.layers}
    assert not doc.modelspace().query('*[layer=="ROOM" | layer=="DOOR"]')
    assert "floorscan_n_rooms" not in doc.ezdxf_metadata()


# ------------------------------------------------------------------------------ IFC


def _validate(path):
    from ifcopenshell import validate

    log = validate.json_logger()
    validate.validate(str(path), log, express_rules=True)
    return log.statements


def _footprint(space) -> shapely.Polygon:
    """An IfcSpace's extruded profile in the storey's frame (metres)."""
    import ifcopenshell.util.placement as up

    m = up.get_local_placement(space.ObjectPlacement)
    solid = space.Representation.Representations[0].Items[0]
    profile = solid.SweptArea

    def ring(curve):
        return np.asarray(curve.Points.CoordList)[:, :2] + m[:2, 3]

    holes = [ring(c) for c in profile.InnerCurves] if profile.is_a("IfcArbitraryProfileDefWithVoids") else []
    return shapely.Polygon(ring(profile.OuterCurve), holes)


@pytest.mark.slow
def test_ifc_spaces_and_a_door_in_an_opening_of_its_wall(tmp_path):
    import ifcopenshell
    import ifcopenshell.util.element as ue
    import ifcopenshell.util.placement as up

    path = write(rooms_plan(), tmp_path, "ifc")
    assert _validate(path) == []
    model = ifcopenshell.open(str(path))
    (storey,) = model.by_type("IfcBuildingStorey")
    spaces = model.by_type("IfcSpace")
    assert [(sp.Name, sp.LongName) for sp in spaces] == [("Room 1", "room"), ("Corridor 1", "corridor")]
    assert [sp.Representation.Representations[0].Items[0].SweptArea.is_a() for sp in spaces] == [
        "IfcArbitraryClosedProfileDef", "IfcArbitraryProfileDefWithVoids"]  # fmt: skip
    for sp, want in zip(spaces, (ROOM, CORRIDOR)):
        assert ue.get_aggregate(sp) == storey
        assert sp.ObjectPlacement.PlacementRelTo == storey.ObjectPlacement
        q = ue.get_psets(sp)["Qto_SpaceBaseQuantities"]
        assert q["NetFloorArea"] == pytest.approx(want.area, abs=1e-12)
        assert q["GrossPerimeter"] == pytest.approx(want.length, abs=1e-12)
        assert sp.Representation.Representations[0].Items[0].Depth == pytest.approx(H)
        got = _footprint(sp)
        assert got.is_valid and got.symmetric_difference(want).area < 1e-9
    (door,) = model.by_type("IfcDoor")
    (opening,) = model.by_type("IfcOpeningElement")
    assert (door.OverallWidth, door.OverallHeight) == (0.9, 2.1)
    assert opening.VoidsElements[0].RelatingBuildingElement.Name == "Wall 4"  # the wall it is in
    assert opening.HasFillings[0].RelatedBuildingElement == door
    assert door in storey.ContainsElements[0].RelatedElements  # the opening only through its wall:
    assert not opening.ContainedInStructure and ue.get_container(opening) == storey
    # at the opening's start on the partition's axis, x along the wall (+y)
    for element in (door, opening):
        m = up.get_local_placement(element.ObjectPlacement)
        np.testing.assert_allclose(m[:3, 3], [3.0, 1.0, 0.0], atol=1e-12)
        np.testing.assert_allclose(m[:3, 0], [0.0, 1.0, 0.0], atol=1e-12)
    box = opening.Representation.Representations[0].Items[0]
    assert box.Depth == pytest.approx(2.1)
    assert box.SweptArea.OuterCurve.Points.CoordList[2] == pytest.approx((0.9, 0.1 + 2 * 0.05))  # through the wall
    # every wall stays contained in the storey beside the doors
    assert {e.is_a() for e in ue.get_decomposition(storey)} >= {"IfcWall", "IfcDoor", "IfcSpace"}
    assert all(ue.get_container(w) == storey for w in model.by_type("IfcWall"))


@pytest.mark.slow
def test_ifc_door_of_no_wall_has_no_opening_and_clutter_keeps_walls_contained(tmp_path):
    import ifcopenshell
    import ifcopenshell.util.element as ue
    import ifcopenshell.util.placement as up

    plan = rooms_plan(door_wall=-1)
    plan.clutter = pd.DataFrame({"clutter_id": [0], "x0": [1.0], "y0": [1.0], "x1": [2.0], "y1": [1.0],
                                 "length_m": [1.0], "reason": ["object"]})  # fmt: skip
    path = write(plan, tmp_path, "ifc")
    assert _validate(path) == []
    model = ifcopenshell.open(str(path))
    (storey,) = model.by_type("IfcBuildingStorey")
    (door,) = model.by_type("IfcDoor")
    assert not model.by_type("IfcOpeningElement") and not door.FillsVoids
    assert ue.get_container(door) == storey
    m = up.get_local_placement(door.ObjectPlacement)
    np.testing.assert_allclose(m[:3, 3], [3.0, 1.9, 0.0], atol=1e-12)  # along its own segment, downwards
    np.testing.assert_allclose(m[:3, 0], [0.0, -1.0, 0.0], atol=1e-12)
    contained = [e.Name for e in storey.ContainsElements[0].RelatedElements]
    assert contained == [f"Wall {i}" for i in range(len(WALLS))] + ["Clutter 0", "Door 0"]


# ------------------------------------------------------------------------------ every format


@pytest.mark.parametrize("params", [FloorplanParams(), FloorplanParams(dxf_version="R12")])
def test_rooms_exports_are_byte_identical_written_twice_and_after_a_renamed_ifc(tmp_path, params):
    for run in ("a", "b"):  # the same name in two folders (the IFC header names its file)
        (tmp_path / run).mkdir()
        exports = PlanExports(rooms_plan())
        for fmt in FLOORPLAN_FORMATS:
            write(None, tmp_path / run, fmt, params, exports=exports)
    for fmt in FLOORPLAN_FORMATS:
        first, again = (tmp_path / run / f"p{EXPORT_FORMATS[fmt].suffix}" for run in ("a", "b"))
        assert first.read_bytes() == again.read_bytes(), fmt
    # the IFC model kept for the plan, renamed for another title, equals a fresh one
    exports = PlanExports(rooms_plan())
    write(None, tmp_path, "ifc", params, exports=exports, name="first")
    other = PlanMetadata(dataset="box", ordering="wall_coverage", k="all")
    write(None, tmp_path, "ifc", params, other, exports=exports, name="again")
    write(rooms_plan(), tmp_path, "ifc", params, other, name="again_fresh")
    again, fresh = ((tmp_path / f"{n}.ifc").read_text() for n in ("again", "again_fresh"))
    assert again.replace("again.ifc", "X") == fresh.replace("again_fresh.ifc", "X")


def test_a_plan_without_rooms_exports_no_room_features_counts_or_legend(tmp_path):
    plan = plan_of(WALLS)
    doc = json.loads(write(plan, tmp_path, "geojson").read_text())
    assert {f["properties"]["kind"] for f in doc["features"]} == {"axis", "footprint"}
    assert not {"n_rooms", "n_doors", "floor_area_m2"} & set(doc["floorscan"])
    svg = write(plan, tmp_path, "svg").read_text()
    assert 'id="rooms"' not in svg and 'id="doors"' not in svg and "rooms-summary" not in svg
    import ifcopenshell

    model = ifcopenshell.open(str(write(plan, tmp_path, "ifc")))
    assert not model.by_type("IfcSpace") and not model.by_type("IfcDoor")


# ------------------------------------------------------------------------------ front page


def test_front_page_lists_the_rooms_and_the_run_counts_them(tmp_path):
    from floorscan.figures.answer import plan_counts
    from floorscan.figures.report import FrontPage, front_page
    from floorscan.figures.room_table import read_plan_rooms
    from floorscan.floorplan.scans import write_plan

    path = write(rooms_plan(), tmp_path, "geojson")
    write_plan(rooms_plan(), tmp_path / "plan")
    write_plan(plan_of(WALLS), tmp_path / "bare")
    rooms = read_plan_rooms(tmp_path / "plan")
    assert [(r["name"], r["kind"]) for r in rooms] == [("Room 1", "room"), ("Corridor 1", "corridor")]
    assert [r["area_m2"] for r in rooms] == pytest.approx([10.83, 9.83])
    svg = write(rooms_plan(), tmp_path, "svg").read_text()
    page = front_page(FrontPage("box", floorplan_svg=svg, rooms=rooms))
    assert "<h3>Rooms (2)</h3>" in page
    assert '<tr><td>Room 1</td><td>room</td><td class="num">10.8</td></tr>' in page
    assert '<th colspan="2">floor area</th><td class="num">20.7</td>' in page
    assert "<h3>Rooms" not in front_page(FrontPage("box", floorplan_svg=svg, rooms=read_plan_rooms(tmp_path / "bare")))
    assert plan_counts(path) == " (6 walls, 2 rooms, 1 door)"


def _text_sizes(el, size=None, scale=1.0, out=None):
    """Each text of an SVG element tree with its size as drawn, px of the viewBox: its
    own or an ancestor's font-size times its ancestors' scale()."""
    import re

    out = [] if out is None else out
    m = re.search(r"scale\(([\d.]+)", el.get("transform", ""))
    scale *= float(m.group(1)) if m else 1.0
    size = float(el.get("font-size", size or 0))
    if el.tag.endswith("}text") or el.tag.endswith("}tspan"):
        own = "".join(t for t in [el.text] if t and t.strip())
        if own:
            out.append((own.strip(), size * scale))
    for child in el:
        _text_sizes(child, size, scale, out)
    return out


def test_the_drawings_text_is_readable_when_the_page_shows_it_900_px_wide(tmp_path):
    """Issue 47: room labels, legend, title and scale bar at least 11 px when the plan is
    shown 900 px wide (its longer side 1000 px of the viewBox); before, 7 to 10 px."""
    root = ET.parse(write(rooms_plan(), tmp_path, "svg")).getroot()
    vb_w = float(root.get("viewBox").split()[2])
    sizes = _text_sizes(root)
    names = {text for text, _ in sizes}
    assert {"Room 1", "Corridor 1", "wall axis", "door (opening in a wall, its leaf)", "map frame (m)"} <= names
    assert any(t.endswith(" m") for t in names) and any(t.endswith("m\u00b2") for t in names)
    small = [(t, round(s * 900 / vb_w, 1)) for t, s in sizes if s * 900 / vb_w < 11]
    assert not small, small

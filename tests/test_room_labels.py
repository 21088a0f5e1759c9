"""Room labels on the drawings (floorscan.floorplan.labels): inside their room, as large as
fits, never over one another; the SVG and the DXF place them so."""

import math
import xml.etree.ElementTree as ET

import numpy as np
import pandas as pd
import pytest
import shapely
import shapely.affinity

from floorscan.floorplan.footprints import PlanExports
from floorscan.floorplan.labels import LABEL_SCALES, place_room_labels, text_box
from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.plan import ROOM_COLUMNS
from floorscan.floorplan.svg import SVG_ROOM_AREA_PX, SVG_ROOM_LABEL_PX
from test_floorplan import SVG_NS, plan_of
from test_rooms_export import write


def boxes_of(xy, scale, with_area, full, alone, angle=None):
    out = []
    angle = np.zeros(len(xy)) if angle is None else angle
    for (x, y), f, both, a, b, turn in zip(xy, scale, with_area, full, alone, angle):
        w, h = (a if both else b) * f
        box = shapely.box(x - w / 2, y - h / 2, x + w / 2, y + h / 2)
        out.append(shapely.affinity.rotate(box, turn, origin=(x, y), use_radians=True))
    return out


def test_a_large_room_has_its_full_label_at_its_pole():
    room = shapely.box(0.0, 0.0, 10.0, 8.0)
    xy, scale, with_area, angle = place_room_labels([room], [[5.0, 4.0]], [[2.0, 0.8]], [[1.5, 0.4]], [0.4])
    np.testing.assert_array_equal(xy, [[5.0, 4.0]])
    assert scale.tolist() == [1.0] and with_area.tolist() == [True]


def test_a_room_too_small_for_its_label_turns_it_along_or_takes_its_name_alone():
    """A label 2 m x 0.8 m at full size: a room 1.5 m x 3 m takes it level at 2/3
    (1.33 m); one 1.0 m x 3 m, too narrow for it level at any size, turned along its
    length at full size; one 1.2 m wide and 0.5 m deep only the name alone, level, at 2/3
    (1.0 m x 0.27 m)."""
    rooms = [shapely.box(0.0, 0.0, 1.5, 3.0), shapely.box(4.0, 0.0, 5.0, 3.0), shapely.box(2.0, 0.0, 3.2, 0.5)]
    poles = [[0.75, 1.5], [4.5, 1.5], [2.6, 0.25]]
    full, alone = np.array([[2.0, 0.8]] * 3), np.array([[1.5, 0.4]] * 3)
    xy, scale, with_area, angle = place_room_labels(rooms, poles, full, alone, [0.4] * 3)
    assert scale.tolist() == pytest.approx([2 / 3, 1.0, 2 / 3]) and with_area.tolist() == [True, True, False]
    assert angle.tolist() == pytest.approx([0.0, np.pi / 2, 0.0])
    for room, box in zip(rooms, boxes_of(xy, scale, with_area, full, alone, angle)):
        assert room.contains(box)


def test_labels_of_neighbouring_rooms_never_overlap():
    """Six rooms 0.9 m x 3 m side by side, each label 5 m long at full size (longer than
    its room at any size, level or turned): the names alone, level, at the least size,
    stand clear of one another, staggered up and down the rooms; the hall beside them
    keeps its full label at its pole."""
    rooms = [shapely.box(1.0 * i, 0.0, 1.0 * i + 0.9, 3.0) for i in range(6)] + [shapely.box(0.0, 3.1, 5.9, 9.0)]
    poles = [[1.0 * i + 0.45, 1.5] for i in range(6)] + [[2.95, 6.05]]
    full, alone = np.array([[5.0, 0.7]] * 7), np.array([[5.0, 0.35]] * 7)
    xy, scale, with_area, angle = place_room_labels(rooms, poles, full, alone, np.full(7, 0.35))
    boxes = boxes_of(xy, scale, with_area, full, alone, angle)
    for i in range(7):
        for j in range(i + 1, 7):
            assert not boxes[i].intersects(boxes[j]), (i, j)
    assert scale[:6].tolist() == [LABEL_SCALES[-1]] * 6 and not with_area[:6].any() and not angle.any()
    assert all(rooms[i].contains(shapely.Point(xy[i])) for i in range(6))
    assert (scale[6], with_area[6]) == (1.0, True) and xy[6].tolist() == [2.95, 6.05]
    assert len({round(y, 3) for y in xy[:6, 1]}) > 1  # staggered


def test_no_polygon_no_label():
    xy, scale, with_area, angle = place_room_labels([None, shapely.Polygon()], np.full((2, 2), np.nan), np.ones((2, 2)),
                                             np.ones((2, 2)), np.ones(2))
    assert np.isnan(xy).all() and np.isnan(scale).all() and not with_area.any()


def row_of_offices_plan():
    """A corridor 30 m long under a row of five offices 1.2 m wide (on a drawing 1000 px
    wide their labels at full size are wider than they are)."""
    plan = plan_of([(0.0, 0.0, 30.0, 0.0, 0.2, 2.7, True)])
    polys = [shapely.box(1.25 * i, 2.0, 1.25 * i + 1.2, 5.0) for i in range(5)] + [shapely.box(0.0, 0.0, 30.0, 1.95)]
    names = [f"Room {i + 1}" for i in range(5)] + ["Corridor 1"]
    plan.rooms = pd.DataFrame({
        "room_id": np.arange(1, 7), "name": names, "kind": ["room"] * 5 + ["corridor"],
        "area_m2": [p.area for p in polys], "perimeter_m": [p.length for p in polys], "polygon": polys,
    })[ROOM_COLUMNS]  # fmt: skip
    return plan


def test_svg_labels_of_a_row_of_small_offices_stand_clear_of_one_another(tmp_path):
    """The offices' labels, wider than the offices, turn along them (a quarter turn to
    the left, read from below) at full size; the corridor's stays level; none overlaps
    another, their boxes read back from the SVG's text, sizes and turns."""
    root = ET.parse(write(row_of_offices_plan(), tmp_path, "svg")).getroot()
    s = float(root.find(".//s:g[@id='plan']", SVG_NS).get("transform")[7:-1].split()[0])
    labels = root.findall(".//s:g[@id='room-labels']/s:text", SVG_NS)
    assert [t.text for t in labels] == [f"Room {i + 1}" for i in range(5)] + ["Corridor 1"]
    assert 1.2 * s < text_box([("Room 1", SVG_ROOM_LABEL_PX)])[0]  # wider than an office, level
    boxes = []
    for t in labels:
        size = float(t.get("font-size", SVG_ROOM_LABEL_PX))
        lines = [(t.text, size)] + [(sp.text, float(sp.get("font-size"))) for sp in t.findall("s:tspan", SVG_NS)]
        w, h = text_box(lines)
        x, y = float(t.get("x")), float(t.get("y")) - 0.73 * size  # the first line's top
        box = shapely.box(x - w / 2, y, x + w / 2, y + h)
        if t.get("transform"):  # rotate(a cx cy), the drawing's y down
            a, cx, cy = (float(v) for v in t.get("transform")[7:-1].split())
            box = shapely.affinity.rotate(box, a, origin=(cx, cy))
        boxes.append(box)
        assert min(abs(f * SVG_ROOM_LABEL_PX - size) for f in LABEL_SCALES) < 1e-3  # one of the sizes
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            assert not boxes[i].intersects(boxes[j]), (labels[i].text, labels[j].text)
    for t in labels[:5]:
        assert t.get("font-size") is None and t.get("transform").startswith("rotate(-90.00 ")
        assert t.find("s:tspan", SVG_NS).get("font-size") == f"{SVG_ROOM_AREA_PX:g}"
    # the corridor keeps its name and area at full size, level
    corridor = labels[5]
    assert corridor.get("font-size") is None and corridor.get("transform") is None
    assert corridor.find("s:tspan", SVG_NS).get("font-size") == f"{SVG_ROOM_AREA_PX:g}"


def test_dxf_labels_take_the_same_places(tmp_path):
    from ezdxf import recover

    plan = row_of_offices_plan()
    doc, _ = recover.readfile(write(plan, tmp_path, "dxf", FloorplanParams(dxf_version="R2010")))
    labels = doc.modelspace().query('MTEXT[layer=="ROOM"]')
    exports = PlanExports(plan)
    from floorscan.floorplan.dxf import DXF_LINE_GAP, DXF_ROOM_TEXT_HEIGHT_M as h

    names = plan.rooms["name"].tolist()
    areas = [f"{a:.1f} m\u00b2" for a in plan.rooms["area_m2"]]
    full = np.array([text_box([(n, h), (a, h)], DXF_LINE_GAP * h) for n, a in zip(names, areas)])
    alone = np.array([text_box([(n, h)]) for n in names])
    xy, scale, with_area, angle = place_room_labels(exports.room_polys, exports.room_labels, full, alone, np.full(6, h))
    got = np.array([[m.dxf.insert.x, m.dxf.insert.y] for m in labels])
    np.testing.assert_allclose(got, xy)
    np.testing.assert_allclose([m.dxf.char_height for m in labels], h * scale)
    np.testing.assert_allclose([m.dxf.rotation for m in labels], np.degrees(angle))
    assert [m.plain_text().count("\n") for m in labels] == with_area.astype(int).tolist()


def test_a_label_that_fits_its_room_moves_off_a_neighbour_label_spilling_into_it():
    """A room 0.3 m wide, larger than its neighbour, is labelled first: its name fits
    neither level nor turned, and spills 0.33 m into the neighbour at the height of the
    neighbour's pole; the neighbour's label, which fits at its pole, moves and shrinks
    to stand clear of it."""
    rooms = [shapely.box(0.0, 0.0, 0.3, 12.0), shapely.box(0.35, 5.5, 2.05, 6.5)]
    poles = [[0.15, 6.0], [1.2, 6.0]]
    full, alone = np.array([[1.6, 0.9]] * 2), np.array([[1.6, 0.5]] * 2)
    xy, scale, with_area, angle = place_room_labels(rooms, poles, full, alone, np.full(2, 0.5))
    a, b = boxes_of(xy, scale, with_area, full, alone, angle)
    assert a.bounds[2] > 0.6 and not a.intersects(b)  # the first spills into the second room
    assert rooms[1].contains(b) and with_area[1] and scale[1] < 1.0


@pytest.mark.parametrize("version", ["R2010", "R12"])
def test_dxf_labels_of_narrow_rooms_run_along_them(tmp_path, version):
    """Offices 0.5 m wide (a closet row) in a DXF, whose labels (0.25 m text) fit them
    only turned a quarter to the left, at 2/3: MTEXT rotated 90 degrees; in R12 two TEXT
    lines, each rotated, the name's line to the left of (above, as read) the area's."""
    from ezdxf import recover

    from floorscan.floorplan.dxf import DXF_LINE_GAP, DXF_ROOM_TEXT_HEIGHT_M as h

    plan = plan_of([(0.0, 0.0, 3.0, 0.0, 0.2, 2.7, True)])
    polys = [shapely.box(0.6 * i, 0.1, 0.6 * i + 0.5, 3.1) for i in range(3)]
    plan.rooms = pd.DataFrame({
        "room_id": np.arange(1, 4), "name": [f"Room {i + 1}" for i in range(3)], "kind": ["room"] * 3,
        "area_m2": [p.area for p in polys], "perimeter_m": [p.length for p in polys], "polygon": polys,
    })[ROOM_COLUMNS]  # fmt: skip
    doc, _ = recover.readfile(write(plan, tmp_path, "dxf", FloorplanParams(dxf_version=version)))
    msp = doc.modelspace()
    if version == "R12":
        texts = msp.query('TEXT[layer=="ROOM"]')
        assert [t.dxf.text for t in texts][:2] == ["Room 1", "1.5 m\u00b2"]
        assert all(t.dxf.rotation == pytest.approx(90.0) and t.dxf.height == pytest.approx(h * 2 / 3) for t in texts)
        name, area = texts[0].dxf.align_point, texts[1].dxf.align_point
        assert area.x - name.x == pytest.approx((1 + DXF_LINE_GAP) * h * 2 / 3) and area.y == pytest.approx(name.y)
        assert polys[0].contains(shapely.Point(name.x, name.y)) and polys[0].contains(shapely.Point(area.x, area.y))
    else:
        labels = msp.query('MTEXT[layer=="ROOM"]')
        assert [m.dxf.rotation for m in labels] == pytest.approx([90.0] * 3)
        assert [m.dxf.char_height for m in labels] == pytest.approx([h * 2 / 3] * 3)
        assert all(p.contains(shapely.Point(m.dxf.insert.x, m.dxf.insert.y)) for p, m in zip(polys, labels))


def test_a_label_moves_off_a_door_swing_but_does_not_shrink_for_it():
    """A room 4 m x 3 m whose pole lies in a door's swing (a quarter disc of 0.9 m): its
    label, 2 m x 0.8 m, moves off the swing at full size; in a room 2.1 m x 1 m, where
    no place clear of the swing holds it, it stays at full size over it."""
    swing = shapely.Polygon([(2.0, 1.5)] + [(2.0 + 0.9 * math.cos(t), 1.5 + 0.9 * math.sin(t))
                                            for t in np.linspace(0, math.pi / 2, 9)])  # fmt: skip
    rooms = [shapely.box(0.0, 0.0, 4.0, 3.0)]
    full, alone = np.array([[2.0, 0.8]]), np.array([[1.5, 0.4]])
    xy, scale, with_area, angle = place_room_labels(rooms, [[2.0, 1.5]], full, alone, [0.4], swing)
    (box,) = boxes_of(xy, scale, with_area, full, alone, angle)
    assert not box.intersects(swing) and scale[0] == 1.0 and with_area[0] and rooms[0].contains(box)
    small = [shapely.box(1.0, 1.0, 3.1, 2.0)]
    xy, scale, with_area, angle = place_room_labels(small, [[2.05, 1.5]], full, alone, [0.4], swing)
    (box,) = boxes_of(xy, scale, with_area, full, alone, angle)
    assert box.intersects(swing) and scale[0] == 1.0 and with_area[0]


def test_the_svg_labels_keep_clear_of_the_quarter_discs_its_doors_swing_through():
    from floorscan.floorplan.svg import door_leaves, door_swings
    from test_rooms_export import ROOM, rooms_plan

    swing = door_swings(door_leaves(rooms_plan()))
    # hinged at the opening's first end (3.0, 1.9), 0.9 m wide, into the room (not the corridor)
    assert swing.area == pytest.approx(math.pi * 0.9**2 / 4, rel=0.02)
    assert ROOM.buffer(0.06).contains(swing) and swing.bounds == pytest.approx((2.1, 1.0, 3.0, 1.9), abs=1e-9)

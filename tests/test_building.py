"""Building descriptions: parsing, validation, mesh and ground truth (thesis 4.1, 5.2)."""

from pathlib import Path

import numpy as np
import pytest
import yaml
from shapely.geometry import LineString
from shapely.ops import unary_union

from floorscan.sim.building_file import load_building, parse_building
from floorscan.sim.footprint import building_outline, wall_footprint, walls_union
from floorscan.sim.ground_truth import ground_truth_walls, observed_faces, wall_faces
from floorscan.sim.mesh import building_mesh, mesh_section, wall_mesh
from floorscan.core.io import InputError

REPO = Path(__file__).resolve().parents[1]
BUILDINGS = REPO / "config" / "buildings"


def room(width=4.0, depth=6.0, t=0.1, openings=(), furniture=(), waypoints=((0, 0), (0, 1))):
    """An empty room whose INNER faces are x = +-width/2, y = +-depth/2."""
    hx, hy = width / 2 + t / 2, depth / 2 + t / 2
    return {
        "name": "room",
        "height_m": 2.5,
        "walls": [
            {
                "id": "room",
                "closed": True,
                "thickness_m": t,
                "points": [[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]],
                "openings": list(openings),
            }
        ],
        "furniture": list(furniture),
        "waypoints": [list(p) for p in waypoints],
    }


def write(tmp_path, data, name="b.yaml"):
    p = tmp_path / name
    p.write_text(yaml.safe_dump(data))
    return p


DOOR = {"id": "door", "kind": "door", "segment": 0, "offset_m": 1.0, "width_m": 0.9}
WINDOW = {"id": "win", "kind": "window", "segment": 1, "offset_m": 1.0, "width_m": 1.2,
          "sill_m": 0.9, "head_m": 2.0}


def test_room_faces_are_the_inner_walls_with_a_door_gap_and_jambs():
    b = parse_building(room(openings=[DOOR, WINDOW]), "room.yaml")
    faces = wall_faces(b, 0.3)
    lengths = sorted(round(float(np.hypot(*(q - p))), 6) for p, q in faces)
    # inner perimeter 20 m; the door removes 0.9 m of the south face and adds two
    # 0.1 m jambs; the window (sill 0.9 m) is a wall at 0.3 m; outside faces excluded.
    assert sum(lengths) == pytest.approx(20 - 0.9 + 0.2)
    assert lengths == sorted([0.1, 0.1, 4.0, 6.0, 6.0, 0.95, 2.15])
    # every face point lies on an inner face x = +-2 or y = +-3 (or a jamb at the door)
    for p, q in faces:
        mid = (p + q) / 2
        on_inner = np.isclose(abs(mid[0]), 2.0) or np.isclose(abs(mid[1]), 3.0)
        in_jamb = np.isclose(mid[1], -3.05) and (np.isclose(mid[0], -1.05) or np.isclose(mid[0], -0.15))
        assert on_inner or in_jamb, (p, q)


def test_window_is_a_gap_only_between_sill_and_head():
    b = parse_building(room(openings=[WINDOW]), "room.yaml")
    full = walls_union(b).area
    cut = 1.2 * 0.1  # the window's width times the wall's thickness
    assert wall_footprint(b, 0.3).area == pytest.approx(full)
    assert wall_footprint(b, 1.5).area == pytest.approx(full - cut)
    assert wall_footprint(b, 2.2).area == pytest.approx(full)


@pytest.mark.parametrize("name", ["demo", "hallways"])
def test_ground_truth_equals_a_slice_of_the_mesh(name):
    b = load_building(BUILDINGS / f"{name}.yaml")
    h = 0.3  # the default sensor height: below every window sill, doors are gaps
    walls = wall_mesh(b)
    assert walls.is_volume
    sec = mesh_section(walls, h)
    fp = wall_footprint(b, h)
    assert sec.area == pytest.approx(fp.area, rel=1e-9)
    assert sec.symmetric_difference(fp).area < 1e-6
    # the full mesh (furniture, floor, ceiling) slices to the walls plus the furniture
    full = building_mesh(b)
    assert full.is_volume
    clutter = unary_union([fp, *[f.section(h) for f in b.furniture]])
    assert mesh_section(full, h).symmetric_difference(clutter).area < 1e-6
    # the GeoJSON footprint is that slice, and every face lies on its boundary
    gt = ground_truth_walls(b, h)
    assert gt["slice_height_m"] == h
    from shapely.geometry import shape

    gt_fp = unary_union([shape(f["geometry"]) for f in gt["features"]
                         if f["properties"]["kind"] == "footprint"])
    assert gt_fp.symmetric_difference(sec).area < 1e-6
    faces = [shape(f["geometry"]) for f in gt["features"] if f["properties"]["kind"] == "face"]
    assert len(faces) > 10
    near_boundary = sec.boundary.buffer(1e-6)
    assert all(f.difference(near_boundary).length < 1e-6 for f in faces)


def test_ground_truth_axes_carry_thickness_and_height():
    b = load_building(BUILDINGS / "demo.yaml")
    gt = ground_truth_walls(b, 0.3)
    axes = [f for f in gt["features"] if f["properties"]["kind"] == "axis"]
    assert len(axes) == sum(len(w.segments()) for w in b.walls)
    outer = [f for f in axes if f["properties"]["wall"] == "outer"]
    assert {f["properties"]["thickness_m"] for f in outer} == {0.25}
    assert {f["properties"]["height_m"] for f in axes} == {2.6}
    assert sum(LineString(f["geometry"]["coordinates"]).length for f in outer) == pytest.approx(27.0)


def test_mesh_volume_is_walls_minus_openings_plus_furniture():
    b = parse_building(room(openings=[DOOR, WINDOW]), "room.yaml")
    walls = wall_mesh(b)
    area = walls_union(b).area  # 4.2 x 6.2 minus 4 x 6
    assert area == pytest.approx(4.2 * 6.2 - 4 * 6)
    expected = area * 2.5 - 0.9 * 0.1 * 2.1 - 1.2 * 0.1 * (2.0 - 0.9)
    assert walls.volume == pytest.approx(expected, rel=1e-9)


def test_demo_and_hallways_sizes():
    hall = load_building(BUILDINGS / "hallways.yaml")
    inside = building_outline(hall).area - wall_footprint(hall, 0.3).area
    assert 330 < inside < 380  # the thesis's ~350 m2 test floor
    assert len(hall.furniture) >= 20
    demo = load_building(BUILDINGS / "demo.yaml")
    assert len(demo.walls) >= 4


# ----------------------------------------------------------------------- bad input


def test_zero_length_wall_names_the_wall_and_file(tmp_path):
    d = room()
    d["walls"].append({"id": "stub", "points": [[0, 0], [0, 0]]})
    with pytest.raises(InputError, match=r"b\.yaml.*'stub'.*zero length"):
        load_building(write(tmp_path, d))


def test_self_intersecting_wall(tmp_path):
    d = room(waypoints=((1.5, 2.5), (1.5, 2.0)))
    d["walls"].append({"id": "bowtie", "points": [[-1, -1], [1, 1], [1, -1], [-1, 1]]})
    with pytest.raises(InputError, match=r"b\.yaml.*'bowtie'.*intersects itself"):
        load_building(write(tmp_path, d))


def test_opening_wider_than_its_wall(tmp_path):
    wide = dict(DOOR, id="garage", offset_m=1.0, width_m=3.5)  # segment 0 is 4.1 m long
    with pytest.raises(InputError, match=r"b\.yaml.*'room'.*'garage'.*wider than its wall"):
        load_building(write(tmp_path, room(openings=[wide])))


def test_window_above_ceiling(tmp_path):
    bad = dict(WINDOW, head_m=3.0)
    with pytest.raises(InputError, match=r"'win'.*head_m"):
        load_building(write(tmp_path, room(openings=[bad])))


def test_waypoint_inside_a_wall(tmp_path):
    d = room(waypoints=((0, 0), (2.03, 0.5)))
    with pytest.raises(InputError, match=r"b\.yaml.*waypoints\[1\].*inside wall 'room'"):
        load_building(write(tmp_path, d))


def test_waypoint_inside_furniture(tmp_path):
    d = room(furniture=[{"id": "desk", "center": [1, 1], "size": [1, 1, 0.75]}],
             waypoints=((0, 0), (1.2, 1.2)))
    with pytest.raises(InputError, match=r"waypoints\[1\].*furniture 'desk'"):
        load_building(write(tmp_path, d))


def test_path_through_a_wall_but_not_through_a_door(tmp_path):
    # from inside the room straight out through the east wall: an error
    d = room(waypoints=((0, 0), (3, 0)))
    with pytest.raises(InputError, match=r"waypoints\[0\] -> waypoints\[1\].*crosses wall 'room'"):
        load_building(write(tmp_path, d))
    # out through the door (x -1.05..-0.15 on the south wall) is fine
    ok = room(openings=[DOOR], waypoints=((-0.6, 0), (-0.6, -4)))
    assert len(load_building(write(tmp_path, ok, "ok.yaml")).waypoints) == 2


def test_unknown_key_and_missing_file(tmp_path):
    d = room()
    d["walls"][0]["thicknes_m"] = 0.2
    with pytest.raises(InputError, match=r"unknown keys \['thicknes_m'\]"):
        load_building(write(tmp_path, d))
    with pytest.raises(InputError, match="not found"):
        load_building(tmp_path / "nope.yaml")


def test_a_table_is_a_top_on_four_legs(tmp_path):
    d = room(furniture=[{"id": "desk", "center": [1, 1], "size": [1.2, 0.6, 0.75], "legs_m": 0.05}])
    b = parse_building(d, "t.yaml")
    desk = b.furniture[0]
    assert desk.section(0.3).area == pytest.approx(4 * 0.05**2)  # four legs at scanner height
    assert desk.section(0.74).area == pytest.approx(1.2 * 0.6)  # the top
    assert desk.section(0.8).is_empty
    legs = desk.section(0.3)
    # legs in the corners: their union's bounds are the top's
    assert legs.bounds == pytest.approx((0.4, 0.7, 1.6, 1.3))
    full = building_mesh(b)
    assert full.is_volume
    assert mesh_section(full, 0.3).area == pytest.approx(wall_footprint(b, 0.3).area + 0.01, rel=1e-6)
    with pytest.raises(InputError, match=r"legs_m"):
        parse_building(room(furniture=[{"id": "t", "center": [1, 1], "size": [0.2, 0.2, 0.7],
                                            "legs_m": 0.15}]), "t.yaml")


def test_observed_faces_keep_the_parts_with_returns():
    faces = [(np.array([0.0, 0.0]), np.array([4.0, 0.0])), (np.array([0.0, 3.0]), np.array([4.0, 3.0]))]
    # returns every 5 cm on x in [0, 1] and [1.1, 2] (a 10 cm gap: bridged), and [3, 3.5]
    xs = np.r_[np.arange(0, 1.001, 0.05), np.arange(1.1, 2.001, 0.05), np.arange(3, 3.501, 0.05)]
    pts = np.c_[xs, np.full(len(xs), 0.02)]
    obs = observed_faces(faces, pts)
    assert len(obs) == 2  # the second face saw nothing
    (a0, b0), (a1, b1) = obs
    # within 5 cm of a return: a run reaches ~4.6 cm past its last return
    assert a0[0] == pytest.approx(0.0) and b0[0] == pytest.approx(2.04, abs=0.011)
    assert a1[0] == pytest.approx(2.96, abs=0.011) and b1[0] == pytest.approx(3.54, abs=0.011)
    assert observed_faces(faces, np.zeros((0, 2))) == []

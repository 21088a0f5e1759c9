"""A floor plan from a map whose rooms and doors are known: the simulator rasterises its
own building (:mod:`floorscan.sim.occupancy_map`), writes it as a map_server map, and
the map input (:func:`floorscan.ingest.occupancy_map.read_occupancy_map`, the map's
walls, :func:`floorscan.walls.map_stage.map_of_grid`, and the plan,
:func:`floorscan.floorplan.scans.plan_of_scans`) must find every room and door exactly.

Exactly means, on the building's own frame (the map's frame):

- as many plan rooms as true rooms (:func:`floorscan.sim.ground_truth.true_rooms`),
  matched one to one (:func:`floorscan.score.rooms.match_rooms`) each at IoU at least
  :data:`EXACT_IOU`. Not 1: at 5 cm cells every wall face is drawn within half a cell of
  where it is, and the plan's wall (one thickness along its length, fitted on the cells;
  an outer wall seen from inside only) moves a room's edge by up to a cell or two on
  each side: a 6.75 m x 1.28 m corridor that gains 0.05 m on each long side is at IoU
  0.93. Measured: hallways' rooms 0.956 to 0.988, demo's 0.905 to 0.977 (its corridor
  the lowest: the room also takes the entrance's opening and a little outside it); a
  room that takes in its neighbour (a missed wall) is at 0.5 or less;
- as many plan doors as true doors between two rooms (the entrance leads outside: a
  plan's doors join two of its rooms, so it has none there; the room scorer leaves it
  out too), each matched one to one (:func:`floorscan.score.rooms.match_doors`) within
  :data:`~floorscan.score.rooms.DOOR_TOLERANCE_M` (0.2 m) of its centre, and joining
  the plan rooms matched to the two true rooms the true door joins.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.scans import plan_of_scans
from floorscan.ingest.occupancy_map import read_occupancy_map
from floorscan.score.rooms import match_doors, match_rooms
from floorscan.sim.building_file import load_building
from floorscan.sim.footprint import building_outline
from floorscan.sim.ground_truth import true_doors, true_rooms
from floorscan.sim.occupancy_map import building_map, building_map_classes, write_building_map
from floorscan.walls.map_stage import map_of_grid

BUILDINGS = Path(__file__).resolve().parents[1] / "config" / "buildings"
#: A plan room is the true room when their IoU is at least this (module docstring).
EXACT_IOU = 0.9
#: An origin that is no whole number of 5 cm cells from the default one: the cells fall
#: elsewhere on the walls, and the map frame is still the building's.
SHIFTED_ORIGIN = (-1.237, -0.713)


def _building(name):
    return load_building(BUILDINGS / f"{name}.yaml")


def plan_of_map(yaml_path):
    """The plan of a map_server map, as the map input makes it."""
    grid, _ = read_occupancy_map(yaml_path)
    return plan_of_scans(map_of_grid(grid, None), None, FloorplanParams(), grid)


def exact_match(plan, building) -> dict:
    """The plan's rooms and doors against the building's: counts, IoUs, door errors."""
    rooms, doors = true_rooms(building), true_doors(building)
    true_polys, plan_polys = list(rooms["polygon"]), list(plan.rooms["polygon"])
    inter = np.array([[t.intersection(p).area for p in plan_polys] for t in true_polys]).reshape(len(true_polys), -1)
    room_scores, room_detail = match_rooms(
        inter, np.array([t.area for t in true_polys]), np.array([p.area for p in plan_polys]),
        np.ones(len(true_polys), dtype=bool), min_iou=EXACT_IOU,
    )  # fmt: skip
    inner = ~doors["exterior"].to_numpy(bool)
    plan_xy = np.column_stack([(plan.doors["x0"] + plan.doors["x1"]) / 2, (plan.doors["y0"] + plan.doors["y1"]) / 2])
    door_scores, door_detail = match_doors(doors[["x", "y"]].to_numpy(np.float64), inner, plan_xy)
    # the true room of each plan room (by the matching), and the rooms each door joins
    true_of_plan = dict(zip(plan.rooms["room_id"].to_numpy()[room_detail["pairs"][:, 1]].tolist(),
                            rooms["room_id"].to_numpy()[room_detail["pairs"][:, 0]].tolist()))  # fmt: skip
    joins_wrong = []
    for t, p in door_detail["pairs"].tolist():
        got = sorted(true_of_plan.get(int(r), -2) for r in plan.doors[["room_a", "room_b"]].to_numpy()[p])
        want = sorted(doors[["room_a", "room_b"]].to_numpy()[t].tolist())
        if got != want:
            joins_wrong.append((doors["door_id"].iloc[t], got, want))
    return {
        "true_rooms": len(true_polys), "plan_rooms": len(plan_polys), "matched_rooms": room_scores["n_matched_rooms"],
        "iou": np.sort(room_detail["pair_iou"]), "true_doors": int(inner.sum()), "plan_doors": len(plan.doors),
        "matched_doors": door_scores["n_matched_doors"], "door_error_m": door_detail["distance_m"],
        "joins_wrong": joins_wrong,
    }  # fmt: skip


def assert_exact(m: dict) -> None:
    assert m["plan_rooms"] == m["true_rooms"], m
    assert m["matched_rooms"] == m["true_rooms"], m
    assert m["iou"].min() >= EXACT_IOU, m
    assert m["plan_doors"] == m["true_doors"], m
    assert m["matched_doors"] == m["true_doors"], m
    assert m["joins_wrong"] == [], m


@pytest.mark.parametrize("name", ["demo", "hallways"])
@pytest.mark.parametrize("origin", [None, SHIFTED_ORIGIN], ids=["origin", "shifted"])
def test_every_room_and_door_of_an_empty_building_exactly(tmp_path, name, origin):
    building = _building(name)
    write_building_map(building, tmp_path / "map.yaml", furniture=False, origin_xy=origin)
    assert_exact(exact_match(plan_of_map(tmp_path / "map.yaml"), building))


#: Furniture in the map that today's plan does not keep out of its walls and rooms.
RACK_IS_A_CLOSET = pytest.mark.xfail(strict=True, reason=(
    "hallways' 3 m rack c2_racks (full height, 0.6 m deep) stands 0.225 m in front of the core's south wall: the map "
    "shows all four of its faces, the front face (2.8 m) is longer than clutter_max_length_m (2.5 m) so it is a wall, "
    "and its end faces snap onto the core wall: a closet of three walls, whose 2.1 m2 the room C2 loses (IoU 0.87-0.88; "
    "13 of 14 rooms at >= 0.95, 13 of 13 doors within 0.03 m). A recording sees the rack's front only, and structure "
    "pass 6 (loose in the free space) makes it clutter there"))  # fmt: skip


@pytest.mark.parametrize(("name", "origin"), [
    ("demo", None),
    ("demo", SHIFTED_ORIGIN),
    pytest.param("hallways", None, marks=RACK_IS_A_CLOSET),
    pytest.param("hallways", SHIFTED_ORIGIN, marks=RACK_IS_A_CLOSET),
], ids=["demo-origin", "demo-shifted", "hallways-origin", "hallways-shifted"])  # fmt: skip
def test_furniture_keeps_every_room_and_door(tmp_path, name, origin):
    """The furniture at the scanner's height (tables' legs, cabinets, shelves, racks,
    boxes) drawn occupied: it is clutter, and the rooms and doors stay exact."""
    building = _building(name)
    assert building.furniture
    write_building_map(building, tmp_path / "map.yaml", furniture=True, origin_xy=origin)
    assert_exact(exact_match(plan_of_map(tmp_path / "map.yaml"), building))


def test_the_map_read_back_is_the_map_written(tmp_path):
    building = _building("demo")
    grid = write_building_map(building, tmp_path / "demo.yaml", origin_xy=SHIFTED_ORIGIN)
    assert (tmp_path / "demo.pgm").is_file()
    back, info = read_occupancy_map(tmp_path / "demo.yaml")
    assert info.image == str(tmp_path / "demo.pgm")
    assert back.resolution_m == grid.resolution_m == 0.05
    np.testing.assert_allclose(back.origin_xy, SHIFTED_ORIGIN)
    assert back.shape == grid.shape
    assert (back.occupied() == grid.occupied()).all() and (back.free() == grid.free()).all()
    assert back.scan_xy is None


def test_classes_of_the_building_frame():
    """Walls, door openings, floor, furniture legs and the outside, cell by cell."""
    building = _building("demo")
    grid = building_map(building)
    bare, free, origin = building_map_classes(building, furniture=False)
    np.testing.assert_allclose(origin, (-0.65, -0.65))  # the outline from -0.125, less 0.5, in whole cells

    def cls(x, y, g_occ, g_free):
        r, c, inside = grid.cells_of(np.array([[x, y]]))
        assert inside[0]
        return "occupied" if g_occ[r[0], c[0]] else "free" if g_free[r[0], c[0]] else "unknown"

    occ, fr = grid.occupied(), grid.free()
    assert cls(3.0, 0.0, occ, fr) == "occupied"  # the outer wall's axis, south
    assert cls(1.6, 2.8, occ, fr) == "free"  # door_a's opening in corridor_south
    assert cls(0.0, 3.65, occ, fr) == "free"  # the entrance
    assert cls(1.6, 1.5, occ, fr) == "free"  # room A's floor
    assert cls(-0.4, 3.0, occ, fr) == "unknown"  # outside, in the margin
    leg = next(f for f in building.furniture if f.id == "desk_a").legs()[0].centroid
    assert cls(leg.x, leg.y, occ, fr) == "occupied"
    assert cls(leg.x, leg.y, bare, free) == "free"  # without furniture, the floor
    assert not fr[occ].any()
    x0, y0, x1, y1 = building_outline(building).bounds
    assert grid.shape == (int(np.ceil((y1 + 0.5 - origin[1]) / 0.05)), int(np.ceil((x1 + 0.5 - origin[0]) / 0.05)))


def test_bad_arguments():
    building = _building("demo")
    with pytest.raises(ValueError, match="resolution_m"):
        building_map(building, resolution_m=0)
    with pytest.raises(ValueError, match="height_m"):
        building_map(building, height_m=building.height_m)
    with pytest.raises(ValueError, match="origin_xy"):
        building_map(building, origin_xy=(0.0, 0.0))  # inside the outline, which starts at -0.125

"""Rooms and doors scored as room segmentation is (floorscan.score.rooms,
floorscan.score.drawn_rooms; Bormann et al., ICRA 2016): the matching by IoU on
handmade polygons, the seen rule, the flood-fill of a drawn segmentation, the door
matching, the true rooms and doors of the synthetic buildings
(floorscan.sim.ground_truth), and the rooms of intel's drawn segmentation."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from shapely.geometry import Polygon, box

from conftest import REPO, SHARED_DATA, needs_shared
from floorscan.core.config import BUILDINGS_DIR
from floorscan.core.occupancy import OccupancyGrid, OccupancyParams
from floorscan.score.drawn import Similarity
from floorscan.score.drawn_rooms import drawn_rooms, read_drawn_rooms, score_drawn_rooms
from floorscan.score.rooms import (
    ROOM_SCORE_COLUMNS,
    match_doors,
    match_rooms,
    read_rooms,
    room_seen_share,
    score_room_plans,
)
from floorscan.sim.building_file import load_building
from floorscan.sim.ground_truth import ground_truth_walls, true_doors, true_rooms

BUILDINGS = REPO / BUILDINGS_DIR


def _inter(true, plan) -> np.ndarray:
    return np.array([[t.intersection(p).area for p in plan] for t in true]).reshape(len(true), len(plan))


def _match(true, plan, counted=None):
    counted = np.ones(len(true), bool) if counted is None else np.asarray(counted)
    return match_rooms(_inter(true, plan), np.array([t.area for t in true]), np.array([p.area for p in plan]), counted)


def _grid(free: np.ndarray, origin=(0.0, 0.0), resolution_m=0.1) -> OccupancyGrid:
    """A reference map whose cells ``free`` were crossed by 5 scans' rays, the rest unknown."""
    free = np.asarray(free, bool)
    return OccupancyGrid(np.asarray(origin, float), resolution_m, np.zeros(free.shape, np.int32),
                         np.where(free, 5, 0).astype(np.int32), OccupancyParams())  # fmt: skip


def _geojson(path, rooms=(), doors=()):
    """A plan GeoJSON in the floorplan stage's format: ``rooms`` polygons, ``doors``
    ((x0, y0), (x1, y1)) segments, and a wall feature the readers must skip."""
    feats = [{"type": "Feature", "properties": {"kind": "axis", "wall_id": 0},
              "geometry": {"type": "LineString", "coordinates": [[0, 0], [1, 0]]}}]  # fmt: skip
    for i, poly in enumerate(rooms):
        rings = [list(poly.exterior.coords), *[list(r.coords) for r in poly.interiors]]
        feats.append({"type": "Feature", "geometry": {"type": "Polygon", "coordinates": rings},
                      "properties": {"kind": "room", "room_id": i, "name": f"Room {i + 1}", "room_kind": "room",
                                     "area_m2": poly.area, "perimeter_m": poly.length}})  # fmt: skip
    for i, (a, b) in enumerate(doors):
        feats.append({"type": "Feature", "geometry": {"type": "LineString", "coordinates": [list(a), list(b)]},
                      "properties": {"kind": "door", "door_id": i, "width_m": math.dist(a, b), "wall_id": -1,
                                     "room_a": 0, "room_b": 1}})  # fmt: skip
    path.write_text(json.dumps({"type": "FeatureCollection", "features": feats}))
    return path


def _plan(folder, rooms=(), doors=()):
    """A plan folder as the floorplan stage passes it (floorscan.core.plan_tables):
    ``rooms`` polygons, ``doors`` ((x0, y0), (x1, y1)) segments, and a wall the
    readers must skip."""
    import pandas as pd

    from floorscan.core.plan_tables import PLAN_SCHEMAS, write_plan_tables

    def table(part, rows):
        return pd.DataFrame(rows, columns=PLAN_SCHEMAS[part].names)

    wall = {"wall_id": 0, "x0": 0.0, "y0": 0.0, "x1": 1.0, "y1": 0.0, "length_m": 1.0, "thickness_m": 0.1,
            "height_m": 2.5, "paired": False, "n_faces": 1, "n_segments": 1, "n_inliers": 10}  # fmt: skip
    write_plan_tables({
        "walls": table("walls", [wall]), "faces": table("faces", []), "clutter": table("clutter", []),
        "junctions": table("junctions", []),
        "rooms": table("rooms", [{"room_id": i, "name": f"Room {i + 1}", "kind": "room", "area_m2": poly.area,
                                  "perimeter_m": poly.length, "polygon": poly} for i, poly in enumerate(rooms)]),
        "doors": table("doors", [{"door_id": i, "x0": a[0], "y0": a[1], "x1": b[0], "y1": b[1],
                                  "width_m": math.dist(a, b), "wall_id": -1, "room_a": 0, "room_b": 1}
                                 for i, (a, b) in enumerate(doors)]),
    }, folder)  # fmt: skip
    return folder


# ------------------------------------------------------------------ matching by IoU


def test_match_rooms_on_handmade_polygons():
    """True rooms A, B, C (16 m2 each); plan rooms: 3/4 of A (IoU 0.75), B and a 2 m2
    strip of C (IoU 16/18), a 3 m2 corner of C (IoU 3/16, too low) and a room outside."""
    true = [box(0, 0, 4, 4), box(4, 0, 8, 4), box(0, 4, 8, 6)]
    plan = [box(0, 0, 4, 3), box(4, 0, 8, 4.5), box(0, 4.5, 2, 6), box(10, 0, 12, 2)]
    scores, detail = _match(true, plan)
    assert detail["iou"][0, 0] == pytest.approx(0.75)
    assert detail["iou"][1, 1] == pytest.approx(16 / 18)
    assert detail["iou"][2, 1] == pytest.approx(2 / 32)
    assert detail["iou"][2, 2] == pytest.approx(3 / 16)
    assert detail["pairs"].tolist() == [[0, 0], [1, 1]]
    assert scores["room_precision"] == pytest.approx(2 / 4)
    assert scores["room_recall"] == pytest.approx(2 / 3)
    assert scores["room_mean_iou"] == pytest.approx((0.75 + 16 / 18) / 2)
    assert (scores["n_true_rooms"], scores["n_plan_rooms_scored"], scores["n_matched_rooms"]) == (3, 4, 2)


def test_unmatched_rooms_are_merged_split_uncovered_pieces_spanning_or_extra():
    """A and B in one plan room a little larger than both (IoU 16/36 each): merged, and
    that plan room spans them; C in three strips of a third (IoU 1/3 each): split, three
    pieces; D with no plan room: uncovered; a plan room where nothing was drawn: extra; E
    matched, in no count. A room left out of precision is in none either."""
    true = [box(0, 0, 4, 4), box(4, 0, 8, 4), box(0, 10, 6, 14), box(20, 0, 24, 4), box(10, 0, 14, 4)]
    plan = [box(0, 0, 8, 4.5), box(0, 10, 2, 14), box(2, 10, 4, 14), box(4, 10, 6, 14), box(30, 0, 32, 2),
            box(10, 0, 14, 4), box(20, 0, 24, 1)]  # fmt: skip
    scores, detail = _match(true, plan)
    assert detail["pairs"].tolist() == [[4, 5]]
    assert detail["true_cause"].tolist() == ["merged", "merged", "split", "uncovered", ""]
    assert detail["plan_cause"].tolist() == ["spanning", "pieces", "pieces", "pieces", "extra", "", "pieces"]
    got = {k: scores[k] for k in ("n_true_merged", "n_true_split", "n_true_uncovered", "n_plan_pieces",
                                  "n_plan_spanning", "n_plan_extra")}  # fmt: skip
    # D's quarter strip is a piece of D, and D, a quarter of it covered, is uncovered
    assert got == {"n_true_merged": 2, "n_true_split": 1, "n_true_uncovered": 1, "n_plan_pieces": 4,
                   "n_plan_spanning": 1, "n_plan_extra": 1}  # fmt: skip
    # the strip in D left out of precision (D not counted): neither piece nor uncovered
    scores, _ = _match(true, plan, counted=[True, True, True, False, True])
    assert (scores["n_true_uncovered"], scores["n_plan_pieces"], scores["n_plan_extra"]) == (0, 3, 1)


def test_match_rooms_is_one_to_one():
    """Two plan rooms on one true room: one matches, the other is a false room."""
    scores, detail = _match([box(0, 0, 4, 4)], [box(0, 0, 4, 4), box(0, 0, 4, 3.9)])
    assert detail["pairs"].tolist() == [[0, 0]] and detail["pair_iou"].tolist() == [1.0]
    assert (scores["room_precision"], scores["room_recall"], scores["room_mean_iou"]) == (0.5, 1.0, 1.0)


def test_match_rooms_iou_threshold_is_inclusive():
    """IoU exactly 0.5 matches (Bormann et al.: IoU >= 0.5)."""
    scores, detail = _match([box(0, 0, 4, 4)], [box(0, 0, 4, 2)])
    assert detail["pair_iou"].tolist() == [0.5] and scores["room_recall"] == 1.0


def test_plan_rooms_mostly_in_unscored_rooms_are_left_out_of_precision():
    """True room U is not scored: plan room Q with 60 % of its area in U is left out;
    Q' with 40 % in U counts (and matches nothing: precision 1/2)."""
    true = [box(0, 0, 4, 4), box(4, 0, 8, 4)]  # A scored, U not
    plan = [box(0, 0, 4, 4), box(1.6, 0, 5.6, 1), box(2.4, 0, 6.4, 1)]  # A, Q', Q
    assert plan[1].intersection(true[1]).area / plan[1].area == pytest.approx(0.4)
    assert plan[2].intersection(true[1]).area / plan[2].area == pytest.approx(0.6)
    scores, detail = _match(true, plan, counted=[True, False])
    assert detail["left_out"].tolist() == [False, False, True]
    assert (scores["n_plan_rooms"], scores["n_plan_rooms_scored"]) == (3, 2)
    assert (scores["room_precision"], scores["room_recall"]) == (0.5, 1.0)


def test_no_plan_room_gives_zero_recall_and_undefined_precision():
    scores, _ = _match([box(0, 0, 4, 4)], [])
    assert scores["room_recall"] == 0.0
    assert math.isnan(scores["room_precision"]) and math.isnan(scores["room_mean_iou"])


# ------------------------------------------------------------------ the seen rule


def test_a_room_half_seen_counts_a_room_a_third_seen_does_not(tmp_path):
    """Free space over x < 2 (room H, 4 m wide: half) and x in [5, 6) (room T, 3 m
    wide: a third); the rule admits one cell beyond the free space (0.1 m here)."""
    free = np.zeros((40, 100), bool)  # 4 m x 10 m at 0.1 m
    free[:, :20] = True
    free[:, 50:60] = True
    grid = _grid(free)
    rooms = [box(0, 0, 4, 2), box(5, 0, 8, 3)]
    share = room_seen_share(rooms, grid)
    assert share == pytest.approx([21 / 40, 11 / 30])
    truth = _geojson(tmp_path / "truth.geojson", rooms, doors=[((4.0, 0.5), (4.0, 1.4))])
    plan = _plan(tmp_path / "plan", [box(0, 0, 4, 2), box(5, 0, 8, 3)], doors=[((4.0, 0.6), (4.0, 1.5))])
    table, overlay = score_room_plans({"recommended": plan}, grid, truth)
    assert overlay["counted"].tolist() == [True, False]
    row = table.iloc[0]
    assert list(table.columns) == ROOM_SCORE_COLUMNS and row["truth"] == "ground_truth"
    # the plan room on T lies wholly in an unscored room: left out of precision
    assert (row["n_true_rooms"], row["n_true_rooms_all"], row["n_plan_rooms"], row["n_plan_rooms_scored"]) == (1, 2, 2, 1)
    assert (row["room_precision"], row["room_recall"], row["room_mean_iou"]) == (1.0, 1.0, 1.0)
    # the true door joins a scored and an unscored room: not scored; the plan door
    # 0.1 m from it is left out of precision
    assert (row["n_true_doors"], row["n_plan_doors"], row["n_plan_doors_scored"]) == (0, 1, 0)
    assert math.isnan(row["door_recall"]) and math.isnan(row["door_precision"])


# ------------------------------------------------------------------ doors


def test_a_door_015_m_off_matches_025_m_off_does_not():
    true = np.array([[0.0, 0.0], [5.0, 0.0]])
    plan = np.array([[0.15, 0.0], [5.0, 0.25]])
    scores, detail = match_doors(true, [True, True], plan)
    assert detail["pairs"].tolist() == [[0, 0]]
    assert scores["door_centre_error_m"] == pytest.approx(0.15)
    assert (scores["door_recall"], scores["door_precision"]) == (0.5, 0.5)


def test_door_matching_is_one_to_one_and_skips_doors_that_do_not_count():
    """Two plan doors near one true door: the nearer matches; a plan door at an exterior
    (not scored) true door is left out of precision."""
    true = np.array([[0.0, 0.0], [3.0, 0.0]])
    plan = np.array([[0.1, 0.0], [0.0, 0.05], [3.0, 0.1]])
    scores, detail = match_doors(true, [True, False], plan)
    assert detail["pairs"].tolist() == [[0, 1]] and detail["left_out"].tolist() == [False, False, True]
    assert (scores["n_true_doors"], scores["n_plan_doors_scored"], scores["n_matched_doors"]) == (1, 2, 1)
    assert (scores["door_recall"], scores["door_precision"]) == (1.0, 0.5)
    assert scores["door_centre_error_m"] == pytest.approx(0.05)


# ------------------------------------------------------------------ drawn segmentation


def _segmentation() -> np.ndarray:
    """A 60 x 80 RGB drawing: grey outside, two rooms parted by a black line, a sliver
    3 px high, a 4 x 4 px speck and a white strip on the image border."""
    img = np.full((60, 80, 3), 0.8)
    img[5:30, 5:70] = 1.0
    img[5:30, 35] = 0.0  # the drawn line between room 1 (30 cols) and room 2 (34 cols)
    img[35:38, 5:70] = 1.0  # sliver: no disc 10 px wide fits
    img[45:49, 40:44] = 1.0  # speck: 16 px
    img[55:60, 0:20] = 1.0  # touches the border: the outside
    return img


def test_drawn_rooms_floods_each_white_region_between_lines():
    labels = drawn_rooms(_segmentation(), min_width_px=10, min_area_px=20)
    assert labels.max() == 2
    assert np.bincount(labels.ravel())[1:].tolist() == [25 * 30, 25 * 34]
    assert labels[10, 10] == 1 and labels[10, 60] == 2 and labels[10, 35] == 0
    # without the width limit the sliver is a room, without the area limit the speck too
    assert drawn_rooms(_segmentation(), min_width_px=0, min_area_px=20).max() == 3
    assert drawn_rooms(_segmentation(), min_width_px=0, min_area_px=0).max() == 4


def test_drawn_rooms_scored_on_pixels(tmp_path):
    """Pixel (col, row) -> (0.1 col, -0.1 row) m. Plan room 1 covers the top 4 of room
    1's 8 rows (IoU 40/80); plan room 2 covers room 2 (8 x 14 px) and 8 x 4 px beyond
    the image, outside the drawn building, which is not scored (IoU 1); a third plan
    room lies wholly outside the drawing (scored as a room of no pixels: unmatched,
    and left out of precision); all seen."""
    labels = np.zeros((20, 30), np.int32)
    labels[2:10, 2:12] = 1
    labels[2:10, 14:28] = 2
    t = Similarity(scale=0.1, angle=0.0, tx=0.0, ty=0.0)
    px = lambda c0, c1, r0, r1: box(0.1 * c0, -0.1 * r1, 0.1 * c1, -0.1 * r0)  # noqa: E731
    plan = _plan(tmp_path / "plan", [px(1.5, 11.5, 1.5, 5.5), px(13.5, 31.5, 1.5, 9.5), px(40.5, 45.5, 1.5, 9.5)])
    grid = _grid(np.ones((80, 120), bool), origin=(-1.0, -3.0), resolution_m=0.05)
    table, overlay = score_drawn_rooms({"recommended": plan}, labels, t, grid)
    row = table.iloc[0]
    assert overlay["counted"].tolist() == [True, True]
    assert overlay["plans"]["recommended"]["rooms_detail"]["iou"][[0, 1], [0, 1]] == pytest.approx([0.5, 1.0])
    assert overlay["plans"]["recommended"]["rooms_detail"]["left_out"].tolist() == [False, False, True]
    assert (row["room_precision"], row["room_recall"]) == (1.0, 1.0)
    assert (row["n_plan_rooms"], row["n_plan_rooms_scored"]) == (3, 2)
    assert row["room_mean_iou"] == pytest.approx(0.75)
    assert row["truth"] == "drawn" and math.isnan(row["door_recall"])


def test_drawn_rooms_scored_on_the_drawn_floor_not_its_walls(tmp_path):
    """Pixel (col, row) -> (0.1 col, -0.1 row) m; walls drawn 4 px thick at most. Room 1
    (rows 5-54, cols 5-27, 1150 px) and room 2 (cols 30-54, round a hole of rows 15-44,
    cols 33-51 that the drawing gives no room) with a 2 px drawn wall between them. A
    plan room over room 1 and the wall is room 1 (IoU 1, not 1150 / 1250); a plan room
    in the hole is scored on its 242 px farther than a wall from every room, a room where
    none is drawn: unmatched, counted in precision."""
    labels = np.zeros((60, 60), np.int32)
    labels[5:55, 5:28] = 1
    labels[5:55, 30:55] = 2
    labels[15:45, 33:52] = 0
    t = Similarity(scale=0.1, angle=0.0, tx=0.0, ty=0.0)
    px = lambda c0, c1, r0, r1: box(0.1 * c0, -0.1 * r1, 0.1 * c1, -0.1 * r0)  # noqa: E731
    plan = _plan(tmp_path / "plan", [px(4.5, 29.5, 4.5, 54.5), px(33.5, 50.5, 15.5, 43.5)])
    grid = _grid(np.ones((140, 140), bool), origin=(-1.0, -7.0), resolution_m=0.05)
    table, overlay = score_drawn_rooms({"recommended": plan}, labels, t, grid)
    row = table.iloc[0]
    detail = overlay["plans"]["recommended"]["rooms_detail"]
    assert detail["iou"][0, 0] == pytest.approx(1.0)
    assert detail["left_out"].tolist() == [False, False]
    assert (row["n_plan_rooms_scored"], row["n_matched_rooms"]) == (2, 1)
    assert (row["room_precision"], row["room_recall"]) == (0.5, 0.5)


@needs_shared
def test_intel_drawn_segmentation_has_26_rooms():
    """ipa_room_segmentation's lab_intel_gt_segmentation.png: 7 rooms along the top, 5 on
    the right, 3 at the bottom, 3 on the left (with the bottom-left corner room), the
    corridor ring, and 7 in the middle (the 3 compartments of the curved strip, the
    rectangle and the square, the two rooms at the lower left and the narrow one)."""
    labels = read_drawn_rooms(SHARED_DATA / "ipa-maps" / "lab_intel_gt_segmentation.png", 0.05)
    assert labels.max() == 26
    assert int(np.bincount(labels.ravel())[1:].max()) == 101532  # the corridor ring, px
    freiburg = read_drawn_rooms(SHARED_DATA / "ipa-maps" / "Freiburg101_scan_gt_segmentation.png", 0.05)
    assert freiburg.max() == 10  # corridor, 4 rooms north of it, 5 south (a 3 x 5 px-high sliver dropped)


# ------------------------------------------------------------------ true rooms and doors


def test_demo_true_rooms_and_doors():
    """demo: outer wall 0.25 m thick (faces 0.125 in from its axis at 0, 7 / 0, 6.5),
    inner walls 0.12 m (0.06 each side): corridor y 2.8..4.2, rooms A, B south of it
    (parted at x 3.5), C, D north (parted at x 4)."""
    b = load_building(BUILDINGS / "demo.yaml")
    rooms = true_rooms(b)
    lo, hi_x, hi_y, h = 0.125, 7 - 0.125, 6.5 - 0.125, 0.06
    expected = {  # by room_id: (y, then x) of the room's representative point
        0: (3.5 - h - lo) * (2.8 - h - lo),  # A: 3.315 x 2.615
        1: (hi_x - 3.5 - h) * (2.8 - h - lo),  # B
        2: (hi_x - lo) * (4.2 - h - 2.8 - h),  # corridor: 6.75 x 1.28
        3: (4 - h - lo) * (hi_y - 4.2 - h),  # C: 3.815 x 2.115
        4: (hi_x - 4 - h) * (hi_y - 4.2 - h),  # D: 2.815 x 2.115
    }
    assert len(rooms) == 5
    assert rooms["area_m2"].tolist() == pytest.approx([expected[i] for i in range(5)])
    assert rooms["area_m2"].tolist() == pytest.approx([8.668725, 8.668725, 8.64, 8.068725, 5.953725])
    doors = true_doors(b, rooms)
    assert len(doors) == 6 and int(doors["exterior"].sum()) == 1
    joins = {d: (a, c) for d, a, c in zip(doors["door_id"], doors["room_a"], doors["room_b"])}
    assert joins == {"entrance": (-1, 2), "door_a": (0, 2), "door_b": (1, 2), "door_c": (2, 3),
                     "door_d": (2, 4), "door_ab": (0, 1)}  # fmt: skip
    ab = doors.set_index("door_id").loc["door_ab"]
    assert (ab["x"], ab["y"], ab["width_m"]) == pytest.approx((3.5, 1.45, 0.9))
    assert (ab["x0"], ab["y0"], ab["x1"], ab["y1"]) == pytest.approx((3.5, 1.0, 3.5, 1.9))


def test_hallways_true_rooms_and_doors():
    """hallways: 14 rooms = 4 south and 4 north of the ring (parted at x 7, 14, 21), the
    west and east rooms, the hallway ring (one room: no wall parts it, the core its
    hole) and the core's 3 rooms; 14 doors = the entrance (outside -> south-west room),
    10 in the ring's wall, 3 in the core's; every room has a door."""
    b = load_building(BUILDINGS / "hallways.yaml")
    rooms = true_rooms(b)
    doors = true_doors(b, rooms)
    assert len(rooms) == 14
    assert len(doors) == 14 and doors["exterior"].tolist().count(True) == 1
    ring = rooms[rooms["area_m2"] == rooms["area_m2"].max()].iloc[0]
    # inside faces of the ring wall (0.15 thick) less the core's outside faces
    assert ring["area_m2"] == pytest.approx((24.425 - 3.575) * (10.425 - 3.575) - (22.975 - 5.025) * (8.975 - 5.025))
    assert len(ring["polygon"].interiors) == 1
    assert sorted(doors["room_b"][doors["room_a"] == ring["room_id"]].tolist()
                  + doors["room_a"][doors["room_b"] == ring["room_id"]].tolist()) == sorted(
        set(range(14)) - {ring["room_id"]})  # 13 doors from the ring, one to every other room
    entrance = doors.set_index("door_id").loc["entrance"]
    assert entrance["room_a"] == -1 and rooms.loc[entrance["room_b"], "polygon"].contains(
        box(0.2, 1.3, 1.0, 2.5))  # the south-west room


def test_ground_truth_geojson_holds_rooms_and_doors_and_readers_skip_them(tmp_path):
    from floorscan.score.answer import read_truth
    from floorscan.score.geojson import read_wall_faces
    from floorscan.sim.ground_truth import wall_faces

    b = load_building(BUILDINGS / "demo.yaml")
    path = tmp_path / "walls.geojson"
    path.write_text(json.dumps(ground_truth_walls(b, 0.3)))
    rooms, doors = read_rooms(path)
    assert len(rooms) == 5 and len(doors) == 6 and int(doors["exterior"].sum()) == 1
    assert rooms["polygon"].apply(lambda p: p.exterior.is_ccw).all()
    assert sum(p.area for p in rooms["polygon"]) == pytest.approx(8.668725 * 2 + 8.64 + 8.068725 + 5.953725)
    assert len(read_wall_faces(path, "face")) == len(wall_faces(b, 0.3))
    truth = read_truth(path)
    assert len(truth["axis"]) == sum(len(w.segments()) for w in b.walls) and len(truth["observed_face"]) == 0


def test_plan_equal_to_the_truth_scores_one(tmp_path):
    """demo's true rooms as the plan, its doors shifted 0.15 m along their wall: all
    rooms and the 5 inner doors match; the exterior door's plan door is left out."""
    b = load_building(BUILDINGS / "demo.yaml")
    truth = tmp_path / "walls.geojson"
    truth.write_text(json.dumps(ground_truth_walls(b, 0.3)))
    rooms, doors = read_rooms(truth)
    shift = lambda d: np.array([d.x1 - d.x0, d.y1 - d.y0]) / d.width_m * 0.15  # noqa: E731
    plan_doors = [((d.x0 + shift(d)[0], d.y0 + shift(d)[1]), (d.x1 + shift(d)[0], d.y1 + shift(d)[1]))
                  for d in doors.itertuples()]  # fmt: skip
    plan = _plan(tmp_path / "plan", list(rooms["polygon"]), plan_doors)
    grid = _grid(np.ones((70, 75), bool), origin=(0.0, 0.0))
    table, _ = score_room_plans({"recommended": plan, "all_scans_map": plan}, grid, truth)
    assert table["plan"].tolist() == ["recommended", "all_scans_map"]
    row = table.iloc[0]
    assert (row["room_precision"], row["room_recall"], row["room_mean_iou"]) == (1.0, 1.0, 1.0)
    assert (row["n_true_rooms"], row["n_plan_rooms"], row["n_true_doors"], row["n_plan_doors"]) == (5, 5, 5, 6)
    assert (row["door_recall"], row["door_precision"], row["n_plan_doors_scored"]) == (1.0, 1.0, 5)
    assert row["door_centre_error_m"] == pytest.approx(0.15)


def test_truth_without_rooms_is_refused(tmp_path):
    from floorscan.core.io import InputError

    old = _geojson(tmp_path / "old.geojson")  # walls only: written before rooms existed
    with pytest.raises(InputError, match="rerun the simulate stage"):
        score_room_plans({"recommended": _plan(tmp_path / "plan")}, _grid(np.ones((5, 5), bool)), old)


def test_rooms_overlay_figure_is_written(tmp_path):
    import matplotlib.image as mpimg

    from floorscan.figures.rooms import rooms_overlay_figure

    free = np.zeros((40, 100), bool)
    free[:, :20] = True
    grid = _grid(free)
    truth = _geojson(tmp_path / "truth.geojson", [box(0, 0, 4, 2), box(5, 0, 8, 3)], [((4.0, 0.5), (4.0, 1.4))])
    plan = _plan(tmp_path / "plan", [box(0, 0, 3.5, 2), Polygon([(9, 0), (10, 0), (10, 1)])])
    table, overlay = score_room_plans({"recommended": plan}, grid, truth)
    rooms_overlay_figure(overlay, "tiny", tmp_path / "rooms.png")
    # 10 inches wide at 110 dpi; the rooms span 10 x 3 m, so the axes take the shortest
    # aspect (0.3 of 8.5 inches) and the title and legend 2.6 inches: 5.15 inches tall
    assert mpimg.imread(tmp_path / "rooms.png").shape[:2] == (566, 1100)
    assert table.iloc[0]["room_precision"] == 0.5  # the triangle outside is a false room
    assert table.iloc[0][["n_true_merged", "n_true_split", "n_true_uncovered", "n_plan_pieces", "n_plan_spanning",
                          "n_plan_extra"]].tolist() == [0, 0, 0, 0, 0, 1]  # fmt: skip


def test_a_plan_room_over_two_true_rooms_is_said_to_merge_them(tmp_path):
    """Two true rooms of 8 m2 under one plan room of 16 m2 (IoU 0.5 each): one matches
    it, the other is merged into it; under one of 18 m2 (IoU 4/9) both are merged and
    the plan room spans them, as the overlay's title says."""
    from floorscan.figures.rooms import _title

    free = np.ones((40, 100), bool)
    truth = _geojson(tmp_path / "truth.geojson", [box(0, 0, 4, 2), box(4, 0, 8, 2)])
    for name, top, want in (("flush", 2.0, [1, 1, 0, 0, 0, 0, 0]), ("over", 2.25, [0, 2, 0, 0, 0, 1, 0])):
        plan = _plan(tmp_path / name, [box(0, 0, 8, top)])
        table, overlay = score_room_plans({"recommended": plan}, _grid(free), truth)
        row = table.iloc[0]
        assert row[["n_matched_rooms", "n_true_merged", "n_true_split", "n_true_uncovered", "n_plan_pieces",
                    "n_plan_spanning", "n_plan_extra"]].tolist() == want  # fmt: skip
    assert "unmatched true rooms: 2 merged, 0 split, 0 uncovered\nunmatched plan rooms: 0 a piece of one, 1 across" in \
        _title(overlay, "tiny", "recommended")


def test_a_plans_tables_give_the_rooms_and_doors_of_its_geojson_export(tmp_path):
    """What the score stage reads (the plan folder) equals what it read before (the
    plan's GeoJSON): a clockwise room with a hole at coordinates off the 10 um grid, a
    room without a polygon (skipped by both) and a door, the same rows and doubles."""
    import pandas as pd

    from floorscan.floorplan.geojson import write_geojson
    from floorscan.floorplan.plan import FloorPlan
    from floorscan.floorplan.scans import write_plan
    from floorscan.score.rooms import read_plan_folder_rooms

    cw = Polygon([(0.1234567, 0.0), (0.0, 3.3333333), (4.0000049, 3.1), (4.2, 0.1)],
                 [[(1.0, 1.0), (2.0000051, 1.0), (2.0, 2.0), (1.0, 2.0)]])  # fmt: skip
    assert not cw.exterior.is_ccw
    plan = FloorPlan(walls=pd.DataFrame(columns=["wall_id", "x0", "y0", "x1", "y1", "length_m", "thickness_m",
                                                 "height_m", "paired", "n_faces", "n_segments", "n_inliers"]),
                     faces=pd.DataFrame(columns=["face_id", "wall_id", "x0", "y0", "x1", "y1", "length_m",
                                                 "n_segments", "n_inliers"]))  # fmt: skip
    plan.rooms = pd.DataFrame({"room_id": [0, 1, 2], "name": ["A", "B", "C"], "kind": ["room", "corridor", "room"],
                               "area_m2": [cw.area, 0.0, 1.0], "perimeter_m": [cw.length, 0.0, 4.0],
                               "polygon": [cw, None, box(5.0000001, 0, 6, 1)]})  # fmt: skip
    plan.doors = pd.DataFrame({"door_id": [0], "x0": [4.1000004], "y0": [1.0], "x1": [4.1], "y1": [1.9000006],
                               "width_m": [0.90000061], "wall_id": [-1], "room_a": [0], "room_b": [2]})  # fmt: skip
    write_geojson(plan, tmp_path / "plan.geojson")
    write_plan(plan, tmp_path / "plan")
    gj_rooms, gj_doors = read_rooms(tmp_path / "plan.geojson")
    rooms, doors = read_plan_folder_rooms(tmp_path / "plan")
    assert rooms["room_id"].tolist() == gj_rooms["room_id"].tolist() == [0, 2]
    assert all(a.equals_exact(b, 0.0) for a, b in zip(rooms["polygon"], gj_rooms["polygon"]))
    pd.testing.assert_frame_equal(rooms.drop(columns="polygon"), gj_rooms.drop(columns="polygon"))
    pd.testing.assert_frame_equal(doors, gj_doors)

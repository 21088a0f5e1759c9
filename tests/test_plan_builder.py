"""The one plan builder (floorscan.floorplan.scans) and the plan as Parquet tables
(floorscan.core.plan_tables): the evaluation grid, the curves and the answer build the
plan of a set of scans the same way, and the score stage reads the tables."""

import numpy as np
import pandas as pd
import pytest
import shapely

from floorscan.core.plan_tables import PLAN_SCHEMAS, plan_faces_and_walls, read_plan_tables, write_plan_tables
from floorscan.floorplan.footprints import PlanExports
from floorscan.floorplan.grid import write_plan_grid
from floorscan.floorplan.metadata import PlanMetadata
from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.plan import FloorPlan, build_floorplan
from floorscan.floorplan.scans import ScanPlans, plan_of_scans, read_plan, write_plan
from floorscan.floorplan.writer import FloorplanWriter
from floorscan.score.geojson import read_floorplan
from floorscan.select.deliverables import SCAN_TABLE, write_scan_table
from floorscan.core.selection import selected_scan_ids
from floorscan.walls.first_k import first_k_walls
from test_floorplan import BOX, THICK, scans_segments

ORIGINS = [(2, 1.2), (2, -1.0), (1, 1.5), (3, -1.5), (0, 0.8), (4, 1.0)]


@pytest.fixture(scope="module")
def per_scan():
    """The box room (6 x 4.2 m) with a 4 m x 20 cm wall inside, seen by six scans
    (ransac): the walls stage's per-scan table."""
    return scans_segments(BOX + THICK, ORIGINS, "ransac")


@pytest.fixture(scope="module")
def orderings():
    return {
        "forward": pd.DataFrame({"rank": range(6), "scan_id": range(6)}),
        "backward": pd.DataFrame({"rank": range(6), "scan_id": range(5, -1, -1)}),
    }


def test_the_plan_of_a_set_of_scans_is_the_plan_of_their_first_k_table(per_scan, orderings):
    """The builder's plan of the first k scans equals build_floorplan of the walls
    stage's k table (what the grid built before), prepared or not, exactly; the curves'
    faces are its faces. Measured: the 4 scans' plan has 5 walls, the inner one
    paired at 0.2 m."""
    params = FloorplanParams()
    plain, prepared = ScanPlans(per_scan, params), ScanPlans(per_scan, params, prepared=True)
    for name, ordering in orderings.items():
        for k in (1, 2, 4, "all"):
            segments, ids = first_k_walls(per_scan, ordering, k)
            want = build_floorplan(segments, params)
            for builder in (plain, prepared):
                got = builder.plan(ids)
                pd.testing.assert_frame_equal(got.walls, want.walls, check_exact=True)
                pd.testing.assert_frame_equal(got.faces, want.faces, check_exact=True)
            np.testing.assert_array_equal(prepared.faces(ids), want.faces[["x0", "y0", "x1", "y1"]].to_numpy())
    plan = plan_of_scans(per_scan, [3, 0, 2, 1], params)  # any order: the same scans, the same plan
    pd.testing.assert_frame_equal(plan.walls, plain.plan(range(4)).walls, check_exact=True)
    assert len(plan.walls) == 5 and int(plan.walls["paired"].sum()) == 1
    inner = plan.walls[plan.walls["paired"]].iloc[0]
    assert inner["thickness_m"] == pytest.approx(0.2, abs=0.02) and inner["length_m"] == pytest.approx(4.0, abs=0.1)
    assert plain.rows(None).all() and plain.rows([99]).sum() == 0


def test_a_table_without_scan_ids_has_a_plan_of_all_its_rows_only(per_scan):
    walls = per_scan.drop(columns="scan_id")
    plans = ScanPlans(walls)
    assert len(plans.plan().walls) == len(build_floorplan(walls).walls)
    with pytest.raises(ValueError, match="scan_id"):
        plans.plan([0])


def test_plan_tables_give_the_faces_and_walls_the_geojson_gives(per_scan, tmp_path):
    """The score stage read the GeoJSON's faces and wall count; the Parquet tables of
    the same plan give the same numbers bit for bit (coordinates rounded to 10 um
    as the export rounds them), so the scores stay."""
    plan = plan_of_scans(per_scan, None)
    write_plan(plan, tmp_path / "plan", {"dataset": "box", "k": "all"})
    FloorplanWriter({}).export(PlanExports(plan), {"geojson": tmp_path / "plan.geojson"},
                               PlanMetadata("box", "forward", "ransac", "all", 0))
    faces, n_walls = plan_faces_and_walls(tmp_path / "plan")
    gj_faces, gj_walls = read_floorplan(tmp_path / "plan.geojson")
    np.testing.assert_array_equal(faces, gj_faces)
    assert n_walls == gj_walls == len(plan.walls) and len(faces) == len(plan.faces)
    assert np.abs(faces - plan.faces[["x0", "y0", "x1", "y1"]].to_numpy()).max() <= 5e-6
    # the files: the four parts (no rooms without a grid), schema and metadata
    assert sorted(p.name for p in (tmp_path / "plan").iterdir()) == [
        "clutter.parquet", "faces.parquet", "junctions.parquet", "walls.parquet"]
    import pyarrow.parquet as pq

    schema = pq.read_schema(tmp_path / "plan" / "walls.parquet")
    assert schema.remove_metadata() == PLAN_SCHEMAS["walls"] and schema.metadata[b"dataset"] == b"box"
    back = read_plan(tmp_path / "plan")
    assert back.walls["wall_id"].tolist() == plan.walls["wall_id"].tolist() and back.rooms.empty
    np.testing.assert_allclose(back.walls["thickness_m"], plan.walls["thickness_m"], atol=5e-5)


def test_rooms_pass_as_wkb_and_come_back_as_polygons(tmp_path):
    empty = FloorPlan(walls=pd.DataFrame(columns=list(PLAN_SCHEMAS["walls"].names)),
                      faces=pd.DataFrame(columns=list(PLAN_SCHEMAS["faces"].names)))
    room = shapely.Polygon([(0, 0), (4, 0), (4, 3), (0, 3)], [[(1, 1), (2, 1), (2, 2), (1, 2)]])
    empty.rooms = pd.DataFrame({"room_id": [0], "name": ["Room 1"], "kind": ["room"], "area_m2": [room.area],
                                "perimeter_m": [room.length], "polygon": [room]})
    empty.doors = pd.DataFrame({"door_id": [0], "x0": [4.0], "y0": [1.0], "x1": [4.0], "y1": [1.9], "width_m": [0.9],
                                "wall_id": [-1], "room_a": [0], "room_b": [1]})
    write_plan(empty, tmp_path / "p")
    back = read_plan(tmp_path / "p")
    assert back.rooms["polygon"].iloc[0].equals(room) and back.rooms["area_m2"].iloc[0] == 11.0
    assert back.doors["width_m"].tolist() == [0.9] and back.walls.empty
    raw = read_plan_tables(tmp_path / "p", ["rooms"])["rooms"]
    assert shapely.from_wkb(raw["polygon"].iloc[0]).equals(room)  # WKB on disk


def test_plan_tables_refuse_a_missing_part_and_leave_no_half_folder(tmp_path):
    with pytest.raises(KeyError, match="missing"):
        write_plan_tables({"walls": pd.DataFrame()}, tmp_path / "p")
    with pytest.raises(FileNotFoundError):
        plan_faces_and_walls(tmp_path / "nothing")
    assert not (tmp_path / "p").exists()


def test_the_grid_writes_every_run_and_builds_the_same_scans_once(per_scan, orderings, tmp_path):
    """Every ordering's k = all holds the same scans: built once, written per run with
    its own metadata; the tables equal the builder's plan of the run's scans."""
    runs = [(o, k) for o in orderings for k in ("2", "all")]
    folders = [tmp_path / f"{o}_ransac_k{k}" for o, k in runs]
    exports = [{"svg": tmp_path / f"{o}_ransac_k{k}.svg"} for o, k in runs]
    done = write_plan_grid(per_scan, orderings, runs, folders, exports, {}, "box", "ransac", 0.0)
    assert [d["reused"] for d in done] == [False, False, False, True]
    assert [d["n_scans"] for d in done] == [2, 6, 2, 6]
    for (o, k), folder, exp in zip(runs, folders, exports):
        faces, n_walls = plan_faces_and_walls(folder)
        _, ids = first_k_walls(per_scan, orderings[o], k)
        want = build_floorplan(per_scan[per_scan["scan_id"].isin(ids)])
        assert n_walls == len(want.walls) and len(faces) == len(want.faces)
        assert np.abs(faces - want.faces[["x0", "y0", "x1", "y1"]].to_numpy()).max() <= 5e-6
        assert exp["svg"].stat().st_size > 500
    import pyarrow.parquet as pq

    assert pq.read_schema(folders[1] / "faces.parquet").metadata[b"ordering"] == b"forward"
    assert pq.read_schema(folders[3] / "faces.parquet").metadata[b"ordering"] == b"backward"


def test_the_answer_reads_the_selection_stage_table_in_rank_order(tmp_path):
    table = pd.DataFrame({"rank": [2, 1, 3], "scan_id": [7, 4, 1], "t_ns": [3, 2, 1], "time_iso": ["a", "b", "c"],
                          "x_m": [0.0, 1.0, 2.0], "y_m": [0.0] * 3, "yaw_rad": [0.0] * 3, "gain": [5.0, 9.0, 1.0]})
    write_scan_table(table, tmp_path / "scans.parquet", {"ordering": "wall_coverage"})
    assert selected_scan_ids(tmp_path / "scans.parquet").tolist() == [4, 7, 1]
    import pyarrow.parquet as pq

    assert pq.read_schema(tmp_path / "scans.parquet").remove_metadata().names == SCAN_TABLE.names

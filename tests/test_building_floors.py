"""The floors of one building (floorscan.floorplan.building): one IFC with a storey per
floor, a GeoJSON per floor, the building's page; and the recommended plan built without
writing it (floorscan.floorplan.writer.recommended_plan), the same as the plan tables it
writes, which the building reads.

The floors: the box plan of test_rooms_export (6 walls, a room and a corridor, a door)
on the ground floor, and a 4-wall box of one room above it.
"""

import json

import numpy as np
import pandas as pd
import pytest
import shapely

from floorscan.floorplan.building import Floor, building_files, write_building
from floorscan.floorplan.geojson import floorplan_geojson, write_geojson
from floorscan.floorplan.ifc import STOREY_NAME, write_building_ifc, write_ifc
from floorscan.floorplan.metadata import PlanMetadata
from floorscan.floorplan.plan import ROOM_COLUMNS
from floorscan.floorplan.scans import plan_metadata, read_plan
from floorscan.floorplan.writer import recommended_plan, write_recommended_floorplan
from test_floorplan import BOX, THICK, plan_of, scans_segments
from test_rooms_export import WALLS, rooms_plan

ifcopenshell = pytest.importorskip("ifcopenshell")

FLOORS = [Floor("ground", "Ground floor", 0.0), Floor("upper", "First <floor> & roof", 3.1)]
META = {"ground": PlanMetadata("ground", "random", "ransac", "all", 1_600_000_000)}


def upper_plan():
    """The box's four outer walls, one room inside, no doors."""
    plan = plan_of(WALLS[:4])
    room = shapely.box(0.1, 0.1, 5.9, 3.9)
    plan.rooms = pd.DataFrame({
        "room_id": [1], "name": ["Room 1"], "kind": ["room"], "area_m2": [room.area], "perimeter_m": [room.length],
        "polygon": [room],
    })[ROOM_COLUMNS]  # fmt: skip
    return plan


@pytest.fixture(scope="module")
def plans():
    return {"ground": rooms_plan(), "upper": upper_plan()}


@pytest.fixture(scope="module")
def building(tmp_path_factory, plans):
    out = tmp_path_factory.mktemp("results") / "building"
    return write_building(FLOORS, plans, out, "Test & house", META)


def storeys(model):
    return {s.Name: s for s in model.by_type("IfcBuildingStorey")}


def test_the_files_are_the_building_files(building, tmp_path):
    out = building_files(tmp_path.parent / "x", ["ground", "upper"])
    assert out["ifc"].endswith("/x/building.ifc") and out["page"].endswith("/x/index.html")
    assert [p.rsplit("/", 1)[1] for p in out["geojson"]] == ["ground.geojson", "upper.geojson"]
    assert [p.rsplit("/", 1)[1] for p in building["geojson"]] == ["ground.geojson", "upper.geojson"]


def test_a_storey_per_floor_at_its_elevation(building):
    import ifcopenshell.util.placement

    model = ifcopenshell.open(building["ifc"])
    by_name = storeys(model)
    assert list(by_name) == ["Ground floor", "First <floor> & roof"]
    for floor in FLOORS:
        storey = by_name[floor.storey]
        assert storey.Elevation == floor.elevation_m
        assert ifcopenshell.util.placement.get_local_placement(storey.ObjectPlacement)[2, 3] == floor.elevation_m
    (rel,) = model.by_type("IfcBuilding")[0].IsDecomposedBy
    assert [s.Name for s in rel.RelatedObjects] == [f.storey for f in FLOORS]
    assert model.by_type("IfcProject")[0].Name == "Test & house"


def test_each_storey_holds_its_own_plan_at_its_elevation(building, plans):
    import ifcopenshell.util.element
    import ifcopenshell.util.placement

    model = ifcopenshell.open(building["ifc"])
    for floor in FLOORS:
        storey, plan = storeys(model)[floor.storey], plans[floor.dataset]
        contained = ifcopenshell.util.element.get_contained(storey)
        spaces = [o for rel in storey.IsDecomposedBy for o in rel.RelatedObjects]
        assert sum(e.is_a("IfcWall") for e in contained) == len(plan.walls)
        assert sum(e.is_a("IfcDoor") for e in contained) == len(plan.doors)
        assert sorted(s.Name for s in spaces if s.is_a("IfcSpace")) == sorted(plan.rooms["name"])
        for element in [*contained, *spaces]:  # on the storey: z (in the model) its elevation
            z = ifcopenshell.util.placement.get_local_placement(element.ObjectPlacement)[2, 3]
            assert z == pytest.approx(floor.elevation_m, abs=1e-12)
    assert len(model.by_type("IfcWall")) == sum(len(p.walls) for p in plans.values())
    # junction connections stay within their storey
    for rel in model.by_type("IfcRelConnectsPathElements"):
        a, b = (ifcopenshell.util.element.get_container(e) for e in (rel.RelatingElement, rel.RelatedElement))
        assert a == b


@pytest.mark.slow
def test_the_building_ifc_is_valid_with_unique_deterministic_ids(building, plans, tmp_path):
    from ifcopenshell import validate

    log = validate.json_logger()
    validate.validate(building["ifc"], log, express_rules=True)
    assert log.statements == []
    model = ifcopenshell.open(building["ifc"])
    ids = [e.GlobalId for e in model.by_type("IfcRoot")]
    assert len(ids) == len(set(ids))
    assert model.header.file_name.time_stamp == "2020-09-13T12:26:40+00:00"  # the least floor stamp


def test_the_floor_geojson_is_its_plan_naming_the_storey_and_elevation(building, plans):
    for floor, path in zip(FLOORS, building["geojson"]):
        doc = json.loads(open(path).read())
        member = doc["floorscan"]
        assert (member["building"], member["storey"], member["elevation_m"]) == (
            "Test & house", floor.storey, floor.elevation_m)  # fmt: skip
        plain = floorplan_geojson(plans[floor.dataset], META.get(floor.dataset, PlanMetadata(dataset=floor.dataset)))
        assert doc["features"] == json.loads(json.dumps(plain["features"]))
        assert {k: v for k, v in member.items() if k not in ("building", "storey", "elevation_m")} == plain["floorscan"]
    assert json.loads(open(building["geojson"][0]).read())["floorscan"]["n_rooms"] == 2


def test_the_page_lists_the_floors_with_their_plans_and_front_pages(building, plans):
    page = open(building["page"], encoding="utf-8").read()
    assert "<h1>Test &amp; house</h1>" in page
    assert "First &lt;floor&gt; &amp; roof" in page and "<floor>" not in page
    for floor in FLOORS:
        assert f'href="../{floor.dataset}/front.html"' in page
        assert f'src="../{floor.dataset}/floorplan.svg"' in page
        assert f'href="{floor.dataset}.geojson"' in page
    ground = page[page.index("Ground floor"):page.index("</tr>", page.index("Ground floor"))]
    assert "<td>0.00</td><td>6</td><td>2</td><td>20.7</td><td>1</td>" in ground  # elevation, walls, rooms, m2, doors
    assert "<td>3.10</td><td>4</td><td>1</td>" in page


def test_the_same_building_gives_the_same_bytes(building, plans, tmp_path):
    again = write_building(FLOORS, plans, tmp_path / "building", "Test & house", META)
    for a, b in zip([building["ifc"], building["page"], *building["geojson"]],
                    [again["ifc"], again["page"], *again["geojson"]]):  # fmt: skip
        assert open(a, "rb").read() == open(b, "rb").read()


def test_a_one_storey_building_is_the_floor_plans_ifc(tmp_path):
    # one storey builder: the single-floor IFC's data equal a one-storey building's but
    # for the project's description
    plan = rooms_plan()
    write_ifc(plan, tmp_path / "plan.ifc", metadata=META["ground"])
    write_building_ifc([(STOREY_NAME, 0.0, plan)], tmp_path / "plan_b.ifc", metadata=META["ground"])

    def data(name):
        text = (tmp_path / name).read_text()
        return [line for line in text[text.index("DATA;"):].splitlines() if "IFCPROJECT(" not in line]

    assert data("plan.ifc") == data("plan_b.ifc")


def test_a_building_needs_distinct_floors_with_plans(plans, tmp_path):
    with pytest.raises(ValueError, match="at least one floor"):
        write_building([], plans, tmp_path)
    with pytest.raises(ValueError, match="one floor only"):
        write_building([FLOORS[0], Floor("ground", "Again", 6.0)], plans, tmp_path)
    with pytest.raises(KeyError, match="cellar"):
        write_building([*FLOORS, Floor("cellar", "Cellar", -3.0)], plans, tmp_path)
    with pytest.raises(ValueError, match="finite"):
        write_building_ifc([("Up", float("nan"), plans["upper"])], tmp_path / "x.ifc")


def test_recommended_plan_is_the_plan_the_recommended_floorplan_writes(tmp_path):
    segments = scans_segments(BOX + THICK, [(2, 1.2), (2, -1.0), (1, 1.5), (3, -1.5)], "ransac")
    # the selection stage's table (selection/scans.parquet), ranks out of scan order
    pd.DataFrame({"rank": [1, 2, 3], "scan_id": [3, 0, 2]}).to_parquet(tmp_path / "scans.parquet")
    segments.to_parquet(tmp_path / "walls.parquet")
    pd.DataFrame({"t_ns": np.array([1_650_000_000_500_000_000, 1_650_000_009_000_000_000], np.int64)}).to_parquet(
        tmp_path / "index.parquet")  # fmt: skip
    args = (tmp_path / "scans.parquet", tmp_path / "walls.parquet", tmp_path / "index.parquet")
    counts = write_recommended_floorplan(
        *args, {"geojson": tmp_path / "floorplan.geojson"}, {}, dataset="box", ordering="random", extractor="ransac",
        plan_folder=tmp_path / "plan_tables",
    )
    rec = recommended_plan(*args, {}, "box", "random", "ransac")
    assert rec.metadata == PlanMetadata("box", "random", "ransac", 3, 1_650_000_000)
    assert (rec.n_scans, rec.n_segments) == (3, int(segments["scan_id"].isin([0, 2, 3]).sum()))
    assert counts["n_walls"] == len(rec.plan.walls) > 0
    tables = read_plan(tmp_path / "plan_tables")  # the same plan for programs, to 10 um
    assert plan_metadata(tmp_path / "plan_tables") == rec.metadata  # what the building names each floor by
    assert tables.walls["wall_id"].tolist() == rec.plan.walls["wall_id"].tolist()
    np.testing.assert_allclose(tables.faces[["x0", "y0", "x1", "y1"]], rec.plan.faces[["x0", "y0", "x1", "y1"]], atol=5e-6)
    write_geojson(rec.plan, tmp_path / "again.geojson", rec.metadata)
    assert (tmp_path / "again.geojson").read_bytes() == (tmp_path / "floorplan.geojson").read_bytes()

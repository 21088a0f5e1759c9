"""Floor plan: duplicates merge, faces pair into thick walls, exports reopen with their tools."""

import json
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import shapely
import yaml

from floorscan.floorplan import (
    FloorplanParams,
    build_floorplan,
    fit_groups,
    fit_segments,
    merge_segments,
    pair_faces,
    write_floorplan,
)
from floorscan.walls import cluster_ransac, ransac
from test_walls import ROOM, match, raycast

REPO = Path(__file__).resolve().parents[1]
BOX = [(-1, -2, 5, -2), (5, -2, 5, 2.2), (5, 2.2, -1, 2.2), (-1, 2.2, -1, -2)]
THICK = [(0, 0, 4, 0), (4, 0, 4, 0.2), (4, 0.2, 0, 0.2), (0, 0.2, 0, 0)]  # a 4 m x 20 cm wall


def scans_segments(walls, origins, extractor):
    out = []
    for sid, o in enumerate(origins):
        pts = raycast(walls, o, seed=sid)
        df = ransac(pts, seed=sid) if extractor == "ransac" else cluster_ransac(pts, seed=sid)
        out.append(df.assign(scan_id=sid))
    return pd.concat(out, ignore_index=True)


def test_fit_segments_weighted_line_and_union_extent():
    two_faces = np.array([[0.0, 0.0, 2.0, 0.0], [2.0, 0.02, 0.0, 0.02]])  # opposite directions
    np.testing.assert_allclose(fit_segments(two_faces, [1, 1]), [0, 0.01, 2, 0.01], atol=1e-12)
    np.testing.assert_allclose(fit_segments(two_faces, [3, 1]), [0, 0.005, 2, 0.005], atol=1e-12)
    collinear = np.array([[0.0, 1.0, 2.0, 3.0], [1.0, 2.0, 3.0, 4.0]])  # on y = x + 1
    np.testing.assert_allclose(fit_segments(collinear, [5, 1]), [0, 1, 3, 4], atol=1e-12)


def test_fit_groups_fits_each_group_on_its_own():
    # three groups, interleaved rows: the grouped fit is each group's own fit
    seg = np.array([
        [0.0, 0.0, 2.0, 0.0], [5.0, 5.0, 5.0, 7.0], [2.0, 0.02, 0.0, 0.02],
        [0.0, 1.0, 2.0, 3.0], [5.1, 4.0, 5.1, 8.0], [1.0, 2.0, 3.0, 4.0],
    ])  # fmt: skip
    w = np.array([3.0, 1.0, 1.0, 5.0, 2.0, 1.0])
    group = np.array([0, 1, 0, 2, 1, 2])
    fitted = fit_groups(seg, w, group, 3)
    np.testing.assert_allclose(fitted[0], [0, 0.005, 2, 0.005], atol=1e-12)
    np.testing.assert_allclose(fitted[2], [0, 1, 3, 4], atol=1e-12)
    # the vertical pair, midpoints at one height: centroid x = (5 * 1 + 5.1 * 2) / 3, extent y 4 .. 8
    np.testing.assert_allclose(fitted[1], [15.2 / 3, 4.0, 15.2 / 3, 8.0], atol=1e-9)
    for g in range(3):
        np.testing.assert_allclose(fitted[g], fit_segments(seg[group == g], w[group == g]), atol=1e-12)


def test_merge_keeps_apart_what_is_not_one_face():
    seg = np.array(
        [
            [0, 0, 2, 0], [2.2, 0.0, 4, 0.0],  # collinear, 0.2 m gap: one face
            [0, 1, 2, 1],  # parallel 1 m away
            [5, 0, 5, 2],  # perpendicular
            [7, 0, 9, 0],  # collinear but 3 m away
            [0, 0.5, 2, 0.5 + 2 * np.tan(np.radians(10))],  # 10 degrees off
        ],
        dtype=float,
    )  # fmt: skip
    faces, w, labels = merge_segments(seg, np.ones(6))
    assert len(faces) == 5
    assert labels[0] == labels[1] and len(set(labels[1:].tolist())) == 5
    np.testing.assert_allclose(faces[labels[0]], [0, 0, 4, 0], atol=1e-12)
    assert w[labels[0]] == 2


@pytest.mark.parametrize("extractor", ["ransac", "cluster_ransac"])
def test_duplicates_from_several_scans_merge_to_one_wall_each(extractor):
    segs = scans_segments(ROOM, [(1.0, 1.0), (3.0, 2.0), (2.0, 5.0), (1.2, 3.5)], extractor)
    assert len(segs) >= 16
    plan = build_floorplan(segs, FloorplanParams())
    assert len(plan.walls) == 4 and len(plan.faces) == 4
    assert plan.walls["n_segments"].sum() == len(segs)
    for wall in ROOM:
        ang, perp, ends = min((match(r, wall) for r in plan.faces[["x0", "y0", "x1", "y1"]].to_numpy()), key=lambda m: m[1])
        assert ang < 0.5 and perp < 0.01 and ends < 0.05
    assert (plan.walls["thickness_m"] == 0.10).all() and not plan.walls["paired"].any()


@pytest.mark.parametrize("extractor", ["ransac", "cluster_ransac"])
def test_two_faces_pair_into_one_wall_with_its_thickness(extractor):
    segs = scans_segments(BOX + THICK, [(2, 1.2), (2, -1.0), (1, 1.5), (3, -1.5)], extractor)
    plan = build_floorplan(segs, FloorplanParams())
    paired = plan.walls[plan.walls["paired"]]
    assert len(paired) == 1 and len(plan.walls) == 5
    w = paired.iloc[0]
    assert abs(w.thickness_m - 0.20) < 0.01
    np.testing.assert_allclose([w.y0, w.y1], [0.10, 0.10], atol=0.01)
    np.testing.assert_allclose(sorted([w.x0, w.x1]), [0.0, 4.0], atol=0.05)


def test_pairing_range_and_overlap():
    faces = np.array([[0, 0, 4, 0], [0, 0.3, 4, 0.3], [0, 5, 4, 5], [3.5, 5.2, 8, 5.2]], dtype=float)
    axes, thick, wall_of_face = pair_faces(faces, np.ones(4), FloorplanParams())
    assert wall_of_face[0] == wall_of_face[1] and wall_of_face[2] != wall_of_face[3]  # 0.5 m overlap < half of 4 m
    np.testing.assert_allclose(thick, [0.3, 0.1, 0.1])
    np.testing.assert_allclose(axes[0], [0, 0.15, 4, 0.15], atol=1e-12)
    _, _, w2 = pair_faces(faces, np.ones(4), FloorplanParams(pair_max_m=0.25))
    assert len(set(w2.tolist())) == 4


def test_exports_reopen_with_ifcopenshell_and_ezdxf(tmp_path):
    import ezdxf
    import ifcopenshell
    import ifcopenshell.util.element as ue

    segs = scans_segments(BOX + THICK, [(2, 1.2), (2, -1.0), (1, 1.5), (3, -1.5)], "ransac")
    out = {f: tmp_path / f"plan.{f}" for f in ("geojson", "svg", "dxf", "ifc")}
    plan = write_floorplan(segs, {"wall_height_m": 2.7}, out, name="test")
    n = len(plan.walls)
    assert n == 5
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(p.name for p in out.values())  # no temp files

    model = ifcopenshell.open(str(out["ifc"]))
    walls = model.by_type("IfcWall")
    assert len(walls) == n
    assert all(ue.get_container(w).is_a("IfcBuildingStorey") for w in walls)
    q = sorted((ue.get_psets(w)["Qto_WallBaseQuantities"]["Length"], ue.get_psets(w)["Qto_WallBaseQuantities"]["Width"]) for w in walls)
    np.testing.assert_allclose(q, sorted(zip(plan.walls.length_m, plan.walls.thickness_m)), atol=1e-6)
    assert {ue.get_psets(w)["Qto_WallBaseQuantities"]["Height"] for w in walls} == {2.7}
    assert model.by_type("IfcProject")[0].Name == "test"
    write_floorplan(segs, {"wall_height_m": 2.7}, {"ifc": tmp_path / "again.ifc"}, name="test")
    again = ifcopenshell.open(str(tmp_path / "again.ifc"))
    assert [w.GlobalId for w in again.by_type("IfcWall")] == [w.GlobalId for w in walls]  # stable ids

    # DXF R12 (default): every entity on its layer with the layer's colour, the
    # coordinates to the micrometre; R2010: the layer table and units (metres)
    doc = ezdxf.readfile(out["dxf"])
    msp = doc.modelspace()
    assert doc.dxfversion == "AC1009"
    axes = msp.query('LINE[layer=="WALL_AXIS"]')
    assert len(axes) == n and {e.dxf.color for e in axes} == {1}
    got = sorted((e.dxf.start.x, e.dxf.start.y, e.dxf.end.x, e.dxf.end.y) for e in axes)
    np.testing.assert_allclose(got, sorted(plan.walls[["x0", "y0", "x1", "y1"]].itertuples(index=False)), atol=1e-6)
    outlines = msp.query('POLYLINE[layer=="WALL_OUTLINE"]')
    assert len(outlines) == n and all(p.is_closed for p in outlines)
    rings = sorted(round(shapely.Polygon([(v.dxf.location.x, v.dxf.location.y) for v in p.vertices]).area, 5) for p in outlines)
    assert rings == sorted(round(a, 5) for a in shapely.area(plan.footprints()))
    assert len(msp.query('LINE[layer=="WALL_FACE"]')) == len(plan.faces)
    write_floorplan(segs, {"wall_height_m": 2.7, "dxf_version": "R2010"}, {"dxf": tmp_path / "r2010.dxf"})
    doc = ezdxf.readfile(tmp_path / "r2010.dxf")
    msp = doc.modelspace()
    assert doc.dxfversion == "AC1024" and doc.units == 6  # metres
    assert {layer.dxf.name: layer.dxf.color for layer in doc.layers if layer.dxf.name.startswith("WALL")} == {
        "WALL_AXIS": 1, "WALL_OUTLINE": 7, "WALL_FACE": 3}  # fmt: skip
    assert len(msp.query('LINE[layer=="WALL_AXIS"]')) == n
    outlines = msp.query('LWPOLYLINE[layer=="WALL_OUTLINE"]')
    assert len(outlines) == n and all(p.closed for p in outlines)
    assert len(msp.query('LINE[layer=="WALL_FACE"]')) == len(plan.faces)

    gj = json.loads(out["geojson"].read_text())
    kinds = pd.Series([f["properties"]["kind"] for f in gj["features"]]).value_counts().to_dict()
    assert kinds == {"axis": n, "footprint": n, "face": len(plan.faces)}
    thick = [f["properties"]["thickness_m"] for f in gj["features"] if f["properties"]["kind"] == "axis"]
    assert sorted(thick)[-1] == pytest.approx(0.20, abs=0.01) and sorted(thick)[0] == 0.10
    areas = [f for f in gj["features"] if f["properties"]["kind"] == "footprint"]
    assert areas[0]["geometry"]["type"] == "Polygon"

    svg = ET.parse(out["svg"]).getroot()
    ns = {"s": "http://www.w3.org/2000/svg"}
    assert len(svg.findall(".//s:polygon", ns)) == n and len(svg.findall(".//s:line", ns)) == n


def test_empty_segments_write_an_empty_plan(tmp_path):
    empty = pd.DataFrame({c: pd.Series(dtype="float64") for c in ("x0", "y0", "x1", "y1", "rmse_m")})
    out = {f: tmp_path / f"e.{f}" for f in ("geojson", "svg", "dxf", "ifc")}
    plan = write_floorplan(empty.assign(n_inliers=pd.Series(dtype="int32")), None, out)
    assert len(plan.walls) == 0
    assert json.loads(out["geojson"].read_text())["features"] == []
    import ifcopenshell

    assert len(ifcopenshell.open(str(out["ifc"])).by_type("IfcWall")) == 0


def test_bad_config_and_columns_are_named():
    with pytest.raises(KeyError, match="merge_angle"):
        write_floorplan(pd.DataFrame(), {"merge_angel_deg": 3}, {})
    with pytest.raises(KeyError, match="x0"):
        build_floorplan(pd.DataFrame({"a": [1]}))
    with pytest.raises(ValueError, match="pair_min_m"):
        FloorplanParams(pair_min_m=0.5, pair_max_m=0.4)
    with pytest.raises(ValueError, match="dxf_version"):
        FloorplanParams(dxf_version="R14")


def test_schema_defaults_agree_with_floorplan_params():
    schema = yaml.safe_load((REPO / "workflow/schemas/floorplan.schema.yaml").read_text())["properties"]
    defaults = {k: v["default"] for k, v in schema.items()}
    assert defaults == {f: getattr(FloorplanParams(), f) for f in FloorplanParams.__dataclass_fields__}


def test_candidate_pairs_equal_shapely_dwithin():
    import shapely

    from floorscan.floorplan import _candidate_pairs

    rng = np.random.default_rng(7)
    p0 = rng.uniform(0, 6, (300, 2))
    ang = rng.choice([0.0, np.pi / 2, rng.uniform(0, np.pi)], 300)
    seg = np.hstack([p0, p0 + rng.uniform(0.1, 2.0, (300, 1)) * np.c_[np.cos(ang), np.sin(ang)]])
    seg[:20] = seg[20:40] + [0.0, 0.3, 0.0, 0.3]  # parallel pairs exactly 0.3 m apart
    lines = shapely.linestrings(seg.reshape(-1, 2, 2))
    for dist in (0.05, 0.3):
        i, j = shapely.STRtree(lines).query(lines, predicate="dwithin", distance=dist)
        want = sorted(zip(*(a[i < j] for a in (i, j))))
        got = list(zip(*_candidate_pairs(seg, dist)))
        assert got == want and len(want) > 50
    i, j = _candidate_pairs(seg, 0.3, np.radians(3.0))
    d = np.abs(np.arctan2(*(seg[i, 2:] - seg[i, :2]).T[::-1]) - np.arctan2(*(seg[j, 2:] - seg[j, :2]).T[::-1])) % np.pi
    assert (np.minimum(d, np.pi - d) <= np.radians(3.0) + 1e-12).all() and len(i) > 10


def test_ifc_wall_placement_and_body(tmp_path):
    """The walls written as STEP lines: placement, body, axis, and a schema-valid file."""
    import ifcopenshell
    import ifcopenshell.util.placement as up
    import ifcopenshell.validate

    from floorscan.floorplan import FloorPlan, write_ifc

    walls = pd.DataFrame({"wall_id": [0], "x0": [1.0], "y0": [2.0], "x1": [1.0], "y1": [6.0], "length_m": [4.0],
                          "thickness_m": [0.2], "height_m": [2.7], "paired": [True], "n_faces": [2],
                          "n_segments": [5], "n_inliers": [100]})
    write_ifc(FloorPlan(walls=walls, faces=pd.DataFrame()), tmp_path / "w.ifc", name="O'Brien's plan")
    model = ifcopenshell.open(str(tmp_path / "w.ifc"))
    log = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(model, log, express_rules=False)
    assert log.statements == []
    assert model.by_type("IfcProject")[0].Name == "O'Brien's plan"
    (wall,) = model.by_type("IfcWall")
    m = up.get_local_placement(wall.ObjectPlacement)
    np.testing.assert_allclose(m[:3, 3], [1.0, 2.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(m[:3, 0], [0.0, 1.0, 0.0], atol=1e-12)  # x along the axis
    body, axis = wall.Representation.Representations
    assert (body.RepresentationIdentifier, body.RepresentationType) == ("Body", "SweptSolid")
    solid = body.Items[0]
    assert solid.Depth == pytest.approx(2.7) and solid.Position.Location.Coordinates == pytest.approx((0.0, -0.1, 0.0))
    assert solid.SweptArea.OuterCurve.Points.CoordList[2] == pytest.approx((4.0, 0.2))
    assert (axis.RepresentationIdentifier, axis.RepresentationType) == ("Axis", "Curve2D")


def test_union_find_numbers_components_by_smallest_node():
    from floorscan.floorplan import _union_find

    # Components {0}, {1, 3, 5} (a chain 5-3-1), {2, 4}, {6}; numbered by smallest node.
    labels = _union_find(7, np.array([5, 3, 2]), np.array([3, 1, 4]))
    assert labels.tolist() == [0, 1, 2, 1, 2, 1, 3]
    chain = np.arange(999)
    assert (_union_find(1000, chain[::-1], chain[::-1] + 1) == 0).all()
    assert _union_find(3, np.empty(0, int), np.empty(0, int)).tolist() == [0, 1, 2]


def test_ifc_walls_sharing_geometry_read_back_their_own_axis_height_thickness(tmp_path):
    """Walls of one thickness share the body's profile placement (one entity), and
    every wall still reads back its own axis, height, thickness and name."""
    import ifcopenshell
    import ifcopenshell.util.element as ue
    import ifcopenshell.util.placement as up
    import ifcopenshell.validate

    from floorscan.floorplan import FloorPlan, write_ifc

    walls = pd.DataFrame({
        "wall_id": [0, 1, 2], "x0": [0.0, 5.0, 0.0], "y0": [0.0, 0.0, 3.0], "x1": [5.0, 5.0, 3.0],
        "y1": [0.0, 4.0, 7.0], "length_m": [5.0, 4.0, 5.0], "thickness_m": [0.1, 0.1, 0.25],
        "height_m": [2.5, 2.5, 3.0], "paired": [False, False, True], "n_faces": [1, 1, 2],
        "n_segments": [3, 4, 5], "n_inliers": [50, 60, 70],
    })  # fmt: skip
    write_ifc(FloorPlan(walls=walls, faces=pd.DataFrame()), tmp_path / "w.ifc", name="shared")
    model = ifcopenshell.open(str(tmp_path / "w.ifc"))
    log = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(model, log, express_rules=False)
    assert log.statements == []
    ws = model.by_type("IfcWall")
    assert [w.Name for w in ws] == ["Wall 0", "Wall 1", "Wall 2"]
    solids = [w.Representation.Representations[0].Items[0] for w in ws]
    assert solids[0].Position == solids[1].Position and solids[0].Position.id() == solids[1].Position.id()
    assert solids[2].Position.id() != solids[0].Position.id()
    # the model context's world coordinate system, 2 profile placements, 3 wall placements
    assert len(model.by_type("IfcAxis2Placement3D")) == 1 + 2 + 3
    for w, solid, want in zip(ws, solids, walls.itertuples(index=False)):
        m = up.get_local_placement(w.ObjectPlacement)
        length = np.hypot(want.x1 - want.x0, want.y1 - want.y0)
        np.testing.assert_allclose(m[:3, 3], [want.x0, want.y0, 0.0], atol=1e-12)
        along = [(want.x1 - want.x0) / length, (want.y1 - want.y0) / length, 0.0]
        np.testing.assert_allclose(m[:3, 0], along, atol=1e-12)
        assert solid.Depth == want.height_m
        assert solid.Position.Location.Coordinates == pytest.approx((0.0, -want.thickness_m / 2, 0.0))
        assert solid.SweptArea.OuterCurve.Points.CoordList[2] == pytest.approx((length, want.thickness_m))
        axis = w.Representation.Representations[1].Items[0].Points.CoordList
        np.testing.assert_allclose(axis, [[0.0, 0.0], [length, 0.0]], atol=1e-12)
        q = ue.get_psets(w)["Qto_WallBaseQuantities"]
        assert (q["Length"], q["Width"], q["Height"]) == pytest.approx((length, want.thickness_m, want.height_m))


def test_geojson_is_one_feature_per_line_and_equals_floorplan_geojson(tmp_path):
    from floorscan.floorplan import floorplan_geojson, write_geojson

    segs = scans_segments(BOX + THICK, [(2, 1.2), (2, -1.0), (1, 1.5), (3, -1.5)], "ransac")
    plan = build_floorplan(segs, FloorplanParams())
    write_geojson(plan, tmp_path / "p.geojson")
    text = (tmp_path / "p.geojson").read_text()
    lines = text.splitlines()
    n = len(plan.walls) * 2 + len(plan.faces)
    assert len(lines) == n + 2 and lines[0] == '{"type": "FeatureCollection", "features": [' and lines[-1] == "]}"
    assert json.loads(text) == floorplan_geojson(plan)
    first = json.loads(lines[1].rstrip(","))
    assert first["properties"]["kind"] == "axis" and len(first["geometry"]["coordinates"]) == 2
    x0, y0, x1, y1 = plan.walls.loc[0, ["x0", "y0", "x1", "y1"]].to_numpy(float).tolist()
    assert first["geometry"]["coordinates"] == [[round(x0, 5), round(y0, 5)], [round(x1, 5), round(y1, 5)]]
    assert abs(first["geometry"]["coordinates"][0][0] - x0) <= 5e-6


def test_candidate_pairs_by_direction_bins_equal_dwithin_and_angle():
    """Binned by direction (with the wrap at 0 / 180 degrees), the candidates are
    exactly the dwithin pairs within the angle."""
    import shapely

    from floorscan.floorplan import _angle_diff, _axial_angle, _candidate_pairs

    rng = np.random.default_rng(11)
    p0 = rng.uniform(0, 5, (400, 2))
    ang = rng.choice([0.0, np.pi / 2, np.pi - 0.01, rng.uniform(0, np.pi)], 400) + rng.normal(0, 0.03, 400)
    seg = np.hstack([p0, p0 + rng.uniform(0.1, 2.0, (400, 1)) * np.c_[np.cos(ang), np.sin(ang)]])
    lines = shapely.linestrings(seg.reshape(-1, 2, 2))
    for dist, max_deg in ((0.3, 3.0), (0.05, 1.0), (0.3, 20.0), (0.3, 80.0)):
        i, j = shapely.STRtree(lines).query(lines, predicate="dwithin", distance=dist)
        a = _axial_angle(seg)
        keep = (i < j) & (_angle_diff(a[i], a[j]) <= np.radians(max_deg))
        want = sorted(zip(i[keep].tolist(), j[keep].tolist()))
        got = list(zip(*(x.tolist() for x in _candidate_pairs(seg, dist, np.radians(max_deg)))))
        assert got == want and len(want) > 20
        if max_deg == 3.0:  # 59 direction bins: pairs across the 0/180 degree wrap are found
            across = [(p, q) for p, q in want if abs(a[p] - a[q]) > np.pi / 2]
            assert across


def test_merge_skips_connected_pairs_without_changing_faces(monkeypatch):
    """Testing the candidates a few at a time and skipping pairs already connected
    gives the faces that testing all of them gives."""
    import floorscan.floorplan as fp

    rng = np.random.default_rng(5)
    walls = np.array([[0, 0, 6, 0], [0, 0.2, 6, 0.2], [6.5, -1, 6.5, 4], [0, 3, 3, 3.02]], dtype=float)
    segs, w = [], []
    for wall in walls:  # 60 scans see each wall: noisy, partial, stacked segments
        t = np.sort(rng.uniform(0, 1, (60, 2)), axis=1)
        t[:, 1] = np.maximum(t[:, 1], t[:, 0] + 0.3)
        a, b = wall[:2], wall[2:]
        ends = np.hstack([a + t[:, :1] * (b - a), a + np.minimum(t[:, 1:], 1) * (b - a)])
        segs.append(ends + rng.normal(0, 0.004, (60, 4)))
        w.append(rng.integers(20, 200, 60))
    seg, w = np.vstack(segs), np.concatenate(w).astype(float)
    monkeypatch.setattr(fp, "_MERGE_CHUNK", 1 << 30)
    faces_all, w_all, labels_all = fp.merge_segments(seg, w)
    monkeypatch.setattr(fp, "_MERGE_CHUNK", 7)
    faces, fw, labels = fp.merge_segments(seg, w)
    assert len(faces) == 4
    np.testing.assert_array_equal(faces, faces_all)
    np.testing.assert_array_equal(fw, w_all)
    np.testing.assert_array_equal(labels, labels_all)
    np.testing.assert_allclose(np.sort(fw), np.sort([x.sum() for x in np.split(w, 4)]))
    np.testing.assert_allclose(faces[labels[0]][[1, 3]], [0, 0], atol=0.01)


def test_plan_depends_on_the_scans_not_their_ranking_and_a_repeat_is_copied(tmp_path):
    """Every ordering's k = all holds the same scans in another order: the same plan.
    The writer copies it (GeoJSON, DXF bytes) and names it (SVG title, IFC project and
    GlobalIds, exactly as a fresh export of that name)."""
    from floorscan.floorplan import FLOORPLAN_FORMATS, FloorplanWriter, write_ifc

    segs = scans_segments(BOX + THICK, [(2, 1.2), (2, -1.0), (1, 1.5), (3, -1.5)], "ransac")
    reranked = pd.concat([segs[segs.scan_id == s] for s in (2, 0, 3, 1)], ignore_index=True)
    assert not reranked["scan_id"].is_monotonic_increasing
    a, b = build_floorplan(segs), build_floorplan(reranked)
    pd.testing.assert_frame_equal(a.walls, b.walls)
    pd.testing.assert_frame_equal(a.faces, b.faces)

    writer = FloorplanWriter({})
    out = {run: {f: tmp_path / f"{run}.{f}" for f in FLOORPLAN_FORMATS} for run in ("first", "again", "fewer")}
    assert writer.write(segs, out["first"], name="first")[1] is False
    plan, copied = writer.write(reranked, out["again"], name="again")
    assert copied is True
    pd.testing.assert_frame_equal(plan.walls, a.walls)
    for f in ("geojson", "dxf"):
        assert out["again"][f].read_bytes() == out["first"][f].read_bytes()
    assert "<title>again</title>" in out["again"]["svg"].read_text()
    write_ifc(a, tmp_path / "fresh.ifc", name="again")
    fresh = [line for line in (tmp_path / "fresh.ifc").read_text().splitlines() if not line.startswith("FILE_NAME")]
    again = [line for line in out["again"]["ifc"].read_text().splitlines() if not line.startswith("FILE_NAME")]
    assert again == fresh and "IFCPROJECT(" in "".join(again) and "'again'" in "".join(again)
    # another scan set is built anew
    assert writer.write(segs[segs.scan_id != 3], out["fewer"], name="fewer")[1] is False
    assert out["fewer"]["geojson"].read_bytes() != out["first"]["geojson"].read_bytes()


def test_footprint_geojson_equals_shapely_to_geojson_rounded():
    """Footprint coordinates from the rings equal shapely.to_geojson's, read and rounded."""
    import shapely

    from floorscan.floorplan import FloorPlan, _round_coords, floorplan_geojson

    rng = np.random.default_rng(3)
    n = 200
    p0 = rng.uniform(-30, 30, (n, 2))
    p1 = p0 + rng.normal(0, 3, (n, 2))
    p1[0] = p0[0]  # a zero-length wall: an empty footprint, no footprint feature
    walls = pd.DataFrame({
        "wall_id": np.arange(n, dtype=np.int32), "x0": p0[:, 0], "y0": p0[:, 1], "x1": p1[:, 0], "y1": p1[:, 1],
        "length_m": np.hypot(*(p1 - p0).T), "thickness_m": rng.uniform(0.05, 0.4, n), "height_m": 2.5,
        "paired": True, "n_faces": 2, "n_segments": 3, "n_inliers": 10,
    })  # fmt: skip
    faces = pd.DataFrame(columns=["face_id", "wall_id", "x0", "y0", "x1", "y1", "n_segments", "n_inliers"])
    plan = FloorPlan(walls=walls, faces=faces)
    feats = [f for f in floorplan_geojson(plan)["features"] if f["properties"]["kind"] == "footprint"]
    polys = plan.footprints()
    assert polys[0].is_empty and [f["properties"]["wall_id"] for f in feats] == list(range(1, n))
    for f, poly in zip(feats, polys[1:]):
        assert f["geometry"] == _round_coords(json.loads(shapely.to_geojson(poly)))
        assert len(f["geometry"]["coordinates"][0]) == 5


def test_ifc_guid_list_equals_uuid5_compressed_by_ifcopenshell():
    """The batched GlobalIds are ifcopenshell.guid.compress(uuid5(ns, str(i)).hex)."""
    import uuid

    import ifcopenshell.guid

    from floorscan.floorplan import _ifc_guid_list

    for name in ("hallways3d random ransac k5", "O'Brien's plan", "é"):
        ns = uuid.uuid5(uuid.NAMESPACE_URL, f"floorscan:{name}")
        ids = _ifc_guid_list(name, 1200)
        assert ids == [ifcopenshell.guid.compress(uuid.uuid5(ns, str(i)).hex) for i in range(1200)]
        assert len(set(ids)) == 1200 and all(len(g) == 22 for g in ids)
    assert _ifc_guid_list("x", 0) == []


def test_ifc_entity_maker_makes_what_create_entity_makes():
    """Positional and keyword attributes (entities, lists of points, None) set as
    file.create_entity sets them; an unknown keyword is an error."""
    import ifcopenshell

    from floorscan.floorplan import _entity_maker

    def build(model, ent):
        z = ent("IfcDirection", (0.0, 0.0, 1.0))
        pts = ent("IfcCartesianPointList2D", ((0.0, 0.0), (0.0, 0.25), (3.5, 0.25), (3.5, 0.0), (0.0, 0.0)))
        curve = ent("IfcIndexedPolyCurve", Points=pts, SelfIntersect=False)
        place = ent("IfcAxis2Placement3D", ent("IfcCartesianPoint", (1.0, -0.125, 0.0)), z, None)
        ent("IfcQuantityLength", Name="Width", LengthValue=0.25)
        ent("IfcExtrudedAreaSolid", ent("IfcArbitraryClosedProfileDef", "AREA", OuterCurve=curve), place, z, 2.5)
        return model.to_string().split("DATA;")[1]

    ref, fast = ifcopenshell.file(schema="IFC4"), ifcopenshell.file(schema="IFC4")
    text = build(fast, _entity_maker(fast))
    assert text == build(ref, ref.create_entity)
    assert "#8=IFCEXTRUDEDAREASOLID(#7,#5,#1,2.5);" in text and "#3=IFCINDEXEDPOLYCURVE(#2,$,.F.);" in text
    with pytest.raises(ValueError, match="Width"):
        _entity_maker(fast)("IfcQuantityLength", Width=1.0)


def test_candidate_pairs_by_direction_bins_far_from_the_origin():
    """The one-query binned search (each bin its own stretch of x) finds exactly the
    dwithin pairs within the angle also at UTM-sized coordinates, with pairs exactly
    at the distance and across the 0/180 degree wrap."""
    import shapely

    from floorscan.floorplan import _angle_diff, _axial_angle, _candidate_pairs

    rng = np.random.default_rng(12)
    p0 = rng.uniform(0, 40, (500, 2))
    ang = rng.choice([0.0, np.pi / 2, np.pi - 0.005, 0.005], 500) + rng.normal(0, 0.01, 500)
    seg = np.hstack([p0, p0 + rng.uniform(0.5, 3.0, (500, 1)) * np.c_[np.cos(ang), np.sin(ang)]])
    seg[:30] = seg[30:60] + [0.0, 0.25, 0.0, 0.25]  # exactly 0.25 m from a neighbour (same x)
    seg += [500_000.0, 4_000_000.0, 500_000.0, 4_000_000.0]
    lines = shapely.linestrings(seg.reshape(-1, 2, 2))
    a = _axial_angle(seg)
    for exact in (True, False):
        i, j = shapely.STRtree(lines).query(lines, predicate="dwithin", distance=0.25)
        keep = (i < j) & (_angle_diff(a[i], a[j]) <= np.radians(3.0))
        want = set(zip(i[keep].tolist(), j[keep].tolist()))
        got_i, got_j = _candidate_pairs(seg, 0.25, np.radians(3.0), exact=exact)
        got = set(zip(got_i.tolist(), got_j.tolist()))
        assert (got == want) if exact else (got >= want), exact
        assert (got_i < got_j).all() and len(got) == len(got_i)
    assert {(p, p + 30) for p in range(30)} <= want
    assert any(abs(a[p] - a[q]) > np.pi / 2 for p, q in want)

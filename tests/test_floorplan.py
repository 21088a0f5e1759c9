"""Floor plan: duplicates merge, faces pair into thick walls, exports reopen with their tools."""

import json
import os
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import shapely
import yaml

from floorscan.floorplan import EXPORT_FORMATS, FLOORPLAN_FORMATS, floorplan_outputs
from floorscan.floorplan.dxf import DXF_LAYERS
from floorscan.floorplan.fit import fit_groups, fit_segments
from floorscan.floorplan.georeference import Georeference, lonlat_to_map, map_to_lonlat
from floorscan.floorplan.merge import merge_segments
from floorscan.floorplan.metadata import PlanMetadata
from floorscan.floorplan.pairing import pair_faces
from floorscan.core.config import stage_params
from floorscan.floorplan.params import WORKFLOW_KEYS, FloorplanParams
from floorscan.floorplan.plan import FloorPlan, build_floorplan
from floorscan.floorplan.writer import FloorplanWriter, write_floorplan
from floorscan.walls.cluster import cluster_ransac
from floorscan.walls.ransac import ransac
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


def test_faces_a_thick_wall_apart_pair_where_the_map_shows_its_body_occupied():
    from floorscan.core.occupancy_classes import grid_of_classes
    from floorscan.floorplan.pairing import THICK_WALL_MAX_M

    # a map with walls 0.5 m thick: A (y 0..0.5, x 0..4) meets a wall whose face runs
    # along x 4.2, and a partition (x 2) joins A to B (y 2..2.5); a rack 0.55 m deep
    # stands free (y 4..4.55, x 0..3); two shelves 0.55 m apart have the floor between
    # them seen free (y 6..6.05 and 6.55..6.6)
    r = 0.05
    occupied = np.zeros((160, 120), dtype=bool)  # rows: y -1..7, cols: x -1..5
    occupied[20:30, 20:100] = occupied[60:70, 20:100] = True  # A, B
    occupied[30:60, 59:61] = True  # the partition
    occupied[100:111, 20:80] = True  # the rack
    occupied[140, 20:100] = occupied[151, 20:100] = True  # the shelves
    occupied[:, 104:110] = True  # the wall A meets
    grid = grid_of_classes(occupied, ~occupied, (-1.0, -1.0), r)
    faces = np.array([[0, 0, 4, 0], [0, 0.5, 4, 0.5], [4.2, -1, 4.2, 1.5], [0, 2.0, 4, 2.0], [0, 2.5, 4, 2.5],
                      [2, 0.5, 2, 2], [0, 4.0, 3, 4.0], [0, 4.55, 3, 4.55], [0, 6.0, 4, 6.0], [0, 6.55, 4, 6.55]], dtype=float)  # fmt: skip
    assert 0.55 < THICK_WALL_MAX_M
    axes, thick, wall_of_face = pair_faces(faces, np.ones(len(faces)), FloorplanParams(), grid)
    assert wall_of_face.tolist() == [0, 0, 2, 1, 1, 3, 4, 5, 6, 7]
    np.testing.assert_allclose(thick[:2], [0.5, 0.5])
    np.testing.assert_allclose(axes[:2], [[0, 0.25, 4, 0.25], [0, 2.25, 4, 2.25]], atol=1e-9)
    # without a grid (a recording's faces: a wall's inside is never seen) and beyond
    # the thickest wall, the faces stay apart
    assert len(set(pair_faces(faces, np.ones(len(faces)), FloorplanParams())[2].tolist())) == len(faces)
    wide = faces.copy()
    wide[[1, 4], 1::2] += 0.2
    assert len(set(pair_faces(wide, np.ones(len(faces)), FloorplanParams(), grid)[2].tolist())) == len(faces)


def test_bad_config_and_columns_are_named():
    from floorscan.core.config import ConfigError

    with pytest.raises(ConfigError, match=r"floorplan\.merge_angel_deg: unknown key"):
        write_floorplan(pd.DataFrame(), {"merge_angel_deg": 3}, {})
    with pytest.raises(KeyError, match="x0"):
        build_floorplan(pd.DataFrame({"a": [1]}))
    with pytest.raises(ValueError, match="pair_min_m"):
        FloorplanParams(pair_min_m=0.5, pair_max_m=0.4)
    with pytest.raises(ValueError, match="dxf_version"):
        FloorplanParams(dxf_version="R14")
    with pytest.raises(ValueError, match="georeference.lat"):
        FloorplanParams(georeference={"lat": 90.0, "lon": 8.0})
    with pytest.raises(ValueError, match="georeference.lon"):
        FloorplanParams(georeference={"lat": 50.0, "lon": 181.0})
    with pytest.raises(ConfigError, match=r"georeference\.lat: missing"):
        FloorplanParams(georeference={"lon": 8.0})
    with pytest.raises(ConfigError, match=r"georeference\.heading: unknown key"):
        FloorplanParams(georeference={"lat": 50.0, "lon": 8.0, "heading": 3.0})


def test_schema_defaults_agree_with_floorplan_params():
    """The options' defaults are the schema's, the other fields' the named constants."""
    from floorscan.floorplan import free_space, params, room_space

    schema = yaml.safe_load((REPO / "workflow/schemas/floorplan.schema.yaml").read_text())["properties"]
    defaults = {k: v.get("default") for k, v in schema.items()}  # georeference: none, unset
    # the workflow's key: the recommended plan's extractor
    assert {k: defaults.pop(k) for k in WORKFLOW_KEYS} == {"extractor": "map"}
    assert defaults.pop("rooms") == {}
    rooms = vars(FloorplanParams().rooms)
    for key, prop in schema["rooms"]["properties"].items():
        assert rooms.pop(key) == prop["default"]
    assert rooms == {k: getattr(room_space, k.upper()) for k in rooms}
    structure = vars(FloorplanParams().structure)
    assert structure == {k: getattr(free_space, k.upper()) for k in structure}
    plan = {f: getattr(FloorplanParams(), f) for f in FloorplanParams.__dataclass_fields__ if f not in ("structure", "rooms")}
    assert {k: plan.pop(k) for k in defaults} == defaults
    assert plan == {k: getattr(params, k.upper()) for k in plan}
    assert stage_params(FloorplanParams, {"extractor": "cluster_ransac"}) == FloorplanParams()


def test_export_registry_names_the_formats_of_the_schema():
    """FLOORPLAN_FORMATS is the registry's; the evaluation grid's formats are some of
    them; a plan's files are its stem and each format's suffix."""
    from floorscan.floorplan import EVALUATION_FORMATS

    assert FLOORPLAN_FORMATS == tuple(EXPORT_FORMATS) and {"geojson", "svg", "dxf", "ifc"} <= set(FLOORPLAN_FORMATS)
    assert EVALUATION_FORMATS == ("svg",)
    assert floorplan_outputs("r/floorplan", ["svg", "geojson"]) == {"svg": "r/floorplan.svg", "geojson": "r/floorplan.geojson"}
    with pytest.raises(KeyError, match="pdf"):
        floorplan_outputs("r/floorplan", ["pdf"])
    with pytest.raises(KeyError, match="pdf"):
        write_floorplan(pd.DataFrame({c: [0.0] for c in ("x0", "y0", "x1", "y1")}), {}, {"pdf": "p.pdf"})


def test_candidate_pairs_equal_shapely_dwithin():
    import shapely

    from floorscan.floorplan.candidates import candidate_pairs

    rng = np.random.default_rng(7)
    p0 = rng.uniform(0, 6, (300, 2))
    ang = rng.choice([0.0, np.pi / 2, rng.uniform(0, np.pi)], 300)
    seg = np.hstack([p0, p0 + rng.uniform(0.1, 2.0, (300, 1)) * np.c_[np.cos(ang), np.sin(ang)]])
    seg[:20] = seg[20:40] + [0.0, 0.3, 0.0, 0.3]  # parallel pairs exactly 0.3 m apart
    lines = shapely.linestrings(seg.reshape(-1, 2, 2))
    for dist in (0.05, 0.3):
        i, j = shapely.STRtree(lines).query(lines, predicate="dwithin", distance=dist)
        want = sorted(zip(*(a[i < j] for a in (i, j))))
        got = list(zip(*candidate_pairs(seg, dist)))
        assert got == want and len(want) > 50
    i, j = candidate_pairs(seg, 0.3, np.radians(3.0))
    d = np.abs(np.arctan2(*(seg[i, 2:] - seg[i, :2]).T[::-1]) - np.arctan2(*(seg[j, 2:] - seg[j, :2]).T[::-1])) % np.pi
    assert (np.minimum(d, np.pi - d) <= np.radians(3.0) + 1e-12).all() and len(i) > 10


def test_merge_components_are_numbered_by_smallest_node():
    """The merge numbers its faces as SciPy numbers connected components (the order of
    their smallest segment), which the merged faces' order depends on."""
    from floorscan.floorplan.merge import _components

    # Components {0}, {1, 3, 5} (a chain 5-3-1), {2, 4}, {6}; numbered by smallest node.
    labels = _components(7, np.array([5, 3, 2]), np.array([3, 1, 4]))
    assert labels.tolist() == [0, 1, 2, 1, 2, 1, 3] and labels.dtype == np.int64
    chain = np.arange(999)
    assert (_components(1000, chain[::-1], chain[::-1] + 1) == 0).all()
    assert _components(3, np.empty(0, int), np.empty(0, int)).tolist() == [0, 1, 2]


def test_candidate_pairs_by_direction_bins_equal_dwithin_and_angle():
    """Binned by direction (with the wrap at 0 / 180 degrees), the candidates are
    exactly the dwithin pairs within the angle."""
    import shapely

    from floorscan.floorplan.candidates import angle_diff, axial_angle, candidate_pairs

    rng = np.random.default_rng(11)
    p0 = rng.uniform(0, 5, (400, 2))
    ang = rng.choice([0.0, np.pi / 2, np.pi - 0.01, rng.uniform(0, np.pi)], 400) + rng.normal(0, 0.03, 400)
    seg = np.hstack([p0, p0 + rng.uniform(0.1, 2.0, (400, 1)) * np.c_[np.cos(ang), np.sin(ang)]])
    lines = shapely.linestrings(seg.reshape(-1, 2, 2))
    for dist, max_deg in ((0.3, 3.0), (0.05, 1.0), (0.3, 20.0), (0.3, 80.0)):
        i, j = shapely.STRtree(lines).query(lines, predicate="dwithin", distance=dist)
        a = axial_angle(seg)
        keep = (i < j) & (angle_diff(a[i], a[j]) <= np.radians(max_deg))
        want = sorted(zip(i[keep].tolist(), j[keep].tolist()))
        got = list(zip(*(x.tolist() for x in candidate_pairs(seg, dist, np.radians(max_deg)))))
        assert got == want and len(want) > 20
        if max_deg == 3.0:  # 59 direction bins: pairs across the 0/180 degree wrap are found
            across = [(p, q) for p, q in want if abs(a[p] - a[q]) > np.pi / 2]
            assert across


def test_merge_skips_connected_pairs_without_changing_faces(monkeypatch):
    """Testing the candidates a few at a time and skipping pairs already connected
    gives the faces that testing all of them gives."""
    import floorscan.floorplan.merge as fp

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


def test_first_merge_pass_prepared_once_gives_every_subsets_faces():
    """The merge's first pass prepared for the whole set (every candidate pair tested
    once) gives each subset the faces, weights and labels of merging it alone: the
    first k scans of an ordering, a subset where nothing merges, and an empty one."""
    from floorscan.floorplan.merge import FirstMergePass

    rng = np.random.default_rng(11)
    walls = np.array([[0, 0, 6, 0], [0, 0.2, 6, 0.2], [6.5, -1, 6.5, 4], [0, 3, 3, 3.02], [4.5, 3.5, 4.5, 6]])
    scan = np.repeat(np.arange(40), len(walls))
    t = np.sort(rng.uniform(0, 1, (len(scan), 2)), axis=1)
    t[:, 1] = np.maximum(t[:, 1], t[:, 0] + 0.2)
    a, b = walls[np.tile(np.arange(len(walls)), 40), :2], walls[np.tile(np.arange(len(walls)), 40), 2:]
    seg = np.hstack([a + t[:, :1] * (b - a), a + np.minimum(t[:, 1:], 1) * (b - a)]) + rng.normal(0, 0.01, (len(scan), 4))
    w = rng.integers(20, 200, len(scan)).astype(float)
    first = FirstMergePass(seg)
    order = rng.permutation(40)
    subsets = [np.isin(scan, order[:k]) for k in (1, 2, 5, 17, 40)]
    subsets += [np.arange(len(scan)) == 3, np.zeros(len(scan), bool), scan == 0]
    n_faces = []
    for rows in subsets:
        want = merge_segments(seg[rows], w[rows])
        got = merge_segments(seg[rows], w[rows], first_groups=first.groups(rows))
        for x, y in zip(got, want):
            np.testing.assert_array_equal(x, y)
        n_faces.append(len(want[0]))
    assert n_faces[4] == 5 and n_faces[5] == 1 and n_faces[6] == 0 and n_faces[7] == 5
    assert FirstMergePass(seg, max_pairs=10).groups(subsets[0]) is None


def test_ifc_guid_list_equals_uuid5_compressed_by_ifcopenshell():
    """The batched GlobalIds are ifcopenshell.guid.compress(uuid5(ns, str(i)).hex)."""
    import uuid

    import ifcopenshell.guid

    from floorscan.floorplan.ifc import _ifc_guid_list

    for name in ("hallways3d random ransac k5", "O'Brien's plan", "é"):
        ns = uuid.uuid5(uuid.NAMESPACE_URL, f"floorscan:{name}")
        ids = _ifc_guid_list(name, 1200)
        assert ids == [ifcopenshell.guid.compress(uuid.uuid5(ns, str(i)).hex) for i in range(1200)]
        assert len(set(ids)) == 1200 and all(len(g) == 22 for g in ids)
    assert _ifc_guid_list("x", 0) == []


def test_candidate_pairs_by_direction_bins_far_from_the_origin():
    """The one-query binned search (each bin its own stretch of x) finds exactly the
    dwithin pairs within the angle also at UTM-sized coordinates, with pairs exactly
    at the distance and across the 0/180 degree wrap."""
    import shapely

    from floorscan.floorplan.candidates import angle_diff, axial_angle, candidate_pairs

    rng = np.random.default_rng(12)
    p0 = rng.uniform(0, 40, (500, 2))
    ang = rng.choice([0.0, np.pi / 2, np.pi - 0.005, 0.005], 500) + rng.normal(0, 0.01, 500)
    seg = np.hstack([p0, p0 + rng.uniform(0.5, 3.0, (500, 1)) * np.c_[np.cos(ang), np.sin(ang)]])
    seg[:30] = seg[30:60] + [0.0, 0.25, 0.0, 0.25]  # exactly 0.25 m from a neighbour (same x)
    seg += [500_000.0, 4_000_000.0, 500_000.0, 4_000_000.0]
    lines = shapely.linestrings(seg.reshape(-1, 2, 2))
    a = axial_angle(seg)
    for exact in (True, False):
        i, j = shapely.STRtree(lines).query(lines, predicate="dwithin", distance=0.25)
        keep = (i < j) & (angle_diff(a[i], a[j]) <= np.radians(3.0))
        want = set(zip(i[keep].tolist(), j[keep].tolist()))
        got_i, got_j = candidate_pairs(seg, 0.25, np.radians(3.0), exact=exact)
        got = set(zip(got_i.tolist(), got_j.tolist()))
        assert (got == want) if exact else (got >= want), exact
        assert (got_i < got_j).all() and len(got) == len(got_i)
    assert {(p, p + 30) for p in range(30)} <= want
    assert any(abs(a[p] - a[q]) > np.pi / 2 for p, q in want)


# --------------------------------------------------------------------------------------
# Exports
# --------------------------------------------------------------------------------------

META = {"dataset": "intel", "ordering": "random", "extractor": "ransac", "k": 5}
SVG_NS = {"s": "http://www.w3.org/2000/svg"}


@pytest.fixture(scope="module")
def box_segments():
    """The box room with one 20 cm wall inside, seen by four scans (ransac): 5 walls,
    the inner one with both faces seen."""
    return scans_segments(BOX + THICK, [(2, 1.2), (2, -1.0), (1, 1.5), (3, -1.5)], "ransac")


def signed_area(ring) -> float:
    """Shoelace area of a closed ring: > 0 counter-clockwise."""
    xy = np.asarray(ring, dtype=float)
    return 0.5 * float(np.sum(xy[:-1, 0] * xy[1:, 1] - xy[1:, 0] * xy[:-1, 1]))


def plan_of(rows) -> FloorPlan:
    """A plan of walls (x0, y0, x1, y1, thickness_m, height_m, paired), no faces."""
    x0, y0, x1, y1, t, h, paired = (list(c) for c in zip(*rows))
    walls = pd.DataFrame({
        "wall_id": np.arange(len(rows), dtype=np.int32), "x0": x0, "y0": y0, "x1": x1, "y1": y1,
        "length_m": np.hypot(np.subtract(x1, x0), np.subtract(y1, y0)), "thickness_m": t, "height_m": h,
        "paired": paired, "n_faces": [2 if p else 1 for p in paired], "n_segments": 3, "n_inliers": 50,
    })  # fmt: skip
    columns = ("face_id", "wall_id", "x0", "y0", "x1", "y1", "length_m", "n_segments", "n_inliers")
    faces = pd.DataFrame({c: pd.Series(dtype="int32" if c in columns[:2] else "float64") for c in columns})
    return FloorPlan(walls=walls, faces=faces)


def test_georeference_puts_a_point_100_m_east_where_the_ellipsoid_says():
    """(lat 50, lon 8): a degree of longitude is 71.696 km, of latitude 111.229 km
    (WGS84, published tables): 100 m east is 100 / 71696 degree of longitude."""
    east_of_x_north = map_to_lonlat([0.0], [-100.0], Georeference(50.0, 8.0, 0.0))  # +x north, +y west
    east_of_x_east = map_to_lonlat([100.0], [0.0], Georeference(50.0, 8.0, 90.0))  # +x east
    for lon, lat in (east_of_x_north, east_of_x_east):
        assert lon[0] - 8.0 == pytest.approx(100.0 / 71_696.0, rel=1e-5)  # the tables' 5 digits
        assert abs(lon[0] - 8.0013948) < 1e-7 and lat[0] == pytest.approx(50.0, abs=1e-12)
    lon, lat = map_to_lonlat([100.0], [0.0], Georeference(50.0, 8.0, 0.0))  # 100 m north
    assert lat[0] - 50.0 == pytest.approx(100.0 / 111_229.0, rel=1e-5) and lon[0] == pytest.approx(8.0, abs=1e-12)
    # heading 30: +x points 30 degrees east of north
    lon, lat = map_to_lonlat([100.0], [0.0], Georeference(-33.9, 151.2, 30.0))
    x, y = lonlat_to_map(lon, lat, Georeference(-33.9, 151.2, 30.0))
    np.testing.assert_allclose([x[0], y[0]], [100.0, 0.0], atol=1e-9)
    assert (lon[0] - 151.2) > 0 and (lat[0] + 33.9) > 0  # north-east of the origin


def test_geojson_rings_counter_clockwise_members_and_one_feature_per_line(tmp_path, box_segments):
    from floorscan.floorplan.geojson import LOCAL_FRAME_WKT, floorplan_geojson

    out = {"geojson": tmp_path / "p.geojson"}
    plan = write_floorplan(box_segments, {}, out, **META, timestamp=1_600_000_000.7)
    text = out["geojson"].read_text()
    lines = text.splitlines()
    n = len(plan.walls)
    assert n == 5 and len(lines) == 2 * n + len(plan.faces) + 2 and lines[-1] == "]}"
    doc = json.loads(text)
    assert doc == floorplan_geojson(plan, PlanMetadata(**META, timestamp=1_600_000_000.7))
    assert lines[0].startswith('{"type": "FeatureCollection", "crs": ') and lines[0].endswith('"features": [')
    assert doc["crs"] == {"type": "name", "properties": {"name": LOCAL_FRAME_WKT}}
    assert LOCAL_FRAME_WKT.startswith("LOCAL_CS[") and 'UNIT["metre",1]' in LOCAL_FRAME_WKT
    member = doc["floorscan"]
    assert {k: member[k] for k in ("frame", "units", "dataset", "ordering", "extractor", "k", "n_walls")} == {
        "frame": "map", "units": "metres", "dataset": "intel", "ordering": "random", "extractor": "ransac",
        "k": "5", "n_walls": 5}  # fmt: skip
    assert member["n_walls_both_faces"] == 1 and member["n_faces"] == len(plan.faces) == 6
    assert member["crs"] == "local engineering frame of the recording" and member["georeference"] is None
    assert member["time_stamp"] == "2020-09-13T12:26:40+00:00"  # 1.6e9 s, the fraction dropped
    kinds = pd.Series([f["properties"]["kind"] for f in doc["features"]]).value_counts().to_dict()
    assert kinds == {"axis": n, "footprint": n, "face": len(plan.faces)}
    footprints = [f["geometry"] for f in doc["features"] if f["properties"]["kind"] == "footprint"]
    areas = [signed_area(g["coordinates"][0]) for g in footprints]
    assert all(a > 0 for a in areas)  # RFC 7946: outer rings counter-clockwise
    np.testing.assert_allclose(sorted(areas), sorted(shapely.area(plan.footprints())), atol=1e-4)
    first = json.loads(lines[1].rstrip(","))
    x0, y0, x1, y1 = plan.walls.loc[0, ["x0", "y0", "x1", "y1"]].to_numpy(float).tolist()
    assert first["geometry"]["coordinates"] == [[round(x0, 5), round(y0, 5)], [round(x1, 5), round(y1, 5)]]
    thick = sorted(f["properties"]["thickness_m"] for f in doc["features"] if f["properties"]["kind"] == "axis")
    assert thick[-1] == pytest.approx(0.20, abs=0.01) and thick[0] == 0.10


def test_georeferenced_geojson_is_wgs84_lon_lat(tmp_path):
    """A 10 m wall along +x from the origin, heading 90 (+x east), at (lat 50, lon 8):
    its axis ends 10 / 71696 degree east; the member says WGS84; no crs member
    (RFC 7946: WGS84 is the default); rings stay counter-clockwise."""
    from floorscan.floorplan.geojson import write_geojson

    geo = {"lat": 50.0, "lon": 8.0, "heading_deg": 90.0}
    plan = plan_of([(0.0, 0.0, 10.0, 0.0, 0.2, 2.5, True), (10.0, 0.0, 10.0, 5.0, 0.1, 2.5, False)])
    write_geojson(plan, tmp_path / "g.geojson", PlanMetadata(**META), geo)
    doc = json.loads((tmp_path / "g.geojson").read_text())
    assert "crs" not in doc
    member = doc["floorscan"]
    assert (member["frame"], member["units"]) == ("WGS84", "degrees")
    assert {k: member["georeference"][k] for k in ("lat", "lon", "heading_deg")} == geo
    axes = [f["geometry"]["coordinates"] for f in doc["features"] if f["properties"]["kind"] == "axis"]
    assert axes[0][0] == [8.0, 50.0]
    assert axes[0][1][0] - 8.0 == pytest.approx(10.0 / 71_696.0, rel=1e-5) and axes[0][1][1] == 50.0
    assert axes[1][1][1] - 50.0 == pytest.approx(5.0 / 111_229.0, rel=1e-5)  # +y is north
    assert axes[0][1] == [round(v, 10) for v in axes[0][1]]  # 1e-10 degree: 11 um
    rings = [f["geometry"]["coordinates"][0] for f in doc["features"] if f["properties"]["kind"] == "footprint"]
    assert len(rings) == 2 and all(signed_area(r) > 0 for r in rings)
    back = lonlat_to_map(*np.array(axes[0]).T, Georeference(**geo))
    np.testing.assert_allclose(np.column_stack(back), [[0.0, 0.0], [10.0, 0.0]], atol=2e-5)


@pytest.mark.parametrize("version", ["R2010", "R12"])
def test_dxf_units_layers_metadata_and_a_clean_audit(tmp_path, box_segments, version):
    from ezdxf import recover

    path = tmp_path / "p.dxf"
    plan = write_floorplan(box_segments, {"dxf_version": version}, {"dxf": path}, **META)
    n = len(plan.walls)
    doc, auditor = recover.readfile(path)
    assert len(auditor.errors) == 0 and len(doc.audit().errors) == 0
    assert doc.dxfversion == {"R2010": "AC1024", "R12": "AC1009"}[version]
    if version == "R2010":
        assert doc.header["$INSUNITS"] == 6 and doc.header["$MEASUREMENT"] == 1  # metres, metric
        custom = dict(doc.header.custom_vars)
        assert custom["floorscan_dataset"] == "intel" and custom["floorscan_units"] == "metres"
    else:
        assert "$INSUNITS" not in doc.header and "$MEASUREMENT" not in doc.header  # R12 has none
    meta = doc.ezdxf_metadata()
    assert [meta[f"floorscan_{k}"] for k in ("dataset", "ordering", "extractor", "k", "n_walls", "frame")] == [
        "intel", "random", "ransac", "5", "5", "map"]  # fmt: skip
    msp = doc.modelspace()
    assert {e.dxf.layer for e in msp} <= {layer.dxf.name for layer in doc.layers}
    assert {layer.dxf.name: layer.dxf.color for layer in doc.layers if layer.dxf.name in DXF_LAYERS} == DXF_LAYERS
    axes = msp.query('LINE[layer=="WALL_AXIS"]')
    assert len(axes) == n
    got = sorted((e.dxf.start.x, e.dxf.start.y, e.dxf.end.x, e.dxf.end.y) for e in axes)
    np.testing.assert_allclose(got, sorted(plan.walls[["x0", "y0", "x1", "y1"]].itertuples(index=False)), atol=1e-6)
    outlines = msp.query(f'{"POLYLINE" if version == "R12" else "LWPOLYLINE"}[layer=="WALL_OUTLINE"]')
    assert len(outlines) == n and all(p.is_closed for p in outlines)
    pts = [[(v.x, v.y) for v in p.points_in_wcs()] if version == "R12" else p.get_points("xy") for p in outlines]
    areas = sorted(signed_area(list(p) + [p[0]]) for p in pts)
    np.testing.assert_allclose(areas, sorted(shapely.area(plan.footprints())), atol=1e-9)  # counter-clockwise
    assert len(msp.query('LINE[layer=="WALL_FACE"]')) == len(plan.faces)


def test_svg_fits_the_window_with_title_scale_bar_legend_and_axes(tmp_path, box_segments):
    path = tmp_path / "p.svg"
    plan = write_floorplan(box_segments, {}, {"svg": path}, **META)
    root = ET.parse(path).getroot()
    assert root.tag == "{http://www.w3.org/2000/svg}svg" and not root.findall(".//s:script", SVG_NS)
    assert (root.get("width"), root.get("height")) == ("100%", "100%")
    vb_w, vb_h = (float(v) for v in root.get("viewBox").split()[2:])
    assert root.find("s:title", SVG_NS).text == "intel random ransac k5"
    subtitle = root.find(".//s:text[@id='subtitle']", SVG_NS).text
    assert "5 walls (1 with both faces seen, 4 with one)" in subtitle
    assert subtitle.endswith("map frame of the recording, metres")  # no time stamp: no date (1970)
    write_floorplan(box_segments, {}, {"svg": path}, **META, timestamp=1_600_000_000.7)
    dated = ET.parse(path).getroot().find(".//s:text[@id='subtitle']", SVG_NS).text
    assert dated.endswith("map frame of the recording, metres \u00b7 2020-09-13T12:26:40+00:00")
    # the plan group: matrix(s 0 0 -s tx ty), y flipped; the plan's longer side 1000 px
    plan_g = root.find(".//s:g[@id='plan']", SVG_NS)
    s, b, c, d, tx, ty = (float(v) for v in plan_g.get("transform")[len("matrix("):-1].split())
    assert (b, c, d) == (0.0, 0.0, -s)
    lo, hi = shapely.total_bounds(plan.footprints()).reshape(2, 2)
    px = np.array([tx + s * lo[0], tx + s * hi[0]])
    py = np.array([ty - s * hi[1], ty - s * lo[1]])
    assert (px > 0).all() and (px < vb_w).all() and (py > 0).all() and (py < vb_h).all()  # nothing cut off
    assert max(px[1] - px[0], py[1] - py[0]) == pytest.approx(1000.0 - 2 * 0.5 * s, abs=0.5)  # fills the canvas
    n_both = len(root.findall(".//s:g[@id='walls']/s:polygon", SVG_NS))
    n_one = len(root.findall(".//s:g[@id='walls-one-face']/s:polygon", SVG_NS))
    assert (n_both, n_one) == (1, 4) and len(root.findall(".//s:g[@id='axes']/s:line", SVG_NS)) == len(plan.walls)
    # the scale bar: a round length, drawn s pixels a metre
    bar = root.find(".//s:g[@id='scale-bar']", SVG_NS)
    label = bar.find("s:text", SVG_NS).text
    length_m = float(label.removesuffix(" m"))
    assert label.endswith(" m") and length_m in (1.0, 2.0, 5.0, 10.0)
    line = bar.find("s:line", SVG_NS)
    assert float(line.get("x2")) - float(line.get("x1")) == pytest.approx(length_m * s, abs=1e-3)
    legend = [t.text for t in root.findall(".//s:g[@id='legend']/s:text", SVG_NS)]
    assert legend == ["wall (both faces seen)", "wall, one face seen (thickness assumed)", "wall axis"]
    axes = [t.text for t in root.findall(".//s:g[@id='frame-axes']/s:text", SVG_NS)]
    assert axes[:2] == ["x", "y"] and root.find(".//s:g[@id='north']", SVG_NS) is None


def test_svg_of_a_long_thin_plan_fits_and_shows_north(tmp_path):
    """A 200 m corridor: drawn 1000 px long, a 20 m scale bar; heading 0 puts north
    along +x, drawn to the right."""
    from floorscan.floorplan.svg import write_svg

    plan = plan_of([(0.0, 0.0, 200.0, 0.0, 0.2, 2.5, True), (0.0, 2.0, 200.0, 2.0, 0.2, 2.5, True)])
    write_svg(plan, tmp_path / "c.svg", PlanMetadata(dataset="corridor"), {"lat": 50.0, "lon": 8.0})
    root = ET.parse(tmp_path / "c.svg").getroot()
    s = float(root.find(".//s:g[@id='plan']", SVG_NS).get("transform")[len("matrix("):].split()[0])
    assert s == pytest.approx(1000.0 / 201.0)
    assert root.find(".//s:g[@id='scale-bar']/s:text", SVG_NS).text == "20 m"  # 200 px budget: 40 m -> 20 m
    north = root.find(".//s:g[@id='north']/s:line", SVG_NS)
    assert float(north.get("x2")) > 0 and float(north.get("y2")) == pytest.approx(0.0, abs=1e-9)


def test_ifc_hierarchy_placements_header_and_validation(tmp_path, box_segments):
    import ifcopenshell
    import ifcopenshell.util.element as ue
    import ifcopenshell.util.placement as up
    from ifcopenshell import validate

    from floorscan.floorplan.metadata import floorscan_version

    path = tmp_path / "p.ifc"
    plan = write_floorplan(box_segments, {"wall_height_m": 2.7}, {"ifc": path}, **META, timestamp=1_700_000_000)
    log = validate.json_logger()
    validate.validate(str(path), log, express_rules=False)
    assert log.statements == []
    model = ifcopenshell.open(str(path))
    fn, fd = model.header.file_name, model.header.file_description
    assert (fn.name, fn.time_stamp, fn.author, fn.organization) == (
        "p.ifc", "2023-11-14T22:13:20+00:00", ("floorscan",), ("floorscan",))  # fmt: skip
    assert fn.originating_system == f"floorscan {floorscan_version()}"
    assert fd.description == (
        "ViewDefinition[DesignTransferView]", "Comment[floorscan floor plan of dataset intel ordering random "
        "extractor ransac k 5]")  # fmt: skip
    assert model.mvd.view_definitions == ["DesignTransferView"]
    assert not model.by_type("IfcOwnerHistory")
    (project,) = model.by_type("IfcProject")
    assert project.Name == "intel random ransac k5" and "dataset intel" in project.Description
    (unit,) = [u for u in model.by_type("IfcSIUnit") if u.UnitType == "LENGTHUNIT"]
    assert (unit.Name, unit.Prefix) == ("METRE", None)
    (site,), (building,), (storey,) = (model.by_type(c) for c in ("IfcSite", "IfcBuilding", "IfcBuildingStorey"))
    assert [ue.get_aggregate(e) for e in (site, building, storey)] == [project, site, building]
    assert site.ObjectPlacement.PlacementRelTo is None
    assert building.ObjectPlacement.PlacementRelTo == site.ObjectPlacement
    assert storey.ObjectPlacement.PlacementRelTo == building.ObjectPlacement
    walls = model.by_type("IfcWall")
    assert len(walls) == len(plan.walls) == 5
    for wall, want in zip(walls, plan.walls.itertuples(index=False)):
        assert wall.ObjectPlacement.PlacementRelTo == storey.ObjectPlacement
        assert ue.get_container(wall) == storey
        m = up.get_local_placement(wall.ObjectPlacement)
        np.testing.assert_allclose(m[:3, 3], [want.x0, want.y0, 0.0], atol=1e-12)
        along = np.array([want.x1 - want.x0, want.y1 - want.y0, 0.0]) / want.length_m
        np.testing.assert_allclose(m[:3, 0], along, atol=1e-12)
        body, axis = wall.Representation.Representations
        assert (body.RepresentationIdentifier, body.RepresentationType) == ("Body", "SweptSolid")
        solid = body.Items[0]
        assert solid.Depth == pytest.approx(2.7)
        assert solid.Position.Location.Coordinates == pytest.approx((0.0, -want.thickness_m / 2, 0.0))
        assert solid.SweptArea.OuterCurve.Points.CoordList[2] == pytest.approx((want.length_m, want.thickness_m))
        assert (axis.RepresentationIdentifier, axis.RepresentationType) == ("Axis", "Curve2D")
        np.testing.assert_allclose(axis.Items[0].Points.CoordList, [[0.0, 0.0], [want.length_m, 0.0]], atol=1e-12)
        q = ue.get_psets(wall)["Qto_WallBaseQuantities"]
        assert (q["Length"], q["Width"], q["Height"]) == pytest.approx((want.length_m, want.thickness_m, 2.7))
        assert wall.Description == ("both faces seen" if want.paired else "one face seen, thickness assumed")


def test_ifc_georeference_sets_site_latitude_and_true_north(tmp_path):
    import ifcopenshell
    from ifcopenshell import validate

    from floorscan.floorplan.ifc import write_ifc

    plan = plan_of([(0.0, 0.0, 4.0, 0.0, 0.1, 2.5, False)])
    geo = {"lat": -33.5, "lon": 151.25, "heading_deg": 90.0}
    write_ifc(plan, tmp_path / "g.ifc", "O'Brien's plan", georeference=geo)
    log = validate.json_logger()
    validate.validate(str(tmp_path / "g.ifc"), log, express_rules=False)
    assert log.statements == []
    model = ifcopenshell.open(str(tmp_path / "g.ifc"))
    assert model.by_type("IfcProject")[0].Name == "O'Brien's plan"
    site = model.by_type("IfcSite")[0]
    assert site.RefLatitude == (-33, -30, 0, 0) and site.RefLongitude == (151, 15, 0, 0)
    north = model.by_type("IfcGeometricRepresentationContext", include_subtypes=False)[0].TrueNorth.DirectionRatios
    np.testing.assert_allclose(north, [0.0, 1.0], atol=1e-12)  # +x east: north is +y


def test_exports_stamp_source_date_epoch_never_the_clock(tmp_path, box_segments, monkeypatch):
    from floorscan.floorplan.metadata import export_time

    outputs = {f: tmp_path / f"p.{f}" for f in ("geojson", "ifc")}

    def stamps():
        gj = json.loads(outputs["geojson"].read_text())["floorscan"]["time_stamp"]
        ifc = next(line for line in outputs["ifc"].read_text().splitlines() if line.startswith("FILE_NAME("))
        return gj, ifc.split(",")[1].strip("'")

    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
    writer = FloorplanWriter({})
    writer.write(box_segments, outputs, **META)
    assert stamps() == ("1970-01-01T00:00:00+00:00",) * 2
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    writer.write(box_segments, outputs, **META)
    assert stamps() == ("2023-11-14T22:13:20+00:00",) * 2
    writer.write(box_segments, outputs, **META, timestamp=86_400.9)  # the argument wins
    assert stamps() == ("1970-01-02T00:00:00+00:00",) * 2
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "yesterday")
    with pytest.raises(ValueError, match="SOURCE_DATE_EPOCH"):
        writer.write(box_segments, outputs, **META)
    assert export_time(-1.5) == -2


@pytest.mark.parametrize(
    "cfg", [{}, {"dxf_version": "R12", "georeference": {"lat": 47.37, "lon": 8.54, "heading_deg": 12.5}}]
)
def test_same_input_gives_byte_identical_files(tmp_path, box_segments, cfg, monkeypatch):
    monkeypatch.delenv("SOURCE_DATE_EPOCH", raising=False)
    for run in ("a", "b"):
        out = {f: tmp_path / run / f"plan.{f}" for f in FLOORPLAN_FORMATS}
        FloorplanWriter(cfg).write(box_segments, out, **META, timestamp=1_650_000_000)
    for f in FLOORPLAN_FORMATS:
        first, again = (tmp_path / run / f"plan.{f}" for run in ("a", "b"))
        assert first.read_bytes() == again.read_bytes(), f
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == sorted(f"plan.{f}" for f in FLOORPLAN_FORMATS)


def test_plan_depends_on_the_scans_not_their_ranking_and_a_repeat_is_reused(tmp_path, box_segments):
    """Every ordering's k = all holds the same scans in another order: the same plan.
    The writer reuses it (and its IFC model) and writes each export with the new
    plan's metadata: every file equals a fresh export of that plan and metadata."""
    segs = box_segments
    reranked = pd.concat([segs[segs.scan_id == s] for s in (2, 0, 3, 1)], ignore_index=True)
    assert not reranked["scan_id"].is_monotonic_increasing
    a, b = build_floorplan(segs), build_floorplan(reranked)
    pd.testing.assert_frame_equal(a.walls, b.walls)
    pd.testing.assert_frame_equal(a.faces, b.faces)

    writer = FloorplanWriter({})
    out = {run: {f: tmp_path / run / f"plan.{f}" for f in FLOORPLAN_FORMATS} for run in ("first", "again", "fresh")}
    meta_first = {**META, "ordering": "random", "k": "all"}
    meta_again = {**META, "ordering": "wall_coverage", "k": "all"}
    assert writer.write(segs, out["first"], **meta_first)[1] is False
    plan, reused = writer.write(reranked, out["again"], **meta_again)
    assert reused is True
    pd.testing.assert_frame_equal(plan.walls, a.walls)
    write_floorplan(reranked, {}, out["fresh"], **meta_again)
    for f in FLOORPLAN_FORMATS:
        assert out["again"][f].read_bytes() == out["fresh"][f].read_bytes(), f
        assert out["again"][f].read_bytes() != out["first"][f].read_bytes(), f  # each names its ordering
    assert json.loads(out["again"]["geojson"].read_text())["floorscan"]["ordering"] == "wall_coverage"
    # the name given (scripts/floorplan.py passes one) titles the SVG and the IFC project
    writer.write(segs, {"svg": tmp_path / "named.svg"}, name="intel random ransac kall")
    assert "<title>intel random ransac kall</title>" in (tmp_path / "named.svg").read_text()
    # another scan set is built anew
    assert writer.write(segs[segs.scan_id != 3], {"geojson": tmp_path / "fewer.geojson"}, **META)[1] is False


def test_empty_segments_write_an_empty_plan(tmp_path):
    import ezdxf.recover
    import ifcopenshell
    from ifcopenshell import validate

    empty = pd.DataFrame({c: pd.Series(dtype="float64") for c in ("x0", "y0", "x1", "y1", "rmse_m")})
    out = {f: tmp_path / f"e.{f}" for f in FLOORPLAN_FORMATS}
    plan = write_floorplan(empty.assign(n_inliers=pd.Series(dtype="int32")), None, out, **META)
    assert len(plan.walls) == 0
    doc = json.loads(out["geojson"].read_text())
    assert doc["features"] == [] and doc["floorscan"]["n_walls"] == 0
    assert len(ifcopenshell.open(str(out["ifc"])).by_type("IfcWall")) == 0
    log = validate.json_logger()
    validate.validate(str(out["ifc"]), log, express_rules=False)
    assert log.statements == []
    dxf, auditor = ezdxf.recover.readfile(out["dxf"])
    assert len(auditor.errors) == 0 and len(dxf.modelspace()) == 0
    root = ET.parse(out["svg"]).getroot()
    assert "0 walls" in root.find(".//s:text[@id='subtitle']", SVG_NS).text


def test_footprint_geojson_equals_shapely_to_geojson_oriented_and_rounded():
    """Footprint coordinates from the rings equal shapely.to_geojson's of the
    counter-clockwise polygon, read and rounded."""
    from floorscan.floorplan.geojson import _round_coords, floorplan_geojson

    rng = np.random.default_rng(3)
    n = 200
    p0 = rng.uniform(-30, 30, (n, 2))
    p1 = p0 + rng.normal(0, 3, (n, 2))
    p1[0] = p0[0]  # a zero-length wall: an empty footprint, no footprint feature
    plan = plan_of([(*a, *b, t, 2.5, True) for a, b, t in zip(p0.tolist(), p1.tolist(), rng.uniform(0.05, 0.4, n))])
    feats = [f for f in floorplan_geojson(plan)["features"] if f["properties"]["kind"] == "footprint"]
    polys = shapely.orient_polygons(plan.footprints(), exterior_cw=False)
    assert polys[0].is_empty and [f["properties"]["wall_id"] for f in feats] == list(range(1, n))
    for f, poly in zip(feats, polys[1:]):
        assert f["geometry"] == _round_coords(json.loads(shapely.to_geojson(poly)))
        assert len(f["geometry"]["coordinates"][0]) == 5 and signed_area(f["geometry"]["coordinates"][0]) > 0


@pytest.mark.slow
def test_dxf_bytes_do_not_depend_on_the_hash_seed(tmp_path):
    """ezdxf orders its CLASSES section by a set of entity types; the writer sorts it, so
    the same plan gives the same DXF in any process (seed 4 differed before)."""
    import subprocess
    import sys

    code = (
        "import sys, pandas as pd\n"
        "from floorscan.floorplan.dxf import write_dxf\n"
        "from floorscan.floorplan.plan import build_floorplan\n"
        "seg = pd.DataFrame({'scan_id': [0, 0, 1, 1], 'x0': [0, 4, 0, 0.0], 'y0': [0, 0, 0.2, 0],\n"
        "                    'x1': [4, 4, 4, 0], 'y1': [0, 0.2, 0.2, 0.2]})\n"
        "write_dxf(build_floorplan(seg), sys.argv[1])\n"
    )
    outs = []
    for seed in ("1", "4", "7"):
        out = tmp_path / f"seed{seed}.dxf"
        env = {**os.environ, "PYTHONHASHSEED": seed}
        subprocess.run([sys.executable, "-c", code, str(out)], check=True, env=env, cwd=REPO)
        outs.append(out.read_bytes())
    assert outs[0] == outs[1] == outs[2] and b"CLASSES" in outs[0]

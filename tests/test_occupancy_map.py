"""An occupancy map as the recording (issue 43): floorscan.ingest.occupancy_map reads a
map_server map or an image as map_server does, refuses bad maps with one message naming
the file, is detected and found in folders; the map's walls are the occupied cells facing
its free space; and the workflow's plan target makes the plan of a map with nothing that
needs scans."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from floorscan.core.datasets import dataset_name
from floorscan.core.io import InputError
from floorscan.ingest.detect import detect_format, recordings_in
from floorscan.core.occupancy_classes import grid_of_classes
from floorscan.core.map_info import map_line
from floorscan.ingest.occupancy_map import is_map_path, read_occupancy_map
from floorscan.walls.map_stage import map_of_grid, wall_cells

from conftest import snakemake

RES = 0.05
MAP_YAML = "image: {image}\nresolution: {res}\norigin: [{x}, {y}, 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"


def two_rooms_image(res=RES, w=10.0, h=5.0, t=0.2, door=0.9, margin=0.5) -> np.ndarray:
    """A map_server image (row 0 at the top) of two rooms side by side, w x h metres
    outside, walls t thick, a door of ``door`` metres in the middle wall; unknown around."""
    width, height = int(round((w + 2 * margin) / res)), int(round((h + 2 * margin) / res))
    x = (np.arange(width) + 0.5) * res - margin
    y = (np.arange(height) + 0.5) * res - margin
    X, Y = np.meshgrid(x, y[::-1])
    inside = (X > 0) & (X < w) & (Y > 0) & (Y < h)
    wall = inside & ((X < t) | (X > w - t) | (Y < t) | (Y > h - t) | (np.abs(X - w / 2) < t / 2))
    wall &= ~((np.abs(X - w / 2) < t / 2 + 1e-9) & (np.abs(Y - h / 2) < door / 2))
    img = np.full((height, width), 205, np.uint8)
    img[inside] = 254
    img[wall] = 0
    return img


def write_map(folder: Path, img: np.ndarray, name="floor", origin=(-0.5, -0.5), extra="") -> Path:
    Image.fromarray(img).save(folder / f"{name}.pgm")
    yaml = folder / f"{name}.yaml"
    yaml.write_text(MAP_YAML.format(image=f"{name}.pgm", res=RES, x=origin[0], y=origin[1]) + extra)
    return yaml


# ------------------------------------------------------------------ reading


def test_yaml_map_reads_as_map_server(tmp_path):
    img = np.full((4, 6), 254, np.uint8)
    img[0, :] = 0  # the top row: the largest y
    img[3, 5] = 205
    yaml = write_map(tmp_path, img, origin=(1.0, -2.0))
    grid, info = read_occupancy_map(yaml)
    assert grid.shape == (4, 6) and grid.resolution_m == RES
    np.testing.assert_allclose(grid.origin_xy, [1.0, -2.0])
    assert grid.occupied()[3].all() and not grid.occupied()[:3].any()  # row 3 of the grid is the image's top
    assert not grid.free()[0, 5] and not grid.occupied()[0, 5]  # the bottom-right pixel is unknown
    assert (info.n_occupied, info.n_free, info.n_unknown) == (6, 17, 1)
    assert info.mode == "trinary" and info.defaults == ("mode",)
    # a cell's centre: origin + (col + 0.5, row + 0.5) * resolution
    np.testing.assert_allclose(grid.cell_centres(grid.occupied())[0], [1.0 + 0.025, -2.0 + 3.5 * RES])
    assert grid.structure().sum() == 6 and grid.scan_xy is None
    assert "6 x 4 cells of 0.05 m" in map_line(info)


def test_modes_negate_alpha_and_bare_image(tmp_path):
    img = np.array([[0, 128, 254], [60, 200, 255]], np.uint8)
    Image.fromarray(img).save(tmp_path / "m.pgm")
    base = "image: m.pgm\nresolution: 0.1\norigin: [0, 0, 0]\n"
    cases = {
        # occ = (255 - v) / 255: 0 -> 1, 128 -> 0.50, 254 -> 0.004, 60 -> 0.76, 200 -> 0.22, 255 -> 0
        "mode: trinary\n": ([[1, 0, 0], [1, 0, 0]], [[0, 0, 1], [0, 0, 1]]),
        "mode: scale\n": ([[1, 0, 0], [1, 0, 0]], [[0, 0, 1], [0, 0, 1]]),
        "mode: trinary\nnegate: 1\n": ([[0, 0, 1], [0, 1, 1]], [[1, 0, 0], [0, 0, 0]]),
    }
    for extra, (occ, free) in cases.items():
        (tmp_path / "m.yaml").write_text(base + extra)
        grid, info = read_occupancy_map(tmp_path / "m.yaml")
        np.testing.assert_array_equal(grid.occupied()[::-1], np.array(occ, bool), err_msg=extra)
        np.testing.assert_array_equal(grid.free()[::-1], np.array(free, bool), err_msg=extra)
    # raw: the shade is percent occupancy (80: occupied, 0 and 10: free), above 100 unknown
    (tmp_path / "m.yaml").write_text(base + "mode: raw\n")
    Image.fromarray(np.array([[0, 80, 255], [60, 10, 255]], np.uint8)).save(tmp_path / "m.pgm")
    grid, _ = read_occupancy_map(tmp_path / "m.yaml")
    np.testing.assert_array_equal(grid.occupied()[::-1], [[0, 1, 0], [0, 0, 0]])
    np.testing.assert_array_equal(grid.free()[::-1], [[1, 0, 0], [0, 1, 0]])
    # grey and alpha: the colours give the shade (map_server would average alpha in); transparent unknown
    la = np.stack([np.array([[0, 254], [0, 254]], np.uint8), np.array([[255, 255], [0, 255]], np.uint8)], -1)
    Image.fromarray(la, "LA").save(tmp_path / "la.png")
    grid, info = read_occupancy_map(tmp_path / "la.png", resolution_m=0.2)
    assert info.resolution_m == 0.2 and tuple(grid.origin_xy) == (0.0, 0.0)
    np.testing.assert_array_equal(grid.occupied()[::-1], [[1, 0], [0, 0]])
    np.testing.assert_array_equal(grid.free()[::-1], [[0, 1], [0, 1]])


def test_a_bare_image_whose_unknown_grey_is_not_205_keeps_its_outside_unknown(tmp_path):
    """A photographed or re-encoded map: its unknown grey spread over 203-214 (part of
    it brighter than map_server's free threshold, a shade of 205.02). Read on its own,
    the free threshold lies midway between the unknown and free shades' modes, so the
    outside stays unknown; the same image with a yaml keeps the yaml's thresholds."""
    rng = np.random.default_rng(7)
    img = two_rooms_image().astype(np.int64)
    grey = img == 205
    img[grey] = np.where(rng.random(int(grey.sum())) < 0.6, 205, rng.integers(203, 215, int(grey.sum())))
    Image.fromarray(img.astype(np.uint8)).save(tmp_path / "photo.png")
    grid, info = read_occupancy_map(tmp_path / "photo.png")
    assert info.free_thresh == pytest.approx((255 - (205 + 254) / 2) / 255)
    free = grid.free()[::-1]
    assert not free[grey].any()
    assert free[img == 254].all()
    yaml = tmp_path / "photo.yaml"
    yaml.write_text(MAP_YAML.format(image="photo.png", res=RES, x=0, y=0))
    _, by_yaml = read_occupancy_map(yaml)
    assert by_yaml.free_thresh == 0.196 and by_yaml.n_free > info.n_free + 0.25 * grey.sum()
    # a black-and-white drawing has no unknown grey: map_server's threshold stays
    bw = np.where(two_rooms_image() == 0, 0, 255).astype(np.uint8)
    Image.fromarray(bw).save(tmp_path / "bw.png")
    assert read_occupancy_map(tmp_path / "bw.png")[1].free_thresh == 0.196


def test_grid_of_classes_keeps_the_classes():
    rng = np.random.default_rng(3)
    labels = rng.integers(0, 3, size=(7, 9))
    grid = grid_of_classes(labels == 1, labels == 2, (0.5, 0.25), 0.1)
    np.testing.assert_array_equal(grid.occupied(), labels == 1)
    np.testing.assert_array_equal(grid.free(), labels == 2)
    np.testing.assert_array_equal(grid.structure(), labels == 1)
    with pytest.raises(ValueError, match="both occupied and free"):
        grid_of_classes(labels == 1, labels >= 1, (0, 0), 0.1)


@pytest.mark.parametrize(
    "case, expected",
    [
        ("missing image", r"bad\.yaml: its image 'nothere\.pgm' does not exist"),
        ("zero resolution", r"bad\.yaml: resolution: expected a positive number of metres a pixel, got 0"),
        ("negative resolution", r"bad\.yaml: resolution: expected a positive number of metres a pixel, got -0\.05"),
        ("unknown mode", r"bad\.yaml: mode 'fancy': expected one of trinary, scale, raw"),
        ("one value", r"one\.png: every pixel has one value, so there is no free space and no wall"),
        ("colour photograph", r"photo\.png: 9\d% of its pixels are coloured, so it is a colour picture, not an occupancy map"),
        ("no free pixel", r"dark\.png: no free pixel"),
        ("thresholds", r"bad\.yaml: expected 0 <= free_thresh < occupied_thresh <= 1"),
        ("not a map yaml", r"bad\.yaml: a yaml without an 'image' key"),
        ("rotated", r"bad\.yaml: origin yaw 0\.3 rad: a rotated map is not supported"),
        ("not an image", r"bad\.pgm: not an image that can be read"),
    ],
)
def test_bad_maps_one_clear_message(tmp_path, case, expected):
    Image.fromarray(two_rooms_image()).save(tmp_path / "ok.pgm")
    bad = tmp_path / "bad.yaml"
    yaml = {
        "missing image": "image: nothere.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n",
        "zero resolution": "image: ok.pgm\nresolution: 0\norigin: [0, 0, 0]\n",
        "negative resolution": "image: ok.pgm\nresolution: -0.05\norigin: [0, 0, 0]\n",
        "unknown mode": "image: ok.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nmode: fancy\n",
        "thresholds": "image: ok.pgm\nresolution: 0.05\norigin: [0, 0, 0]\noccupied_thresh: 0.1\nfree_thresh: 0.5\n",
        "not a map yaml": "name: a config\n",
        "rotated": "image: ok.pgm\nresolution: 0.05\norigin: [0, 0, 0.3]\n",
    }
    path = bad
    if case in yaml:
        bad.write_text(yaml[case])
    elif case == "one value":
        path = tmp_path / "one.png"
        Image.fromarray(np.full((30, 40), 254, np.uint8)).save(path)
    elif case == "colour photograph":
        path = tmp_path / "photo.png"
        Image.fromarray(np.random.default_rng(0).integers(0, 256, (30, 40, 3), dtype=np.uint8)).save(path)
    elif case == "no free pixel":
        path = tmp_path / "dark.png"
        Image.fromarray(np.tile(np.array([0, 128], np.uint8), (30, 20))).save(path)
    elif case == "not an image":
        path = tmp_path / "bad.pgm"
        path.write_bytes(b"P5\n12 x\n")
    with pytest.raises(InputError, match=expected) as info:
        read_occupancy_map(path)
    assert "\n" not in str(info.value)


def test_resolution_only_for_a_bare_image(tmp_path):
    yaml = write_map(tmp_path, two_rooms_image())
    with pytest.raises(InputError, match="resolution_m is for a map image on its own"):
        read_occupancy_map(yaml, resolution_m=0.1)
    with pytest.raises(InputError, match="resolution_m: expected a positive number"):
        read_occupancy_map(tmp_path / "floor.pgm", resolution_m=-1)


# ------------------------------------------------------------------ detection


def test_detection_folders_and_names(tmp_path):
    write_map(tmp_path, two_rooms_image(), "ground")
    Image.fromarray(two_rooms_image()).save(tmp_path / "loose.png")
    (tmp_path / "house.yaml").write_text("building: {name: B}\n")
    (tmp_path / "notes.txt").write_text("hello\n")
    assert detect_format(tmp_path / "ground.yaml") == "map" and detect_format(tmp_path / "loose.png") == "map"
    with pytest.raises(InputError, match="house.yaml: a yaml without an 'image' key"):
        detect_format(tmp_path / "house.yaml")
    assert is_map_path(tmp_path / "ground.yaml") and not is_map_path(tmp_path / "house.yaml")
    recordings, skipped = recordings_in(tmp_path)
    # the image a map yaml names is that map's, not a recording of its own
    assert [p.name for p in recordings] == ["ground.yaml", "loose.png"]
    assert skipped == ["house.yaml", "notes.txt"]
    assert [dataset_name(p) for p in recordings] == ["ground", "loose"]


# ------------------------------------------------------------------ walls


def test_wall_cells_are_the_faces_the_free_space_sees():
    # a room of free cells, walls 3 cells thick, the outside painted occupied (as some
    # maps are drawn), and a grey (unknown) seam of 2 cells between floor and wall
    occ = np.ones((40, 60), bool)
    free = np.zeros_like(occ)
    free[10:30, 10:50] = True
    occ[8:32, 8:52] = False  # the seam
    grid = grid_of_classes(occ, free, (0.0, 0.0), RES)
    cells = wall_cells(grid)
    # the one ring of occupied cells around the seam, nothing of the painted outside
    ring = np.zeros_like(occ)
    ring[7:33, 7:53] = True
    ring[8:32, 8:52] = False
    np.testing.assert_array_equal(cells, ring)
    segments = map_of_grid(grid, None)
    assert len(segments) == 4 and (segments["scan_id"] == -1).all()
    lengths = np.hypot(segments["x1"] - segments["x0"], segments["y1"] - segments["y0"])
    np.testing.assert_allclose(np.sort(lengths), [1.25, 1.25, 2.25, 2.25], atol=0.06)


# ------------------------------------------------------------------ the workflow


@pytest.mark.workflow
def test_map_plan_target(demo_run, tmp_path):
    """The README's map command on a map_server map: the plan with its rooms and door in
    every export, the map as read, the front page and summary.md; nothing that needs
    scans; a bad map fails alone with one clear line and leaves no output."""
    import ezdxf
    import ifcopenshell
    from shapely.geometry import shape

    folder = tmp_path / "my maps"  # a space in the path
    folder.mkdir()
    yaml = write_map(folder, two_rooms_image(), "two_rooms", origin=(-0.5, -0.5))
    res = snakemake(demo_run, "--config", f"path={yaml}")
    assert res.returncode == 0, res.stderr[-3000:]
    # the report's command, pasted into a shell, names the same path (issue 47)
    assert f"--config 'path={yaml}' --report results/report.html\n" in res.stdout
    out = demo_run / "results" / "two_rooms"
    answer = res.stdout[res.stdout.index("two_rooms: floor plan of an occupancy map"):]
    assert "220 x 120 cells of 0.05 m" in answer.splitlines()[0]
    assert "2 rooms, 1 door" in answer and "not from a map:     a map holds no scans" in answer
    for missing in ("selection", "registration.parquet", "poses.parquet", "scans.parquet", "evaluation"):
        assert not (out / missing).exists(), missing
    gj = json.loads((out / "floorplan.geojson").read_text())
    assert gj["floorscan"]["n_rooms"] == 2 and gj["floorscan"]["n_doors"] == 1
    rooms = [shape(f["geometry"]) for f in gj["features"] if f["properties"].get("kind") == "room"]
    assert len(rooms) == 2 and all(r.is_valid for r in rooms)
    # the map frame is map_server's: the rooms lie at the map's metres (inside 0..10 x 0..5)
    assert all(-0.05 < r.bounds[0] and r.bounds[2] < 10.05 and -0.05 < r.bounds[1] and r.bounds[3] < 5.05 for r in rooms)
    np.testing.assert_allclose(sorted(r.centroid.x for r in rooms), [2.5, 7.5], atol=0.1)
    np.testing.assert_allclose([r.centroid.y for r in rooms], [2.5, 2.5], atol=0.1)
    door = next(f for f in gj["features"] if f["properties"].get("kind") == "door")
    assert abs(door["properties"]["width_m"] - 0.9) <= 0.1
    model = ifcopenshell.open(str(out / "floorplan.ifc"))
    assert len(model.by_type("IfcSpace")) == 2 and len(model.by_type("IfcDoor")) == 1
    doc = ezdxf.readfile(out / "floorplan.dxf")
    auditor = doc.audit()
    assert not auditor.has_errors
    assert "origin: [-0.5, -0.5, 0.0]" in (out / "map.yaml").read_text()
    assert "Floor plan of an occupancy map: two_rooms" in (out / "summary.md").read_text()
    assert "What was read" in (out / "front.html").read_text()

    photo = tmp_path / "photo.png"
    Image.fromarray(np.random.default_rng(1).integers(0, 256, (60, 80, 3), dtype=np.uint8)).save(photo)
    res = snakemake(demo_run, "--workflow-profile", "workflow/profiles/default", "--config", f"path={photo}")
    assert res.returncode == 1
    assert "photo: FAILED: its error is the paragraph above; its log: results/photo/logs/ingest.log" in res.stdout
    shown = res.stdout + res.stderr  # the job's log, shown by the profile's show-failed-logs
    assert f"map_ingest failed: {photo}: 99% of its pixels are coloured, so it is a colour picture, not an occupancy map" in shown
    assert not (demo_run / "results" / "photo" / "map").exists() and not (demo_run / "results" / "photo" / "floorplan.svg").exists()


@pytest.mark.workflow
def test_maps_are_the_floors_of_a_building_as_their_own_plans(tmp_path):
    """Two maps named as the floors of one building (docs/running.md's house.yaml block,
    with map files): the building's IFC holds a storey per map at its elevation, each
    with its floor's walls and rooms, and each floor's GeoJSON in results/building is
    the plan tables the floor plan stage wrote (results/<dataset>/plan_tables), the same
    walls, rooms and doors as the map's own answer: the building reads them, it does not
    build them again. Before, a map could not be a floor."""
    import ifcopenshell
    from ifcopenshell.util.element import get_decomposition

    from conftest import copy_workflow
    from floorscan.floorplan.geojson import floorplan_geojson
    from floorscan.floorplan.scans import plan_metadata, read_plan

    wd = copy_workflow(tmp_path / "floorscan")
    folder = tmp_path / "levels"
    folder.mkdir()
    write_map(folder, two_rooms_image(), "level0")
    write_map(folder, two_rooms_image(w=8.0, h=4.0, door=1.2), "level1", origin=(-1.0, 2.0))
    (wd / "house.yaml").write_text(
        "building:\n  name: Map house\n  floors:\n"
        "    - {recording: level0.yaml, storey: Ground floor, elevation_m: 0.0}\n"
        "    - {recording: level1.yaml, storey: First floor, elevation_m: 3.2}\n"
    )
    res = snakemake(wd, "--config", f"path={folder}/", "--configfile", "house.yaml")
    assert res.returncode == 0, res.stderr[-3000:]
    assert "building: results/building/index.html, results/building/building.ifc (2 storeys)" in res.stdout
    model = ifcopenshell.open(str(wd / "results" / "building" / "building.ifc"))
    storeys = {s.Name: s for s in model.by_type("IfcBuildingStorey")}
    assert sorted(storeys) == ["First floor", "Ground floor"] and storeys["First floor"].Elevation == pytest.approx(3.2)
    for ds, storey in (("level0", "Ground floor"), ("level1", "First floor")):
        plan = read_plan(wd / "results" / ds / "plan_tables")
        parts = get_decomposition(storeys[storey])
        assert len(plan.rooms) == 2 and len(plan.doors) == 1, ds
        assert sum(e.is_a("IfcSpace") for e in parts) == 2 and sum(e.is_a("IfcWall") for e in parts) == len(plan.walls)
        own = json.loads((wd / "results" / ds / "floorplan.geojson").read_text())
        floor = json.loads((wd / "results" / "building" / f"{ds}.geojson").read_text())
        tables = floorplan_geojson(plan, plan_metadata(wd / "results" / ds / "plan_tables"))
        assert floor["features"] == json.loads(json.dumps(tables["features"])), ds
        assert [f["properties"] for f in floor["features"]] == [f["properties"] for f in own["features"]], ds
        assert floor["floorscan"]["extractor"] == "map" and floor["floorscan"]["storey"] == storey


def test_rooms_are_a_coverage_on_a_real_robot_map():
    """No two rooms overlap (issue 44): on ROSE^2's map15, five pairs of rooms grown into
    the same door gaps overlapped by 0.002 to 0.024 m2 before the room step gave each
    sliver to one of them."""
    import itertools

    from floorscan.floorplan.params import FloorplanParams
    from floorscan.floorplan.scans import plan_of_scans

    from conftest import SHARED_DATA

    path = SHARED_DATA / "room-maps" / "rose2" / "map15.png"
    if not path.is_file():
        pytest.skip(f"{path} is absent (../shared/data: the room segmentation benchmarks)")
    grid, _ = read_occupancy_map(path)
    rooms = list(plan_of_scans(map_of_grid(grid, None), None, FloorplanParams(), grid).rooms["polygon"])
    assert len(rooms) >= 10
    overlaps = [(i, j, a.intersection(b).area) for (i, a), (j, b) in itertools.combinations(enumerate(rooms), 2)]
    assert max(area for *_, area in overlaps) < 1e-6, [o for o in overlaps if o[2] >= 1e-6]


def test_a_room_ends_at_its_entrance_whatever_the_map_saw_outside(tmp_path):
    """A room of 6.6 x 3.6 m inside walls 0.2 m thick, with a 0.9 m entrance in its
    bottom wall and a fan of free cells the scans saw through it, 0.45 m deep: the room
    reaches into the doorway to the wall's outer face and no further. Before, the
    opening was no cut because only its inside is space (the outside a fan, then
    nothing), and the room ran a cell past the wall, into the fan."""
    from floorscan.floorplan.params import FloorplanParams
    from floorscan.floorplan.scans import plan_of_scans

    image = np.full((120, 160), 205, np.uint8)  # 5 cm pixels: the outside unknown
    image[10:90, 10:150] = 0  # the outer walls
    image[14:86, 14:146] = 255  # the floor
    image[86:90, 40:58] = 255  # the entrance
    for k in range(1, 10):  # the fan seen through it
        image[89 + k, 40 - k : 58 + k] = 255
    path = tmp_path / "entrance.png"
    Image.fromarray(image).save(path)
    grid, _ = read_occupancy_map(path)
    plan = plan_of_scans(map_of_grid(grid, None), None, FloorplanParams(), grid)
    outer_face = (image.shape[0] - 90) * RES  # y of the bottom wall's outer face, metres
    assert len(plan.rooms) == 1
    assert plan.rooms["polygon"].iloc[0].bounds[1] >= outer_face - 1e-6


@pytest.mark.parametrize("shade", [180, 204])
def test_a_wall_drawn_in_grey_divides_the_rooms(tmp_path, shade):
    """A map may draw a wall in a shade its thresholds read as unknown (ipa's maps draw
    some in light grey 170-211): in a map, what is not free bounds the rooms, so a
    partition of that shade, 0.2 m thick with a 0.9 m door, keeps two rooms of 4 x 5 m
    apart. Before, the room step closed the unknown seam over as it closes the
    shadows of a recording, and made one room of 40 m2."""
    from floorscan.floorplan.params import FloorplanParams
    from floorscan.floorplan.scans import plan_of_scans

    image = np.full((140, 220), 205, np.uint8)  # 5 cm pixels: the outside unknown
    image[10:130, 10:210] = 0  # black outer walls, 0.2 m thick
    image[14:114, 14:174] = 255  # 8 m x 5 m of floor (rows: y from the top)
    image[14:114, 92:96] = shade  # the partition, 4 pixels thick
    image[60:78, 92:96] = 255  # its 0.9 m door
    path = tmp_path / "grey_wall.png"
    Image.fromarray(image).save(path)
    grid, _ = read_occupancy_map(path)
    plan = plan_of_scans(map_of_grid(grid, None), None, FloorplanParams(), grid)
    areas = sorted(round(p.area, 1) for p in plan.rooms["polygon"])
    assert len(areas) == 2 and all(19.0 <= a <= 20.5 for a in areas), areas
    assert len(plan.doors) == 1
    assert 0.8 <= float(plan.doors["width_m"].iloc[0]) <= 1.0


def test_the_rays_a_map_holds_beyond_its_walls_are_no_room(tmp_path):
    """A SLAM map marks free the rays its scans cast through windows and glass into the
    outside. Here a 3 m window in the north wall of an 8 m x 5 m room lets a fan of free
    space 5 m deep out, wider than the window: the room ends at the convex hull of the
    map's walls, and no room lies beyond it (before: the room took the fan, 5 m out)."""
    from floorscan.floorplan.params import FloorplanParams
    from floorscan.floorplan.scans import plan_of_scans

    image = np.full((260, 220), 205, np.uint8)  # 5 cm pixels; rows: y from the top
    image[110:250, 10:210] = 0  # black outer walls, 0.2 m thick
    image[114:246, 14:206] = 255  # the room: 9.6 m x 6.6 m of floor
    image[110:114, 80:140] = 255  # a 3 m window in the north wall
    rows, cols = np.mgrid[0:110, 0:220]
    image[:110][(rows >= 10) & (np.abs(cols - 110) <= 30 + (110 - rows) * 0.8)] = 255  # the fan, 5 m out
    path = tmp_path / "fan.png"
    Image.fromarray(image).save(path)
    grid, _ = read_occupancy_map(path)
    plan = plan_of_scans(map_of_grid(grid, None), None, FloorplanParams(), grid)
    north = grid.origin_xy[1] + (260 - 110) * RES  # the outer face of the north wall
    assert len(plan.rooms) == 1
    room = plan.rooms["polygon"].iloc[0]
    assert room.bounds[3] <= north + 0.05, room.bounds
    assert 60.0 <= room.area <= 66.0, room.area

"""The whole workflow on the embedded default dataset, checked on real numbers.

The workflow files are copied to a temporary folder and run there with
``snakemake --cores 2``, so the test never touches the repository's ``results/``.
"""

from pathlib import Path

import numpy as np
import pytest

from conftest import snakemake
from floorscan.core.io import read_table
from floorscan.core.plan_tables import read_plan_tables

pytestmark = [pytest.mark.workflow, pytest.mark.slow]


@pytest.fixture(scope="module")
def default_run(demo_run):
    """The demo's default target, run once for the session (conftest.demo_run)."""
    return demo_run


def test_default_target_runs_and_writes_consistent_tables(default_run):
    wd = default_run
    import yaml

    cfg = yaml.safe_load((wd / "config" / "config.yaml").read_text())
    for ds in cfg["target"]:
        out = wd / "results" / ds
        index = read_table(out / "scan_index.parquet")
        poses = read_table(out / "poses.parquet")
        scans = read_table(out / "scans.parquet")
        assert len(index) > 100
        assert index["n_points"].sum() == len(scans)
        assert poses["scan_id"].tolist() == index["scan_id"].tolist()
        assert poses["valid"].mean() > 0.95
        assert np.isfinite(poses.loc[poses["valid"], ["x", "y", "yaw"]].to_numpy()).all()
        # every rule logs and benchmarks
        for stage in ("ingest", "poses"):
            assert (out / "logs" / f"{stage}.log").stat().st_size > 0
            assert (out / "benchmarks" / f"{stage}.tsv").read_text().startswith("s\t")


def test_rerun_of_one_stage(default_run):
    """`-R poses` reruns poses and not ingest (run --until poses: the stages after it
    would rerun too, which the demo's run already tested; then marked up to date, so
    the session's demo run stays complete for the tests after this one)."""
    res = snakemake(default_run, "-R", "poses", "--until", "poses")
    assert res.returncode == 0, res.stderr[-3000:]
    stats = res.stderr.split("Job stats")[-1].split("Reasons")[0]
    assert "poses" in stats and "ingest" not in stats and "register" not in stats
    assert (default_run / "results" / "demo" / "logs" / "poses.log").stat().st_size > 0
    res = snakemake(default_run, "--touch")
    assert res.returncode == 0, res.stderr[-3000:]
    again = snakemake(default_run, "-n")
    stats = (again.stdout + again.stderr).split("Job stats:")[-1].split("Reasons")[0]
    assert stats.split() == ["job", "count", "-----", "-------", "all", "1", "total", "1"]  # the target rule alone


def test_default_run_selection_walls_and_scores(default_run):
    """On the demo building registration halves the pose error, the walls from all
    scans match the ground truth (issue 6: F1 at 5 cm >= 0.9 with both extractors;
    measured 0.95, the merged floor plan 0.93), the thesis's ordering beats recording
    order at 15 scans, and every floor plan format is written."""
    out = default_run / "results" / "demo"
    reg = read_table(out / "registration.parquet")
    truth = read_table(out / "sim" / "true_poses.parquet")
    poses = read_table(out / "poses.parquet")
    kept = reg[reg["kept"]].merge(truth, on="t_ns", suffixes=("", "_true"))
    prior = poses.set_index("scan_id").loc[kept["scan_id"]]
    err_prior = np.hypot(prior["x"].to_numpy() - kept["x"], prior["y"].to_numpy() - kept["y"])
    err_reg = np.hypot(kept["x_m"] - kept["x"], kept["y_m"] - kept["y"])
    assert len(kept) >= 60
    # pose graph: 7.6 -> 3.1 cm
    assert np.sqrt(np.mean(err_reg**2)) < 0.5 * np.sqrt(np.mean(err_prior**2))

    summary = read_table(out / "orderings" / "summary.parquet").set_index("ordering")
    assert summary.loc["cluster_hull", "k_95"] < summary.loc["sequential", "k_95"] / 2

    m = read_table(out / "metrics.parquet")
    assert set(m["reference_kind"]) == {"ground_truth"}
    assert len(m) == 7 * 2 * 10  # orderings x extractors x k
    mi = m.set_index(["ordering", "extractor", "k"])
    f1 = mi["f1_5cm"]
    for ext in ("ransac", "cluster_ransac"):
        assert f1[("cluster_hull", ext, "15")] > f1[("sequential", ext, "15")] + 0.1
        assert f1[("cluster_hull", ext, "all")] >= 0.9
        assert mi.loc[("cluster_hull", ext, "all"), "plan_f1_5cm"] >= 0.88
        # recall against every face is lower: rooms C and D are only seen through doors
        assert 0.6 < mi.loc[("cluster_hull", ext, "all"), "recall_all_5cm"] < 0.85
    # floorscan.floorplan.EVALUATION_FORMATS (svg); the recommended plan has all four
    assert (out / "evaluation" / "floorplan" / "cluster_hull_cluster_ransac_k15.svg").stat().st_size > 500
    for fmt in ("geojson", "ifc"):
        assert not (out / "evaluation" / "floorplan" / f"cluster_hull_cluster_ransac_k15.{fmt}").exists()
    # what the score stage read: the plan's Parquet tables, the walls of the plan it scored
    plan = read_plan_tables(out / "evaluation" / "plans" / "cluster_hull_cluster_ransac_k15")
    assert mi.loc[("cluster_hull", "cluster_ransac", "15"), "n_floorplan_walls"] == len(plan["walls"]) > 10
    assert set(plan) == {"walls", "faces", "clutter", "junctions", "rooms", "doors"} and plan["rooms"].empty


def test_default_run_reference_map_curves_and_summary(default_run):
    """Issue 21 on the demo: the reference map is written for map_server, every plan
    is scored against it (correctness below 1), and the summary reads k95 for every
    ordering and extractor from the curves: random from 10 seeds, the oracle as the
    bound. Measured: all-scan plan F1 0.932 / 0.935 (cluster_ransac / ransac);
    cluster_hull k95 7 of 76 kept, oracle 4 / 5, random 9.9 +- 4.2 / 10.0 +- 4.1;
    AUC cluster_hull 0.824 / 0.829 against random 0.782 / 0.782."""
    out = default_run / "results" / "demo"
    assert (out / "reference" / "map.pgm").read_bytes().startswith(b"P5\n")
    assert "mode: trinary" in (out / "reference" / "map.yaml").read_text()
    m = read_table(out / "metrics.parquet")
    assert (m["map_correctness_5cm"] < 1).all() and (m["map_correctness_5cm"] > 0.9).all()
    s = read_table(out / "summary.parquet").set_index(["extractor", "ordering"])
    assert set(s.index.get_level_values("ordering")) == {
        "cluster_hull", "convex_hull", "motion_filter", "oracle", "random", "sequential", "surface_coverage",
        "wall_coverage"}
    # issue 22: the default ordering beats random (measured AUC 0.862 / 0.853 against 0.782,
    # k95 4 against 10 +- 4) and the summary says so first
    for ext in ("ransac", "cluster_ransac"):
        assert s.loc[(ext, "wall_coverage"), "auc"] > s.loc[(ext, "random"), "auc"] + 0.05
        assert s.loc[(ext, "wall_coverage"), "k_95"] <= 1.25 * s.loc[(ext, "oracle"), "k_95"]
    assert (out / "summary.md").read_text().count("wall_coverage beats random with") == 2
    for ext in ("ransac", "cluster_ransac"):
        assert s.loc[(ext, "random"), "n_seeds"] == 10 and s.loc[(ext, "random"), "k_95_seed_sd"] > 0
        assert s.loc[(ext, "oracle"), "k95_over_oracle"] == 1.0
        assert s.loc[(ext, "oracle"), "k_95"] <= s.loc[(ext, "cluster_hull"), "k_95"] <= 10
        assert s.loc[(ext, "cluster_hull"), "auc"] > s.loc[(ext, "random"), "auc"] + 0.02
        assert s.loc[(ext, "sequential"), "k_95"] > 40
        assert 0.9 < s.loc[(ext, "cluster_hull"), "f1_all"] < 0.96
    curves = read_table(out / "score" / "curves_ransac.parquet")
    cluster = curves[curves["ordering"] == "cluster_hull"]["k"]
    assert list(cluster[cluster <= 15]) == list(range(1, 16))  # every k up to 20 % of 76
    md = (out / "summary.md").read_text()
    assert md.startswith("# Scan reduction summary: demo") and "**Verdict: GOOD" in md
    assert "cluster_hull beats random with ransac" in md
    assert "<table" in (out / "summary.html").read_text()
    assert (out / "figures" / "floorplan_f1_vs_k.png").stat().st_size > 20_000
    front = (out / "front.html").read_text()  # the report opens on it
    assert "<svg" in front and "wall_coverage" in front and "GOOD" in front and "<table" in front


def test_default_run_writes_the_answer(default_run):
    """Issue 23 on the demo: the scan list of select.k (auto: 99 % of wall_coverage's
    cells; measured 10 of 76 kept scans), the reduced recording that reads back with
    rosbags with one scan message per listed scan, the points as PLY and PCD, and the
    recommended floor plan in four formats that validate."""
    import json

    import ezdxf
    import ifcopenshell
    import ifcopenshell.validate
    import open3d as o3d
    import pandas as pd
    import shapely
    from rosbags.highlevel import AnyReader

    out = default_run / "results" / "demo"
    sel = json.loads((out / "selection" / "selection.json").read_text())
    scans = pd.read_csv(out / "selection" / "scans.csv")
    assert sel["k"] == len(scans) == 10 and sel["n_kept"] == 76 and sel["ordering"] == "wall_coverage"
    assert "99 %" in sel["reason"]
    assert scans["rank"].tolist() == list(range(1, 11)) and scans["time_iso"].str.endswith("Z").all()
    order = read_table(out / "orderings" / "wall_coverage.parquet").sort_values("rank")
    assert scans["scan_id"].tolist() == order["scan_id"].head(10).tolist()
    # the same table for the later stages (the recommended plan reads it), units kept
    table = read_table(out / "selection" / "scans.parquet")
    assert table["scan_id"].tolist() == scans["scan_id"].tolist() and str(table["t_ns"].dtype) == "int64"
    assert np.allclose(table["x_m"], scans["x_m"], atol=1e-6)

    bag = Path(sel["recording"]["path"])
    assert bag.parent == Path("results/demo/selection/recording") and bag.suffix == ".bag"
    with AnyReader([default_run / bag]) as reader:
        counts = {c.topic: c.msgcount for c in reader.connections}
        stamps = [t for c, t, _ in reader.messages(connections=[c for c in reader.connections if c.topic == "/scan"])]
    assert counts["/scan"] == len(scans) and len(stamps) == len(scans)
    assert sel["recording"]["bytes_out"] < 0.25 * sel["recording"]["bytes_in"]

    n_points = sel["n_points"]
    assert n_points > 1000
    for ext in ("ply", "pcd"):
        cloud = o3d.t.io.read_point_cloud(str(out / "selection" / f"points.{ext}"))
        assert len(cloud.point.positions) == n_points

    plan = json.loads((out / "floorplan.geojson").read_text())
    assert plan["floorscan"]["k"] in (10, "10") and plan["floorscan"]["units"] == "metres"
    rings = [shapely.geometry.shape(f["geometry"]) for f in plan["features"] if f["geometry"]["type"] == "Polygon"]
    assert rings and all(shapely.Polygon(p.exterior).area > 0 and p.exterior.is_ccw for p in rings)
    doc = ezdxf.readfile(out / "floorplan.dxf")
    assert doc.header["$INSUNITS"] == 6 and not doc.audit().has_errors
    logger = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(str(out / "floorplan.ifc"), logger)
    assert logger.statements == []
    assert len(ifcopenshell.open(str(out / "floorplan.ifc")).by_type("IfcWall")) >= 8
    assert "<svg" in (out / "floorplan.svg").read_text()
    # the selected scans' occupancy grid as a Nav2 map: the PGM's size is the grid's
    import yaml

    from floorscan.core.occupancy import read_grid

    nav = yaml.safe_load((out / "map.yaml").read_text())
    grid = read_grid(out / "walls" / "map" / "selected_grid.parquet")
    assert nav["image"] == "map.pgm" and nav["resolution"] == 0.05 and nav["mode"] == "trinary"
    assert nav["origin"][:2] == pytest.approx(grid.origin_xy.tolist())
    head = (out / "map.pgm").read_bytes()[:120].split(b"\n")
    assert head[0] == b"P5" and head[2] == f"{grid.shape[1]} {grid.shape[0]}".encode()


def test_default_run_rooms_and_doors(default_run):
    """Issue 34 on the demo (a corridor and four rooms, five doors between them): the
    recommended plan's rooms and doors against the simulator's (evaluation/
    room_scores.csv; measured: 5 of 5 rooms matched, mean IoU 0.95, 5 of 5 doors within
    3 cm of their centre), and in every export: GeoJSON rings valid and counter-
    clockwise, an IfcSpace per room and an IfcDoor per door that validate, DXF layers
    ROOM and DOOR that audit clean."""
    import json

    import ezdxf
    import ifcopenshell
    import ifcopenshell.validate
    import pandas as pd
    import shapely

    out = default_run / "results" / "demo"
    scores = pd.read_csv(out / "evaluation" / "room_scores.csv").set_index("plan")
    rec = scores.loc["recommended"]
    assert rec["n_plan_rooms"] == rec["n_true_rooms"] == 5
    assert rec["room_precision"] == rec["room_recall"] == 1.0 and rec["room_mean_iou"] >= 0.9
    assert rec["n_true_doors"] == 5 and rec["door_recall"] == rec["door_precision"] == 1.0
    assert rec["door_centre_error_m"] <= 0.2
    plan = json.loads((out / "floorplan.geojson").read_text())
    rooms = [f for f in plan["features"] if f["properties"]["kind"] == "room"]
    doors = [f for f in plan["features"] if f["properties"]["kind"] == "door"]
    assert len(rooms) == plan["floorscan"]["n_rooms"] == 5 and len(doors) == plan["floorscan"]["n_doors"] == 5
    kinds = sorted(f["properties"]["room_kind"] for f in rooms)
    assert kinds == ["corridor", "room", "room", "room", "room"]
    for f in rooms:
        poly = shapely.geometry.shape(f["geometry"])
        assert poly.is_valid and poly.exterior.is_ccw and all(not h.is_ccw for h in poly.interiors)
        assert f["properties"]["area_m2"] == pytest.approx(poly.area, rel=1e-3)
    assert all(0.6 <= f["properties"]["width_m"] <= 1.2 for f in doors)
    model = ifcopenshell.open(str(out / "floorplan.ifc"))
    assert len(model.by_type("IfcSpace")) == 5 and len(model.by_type("IfcDoor")) == 5
    assert len(model.by_type("IfcOpeningElement")) == len(model.by_type("IfcRelVoidsElement")) == 5
    logger = ifcopenshell.validate.json_logger()
    ifcopenshell.validate.validate(str(out / "floorplan.ifc"), logger, express_rules=True)
    assert logger.statements == []
    doc = ezdxf.readfile(out / "floorplan.dxf")
    assert not doc.audit().has_errors
    msp = doc.modelspace()
    assert len(msp.query('LWPOLYLINE[layer=="ROOM"]')) >= 5 and len(msp.query('LINE[layer=="DOOR"]')) == 5
    # the front page: the rooms with their areas, and how they compare with the true ones
    front = (out / "front.html").read_text()
    assert "<h3>Rooms (5)</h3>" in front and "Corridor 1" in front and "floor area" in front
    for label in ("true rooms matched (IoU 0.5)", "true doors found (0.2 m)"):
        assert f'<tr><th>{label}</th><td class="num">100 %</td><td class="num">100 %</td></tr>' in front


def test_a_bare_recording_path_runs_only_the_plan(default_run):
    """`--config path=...` (a user's own recording) builds the answer and nothing of the
    evaluation: no hulls, no grid of plans, no reference map, no scores."""
    # the path as the README's command gives it (tests/test_readme.py): the same dataset, built once
    res = snakemake(default_run, "--config", f"path={default_run / 'results' / 'demo' / 'sim' / 'recording.bag'}")
    assert res.returncode == 0, res.stderr[-3000:]
    out = default_run / "results" / "recording"
    for name in ("floorplan.geojson", "floorplan.ifc", "selection/scans.csv", "selection/points.ply"):
        assert (out / name).is_file(), name
    assert not (out / "evaluation").exists() and not (out / "reference").exists()
    assert not (out / "hulls.parquet").exists() and not (out / "metrics.parquet").exists()
    assert not (out / "walls" / "cluster_ransac").exists()  # only the recommended plan's extractor
    assert "floor plan:" in res.stdout and "results/recording/selection/scans.csv" in res.stdout


def test_default_run_scores_the_answer(default_run):
    """Issue 33 on the demo: the recommended plan is made of the map of the 10 selected
    scans (walls/map/selected.parquet and its occupancy grid) through the structure
    passes, and scored as a plan (evaluation/answer_scores.csv; measured: precision
    0.92, recall 0.91 at 5 cm against the true walls, no crossing, no wall under 0.5 m;
    the all-scan map plan 0.90 / 0.91). Its quality curve ends at all 76 kept scans, whose
plan is the all-scan map plan."""
    import pandas as pd

    out = default_run / "results" / "demo"
    assert len(read_table(out / "walls" / "map" / "selected.parquet")) > 10
    assert (out / "walls" / "map" / "selected_grid.parquet").is_file()
    scores = pd.read_csv(out / "evaluation" / "answer_scores.csv").set_index("plan")
    rec, full = scores.loc["recommended"], scores.loc["all_scans_map"]
    assert rec["gt_precision_5cm"] >= 0.88 and rec["gt_recall_5cm"] >= 0.86
    assert full["gt_precision_5cm"] >= 0.86 and full["gt_recall_5cm"] >= 0.86
    assert rec["n_crossings"] == 0 and rec["short_wall_share"] <= 0.05
    assert 10 <= rec["n_walls"] <= 20 and rec["gt_n_walls"] == 16
    assert rec["map_correctness_5cm"] >= 0.9
    curve = pd.read_csv(out / "evaluation" / "answer_curve.csv")
    assert curve["k"].iloc[-1] == 76 and curve["k"].is_monotonic_increasing
    assert curve["f1_5cm"].iloc[-1] >= 0.85 and curve["f1_5cm"].iloc[0] < curve["f1_5cm"].iloc[-1]
    # each k's plan is built once, by the floorplan stage, and read by the score stage
    plans = sorted(int(p.name[1:]) for p in (out / "evaluation" / "answer_plans").iterdir() if p.is_dir())
    assert plans == curve["k"].tolist()
    walls = read_table(out / "evaluation" / "answer_plans" / "k76" / "walls.parquet")
    assert len(walls) == curve["n_walls"].iloc[-1]
    # the last k is the plan of all kept scans, built once (rule all_scans_floorplan)
    assert walls.equals(read_table(out / "evaluation" / "plans" / "all_scans_map" / "walls.parquet"))

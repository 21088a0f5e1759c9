"""Scoring figures from tiny hand-made tables; stage times from a hand-written benchmark."""

import json
import re

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
import shapely
from matplotlib.collections import LineCollection, PathCollection

from floorscan.figures import floorplans as figures_floorplans
from floorscan.figures import maps as figures_maps
from floorscan.figures.bitmaps import block_any, overlay_image
from floorscan.figures.curves import plot_metrics_vs_k
from floorscan.figures.floorplans import plot_floorplans, read_geojson_geometries
from floorscan.figures.maps import plot_walls_over_points, subsample_points
from floorscan.figures.scoring import make_score_figures, make_walls_figures
from floorscan.figures.stage_times import plot_stage_times, stage_of, stage_times
from floorscan.core.score_tables import GROUND_TRUTH

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"

BENCH_HEADER = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"


def _is_png(path, min_bytes=5000):
    data = path.read_bytes()
    return data[:8] == PNG_MAGIC and len(data) > min_bytes


def _metrics():
    rows = []
    for o, base in (("sequential", 0.3), ("cluster_hull", 0.6)):
        for e in ("ransac", "cluster_ransac"):
            for k, n in (("5", 5), ("15", 15), ("all", 40)):
                f1 = min(1.0, base + n / 50)
                rows.append({
                    "dataset": "toy", "reference_kind": "ground_truth", "ordering": o,
                    "extractor": e, "k": k, "n_scans": n, "n_scans_kept": 40,
                    "correct_match": 0.99, "false_positive": 0.004, "false_negative": 0.006,
                    "wall_correct_match": f1 * 0.8, "f1_5cm": f1,
                })
    return pd.DataFrame(rows)


def test_stage_times_from_hand_written_benchmarks(tmp_path):
    b = tmp_path / "benchmarks"
    (b / "walls").mkdir(parents=True)
    (b / "ingest.tsv").write_text(BENCH_HEADER + "12.5\t0:00:12\t300.5\t900\t1\t1\t0\t0\t50\t10\n")
    (b / "walls_sequential_ransac_k5.tsv").write_text(
        BENCH_HEADER + "2.0\t0:00:02\t100\t500\tNA\tNA\tNA\tNA\tNA\tNA\n"
    )
    (b / "walls" / "random_ransac_k10.tsv").write_text(
        BENCH_HEADER + "3.0\t0:00:03\t150\t500\t-\t-\t-\t-\t-\t-\n"
        "5.0\t0:00:05\t170\t500\t-\t-\t-\t-\t-\t-\n"  # a repeat: mean 4 s
    )
    (b / "register.tsv").write_text(BENCH_HEADER + "40\t0:00:40\tNA\tNA\tNA\tNA\tNA\tNA\tNA\tNA\n")
    (b / "broken.tsv").write_text("")
    t = stage_times(b)
    assert t["stage"].tolist() == ["ingest", "register", "walls"]
    walls = t.set_index("stage").loc["walls"]
    assert walls["n_jobs"] == 2
    assert walls["s_total"] == pytest.approx(6.0)
    assert walls["s_max"] == pytest.approx(4.0)
    assert walls["max_rss_mb"] == pytest.approx(170.0)
    assert t.set_index("stage").loc["ingest", "max_rss_mb"] == pytest.approx(300.5)
    assert np.isnan(t.set_index("stage").loc["register", "max_rss_mb"])
    out = tmp_path / "stage_times.png"
    plot_stage_times(t, out, "toy")
    assert _is_png(out)
    assert stage_times(tmp_path / "missing").empty


def test_stage_of_names():
    assert stage_of("walls/sequential/ransac/k5") == "walls"
    assert stage_of("select") == "select"
    assert stage_of("score_figures") == "score"
    assert stage_of("custom_thing") == "custom"


def test_metrics_vs_k_figure(tmp_path):
    out = tmp_path / "metrics_vs_k.png"
    plot_metrics_vs_k(_metrics(), out, 0.05)
    assert _is_png(out, 20000)


def test_overlay_colours():
    bi = np.array([[1, 1, 0]], bool)
    bg = np.array([[1, 0, 1]], bool)
    img = overlay_image(bi, bg)
    assert tuple(img[0, 0]) == (0.55, 0.0, 0.65)  # both: purple
    assert tuple(img[0, 1]) == (1.0, 0.1, 0.1)  # inferred only: red
    assert tuple(img[0, 2]) == (0.1, 0.2, 1.0)  # ground truth only: blue


def test_all_figures_from_tiny_tables(tmp_path):
    gt = np.array([[0, 0, 10, 0], [10, 0, 10, 6], [10, 6, 0, 6], [0, 6, 0, 0]], float)
    cols = ["x0", "y0", "x1", "y1"]
    walls = {}
    for o in ("sequential", "cluster_hull"):
        for e in ("ransac", "cluster_ransac"):
            walls[(o, e, "15")] = pd.DataFrame(gt[:2] + 0.02, columns=cols)
            walls[(o, e, "all")] = pd.DataFrame(gt, columns=cols)
    floorplans = {
        (o, e): [shapely.LineString([(0, 0), (10, 0)]), shapely.box(9.9, 0, 10.1, 6)]
        for o in ("sequential", "cluster_hull") for e in ("ransac", "cluster_ransac")
    }
    rng = np.random.default_rng(0)
    pts = pd.DataFrame(rng.uniform(0, 10, size=(3000, 3)), columns=["x", "y", "z"])
    status = {
        e: pd.DataFrame({"scan_id": np.arange(30), "n_walls": np.arange(30) % 4, "reason": [""] * 30})
        for e in ("ransac", "cluster_ransac")
    }
    times = {e: pd.DataFrame({"scan_id": np.arange(30), "time_s": np.linspace(0.01, 0.05, 30)}) for e in status}
    bench = tmp_path / "benchmarks"
    bench.mkdir()
    (bench / "hulls.tsv").write_text(BENCH_HEADER + "1.5\t0:00:01\t80\t90\t1\t1\t0\t0\t1\t1\n")
    names = ["metrics_vs_k", "floorplan", "bitmap_overlay", "walls_over_points_k",
             "walls_over_points_all", "stage_times_png", "wall_extraction"]
    outputs = {n: tmp_path / "figures" / f"{n}.png" for n in names}
    outputs["stage_times_tsv"] = tmp_path / "figures" / "stage_times.tsv"
    cfg = {"figure_k": 15, "summary_tau_m": 0.05, "figure_extractor": "cluster_ransac",
           "figure_ordering": "cluster_hull", "figure_orderings": ["sequential", "cluster_hull"],
           "cell_m": 0.05, "margin_m": 1.0, "wall_width_m": 0.1, "max_plot_points": 1000,
           "seed": 0, "points_z_band_m": [0.5, 2.0]}
    make_walls_figures(
        dataset="toy", reference={"ransac": gt, "cluster_ransac": gt}, reference_kind=GROUND_TRUTH,
        walls=walls, scores=_metrics(), floorplans=floorplans, points=pts, scan_status=status, scan_times=times,
        outputs=outputs, cfg=cfg,
    )
    table = make_score_figures(dataset="toy", metrics=_metrics(), bench_dir=bench, outputs=outputs, cfg=cfg)
    for n in names:
        assert _is_png(outputs[n]), n
    assert table["stage"].tolist() == ["hulls"]
    tsv = pd.read_csv(outputs["stage_times_tsv"], sep="\t")
    assert tsv.loc[0, "s_total"] == pytest.approx(1.5)
    assert tsv.loc[0, "max_rss_mb"] == pytest.approx(80.0)


def test_subsample_points_is_seeded_and_cuts_the_height_band():
    rng = np.random.default_rng(2)
    pts = pd.DataFrame(rng.uniform(0, 3, size=(5000, 3)), columns=["x", "y", "z"])
    a = subsample_points(pts, 500, seed=4, z_band=(0.5, 2.0))
    b = subsample_points(pts, 500, seed=4, z_band=(0.5, 2.0))
    np.testing.assert_array_equal(a, b)
    assert a.shape == (500, 2)
    flat = pts.assign(z=0.0)
    assert subsample_points(flat, 10**6, seed=0, z_band=(0.5, 2.0)).shape == (5000, 2)


def test_block_any_keeps_thin_walls():
    b = np.zeros((5, 7), bool)
    b[2, :] = True
    r = block_any(b, 2)
    assert r.shape == (3, 4)
    assert r[1].all() and not r[0].any() and not r[2].any()
    np.testing.assert_array_equal(block_any(b, 1), b)


def test_subsample_points_from_file_equals_the_frame(tmp_path):
    from floorscan.core.io import write_table

    rng = np.random.default_rng(2)
    pts = pd.DataFrame({"scan_id": np.repeat(np.arange(30, dtype=np.int32), 200),
                        "x": rng.uniform(0, 10, 6000).astype(np.float32),
                        "y": rng.uniform(0, 5, 6000).astype(np.float32),
                        "z": rng.uniform(0, 3, 6000).astype(np.float32)})
    path = tmp_path / "registered.parquet"
    write_table(pts, path)
    for max_points, band in ((500, (0.5, 2.0)), (10**6, (0.5, 2.0)), (700, None)):
        a = subsample_points(pts, max_points, seed=4, z_band=band)
        b = subsample_points(str(path), max_points, seed=4, z_band=band, batch_rows=999)
        assert np.array_equal(a, b), (max_points, band)
    assert len(subsample_points(str(path), 10**6, seed=0, z_band=(0.5, 2.0))) == int(
        ((pts["z"] >= 0.5) & (pts["z"] <= 2.0)).sum())
    # a 2D table (all z = 0): the band does not apply, every point can be drawn
    flat = pts.assign(z=np.float32(0))
    write_table(flat, path)
    for max_points in (500, 10**6):
        a = subsample_points(flat, max_points, seed=4, z_band=(0.5, 2.0))
        b = subsample_points(str(path), max_points, seed=4, z_band=(0.5, 2.0), batch_rows=999)
        assert len(b) == min(max_points, 6000) and np.array_equal(a, b)


def _capture_figures(monkeypatch, module):
    """Keep the figures the plot functions of ``module`` save (the PNG is written as well)."""
    figures = []
    save = module.save_figure

    def keep(fig, path):
        figures.append(fig)
        fig.canvas.draw()  # lay out before the figure is closed
        save(fig, path)

    monkeypatch.setattr(module, "save_figure", keep)
    return figures


def test_floorplan_figure_title_counts_the_plans_walls(tmp_path, monkeypatch):
    from floorscan.floorplan.geojson import write_geojson
    from floorscan.floorplan.plan import build_floorplan

    # a room's four walls seen from both faces (20 cm thick) and a lone wall of one face
    faces = []
    for x0, y0, x1, y1 in ((0, 0, 6, 0), (6, 0, 6, 4), (6, 4, 0, 4), (0, 4, 0, 0)):
        dx, dy = (0.0, 0.2) if y0 == y1 else (0.2, 0.0)
        faces += [(x0 - dx, y0 - dy, x1 - dx, y1 - dy), (x0 + dx / 2, y0 + dy / 2, x1 + dx / 2, y1 + dy / 2)]
    faces.append((2, 1, 4, 1))
    segments = pd.DataFrame(faces, columns=["x0", "y0", "x1", "y1"]).assign(n_inliers=100)
    plan = build_floorplan(segments)
    path = tmp_path / "plan.geojson"
    write_geojson(plan, path)
    geoms = read_geojson_geometries(path)
    n_features = len(json.loads(path.read_text())["features"])
    assert len(geoms) == len(plan.walls) < n_features  # axes, footprints and faces: one per wall
    figures = _capture_figures(monkeypatch, figures_floorplans)
    plot_floorplans([("cluster_hull, first 15 scans", geoms)], np.array(faces, float), GROUND_TRUTH,
                      tmp_path / "floorplans.png", "toy")
    title = figures[0].axes[0].get_title()
    assert int(re.search(r"\((\d+) walls\)", title).group(1)) == len(plan.walls)
    assert _is_png(tmp_path / "floorplans.png")


def test_read_geojson_geometries_of_other_geojson_returns_every_feature(tmp_path):
    path = tmp_path / "lines.geojson"
    path.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {}, "geometry": {"type": "LineString", "coordinates": [[0, 0], [1, 0]]}},
        {"type": "Feature", "properties": {"name": "b"},
         "geometry": {"type": "LineString", "coordinates": [[0, 1], [1, 1]]}},
        {"type": "Feature", "properties": {}, "geometry": None},
    ]}))
    assert len(read_geojson_geometries(path)) == 2


def test_walls_over_points_draws_the_points_under_the_walls(tmp_path, monkeypatch):
    # points of a 2D scanner mounted 0.3 m high (z constant, not 0): all of them are drawn
    rng = np.random.default_rng(3)
    pts = pd.DataFrame({"x": rng.uniform(0, 10, 20000), "y": rng.uniform(0, 6, 20000), "z": 0.3})
    xy = subsample_points(pts, 5000, seed=1, z_band=(0.5, 2.0))
    assert xy.shape == (5000, 2)
    walls = np.array([[0, 0, 10, 0], [10, 0, 10, 6]], float)
    figures = _capture_figures(monkeypatch, figures_maps)
    out = tmp_path / "walls_over_points.png"
    plot_walls_over_points(xy, [("ransac, all kept scans", walls)], out, "toy", max_points=3000)
    ax = figures[0].axes[0]
    scatter = [c for c in ax.collections if isinstance(c, PathCollection)]
    lines = [c for c in ax.collections if isinstance(c, LineCollection)]
    assert len(scatter) == 1 and len(scatter[0].get_offsets()) == 3000  # every n-th of 5000
    assert scatter[0].get_zorder() < lines[0].get_zorder()  # under the walls
    # the points show: grey pixels in the panel's free space (no wall there), 8 % of them
    # (the 0.2 pt^2 light grey dots drawn before gave 1.7 %)
    img = plt.imread(out)[..., :3]
    h, w = img.shape[:2]
    inner = img[int(0.3 * h):int(0.7 * h), int(0.3 * w):int(0.6 * w)]
    grey = (np.ptp(inner, axis=2) < 0.05) & (inner.mean(axis=2) < 0.9)
    assert grey.mean() > 0.05, grey.mean()


def test_subsample_points_3d_is_cut_to_the_band_2d_at_any_height_is_not():
    rng = np.random.default_rng(5)
    n = 4000
    three_d = pd.DataFrame({"x": rng.uniform(0, 5, n), "y": rng.uniform(0, 5, n), "z": rng.uniform(0, 3, n)})
    in_band = int(((three_d["z"] >= 0.5) & (three_d["z"] <= 2.0)).sum())
    assert len(subsample_points(three_d, 10**6, seed=0, z_band=(0.5, 2.0))) == in_band
    mounted = three_d.assign(z=0.3 + rng.uniform(0, 0.005, n))  # within the planar tolerance
    assert len(subsample_points(mounted, 10**6, seed=0, z_band=(0.5, 2.0))) == n


def test_reference_map_shows_one_cell_walls_of_a_large_building(tmp_path):
    """On an 80 m map a 5 cm structure cell is a fifth of a pixel: the walls are drawn
    as markers of a visible size (dark pixels along the wall), structure over the
    single-scan cells."""
    import matplotlib.image as mpimg

    from floorscan.core.occupancy import OccupancyGrid, OccupancyParams

    h, w = 1600, 1600  # 80 m x 80 m of 5 cm cells
    hits, misses = np.zeros((h, w), np.int32), np.zeros((h, w), np.int32)
    misses[200:1400, 200:1400] = 5  # free inside
    hits[800, 200:1400] = 4  # a wall seen by 4 scans, one cell thick, along x at y = 40 m
    hits[200:1400, 800], misses[200:1400, 800] = 1, 0  # a line one scan saw, crossing it
    grid = OccupancyGrid(np.zeros(2), 0.05, hits, misses, OccupancyParams())
    out = tmp_path / "reference_map.png"
    figures_maps.plot_reference_map(grid, out, title="large")
    img = mpimg.imread(out)[..., :3]
    dark = (img.max(axis=2) < 0.35).sum(axis=1)  # black pixels per image row
    assert dark.max() > 400  # the wall: a dark line across most of the 600-pixel axes
    red = ((img[..., 0] > 0.6) & (img[..., 1] < 0.35)).sum(axis=0)
    assert red.max() > 300


def test_an_ordering_has_one_colour_in_every_figure(tmp_path, monkeypatch):
    """Every ordering of the registry has a colour of its own, and the walls' metrics
    (Fig. 5.4) and the covered area (Fig. 5.6) draw each ordering in it."""
    from matplotlib.colors import to_hex

    from floorscan.figures import curves as figures_curves
    from floorscan.figures import selection as figures_selection
    from floorscan.figures.style import ORDERING_COLOURS
    from floorscan.select.registry import COVERAGE_ORDERINGS, ORDERINGS

    assert list(ORDERING_COLOURS) == list(ORDERINGS + COVERAGE_ORDERINGS)
    assert len(set(ORDERING_COLOURS.values())) == len(ORDERING_COLOURS)
    figures = _capture_figures(monkeypatch, figures_curves)
    plot_metrics_vs_k(_metrics(), tmp_path / "metrics.png")
    figures += _capture_figures(monkeypatch, figures_selection)
    area = pd.DataFrame({"rank": [1, 2, 3], "covered_area_m2": [5.0, 9.0, 10.0]})
    figures_selection.plot_coverage_vs_scans({"sequential": area, "cluster_hull": area},
                                             {"sequential": 3, "cluster_hull": 3}, tmp_path / "area.png")
    for fig in figures:
        lines = [ln for ax in fig.axes for ln in ax.get_lines() if not ln.get_label().startswith("_")]
        assert {ln.get_label().split(" ")[0] for ln in lines} == {"sequential", "cluster_hull"}
        for ln in lines:
            assert to_hex(ln.get_color()) == to_hex(ORDERING_COLOURS[ln.get_label().split(" ")[0]])

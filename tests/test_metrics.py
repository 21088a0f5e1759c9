"""Metric code on hand-made bitmaps and segments with known answers (thesis section 5.1,
ISPRS-style tolerance metrics)."""

import json
import math

import numpy as np
import pandas as pd
import pytest
import shapely

from floorscan.core.io import InputError
from floorscan.core.geometry import point_segment_dist2
from floorscan.score.bitmap import bitmap_metrics, error_map
from floorscan.core.segment_raster import Grid, segment_cells, grid_for, rasterize_segments
from floorscan.score.capsule import length_within
from floorscan.score.geojson import wall_faces, floorplan_faces, floorplan_wall_count, read_wall_faces
from floorscan.score.ground_truth import load_recall_references
from floorscan.core.score_tables import GROUND_TRUTH, REFERENCE
from floorscan.score.growing import SamplePairs, score_walls, wall_batches
from floorscan.score.nearest import SegmentIndex, nearest_below, nearest_distances
from floorscan.score.runs import score_dataset
from floorscan.score.segments import row_keys, dedupe_samples, gt_samples, sample_segments
from floorscan.core.segments import as_segments, segment_lengths
from floorscan.score.summary import grid_summary_markdown, summarize
from floorscan.score.tolerance import tolerance_metrics

WALL = [[0.0, 0.0, 10.0, 0.0]]


# ------------------------------------------------------------------------- bitmaps


def test_thesis_fractions_on_hand_made_bitmaps():
    bi = np.array([[1, 1, 0], [0, 0, 0], [0, 1, 0]], bool)
    bg = np.array([[1, 0, 0], [1, 0, 0], [0, 1, 0]], bool)
    be = error_map(bi, bg)
    assert be.tolist() == [[0, 1, 0], [-1, 0, 0], [0, 0, 0]]
    m = bitmap_metrics(bi, bg)
    assert m["correct_match"] == pytest.approx(7 / 9)
    assert m["false_positive"] == pytest.approx(1 / 9)
    assert m["false_negative"] == pytest.approx(1 / 9)
    # Wall cells only: union = 4 cells, 2 in both.
    assert m["wall_correct_match"] == pytest.approx(2 / 4)
    assert m["wall_false_positive"] == pytest.approx(1 / 4)
    assert m["wall_false_negative"] == pytest.approx(1 / 4)
    assert m["cell_precision"] == pytest.approx(2 / 3)
    assert m["cell_recall"] == pytest.approx(2 / 3)
    assert m["n_cells"] == 9


def test_bitmaps_of_different_shape_raise():
    with pytest.raises(ValueError, match="shape"):
        error_map(np.zeros((2, 2), bool), np.zeros((2, 3), bool))


def test_crossing_walls_on_a_tiny_grid():
    # 10 x 10 cells of 1 m; a horizontal ground-truth wall through the centres of row 2,
    # an inferred vertical wall through the centres of column 2: one cell in both.
    grid = Grid(0.0, 0.0, 1.0, 10, 10)
    bg = rasterize_segments([[0.5, 2.5, 9.5, 2.5]], grid, width_m=0.5)
    bi = rasterize_segments([[2.5, 0.5, 2.5, 9.5]], grid, width_m=0.5)
    assert bg.sum() == 10 and bg[2].all()
    assert bi.sum() == 10 and bi[:, 2].all()
    m = bitmap_metrics(bi, bg)
    assert m["false_positive"] == pytest.approx(0.09)
    assert m["false_negative"] == pytest.approx(0.09)
    assert m["correct_match"] == pytest.approx(0.82)
    assert m["wall_correct_match"] == pytest.approx(1 / 19)
    assert m["wall_false_positive"] == pytest.approx(9 / 19)


def test_identical_walls_match_every_wall_cell():
    gt = [[0, 0, 10, 0], [10, 0, 10, 6], [0, 0, 3, 4.2]]
    grid = grid_for(gt, cell_m=0.05, margin_m=0.5)
    m = score_walls(gt, gt, grid, wall_width_m=0.10)
    assert m["wall_correct_match"] == 1.0
    assert m["false_positive"] == 0.0 and m["false_negative"] == 0.0
    assert m["correct_match"] == 1.0


def test_rasterize_equals_shapely_buffer_on_cell_centres():
    rng = np.random.default_rng(3)
    seg = rng.uniform(0, 6, size=(12, 4))
    seg[0] = [1.0, 1.0, 1.0, 1.0]  # a point: its buffer is a disk
    grid = Grid(-0.5, -0.5, 0.05, 140, 140)
    got = rasterize_segments(seg, grid, width_m=0.13)
    ix, iy = np.meshgrid(np.arange(grid.nx), np.arange(grid.ny))
    cx = grid.x0 + (ix + 0.5) * grid.cell_m
    cy = grid.y0 + (iy + 0.5) * grid.cell_m
    lines = shapely.linestrings(seg.reshape(-1, 2, 2))
    lines[0] = shapely.Point(1.0, 1.0)
    buf = shapely.union_all(shapely.buffer(lines, 0.065, quad_segs=64))
    ref = shapely.contains_xy(buf, cx, cy)
    # Cells whose centre lies within 0.1 mm of the buffer edge may differ (polygonized
    # circle); no other cell may.
    d = shapely.distance(shapely.boundary(buf), shapely.points(cx.ravel(), cy.ravel()))
    differ = (got != ref).ravel()
    assert np.all(d[differ] < 1e-4)
    assert got.sum() > 1000


def test_rasterize_clips_walls_outside_the_grid_and_keeps_input():
    grid = Grid(0.0, 0.0, 0.1, 20, 10)
    seg = np.array([[-5.0, 0.55, 5.0, 0.55], [50.0, 50.0, 60.0, 50.0]])
    copy = seg.copy()
    b = rasterize_segments(seg, grid, width_m=0.05)
    assert b.shape == (10, 20)
    assert b.sum() == 20 and b[5].all()
    np.testing.assert_array_equal(seg, copy)


def test_grid_is_snapped_and_covers_margin():
    g = grid_for([[0.02, 0.03, 10.0, 5.0]], cell_m=0.05, margin_m=1.0)
    assert g.x0 == pytest.approx(-1.0) and g.y0 == pytest.approx(-1.0)
    xmin, xmax, ymin, ymax = g.extent
    assert xmax >= 11.0 - 1e-9 and ymax >= 6.0 - 1e-9
    assert g.nx == 240 and g.ny == 140
    with pytest.raises(ValueError, match="no wall segment"):
        grid_for(np.zeros((0, 4)))


def test_rasterize_a_50_by_30_m_map_of_many_walls():
    rng = np.random.default_rng(0)
    start = rng.uniform([0, 0], [50, 30], size=(3000, 2))
    ang = rng.uniform(0, np.pi, 3000)
    seg = np.column_stack([start, start + 3 * np.column_stack([np.cos(ang), np.sin(ang)])])
    grid = grid_for(seg, 0.05, 1.0)
    b = rasterize_segments(seg, grid, 0.10)
    # 9 km of 10 cm wide walls, overlapping: at most 9000 * 0.1 / 0.0025 cells.
    assert 0.5 * 360_000 < b.sum() < 1.1 * 360_000


# ------------------------------------------------------------- tolerance metrics


def test_identical_segments_have_precision_and_recall_one():
    gt = [[0, 0, 10, 0], [10, 0, 10, 6]]
    m = tolerance_metrics(gt, gt, taus=(0.05, 0.10))
    for lab in ("5cm", "10cm"):
        assert m[f"precision_{lab}"] == pytest.approx(1.0)
        assert m[f"recall_{lab}"] == pytest.approx(1.0)
        assert m[f"f1_{lab}"] == pytest.approx(1.0)
    assert m["median_distance_m"] == pytest.approx(0.0, abs=1e-12)
    assert m["gt_length_m"] == pytest.approx(16.0)


def test_a_wall_shifted_3_cm_is_within_5_cm_but_not_2_cm():
    inferred = [[0, 0.03, 10, 0.03]]
    m = tolerance_metrics(inferred, WALL, taus=(0.02, 0.05))
    assert m["precision_5cm"] == pytest.approx(1.0)
    assert m["recall_5cm"] == pytest.approx(1.0)
    assert m["precision_2cm"] == 0.0
    assert m["recall_2cm"] == 0.0
    assert m["f1_2cm"] == 0.0
    assert m["median_distance_m"] == pytest.approx(0.03)


def test_a_missing_wall_halves_recall():
    gt = [[0, 0, 5, 0], [0, 3, 5, 3]]
    m = tolerance_metrics([[0, 0, 5, 0]], gt, taus=(0.05,))
    assert m["recall_5cm"] == pytest.approx(0.5)
    assert m["precision_5cm"] == pytest.approx(1.0)
    assert m["f1_5cm"] == pytest.approx(2 / 3)
    # Half the ground truth is 3 m away, beyond the cut-off: the distances count the
    # half on the wall only.
    assert m["median_distance_m"] == pytest.approx(0.0, abs=1e-12)
    assert m["mean_distance_m"] == pytest.approx(0.0, abs=1e-12)


def test_the_distances_count_the_ground_truth_within_the_cut_off():
    """The ISPRS benchmark's accuracy: the samples within DISTANCE_CUTOFF_M (1 m) of an
    inferred wall, here a wall on the inferred one and one 0.5 m from it; the wall 3 m
    away does not count (with it, the median would be 0.5 m and the mean 1.17 m)."""
    from floorscan.score.tolerance import DISTANCE_CUTOFF_M

    assert DISTANCE_CUTOFF_M == 1.0
    gt = [[0, 0, 5, 0], [0, 0.5, 5, 0.5], [0, 3, 5, 3]]
    m = tolerance_metrics([[0, 0, 5, 0]], gt, taus=(0.05,))
    assert m["recall_5cm"] == pytest.approx(1 / 3)
    assert m["median_distance_m"] == pytest.approx(0.25)
    assert m["mean_distance_m"] == pytest.approx(0.25)
    # nothing within the cut-off: no distance to report
    far = tolerance_metrics([[0, 0, 5, 0]], [[0, 3, 5, 3]], taus=(0.05,))
    assert math.isnan(far["median_distance_m"]) and math.isnan(far["mean_distance_m"])
    # a tolerance beyond the cut-off is measured in full (the bound is twice it)
    wide = tolerance_metrics([[0, 0, 5, 0]], gt, taus=(0.05, 3.0))
    assert wide["recall_300cm"] == pytest.approx(1.0)
    assert wide["median_distance_m"] == pytest.approx(0.25)


def test_partial_overlap_counts_the_end_disk():
    # Inferred 0..4 m, ground truth 2..6 m on the same line: within tau of the ground
    # truth are x in [2 - tau, 4], i.e. 2 + tau metres of 4.
    m = tolerance_metrics([[0, 0, 4, 0]], [[2, 0, 6, 0]], taus=(0.05,))
    assert m["precision_5cm"] == pytest.approx(2.05 / 4)
    assert m["recall_5cm"] == pytest.approx(2.05 / 4)


def test_crossing_segment_is_covered_over_two_tau():
    lw = length_within([[0, -1, 0, 1]], [[-1, 0, 1, 0]], 0.05)
    assert lw[0] == pytest.approx(0.10)
    # Duplicate and overlapping others do not count twice.
    lw = length_within([[0, 0, 4, 0]], [[0, 0, 3, 0], [1, 0, 4, 0], [1, 0, 4, 0]], 0.01)
    assert lw[0] == pytest.approx(4.0)


def test_exact_lengths_agree_with_dense_sampling():
    rng = np.random.default_rng(7)
    gt = rng.uniform(0, 5, size=(15, 4))
    inferred = gt + rng.normal(0, 0.04, size=gt.shape)
    tau = 0.05
    exact = length_within(inferred, gt, tau).sum()
    pts, w = sample_segments(inferred, 0.0005)
    d = nearest_distances(pts, gt)
    sampled = w[d <= tau].sum()
    assert exact == pytest.approx(sampled, rel=2e-3)
    assert 0 < exact < segment_lengths(inferred).sum()


def test_sample_segments_weights_sum_to_length():
    pts, w = sample_segments([[0, 0, 0.025, 0], [0, 0, 3, 4]], 0.01)
    assert len(pts) == 3 + 500
    assert w.sum() == pytest.approx(5.025)
    assert pts[0] == pytest.approx([0.025 / 6, 0])


def test_empty_inferred_walls_never_crash():
    m = tolerance_metrics(np.zeros((0, 4)), WALL, taus=(0.05,))
    assert math.isnan(m["precision_5cm"])
    assert m["recall_5cm"] == 0.0
    assert m["f1_5cm"] == 0.0
    assert math.isnan(m["median_distance_m"])
    grid = grid_for(WALL, 0.05, 1.0)
    s = score_walls(pd.DataFrame(columns=["x0", "y0", "x1", "y1"]), WALL, grid)
    assert s["false_positive"] == 0.0
    assert s["wall_correct_match"] == 0.0
    assert s["false_negative"] == pytest.approx(s["n_gt_cells"] / s["n_cells"])


def test_empty_ground_truth_gives_nan_recall():
    m = tolerance_metrics(WALL, [], taus=(0.05,))
    assert m["precision_5cm"] == 0.0
    assert math.isnan(m["recall_5cm"])
    assert m["f1_5cm"] == 0.0
    assert math.isnan(tolerance_metrics([], [], taus=(0.05,))["f1_5cm"])


def test_nan_rows_are_dropped_and_bad_shapes_raise():
    m = tolerance_metrics([[0, 0, 10, 0], [np.nan, 0, 1, 1]], WALL, taus=(0.05,))
    assert m["precision_5cm"] == pytest.approx(1.0)
    with pytest.raises(ValueError, match=r"\(M, 4\)"):
        as_segments(np.zeros((3, 3)))


def test_metrics_are_deterministic_and_do_not_mutate_inputs():
    rng = np.random.default_rng(1)
    gt = rng.uniform(0, 8, size=(20, 4))
    inf = gt + rng.normal(0, 0.03, size=gt.shape)
    keep = inf.copy()
    grid = grid_for(gt, 0.05, 1.0)
    a = score_walls(inf, gt, grid)
    b = score_walls(inf, gt, grid)
    assert a == b
    np.testing.assert_array_equal(inf, keep)


# ------------------------------------------------------------------ dataset level


def _geojson(tmp_path):
    doc = {
        "type": "FeatureCollection",
        "features": [
            {"type": "Feature", "properties": {"kind": "face"},
             "geometry": {"type": "LineString", "coordinates": [[0, 0], [10, 0], [10, 6]]}},
            {"type": "Feature", "properties": {"kind": "axis", "thickness_m": 0.2},
             "geometry": {"type": "LineString", "coordinates": [[0, -0.1], [10, -0.1]]}},
            {"type": "Feature", "properties": {"kind": "footprint"},
             "geometry": {"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 1], [0, 0]]]}},
        ],
    }
    p = tmp_path / "walls.geojson"
    p.write_text(json.dumps(doc))
    return p


def test_read_wall_faces_keeps_faces_only(tmp_path):
    seg = read_wall_faces(_geojson(tmp_path))
    np.testing.assert_allclose(seg, [[0, 0, 10, 0], [10, 0, 10, 6]])
    with pytest.raises(InputError, match="kind='door'"):
        read_wall_faces(_geojson(tmp_path), kind="door")


def test_wall_faces_splits_lines_and_multilines_into_pieces():
    """Every line's consecutive vertices give a piece (z dropped), lines of one vertex
    and other geometry types give none, in feature and line order."""
    line = lambda c: {"type": "LineString", "coordinates": c}  # noqa: E731
    doc = {"type": "FeatureCollection", "features": [
        {"properties": {"kind": "face"}, "geometry": {"type": "MultiLineString", "coordinates": [
            [[0, 0, 1.5], [1, 0, 1.5], [1, 2, 1.5]], [[5, 5]], [[2, 2], [3, 3]]]}},
        {"properties": {"kind": "axis"}, "geometry": line([[7, 7], [8, 8]])},
        {"properties": {"kind": "face"}, "geometry": {"type": "Point", "coordinates": [9, 9]}},
        {"properties": {"kind": "face"}, "geometry": line([[9, 9], [8, 8.5], [7, 7]])},
    ]}  # fmt: skip
    seg = wall_faces(doc, "face")
    assert seg.tolist() == [[0, 0, 1, 0], [1, 0, 1, 2], [2, 2, 3, 3], [9, 9, 8, 8.5], [8, 8.5, 7, 7]]
    assert wall_faces(doc, "footprint").shape == (0, 4)


def test_floorplan_wall_count(tmp_path):
    def feat(kind, wid, geom):
        return {"type": "Feature", "properties": {"kind": kind, "wall_id": wid}, "geometry": geom}

    line = {"type": "LineString", "coordinates": [[0, 0], [1, 0]]}
    poly = {"type": "Polygon", "coordinates": [[[0, 0], [1, 0], [1, 0.1], [0, 0]]]}
    doc = {"type": "FeatureCollection", "features": [
        feat("axis", 0, line), feat("footprint", 0, poly), feat("axis", 1, line),
        feat("footprint", 1, poly), feat("axis", 2, line)]}
    p = tmp_path / "plan.geojson"
    p.write_text(json.dumps(doc))
    assert floorplan_wall_count(p) == 3
    for f in doc["features"]:
        del f["properties"]["wall_id"]
    p.write_text(json.dumps(doc))
    assert floorplan_wall_count(p) == 3


def test_score_dataset_and_summary(tmp_path):
    gt = read_wall_faces(_geojson(tmp_path))
    walls = {
        "5": pd.DataFrame([[0, 0, 5, 0]], columns=["x0", "y0", "x1", "y1"]),
        "10": pd.DataFrame([[0, 0, 10, 0], [10, 0, 10, 3]], columns=["x0", "y0", "x1", "y1"]),
        "all": pd.DataFrame([[0, 0, 10, 0], [10, 0, 10, 6]], columns=["x0", "y0", "x1", "y1"]),
    }
    runs = [
        {"ordering": "sequential", "extractor": "ransac", "k": k, "walls": w, "n_kept": 40,
         "n_floorplan_walls": 2}
        for k, w in walls.items()
    ]
    cfg = {"cell_m": 0.05, "wall_width_m": 0.1, "margin_m": 1.0, "taus_m": [0.05, 0.1],
           "sample_step_m": 0.01}
    df = score_dataset(runs, {"ransac": gt}, GROUND_TRUTH, cfg, dataset="toy")
    assert list(df["k"]) == ["5", "10", "all"]
    assert list(df["n_scans"]) == [5, 10, 40]
    # End disks: each partial wall covers tau more of the ground truth.
    assert df["recall_5cm"].tolist() == pytest.approx([5.05 / 16, 13.05 / 16, 1.0])
    assert (df["reference_kind"] == "ground_truth").all()
    # The same grid for every run.
    assert df["n_cells"].nunique() == 1
    s = summarize(df, tau=0.05, levels=(0.8, 0.95))
    r = s.iloc[0]
    f1_10 = 2 * 13.05 / 16 / (1 + 13.05 / 16)
    assert f1_10 > 0.8 and f1_10 < 0.95
    assert r["k_80"] == "10" and r["n_scans_80"] == 10
    assert r["fraction_80"] == pytest.approx(0.25) and r["reduction_80"] == pytest.approx(4.0)
    assert r["k_95"] == "all" and r["fraction_95"] == pytest.approx(1.0)
    md = grid_summary_markdown(s, 0.05, (0.8, 0.95))
    assert "ground-truth" in md and "| sequential | ransac | 40 |" in md


def test_score_dataset_in_worker_processes_gives_the_same_table(tmp_path):
    """Orderings x extractors split over two processes: the same rows, in the same
    order, except the timing column."""
    gt = read_wall_faces(_geojson(tmp_path))
    runs = []
    for o, shift in (("sequential", 0.0), ("random", 0.02), ("cluster_hull", 0.04)):
        for k, w in (("5", [[0, shift, 5, shift]]), ("all", [[0, shift, 10, shift], [10, 0, 10, 6]])):
            p = tmp_path / f"{o}_{k}.parquet"
            pd.DataFrame(w, columns=["x0", "y0", "x1", "y1"], dtype=float).to_parquet(p)
            runs.append({"ordering": o, "extractor": "ransac", "k": k, "walls": str(p), "n_kept": 40,
                         "n_floorplan_walls": 2})
    cfg = {"cell_m": 0.05, "wall_width_m": 0.1, "margin_m": 1.0, "taus_m": [0.05, 0.025],
           "sample_step_m": 0.01}
    one = score_dataset(runs, {"ransac": gt}, GROUND_TRUTH, cfg, dataset="toy")
    two = score_dataset(runs, {"ransac": gt}, GROUND_TRUTH, cfg, dataset="toy", workers=2)
    assert len(two) == 6 and list(two["ordering"]) == ["cluster_hull"] * 2 + ["random"] * 2 + ["sequential"] * 2
    assert two.loc[two["ordering"] == "sequential", "recall_5cm"].tolist() == pytest.approx([5.05 / 16, 1.0])
    pd.testing.assert_frame_equal(one.drop(columns="score_time_s"), two.drop(columns="score_time_s"))


def test_score_dataset_labels_a_reference():
    ref = np.array([[0.0, 0, 4, 0]])
    runs = [{"ordering": "random", "extractor": "ransac", "k": "all", "walls": ref,
             "n_kept": 3, "n_floorplan_walls": None}]
    cfg = {"cell_m": 0.05, "wall_width_m": 0.1, "margin_m": 0.5, "taus_m": [0.05],
           "sample_step_m": 0.01}
    df = score_dataset(runs, {"ransac": ref}, REFERENCE, cfg)
    assert df["reference_kind"].iloc[0] == "reference"
    assert df["f1_5cm"].iloc[0] == pytest.approx(1.0)
    assert df["n_scans"].iloc[0] == 3 and df["n_floorplan_walls"].iloc[0] == -1
    with pytest.raises(ValueError, match="empty"):
        score_dataset(runs, {"ransac": np.zeros((0, 4))}, REFERENCE, cfg)
    assert "not ground truth" in grid_summary_markdown(summarize(df, 0.05, (0.95,)), 0.05, (0.95,))


def test_overlapping_reference_walls_count_once_in_recall():
    # A reference made of 30 copies of wall A (as when every scan sees it) and one of
    # wall B, both 10 m; the inferred walls cover half of A: recall is 5 of 20 m.
    a = [[0.0, 0.0, 10.0, 0.0]] * 30
    b = [[0.0, 5.0, 10.0, 5.0]]
    m = tolerance_metrics([[0, 0, 5, 0]], a + b, taus=(0.05,))
    assert m["recall_5cm"] == pytest.approx(5.05 / 20, abs=1e-3)
    assert m["precision_5cm"] == pytest.approx(1.0)
    pts = dedupe_samples(np.array([[0.001, 0.001], [0.002, 0.003], [0.5, 0.5]]), 0.01)
    np.testing.assert_array_equal(pts, [[0.001, 0.001], [0.5, 0.5]])


def test_recall_against_observed_faces_precision_against_all(tmp_path):
    # ground truth: a 10 m and a 6 m face; the recording saw only the first 8 m of the
    # 10 m face. Walls found: that 8 m and 1 m of clutter.
    gt = np.array([[0, 0, 10, 0], [10, 0, 10, 6]], float)
    observed = {"ransac": np.array([[0, 0, 8, 0]], float)}
    walls = pd.DataFrame([[0, 0, 8, 0], [3, 3, 4, 3]], columns=["x0", "y0", "x1", "y1"])
    runs = [{"ordering": "random", "extractor": "ransac", "k": "all", "walls": walls,
             "n_kept": 3, "n_floorplan_walls": 1}]
    cfg = {"cell_m": 0.05, "wall_width_m": 0.1, "margin_m": 1.0, "taus_m": [0.05],
           "sample_step_m": 0.01}
    r = score_dataset(runs, {"ransac": gt}, GROUND_TRUTH, cfg, recall_references=observed).iloc[0]
    assert r["precision_5cm"] == pytest.approx(8 / 9)
    assert r["recall_5cm"] == pytest.approx(1.0)
    # against every face: 8 m + the 5 cm end disk of 16 m
    assert r["recall_all_5cm"] == pytest.approx(8.05 / 16, abs=2e-3)
    # without recall references there is no recall_all column and recall is against all
    r2 = score_dataset(runs, {"ransac": gt}, GROUND_TRUTH, cfg).iloc[0]
    assert "recall_all_5cm" not in r2 and r2["recall_5cm"] == pytest.approx(8.05 / 16, abs=2e-3)
    with pytest.raises(ValueError, match="recall reference"):
        score_dataset(runs, {"ransac": gt}, GROUND_TRUTH, cfg, recall_references={})


def test_load_recall_references(tmp_path):
    p = _geojson(tmp_path)
    doc = json.loads(p.read_text())
    doc["features"].append({"type": "Feature", "properties": {"kind": "observed_face"},
                            "geometry": {"type": "LineString", "coordinates": [[0, 0], [4, 0]]}})
    p.write_text(json.dumps(doc))
    refs = load_recall_references(GROUND_TRUTH, ["ransac", "cluster_ransac"], p)
    np.testing.assert_allclose(refs["cluster_ransac"], [[0, 0, 4, 0]])
    assert load_recall_references(GROUND_TRUTH, ["ransac"], p, recall_kind="face") is None
    assert load_recall_references(REFERENCE, ["ransac"], p) is None


def test_floorplan_faces_are_scored_too(tmp_path):
    gt = np.array([[0, 0, 10, 0]], float)
    walls = pd.DataFrame([[0, 0.02, 10, 0.02], [0, -0.08, 10, -0.08]], columns=["x0", "y0", "x1", "y1"])
    plan = np.array([[0, 0.01, 6, 0.01]])  # merged: 6 m of the face, 1 cm off
    runs = [{"ordering": "random", "extractor": "ransac", "k": "all", "walls": walls,
             "n_kept": 3, "n_floorplan_walls": 1, "floorplan_faces": plan}]
    cfg = {"cell_m": 0.05, "wall_width_m": 0.1, "margin_m": 1.0, "taus_m": [0.05],
           "sample_step_m": 0.01}
    r = score_dataset(runs, {"ransac": gt}, GROUND_TRUTH, cfg).iloc[0]
    assert r["precision_5cm"] == pytest.approx(0.5)  # the segment 8 cm off is not within 5 cm
    assert r["plan_precision_5cm"] == pytest.approx(1.0)
    assert r["plan_recall_5cm"] == pytest.approx(6.05 / 10, abs=2e-3)
    doc = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"kind": "axis", "wall_id": 0},
         "geometry": {"type": "LineString", "coordinates": [[0, 0], [1, 0]]}}]}
    p = tmp_path / "plan.geojson"
    p.write_text(json.dumps(doc))
    assert floorplan_faces(p).shape == (0, 4)


# ------------------------------------------------------- speed paths give the same numbers


def _stacked_walls(n_scans, seed):
    """Walls of a 10 x 6 m room seen by ``n_scans`` scans: noisy duplicates (a stack
    per wall, as per-scan extraction makes) and a few stray segments."""
    rng = np.random.default_rng(seed)
    room = np.array([[0, 0, 10, 0], [10, 0, 10, 6], [10, 6, 0, 6], [0, 6, 0, 0]], dtype=float)
    rows = []
    for _ in range(n_scans):
        w = room[rng.random(4) < 0.7]
        t = np.sort(rng.uniform(0, 1, (len(w), 2)), axis=1)
        p0 = w[:, :2] + t[:, :1] * (w[:, 2:] - w[:, :2])
        p1 = w[:, :2] + t[:, 1:] * (w[:, 2:] - w[:, :2])
        rows.append(np.hstack([p0, p1]) + rng.normal(0, 0.015, (len(w), 4)))
        rows.append(rng.uniform([-1, -1, -1, -1], [11, 7, 11, 7], (1, 4)))
    return np.vstack(rows)


def test_nearest_distances_equal_brute_force_on_stacked_duplicates():
    seg = _stacked_walls(40, seed=3)
    rng = np.random.default_rng(4)
    pts = np.vstack([rng.uniform([-30, -30], [40, 36], (300, 2)), rng.uniform([0, -0.1], [10, 0.1], (300, 2))])
    brute = np.sqrt(
        point_segment_dist2(np.repeat(pts[:, 0], len(seg)), np.repeat(pts[:, 1], len(seg)), np.tile(seg, (len(pts), 1)))
    ).reshape(len(pts), len(seg)).min(axis=1)
    np.testing.assert_allclose(nearest_distances(pts, seg), brute, rtol=1e-12, atol=1e-12)
    assert np.isinf(nearest_distances(pts[:3], np.zeros((0, 4)))).all()


def test_growing_runs_score_as_from_scratch(tmp_path):
    """score_dataset scores the walls of k scans from those of fewer (subsets) and
    reads paths; every number equals scoring each wall set on its own."""
    gt = np.array([[0, 0, 10, 0], [10, 0, 10, 6], [10, 6, 0, 6], [0, 6, 0, 0], [4, 0, 4, 6]], dtype=float)
    seg = _stacked_walls(30, seed=5)
    cols = ["x0", "y0", "x1", "y1"]
    cfg = {"cell_m": 0.05, "wall_width_m": 0.1, "margin_m": 1.0, "taus_m": [0.02, 0.05],
           "sample_step_m": 0.01}
    sizes = {"2": 8, "5": 20, "all": len(seg)}
    runs = []
    for k, n in sizes.items():
        path = tmp_path / f"k{k}.parquet"
        pd.DataFrame(seg[:n], columns=cols).to_parquet(path)
        runs.append({"ordering": "o", "extractor": "ransac", "k": k, "walls": str(path), "n_kept": 30})
    runs.append({"ordering": "o", "extractor": "ransac", "k": "1", "walls": pd.DataFrame(seg[:3], columns=cols),
                 "n_kept": 30})  # not a superset of the previous run: scored from scratch
    observed = gt[:4]
    df = score_dataset(runs, {"ransac": gt}, GROUND_TRUTH, cfg, recall_references={"ransac": observed})
    grid = grid_for(gt, 0.05, 1.0)
    samples = gt_samples(observed)
    for n, (_, row) in zip([3, 8, 20, len(seg)], df.iterrows()):
        want = score_walls(seg[:n], gt, grid, 0.1, cfg["taus_m"], 0.01, samples=samples)
        for key, value in want.items():
            assert row[key] == pytest.approx(value, rel=1e-12, abs=1e-12, nan_ok=True), key
        d_all = nearest_distances(gt_samples(gt), seg[:n])
        assert row["recall_all_5cm"] == pytest.approx(np.mean(d_all <= 0.05), rel=1e-12)
    assert df["recall_5cm"].iloc[-1] > 0.9 and df["precision_5cm"].iloc[-1] < 1.0


def _brute_d(pts, seg):
    """(S, M) exact distances, the way the metrics measure them (numpy)."""
    return np.sqrt(
        point_segment_dist2(np.repeat(pts[:, 0], len(seg)), np.repeat(pts[:, 1], len(seg)), np.tile(seg, (len(pts), 1)))
    ).reshape(len(pts), len(seg))


def test_sample_pairs_are_every_wall_sample_pair_within_reach():
    """The pairs a wall set gets from SamplePairs (measured in batches, cached by row)
    are exactly the (wall, sample) pairs within the reach, with the same distances."""
    seg = np.vstack([_stacked_walls(25, seed=7), [[2.0, 2.0, 2.0, 2.0], [5.0, 1.0, 5.3, 1.7]]])
    samples = gt_samples(np.array([[0, 0, 10, 0], [10, 0, 10, 6], [3, 1, 7, 3]], float), 0.02)
    pairs = SamplePairs(samples, 0.1)
    keys = row_keys(seg)
    pairs.of(seg[5:40], keys[5:40])  # an earlier batch, cached
    brute = _brute_d(samples, seg)
    for i in (0, 7, 39, len(seg) - 2, len(seg) - 1):
        si, d = pairs.of(seg[i:i + 1], keys[i:i + 1])
        want = np.flatnonzero(brute[:, i] <= 0.1)
        order = np.argsort(si)
        assert si[order].tolist() == want.tolist()
        assert np.array_equal(d[order], brute[want, i])
    si, d = pairs.of(seg, keys)
    assert len(si) == int((brute <= 0.1).sum()) > 1000


def test_segment_index_exact_and_nearest_below_match_brute_force():
    """Every radius level of SegmentIndex.exact (reach trees, segment boxes) and the
    direct, box-bounded and KD-tree paths of nearest_below give the brute-force
    minimum bit for bit."""
    seg = _stacked_walls(30, seed=11)
    rng = np.random.default_rng(12)
    pts = np.vstack([rng.uniform([-3, -3], [13, 9], (400, 2)), rng.uniform([0, -0.05], [10, 0.05], (400, 2))])
    brute = _brute_d(pts, seg)
    index = SegmentIndex(seg)
    radius = rng.choice([0.005, 0.02, 0.05, 0.1, 0.4, 3.0], len(pts))
    ids = np.arange(len(pts))
    got = index.exact(pts, ids, radius)
    want = np.where(brute <= radius[:, None] * (1 + 1e-9) + 1e-9, brute, np.inf).min(axis=1)
    assert np.array_equal(got, want)
    bound = rng.choice([np.inf, 0.01, 0.08, 0.6, 2.0, 50.0], len(pts))
    got = nearest_below(pts, SegmentIndex(seg[:20]), bound)
    assert np.array_equal(got, np.minimum(bound, brute[:, :20].min(axis=1)))


def test_far_points_by_cells_match_brute_force(monkeypatch):
    """SegmentIndex.far (the points far from every segment, by cells) gives the
    brute-force minimum under each point's bound bit for bit, in one chunk of pairs
    or in many, for dense runs of samples along far walls and scattered points."""
    import floorscan.score.nearest as N

    seg = _stacked_walls(30, seed=21)
    rng = np.random.default_rng(22)
    wall = np.column_stack([np.linspace(-40, 50, 3000), np.full(3000, 25.0)])  # a far wall's samples, 3 cm apart
    pts = np.vstack([wall, rng.uniform([-60, -60], [70, 66], (600, 2)), rng.uniform([0, 0.4], [10, 5.6], (200, 2))])
    brute = _brute_d(pts, seg).min(axis=1)
    bound = rng.choice([np.inf, 0.5, 3.0, 19.3, 40.0], len(pts))
    ids = np.arange(len(pts))
    want = np.minimum(bound, brute)
    assert np.array_equal(SegmentIndex(seg).far(pts, ids, bound), want)
    monkeypatch.setattr(N, "FAR_CHUNK_PAIRS", 97)  # many chunks, each of whole cells
    assert np.array_equal(SegmentIndex(seg).far(pts, ids, bound), want)
    some = ids[::7]
    assert np.array_equal(SegmentIndex(seg).far(pts, some, bound[some]), want[some])
    assert (brute[:3000] > 18).all() and (want < bound).sum() > 1000 and (want == bound).sum() > 500


def test_wall_cells_of_batches_union_to_the_bitmap():
    """Rasterizing walls one by one (the cache shared by the orderings) gives the
    bitmap of rasterizing them all at once."""
    seg = _stacked_walls(15, seed=13)
    grid = grid_for([[0, 0, 10, 6]], 0.05, 0.5)
    whole = rasterize_segments(seg, grid, 0.1)
    parts = np.zeros(grid.shape, bool)
    for i in range(len(seg)):
        owner, flat = segment_cells(seg[i:i + 1], grid, 0.1)
        assert (owner == 0).all()
        parts.reshape(-1)[flat] = True
    assert np.array_equal(parts, whole) and whole.sum() > 1000


def test_orderings_sharing_caches_score_as_from_scratch(tmp_path):
    """Two orderings of the same walls share the pairs and raster caches of their
    extractor; every number equals scoring each wall set on its own."""
    gt = np.array([[0, 0, 10, 0], [10, 0, 10, 6], [10, 6, 0, 6], [0, 6, 0, 0], [4, 0, 4, 6]], dtype=float)
    seg = _stacked_walls(20, seed=17)
    cfg = {"cell_m": 0.05, "wall_width_m": 0.1, "margin_m": 1.0, "taus_m": [0.02, 0.05], "sample_step_m": 0.01}
    rev = seg[::-1].copy()
    cols = ["x0", "y0", "x1", "y1"]
    runs = [{"ordering": o, "extractor": "ransac", "k": str(n), "walls": pd.DataFrame(w[:n], columns=cols),
             "n_kept": 20, "n_floorplan_walls": 2, "floorplan_faces": w[n // 2:n]}
            for o, w in (("a", seg), ("b", rev)) for n in (4, 15, len(seg))]
    df = score_dataset(runs, {"ransac": gt}, GROUND_TRUTH, cfg, recall_references={"ransac": gt[:4]})
    grid = grid_for(gt, 0.05, 1.0)
    samples = gt_samples(gt[:4])
    for (_, row), run in zip(df.iterrows(), runs):
        w = run["walls"].to_numpy()
        want = score_walls(w, gt, grid, 0.1, cfg["taus_m"], 0.01, samples=samples)
        for key in ("n_both_cells", "n_inferred_cells", "median_distance_m", "mean_distance_m", "recall_2cm",
                    "recall_5cm"):
            assert row[key] == want[key], key
        for key in ("precision_2cm", "f1_5cm"):
            assert row[key] == pytest.approx(want[key], rel=1e-12), key
        d_all = nearest_distances(gt_samples(gt), w)
        assert row["recall_all_2cm"] == np.mean(d_all <= 0.02)
        plan = tolerance_metrics(run["floorplan_faces"], gt, cfg["taus_m"], samples=samples)
        assert row["plan_recall_2cm"] == plan["recall_2cm"] and row["plan_recall_5cm"] == plan["recall_5cm"]
        assert row["plan_f1_5cm"] == pytest.approx(plan["f1_5cm"], rel=1e-12)
    assert df["recall_5cm"].iloc[-1] > 0.9 and 0 < df["plan_recall_5cm"].iloc[0] < df["plan_recall_5cm"].iloc[-1]


def test_a_last_run_with_the_walls_and_plan_of_an_earlier_one_takes_its_metrics(tmp_path):
    """Every ordering's k = all holds the same walls (in another order) and plan: the
    later orderings take the first one's metrics (identical rows) instead of growing
    their own state to it, and those equal scoring the wall set on its own."""
    gt = np.array([[0, 0, 10, 0], [10, 0, 10, 6], [10, 6, 0, 6], [0, 6, 0, 0], [4, 0, 4, 6]], dtype=float)
    seg = _stacked_walls(20, seed=5)
    cfg = {"cell_m": 0.05, "wall_width_m": 0.1, "margin_m": 1.0, "taus_m": [0.02, 0.05], "sample_step_m": 0.01}
    cols = ["x0", "y0", "x1", "y1"]
    order = np.random.default_rng(1).permutation(len(seg))
    runs = [{"ordering": o, "extractor": "ransac", "k": k, "walls": pd.DataFrame(w[:n], columns=cols),
             "n_kept": 20, "n_floorplan_walls": 3, "floorplan_faces": seg[:6] if k == "all" else w[:2]}
            for o, w in (("a", seg), ("b", seg[order])) for k, n in (("5", 5), ("all", len(seg)))]
    df = score_dataset(runs, {"ransac": gt}, GROUND_TRUTH, cfg)
    metric_cols = [c for c in df.columns if c not in ("ordering", "score_time_s")]
    a_all, b_all = (df[(df.ordering == o) & (df.k == "all")][metric_cols].reset_index(drop=True) for o in "ab")
    pd.testing.assert_frame_equal(a_all, b_all, check_exact=True)
    want = score_walls(seg, gt, grid_for(gt, 0.05, 1.0), 0.1, cfg["taus_m"], 0.01)
    assert b_all.loc[0, "f1_5cm"] == pytest.approx(want["f1_5cm"], rel=1e-12) and want["f1_5cm"] > 0.5
    # a different plan for the same walls is scored, not taken
    runs[3] = {**runs[3], "floorplan_faces": seg[6:9]}
    df2 = score_dataset(runs, {"ransac": gt}, GROUND_TRUTH, cfg)
    b2 = df2[(df2.ordering == "b") & (df2.k == "all")].iloc[0]
    plan = tolerance_metrics(seg[6:9], gt, cfg["taus_m"], samples=gt_samples(gt))
    assert b2["plan_recall_5cm"] == plan["recall_5cm"] != a_all.loc[0, "plan_recall_5cm"]


def test_wall_batches_cover_the_walls_in_order_with_bounded_pieces():
    """Batches of at most max_pieces pieces of 2 m; a wall of more pieces alone."""
    walls = np.array([[0, 0, 1, 0], [0, 0, 3, 0], [0, 0, 0, 9.5], [0, 0, 0, 0], [0, 0, 4, 0]], float)
    # pieces: 1, 2, 5, 1, 2
    assert wall_batches(walls, 3) == [slice(0, 2), slice(2, 3), slice(3, 5)]
    assert wall_batches(walls, 100) == [slice(0, 5)]
    assert wall_batches(walls, 1) == [slice(i, i + 1) for i in range(5)]
    assert wall_batches(np.zeros((0, 4)), 3) == []


def test_growing_walls_in_batches_score_the_same_with_a_fraction_of_the_memory(monkeypatch):
    """The walls a run adds are paired and rasterized in batches (PAIR_BATCH_PIECES):
    the same metrics, bit for bit, and the peak of the batch's candidates instead of all
    of them (1512 stacked walls, 338 891 pairs: 82.4 MB traced without batches, 11.9 MB
    in batches of 64 pieces)."""
    import tracemalloc

    import floorscan.score.growing as growing

    gt = np.array([[0, 0, 10, 0], [10, 0, 10, 6], [10, 6, 0, 6], [0, 6, 0, 0], [4, 0, 4, 6]], dtype=float)
    seg = _stacked_walls(400, seed=5)
    grid = grid_for(gt, 0.05, 1.0)
    samples = gt_samples(gt, 0.01)
    gt_bitmap = rasterize_segments(gt, grid, 0.1)
    out, peaks = [], []
    for batch in (10**9, 64):
        monkeypatch.setattr(growing, "PAIR_BATCH_PIECES", batch)
        walls = growing.GrowingWalls(gt, gt_bitmap, grid, 0.1, [0.02, 0.05], samples, samples,
                                     SamplePairs(samples, 0.1), SamplePairs(samples, 0.05), {})
        tracemalloc.start()
        out.append(walls.score(seg))
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    assert out[0] == out[1] and out[0]["f1_5cm"] == pytest.approx(0.754, abs=1e-3)
    assert sum(len(v[0]) for v in walls.pairs.cache.values()) == 338891
    assert peaks[1] < 0.25 * peaks[0]

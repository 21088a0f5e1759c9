"""The reference map (occupancy grid of all kept scans) and the floor plan against it
(issue 21, parts 1 and 2)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from floorscan.core.geometry import sample_segments, samples_per_segment, segment_weights
from floorscan.score.against_reference import (
    Structure,
    plan_against_reference,
    reference_against_ground_truth,
    within_bound,
)
from floorscan.core.occupancy import (
    PGM_FREE,
    PGM_OCCUPIED,
    PGM_UNKNOWN,
    OccupancyGrid,
    OccupancyParams,
    logit,
    map_image,
    occupancy_grid,
    read_grid,
    write_grid,
    write_map_server,
)
from floorscan.core.prefix_grids import prefix_grids
from floorscan.core.ray_casting import CellCounts, sample_cells
from test_registration import ROOM, SEGMENTS, ray_cast

# off the 5 cm cell boundaries, so that no wall lies on one
SHIFT = np.array([0.0123, 0.0171])
WALLS = (SEGMENTS.reshape(-1, 4) + np.tile(SHIFT, 2))
POSES = [(1.5, 1.5, 0.0), (5.0, 1.2, 0.4), (8.5, 3.0, 2.0), (3.0, 3.5, -1.0), (8.0, 5.0, 3.0)]


def _scans(poses=POSES, extra=None):
    """(origin, map-frame points) of a scanner at each pose in the test room; ``extra``:
    {scan index: (M, 2) points added to that scan only}."""
    out = []
    for i, (x, y, yaw) in enumerate(poses):
        local = ray_cast((x, y, yaw), n_beams=1440)[:, :2]
        c, s = math.cos(yaw), math.sin(yaw)
        pts = local @ np.array([[c, s], [-s, c]]) + np.array([x, y]) + SHIFT
        if extra and i in extra:
            pts = np.vstack([pts, extra[i]])
        out.append((np.array([x, y]) + SHIFT, pts))
    return out


def _distance_to_walls(xy):
    a, b = WALLS[:, :2], WALLS[:, 2:]
    e = b - a
    t = np.clip(np.einsum("nsk,sk->ns", xy[:, None] - a[None], e) / np.einsum("sk,sk->s", e, e), 0, 1)
    p = a[None] + t[..., None] * e[None]
    return np.min(np.linalg.norm(xy[:, None] - p, axis=2), axis=1)


def test_occupancy_grid_of_a_known_room():
    """Structure cells sit on the walls (centres within a cell's half diagonal, 3.5 cm);
    every interior cell is crossed by some ray and none is occupied; those crossed by at
    least 4 scans are free (4 misses: probability 0.165 < 0.196); outside the walls
    nothing is known. Measured: 674 structure cells, 40 occupied cells hit by one scan
    only, 92.4 % of the walls' length within 5 cm of structure (the rest is seen by
    fewer than two of the five poses: behind the pillar, in the notch)."""
    grid = occupancy_grid(_scans())
    counts = grid.counts()
    structure = grid.cell_centres(grid.structure())
    assert counts["structure"] == len(structure) and 650 <= len(structure) <= 700
    assert _distance_to_walls(structure).max() <= 0.05 * math.sqrt(0.5) + 1e-9
    assert 30 <= counts["single_scan"] <= 50
    # the walls' length is covered: every 5 cm of a wall has a structure cell within 5 cm
    samples = sample_segments(WALLS, 0.05)
    near = np.min(np.linalg.norm(samples[:, None] - structure[None], axis=2), axis=1)
    assert 0.90 < np.mean(near <= 0.05) < 0.95
    centres = grid.cell_centres(np.ones(grid.shape, bool))
    from matplotlib.path import Path as MplPath

    room = MplPath(ROOM + SHIFT).contains_points(centres)
    far = _distance_to_walls(centres) > 0.10
    inside, outside = room & far, ~room & far
    misses, hits = grid.n_miss_scans.ravel(), grid.n_hit_scans.ravel()
    free, occupied = grid.free().ravel(), grid.occupied().ravel()
    assert (misses[inside] >= 1).all() and (hits[inside] == 0).all() and not occupied[inside].any()
    np.testing.assert_array_equal(free[inside], misses[inside] >= 4)
    assert 0.7 < free[inside].mean() < 0.8
    assert (misses[outside] == 0).all() and (hits[outside] == 0).all()


def test_returns_of_one_scan_are_not_structure():
    """A stray cluster of returns that one scan sees where no other scan looks (behind
    a wall: a reflection) makes occupied cells hit by a single scan: counted apart, not
    structure (with min_scans 1 they are). A person in the open that one scan sees and
    the others see through leaves no occupied cell at all."""
    rng = np.random.default_rng(0)
    stray = np.array([[-0.6, 3.0]]) + SHIFT + rng.normal(0, 0.03, (40, 2))
    base = occupancy_grid(_scans())
    grid = occupancy_grid(_scans(extra={0: stray}))
    rows, cols, inside = grid.cells_of(stray)
    assert inside.all()
    assert grid.single_scan()[rows, cols].all() and not grid.structure()[rows, cols].any()
    assert grid.counts()["structure"] == base.counts()["structure"]
    n_stray = len(set(zip(rows.tolist(), cols.tolist())))
    assert grid.counts()["single_scan"] == base.counts()["single_scan"] + n_stray
    loose = occupancy_grid(_scans(extra={0: stray}), OccupancyParams(min_scans=1))
    assert loose.structure()[rows, cols].all()
    person = np.array([[4.0, 2.0]]) + SHIFT + rng.normal(0, 0.03, (40, 2))
    walked = occupancy_grid(_scans(extra={0: person}))
    rows, cols, _ = walked.cells_of(person)
    assert walked.n_hit_scans[rows, cols].max() == 1 and walked.n_miss_scans[rows, cols].min() >= 2
    assert not walked.occupied()[rows, cols].any()


def test_the_grid_does_not_depend_on_the_scans_order():
    a = occupancy_grid(_scans())
    b = occupancy_grid(list(reversed(_scans())))
    np.testing.assert_array_equal(a.n_hit_scans, b.n_hit_scans)
    np.testing.assert_array_equal(a.n_miss_scans, b.n_miss_scans)
    np.testing.assert_array_equal(a.log_odds, b.log_odds)


def _same_grid(a, b) -> bool:
    return (a.shape == b.shape and a.origin_xy.tobytes() == b.origin_xy.tobytes() and a.resolution_m == b.resolution_m
            and np.array_equal(a.n_hit_scans, b.n_hit_scans) and np.array_equal(a.n_miss_scans, b.n_miss_scans)
            and a.scan_xy.tobytes() == b.scan_xy.tobytes() and a.params == b.params)


def test_prefix_grids_are_the_grids_of_the_first_k_scans(monkeypatch):
    """The grids of the first k scans built incrementally equal occupancy_grid of those
    scans, array for array, also for scanners on cell edges (poses in whole
    centimetres, on the 5 cm lattice: measured from another origin, their own cell and
    their rays' first samples would round to the cell beside); a scan without a
    return counts in k; the extent grows with k. Each scan away from an edge is cast
    once; a scan on an edge once per origin the grids take."""
    on_edge = [(np.array([x, y]), pts - np.array([x, y]) - SHIFT + np.array([round(x, 2), round(y, 2)]))
               for (x, y), pts in [(o - SHIFT, p) for o, p in _scans([(2.0, 1.5, 0.3), (7.0, 2.5, 1.0)])]]
    on_edge = [(np.round(o, 2), p) for o, p in on_edge]
    assert all((np.abs(o / 0.05 - np.round(o / 0.05)) < 1e-9).all() for o, _ in on_edge)
    empty = (np.array([5.0, 3.0]), np.empty((0, 2)))
    base = _scans()
    part = (base[0][0], base[0][1][base[0][1][:, 0] > 3.0])  # sees the right of the room only
    scans = [empty, part, on_edge[0], base[1], base[2], empty, on_edge[1], base[3], base[4]]
    calls = []
    cells = CellCounts.cells
    monkeypatch.setattr(CellCounts, "cells", lambda self, *a, **kw: calls.append(1) or cells(self, *a, **kw))
    ks = [1, 2, 3, 5, 6, 8, 9]
    grids = dict(prefix_grids(scans, ks))
    n_cast = len(calls)
    assert list(grids) == ks and grids[1] is None
    for k in ks[1:]:
        assert _same_grid(grids[k], occupancy_grid(scans[:k])), k
    assert len({grids[k].shape for k in ks[1:]}) >= 2 and len({grids[k].origin_xy.tobytes() for k in ks[1:]}) >= 2
    # 5 scans away from edges once; 2 on edges once each, then again per origin of the grids after them
    origins = {grids[k].origin_xy.tobytes() for k in ks if k >= 3}
    assert 5 + 2 + 2 <= n_cast <= 5 + 2 + 2 * len(origins)
    with pytest.raises(ValueError, match="increasing k"):
        list(prefix_grids(scans, [3, 2]))
    with pytest.raises(ValueError, match="increasing k"):
        list(prefix_grids(scans, [10]))


def test_map_server_files_and_the_cell_table_round_trip(tmp_path):
    """PGM (P5) with map_server's trinary values, row 0 at the top; YAML with the
    image, resolution, origin and thresholds; the cell table restores the grid."""
    grid = occupancy_grid(_scans())
    write_map_server(grid, tmp_path / "map.pgm", tmp_path / "map.yaml")
    raw = (tmp_path / "map.pgm").read_bytes()
    lines = raw.split(b"\n", 4)
    assert lines[0] == b"P5" and lines[1].startswith(b"#")
    w, h = map(int, lines[2].split())
    assert (h, w) == grid.shape and lines[3] == b"255"
    img = np.frombuffer(lines[4], dtype=np.uint8).reshape(h, w)
    np.testing.assert_array_equal(img, map_image(grid))
    assert set(np.unique(img)) == {PGM_OCCUPIED, PGM_FREE, PGM_UNKNOWN}
    # row 0 of the image is the top of the map: the occupied cells flipped back
    np.testing.assert_array_equal(img[::-1] == PGM_OCCUPIED, grid.occupied())
    import yaml

    meta = yaml.safe_load((tmp_path / "map.yaml").read_text())
    assert meta["image"] == "map.pgm" and meta["resolution"] == 0.05 and meta["mode"] == "trinary"
    assert meta["origin"][:2] == pytest.approx(grid.origin_xy.tolist()) and meta["origin"][2] == 0.0
    assert (meta["occupied_thresh"], meta["free_thresh"], meta["negate"]) == (0.65, 0.196, 0)
    write_grid(grid, tmp_path / "occupancy.parquet", {"dataset": "room"})
    back = read_grid(tmp_path / "occupancy.parquet")
    np.testing.assert_array_equal(back.n_hit_scans, grid.n_hit_scans)
    np.testing.assert_array_equal(back.n_miss_scans, grid.n_miss_scans)
    np.testing.assert_array_equal(back.origin_xy, grid.origin_xy)
    np.testing.assert_array_equal(back.structure(), grid.structure())
    assert back.params == grid.params


def test_segment_samples_cover_each_segment_with_their_weights():
    seg = np.array([[0, 0, 1, 0], [0, 0, 0, 0.25]], float)
    pts, wts = sample_segments(seg, 0.1), segment_weights(seg, 0.1)
    assert len(pts) == len(wts) == 11 + 4
    assert wts.sum() == pytest.approx(1.25)
    assert pts[0].tolist() == [0, 0] and pts[10].tolist() == [1, 0] and pts[-1].tolist() == [0, 0.25]


def test_segment_samples_are_the_formula_to_the_bit():
    """Sample k of a segment's n is a + (b - a) (k / (n - 1)), the same floats."""
    seg = np.random.default_rng(4).normal(0, 30, (300, 4))
    seg[:5, 2:] = seg[:5, :2]
    n = samples_per_segment(seg, 0.02)
    which = np.repeat(np.arange(len(seg)), n)
    k = np.arange(n.sum()) - np.repeat(np.cumsum(n) - n, n)
    want = seg[which, :2] + (seg[which, 2:] - seg[which, :2]) * (k / (n[which] - 1))[:, None]
    assert np.array_equal(sample_segments(seg, 0.02), want)


def test_a_plan_of_the_true_walls_scores_high_and_a_spurious_wall_lowers_correctness():
    """The true walls as the plan: completeness 1.000 and correctness 0.924 at 5 cm (the
    wall parts fewer than two poses see are not structure). A 3 m wall drawn through the
    free middle of the room lowers correctness by its share of the plan's length (3 of
    39.5 m) and shows as free_fraction (0.055 of 0.076: the part over cells that at
    least 4 scans see through); completeness is unchanged."""
    grid = occupancy_grid(_scans())
    good = plan_against_reference(WALLS, grid)
    assert good["completeness_5cm"] == 1.0 and 0.91 < good["correctness_5cm"] < 0.94
    assert good["correctness_10cm"] == pytest.approx(good["correctness_5cm"], abs=0.01)
    assert good["median_distance_m"] < 0.025 and good["free_fraction"] == 0.0
    spurious = np.array([[2.5, 2.5, 5.5, 2.5]]) + np.tile(SHIFT, 2)
    bad = plan_against_reference(np.vstack([WALLS, spurious]), grid)
    share = 3.0 / bad["plan_length_m"]
    assert bad["correctness_5cm"] == pytest.approx(good["correctness_5cm"] * (1 - share), abs=0.005)
    assert bad["correctness_10cm"] < 1 - 0.9 * share
    assert 0.6 * share < bad["free_fraction"] <= share + 0.005  # over cells >= 4 scans see through
    assert bad["completeness_5cm"] == pytest.approx(good["completeness_5cm"])
    assert bad["f1_5cm"] < good["f1_5cm"]
    # a plan missing half the room loses completeness, not correctness
    half = plan_against_reference(WALLS[:4], grid)
    assert 0.6 < half["completeness_5cm"] < 0.75 and half["correctness_5cm"] > 0.9
    empty = plan_against_reference(np.empty((0, 4)), grid)
    assert empty["completeness_5cm"] == 0.0 and math.isnan(empty["correctness_5cm"])


def _brute_force_plan(faces, structure, taus=(0.05, 0.10), sample_m=0.02):
    """The definition of plan_against_reference, every sample against every cell."""
    samples, weights = sample_segments(faces, sample_m), segment_weights(faces, sample_m)
    d = np.sqrt(((samples[:, None, :] - structure.xy[None]) ** 2).sum(axis=2))  # (samples, cells)
    d_plan, d_ref = d.min(axis=1), d.min(axis=0)
    out = {}
    for tau in taus:
        key = f"{round(tau * 100):d}cm"
        out[f"correctness_{key}"] = weights[d_plan <= tau].sum() / weights.sum()
        out[f"completeness_{key}"] = np.mean(d_ref <= within_bound(tau, sample_m))
    out["median_distance_m"] = np.median(np.where(d_plan <= 10 * max(taus), d_plan, np.inf))
    return out


def test_plans_sharing_faces_score_as_each_alone_and_as_the_definition():
    """Plans scored one after another against one Structure reuse the work of the faces
    they share; each scores exactly as against a fresh Structure, and as the
    brute-force definition (every sample against every structure cell)."""
    grid = occupancy_grid(_scans())
    shared = Structure(grid)
    rng = np.random.default_rng(3)
    spurious = np.array([[2.5, 2.5, 5.5, 2.5], [1.0, 1.0, 1.0, 1.0]]) + np.tile(SHIFT, 2)  # one of zero length
    noisy = WALLS + rng.normal(0, 0.02, WALLS.shape)
    plans = [WALLS[:3], WALLS, np.vstack([WALLS, spurious]), np.vstack([noisy[:5], WALLS[5:]]),
             np.vstack([WALLS[2:], WALLS[2:3]]), noisy, WALLS[:3]]  # fmt: skip
    for faces in plans:
        got = plan_against_reference(faces, shared)
        alone = plan_against_reference(faces, Structure(grid))
        assert got == alone
        want = _brute_force_plan(faces, shared)
        for key, value in want.items():
            assert got[key] == pytest.approx(value, abs=1e-12), key
    assert 0.5 < plan_against_reference(noisy, shared)["correctness_5cm"] < 0.95


def test_a_full_face_cache_drops_the_faces_least_recently_asked_for(monkeypatch):
    """Past its capacity the face cache keeps the faces asked for last: a plan scored
    again right after is not sampled again, one of the first plans is; every score is
    a fresh Structure's, and the cache never holds much more than its capacity."""
    import floorscan.score.against_reference as A

    grid = occupancy_grid(_scans())
    shared = Structure(grid)
    per_face = 1 + np.ceil(np.hypot(WALLS[:, 2] - WALLS[:, 0], WALLS[:, 3] - WALLS[:, 1]) / 0.02)
    shared.CACHE_SAMPLES = int(per_face.sum() * 4.5)  # four and a half plans' samples
    scored = []
    real = A._score_faces
    monkeypatch.setattr(A, "_score_faces", lambda ref, seg, *a: scored.append(len(seg)) or real(ref, seg, *a))
    plans = [WALLS + np.tile(np.array([0.001 * i, 0.0]), 2) for i in range(10)]  # no face shared between them
    for faces in plans:
        assert plan_against_reference(faces, shared) == plan_against_reference(faces, Structure(grid))
        assert shared._cached_samples <= shared.CACHE_SAMPLES + per_face.sum()
    assert shared._cached_samples > shared.CACHE_SAMPLES / 2
    scored.clear()
    plan_against_reference(plans[-1], shared)  # asked for last: still cached
    assert scored == []
    plan_against_reference(plans[0], shared)  # dropped long ago: scored again
    assert scored == [len(WALLS)]


def test_ray_samples_fall_in_the_cells_of_the_whole_expression():
    """The grid's in-place per-axis cell computation equals floor((o + d * frac -
    origin) / r) of the (N, 2) arrays, to the cell, on rays of any direction."""
    rng = np.random.default_rng(5)
    o, origin, r, width = rng.uniform(-3, 3, 2), np.array([-7.35, -4.1]), 0.05, 400
    d = rng.uniform(-6, 6, (500, 2))
    ray = np.repeat(np.arange(500), 40)
    frac = np.tile(np.arange(40), 500) / 40
    c = np.floor((o + d[ray] * frac[:, None] - origin) / r).astype(np.int64)
    assert np.array_equal(sample_cells(o, d, ray, frac, origin, r, width)[0], c[:, 1] * width + c[:, 0])
    # exact binary fractions: many samples fall on cell edges, where a floor off by a
    # rounding or taken on the other side of zero would show
    o, origin, r = np.array([0.5, -0.25]), np.array([-8.0, -4.0]), 0.25
    d = rng.integers(-24, 25, (300, 2)) * 0.25
    ray, frac = np.repeat(np.arange(300), 32), np.tile(np.arange(32), 300) / 32
    c = np.floor((o + d[ray] * frac[:, None] - origin) / r).astype(np.int64)
    edge = (o + d[ray] * frac[:, None] - origin) / r
    assert (edge == np.round(edge)).mean() > 0.05
    assert np.array_equal(sample_cells(o, d, ray, frac, origin, r, width)[0], c[:, 1] * width + c[:, 0])


def test_reference_against_the_true_walls():
    """On a synthetic recording the reference's own quality: its structure against the
    true faces (correctness) and the faces against the structure (completeness)."""
    grid = occupancy_grid(_scans())
    q = reference_against_ground_truth(grid, WALLS)
    assert q["correctness_5cm"] == 1.0 and 0.91 < q["completeness_5cm"] < 0.94
    q_half = reference_against_ground_truth(grid, WALLS, observed=WALLS[:4])
    assert q_half["correctness_5cm"] == q["correctness_5cm"]


def test_bad_settings_and_empty_input_are_refused():
    with pytest.raises(ValueError, match="resolution_m"):
        occupancy_grid(_scans(), OccupancyParams(resolution_m=0))
    with pytest.raises(ValueError, match="free_thresh"):
        occupancy_grid(_scans(), OccupancyParams(free_thresh=0.7))
    with pytest.raises(ValueError, match="no scan has a return"):
        occupancy_grid([(np.zeros(2), np.empty((0, 2)))])
    with pytest.raises(ValueError, match="not finite"):
        occupancy_grid([(np.zeros(2), np.array([[np.nan, 1.0]]))])


def test_occupied_and_free_are_the_thresholds_of_the_log_odds():
    """occupied() and free() sum the log-odds only where a threshold can be passed: the
    same cells as comparing the whole log-odds array (random counts, and settings whose
    signs make the short cut not apply)."""
    from dataclasses import replace

    rng = np.random.default_rng(3)
    params = OccupancyParams()
    for settings in (params, replace(params, occupied_thresh=0.52, free_thresh=0.48),
                     replace(params, occupied_thresh=0.45, free_thresh=0.55)):
        for _ in range(50):
            hits = rng.integers(0, 5, (23, 31)).astype(np.int32)
            misses = (rng.integers(0, 9, hits.shape) * (rng.random(hits.shape) < 0.7)).astype(np.int32)
            grid = OccupancyGrid(np.zeros(2), 0.05, hits, misses, settings)
            assert np.array_equal(grid.occupied(), grid.log_odds > logit(settings.occupied_thresh))
            assert np.array_equal(grid.free(), grid.log_odds < logit(settings.free_thresh))
    empty = OccupancyGrid(np.zeros(2), 0.05, np.zeros((0, 4), np.int32), np.zeros((0, 4), np.int32), params)
    assert empty.occupied().shape == (0, 4) and empty.free().shape == (0, 4)

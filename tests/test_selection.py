"""Scan orderings (floorscan.select.orderings, registry, greedy, raster, baselines, summary;
thesis section 3.3, Algorithm 1) and figures."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import shapely
import yaml
from shapely.geometry import box

from floorscan.select import hulls as fh
from floorscan.select.baselines import motion_filter_mask, motion_filter_order, random_order, sequential_order
from floorscan.select.greedy import greedy_coverage, greedy_exact, greedy_reference
from floorscan.select.orderings import coverage_along, select_stage
from floorscan.select.params import HullParams, SelectParams
from floorscan.select.raster import TILE, RasterCoverage, _order_crossings
from floorscan.select.registry import ORDERINGS
from floorscan.select.summary import first_k, k_for_fraction, summarize

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
INTEL_LOG = DATA / "radish" / "intel-corrected.log.gz"


# ----------------------------------------------------------------------------------
# synthetic 2D scans: numpy ray casting against a Shapely floor plan
# ----------------------------------------------------------------------------------
def _building():
    """Two rooms (10 x 6, 6 x 6 m) joined by a 1.2 m door, and a corridor below."""
    return shapely.union_all([box(0, 0, 10, 6), box(11, 0, 17, 6), box(10, 2.4, 11, 3.6),
                              box(0, -3, 17, -1), box(4, -1, 5.2, 0)])


def _walls(free):
    rings = [free.exterior, *free.interiors]
    return np.concatenate([np.column_stack([np.asarray(r.coords)[:-1], np.asarray(r.coords)[1:]]) for r in rings])


def raycast_scans(n_scans: int, seed: int = 0, n_beams: int = 360, max_range_m: float = 8.0):
    """Registered 2D scans along a path through :func:`_building` and their poses:
    (registered points frame, registration frame)."""
    rng = np.random.default_rng(seed)
    free = _building()
    segs = _walls(free)
    path = np.array([[1, -2], [16, -2], [16, -2], [4.6, -2], [4.6, 3], [9, 3], [14, 3], [14, 5]], float)
    s = np.linspace(0, 1, n_scans)
    seglen = np.hypot(*np.diff(path, axis=0).T)
    cum = np.r_[0, np.cumsum(seglen)] / seglen.sum()
    i = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(seglen) - 1)
    f = np.where(seglen[i] > 0, (s - cum[i]) / np.maximum(cum[i + 1] - cum[i], 1e-12), 0)
    xy = path[i] + (path[i + 1] - path[i]) * f[:, None] + rng.normal(0, 0.05, (n_scans, 2))
    yaw = rng.uniform(-np.pi, np.pi, n_scans)
    frames = []
    for sid in range(n_scans):
        ang = yaw[sid] + np.linspace(-np.pi, np.pi, n_beams, endpoint=False)
        d = np.column_stack([np.cos(ang), np.sin(ang)])
        p0 = segs[:, :2] - xy[sid]
        e = segs[:, 2:] - segs[:, :2]
        den = d[:, :1] * e[None, :, 1] - d[:, 1:] * e[None, :, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (p0[None, :, 0] * e[None, :, 1] - p0[None, :, 1] * e[None, :, 0]) / den
            u = (p0[None, :, 0] * d[:, 1:] - p0[None, :, 1] * d[:, :1]) / den
        t = np.where((den != 0) & (t > 1e-9) & (u >= 0) & (u <= 1), t, np.inf).min(axis=1)
        t = t + rng.normal(0, 0.01, t.shape)
        ok = t < max_range_m
        pts = xy[sid] + d[ok] * t[ok, None]
        frames.append(pd.DataFrame({"scan_id": np.int32(sid), "x": pts[:, 0].astype(np.float32),
                                    "y": pts[:, 1].astype(np.float32), "z": np.float32(0)}))
    registration = pd.DataFrame({
        "scan_id": np.arange(n_scans, dtype=np.int32),
        "t_ns": (np.arange(n_scans) * 250_000_000).astype(np.int64),
        "kept": True, "x_m": xy[:, 0], "y_m": xy[:, 1], "yaw_rad": yaw,
    })
    return pd.concat(frames, ignore_index=True), registration


@pytest.fixture(scope="module")
def synthetic():
    registered, registration = raycast_scans(60, seed=2)
    hulls = fh.cluster_hulls(registered, HullParams(seed=0))
    convex = fh.convex_hulls(registered)
    ids, geoms = fh.scan_coverage(hulls)
    return registered, registration, hulls, convex, ids, geoms


# ----------------------------------------------------------------------------------
def test_raster_counts_cells_by_centre():
    sq = box(0.01, 0.01, 1.01, 2.01)
    holed = box(0, 0, 2, 2).difference(box(0.5, 0.5, 1.5, 1.5))
    cov = RasterCoverage(np.array([sq, shapely.Polygon(), holed, shapely.MultiPolygon([box(5, 5, 6, 6), box(7, 5, 7.5, 6)])], dtype=object), 0.1)
    assert cov.counts.tolist() == [200, 0, 300, 150]
    assert len(np.unique(cov.cells_of(2))) == 300
    assert cov.gains([0, 2]).tolist() == [200, 300]
    cov.add(2)
    # box(0.01..1.01, 0.01..2.01) minus holed square's cells
    assert cov.gains([0]).tolist() == [200 - 150]


def test_raster_size_follows_the_cells_hit_not_the_bounding_box():
    """Two clusters of scans 1 km apart (issue 46): the raster holds the tiles the scans
    touch and a scan's runs (about its perimeter), not a grid of the bounding box
    (20 000 x 20 000 cells at 5 cm) nor a cell per (scan, cell); the greedies still
    agree with set arithmetic on the scans' cells."""
    rng = np.random.default_rng(3)
    lo = np.r_[rng.uniform(0, 4, (12, 2)), rng.uniform(0, 4, (12, 2)) + 1000.0]
    geoms = np.array([box(x, y, x + w, y + h) for (x, y), w, h in
                      zip(lo, rng.uniform(0.5, 6, 24), rng.uniform(0.5, 6, 24))], dtype=object)
    cov = RasterCoverage(geoms, 0.05)
    bbox_cells = (1010 / 0.05) ** 2
    # each cluster spans at most 10 m = 200 cells, so at most `across` tiles a side
    across = -(-200 // TILE) + 1
    assert len(cov.tiles) <= 2 * across**2
    assert cov.covered.size == len(cov.tiles) * TILE**2 <= 2 * across**2 * TILE**2 < bbox_cells / 500
    # a box's runs: one per row it covers and tile it crosses (<= 6 m = 120 cells wide)
    rows = np.ceil(np.array([shapely.bounds(g)[3] - shapely.bounds(g)[1] for g in geoms]) / 0.05) + 1
    assert np.all(cov.run_stop - cov.run_start <= (-(-120 // TILE) + 1) * rows)
    assert len(cov.run_row) < cov.counts.sum() / 20
    cells = [set(cov.cells_of(j).tolist()) for j in range(len(geoms))]
    assert [len(c) for c in cells] == cov.counts.tolist()
    order, gains = _set_greedy(cells)
    for fn in (greedy_reference, greedy_coverage):
        o = fn(np.arange(len(geoms)), geoms, 0.05)
        assert o["scan_id"].tolist() == order
        np.testing.assert_allclose(o["gain_m2"], np.asarray(gains) * 0.05**2, rtol=0, atol=1e-9)


def test_greedy_hand_geometry_ties_and_zero_area_last():
    ids = [5, 3, 8, 0, 1]
    geoms = [box(0, 0, 2, 2), box(1, 0, 3, 2), box(10, 0, 11, 1), shapely.Polygon(),
             shapely.LineString([(0, 0), (5, 5)]).buffer(0)]  # empty after buffer(0): zero area
    for fn in (greedy_coverage, greedy_reference):
        o = fn(ids, geoms, raster_m=0.1)
        # 5 and 3 tie at 4 m^2: lowest id (3) first; then 5 adds 2, 8 adds 1; empties last by id
        assert o["scan_id"].tolist() == [3, 5, 8, 0, 1]
        assert o["gain_m2"].round(9).tolist() == [4.0, 2.0, 1.0, 0.0, 0.0]
        assert o["covered_area_m2"].round(9).tolist() == [4.0, 6.0, 7.0, 7.0, 7.0]
        assert o["rank"].tolist() == [0, 1, 2, 3, 4]


def test_fast_greedy_equals_reference_on_synthetic_scans(synthetic):
    *_, ids, geoms = synthetic
    stats = {}
    fast = greedy_coverage(ids, geoms, 0.05, stats=stats)
    ref = greedy_reference(ids, geoms, 0.05)
    pd.testing.assert_frame_equal(fast, ref)
    assert stats["evaluations"] < len(ids) * (len(ids) + 1) / 2  # lazy did less work
    assert fast["covered_area_m2"].iloc[-1] == pytest.approx(shapely.union_all(geoms).area, rel=0.03)


def test_raster_greedy_picks_what_exact_algorithm1_picks(synthetic):
    """The raster greedy and thesis Algorithm 1 on exact Shapely unions pick the same
    first scans; afterwards only near-tied scans (gains within the raster's error) may
    swap, and the covered areas stay within 1 %."""
    *_, ids, geoms = synthetic
    exact = greedy_exact(ids, geoms, max_scans=12)
    raster = greedy_coverage(ids, geoms, 0.02)
    assert raster["scan_id"].tolist()[:8] == exact["scan_id"].tolist()[:8]
    along = [shapely.union_all(geoms[np.isin(ids, raster["scan_id"].to_numpy()[:k])]).area for k in range(1, 13)]
    assert np.allclose(along, exact["covered_area_m2"], rtol=0.01)


def _intel_registered(step: int = 3):
    reg = REPO / "results" / "intel" / "registered.parquet"
    rgn = REPO / "results" / "intel" / "registration.parquet"
    if reg.exists() and rgn.exists():
        from floorscan.core.io import read_table

        registered, registration = read_table(reg), read_table(rgn)
        keep = registration.loc[registration["kept"], "scan_id"].to_numpy()[::step]
        return registered[registered["scan_id"].isin(keep)], registration
    if not INTEL_LOG.exists():
        pytest.skip(f"real recording {INTEL_LOG} absent (../shared/data not mounted)")
    from floorscan.ingest.carmen import parse_carmen

    scans, _ = parse_carmen(INTEL_LOG)
    frames, rows = [], []
    for sid, s in list(enumerate(scans))[::step]:
        x, y, th = s["pose"]
        p = np.asarray(s["points"], dtype=np.float64)
        c, si = np.cos(th), np.sin(th)
        frames.append(pd.DataFrame({"scan_id": np.int32(sid), "x": (x + c * p[:, 0] - si * p[:, 1]).astype(np.float32),
                                    "y": (y + si * p[:, 0] + c * p[:, 1]).astype(np.float32), "z": np.float32(0)}))
        rows.append({"scan_id": sid, "t_ns": int(s["t_s"] * 1e9), "kept": True, "x_m": x, "y_m": y, "yaw_rad": th})
    return pd.concat(frames, ignore_index=True), pd.DataFrame(rows)


@pytest.mark.realdata
@pytest.mark.slow
def test_fast_greedy_equals_reference_on_intel():
    registered, _ = _intel_registered(step=3)  # ~300 scans of the Intel Research Lab
    hulls = fh.cluster_hulls(registered, HullParams())
    ids, geoms = fh.scan_coverage(hulls)
    assert len(ids) > 250
    fast = greedy_coverage(ids, geoms, 0.1)
    ref = greedy_reference(ids, geoms, 0.1)
    pd.testing.assert_frame_equal(fast, ref)
    assert fast["covered_area_m2"].iloc[-1] > 100.0


def test_motion_filter_hand_poses():
    t = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 6.0, 6.1, 6.2])
    x = np.array([0.0, 0.10, 0.25, 0.40, 0.40, 0.40, 0.41, 0.41, np.nan, 0.41])
    yaw = np.deg2rad([0, 0, 0, 0, 0.5, 1.5, 1.5, 1.5, 1.5, 1.5])
    kept = motion_filter_mask((t * 1e9).astype(np.int64), x, np.zeros_like(x), yaw)
    # 0 first; 2 moved 0.25 m; 5 turned 1.5 deg; 7 after 5.4 s; 8 has no pose
    assert np.flatnonzero(kept).tolist() == [0, 2, 5, 7]
    poses = pd.DataFrame({"scan_id": np.arange(10)[::-1], "t_ns": (t * 1e9).astype(np.int64)[::-1],
                          "x_m": x[::-1], "y_m": 0.0, "yaw_rad": yaw[::-1]})
    poses["scan_id"] = np.arange(10)[::-1]
    assert motion_filter_order(poses).tolist() == [0, 2, 5, 7, 1, 3, 4, 6, 8, 9]
    # thresholds are configurable; yaw wraps at +-pi (179.8 -> -179.8 deg is 0.4 deg)
    wrap = motion_filter_mask(np.array([0, 1, 2]), np.zeros(3), np.zeros(3), np.deg2rad([179.8, -179.8, -178.0]))
    assert wrap.tolist() == [True, False, True]
    loose = motion_filter_mask((t[:8] * 1e9).astype(np.int64), x[:8], np.zeros(8), yaw[:8],
                                  max_distance_m=1.0, max_angle_rad=1.0, max_time_s=10.0)
    assert np.flatnonzero(loose).tolist() == [0]


def test_coverage_fraction_and_first_k():
    o = pd.DataFrame({"rank": [0, 1, 2, 3], "scan_id": [7, 2, 9, 4],
                      "covered_area_m2": [4.0, 6.0, 7.0, 7.0], "gain_m2": [4.0, 2.0, 1.0, 0.0]})
    assert k_for_fraction(o, 0.5) == 1
    assert k_for_fraction(o, 0.85) == 2  # 5.95 m^2
    assert k_for_fraction(o, 0.9) == 3  # 6.3 m^2
    assert k_for_fraction(o, 1.0) == 3
    assert first_k(o, fraction=0.85).tolist() == [7, 2]
    assert first_k(o, count=3).tolist() == [7, 2, 9]
    assert first_k(o, count=10).tolist() == [7, 2, 9, 4]
    with pytest.raises(ValueError, match="exactly one"):
        first_k(o, count=2, fraction=0.5)
    with pytest.raises(ValueError, match="fraction"):
        first_k(o, fraction=1.5)
    s = summarize({"x": o})
    assert s[["k_90", "k_95", "k_99"]].iloc[0].tolist() == [3, 3, 3]


def test_random_and_sequential_orders():
    ids = np.arange(50)[::-1]
    a, b = random_order(ids, 4), random_order(ids, 4)
    assert np.array_equal(a, b) and sorted(a.tolist()) == list(range(50))
    assert not np.array_equal(a, random_order(ids, 5))
    assert sequential_order([3, 1, 2], [30, 10, 10]).tolist() == [1, 2, 3]


def test_select_stage_all_orderings(synthetic):
    _, registration, hulls, convex, ids, _ = synthetic
    h = fh.from_table(fh.to_table(hulls).to_pandas())  # as read from hulls.parquet
    c = fh.to_table(convex).to_pandas()  # WKB geometry is accepted as well
    orderings, summary = select_stage(h, c, registration, SelectParams())
    assert list(orderings) == list(ORDERINGS)
    finals = []
    for name, o in orderings.items():
        assert sorted(o["scan_id"].tolist()) == sorted(ids.tolist()), name
        assert (np.diff(o["covered_area_m2"]) >= 0).all()
        finals.append(o["covered_area_m2"].iloc[-1])
    assert np.ptp(finals) < 1e-9  # the same union, counted on the same raster
    s = summary.set_index("ordering")
    assert s.loc["cluster_hull", "k_90"] < s.loc["sequential", "k_90"]
    assert (s["k_90"] <= s["k_95"]).all() and (s["k_95"] <= s["k_99"]).all()
    assert s.loc["sequential", "k_99"] <= len(ids)
    # the motion filter keeps scans 0.35 m apart: it keeps nearly all, in recording order
    assert orderings["motion_filter"]["scan_id"].iloc[0] == 0


def test_a_registered_ordering_is_made_measured_and_summarised(synthetic, monkeypatch):
    """Adding an ordering is an entry of the registry: the select job ranks with it,
    measures the cluster-hull area along it and summarises it; the names follow."""
    from floorscan.select import registry

    _, registration, hulls, convex, ids, geoms = synthetic
    assert registry.ORDERINGS == tuple(registry.RANKERS) and ORDERINGS[0] == "cluster_hull"
    assert registry.COVERAGE_ORDERINGS == ("wall_coverage", "surface_coverage")
    monkeypatch.setitem(registry.RANKERS, "reverse", lambda inputs: inputs.scan_ids[::-1])
    orderings, summary = select_stage(hulls, convex, registration, SelectParams())
    assert list(orderings) == [*ORDERINGS, "reverse"] and summary["ordering"].tolist() == list(orderings)
    assert orderings["reverse"].equals(coverage_along(ids, geoms, ids[::-1], 0.05))


def test_schema_defaults_match_dataclasses():
    from floorscan.select.figure_data import FigureParams
    from floorscan.select.params import CoverageParams

    schema = yaml.safe_load((REPO / "workflow/schemas/select.schema.yaml").read_text())
    defaults = {k: v["default"] for k, v in schema["properties"].items()}
    fig = {k: list(v) if isinstance(v, tuple) else v for k, v in FigureParams().__dict__.items()}
    coverage = {k: v["default"] for k, v in schema["properties"].pop("coverage")["properties"].items()}
    assert defaults.pop("coverage") == {} and coverage == CoverageParams().__dict__
    assert defaults.pop("default_ordering") == "wall_coverage"
    # the recommended selection's k (floorscan.select.recommend reads them from the config)
    assert (defaults.pop("k"), defaults.pop("k_coverage")) == ("auto", 0.99)
    assert defaults == {**SelectParams().as_dict(), **fig}
    from floorscan.core.config import ConfigError, stage_params

    with pytest.raises(ConfigError, match=r"select\.tile: unknown key"):
        stage_params(SelectParams, {"tile": 3})


def test_figures(synthetic, tmp_path):
    from floorscan.figures.selection import selection_figures
    from floorscan.select.figure_data import FigureParams, selection_figure_data

    registered, registration, hulls, convex, ids, _ = synthetic
    orderings, _ = select_stage(hulls, convex, registration)
    out = [tmp_path / f"{n}.png" for n in ("cov", "clu", "time")]
    data = selection_figure_data(registered, registration, hulls, orderings, HullParams(), SelectParams(),
                                 FigureParams(figure_k_clusters=(1, 10), figure_reference_max_scans=30),
                                 convex_hulls=convex)
    selection_figures(orderings, data.k99, data.clusters, data.timing, *out, title="synthetic")
    assert all(p.stat().st_size > 10_000 for p in out)
    assert data.k99 == {name: k_for_fraction(o.sort_values("rank"), 0.99) for name, o in orderings.items()}
    assert sorted(data.clusters) == [1, 10]
    timing = data.timing
    assert timing["n_scans"].max() == len(ids)
    ran = timing.dropna(subset=["reference_s"])
    assert len(ran) >= 2 and ran["identical"].all()


def test_coverage_vs_clusters_streamed_and_reusing_the_stage_hulls(synthetic, tmp_path):
    from floorscan.select.figure_data import coverage_vs_clusters
    from floorscan.core.io import write_table

    registered, _, hulls, convex, ids, _ = synthetic
    sub = ids[::3]
    path = tmp_path / "registered.parquet"
    write_table(registered, path)
    ks = (1, 3, 10)
    plain = {k: greedy_coverage(*fh.scan_coverage(fh.cluster_hulls(registered, HullParams(k_clusters=k)), sub))
             for k in ks}
    from_frame = coverage_vs_clusters(registered, sub, ks, HullParams())
    streamed = coverage_vs_clusters(str(path), sub, ks, HullParams(), hulls=fh.to_table(hulls).to_pandas())
    # k = 1 from the stage's convex hulls (WKB as on disk): the same curve, no hulling
    reused = coverage_vs_clusters(iter(()), sub, (1, 10), HullParams(), hulls=fh.to_table(hulls).to_pandas(),
                                  convex=fh.to_table(convex).to_pandas())
    for k in ks:
        assert from_frame[k].equals(plain[k]) and streamed[k].equals(plain[k]), k
    assert reused[1].equals(plain[1]) and reused[10].equals(plain[10])
    # the k = 1 curve against hulls made here without floorscan.select.hulls: GEOS's convex hull
    # of each scan's points
    import shapely

    xy = {s: g[["x", "y"]].to_numpy() for s, g in registered.groupby("scan_id")}
    direct = greedy_coverage(sub, np.array([shapely.convex_hull(shapely.multipoints(xy[s])) for s in sub]))
    assert plain[1]["scan_id"].tolist() == direct["scan_id"].tolist()
    np.testing.assert_allclose(plain[1]["covered_area_m2"], direct["covered_area_m2"], rtol=1e-9)
    # fewer clusters cover more (a coarser hull spans the gaps), k=1 is the convex hull
    final = {k: plain[k]["covered_area_m2"].iloc[-1] for k in ks}
    assert final[1] > final[3] > final[10] > 0


def test_one_raster_reused_for_every_ordering(synthetic):
    _, _, _, _, ids, geoms = synthetic
    raster = RasterCoverage(geoms, 0.05)
    a = greedy_coverage(ids, geoms, 0.05, raster=raster)
    assert a.equals(greedy_coverage(ids, geoms, 0.05))
    order = ids[::-1]
    b = coverage_along(ids, geoms, order, 0.05, raster=raster)  # the union is emptied first
    assert b.equals(coverage_along(ids, geoms, order, 0.05))
    assert b["covered_area_m2"].iloc[-1] == pytest.approx(a["covered_area_m2"].iloc[-1], abs=1e-9)
    with pytest.raises(ValueError, match="raster"):
        greedy_coverage(ids, geoms, 0.1, raster=raster)


def _set_greedy(cells: list[set]) -> tuple[list[int], list[int]]:
    """Algorithm 1 on Python sets of cells: max gain, ties to the lowest index."""
    union, left, order, gains = set(), [i for i in range(len(cells)) if cells[i]], [], []
    while left:
        g = [len(cells[i] - union) for i in left]
        i = left[int(np.argmax(g))]
        order.append(i)
        gains.append(max(g))
        union |= cells[i]
        left.remove(i)
    return order, gains


def test_greedies_equal_set_arithmetic_on_overlapping_boxes():
    """Heavily overlapping boxes (most cells covered after a few picks, so the
    reference drops covered cells and chosen scans many times, and the lazy greedy
    keeps only uncovered cells): both orderings and gains equal plain set arithmetic
    on the same cells, and RasterCoverage.gain equals gains."""
    rng = np.random.default_rng(4)
    lo = rng.uniform(0, 3, (70, 2))
    geoms = np.array([box(x, y, x + w, y + h) for (x, y), w, h in
                      zip(lo, rng.uniform(0.2, 2.5, 70), rng.uniform(0.2, 2.5, 70))] + [shapely.Polygon()], dtype=object)
    ids = np.arange(len(geoms))[::-1] * 3  # ids descending: ties go by id, not position
    cov = RasterCoverage(geoms, 0.1)
    cells = [set(cov.cells_of(j).tolist()) for j in range(len(geoms))]
    pos = np.argsort(ids)  # positions in ascending id, so index ties = id ties
    order, gains = _set_greedy([cells[j] for j in pos])
    want_ids = ids[pos[order]].tolist() + [ids[-1]]
    for fn in (greedy_reference, greedy_coverage):
        o = fn(ids, geoms, 0.1)
        assert o["scan_id"].tolist() == want_ids
        np.testing.assert_allclose(o["gain_m2"], np.r_[gains, 0] * 0.01, rtol=0, atol=1e-12)
    assert sum(gains) == len(set().union(*cells))
    for j in (0, 5, 40):
        cov.add(j)
    assert [cov.gain(j) for j in range(len(geoms))] == cov.gains(np.arange(len(geoms))).tolist()
    assert cov.gain(0) == 0 and cov.gain(len(geoms) - 1) == 0


def test_gains_after_adds_equal_set_arithmetic_across_tiles():
    """RasterCoverage.add sums the prefix again only on the rows where a scan adds a
    cell: after every add, in any order and with scans added twice, each scan's gain is
    its cells less the union's (set arithmetic), on hulls that cross the tiles' edges
    and cover one another in part."""
    rng = np.random.default_rng(11)
    centres = rng.uniform(0, 12, (40, 2))  # 12 m = 240 cells at 5 cm: two tiles a side
    geoms = np.array([shapely.MultiPoint(c + rng.normal(0, rng.uniform(0.3, 3), (10, 2))).convex_hull
                      for c in centres], dtype=object)
    cov = RasterCoverage(geoms, 0.05)
    assert len(cov.tiles) >= 4
    cells = [set(cov.cells_of(j).tolist()) for j in range(len(geoms))]
    union: set = set()
    for j in rng.choice(len(geoms), 60):
        cov.add(int(j))
        union |= cells[j]
        assert cov.gains(np.arange(len(geoms))).tolist() == [len(c - union) for c in cells]
    assert int(cov.covered.sum()) == len(union)



def test_crossings_ordered_as_lexsort():
    rng = np.random.default_rng(7)
    key = np.sort(rng.integers(0, 400, 3000))  # runs of 1 to ~20 equal keys
    key[::7] = rng.integers(0, 400, len(key[::7]))  # not quite sorted
    x = rng.integers(0, 5, len(key)).astype(float)  # ties in x too
    want = np.lexsort((x, key))
    got = _order_crossings(key, x)
    assert sorted(got.tolist()) == list(range(len(key)))
    np.testing.assert_array_equal(key[got], key[want])
    np.testing.assert_array_equal(x[got], x[want])
    pairs = np.array([3, 3, 1, 1, 2, 2]), np.array([0.5, 0.2, 0.1, 0.9, 4.0, 4.0])
    assert _order_crossings(*pairs).tolist() == [2, 3, 4, 5, 1, 0]  # the pair of key 3 swapped



def test_coverage_vs_clusters_streams_float64_tables_unrounded(synthetic, tmp_path, monkeypatch):
    """registered.parquet is float32 (read as stored, widened exactly); a table stored
    in float64 is read as float64, not rounded to float32."""
    import floorscan.select.figure_data as fsel
    from floorscan.core.io import write_table

    registered, _, _, _, ids, _ = synthetic
    sub = ids[::4]
    wide = registered.astype({"x": np.float64, "y": np.float64})
    wide["x"] += 1e-9  # not representable in float32
    seen = {}

    def spy(scans, *a, **k):
        scans = [(s, p) for s, p in scans]
        seen.update(scans)
        return fh.scan_hulls(scans, *a, **k)

    monkeypatch.setattr(fsel, "scan_hulls", spy)
    for name, df in (("f32", registered), ("f64", wide)):
        seen.clear()
        write_table(df, tmp_path / f"{name}.parquet")
        fsel.coverage_vs_clusters(str(tmp_path / f"{name}.parquet"), sub, (3,), HullParams())
        s = int(sub[1])
        want = df.loc[df["scan_id"] == s, ["x", "y"]].to_numpy()
        assert seen[s].dtype == want.dtype and np.array_equal(seen[s], want), name
        assert len(seen) == len(np.unique(df["scan_id"]))  # every scan streamed, unasked ones skipped by scan_hulls

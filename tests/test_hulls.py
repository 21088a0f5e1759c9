"""Coverage hulls (floorscan.select.hulls, clusters, convex; thesis section 3.3.2, Algorithm 2)."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import shapely
import yaml

from floorscan.core.io import split_by_scan
from floorscan.select import clusters as cl
from floorscan.select import hulls as fh
from floorscan.select.params import HullParams

REPO = Path(__file__).resolve().parents[1]


def frame(points_by_scan: dict[int, np.ndarray]) -> pd.DataFrame:
    parts = []
    for sid, p in points_by_scan.items():
        p = np.asarray(p, dtype=np.float64).reshape(-1, 2)
        parts.append(pd.DataFrame({"scan_id": np.int32(sid), "x": p[:, 0].astype(np.float32),
                                   "y": p[:, 1].astype(np.float32), "z": np.float32(0)}))
    return pd.concat(parts, ignore_index=True) if parts else pd.DataFrame(
        {"scan_id": np.zeros(0, np.int32), "x": np.zeros(0, np.float32), "y": np.zeros(0, np.float32),
         "z": np.zeros(0, np.float32)})


def l_shape(step: float = 0.05) -> np.ndarray:
    """Grid points filling an L: [0,4]x[0,1] and [0,1]x[0,4] (area 7 m^2; convex hull 11.5)."""
    g = np.arange(0, 4 + step / 2, step)
    xx, yy = np.meshgrid(g, g)
    p = np.column_stack([xx.ravel(), yy.ravel()])
    return p[(p[:, 1] <= 1 + 1e-9) | (p[:, 0] <= 1 + 1e-9)]


def test_l_shape_convex_vs_cluster_hull_area():
    pts = {0: l_shape()}
    convex = fh.convex_hulls(frame(pts))
    assert convex["cluster"].tolist() == [fh.CONVEX_CLUSTER]
    assert convex["area_m2"].iloc[0] == pytest.approx(11.5, abs=1e-4)  # hull (0,0)(4,0)(4,1)(1,4)(0,4)
    h = fh.cluster_hulls(frame(pts), HullParams(k_clusters=10, seed=3))
    assert len(h) == 10 and (h["area_m2"] > 0).all()
    _, cov = fh.scan_coverage(h)
    # cluster hulls follow the L (area 7): thin gaps between clusters are lost, and only
    # a cluster straddling the inner corner spills a small triangle outside
    assert 6.3 < cov[0].area < 7.05
    ell = shapely.union_all([shapely.box(0, 0, 4, 1), shapely.box(0, 0, 1, 4)])
    assert cov[0].difference(ell).area < 0.05


def test_k1_is_the_convex_hull():
    pts = {4: l_shape(0.1)}
    one = fh.cluster_hulls(frame(pts), HullParams(k_clusters=1))
    assert one["area_m2"].sum() == pytest.approx(11.5, abs=1e-4)


def test_outlier_is_not_covered():
    g = np.arange(0, 1.0001, 0.02)
    xx, yy = np.meshgrid(g, g)
    blob = np.column_stack([xx.ravel(), yy.ravel()])
    pts = {1: np.vstack([blob, [[30.0, 0.5]]])}
    assert fh.convex_hulls(frame(pts))["area_m2"].iloc[0] > 14.0  # the outlier inflates the hull
    h = fh.cluster_hulls(frame(pts), HullParams(k_clusters=10, seed=0))
    total = fh.scan_coverage(h)[1][0].area
    assert 0.8 < total <= 1.0 + 1e-6


def test_radius_rules_and_labels():
    p = l_shape(0.1)
    near = cl.cluster_labels(p, HullParams(radius_rule="nearest_centre", seed=1), scan_id=7)
    glob = cl.cluster_labels(p, HullParams(radius_rule="global_min", seed=1), scan_id=7)
    tight = cl.cluster_labels(p, HullParams(radius_factor=0.25, seed=1), scan_id=7)
    assert near.shape == (len(p),) and set(np.unique(near)) <= set(range(-1, 10))
    # the global radius is the smallest per-centre radius: it keeps a subset
    assert np.all((glob == -1) | (glob == near))
    assert (glob >= 0).sum() <= (near >= 0).sum()
    assert (tight >= 0).sum() < (near >= 0).sum()
    # same centres for the same seed, so a point kept by both has the same label
    assert np.array_equal(near, cl.cluster_labels(p, HullParams(seed=1), scan_id=7))


def test_degenerate_scans_have_zero_area_and_do_not_crash():
    pts = {
        0: np.array([[0.0, 0.0], [1.0, 1.0]]),  # 2 points
        1: np.column_stack([np.linspace(0, 5, 40), 2 * np.linspace(0, 5, 40)]),  # collinear
        2: np.array([[3.0, 3.0]] * 20),  # one distinct point repeated
        3: l_shape(0.2),
    }
    ids = [0, 1, 2, 3, 9]  # 9: kept but no points
    h = fh.cluster_hulls(frame(pts), HullParams(k_clusters=10), scan_ids=ids)
    per = h.groupby("scan_id")["area_m2"].sum()
    assert per.loc[[0, 1, 2, 9]].tolist() == [0.0, 0.0, 0.0, 0.0]
    assert per.loc[3] > 5.0
    assert sorted(h["scan_id"].unique()) == ids
    assert h.loc[h["area_m2"] == 0, "geometry"].map(lambda g: g.is_empty and g.geom_type == "Polygon").all()
    c = fh.convex_hulls(frame(pts), scan_ids=ids)
    assert c["scan_id"].tolist() == ids
    assert c["area_m2"].tolist()[:3] == [0.0, 0.0, 0.0] and c["area_m2"].iloc[4] == 0.0
    empty = fh.cluster_hulls(frame({}), scan_ids=[5])
    assert empty["area_m2"].tolist() == [0.0]


def test_seeded_determinism_and_independence_of_other_scans():
    rng = np.random.default_rng(0)
    pts = {s: rng.uniform(0, 10, (600, 2)) for s in range(4)}
    p = HullParams(sample_size=200, seed=11)
    a = fh.to_table(fh.cluster_hulls(frame(pts), p))
    b = fh.to_table(fh.cluster_hulls(frame(pts), p))
    assert a.equals(b)
    alone = fh.to_table(fh.cluster_hulls(frame({2: pts[2]}), p))
    sub = a.filter(np.asarray(a["scan_id"]) == 2)
    assert sub["geometry"].to_pylist() == alone["geometry"].to_pylist()


def test_wkb_table_roundtrip_little_endian_2d():
    h = fh.cluster_hulls(frame({0: l_shape(0.2)}), HullParams(k_clusters=3))
    t = fh.to_table(h)
    assert t.schema.equals(fh.HULLS)
    wkb = t["geometry"].to_pylist()
    assert all(w[0] == 1 for w in wkb)  # little endian
    back = fh.from_table(t.to_pandas())
    assert np.allclose(shapely.area(back["geometry"].to_numpy()), h["area_m2"])
    assert not shapely.has_z(back["geometry"].to_numpy()).any()
    with pytest.raises(KeyError, match="hulls.parquet"):
        fh.from_table(t.to_pandas().drop(columns="area_m2"), "hulls.parquet")


def test_compute_hulls_counts_and_kept_only():
    pts = {0: l_shape(0.2), 1: l_shape(0.2) + 10, 2: np.array([[0.0, 0.0]])}
    registration = pd.DataFrame({"scan_id": [0, 1, 2, 3], "kept": [True, False, True, True]})
    cluster, convex, counts = fh.compute_hulls(frame(pts), registration, HullParams(k_clusters=4))
    assert sorted(cluster["scan_id"].unique()) == [0, 2, 3]
    assert convex["scan_id"].tolist() == [0, 2, 3]
    assert counts["n_scans"] == 3 and counts["n_no_points"] == 1 and counts["n_zero_area"] == 2
    assert counts["n_points_ignored"] == len(pts[1])
    with pytest.raises(KeyError, match="registration.parquet"):
        fh.compute_hulls(frame(pts), registration.drop(columns="kept"))


def test_bad_input_errors():
    with pytest.raises(ValueError, match=r"\(N, 2\)"):
        cl.cluster_labels(np.zeros((5, 3)))
    with pytest.raises(ValueError, match="NaN"):
        cl.cluster_labels(np.array([[0.0, np.nan], [1, 1], [2, 2]]), scan_id=4)
    from floorscan.core.config import ConfigError, stage_params

    with pytest.raises(ConfigError, match=r"hulls\.k: unknown key"):
        stage_params(HullParams, {"k": 3})
    with pytest.raises(ValueError, match="k_clusters"):
        HullParams(k_clusters=0)


def test_schema_defaults_match_dataclass():
    schema = yaml.safe_load((REPO / "workflow/schemas/hulls.schema.yaml").read_text())
    # shard_scans is runtime (how the scans are split into jobs), not a hull parameter
    defaults = {k: v["default"] for k, v in schema["properties"].items() if k != "shard_scans"}
    assert defaults == HullParams().as_dict()


# ----------------------------------------------------------------------------------
# speed-ups (issue 8): the same hulls as the plain formulation, streamed scan by scan
# ----------------------------------------------------------------------------------
def _multipoint_hulls(xy: np.ndarray, labels: np.ndarray, k: int) -> np.ndarray:
    """The hulls as first written: a MultiPoint per cluster, convex hull, degenerate -> empty."""
    out = np.full(k, shapely.Polygon(), dtype=object)
    for c in range(k):
        pts = xy[labels == c]
        if len(pts):
            h = shapely.convex_hull(shapely.multipoints(pts))
            if h.geom_type == "Polygon" and h.area > 0:
                out[c] = h
    return out


def _scans_3d(n_scans: int, seed: int = 0) -> dict[int, np.ndarray]:
    """3D-like scans seen from above: wall rings at 16 heights (jittered) and a floor disc."""
    rng = np.random.default_rng(seed)
    out = {}
    for s in range(n_scans):
        ang = rng.uniform(0, 2 * np.pi, 3000)
        r = np.minimum(4.0 / np.maximum(np.abs(np.cos(ang)), 1e-9), 2.5 / np.maximum(np.abs(np.sin(ang)), 1e-9))
        walls = np.column_stack([r * np.cos(ang), r * np.sin(ang)]) + rng.normal(0, 0.01, (3000, 2))
        floor = rng.uniform(-2.4, 2.4, (1500, 2))
        out[s] = np.vstack([walls, floor]) + [3.0 * s, 0.0]
    return out


def test_hulls_equal_the_multipoint_formulation():
    pts = {0: l_shape(0.1), 1: _scans_3d(1, seed=5)[0], 2: np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])}
    p = HullParams(k_clusters=6, seed=2)
    h = fh.cluster_hulls(frame(pts), p)
    c = fh.convex_hulls(frame(pts))
    reg = frame(pts)  # float32 on disk: compare on the same coordinates
    for sid in pts:
        xy = reg.loc[reg["scan_id"] == sid, ["x", "y"]].to_numpy(np.float64)
        lab = cl.cluster_labels(xy, p, scan_id=sid)
        k = int(lab.max()) + 1
        want = _multipoint_hulls(xy, lab, k)
        got = h.loc[h["scan_id"] == sid, "geometry"].to_numpy()
        assert len(got) == k
        assert shapely.to_wkb(got).tolist() == shapely.to_wkb(want).tolist()
        whole = _multipoint_hulls(xy, np.zeros(len(xy), int), 1)[0]
        assert shapely.to_wkb(c.loc[c["scan_id"] == sid, "geometry"].iloc[0]) == shapely.to_wkb(whole)
    # the 8 x 5 m room, grown by the 1 cm wall noise (at most ~4 sigma along 26 m of walls)
    assert 40.0 < c["area_m2"].iloc[1] < 40.0 + 26 * 0.04
    assert c["area_m2"].iloc[2] == 0.0  # collinear


def test_n_distinct_matches_unique():
    rng = np.random.default_rng(1)
    for xy in (rng.integers(0, 4, (200, 2)).astype(float), np.zeros((0, 2)), np.ones((1, 2)),
               np.array([[0.0, -0.0], [-0.0, 0.0], [1.0, 0.0]])):
        assert cl._n_distinct(xy) == len(np.unique(xy, axis=0))


def test_scan_hulls_streamed_from_parquet_equal_the_frame(tmp_path):
    from floorscan.core.io import iter_scans, write_table

    pts = _scans_3d(5, seed=1)
    pts[7] = l_shape(0.2)
    reg = frame(pts)
    path = tmp_path / "registered.parquet"
    write_table(reg, path)
    ids = [0, 2, 3, 7, 9]  # 1 and 4 not kept, 9 kept without points
    params = [HullParams(k_clusters=k, seed=3) for k in (1, 4, 10)]
    # batches of 1000 rows: every scan is cut across batches
    streamed, convex, counts = fh.scan_hulls(iter_scans(path, ("x", "y"), batch_rows=1000), params, ids)
    for p, got in zip(params, streamed):
        want = fh.cluster_hulls(reg, p, scan_ids=ids)
        assert fh.to_table(got).equals(fh.to_table(want))
    assert fh.to_table(convex).equals(fh.to_table(fh.convex_hulls(reg, scan_ids=ids)))
    assert counts == {"n_scans": 5, "n_points": 3 * 4500 + len(pts[7]), "n_points_ignored": 2 * 4500,
                      "n_no_points": 1}
    # the stage on the stream: same tables and counts as on the frame
    registration = pd.DataFrame({"scan_id": [0, 1, 2, 3, 4, 7, 9], "kept": [1, 0, 1, 1, 0, 1, 1]}).astype(
        {"kept": bool})
    a = fh.compute_hulls(reg, registration, params[1])
    b = fh.compute_hulls(iter_scans(path, ("x", "y")), registration, params[1])
    assert fh.to_table(a[0]).equals(fh.to_table(b[0])) and fh.to_table(a[1]).equals(fh.to_table(b[1]))
    assert a[2] == b[2] and a[2]["n_no_points"] == 1 and a[2]["n_scans"] == 5


def test_iter_scans_range_and_non_contiguous_rows(tmp_path):
    from floorscan.core.io import InputError, iter_scans, write_table

    reg = frame({3: l_shape(0.5), 5: l_shape(0.5) + 1, 8: l_shape(0.5) + 2})
    path = tmp_path / "r.parquet"
    write_table(reg, path)
    got = dict(iter_scans(path, ("x", "y", "z"), scan_range=(4, 8), batch_rows=7))
    assert list(got) == [5, 8]
    assert np.array_equal(got[5], reg.loc[reg["scan_id"] == 5, ["x", "y", "z"]].to_numpy(np.float64))
    shuffled = pd.concat([reg.iloc[:10], reg.iloc[len(reg) - 5:], reg.iloc[10:len(reg) - 5]])
    write_table(shuffled, path)
    with pytest.raises(InputError, match="r.parquet.*scan 3.*not contiguous"):
        list(iter_scans(path))
    with pytest.raises(InputError, match="columns \\['w'\\] missing"):
        list(iter_scans(path, ("x", "w")))
    with pytest.raises(ValueError, match="scan 3.*two separate runs"):
        fh.scan_hulls([(3, l_shape(0.5)), (5, l_shape(0.5)), (3, l_shape(0.5))])


def test_nearest_centre_is_argmin_of_the_squared_distances_ties_to_the_first():
    rng = np.random.default_rng(12)
    xy = rng.uniform(-5, 5, (3000, 2))
    centres = rng.uniform(-5, 5, (20, 2))
    xy[:10] = [20.0, 3.0]  # equidistant from centres (20, 1) and (20, 5): the lower index wins
    centres[3] = [20.0, 5.0]
    centres[12] = [20.0, 1.0]
    d2 = ((xy[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2)
    labels, best = cl._nearest_centre(xy, centres)
    np.testing.assert_array_equal(labels, d2.argmin(axis=1))
    np.testing.assert_array_equal(best, d2.min(axis=1))
    assert (labels[:10] == 3).all() and best[0] == 4.0


def test_convex_hull_from_cluster_hull_vertices_equals_the_direct_hull():
    """The convex hull of a scan is made from its cluster hulls' vertices, outliers
    and one-point clusters: the same WKB as the hull of every point, also with
    collinear points on the hull's edges, duplicates, and scans cut across batches."""
    rng = np.random.default_rng(4)
    g = np.arange(0, 2.0001, 0.25)
    grid = np.array([[x, y] for x in g for y in g])  # collinear points on every edge
    pts = {
        0: l_shape(0.1),
        1: np.vstack([grid, grid, [[9.0, 1.0]]]),  # duplicates and one far outlier
        2: np.vstack([rng.uniform(0, 1, (300, 2)), [[5.0, 5.0], [5.0, 5.0]]]),  # a 2-point cluster
        3: np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [1.0, 1.0]]),  # bottom edge: 3 collinear
        4: np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]),  # collinear: a LineString hull, no area
        5: np.array([[3.0, 3.0]]),
        6: _scans_3d(1, seed=9)[0],
    }
    reg = frame(pts)
    direct = fh.convex_hulls(reg)  # no clustering: the hull of every point
    for k, factor, batch in ((10, 1.0, 1 << 20), (4, 0.3, 500), (3, 1e-6, 50)):  # 1e-6: all points outliers
        p = HullParams(k_clusters=k, radius_factor=factor, seed=1)
        scans = [(s, reg.loc[reg["scan_id"] == s, ["x", "y"]].to_numpy(np.float64)) for s in pts]
        (cl,), conv, _ = fh.scan_hulls(scans, [p], batch_points=batch)
        assert fh.to_table(conv).equals(fh.to_table(direct)), (k, factor, batch)
        if factor == 1e-6:
            assert (cl["area_m2"] == 0).all()
    areas = direct["area_m2"].to_numpy()
    assert areas[1] == pytest.approx(4.0 + 0.5 * 2.0 * 7.0)  # the square and a triangle to (9, 1)
    assert 4.5 < areas[2] < 5.0  # the unit square and two triangles of 2 m^2 to (5, 5)
    assert areas[3:6].tolist() == [1.0, 0.0, 0.0]
    wkb = shapely.to_wkb(direct["geometry"].iloc[3])
    assert shapely.from_wkb(wkb).exterior.coords[:] == [(0.0, 0.0), (1.0, 1.0), (2.0, 0.0), (0.0, 0.0)]


@pytest.mark.skipif((__import__("os").cpu_count() or 1) < 2,
                    reason="one CPU: OpenMP runs one thread anyway, the limit cannot be seen")
def test_scan_hulls_runs_kmeans_single_threaded_in_a_fresh_interpreter():
    """threadpoolctl limits only loaded libraries, so scikit-learn (its OpenMP) must
    be loaded before the limit, also when nothing imported it yet."""
    import subprocess
    import sys

    code = (
        "import numpy as np, threadpoolctl\n"
        "from floorscan.select import hulls as fh\n"
        "from floorscan.select.params import HullParams\n"
        "seen = []\n"
        "def scans():\n"
        "    rng = np.random.default_rng(0)\n"
        "    for s in range(2):\n"
        "        yield s, rng.uniform(0, 5, (400, 2))\n"
        "        seen.extend((i['user_api'], i['num_threads']) for i in threadpoolctl.threadpool_info())\n"
        "fh.scan_hulls(scans(), [HullParams(k_clusters=3)])\n"
        "print(sorted(set(seen)))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, check=True)
    seen = eval(out.stdout.strip())
    assert ("openmp", 1) in seen and all(n == 1 for _, n in seen), seen


def test_select_modules_do_not_import_sklearn():
    """scikit-learn is imported where KMeans runs: the select job, which merges and
    reads hulls, does not pay its imports."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "import floorscan.select.hulls, floorscan.select.orderings, floorscan.select.registry\n"
        "print('sklearn' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=REPO, check=True)
    assert out.stdout.split() == ["False"]


def test_k_is_at_most_the_distinct_points():
    reg = frame({0: l_shape(0.1), 1: _scans_3d(1, seed=5)[0], 2: np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])})
    h = fh.cluster_hulls(reg, HullParams(k_clusters=7, seed=2))
    assert h["scan_id"].tolist() == [0] * 7 + [1] * 7 + [2] * 3  # k = min(7, distinct points)


def test_hull_params_must_be_integers():
    with pytest.raises(ValueError, match="hulls.k_clusters must be an integer"):
        HullParams(k_clusters=2.5)
    with pytest.raises(ValueError, match="hulls.n_init must be an integer"):
        HullParams(n_init=True)
    assert HullParams(k_clusters=np.int64(4)).k_clusters == 4


def test_several_parameter_sets_in_one_pass_equal_separate_runs():
    """scan_hulls shares the KMeans sample between parameter sets with the same seed
    and sample size (Fig. 5.7): every table equals a run with that set alone, and the
    cluster hulls of k = 1 are the convex hulls (WKB bytes)."""
    pts = {0: l_shape(0.1), 1: _scans_3d(1, seed=5)[0], 2: np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]]),
           3: np.array([[1.0, 1.0]] * 4)}
    reg = frame(pts)
    sets = [HullParams(k_clusters=k, seed=s, sample_size=n) for k, s, n in
            ((1, 0, 1000), (2, 0, 1000), (7, 0, 1000), (7, 4, 1000), (7, 0, 300))]
    scans = split_by_scan(reg, ("x", "y")).items()
    together, conv, counts = fh.scan_hulls(scans, sets, convex=True)
    assert counts["n_scans"] == 4 and counts["n_points"] == len(reg)
    for p, got in zip(sets, together):
        alone = fh.cluster_hulls(reg, p)
        assert got[["scan_id", "cluster"]].equals(alone[["scan_id", "cluster"]])
        assert shapely.to_wkb(got["geometry"].to_numpy()).tolist() == shapely.to_wkb(alone["geometry"].to_numpy()).tolist()
        np.testing.assert_array_equal(got["area_m2"], alone["area_m2"])
    # other seeds / sample sizes give other clusters of the 3D scan
    wkb = [shapely.to_wkb(t.loc[t["scan_id"] == 1, "geometry"].to_numpy()).tolist() for t in together[2:]]
    assert wkb[0] != wkb[1] and wkb[0] != wkb[2]
    assert shapely.to_wkb(together[0]["geometry"].to_numpy()).tolist() == shapely.to_wkb(conv["geometry"].to_numpy()).tolist()
    assert together[0]["area_m2"].iloc[0] == pytest.approx(11.5, abs=1e-4)  # the L's convex hull

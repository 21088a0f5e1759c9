"""Wall extraction: known rooms ray-cast with noise in, walls within toleranced numbers out."""

from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml

from floorscan.walls.cluster import cluster_ransac, wall_signature
from floorscan.walls.extract import extract_walls
from floorscan.walls.first_k import first_k_walls
from floorscan.core.selection import parse_k
from floorscan.walls.meanshift import mean_shift
from floorscan.walls.normals import point_normals
from floorscan.walls.params import ClusterParams, RansacParams
from floorscan.core.wall_points import ScanParams, scan_points_2d
from floorscan.walls.ransac import ransac

REPO = Path(__file__).resolve().parents[1]
ROOM = [(0, 0, 4, 0), (4, 0, 4, 6), (4, 6, 0, 6), (0, 6, 0, 0)]  # 4 x 6 m room, metres


def raycast(segments, origin, n_rays=720, noise=0.01, seed=0, max_range=20.0):
    """A 2D LIDAR scan at ``origin``: the nearest hit of each of ``n_rays`` rays with the
    wall segments (K, 4), plus Gaussian range noise (sigma ``noise``, metres)."""
    rng = np.random.default_rng(seed)
    seg = np.asarray(segments, float)
    o = np.asarray(origin, float)
    ang = np.linspace(0, 2 * np.pi, n_rays, endpoint=False)
    u = np.stack([np.cos(ang), np.sin(ang)], 1)
    a, e = seg[:, :2], seg[:, 2:] - seg[:, :2]

    def cross(p, q):
        return p[..., 0] * q[..., 1] - p[..., 1] * q[..., 0]

    den = cross(u[:, None, :], e[None])
    ao = a[None] - o
    with np.errstate(divide="ignore", invalid="ignore"):
        t = cross(ao, e[None]) / den
        s = cross(ao, u[:, None, :]) / den
    t = np.where((np.abs(den) > 1e-12) & (t > 1e-9) & (s >= 0) & (s <= 1), t, np.inf)
    r = t.min(1)
    ok = r < max_range
    return o + u[ok] * (r[ok] + rng.normal(0, noise, ok.sum()))[:, None]


def extract(extractor, points, seed=0, params=RansacParams()):
    if extractor == "ransac":
        return ransac(points, params, seed=seed)
    return cluster_ransac(points, params, ClusterParams(), seed=seed)


def match(segment, truth):
    """(angle difference in degrees, max distance of the segment's ends to the true
    line, max distance along the line between matched ends) of a segment and a wall."""
    s, t = np.asarray(segment, float), np.asarray(truth, float)
    d = (t[2:] - t[:2]) / np.linalg.norm(t[2:] - t[:2])
    n = np.array([-d[1], d[0]])
    u = s[2:] - s[:2]
    ang = np.degrees(np.arccos(min(1.0, abs(u @ d) / np.linalg.norm(u))))
    perp = max(abs((s[:2] - t[:2]) @ n), abs((s[2:] - t[:2]) @ n))
    ends_s = np.sort([(s[:2] - t[:2]) @ d, (s[2:] - t[:2]) @ d])
    ends_t = np.array([0.0, np.linalg.norm(t[2:] - t[:2])])
    return ang, perp, float(np.abs(ends_s - ends_t).max())


def best_match(df, truth):
    rows = [match(r, truth) for r in df[["x0", "y0", "x1", "y1"]].to_numpy()]
    return min(rows, key=lambda m: m[1] + m[0])


@pytest.mark.parametrize("extractor", ["ransac", "cluster_ransac"])
def test_room_walls_within_1cm_and_half_degree(extractor):
    pts = raycast(ROOM, (1.5, 2.2), noise=0.01, seed=3)
    df = extract(extractor, pts, seed=7)
    assert len(df) == 4
    for wall in ROOM:
        ang, perp, ends = best_match(df, wall)
        assert ang < 0.5
        assert perp < 0.01
        assert ends < 0.05  # ends: within about two point spacings of the corners
    assert (df["rmse_m"] > 0.005).all() and (df["rmse_m"] < 0.015).all()  # noise sigma 1 cm
    assert df["n_inliers"].sum() <= len(pts) + 8  # corner points may end two walls


@pytest.mark.parametrize("extractor", ["ransac", "cluster_ransac"])
def test_wall_with_door_gives_two_segments(extractor):
    # Bottom wall y=0 has a 0.9 m door from x=1.5 to x=2.4; a corridor wall behind it.
    walls = [(0, 0, 1.5, 0), (2.4, 0, 4, 0), (4, 0, 4, 6), (4, 6, 0, 6), (0, 6, 0, 0), (-3, -3, 7, -3)]
    pts = raycast(walls, (2.0, 3.0), n_rays=1440, seed=1)
    df = extract(extractor, pts, seed=1)
    on_wall = df[(df[["y0", "y1"]].abs() < 0.02).all(axis=1)]
    assert len(on_wall) == 2
    xs = np.sort(on_wall[["x0", "x1"]].to_numpy(), axis=1)
    xs = xs[np.argsort(xs[:, 0])]
    np.testing.assert_allclose(xs, [[0.0, 1.5], [2.4, 4.0]], atol=0.03)


def test_cluster_ransac_separates_parallel_walls_20cm_apart():
    rng = np.random.default_rng(0)
    x = rng.uniform(0, 4, 400)
    y = np.r_[np.zeros(200), np.full(200, 0.20)] + rng.normal(0, 0.01, 400)
    df = cluster_ransac(np.c_[x, y], seed=0)
    assert len(df) == 2
    ys = np.sort(df[["y0", "y1"]].mean(axis=1).to_numpy())
    np.testing.assert_allclose(ys, [0.0, 0.20], atol=0.005)
    np.testing.assert_allclose(np.sort(df["n_inliers"]), [200, 200], atol=6)


def test_wall_signature_puts_parallel_walls_at_their_distance():
    # Far from the origin (x ~ 50 m), where a per-point-normal rho would smear.
    rng = np.random.default_rng(1)
    x = rng.uniform(48, 52, 300)
    pts = np.c_[x, np.r_[np.full(150, 3.0), np.full(150, 3.2)] + rng.normal(0, 0.005, 300)]
    normals = point_normals(pts, 0.25, 20)
    rho, cn = wall_signature(pts, normals, np.zeros(300, dtype=int))
    assert abs(abs(cn[0, 1]) - 1.0) < 1e-3  # normal of a wall along x is +-y
    assert abs(abs(np.median(rho[150:]) - np.median(rho[:150])) - 0.20) < 0.005
    assert rho[:150].std() < 0.01 and rho[150:].std() < 0.01  # each wall falls together


def test_mean_shift_gives_the_clusters_of_sklearn():
    from sklearn.cluster import MeanShift

    rng = np.random.default_rng(4)
    one = np.r_[rng.normal(0, 0.01, 120), rng.normal(0.2, 0.01, 80), rng.normal(1.0, 0.02, 40), rng.uniform(-1, 2, 20)]
    ang = rng.normal(0, 0.02, 300) + np.repeat([0.3, 1.9, 2.5], 100)
    two = 0.5 * np.c_[np.cos(2 * ang), np.sin(2 * ang)]
    for x, bw in ((one[:, None], 0.05), (two, 0.1)):
        ours = mean_shift(x, bw, min_bin_freq=5)
        ref = MeanShift(bandwidth=bw, bin_seeding=True, min_bin_freq=5).fit_predict(x)
        np.testing.assert_array_equal(ours, ref)
    labels = mean_shift(one[:, None], 0.05, min_bin_freq=5)
    assert len(np.unique(labels[:240])) == 3 and (labels[:120] == labels[0]).all()
    assert (mean_shift(np.array([[0.0], [1.0], [2.0]]), 0.1, min_bin_freq=2) == -1).all()


def test_open3d_normals_are_z_for_planar_points_so_covariances_are_used():
    import open3d as o3d

    t = np.linspace(0, 3, 200)
    pts = np.c_[t, 0.5 * t]  # a line of slope 0.5
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.c_[pts, np.zeros(200)]))
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamHybrid(radius=0.25, max_nn=20))
    assert np.allclose(np.abs(np.asarray(pcd.normals)[:, 2]), 1.0)  # useless in-plane
    n = point_normals(pts, 0.25, 20)
    expected = np.array([-0.5, 1.0]) / np.hypot(0.5, 1.0)  # angle in [0, pi)
    np.testing.assert_allclose(n, np.broadcast_to(expected, n.shape), atol=1e-6)


def test_covariances_are_open3d_estimate_covariances_bit_for_bit():
    import open3d as o3d

    from floorscan.walls.normals import neighbourhood_covariances

    rng = np.random.default_rng(8)
    # two walls, a corner, clutter, an isolated point (< 3 neighbours: identity)
    t = rng.uniform(0, 3, 400)
    pts = np.r_[np.c_[t[:200], 0.01 * rng.normal(size=200)], np.c_[0.01 * rng.normal(size=200), t[200:]],
                rng.uniform(0.5, 2.5, (100, 2)), [[9.0, 9.0]]]
    for radius, max_nn in ((0.25, 20), (0.1, 5), (0.4, 60)):
        pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.c_[pts, np.zeros(len(pts))]))
        pcd.estimate_covariances(o3d.geometry.KDTreeSearchParamHybrid(radius=radius, max_nn=max_nn))
        ref = np.asarray(pcd.covariances)
        sxx, syy, sxy = neighbourhood_covariances(pts, radius, max_nn)
        np.testing.assert_array_equal(sxx, ref[:, 0, 0])
        np.testing.assert_array_equal(syy, ref[:, 1, 1])
        np.testing.assert_array_equal(sxy, ref[:, 0, 1])
    assert (sxx[-1], syy[-1], sxy[-1]) == (1.0, 1.0, 0.0)
    assert np.isnan(point_normals(pts, 0.25, 20)[-1]).all()


def _walls_map(seed, n=30000, n_walls=40):
    """A map of ``n`` noisy points on ``n_walls`` axis-parallel walls over 60 m and 50
    scattered points, metres."""
    rng = np.random.default_rng(seed)
    a = rng.uniform(0, 60, (n_walls, 2))
    turn = rng.integers(0, 4, n_walls) * np.pi / 2
    b = a + np.column_stack([np.cos(turn), np.sin(turn)]) * rng.uniform(1, 20, (n_walls, 1))
    t, w = rng.uniform(0, 1, n), rng.integers(0, n_walls, n)
    return np.vstack([a[w] + t[:, None] * (b[w] - a[w]) + rng.normal(0, 0.01, (n, 2)), rng.uniform(-20, 80, (50, 2))])


def test_tiled_inlier_counts_and_runs_equal_the_whole_product(monkeypatch):
    """The inlier counts of a large map by tiles (each line against the tiles it
    passes near) are the counts of one product over all points, bit for bit, for tiles
    of one point to thousands, hypotheses near one tile or all, and tiles some of whose
    points a line took; a tile's near points hold every point within the threshold; a
    RANSAC run by tiles gives the rows of the plain loop, float for float."""
    import floorscan.walls.ransac as R
    from floorscan.walls.tiles import Tiles

    rng = np.random.default_rng(21)
    pts = _walls_map(21)
    assert len(pts) > R.TILED_MIN_POINTS
    pt = np.vstack([pts.T, np.ones(len(pts))])
    i, j = rng.integers(len(pts), size=600), rng.integers(len(pts), size=600)
    d = pts[j] - pts[i] + 1e-3
    normal = np.column_stack([-d[:, 1], d[:, 0]]) / np.hypot(*d.T)[:, None]
    hyp = np.column_stack([normal, (normal * pts[i]).sum(axis=1)])
    hyp = np.vstack([hyp, [[0.0, 1.0, 1000.0]]])  # a line far from every tile
    want = R._hypothesis_counts(pt, hyp, 0.04, negate=True)
    everyone = np.arange(len(pts))
    for tile_points in (1, 7, 512, 2048, 10**6):
        assert np.array_equal(R._tiled_counts(Tiles(pts, everyone, tile_points), hyp, 0.04), want), tile_points
    assert want.max() > 500 and want[-1] == 0
    line = np.column_stack([np.linspace(0, 900, 30000), np.full(30000, 3.0)])  # one straight wall: a box of no area
    on_line = np.vstack([line.T, np.ones(len(line))])
    counts = R._tiled_counts(Tiles(line, np.arange(len(line)), 512), hyp, 0.04)
    assert np.array_equal(counts, R._hypothesis_counts(on_line, hyp, 0.04, negate=True))

    # points taken out of their tiles: the counts and near points of those left
    whole = Tiles(pts, everyone, 512)
    radius = whole.radius.copy()
    tiles, dead = whole.copy(), np.zeros(len(pts), dtype=bool)  # its own tiles to take points out of
    for h in range(5):
        gone = np.flatnonzero(~dead & (np.abs(pts @ hyp[h, :2] - hyp[h, 2]) < 0.3))
        dead[gone] = True
        tiles.remove(gone, dead)
    left = np.flatnonzero(~dead)
    assert sum(len(ids) for ids in tiles.ids) == len(left) < len(pts) - 1000
    assert sum(len(ids) for ids in whole.ids) == len(pts) and np.array_equal(whole.radius, radius)  # the copy's alone
    assert np.array_equal(R._tiled_counts(tiles, hyp, 0.04), R._hypothesis_counts(pt[:, left], hyp, 0.04, negate=True))
    sizes = []
    for h in range(len(hyp)):
        near = tiles.near_ids(hyp[h, :2], hyp[h, 2], 0.04)
        assert set(near.tolist()) <= set(left.tolist())
        inside = left[np.abs(pts[left] @ hyp[h, :2] - hyp[h, 2]) < 0.04]
        assert np.isin(inside, near).all()
        sizes.append(len(near))
    assert sizes[-1] == 0 and np.mean(sizes) < len(left) / 2  # a line's near tiles hold a part of the points

    # the counts, the refit and the segments measure the points of the near tiles only:
    # each distance the same float as over all points, also of one point or one line
    # (which numpy hands to other BLAS routines than the matrix products)
    full = hyp @ np.vstack([pt[:2], -pt[2]])  # (nx, ny, offset) by (x, y, -1): BLAS dgemm
    for k, n in ((1, 1), (1, 5), (5, 1), (2, 2), (7, 300)):
        for _ in range(10):
            h, cols = rng.choice(len(hyp), k, replace=False), rng.choice(len(pts), n, replace=False)
            out = np.empty((k, n))
            R._product(hyp[h] * [1.0, 1.0, -1.0], pt[:, cols], out)
            np.testing.assert_array_equal(out, full[np.ix_(h, cols)])
    for c in (None, pts[7]):
        all_rows = pts @ normal[3] if c is None else (pts - c) @ normal[3]
        for n in (1, 1, 1, 2, 13, 511, 29000):
            for rows in (np.sort(rng.choice(len(pts), n, replace=False)), np.arange(n) + 17):
                got = R._row_products(pts[rows] if c is None else pts[rows] - c, normal[3])
                np.testing.assert_array_equal(got, all_rows[rows])
    one = [(pts[r : r + 1] @ normal[3])[0] == (pts @ normal[3])[r] for r in range(30)]
    assert not all(one)  # numpy's one-row product rounds otherwise: why _row_products doubles it
    one = [np.array_equal(hyp[h : h + 1] * [1.0, 1.0, -1.0] @ pt[:, :30], full[h : h + 1, :30]) for h in range(30)]
    assert not all(one)  # and so does its product of one hypothesis: why _product doubles it

    params = R.RansacParams(threshold_m=0.04, iterations=300, min_points=5, min_inliers=5, max_lines=40,
                            min_length_m=0.1, max_gap_m=0.3, min_coverage=0.0, coverage_gap_m=0.3)
    built = []

    class Counted(Tiles):
        def __init__(self, xy, ids, size):
            built.append(len(ids))
            super().__init__(xy, ids, size)

    monkeypatch.setattr(R, "Tiles", Counted)
    view = np.asfortranarray(pts)  # not C-ordered: the rows are gathered as the plain loop gathers them
    for seed, tile_points in ((3, 512), (4, 64), (5, 4096)):
        monkeypatch.setattr(R, "TILED_MIN_POINTS", 10**9)
        whole = R.ransac_rows(pts, params, seed)
        monkeypatch.setattr(R, "TILED_MIN_POINTS", 20_000)
        monkeypatch.setattr(R, "TILE_POINTS", tile_points)
        built.clear()
        assert R.ransac_rows(view, params, seed) == whole and len(whole) >= 40, seed
        assert len(built) >= 3 and min(built) < len(pts) / 2  # the points left were tiled anew
    assert np.array_equal(view, pts)


def test_fast_grid_means_and_inlier_counts_equal_the_plain_numpy():
    from floorscan.core.grid import cell_groups, cell_means
    from floorscan.walls.ransac import _inlier_counts

    def _grid_means(p, cell):
        return cell_means(p, cell)[0]

    def _unique_rows(cells):
        _, counts, first = cell_groups(cells, first=True)
        return cells[first], counts

    rng = np.random.default_rng(9)
    pts = rng.uniform(-3, 5, (5000, 2))
    cell = np.floor(pts / 0.02).astype(np.int64)
    _, inv, counts = np.unique(cell, axis=0, return_inverse=True, return_counts=True)
    sums = np.zeros((len(counts), 2))
    np.add.at(sums, inv.ravel(), pts)
    np.testing.assert_array_equal(_grid_means(pts, 0.02), sums / counts[:, None])
    for x in (np.round(pts / 0.3), np.round(pts[:, :1] / 0.1)):
        for a, b in zip(_unique_rows(x), np.unique(x, axis=0, return_counts=True)):
            np.testing.assert_array_equal(a, b)
    normals = rng.normal(size=(200, 2))
    normals /= np.hypot(normals[:, 0], normals[:, 1])[:, None]
    offsets = rng.uniform(-2, 2, 200)
    expected = (np.abs(pts @ normals.T - offsets) < 0.03).sum(axis=0)
    np.testing.assert_array_equal(_inlier_counts(pts, normals, offsets, 0.03), expected)
    assert expected.max() > 50  # lines through the cloud, not only empty strips


@pytest.mark.parametrize("extractor", ["ransac", "cluster_ransac"])
def test_streamed_scans_give_the_walls_of_the_frame(extractor):
    scans = {s: with_z(raycast(ROOM, o, seed=s)) for s, o in enumerate([(1, 1), (3, 5), (2, 3)])}
    frame_walls, frame_status = extract_walls(scans_frame(scans), extractor, {"seed": 3})
    stream_walls, stream_status = extract_walls(reversed(list(scans.items())), extractor, {"seed": 3})
    pd.testing.assert_frame_equal(stream_walls, frame_walls)
    pd.testing.assert_frame_equal(stream_status.drop(columns="time_s"), frame_status.drop(columns="time_s"))
    assert len(frame_walls) >= 12 and frame_walls.scan_id.is_monotonic_increasing
    with pytest.raises(ValueError, match="scan 1"):
        extract_walls([(1, scans[1]), (1, scans[1])], extractor, {"seed": 3})


@pytest.mark.parametrize("extractor", ["ransac", "cluster_ransac"])
def test_seeded_determinism_and_input_not_mutated(extractor):
    pts = raycast(ROOM + [(1, 1, 2, 2)], (3.0, 4.0), seed=2)
    before = pts.copy()
    a, b = extract(extractor, pts, seed=11), extract(extractor, pts, seed=11)
    pd.testing.assert_frame_equal(a, b)
    np.testing.assert_array_equal(pts, before)


def scans_frame(scans):
    return pd.concat(
        [pd.DataFrame({"scan_id": s, "x": p[:, 0], "y": p[:, 1], "z": p[:, 2]}) for s, p in scans.items()],
        ignore_index=True,
    )


def with_z(p, z=0.3):
    return np.c_[p, np.full(len(p), z)]


@pytest.mark.parametrize("extractor", ["ransac", "cluster_ransac"])
def test_bad_scans_give_counted_reasons_never_a_crash(extractor):
    good = with_z(raycast(ROOM, (1.0, 1.0), seed=4))
    nan = good.copy()
    nan[5, 0] = np.nan
    line = with_z(np.c_[np.linspace(0, 3, 100), np.full(100, 2.0)])  # all collinear: one wall
    same = with_z(np.ones((50, 2)))  # all points identical: no line
    high = np.c_[np.random.default_rng(0).uniform(0, 3, (100, 2)), np.linspace(2.5, 3.0, 100)]
    scans = {0: good, 1: nan, 2: good[:5], 3: line, 4: same, 5: high}
    walls, status = extract_walls(scans_frame(scans), extractor, {"seed": 0})
    st = status.set_index("scan_id")
    assert st["reason"].to_dict() == {
        0: "", 1: "non_finite_coordinates", 2: "too_few_points", 3: "",
        4: "no_wall_found", 5: "no_points_in_height_band",
    }  # fmt: skip
    assert st["n_walls"].to_dict() == {0: 4, 1: 0, 2: 0, 3: 1, 4: 0, 5: 0}
    assert walls.groupby("scan_id").size().to_dict() == {0: 4, 3: 1}
    seg = walls[walls.scan_id == 3].iloc[0]
    np.testing.assert_allclose(sorted([seg.x0, seg.x1]), [0.0, 3.0], atol=1e-9)
    assert walls.dtypes["scan_id"] == np.int32 and walls.dtypes["n_inliers"] == np.int32


@pytest.mark.parametrize("extractor", ["ransac", "cluster_ransac"])
def test_3d_scan_is_cut_to_the_height_band(extractor):
    rng = np.random.default_rng(6)
    rings = [with_z(raycast(ROOM, (1.5, 2.2), seed=i), z) for i, z in enumerate(np.arange(0.1, 2.5, 0.2))]
    floor = np.c_[rng.uniform(0, 4, (3000, 1)), rng.uniform(0, 6, (3000, 1)), rng.normal(0, 0.01, (3000, 1))]
    ceiling = floor + [0.0, 0.0, 2.6]
    furniture = np.c_[rng.uniform(1, 3, (500, 2)), np.full((500, 1), 0.4)]  # a table top below the band
    xyz = np.vstack(rings + [floor, ceiling, furniture])
    walls, status = extract_walls(scans_frame({0: xyz}), extractor, {"seed": 0})
    assert status["reason"].tolist() == [""] and len(walls) == 4
    for wall in ROOM:
        ang, perp, ends = best_match(walls, wall)
        assert ang < 0.5 and perp < 0.01 and ends < 0.05


def test_walls_of_a_scan_do_not_depend_on_other_scans():
    scans = {s: with_z(raycast(ROOM, o, seed=s)) for s, o in enumerate([(1, 1), (3, 5), (2, 3)])}
    all_walls, _ = extract_walls(scans_frame(scans), "ransac", {"seed": 5})
    one, _ = extract_walls(scans_frame({2: scans[2]}), "ransac", {"seed": 5})
    pd.testing.assert_frame_equal(all_walls[all_walls.scan_id == 2].reset_index(drop=True), one)


def test_scan_points_2d_height_band_and_2d_rule():
    rng = np.random.default_rng(0)
    xy = rng.uniform(0, 5, (1000, 2))
    pts3 = np.c_[xy, rng.uniform(0.0, 3.0, 1000)]
    out, reason = scan_points_2d(pts3, ScanParams(grid_m=0.0))
    keep = (pts3[:, 2] >= 0.5) & (pts3[:, 2] <= 2.0)
    assert reason == "" and np.array_equal(out, xy[keep])
    flat = np.c_[xy, np.full(1000, 0.2)]  # a 2D scanner 0.2 m above the floor: below the band
    out, reason = scan_points_2d(flat, ScanParams())
    assert reason == "" and np.array_equal(out, xy)
    wall = np.c_[np.repeat(np.linspace(0, 1, 11), 20), np.zeros(220), np.tile(np.linspace(0.6, 1.9, 20), 11)]
    out, _ = scan_points_2d(wall, ScanParams(grid_m=0.02))  # 20 rings of one wall column -> 1 point
    assert len(out) == 11


def test_bad_walls_config_is_named():
    with pytest.raises(ValueError, match="height_band_m"):
        extract_walls(scans_frame({0: with_z(np.zeros((30, 2)))}), "ransac", {"height_band_m": [2.0, 0.5]})
    from floorscan.core.config import ConfigError

    with pytest.raises(ConfigError, match=r"walls\.ransac\.treshold_m: unknown key"):
        extract_walls(scans_frame({0: with_z(np.zeros((30, 2)))}), "ransac", {"ransac": {"treshold_m": 0.1}})
    with pytest.raises(ValueError, match="unknown extractor"):
        extract_walls(scans_frame({0: with_z(np.zeros((30, 2)))}), "hough", {})
    with pytest.raises(KeyError, match="scan_id"):
        extract_walls(pd.DataFrame({"x": [1.0]}), "ransac", {})


def test_first_k_walls_takes_the_first_k_scans_of_the_ordering():
    walls = pd.DataFrame(
        {"scan_id": np.array([0, 1, 1, 2, 3], dtype=np.int32), "x0": [0.0, 1, 2, 3, 4], "y0": 0.0,
         "x1": 1.0, "y1": 1.0, "n_inliers": np.int32(20), "rmse_m": 0.01}  # fmt: skip
    )
    ordering = pd.DataFrame({"rank": [2, 0, 1, 3], "scan_id": [0, 3, 1, 2]})
    seg, ids = first_k_walls(walls, ordering, "2")
    assert ids == [3, 1] and seg["scan_id"].tolist() == [3, 1, 1]
    seg, ids = first_k_walls(walls, ordering, 50)  # k > number of scans: all
    assert ids == [3, 1, 0, 2] and len(seg) == 5
    assert first_k_walls(walls, ordering, "all")[1] == ids
    assert parse_k("all") is None and parse_k("15") == 15
    for bad in ("0", "x", -1):
        with pytest.raises(ValueError, match="positive integer"):
            parse_k(bad)


def test_schema_defaults_agree_with_the_parameter_classes():
    """The options' defaults are the schema's; the extractors' thresholds are no options
    (no section of the schema) and default to the constants of floorscan.walls.params."""
    from floorscan.walls import params

    schema = yaml.safe_load((REPO / "workflow/schemas/walls.schema.yaml").read_text())["properties"]
    assert "ransac" not in schema and "cluster_ransac" not in schema and "grid_m" not in schema
    assert schema["height_band_m"]["default"] == [ScanParams.min_height_m, ScanParams.max_height_m]
    assert RansacParams() == RansacParams(**{f: getattr(params, f.upper()) for f in RansacParams.__dataclass_fields__})
    assert ClusterParams() == ClusterParams(**{f: getattr(params, f.upper()) for f in ClusterParams.__dataclass_fields__})


def _legs(center, size, leg=0.05):
    """Four square legs of a table (as wall segments: their outlines)."""
    cx, cy = center
    sx, sy = size[0] / 2 - leg / 2, size[1] / 2 - leg / 2
    out = []
    for x in (cx - sx, cx + sx):
        for y in (cy - sy, cy + sy):
            h = leg / 2
            out += [(x - h, y - h, x + h, y - h), (x + h, y - h, x + h, y + h),
                    (x + h, y + h, x - h, y + h), (x - h, y + h, x - h, y - h)]
    return out


@pytest.mark.parametrize("extractor", ["ransac", "cluster_ransac"])
def test_table_legs_give_no_wall_but_the_room_stays(extractor):
    # a 0.6 x 0.45 m table (a chair) in front of the scanner: its legs line up in pairs
    walls = ROOM + _legs((1.5, 1.5), (0.6, 0.45))
    pts = raycast(walls, (1.5, 2.2), n_rays=1440, seed=2, noise=0.005)
    df = extract(extractor, pts, seed=3)
    for wall in ROOM:
        assert best_match(df, wall)[1] < 0.01
    # every segment lies on a room wall: none through the legs
    assert len(df) == 4
    # without the coverage rule a line through the legs appears
    off = extract(extractor, pts, seed=3, params=RansacParams(min_coverage=0.0))
    assert len(off) > 4


def test_a_wall_seen_at_a_grazing_angle_is_covered():
    # 1 degree beams along a 10 m wall 1 m away: spacing grows from 2 cm to 1.7 m
    pts = raycast([(0.0, 1.0, 10.0, 1.0)], (0.0, 0.0), n_rays=360, noise=0.002)
    pts = pts[pts[:, 0] <= 6.0]  # spacing up to ~0.6 m at the far end
    df = ransac(pts, RansacParams(min_inliers=5, max_gap_m=1.0), seed=0)
    assert len(df) == 1
    assert df["x1"].max() - df["x0"].min() > 5.0


def _plain_mean_shift(x, bandwidth, min_bin_freq):
    """mean_shift in its plain form (before issue 8's shortcuts): the reference."""
    from floorscan.core.grid import cell_groups

    cells = np.round(x / bandwidth)
    _, counts, first = cell_groups(cells, first=True)
    seeds = cells[first][counts >= min_bin_freq] * bandwidth
    seeds = x.copy() if len(seeds) == len(x) else seeds
    if len(seeds) == 0:
        return np.full(len(x), -1)
    r2, means = bandwidth**2, seeds.copy()
    within, active = np.zeros(len(means), dtype=np.int64), np.ones(len(means), dtype=bool)
    for _ in range(300):
        idx = np.flatnonzero(active)
        if len(idx) == 0:
            break
        m = means[idx]
        d2 = (m**2).sum(axis=1)[:, None] - 2.0 * (m @ x.T) + (x**2).sum(axis=1)[None, :]
        w = d2 <= r2
        cnt = w.sum(axis=1)
        within[idx] = cnt
        moved = cnt > 0
        new = (w[moved].astype(np.float64) @ x) / cnt[moved, None]
        shift = np.sqrt(((new - m[moved]) ** 2).sum(axis=1))
        means[idx[moved]] = new
        done = ~moved
        done[np.flatnonzero(moved)[shift <= 1e-3 * bandwidth]] = True
        active[idx[done]] = False
    keep = within > 0
    centers, n_in = means[keep], within[keep]
    order = np.lexsort(tuple(centers[:, k] for k in range(centers.shape[1] - 1, -1, -1)) + (n_in,))[::-1]
    centers = centers[order]
    unique = np.ones(len(centers), dtype=bool)
    for i in range(len(centers)):
        if unique[i]:
            unique[((centers - centers[i]) ** 2).sum(axis=1) <= r2] = False
            unique[i] = True
    centers = centers[unique]
    return np.argmin(((x[:, None, :] - centers[None, :, :]) ** 2).sum(axis=2), axis=1)


def test_issue8_shortcuts_equal_the_plain_forms_bit_for_bit():
    """mean_shift (one BLAS product for the squared distances, only the moving seeds),
    the bin counts and the inlier counts beyond 2**16 points give exactly what the
    plain forms give; a line's segments do not depend on the order of its points."""
    from floorscan.core.grid import cell_groups
    from floorscan.walls.ransac import _inlier_counts
    from floorscan.walls.segments import claimed_segments

    rng = np.random.default_rng(11)
    one = np.r_[rng.normal(0, 0.01, 120), rng.normal(0.2, 0.01, 80), rng.normal(1.0, 0.02, 40), rng.uniform(-1, 2, 20)]
    ang = rng.normal(0, 0.02, 300) + np.repeat([0.3, 1.9, 2.5], 100)
    two = 0.5 * np.c_[np.cos(2 * ang), np.sin(2 * ang)]
    sparse = (np.arange(300) * 0.2 + rng.uniform(-0.01, 0.01, 300))[rng.permutation(300), None]  # 300 seeds and modes
    for x, bw, mbf in ((one[:, None], 0.05, 5), (two, 0.1, 5), (two, 0.03, 1), (sparse, 0.05, 1)):
        labels = mean_shift(x, bw, min_bin_freq=mbf)
        np.testing.assert_array_equal(labels, _plain_mean_shift(x, bw, mbf))
        _, counts, first = cell_groups(np.round(x / bw), first=True)
        for a, b in zip(cell_groups(np.round(x / bw), first=True, inverse=False), (counts, first)):
            np.testing.assert_array_equal(a, b)
    assert len(np.unique(mean_shift(sparse, 0.05, 1))) == 300  # > 256 modes: the pairwise loop, not the matrix
    assert len(np.unique(mean_shift(one[:, None], 0.05, 5)[:240])) == 3

    big = rng.uniform(-3, 5, (70000, 2))  # counts past the 16-bit sum
    normals = np.array([[0.0, 1.0], [1.0, 0.0], [0.6, 0.8], [-0.8, 0.6]])
    offsets = np.array([1.0, -2.5, 0.3, 4.0])
    expected = (np.abs(big @ normals.T - offsets) < 0.03).sum(axis=0)
    np.testing.assert_array_equal(_inlier_counts(big, normals, offsets, 0.03), expected)
    assert expected.min() > 100

    t = np.r_[np.linspace(0, 2, 80), np.linspace(2.8, 4, 50)]  # a wall with a 0.8 m door
    wall = np.c_[t, 1.0 + 0.005 * rng.normal(size=len(t))]
    direction = np.array([1.0, 0.0])
    shuffled = wall[rng.permutation(len(wall))]
    claimed = np.ones(len(wall), dtype=bool)
    got = claimed_segments(wall, np.array([2.0, 1.0]), direction, claimed, RansacParams())
    assert got == claimed_segments(shuffled, np.array([2.0, 1.0]), direction, claimed, RansacParams())
    assert len(got) == 2 and [r[4] for r in got] == [80, 50]
    np.testing.assert_allclose([got[0][0], got[0][2], got[1][0], got[1][2]], [0, 2, 2.8, 4], atol=0.02)


def _plain_fit_line(points):
    """fit_line as written before issue 8's third round (three separate sums)."""
    c = points.mean(axis=0)
    d = points - c
    dx, dy = d[:, 0], d[:, 1]
    phi = 0.5 * np.arctan2(2.0 * (dx * dy).sum(), (dx * dx).sum() - (dy * dy).sum())
    return c, np.array([np.cos(phi), np.sin(phi)])


def _plain_covariances(pts, radius_m, max_nn):
    """neighbourhood_covariances as written before issue 8's third round (masked zeros)."""
    from scipy.spatial import cKDTree

    n, k = len(pts), min(max_nn, len(pts))
    _, idx = cKDTree(pts).query(pts, k=k, distance_upper_bound=radius_m * (1 + 1e-9))
    idx = np.ascontiguousarray(np.asarray(idx).reshape(n, k).T)
    ok = idx < n
    idx[~ok] = 0
    x, y = pts[idx, 0], pts[idx, 1]
    dx, dy = x - pts[:, 0], y - pts[:, 1]
    ok &= dx * dx + dy * dy < radius_m * radius_m
    x[~ok], y[~ok] = 0.0, 0.0
    cnt = ok.sum(axis=0)
    m = np.maximum(cnt, 1).astype(np.float64)
    sx, sy = (x.sum(axis=0) + 0.0) / m, (y.sum(axis=0) + 0.0) / m
    sxx, sxy, syy = ((x * x).sum(axis=0) + 0.0) / m, ((x * y).sum(axis=0) + 0.0) / m, ((y * y).sum(axis=0) + 0.0) / m
    cxx, cyy, cxy = sxx - sx * sx, syy - sy * sy, sxy - sx * sy
    few = cnt < 3
    cxx[few], cyy[few], cxy[few] = 1.0, 1.0, 0.0
    return cxx, cyy, cxy


def test_issue8_third_round_shortcuts_equal_the_plain_forms_bit_for_bit():
    """fit_line's sums in one reduction, the covariances' zeros by a product, MeanShift's
    1D bin seeds by a sort, the squared distances term by term, the cell keys without
    ravel_multi_index and ``integers(n)`` for ``integers(0, n)`` give the same numbers."""
    from floorscan.core.grid import cell_groups, cell_keys
    from floorscan.walls.meanshift import _bin_seeds, _pair_squares, _row_squares
    from floorscan.walls.normals import neighbourhood_covariances
    from floorscan.walls.segments import fit_line

    rng = np.random.default_rng(12)
    for n in (*range(2, 40), 129, 1000, 9000):
        pts = rng.normal(size=(n, 2)) * [3.0, 0.01] + rng.uniform(-20, 20, 2)
        for a, b in zip(fit_line(pts), _plain_fit_line(pts)):
            np.testing.assert_array_equal(a, b)

    # negative coordinates (zeros of both signs), an isolated point, max_nn beyond the points
    t = rng.uniform(-3, 0, 300)
    pts = np.r_[np.c_[t, 0.01 * rng.normal(size=300)], rng.uniform(-2, 2, (80, 2)), [[-9.0, 0.0]]]
    for radius, max_nn in ((0.25, 20), (0.1, 3), (0.5, 1000)):
        for a, b in zip(neighbourhood_covariances(pts, radius, max_nn), _plain_covariances(pts, radius, max_nn)):
            np.testing.assert_array_equal(a, b)
            assert (np.signbit(a) == np.signbit(b)).all()

    for x, bw, mbf in ((rng.normal(0, 0.1, (500, 1)), 0.05, 5), (np.r_[-0.01, -0.02, 0.01, 3.0][:, None], 0.05, 1),
                       (np.zeros((4, 1)), 0.1, 5), (rng.normal(0, 1, (300, 2)), 0.3, 2)):
        cells = np.round(x / bw)
        _, counts, first = cell_groups(cells, first=True)
        expected = cells[first[counts >= mbf]] * bw
        np.testing.assert_array_equal(_bin_seeds(x, bw, mbf), expected)
    assert _bin_seeds(np.zeros((4, 1)), 0.1, 5).shape == (0, 1)

    for d in (1, 2, 3):
        a, b = rng.normal(size=(50, d)), rng.normal(size=(7, d))
        np.testing.assert_array_equal(_row_squares(a), (a**2).sum(axis=1))
        np.testing.assert_array_equal(_pair_squares(a, b), ((a[:, None, :] - b[None, :, :]) ** 2).sum(axis=2))
        cells = np.floor(rng.uniform(-1e4, 1e4, (500, d))).astype(np.int64)
        lo, span = cells.min(axis=0), cells.max(axis=0) - cells.min(axis=0) + 1
        np.testing.assert_array_equal(cell_keys(cells), np.ravel_multi_index(tuple((cells - lo).T), tuple(span)))
    assert cell_keys(np.array([[0, 0, 0], [2**21, 2**21, 2**21]])) is None  # beyond 2**62 cells


def test_ranks_in_runs_number_each_run_from_zero():
    from floorscan.core.grid import ranks_in_runs

    assert ranks_in_runs(np.array([2, 0, 3, 1])).tolist() == [0, 1, 0, 1, 2, 0]
    assert ranks_in_runs(np.array([0, 0])).tolist() == [] and ranks_in_runs(np.array([], dtype=int)).dtype == np.int64


def test_unique_ints_are_numpy_unique_by_a_sort():
    """unique_ints gives numpy.unique's values and dtype: empty, one value, negative keys,
    repeats and the int16/int32/int64 arrays the stages hold."""
    from floorscan.core.grid import unique_ints

    rng = np.random.default_rng(5)
    cases = [np.zeros(0, np.int64), np.array([7]), np.array([3, 3, 3], np.int32), rng.integers(-50, 50, 1000),
             rng.integers(0, 2**40, 20_000), rng.integers(-3, 3, 999).astype(np.int16)]
    for values in cases:
        got = unique_ints(values)
        np.testing.assert_array_equal(got, np.unique(values))
        assert got.dtype == values.dtype
    assert unique_ints(np.array([5, -2, 5, 0, -2])).tolist() == [-2, 0, 5]

    for n in (2, 3, 129, 2000):
        r1, r2 = np.random.default_rng((0, n)), np.random.default_rng((0, n))
        np.testing.assert_array_equal(r1.integers(0, n, size=200), r2.integers(n, size=200))
        np.testing.assert_array_equal(r1.integers(0, n - 1, size=200), r2.integers(n - 1, size=200))


def _plain_best_line(points, rng, params):
    """_best_line as written before issue 8's fourth round (row gathers, einsum offsets)."""
    from floorscan.walls.ransac import _inlier_counts, _refine_line

    n = len(points)
    i = rng.integers(n, size=params.iterations)
    j = rng.integers(n - 1, size=params.iterations)
    j += j >= i
    start = points[i]
    d = points[j] - start
    length = np.hypot(d[:, 0], d[:, 1])
    ok = length > 1e-9
    if not ok.any():
        return None
    d, length, start = d[ok], length[ok], start[ok]
    normals = d[:, ::-1] * np.array([-1.0, 1.0])
    normals /= length[:, None]
    offsets = np.einsum("ij,ij->i", normals, start)
    best = int(np.argmax(_inlier_counts(points, normals, offsets, params.threshold_m)))
    return _refine_line(points, normals[best], offsets[best], params)  # the refit is shared


def test_issue8_fourth_round_shortcuts_equal_the_plain_forms_bit_for_bit():
    """The RANSAC hypotheses built on coordinate columns (offsets as a sum of two
    products instead of einsum) and the 3D grid thinning on contiguous columns give
    the same lines and points as the plain forms; the same seed, the same line."""
    from floorscan.core.grid import cell_means
    from floorscan.walls.ransac import _best_line

    rng = np.random.default_rng(13)
    nrm = rng.normal(size=(100000, 2))
    nrm /= np.hypot(nrm[:, 0], nrm[:, 1])[:, None]
    start = rng.uniform(-60, 60, (100000, 2))
    np.testing.assert_array_equal(nrm[:, 0] * start[:, 0] + nrm[:, 1] * start[:, 1], np.einsum("ij,ij->i", nrm, start))

    room = np.vstack([raycast(ROOM, o, seed=s) for s, o in enumerate([(1, 1), (3, 5)])]) + [-31.7, 12.4]
    dup = np.r_[room[:5], room[:5]]  # only duplicate pairs: no hypothesis
    for params in (RansacParams(), RansacParams(iterations=7, refine_iterations=0), RansacParams(refine_iterations=5)):
        for pts in (room, room[:40], room[::-1][:333], np.r_[room[:3], room[:3], room[:2]], dup):
            for seed in range(3):
                got = _best_line(pts, np.random.default_rng(seed), params)
                want = _plain_best_line(pts, np.random.default_rng(seed), params)
                if want is None:
                    assert got is None
                    continue
                for a, b in zip(got, want):
                    np.testing.assert_array_equal(a, b)
    assert _best_line(dup[:1], np.random.default_rng(0), RansacParams()) is None
    mask, c, direction = _best_line(room, np.random.default_rng(0), RansacParams())
    assert mask.sum() > 150 and abs(abs(direction[0]) * abs(direction[1])) < 1e-2  # a wall of the room

    # 3D scan in the map frame (negative coordinates): band cut and one mean per 2 cm cell
    n = 20000
    xyz = np.c_[rng.uniform(-45.3, -38.1, n), rng.uniform(7.2, 13.9, n), rng.uniform(-0.2, 2.8, n)]
    for scan in (ScanParams(), ScanParams(grid_m=0.05), ScanParams(grid_m=0.0), ScanParams(min_height_m=1.0, max_height_m=1.2)):
        band = xyz[(xyz[:, 2] >= scan.min_height_m) & (xyz[:, 2] <= scan.max_height_m), :2]
        want = cell_means(band, scan.grid_m)[0] if scan.grid_m > 0 else band
        got, reason = scan_points_2d(xyz, scan)
        assert reason == "" and got.shape == want.shape and len(got) > 100
        np.testing.assert_array_equal(got, want)
    assert scan_points_2d(xyz, ScanParams(min_height_m=5.0, max_height_m=6.0))[1] == "no_points_in_height_band"


def test_the_schema_enum_names_the_registered_extractors():
    from floorscan.walls.extractors import EXTRACT_KEYS, EXTRACTORS, get_extractor

    schema = yaml.safe_load((REPO / "workflow/schemas/walls.schema.yaml").read_text())["properties"]
    assert schema["extractors"]["items"]["enum"] == list(EXTRACTORS) == ["ransac", "cluster_ransac"]
    assert EXTRACT_KEYS == ("seed", "height_band_m")
    assert all(key in schema for key in EXTRACT_KEYS)
    with pytest.raises(ValueError, match="unknown extractor 'hough'; expected one of"):
        get_extractor("hough")


def test_a_registered_extractor_runs_with_its_config_sections(monkeypatch):
    from floorscan.walls import extractors

    calls = []

    def rows(points, params, cluster, seed):
        calls.append((len(points), params.min_points, cluster.min_cluster_points, seed))
        return [(0.0, 0.0, 1.0, 0.0, 20, 0.01)] if len(calls) == 1 else []

    entry = extractors.Extractor(rows=rows, config={"ransac": RansacParams, "cluster_ransac": ClusterParams}, cost=1.0)
    monkeypatch.setitem(extractors.REGISTRY, "fake", entry)
    scans = {4: with_z(raycast(ROOM, (1, 1), seed=0)), 7: with_z(raycast(ROOM, (2, 3), seed=1))}
    cfg = {"seed": 2, "ransac": {"min_points": 25}, "cluster_ransac": {"min_cluster_points": 9}}
    walls, status = extract_walls(scans_frame(scans), "fake", cfg)
    assert calls == [(len(scans[4]), 25, 9, (2, 4)), (len(scans[7]), 25, 9, (2, 7))]
    assert walls["scan_id"].tolist() == [4] and walls["n_inliers"].tolist() == [20]
    assert status["reason"].tolist() == ["", "no_wall_found"]


def test_k_walls_tables_in_the_order_of_the_rule():
    from floorscan.walls.first_k import k_walls_tables

    walls = pd.DataFrame(
        {"scan_id": np.array([0, 1, 2], dtype=np.int32), "x0": [0.0, 1, 2], "y0": 0.0,
         "x1": 1.0, "y1": 1.0, "n_inliers": np.int32(20), "rmse_m": 0.01}  # fmt: skip
    )
    orderings = {"a": pd.DataFrame({"rank": [0, 1, 2], "scan_id": [2, 0, 1]}),
                 "b": pd.DataFrame({"rank": [0, 1, 2], "scan_id": [1, 2, 0]})}
    got = [(o, k, seg["scan_id"].tolist(), ids) for o, k, seg, ids in k_walls_tables(walls, orderings, ["b", "a"], ["1", "all"])]
    assert got == [("b", "1", [1], [1]), ("b", "all", [1, 2, 0], [1, 2, 0]),
                   ("a", "1", [2], [2]), ("a", "all", [2, 0, 1], [2, 0, 1])]

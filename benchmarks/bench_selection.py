"""Benchmark of the hulls and select stages (issue 5; thesis section 3.3, Table 5.1).

Run: ``.venv/bin/python -m benchmarks.bench_selection [--quick]``

Prints
- hull creation, ms per scan, for 2D scans (~700 points) and 3D scans (~20k points);
- the full ``cluster_hull`` ordering of 1000 scans by the lazy greedy and by the
  reference Algorithm 1 in the same run: times, ratio, and whether the orderings are
  identical (they must be);
- the full ``cluster_hull`` ordering of the 5000-scan ``hallways`` recording
  (``results/hallways/hulls.parquet`` when it exists, else 5000 synthetic scans made
  here), target under 10 s on 2 cores;
- with ``--hallways3d DIR`` (a hallways3d result set: registered.parquet,
  registration.parquet, hulls.parquet, convex_hulls.parquet, orderings/), the CPU
  seconds (``time.process_time``, imports excluded) of the hulls stage's work on the
  first 509 kept scans, of the select stage and of the three selection figures
  (issue 8: these stages' CPU counts toward the 10x real-time target);
- the ``wall_coverage`` and ``surface_coverage`` orderings (issue 22) of 1000 and 5000
  synthetic scans (walls by :func:`floorscan.walls.ransac.ransac`, not timed): the cells,
  the lazy greedy and the plain greedy (:func:`floorscan.core.greedy.plain_greedy`)
  side by side, and whether their orderings are identical (they must be).

The synthetic scans are ray cast in numpy against a Shapely floor plan (corridor
ring with rooms off it), a rover path along the corridors; no timed assertions.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import shapely
import sklearn.cluster  # noqa: F401  (imported first: the hull timings exclude its import)
from shapely.geometry import box

from floorscan.select import greedy
from floorscan.select import hulls as fh
from floorscan.select.orderings import select_stage
from floorscan.select.params import HullParams, SelectParams
from floorscan.select.raster import RasterCoverage
from floorscan.select.summary import k_for_fraction


# ----------------------------------------------------------------------------------
# Synthetic scans: ray casting against a polygonal floor plan
# ----------------------------------------------------------------------------------
def hallway_building(n_rooms_per_side: int = 6) -> shapely.Geometry:
    """Free space of a building: a rectangular corridor ring (2.4 m wide, 72 x 30 m)
    with rooms (6 x 5 m) off its outside, joined by 1 m doors. Metres."""
    outer = box(0, 0, 72, 30)
    inner = box(2.4, 2.4, 72 - 2.4, 30 - 2.4)
    parts = [outer.difference(inner)]
    step = 72 / n_rooms_per_side
    for i in range(n_rooms_per_side):
        x0 = i * step + 3
        for y_room, y_door in (((-5.2, -0.2), (-0.3, 0.1)), ((30.2, 35.2), (29.9, 30.3))):
            parts.append(box(x0, y_room[0], x0 + 6, y_room[1]))
            parts.append(box(x0 + 2.5, y_door[0], x0 + 3.5, y_door[1]))
    return shapely.union_all(parts)


def hallway_path(n_scans: int, seed: int = 0) -> np.ndarray:
    """(n_scans, 3) poses x, y (m), yaw (rad) along the corridor ring, looping as
    often as needed with 2 cm noise, so neighbouring scans overlap strongly."""
    rng = np.random.default_rng(seed)
    ring = np.array([[1.2, 1.2], [70.8, 1.2], [70.8, 28.8], [1.2, 28.8], [1.2, 1.2]])
    seg = np.diff(ring, axis=0)
    seg_len = np.hypot(seg[:, 0], seg[:, 1])
    cum = np.r_[0, np.cumsum(seg_len)]
    s = np.linspace(0, 2 * cum[-1], n_scans, endpoint=False) % cum[-1]  # two laps
    i = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, len(seg) - 1)
    frac = (s - cum[i]) / seg_len[i]
    xy = ring[i] + seg[i] * frac[:, None] + rng.normal(0, 0.02, (n_scans, 2))
    yaw = np.arctan2(seg[i, 1], seg[i, 0]) + rng.normal(0, 0.02, n_scans)
    return np.column_stack([xy, yaw])


def _segments(free: shapely.Geometry) -> np.ndarray:
    rings = [free.exterior, *free.interiors] if free.geom_type == "Polygon" else [
        r for p in free.geoms for r in (p.exterior, *p.interiors)
    ]
    segs = [np.column_stack([np.asarray(r.coords)[:-1], np.asarray(r.coords)[1:]]) for r in rings]
    return np.concatenate(segs)  # (M, 4) x0 y0 x1 y1


def ray_cast(free, pose, n_beams=720, fov_rad=2 * np.pi, max_range_m=12.0,
             noise_m=0.01, rng=None) -> np.ndarray:
    """Ranges (n_beams,) of a 2D scan at ``pose`` (x, y, yaw) against the walls of
    ``free``; inf for no return within ``max_range_m``."""
    segs = free if isinstance(free, np.ndarray) else _segments(free)
    ang = pose[2] + np.linspace(-fov_rad / 2, fov_rad / 2, n_beams, endpoint=False)
    d = np.column_stack([np.cos(ang), np.sin(ang)])  # (B, 2)
    p0 = segs[:, :2] - pose[:2]
    e = segs[:, 2:] - segs[:, :2]  # (M, 2)
    den = d[:, 0:1] * e[None, :, 1] - d[:, 1:2] * e[None, :, 0]  # (B, M)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (p0[None, :, 0] * e[None, :, 1] - p0[None, :, 1] * e[None, :, 0]) / den
        u = (p0[None, :, 0] * d[:, 1:2] - p0[None, :, 1] * d[:, 0:1]) / den
    t = np.where((den != 0) & (t > 1e-9) & (u >= 0) & (u <= 1), t, np.inf)
    r = t.min(axis=1)
    if rng is not None and noise_m > 0:
        r = r + rng.normal(0, noise_m, r.shape)
    return np.where(r <= max_range_m, r, np.inf)


def simulate_scans(n_scans: int, seed: int = 0, three_d: bool = False,
                   n_beams: int = 720) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Synthetic registered scans of :func:`hallway_building`.

    Returns ``(registered, registration)`` frames in the registration stage's
    contract (map-frame points; one row per scan with the pose). 3D scans have 16
    rings from -15 to +15 degrees, 0.3 m scanner height: a ring hits the floor where
    that is nearer than the wall, giving ~20k points.
    """
    rng = np.random.default_rng(seed)
    free = hallway_building()
    segs = _segments(free)
    poses = hallway_path(n_scans, seed)
    frames = []
    elev = np.deg2rad(np.linspace(-15, 15, 16)) if three_d else np.zeros(1)
    for sid, pose in enumerate(poses):
        ang = pose[2] + np.linspace(-np.pi, np.pi, n_beams, endpoint=False)
        r = ray_cast(segs, pose, n_beams=n_beams, rng=rng, max_range_m=30.0 if three_d else 12.0)
        pts = []
        for el in elev:
            rr = r.copy()
            z = np.zeros_like(rr)
            if el < 0:
                floor = 0.3 / np.tan(-el)
                rr = np.minimum(rr, floor)
            z = 0.3 + np.where(np.isfinite(rr), rr, 0.0) * np.tan(el)
            ok = np.isfinite(rr)
            pts.append(np.column_stack([pose[0] + rr[ok] * np.cos(ang[ok]),
                                        pose[1] + rr[ok] * np.sin(ang[ok]), z[ok]]))
        p = np.concatenate(pts)
        frames.append(pd.DataFrame({"scan_id": np.int32(sid), "x": p[:, 0].astype(np.float32),
                                    "y": p[:, 1].astype(np.float32), "z": p[:, 2].astype(np.float32)}))
    registered = pd.concat(frames, ignore_index=True)
    registration = pd.DataFrame({
        "scan_id": np.arange(n_scans, dtype=np.int32),
        "t_ns": (1_700_000_000 * 10**9 + np.arange(n_scans) * 100_000_000).astype(np.int64),
        "kept": True, "x_m": poses[:, 0], "y_m": poses[:, 1], "yaw_rad": poses[:, 2],
    })
    return registered, registration


# ----------------------------------------------------------------------------------
def _timed(fn, *a, **k):
    t0 = time.perf_counter()
    out = fn(*a, **k)
    return out, time.perf_counter() - t0


def _hull_bench(n_scans: int, three_d: bool) -> None:
    reg, _ = simulate_scans(n_scans, seed=3, three_d=three_d)
    pts = len(reg) / n_scans
    _, t_cluster = _timed(fh.cluster_hulls, reg, HullParams())
    _, t_convex = _timed(fh.convex_hulls, reg)
    kind = "3D" if three_d else "2D"
    print(f"hull creation {kind}: {n_scans} scans, {pts:.0f} points/scan: "
          f"cluster hulls {t_cluster / n_scans * 1e3:.2f} ms/scan, convex hull {t_convex / n_scans * 1e3:.3f} ms/scan")


def _coverage(n_scans: int, seed: int):
    reg, regi = simulate_scans(n_scans, seed=seed)
    hulls, t = _timed(fh.cluster_hulls, reg, HullParams())
    ids, geoms = fh.scan_coverage(hulls)
    return ids, geoms, t


def _coverage_orderings_bench(n_scans: int, seed: int) -> None:
    """Both coverage orderings of ``n_scans`` synthetic 2D scans: the cell sets, the
    lazy greedy and the plain greedy, seconds."""
    from floorscan.core.greedy import lazy_greedy, plain_greedy
    from floorscan.select.coverage import surface_cells, wall_cells
    from floorscan.select.params import CoverageParams
    from floorscan.walls.ransac import ransac

    registered, _ = simulate_scans(n_scans, seed=seed)
    scans = [(int(s), g[["x", "y"]].to_numpy(np.float64)) for s, g in registered.groupby("scan_id", sort=True)]
    per_scan = pd.concat([ransac(xy, seed=s).assign(scan_id=s) for s, xy in scans], ignore_index=True)
    ids = [s for s, _ in scans]
    params = CoverageParams()
    for name, make in (("wall_coverage", lambda: wall_cells(per_scan, params)),
                       ("surface_coverage", lambda: surface_cells(scans, params))):
        sets, t_cells = _timed(make)
        lazy, t_lazy = _timed(lazy_greedy, sets[0], ids, sets[1], sets[2])
        plain, t_plain = _timed(plain_greedy, sets[0], ids, sets[1], sets[2])
        same = lazy.equals(plain)
        adds = int((lazy["gain"] > 0).sum())
        print(f"{name} of {n_scans} scans: cells {t_cells:.2f} s, lazy greedy {t_lazy:.3f} s, plain greedy "
              f"{t_plain:.2f} s (ratio {t_plain / max(t_lazy, 1e-9):.0f}x); {adds} scans add coverage; "
              f"identical ordering {same}")


def _hallways3d_cpu(root: Path) -> None:
    """CPU seconds of the hulls, select and selection-figure work on a hallways3d
    result set (issue 8)."""
    import tempfile

    from floorscan.figures.selection import selection_figures
    from floorscan.select.figure_data import FigureParams, selection_figure_data
    from floorscan.core.io import iter_scans, read_table

    registration = read_table(root / "registration.parquet")
    kept = fh.kept_scan_ids(registration)
    last = int(kept[len(kept) // 2 - 1])  # the first of two shards
    t0 = time.process_time()
    _, _, counts = fh.compute_hulls(iter_scans(root / "registered.parquet", ("x", "y"), scan_range=(0, last)),
                                    registration[registration["scan_id"] <= last], HullParams())
    t_hulls = time.process_time() - t0
    hulls, convex = read_table(root / "hulls.parquet"), read_table(root / "convex_hulls.parquet")
    t0 = time.process_time()
    orderings, _ = select_stage(hulls, convex, registration)
    t_select = time.process_time() - t0
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.process_time()
        data = selection_figure_data(root / "registered.parquet", registration, hulls, orderings, HullParams(),
                                     SelectParams(), FigureParams(), convex_hulls=convex)
        selection_figures(orderings, data.k99, data.clusters, data.timing,
                          *(Path(tmp) / f"{n}.png" for n in "abc"), title="hallways3d")
        t_fig = time.process_time() - t0
    print(f"hallways3d [{root}]: hulls of {counts['n_scans']} scans {t_hulls:.2f} CPU-s, select of "
          f"{len(kept)} scans {t_select:.2f} CPU-s, selection figures {t_fig:.2f} CPU-s")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="smaller sizes (smoke run)")
    ap.add_argument("--raster-m", type=float, default=SelectParams().raster_m)
    ap.add_argument("--hallways3d", type=Path, help="a hallways3d result set: time its hulls/select/figures")
    args = ap.parse_args(argv)
    if args.hallways3d:
        _hallways3d_cpu(args.hallways3d)
        return
    n_ref = 200 if args.quick else 1000
    n_big = 1000 if args.quick else 5000
    res = args.raster_m
    print(f"bench_selection: raster {res} m, {'quick' if args.quick else 'full'} run")

    _hull_bench(50 if args.quick else 200, three_d=False)
    _hull_bench(5 if args.quick else 20, three_d=True)

    ids, geoms, _ = _coverage(n_ref, seed=4)
    stats: dict = {}
    fast, t_fast = _timed(greedy.greedy_coverage, ids, geoms, res, stats=stats)
    ref, t_ref = _timed(greedy.greedy_reference, ids, geoms, res)
    same = np.array_equal(fast["scan_id"].to_numpy(), ref["scan_id"].to_numpy())
    same_gain = np.array_equal(fast["gain_m2"].to_numpy(), ref["gain_m2"].to_numpy())
    print(f"full ordering of {len(ids)} scans: lazy greedy {t_fast:.3f} s "
          f"({stats['evaluations']} gain evaluations), reference Algorithm 1 {t_ref:.2f} s "
          f"({len(ids) * (len(ids) + 1) // 2} evaluations): ratio {t_ref / t_fast:.0f}x; "
          f"identical ordering {same}, identical gains {same_gain}")

    for n in ((200, 1000) if args.quick else (1000, 5000)):
        _coverage_orderings_bench(n, seed=6)

    hall = Path("results/hallways")
    if (hall / "hulls.parquet").exists() and (hall / "registration.parquet").exists():
        from floorscan.core.io import read_table

        registration = read_table(hall / "registration.parquet")
        ids, geoms = fh.scan_coverage(read_table(hall / "hulls.parquet"), fh.kept_scan_ids(registration))
        source = "results/hallways/hulls.parquet"
    else:
        ids, geoms, t_h = _coverage(n_big, seed=5)
        source = f"synthetic ({n_big} scans; hull creation {t_h:.1f} s, not counted)"
    stats = {}
    big, t_big = _timed(greedy.greedy_coverage, ids, geoms, res, stats=stats)
    _, t_raster = _timed(RasterCoverage, geoms, res)
    print(f"full cluster_hull ordering of {len(ids)} scans [{source}]: {t_big:.2f} s "
          f"(of which rasterisation {t_raster:.2f} s; {stats['evaluations']} evaluations; "
          f"target < 10 s), covered {big['covered_area_m2'].iloc[-1]:.1f} m2, "
          f"99 % after {k_for_fraction(big, 0.99)} scans")


if __name__ == "__main__":
    main(sys.argv[1:])

"""Wall extraction per scan: ransac against cluster_ransac (thesis Fig. 5.10), and a
loop of Open3D's ``segment_plane`` as the library baseline, on the real recordings.

Per dataset: time per scan (mean, median, 95th percentile) and walls per scan for
each extractor with the default ``walls`` config (schema defaults), cluster_ransac
also with scikit-learn's MeanShift (``meanshift: sklearn``), and the ratios.
The scans are ``results/<dataset>/registered.parquet`` (map frame, kept scans); when
it is absent, ``scans.parquet`` (scanner frame, all scans): the walls of one scan do
not depend on its frame (the clustering works around the cluster centroid), so the
per-scan figures are the same. A dataset with neither is skipped with a message.
With registered scans, the segments of the benchmarked scans are also merged into a
floor plan (faces and walls after the merge: one wall per wall).

The baseline embeds a 2D scan in 3D with a random height in [0, 1] m per point (a
2D scan at one height is itself a plane; vertical walls need a height) and removes
the inliers of ``segment_plane`` (same threshold, iterations, min inliers and max
lines as ``ransac``) until fewer than ``min_points`` remain. It finds planes, not
segments (no gap splitting), so its count is of lines, not wall segments.

Run: ``.venv/bin/python -m benchmarks.bench_walls [--max-scans N] [datasets ...]``.

Shard mode (issue 8: the cost of one ``scan_walls`` job): ``--shard PATH START STOP``
times :func:`floorscan.walls.extract.extract_walls` on the scans START..STOP of a points
table (e.g. hallways3d's ``registered.parquet``, scans 0..1694), per extractor with
the default config: CPU seconds (``time.process_time``) and wall seconds, ms per
scan, ``--repeats`` times (the scans are read once, before timing).
"""
from __future__ import annotations

import argparse
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np
import pandas as pd
import yaml

from floorscan.floorplan.plan import build_floorplan
from floorscan.core.io import iter_scans, read_table, split_by_scan
from floorscan.walls.extract import extract_scan, extract_walls
from floorscan.core.config import stage_params
from floorscan.walls.extractors import EXTRACTORS, REGISTRY
from floorscan.walls.params import ClusterParams, RansacParams
from floorscan.core.wall_points import ScanParams, scan_points_2d

REPO = Path(__file__).resolve().parents[1]
DATASETS = ["intel", "aces", "freiburg101", "orebro", "trace0", "mac_ros2"]


def schema_defaults(path: Path) -> dict:
    props = yaml.safe_load(path.read_text())["properties"]
    out = {}
    for k, v in props.items():
        if v.get("type") == "object" and "properties" in v:
            out[k] = {kk: vv["default"] for kk, vv in v["properties"].items()}
        elif "default" in v:
            out[k] = v["default"]
    return out


def load_scans(ds: str):
    base = REPO / "results" / ds
    for name, note in (("registered.parquet", "map frame, kept scans"), ("scans.parquet", "scanner frame, all scans; registered.parquet absent")):
        if (base / name).exists():
            return split_by_scan(read_table(base / name)), f"{name} ({note})"
    return None, "no registered.parquet or scans.parquet"


def o3d_plane_loop(xyz2d: np.ndarray, rp, seed: int) -> int:
    """Planes found by repeated Open3D segment_plane on 3D-embedded points."""
    import open3d as o3d

    rng = np.random.default_rng(seed)
    pts = np.c_[xyz2d, rng.uniform(0.0, 1.0, len(xyz2d))]
    o3d.utility.random.seed(seed)
    n = 0
    while len(pts) >= rp.min_points and n < rp.max_lines:
        pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts))
        _, inl = pcd.segment_plane(distance_threshold=rp.threshold_m, ransac_n=3, num_iterations=rp.iterations)
        if len(inl) < rp.min_inliers:
            break
        n += 1
        keep = np.ones(len(pts), dtype=bool)
        keep[np.asarray(inl)] = False
        pts = pts[keep]
    return n


def stats(times: list[float]) -> str:
    t = np.asarray(times) * 1e3
    return f"{t.mean():7.1f} {np.median(t):7.1f} {np.percentile(t, 95):7.1f}"


def time_shard(path: str, start: int, stop: int, repeats: int) -> None:
    """CPU and wall ms per scan of extract_walls on one scan range, per extractor."""
    scans = list(iter_scans(path, ("x", "y", "z"), scan_range=(start, stop)))
    n = max(len(scans), 1)
    import scipy.spatial  # noqa: F401  (imported by a job before its first scan)

    print(f"{path}: scans {start}..{stop}: {len(scans)} scans, {np.mean([len(p) for _, p in scans]):.0f} points/scan")
    for extractor in EXTRACTORS:
        cpu, wall = [], []
        for _ in range(repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            walls, _ = extract_walls(iter(scans), extractor, {})
            cpu.append(time.process_time() - c0)
            wall.append(time.perf_counter() - t0)
        print(
            f"  {extractor:15s} CPU ms/scan {' '.join(f'{1e3 * c / n:6.2f}' for c in cpu)}   "
            f"wall ms/scan {' '.join(f'{1e3 * w / n:6.2f}' for w in wall)}   ({len(walls)} wall segments)"
        )


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("datasets", nargs="*", default=DATASETS)
    ap.add_argument("--max-scans", type=int, default=150, help="evenly spaced subset per dataset (0 = all)")
    ap.add_argument("--shard", nargs=3, metavar=("PATH", "START", "STOP"), help="time extract_walls on one scan range")
    ap.add_argument("--repeats", type=int, default=3, help="shard mode: timed runs per extractor")
    args = ap.parse_args(argv if argv is not None else [])
    if args.shard:
        time_shard(args.shard[0], int(args.shard[1]), int(args.shard[2]), args.repeats)
        return
    cfg = schema_defaults(REPO / "workflow/schemas/walls.schema.yaml")
    scan_p = stage_params(ScanParams, cfg)
    rp, cp = stage_params(RansacParams, cfg.get("ransac")), stage_params(ClusterParams, cfg.get("cluster_ransac"))
    from floorscan.walls.cluster import cluster_ransac  # noqa: F401  (warm imports)
    import open3d  # noqa: F401
    import sklearn.cluster  # noqa: F401

    print(f"config: walls schema defaults; ransac {rp}; cluster_ransac {cp}")
    print("times in ms per scan: mean median p95; walls = segments per scan (mean)")
    summary = []
    for ds in args.datasets:
        scans, source = load_scans(ds)
        if scans is None:
            print(f"\n{ds}: skipped ({source})")
            continue
        ids = sorted(scans)
        if args.max_scans and len(ids) > args.max_scans:
            ids = [ids[i] for i in np.linspace(0, len(ids) - 1, args.max_scans).round().astype(int)]
        npts = np.mean([len(scans[s]) for s in ids])
        print(f"\n{ds}: {len(ids)} of {len(scans)} scans from {source}, {npts:.0f} points/scan")
        res = {}
        params = {key: stage_params(c, cfg.get(key)) for e in REGISTRY.values() for key, c in e.config.items()}
        params_sk = {**params, "cluster_ransac": dataclasses.replace(cp, meanshift="sklearn")}
        runs = (("ransac", "ransac", params), ("cluster_ransac", "cluster_ransac", params),
                ("cluster_sklearn", "cluster_ransac", params_sk))
        for label, ex, pp in runs:
            times, walls, fails, segs = [], [], 0, []
            for s in ids:
                t0 = time.perf_counter()
                seg, reason, _ = extract_scan(scans[s], ex, scan_p, pp, (0, s))
                times.append(time.perf_counter() - t0)
                walls.append(len(seg))
                fails += bool(reason)
                segs.append(seg)
            res[label] = (np.mean(times), np.mean(walls))
            merged = ""
            if source.startswith("registered") and label != "cluster_sklearn":
                t0 = time.perf_counter()
                plan = build_floorplan(pd.concat(segs, ignore_index=True))
                merged = (
                    f"; merged floor plan: {len(plan.faces)} faces, {len(plan.walls)} walls "
                    f"({int(plan.walls.paired.sum())} paired) in {time.perf_counter() - t0:.2f} s"
                )
            print(
                f"  {label:15s} {stats(times)}   walls/scan {np.mean(walls):5.2f} "
                f"(total {sum(walls)}, {fails} scans without walls){merged}"
            )
        times, planes = [], []
        for s in ids:
            pts2d, reason = scan_points_2d(scans[s], scan_p)
            t0 = time.perf_counter()
            planes.append(o3d_plane_loop(pts2d, rp, s) if not reason else 0)
            times.append(time.perf_counter() - t0)
        res["o3d"] = (np.mean(times), np.mean(planes))
        print(f"  {'o3d plane loop':15s} {stats(times)}   planes/scan {np.mean(planes):5.2f}")
        r, c, k, o = res["ransac"], res["cluster_ransac"], res["cluster_sklearn"], res["o3d"]
        print(
            f"  ratios: time cluster_ransac/ransac {c[0] / r[0]:.2f}, cluster(sklearn MeanShift)/cluster(numpy) "
            f"{k[0] / c[0]:.1f}, o3d loop/ransac {o[0] / r[0]:.2f}; walls cluster_ransac/ransac {c[1] / max(r[1], 1e-9):.2f}"
        )
        summary.append((ds, len(ids), npts, r, c, k, o))
    if summary:
        print("\n| dataset | scans | pts/scan | ransac ms | ransac walls | cluster ms | cluster walls | cluster (sklearn MS) ms | o3d loop ms | o3d planes |")
        print("|---|---|---|---|---|---|---|---|---|---|")
        for ds, n, npts, r, c, k, o in summary:
            print(f"| {ds} | {n} | {npts:.0f} | {r[0]*1e3:.1f} | {r[1]:.2f} | {c[0]*1e3:.1f} | {c[1]:.2f} | {k[0]*1e3:.1f} | {o[0]*1e3:.1f} | {o[1]:.2f} |")


if __name__ == "__main__":
    main(sys.argv[1:])

"""Registration throughput (scans/s) for 2D and 3D scans.

Run: ``.venv/bin/python -m benchmarks.bench_registration``. 2D: the trace0 recording
when its ingest outputs exist (results/trace0), and a synthetic 2D recording; 3D: a
synthetic box room sampled by a 16-beam spinning LIDAR (1800 points per ring, walls,
floor and ceiling), since no 3D recording is available yet.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import pandas as pd

from floorscan.registration import register_scans

REPO = Path(__file__).resolve().parents[1]


def box_scan(pose, n_az=1800, elevations=(0.0,), size=(12.0, 8.0), height=3.0, z0=0.5, rng=None):
    """Points (scanner frame) of a scanner at (x, y, yaw), z0 above the floor, in a box room
    [0, size_x] x [0, size_y] x [0, height], one ring per elevation (radians)."""
    x, y, yaw = pose
    az = np.arange(n_az) * 2 * np.pi / n_az
    out = []
    for el in elevations:
        d = np.stack([np.cos(az + yaw) * math.cos(el), np.sin(az + yaw) * math.cos(el), np.full(n_az, math.sin(el))], 1)
        with np.errstate(divide="ignore"):
            tx = np.where(d[:, 0] > 0, (size[0] - x) / d[:, 0], np.where(d[:, 0] < 0, -x / d[:, 0], np.inf))
            ty = np.where(d[:, 1] > 0, (size[1] - y) / d[:, 1], np.where(d[:, 1] < 0, -y / d[:, 1], np.inf))
            tz = np.where(d[:, 2] > 0, (height - z0) / d[:, 2], np.where(d[:, 2] < 0, -z0 / d[:, 2], np.inf))
        r = np.minimum(np.minimum(tx, ty), tz)
        if rng is not None:
            r = r + rng.normal(0, 0.01, len(r))
        local = np.stack([np.cos(az) * math.cos(el), np.sin(az) * math.cos(el), np.full(n_az, math.sin(el))], 1) * r[:, None]
        out.append(local)
    return np.concatenate(out)


def synthetic(n_scans, elevations, n_az, seed=0):
    rng = np.random.default_rng(seed)
    s = np.arange(n_scans) * 0.05
    poses = np.stack([2 + s % 8, 3 + 0.5 * np.sin(s), 0.2 * np.sin(s / 2)], 1)
    t = 1_700_000_000_000_000_000 + np.arange(n_scans, dtype=np.int64) * 100_000_000
    rows = []
    for i, p in enumerate(poses):
        pts = box_scan(p, n_az=n_az, elevations=elevations, rng=rng)
        rows.append(pd.DataFrame({"scan_id": np.int32(i), "x": pts[:, 0], "y": pts[:, 1], "z": pts[:, 2]}))
    scans = pd.concat(rows, ignore_index=True)
    index = pd.DataFrame({"scan_id": np.arange(n_scans, dtype=np.int32), "t_ns": t})
    err = rng.normal(0, [0.03, 0.03, 0.01], (n_scans, 3))
    posed = pd.DataFrame({"scan_id": index["scan_id"], "t_ns": t, "x": poses[:, 0] + err[:, 0],
                          "y": poses[:, 1] + err[:, 1], "z": 0.5, "yaw": poses[:, 2] + err[:, 2],
                          "valid": True, "reason": ""})
    return scans, index, posed


def run(name, scans, index, poses, cfg, repeat=2):
    best = math.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        r = register_scans(scans, index, poses, cfg)
        best = min(best, time.perf_counter() - t0)
    n = r.summary["n_sampled"]
    pts = scans.groupby("scan_id").size().median()
    print(f"{name:38s} {n:5d} scans registered ({pts:6.0f} pts/scan) in {best:6.2f} s: {n / best:7.1f} scans/s")
    return n / best


def main():
    print("register: throughput (best of 2; scans/s counts the scans that went through fitness + ICP)")
    results = {}
    trace0 = REPO / "results" / "trace0"
    if (trace0 / "poses.parquet").exists():
        sc = pd.read_parquet(trace0 / "scans.parquet")
        si = pd.read_parquet(trace0 / "scan_index.parquet")
        po = pd.read_parquet(trace0 / "poses.parquet")
        results["trace0_p2p"] = run("2D trace0 (every_n=1, point-to-point)", sc, si, po, {"every_n": 1})
        results["trace0_p2l"] = run("2D trace0 (every_n=1, point-to-plane)", sc, si, po,
                                    {"every_n": 1, "icp_method": "point_to_plane"})
    else:
        print("(trace0 not ingested: results/trace0/poses.parquet missing)")
    sc, si, po = synthetic(200, (0.0,), 720)
    results["2d"] = run("2D synthetic (720 beams)", sc, si, po, {"every_n": 1})
    el = np.radians(np.linspace(-15, 15, 16))
    sc, si, po = synthetic(60, el, 1800)
    results["3d"] = run("3D synthetic (16 x 1800 beams)", sc, si, po, {"every_n": 1, "voxel_size_m": 0.1})
    results["3d_p2l"] = run("3D synthetic (point-to-plane)", sc, si, po,
                            {"every_n": 1, "voxel_size_m": 0.1, "icp_method": "point_to_plane"})
    print(f"ratio 2D/3D synthetic: {results['2d'] / results['3d']:.1f}x")


if __name__ == "__main__":
    main()

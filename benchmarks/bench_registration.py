"""Registration: throughput (scans/s) for 2D and 3D scans, accuracy, and odometry mode.

Run: ``.venv/bin/python -m benchmarks bench_registration`` (or
``.venv/bin/python -m benchmarks.bench_registration [--max-3d-scans N] [--baseline]``).

Inputs are the stage inputs under ``results/<dataset>/`` (``--results DIR`` for another
folder; a dataset whose files are missing is skipped with a message):

- the stage as it runs (streamed from the files, default config, a fresh process per
  run: wall, CPU and peak RSS) on hallways (2D) and hallways3d, with one and two
  edge-ICP workers;

- pose mode, ``reference: graph`` (default) and ``map``: 2D trace0 (every scan and
  every 5th), demo (RMS error against the simulator's true poses, before = the
  localizer's poses); 3D hallways3d, its first ``--max-3d-scans`` scans (16 x 900 rays;
  RMS against truth). Without hallways3d, a synthetic 3D box room (16 x 1800 rays)
  stands in;
- odometry mode (no poses read): trace0 and mac_ros2 (drift against the recording's
  own poses after aligning the first pose: median and final position error, metres and
  % of the distance travelled), demo and hallways3d (against the true poses);
- ``--baseline``: 3D ``map`` with ``icp_voxel_size_3d_m: 0.05`` (ICP on nearly every
  point, as before the coarse grid) on a shorter stretch, for the ratio.

"scans/s" counts the sampled scans the stage registered (the every-n-th); odometry
mode also registers the scans in between (``odometry_scans: all``), shown as
"processed/s". Times are wall-clock, best of ``--repeat`` runs.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
import pandas as pd

from floorscan.register.pipeline import register_scans

REPO = Path(__file__).resolve().parents[1]
RESULTS = REPO / "results"


# --------------------------------------------------------------------------- inputs


def load(dataset: str, max_scans: int | None = None):
    """scans, scan_index, poses (None if absent) and true poses (None) of a dataset, or
    None when its stage inputs are missing."""
    d = RESULTS / dataset
    if not (d / "scans.parquet").exists() or not (d / "scan_index.parquet").exists():
        return None
    filt = [("scan_id", "<", max_scans)] if max_scans else None
    scans = pd.read_parquet(d / "scans.parquet", filters=filt)
    index = pd.read_parquet(d / "scan_index.parquet", filters=filt)
    poses = pd.read_parquet(d / "poses.parquet", filters=filt) if (d / "poses.parquet").exists() else None
    true = None
    if (d / "sim" / "true_poses.parquet").exists():
        tp = pd.read_parquet(d / "sim" / "true_poses.parquet")
        true = index[["t_ns"]].merge(tp, on="t_ns", how="left")[["x", "y", "z", "yaw"]].to_numpy(np.float64)
    return scans, index, poses, true


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
        local = np.stack([np.cos(az) * math.cos(el), np.sin(az) * math.cos(el), np.full(n_az, math.sin(el))], 1)
        out.append(local * r[:, None])
    return np.concatenate(out)


def synthetic_3d(n_scans=100, seed=0):
    """A 16-beam scanner (1800 rays per ring) driven through a box room at 0.3 m/s,
    10 Hz, with independent localizer errors (3 cm, 0.01 rad): scans, index, poses, truth."""
    rng = np.random.default_rng(seed)
    el = np.radians(np.linspace(-15, 15, 16))
    s = np.arange(n_scans) * 0.03
    truth = np.stack([2 + s % 8, 3 + 0.5 * np.sin(s), np.full(n_scans, 0.5), 0.2 * np.sin(s / 2)], 1)
    t = 1_700_000_000_000_000_000 + np.arange(n_scans, dtype=np.int64) * 100_000_000
    rows = []
    for i, p in enumerate(truth):
        pts = box_scan(p[[0, 1, 3]], elevations=el, rng=rng)
        rows.append(pd.DataFrame({"scan_id": np.int32(i), "x": pts[:, 0], "y": pts[:, 1], "z": pts[:, 2]}))
    index = pd.DataFrame({"scan_id": np.arange(n_scans, dtype=np.int32), "t_ns": t})
    err = rng.normal(0, [0.03, 0.03, 0.01], (n_scans, 3))
    poses = pd.DataFrame({"scan_id": index["scan_id"], "t_ns": t, "x": truth[:, 0] + err[:, 0],
                          "y": truth[:, 1] + err[:, 1], "z": 0.5, "yaw": truth[:, 3] + err[:, 2],
                          "valid": True, "reason": ""})
    return pd.concat(rows, ignore_index=True), index, poses, truth


# --------------------------------------------------------------------------- measures


def rms(table: pd.DataFrame, xy_yaw: np.ndarray, truth: np.ndarray) -> tuple[float, float]:
    """RMS position (cm) and yaw (deg) error of the kept scans' poses ``xy_yaw``."""
    k = table["kept"].to_numpy() & np.isfinite(truth[:, 0])
    d = xy_yaw[k, :2] - truth[k, :2]
    dyaw = (xy_yaw[k, 2] - truth[k, 3] + np.pi) % (2 * np.pi) - np.pi
    return 100 * float(np.sqrt(np.mean(np.sum(d**2, axis=1)))), math.degrees(float(np.sqrt(np.mean(dyaw**2))))


def _relative(p: np.ndarray) -> np.ndarray:
    c, s = math.cos(-p[0, 2]), math.sin(-p[0, 2])
    d = p[:, :2] - p[0, :2]
    return np.column_stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]])


def drift(table: pd.DataFrame, reference: np.ndarray) -> dict:
    """Odometry poses of the kept scans against ``reference`` (x, y, z, yaw per table row)
    after aligning the first kept pose of each: median and final position error (m),
    the reference's path length (m), final error in % of it."""
    k = table["kept"].to_numpy() & np.isfinite(reference[:, 0])
    est = table[["x_m", "y_m", "yaw_rad"]].to_numpy()[k]
    ref = reference[k][:, [0, 1, 3]]
    e = np.hypot(*(_relative(est) - _relative(ref)).T)
    path = float(np.sum(np.hypot(*np.diff(ref[:, :2], axis=0).T)))
    return {"median": float(np.median(e)), "final": float(e[-1]), "path": path, "pct": 100 * float(e[-1]) / path}


def timed(scans, index, poses, cfg, repeat):
    best, r = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        r = register_scans(scans, index, poses, cfg)
        best = min(best, time.perf_counter() - t0)
    return r, best


def pose_row(name, data, cfg, repeat):
    scans, index, poses, true = data
    r, dt = timed(scans, index, poses, cfg, repeat)
    s = r.summary
    n = s["n_sampled"]
    line = (f"{name:44s} {n:5d} scans ({scans.groupby('scan_id').size().median():6.0f} pts) "
            f"{dt:6.2f} s {n / dt:7.1f} scans/s; kept {s['n_kept']}")
    if true is not None:
        loc = poses.set_index("scan_id").reindex(r.table["scan_id"])[["x", "y", "yaw"]].to_numpy()
        b = rms(r.table, loc, true)
        a = rms(r.table, r.table[["x_m", "y_m", "yaw_rad"]].to_numpy(), true)
        line += f"; RMS {b[0]:.2f} cm {b[1]:.2f} deg -> {a[0]:.2f} cm {a[1]:.2f} deg"
    print(line, flush=True)
    return n / dt


def odometry_row(name, data, cfg, repeat):
    scans, index, poses, true = data
    r, dt = timed(scans, index, None, dict(cfg, mode="odometry"), repeat)
    s = r.summary
    processed = int(r.table["x_m"].notna().sum())
    if true is not None:
        ref, what = true, "truth"
    else:
        p = poses.set_index("scan_id").reindex(r.table["scan_id"])
        ref = np.where(p["valid"].fillna(False).to_numpy(bool)[:, None], p[["x", "y", "z", "yaw"]].to_numpy(float), np.nan)
        what = "recording's poses"
    d = drift(r.table, ref)
    print(f"{name:44s} kept {s['n_kept']}/{s['n_sampled']} ({s['n_kept'] / s['n_sampled']:.1%}) "
          f"{dt:6.2f} s {s['n_sampled'] / dt:6.1f} scans/s ({processed / dt:6.1f} processed/s); drift vs {what}: "
          f"median {d['median']:.3f} m, final {d['final']:.3f} m = {d['pct']:.2f} % of {d['path']:.1f} m", flush=True)
    return s["n_sampled"] / dt


_STAGE = """
import json, resource, sys, tempfile, time
from pathlib import Path
from floorscan.core.io import read_table
from floorscan.register.stream import register_recording
d, workers = Path(sys.argv[1]), int(sys.argv[2])
t0, c0 = time.perf_counter(), time.process_time()
index = read_table(d / "scan_index.parquet")
poses = read_table(d / "poses.parquet")
with tempfile.TemporaryDirectory() as tmp:
    r = register_recording(d / "scans.parquet", index, poses, {"graph": {"workers": workers}}, Path(tmp) / "r.parquet")
wall, cpu = time.perf_counter() - t0, time.process_time() - c0
kids = resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"wall": wall, "cpu": cpu + kids.ru_utime + kids.ru_stime, "n": r.summary["n_sampled"],
                  "kept": r.summary["n_kept"], "points": int(index["n_points"].sum()),
                  "rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def stage_rows(results: Path, datasets=("hallways", "hallways3d")) -> None:
    """The stage's own path (:func:`register_recording`: scans.parquet streamed,
    default config) in a fresh process per run, one and two edge-ICP workers."""
    import json
    import subprocess
    import sys

    print(f"register stage (streamed from {results}/<dataset>/scans.parquet, default config)")
    for name in datasets:
        d = results / name
        if not (d / "scans.parquet").exists() or not (d / "poses.parquet").exists():
            print(f"  ({name}: {d}/scans.parquet or poses.parquet missing, skipped)")
            continue
        walls = {}
        for workers in (1, 2):
            out = subprocess.run([sys.executable, "-c", _STAGE, str(d), str(workers)], capture_output=True,
                                 text=True, check=True).stdout
            m = json.loads(out.strip().splitlines()[-1])
            walls[workers] = m["wall"]
            print(f"  {name:12s} workers={workers}  {m['n']:5d} sampled scans of {m['points'] / 1e6:.1f} M points: "
                  f"{m['wall']:6.1f} s wall, {m['cpu']:6.1f} s CPU, {m['n'] / m['wall']:5.1f} scans/s, "
                  f"peak RSS {m['rss_mb']:.0f} MB; kept {m['kept']}", flush=True)
        print(f"  {name:12s} two workers / one: {walls[1] / walls[2]:.2f}x wall")


def main(argv: list[str] | None = None) -> None:
    global RESULTS
    ap = argparse.ArgumentParser(prog="bench_registration")
    ap.add_argument("--results", type=Path, default=RESULTS,
                    help="folder of the stage inputs <dataset>/scans.parquet ... (default results/; "
                         "the pipeline benchmark's --workdir DIR has DIR/repo/results)")
    ap.add_argument("--max-3d-scans", type=int, default=750, help="first scans of hallways3d (default 750)")
    ap.add_argument("--repeat", type=int, default=1, help="runs per case, best taken (default 1)")
    ap.add_argument("--baseline", action="store_true", help="also 3D map with icp_voxel_size_3d_m 0.05")
    args = ap.parse_args(argv or [])
    RESULTS = args.results
    stage_rows(RESULTS)
    rate = {}
    data3 = load("hallways3d", args.max_3d_scans)
    name3 = f"hallways3d[:{args.max_3d_scans}]"
    if data3 is None:
        print("(hallways3d not simulated: a synthetic 3D box room stands in)")
        data3, name3 = synthetic_3d(), "3D box room"
    for ref, what in (("graph", "default: ICP edges + localizer priors"), ("map", "scan-to-map, 3 passes")):
        print(f"register, pose mode, reference {ref} ({what})")
        for name, cfg in (("trace0", {"every_n": 1}), ("trace0", {}), ("demo", {})):
            data = load(name)
            if data is None:
                print(f"  ({name}: results/{name}/scans.parquet missing, skipped)")
                continue
            rate[f"2d {name} {cfg} {ref}"] = pose_row(
                f"  2D {name} every_n={cfg.get('every_n', 5)}", data, dict(cfg, reference=ref), args.repeat
            )
        rate[f"3d {ref}"] = pose_row(f"  3D {name3}", data3, {"reference": ref}, args.repeat)
        key2 = f"2d trace0 {{}} {ref}"
        if key2 in rate:
            print(f"  ratio 2D trace0 / 3D: {rate[key2] / rate[f'3d {ref}']:.1f}x")
    if args.baseline:
        n = max(args.max_3d_scans // 4, 50)
        sub = tuple(x[x["scan_id"] < n] if isinstance(x, pd.DataFrame) else x for x in data3[:3]) + (
            data3[3][:n] if data3[3] is not None else None,)
        base = pose_row(f"  3D [:{n}] map, icp_voxel_size_3d_m=0.05", sub,
                        {"reference": "map", "icp_voxel_size_3d_m": 0.05}, args.repeat)
        new = pose_row(f"  3D [:{n}] map, default grid (0.2)", sub, {"reference": "map"}, args.repeat)
        print(f"  3D map speed-up from the coarse ICP grid: {new / base:.1f}x")

    print("register, odometry mode (no poses read; default config)")
    for name in ("trace0", "mac_ros2", "demo"):
        data = load(name)
        if data is None:
            print(f"  ({name}: results/{name}/scans.parquet missing, skipped)")
            continue
        odometry_row(f"  2D {name}", data, {}, args.repeat)
    odometry_row(f"  3D {name3}", data3, {}, args.repeat)


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])

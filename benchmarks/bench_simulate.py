"""Simulation speed and size: demo and hallways (2D and 3D), scans/s and bytes on disk.

For each case it times the whole ``simulate`` stage (:func:`floorscan.sim.simulate.run_simulation`:
trajectory, ray casting, ROS1 bag, PCD folder, ground truth) into a temporary folder,
and separately the ray casting alone (Embree via Open3D), so the share of the writers is
visible. ``python -m benchmarks.bench_simulate [--no-3d]``; the 3D case writes about
1.7 GB to a temporary folder (removed afterwards) and takes about a minute.
"""

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from floorscan.sim.building_file import load_building
from floorscan.sim.params import SimParams
from floorscan.sim.raycast import RayCaster, iter_scan_batches, measure_ranges
from floorscan.sim.recording import simulate_recording
from floorscan.sim.scanners import scanner_from_config
from floorscan.sim.simulate import run_simulation

REPO = Path(__file__).resolve().parents[1]
CFG = {"scanners": {"2d": {}, "3d": {}}}  # the schema's defaults
CASES = [("demo", "2d"), ("hallways", "2d"), ("hallways", "3d")]


def _size(p: Path) -> int:
    return p.stat().st_size if p.is_file() else sum(f.stat().st_size for f in p.rglob("*") if f.is_file())


def _mb(n: int) -> str:
    return f"{n / 1e6:8.1f} MB"


def cast_only(building: str, scanner_name: str) -> tuple[float, int, int]:
    """Seconds to cast every ray of the recording (no writers), scans, rays."""
    b = load_building(REPO / "config" / "buildings" / f"{building}.yaml")
    sc = scanner_from_config(scanner_name, CFG["scanners"][scanner_name])
    rec = simulate_recording(b, sc, SimParams(), seed=1)
    caster = RayCaster.from_mesh(rec.mesh)
    rng = np.random.default_rng(0)
    n_rays = len(sc.directions())
    t0 = time.perf_counter()
    for s in iter_scan_batches(len(rec.scan_t_ns), n_rays):
        measure_ranges(caster, sc, rec.scan_poses[s], rng)
    return time.perf_counter() - t0, len(rec.scan_t_ns), len(rec.scan_t_ns) * n_rays


def main(argv: list[str] | None = None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    cases = [c for c in CASES if not ("--no-3d" in argv and c[1] == "3d")]
    import open3d  # noqa: F401  (import once, outside the timings)

    print("case            scans   wall s   scans/s  points     bag          pcd/         others")
    for building, scanner in cases:
        with tempfile.TemporaryDirectory(prefix="bench_sim_") as tmp:
            outs = {k: Path(tmp) / v for k, v in
                    {"bag": "recording.bag", "pcd": "pcd", "true_poses": "true_poses.parquet",
                     "stl": "building.stl", "walls": "walls.geojson"}.items()}
            t0 = time.perf_counter()
            counts = run_simulation(
                REPO / "config" / "buildings" / f"{building}.yaml",
                {"name": building, "scanner": scanner, "seed": 1}, CFG, outs,
            )
            dt = time.perf_counter() - t0
            others = sum(_size(outs[k]) for k in ("true_poses", "stl", "walls"))
            print(
                f"{building + ' ' + scanner:14s} {counts['n_scans']:6d} {dt:8.1f} "
                f"{counts['n_scans'] / dt:9.0f} {counts['n_points']:9d} {_mb(_size(outs['bag']))} "
                f"{_mb(_size(outs['pcd']))} {_mb(others)}"
            )
    print("\nray casting alone (Embree via Open3D, all scans, noise included):")
    for building, scanner in cases:
        dt, n_scans, n_rays = cast_only(building, scanner)
        print(f"  {building} {scanner}: {dt:6.2f} s for {n_scans} scans, {n_rays / dt / 1e6:5.1f} M rays/s")


if __name__ == "__main__":
    main()

"""Ingest throughput (MB/s) against a plain read of the same file, side by side.

Three readings of each recording: the bytes alone (``plain read``), rosbags' raw
message iteration without deserializing (``raw messages``), and floorscan's full ingest
(deserialize, convert to points, write Parquet). Recordings: the largest simulated bag
under ``results/*/sim/recording.bag``, the real ones in ``../shared/data`` that exist,
and any ``--bag PATH`` (a simulated ROS1 bag with ``/scan`` and ``/amcl_pose``, e.g. the
840 MB 3D bag the pipeline benchmark simulates: ``DIR/repo/results/hallways3d/sim/
recording.bag`` with ``--workdir DIR``).
"""
import tempfile
import time
from pathlib import Path

from floorscan.ingest.readers import open_recording
from floorscan.ingest.writer import write_recording

REPO = Path(__file__).resolve().parents[1]
SHARED = REPO.parent / "shared" / "data"

REAL = {
    "trace0 (ROS1)": {"format": "rosbag", "path": SHARED / "uob-pioneer/trace0.bag", "scan_topic": "/base_scan",
                      "pose": {"source": "tf", "fixed_frame": "map"}},
    "mac_ros2 (ROS2)": {"format": "rosbag", "path": SHARED / "comprobo-mac/macfirst_floor_take_2", "scan_topic": "/scan",
                        "pose": {"source": "tf", "fixed_frame": "odom"}},
    "intel (CARMEN)": {"format": "carmen", "path": SHARED / "radish/intel-corrected.log.gz"},
}


def size_bytes(path: Path) -> int:
    return sum(p.stat().st_size for p in path.rglob("*") if p.is_file()) if path.is_dir() else path.stat().st_size


def plain_read(path: Path) -> float:
    t0 = time.perf_counter()
    files = sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    for f in files:
        with open(f, "rb") as fh:
            while fh.read(1 << 24):
                pass
    return time.perf_counter() - t0


def raw_messages(path: Path) -> float:
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_typestore

    t0 = time.perf_counter()
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as r:
        for _ in r.messages():
            pass
    return time.perf_counter() - t0


def full_ingest(ds: dict) -> tuple[float, int]:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        rec = open_recording({**ds, "path": str(ds["path"])}, {}, max_gap_s=0.5)
        index = write_recording(rec, f"{tmp}/s.parquet", f"{tmp}/i.parquet", f"{tmp}/p.parquet")
        return time.perf_counter() - t0, len(index)


def main(argv: list[str] | None = None) -> None:
    import argparse

    ap = argparse.ArgumentParser(prog="bench_ingest")
    ap.add_argument("--bag", type=Path, action="append", default=[],
                    help="also a simulated ROS1 bag (/scan, /amcl_pose); repeatable")
    args = ap.parse_args(argv or [])
    sets = dict(REAL)
    sims = sorted((REPO / "results").glob("*/sim/recording.bag"), key=lambda p: p.stat().st_size)
    if sims:
        sets[f"{sims[-1].parts[-3]} (simulated ROS1)"] = {
            "format": "rosbag", "path": sims[-1], "scan_topic": "/scan",
            "pose": {"source": "topic", "topic": "/amcl_pose"}}
    for bag in args.bag:
        sets[f"{bag.parent.parent.name} (--bag)"] = {
            "format": "rosbag", "path": bag, "scan_topic": "/scan", "pose": {"source": "topic", "topic": "/amcl_pose"}}
    print(f"{'recording':28s} {'MB':>8s} {'scans':>6s} {'plain MB/s':>11s} {'raw msg MB/s':>13s} "
          f"{'ingest MB/s':>12s} {'ingest/plain':>13s}")
    for name, ds in sets.items():
        path = Path(ds["path"])
        if not path.exists():
            print(f"{name:28s} skipped: {path} not found")
            continue
        mb = size_bytes(path) / 1e6
        t_plain = plain_read(path)
        t_raw = raw_messages(path) if ds["format"] == "rosbag" else float("nan")
        t_ing, n = full_ingest(ds)
        print(f"{name:28s} {mb:8.1f} {n:6d} {mb / t_plain:11.0f} {mb / t_raw:13.1f} {mb / t_ing:12.1f} "
              f"{t_ing / t_plain:12.0f}x")


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])

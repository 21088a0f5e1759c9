"""Write a simulated recording: the ROS1 bag and the PCD folder, every scan cast once.

:func:`write_recording` writes, deterministic for a seed and atomically:

- the ROS1 bag (its messages: :mod:`floorscan.sim.ros1`); message times equal header
  stamps;
- the PCD folder in the thesis's layout (section 4.1): ``scan_00000.pcd``... one binary
  PCD per scan in the MAP frame (true pose), equal point for point to the bag's scan
  transformed by the true pose (to float32 precision), and ``locations.csv`` with
  ``file,t_ns,x,y,z,yaw`` (the true scanner pose; ``file`` relative to the folder).

On the way it gathers the 1 cm plan cells of the returns, from which the ground truth
marks the wall faces the recording observed (:mod:`floorscan.sim.ground_truth`).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pandas as pd

from floorscan.core.files import atomic_path, staged_path
from floorscan.core.grid import unique_ints
from floorscan.sim.raycast import scanner_points, to_map
from floorscan.sim.recording import Recording
from floorscan.sim.ros1 import Ros1Messages
from floorscan.sim.scanners import Scanner2D

#: Plan cell of the returns kept for the observed faces, metres.
OBSERVED_CELL_M = 0.01
#: 3D scanners: the returns that observe a wall face lie in this height band above the
#: floor (the walls stage's default band), metres; a 2D scanner's returns all count.
OBSERVED_BAND_3D_M = (0.5, 2.0)


def pcd_bytes(points: np.ndarray, viewpoint: np.ndarray | None = None) -> bytes:
    """A binary PCD (v0.7) file with float32 ``x y z`` fields.

    Parameters
    ----------
    points : (N, 3) float ndarray
        Metres; written as little-endian float32.
    viewpoint : (4,) float64 ndarray, optional
        ``x, y, z, yaw`` of the scanner, stored in the VIEWPOINT header line.

    Returns
    -------
    bytes
    """
    pts = np.ascontiguousarray(points, dtype="<f4")
    vp = "0 0 0 1 0 0 0"
    if viewpoint is not None:
        x, y, z, yaw = (float(v) for v in viewpoint)
        vp = f"{x!r} {y!r} {z!r} {math.cos(yaw / 2)!r} 0 0 {math.sin(yaw / 2)!r}"
    n = len(pts)
    header = (
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
        f"TYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT {vp}\nPOINTS {n}\nDATA binary\n"
    )
    return header.encode("ascii") + pts.tobytes()


def scan_file_name(k: int) -> str:
    """File name of scan ``k`` in the pcd folder (zero-padded: sorts in time order).

    Parameters
    ----------
    k : int

    Returns
    -------
    str
        ``scan_<k, 5 digits>.pcd``.
    """
    return f"scan_{k:05d}.pcd"


def write_recording(rec: Recording, bag_path: str | os.PathLike, pcd_dir: str | os.PathLike) -> dict:
    """Cast every scan once and write the ROS1 bag and the PCD folder atomically.

    Parameters
    ----------
    rec : Recording
    bag_path : path
        The ``.bag`` to write (replaced if present).
    pcd_dir : path
        The folder of ``.pcd`` files and ``locations.csv`` (replaced if present).

    Returns
    -------
    dict
        Counts: ``n_scans``, ``n_points``, ``n_no_return`` (beams without a return),
        ``n_pose``, ``n_odom``; and ``observed_xy``, ``(C, 2)`` float64, the centres of
        the 1 cm plan cells holding a return (3D: a return in ``OBSERVED_BAND_3D_M``),
        metres, for :func:`floorscan.sim.ground_truth.observed_faces`.
    """
    from rosbags.rosbag1 import Writer

    bag_path, pcd_dir = Path(bag_path), Path(pcd_dir)
    msgs = Ros1Messages(rec)
    is_2d = isinstance(rec.scanner, Scanner2D)
    scan_type = "sensor_msgs/msg/LaserScan" if is_2d else "sensor_msgs/msg/PointCloud2"
    others = sorted(
        [(int(t), 1, i) for i, t in enumerate(rec.pose_t_ns)]
        + [(int(t), 2, i) for i, t in enumerate(rec.odom_t_ns)]
    )
    n_points = n_missing = 0
    cells: list[np.ndarray] = []  # 1 cm plan cells of the returns (observed faces)
    with atomic_path(bag_path) as tmp_bag, staged_path(pcd_dir) as tmp_dir:
        tmp_bag.unlink()  # rosbags refuses to overwrite
        tmp_dir.mkdir()
        with Writer(tmp_bag) as w:
            ts = msgs.ts
            c_tf = w.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts, latching=1)
            c_scan = w.add_connection("/scan", scan_type, typestore=ts)
            c_pose = w.add_connection(
                "/amcl_pose", "geometry_msgs/msg/PoseWithCovarianceStamped", typestore=ts
            )
            c_odom = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
            t0 = min(int(rec.scan_t_ns[0]), others[0][0])
            w.write(c_tf, t0, msgs.tf_static(t0))
            o = 0

            def flush(until_ns: int) -> None:
                nonlocal o
                while o < len(others) and others[o][0] <= until_ns:
                    t, kind, i = others[o]
                    if kind == 1:
                        w.write(c_pose, t, msgs.amcl(i))
                    else:
                        w.write(c_odom, t, msgs.odom(i))
                    o += 1

            dirs = rec.scanner.directions()
            for k, ranges in rec.iter_scans():
                t = int(rec.scan_t_ns[k])
                flush(t - 1)
                pts, valid = scanner_points(rec.scanner, ranges, dirs)
                n_points += len(pts)
                n_missing += int((~valid).sum())
                w.write(c_scan, t, msgs.scan(k, ranges, pts))
                map_pts = to_map(pts, rec.scan_poses[k]).astype(np.float32)
                cells.append(_plan_cells(map_pts, is_2d))
                if len(cells) >= 256:
                    cells = [unique_ints(np.concatenate(cells))]
                (tmp_dir / scan_file_name(k)).write_bytes(pcd_bytes(map_pts, rec.scan_poses[k]))
            flush(np.iinfo(np.int64).max)
        locations = pd.DataFrame(
            {
                "file": [scan_file_name(k) for k in range(len(rec.scan_t_ns))],
                "t_ns": rec.scan_t_ns.astype(np.int64),
                "x": rec.scan_poses[:, 0],
                "y": rec.scan_poses[:, 1],
                "z": rec.scan_poses[:, 2],
                "yaw": rec.scan_poses[:, 3],
            }
        )
        locations.to_csv(tmp_dir / "locations.csv", index=False, lineterminator="\n")
    keys = unique_ints(np.concatenate(cells)) if cells else np.zeros(0, np.int64)
    ij = np.column_stack([keys >> 32, keys & 0xFFFFFFFF]) - 2**30
    return {
        "observed_xy": (ij + 0.5) * OBSERVED_CELL_M,
        "n_scans": len(rec.scan_t_ns),
        "n_points": n_points,
        "n_no_return": n_missing,
        "n_pose": len(rec.pose_t_ns),
        "n_odom": len(rec.odom_t_ns),
    }


def _plan_cells(map_pts: np.ndarray, is_2d: bool) -> np.ndarray:
    """Unique int64 keys of the 1 cm plan cells of one scan's map-frame returns."""
    p = map_pts
    if not is_2d:
        p = p[(p[:, 2] >= OBSERVED_BAND_3D_M[0]) & (p[:, 2] <= OBSERVED_BAND_3D_M[1])]
    ij = np.floor(p[:, :2].astype(np.float64) / OBSERVED_CELL_M).astype(np.int64) + 2**30
    return unique_ints((ij[:, 0] << 32) | ij[:, 1])

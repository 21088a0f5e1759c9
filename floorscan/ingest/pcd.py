"""Folder of ``.pcd`` scans in the map frame plus a CSV of scan locations (thesis 4.1).

The thesis's simulated recordings are a ``.pcd`` file per scan location, already in the
map frame, with the location of each scan. The CSV (dataset option ``locations``,
default ``locations.csv`` inside the folder) has the columns::

    file,t_ns,x,y,z,yaw

``file`` is relative to the folder; ``x, y, z`` (metres) and ``yaw`` (radians) are the
scanner pose in the map frame; ``t_ns`` (optional) the scan time. Without ``t_ns`` the
scans are stamped at their row index times ``missing_time_period_s``; without ``yaw``
it is 0. Rows are taken in ``t_ns`` order (file order when there is no ``t_ns``).

Points are moved into the scanner frame with the inverse pose, so a PCD recording flows
through the same stages as a bag; the pose stream is the locations themselves (pose kind
``map``, source ``embedded``; stamps ``recorded`` with ``t_ns``, else ``made_up``).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np
import pandas as pd

from floorscan.ingest import Recording, Scan, filter_points, pose_stream_frame
from floorscan.io import InputError

log = logging.getLogger(__name__)


def read_pcd_xyz(path: str | Path) -> np.ndarray:
    """Read the ``x, y, z`` of a ``.pcd`` file (ascii, binary or binary_compressed).

    Returns
    -------
    (N, 3) float64 ndarray
        Points as stored, NaN included (the caller drops and counts them).

    Raises
    ------
    InputError
        Missing, unreadable or truncated file (the point count read differs from the
        header's ``POINTS``), or no x/y/z fields.
    """
    from floorscan.o3d import o3d

    path = Path(path)
    header = _pcd_header(path)
    if not {"x", "y", "z"} <= set(header.get("FIELDS", [])):
        raise InputError(f"{path}: PCD has fields {header.get('FIELDS')}; expected x, y, z")
    expected = int(header.get("POINTS", ["-1"])[0])
    pcd = o3d.t.io.read_point_cloud(str(path), remove_nan_points=False, remove_infinite_points=False)
    pts = pcd.point.positions.numpy().astype(np.float64) if "positions" in pcd.point else np.zeros((0, 3))
    if expected >= 0 and len(pts) != expected:
        raise InputError(f"{path}: read {len(pts)} points, header says POINTS {expected}; truncated or corrupt")
    return pts


def _pcd_header(path: Path) -> dict[str, list[str]]:
    if not path.is_file():
        raise InputError(f"{path}: PCD file not found")
    header: dict[str, list[str]] = {}
    with open(path, "rb") as f:
        for _ in range(20):
            line = f.readline().decode("ascii", errors="replace").strip()
            if not line or line.startswith("#"):
                continue
            key, *vals = line.split()
            header[key.upper()] = vals
            if key.upper() == "DATA":
                break
    if "DATA" not in header:
        raise InputError(f"{path}: not a PCD file (no DATA line in the header)")
    return header


def read_locations(folder: Path, name: str, period_s: float) -> pd.DataFrame:
    """Read and check the locations CSV of a PCD folder.

    Returns
    -------
    DataFrame
        Columns ``file``, ``t_ns`` (int64, ns), ``x``, ``y``, ``z`` (metres), ``yaw``
        (radians); ``attrs["stamps"]`` is ``recorded`` (a ``t_ns`` column) or
        ``made_up`` (row index x ``period_s``).

    Raises
    ------
    InputError
        Missing file, missing columns, non-numeric or non-finite values, duplicate or
        unsorted stamps, or a named ``.pcd`` that does not exist.
    """
    path = folder / name
    if not path.is_file():
        raise InputError(f"{path}: scan locations CSV not found (dataset option 'locations')")
    try:
        df = pd.read_csv(path)
    except Exception as e:
        raise InputError(f"{path}: cannot read the CSV ({e})") from None
    need = ["file", "x", "y", "z"]
    missing = [c for c in need if c not in df.columns]
    if missing:
        raise InputError(f"{path}: columns {missing} missing; expected file,t_ns,x,y,z,yaw (t_ns, yaw optional)")
    if df.empty:
        raise InputError(f"{path}: no scan locations")
    for c in ["x", "y", "z"] + [c for c in ("yaw", "t_ns") if c in df.columns]:
        vals = pd.to_numeric(df[c], errors="coerce")
        if vals.isna().any() or not np.isfinite(vals.to_numpy(dtype=float)).all():
            row = int(np.flatnonzero(vals.isna().to_numpy() | ~np.isfinite(vals.to_numpy(dtype=float)))[0])
            raise InputError(f"{path}: column {c!r} row {row + 1} is not a finite number")
        df[c] = vals
    if "yaw" not in df.columns:
        df["yaw"] = 0.0
    df.attrs["stamps"] = "recorded" if "t_ns" in df.columns else "made_up"
    if "t_ns" not in df.columns:
        log.warning("%s: no t_ns column; scans stamped at row index x %s s", path, period_s)
        df["t_ns"] = np.round(np.arange(len(df)) * period_s * 1e9).astype(np.int64)
    df["t_ns"] = df["t_ns"].astype(np.int64)
    t = df["t_ns"].to_numpy()
    if np.any(np.diff(t) <= 0):
        i = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1
        raise InputError(f"{path}: t_ns not strictly increasing at row {i + 1}; expected sorted, unique stamps")
    for f in df["file"]:
        if not (folder / str(f)).is_file():
            raise InputError(f"{path}: names {f!r}, which is not in {folder}")
    return df


def open_pcd_folder(path: Path, dataset: Mapping[str, Any], cfg: Mapping[str, Any]) -> Recording:
    """Open a folder of map-frame ``.pcd`` scans as a :class:`~floorscan.ingest.Recording`.

    ``Recording.detected``: scan topic ``pcd files``, pose source embedded (the
    locations CSV), pose kind ``map``, stamps from :func:`read_locations`.

    Raises
    ------
    InputError
        See :func:`read_locations` and :func:`read_pcd_xyz`.
    """
    if not path.is_dir():
        raise InputError(f"{path}: expected a folder of .pcd files")
    loc = read_locations(path, dataset.get("locations", "locations.csv"), float(cfg.get("missing_time_period_s", 0.1)))
    stream = pose_stream_frame(loc["t_ns"].to_numpy(), loc["x"], loc["y"], loc["z"], loc["yaw"])
    rmin, rmax = dataset.get("range_min_m"), dataset.get("range_max_m")

    def _scans() -> Iterator[Scan]:
        for row in loc.itertuples(index=False):
            pts = read_pcd_xyz(path / str(row.file))
            c, s = np.cos(row.yaw), np.sin(row.yaw)
            d = pts - np.array([row.x, row.y, row.z])
            local = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], d[:, 2]], axis=1)
            kept, dropped = filter_points(local, rmin, rmax)
            yield Scan(int(row.t_ns), "scanner", kept, dropped)

    name = dataset.get("locations", "locations.csv")
    detected = {
        "scan_topic": "pcd files",
        "pose_source": f"embedded (scan locations in {name})",
        "pose_kind": "map",
        "stamps": loc.attrs.get("stamps", "recorded"),
    }
    notes = [f"{len(loc)} scans listed in {name}; stamps {detected['stamps']}"]
    return Recording(scans=_scans(), pose_stream=stream, source=str(path), notes=notes, detected=detected)

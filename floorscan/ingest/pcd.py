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

Checks: bad input is an ``InputError`` naming the file (and line, field or
column), never a wrong point or pose. Each ``.pcd`` file is read and checked by
:func:`floorscan.ingest.pcd_file.read_pcd_xyz` (header and data rules in
:mod:`floorscan.ingest.pcd_file`); the locations CSV here: ``x, y, z, yaw`` finite
numbers, ``t_ns`` a decimal integer in [0, 2^63), strictly increasing, every named
file present, ``yaw`` in radians (not degrees: :mod:`floorscan.ingest.units`); the
points in metres (not millimetres) are checked by the ingest writer.

Losses: a listed file without a valid point (all NaN, or none inside the dataset's range
limits) is skipped and counted (``lost_no_points``), the first named in a note; none
usable is an ``InputError`` (:class:`~floorscan.ingest.points.ScanLosses`). ``.pcd``
files in the folder (or below it) that the CSV does not list are not read: counted
(``lost_unlisted_files``) and the first few named in a note. A malformed file stays an
error, as a malformed CARMEN line does: the reader would otherwise guess at its layout.
"""

from __future__ import annotations

import logging
import re
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np
import pandas as pd

from floorscan.core.config import stage_params
from floorscan.core.io import InputError
from floorscan.ingest.detect import LOCATIONS_CSV
from floorscan.ingest.params import IngestParams
from floorscan.ingest.pcd_file import read_pcd_xyz
from floorscan.ingest.points import FrameError, ScanLosses, filter_points, no_point_reason
from floorscan.ingest.recording import Recording, Scan, pose_stream_frame
from floorscan.ingest.text import parse_number
from floorscan.ingest.units import yaw_units_problem

log = logging.getLogger(__name__)


def read_locations(folder: Path, name: str, period_s: float) -> pd.DataFrame:
    """Read and check the locations CSV of a PCD folder.

    Every cell is read as text and parsed here (:func:`floorscan.ingest.text.parse_number`
    for the numbers), so nothing is guessed or rounded. Without a ``t_ns`` column a
    warning is logged.

    Parameters
    ----------
    folder : Path
        The PCD folder; the CSV's ``file`` names are relative to it.
    name : str
        The CSV's file name relative to ``folder`` (dataset option ``locations``).
    period_s : float
        Seconds between the made-up stamps when the CSV has no ``t_ns`` column.

    Returns
    -------
    pandas.DataFrame
        A row per CSV row, in the CSV's order (which is ``t_ns`` order): ``file``
        (str, as written), ``x``, ``y``, ``z`` (float64, metres, map frame), ``yaw``
        (float64, radians; 0.0 without the column), ``t_ns`` (int64, nanoseconds; without
        the column ``round(row index x period_s x 1e9)``); other columns kept as text.
        ``attrs["stamps"]`` is ``recorded`` (a ``t_ns`` column) or ``made_up``.

    Raises
    ------
    InputError
        Missing file or one pandas cannot read as CSV; a column of ``file, x, y, z``
        missing; no row; an ``x, y, z`` or ``yaw`` cell that is not a finite number; a
        ``t_ns`` cell that is not a decimal integer in [0, 2^63); stamps not strictly
        increasing; a named file that is not in ``folder``; a ``yaw`` column that is not
        radians (:func:`floorscan.ingest.units.yaw_units_problem`: degrees). The message
        names the CSV and the column (and row).
    """
    path = folder / name
    if not path.is_file():
        raise InputError(f"{path}: scan locations CSV not found (dataset option 'locations')")
    try:  # every cell as text: each column is parsed here, so nothing is guessed or rounded
        # spaces after the commas ("file, t_ns, x, ...", as people and spreadsheets write) are no part of a name or a value
        df = pd.read_csv(path, dtype=str, keep_default_na=False, skipinitialspace=True)
    except Exception as e:
        raise InputError(f"{path}: cannot read the CSV ({e})") from None
    df.columns = [str(c).strip() for c in df.columns]
    need = ["file", "x", "y", "z"]
    missing = [c for c in need if c not in df.columns]
    if missing:
        raise InputError(f"{path}: columns {missing} missing (the header has {list(df.columns)}); expected "
                         "file,t_ns,x,y,z,yaw (t_ns, yaw optional)")
    if df.empty:
        raise InputError(f"{path}: no scan locations")
    for c in ["x", "y", "z"] + [c for c in ("yaw",) if c in df.columns]:
        df[c] = _finite_column(path, c, df[c])
    if "t_ns" in df.columns:
        df["t_ns"] = stamp_column(path, df["t_ns"])
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
    problem = yaw_units_problem(t, df["yaw"].to_numpy(np.float64))
    if problem:
        raise InputError(f"{path}: column 'yaw' {problem}")
    return df


def _finite_column(path: Path, name: str, col: pd.Series) -> np.ndarray:
    """A CSV column of finite numbers as float64; else an InputError naming the row."""
    out = np.empty(len(col), dtype=np.float64)
    for i, v in enumerate(col):
        t = str(v).strip()
        x = parse_number(t)
        if x is None or not np.isfinite(x):
            raise InputError(f"{path}: column {name!r} row {i + 1} is {t!r}; expected a finite number")
        out[i] = x
    return out


def stamp_column(path: Path, col: pd.Series) -> np.ndarray:
    """The ``t_ns`` column of a locations CSV read as text: decimal integers in [0, 2^63)
    as int64, exact (an epoch stamp in nanoseconds, ~1.6e18, has more digits than a
    float64 holds: never parse it as a float). Ingest and the reduced recording
    (:mod:`floorscan.ingest.reduced_pcd`) read it here.

    Raises
    ------
    InputError
        A cell that is not such an integer, naming the CSV ``path`` and the row.
    """
    out = np.empty(len(col), dtype=np.int64)
    for i, v in enumerate(col):
        t = str(v).strip()
        if not re.fullmatch(r"\+?[0-9]+", t) or int(t) >= 2**63:
            raise InputError(
                f"{path}: column 't_ns' row {i + 1} is {t!r}; expected an integer number of nanoseconds, "
                "0 to 2^63 - 1"
            )
        out[i] = int(t)
    return out


def open_pcd_folder(path: Path, dataset: Mapping[str, Any], cfg: Mapping[str, Any]) -> Recording:
    """Open a folder of map-frame ``.pcd`` scans as a :class:`~floorscan.ingest.recording.Recording`.

    ``Recording.detected``: scan topic ``pcd files``, pose source embedded (the
    locations CSV), pose kind ``map``, stamps from :func:`read_locations`;
    ``lost_unlisted_files`` at once, ``n_frames_read`` and ``lost_no_points`` once the
    scans are read (see the module docstring).

    Parameters
    ----------
    path : Path
        The folder of ``.pcd`` files.
    dataset : mapping
        The dataset's config entry: ``locations`` (the CSV's name in the folder,
        default ``locations.csv``), ``range_min_m`` and ``range_max_m`` (metres,
        optional: a point is kept at ``range_min_m <= distance < range_max_m`` from the
        scanner).
    cfg : mapping
        The ``ingest`` config section (:class:`~floorscan.ingest.params.IngestParams`;
        ``missing_time_period_s`` spaces made-up stamps).

    Returns
    -------
    Recording
        ``scans``: a lazy iterator of :class:`~floorscan.ingest.recording.Scan`, one per
        CSV row with a valid point, in row order: its ``t_ns``, frame ``scanner``, the
        points (M, 3) float32, metres, moved into the scanner frame by the inverse of
        the row's pose (x, y, z and yaw about z), ``n_dropped`` and the row index as
        ``source_ordinal``. ``pose_stream``: the rows' poses
        (:func:`~floorscan.ingest.recording.pose_stream_frame`). ``source`` the folder;
        ``notes`` and ``detected`` as above (completed as the scans are read).

    Raises
    ------
    InputError
        ``path`` is not a folder; as :func:`read_locations` (at once). As
        :func:`floorscan.ingest.pcd_file.read_pcd_xyz`, or no listed file with a valid
        point, as the scans are read.
    ConfigError
        A bad ``cfg`` (:func:`floorscan.core.config.stage_params`).
    """
    if not path.is_dir():
        raise InputError(f"{path}: expected a folder of .pcd files")
    period = stage_params(IngestParams, cfg).missing_time_period_s
    name = dataset.get("locations", LOCATIONS_CSV)
    loc = read_locations(path, name, float(period))
    stream = pose_stream_frame(loc["t_ns"].to_numpy(), loc["x"], loc["y"], loc["z"], loc["yaw"])
    rmin, rmax = dataset.get("range_min_m"), dataset.get("range_max_m")
    detected = {
        "scan_topic": "pcd files",
        "pose_source": f"embedded (scan locations in {name})",
        "pose_kind": "map",
        "stamps": loc.attrs.get("stamps", "recorded"),
    }
    notes = [f"{len(loc)} scans listed in {name}; stamps {detected['stamps']}"]
    unlisted = unlisted_files(path, loc["file"])
    if unlisted:
        detected["lost_unlisted_files"] = str(len(unlisted))
        line = (
            f"{path}: {len(unlisted)} .pcd files are not listed in {name} and were not read "
            f"(lost_unlisted_files; {', '.join(unlisted[:5])}{', ...' if len(unlisted) > 5 else ''}); "
            f"expected a row of {name} for each scan"
        )
        notes.append(line)
        log.warning("%s", line)

    def _scans() -> Iterator[Scan]:
        losses = ScanLosses("listed PCD files")
        for i, row in enumerate(loc.itertuples(index=False)):
            losses.n_read, file = losses.n_read + 1, path / str(row.file)
            pts = read_pcd_xyz(file)
            c, s = np.cos(row.yaw), np.sin(row.yaw)
            d = pts - np.array([row.x, row.y, row.z])
            local = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1], d[:, 2]], axis=1)
            kept, dropped = filter_points(local, rmin, rmax)
            if not len(kept):
                losses.skip(i, FrameError(
                    f"{file} ({name} row {i + 1})", f"no valid point: {no_point_reason(pts, rmin, rmax)}", loss="no_points"
                ))
                continue
            yield Scan(int(row.t_ns), "scanner", kept, dropped, i)
        losses.report(detected, notes, str(path))

    return Recording(scans=_scans(), pose_stream=stream, source=str(path), notes=notes, detected=detected)


def unlisted_files(folder: Path, listed) -> list[str]:
    """The ``.pcd`` files in and below ``folder`` that ``listed`` (paths relative to it) does not name, sorted.

    Parameters
    ----------
    folder : Path
        The PCD folder.
    listed : iterable of str or Path
        File names relative to ``folder`` (the locations CSV's ``file`` column).

    Returns
    -------
    list of str
        Paths relative to ``folder`` of the files whose suffix is ``.pcd`` in any case
        and that no entry of ``listed`` names (compared as resolved paths), sorted;
        empty when every file is listed.
    """
    names = {(folder / str(f)).resolve() for f in listed}
    found = (p for p in folder.rglob("*") if p.suffix.lower() == ".pcd" and p.is_file())
    return sorted(str(p.relative_to(folder)) for p in found if p.resolve() not in names)

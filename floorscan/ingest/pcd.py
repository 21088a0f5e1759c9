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
column), never a wrong point or pose.

- PCD header (the PCD v0.7 format of the Point Cloud Library): ``FIELDS``, ``SIZE``,
  ``TYPE``, ``WIDTH``, ``HEIGHT``, ``POINTS`` and ``DATA`` present once each (``VERSION``,
  ``VIEWPOINT`` optional; ``COUNT`` optional, 1 each), no other key; one ``SIZE``,
  ``TYPE`` and ``COUNT`` per field; sizes 1, 2, 4 or 8, types I, U or F (F only 4 or 8);
  ``x``, ``y`` and ``z`` once each, ``F 4`` or ``F 8``, ``COUNT 1``; ``POINTS`` =
  ``WIDTH x HEIGHT``.
- PCD data: ``ascii`` has exactly ``POINTS`` non-blank rows of exactly sum(``COUNT``)
  numbers (an ``F 4`` value must fit in float32); ``binary`` exactly ``POINTS`` x the point
  size bytes; ``binary_compressed`` the sizes its own header states (then decompressed
  by Open3D, PCL's reader, to exactly ``POINTS`` points). NaN or inf points are read as
  they are: ingest drops and counts them.
- Locations CSV: ``x, y, z, yaw`` finite numbers, ``t_ns`` a decimal integer in
  [0, 2^63), strictly increasing.

Losses: a listed file without a valid point (all NaN, or none inside the dataset's range
limits) is skipped and counted (``lost_no_points``), the first named in a note; none
usable is an ``InputError`` (:class:`~floorscan.ingest.points.ScanLosses`). ``.pcd``
files in the folder (or below it) that the CSV does not list are not read: counted
(``lost_unlisted_files``) and the first few named in a note. A malformed file stays an
error, as a malformed CARMEN line does: the reader would otherwise guess at its layout.
"""

from __future__ import annotations

import dataclasses
import logging
import re
import warnings
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np
import pandas as pd

from floorscan.core.config import stage_params
from floorscan.core.io import InputError
from floorscan.ingest.params import IngestParams
from floorscan.ingest.points import FrameError, ScanLosses, filter_points, no_point_reason
from floorscan.ingest.recording import Recording, Scan, pose_stream_frame
from floorscan.ingest.text import parse_number, parse_numbers

log = logging.getLogger(__name__)


#: Header keys of a PCD v0.7 file, in their order.
PCD_KEYS = ("VERSION", "FIELDS", "SIZE", "TYPE", "COUNT", "WIDTH", "HEIGHT", "VIEWPOINT", "POINTS", "DATA")
#: Keys a PCD header must have.
PCD_REQUIRED = ("FIELDS", "SIZE", "TYPE", "WIDTH", "HEIGHT", "POINTS", "DATA")
#: PCD TYPE and SIZE -> numpy type (little-endian, as PCL writes binary data).
PCD_DTYPES = {
    **{("I", n): f"<i{n}" for n in (1, 2, 4, 8)},
    **{("U", n): f"<u{n}" for n in (1, 2, 4, 8)},
    ("F", 4): "<f4",
    ("F", 8): "<f8",
}
PCD_DATA = ("ascii", "binary", "binary_compressed")
#: A header longer than this many lines has no DATA line: not a PCD file.
PCD_MAX_HEADER_LINES = 1000


@dataclasses.dataclass(frozen=True)
class PcdHeader:
    """A checked PCD header.

    Attributes
    ----------
    fields : tuple of str
    types, sizes, counts : tuple
        TYPE letter, SIZE in bytes and COUNT of each field.
    width, height, points : int
    data : str
        ``ascii``, ``binary`` or ``binary_compressed``.
    offset : int
        Byte offset of the data (after the DATA line).
    n_lines : int
        Lines of the header (the first data row is line ``n_lines + 1``).
    """

    fields: tuple[str, ...]
    types: tuple[str, ...]
    sizes: tuple[int, ...]
    counts: tuple[int, ...]
    width: int
    height: int
    points: int
    data: str
    offset: int
    n_lines: int

    def dtype(self) -> np.dtype:
        """The record of one point (fields with COUNT > 1 as sub-arrays)."""
        layout = zip(self.types, self.sizes, self.counts)
        return np.dtype([(f"f{i}", PCD_DTYPES[t, s], (c,) if c > 1 else ()) for i, (t, s, c) in enumerate(layout)])


def read_pcd_xyz(path: str | Path) -> np.ndarray:
    """Read the ``x, y, z`` of a ``.pcd`` file (ascii, binary or binary_compressed).

    The header is checked (:func:`read_pcd_header`) and the data against it (see the
    module docstring).

    Returns
    -------
    (N, 3) float64 ndarray
        Points as stored (F 4 values exactly their float32), NaN included (the caller
        drops and counts them).

    Raises
    ------
    InputError
        Missing file, a header that breaks the rules above, data that is not what the
        header says (row count, row length, non-numbers, byte count, a compressed block
        that does not decompress to its stated size), or an F 4 ascii value beyond
        float32. The message names the file and the line or field.
    """
    path = Path(path)
    h = read_pcd_header(path)
    with open(path, "rb") as f:
        f.seek(h.offset)
        raw = f.read()
    if h.data == "ascii":
        return _ascii_xyz(path, h, raw)
    if h.data == "binary":
        point = h.dtype()
        need = h.points * point.itemsize
        if len(raw) != need:
            raise InputError(
                f"{path}: {len(raw)} bytes of binary data; expected POINTS x {point.itemsize} bytes a point "
                f"= {need} (POINTS {h.points}); truncated or corrupt"
            )
        rec = np.frombuffer(raw, dtype=point, count=h.points)
        return np.stack([rec[f"f{h.fields.index(n)}"].astype(np.float64) for n in "xyz"], axis=1)
    return _compressed_xyz(path, h, raw)


def _ascii_xyz(path: Path, h: PcdHeader, raw: bytes) -> np.ndarray:
    try:
        text = raw.decode("ascii")
    except UnicodeDecodeError as e:
        raise InputError(f"{path}: non-ASCII byte at data offset {e.start} of an ascii PCD") from None
    lines = text.split("\n")
    width = sum(h.counts)
    table = _ascii_table(lines, h.points, width)
    rows = None
    if table is None:  # numpy refused the rows: find which row or value, one by one
        rows = _ascii_rows(lines, h.n_lines)
        if len(rows) != h.points:
            raise InputError(f"{path}: {len(rows)} rows stored, the header says POINTS {h.points}; truncated or corrupt")
        for lineno, tok in rows:
            if len(tok) != width:
                raise InputError(
                    f"{path}:{lineno}: row of {len(tok)} values; expected {width} "
                    f"(FIELDS {' '.join(h.fields)}, COUNT {' '.join(map(str, h.counts))})"
                )
    cols = np.cumsum((0,) + h.counts[:-1])  # column of each field's first value
    out = np.empty((h.points, 3), dtype=np.float64)
    for k, name in enumerate("xyz"):
        j = h.fields.index(name)
        v = table[:, cols[j]] if rows is None else _ascii_column(path, rows, cols[j], name)
        if h.sizes[j] == 4:
            big = np.isfinite(v) & (np.abs(v) > np.finfo(np.float32).max)
            if big.any():
                i = int(np.flatnonzero(big)[0])
                lineno = (rows or _ascii_rows(lines, h.n_lines))[i][0]
                raise InputError(
                    f"{path}:{lineno}: field {name!r} is {v[i]:g}, beyond the range of its TYPE F SIZE 4 (float32)"
                )
            v = v.astype(np.float32).astype(np.float64)
        out[:, k] = v
    if rows is not None:  # the other fields must be numbers too (a word there is a malformed row)
        for j, name in enumerate(h.fields):
            if name not in ("x", "y", "z"):
                for c in range(h.counts[j]):
                    _ascii_column(path, rows, cols[j] + c, name)
    return out


def _ascii_table(lines: list[str], points: int, width: int) -> np.ndarray | None:
    """The ascii rows as a (points, width) float64 table, parsed by numpy in one call
    (whitespace between values, blank lines skipped; no number that
    :func:`floorscan.ingest.text.parse_number` refuses, ``1_0`` included); None when numpy
    refuses a value or the table has another shape (the caller then reads row by row)."""
    if points == 0:
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # "input contained no data": the shape says so
            table = np.loadtxt(lines, dtype=np.float64, comments=None, ndmin=2)
    except ValueError:
        return None
    return table if table.shape == (points, width) else None


def _ascii_rows(lines: list[str], header_lines: int) -> list[tuple[int, list[str]]]:
    """The non-blank ascii rows as (line number in the file, values)."""
    return [(i, line.split()) for i, line in enumerate(lines, header_lines + 1) if line.strip()]


def _ascii_column(path: Path, rows: list[tuple[int, list[str]]], col: int, name: str) -> np.ndarray:
    """Column ``col`` of the ascii rows as float64; a value that is not a number is an
    ``InputError`` naming its line and field."""
    values = parse_numbers([tok[col] for _, tok in rows])
    if values is None:  # name the first that is not (one by one: only on a bad file)
        lineno, t = next((lineno, tok[col]) for lineno, tok in rows if parse_number(tok[col]) is None)
        raise InputError(f"{path}:{lineno}: field {name!r} is {t!r}; expected a number")
    return values


def _compressed_xyz(path: Path, h: PcdHeader, raw: bytes) -> np.ndarray:
    point_size = h.dtype().itemsize
    need = h.points * point_size
    if len(raw) < 8:
        raise InputError(f"{path}: {len(raw)} bytes of binary_compressed data; expected at least the 8-byte sizes")
    compressed, uncompressed = (int(v) for v in np.frombuffer(raw[:8], dtype="<u4"))
    if uncompressed != need:
        raise InputError(
            f"{path}: binary_compressed data of {uncompressed} bytes; expected POINTS x {point_size} "
            f"bytes a point = {need} (POINTS {h.points})"
        )
    if len(raw) - 8 != compressed:
        raise InputError(
            f"{path}: {len(raw) - 8} bytes of compressed data; the header of the data says {compressed}; "
            "truncated or corrupt"
        )
    xyz = {(h.types[h.fields.index(n)], h.sizes[h.fields.index(n)]) for n in "xyz"}
    if len(xyz) != 1:
        raise InputError(
            f"{path}: binary_compressed data with x, y, z of different TYPE/SIZE {sorted(xyz)}; expected one of "
            "F 4 or F 8 for all three (Open3D, which decompresses it, reads no other)"
        )
    # the sizes agree: Open3D (PCL's reader) decompresses the LZF block and splits the
    # fields (stored field by field: every x, then every y, ...)
    import open3d as o3d

    try:
        cloud = o3d.t.io.read_point_cloud(str(path), format="pcd")
    except RuntimeError as e:
        raise InputError(f"{path}: the binary_compressed data does not decompress ({e}); truncated or corrupt") from None
    positions = cloud.point.positions.numpy() if "positions" in cloud.point else np.empty((0, 3))
    if len(positions) != h.points:
        raise InputError(
            f"{path}: the binary_compressed data holds {len(positions)} points; expected POINTS {h.points}; "
            "truncated or corrupt"
        )
    return positions.astype(np.float64)


def read_pcd_header(path: str | Path) -> PcdHeader:
    """Read and check the header of a ``.pcd`` file (rules in the module docstring).

    Returns
    -------
    PcdHeader

    Raises
    ------
    InputError
        Missing file, no DATA line, an unknown or repeated key, a missing required key,
        a value that is not what its key takes, or x, y, z not F 4 / F 8 with COUNT 1.
        The message names the file and the key or field.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError(f"{path}: PCD file not found")
    header: dict[str, list[str]] = {}
    n_lines = 0
    with open(path, "rb") as f:
        while "DATA" not in header:
            line = f.readline()
            n_lines += 1
            if not line or n_lines > PCD_MAX_HEADER_LINES:
                raise InputError(f"{path}: not a PCD file (no DATA line in the header)")
            text = line.decode("ascii", errors="replace").strip()
            if not text or text.startswith("#"):
                continue
            key, *vals = text.split()
            key = key.upper()
            if key not in PCD_KEYS:
                raise InputError(
                    f"{path}:{n_lines}: unknown PCD header key {key!r}; expected one of {', '.join(PCD_KEYS)}"
                )
            if key in header:
                raise InputError(f"{path}:{n_lines}: PCD header {key} given twice")
            header[key] = vals
        offset = f.tell()
    missing = [k for k in PCD_REQUIRED if k not in header]
    if missing:
        raise InputError(f"{path}: PCD header lacks {', '.join(missing)}; expected {' '.join(PCD_KEYS)}")
    fields = tuple(header["FIELDS"])
    if not all(fields.count(n) == 1 for n in "xyz"):
        raise InputError(f"{path}: PCD header FIELDS {' '.join(fields)}; expected the fields x, y and z, once each")
    counts_raw = header.get("COUNT", ["1"] * len(fields))
    for key, vals in (("SIZE", header["SIZE"]), ("TYPE", header["TYPE"]), ("COUNT", counts_raw)):
        if len(vals) != len(fields):
            raise InputError(
                f"{path}: PCD header {key} has {len(vals)} values for {len(fields)} FIELDS ({' '.join(fields)}); "
                "expected one per field"
            )
    sizes = tuple(_pcd_int(path, "SIZE", v, 1) for v in header["SIZE"])
    counts = tuple(_pcd_int(path, "COUNT", v, 1) for v in counts_raw)
    types = tuple(t.upper() for t in header["TYPE"])
    for name, t, size, count in zip(fields, types, sizes, counts):
        if name in ("x", "y", "z"):
            if (t, size) not in (("F", 4), ("F", 8)):
                raise InputError(
                    f"{path}: PCD field {name!r} is TYPE {t} SIZE {size}; expected F 4 or F 8 (float32, float64)"
                )
            if count != 1:
                raise InputError(f"{path}: PCD field {name!r} has COUNT {count}; expected 1")
        elif (t, size) not in PCD_DTYPES:
            raise InputError(
                f"{path}: PCD field {name!r} is TYPE {t} SIZE {size}; "
                "expected I or U of 1, 2, 4 or 8 bytes, or F 4 or F 8"
            )
    dims = {}
    for key in ("WIDTH", "HEIGHT", "POINTS"):
        vals = header[key]
        if len(vals) != 1:
            raise InputError(f"{path}: PCD header {key} is {' '.join(vals)!r}; expected one non-negative integer")
        dims[key] = _pcd_int(path, key, vals[0], 0)
    if dims["POINTS"] != dims["WIDTH"] * dims["HEIGHT"]:
        raise InputError(
            f"{path}: PCD header POINTS {dims['POINTS']} but WIDTH x HEIGHT = {dims['WIDTH']} x {dims['HEIGHT']} "
            f"= {dims['WIDTH'] * dims['HEIGHT']}; expected them equal"
        )
    if "VIEWPOINT" in header and (len(header["VIEWPOINT"]) != 7 or parse_numbers(header["VIEWPOINT"]) is None):
        raise InputError(f"{path}: PCD header VIEWPOINT is {' '.join(header['VIEWPOINT'])!r}; expected 7 numbers")
    data = " ".join(header["DATA"]).lower()
    if data not in PCD_DATA:
        raise InputError(f"{path}: PCD header DATA is {data!r}; expected one of {', '.join(PCD_DATA)}")
    return PcdHeader(fields, types, sizes, counts, dims["WIDTH"], dims["HEIGHT"], dims["POINTS"], data, offset, n_lines)


def _pcd_int(path: Path, key: str, v: str, minimum: int) -> int:
    if not re.fullmatch(r"[0-9]+", v) or int(v) < minimum:
        what = "a non-negative integer" if minimum == 0 else f"integers >= {minimum}"
        raise InputError(f"{path}: PCD header {key} is {v!r}; expected {what}")
    return int(v)


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
    try:  # every cell as text: each column is parsed here, so nothing is guessed or rounded
        df = pd.read_csv(path, dtype=str, keep_default_na=False)
    except Exception as e:
        raise InputError(f"{path}: cannot read the CSV ({e})") from None
    need = ["file", "x", "y", "z"]
    missing = [c for c in need if c not in df.columns]
    if missing:
        raise InputError(f"{path}: columns {missing} missing; expected file,t_ns,x,y,z,yaw (t_ns, yaw optional)")
    if df.empty:
        raise InputError(f"{path}: no scan locations")
    for c in ["x", "y", "z"] + [c for c in ("yaw",) if c in df.columns]:
        df[c] = _finite_column(path, c, df[c])
    if "t_ns" in df.columns:
        df["t_ns"] = _stamp_column(path, df["t_ns"])
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


def _stamp_column(path: Path, col: pd.Series) -> np.ndarray:
    """The ``t_ns`` column: decimal integers in [0, 2^63) as int64."""
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

    Raises
    ------
    InputError
        See :func:`read_locations` and :func:`read_pcd_xyz`; no listed file with a valid
        point (as the scans are read).
    """
    if not path.is_dir():
        raise InputError(f"{path}: expected a folder of .pcd files")
    period = stage_params(IngestParams, cfg).missing_time_period_s
    loc = read_locations(path, dataset.get("locations", "locations.csv"), float(period))
    stream = pose_stream_frame(loc["t_ns"].to_numpy(), loc["x"], loc["y"], loc["z"], loc["yaw"])
    rmin, rmax = dataset.get("range_min_m"), dataset.get("range_max_m")
    name = dataset.get("locations", "locations.csv")
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
    """The ``.pcd`` files in and below ``folder`` that ``listed`` (paths relative to it) does not name, sorted."""
    names = {(folder / str(f)).resolve() for f in listed}
    found = (p for p in folder.rglob("*") if p.suffix.lower() == ".pcd" and p.is_file())
    return sorted(str(p.relative_to(folder)) for p in found if p.resolve() not in names)

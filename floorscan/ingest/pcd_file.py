"""One ``.pcd`` file: its header checked and its ``x, y, z`` read (PCD v0.7, thesis 4.1).

The PCD v0.7 format of the Point Cloud Library: a text header, then the points as
``ascii`` rows, ``binary`` records or ``binary_compressed`` blocks (LZF, decompressed by
Open3D, PCL's reader). :func:`read_pcd_header` reads and checks the header
(:class:`PcdHeader`), :func:`read_pcd_xyz` the points it describes; the folder of
scans and its locations CSV are read by :mod:`floorscan.ingest.pcd`.

Checks: bad input is an ``InputError`` naming the file (and line or field), never a
wrong point.

- PCD header: ``FIELDS``, ``SIZE``, ``TYPE``, ``WIDTH``, ``HEIGHT``, ``POINTS`` and
  ``DATA`` present once each (``VERSION``, ``VIEWPOINT`` optional; ``COUNT`` optional,
  1 each), no other key; one ``SIZE``, ``TYPE`` and ``COUNT`` per field; sizes 1, 2, 4
  or 8, types I, U or F (F only 4 or 8); ``x``, ``y`` and ``z`` once each, ``F 4`` or
  ``F 8``, ``COUNT 1``; ``POINTS`` = ``WIDTH x HEIGHT``.
- PCD data: ``ascii`` has exactly ``POINTS`` non-blank rows of exactly sum(``COUNT``)
  numbers (an ``F 4`` value must fit in float32); ``binary`` exactly ``POINTS`` x the point
  size bytes; ``binary_compressed`` the sizes its own header states (then decompressed
  by Open3D to exactly ``POINTS`` points). NaN or inf points are read as they are:
  ingest drops and counts them.

A malformed file is an error, never skipped: the reader would otherwise guess at its
layout.
"""

from __future__ import annotations

import dataclasses
import re
import warnings
from pathlib import Path

import numpy as np

from floorscan.core.io import InputError
from floorscan.ingest.text import parse_number, parse_numbers


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
        """The record of one point (fields with COUNT > 1 as sub-arrays).

        Returns
        -------
        numpy.dtype
            Structured, little-endian: one member per header field, in header order,
            named ``f0``, ``f1``, ... (field names may repeat, e.g. PCL's padding ``_``),
            of the field's TYPE and SIZE (:data:`PCD_DTYPES`), a ``(COUNT,)`` sub-array
            when COUNT > 1. Its ``itemsize`` is the point size in bytes.
        """
        layout = zip(self.types, self.sizes, self.counts)
        return np.dtype([(f"f{i}", PCD_DTYPES[t, s], (c,) if c > 1 else ()) for i, (t, s, c) in enumerate(layout)])


def read_pcd_xyz(path: str | Path) -> np.ndarray:
    """Read the ``x, y, z`` of a ``.pcd`` file (ascii, binary or binary_compressed).

    The header is checked (:func:`read_pcd_header`) and the data against it (see the
    module docstring). Fields other than ``x, y, z`` are not returned (in an ascii
    file they must be numbers too).

    Parameters
    ----------
    path : str or Path
        The ``.pcd`` file.

    Returns
    -------
    (N, 3) float64 ndarray
        ``x, y, z`` of the ``POINTS`` points in file order, as stored (a floorscan PCD
        folder: metres, map frame; F 4 values exactly their float32), NaN and inf
        included (the caller drops and counts them). N is the header's ``POINTS``.

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

    Keys are case-insensitive; blank lines and ``#`` comments are skipped (but counted
    in ``n_lines``). At most :data:`PCD_MAX_HEADER_LINES` lines are read looking for
    ``DATA``.

    Parameters
    ----------
    path : str or Path
        The ``.pcd`` file.

    Returns
    -------
    PcdHeader
        ``fields`` as written; ``types`` upper-case; ``sizes`` (bytes) and ``counts``
        (1 each without ``COUNT``) one per field; ``width``, ``height``, ``points``;
        ``data`` lower-case; ``offset``, the byte offset of the data (just after the
        DATA line); ``n_lines``, the lines of the header.

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

"""Tables on disk: the schemas every stage reads and writes.

Every stage of the workflow exchanges Parquet files (pyarrow) with the explicit
schemas below, and geometry as WKB (little-endian, 2D) or GeoJSON. Tables are written
atomically (:mod:`floorscan.core.files`).

Units are in the column names where they are not obvious: ``t_ns`` is nanoseconds
since the Unix epoch, ``*_m`` metres, ``*_rad`` radians, ``area_m2`` square metres.
Point coordinates ``x, y, z`` are always metres.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Iterator, Mapping

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from floorscan.core.files import atomic_path

if TYPE_CHECKING:  # pandas is imported by the functions that use it
    import pandas as pd

#: Points of every scan in the scanner frame (ingest output ``scans.parquet``).
SCANS = pa.schema(
    [("scan_id", pa.int32()), ("x", pa.float32()), ("y", pa.float32()), ("z", pa.float32())]
)
#: Points of the kept scans in the map frame (``registered.parquet``).
REGISTERED = SCANS
#: Field metadata of a column that a table written before it existed lacks: a frame
#: without it is written with the column null (:func:`table_from_frame`), and its
#: readers fall back to what it replaced.
OPTIONAL_FIELD = {b"optional": b"1"}
#: One row per scan of the recording (``scan_index.parquet``). ``frame`` is the scanner
#: frame of its points; ``source_ordinal`` (optional: null in an index written before it
#: existed) the 0-based ordinal of the scan's frame in the recording ingest read, the
#: numbering of ingest's ``skipped_frames``: a bag's message on the scan topic (in the
#: order rosbags' ``AnyReader`` yields them), a CARMEN log's laser line (in file order),
#: a PCD folder's row of the locations CSV. Ingest skips bad frames and sorts stamps a
#: little out of order, so it is not ``scan_id`` in general.
SCAN_INDEX = pa.schema(
    [
        ("scan_id", pa.int32()),
        ("t_ns", pa.int64()),
        ("n_points", pa.int32()),
        ("n_dropped", pa.int32()),
        ("frame", pa.string()),
        pa.field("source_ordinal", pa.int64(), metadata=OPTIONAL_FIELD),
    ]
)
#: The localizer's raw pose stream in the map frame (``pose_stream.parquet``).
POSE_STREAM = pa.schema(
    [
        ("t_ns", pa.int64()),
        ("x", pa.float64()),
        ("y", pa.float64()),
        ("z", pa.float64()),
        ("yaw", pa.float64()),
    ]
)
#: The scanner pose of every scan at its timestamp (``poses.parquet``). Rows with
#: ``valid`` false have NaN pose and a non-empty ``reason``.
POSES = pa.schema(
    [
        ("scan_id", pa.int32()),
        ("t_ns", pa.int64()),
        ("x", pa.float64()),
        ("y", pa.float64()),
        ("z", pa.float64()),
        ("yaw", pa.float64()),
        ("valid", pa.bool_()),
        ("reason", pa.string()),
    ]
)
#: Values of ``poses.parquet``'s ``reason``: why a scan has no pose (the ``poses``
#: stage's interpolation, :mod:`floorscan.ingest.poses`; the register stage counts them).
BEFORE = "before_pose_stream"
AFTER = "after_pose_stream"
GAP = "pose_gap"
NO_POSE_SOURCE = "no_pose_source"


class InputError(ValueError):
    """Bad input: the message names the file, topic or field and what was expected."""


def table_from_frame(df: pd.DataFrame, schema: pa.Schema) -> pa.Table:
    """Convert ``df`` to a table with exactly ``schema`` (column order and dtypes).

    A column the schema marks optional (:data:`OPTIONAL_FIELD`) that ``df`` lacks is
    written null; ``df`` is not changed.

    Parameters
    ----------
    df : pandas.DataFrame
    schema : pyarrow.Schema

    Returns
    -------
    pyarrow.Table
        The schema's columns in its order, no index.

    Raises
    ------
    KeyError
        When a column of the schema that is not optional is missing from ``df``.
    """
    absent = [f for f in schema if f.name not in df.columns]
    missing = [f.name for f in absent if (f.metadata or {}).get(b"optional") != OPTIONAL_FIELD[b"optional"]]
    if missing:
        raise KeyError(f"columns {missing} missing; expected {schema.names}")
    if absent:
        df = df.assign(**{f.name: None for f in absent})
    return pa.Table.from_pandas(df[schema.names], schema=schema, preserve_index=False)


def write_table(
    table: pa.Table | pd.DataFrame,
    path: str | os.PathLike,
    schema: pa.Schema | None = None,
    metadata: Mapping[str, str] | None = None,
) -> None:
    """Write a Parquet file atomically (LZ4, :func:`parquet_options`), optionally cast
    to ``schema``.

    Parameters
    ----------
    table : pyarrow.Table or pandas.DataFrame
    path : path
    schema : pyarrow.Schema, optional
        Columns selected and cast to it (a frame through :func:`table_from_frame`).
    metadata : mapping of str to str, optional
        Stored as key/value strings in the file's schema metadata (units, provenance,
        e.g. the dataset name); values are passed through ``str``.

    Raises
    ------
    KeyError
        A frame lacks a column of ``schema`` that is not optional.
    """
    if not isinstance(table, pa.Table):  # a pandas DataFrame
        table = (
            table_from_frame(table, schema)
            if schema is not None
            else pa.Table.from_pandas(table, preserve_index=False)
        )
    elif schema is not None:
        table = table.select(schema.names).cast(schema)
    if metadata:
        merged = dict(table.schema.metadata or {})
        merged.update({k.encode(): str(v).encode() for k, v in metadata.items()})
        table = table.replace_schema_metadata(merged)
    with atomic_path(path) as tmp:
        pq.write_table(table, tmp, **parquet_options(table.schema))


def parquet_options(schema: pa.Schema, statistics: list[str] | None = None) -> dict:
    """Keyword arguments for ``pyarrow.parquet.write_table`` / ``ParquetWriter``: LZ4
    (pyarrow's ``"lz4"`` is the interoperable LZ4_RAW codec of the Parquet format);
    floating-point columns BYTE_STREAM_SPLIT-encoded without a dictionary (coordinates
    rarely repeat: a dictionary is built and dropped), the other columns
    dictionary-encoded. LZ4 rather than zstd (benchmarks/README.md).

    Parameters
    ----------
    schema : pyarrow.Schema
        The table's schema.
    statistics : list of str, optional
        The columns whose row-group min/max are written (default: all). The points
        tables keep them for ``scan_id`` (row groups of a scan range, :func:`iter_scans`)
        and, where a reader uses them, ``x`` and ``y``.

    Returns
    -------
    dict
        ``compression``, ``use_dictionary``, ``column_encoding`` and, with
        ``statistics``, ``write_statistics``.
    """
    floats = [f.name for f in schema if pa.types.is_floating(f.type)]
    options = {
        "compression": "lz4",
        "use_dictionary": [f.name for f in schema if f.name not in floats],
        "column_encoding": {name: "BYTE_STREAM_SPLIT" for name in floats},
    }
    if statistics is not None:
        options["write_statistics"] = list(statistics)
    return options


def read_table(path: str | os.PathLike, columns: list[str] | None = None) -> pd.DataFrame:
    """Read a Parquet file into a DataFrame (no index).

    Parameters
    ----------
    path : path
    columns : list of str, optional
        The columns to read (default: all).

    Returns
    -------
    pandas.DataFrame
    """
    return pq.read_table(path, columns=columns).to_pandas()


#: Schema metadata keys that pyarrow and pandas write for themselves.
_LIBRARY_METADATA = (b"pandas", b"ARROW:schema")


def read_metadata(path: str | os.PathLike) -> dict[str, str]:
    """The key/value strings :func:`write_table` stored in a Parquet file's schema
    metadata (pyarrow's and pandas' own keys left out); the data is not read.

    Parameters
    ----------
    path : path

    Returns
    -------
    dict of str to str
    """
    meta = pq.read_schema(path).metadata or {}
    return {k.decode(): v.decode() for k, v in meta.items() if k not in _LIBRARY_METADATA}


def recording_source(path: str | os.PathLike) -> str | None:
    """The user's recording an ingest table was read from, for messages.

    Parameters
    ----------
    path : path
        An ingest table (``scans``, ``scan_index``, ``pose_stream``).

    Returns
    -------
    str or None
        Ingest's ``source`` metadata, the file and the scan topic (e.g.
        ``/data/run.bag /scan``); None when the table has none or is unreadable.
    """
    try:
        return read_metadata(path).get("source")
    except (OSError, pa.ArrowException):
        return None


def describe_recording(detected: Mapping[str, str], mode: str = "") -> str:
    """What a recording was found to be and how it was registered, for people (the
    report's figure title, ``summary.md``): ``format rosbag, scan_topic /scan,
    pose_source ..., stamps recorded; registered in odometry mode``.

    Parameters
    ----------
    detected : mapping of str to str
        The scan index's schema metadata (:func:`read_metadata`): what ingest detected
        (:attr:`floorscan.ingest.recording.Recording.detected`).
    mode : str
        The register mode used; ``""``: ``pose``.

    Returns
    -------
    str
    """
    found = ", ".join(f"{k} {detected[k]}" for k in ("format", "scan_topic", "pose_source", "stamps") if k in detected)
    return f"{found or 'as configured'}; registered in {mode or 'pose'} mode"


def split_by_scan(df: pd.DataFrame, columns: tuple[str, ...] = ("x", "y", "z")) -> dict[int, np.ndarray]:
    """Group a points table by ``scan_id``.

    Arrays are new (the frame is not mutated); a scan's points keep their row order.

    Parameters
    ----------
    df : pandas.DataFrame
        ``scan_id`` and ``columns``.
    columns : tuple of str
        The coordinate columns to take, metres.

    Returns
    -------
    dict of int to (N, len(columns)) float64 ndarray
        In ascending ``scan_id``; empty for an empty frame.

    Raises
    ------
    KeyError
        When ``scan_id`` or one of ``columns`` is missing.
    """
    missing = [c for c in ("scan_id", *columns) if c not in df.columns]
    if missing:
        raise KeyError(f"points table: columns {missing} missing; expected scan_id, {', '.join(columns)}")
    if df.empty:
        return {}
    ids = df["scan_id"].to_numpy()
    pts = df[list(columns)].to_numpy(dtype=np.float64)
    order = np.argsort(ids, kind="stable")
    ids_sorted = ids[order]
    starts = np.flatnonzero(np.r_[True, ids_sorted[1:] != ids_sorted[:-1]])
    ends = np.r_[starts[1:], len(ids_sorted)]
    return {int(ids_sorted[s]): pts[order[s:e]] for s, e in zip(starts, ends)}


class ScanRowGroups:
    """Writes a points table (``scan_id, x, y, z``) scan by scan through a
    ``pyarrow.parquet.ParquetWriter``, buffered into row groups of about ``rows`` points
    (the ingest and register stages; :func:`iter_scans` reads them back batch by batch).

    ``add(scan_id, points)`` buffers one scan ((n, 3) metres, cast to the writer's
    float32 columns); ``flush()`` writes what is buffered and waits until it is written
    (call it once at the end). Use it as a context manager around the writing, so that a
    failure waits for the row group being written before the writer closes.

    A full row group is encoded and compressed in a background thread while the caller
    produces the next one (Arrow releases the GIL while it writes): in the ingest stage
    reading the bag and writing ``scans.parquet`` overlap. One row group at a time is in
    the thread, in order, so the file is the same as written in line, and memory holds
    two row groups at most.
    """

    def __init__(self, writer: pq.ParquetWriter, rows: int = 1 << 20):
        from concurrent.futures import ThreadPoolExecutor

        self.writer = writer
        self.rows = rows
        self.ids: list[np.ndarray] = []
        self.pts: list[np.ndarray] = []
        self.n = 0
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="ScanRowGroups")
        self._pending = None

    def __enter__(self) -> "ScanRowGroups":
        return self

    def __exit__(self, *exc) -> None:
        try:
            if exc[0] is None:
                self.flush()
            else:  # let the row group in the thread finish; its error, if any, is secondary
                self._wait(raise_error=False)
        finally:
            self._pool.shutdown(wait=True)

    def add(self, scan_id: int, points: np.ndarray) -> None:
        """Buffer one scan; a full row group goes to the writer thread.

        Parameters
        ----------
        scan_id : int
        points : (n, 3) float ndarray
            The scan's points, metres; cast to float32.
        """
        pts = np.asarray(points, dtype=np.float32).reshape(-1, 3)
        self.ids.append(np.full(len(pts), scan_id, np.int32))
        self.pts.append(pts)
        self.n += len(pts)
        if self.n >= self.rows:
            self._submit()

    def flush(self) -> None:
        self._submit()
        self._wait()

    def _wait(self, raise_error: bool = True) -> None:
        pending, self._pending = self._pending, None
        if pending is not None:
            err = pending.exception()
            if err is not None and raise_error:
                raise err

    def _submit(self) -> None:
        if not self.n:
            return
        # (3, n) with each coordinate contiguous: Arrow takes the rows without a copy
        # (columns of an (n, 3) array are strided and were copied once more)
        p = np.concatenate([a.T for a in self.pts], axis=1)
        table = pa.table(
            {"scan_id": np.concatenate(self.ids), "x": p[0], "y": p[1], "z": p[2]},
            schema=self.writer.schema,
        )
        self.ids, self.pts, self.n = [], [], 0
        self._wait()  # the previous row group is written first
        self._pending = self._pool.submit(self.writer.write_table, table, row_group_size=p.shape[1])


def iter_scans(
    path: str | os.PathLike,
    columns: tuple[str, ...] = ("x", "y", "z"),
    scan_range: tuple[int, int] | None = None,
    batch_rows: int = 1 << 16,
    dtype: type = np.float64,
) -> Iterator[tuple[int, np.ndarray]]:
    """Stream a points table (``scan_id, x, y, z``) scan by scan.

    Reads ``path`` in record batches, so memory holds one batch and one scan, never
    the whole recording (peak memory follows the largest scan).

    Parameters
    ----------
    path : path
        A Parquet points table, its rows grouped by scan (as ``scans.parquet`` and
        ``registered.parquet`` are written).
    columns : tuple of str
        Point columns returned, in this order.
    scan_range : (int, int), optional
        Only scans with ``start <= scan_id <= stop``; row groups outside the range
        (by their statistics) are not read.
    batch_rows : int
        Rows per record batch.
    dtype : numpy dtype
        Of the points yielded: float64 (default), or float32 to read the stored
        (float32) coordinates without widening them (half the memory traffic for a
        reader that only screens most scans, as the register stage).

    Yields
    ------
    scan_id : int
    points : (n, len(columns)) ndarray of ``dtype``
        A new array per scan, in file order.

    Raises
    ------
    InputError
        When a column is missing, or a scan's rows are not contiguous (the message
        names the file and the scan).
    """
    pf = pq.ParquetFile(path, pre_buffer=False)  # pre-buffering holds more row groups at once
    names = pf.schema_arrow.names
    missing = [c for c in ("scan_id", *columns) if c not in names]
    if missing:
        raise InputError(f"{path}: columns {missing} missing; expected scan_id, {', '.join(columns)}")
    groups = list(range(pf.metadata.num_row_groups))
    if scan_range is not None:
        lo, hi = int(scan_range[0]), int(scan_range[1])
        col = names.index("scan_id")
        keep = []
        for g in groups:
            st = pf.metadata.row_group(g).column(col).statistics
            if st is not None and st.has_min_max and (st.max < lo or st.min > hi):
                continue
            keep.append(g)
        groups = keep
    done: set[int] = set()
    cur, parts = None, []
    if not groups:
        return
    for batch in pf.iter_batches(batch_size=batch_rows, row_groups=groups, columns=["scan_id", *columns]):
        ids = batch.column(0).to_numpy(zero_copy_only=False)
        pts = np.empty((len(ids), len(columns)), dtype=dtype)
        for i in range(len(columns)):
            pts[:, i] = batch.column(i + 1).to_numpy(zero_copy_only=False)
        if scan_range is not None:
            sel = (ids >= lo) & (ids <= hi)
            ids, pts = ids[sel], pts[sel]
        if len(ids) == 0:
            continue
        cuts = np.flatnonzero(ids[1:] != ids[:-1]) + 1
        for a, b in zip(np.r_[0, cuts], np.r_[cuts, len(ids)]):
            sid = int(ids[a])
            if sid == cur:
                parts.append(pts[a:b])
                continue
            if cur is not None:
                done.add(cur)
                yield cur, np.concatenate(parts)
            if sid in done:
                raise InputError(
                    f"{path}: the rows of scan {sid} are not contiguous; expected the points "
                    "grouped by scan_id, as the ingest and register stages write them"
                )
            cur, parts = sid, [pts[a:b]]
    if cur is not None:
        yield cur, np.concatenate(parts)

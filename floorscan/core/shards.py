"""Shards: the per-scan stages split by scan range into independent jobs.

The hulls of a scan (:mod:`floorscan.select.hulls`) and its wall segments
(:mod:`floorscan.walls.extract`) depend only on that scan's points, the stage parameters and
a random generator seeded with ``(seed, scan_id)``, never on the other scans a job
processes. So the stages ``hulls`` and ``scan_walls`` can run on contiguous scan id
ranges (shards) in separate jobs, in parallel on local cores or cluster nodes, and
the shard tables concatenated in scan order equal the table of one unsharded job.

The number of shards depends on the number of kept scans, which is known only after
registration, so the workflow's ``register`` rule is a Snakemake checkpoint: when it
ends, the Snakemake process reads the shard plan from its files
(:func:`plan_from_files`, a few milliseconds) and names the shard jobs. The plan
(:func:`plan_shards`) cuts the scan id axis ``[first, last]`` into contiguous,
inclusive ranges holding at most ``shard_scans`` kept scans each, as evenly as
possible. The ranges cover every scan id (kept or not) exactly once, so each point
of ``registered.parquet`` falls in exactly one shard. A shard's range is in its file
name (:func:`shard_label`), so a shard job needs only its inputs and its wildcards.

Why shards of kept scans rather than fixed ranges of scan ids: the kept scans
are spread unevenly over the recording (hallways keeps 1017 of 5081 scans), so fixed
id ranges would give unequal jobs, and a fixed number of shards would split small
recordings into jobs that cost more to start than to run.
"""

from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path
from typing import TYPE_CHECKING, Iterable, Sequence

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

if TYPE_CHECKING:
    import pandas as pd

from floorscan.core.io import InputError

#: A shard label (:func:`shard_label`) as a regular expression, without anchors: the
#: constraint of the ``{shard}`` wildcard of the workflow's shard rules
#: (``workflow/rules/common.smk``) and what :func:`parse_shard_label` accepts.
SHARD_LABEL = r"scans_\d+-\d+"


def shard_ranges(
    kept_ids: Iterable[int], shard_scans: int, first: int | None = None, last: int | None = None
) -> list[tuple[int, int]]:
    """Cut the scan id axis into ranges of at most ``shard_scans`` kept scans each.

    Parameters
    ----------
    kept_ids : iterable of int
        Ids of the kept scans (any order; duplicates are counted once).
    shard_scans : int
        Kept scans per shard at most; 0 means no sharding (one range).
    first, last : int, optional
        The ranges cover ``[first, last]`` (inclusive), e.g. every scan id of the
        recording; default the smallest and largest kept id.

    Returns
    -------
    list of (start, stop) int tuples
        Inclusive, contiguous, ascending: the first starts at ``first``, the last
        stops at ``last`` and each starts one after the previous one's stop. Their
        number is ``ceil(K / shard_scans)`` for K kept scans, and the kept scans are
        split as evenly as possible (sizes differ by at most one, larger first). A
        range starts at a kept scan (except the first, which starts at ``first``).

    Raises
    ------
    ValueError
        When there is no kept scan, ``shard_scans`` is negative, or ``[first, last]``
        does not contain every kept id.
    """
    kept = np.unique(np.asarray(list(kept_ids), dtype=np.int64))
    if int(shard_scans) < 0:
        raise ValueError(f"shard_scans must be >= 0 (0 = one shard), got {shard_scans}")
    if len(kept) == 0:
        raise ValueError("no kept scans to shard: every scan was dropped by registration")
    first = int(kept[0]) if first is None else int(first)
    last = int(kept[-1]) if last is None else int(last)
    if first > kept[0] or last < kept[-1]:
        raise ValueError(
            f"scan range [{first}, {last}] does not contain every kept scan "
            f"(kept ids {int(kept[0])}..{int(kept[-1])})"
        )
    n = 1 if int(shard_scans) == 0 else math.ceil(len(kept) / int(shard_scans))
    chunks = np.array_split(kept, n)
    starts = [first] + [int(c[0]) for c in chunks[1:]]
    stops = [s - 1 for s in starts[1:]] + [last]
    return list(zip(starts, stops))


def shard_label(start: int, stop: int) -> str:
    """Name of the shard of scans ``start..stop`` (inclusive).

    Parameters
    ----------
    start, stop : int
        First and last scan id.

    Returns
    -------
    str
        ``scans_<start>-<stop>``, six digits each, e.g. ``scans_000120-000239``.

    Raises
    ------
    ValueError
        Unless 0 <= start <= stop.
    """
    if not 0 <= int(start) <= int(stop):
        raise ValueError(f"a shard needs 0 <= start <= stop, got {start}, {stop}")
    return f"scans_{int(start):06d}-{int(stop):06d}"


def parse_shard_label(label: str) -> tuple[int, int]:
    """``"scans_000120-000239"`` -> ``(120, 239)``: the inverse of :func:`shard_label`.

    Parameters
    ----------
    label : str

    Returns
    -------
    start, stop : int

    Raises
    ------
    ValueError
        When ``label`` does not match :data:`SHARD_LABEL` or start > stop.
    """
    if re.fullmatch(SHARD_LABEL, str(label)):
        start, stop = (int(n) for n in str(label).removeprefix("scans_").split("-"))
        if start <= stop:
            return start, stop
    raise ValueError(f"not a shard label scans_<start>-<stop> with start <= stop: {label!r}")


def plan_shards(
    registration: pd.DataFrame,
    point_scan_ids: np.ndarray | Sequence[int] = (),
    shard_scans: int = 0,
    path: str = "registration.parquet",
) -> dict:
    """The shard plan of a per-scan stage: its shards' scan ranges and labels.

    Parameters
    ----------
    registration : pandas.DataFrame or pyarrow.Table
        ``registration.parquet``: a row per scan with ``scan_id`` and ``kept`` (and
        ``reason``, quoted when no scan is kept).
    point_scan_ids : (P,) int array_like
        ``scan_id`` of the points of ``registered.parquet`` (or just their smallest
        and largest): the ranges also cover these, so no point falls outside every
        shard.
    shard_scans : int
        Kept scans per shard at most; 0 = one shard.
    path : str
        Name of the registration file in error messages.

    Returns
    -------
    dict
        ``shard_scans``, ``n_kept``, ``first``, ``last`` and ``shards``: a list of
        ``{"label", "start", "stop", "n_kept"}`` in scan order (see
        :func:`shard_ranges`).

    Raises
    ------
    InputError
        When ``registration`` lacks ``scan_id`` or ``kept``, or keeps no scan.
    """
    names = list(registration.column_names if isinstance(registration, pa.Table) else registration.columns)
    missing = [c for c in ("scan_id", "kept") if c not in names]
    if missing:
        raise InputError(f"{path}: columns {missing} missing; expected scan_id, kept, ...")
    ids = np.asarray(registration["scan_id"], dtype=np.int64)
    kept = np.unique(ids[np.asarray(registration["kept"], dtype=bool)])
    if len(kept) == 0:
        reasons = {}
        if "reason" in names:  # the drop reasons, counted with pandas
            reason = registration["reason"]
            reasons = (reason.to_pandas() if isinstance(reason, pa.ChunkedArray) else reason).value_counts().to_dict()
        raise InputError(
            f"{path}: no kept scan (of {len(ids)}), so no hulls or walls to compute; "
            f"registration drop reasons: {reasons or 'none recorded'}"
        )
    pts = np.asarray(point_scan_ids, dtype=np.int64).ravel()
    first = int(min(ids.min(), pts.min())) if len(pts) else int(ids.min())
    last = int(max(ids.max(), pts.max())) if len(pts) else int(ids.max())
    ranges = shard_ranges(kept, shard_scans, first, last)
    shards = []
    for start, stop in ranges:
        n = int(((kept >= start) & (kept <= stop)).sum())
        shards.append({"label": shard_label(start, stop), "start": start, "stop": stop, "n_kept": n})
    return {"shard_scans": int(shard_scans), "n_kept": int(len(kept)), "first": first, "last": last, "shards": shards}


def scan_id_bounds(path: str | os.PathLike) -> tuple[int, int] | None:
    """Smallest and largest ``scan_id`` of a Parquet table, from its row groups'
    statistics (the column itself is read only when a row group has none).

    Parameters
    ----------
    path : path

    Returns
    -------
    (int, int) or None
        None for a table without rows.

    Raises
    ------
    InputError
        Naming ``path``, when it has no ``scan_id`` column.
    """
    pf = pq.ParquetFile(path)
    names = pf.schema_arrow.names
    if "scan_id" not in names:
        raise InputError(f"{path}: no scan_id column; expected {names} to have one")
    col = names.index("scan_id")
    lo = hi = None
    for g in range(pf.metadata.num_row_groups):
        group = pf.metadata.row_group(g)
        if group.num_rows == 0:
            continue
        stats = group.column(col).statistics
        if stats is None or not stats.has_min_max:
            ids = pf.read(columns=["scan_id"])["scan_id"].to_numpy()
            return (int(ids.min()), int(ids.max())) if len(ids) else None
        lo = int(stats.min) if lo is None else min(lo, int(stats.min))
        hi = int(stats.max) if hi is None else max(hi, int(stats.max))
    return None if lo is None else (lo, hi)


def plan_from_files(
    registration: str | os.PathLike, registered: str | os.PathLike, shard_scans: int
) -> dict:
    """:func:`plan_shards` of the register stage's files, reading only what it needs.

    The workflow calls this in the Snakemake process once ``register`` (a checkpoint)
    has ended, to name the shard jobs, and the merging jobs call it again to check
    their shards: the columns ``scan_id`` and ``kept`` of ``registration`` (a row per
    recorded scan) and the ``scan_id`` bounds of ``registered`` (row-group
    statistics, :func:`scan_id_bounds`), with pyarrow only.

    Parameters
    ----------
    registration : path
        ``registration.parquet``.
    registered : path
        ``registered.parquet``.
    shard_scans : int
        Kept scans per shard at most; 0 = one shard.

    Returns
    -------
    dict
        As :func:`plan_shards`.

    Raises
    ------
    InputError
        As :func:`plan_shards`, naming the file; or ``registered`` has no ``scan_id``.
    """
    # ParquetFile.read: pq.read_table imports pyarrow.dataset (0.3 s of CPU)
    pf = pq.ParquetFile(registration)
    cols = [c for c in ("scan_id", "kept") if c in pf.schema_arrow.names]
    table = pf.read(columns=cols) if len(cols) == 2 else pf.read()
    if len(cols) == 2 and not np.asarray(table["kept"], dtype=bool).any():
        table = pf.read()  # with the drop reasons, for the error message
    bounds = scan_id_bounds(registered)
    return plan_shards(table, np.array(bounds or (), dtype=np.int64), shard_scans, path=str(registration))


def read_scan_range(
    path: str | os.PathLike, start: int, stop: int, columns: Sequence[str] | None = None
) -> pd.DataFrame:
    """The rows of a Parquet table with ``start <= scan_id <= stop``, in file order.

    Reads with a pyarrow filter, so row groups outside the range are skipped.

    Parameters
    ----------
    path : path
    start, stop : int
        Inclusive scan id range.
    columns : sequence of str, optional
        The columns to read (default: all).

    Returns
    -------
    pandas.DataFrame

    Raises
    ------
    InputError
        Naming ``path``, when it has no ``scan_id`` column.
    """
    names = pq.read_schema(path).names
    if "scan_id" not in names:
        raise InputError(f"{path}: no scan_id column; expected {names} to have one")
    table = pq.read_table(
        path, columns=list(columns) if columns else None,
        filters=[("scan_id", ">=", int(start)), ("scan_id", "<=", int(stop))],
    )
    return table.to_pandas()


def concat_shards(tables: Sequence[pa.Table], labels: Sequence[str], what: str = "shard") -> pa.Table:
    """Concatenate shard tables in scan order, checking each stays in its range.

    Parameters
    ----------
    tables : sequence of pyarrow.Table
        One table per shard with a ``scan_id`` column, same schema, in the order of
        ``labels``.
    labels : sequence of str
        The shards' labels (:func:`shard_label`): contiguous, ascending ranges.
    what : str
        What the tables are, for error messages (e.g. a file pattern).

    Returns
    -------
    pyarrow.Table
        The rows of all shards in order, one chunk per column, without schema
        metadata (the writer adds the stage's own).

    Raises
    ------
    ValueError
        When the counts differ, the ranges are not contiguous and ascending, a shard
        has a scan outside its range or its scan ids are not ascending, or the
        schemas differ.
    """
    if len(tables) != len(labels) or not tables:
        raise ValueError(f"{what}: {len(tables)} tables for {len(labels)} shard labels (need >= 1 each)")
    ranges = [parse_shard_label(lb) for lb in labels]
    for (a0, b0), (a1, b1) in zip(ranges, ranges[1:]):
        if a1 != b0 + 1:
            raise ValueError(f"{what}: shards {shard_label(a0, b0)} and {shard_label(a1, b1)} are not contiguous")
    schema = tables[0].schema.remove_metadata()
    for t, label, (a, b) in zip(tables, labels, ranges):
        if not t.schema.remove_metadata().equals(schema):
            raise ValueError(f"{what} {label}: schema {t.schema.remove_metadata()} differs from {schema}")
        sid = t.column("scan_id").to_numpy()
        if len(sid) and (sid.min() < a or sid.max() > b):
            raise ValueError(f"{what} {label}: scan ids {sid.min()}..{sid.max()} outside its range {a}..{b}")
        if len(sid) > 1 and (np.diff(sid) < 0).any():
            raise ValueError(f"{what} {label}: scan ids not ascending")
    merged = pa.concat_tables([t.replace_schema_metadata(None) for t in tables])
    return merged.combine_chunks()


def read_shards(paths: Sequence[str | os.PathLike], plan: dict, what: str = "shard") -> tuple[pa.Table, dict]:
    """Read the shard files of a plan and concatenate them in scan order.

    Parameters
    ----------
    paths : sequence of path
        One Parquet file per shard, each in a folder named by its label
        (``.../scans_000000-000339/hulls.parquet``), in plan order.
    plan : dict
        The plan (:func:`plan_shards`) the shards were made for.
    what : str
        What the files are, for error messages.

    Returns
    -------
    table : pyarrow.Table
        :func:`concat_shards` of the files.
    counts : dict
        The sum over shards of the JSON ``counts`` of each file's schema metadata
        (per-shard drop counts), ``{}`` when the files carry none.

    Raises
    ------
    ValueError
        When the files' labels are not the plan's shards (a stale plan or shard), or
        as :func:`concat_shards`.
    """
    labels = [Path(p).parent.name for p in paths]
    expected = [s["label"] for s in plan["shards"]]
    if labels != expected:
        raise ValueError(f"{what}: shard files {labels} do not match the plan's shards {expected}")
    tables = [pq.read_table(p) for p in paths]
    counts: dict = {}
    for t in tables:
        for key, value in json.loads((t.schema.metadata or {}).get(b"counts", b"{}")).items():
            counts[key] = counts.get(key, 0) + value
    return concat_shards(tables, labels, what), counts

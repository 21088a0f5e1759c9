"""What a user takes home from the select stage: how many scans to keep, which ones,
and their points.

An ordering (``orderings/<name>.parquet``) ranks every kept scan by what it adds; its
cumulative objective (covered area, covered cells) rises quickly, then flattens. Three
deliverables come from it:

- :func:`recommended_k`: the number of scans to keep, by a rule (``"auto"``: the
  smallest k whose cumulative objective reaches a fraction of what all scans reach, the
  ``k_99`` of thesis section 3.3's coverage curves; a count; a fraction of the scans),
  with a one-sentence reason quoting the numbers;
- :func:`scan_list` / :func:`write_scan_list`: the first k scans as a table for people
  and scripts (rank, scan id, time, registered pose, gain), CSV with fixed formatting;
- :func:`write_selected_points`: the selected scans' map-frame points as PLY and PCD
  (Open3D), for a point-cloud viewer or a CAD tool.

The reduced recording (the same recording with the selected scans only) is written by
the ingest stage, which reads the recording's formats: :mod:`floorscan.ingest.reduced`.

Usage::

    k, reason = recommended_k(ordering["covered_area_m2"].to_numpy(), "auto", 0.99,
                              objective="cluster_hull", unit="m2")
    table = scan_list(ordering, k, scan_index, registration)
    write_scan_list(table, "results/demo/deliverables/scans.csv")
    write_selected_points("results/demo/registered.parquet", table["scan_id"], "scans.ply", "scans.pcd")

Every file is written under a temporary name beside its target and renamed
(:func:`floorscan.core.files.atomic_path`, :func:`floorscan.core.files.staged_path`).
"""

from __future__ import annotations

import math
import numbers
import os
from typing import Iterable

import numpy as np
import pandas as pd
import pyarrow as pa

from floorscan.core.files import atomic_path, staged_path
from floorscan.core.io import iter_scans

#: Columns of :func:`scan_list`, in order.
SCAN_LIST_COLUMNS = ("rank", "scan_id", "t_ns", "time_iso", "x_m", "y_m", "yaw_rad", "gain")
#: The scan list as the stages read it (``selection/scans.parquet``): the columns of
#: :data:`SCAN_LIST_COLUMNS` with their units; ``rank`` 1-based.
SCAN_TABLE = pa.schema(
    [
        ("rank", pa.int64()), ("scan_id", pa.int64()), ("t_ns", pa.int64()), ("time_iso", pa.string()),
        ("x_m", pa.float64()), ("y_m", pa.float64()), ("yaw_rad", pa.float64()), ("gain", pa.float64()),
    ]  # fmt: skip
)
#: Gain columns an ordering may carry, in the order they are looked for.
GAIN_COLUMNS = ("gain", "gain_m2")
#: ``printf`` format of every float column of the scan list CSV: micrometres and
#: microradians, more than any registration resolves, and the same bytes every run.
CSV_FLOAT_FORMAT = "%.6f"


def recommended_k(
    covered,
    rule: str | int | float = "auto",
    fraction: float = 0.99,
    *,
    objective: str = "the ordering's objective",
    unit: str = "",
) -> tuple[int, str]:
    """The number of scans to keep from an ordering, and why.

    Parameters
    ----------
    covered : (n,) float array_like
        Cumulative objective of the ordering in rank order (covered area in m2,
        covered cells, ...): ``covered[i]`` is what the first ``i + 1`` scans reach.
        Non-decreasing.
    rule : ``"auto"``, int or float
        ``"auto"``: the smallest k with ``covered[k - 1] >= fraction * covered[-1]``
        (with a relative slack of 1e-12 for the rounding of a cumulative sum; with
        nothing covered at all, k = 1). An int: that k, clipped to ``[1, n]`` (the
        reason says so). A float in (0, 1]: that fraction of the n scans, rounded up
        (at least 1).
    fraction : float
        ``"auto"``: the share of what all scans reach that k scans must reach, in (0, 1].
    objective : str
        Name of the objective in the reason (e.g. the ordering, ``"wall_coverage"``).
    unit : str
        Unit of ``covered`` in the reason (``"cells"``, ``"m2"``); empty for none.

    Returns
    -------
    k : int
        In ``[1, n]``.
    reason : str
        One sentence with the numbers, e.g. ``"k = 64 of 893 kept scans: the smallest k
        whose wall_coverage reaches 99 % of what all scans cover (5,012 of 5,063
        cells)"``.

    Raises
    ------
    ValueError
        An empty ordering; ``covered`` not 1-D, not finite or decreasing; a ``rule``
        that is none of ``"auto"``, an int, a float in (0, 1]; ``fraction`` outside
        (0, 1].
    """
    cov = np.asarray(covered, dtype=np.float64)
    if cov.ndim != 1:
        raise ValueError(f"covered: expected a 1-D array of the cumulative objective, got shape {cov.shape}")
    n = len(cov)
    if n == 0:
        raise ValueError("empty ordering: no scans to recommend (covered has no values)")
    if not np.all(np.isfinite(cov)):
        raise ValueError(f"covered: {int(np.count_nonzero(~np.isfinite(cov)))} values are not finite")
    drops = np.diff(cov) < -1e-9 * max(abs(cov[-1]), 1.0)
    if np.any(drops):
        i = int(np.flatnonzero(drops)[0]) + 1
        raise ValueError(
            f"covered: expected a non-decreasing cumulative objective, but rank {i + 1} "
            f"({cov[i]:g}) is below rank {i} ({cov[i - 1]:g})"
        )
    total = _amount(cov[-1], cov, unit)
    if isinstance(rule, str):
        if rule != "auto":
            raise ValueError(f"rule {rule!r}: expected 'auto', an int count of scans or a float fraction in (0, 1]")
        if not (isinstance(fraction, numbers.Real) and 0 < fraction <= 1):
            raise ValueError(f"fraction {fraction!r}: expected a number in (0, 1]")
        if cov[-1] <= 0:
            return 1, (
                f"k = 1 of {n} kept scans: {objective} is {total} for every k, so the smallest k "
                f"reaching {_percent(fraction)} of it is 1"
            )
        target = fraction * cov[-1] * (1 - 1e-12)
        k = int(np.argmax(cov >= target)) + 1
        return k, (
            f"k = {k} of {n} kept scans: the smallest k whose {objective} reaches {_percent(fraction)} "
            f"of what all scans cover ({_amount(cov[k - 1], cov, '')} of {total})"
        )
    if isinstance(rule, (bool, np.bool_)):
        raise ValueError(f"rule {rule!r}: expected 'auto', an int count of scans or a float fraction in (0, 1]")
    if isinstance(rule, numbers.Integral):
        asked = int(rule)
        k = min(max(asked, 1), n)
        why = f"{asked} asked" if k == asked else f"{asked} asked, clipped to [1, {n}]"
    elif isinstance(rule, numbers.Real) and 0 < rule <= 1:
        k = min(max(math.ceil(float(rule) * n - 1e-9), 1), n)
        why = f"{_percent(rule)} of the scans, rounded up"
    else:
        raise ValueError(
            f"rule {rule!r}: expected 'auto', an int count of scans or a float fraction in (0, 1] "
            "(for a count, give an int)"
        )
    share = f"{_percent(cov[k - 1] / cov[-1])} of what all scans cover, " if cov[-1] > 0 else ""
    return k, (
        f"k = {k} of {n} kept scans: {why} (its {objective} reaches {share}"
        f"{_amount(cov[k - 1], cov, '')} of {total})"
    )


def _percent(f: float) -> str:
    return f"{100 * float(f):.3g} %"


def _amount(value: float, cov: np.ndarray, unit: str) -> str:
    """``5,012`` for whole numbers (cells), ``12.35`` otherwise, with the unit."""
    whole = np.all(cov == np.round(cov))
    text = f"{value:,.0f}" if whole else f"{value:,.2f}"
    return f"{text} {unit}" if unit else text


def scan_list(
    ordering: pd.DataFrame, k: int, scan_index: pd.DataFrame, registration: pd.DataFrame
) -> pd.DataFrame:
    """The first ``k`` scans of an ordering, with their time and registered pose.

    Parameters
    ----------
    ordering : pandas.DataFrame
        ``orderings/<name>.parquet``: ``rank``, ``scan_id`` and a gain column
        (``gain`` or ``gain_m2``, whichever exists). Rows are taken in ``rank`` order.
    k : int
        Number of scans, ``1 <= k <= len(ordering)``.
    scan_index : pandas.DataFrame
        ``scan_index.parquet``: ``scan_id``, ``t_ns``.
    registration : pandas.DataFrame
        ``registration.parquet``: ``scan_id``, ``kept`` and the final registered pose
        ``x_m``, ``y_m`` (metres), ``yaw_rad`` (radians).

    Returns
    -------
    pandas.DataFrame
        ``k`` rows, columns :data:`SCAN_LIST_COLUMNS`: ``rank`` (int64, 1-based),
        ``scan_id`` (int64), ``t_ns`` (int64, ns since the Unix epoch), ``time_iso``
        (UTC ISO 8601, nanoseconds truncated to microseconds, e.g.
        ``2023-05-01T12:00:00.123456Z``), ``x_m``, ``y_m`` (metres), ``yaw_rad``
        (radians, counter-clockwise from +x), ``gain`` (float64, the ordering's gain
        of the scan, in the ordering's unit).

    Raises
    ------
    ValueError
        ``k`` outside ``[1, len(ordering)]``; a missing column (named with its table);
        a selected scan that is not in the scan index, not in the registration table
        or not kept there (the tables are from different runs).
    """
    gain_col = next((c for c in GAIN_COLUMNS if c in ordering.columns), None)
    _need(ordering, ("rank", "scan_id"), "ordering")
    if gain_col is None:
        raise ValueError(f"ordering: no gain column; expected one of {list(GAIN_COLUMNS)}, got {list(ordering.columns)}")
    _need(scan_index, ("scan_id", "t_ns"), "scan_index")
    _need(registration, ("scan_id", "kept", "x_m", "y_m", "yaw_rad"), "registration")
    n = len(ordering)
    if isinstance(k, (bool, np.bool_)) or not isinstance(k, numbers.Integral) or not 1 <= k <= n:
        raise ValueError(f"k {k!r}: expected an int in [1, {n}] (the ordering's scans)")
    top = ordering.sort_values("rank", kind="stable").head(int(k))
    ids = top["scan_id"].to_numpy(dtype=np.int64)
    t = scan_index.set_index(scan_index["scan_id"].astype(np.int64))["t_ns"]
    missing = np.setdiff1d(ids, t.index.to_numpy())
    if missing.size:
        raise ValueError(f"scan_index: selected scans {missing.tolist()[:10]} are not in it; expected every ordered scan")
    reg = registration.set_index(registration["scan_id"].astype(np.int64))
    missing = np.setdiff1d(ids, reg.index.to_numpy())
    if missing.size:
        raise ValueError(f"registration: selected scans {missing.tolist()[:10]} are not in it; expected every ordered scan")
    reg = reg.loc[ids]
    rejected = ids[~reg["kept"].to_numpy(dtype=bool)]
    if rejected.size:
        raise ValueError(
            f"registration: selected scans {rejected.tolist()[:10]} are not kept there; "
            "expected the ordering's scans to be kept scans (tables from different runs?)"
        )
    t_ns = t.loc[ids].to_numpy(dtype=np.int64)
    return pd.DataFrame(
        {
            "rank": np.arange(1, len(ids) + 1, dtype=np.int64),
            "scan_id": ids,
            "t_ns": t_ns,
            "time_iso": iso_times(t_ns),
            "x_m": reg["x_m"].to_numpy(dtype=np.float64),
            "y_m": reg["y_m"].to_numpy(dtype=np.float64),
            "yaw_rad": reg["yaw_rad"].to_numpy(dtype=np.float64),
            "gain": top[gain_col].to_numpy(dtype=np.float64),
        },
        columns=list(SCAN_LIST_COLUMNS),
    )


def _need(df: pd.DataFrame, columns: Iterable[str], name: str) -> None:
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise ValueError(f"{name}: columns {missing} missing; expected {list(columns)} (got {list(df.columns)})")


def iso_times(t_ns) -> list[str]:
    """UTC ISO 8601 times of nanosecond stamps, truncated to microseconds.

    Parameters
    ----------
    t_ns : (n,) int64 array_like
        Nanoseconds since the Unix epoch.

    Returns
    -------
    list of str
        ``"2023-05-01T12:00:00.123456Z"`` per stamp.
    """
    t = np.asarray(t_ns, dtype=np.int64)
    us = (t // 1000).astype("datetime64[us]")  # floor: truncation for stamps after 1970
    return [s + "Z" for s in np.datetime_as_string(us, unit="us")]


def write_scan_list(df: pd.DataFrame, path: str | os.PathLike) -> None:
    """Write a :func:`scan_list` table as CSV, atomically.

    Floats are written with :data:`CSV_FLOAT_FORMAT` and lines end in ``\\n``, so the
    same table gives the same bytes; a missing value is an empty field.

    Parameters
    ----------
    df : pandas.DataFrame
        A :func:`scan_list` table.
    path : path
        CSV output.
    """
    with atomic_path(path) as tmp:
        df.to_csv(tmp, index=False, float_format=CSV_FLOAT_FORMAT, lineterminator="\n")


def write_selected_points(
    registered_path: str | os.PathLike,
    scan_ids: Iterable[int],
    ply_path: str | os.PathLike,
    pcd_path: str | os.PathLike,
) -> int:
    """Write the selected scans' map-frame points as a binary PLY and a binary PCD.

    The points are read from ``registered.parquet`` scan by scan
    (:func:`floorscan.core.io.iter_scans`), in scan id order, with their stored float32
    coordinates; both files hold one plain cloud of float32 ``x, y, z`` (metres, map
    frame), written with Open3D's tensor API (``open3d.t.io.write_point_cloud``).

    Parameters
    ----------
    registered_path : path
        ``registered.parquet`` (``scan_id, x, y, z``).
    scan_ids : iterable of int
        The selected scans (kept scans of the registration).
    ply_path, pcd_path : path
        Outputs; each is written under a temporary name with its extension beside it
        and renamed (:func:`floorscan.core.files.staged_path`).

    Returns
    -------
    int
        Number of points written.

    Raises
    ------
    ValueError
        No scan selected, or selected scans without points in ``registered_path``
        (listed; not kept, or a file of another run).
    OSError
        Open3D could not write a file.
    """
    import open3d as o3d

    wanted = sorted({int(s) for s in scan_ids})
    if not wanted:
        raise ValueError("no scans selected: expected at least one scan id")
    keep = set(wanted)
    parts, found = [], set()
    for sid, pts in iter_scans(registered_path, scan_range=(wanted[0], wanted[-1]), dtype=np.float32):
        if sid in keep:
            parts.append(pts)
            found.add(sid)
    missing = sorted(keep - found)
    if missing:
        raise ValueError(
            f"{registered_path}: selected scans {missing[:10]} have no points in it; expected kept scans"
        )
    xyz = np.ascontiguousarray(np.concatenate(parts), dtype=np.float32)
    cloud = o3d.t.geometry.PointCloud(o3d.core.Tensor(xyz))
    for path in (ply_path, pcd_path):
        with staged_path(path) as tmp:
            if not o3d.t.io.write_point_cloud(str(tmp), cloud, write_ascii=False, compressed=False):
                raise OSError(f"{path}: Open3D could not write the point cloud")
    return len(xyz)


def write_scan_table(df: pd.DataFrame, path: str | os.PathLike, metadata: dict | None = None) -> None:
    """Write a :func:`scan_list` table as Parquet (schema :data:`SCAN_TABLE`), atomically:
    the selection as the later stages read it (``selection/scans.csv`` is the same
    table for people).

    Parameters
    ----------
    df : pandas.DataFrame
        A :func:`scan_list` table.
    path : path
        Parquet output.
    metadata : dict, optional
        Key/value strings for the file (ordering, k).

    Raises
    ------
    KeyError
        When ``df`` lacks a column of :data:`SCAN_TABLE`.
    """
    from floorscan.core.io import write_table

    write_table(df, path, SCAN_TABLE, metadata=metadata)

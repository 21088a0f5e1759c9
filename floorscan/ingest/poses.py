"""Pose of each scan at its timestamp (thesis section 3.5, Algorithm 3 step 1).

The localizer (AMCL in the thesis) reports poses at its own rate, not synchronized with
the scans. Each scan's pose is interpolated between the two poses around its stamp:
linearly in position and along the shorter arc in yaw. Nothing is extrapolated: a scan
before the first or after the last pose, or between two poses further apart than
``max_gap_s``, gets no pose and is dropped with its reason.

A recording without a map pose source (ingest's pose kind ``none``: wheel odometry only)
has an empty pose stream; then no scan has a pose (reason ``no_pose_source``) and the
register stage places the scans by LIDAR odometry.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from floorscan.core.geometry import wrap_angle
from floorscan.core.io import AFTER, BEFORE, GAP, NO_POSE_SOURCE, InputError
from floorscan.ingest.params import PosesParams


def interpolate_poses(
    stream: pd.DataFrame, t_ns: np.ndarray, max_gap_s: float | None = None, source: str = "pose stream"
) -> pd.DataFrame:
    """Interpolate a pose stream at the given times.

    Parameters
    ----------
    stream : DataFrame
        Columns ``t_ns`` (int64, strictly increasing), ``x``, ``y``, ``z`` (metres) and
        ``yaw`` (radians), in the map frame. Empty: the recording has no map pose
        source, and every query gets reason ``no_pose_source``.
    t_ns : (S,) int64 ndarray
        Query times (scan stamps), nanoseconds.
    max_gap_s : float, optional
        Largest time between the two bracketing poses, seconds; None: ``poses.max_gap_s``'s
        default.
    source : str
        Name of the stream in error messages (e.g. the file).

    Returns
    -------
    DataFrame
        S rows: ``t_ns``, ``x``, ``y``, ``z``, ``yaw`` (wrapped to [-pi, pi); NaN when
        there is no pose), ``valid`` (bool), ``reason`` ("" or one of
        ``before_pose_stream``, ``after_pose_stream``, ``pose_gap``,
        ``no_pose_source``). A query equal to a stream stamp gets that pose exactly.

    Raises
    ------
    InputError
        Unsorted or duplicate stream stamps, or no query time within the stream's span
        (the stream does not overlap the scans).
    """
    if max_gap_s is None:
        max_gap_s = PosesParams().max_gap_s
    ts = stream["t_ns"].to_numpy(dtype=np.int64)
    q = np.asarray(t_ns, dtype=np.int64)
    if ts.size == 0:
        nan = np.full(q.size, np.nan)
        return pd.DataFrame(
            {"t_ns": q, "x": nan, "y": nan.copy(), "z": nan.copy(), "yaw": nan.copy(),
             "valid": np.zeros(q.size, dtype=bool), "reason": np.full(q.size, NO_POSE_SOURCE, dtype=object).astype(str)}
        )
    d = np.diff(ts)
    if np.any(d <= 0):
        i = int(np.flatnonzero(d <= 0)[0]) + 1
        kind = "duplicate" if d[i - 1] == 0 else "unsorted"
        raise InputError(
            f"{source}: {kind} t_ns at row {i} ({ts[i]} after {ts[i - 1]}); expected strictly increasing stamps"
        )
    n = q.size
    out = {k: np.full(n, np.nan) for k in ("x", "y", "z", "yaw")}
    reason = np.full(n, "", dtype=object)
    # index of the first stream stamp >= query
    hi = np.searchsorted(ts, q, side="left")
    exact = (hi < ts.size) & (ts[np.minimum(hi, ts.size - 1)] == q)
    before = (hi == 0) & ~exact
    after = hi >= ts.size
    reason[before] = BEFORE
    reason[after] = AFTER
    inner = ~(before | after | exact)
    lo_i = np.clip(hi - 1, 0, ts.size - 1)
    hi_i = np.clip(hi, 0, ts.size - 1)
    gap = inner & ((ts[hi_i] - ts[lo_i]) > int(round(max_gap_s * 1e9)))
    reason[gap] = GAP
    ok = inner & ~gap
    cols = {k: stream[k].to_numpy(dtype=np.float64) for k in ("x", "y", "z", "yaw")}
    if exact.any():
        for k in cols:
            out[k][exact] = cols[k][hi_i[exact]]
    if ok.any():
        a, b = lo_i[ok], hi_i[ok]
        w = (q[ok] - ts[a]).astype(np.float64) / (ts[b] - ts[a]).astype(np.float64)
        for k in ("x", "y", "z"):
            out[k][ok] = cols[k][a] + w * (cols[k][b] - cols[k][a])
        dyaw = wrap_angle(cols["yaw"][b] - cols["yaw"][a])  # shorter arc
        out["yaw"][ok] = cols["yaw"][a] + w * dyaw
    valid = ok | exact
    out["yaw"][valid] = wrap_angle(out["yaw"][valid])
    if n and not valid.any() and not gap.any():
        raise InputError(
            f"{source}: the pose stream [{ts[0]}, {ts[-1]}] ns does not overlap the scans "
            f"[{q.min()}, {q.max()}] ns"
        )
    return pd.DataFrame(
        {"t_ns": q, **out, "valid": valid, "reason": reason.astype(str)}
    )


def scan_poses(scan_index: pd.DataFrame, stream: pd.DataFrame, max_gap_s: float, source: str) -> pd.DataFrame:
    """The pose of every scan of ``scan_index`` (see :func:`interpolate_poses` for the
    rules).

    Parameters
    ----------
    scan_index : pandas.DataFrame
        ``scan_id``, ``t_ns`` (nanoseconds).
    stream : pandas.DataFrame
        A pose stream (:data:`floorscan.core.io.POSE_STREAM`).
    max_gap_s : float
        Longest gap between pose samples to interpolate across, seconds.
    source : str
        The recording, for messages.

    Returns
    -------
    pandas.DataFrame
        Columns of :data:`floorscan.core.io.POSES`, ``scan_id`` int32 first.

    Raises
    ------
    InputError
        As :func:`interpolate_poses`.
    """
    poses = interpolate_poses(stream, scan_index["t_ns"].to_numpy(), max_gap_s=max_gap_s, source=source)
    poses.insert(0, "scan_id", scan_index["scan_id"].to_numpy(dtype=np.int32))
    return poses


def missing_poses_line(poses: pd.DataFrame) -> str:
    """One log line on the scans without a pose, e.g. ``201 of 300 scans have no pose
    (after_pose_stream 201); the register stage counts them as lost
    (register.max_lost_fraction)``.

    Parameters
    ----------
    poses : pandas.DataFrame
        The table of :func:`scan_poses` (``valid``, ``reason``).

    Returns
    -------
    str
        ``""`` when every scan has a pose.
    """
    missing = ~poses["valid"].to_numpy(bool)
    if not missing.any():
        return ""
    counts = poses.loc[missing, "reason"].value_counts()
    reasons = ", ".join(f"{r} {n}" for r, n in counts.items())
    return (
        f"{int(missing.sum())} of {len(poses)} scans have no pose ({reasons}); the register stage counts them "
        "as lost (register.max_lost_fraction)"
    )

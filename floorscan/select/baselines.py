"""Baseline orderings: ``random``, ``sequential`` and ``motion_filter`` (thesis section
3.3, the comparisons of Fig. 5.6).

``random``
    A seeded permutation (:func:`random_order`).
``sequential``
    Recording order (:func:`sequential_order`).
``motion_filter``
    The SLAM practice (Cartographer's ``MotionFilter``): a scan is kept when, since
    the last kept scan, the scanner moved more than ``max_distance_m``, turned more
    than ``max_angle_rad`` or more than ``max_time_s`` passed; the first scan is
    kept. Kept scans in recording order, then the never-kept ones in recording order
    (:func:`motion_filter_order`).

Each returns the scan ids in rank order; the select stage measures the hull area
along them (:func:`floorscan.select.orderings.coverage_along`).
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import pandas as pd


def random_order(scan_ids: Sequence[int], seed: int) -> np.ndarray:
    """A seeded random permutation of ``scan_ids`` (sorted first, so the result
    depends only on the set and the seed): the random baseline ordering.

    Parameters
    ----------
    scan_ids : sequence of int
    seed : int
        Seeds ``numpy.random.default_rng``.

    Returns
    -------
    (S,) int64 ndarray
    """
    ids = np.sort(np.asarray(scan_ids, dtype=np.int64))
    return np.random.default_rng(seed).permutation(ids)


def sequential_order(scan_ids: Sequence[int], t_ns: Sequence[int] | None = None) -> np.ndarray:
    """Recording order: the sequential baseline ordering.

    Parameters
    ----------
    scan_ids : (S,) sequence of int
    t_ns : (S,) sequence of int, optional
        Each scan's stamp, nanoseconds.

    Returns
    -------
    (S,) int64 ndarray
        ``scan_ids`` by ascending ``t_ns`` (ties: scan_id), or ascending scan_id without
        ``t_ns``.
    """
    ids = np.asarray(scan_ids, dtype=np.int64)
    if t_ns is None:
        return np.sort(ids)
    return ids[np.lexsort((ids, np.asarray(t_ns, dtype=np.int64)))]


def motion_filter_mask(
    t_ns: Sequence[int],
    x_m: Sequence[float],
    y_m: Sequence[float],
    yaw_rad: Sequence[float],
    max_distance_m: float = 0.2,
    max_angle_rad: float = np.deg2rad(1.0),
    max_time_s: float = 5.0,
) -> np.ndarray:
    """Which scans a motion filter keeps (Cartographer ``MotionFilter``).

    Parameters
    ----------
    t_ns : (S,) int
        Scan times, ns, in recording order.
    x_m, y_m : (S,) float
        Scanner position in the map frame, metres.
    yaw_rad : (S,) float
        Heading, radians CCW from +x.
    max_distance_m, max_angle_rad, max_time_s : float
        Cartographer defaults 0.2 m, 1 degree, 5 s.

    Returns
    -------
    kept : (S,) bool ndarray
        The first scan with a finite pose is kept; a later scan is kept when, since
        the last kept scan, the time passed, the distance moved or the absolute
        wrapped yaw change is strictly greater than its threshold (Cartographer's
        ``IsSimilar`` drops a scan when all three are ``<=``). Scans with a NaN pose
        are never kept.

    Notes
    -----
    Sequential by nature (each decision depends on the last kept scan); a loop of
    S simple float steps.
    """
    t = np.asarray(t_ns, dtype=np.int64)
    x = np.asarray(x_m, dtype=np.float64)
    y = np.asarray(y_m, dtype=np.float64)
    a = np.asarray(yaw_rad, dtype=np.float64)
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(a)
    kept = np.zeros(len(t), dtype=bool)
    last = -1
    max_t_ns = max_time_s * 1e9
    for i in range(len(t)):
        if not ok[i]:
            continue
        if last < 0:
            kept[i] = True
            last = i
            continue
        dyaw = abs((a[i] - a[last] + np.pi) % (2 * np.pi) - np.pi)
        if (
            (t[i] - t[last]) > max_t_ns
            or np.hypot(x[i] - x[last], y[i] - y[last]) > max_distance_m
            or dyaw > max_angle_rad
        ):
            kept[i] = True
            last = i
    return kept


def motion_filter_order(poses: pd.DataFrame, **thresholds) -> np.ndarray:
    """Motion-filter ordering: kept scans in recording order, then the rest.

    Parameters
    ----------
    poses : DataFrame
        ``scan_id, t_ns, x_m, y_m, yaw_rad`` (e.g. the kept rows of
        ``registration.parquet``).
    **thresholds
        ``max_distance_m``, ``max_angle_rad``, ``max_time_s`` of
        :func:`motion_filter_mask`.

    Returns
    -------
    (S,) int64 scan ids.
    """
    p = poses.sort_values(["t_ns", "scan_id"], kind="stable")
    kept = motion_filter_mask(p["t_ns"], p["x_m"], p["y_m"], p["yaw_rad"], **thresholds)
    ids = p["scan_id"].to_numpy(dtype=np.int64)
    return np.r_[ids[kept], ids[~kept]]

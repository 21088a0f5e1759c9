"""The returns every reader keeps: finite and in ``[range_min, range_max)``.

A return at the maximum range is the scanner's "no return" (the Stage simulator, for
one, reports every beam that hits nothing at exactly ``range_max``) and would draw an arc
of fake wall, so the interval is open at the top. :func:`laser_scan_points` turns a
planar range scan into points; :func:`filter_points` applies the same rule to points.
"""

from __future__ import annotations

import numpy as np


def laser_scan_points(
    ranges: np.ndarray,
    angle_min: float,
    angle_increment: float,
    range_min: float,
    range_max: float,
) -> tuple[np.ndarray, int]:
    """Convert a planar range scan to points in the scanner frame.

    Parameters
    ----------
    ranges : (B,) float ndarray
        Range of each beam, metres; beam i points at ``angle_min + i * angle_increment``
        radians, counter-clockwise from the scanner's +x.
    range_min, range_max : float
        Valid range interval ``[range_min, range_max)``, metres: a return at
        ``range_max`` is the scanner's "no return" (the Stage simulator, for one,
        reports every beam that hits nothing at exactly ``range_max``).

    Returns
    -------
    points : (N, 3) float32 ndarray
        Valid returns (z = 0), metres.
    n_dropped : int
        Beams dropped: NaN, inf, below ``range_min``, at or beyond ``range_max``.
    """
    r = np.asarray(ranges, dtype=np.float64)
    angles = angle_min + angle_increment * np.arange(r.size)
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(r) & (r >= range_min) & (r < range_max)
    pts = np.zeros((int(ok.sum()), 3), dtype=np.float32)
    pts[:, 0] = r[ok] * np.cos(angles[ok])
    pts[:, 1] = r[ok] * np.sin(angles[ok])
    return pts, int(r.size - ok.sum())


def filter_points(
    points: np.ndarray, range_min: float | None = None, range_max: float | None = None
) -> tuple[np.ndarray, int]:
    """Drop non-finite points and points outside a range interval (distance from origin).

    The same rule as :func:`laser_scan_points`: a point is kept when its distance ``d``
    satisfies ``range_min <= d < range_max`` (each bound only when given).

    Parameters
    ----------
    points : (N, 3) float ndarray
        Points in the scanner frame, metres.
    range_min, range_max : float, optional
        Range interval ``[range_min, range_max)``, metres.

    Returns
    -------
    points : (M, 3) float32 ndarray
        ``points`` itself when it is float32 and every point is kept (no copy).
    n_dropped : int
        Points dropped: non-finite or outside the range interval.
    """
    p = np.asarray(points)
    if p.dtype != np.float32:  # float32 input (PointCloud2) is checked as it is: no copy
        p = p.astype(np.float64)
    p = p.reshape(-1, 3)
    ok = np.isfinite(p[:, 0]) & np.isfinite(p[:, 1]) & np.isfinite(p[:, 2])  # per column: cheaper than all(axis=1)
    if range_min is not None or range_max is not None:
        q = p.astype(np.float64)  # distances in float64, whatever the input
        with np.errstate(invalid="ignore"):
            d = np.sqrt(q[:, 0] ** 2 + q[:, 1] ** 2 + q[:, 2] ** 2)
        if range_min is not None:
            ok &= d >= range_min
        if range_max is not None:
            ok &= d < range_max
    n_ok = int(np.count_nonzero(ok))
    kept = p.astype(np.float32, copy=False) if n_ok == len(p) else p[ok].astype(np.float32, copy=False)
    return kept, len(p) - n_ok

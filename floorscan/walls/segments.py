"""Wall segments of a fitted line: total least squares, gaps, coverage, ends.

The two extractors (:mod:`floorscan.walls.ransac`, :mod:`floorscan.walls.cluster`)
turn a line found by RANSAC into wall segments with the same rules
(:func:`claimed_segments`): the points of the whole scan within ``threshold_m`` of
the line are sorted along it and split where they leave a gap wider than
``max_gap_m`` (a wall with a door is two segments); a piece is the line's when at
least ``min_inliers`` of its points are the line's RANSAC inliers; each such piece is
refit by total least squares (:func:`fit_line`), its ends are the extent of its
points along the refit line, and it is kept when at least ``min_length_m`` long and
covered by its points over ``min_coverage`` of its length (:func:`_uncovered_length`:
jumps, as between table legs, are uncovered). Parameters:
:class:`~floorscan.walls.params.RansacParams`. Thesis section 5.3.
"""

from __future__ import annotations

import math

import numpy as np

from floorscan.walls.params import RansacParams


def fit_line(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Total least squares line through 2D points (principal axis of their covariance).

    Parameters
    ----------
    points : (N, 2) float ndarray, N >= 2
        Points, metres.

    Returns
    -------
    centroid : (2,) float64 ndarray
        A point of the line (the points' mean), metres.
    direction : (2,) float64 ndarray
        Unit direction of the line; the normal is ``(-direction[1], direction[0])``.
    """
    c = np.add.reduce(points, axis=0) / len(points)  # points.mean(axis=0), fewer calls
    d = (points - c).T  # rows dx, dy
    prod = np.empty((3, len(points)))  # rows dx * dx, dy * dy, dx * dy
    np.multiply(d, d, out=prod[:2])
    np.multiply(d[0], d[1], out=prod[2])
    # one reduction along the rows: each row is summed as np.add.reduce sums it alone
    # (a test checks it)
    sxx, syy, sxy = np.add.reduce(prod, axis=1)
    phi = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)  # angle of the major axis
    return c, np.array([np.cos(phi), np.sin(phi)])


def claimed_segments(pts, c, direction, claimed, params) -> list[tuple]:
    """Segments of a line found by RANSAC, with ends from all points of the scan
    (thesis section 5.3).

    The points of the whole scan within ``threshold_m`` of the line are split at gaps
    wider than ``max_gap_m``; a piece is this line's when at least ``min_inliers`` of its
    points were ``claimed`` by it (its RANSAC inliers). Points near a corner, claimed by
    the other wall or left out of a cluster for their mixed normal, so still extend the
    segment to the corner.

    Parameters
    ----------
    pts : (N, 2) float64 ndarray
        All points of the scan, metres.
    c : (2,) float ndarray
        A point on the line (its inliers' centroid), metres.
    direction : (2,) float ndarray
        Unit direction of the line.
    claimed : (N,) bool ndarray
        The line's RANSAC inliers.
    params : RansacParams
        ``threshold_m``, ``max_gap_m``, ``min_inliers``, length and coverage tests.

    Returns
    -------
    list of tuple
        ``(x0, y0, x1, y1, n_inliers, rmse_m)`` per kept piece, metres, in order along
        ``direction``.
    """
    normal = np.array([-direction[1], direction[0]])
    cand = np.flatnonzero(np.abs((pts - c) @ normal) < params.threshold_m)
    return candidate_segments(pts, cand, direction, claimed, params)


def candidate_segments(pts, cand, direction, claimed, params) -> list[tuple]:
    """:func:`claimed_segments` of the points ``cand`` near the line (thesis section 5.3).

    Parameters
    ----------
    pts : (N, 2) float64 ndarray
        All points of the scan, metres.
    cand : (M,) int ndarray
        Ascending indices into ``pts`` of the points within ``threshold_m`` of the line.
    direction : (2,) float ndarray
        Unit direction of the line.
    claimed : (N,) bool ndarray
        The line's RANSAC inliers.
    params : RansacParams

    Returns
    -------
    list of tuple
        As :func:`claimed_segments`.
    """
    t = pts[cand] @ direction
    order = np.argsort(t, kind="stable")
    bounds = _piece_bounds(t[order], params.max_gap_m)
    cand = cand[order]
    rows = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        piece = cand[a:b]
        if b - a >= params.min_inliers and np.count_nonzero(claimed[piece]) >= params.min_inliers:
            row = _piece_segment(pts[piece], direction, params)
            if row is not None:
                rows.append(row)
    return rows


def _piece_bounds(ts: np.ndarray, max_gap: float) -> list[int]:
    """Start of each piece of sorted positions ``ts`` split at gaps wider than
    ``max_gap``, and the end: pieces are ``ts[b[i]:b[i+1]]`` (as ``numpy.split``)."""
    wide = (ts[1:] - ts[:-1]) > max_gap  # numpy.diff
    if not wide.any():  # one piece: the usual case
        return [0, len(ts)]
    return [0, *(np.flatnonzero(wide) + 1).tolist(), len(ts)]


def _uncovered_length(t: np.ndarray, min_gap: float) -> float:
    """Summed length of the jumps between sorted positions ``t`` (metres): gaps wider
    than ``min_gap`` and 3 times both neighbouring gaps (see ``RansacParams``)."""
    g = t[1:] - t[:-1]  # numpy.diff
    if len(g) == 0 or not (g > min_gap).any():  # no jump: the usual case
        return 0.0
    near = np.zeros(len(g))  # the larger neighbouring gap (0 beyond the ends)
    near[1:] = g[:-1]
    np.maximum(near[:-1], g[1:], out=near[:-1])
    jump = (g > min_gap) & (g > 3.0 * near)
    return float(g[jump].sum())


def _piece_segment(points: np.ndarray, direction: np.ndarray, params: RansacParams) -> tuple | None:
    """The wall segment of one piece of a line's inliers (no gap wider than
    ``max_gap_m``, :func:`claimed_segments`), or None.

    A piece with at least ``min_inliers`` points is refit by total least squares;
    its ends are the extent of its points along the refit line; it is kept when at
    least ``min_length_m`` long and covered by its inliers over ``min_coverage`` of
    its length. Returns (x0, y0, x1, y1, n_inliers, rmse_m).
    """
    if len(points) < max(params.min_inliers, 2):
        return None
    c, d = fit_line(points)
    if d @ direction < 0:
        d = -d
    pc = points - c
    u = pc @ d
    lo, hi = float(np.minimum.reduce(u)), float(np.maximum.reduce(u))
    if hi - lo < params.min_length_m:
        return None
    if params.min_coverage > 0:
        uncovered = _uncovered_length(np.sort(u), params.coverage_gap_m)
        if 1.0 - uncovered / (hi - lo) < params.min_coverage:
            return None
    resid = pc @ np.array([-d[1], d[0]])
    a, b = c + lo * d, c + hi * d
    rmse = math.sqrt(np.add.reduce(resid * resid) / len(resid))  # sqrt(mean(resid**2))
    return (a[0], a[1], b[0], b[1], len(points), rmse)

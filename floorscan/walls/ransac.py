"""Iterative RANSAC: the wall segments of one scan (thesis section 5.3, Algorithm 4).

:func:`ransac` repeats: the best of ``iterations`` lines through two random points
(most points closer than ``threshold_m``, :func:`_best_line`), refit by total least
squares on its inliers (:func:`_refine_line`), turned into wall segments
(:func:`floorscan.walls.segments.claimed_segments`), its inliers removed; until fewer
than ``min_points`` points remain, the best line has fewer than ``min_inliers``
inliers, or ``max_lines`` lines were found. It tends to find several candidates for
one wall (section 5.3). Fischler and Bolles (1981), Random sample consensus.

:func:`fit_wall` (one RANSAC line and its segments) is also the last step of
:func:`floorscan.walls.cluster.cluster_ransac`, once per cluster.

The inlier counts of all hypotheses are one BLAS product per cache-sized block
(:func:`_hypothesis_counts`): the same counts as ``abs(points @ normals.T - offsets)
< threshold`` (the tests check it bit for bit). On many points (the map of a large
site) each line is measured only on the tiles of points it passes near
(:func:`_tiled_counts`): the same counts, at a cost that grows with the site's size,
not with its square. Parameters:
:class:`~floorscan.walls.params.RansacParams`; randomness from
``numpy.random.default_rng(seed)``: the same seed, the same walls.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from floorscan.walls.params import RansacParams
from floorscan.walls.segments import claimed_segments, fit_line
from floorscan.walls.tables import segments_frame


def ransac(points: np.ndarray, params: RansacParams = RansacParams(), seed=0) -> pd.DataFrame:
    """Wall segments of one scan by iterative RANSAC (thesis section 5.3, Algorithm 4).

    Repeat: the best of ``iterations`` lines through two random points (most points
    closer than ``threshold_m``), refit by total least squares on its inliers
    (``refine_iterations`` times), split into segments (:func:`claimed_segments`),
    remove its inliers. The segment ends come from all points of the scan near the
    line (:func:`claimed_segments`), so a corner point claimed by the first of two
    walls still ends the second one. Stop when fewer than ``min_points`` points
    remain, the best line has fewer than ``min_inliers`` inliers, or ``max_lines``
    lines were found.
    Fischler and Bolles (1981), Random sample consensus.

    Parameters
    ----------
    points : (N, 2) float ndarray
        Wall points of one scan (map frame), metres. Not modified.
    params : RansacParams
    seed : int, sequence of int or numpy.random.Generator
        Seeds the generator (``numpy.random.default_rng(seed)``); same seed, same walls.

    Returns
    -------
    pandas.DataFrame
        One row per wall segment: ``x0, y0, x1, y1`` (metres), ``n_inliers`` (int32),
        ``rmse_m`` (RMS distance of its inliers to it, metres); in order of discovery.
    """
    return segments_frame(ransac_rows(points, params, seed))


def ransac_rows(points: np.ndarray, params: RansacParams, seed) -> list[tuple]:
    """:func:`ransac` as a list of rows, before they become a frame (thesis section 5.3,
    Algorithm 4).

    Parameters
    ----------
    points : (N, 2) float ndarray
        Wall points (map frame), metres. Not modified.
    params : RansacParams
    seed : int, sequence of int or numpy.random.Generator
        Seeds ``numpy.random.default_rng``; same seed, same rows.

    Returns
    -------
    list of tuple
        ``(x0, y0, x1, y1, n_inliers, rmse_m)`` per wall segment, metres, in order of
        discovery.
    """
    rng = np.random.default_rng(seed)
    all_pts = np.asarray(points, dtype=np.float64)
    alive = np.arange(len(all_pts))  # indices of the points not yet claimed by a line
    rows: list[tuple] = []
    n_lines = 0
    while len(alive) >= params.min_points and n_lines < params.max_lines:
        fit = fit_wall(all_pts, alive, rng, params)
        if fit is None:
            break
        mask, segments = fit
        rows += segments
        alive = alive[~mask]
        n_lines += 1
    return rows


def fit_wall(pts: np.ndarray, idx: np.ndarray, rng: np.random.Generator, params: RansacParams):
    """One RANSAC line on ``pts[idx]``: its inlier mask over ``idx`` and its wall segments
    (Fischler and Bolles 1981; thesis section 5.3).

    The segments' ends and gaps come from all of ``pts`` near the line (see
    :func:`claimed_segments`).

    Parameters
    ----------
    pts : (N, 2) float64 ndarray
        All points of the scan, metres.
    idx : (K,) int ndarray
        The indices into ``pts`` the line is fitted on.
    rng : numpy.random.Generator
        Draws the two-point hypotheses.
    params : RansacParams

    Returns
    -------
    tuple or None
        ``(mask, segments)``: ``mask`` (K,) bool, the line's inliers among ``idx``;
        ``segments`` a list of ``(x0, y0, x1, y1, n_inliers, rmse_m)`` tuples, metres.
        None when no line has at least ``params.min_inliers`` inliers.
    """
    found = _best_line(pts[idx], rng, params)
    if found is None:
        return None
    mask, c, direction = found
    if np.count_nonzero(mask) < params.min_inliers:
        return None
    claimed = np.zeros(len(pts), dtype=bool)
    claimed[idx[mask]] = True
    return mask, claimed_segments(pts, c, direction, claimed, params)


def _best_line(points: np.ndarray, rng: np.random.Generator, params: RansacParams):
    """One RANSAC run: the line with most inliers among ``iterations`` point pairs,
    refit by total least squares on its inliers. Returns (inlier mask, centroid,
    direction) or None when no hypothesis is possible.

    The hypotheses are built on contiguous coordinate columns, straight into the rows
    ``(nx, ny, -offset)`` of :func:`_hypothesis_counts`: the same floats as
    ``normals = (-dy, dx) / length`` and ``offsets = einsum("ij,ij->i", normals,
    start)`` (a sum of two products, rounded term by term; a test checks it)."""
    n = len(points)
    if n < 2:
        return None
    # integers(n) is integers(0, n) (the same draws), without the checks of low
    i = rng.integers(n, size=params.iterations)
    j = rng.integers(n - 1, size=params.iterations)
    j += j >= i  # j != i
    pt = np.empty((3, n))  # rows x, y, 1 (the columns of _hypothesis_counts)
    pt[:2] = points.T
    pt[2] = 1.0
    sx, sy = pt[0, i], pt[1, i]
    dx, dy = pt[0, j], pt[1, j]
    dx -= sx
    dy -= sy
    length = np.hypot(dx, dy)
    ok = length > 1e-9
    if not ok.all():
        if not ok.any():
            return None
        dx, dy, length, sx, sy = dx[ok], dy[ok], length[ok], sx[ok], sy[ok]
    hyp = np.empty((3, len(length)))  # rows nx = -dy / length, ny = dx / length, offset
    np.negative(dy, out=dy)
    np.divide(dy, length, out=hyp[0])
    np.divide(dx, length, out=hyp[1])
    np.multiply(hyp[0], sx, out=sx)
    np.multiply(hyp[1], sy, out=sy)
    np.add(sx, sy, out=hyp[2])  # the offsets
    if n >= TILED_MIN_POINTS:
        counts = _tiled_counts(points, pt, hyp.T, params.threshold_m)
    else:
        counts = _hypothesis_counts(pt, hyp.T, params.threshold_m, negate=True)
    best = int(np.argmax(counts))
    return _refine_line(points, hyp[:2, best].copy(), hyp[2, best], params)


#: Points of a RANSAC run from which :func:`_tiled_counts` counts the inliers by tiles:
#: below it one product over all points is as quick (a scan, a room's map).
TILED_MIN_POINTS = 20_000
#: Points per tile of :func:`_tiled_counts`, about: a tile's product is large enough
#: for BLAS, and a line crosses few of the tiles of a large map.
TILE_POINTS = 2048


def _tiled_counts(points: np.ndarray, pt: np.ndarray, hyp: np.ndarray, threshold: float) -> np.ndarray:
    """:func:`_hypothesis_counts` (``negate=True``) of many points, by square tiles of
    about :data:`TILE_POINTS` points: a hypothesis' line is measured only against the
    tiles it passes within ``threshold`` of (the distance from a tile's centre to the
    line, less the half diagonal of the tile's points, bounds the distance of each of
    its points; a relative margin of 1e-9 and 1e-9 m), so a run on the map of a large
    site measures each line against the few tiles it crosses, not the whole site.

    Each count is the same integer as :func:`_hypothesis_counts`': the same product
    (BLAS, ``(nx, ny, -offset)`` with ``(x, y, 1)``, a test checks it bit for bit) on
    the tile's columns, and the tiles it skips hold no inlier.

    Parameters
    ----------
    points : (N, 2) float64 ndarray
        Metres.
    pt : (3, N) float64 ndarray
        Rows x, y, 1 of ``points``.
    hyp : (H, 3) float ndarray
        ``(nx, ny, offset)`` per line.
    threshold : float
        Metres.

    Returns
    -------
    (H,) int64 ndarray
    """
    n = len(points)
    h3 = hyp * np.array([1.0, 1.0, -1.0])  # (nx, ny, -offset), C-ordered
    lo, hi = points.min(axis=0), points.max(axis=0)
    extent = np.maximum(hi - lo, 1e-9)
    # about n / TILE_POINTS tiles over the box, and no more along its longer side (the
    # points of one straight wall, whose box has no area)
    side = max(float(np.sqrt(np.prod(extent) * TILE_POINTS / n)), float(extent.max()) * TILE_POINTS / n, 1e-6)
    cell = np.floor((points - lo) / side).astype(np.int64)
    key = cell[:, 0] * (int(cell[:, 1].max()) + 1) + cell[:, 1]
    order = np.argsort(key, kind="stable")
    key = key[order]
    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
    stops = np.r_[starts[1:], n]
    ps = np.ascontiguousarray(pt[:, order])
    t_lo, t_hi = np.minimum.reduceat(ps[:2], starts, axis=1), np.maximum.reduceat(ps[:2], starts, axis=1)
    centre, radius = (t_lo + t_hi) / 2, np.hypot(*(t_hi - t_lo)) / 2  # (2, T), (T,)
    reach = np.abs(h3[:, :2] @ centre + h3[:, 2:])  # (H, T) distance of each tile's centre
    near = reach <= (radius + threshold) * (1 + 1e-9) + 1e-9
    counts = np.zeros(len(h3), dtype=np.int64)
    for t in np.flatnonzero(near.any(axis=0)):
        sel = np.flatnonzero(near[:, t])
        counts[sel] += _hypothesis_counts(ps[:, starts[t]:stops[t]], h3[sel], threshold)
    return counts


def _refine_line(points: np.ndarray, normal: np.ndarray, offset: float, params: RansacParams):
    """The inliers of the line ``points @ normal == offset`` refitted (least squares)
    to their own inliers up to ``params.refine_iterations`` times, until they no longer
    change: ``(mask, centre, direction)`` as :func:`_best_line` returns them."""
    mask = np.abs(points @ normal - offset) < params.threshold_m
    n_mask = np.count_nonzero(mask)
    c, direction = None, np.array([normal[1], -normal[0]])
    for _ in range(params.refine_iterations):
        if n_mask < 2:
            break
        c, direction = fit_line(points[mask])
        normal = np.array([-direction[1], direction[0]])
        new = np.abs((points - c) @ normal) < params.threshold_m
        n_new = np.count_nonzero(new)
        if n_new < 2 or (n_new == n_mask and (new == mask).all()):
            mask = new if n_new >= 2 else mask
            break
        mask, n_mask = new, n_new
    if c is None:  # no refit: the line through the inliers' mean
        c = points[mask].mean(axis=0)
    return mask, c, direction


def _inlier_counts(points: np.ndarray, normals: np.ndarray, offsets: np.ndarray, threshold: float) -> np.ndarray:
    """Points closer than ``threshold`` to each line ``normals[h] . p = offsets[h]``
    (:func:`_hypothesis_counts` of the points and hypotheses)."""
    n = len(points)
    pt = np.empty((3, n))
    pt[:2] = points.T
    pt[2] = 1.0
    hyp = np.empty((len(normals), 3))
    hyp[:, :2] = normals
    np.negative(offsets, out=hyp[:, 2])
    return _hypothesis_counts(pt, hyp, threshold)


def _hypothesis_counts(pt: np.ndarray, hyp: np.ndarray, threshold: float, negate: bool = False) -> np.ndarray:
    """Columns ``pt`` (3, N) = (x, y, 1) closer than ``threshold`` to each line ``hyp``
    (H, 3) = (nx, ny, -offset), or (nx, ny, offset) with ``negate`` (the offsets are
    negated in a copy; ``hyp`` is not modified).

    Hypotheses in blocks of about 64k distances (at least 4; the block stays in the CPU
    cache), laid out (hypothesis, point) so the count runs along contiguous memory,
    into reused buffers. The signed distance is one BLAS product of ``(nx, ny,
    -offset)`` with ``(x, y, 1)``: the kernel accumulates along the 3 terms in order
    with fused multiply-adds, so it rounds as ``points @ normals.T`` then ``- offsets``
    (the tests check it bit for bit), without a second pass over the block. The count
    sums the bytes of the boolean block (exact, and quicker than
    ``count_nonzero(axis=1)``).
    """
    n = pt.shape[1]
    if negate:
        hyp = hyp * np.array([1.0, 1.0, -1.0])  # a C-ordered copy, exact
    counts = np.empty(len(hyp), dtype=np.int64)
    block = max(4, 65536 // max(n, 1))
    dist = np.empty((min(block, len(hyp)), n))
    inlier = np.empty(dist.shape, dtype=bool)
    count_type = np.uint16 if n < 2**16 else np.int64
    for s in range(0, len(hyp), block):
        e = min(s + block, len(hyp))
        d, m = dist[: e - s], inlier[: e - s]
        np.matmul(hyp[s:e], pt, out=d)
        np.abs(d, out=d)
        np.less(d, threshold, out=m)
        counts[s:e] = m.view(np.uint8).sum(axis=1, dtype=count_type)
    return counts

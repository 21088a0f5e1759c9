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
(:func:`_hypothesis_counts`): the counts of ``abs(points @ normals.T - offsets) <
threshold`` but where a distance lies within a rounding step of the threshold (a test
checks the counts). On many points (the map of a large site, :data:`TILED_MIN_POINTS`)
the points are sorted once into square tiles (:class:`~floorscan.walls.tiles.Tiles`)
and each line, the hypotheses' counts (:func:`_tiled_counts`) as the refit and the
segments' ends (:func:`_tiled_rows`), is measured only on the tiles it passes near: the
same rows, at a cost that grows with the site's size, not with its square. Parameters:
:class:`~floorscan.walls.params.RansacParams`; randomness from
``numpy.random.default_rng(seed)``: the same seed, the same walls.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from floorscan.walls.params import RansacParams
from floorscan.walls.segments import candidate_segments, claimed_segments, fit_line
from floorscan.walls.tables import segments_frame
from floorscan.walls.tiles import Tiles


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
    if len(all_pts) >= TILED_MIN_POINTS:
        return _tiled_rows(all_pts, rng, params)
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
    hyp = _hypotheses(pt[0, i], pt[1, i], pt[0, j], pt[1, j])
    if hyp is None:
        return None
    if n >= TILED_MIN_POINTS:
        counts = _tiled_counts(Tiles(points, np.arange(n), TILE_POINTS), hyp.T, params.threshold_m)
    else:
        counts = _hypothesis_counts(pt, hyp.T, params.threshold_m, negate=True)
    best = int(np.argmax(counts))
    return _refine_line(points, hyp[:2, best].copy(), hyp[2, best], params)


def _hypotheses(sx: np.ndarray, sy: np.ndarray, dx: np.ndarray, dy: np.ndarray) -> np.ndarray | None:
    """The lines through the point pairs ``(sx, sy)``, ``(dx, dy)`` (metres, fresh
    contiguous (H,) arrays, overwritten), pairs closer than 1e-9 m dropped: rows
    ``(nx, ny, offset)`` of a (3, H') array, or None when every pair is dropped.

    ``normal = (-(dy - sy), dx - sx) / length``, ``offset = nx * sx + ny * sy`` (see
    :func:`_best_line`)."""
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
    return hyp


#: Points of a RANSAC run from which it measures its lines by tiles (:func:`_tiled_rows`,
#: :func:`_tiled_counts`): below it one product over all points is as quick (a scan, a
#: room's map).
TILED_MIN_POINTS = 20_000
#: Points per tile of :func:`_tiled_counts`, about: a tile's product is large enough
#: for BLAS, and a line crosses few of the tiles of a large map.
TILE_POINTS = 512
#: Distances of a block of :func:`_hypothesis_counts` on a tile, at most (its buffers).
_BLOCK = 4 * 65536


def _tiled_rows(pts: np.ndarray, rng: np.random.Generator, params: RansacParams) -> list[tuple]:
    """:func:`ransac_rows` of many points, each line measured only against the tiles
    of points it passes near (:class:`~floorscan.walls.tiles.Tiles`; thesis section
    5.3, Algorithm 4; Fischler and Bolles 1981).

    The same rows as the plain loop (:func:`fit_wall` on the points left), float for
    float: the same draws from the points left in the same order, the same counts
    (:func:`_tiled_counts`), and the refit and the segments (:func:`_refit`,
    :func:`~floorscan.walls.segments.candidate_segments`) computed by the same
    expressions on the points of the near tiles, in the same order, which hold every
    point within ``threshold_m`` of the line. The points left are tiled anew each time
    half of them are gone, so the tiles stay about :data:`TILE_POINTS` points.

    Parameters
    ----------
    pts : (N, 2) float64 ndarray
        Wall points (map frame), metres. Not modified.
    rng : numpy.random.Generator
    params : RansacParams

    Returns
    -------
    list of tuple
        As :func:`ransac_rows`.
    """
    thr = params.threshold_m
    alive = np.arange(len(pts))  # indices of the points not yet claimed by a line, ascending
    everyone = Tiles(pts, alive, TILE_POINTS)  # all points: the segments' ends
    tiles = everyone.copy()  # the points left: the counts and the refit
    xs, ys = np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1])
    dead = np.zeros(len(pts), dtype=bool)  # claimed by a line
    claimed = np.zeros(len(pts), dtype=bool)  # by the current line

    def inliers(normal, offset, c):  # ascending indices of the points left within thr
        if c is not None:
            offset = float(c @ normal)
        cand = tiles.near_ids(normal, offset, thr)
        q = pts[cand]
        dist = _row_products(q, normal) - offset if c is None else _row_products(q - c, normal)
        return np.sort(cand[np.abs(dist) < thr])

    rows: list[tuple] = []
    n_lines = 0
    while len(alive) >= params.min_points and n_lines < params.max_lines:
        n = len(alive)
        if n < 2:
            break
        i = rng.integers(n, size=params.iterations)  # as _best_line
        j = rng.integers(n - 1, size=params.iterations)
        j += j >= i
        i, j = alive[i], alive[j]
        hyp = _hypotheses(xs[i], ys[i], xs[j], ys[j])
        if hyp is None:
            break
        best = int(np.argmax(_tiled_counts(tiles, hyp.T, thr)))
        ids, c, direction = _refit(inliers, pts, hyp[:2, best].copy(), hyp[2, best], params)
        if len(ids) < params.min_inliers:
            break
        normal = np.array([-direction[1], direction[0]])
        cand = everyone.near_ids(normal, float(c @ normal), thr)
        cand = np.sort(cand[np.abs(_row_products(pts[cand] - c, normal)) < thr])  # claimed_segments' candidates
        claimed[ids] = True
        rows += candidate_segments(pts, cand, direction, claimed, params)
        claimed[ids] = False
        dead[ids] = True
        alive = np.delete(alive, np.searchsorted(alive, ids))
        if len(alive) < tiles.n_built / 2:
            if len(alive):
                tiles = Tiles(pts, alive, TILE_POINTS)
        else:
            tiles.remove(ids, dead)
        n_lines += 1
    return rows


def _tiled_counts(tiles: Tiles, hyp: np.ndarray, threshold: float) -> np.ndarray:
    """:func:`_hypothesis_counts` (``negate=True``) of the points of ``tiles``, each
    hypothesis' line measured only against the tiles it passes within ``threshold`` of
    (:meth:`~floorscan.walls.tiles.Tiles.near`): on the map of a large site, the few
    tiles it crosses, not the whole site.

    Each count is the same integer as :func:`_hypothesis_counts`': the same product
    (BLAS, ``(nx, ny, -offset)`` with ``(x, y, 1)``, a test checks the counts) on the
    tile's columns, and the tiles it skips hold no inlier.

    Parameters
    ----------
    tiles : Tiles
        The points, metres.
    hyp : (H, 3) float ndarray
        ``(nx, ny, offset)`` per line.
    threshold : float
        Metres.

    Returns
    -------
    (H,) int64 ndarray
    """
    h3 = hyp * np.array([1.0, 1.0, -1.0])  # (nx, ny, -offset), C-ordered
    near = tiles.near(hyp[:, :2], hyp[:, 2], threshold)  # (H, T)
    tile, sel = np.nonzero(near.T)  # by tile, then hypothesis
    bounds = [*np.flatnonzero(np.r_[True, tile[1:] != tile[:-1]]).tolist(), len(tile)] if len(tile) else [0]
    pairs, part = h3[sel], np.empty(len(sel), dtype=np.int64)  # a count per (tile, hypothesis)
    work = np.empty(_BLOCK), np.empty(_BLOCK, dtype=bool)
    for a, b in zip(bounds[:-1], bounds[1:]):
        part[a:b] = _hypothesis_counts(tiles.cols[tile[a]], pairs[a:b], threshold, work=work)
    return np.bincount(sel, weights=part, minlength=len(h3)).astype(np.int64)  # exact below 2**53


def _refine_line(points: np.ndarray, normal: np.ndarray, offset: float, params: RansacParams):
    """The inliers of the line ``points @ normal == offset`` refitted (least squares)
    to their own inliers up to ``params.refine_iterations`` times, until they no longer
    change: ``(mask, centre, direction)`` as :func:`_best_line` returns them
    (:func:`_refit` on all of ``points``)."""
    thr = params.threshold_m

    def inliers(normal, offset, c):
        dist = points @ normal - offset if c is None else (points - c) @ normal
        return np.flatnonzero(np.abs(dist) < thr)

    ids, c, direction = _refit(inliers, points, normal, offset, params)
    mask = np.zeros(len(points), dtype=bool)
    mask[ids] = True
    return mask, c, direction


def _refit(inliers, xy: np.ndarray, normal: np.ndarray, offset: float, params: RansacParams):
    """The inliers of the line ``normal . p = offset`` refitted by total least squares
    (:func:`~floorscan.walls.segments.fit_line`) to their own inliers up to
    ``params.refine_iterations`` times, until they no longer change (Fischler and
    Bolles 1981; thesis section 5.3).

    Parameters
    ----------
    inliers : callable
        ``inliers(normal, offset, c)``: ascending indices into ``xy`` of the points
        closer than ``threshold_m`` to the line, ``abs(xy @ normal - offset)`` when
        ``c`` is None, else ``abs((xy - c) @ normal)``, those expressions row by row.
    xy : (N, 2) float64 ndarray
        Metres.
    normal : (2,) float ndarray
    offset : float
        Metres.
    params : RansacParams

    Returns
    -------
    ids : (K,) int ndarray
        The final inliers, ascending indices into ``xy``.
    c : (2,) float64 ndarray
        A point of the line (the inliers' mean), metres.
    direction : (2,) float64 ndarray
        Unit direction of the line.
    """
    ids = inliers(normal, offset, None)
    c, direction = None, np.array([normal[1], -normal[0]])
    for _ in range(params.refine_iterations):
        if len(ids) < 2:
            break
        c, direction = fit_line(xy[ids])
        normal = np.array([-direction[1], direction[0]])
        new = inliers(normal, None, c)
        if len(new) < 2 or (len(new) == len(ids) and np.array_equal(new, ids)):
            ids = new if len(new) >= 2 else ids
            break
        ids = new
    if c is None:  # no refit: the line through the inliers' mean
        c = xy[ids].mean(axis=0)
    return ids, c, direction


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


def _hypothesis_counts(
    pt: np.ndarray, hyp: np.ndarray, threshold: float, negate: bool = False, work=None
) -> np.ndarray:
    """Columns ``pt`` (3, N) = (x, y, 1) closer than ``threshold`` to each line ``hyp``
    (H, 3) = (nx, ny, -offset), or (nx, ny, offset) with ``negate`` (the offsets are
    negated in a copy; ``hyp`` is not modified).

    Hypotheses in blocks of about 64k distances (at least 4; the block stays in the CPU
    cache), laid out (hypothesis, point) so the count runs along contiguous memory,
    into reused buffers (``work``: a float64 and a bool flat array of the caller's,
    used when large enough for a block). The signed distance is one BLAS product of
    ``(nx, ny, -offset)`` with ``(x, y, 1)``, without a second pass over the block; it
    rounds otherwise than ``points @ normals.T`` then ``- offsets`` for a few distances
    in a thousand (the kernel's fused multiply-adds), so a count may differ from theirs
    only where a distance lies within a rounding step of the threshold (a test checks
    the counts). The count sums the bytes of the boolean block (exact, and quicker than
    ``count_nonzero(axis=1)``).
    """
    n = pt.shape[1]
    if negate:
        hyp = hyp * np.array([1.0, 1.0, -1.0])  # a C-ordered copy, exact
    counts = np.empty(len(hyp), dtype=np.int64)
    block = max(4, 65536 // max(n, 1))
    size = min(block, len(hyp)) * n
    if work is None or len(work[0]) < size:
        work = np.empty(size), np.empty(size, dtype=bool)
    count_type = np.uint16 if n < 2**16 else np.int64
    for s in range(0, len(hyp), block):
        e = min(s + block, len(hyp))
        d, m = work[0][: (e - s) * n].reshape(e - s, n), work[1][: (e - s) * n].reshape(e - s, n)
        _product(hyp[s:e], pt, d)
        np.abs(d, out=d)
        np.less(d, threshold, out=m)
        counts[s:e] = np.add.reduce(m.view(np.uint8), axis=1, dtype=count_type)
    return counts


def _product(a: np.ndarray, b: np.ndarray, out: np.ndarray) -> None:
    """``a @ b`` (K, 3) by (3, N) into ``out`` (K, N) by BLAS's matrix product (dgemm),
    also for one row or one column (numpy hands those to its matrix-vector or dot
    product, which rounds otherwise; the row or column is doubled): each element the
    same float whatever the shapes and the other rows and columns."""
    k, n = out.shape
    if k > 1 and n > 1:
        np.matmul(a, b, out=out)
    else:
        out[...] = ((np.repeat(a, 2, axis=0) if k == 1 else a) @ (np.repeat(b, 2, axis=1) if n == 1 else b))[:k, :n]


def _row_products(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``q @ v`` of (M, 2) rows by BLAS's matrix-vector product (dgemv), also for one
    row (numpy hands it to its dot product, which rounds otherwise; the row is doubled):
    each row's float whatever the other rows."""
    return (np.repeat(q, 2, axis=0) @ v)[:1] if len(q) == 1 else q @ v

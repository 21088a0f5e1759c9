"""Correlative matching of two 2D point sets over rotation, scale and translation: the
start of a drawn plan's alignment (:func:`floorscan.score.drawn.align_drawn`).

:func:`correlative_search` scores every (scale, angle) of a grid: the source points,
rotated and scaled, are counted on square cells and cross-correlated with the target's
cells blurred by a Gaussian of one cell (SciPy's FFT, circular); a transform's score is
the correlation's peak and its translation the peak's shift. The best of the grid wins,
the first in grid order among equal scores.

Not every grid point is correlated at full resolution. A coarse raster, ``factor``
cells to a side per coarse cell, holds the largest blurred target value within reach of
each coarse cell (:func:`coarse_bound`); correlated with the source's coarse counts, it
bounds from above the fine correlation at every shift that the coarse shift stands for.
The grid points are then correlated at full resolution in decreasing order of their
bounds, until the next bound is below the best score found: the branch and bound of
multi-resolution correlative scan matching (Olson, "Real-time correlative scan
matching", ICRA 2009, section III-C; Hess et al., "Real-time loop closure in 2D LIDAR
SLAM", ICRA 2016, section V-C). The answer is the exhaustive search's: a grid point it
skips cannot score as high, and one it correlates is computed as the exhaustive search
computes it (the same floats).
"""

from __future__ import annotations

import math

import numpy as np

#: Bounds within this share of the source's point count of the best score are
#: correlated at full resolution: a margin over the FFTs' rounding (about 1e-15 of it).
BOUND_MARGIN = 1e-9


def coarse_bound(ref: np.ndarray, factor: int) -> np.ndarray:
    """The coarse raster that bounds the circular correlation with ``ref`` from above.

    Coarse cell ``Q`` holds the largest value of ``ref`` over the fine cells
    ``factor * Q + [0, w)`` (both axes, circular), ``w = 2 * factor - 1 + e`` with
    ``e = factor * m - n``: a point in coarse cell ``q`` and a fine shift in coarse
    shift ``D``'s block (``factor * D + [0, factor)``) land in that window of
    ``Q = (q + D) mod m``, also where ``m`` coarse cells overrun the ``n`` fine ones.

    Parameters
    ----------
    ref : (n, n) float ndarray
        The fine target raster.
    factor : int
        Fine cells to a coarse cell's side, >= 1.

    Returns
    -------
    (m, m) float64 ndarray
        ``m = ceil(n / factor)``.

    Raises
    ------
    ValueError
        When ``ref`` is not square or ``factor`` < 1.
    """
    from scipy import ndimage

    n = ref.shape[0]
    if ref.ndim != 2 or ref.shape[1] != n or factor < 1:
        raise ValueError(f"coarse_bound: a square raster and a factor >= 1, not {ref.shape} and {factor}")
    m = -(-n // factor)
    w = 2 * factor - 1 + (factor * m - n)
    window_max = ndimage.maximum_filter(np.asarray(ref, dtype=np.float64), size=w, mode="wrap", origin=-(w // 2))
    at = (factor * np.arange(m)) % n
    return window_max[np.ix_(at, at)]


def _counts(cells: np.ndarray, n: int) -> np.ndarray:
    """(n, n) float64 raster of how many of the (col, row) ``cells`` fall in each cell."""
    return np.bincount(cells[:, 1] * n + cells[:, 0], minlength=n * n).astype(np.float64).reshape(n, n)


def correlative_search(
    src: np.ndarray,
    dst: np.ndarray,
    scales,
    angles_rad,
    cell_m: float = 0.2,
    origin=None,
    size: int | None = None,
    factor: int = 2,
) -> tuple[float, float, np.ndarray, dict]:
    """The (scale, angle, shift) of the grid that puts the most of ``src`` on ``dst``.

    Parameters
    ----------
    src : (N, 2) float ndarray
        Source points, metres about their own centre.
    dst : (M, 2) float ndarray
        Target points, metres.
    scales : sequence of float
        Scales tried (metres per source unit).
    angles_rad : sequence of float
        Rotations tried, radians counter-clockwise; the grid is every scale with every
        angle, scales outermost.
    cell_m : float
        Cell side, metres.
    origin : (2,) float, optional
        The target raster's corner, metres (default: ``dst``'s minimum less 2 m).
    size : int, optional
        Cells to the raster's side (default: twice the larger extent of ``dst`` and the
        scaled ``src``, plus 8 m, to a fast FFT length).
    factor : int
        Fine cells to a coarse cell's side in the bound (1: every grid point is
        correlated at full resolution).

    Returns
    -------
    scale, angle : float
        The best grid point (angle in radians).
    shift : (2,) float64 ndarray
        Metres: the translation that puts ``src``'s origin on the target.
    info : dict
        ``n_grid`` grid points, ``n_fine`` of them correlated at full resolution,
        ``score`` the best correlation peak, ``size`` the raster's cells to a side.

    Raises
    ------
    ValueError
        When ``src`` or ``dst`` is empty, or a grid is empty.
    """
    from scipy import fft, ndimage

    src, dst = np.asarray(src, dtype=np.float64), np.asarray(dst, dtype=np.float64)
    grid = [(float(s), float(a)) for s in scales for a in angles_rad]
    if not len(src) or not len(dst) or not grid:
        raise ValueError("correlative_search: no source point, no target point or an empty grid")
    lo = dst.min(axis=0) - 2.0 if origin is None else np.asarray(origin, dtype=np.float64)
    if size is None:
        extent = max(np.ptp(dst, axis=0).max(), np.ptp(src, axis=0).max() * max(s for s, _ in grid)) + 8.0
        size = int(fft.next_fast_len(int(math.ceil(2 * extent / cell_m))))
    n = int(size)
    ref = np.zeros((n, n))
    ij = np.floor((dst - lo) / cell_m).astype(np.int64)
    ij = ij[(ij >= 0).all(axis=1) & (ij < n).all(axis=1)]
    ref[ij[:, 1], ij[:, 0]] = 1.0
    ref = ndimage.gaussian_filter(ref, 1.0)
    ref_f = fft.rfft2(ref)

    def cells(scale, a):
        c, s = math.cos(a), math.sin(a)
        return np.floor(scale * (src @ np.array([[c, s], [-s, c]])) / cell_m).astype(np.int64) % n

    if factor > 1:
        bound = coarse_bound(ref, factor)
        m = len(bound)
        bound_f = fft.rfft2(bound)
        bounds = np.array([
            fft.irfft2(bound_f * np.conj(fft.rfft2(_counts(cells(s, a) // factor, m))), s=(m, m)).max()
            for s, a in grid
        ])  # fmt: skip
    else:
        bounds = np.full(len(grid), np.inf)
    margin = BOUND_MARGIN * len(src)
    best, n_fine = (-np.inf, -1, 0), 0
    for i in np.argsort(-bounds, kind="stable"):
        if bounds[i] + margin < best[0]:
            break
        corr = fft.irfft2(ref_f * np.conj(fft.rfft2(_counts(cells(*grid[i]), n))), s=(n, n))
        n_fine += 1
        peak = int(np.argmax(corr))
        score = corr.flat[peak]
        if score > best[0] or (score == best[0] and i < best[1]):
            best = (score, int(i), peak)
    score, i, peak = best
    dy, dx = divmod(peak, n)
    info = {"n_grid": len(grid), "n_fine": n_fine, "score": float(score), "size": n}
    return grid[i][0], grid[i][1], np.array([dx, dy], dtype=np.float64) * cell_m + lo, info

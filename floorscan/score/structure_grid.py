"""The reference map's structure cells searched through the grid they lie on.

The structure cells' centres (:class:`floorscan.score.against_reference.Structure`)
lie on the lattice of the occupancy grid, so the cells near a point or a segment are
found from its rows and columns rather than by a KD-tree:

- the nearest cell of a point: the 2 x 2 cells around it, then rings of cells around
  those (a cell outside the 2k x 2k block around a point lies at least k cells from
  it). A point whose nearest cell is not settled by the rings is left to the KD-tree;
- the cells near a segment: on each row (or column) of the grid that crosses the
  segment grown by the distance, the run of cells the segment's grown span covers.
  The structure cells of a run are a slice of the cells sorted by row (or column).

The distances are those of :class:`scipy.spatial.cKDTree`: the same cell centres
(:meth:`floorscan.core.occupancy.OccupancyGrid.cell_centres`), the same sums of squares
(``dx * dx + dy * dy``, then the square root), so the results are the same floats, and
the same cells within a distance (:func:`nearest_sample_d2`).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from floorscan.core.grid import ranks_in_runs
from floorscan.core.occupancy import OccupancyGrid

#: Rings of cells around a point's 2 x 2 cells that :meth:`StructureGrid.nearest`
#: searches before the KD-tree: its nearest cell within ``RINGS`` cells is settled on
#: the grid.
RINGS = 3
#: Points per chunk of :meth:`StructureGrid.nearest` and :func:`nearest_sample_d2`
#: (bounds their temporaries, about 200 bytes a point).
NEAREST_CHUNK = 1 << 20


class StructureGrid:
    """The structure cells of an occupancy grid, indexed by the grid's rows and columns.

    Parameters
    ----------
    grid : OccupancyGrid
    mask : (H, W) bool ndarray
        The structure cells (``grid.structure()``); their centres, in row-major order,
        are the points of ``tree``.
    tree : scipy.spatial.cKDTree
        Of those centres: :meth:`nearest` asks it for the points the rings leave.
    """

    def __init__(self, grid: OccupancyGrid, mask: np.ndarray, tree: cKDTree):
        self.tree = tree
        self.shape = mask.shape
        self.resolution_m = grid.resolution_m
        self.origin_xy = grid.origin_xy
        height, width = self.shape
        pad = RINGS
        # the centre coordinates of the columns and rows -pad .. width + pad, as cell_centres computes them
        self._x = (np.arange(-pad, width + pad + 1) + 0.5) * grid.resolution_m + grid.origin_xy[0]
        self._y = (np.arange(-pad, height + pad + 1) + 0.5) * grid.resolution_m + grid.origin_xy[1]
        # bit 0: the cell is structure; bits 1, 2, 3: the cell to its right, above, above right
        blocks = np.zeros((height + 2 * pad + 1, width + 2 * pad + 1), dtype=np.uint8)
        blocks[pad : pad + height, pad : pad + width] = mask
        blocks[:, :-1] |= (blocks[:, 1:] & 1) << 1
        blocks[:-1, :] |= (blocks[1:, :] & 1) << 2
        blocks[:-1, :-1] |= (blocks[1:, 1:] & 1) << 3
        self._blocks = blocks
        rows, cols = np.nonzero(mask)
        self._row_keys = rows * width + cols  # sorted: the cells' order
        col_keys = cols * height + rows
        self._col_order = np.argsort(col_keys, kind="stable")
        self._col_keys = col_keys[self._col_order]

    def nearest(self, points: np.ndarray, bound: float) -> np.ndarray:
        """Distance from each point to the nearest structure cell centre:
        ``tree.query(points, k=1, distance_upper_bound=bound)[0]``, the same floats.

        Parameters
        ----------
        points : (N, 2) float64 ndarray
            Metres.
        bound : float
            Metres: points whose nearest cell is not nearer are at inf.

        Returns
        -------
        (N,) float64 ndarray
            Metres.
        """
        points = np.asarray(points, dtype=np.float64).reshape(-1, 2)
        out = np.empty(len(points))
        for start in range(0, len(points), NEAREST_CHUNK):
            out[start : start + NEAREST_CHUNK] = self._nearest(points[start : start + NEAREST_CHUNK], bound)
        return out

    def _nearest(self, points: np.ndarray, bound: float) -> np.ndarray:
        height, width = self.shape
        pad, r = RINGS, self.resolution_m
        x, y = points[:, 0], points[:, 1]
        # the cell whose centre is at or below-left of the point: the 2 x 2 block from it surrounds the point
        col = np.floor((x - self.origin_xy[0]) / r - 0.5)
        row = np.floor((y - self.origin_xy[1]) / r - 0.5)
        todo = np.flatnonzero((col >= -1) & (col <= width - 1) & (row >= -1) & (row <= height - 1))  # not NaN
        col, row = col[todo].astype(np.int64) + pad, row[todo].astype(np.int64) + pad
        x, y = x[todo], y[todo]
        blocks = self._blocks.reshape(-1)
        stride = self._blocks.shape[1]
        block = blocks[row * stride + col]
        dx0, dx1, dy0, dy1 = x - self._x[col], x - self._x[col + 1], y - self._y[row], y - self._y[row + 1]
        dx0 *= dx0
        dx1 *= dx1
        dy0 *= dy0
        dy1 *= dy1
        best = np.where(block & 1, dx0 + dy0, np.inf)
        np.minimum(best, np.where(block & 2, dx1 + dy0, np.inf), out=best)
        np.minimum(best, np.where(block & 4, dx0 + dy1, np.inf), out=best)
        np.minimum(best, np.where(block & 8, dx1 + dy1, np.inf), out=best)
        d2 = np.full(len(points), np.inf)
        for k in range(1, RINGS + 1):
            if k > 1:
                for di, dj in _ring(k):
                    near = np.flatnonzero(blocks[(row + di) * stride + (col + dj)] & 1)
                    dx, dy = x[near] - self._x[col[near] + dj], y[near] - self._y[row[near] + di]
                    best[near] = np.minimum(best[near], dx * dx + dy * dy)
            # every cell beyond the block lies at least k cells away (less a margin for rounding)
            settled = best < (min(k * r, bound) * (1 - 1e-6)) ** 2
            d2[todo[settled]] = best[settled]
            left = ~settled
            todo, row, col, x, y, best = todo[left], row[left], col[left], x[left], y[left], best[left]
            if len(todo) == 0:
                break
        out = np.sqrt(d2)
        left = np.flatnonzero(d2 == np.inf)  # off the grid, or not settled by the rings
        if len(left):
            out[left] = self.tree.query(points[left], k=1, distance_upper_bound=bound)[0]
        return out

    def segment_cells(self, seg: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
        """The structure cells whose centres may lie within ``reach`` of each segment:
        all those that do (and a micrometre more), and none beyond ``sqrt(2) reach``.

        Parameters
        ----------
        seg : (F, 4) float64 ndarray
            ``x0, y0, x1, y1``, metres.
        reach : float
            Metres.

        Returns
        -------
        cell, face : (P,) int64 ndarray
            Indices into the structure cells (row-major order) and into ``seg``: by
            segment, and by cell within a segment.
        """
        height, width = self.shape
        r, reach = self.resolution_m, reach * (1 + 1e-6) + 1e-6
        dx, dy = seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]
        by_rows = np.abs(dx) >= np.abs(dy)  # else by columns
        # across the lines (rows: y) v, along them u
        au, av = np.where(by_rows, seg[:, 0], seg[:, 1]), np.where(by_rows, seg[:, 1], seg[:, 0])
        du, dv = np.where(by_rows, dx, dy), np.where(by_rows, dy, dx)
        ou = np.where(by_rows, self.origin_xy[0], self.origin_xy[1])
        ov = np.where(by_rows, self.origin_xy[1], self.origin_xy[0])
        n_lines, n_along = np.where(by_rows, height, width), np.where(by_rows, width, height)
        first = np.clip(np.ceil((np.minimum(av, av + dv) - reach - ov) / r - 0.5), 0, n_lines)
        last = np.clip(np.floor((np.maximum(av, av + dv) + reach - ov) / r - 0.5), -1, n_lines - 1)
        count = np.where((last >= first) & np.isfinite(seg).all(axis=1), last - first + 1, 0).astype(np.int64)
        face = np.repeat(np.arange(len(seg)), count)
        line = np.repeat(first[count > 0].astype(np.int64), count[count > 0])
        line += ranks_in_runs(count)
        # the segment's points within reach of the line, grown by reach along it
        v = (line + 0.5) * r + ov[face]
        au, av, du, dv, ou = au[face], av[face], du[face], dv[face], ou[face]
        with np.errstate(divide="ignore", invalid="ignore"):
            t0, t1 = (v - reach - av) / dv, (v + reach - av) / dv
        along = dv == 0
        t0, t1 = np.clip(np.minimum(t0, t1), 0, 1), np.clip(np.maximum(t0, t1), 0, 1)
        t0[along], t1[along] = 0.0, 1.0
        u0, u1 = au + t0 * du, au + t1 * du
        lo = np.clip(np.ceil((np.minimum(u0, u1) - reach - ou) / r - 0.5), 0, n_along[face]).astype(np.int64)
        hi = np.clip(np.floor((np.maximum(u0, u1) + reach - ou) / r - 0.5), -1, n_along[face] - 1).astype(np.int64)
        lo, hi = line * n_along[face] + lo, line * n_along[face] + hi
        rows = by_rows[face]
        start, stop = np.empty(len(line), dtype=np.int64), np.empty(len(line), dtype=np.int64)
        for keys, on in ((self._row_keys, rows), (self._col_keys, ~rows)):
            start[on], stop[on] = np.searchsorted(keys, lo[on], "left"), np.searchsorted(keys, hi[on], "right")
        n = np.maximum(stop - start, 0)
        cell = np.repeat(start, n) + ranks_in_runs(n)
        face, on_columns = np.repeat(face, n), np.repeat(~rows, n)
        cell[on_columns] = self._col_order[cell[on_columns]]
        if on_columns.any():  # a column's cells come row by row
            order = np.argsort(face * max(len(self._row_keys), 1) + cell, kind="stable")
            cell, face = cell[order], face[order]
        return cell, face


def _ring(k: int) -> list[tuple[int, int]]:
    """(row, column) offsets of the cells of the 2k x 2k block around a point's cell
    (rows and columns ``-k + 1 .. k``) not in the block of ``k - 1``."""
    span = range(-k + 1, k + 1)
    return [(i, j) for i in span for j in span if not (-k + 2 <= i <= k - 1 and -k + 2 <= j <= k - 1)]


def nearest_sample_d2(
    px: np.ndarray, py: np.ndarray, face: np.ndarray, seg: np.ndarray, samples: np.ndarray, starts: np.ndarray
) -> np.ndarray:
    """Squared distance from each point to the nearest sample of its segment.

    ``samples`` are :func:`floorscan.core.geometry.sample_segments` of ``seg``, segment
    ``f``'s from ``starts[f]`` to ``starts[f + 1]``. They are equally spaced along the
    segment, so a point's nearest sample is one of the two around its projection on
    the segment: the four around it are measured, each as a KD-tree measures it
    (point minus sample, squares summed).

    Parameters
    ----------
    px, py : (P,) float64 ndarray
        Metres.
    face : (P,) int ndarray
        Each point's segment, an index into ``seg``.
    seg : (F, 4) float64 ndarray
        ``x0, y0, x1, y1``, metres.
    samples : (N, 2) float64 ndarray
        Metres.
    starts : (F + 1,) int ndarray

    Returns
    -------
    (P,) float64 ndarray
        Square metres.
    """
    ax, ay = seg[:, 0], seg[:, 1]
    abx, aby = seg[:, 2] - ax, seg[:, 3] - ay
    length2 = abx * abx + aby * aby
    out = np.empty(len(px))
    for start in range(0, len(px), NEAREST_CHUNK):  # temporaries of a chunk, reused
        part = slice(start, start + NEAREST_CHUNK)
        f = face[part]
        out[part] = _nearest_sample_d2(px[part], py[part], ax[f], ay[f], abx[f], aby[f], length2[f],
                                       starts[f], starts[f + 1] - 1, samples)
    return out


def _nearest_sample_d2(px, py, ax, ay, abx, aby, length2, first, last, samples):
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(length2 > 0, ((px - ax) * abx + (py - ay) * aby) / length2, 0.0)
    i0 = first + np.floor(np.clip(t, 0.0, 1.0) * (last - first)).astype(np.int64)
    sx, sy = samples[:, 0], samples[:, 1]
    d2 = np.full(len(px), np.inf)
    for offset in (-1, 0, 1, 2):
        i = np.minimum(np.maximum(i0 + offset, first), last)
        dx, dy = px - sx[i], py - sy[i]
        np.minimum(d2, dx * dx + dy * dy, out=d2)
    return d2

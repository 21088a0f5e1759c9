"""Square tiles of many points: the points a line passes near, without measuring the others.

:class:`Tiles` sorts points (a subset of an array, by index) into square tiles of
about ``size`` points each and keeps, per tile, the box of its points. A line ``n . p
= offset`` passes within ``threshold`` of a point of a tile only when its distance
from the centre of the tile's box is at most ``threshold`` plus the box's half
diagonal (the triangle inequality; :meth:`Tiles.near`, with margins for rounding), so
the points within ``threshold`` of a line are among those of the tiles
:meth:`Tiles.near` keeps: on the map of a large site, the few tiles a line crosses,
not the whole site. Points leave their tile (:meth:`Tiles.remove`, a RANSAC line's
inliers) and its box shrinks to the points left.

Used by the iterative RANSAC of many points (:mod:`floorscan.walls.ransac`; thesis
section 5.3; Fischler and Bolles 1981), which measures each line against its near
tiles only.
"""

from __future__ import annotations

import numpy as np


class Tiles:
    """The points ``xy[ids]`` in square tiles of about ``size`` points.

    The tiles are the cells of a square grid over the box of the points, of a side
    that puts ``size`` points in a cell on average, and no longer than ``size``
    points' share of the box's longer side (the points of one straight wall, whose
    box has no area).

    Parameters
    ----------
    xy : (N, 2) float64 ndarray
        All points, metres. Not modified; kept by reference.
    ids : (K,) int ndarray, K >= 1
        Ascending indices into ``xy`` of the points to tile.
    size : int
        Points per tile, about.

    Attributes
    ----------
    ids : list of (n_t,) int64 ndarray
        Per tile, the ascending indices into ``xy`` of its points.
    cols : list of (3, n_t) float64 ndarray
        Per tile, rows x, y, 1 of its points (metres), in the order of ``ids``.
    tile : (N,) int64 ndarray
        The tile of each point of ``ids`` (0 elsewhere).
    centre : (2, T) float64 ndarray
        Centre of each tile's box, metres.
    radius : (T,) float64 ndarray
        Half diagonal of each tile's box, metres; ``-inf`` for a tile left empty.
    n_built : int
        Points tiled at construction (K).
    """

    def __init__(self, xy: np.ndarray, ids: np.ndarray, size: int):
        pts = xy[ids]
        n = len(ids)
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        extent = np.maximum(hi - lo, 1e-9)
        side = max(float(np.sqrt(np.prod(extent) * size / n)), float(extent.max()) * size / n, 1e-6)
        cell = np.floor((pts - lo) / side).astype(np.int64)
        key = cell[:, 0] * (int(cell[:, 1].max()) + 1) + cell[:, 1]
        order = np.argsort(key, kind="stable")  # ascending indices within a tile
        key = key[order]
        starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
        stops = np.r_[starts[1:], n]
        cols = np.empty((3, n))
        cols[:2] = pts[order].T
        cols[2] = 1.0
        sorted_ids = np.asarray(ids, dtype=np.int64)[order]
        self.ids = [sorted_ids[s:e] for s, e in zip(starts.tolist(), stops.tolist())]
        self.cols = [cols[:, s:e] for s, e in zip(starts.tolist(), stops.tolist())]
        self.tile = np.zeros(len(xy), dtype=np.int64)  # the tile of each tiled point
        self.tile[sorted_ids] = np.repeat(np.arange(len(starts)), stops - starts)
        self.n_built = n
        # margin for the rounding of a distance: far above a few ulps of the coordinates
        self._slack = 1e-9 + 1e-12 * float(np.abs(pts).max())
        t_lo, t_hi = np.minimum.reduceat(cols[:2], starts, axis=1), np.maximum.reduceat(cols[:2], starts, axis=1)
        self.centre, self.radius = (t_lo + t_hi) / 2, np.hypot(*(t_hi - t_lo)) / 2  # (2, T), (T,)

    def copy(self) -> "Tiles":
        """The same tiles, to take points out of (:meth:`remove`) apart from these: the
        per-tile arrays are shared (:meth:`remove` replaces them, never writes into
        them), the lists and boxes copied."""
        out = object.__new__(Tiles)
        out.__dict__.update(self.__dict__)
        out.ids, out.cols = list(self.ids), list(self.cols)
        out.centre, out.radius = self.centre.copy(), self.radius.copy()
        return out

    def near(self, normals: np.ndarray, offsets: np.ndarray, threshold: float) -> np.ndarray:
        """Which tiles each line ``normals[h] . p = offsets[h]`` may pass within
        ``threshold`` of a point of: the distance from the tile's centre, less its half
        diagonal, is at most ``threshold`` (relative margin 1e-9, and 1e-9 m plus 1e-12
        of the largest coordinate for the rounding). Empty tiles are near no line.

        Parameters
        ----------
        normals : (H, 2) float ndarray
            Unit normals.
        offsets : (H,) float ndarray
            Metres.
        threshold : float
            Metres.

        Returns
        -------
        (H, T) bool ndarray
        """
        reach = np.abs(normals @ self.centre - offsets[:, None])
        return reach <= (self.radius + threshold) * (1 + 1e-9) + self._slack

    def near_ids(self, normal: np.ndarray, offset: float, threshold: float) -> np.ndarray:
        """Indices into ``xy`` of the points of the tiles near the line
        ``normal . p = offset`` (:meth:`near`): every point within ``threshold`` of it,
        and others; ascending within a tile, tile after tile.

        Parameters
        ----------
        normal : (2,) float ndarray
            Unit normal.
        offset : float
            Metres.
        threshold : float
            Metres.

        Returns
        -------
        (M,) int64 ndarray
        """
        sel = np.flatnonzero(self.near(normal[None], np.array([offset]), threshold)[0])
        return np.concatenate([self.ids[t] for t in sel.tolist()]) if len(sel) else np.empty(0, dtype=np.int64)

    def remove(self, gone: np.ndarray, dead: np.ndarray) -> None:
        """Take the points ``gone`` out of their tiles; each tile that loses points
        gets the box of those left (none: near no line).

        Parameters
        ----------
        gone : (G,) int ndarray
            Indices into ``xy`` of tiled points.
        dead : (N,) bool ndarray
            True at ``gone`` (and at any point no longer tiled): the caller's mask,
            read only.
        """
        for t in np.unique(self.tile[gone]).tolist():
            keep = ~dead[self.ids[t]]
            self.ids[t] = self.ids[t][keep]
            self.cols[t] = cols = self.cols[t][:, keep]
            if cols.shape[1]:
                lo, hi = cols[:2].min(axis=1), cols[:2].max(axis=1)
                self.centre[:, t], self.radius[t] = (lo + hi) / 2, np.hypot(*(hi - lo)) / 2
            else:
                self.centre[:, t], self.radius[t] = 0.0, -np.inf

"""Coverage on a raster: scans' coverage polygons as sets of grid cells (thesis section
3.3, the area measure of Algorithm 1).

Areas are counted on a raster of square cells of ``raster_m`` (default 5 cm) anchored
at the map origin: a scan covers the cells whose centre lies in its coverage polygon
(Shapely geometry rasterised once, vectorised over all scans), the union ``U`` of the
chosen scans is a boolean grid, and a gain is the number of the scan's cells not yet
in ``U`` times ``raster_m**2``.

Memory follows the scans and the cells they touch, not the site's bounding box: a scan
is held as runs (the cells of one row within one tile of :data:`TILE` x :data:`TILE`
cells: about the scan's perimeter, not its area), and ``U`` only in the tiles some scan
touches, with prefix sums along each tile row so that a gain is a sum over the scan's
runs (a tiled raster; the same idea as run-length scan conversion, Foley et al.,
Computer Graphics, section 3.6).

Why not exact polygon overlays: hulls of neighbouring scans share nearly collinear wall
edges, which make each GEOS difference against the growing union slow, and a greedy
over thousands of scans needs ~10^5 of them; on the raster an evaluation is a gather
over the scan's runs and, gains being integers, comparisons are exact, with no float
tie tolerance. The raster area differs from the polygon area by at most about half a
cell along the boundary; :func:`floorscan.select.greedy.greedy_exact` (literal
Algorithm 1 on Shapely unions) checks that the raster greedy picks the same scans
(tests).

Usage::

    ids, raster = raster_for(scan_ids, geometries, raster_m)
    gain = raster.gain(j)          # cells scan j (a position) would add to U
    raster.add(j)                  # add them
    table = ordering_table(ids, order, gains, raster_m**2)

The rasteriser orders a row's crossings by a stable sort of (scan, row) and a swap per
pair instead of a three-key ``lexsort`` (:func:`_order_crossings`), exactly.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import pandas as pd
import shapely

from floorscan.core.grid import ranks_in_runs, unique_ints

#: Side of a raster tile, cells: the union ``U`` is kept only in the tiles some scan
#: touches (a tile of 128 cells is 6.4 m at the default 5 cm), and a run of a scan's
#: cells never crosses a tile's edge. A wider tile makes fewer runs of a large scan and
#: a longer row to sum again when a scan is added.
TILE = 128


class RasterCoverage:
    """Coverage geometries as sets of raster cells, and the union ``U`` of chosen ones.

    Parameters
    ----------
    geometries : (S,) object ndarray of Shapely Polygon / MultiPolygon
        Valid coverage of each scan (map frame, metres), e.g. from
        :func:`floorscan.select.hulls.scan_coverage`; empty allowed. Not modified.
    raster_m : float
        Cell side, metres. The grid is anchored at multiples of ``raster_m`` in the map
        frame, so a scan's cells do not depend on the other scans.
    chunk : int
        Scans rasterised at once.

    Attributes
    ----------
    counts : (S,) int64 ndarray
        Cells of each scan.
    tiles : (N,) int64 ndarray
        The tiles some scan touches, as ``tile_row * _tiles_per_row + tile_col`` on
        the grid of :data:`TILE` x :data:`TILE` cells anchored at ``(x0, y0)``,
        ascending; a tile's slot is its position here.
    covered : (N * TILE, TILE) bool ndarray
        The union ``U``: row ``slot * TILE + r`` is row ``r`` of the slot's tile.

    Notes
    -----
    A cell belongs to a geometry when its centre is inside (scanline fill with the
    even-odd rule over all rings, half-open in y and x, vectorised over all scans).
    A scan is held as runs, the cells of one raster row within one tile, not as cells,
    and the union only in the tiles the scans touch; its row prefix sums make a gain a
    sum over the scan's runs. Memory: 8 bytes per run (16 while rasterising) and 3
    bytes per cell of a touched tile, whatever the site's bounding box. Areas are
    integer cell counts, so gains compare exactly: no float ties. Cell numbers
    (:meth:`cells_of`) are ``covered.ravel()`` positions.
    """

    def __init__(self, geometries: Sequence, raster_m: float = 0.05, chunk: int = 128):
        geoms = np.asarray(geometries, dtype=object)
        if geoms.ndim != 1:
            raise ValueError("geometries must be 1-D")
        self.n = len(geoms)
        self.raster_m = r = float(raster_m)
        nonempty = ~shapely.is_empty(geoms) if self.n else np.zeros(0, bool)
        if nonempty.any():
            b = shapely.bounds(geoms[nonempty])
            self.x0 = np.floor(b[:, 0].min() / r) * r
            self.y0 = np.floor(b[:, 1].min() / r) * r
            nx = int(np.ceil((b[:, 2].max() - self.x0) / r)) + 1
        else:
            self.x0 = self.y0 = 0.0
            nx = 1
        self._tiles_per_row = nx // TILE + 2
        # a scan as runs (tile, row in the tile, first column in the tile, length), in
        # scan order, kept in small dtypes chunk by chunk; the tiles get their slots
        # (their rows of `covered`) once every chunk is known
        key, row, col, length = [], [], [], []
        runs_per_scan = np.zeros(self.n, dtype=np.int64)
        self.counts = np.zeros(self.n, dtype=np.int64)
        for a in range(0, self.n, chunk):
            k, rw, c, ln, own, cnt = self._rasterize(geoms[a : a + chunk])
            key.append(k)
            row.append((rw % TILE).astype(np.int16))
            col.append((c % TILE).astype(np.int16))
            length.append(ln.astype(np.int16))
            runs_per_scan[a : a + chunk] = np.bincount(own, minlength=len(cnt))
            self.counts[a : a + chunk] = cnt
        self.tiles = unique_ints(np.concatenate([unique_ints(k) for k in key] or [np.zeros(0, np.int64)]))
        dtype = np.int32 if len(self.tiles) * TILE < 2**31 else np.int64
        for i, k in enumerate(key):
            row[i] = np.searchsorted(self.tiles, k).astype(dtype) * TILE + row[i]
            key[i] = None
        # the run's row of `covered`, its first column there and its length
        self.run_row = np.concatenate(row) if row else np.zeros(0, dtype)
        self.run_col = np.concatenate(col) if col else np.zeros(0, np.int16)
        self.run_len = np.concatenate(length) if length else np.zeros(0, np.int16)
        self.run_stop = np.cumsum(runs_per_scan)
        self.run_start = self.run_stop - runs_per_scan
        self.covered = np.zeros((len(self.tiles) * TILE, TILE), dtype=bool)
        self._prefix = np.zeros((len(self.tiles) * TILE, TILE + 1), dtype=np.int16)

    def _rasterize(self, geoms: np.ndarray) -> tuple[np.ndarray, ...]:
        """The runs of ``geoms``: tile key, row, first column, length and scan (a position
        in ``geoms``) of each, by scan; and the cells of each scan."""
        r, n = self.raster_m, len(geoms)
        empty = np.zeros(0, np.int64)
        parts, owner = shapely.get_parts(geoms, return_index=True)
        poly = shapely.get_type_id(parts) == 3  # Polygon parts; points/lines have no area
        parts, owner = parts[poly], owner[poly]
        if len(parts) == 0:
            return empty, empty, empty, empty, empty, np.zeros(n, np.int64)
        rings, part_idx = shapely.get_rings(parts, return_index=True)
        xy, ring_idx = shapely.get_coordinates(rings, return_index=True)
        same = ring_idx[:-1] == ring_idx[1:]
        e0, e1 = xy[:-1][same], xy[1:][same]
        e_owner = owner[part_idx[ring_idx[:-1][same]]]
        # rows whose centre y0 + (k + 0.5) r lies in [min(ya, yb), max(ya, yb))
        ya = (e0[:, 1] - self.y0) / r - 0.5
        yb = (e1[:, 1] - self.y0) / r - 0.5
        k_lo = np.ceil(np.minimum(ya, yb)).astype(np.int64)
        k_hi = np.ceil(np.maximum(ya, yb)).astype(np.int64)
        span = np.maximum(k_hi - k_lo, 0)
        edge = np.repeat(np.arange(len(span)), span)
        row = k_lo[edge] + ranks_in_runs(span)
        if len(row) == 0:
            return empty, empty, empty, empty, empty, np.zeros(n, np.int64)
        yc = self.y0 + (row + 0.5) * r
        p0, p1 = e0[edge], e1[edge]
        x = p0[:, 0] + (yc - p0[:, 1]) * (p1[:, 0] - p0[:, 0]) / (p1[:, 1] - p0[:, 1])
        own = e_owner[edge]
        order = _order_crossings(own * (int(row.max()) + 1) + row, x)
        x, row, own = x[order], row[order], own[order]
        # crossings pair up (even-odd) within each (owner, row): the runs of cells
        xa, xb, row, own = x[0::2], x[1::2], row[0::2], own[0::2]
        i_lo = np.ceil((xa - self.x0) / r - 0.5).astype(np.int64)
        i_hi = np.ceil((xb - self.x0) / r - 0.5).astype(np.int64)
        width = np.maximum(i_hi - i_lo, 0)
        counts = np.bincount(own, weights=width, minlength=n).astype(np.int64)
        run = width > 0
        i_lo, i_hi, row, own = i_lo[run], i_hi[run], row[run], own[run]
        # split the runs at the tiles' edges, in place (the order stays by scan)
        pieces = (i_hi - 1) // TILE - i_lo // TILE + 1
        src = np.repeat(np.arange(len(i_lo)), pieces)
        k = ranks_in_runs(pieces)
        tile_col = i_lo[src] // TILE + k
        lo = np.maximum(i_lo[src], tile_col * TILE)
        hi = np.minimum(i_hi[src], (tile_col + 1) * TILE)
        row = row[src]
        return (row // TILE) * self._tiles_per_row + tile_col, row, lo, hi - lo, own[src], counts

    def _runs(self, j: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        a, b = self.run_start[j], self.run_stop[j]
        return self.run_row[a:b], self.run_col[a:b], self.run_len[a:b]

    def cells_of(self, j: int) -> np.ndarray:
        """Cells covered by scan ``j``.

        Parameters
        ----------
        j : int
            Position of the scan in the raster (not its scan id).

        Returns
        -------
        (C,) int64 ndarray
            Cell numbers (positions in ``covered.ravel()``), a new array; a cell of the
            map has one number whichever scan covers it.
        """
        return _cells(*self._runs(j))

    def _covered_in_runs(self, a: int, b: int) -> np.ndarray:
        rows, cols = self.run_row[a:b], self.run_col[a:b]
        return self._prefix[rows, cols + self.run_len[a:b]] - self._prefix[rows, cols]

    def gains(self, scans: Sequence[int] | np.ndarray) -> np.ndarray:
        """Cells each scan would add to the current union.

        Parameters
        ----------
        scans : (M,) sequence of int
            Positions of the scans in the raster.

        Returns
        -------
        (M,) int64 ndarray
        """
        scans = np.asarray(scans, dtype=np.int64)
        out = self.counts[scans].copy()
        n_runs = self.run_stop[scans] - self.run_start[scans]
        nz = n_runs > 0
        if not nz.any():
            return out
        offs = np.cumsum(n_runs) - n_runs
        idx = np.repeat(self.run_start[scans] - offs, n_runs) + np.arange(int(n_runs.sum()))
        rows, cols = self.run_row[idx], self.run_col[idx]
        hit = self._prefix[rows, cols + self.run_len[idx]] - self._prefix[rows, cols]
        out[nz] -= np.add.reduceat(hit, offs[nz], dtype=np.int64)
        return out

    def gain(self, j: int) -> int:
        """Cells scan ``j`` would add to the current union (``gains([j])[0]``, without
        the array bookkeeping: the lazy greedy evaluates one scan at a time).

        Parameters
        ----------
        j : int
            Position of the scan in the raster.

        Returns
        -------
        int
        """
        hit = self._covered_in_runs(self.run_start[j], self.run_stop[j])
        return int(self.counts[j]) - int(hit.sum(dtype=np.int64))

    def add(self, j: int) -> None:
        """Add scan ``j``'s cells to the union (in place). The row prefix sums are
        summed again only on the rows where the scan adds a cell: a scan added late in
        an ordering covers mostly cells the union holds.

        Parameters
        ----------
        j : int
            Position of the scan in the raster.
        """
        a, b = self.run_start[j], self.run_stop[j]
        if a == b:
            return
        rows, cols, lens = self.run_row[a:b], self.run_col[a:b], self.run_len[a:b]
        fresh = self._prefix[rows, cols + lens] - self._prefix[rows, cols] < lens
        if not fresh.any():
            return
        self.covered.reshape(-1)[_cells(rows[fresh], cols[fresh], lens[fresh])] = True
        changed = unique_ints(rows[fresh])
        self._prefix[changed, 1:] = np.cumsum(self.covered[changed], axis=1, dtype=np.int16)

    def reset(self) -> None:
        """Empty the union (the scans' cells are kept), to order the same scans again."""
        self.covered[:] = False
        self._prefix[:] = 0


def _cells(rows: np.ndarray, cols: np.ndarray, lens: np.ndarray) -> np.ndarray:
    """The cell numbers (positions in ``covered.ravel()``) of runs given by their row of
    ``covered``, first column and length."""
    lens = lens.astype(np.int64)
    first = np.cumsum(lens) - lens
    base = rows.astype(np.int64) * TILE + cols - first
    return np.repeat(base, lens) + np.arange(int(lens.sum()), dtype=np.int64)


def _order_crossings(key: np.ndarray, x: np.ndarray) -> np.ndarray:
    """A permutation sorting the crossings by (``key``, ``x``), as
    ``np.lexsort((x, key))`` (up to the order of equal pairs): a stable sort by
    ``key`` (the crossings come nearly sorted: edge after edge of each scan), then
    ``x`` in order within each run of equal keys, by a swap for the runs of two
    crossings (a row through a convex hull) and ``lexsort`` for the longer ones."""
    order = np.argsort(key, kind="stable")
    ks, xs = key[order], x[order]
    starts, _, size = runs(ks)
    two = starts[size == 2]
    swap = two[xs[two] > xs[two + 1]]
    order[swap], order[swap + 1] = order[swap + 1], order[swap].copy()
    long = size > 2
    if long.any():
        sub = np.repeat(starts[long], size[long]) + ranks_in_runs(size[long])
        order[sub] = order[sub][np.lexsort((xs[sub], ks[sub]))]
    return order


def runs(seg: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The runs of equal values of a non-decreasing array.

    Parameters
    ----------
    seg : (n,) int ndarray
        Non-decreasing.

    Returns
    -------
    starts : (R,) int64 ndarray
        Index of each run's first element.
    values : (R,) ndarray
        Each run's value (``seg``'s dtype).
    lengths : (R,) int ndarray
    """
    starts = np.flatnonzero(np.r_[True, seg[1:] != seg[:-1]]) if len(seg) else np.zeros(0, np.int64)
    return starts, seg[starts], np.diff(np.r_[starts, len(seg)])


def raster_for(
    scan_ids: Sequence[int], geometries: Sequence, raster_m: float, raster: RasterCoverage | None = None
) -> tuple[np.ndarray, RasterCoverage]:
    """The scan ids and the :class:`RasterCoverage` of their geometries, with an empty union.

    Parameters
    ----------
    scan_ids : (S,) int
        Unique scan ids.
    geometries : (S,) Shapely geometries
        Coverage of each scan, metres.
    raster_m : float
        Cell side, metres.
    raster : RasterCoverage, optional
        The raster of ``geometries`` at ``raster_m`` to reuse (its union is emptied)
        instead of rasterising again.

    Returns
    -------
    ids : (S,) int64 ndarray
    raster : RasterCoverage

    Raises
    ------
    ValueError
        When ``scan_ids`` and ``geometries`` are not 1-D of one length, the ids are not
        unique, or ``raster`` is of other scans or another cell size.
    """
    ids = np.asarray(scan_ids, dtype=np.int64)
    geoms = np.asarray(geometries, dtype=object)
    if ids.shape != geoms.shape or ids.ndim != 1:
        raise ValueError(f"scan_ids {ids.shape} and geometries {geoms.shape} must be 1-D of the same length")
    if len(np.unique(ids)) != len(ids):
        raise ValueError("scan_ids must be unique")
    if raster is None:
        return ids, RasterCoverage(geoms, raster_m)
    if raster.n != len(ids) or raster.raster_m != float(raster_m):
        raise ValueError(f"raster: {raster.n} scans at {raster.raster_m} m, expected {len(ids)} at {raster_m} m")
    raster.reset()
    return ids, raster


def ordering_table(
    scan_ids: np.ndarray, order: Sequence[int], gain_cells: Sequence[int], cell_m2: float
) -> pd.DataFrame:
    """An ordering's table from raster gains.

    Parameters
    ----------
    scan_ids : (S,) int64 ndarray
    order : (n,) int
        Positions in ``scan_ids``, in rank order.
    gain_cells : (n,) int
        Cells each scan added.
    cell_m2 : float
        Area of a cell, m^2.

    Returns
    -------
    DataFrame
        ``rank`` int32, ``scan_id`` int32, ``covered_area_m2`` (cumulative) and
        ``gain_m2`` float64 (the columns of :data:`floorscan.select.orderings.ORDERING`).
    """
    g = np.asarray(gain_cells, dtype=np.int64)
    return pd.DataFrame(
        {
            "rank": np.arange(len(order), dtype=np.int32),
            "scan_id": scan_ids[np.asarray(order, dtype=np.int64)].astype(np.int32),
            "covered_area_m2": np.cumsum(g) * cell_m2,
            "gain_m2": g * cell_m2,
        }
    )

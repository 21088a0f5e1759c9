"""Coverage on a raster: scans' coverage polygons as sets of grid cells (thesis section
3.3, the area measure of Algorithm 1).

Areas are counted on a raster of square cells of ``raster_m`` (default 5 cm) anchored
at the map origin: a scan covers the cells whose centre lies in its coverage polygon
(Shapely geometry rasterised once, vectorised over all scans), the union ``U`` of the
chosen scans is a boolean grid, and a gain is the number of the scan's cells not yet
in ``U`` times ``raster_m**2``.

Why not exact polygon overlays: hulls of neighbouring scans share nearly collinear wall
edges, which make each GEOS difference against the growing union slow, and a greedy
over thousands of scans needs ~10^5 of them; on the raster an evaluation is a gather
over the scan's cells and, gains being integers, comparisons are exact, with no float
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

from floorscan.core.grid import check_raster_size


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

    Notes
    -----
    A cell belongs to a geometry when its centre is inside (scanline fill with the
    even-odd rule over all rings, half-open in y and x, vectorised over all scans).
    Areas are integer cell counts, so gains compare exactly: no float ties.
    Memory: 4 bytes per (scan, covered cell).

    Raises
    ------
    floorscan.core.io.InputError
        When the grid would take more than :data:`floorscan.core.grid.MAX_RASTER_BYTES`
        at 1 byte a cell (:func:`floorscan.core.grid.check_raster_size`; fewer than
        2**31 cells, as the int32 cell numbers need).
    """

    def __init__(self, geometries: Sequence, raster_m: float = 0.05, chunk: int = 512):
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
            self.nx = int(np.ceil((b[:, 2].max() - self.x0) / r)) + 1
            self.ny = int(np.ceil((b[:, 3].max() - self.y0) / r)) + 1
        else:
            self.x0 = self.y0 = 0.0
            self.nx = self.ny = 1
        if nonempty.any():  # 1 GB of cells, under 2**31: the int32 cell numbers hold
            check_raster_size(f"coverage raster of {int(nonempty.sum())} scans (select.raster_m)",
                              (b[:, 0].min(), b[:, 1].min()), (b[:, 2].max(), b[:, 3].max()), r,
                              (self.ny, self.nx), 1)
        cells, counts = [], np.zeros(self.n, dtype=np.int64)
        for a in range(0, self.n, chunk):
            c, k = self._rasterize(geoms[a : a + chunk])
            cells.append(c)
            counts[a : a + chunk] = k
        self.cells = np.concatenate(cells) if cells else np.zeros(0, np.int32)
        self.stop = np.cumsum(counts)
        self.start = self.stop - counts
        self.counts = counts
        self.covered = np.zeros(self.nx * self.ny, dtype=bool)

    def _rasterize(self, geoms: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r, n = self.raster_m, len(geoms)
        parts, owner = shapely.get_parts(geoms, return_index=True)
        poly = shapely.get_type_id(parts) == 3  # Polygon parts; points/lines have no area
        parts, owner = parts[poly], owner[poly]
        if len(parts) == 0:
            return np.zeros(0, np.int32), np.zeros(n, np.int64)
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
        row = k_lo[edge] + (np.arange(span.sum()) - np.repeat(np.cumsum(span) - span, span))
        yc = self.y0 + (row + 0.5) * r
        p0, p1 = e0[edge], e1[edge]
        x = p0[:, 0] + (yc - p0[:, 1]) * (p1[:, 0] - p0[:, 0]) / (p1[:, 1] - p0[:, 1])
        own = e_owner[edge]
        order = _order_crossings(own * (int(row.max()) + 1) + row, x)
        x, row, own = x[order], row[order], own[order]
        # crossings pair up (even-odd) within each (owner, row)
        xa, xb, row, own = x[0::2], x[1::2], row[0::2], own[0::2]
        i_lo = np.ceil((xa - self.x0) / r - 0.5).astype(np.int64)
        i_hi = np.ceil((xb - self.x0) / r - 0.5).astype(np.int64)
        width = np.maximum(i_hi - i_lo, 0)
        first = np.cumsum(width) - width  # position of each interval's first cell
        # int32 throughout: the cell numbers are < 2**31 (checked) and the wrapping
        # intermediate sums are exact modulo 2**32
        base = (row * self.nx + i_lo - first).astype(np.int32)
        cells = np.arange(int(width.sum()), dtype=np.int32)
        cells += np.repeat(base, width)
        counts = np.bincount(own, weights=width, minlength=n).astype(np.int64)
        return cells, counts

    def cells_of(self, j: int) -> np.ndarray:
        """Cells covered by scan ``j``.

        Parameters
        ----------
        j : int
            Position of the scan in the raster (not its scan id).

        Returns
        -------
        (C,) int ndarray
            Flat cell indices ``row * nx + col`` (a view).
        """
        return self.cells[self.start[j] : self.stop[j]]

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
        counts = self.counts[scans]
        out = np.zeros(len(scans), dtype=np.int64)
        nz = counts > 0
        if not nz.any():
            return out
        if len(scans) == 1:
            out[0] = counts[0] - np.count_nonzero(self.covered[self.cells_of(int(scans[0]))])
            return out
        idx = np.repeat(self.start[scans] - np.r_[0, np.cumsum(counts)[:-1]], counts) + np.arange(counts.sum())
        new = ~self.covered[self.cells[idx]]
        offs = np.r_[0, np.cumsum(counts)[:-1]]
        out[nz] = np.add.reduceat(new, offs[nz], dtype=np.int64)
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
        a, b = self.start[j], self.stop[j]
        return int(b - a) - int(np.count_nonzero(self.covered[self.cells[a:b]]))

    def add(self, j: int) -> None:
        """Add scan ``j``'s cells to the union (in place).

        Parameters
        ----------
        j : int
            Position of the scan in the raster.
        """
        self.covered[self.cells_of(j)] = True

    def reset(self) -> None:
        """Empty the union (the scans' cells are kept), to order the same scans again."""
        self.covered[:] = False


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
        sub = np.repeat(starts[long], size[long]) + (np.arange(int(size[long].sum())) -
                                                       np.repeat(np.cumsum(size[long]) - size[long], size[long]))
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

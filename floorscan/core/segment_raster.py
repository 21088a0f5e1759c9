"""Wall segments on a raster: the scoring grid (:class:`Grid`, :func:`grid_for`) and the
binary wall map of a set of segments on it (:func:`rasterize_segments`), which the
score stage's bitmap metrics compare (thesis section 5.1,
:mod:`floorscan.score.bitmap`) and the figures draw (the bitmap overlay,
:mod:`floorscan.figures.bitmaps`).

A cell is 1 when its centre lies within ``wall_width_m / 2`` of a segment (the cell
centre is inside the segment's round-capped buffer), else 0; several walls on one cell
count once. :func:`segment_cells` gives the cells of each segment, so that the map of a
growing set of segments is updated, not redrawn.

Usage::

    grid = grid_for(reference_segments, cell_m=0.05, margin_m=1.0)
    bitmap = rasterize_segments(segments, grid, width_m=0.10)   # (grid.ny, grid.nx) bool
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from floorscan.core.geometry import point_segment_dist2
from floorscan.core.grid import MAX_RASTER_BYTES, check_raster_size
from floorscan.core.segments import as_segments, split_long

#: Bytes a cell of the scoring grid takes: the inferred and ground-truth bitmaps, their
#: error map and the metrics' masks (bool).
BITMAP_BYTES_PER_CELL = 5


#: Largest grid a bitmap metric may allocate (cells): the project's raster bound
#: (:data:`floorscan.core.grid.MAX_RASTER_BYTES`), 200 M cells.
MAX_CELLS = MAX_RASTER_BYTES // BITMAP_BYTES_PER_CELL


#: Candidate cells per chunk of :func:`rasterize_segments` (bounds its memory: a dozen
#: arrays of this length).
RASTER_CHUNK = 500_000


@dataclass(frozen=True)
class Grid:
    """A raster over the map frame: ``nx`` by ``ny`` square cells of ``cell_m`` metres.

    Cell ``(iy, ix)`` covers ``[x0 + ix * cell_m, x0 + (ix + 1) * cell_m)`` in x (and
    likewise in y); its centre decides whether it is a wall cell. Arrays on the grid
    have shape ``(ny, nx)`` with row 0 at the smallest y.
    """

    x0: float
    y0: float
    cell_m: float
    nx: int
    ny: int

    @property
    def shape(self) -> tuple[int, int]:
        return (self.ny, self.nx)

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)`` of the grid, for ``matplotlib.imshow``."""
        return (
            self.x0,
            self.x0 + self.nx * self.cell_m,
            self.y0,
            self.y0 + self.ny * self.cell_m,
        )


def grid_for(segments, cell_m: float = 0.05, margin_m: float = 1.0) -> Grid:
    """The grid covering ``segments``' bounds plus ``margin_m`` on every side.

    The origin is snapped to a multiple of ``cell_m`` so that the same ground truth
    always gives the same grid. Every ordering and k of a dataset is scored on the grid
    of its ground truth (reference), so the map area ``|B_E|`` is the same for all.

    Parameters
    ----------
    segments : (M, 4) array_like
        Ground-truth (reference) wall segments, metres.
    cell_m : float
        Cell size in metres (thesis section 5.1 leaves it open; default 5 cm).
    margin_m : float
        Margin around the bounds in metres.

    Returns
    -------
    Grid

    Raises
    ------
    ValueError
        When ``segments`` is empty or ``cell_m`` is not positive; an ``InputError``
        (:func:`floorscan.core.grid.check_raster_size`) when the grid would exceed
        :data:`MAX_CELLS` cells.
    """
    seg = as_segments(segments)
    if len(seg) == 0:
        raise ValueError("cannot build a scoring grid: the ground truth has no wall segment")
    if not cell_m > 0 or margin_m < 0:
        raise ValueError(f"cell_m must be > 0 and margin_m >= 0; got {cell_m}, {margin_m}")
    xs = np.r_[seg[:, 0], seg[:, 2]]
    ys = np.r_[seg[:, 1], seg[:, 3]]
    x0 = math.floor((xs.min() - margin_m) / cell_m) * cell_m
    y0 = math.floor((ys.min() - margin_m) / cell_m) * cell_m
    nx = int(math.ceil((xs.max() + margin_m - x0) / cell_m - 1e-9))
    ny = int(math.ceil((ys.max() + margin_m - y0) / cell_m - 1e-9))
    nx, ny = max(nx, 1), max(ny, 1)
    check_raster_size("scoring grid of the reference walls (score.cell_m)", (xs.min(), ys.min()), (xs.max(), ys.max()),
                      cell_m, (ny, nx), BITMAP_BYTES_PER_CELL)
    return Grid(float(x0), float(y0), float(cell_m), nx, ny)


def rasterize_segments(segments, grid: Grid, width_m: float = 0.10) -> np.ndarray:
    """Binary wall map: cells whose centre is within ``width_m / 2`` of a segment.

    Equivalent to ``shapely.contains_xy(LineString(seg).buffer(width_m / 2), cx, cy)``
    on the cell centres (round caps), but vectorized: segments are cut into pieces of at
    most 0.5 m (the union of their buffers is the same), and the exact point-to-segment
    distance is computed for the cell centres inside each piece's buffered bounds, in
    chunks. Parts of segments outside the grid are clipped (not counted). Thesis
    section 5.1: "If there is one or more wall present, a value of 1 is placed".

    Parameters
    ----------
    segments : (M, 4) array_like
        Wall segments ``x0, y0, x1, y1`` in metres.
    grid : Grid
        The raster.
    width_m : float
        Drawn wall width in metres (> 0).

    Returns
    -------
    (ny, nx) bool ndarray
        True on wall cells.

    Raises
    ------
    ValueError
        When ``width_m`` is not positive.
    """
    if not width_m > 0:
        raise ValueError(f"width_m must be > 0; got {width_m}")
    out = np.zeros(grid.shape, dtype=bool)
    seg = as_segments(segments)
    if len(seg):
        out.reshape(-1)[segment_cells(seg, grid, width_m)[1]] = True
    return out


def segment_cells(seg: np.ndarray, grid: Grid, width_m: float) -> tuple[np.ndarray, np.ndarray]:
    """The wall cells of :func:`rasterize_segments` per segment. Whether a cell is a
    segment's depends on that segment only, so the cells of a union of segment sets are
    the union of theirs.

    Parameters
    ----------
    seg : (M, 4) float64 ndarray
        Finite segments ``x0, y0, x1, y1``, metres.
    grid : Grid
    width_m : float
        Drawn wall width, metres.

    Returns
    -------
    owner : (H,) int64 ndarray
        The row of ``seg`` of each hit, ascending (pieces in row order).
    flat : (H,) int64 ndarray
        Flat cell index ``iy * nx + ix`` of each hit; a cell may repeat.
    """
    half = width_m / 2.0
    seg, owner = split_long(seg, 0.5, return_owner=True)
    c = grid.cell_m
    # Cell index ranges of each piece's buffered bounds (cells whose centre may be in).
    lo_x = np.floor((np.minimum(seg[:, 0], seg[:, 2]) - half - grid.x0) / c - 0.5)
    hi_x = np.ceil((np.maximum(seg[:, 0], seg[:, 2]) + half - grid.x0) / c - 0.5)
    lo_y = np.floor((np.minimum(seg[:, 1], seg[:, 3]) - half - grid.y0) / c - 0.5)
    hi_y = np.ceil((np.maximum(seg[:, 1], seg[:, 3]) + half - grid.y0) / c - 0.5)
    lo_x = np.clip(lo_x, 0, grid.nx - 1).astype(np.int64)
    hi_x = np.clip(hi_x, 0, grid.nx - 1).astype(np.int64)
    lo_y = np.clip(lo_y, 0, grid.ny - 1).astype(np.int64)
    hi_y = np.clip(hi_y, 0, grid.ny - 1).astype(np.int64)
    # Pieces entirely outside the grid have their range collapsed by clipping; the
    # distance test below rejects their cells, so no special case is needed.
    w = hi_x - lo_x + 1
    h = hi_y - lo_y + 1
    counts = w * h
    chunk = RASTER_CHUNK
    starts = np.r_[0, np.cumsum(counts)]
    i = 0
    owners, flats = [], []
    while i < len(seg):
        j = int(np.searchsorted(starts, starts[i] + chunk, side="right")) - 1
        j = max(j, i + 1)
        sl = slice(i, j)
        n = counts[sl]
        rep = np.repeat(np.arange(i, j), n)
        local = np.arange(int(n.sum())) - np.repeat(np.cumsum(n) - n, n)
        ix = lo_x[rep] + local % w[rep]
        iy = lo_y[rep] + local // w[rep]
        cx = grid.x0 + (ix + 0.5) * c
        cy = grid.y0 + (iy + 0.5) * c
        d2 = point_segment_dist2(cx, cy, seg[rep])
        hit = d2 <= half * half * (1 + 1e-12)
        owners.append(owner[rep[hit]])
        flats.append(iy[hit] * grid.nx + ix[hit])
        i = j
    if not owners:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(owners), np.concatenate(flats)

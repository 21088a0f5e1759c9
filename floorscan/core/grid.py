"""Grouping points by grid cell (voxels, 2D cells), shared by registration, the wall
extraction and MeanShift's bin seeding; the dilation of a sparse set of cells.

The cells are numbered by one int64 key (``numpy.ravel_multi_index`` of the cell
offsets from the minimum), whose order is the lexicographic order of the cells, so a 1D
``numpy.unique`` replaces ``numpy.unique(cells, axis=0)`` (a sort of structured rows,
~6x slower); sums come from ``numpy.bincount``, which adds in point order as
``numpy.add.at`` does: the same floats, bit for bit (tested).

A raster sized by the data's extent (the occupancy grid of the scans, the scoring grid)
is checked by :func:`check_raster_size` before it is
allocated: coordinates in millimetres, or one scan far from the others, would otherwise
ask for gigabytes and end in a ``MemoryError`` traceback.
"""

from __future__ import annotations

import math

import numpy as np

#: The memory one job of the workflow may use, bytes: the project's per-job budget of
#: 2 GB (the benchmarks' largest job takes 0.56 GB; the SLURM profile asks 4 GB a job).
JOB_MEMORY_BYTES = 2_000_000_000
#: A raster sized by the data's extent may take at most this, bytes: half of a job's
#: budget, the other half for the points and the arrays derived from the raster (its
#: log-odds, masks, distance transforms). 1 GB is 41 M cells of the occupancy grid's 24
#: bytes, a building 320 m square at 5 cm; the shared recordings' largest grid is 2.7 M
#: cells (2798 x 963, acapulco's 100 m x 45 m hall).
MAX_RASTER_BYTES = JOB_MEMORY_BYTES // 2


def check_raster_size(what: str, lo_xy, hi_xy, cell_m: float, shape: tuple[int, int], bytes_per_cell: int) -> None:
    """Refuse a raster sized by the data's extent that would take more than
    :data:`MAX_RASTER_BYTES`, before it is allocated.

    Parameters
    ----------
    what : str
        The raster and whose data it covers, for the message (``the occupancy grid of
        the 40 selected scans of dataset 'x'``).
    lo_xy, hi_xy : (2,) float
        The data's extent, metres (map frame).
    cell_m : float
        Cell side, metres.
    shape : (int, int)
        Rows, columns the raster would have.
    bytes_per_cell : int
        Bytes the raster's arrays take per cell.

    Raises
    ------
    floorscan.core.io.InputError
        Naming the extent in metres, the cells and the memory it would need, and the bound.
    """
    n_cells = int(shape[0]) * int(shape[1])
    need = n_cells * int(bytes_per_cell)
    if need <= MAX_RASTER_BYTES:
        return
    from floorscan.core.io import InputError

    w, h = (float(b) - float(a) for a, b in zip(lo_xy, hi_xy))
    side = math.sqrt(MAX_RASTER_BYTES / bytes_per_cell) * cell_m
    raise InputError(
        f"{what}: the data spans {w:.6g} m x {h:.6g} m, which at {cell_m:g} m cells needs {shape[1]} x {shape[0]} = "
        f"{n_cells:.3g} cells, {need / 2**30:.3g} GiB ({bytes_per_cell} bytes a cell), more than the "
        f"{MAX_RASTER_BYTES / 1e9:g} GB a raster may take (half of a job's {JOB_MEMORY_BYTES / 1e9:g} GB): expected a "
        f"building's extent in metres, at most about {side:.0f} m square at {cell_m:g} m. Are the recording's ranges "
        "or poses in millimetres, or is a pose far from the others?"
    )


def cell_groups(cells: np.ndarray, first: bool = False, inverse: bool = True):
    """Group rows of integer grid cells.

    Parameters
    ----------
    cells : (N, d) int ndarray
        Cell indices, N >= 1.
    first : bool
        Also return the first row of each group.
    inverse : bool
        Return each row's group (False: only the counts and first rows, one pass
        fewer, e.g. for MeanShift's bin seeding).

    Returns
    -------
    inverse : (N,) intp ndarray
        Each row's group; groups in lexicographic order of their cells (only with
        ``inverse``: without it, ``counts`` or ``(counts, first_rows)``).
    counts : (G,) intp ndarray
        Rows per group.
    first_rows : (G,) intp ndarray
        Only with ``first``: the first row of each group.
    """
    c = np.asarray(cells, dtype=np.int64)
    key = cell_keys(c)
    if key is not None:
        out = np.unique(key, return_index=first, return_inverse=inverse, return_counts=True)
    else:  # an extent beyond the int64 key: sort the rows themselves
        out = np.unique(c, axis=0, return_index=first, return_inverse=inverse, return_counts=True)
    if not inverse:  # (unique, [index], counts)
        return (out[2], out[1]) if first else out[1]
    if first:
        _, first_rows, inv, counts = out
        return inv.ravel(), counts, first_rows
    _, inv, counts = out
    return inv.ravel(), counts


def ranks_in_runs(counts: np.ndarray) -> np.ndarray:
    """Each element's place within its run, for runs of ``counts`` elements laid end to
    end: ``0, 1, .., counts[0] - 1, 0, 1, .., counts[1] - 1, ...``.

    Parameters
    ----------
    counts : (R,) int ndarray
        Non-negative.

    Returns
    -------
    (counts.sum(),) int64 ndarray
    """
    counts = np.asarray(counts, dtype=np.int64).reshape(-1)
    return np.arange(int(counts.sum()), dtype=np.int64) - np.repeat(np.cumsum(counts) - counts, counts)


def unique_ints(values: np.ndarray, kind: str = "quicksort") -> np.ndarray:
    """The distinct values of an integer array, sorted: ``numpy.unique(values)``, by a
    sort and a comparison of neighbours. The locked numpy (2.4) finds plain
    ``numpy.unique``'s values through a hash table, which is many times slower than a
    sort on the millions of cell keys the stages hold.

    Parameters
    ----------
    values : (N,) int ndarray
    kind : str
        ``numpy.sort``'s algorithm; "stable" (a merge of sorted runs) for values made
        of long increasing runs, where it is many times faster.

    Returns
    -------
    (U,) ndarray
        Of ``values``' dtype; a new array.
    """
    out = np.sort(np.asarray(values).reshape(-1), kind=kind)
    if len(out) > 1:
        out = out[np.r_[True, out[1:] != out[:-1]]]
    return out


def cell_keys(cells: np.ndarray) -> np.ndarray | None:
    """One int64 key per row of integer grid cells, ordered as the rows are
    lexicographically (``numpy.ravel_multi_index`` of the offsets from the minimum).

    Parameters
    ----------
    cells : (N, d) int ndarray
        N >= 1.

    Returns
    -------
    (N,) int64 ndarray, or None when the cells' extent has more than 2**62 cells.
    """
    c = np.asarray(cells, dtype=np.int64).T  # a row per axis: column min/max are fast
    lo = [int(v.min()) for v in c]
    span = [int(v.max()) - low + 1 for v, low in zip(c, lo)]
    if float(np.prod(np.array(span, dtype=np.float64))) >= 2.0**62:
        return None
    # numpy.ravel_multi_index of the offsets (C order), in place: the same integers, ~5x faster
    key = c[0] - lo[0]
    for k in range(1, len(span)):
        key *= span[k]
        key += c[k] - lo[k]
    return key


def cell_means(points: np.ndarray, cell_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Mean of the points in each occupied cell of side ``cell_m``.

    Parameters
    ----------
    points : (N, d) float ndarray
        Metres, N >= 1.
    cell_m : float
        Cell side, metres (> 0).

    Returns
    -------
    means : (G, d) float64 ndarray
        One per occupied cell, cells in lexicographic order.
    inverse : (N,) intp ndarray
        Each point's cell (row of ``means``).
    """
    p = np.asarray(points, dtype=np.float64)
    # column by column (contiguous copies): the divisions, floors, keys and bincount
    # sums are those of the (N, d) forms, ~1.5x faster on the walls' 3D band cut
    cols = [np.ascontiguousarray(p[:, i]) for i in range(p.shape[1])]
    cells = np.empty((len(cols), len(p)), dtype=np.int64)
    for i, c in enumerate(cols):
        cells[i] = np.floor(c / cell_m)
    key = cell_keys(cells.T)
    if key is None:
        inverse, counts = cell_groups(cells.T)
    else:
        _, inverse, counts = np.unique(key, return_inverse=True, return_counts=True)
        inverse = inverse.ravel()
    means = np.empty((len(counts), len(cols)))
    for i, c in enumerate(cols):
        means[:, i] = np.bincount(inverse, weights=c, minlength=len(counts))
    means /= counts[:, None]
    return means, inverse


def raster_cells(xy: np.ndarray, origin_xy: np.ndarray, resolution_m: float, shape: tuple[int, int]):
    """The cell of each map-frame point on a raster whose cell (row 0, column 0) has its
    corner at ``origin_xy``.

    Parameters
    ----------
    xy : (N, 2) float ndarray
        Metres.
    origin_xy : (2,) float ndarray
        Metres.
    resolution_m : float
        Cell size, metres.
    shape : (int, int)
        Rows, columns.

    Returns
    -------
    rows, cols : (N,) int64 ndarray
        Cell indices (may be off the raster).
    inside : (N,) bool ndarray
        Whether the cell lies on the raster.
    """
    c = np.floor((np.asarray(xy, dtype=np.float64).reshape(-1, 2) - origin_xy) / resolution_m).astype(np.int64)
    inside = (c[:, 0] >= 0) & (c[:, 1] >= 0) & (c[:, 0] < shape[1]) & (c[:, 1] < shape[0])
    return c[:, 1], c[:, 0], inside


def square_dilation(rows: np.ndarray, cols: np.ndarray, radius: int, shape: tuple[int, int]) -> np.ndarray:
    """The cells within ``radius`` cells (a square of side ``2 radius + 1``) of the given
    cells, on a raster of ``shape``: the binary dilation of a sparse set, one write per
    cell and offset, where a filter over the raster costs its whole area (a recording's
    returns fill a small share of the box its rays span); when the writes would
    outnumber the raster's cells (a map's solid cells), SciPy's filter. Either way the
    cells of ``scipy.ndimage.maximum_filter(mask, size=2 radius + 1, mode="constant")``
    of the mask of the cells.

    Parameters
    ----------
    rows, cols : (N,) int ndarray
        The cells; those off the raster are ignored.
    radius : int
        Cells, at least 0.
    shape : (int, int)
        Rows, columns.

    Returns
    -------
    (H, W) bool ndarray
    """
    rows, cols = np.asarray(rows, dtype=np.int64), np.asarray(cols, dtype=np.int64)
    h, w = shape
    on = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)
    rows, cols = rows[on], cols[on]
    out = np.zeros((h, w), dtype=bool)
    if len(rows) * (2 * radius + 1) ** 2 >= h * w:  # a dense set (a map's solid cells): the filter is cheaper
        from scipy import ndimage

        out[rows, cols] = True
        return ndimage.maximum_filter(out, size=2 * radius + 1, mode="constant")
    for dr in range(-radius, radius + 1):
        r = rows + dr
        on_r = (r >= 0) & (r < h)
        for dc in range(-radius, radius + 1):
            c = cols + dc
            on = on_r & (c >= 0) & (c < w)
            out[r[on], c[on]] = True
    return out

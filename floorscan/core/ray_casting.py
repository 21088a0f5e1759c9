"""The cells of a scan on a grid: those its returns fall in and those its rays cross
(the casting of :func:`floorscan.core.occupancy.occupancy_grid` and
:func:`floorscan.core.prefix_grids.prefix_grids`).

A grid lies in a :class:`GridFrame` (origin, cell size, shape), fixed by the scans'
extent. :class:`CellCounts` holds the hit and miss counts of the scans cast into a frame
so far: :meth:`CellCounts.cells` gives one scan's distinct hit cells and the cells its
rays cross without a return in them (one update per scan and cell, Thrun, Burgard, Fox,
*Probabilistic Robotics*, ch. 9), :meth:`CellCounts.add` counts them, and
:meth:`CellCounts.window` reads the counts over a frame of the same cells. Rays are
sampled every ``step_fraction`` of a cell (the cells a ray crosses, up to a corner
clipped by less than a quarter cell); the return's own cell is not a miss of that scan.

A cell is ``floor((x - origin) / r)``, so the same point measured from two origins of
the same lattice can round differently when it lies on a cell's edge (a pose logged to
the centimetre on a 5 cm grid): :meth:`CellCounts.cells` says whether a return or a ray
sample lies within :data:`EDGE_CELLS` of one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from floorscan.core.grid import check_raster_size, ranks_in_runs
from floorscan.core.memory import JobMemory

#: How near a cell's edge (in cells) a return or ray sample counts as on it. Measured
#: from two origins, a point's cell coordinate differs by rounding, some 1e-12 cells for
#: a site of kilometres.
EDGE_CELLS = 1e-9
#: Bytes a cell of :class:`CellCounts` takes: the hit and miss counts and the last scan
#: with a return in the cell (int32 each) and a scratch position (int64), 20, rounded up
#: to the 24 that :func:`floorscan.core.grid.check_raster_size` has always counted.
COUNTS_BYTES_PER_CELL = 24
#: Bytes a ray sample takes while its scan is cast (:meth:`CellCounts.cells`: its ray,
#: its place along it, its cell, and their temporaries), rounded up.
RAY_SAMPLE_BYTES = 40


def with_returns(scans) -> list[tuple[np.ndarray, np.ndarray]]:
    """The scans as float64, those without a return left out.

    Parameters
    ----------
    scans : iterable of (origin, points)
        The scanner's position ((2,) float, metres) and its returns ((M, 2) float,
        metres), map frame.

    Returns
    -------
    list of ((2,) float64 ndarray, (M, 2) float64 ndarray)
        M >= 1.
    """
    scans = [(np.asarray(o, dtype=np.float64)[:2], np.asarray(p, dtype=np.float64)[:, :2]) for o, p in scans]
    return [(o, p) for o, p in scans if len(p)]


@dataclass(frozen=True)
class GridFrame:
    """Where a grid lies.

    Attributes
    ----------
    origin : (2,) float64 ndarray
        Map-frame corner of cell (row 0, column 0), metres: ``cell0 * r``.
    cell0 : (2,) float64 ndarray
        The origin in cells of ``r`` from (0, 0), whole numbers (x, y).
    r : float
        Cell size, metres.
    height, width : int
        Rows (y) and columns (x).
    """

    origin: np.ndarray
    cell0: np.ndarray
    r: float
    height: int
    width: int

    @classmethod
    def of(cls, scans, resolution_m: float, margin_m: float, what: str | None = None) -> "GridFrame":
        """The frame of the grid of scans: their returns and origins and ``margin_m``.

        Parameters
        ----------
        scans : list of (origin, points)
            :func:`with_returns`' scans, at least one.
        resolution_m, margin_m : float
            Metres.
        what : str, optional
            The grid and whose scans: checked by
            :func:`floorscan.core.grid.check_raster_size` (not checked without it).

        Raises
        ------
        ValueError
            When a coordinate is not finite.
        floorscan.core.io.InputError
            When ``what`` is given and the grid would be too large.
        """
        lo = np.min([np.minimum(o, p.min(axis=0)) for o, p in scans], axis=0)
        hi = np.max([np.maximum(o, p.max(axis=0)) for o, p in scans], axis=0)
        if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
            raise ValueError("occupancy grid: a scan origin or return is not finite")
        r = float(resolution_m)
        cell0 = np.floor((lo - margin_m) / r)
        origin = cell0 * r
        width, height = (np.floor((hi + margin_m - origin) / r).astype(np.int64) + 1).tolist()
        if what is not None:
            check_raster_size(what, lo, hi, r, (height, width), COUNTS_BYTES_PER_CELL)
        return cls(origin, cell0, r, height, width)


def ray_samples(o: np.ndarray, p: np.ndarray, r: float, step_fraction: float) -> int:
    """At most how many ray samples :meth:`CellCounts.cells` takes of one scan: a ray
    per return, to a cell centre at most a cell farther than the return.

    Parameters
    ----------
    o : (2,) float64 ndarray
        The scanner's position, metres.
    p : (M, 2) float64 ndarray
        Its returns, metres.
    r : float
        Cell size, metres.
    step_fraction : float
        Sample spacing, in cells.

    Returns
    -------
    int
    """
    length = np.hypot(p[:, 0] - o[0], p[:, 1] - o[1]) + r
    return int(np.maximum(np.ceil(length / (step_fraction * r)), 1).sum())


def check_memory_of_casting(scans, frame: GridFrame, step_fraction: float, what: str, memory: JobMemory) -> float:
    """Stop a job whose grid of scans would not fit in the memory free on the machine,
    before the grid is allocated: ``memory``'s bytes a cell of ``frame`` and a point of
    the scans, and the ray samples of the largest scan (:func:`ray_samples`,
    :data:`RAY_SAMPLE_BYTES` each).

    Parameters
    ----------
    scans : list of (origin, points)
        :func:`with_returns`' scans.
    frame : GridFrame
    step_fraction : float
        Ray sample spacing, in cells.
    what : str
        The grid and whose scans, for the message.
    memory : JobMemory
        What the job's rasters take a cell of the grid.

    Returns
    -------
    float
        The estimate, bytes.

    Raises
    ------
    floorscan.core.memory.MemoryEstimateError
        When it would not fit.
    """
    samples = max((ray_samples(o, p, frame.r, step_fraction) for o, p in scans), default=0)
    rays = {f"the rays of the largest scan ({samples / 1e6:.3g} M samples x {RAY_SAMPLE_BYTES} bytes)":
            float(samples) * RAY_SAMPLE_BYTES}
    points = sum(len(p) for _, p in scans)
    return memory.check(what, (frame.height, frame.width), frame.r, rays, points=points)


class CellCounts:
    """The hit and miss counts of scans cast one after another into one frame.

    Parameters
    ----------
    frame : GridFrame
    step_fraction : float
        Ray sample spacing, in cells.
    """

    def __init__(self, frame: GridFrame, step_fraction: float):
        self.frame, self.step_fraction = frame, float(step_fraction)
        n_cells = frame.width * frame.height
        self.hits = np.zeros(n_cells, dtype=np.int32)
        self.misses = np.zeros(n_cells, dtype=np.int32)
        self.last = np.zeros(n_cells, dtype=np.int64)  # scratch of distinct_cells
        self.hit_by = np.full(n_cells, -1, dtype=np.int32)  # the last scan with a return in the cell
        self.n_cast = 0

    def cells(self, o: np.ndarray, p: np.ndarray, frame: GridFrame, edges: bool = False):
        """The cells of one scan in ``frame`` (this frame, or one of no more cells).

        Parameters
        ----------
        o : (2,) float64 ndarray
            The scanner's position, map metres.
        p : (M, 2) float64 ndarray
            Its returns, map metres, M >= 1.
        frame : GridFrame
        edges : bool
            Also tell whether a return or a ray sample lies on a cell's edge.

        Returns
        -------
        hit : (H,) int64 ndarray
            Flat indices (row * width + column) of the distinct cells with a return.
        missed : (C,) int64 ndarray
            Of the distinct cells the rays cross without a return of this scan.
        on_edge : bool
            A return or ray sample within :data:`EDGE_CELLS` of a cell's edge (False
            without ``edges``).
        """
        origin, r, width = frame.origin, frame.r, frame.width
        i, self.n_cast = self.n_cast, self.n_cast + 1
        q = (p - origin) / r
        edge = edges and near_edge(q)
        end = np.floor(q).astype(np.int64)
        hit = distinct_cells(end[:, 1] * width + end[:, 0], self.last)
        self.hit_by[hit] = i
        # one ray per return cell (rays to the same cell cross the same cells)
        tip = (np.column_stack([hit % width, hit // width]) + 0.5) * r + origin
        d = tip - o
        length = np.hypot(d[:, 0], d[:, 1])
        n = np.maximum(np.ceil(length / (self.step_fraction * r)).astype(np.int64), 1)
        ray = np.repeat(np.arange(len(n)), n)
        frac = ranks_in_runs(n) / np.repeat(n, n)
        samples, sample_edge = sample_cells(o, d, ray, frac, origin, r, width, edges and not edge)
        crossed = distinct_cells(samples, self.last)
        return hit, crossed[self.hit_by[crossed] != i], edge or sample_edge

    def add(self, hit: np.ndarray, missed: np.ndarray) -> None:
        """Count one scan's cells (:meth:`cells` in this frame)."""
        self.hits[hit] += 1
        self.misses[missed] += 1

    def window(self, frame: GridFrame) -> tuple[np.ndarray, np.ndarray]:
        """The hit and miss counts over ``frame``.

        Parameters
        ----------
        frame : GridFrame
            This frame, or one of the same lattice (origin a whole number of cells away).

        Returns
        -------
        hits, misses : (frame.height, frame.width) int32 ndarray
            This frame's arrays (reshaped, not copied) for this frame; else copies of
            their window over ``frame``, zeros beyond this frame.
        """
        f = self.frame
        hits, misses = self.hits.reshape(f.height, f.width), self.misses.reshape(f.height, f.width)
        if frame is f:
            return hits, misses
        row, col = (int(c) for c in (frame.cell0 - f.cell0)[::-1])
        return _window(hits, row, col, frame), _window(misses, row, col, frame)


def _window(a: np.ndarray, row: int, col: int, frame: GridFrame) -> np.ndarray:
    """A copy of ``a[row:row + frame.height, col:col + frame.width]``, zeros beyond ``a``."""
    if row >= 0 and col >= 0 and row + frame.height <= a.shape[0] and col + frame.width <= a.shape[1]:
        return a[row:row + frame.height, col:col + frame.width].copy()
    out = np.zeros((frame.height, frame.width), dtype=a.dtype)
    r0, c0 = max(row, 0), max(col, 0)
    r1, c1 = min(row + frame.height, a.shape[0]), min(col + frame.width, a.shape[1])
    if r1 > r0 and c1 > c0:
        out[r0 - row:r1 - row, c0 - col:c1 - col] = a[r0:r1, c0:c1]
    return out


def near_edge(q: np.ndarray) -> bool:
    """Whether a cell coordinate of ``q`` (any shape, in cells) lies within
    :data:`EDGE_CELLS` of a whole number."""
    return bool((np.abs(q - np.round(q)) < EDGE_CELLS).any())


def sample_cells(o, d, ray, frac, origin, r: float, width: int, edges: bool = False) -> tuple[np.ndarray, bool]:
    """Flat cell index of each ray sample ``o + d[ray] * frac``.

    floor((o + d[ray] * frac - origin) / r) per axis, computed in place one axis at a
    time (the same values as the whole expression, without its (N, 2) temporaries).

    Parameters
    ----------
    o : (2,) float64 ndarray
        The rays' start, metres.
    d : (R, 2) float64 ndarray
        Each ray's vector, metres.
    ray : (N,) int ndarray
        The ray of each sample.
    frac : (N,) float64 ndarray
        Where along its ray, 0 to 1.
    origin : (2,) float64 ndarray
        The grid's origin, metres.
    r : float
        Cell size, metres.
    width : int
        Columns.
    edges : bool
        Also tell whether a sample lies within :data:`EDGE_CELLS` of a cell's edge.

    Returns
    -------
    cells : (N,) int64 ndarray
        Row * width + column.
    on_edge : bool
        False without ``edges``.
    """
    axes, edge = [], False
    for a in (0, 1):
        v = np.ascontiguousarray(d[:, a])[ray]
        v *= frac
        v += o[a]
        v -= origin[a]
        v /= r
        if edges and not edge:
            edge = near_edge(v)
        axes.append(np.floor(v, out=v).astype(np.int64))
    cells = axes[1]
    cells *= width
    cells += axes[0]
    return cells, edge


def distinct_cells(cells: np.ndarray, last: np.ndarray) -> np.ndarray:
    """The distinct values of ``cells``, without a sort.

    Every entry writes its position into the scratch array ``last`` at its cell;
    whichever write stays, exactly one position per distinct cell finds itself there.

    Parameters
    ----------
    cells : (N,) int64 ndarray
        Cell indices below ``len(last)``.
    last : (C,) int64 ndarray
        Scratch, overwritten.

    Returns
    -------
    (D,) int64 ndarray
        The distinct cells, each once.
    """
    pos = np.arange(len(cells))
    last[cells] = pos
    return cells[last[cells] == pos]

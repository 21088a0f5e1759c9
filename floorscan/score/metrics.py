"""Scoring inferred walls against the ground truth (or a reference): thesis section 5.1
bitmap metrics and ISPRS-benchmark-style tolerance metrics.

Two families of metrics compare a set of *inferred* wall segments (the walls extracted
from the first k scans of an ordering) with a set of *ground-truth* wall segments (the
simulator's wall faces on synthetic datasets) or, on real recordings, *reference*
segments (the walls extracted from all kept scans, as the thesis does in section 5.4).

Bitmap metrics (thesis section 5.1)
    Both segment sets are rasterized on the same grid (:class:`Grid`): a cell is 1 when
    its centre lies within ``wall_width_m / 2`` of a segment (the cell centre is inside
    the segment's round-capped buffer), else 0. Several walls on one cell count once.
    With the error map ``B_E = B_I - B_GT`` (values -1, 0, 1) the thesis defines::

        CorrectMatch  = #[B_E = 0]  / |B_E|
        FalsePositive = #[B_E = 1]  / |B_E|
        FalseNegative = #[B_E = -1] / |B_E|

    normalized by the number of cells of the map ``|B_E|``. These follow the thesis
    exactly, but *CorrectMatch counts the empty cells that both maps leave empty*, which
    are the vast majority (a 50 x 30 m map at 5 cm has 600 000 cells, its walls perhaps
    20 000), so CorrectMatch stays near 1 even with no inferred wall at all. We therefore
    also report the wall-cell-only versions, normalized by the cells that either map
    marks as wall, ``U = B_I | B_GT``::

        wall_correct_match  = |B_I & B_GT|  / |U|   (intersection over union)
        wall_false_positive = |B_I & ~B_GT| / |U|
        wall_false_negative = |~B_I & B_GT| / |U|

    (each triple sums to 1), and the cell precision ``|B_I & B_GT| / |B_I|`` and cell
    recall ``|B_I & B_GT| / |B_GT|``.

Tolerance metrics (Khoshelham et al. 2017, "The ISPRS benchmark on indoor modelling",
and Khoshelham et al. 2018, "An evaluation framework for benchmarking indoor
modelling methods")
    *precision* (the benchmark's *correctness*): the fraction of inferred wall length
    lying within ``tau`` of a ground-truth segment, computed exactly, not by sampling:
    the part of a segment within ``tau`` of another segment is one interval of the first
    segment's parameter (the distance to a convex set along a line is convex, so its
    sublevel set is an interval), found by clipping the line against the other
    segment's capsule (rectangle plus two end disks); the intervals over all nearby
    segments are then merged. This is the limit of sampling every 1 cm (tested).
    *recall* (*completeness*): the fraction of the ground truth within ``tau`` of an
    inferred segment, measured on ground-truth samples every ``sample_step_m`` (default
    1 cm) deduplicated on a grid of the same size, so that a place of a wall counts once
    however many overlapping reference segments describe it (real recordings'
    references are the overlapping walls of all scans); exact sample-to-segment
    distances. *F1*: the harmonic mean. *median distance*: the median (and mean) of the
    same samples' distances to the nearest inferred segment.

On real recordings the reference is the union of the walls of all kept scans, and the
walls of the first k scans are a subset of it: precision is 1 and the false-positive
fraction 0 by construction there; recall, false negatives and F1 carry the comparison.

Empty inputs never raise: with no inferred wall, precision is NaN (0/0, undefined),
recall is 0 and F1 is 0 (a floor plan without walls is worthless, and 0 keeps the
metric-against-k curves continuous); with no ground-truth wall, recall is NaN and F1 is
0 if walls were inferred (all of them false positives), NaN if neither set has walls.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np
import shapely

from floorscan.floorplan.plan import point_segment_dist2

#: Segments shorter than this (metres) have no length and are ignored.
MIN_SEGMENT_M = 1e-9
#: Largest grid a bitmap metric may allocate (cells), a guard against a bad cell size.
MAX_CELLS = 200_000_000
#: Candidate cells per chunk of :func:`rasterize_segments` (bounds its memory: a dozen
#: arrays of this length).
RASTER_CHUNK = 500_000


def as_segments(segments) -> np.ndarray:
    """Return wall segments as a new ``(M, 4)`` float64 array ``x0, y0, x1, y1``.

    Parameters
    ----------
    segments : array_like, shape (M, 4), or pandas.DataFrame with columns x0, y0, x1, y1
        Segment end points in metres (map frame).

    Returns
    -------
    (M, 4) float64 ndarray
        A copy; rows with a NaN or infinite coordinate are dropped.

    Raises
    ------
    ValueError
        When the input does not have 4 columns.
    """
    if hasattr(segments, "columns"):
        missing = [c for c in ("x0", "y0", "x1", "y1") if c not in segments.columns]
        if missing:
            raise ValueError(f"wall table lacks columns {missing}; expected x0, y0, x1, y1")
        arr = segments[["x0", "y0", "x1", "y1"]].to_numpy(dtype=np.float64, copy=True)
    else:
        arr = np.array(segments, dtype=np.float64, copy=True)
        if arr.size == 0:
            return np.zeros((0, 4))
    if arr.ndim != 2 or arr.shape[1] != 4:
        raise ValueError(f"segments must have shape (M, 4) (x0, y0, x1, y1); got {arr.shape}")
    return arr[np.isfinite(arr).all(axis=1)]


def segment_lengths(segments: np.ndarray) -> np.ndarray:
    """Lengths in metres of ``(M, 4)`` segments, shape ``(M,)``."""
    s = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    return np.hypot(s[:, 2] - s[:, 0], s[:, 3] - s[:, 1])


# --------------------------------------------------------------------------- bitmaps


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

    Raises
    ------
    ValueError
        When ``segments`` is empty, ``cell_m`` is not positive or the grid would exceed
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
    if nx * ny > MAX_CELLS:
        raise ValueError(
            f"scoring grid of {nx} x {ny} cells exceeds {MAX_CELLS}; increase score.cell_m"
        )
    return Grid(float(x0), float(y0), float(cell_m), nx, ny)


def _split_long(seg: np.ndarray, max_len: float, return_owner: bool = False):
    """Cut segments into collinear pieces no longer than ``max_len`` (same union); with
    ``return_owner``, also the row of ``seg`` each piece comes from."""
    lengths = segment_lengths(seg)
    n = np.maximum(1, np.ceil(lengths / max_len).astype(np.int64))
    idx = np.repeat(np.arange(len(seg)), n)
    start = np.arange(len(idx)) - np.repeat(np.cumsum(n) - n, n)
    t0 = start / n[idx]
    t1 = (start + 1) / n[idx]
    p = seg[idx, :2]
    d = seg[idx, 2:] - seg[idx, :2]
    pieces = np.column_stack([p + t0[:, None] * d, p + t1[:, None] * d])
    return (pieces, idx) if return_owner else pieces


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
    """
    if not width_m > 0:
        raise ValueError(f"width_m must be > 0; got {width_m}")
    out = np.zeros(grid.shape, dtype=bool)
    seg = as_segments(segments)
    if len(seg):
        out.reshape(-1)[_raster_cells(seg, grid, width_m)[1]] = True
    return out


def _raster_cells(seg: np.ndarray, grid: Grid, width_m: float) -> tuple[np.ndarray, np.ndarray]:
    """The wall cells of :func:`rasterize_segments` per segment: ``(owner, flat)``, the
    row of the finite ``(M, 4)`` ``seg`` and the flat index (``iy * nx + ix``) of each
    hit, grouped by piece, pieces in row order (``owner`` ascending; a cell may
    repeat). Whether a cell is a segment's depends on
    that segment only, so the cells of a union of segment sets are the union of theirs."""
    half = width_m / 2.0
    seg, owner = _split_long(seg, 0.5, return_owner=True)
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


def error_map(inferred: np.ndarray, ground_truth: np.ndarray) -> np.ndarray:
    """The thesis's error map ``B_E = B_I - B_GT`` (section 5.1), int8 in {-1, 0, 1}.

    Raises
    ------
    ValueError
        When the two bitmaps differ in shape.
    """
    bi = np.asarray(inferred, dtype=bool)
    bg = np.asarray(ground_truth, dtype=bool)
    if bi.shape != bg.shape:
        raise ValueError(f"bitmaps differ in shape: {bi.shape} vs {bg.shape}")
    return bi.astype(np.int8) - bg.astype(np.int8)


def bitmap_metrics(inferred: np.ndarray, ground_truth: np.ndarray) -> dict[str, float]:
    """Thesis section 5.1 fractions, and their wall-cell-only versions.

    Parameters
    ----------
    inferred, ground_truth : (ny, nx) bool ndarray
        ``B_I`` and ``B_GT`` on the same grid.

    Returns
    -------
    dict
        ``correct_match``, ``false_positive``, ``false_negative``: the thesis's
        fractions of all map cells (``|B_E|``) with ``B_E`` = 0, 1, -1; they sum to 1 and
        ``correct_match`` is dominated by cells empty in both maps.
        ``wall_correct_match`` (IoU), ``wall_false_positive``, ``wall_false_negative``:
        the same counts over the wall cells ``B_I | B_GT`` only (NaN when neither map has
        a wall cell). ``cell_precision`` ``|B_I & B_GT| / |B_I|`` and ``cell_recall``
        ``|B_I & B_GT| / |B_GT|`` (NaN on an empty denominator). ``n_cells``,
        ``n_inferred_cells``, ``n_gt_cells``, ``n_both_cells`` (counts, as floats).
    """
    be = error_map(inferred, ground_truth)
    n = be.size
    fp = int(np.count_nonzero(be == 1))
    fn = int(np.count_nonzero(be == -1))
    both = int(np.count_nonzero(np.asarray(inferred, bool) & np.asarray(ground_truth, bool)))
    union = both + fp + fn
    n_i = both + fp
    n_g = both + fn

    def ratio(a: int, b: int) -> float:
        return a / b if b else math.nan

    return {
        "correct_match": ratio(n - fp - fn, n),
        "false_positive": ratio(fp, n),
        "false_negative": ratio(fn, n),
        "wall_correct_match": ratio(both, union),
        "wall_false_positive": ratio(fp, union),
        "wall_false_negative": ratio(fn, union),
        "cell_precision": ratio(both, n_i),
        "cell_recall": ratio(both, n_g),
        "n_cells": float(n),
        "n_inferred_cells": float(n_i),
        "n_gt_cells": float(n_g),
        "n_both_cells": float(both),
    }


# ------------------------------------------------------------------ tolerance metrics


def _clip_interval(v0, dv, lo, hi, t_lo, t_hi):
    """Narrow ``[t_lo, t_hi]`` to the t where ``lo <= v0 + t * dv <= hi``."""
    with np.errstate(divide="ignore", invalid="ignore"):
        ta = (lo - v0) / dv
        tb = (hi - v0) / dv
    moving = dv != 0
    inside = (v0 >= lo) & (v0 <= hi)
    t_lo = np.where(moving, np.maximum(t_lo, np.minimum(ta, tb)), np.where(inside, t_lo, np.inf))
    t_hi = np.where(moving, np.minimum(t_hi, np.maximum(ta, tb)), np.where(inside, t_hi, -np.inf))
    return t_lo, t_hi


def _disk_interval(px, py, dx, dy, cx, cy, r):
    """Parameter interval (within [0, 1]) of ``p + t d`` inside the disk ``(c, r)``."""
    a = dx * dx + dy * dy
    ex, ey = px - cx, py - cy
    b = 2.0 * (dx * ex + dy * ey)
    cc = ex * ex + ey * ey - r * r
    disc = b * b - 4.0 * a * cc
    ok = (disc >= 0) & (a > 0)
    sq = np.sqrt(np.where(ok, disc, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = np.where(ok, (-b - sq) / (2.0 * a), np.inf)
        t1 = np.where(ok, (-b + sq) / (2.0 * a), -np.inf)
    return np.maximum(t0, 0.0), np.minimum(t1, 1.0)


def capsule_intervals(a: np.ndarray, b: np.ndarray, tau: float) -> tuple[np.ndarray, np.ndarray]:
    """Parameter interval of each segment ``a[i]`` within ``tau`` of segment ``b[i]``.

    The set ``{t in [0, 1] : dist(a0 + t (a1 - a0), b) <= tau}`` is an interval, the
    intersection of the line with the capsule (stadium) of ``b`` (its rectangle of
    half-width ``tau`` and the disks of radius ``tau`` at its ends), because the
    capsule is convex.

    Parameters
    ----------
    a, b : (P, 4) float64 ndarray
        Paired segments ``x0, y0, x1, y1`` in metres; ``a`` must have non-zero length.
    tau : float
        Tolerance in metres (>= 0).

    Returns
    -------
    t_lo, t_hi : (P,) float64 ndarray
        The interval ends; empty where ``t_lo >= t_hi``.
    """
    px, py = a[:, 0], a[:, 1]
    dx, dy = a[:, 2] - px, a[:, 3] - py
    bx, by = b[:, 0], b[:, 1]
    ux, uy = b[:, 2] - bx, b[:, 3] - by
    lb = np.hypot(ux, uy)
    safe = lb > 0
    gx = np.where(safe, ux / np.where(safe, lb, 1.0), 1.0)
    gy = np.where(safe, uy / np.where(safe, lb, 1.0), 0.0)
    # The line in b's frame: s along b, n across it.
    s0 = (px - bx) * gx + (py - by) * gy
    ds = dx * gx + dy * gy
    n0 = -(px - bx) * gy + (py - by) * gx
    dn = -dx * gy + dy * gx
    zeros = np.zeros_like(px)
    ones = np.ones_like(px)
    r_lo, r_hi = _clip_interval(s0, ds, 0.0, lb, zeros, ones)
    r_lo, r_hi = _clip_interval(n0, dn, -tau, tau, r_lo, r_hi)
    d0_lo, d0_hi = _disk_interval(px, py, dx, dy, bx, by, tau)
    d1_lo, d1_hi = _disk_interval(px, py, dx, dy, b[:, 2], b[:, 3], tau)
    los = np.stack([r_lo, d0_lo, d1_lo])
    his = np.stack([r_hi, d0_hi, d1_hi])
    nonempty = his > los
    t_lo = np.where(nonempty, los, np.inf).min(axis=0)
    t_hi = np.where(nonempty, his, -np.inf).max(axis=0)
    return t_lo, t_hi


def length_within(segments, others, tau: float) -> np.ndarray:
    """Length of each segment lying within ``tau`` of any of ``others`` (exact).

    Candidates pairs come from a Shapely STRtree ``dwithin`` query; for each pair the
    covered parameter interval is :func:`capsule_intervals`; the intervals of a segment
    are merged (sorted sweep with a running maximum) and their total length returned.

    Parameters
    ----------
    segments : (M, 4) array_like
        Segments to measure, metres.
    others : (K, 4) array_like
        Segments to measure against, metres.
    tau : float
        Tolerance in metres (>= 0).

    Returns
    -------
    (M,) float64 ndarray
        Covered length per segment in metres (0 where nothing is near), for the rows of
        ``as_segments(segments)`` (non-finite rows dropped).
    """
    if tau < 0:
        raise ValueError(f"tau must be >= 0; got {tau}")
    return _lengths_within(as_segments(segments), as_segments(others), [tau])[0]


def _lengths_within(seg: np.ndarray, oth: np.ndarray, taus) -> list[np.ndarray]:
    """:func:`length_within` of finite ``seg`` and ``oth`` for each tau of ``taus``
    (>= 0), sharing the geometries and the STRtree between the taus."""
    lengths = segment_lengths(seg)
    if len(seg) == 0 or len(oth) == 0:
        return [np.zeros(len(seg)) for _ in taus]
    geoms_o = shapely.linestrings(oth.reshape(-1, 2, 2))
    geoms_s = shapely.linestrings(seg.reshape(-1, 2, 2))
    tree = shapely.STRtree(geoms_o)
    return [_length_within_tau(seg, oth, lengths, tree, geoms_s, tau) for tau in taus]


def _length_within_tau(seg, oth, lengths, tree, geoms_s, tau: float) -> np.ndarray:
    """:func:`length_within` at one tau, from ``oth``'s STRtree and ``seg``'s lines."""
    covered = np.zeros(len(seg))
    si, oi = tree.query(geoms_s, predicate="dwithin", distance=tau * (1 + 1e-9) + 1e-12)
    keep = lengths[si] > MIN_SEGMENT_M
    si, oi = si[keep], oi[keep]
    if len(si) == 0:
        return covered
    t_lo, t_hi = capsule_intervals(seg[si], oth[oi], tau)
    t_lo = np.clip(t_lo, 0.0, 1.0)
    t_hi = np.clip(t_hi, 0.0, 1.0)
    ok = t_hi > t_lo
    si, t_lo, t_hi = si[ok], t_lo[ok], t_hi[ok]
    if len(si) == 0:
        return covered
    order = np.lexsort((t_lo, si))
    si, t_lo, t_hi = si[order], t_lo[order], t_hi[order]
    # Offset each segment's intervals by 2 * index so one running max spans all groups.
    off = 2.0 * si
    run = np.maximum.accumulate(t_hi + off)
    prev = np.r_[-np.inf, run[:-1]] - off
    gain = np.maximum(0.0, t_hi - np.maximum(t_lo, prev))
    frac = np.bincount(si, weights=gain, minlength=len(seg))
    return np.minimum(frac, 1.0) * lengths


def sample_segments(segments, step_m: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """Points along segments at most ``step_m`` apart, with the length each stands for.

    Each segment of length L is cut into ``n = ceil(L / step_m)`` equal pieces and
    sampled at the pieces' centres, so the weights ``L / n`` sum to L exactly.

    Returns
    -------
    points : (S, 2) float64 ndarray
        Sample positions, metres.
    weights : (S,) float64 ndarray
        Length in metres represented by each sample.
    """
    if not step_m > 0:
        raise ValueError(f"step_m must be > 0; got {step_m}")
    seg = as_segments(segments)
    lengths = segment_lengths(seg)
    keep = lengths > MIN_SEGMENT_M
    seg, lengths = seg[keep], lengths[keep]
    if len(seg) == 0:
        return np.zeros((0, 2)), np.zeros(0)
    n = np.maximum(1, np.ceil(lengths / step_m - 1e-9).astype(np.int64))
    idx = np.repeat(np.arange(len(seg)), n)
    k = np.arange(len(idx)) - np.repeat(np.cumsum(n) - n, n)
    t = (k + 0.5) / n[idx]
    pts = seg[idx, :2] + t[:, None] * (seg[idx, 2:] - seg[idx, :2])
    return pts, (lengths / n)[idx]


#: Spacing (metres) of the points along segments whose KD-tree gives each query point an
#: upper bound of its distance to the nearest segment (:func:`nearest_distances`).
BOUND_STEP_M = 0.1
#: Radius of the first, short-range nearest-segment query (metres): most points are
#: this near a wall, the others are queried again without a limit.
NEAR_QUERY_M = 0.25
#: Query points per chunk of :func:`nearest_distances` (bounds its memory: the pairs of
#: a chunk are about this times the number of overlapping duplicates of a wall).
NEAREST_CHUNK = 4096


def _densify(seg: np.ndarray, step: float) -> np.ndarray:
    """Points along each segment, both ends included, at most ``step`` apart, ``(Q, 2)``."""
    n = np.maximum(1, np.ceil(segment_lengths(seg) / step).astype(np.int64))
    idx = np.repeat(np.arange(len(seg)), n + 1)
    k = np.arange(len(idx)) - np.repeat(np.cumsum(n + 1) - (n + 1), n + 1)
    t = k / n[idx]
    return seg[idx, :2] + t[:, None] * (seg[idx, 2:] - seg[idx, :2])


#: Longest piece (metres) of the segments in the STRtrees of :class:`_SegmentIndex`:
#: short pieces have tight bounding boxes (a long, slightly tilted wall's box is wide).
TREE_PIECE_M = 0.25
#: Reaches (metres) of the STRtrees of :class:`_SegmentIndex` over the pieces' boxes
#: grown by the reach: a point whose search radius is at most a reach finds its
#: candidates by a point query (no box to make per point). Wider radii use the
#: segments' own boxes and a box per point.
REACHES_M = (0.02, 0.1)


def _grown_boxes(pieces: np.ndarray, reach: float) -> np.ndarray:
    """The boxes of ``(P, 4)`` segment pieces grown by ``reach`` (and a relative 1e-6
    and 1e-9 m), as :func:`_box_diagonals`: a point within ``reach`` of a piece is in
    its box."""
    g = reach * (1 + 1e-6) + 1e-9
    return _box_diagonals(
        np.minimum(pieces[:, 0], pieces[:, 2]) - g, np.minimum(pieces[:, 1], pieces[:, 3]) - g,
        np.maximum(pieces[:, 0], pieces[:, 2]) + g, np.maximum(pieces[:, 1], pieces[:, 3]) + g,
    )


def _box_diagonals(xmin, ymin, xmax, ymax) -> np.ndarray:
    """Linestrings from ``(xmin, ymin)`` to ``(xmax, ymax)``: their envelopes are the
    boxes, all an STRtree query without predicate looks at (cheaper to make than
    ``shapely.box`` polygons)."""
    return shapely.linestrings(np.stack([xmin, ymin, xmax, ymax], axis=-1).reshape(-1, 2, 2))


#: Largest bound (metres) up to which :func:`_nearest_below` measures a point against
#: the segments within its bound directly, without the KD-tree's upper bound.
DIRECT_M = 1.0


class _SegmentIndex:
    """Search structures over a fixed set of ``(M, 4)`` segments, each built when first
    needed: a KD-tree (scipy ``cKDTree``) over points at most :data:`BOUND_STEP_M`
    apart along them, both ends included; Shapely STRtrees over the boxes of their
    pieces no longer than :data:`TREE_PIECE_M` grown by each of :data:`REACHES_M`;
    and an STRtree of the segments.

    For a query point at distance ``d`` from the nearest segment, the distance ``u``
    to the nearest KD-tree point bounds it: ``u - BOUND_STEP_M / 2 <= d <= u`` (every
    point of a segment is within half a step of a tree point).
    """

    def __init__(self, seg: np.ndarray):
        self.seg = seg
        self._kd = None
        self._tree = None
        self._pieces = None
        self._reach_trees: dict[float, object] = {}

    @property
    def kd(self):
        if self._kd is None and len(self.seg):
            from scipy.spatial import cKDTree

            self._kd = cKDTree(_densify(self.seg, BOUND_STEP_M))
        return self._kd

    @property
    def tree(self):
        """STRtree of the segments (queried with boxes, without predicate)."""
        if self._tree is None:
            self._tree = shapely.STRtree(shapely.linestrings(self.seg.reshape(-1, 2, 2)))
        return self._tree

    def reach_tree(self, reach: float):
        """STRtree of the pieces' boxes grown by ``reach`` (and a relative 1e-6): a
        point within ``reach`` of a segment lies in the grown box of one of its pieces.
        ``self._owner``: the segment of each piece."""
        if reach not in self._reach_trees:
            if self._pieces is None:
                self._pieces, self._owner = _split_long(self.seg, TREE_PIECE_M, return_owner=True)
            self._reach_trees[reach] = shapely.STRtree(_grown_boxes(self._pieces, reach))
        return self._reach_trees[reach]

    def upper(self, pts: np.ndarray, limit: float = np.inf) -> np.ndarray:
        """The upper bound ``u`` of each point's distance, metres; ``inf`` without
        segments and where ``u > limit`` (a faster query)."""
        if self.kd is None:
            return np.full(len(pts), np.inf)
        return self.kd.query(pts, k=1, distance_upper_bound=limit)[0]

    def exact(self, pts, ids, radius, geoms=None):
        """Exact distance (numpy) from ``pts[ids]`` to the nearest segment within
        ``radius`` (per point, with a relative margin of 1e-9 and 1e-9 m), ``inf``
        where none is; in chunks of :data:`NEAREST_CHUNK` points (``geoms``:
        ``shapely.points(pts)``, if made).

        The candidates are found by STRtree queries without predicate (boxes only): a
        point whose radius is at most a reach of :data:`REACHES_M` in the grown boxes
        of the pieces (:meth:`reach_tree`), the others by their square of half-side
        the radius in the segments' boxes. The candidates' distances are measured in
        numpy (:func:`floorscan.floorplan.plan.point_segment_dist2`, to the whole segment)
        and those beyond the radius dropped: the same minimum as measuring every
        segment within the radius.
        """
        radius = np.asarray(radius, dtype=np.float64)
        out = np.full(len(ids), np.inf)
        if len(ids) == 0 or len(self.seg) == 0:
            return out
        group = np.searchsorted(np.asarray(REACHES_M), radius, side="left")
        for level in range(len(REACHES_M) + 1):
            sel = np.flatnonzero(group == level)
            for start in range(0, len(sel), NEAREST_CHUNK):
                at = sel[start:start + NEAREST_CHUNK]
                p = pts[ids[at]]
                r = radius[at] * (1 + 1e-9) + 1e-9
                if level < len(REACHES_M):
                    g = shapely.points(p) if geoms is None else geoms[ids[at]]
                    pi, qi = self.reach_tree(REACHES_M[level]).query(g)
                else:
                    pi, qi = self.tree.query(_box_diagonals(p[:, 0] - r, p[:, 1] - r, p[:, 0] + r, p[:, 1] + r))
                if len(pi) == 0:
                    continue
                if len(pi) > 1 and not (pi[1:] >= pi[:-1]).all():
                    order = np.argsort(pi, kind="stable")
                    pi, qi = pi[order], qi[order]
                si = qi
                if level < len(REACHES_M):
                    si = self._owner[si]
                d = np.sqrt(point_segment_dist2(p[pi, 0], p[pi, 1], self.seg[si]))
                d[d > r[pi]] = np.inf
                first = np.flatnonzero(np.r_[True, pi[1:] != pi[:-1]])
                out[at[pi[first]]] = np.minimum.reduceat(d, first)
        return out


def _nearest_below(pts, index: _SegmentIndex, bound: np.ndarray, geoms=None) -> np.ndarray:
    """``min(bound, exact distance from each point to the nearest segment of index)``.

    Points farther than ``bound`` from the segments' bounding box keep ``bound``.
    Points with ``bound`` at most :data:`DIRECT_M` are measured against the segments
    within ``bound``. For the others (measured with the KD-tree), points whose lower bound
    ``u - BOUND_STEP_M / 2`` exceeds ``bound`` keep ``bound``; the rest are measured
    against the segments within ``min(u, bound)`` only (the nearest wall's stack of
    duplicates, not every segment nearby). ``geoms``: ``shapely.points(pts)``, if made.
    """
    out = np.array(bound, dtype=np.float64, copy=True)
    if len(pts) == 0 or len(index.seg) == 0:
        return out
    # The distance to the segments' bounding box is a lower bound: points farther from
    # it than their bound keep it.
    seg = index.seg
    gx = np.maximum(np.maximum(np.minimum(seg[:, 0], seg[:, 2]).min() - pts[:, 0], 0.0),
                    pts[:, 0] - np.maximum(seg[:, 0], seg[:, 2]).max())
    gy = np.maximum(np.maximum(np.minimum(seg[:, 1], seg[:, 3]).min() - pts[:, 1], 0.0),
                    pts[:, 1] - np.maximum(seg[:, 1], seg[:, 3]).max())
    open_ = np.hypot(gx, gy) <= out * (1 + 1e-9) + 1e-9
    close = open_ & (out <= DIRECT_M)
    ids = np.flatnonzero(close)
    if len(ids):
        out[ids] = np.minimum(out[ids], index.exact(pts, ids, out[ids], geoms))
    rest = np.flatnonzero(open_ & ~close)
    if len(rest) == 0:
        return out
    # Most points are near a wall: a short-range query first, the rest in full.
    near = NEAR_QUERY_M + 0.5 * BOUND_STEP_M
    u = index.upper(pts[rest], near)
    far = np.flatnonzero(np.isinf(u) & (out[rest] > near - 0.5 * BOUND_STEP_M))
    if len(far):
        u[far] = index.upper(pts[rest[far]])
    keep = u - 0.5 * BOUND_STEP_M <= out[rest] * (1 + 1e-9) + 1e-9
    todo, u = rest[keep], u[keep]
    if len(todo):
        d = index.exact(pts, todo, np.minimum(u, out[todo]), geoms)
        out[todo] = np.minimum(out[todo], d)
    return out


def _within(pts, index: _SegmentIndex, taus, hit: np.ndarray) -> np.ndarray:
    """Whether each point is within each tau of a segment of ``index``, or already was.

    ``hit`` is a ``(T, S)`` bool array (one row per tau), returned updated (a copy):
    the same as ``hit | (nearest_distances(pts, segments) <= tau)``; the points hit
    at every tau are not measured, the others against the segments within the largest
    tau only.
    """
    hit = np.array(hit, dtype=bool, copy=True)
    if len(pts) == 0 or len(index.seg) == 0 or len(taus) == 0:
        return hit
    ids = np.flatnonzero(~hit.all(axis=0))
    if len(ids):
        d = index.exact(pts, ids, np.full(len(ids), float(max(taus))))
        for t, tau in enumerate(taus):
            hit[t, ids] |= d <= tau
    return hit


def nearest_distances(points: np.ndarray, segments) -> np.ndarray:
    """Exact distance in metres from each ``(S, 2)`` point to the nearest segment.

    Each point gets an upper bound ``u`` of its distance from a KD-tree over points
    along the segments; the segments within ``u`` (candidates from Shapely STRtree
    box queries, :meth:`_SegmentIndex.exact`: the nearest wall's overlapping
    duplicates, not every segment nearby) are then measured exactly in numpy, in
    chunks of points.
    Walls from many scans overlap a hundredfold, and querying a fixed search square
    per point, or ``STRtree.query_nearest``, spends its time on them.

    Parameters
    ----------
    points : (S, 2) array_like
        Query points, metres.
    segments : (M, 4) array_like
        Segments ``x0, y0, x1, y1``, metres (non-finite rows dropped).

    Returns
    -------
    (S,) float64 ndarray
        Distances in metres, all ``inf`` when ``segments`` is empty.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    return _nearest_below(pts, _SegmentIndex(as_segments(segments)), np.full(len(pts), np.inf))


def _f1(p: float, r: float, has_inferred: bool, has_gt: bool) -> float:
    if not has_inferred and not has_gt:
        return math.nan
    if not has_inferred or not has_gt:
        return 0.0
    return 2 * p * r / (p + r) if (p + r) > 0 else 0.0


def tau_label(tau: float) -> str:
    """Column suffix for a tolerance: 0.05 -> ``"5cm"``, 0.025 -> ``"2.5cm"``."""
    return f"{round(tau * 100, 6):g}cm"


def dedupe_samples(points: np.ndarray, cell_m: float) -> np.ndarray:
    """Keep one sample per ``cell_m`` square cell (the first in input order).

    Walls from many scans overlap: a wall seen by 100 scans is 100 near-identical
    segments. Deduplicating the samples on a grid makes each place of the wall count
    once (up to the width of the stack of duplicates, a few cells).

    Returns
    -------
    (S', 2) float64 ndarray
        The kept samples, in input order.
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(pts) == 0:
        return pts.copy()
    key = np.floor(pts / cell_m).astype(np.int64)
    key -= key.min(axis=0)
    flat = key[:, 0] * (int(key[:, 1].max()) + 1) + key[:, 1]
    _, first = np.unique(flat, return_index=True)
    return pts[np.sort(first)]


def gt_samples(ground_truth, sample_step_m: float = 0.01) -> np.ndarray:
    """The deduplicated ground-truth samples of :func:`tolerance_metrics`, ``(S, 2)``."""
    return dedupe_samples(sample_segments(ground_truth, sample_step_m)[0], sample_step_m)


def tolerance_metrics(
    inferred, ground_truth, taus=(0.05, 0.10), sample_step_m: float = 0.01, samples=None
) -> dict[str, float]:
    """Precision (correctness), recall (completeness) and F1 of wall length within
    each tolerance, and the median distance from the ground truth to the inferred walls.

    Style of the ISPRS benchmark on indoor modelling (Khoshelham et al. 2017, 2018),
    applied to 2D wall segments; thesis Chapter 6 asks for "more robust error metrics".

    - precision at tau: inferred wall length within tau of a ground-truth segment over
      the inferred wall length, computed exactly (:func:`length_within`); overlapping
      inferred segments (the same wall seen by several scans) each count.
    - recall at tau: the ground truth is sampled every ``sample_step_m`` and the samples
      deduplicated on a ``sample_step_m`` grid (:func:`dedupe_samples`), so that a place
      of a wall counts once however many reference segments overlap there (real
      recordings' references are the overlapping walls of all scans; on the simulator's
      ground truth this changes nothing but the corners); recall is the fraction of
      these samples within tau of an inferred segment (exact distances).
    - median (mean) distance: over the same samples, metres.

    Parameters
    ----------
    inferred : (M, 4) array_like or DataFrame
        Inferred wall segments, metres.
    ground_truth : (K, 4) array_like or DataFrame
        Ground-truth (or reference) wall segments, metres.
    taus : sequence of float
        Tolerances in metres.
    sample_step_m : float
        Spacing and deduplication cell of the ground-truth samples, metres.
    samples : (S, 2) ndarray, optional
        ``gt_samples(ground_truth, sample_step_m)``, when already computed.

    Returns
    -------
    dict
        ``precision_<tau>``, ``recall_<tau>``, ``f1_<tau>`` for each tau (suffix from
        :func:`tau_label`, e.g. ``f1_5cm``); ``median_distance_m`` and
        ``mean_distance_m`` (NaN without inferred or ground-truth walls);
        ``inferred_length_m``, ``gt_length_m`` (sums of segment lengths) and
        ``n_gt_samples``. Empty sets: see the module docstring (precision NaN and F1 0
        with nothing inferred).
    """
    inf = as_segments(inferred)
    gt = as_segments(ground_truth)
    len_i = float(segment_lengths(inf).sum())
    len_g = float(segment_lengths(gt).sum())
    has_i, has_g = len_i > MIN_SEGMENT_M, len_g > MIN_SEGMENT_M
    pts = gt_samples(gt, sample_step_m) if samples is None else samples
    d = nearest_distances(pts, inf) if has_i else np.full(len(pts), np.inf)
    covered = {tau: float(length_within(inf, gt, tau).sum()) if has_i and has_g else 0.0 for tau in taus}
    return _tolerance_from(len_i, len_g, len(pts), d, covered, taus)


def _tolerance_from(len_i: float, len_g: float, n_pts: int, d: np.ndarray, covered: dict, taus) -> dict:
    """:func:`tolerance_metrics` from its parts: the inferred and ground-truth lengths,
    the samples' distances ``d`` to the inferred walls and the inferred length within
    each tau of the ground truth (``covered[tau]``, metres)."""
    has_i, has_g = len_i > MIN_SEGMENT_M, len_g > MIN_SEGMENT_M
    out: dict[str, float] = {
        "inferred_length_m": len_i,
        "gt_length_m": len_g,
        "n_gt_samples": float(n_pts),
    }
    for tau in taus:
        r = float(np.mean(d <= tau)) if has_g and n_pts else math.nan
        _set_prf(out, tau, covered[tau], len_i, r, has_i, has_g)
    if has_i and has_g and n_pts:
        out["median_distance_m"] = float(np.median(d))
        out["mean_distance_m"] = float(np.mean(d))
    else:
        out["median_distance_m"] = math.nan
        out["mean_distance_m"] = math.nan
    return out


def score_walls(
    inferred,
    ground_truth,
    grid: Grid,
    wall_width_m: float = 0.10,
    taus=(0.05, 0.10),
    sample_step_m: float = 0.01,
    gt_bitmap: np.ndarray | None = None,
    samples: np.ndarray | None = None,
) -> dict[str, float]:
    """All metrics of one inferred wall set: :func:`bitmap_metrics` on ``grid`` and
    :func:`tolerance_metrics`.

    ``gt_bitmap`` (the rasterized ground truth on ``grid``) and ``samples``
    (:func:`gt_samples`) may be passed to avoid recomputing them for every ordering
    and k.
    """
    if gt_bitmap is None:
        gt_bitmap = rasterize_segments(ground_truth, grid, wall_width_m)
    bi = rasterize_segments(inferred, grid, wall_width_m)
    out = bitmap_metrics(bi, gt_bitmap)
    out.update(tolerance_metrics(inferred, ground_truth, taus, sample_step_m, samples))
    return out


def _row_keys(seg: np.ndarray) -> list[bytes]:
    """The bytes of each ``(M, 4)`` float64 row: equal rows, equal keys."""
    return np.ascontiguousarray(seg, dtype=np.float64).view(np.dtype((np.void, 32))).ravel().tolist()


#: Reach (metres) of the wall-to-sample pairs that give the samples' nearest distances
#: (:class:`_SamplePairs`); samples farther from every wall are measured by
#: :func:`_nearest_below`.
PAIR_REACH_M = 0.1
#: Longest piece (metres) of the walls whose grown boxes find their samples in
#: :class:`_SamplePairs`.
PAIR_PIECE_M = 2.0


class _SamplePairs:
    """The ground-truth samples within ``reach`` of each wall, for walls met again and
    again: the runs of every ordering of one extractor are subsets of the same walls.

    A fixed ``(S, 2)`` sample set, an STRtree of its points and a cache ``{row key of
    a wall: (sample indices, distances)}``: every sample whose exact distance
    (numpy, :func:`floorscan.floorplan.plan.point_segment_dist2`) to the wall is at most
    ``reach``. Candidates are the samples in the boxes of the wall's pieces (no longer
    than :data:`PAIR_PIECE_M`) grown by ``reach``; a sample within ``reach`` of a wall
    is within ``reach`` of one of its pieces, hence in that piece's grown box.
    """

    def __init__(self, samples: np.ndarray, reach: float):
        self.samples = samples
        self.reach = float(reach)
        self.geoms = shapely.points(samples)
        self._x, self._y = samples[:, 0].copy(), samples[:, 1].copy()
        self._tree = None
        self.cache: dict[bytes, tuple[np.ndarray, np.ndarray]] = {}

    def of(self, walls: np.ndarray, keys: list[bytes]) -> tuple[np.ndarray, np.ndarray]:
        """``(sample indices, distances)`` of the pairs of the finite ``(M, 4)``
        ``walls`` (row keys ``keys``), concatenated; a sample may repeat."""
        cache = self.cache
        todo = [i for i, k in enumerate(keys) if k not in cache]
        if todo:
            self._measure(walls[todo], [keys[i] for i in todo])
        if not keys:
            return np.zeros(0, np.int64), np.zeros(0)
        parts = [cache[k] for k in keys]
        return np.concatenate([q[0] for q in parts]), np.concatenate([q[1] for q in parts])

    def _measure(self, seg: np.ndarray, keys: list[bytes]) -> None:
        if self._tree is None:
            self._tree = shapely.STRtree(self.geoms)
        pc, owner = _split_long(seg, PAIR_PIECE_M, return_owner=True)
        qi, si = self._tree.query(_grown_boxes(pc, self.reach))
        if len(qi) > 1 and not (qi[1:] >= qi[:-1]).all():
            order = np.argsort(qi, kind="stable")
            qi, si = qi[order], si[order]
        # One pair per (wall, sample): the piece holding the sample's closest point of
        # the wall (the sample is in that piece's box when within reach of the wall).
        # The projection and distance are point_segment_dist2's, from per-wall terms
        # looked up per piece: every candidate is measured (most are kept).
        n = np.bincount(owner, minlength=len(seg))
        rank = np.arange(len(pc)) - (np.cumsum(n) - n)[owner]  # of the piece in its wall
        ax, ay = seg[:, 0], seg[:, 1]
        dx, dy = seg[:, 2] - ax, seg[:, 3] - ay
        l2 = dx * dx + dy * dy
        axq, ayq, dxq, dyq, l2q, nq = (v[owner][qi] for v in (ax, ay, dx, dy, l2, n))
        px, py = self._x[si], self._y[si]
        with np.errstate(invalid="ignore", divide="ignore"):
            t = ((px - axq) * dxq + (py - ayq) * dyq) / l2q
        t = np.where(l2q > 0, np.clip(t, 0.0, 1.0), 0.0)
        ex = axq + t * dxq - px
        ey = ayq + t * dyq - py
        d = np.sqrt(ex * ex + ey * ey)
        piece = np.minimum(np.floor(t * nq).astype(np.int64), nq - 1)
        keep = np.flatnonzero((piece == rank[qi]) & (d <= self.reach))
        wi, si, d = owner[qi[keep]], si[keep].astype(np.int32), d[keep]
        bounds = np.searchsorted(wi, np.arange(len(seg) + 1))
        for j, k in enumerate(keys):
            self.cache[k] = (si[bounds[j]:bounds[j + 1]], d[bounds[j]:bounds[j + 1]])


class _GrowingWalls:
    """Metrics of a growing wall set: the walls of the first k scans of one ordering
    and extractor, for increasing k.

    The walls of k scans are a subset of those of more scans, and every metric is
    either a minimum over the walls (the samples' nearest distances), a union of them
    (the bitmap, the samples within tau) or a sum over them (the length within tau),
    so a larger set is scored from the smaller set's state and its new walls only;
    the result is that of :func:`score_walls` from scratch (exact minima and unions,
    sums in the same order up to the last bits). A set that is not a superset of the
    previous one is scored from scratch.

    The samples within :data:`PAIR_REACH_M` of a new wall take their distance from
    the wall's :class:`_SamplePairs` (the nearest wall of a sample within the reach
    of a wall is within it too); the samples no wall has come within reach of yet
    are measured by :func:`_nearest_below`. ``recall_all_<tau>`` takes the pairs
    within the largest tau of ``all_pairs``. The pairs and ``raster_cache``
    (``{row key: flat wall cells}``, see :func:`_raster_cells`) may be shared by the
    growing sets of one extractor (same samples, grid and wall width), so that a wall
    is measured and rasterized once for all orderings.

    ``samples`` (recall, distances) and ``all_samples`` (``recall_all_<tau>``, or
    None) are ground-truth samples (:func:`gt_samples`).
    """

    def __init__(self, gt, gt_bitmap, grid, wall_width_m, taus, samples, all_samples,
                 pairs, all_pairs, raster_cache):  # fmt: skip
        self.gt, self.grid, self.width, self.taus = gt, grid, wall_width_m, list(taus)
        self.gt_bitmap = gt_bitmap
        self.len_g = float(segment_lengths(gt).sum())
        self.samples = samples
        self.all_samples = all_samples
        self.pairs = pairs
        self.all_pairs = all_pairs
        self.raster_cache = raster_cache
        self.keys: set[bytes] | None = None
        self.covered: dict[float, dict[bytes, float]] = {tau: {} for tau in self.taus}

    def _reset(self):
        self.keys = set()
        self.d_near = np.full(len(self.samples), np.inf)
        self.d_far = np.full(len(self.samples), np.inf)
        self.d = np.full(len(self.samples), np.inf)
        if self.all_samples is not None:
            self.hit_all = np.zeros((len(self.taus), len(self.all_samples)), dtype=bool)
        self.bitmap = np.zeros(self.grid.shape, dtype=bool)

    def _wall_cells(self, add: np.ndarray, add_keys: list[bytes]) -> np.ndarray:
        """Flat bitmap cells of the walls ``add`` (rows keyed ``add_keys``), from the
        raster cache, rasterizing the walls it lacks."""
        cache = self.raster_cache
        todo = [i for i, k in enumerate(add_keys) if k not in cache]
        if todo:
            owner, flat = _raster_cells(add[todo], self.grid, self.width)  # owner ascending
            bounds = np.searchsorted(owner, np.arange(len(todo) + 1))
            flat = flat.astype(np.int32 if self.grid.nx * self.grid.ny < 2**31 else np.int64)
            for j, i in enumerate(todo):
                cache[add_keys[i]] = flat[bounds[j]:bounds[j + 1]]
        return np.concatenate([cache[k] for k in add_keys])

    def score(self, walls: np.ndarray) -> dict[str, float]:
        """:func:`score_walls` of ``(M, 4)`` finite ``walls`` (and ``recall_all_<tau>``
        against ``all_samples`` when given)."""
        keys = _row_keys(walls)
        cur = set(keys)
        if self.keys is None or not self.keys <= cur:
            self._reset()
        new = np.fromiter((k not in self.keys for k in keys), dtype=bool, count=len(keys))
        add = walls[new]
        if len(add):
            add_keys = [k for k, n in zip(keys, new) if n]
            si, d = self.pairs.of(add, add_keys)
            np.minimum.at(self.d_near, si, d)
            far = np.flatnonzero(np.isinf(self.d_near))
            if len(far):
                self.d_far[far] = _nearest_below(
                    self.samples[far], _SegmentIndex(add), self.d_far[far], self.pairs.geoms[far]
                )
            self.d = np.where(np.isinf(self.d_near), self.d_far, self.d_near)
            if self.all_samples is not None:
                si, d = self.all_pairs.of(add, add_keys)
                for t, tau in enumerate(self.taus):
                    self.hit_all[t, si[d <= tau]] = True
            self.bitmap.reshape(-1)[self._wall_cells(add, add_keys)] = True
            # Measured once per wall for every tau (the caches of the taus hold the
            # same walls), in the same batches as tau by tau: a wall's covered length
            # depends, in its last bits, on its row in the batch (the sweep's offset).
            todo = [i for i, k in enumerate(add_keys) if any(k not in self.covered[tau] for tau in self.taus)]
            if todo:
                covs = _lengths_within(add[todo], self.gt, self.taus)
                for tau, cov in zip(self.taus, covs):
                    self.covered[tau].update(zip((add_keys[i] for i in todo), cov.tolist()))
        self.keys = cur
        out = bitmap_metrics(self.bitmap, self.gt_bitmap)
        len_i = float(segment_lengths(walls).sum())
        has_i, has_g = len_i > MIN_SEGMENT_M, self.len_g > MIN_SEGMENT_M
        d = self.d if has_i else np.full(len(self.samples), np.inf)
        covered = {
            tau: float(np.array([self.covered[tau][k] for k in keys], dtype=np.float64).sum())
            if has_i and has_g else 0.0
            for tau in self.taus
        }  # fmt: skip
        out.update(_tolerance_from(len_i, self.len_g, len(self.samples), d, covered, self.taus))
        if self.all_samples is not None:
            n = len(self.all_samples)
            for t, tau in enumerate(self.taus):
                frac = float(np.mean(self.hit_all[t])) if len(walls) else 0.0
                out[f"recall_all_{tau_label(tau)}"] = frac if n else math.nan
        return out


def _recall_precision(inferred, gt, taus, samples, pairs=None) -> dict[str, float]:
    """``precision_<tau>``, ``recall_<tau>`` and ``f1_<tau>`` of :func:`tolerance_metrics`
    (same values), without the distances of the samples that tau does not need."""
    inf = as_segments(inferred)
    len_i = float(segment_lengths(inf).sum())
    len_g = float(segment_lengths(gt).sum())
    has_i, has_g = len_i > MIN_SEGMENT_M, len_g > MIN_SEGMENT_M
    hit = np.zeros((len(taus), len(samples)), dtype=bool)
    if has_i:
        if pairs is not None and pairs.samples is samples and max(taus) <= pairs.reach:
            # The samples near each face (:class:`_SamplePairs`; faces of plans of
            # several k recur): the same test as _within.
            si, d = pairs.of(inf, _row_keys(inf))
            for t, tau in enumerate(taus):
                hit[t, si[d <= tau]] = True
        else:
            hit = _within(samples, _SegmentIndex(inf), taus, hit)
    out: dict[str, float] = {}
    covs = _lengths_within(inf, as_segments(gt), taus) if has_i and has_g else None
    for t, tau in enumerate(taus):
        covered = float(covs[t].sum()) if has_i and has_g else 0.0
        r = float(np.mean(hit[t])) if has_g and len(samples) else math.nan
        _set_prf(out, tau, covered, len_i, r, has_i, has_g)
    return out


def _set_prf(out: dict, tau: float, covered_m: float, len_i: float, recall: float, has_i: bool, has_g: bool) -> None:
    """Set ``precision_<tau>`` (inferred length within tau of the ground truth over the
    inferred length; NaN without inferred walls, 0 without ground truth), ``recall_<tau>``
    and ``f1_<tau>`` in ``out``."""
    lab = tau_label(tau)
    p = (float(covered_m / len_i) if has_g else 0.0) if has_i else math.nan
    out[f"precision_{lab}"] = p
    out[f"recall_{lab}"] = recall
    out[f"f1_{lab}"] = _f1(p, recall, has_i, has_g)


# ----------------------------------------------------------------- dataset scoring

#: Values of the ``reference_kind`` column: what the inferred walls are scored against.
GROUND_TRUTH = "ground_truth"
REFERENCE = "reference"
#: Ground-truth feature kind of the observed parts of the faces (recall's reference).
OBSERVED_FACE = "observed_face"


def read_wall_faces(path, kind: str = "face") -> np.ndarray:
    """Ground-truth wall segments of ``kind`` from a ``walls.geojson`` (simulate stage).

    LineString and MultiLineString features whose property ``kind`` equals ``kind`` are
    split into their straight pieces.

    Returns
    -------
    (M, 4) float64 ndarray
        ``x0, y0, x1, y1`` in metres.

    Raises
    ------
    floorscan.core.io.InputError
        When the file is not a FeatureCollection or has no feature of ``kind``.
    """
    from floorscan.core.io import InputError

    seg = _wall_faces(_feature_collection(path), kind)
    if not len(seg):
        raise InputError(f"{path}: no LineString feature with property kind={kind!r}")
    return seg


def _feature_collection(path) -> dict:
    import json

    from floorscan.core.io import InputError

    with open(path, encoding="utf-8") as fh:
        doc = json.load(fh)
    if doc.get("type") != "FeatureCollection":
        raise InputError(f"{path}: expected a GeoJSON FeatureCollection, got {doc.get('type')!r}")
    return doc


def _wall_faces(doc: dict, kind: str) -> np.ndarray:
    """The straight pieces of the (Multi)LineString features of ``kind``, ``(M, 4)``."""
    lines: list = []
    for feat in doc.get("features", []):
        if (feat.get("properties") or {}).get("kind") != kind:
            continue
        geom = feat.get("geometry") or {}
        if geom.get("type") == "LineString":
            lines.append(geom["coordinates"])
        elif geom.get("type") == "MultiLineString":
            lines.extend(geom["coordinates"])
    # All vertices at once (x, y of each; a z is dropped), then the pieces between
    # consecutive vertices of a line.
    lines = [line for line in lines if len(line) >= 2]
    if not lines:
        return np.zeros((0, 4))
    xy = np.array([p[:2] for line in lines for p in line], dtype=np.float64).reshape(-1, 2)
    n = np.fromiter((len(line) for line in lines), dtype=np.int64, count=len(lines))
    end = np.cumsum(n)
    start = np.ones(len(xy), dtype=bool)
    start[end - 1] = False  # a line's last vertex starts no piece
    i = np.flatnonzero(start)
    return as_segments(np.column_stack([xy[i], xy[i + 1]]))


def _wall_count(doc: dict) -> int:
    props = [feat.get("properties") or {} for feat in doc.get("features", [])]
    ids = {p["wall_id"] for p in props if "wall_id" in p}
    if ids:
        return len(ids)
    return sum(p.get("kind", "wall") in ("axis", "wall") for p in props)


def floorplan_wall_count(path) -> int:
    """Number of walls in a merged floor plan ``.geojson`` (floorplan stage).

    The floor plan has features of kind ``axis`` (centre line) and ``footprint``
    (polygon) per wall, sharing a ``wall_id``: the count is the number of distinct
    ``wall_id``; without that property, the features of kind ``axis`` or ``wall`` (or
    without a kind).
    """
    return _wall_count(_feature_collection(path))


def floorplan_faces(path) -> np.ndarray:
    """The merged faces (``kind`` "face") of a floor plan ``.geojson``, ``(F, 4)``
    metres; empty when the plan has none (a plan without walls is valid)."""
    return _wall_faces(_feature_collection(path), "face")


def read_floorplan(path) -> tuple[np.ndarray, int]:
    """:func:`floorplan_faces` and :func:`floorplan_wall_count` of a floor plan
    ``.geojson``, from one read of the file."""
    doc = _feature_collection(path)
    return _wall_faces(doc, "face"), _wall_count(doc)


def k_scans(k_label: str, n_kept: int) -> int:
    """Number of scans behind ``k{k_label}``: ``min(k, n_kept)``, ``n_kept`` for "all"."""
    if str(k_label) == "all":
        return int(n_kept)
    return min(int(k_label), int(n_kept))


def score_dataset(
    runs: list[dict],
    references: dict[str, np.ndarray],
    reference_kind: str,
    cfg: dict,
    dataset: str = "",
    log=None,
    recall_references: dict[str, np.ndarray] | None = None,
    workers: int = 1,
):
    """Score every ordering x extractor x k of a dataset: one row per run.

    Parameters
    ----------
    runs : list of dict
        One per wall file, with keys ``ordering``, ``extractor``, ``k`` (label: "5" or
        "all"), ``walls`` (DataFrame with x0, y0, x1, y1, or the path of its Parquet
        table, read when the run is scored so that one run's walls are in memory at a
        time), ``n_kept`` (scans the ordering ranks, i.e. kept scans) and
        ``n_floorplan_walls`` (int or None); optionally ``floorplan_faces``, the merged
        faces of the run's floor plan (``(F, 4)`` segments), scored with the same
        tolerance metrics into the ``plan_precision_<tau>``, ``plan_recall_<tau>`` and
        ``plan_f1_<tau>`` columns (one wall per wall: the product a user opens, not the
        per-scan segments); or ``floorplan``, the path of the plan's ``.geojson``, from
        which both are read when the run is scored. Runs of one ordering and extractor
        in increasing k (each wall set containing the previous one) are scored
        incrementally, from the new walls only, with the same result. The last run of
        an ordering whose walls (as a set) and plan faces equal an earlier run's of
        its extractor (every ordering's ``k = all``) takes that run's metrics.
    references : dict
        ``{extractor: (M, 4) segments}``: what each extractor's walls are scored
        against. On synthetic datasets every extractor maps to the same ground truth
        (``sim/walls.geojson`` faces); on real ones to the walls of that extractor from
        all kept scans.
    reference_kind : {"ground_truth", "reference"}
        Written to the ``reference_kind`` column.
    cfg : dict
        The ``score`` config section: ``cell_m``, ``wall_width_m``, ``margin_m``,
        ``taus_m``, ``sample_step_m``.
    dataset : str
        Written to the ``dataset`` column.
    recall_references : dict, optional
        ``{extractor: (M, 4) segments}`` that recall (completeness) and the distances
        are measured against instead of ``references``: on synthetic datasets the
        observed faces (:func:`floorscan.sim.building.observed_faces`; thesis 5.2, walls
        never visible from the LIDAR cannot be recovered). Precision and the bitmap
        metrics stay against ``references``, and ``recall_all_<tau>`` gives recall
        against ``references`` too.
    workers : int
        Processes (:func:`floorscan.core.runtime.map_in_processes`; the score rule's
        ``threads``) over which the orderings x extractors are split. Each ordering and
        extractor is scored in one process, so the table does not depend on it
        (tested); the walls are then best given as paths (runs are pickled to the
        workers). The per-run lines are logged when all are scored.

    Returns
    -------
    pandas.DataFrame
        One row per run, sorted by ordering, extractor and number of scans; its
        :data:`SCORE_TIME` column is the seconds the run took (not a metric).

    Raises
    ------
    ValueError
        When ``reference_kind`` is unknown, a run's extractor has no reference, or the
        references are all empty (no grid can be built).
    """
    import pandas as pd

    if reference_kind not in (GROUND_TRUTH, REFERENCE):
        raise ValueError(f"reference_kind must be {GROUND_TRUTH!r} or {REFERENCE!r}")
    groups: dict[tuple, list[dict]] = {}
    for run in runs:
        groups.setdefault((run["ordering"], run["extractor"]), []).append(run)
    keys = list(groups)
    n = max(1, min(int(workers), len(keys)))
    args = (references, reference_kind, cfg, dataset, recall_references)
    if n == 1:
        rows = _score_rows(runs, *args)
    else:
        from floorscan.core.runtime import map_in_processes

        shares = [[r for key in keys[w::n] for r in groups[key]] for w in range(n)]
        rows = [row for part in map_in_processes(_score_rows, [(share, *args) for share in shares], n) for row in part]
    df = sort_scores(pd.DataFrame(rows))
    if log is not None:
        tau = tau_label(cfg["taus_m"][0])
        for r in rows:
            log.info("%s %s k=%s: %d segments, F1@%s %.3f, wall CM %.3f", r["ordering"], r["extractor"], r["k"],
                     r["n_segments"], tau, r[f"f1_{tau}"], r["wall_correct_match"])
    return df


def sort_scores(table):
    """Metrics rows in the order of :func:`score_dataset`: by ordering, extractor,
    number of scans and k label (a new frame, index 0..n-1). Concatenated tables of
    parts of a dataset's runs (the ``score_runs`` jobs, one per extractor) sorted so
    equal the table of one :func:`score_dataset` call over all runs.

    Parameters
    ----------
    table : pandas.DataFrame
        Rows of :func:`score_dataset` (empty allowed).

    Returns
    -------
    pandas.DataFrame
    """
    if not table.empty:
        table = table.sort_values(["ordering", "extractor", "n_scans", "k"], kind="stable")
    return table.reset_index(drop=True)


def _score_rows(runs, references, reference_kind, cfg, dataset, recall_references) -> list[dict]:
    """The rows of :func:`score_dataset` of ``runs``, in run order (one process)."""
    import time

    refs = {e: as_segments(s) for e, s in references.items()}
    nonempty = [s for s in refs.values() if len(s)]
    if not nonempty:
        raise ValueError(f"dataset {dataset!r}: every {reference_kind} wall set is empty")
    # One grid for the whole dataset: the bounds of all references plus the margin.
    grid = grid_for(np.vstack(nonempty), cfg["cell_m"], cfg["margin_m"])
    ref_bitmaps: dict[str, np.ndarray] = {}
    ref_samples: dict[str, np.ndarray] = {}
    all_samples: dict[str, np.ndarray] = {}
    growing: dict[tuple[str, str], _GrowingWalls] = {}
    sample_pairs: dict[str, _SamplePairs] = {}
    all_pairs: dict[str, _SamplePairs | None] = {}
    raster_caches: dict[str, dict] = {}
    # A run with the same walls and floor plan as an earlier one of its extractor (every
    # ordering's k = all: the same scans) has its metrics; when no larger k of its
    # ordering follows, they are taken, not computed again from its growing state.
    last_of_group = {(r["ordering"], r["extractor"]): n for n, r in enumerate(runs)}
    scored: dict[tuple, dict] = {}
    rows = []
    for n_run, run in enumerate(runs):
        ext = run["extractor"]
        if ext not in refs:
            raise ValueError(f"no {reference_kind} walls for extractor {ext!r}")
        if recall_references is not None and ext not in recall_references:
            raise ValueError(f"no recall reference walls for extractor {ext!r}")
        if ext not in ref_bitmaps:
            ref_bitmaps[ext] = rasterize_segments(refs[ext], grid, cfg["wall_width_m"])
            all_samples[ext] = gt_samples(refs[ext], cfg["sample_step_m"])
            ref_samples[ext] = (
                all_samples[ext] if recall_references is None
                else gt_samples(as_segments(recall_references[ext]), cfg["sample_step_m"])
            )
            # Shared by the orderings of an extractor: its samples' pairs and wall cells.
            sample_pairs[ext] = _SamplePairs(ref_samples[ext], PAIR_REACH_M)
            all_pairs[ext] = (
                None if recall_references is None else _SamplePairs(all_samples[ext], max(cfg["taus_m"]))
            )
            raster_caches[ext] = {}
        t0 = time.perf_counter()
        walls = run["walls"]
        if isinstance(walls, (str, os.PathLike)):
            from floorscan.core.io import read_table

            walls = read_table(walls, columns=["x0", "y0", "x1", "y1"])
        walls = as_segments(walls)
        plan_path = run.get("floorplan")
        if plan_path is not None:
            plan, nfp = read_floorplan(plan_path)
        else:
            plan, nfp = run.get("floorplan_faces"), run.get("n_floorplan_walls")
        same = (ext, _set_digest(walls), None if plan is None else _set_digest(as_segments(plan)))
        key = (run["ordering"], ext)
        m = scored.get(same) if last_of_group[key] == n_run else None
        if m is not None:
            rows.append(_score_row(run, dataset, reference_kind, walls, nfp, grid, cfg, dict(m), t0))
            continue
        if key not in growing:
            # One state per ordering and extractor: its k grow in the order of runs.
            growing[key] = _GrowingWalls(
                refs[ext], ref_bitmaps[ext], grid, cfg["wall_width_m"], cfg["taus_m"],
                ref_samples[ext],
                None if recall_references is None else all_samples[ext],
                pairs=sample_pairs[ext], all_pairs=all_pairs[ext], raster_cache=raster_caches[ext],
            )  # fmt: skip
        m = growing[key].score(walls)
        if plan is not None:
            pm = _recall_precision(plan, refs[ext], cfg["taus_m"], ref_samples[ext], pairs=sample_pairs[ext])
            for tau in cfg["taus_m"]:
                for what in ("precision", "recall", "f1"):
                    m[f"plan_{what}_{tau_label(tau)}"] = pm[f"{what}_{tau_label(tau)}"]
        scored.setdefault(same, dict(m))
        rows.append(_score_row(run, dataset, reference_kind, walls, nfp, grid, cfg, m, t0))
    return rows


#: Column of :func:`score_dataset`'s rows: the seconds the run took to score. For the
#: stage's log; the score stage leaves it out of ``metrics.parquet`` (the same input
#: gives the same file).
SCORE_TIME = "score_time_s"


def _score_row(run, dataset, reference_kind, walls, nfp, grid, cfg, m: dict, t0: float) -> dict:
    import time

    n_kept = int(run["n_kept"])
    n_scans = k_scans(run["k"], n_kept)
    return {
        "dataset": dataset,
        "reference_kind": reference_kind,
        "ordering": run["ordering"],
        "extractor": run["extractor"],
        "k": str(run["k"]),
        "n_scans": n_scans,
        "n_scans_kept": n_kept,
        "scan_fraction": n_scans / n_kept if n_kept else math.nan,
        "n_segments": int(len(walls)),
        "n_floorplan_walls": -1 if nfp is None else int(nfp),
        "cell_m": float(grid.cell_m),
        "wall_width_m": float(cfg["wall_width_m"]),
        **m,
        SCORE_TIME: time.perf_counter() - t0,
    }


def _set_digest(segments: np.ndarray) -> bytes:
    """Digest of a set of segments (rows in any order)."""
    import hashlib

    seg = np.ascontiguousarray(segments, dtype=np.float64).reshape(-1, 4)
    seg = seg[np.lexsort(seg.T[::-1])] if len(seg) else seg
    return hashlib.sha256(seg.tobytes()).digest()


def summarize(metrics, tau: float = 0.05, levels=(0.95, 0.99)):
    """The smallest k reaching a fraction of the all-scan F1, per ordering and extractor.

    For each ordering and extractor, with ``F1_all`` the F1 at ``tau`` of ``k = all``,
    the first k of the configured grid (in increasing number of scans) whose F1 is at
    least ``level * F1_all``; the number of scans behind it, that number as a fraction
    of the scans kept and the reduction factor ``n_scans_kept / n_scans`` (the thesis's
    claim is a tenfold reduction). F1 is not monotone in k: this is the first k that
    reaches the level, not a k after which it stays above.

    Parameters
    ----------
    metrics : pandas.DataFrame
        Output of :func:`score_dataset`.
    tau : float
        Tolerance of the F1 used, metres.
    levels : sequence of float
        Fractions of the all-scan F1.

    Returns
    -------
    pandas.DataFrame
        Columns ``dataset, reference_kind, ordering, extractor, n_scans_kept, f1_all``
        and per level L (as a percentage p): ``k_p``, ``n_scans_p``, ``fraction_p``,
        ``reduction_p`` (``k_p`` empty, the others NaN, when F1_all is NaN or 0);
        with the ``map_*`` columns of the reference map in ``metrics``, also
        ``map_completeness_all``, ``map_correctness_all``, ``map_f1_all``: the all-scan
        floor plan against the reference map at ``tau``.
    """
    import pandas as pd

    col = f"f1_{tau_label(tau)}"
    if col not in metrics.columns:
        raise ValueError(f"metrics lack column {col!r}; is tau {tau} in score.taus_m?")
    rows = []
    for (ordering, extractor), g in metrics.groupby(["ordering", "extractor"], sort=True):
        g = g.sort_values("n_scans", kind="stable")
        all_rows = g[g["k"] == "all"]
        f1_all = float(all_rows[col].iloc[0]) if len(all_rows) else math.nan
        n_kept = int(g["n_scans_kept"].iloc[0])
        row = {
            "dataset": g["dataset"].iloc[0],
            "reference_kind": g["reference_kind"].iloc[0],
            "ordering": ordering,
            "extractor": extractor,
            "n_scans_kept": n_kept,
            "f1_all": f1_all,
        }
        # the all-scan floor plan against the reference map (occupancy grid), when scored
        for m in ("completeness", "correctness", "f1"):
            c = f"map_{m}_{tau_label(tau)}"
            if c in g.columns:
                row[f"map_{m}_all"] = float(all_rows[c].iloc[0]) if len(all_rows) else math.nan
        for level in levels:
            p = f"{round(level * 100, 6):g}"
            hit = g[g[col] >= level * f1_all - 1e-12] if f1_all > 0 else g.iloc[0:0]
            if len(hit):
                n = int(hit["n_scans"].iloc[0])
                row[f"k_{p}"] = str(hit["k"].iloc[0])
                row[f"n_scans_{p}"] = n
                row[f"fraction_{p}"] = n / n_kept if n_kept else math.nan
                row[f"reduction_{p}"] = n_kept / n if n else math.nan
            else:
                row[f"k_{p}"] = ""
                row[f"n_scans_{p}"] = -1
                row[f"fraction_{p}"] = math.nan
                row[f"reduction_{p}"] = math.nan
        rows.append(row)
    return pd.DataFrame(rows)


def summary_header(dataset: str, verdict=None, recording=None, mode: str = "") -> list[str]:
    """The lines that head ``summary.md``: the title, the registration's verdict
    (``verdict``: :meth:`floorscan.register.consistency.Verdict.as_dict`) and what the
    recording was found to be (``recording``: ingest's detection; ``mode``: the register
    mode used; :func:`floorscan.ingest.describe_recording`)."""
    from floorscan.ingest import describe_recording

    lines = [f"# Scan reduction summary: {dataset}" if dataset else "# Scan reduction summary", ""]
    if verdict:
        lines += [f"**Verdict: {verdict['line']}**", ""]
    if recording or mode:
        lines += [f"Recording: {describe_recording(recording or {}, mode)}.", ""]
    return lines


def summary_markdown(
    summary, tau: float = 0.05, levels=(0.95, 0.99), verdict=None, recording=None, mode: str = ""
) -> str:
    """The summary table as Markdown, headed by :func:`summary_header`, then what F1 is
    measured against. An F1 from fewer than
    :data:`floorscan.register.consistency.FEW_SCANS` kept scans is marked."""
    ds = "" if summary.empty else summary["dataset"].iloc[0]
    head = "\n".join(summary_header(ds, verdict, recording, mode))
    if summary.empty:
        return head + "No scored runs.\n"
    return head + grid_summary_markdown(summary, tau, levels)


def grid_summary_markdown(summary, tau: float = 0.05, levels=(0.95, 0.99)) -> str:
    """The body of :func:`summary_markdown`: the table of :func:`summarize` (the k of
    the configured grid) and the all-scan plans against the reference map."""
    from floorscan.register.consistency import FEW_SCANS

    kind = summary["reference_kind"].iloc[0]
    against = (
        "the simulator's ground-truth walls"
        if kind == GROUND_TRUTH
        else "the reference: walls of the same extractor from all kept scans (not ground truth)"
    )
    lines = [
        f"F1 at tau = {tau_label(tau)} against {against}. For each level, the smallest k "
        "of the configured grid whose F1 reaches that fraction of the all-scan F1, the "
        "scans it uses as a fraction of the scans kept, and the reduction factor.",
        "",
    ]
    head = ["ordering", "extractor", "scans kept", "F1 all"]
    for level in levels:
        p = f"{round(level * 100, 6):g}"
        head += [f"k {p}%", f"fraction {p}%", f"reduction {p}%"]
    lines.append("| " + " | ".join(head) + " |")
    lines.append("|" + "---|" * len(head))
    for _, r in summary.iterrows():
        f1_all = f"{r['f1_all']:.3f}"
        if int(r["n_scans_kept"]) < FEW_SCANS:
            f1_all += f" (warning: from {int(r['n_scans_kept'])} scans)"
        cells = [r["ordering"], r["extractor"], str(r["n_scans_kept"]), f1_all]
        for level in levels:
            p = f"{round(level * 100, 6):g}"
            k = r[f"k_{p}"] or "-"
            if k not in ("-", "all"):
                k = f"{k} ({r[f'n_scans_{p}']})" if str(r[f"n_scans_{p}"]) != k else k
            cells += [k, f"{r[f'fraction_{p}']:.3f}", f"{r[f'reduction_{p}']:.1f}x"]
        lines.append("| " + " | ".join(cells) + " |")
    if "map_f1_all" in summary.columns:
        lines += [
            "",
            f"The floor plan from all kept scans against the reference map (occupancy grid of all kept "
            f"scans, its structure cells; `reference/map.pgm`), at tau = {tau_label(tau)}: completeness "
            "(structure within tau of a plan face), correctness (plan face length within tau of structure), F1.",
            "",
            "| ordering | extractor | completeness | correctness | F1 |",
            "|---|---|---|---|---|",
        ]
        for _, r in summary.iterrows():
            lines.append(
                f"| {r['ordering']} | {r['extractor']} | {r['map_completeness_all']:.3f} | "
                f"{r['map_correctness_all']:.3f} | {r['map_f1_all']:.3f} |"
            )
    return "\n".join(lines) + "\n"


def load_recall_references(kind: str, extractors, ground_truth=None, recall_kind: str = OBSERVED_FACE):
    """What recall is measured against, ``{extractor: (M, 4) segments}``, or None.

    Synthetic datasets (``kind`` ground_truth): the ``recall_kind`` features of
    ``walls.geojson`` (``observed_face``: the parts of the faces the recording saw,
    :func:`floorscan.sim.building.observed_faces`); ``face`` gives None (recall against
    all faces, like precision). Real recordings: None (the reference is already made
    of what the scans saw).
    """
    if kind != GROUND_TRUTH or recall_kind == "face":
        return None
    seg = read_wall_faces(ground_truth, kind=recall_kind)
    return {e: seg for e in extractors}


def load_references(kind: str, extractors, ground_truth=None, reference_paths=()) -> dict:
    """The walls each extractor is scored against, as ``{extractor: (M, 4) segments}``.

    ``kind`` ground_truth: the ``face`` features of the simulator's ``walls.geojson``
    (``ground_truth``), the same for every extractor. Otherwise the reference: the
    walls of each extractor from all kept scans (``reference_paths``, one Parquet
    table per extractor, in the order of ``extractors``).
    """
    extractors = list(extractors)
    if kind == GROUND_TRUTH:
        gt = read_wall_faces(ground_truth, kind="face")
        return {e: gt for e in extractors}
    from floorscan.core.io import read_table

    return {e: as_segments(read_table(p)) for e, p in zip(extractors, reference_paths)}

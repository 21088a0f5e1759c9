"""Scan orderings: greedy maximum coverage and its baselines (thesis section 3.3).

Every ordering ranks all scans; along each ordering the covered area is measured the
same way (the union of the scans' cluster hulls, :mod:`floorscan.select.hulls`), so the
orderings are comparable (thesis Fig. 5.6):

``cluster_hull``
    Greedy maximum area of the union of cluster hulls (thesis Algorithm 1).
``convex_hull``
    The same greedy on one convex hull per scan (the naive coverage, Fig. 3.2a).
``random``
    A seeded permutation.
``sequential``
    Recording order.
``motion_filter``
    The SLAM practice (Cartographer's ``MotionFilter``): a scan is kept when, since
    the last kept scan, the scanner moved more than ``max_distance_m``, turned more
    than ``max_angle_rad`` or more than ``max_time_s`` passed; the first scan is
    kept. Kept scans in recording order, then the never-kept ones in recording order.

The greedy
----------
Round ``t`` adds the scan ``j`` maximising ``area(U_t ∪ c_j)``, i.e. the gain
``area(c_j \\ U_t)``, where ``U_t`` is the union of the chosen scans' coverage
``c``. Ties go to the lowest ``scan_id`` (Algorithm 1's strict ``>`` keeps the first
index). Scans with zero coverage area (fewer than 3 points, collinear, empty) never
enter the greedy: they are ranked last, in ``scan_id`` order.

Coverage raster. Areas are counted on a raster of square cells of ``raster_m``
(default 5 cm) anchored at the map origin: a scan covers the cells whose centre lies in
its coverage polygon (Shapely geometry rasterised once, vectorised), ``U`` is a boolean
grid, a gain is the number of the scan's cells not yet in ``U`` times ``raster_m**2``.
Why not exact polygon overlays: hulls of neighbouring scans share nearly collinear wall
edges, and GEOS needs 0.05-5 ms per difference of such a piece against the growing
union (measured); 5000 scans need ~10^5 evaluations. On the raster an evaluation is a
gather over ~10^4 cells (~20 us) and, gains being integers, comparisons are exact: the
reference and the lazy greedy agree by construction, with no float tie tolerance. The
raster area differs from the polygon area by at most about half a cell along the
boundary; :func:`greedy_exact` (literal Algorithm 1 on Shapely unions) checks that
the raster greedy picks the same scans (tests).

:func:`greedy_reference` is the plain Algorithm 1: every round recomputes every
remaining candidate's gain against the current union. :func:`greedy_coverage` is the
production greedy, lazy evaluation (Minoux 1978): coverage is monotone submodular, so
a gain computed in an earlier round is an upper bound of the current one.

Speed (issue 8), exact: a covered cell stays covered, so both greedies drop the cells
found covered from what they gather next time (the reference from the remaining
candidates' cells laid end to end, the lazy greedy per scan once half of a scan's
cells are covered); the rasteriser orders a row's crossings by a stable sort of
(scan, row) and a swap per pair instead of a three-key ``lexsort``.
"""

from __future__ import annotations

import heapq
import time
from dataclasses import asdict, dataclass, fields
from typing import Mapping, Sequence

import numpy as np
import pandas as pd
import pyarrow as pa
import shapely

ORDERINGS = ("cluster_hull", "convex_hull", "random", "sequential", "motion_filter")

#: ``orderings/{ordering}.parquet``
ORDERING = pa.schema(
    [
        ("rank", pa.int32()),
        ("scan_id", pa.int32()),
        ("covered_area_m2", pa.float64()),
        ("gain_m2", pa.float64()),
    ]
)

#: Coverage fractions of the summary columns ``k_90, k_95, k_99``.
TARGET_FRACTIONS = (0.90, 0.95, 0.99)

#: ``orderings/summary.parquet``: per ordering the number of scans reaching 90/95/99 %
#: of its final covered area. No timing: the same input gives the same file (the time
#: to compute each ordering is in the select stage's log).
SUMMARY = pa.schema(
    [
        ("ordering", pa.string()),
        ("n_scans", pa.int32()),
        ("n_zero_area", pa.int32()),
        ("final_area_m2", pa.float64()),
        ("k_90", pa.int32()),
        ("k_95", pa.int32()),
        ("k_99", pa.int32()),
    ]
)


@dataclass(frozen=True)
class SelectParams:
    """Parameters of the ``select`` stage (``workflow/schemas/select.schema.yaml``).

    Attributes
    ----------
    raster_m : float
        Cell side of the coverage raster, metres.
    seed : int
        Seed of the ``random`` ordering.
    motion_max_distance_m : float
        Motion filter: keep a scan once the scanner moved more than this, metres.
    motion_max_angle_deg : float
        Motion filter: ... or turned more than this, degrees.
    motion_max_time_s : float
        Motion filter: ... or more than this passed, seconds.
    """

    raster_m: float = 0.05
    seed: int = 0
    motion_max_distance_m: float = 0.2
    motion_max_angle_deg: float = 1.0
    motion_max_time_s: float = 5.0

    def __post_init__(self) -> None:
        if not self.raster_m > 0:
            raise ValueError(f"select.raster_m must be > 0, got {self.raster_m}")
        for name in ("motion_max_distance_m", "motion_max_angle_deg", "motion_max_time_s"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"select.{name} must be >= 0, got {getattr(self, name)}")

    @classmethod
    def from_config(cls, cfg: Mapping | None) -> "SelectParams":
        """Build from the stage's config dict; unknown keys raise ``ValueError``.

        ``figure_*`` keys belong to :class:`floorscan.figures.selection.FigureParams`,
        ``coverage`` to :class:`floorscan.select.coverage.CoverageParams`, and
        ``default_ordering``, ``k`` and ``k_coverage`` to the recommended selection
        (:mod:`floorscan.select.deliverables`); they are skipped here.
        """
        cfg = {
            k: v for k, v in dict(cfg or {}).items()
            if not k.startswith("figure_") and k not in ("coverage", "default_ordering", "k", "k_coverage")
        }  # fmt: skip
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(cfg) - names)
        if unknown:
            raise ValueError(f"unknown select config keys {unknown}; expected {sorted(names)}")
        return cls(**cfg)

    def as_dict(self) -> dict:
        return asdict(self)


# ----------------------------------------------------------------------------------
# Coverage on a raster
# ----------------------------------------------------------------------------------
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
    ValueError
        When the grid would exceed 2**31 cells (use a coarser ``raster_m``).
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
        if self.nx * self.ny >= 2**31:
            raise ValueError(
                f"coverage raster of {self.nx} x {self.ny} cells at {r} m is too large; "
                "raise select.raster_m"
            )
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
        """Flat cell indices (row * nx + col) covered by scan ``j``."""
        return self.cells[self.start[j] : self.stop[j]]

    def gains(self, scans: Sequence[int] | np.ndarray) -> np.ndarray:
        """Cells each scan would add to the current union; (len(scans),) int64."""
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
        the array bookkeeping: the lazy greedy evaluates one scan at a time)."""
        a, b = self.start[j], self.stop[j]
        return int(b - a) - int(np.count_nonzero(self.covered[self.cells[a:b]]))

    def add(self, j: int) -> None:
        """Add scan ``j``'s cells to the union."""
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
    starts, _, size = _segments(ks)
    two = starts[size == 2]
    swap = two[xs[two] > xs[two + 1]]
    order[swap], order[swap + 1] = order[swap + 1], order[swap].copy()
    long = size > 2
    if long.any():
        sub = np.repeat(starts[long], size[long]) + (np.arange(int(size[long].sum())) -
                                                       np.repeat(np.cumsum(size[long]) - size[long], size[long]))
        order[sub] = order[sub][np.lexsort((xs[sub], ks[sub]))]
    return order


def _result(scan_ids: np.ndarray, order: Sequence[int], gain_cells: Sequence[int], cell_m2: float) -> pd.DataFrame:
    g = np.asarray(gain_cells, dtype=np.int64)
    return pd.DataFrame(
        {
            "rank": np.arange(len(order), dtype=np.int32),
            "scan_id": scan_ids[np.asarray(order, dtype=np.int64)].astype(np.int32),
            "covered_area_m2": np.cumsum(g) * cell_m2,
            "gain_m2": g * cell_m2,
        }
    )


def _prepare(scan_ids, geometries, raster_m, raster=None):
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


def _zero_tail(ids: np.ndarray, cov: RasterCoverage) -> list[int]:
    zero = np.flatnonzero(cov.counts == 0)
    return zero[np.argsort(ids[zero], kind="stable")].tolist()


def _cells_of_scans(cov: RasterCoverage, scans: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cells of ``scans`` laid end to end and the position in ``scans`` of the
    scan of each cell."""
    counts = cov.counts[scans]
    offs = np.cumsum(counts) - counts
    idx = np.repeat(cov.start[scans] - offs, counts) + np.arange(int(counts.sum()))
    return cov.cells[idx], np.repeat(np.arange(len(scans)), counts)


def _segments(seg: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Start of each run of equal values of the non-decreasing ``seg``, its value
    and its length."""
    starts = np.flatnonzero(np.r_[True, seg[1:] != seg[:-1]]) if len(seg) else np.zeros(0, np.int64)
    return starts, seg[starts], np.diff(np.r_[starts, len(seg)])


def greedy_reference(scan_ids: Sequence[int], geometries: Sequence, raster_m: float = 0.05) -> pd.DataFrame:
    """Plain greedy maximum coverage (thesis Algorithm 1): the reference.

    Every round recomputes, for every remaining candidate, the area of the union
    of the chosen scans and the candidate (as the candidate's gain over the union)
    and takes the largest; ties go to the lowest scan_id. O(S^2) evaluations.

    Parameters
    ----------
    scan_ids : (S,) int
        Unique scan ids.
    geometries : (S,) Shapely Polygon / MultiPolygon
        Coverage of each scan (map frame, metres). Scans with no covered cell
        (empty, < 3 points, collinear, smaller than a cell) are ranked last by id.
    raster_m : float
        Coverage raster cell side, metres.

    Returns
    -------
    DataFrame
        ``rank`` int32, ``scan_id`` int32, ``covered_area_m2`` (cumulative) and
        ``gain_m2`` float64: all S scans.
    """
    ids, cov = _prepare(scan_ids, geometries, raster_m)
    remaining = np.flatnonzero(cov.counts > 0)
    remaining = remaining[np.argsort(ids[remaining], kind="stable")]  # ascending id
    order, gains = [], []
    # every round recomputes every remaining candidate's gain against the union: one
    # gather over the candidates' cells laid end to end. A covered cell stays covered,
    # so the cells already covered and the chosen candidates are dropped from that
    # array whenever they are half of it (instead of indexing the remaining cells
    # anew every round); a dropped cell adds 0 to every gain, so the gains are exact.
    cand = remaining
    cells, seg = _cells_of_scans(cov, cand)
    starts, owners, lens = _segments(seg)
    alive = np.ones(len(cand), dtype=bool)
    n_alive = len(cand)
    while n_alive:
        g = np.zeros(len(cand), dtype=np.int64)
        if len(cells):
            g[owners] = lens - np.add.reduceat(cov.covered[cells], starts, dtype=np.int64)
        g[~alive] = -1
        i = int(np.argmax(g))  # first maximum = lowest scan_id (ascending order)
        j = int(cand[i])
        order.append(j)
        gains.append(int(g[i]))
        cov.add(j)
        alive[i] = False
        n_alive -= 1
        # cells to keep: at most the alive candidates' gains this round
        if n_alive and 2 * int(g[alive].sum()) <= len(cells):
            keep = alive[seg]
            keep &= ~cov.covered[cells]
            renum = np.cumsum(alive) - 1
            cells, seg, cand = cells[keep], renum[seg[keep]], cand[alive]
            starts, owners, lens = _segments(seg)
            alive = np.ones(len(cand), dtype=bool)
    zero = _zero_tail(ids, cov)
    return _result(ids, order + zero, gains + [0] * len(zero), raster_m**2)


def greedy_coverage(
    scan_ids: Sequence[int],
    geometries: Sequence,
    raster_m: float = 0.05,
    stats: dict | None = None,
    raster: RasterCoverage | None = None,
) -> pd.DataFrame:
    """Greedy maximum coverage with lazy evaluation: the ordering of
    :func:`greedy_reference`, far faster (production greedy of the ``select`` stage).

    Parameters and returns as :func:`greedy_reference`; ``stats``, when given, is
    filled with ``evaluations`` (candidate gains computed) and ``rounds``;
    ``raster``, when given, is the :class:`RasterCoverage` of ``geometries`` at
    ``raster_m``, reused instead of rasterising again (its union is emptied first).

    Notes
    -----
    Lazy greedy (Minoux 1978; Krause and Golovin 2014): coverage is monotone
    submodular, so a gain computed in an earlier round bounds the current gain from
    above. Candidates sit in a heap keyed by (-bound, scan_id). The top is popped;
    if its bound was computed in this round it is chosen, else its gain is
    recomputed and it is pushed back. A chosen top has gain >= every other bound,
    and on equal gain a lower scan_id would sit above it, so the choice is the
    reference's (maximum gain, lowest scan_id). Gains are integer cell counts, so
    the comparison is exact and the two greedies return identical orderings and
    gains.
    """
    ids, cov = _prepare(scan_ids, geometries, raster_m, raster)
    active = np.flatnonzero(cov.counts > 0)
    heap = [(-int(cov.counts[j]), int(ids[j]), int(j), 0) for j in active]  # round-0 gains are exact
    heapq.heapify(heap)
    order, gains = [], []
    live: dict[int, np.ndarray] = {}
    evaluations, rnd = len(active), 0
    while heap:
        neg, sid, j, stamp = heap[0]
        if stamp == rnd:
            heapq.heappop(heap)
            order.append(j)
            gains.append(-neg)
            cov.add(j)
            rnd += 1
            continue
        # the scan's cells not covered at its last evaluation (covered ones stay so)
        cells = live.get(j)
        if cells is None:
            cells = cov.cells_of(j)
        hit = cov.covered[cells]
        g = len(cells) - int(np.count_nonzero(hit))
        if 2 * g <= len(cells):
            live[j] = cells[~hit]
        evaluations += 1
        heapq.heapreplace(heap, (-g, sid, j, rnd))
    zero = _zero_tail(ids, cov)
    if stats is not None:
        stats.update(evaluations=evaluations, rounds=rnd)
    return _result(ids, order + zero, gains + [0] * len(zero), raster_m**2)


def greedy_exact(
    scan_ids: Sequence[int], geometries: Sequence, max_scans: int | None = None, tie_tol_m2: float = 1e-9
) -> pd.DataFrame:
    """Thesis Algorithm 1 literally, on exact Shapely polygon unions (validation only).

    Every round computes ``area(U ∪ c_j)`` with Shapely for every remaining
    candidate; the largest wins, candidates within ``tie_tol_m2`` of it are tied and
    the lowest scan_id wins. Slow (overlays of a union that grows to thousands of
    vertices); used to check that the raster greedy picks the same scans.

    Parameters
    ----------
    scan_ids, geometries
        As :func:`greedy_reference`.
    max_scans : int, optional
        Stop after this many picks (default: all scans with positive area).
    tie_tol_m2 : float
        Tie tolerance, m^2.

    Returns
    -------
    DataFrame
        ``rank, scan_id, covered_area_m2, gain_m2`` of the picked scans only.
    """
    ids = np.asarray(scan_ids, dtype=np.int64)
    geoms = np.asarray(geometries, dtype=object)
    area = shapely.area(geoms)
    remaining = np.flatnonzero(area > 0)
    remaining = remaining[np.argsort(ids[remaining], kind="stable")]
    limit = len(remaining) if max_scans is None else min(max_scans, len(remaining))
    union = shapely.Polygon()
    covered = 0.0
    order, gains = [], []
    while len(order) < limit:
        pot = shapely.area(shapely.union(union, geoms[remaining]))
        i = int(np.flatnonzero(pot >= pot.max() - tie_tol_m2)[0])
        j = int(remaining[i])
        union = shapely.union(union, geoms[j])
        order.append(j)
        gains.append(float(pot[i]) - covered)
        covered = float(pot[i])
        remaining = np.delete(remaining, i)
    g = np.asarray(gains)
    return pd.DataFrame(
        {
            "rank": np.arange(len(order), dtype=np.int32),
            "scan_id": ids[np.asarray(order, dtype=np.int64)].astype(np.int32),
            "covered_area_m2": np.cumsum(g),
            "gain_m2": g,
        }
    )


def with_hull_coverage(orderings: Mapping[str, pd.DataFrame], hulls: pd.DataFrame, scan_ids, raster_m: float) -> dict:
    """The orderings with the hull area they cover along the way (``covered_area_m2``,
    ``gain_m2`` of :func:`coverage_along`), for the orderings whose tables lack it (the
    coverage orderings, which rank by their own objective), so that every ordering is
    compared on the same curve (thesis Fig. 5.6).

    Parameters
    ----------
    orderings : mapping of str to DataFrame
        Ordering tables (``rank, scan_id``, ...).
    hulls : DataFrame
        ``hulls.parquet`` (the cluster hulls of the kept scans).
    scan_ids : (S,) int
        The kept scans.
    raster_m : float
        Coverage raster cell side, metres.

    Returns
    -------
    dict of str to DataFrame
        The same tables; those without ``covered_area_m2`` get both columns (the other
        columns kept, rows in rank order).
    """
    from floorscan.select.hulls import scan_coverage

    missing = [name for name, o in orderings.items() if "covered_area_m2" not in o.columns]
    out = dict(orderings)
    if not missing:
        return out
    ids, geoms = scan_coverage(hulls, scan_ids)
    raster = RasterCoverage(geoms, raster_m)
    for name in missing:
        o = orderings[name].sort_values("rank", kind="stable").reset_index(drop=True)
        along = coverage_along(ids, geoms, o["scan_id"].to_numpy(), raster_m, raster=raster)
        out[name] = o.assign(covered_area_m2=along["covered_area_m2"].to_numpy(), gain_m2=along["gain_m2"].to_numpy())
    return out

def coverage_along(
    scan_ids: Sequence[int],
    geometries: Sequence,
    order: Sequence[int],
    raster_m: float = 0.05,
    raster: RasterCoverage | None = None,
) -> pd.DataFrame:
    """Cumulative covered area along a given ordering.

    Parameters
    ----------
    scan_ids : (S,) int
        Unique scan ids.
    geometries : (S,) Shapely geometries
        Coverage of each scan, metres.
    order : (S,) int
        A permutation of ``scan_ids`` (ids, not positions).
    raster_m : float
        Coverage raster cell side, metres.
    raster : RasterCoverage, optional
        The raster of ``geometries`` at ``raster_m`` to reuse (its union is emptied).

    Returns
    -------
    DataFrame
        ``rank, scan_id, covered_area_m2, gain_m2``.

    Raises
    ------
    ValueError
        When ``order`` is not a permutation of ``scan_ids``, or ``raster`` is of other
        scans or another cell size.
    """
    ids, cov = _prepare(scan_ids, geometries, raster_m, raster)
    order = np.asarray(order, dtype=np.int64)
    pos = np.searchsorted(np.sort(ids), order)
    srt = np.argsort(ids, kind="stable")
    if len(order) != len(ids) or np.any(pos >= len(ids)) or not np.array_equal(np.sort(order), np.sort(ids)):
        raise ValueError("order must be a permutation of scan_ids")
    positions = srt[pos]
    gains = []
    for j in positions.tolist():
        gains.append(cov.gain(j))
        cov.add(j)
    return _result(ids, positions, gains, raster_m**2)


# ----------------------------------------------------------------------------------
# Baseline orderings
# ----------------------------------------------------------------------------------
def random_order(scan_ids: Sequence[int], seed: int) -> np.ndarray:
    """A seeded random permutation of ``scan_ids`` (sorted first, so the result
    depends only on the set and the seed). (S,) int64."""
    ids = np.sort(np.asarray(scan_ids, dtype=np.int64))
    return np.random.default_rng(seed).permutation(ids)


def sequential_order(scan_ids: Sequence[int], t_ns: Sequence[int] | None = None) -> np.ndarray:
    """Recording order: ascending ``t_ns`` (ties: scan_id), or scan_id when no times."""
    ids = np.asarray(scan_ids, dtype=np.int64)
    if t_ns is None:
        return np.sort(ids)
    return ids[np.lexsort((ids, np.asarray(t_ns, dtype=np.int64)))]


def motion_filter_mask(
    t_ns: Sequence[int],
    x_m: Sequence[float],
    y_m: Sequence[float],
    yaw_rad: Sequence[float],
    max_distance_m: float = 0.2,
    max_angle_rad: float = np.deg2rad(1.0),
    max_time_s: float = 5.0,
) -> np.ndarray:
    """Which scans a motion filter keeps (Cartographer ``MotionFilter``).

    Parameters
    ----------
    t_ns : (S,) int
        Scan times, ns, in recording order.
    x_m, y_m : (S,) float
        Scanner position in the map frame, metres.
    yaw_rad : (S,) float
        Heading, radians CCW from +x.
    max_distance_m, max_angle_rad, max_time_s : float
        Cartographer defaults 0.2 m, 1 degree, 5 s.

    Returns
    -------
    kept : (S,) bool ndarray
        The first scan with a finite pose is kept; a later scan is kept when, since
        the last kept scan, the time passed, the distance moved or the absolute
        wrapped yaw change is strictly greater than its threshold (Cartographer's
        ``IsSimilar`` drops a scan when all three are ``<=``). Scans with a NaN pose
        are never kept.

    Notes
    -----
    Sequential by nature (each decision depends on the last kept scan); a loop of
    S simple float steps.
    """
    t = np.asarray(t_ns, dtype=np.int64)
    x = np.asarray(x_m, dtype=np.float64)
    y = np.asarray(y_m, dtype=np.float64)
    a = np.asarray(yaw_rad, dtype=np.float64)
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(a)
    kept = np.zeros(len(t), dtype=bool)
    last = -1
    max_t_ns = max_time_s * 1e9
    for i in range(len(t)):
        if not ok[i]:
            continue
        if last < 0:
            kept[i] = True
            last = i
            continue
        dyaw = abs((a[i] - a[last] + np.pi) % (2 * np.pi) - np.pi)
        if (
            (t[i] - t[last]) > max_t_ns
            or np.hypot(x[i] - x[last], y[i] - y[last]) > max_distance_m
            or dyaw > max_angle_rad
        ):
            kept[i] = True
            last = i
    return kept


def motion_filter_order(poses: pd.DataFrame, **thresholds) -> np.ndarray:
    """Motion-filter ordering: kept scans in recording order, then the rest.

    Parameters
    ----------
    poses : DataFrame
        ``scan_id, t_ns, x_m, y_m, yaw_rad`` (e.g. the kept rows of
        ``registration.parquet``).
    **thresholds
        ``max_distance_m``, ``max_angle_rad``, ``max_time_s`` of
        :func:`motion_filter_mask`.

    Returns
    -------
    (S,) int64 scan ids.
    """
    p = poses.sort_values(["t_ns", "scan_id"], kind="stable")
    kept = motion_filter_mask(p["t_ns"], p["x_m"], p["y_m"], p["yaw_rad"], **thresholds)
    ids = p["scan_id"].to_numpy(dtype=np.int64)
    return np.r_[ids[kept], ids[~kept]]


# ----------------------------------------------------------------------------------
# Coverage targets and "the first k scans"
# ----------------------------------------------------------------------------------
def k_for_fraction(ordering: pd.DataFrame, fraction: float) -> int:
    """Smallest number of scans whose cumulative covered area reaches
    ``fraction`` of the ordering's final covered area (0 for an empty ordering or
    zero final area).

    Raises ``ValueError`` unless ``0 < fraction <= 1``.
    """
    if not 0 < fraction <= 1:
        raise ValueError(f"fraction must be in (0, 1], got {fraction}")
    cov = ordering["covered_area_m2"].to_numpy(dtype=np.float64)
    if len(cov) == 0 or cov[-1] <= 0:
        return 0
    # cumulative area is non-decreasing; tiny slack for float rounding of the sum
    target = fraction * cov[-1] * (1 - 1e-12)
    return int(np.argmax(cov >= target)) + 1


def first_k(ordering: pd.DataFrame, count: int | None = None, fraction: float | None = None) -> np.ndarray:
    """The first scans of an ordering, by count or by coverage fraction.

    Parameters
    ----------
    ordering : DataFrame
        ``rank, scan_id, covered_area_m2`` (an ``orderings/*.parquet``).
    count : int, optional
        Take this many scans (all when larger than the ordering).
    fraction : float, optional
        Take the fewest scans reaching this fraction of the final covered area.

    Returns
    -------
    (k,) int64 scan ids, in rank order.

    Raises
    ------
    ValueError
        Unless exactly one of ``count`` / ``fraction`` is given, or ``count < 0``.
    """
    if (count is None) == (fraction is None):
        raise ValueError("give exactly one of count or fraction")
    o = ordering.sort_values("rank", kind="stable")
    if count is not None:
        if count < 0:
            raise ValueError(f"count must be >= 0, got {count}")
        k = int(count)
    else:
        k = k_for_fraction(o, fraction)
    return o["scan_id"].to_numpy(dtype=np.int64)[:k]


def summarize(orderings: Mapping[str, pd.DataFrame], seconds: Mapping[str, float] | None = None,
              zero_area: int = 0) -> pd.DataFrame:
    """Per ordering the k reaching 90/95/99 % of its final covered area (Fig. 5.6).

    Returns a frame of the :data:`SUMMARY` columns and ``seconds``, the time to compute
    each ordering (``seconds``; NaN when not given), for the log: ``write_table(summary,
    path, schema=SUMMARY)`` leaves it out of the file.
    """
    rows = []
    for name, o in orderings.items():
        cov = o["covered_area_m2"].to_numpy()
        rows.append(
            {
                "ordering": name,
                "n_scans": len(o),
                "n_zero_area": zero_area,
                "final_area_m2": float(cov[-1]) if len(cov) else 0.0,
                **{f"k_{round(f * 100)}": k_for_fraction(o, f) for f in TARGET_FRACTIONS},
                "seconds": float((seconds or {}).get(name, np.nan)),
            }
        )
    return pd.DataFrame(rows, columns=[*SUMMARY.names, "seconds"])


# ----------------------------------------------------------------------------------
# The select stage
# ----------------------------------------------------------------------------------
def select_orderings(
    cluster_geometries: tuple[np.ndarray, np.ndarray],
    convex_geometries: tuple[np.ndarray, np.ndarray],
    poses: pd.DataFrame,
    params: SelectParams = SelectParams(),
) -> tuple[dict[str, pd.DataFrame], pd.DataFrame]:
    """All five orderings of the kept scans and their summary.

    Parameters
    ----------
    cluster_geometries : (scan_ids, geometries)
        Cluster-hull coverage per scan (:func:`floorscan.select.hulls.scan_coverage`).
    convex_geometries : (scan_ids, geometries)
        Convex-hull coverage per scan, the same scan ids.
    poses : DataFrame
        ``scan_id, t_ns, x_m, y_m, yaw_rad`` of at least these scans (registration).
    params : SelectParams

    Returns
    -------
    orderings : dict name -> DataFrame (``rank, scan_id, covered_area_m2, gain_m2``),
        covered area always of the cluster-hull union, so orderings are comparable.
    summary : DataFrame of the :data:`SUMMARY` columns and ``seconds`` (:func:`summarize`).

    Raises
    ------
    ValueError
        When the convex and cluster scan ids differ or a scan has no pose row.
    """
    ids, geoms = (np.asarray(a) for a in cluster_geometries)
    cids, cgeoms = (np.asarray(a) for a in convex_geometries)
    if not np.array_equal(np.sort(ids), np.sort(cids)):
        raise ValueError("hulls and convex hulls cover different scans")
    cg = dict(zip(cids.tolist(), cgeoms))
    cgeoms = np.array([cg[int(s)] for s in ids], dtype=object)
    p = poses.set_index("scan_id")
    missing = sorted(set(ids.tolist()) - set(p.index.tolist()))
    if missing:
        raise ValueError(f"registration: no row for scans {missing[:10]} (of {len(missing)})")
    p = p.loc[ids].reset_index()
    res = params.raster_m
    out, secs = {}, {}
    t0 = time.perf_counter()
    raster = RasterCoverage(geoms, res)  # once for the five orderings
    out["cluster_hull"] = greedy_coverage(ids, geoms, res, raster=raster)
    secs["cluster_hull"] = time.perf_counter() - t0
    fixed = {}
    t0 = time.perf_counter()
    fixed["convex_hull"] = greedy_coverage(ids, cgeoms, res)["scan_id"].to_numpy()
    secs["convex_hull"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    fixed["random"] = random_order(ids, params.seed)
    secs["random"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    fixed["sequential"] = sequential_order(p["scan_id"], p["t_ns"])
    secs["sequential"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    fixed["motion_filter"] = motion_filter_order(
        p,
        max_distance_m=params.motion_max_distance_m,
        max_angle_rad=np.deg2rad(params.motion_max_angle_deg),
        max_time_s=params.motion_max_time_s,
    )
    secs["motion_filter"] = time.perf_counter() - t0
    for name, order in fixed.items():
        out[name] = coverage_along(ids, geoms, order, res, raster=raster)
    area = shapely.area(geoms) if len(geoms) else np.zeros(0)
    return {k: out[k] for k in ORDERINGS}, summarize(
        {k: out[k] for k in ORDERINGS}, secs, zero_area=int((area <= 0).sum())
    )


def select_stage(
    hulls: pd.DataFrame, convex: pd.DataFrame, registration: pd.DataFrame, params: SelectParams = SelectParams()
) -> tuple[dict[str, pd.DataFrame], pd.DataFrame]:
    """The ``select`` stage on its input tables.

    Parameters
    ----------
    hulls, convex : DataFrame
        ``hulls.parquet`` and ``convex_hulls.parquet`` (geometry as WKB or Shapely).
    registration : DataFrame
        ``registration.parquet`` (``scan_id, t_ns, kept, x_m, y_m, yaw_rad``).
    params : SelectParams

    Returns
    -------
    As :func:`select_orderings`: every kept scan ranked in each ordering.

    Raises
    ------
    KeyError
        When a required column is missing (the message names the table).
    """
    from floorscan.select.hulls import kept_scan_ids, scan_coverage

    need = ("scan_id", "t_ns", "kept", "x_m", "y_m", "yaw_rad")
    missing = [c for c in need if c not in registration.columns]
    if missing:
        raise KeyError(f"registration.parquet: columns {missing} missing; expected {list(need)}")
    for name, df in (("hulls.parquet", hulls), ("convex_hulls.parquet", convex)):
        miss = [c for c in ("scan_id", "geometry") if c not in df.columns]
        if miss:
            raise KeyError(f"{name}: columns {miss} missing; expected scan_id, cluster, geometry, area_m2")
    ids = kept_scan_ids(registration)
    cluster_geoms = scan_coverage(hulls, ids)
    convex_geoms = scan_coverage(convex, ids)
    poses = registration[registration["kept"].to_numpy(dtype=bool)]
    return select_orderings(cluster_geoms, convex_geoms, poses, params)

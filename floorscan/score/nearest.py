"""Exact distances from points to the nearest of a set of segments: recall (the ISPRS
benchmark's *completeness*; Khoshelham et al. 2017, 2018) and the median distance are
read from the distances of the ground-truth samples to the inferred walls.

:func:`nearest_distances` gives each point an upper bound of its distance from a
KD-tree (scipy ``cKDTree``) over points along the segments, then measures exactly, in
numpy (:func:`floorscan.core.geometry.point_segment_dist2`), the segments within that
bound only, found by Shapely STRtree box queries (:class:`SegmentIndex`): the nearest
wall's overlapping duplicates, not every segment nearby. Points farther than
:data:`NEAR_QUERY_M` from every segment are measured by cells of points instead
(:meth:`SegmentIndex.far`): the segments that can be nearest to some point of a cell
lie in an annulus around the cell's own nearest distance. :func:`nearest_below` lowers
given bounds (a growing wall set keeps its samples' distances and measures
only its new walls), :func:`pairs_within` tests the tolerances directly.
"""

from __future__ import annotations

import numpy as np
import shapely

from floorscan.core.geometry import point_segment_dist2
from floorscan.core.grid import ranks_in_runs
from floorscan.score.segments import densify
from floorscan.core.segments import split_long, as_segments

#: Spacing (metres) of the points along segments whose KD-tree gives each query point an
#: upper bound of its distance to the nearest segment (:func:`nearest_distances`).
BOUND_STEP_M = 0.1
#: Radius of the first, short-range nearest-segment query (metres): most points are
#: this near a wall, the others are queried again without a limit.
NEAR_QUERY_M = 0.25
#: Query points per chunk of :func:`nearest_distances` (bounds its memory: the pairs of
#: a chunk are about this times the number of overlapping duplicates of a wall).
NEAREST_CHUNK = 4096
#: Longest piece (metres) of the segments in the STRtrees of :class:`SegmentIndex`:
#: short pieces have tight bounding boxes (a long, slightly tilted wall's box is wide).
TREE_PIECE_M = 0.25
#: Reaches (metres) of the STRtrees of :class:`SegmentIndex` over the pieces' boxes
#: grown by the reach: a point whose search radius is at most a reach finds its
#: candidates by a point query (no box to make per point). Wider radii use the
#: segments' own boxes and a box per point.
REACHES_M = (0.02, 0.1)


def grown_boxes(pieces: np.ndarray, reach: float) -> np.ndarray:
    """The boxes of segment pieces grown by ``reach`` (and a relative 1e-6 and 1e-9 m),
    as :func:`_box_diagonals`: a point within ``reach`` of a piece is in its box.

    Parameters
    ----------
    pieces : (P, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    reach : float
        Metres.

    Returns
    -------
    (P,) object ndarray of shapely LineString
        Each box's diagonal (its envelope is the box).
    """
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


#: Side (metres) of the square cells in which :meth:`SegmentIndex.far` groups the points
#: far from every segment: the annulus of candidates around a cell's nearest distance
#: is twice its half-diagonal wide, so smaller cells have fewer candidates per point
#: and more cells to query (0.25 m: the fastest of 0.25, 0.5 and 1 m on a 200 m
#: building's million samples).
FAR_CELL_M = 0.25
#: Point-segment pairs measured at once by :meth:`SegmentIndex.far` (bounds its memory).
FAR_CHUNK_PAIRS = 4_000_000
#: Largest bound (metres) up to which :func:`nearest_below` measures a point against
#: the segments within its bound directly, without the KD-tree's upper bound.
DIRECT_M = 1.0


class SegmentIndex:
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

            self._kd = cKDTree(densify(self.seg, BOUND_STEP_M))
        return self._kd

    @property
    def tree(self):
        """STRtree of the segments (queried with boxes, without predicate)."""
        if self._tree is None:
            self._tree = shapely.STRtree(shapely.linestrings(self.seg.reshape(-1, 2, 2)))
        return self._tree

    def reach_tree(self, reach: float):
        """STRtree of the pieces' boxes grown by ``reach`` (and a relative 1e-6): a point
        within ``reach`` of a segment lies in the grown box of one of its pieces
        (``self._owner``: the segment of each piece). Cached per ``reach``.

        Parameters
        ----------
        reach : float
            Metres.

        Returns
        -------
        shapely.STRtree
        """
        if reach not in self._reach_trees:
            if self._pieces is None:
                self._pieces, self._owner = split_long(self.seg, TREE_PIECE_M, return_owner=True)
            self._reach_trees[reach] = shapely.STRtree(grown_boxes(self._pieces, reach))
        return self._reach_trees[reach]

    def upper(self, pts: np.ndarray, limit: float = np.inf) -> np.ndarray:
        """An upper bound of each point's distance to the segments (KD-tree of their
        samples).

        Parameters
        ----------
        pts : (N, 2) float ndarray
            Metres.
        limit : float
            Metres; beyond it the query stops.

        Returns
        -------
        (N,) float64 ndarray
            Metres; ``inf`` without segments and where the bound exceeds ``limit``.
        """
        if self.kd is None:
            return np.full(len(pts), np.inf)
        return self.kd.query(pts, k=1, distance_upper_bound=limit)[0]

    def exact(self, pts, ids, radius, geoms=None):
        """Exact distance (numpy) from ``pts[ids]`` to the nearest segment within
        ``radius`` (per point, with a relative margin of 1e-9 and 1e-9 m); in chunks of
        :data:`NEAREST_CHUNK` points.

        The candidates are found by STRtree queries without predicate (boxes only): a
        point whose radius is at most a reach of :data:`REACHES_M` in the grown boxes
        of the pieces (:meth:`reach_tree`), the others by their square of half-side
        the radius in the segments' boxes. The candidates' distances are measured in
        numpy (:func:`floorscan.core.geometry.point_segment_dist2`, to the whole segment)
        and those beyond the radius dropped: the same minimum as measuring every
        segment within the radius.

        Parameters
        ----------
        pts : (N, 2) float ndarray
            Metres.
        ids : (K,) int ndarray
            The points to measure.
        radius : (K,) float ndarray
            Metres.
        geoms : (N,) object ndarray, optional
            ``shapely.points(pts)``, if made.

        Returns
        -------
        (K,) float64 ndarray
            Metres; ``inf`` where no segment is within the radius.
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

    def far(self, pts: np.ndarray, ids: np.ndarray, bound: np.ndarray) -> np.ndarray:
        """Exact distance (numpy) from ``pts[ids]`` to the nearest segment, where it is
        below ``bound``, by cells of points: a branch and bound over square cells of
        :data:`FAR_CELL_M`.

        A cell's points lie within ``rho`` (half the diagonal of their box) of its
        centre ``c``, and ``c`` is ``dc`` from its nearest segment (GEOS
        ``query_nearest``). Each point is then within ``dc + rho`` of a segment, so the
        segment nearest to it is within ``dc + 2 rho`` of ``c``, and within ``b + rho``
        of ``c`` if it is nearer than the point's bound ``b``: the segments within the
        smaller radius of the centre (GEOS ``dwithin``, with a relative margin of 1e-9
        and 1e-6 m) are measured against every point of the cell (numpy,
        :func:`floorscan.core.geometry.point_segment_dist2`), in chunks of
        :data:`FAR_CHUNK_PAIRS` pairs. The minimum over these candidates is the minimum
        over all segments, computed by the same arithmetic as :meth:`exact`'s.

        For points far from the segments (a sample of a wall no scan has seen yet),
        where a square or a KD-tree bound around each point holds every segment
        nearby, and the nearest wall's duplicates lie in one annulus. Parameters as
        :meth:`exact`, with ``bound`` ((K,) metres, ``inf`` allowed) for ``radius``;
        returns ``min(bound, distance)``, (K,) float64 metres, a new array.
        """
        out = np.array(bound, dtype=np.float64, copy=True)
        if len(ids) == 0 or len(self.seg) == 0:
            return out
        p = pts[ids]
        key = np.floor(p / FAR_CELL_M).astype(np.int64)
        order = np.lexsort((key[:, 1], key[:, 0]))
        ks = key[order]
        starts = np.flatnonzero(np.r_[True, (ks[1:] != ks[:-1]).any(axis=1)])
        counts = np.diff(np.r_[starts, len(order)])
        ps = p[order]
        lo, hi = np.minimum.reduceat(ps, starts, axis=0), np.maximum.reduceat(ps, starts, axis=0)
        centre, rho = (lo + hi) / 2, np.hypot(*(hi - lo).T) / 2
        cells = shapely.points(centre)
        (ci, _), dc = self.tree.query_nearest(cells, return_distance=True, all_matches=False)
        d_cell = np.full(len(starts), np.inf)
        d_cell[ci] = dc
        radius = np.minimum(d_cell + 2 * rho, np.maximum.reduceat(out[order], starts) + rho)
        qc, qs = self.tree.query(cells, predicate="dwithin", distance=radius * (1 + 1e-9) + 1e-6)
        if len(qc) > 1 and not (qc[1:] >= qc[:-1]).all():
            by_cell = np.argsort(qc, kind="stable")
            qc, qs = qc[by_cell], qs[by_cell]
        n_cand = np.bincount(qc, minlength=len(starts))
        first_cand = np.cumsum(n_cand) - n_cand
        n_pairs = counts * n_cand
        cum = np.cumsum(n_pairs)
        c0 = 0
        while c0 < len(starts):  # chunks of whole cells
            c1 = max(int(np.searchsorted(cum, (cum[c0 - 1] if c0 else 0) + FAR_CHUNK_PAIRS, side="right")), c0 + 1)
            chunk = np.arange(c0, c1)
            chunk = chunk[n_cand[chunk] > 0]
            c0 = c1
            if not len(chunk):
                continue
            # the pairs (point, candidate), point after point within each cell
            n = n_pairs[chunk]
            cell = np.repeat(chunk, n)
            k = ranks_in_runs(n)
            at = starts[cell] + k // n_cand[cell]  # positions in ``order``
            si = qs[first_cand[cell] + k % n_cand[cell]]
            pt = order[at]
            d = np.sqrt(point_segment_dist2(p[pt, 0], p[pt, 1], self.seg[si]))
            first = np.flatnonzero(np.r_[True, at[1:] != at[:-1]])
            mine = pt[first]
            out[mine] = np.minimum(out[mine], np.minimum.reduceat(d, first))
        return out


def nearest_below(pts, index: SegmentIndex, bound: np.ndarray, geoms=None) -> np.ndarray:
    """``min(bound, exact distance from each point to the nearest segment of index)``.

    Points farther than ``bound`` from the segments' bounding box keep ``bound``.
    Points with ``bound`` at most :data:`DIRECT_M` are measured against the segments
    within ``bound``. The others get an upper bound ``u`` within :data:`NEAR_QUERY_M`
    from the KD-tree: points whose lower bound ``u - BOUND_STEP_M / 2`` exceeds
    ``bound`` keep ``bound``; the rest are measured against the segments within
    ``min(u, bound)`` only (the nearest wall's stack of duplicates, not every segment
    nearby). Points farther from every segment are measured by cells
    (:meth:`SegmentIndex.far`).

    Parameters
    ----------
    pts : (N, 2) float ndarray
        Metres.
    index : SegmentIndex
    bound : (N,) float ndarray
        Metres (``inf`` allowed).
    geoms : (N,) object ndarray, optional
        ``shapely.points(pts)``, if made.

    Returns
    -------
    (N,) float64 ndarray
        Metres; a new array.
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
    if len(far):  # farther than `near` from every segment: by cells of points
        out[rest[far]] = index.far(pts, rest[far], out[rest[far]])  # u stays inf: not measured again
    keep = u - 0.5 * BOUND_STEP_M <= out[rest] * (1 + 1e-9) + 1e-9
    todo, u = rest[keep], u[keep]
    if len(todo):
        d = index.exact(pts, todo, np.minimum(u, out[todo]), geoms)
        out[todo] = np.minimum(out[todo], d)
    return out


def pairs_within(pts, index: SegmentIndex, taus, hit: np.ndarray) -> np.ndarray:
    """Whether each point is within each tau of a segment of ``index``, or already was:
    the same as ``hit | (nearest_distances(pts, segments) <= tau)``; the points hit at
    every tau are not measured, the others against the segments within the largest tau
    only.

    Parameters
    ----------
    pts : (S, 2) float ndarray
        Metres.
    index : SegmentIndex
    taus : sequence of float
        Metres.
    hit : (T, S) bool ndarray
        One row per tau; not changed.

    Returns
    -------
    (T, S) bool ndarray
        ``hit`` updated, a copy.
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
    box queries, :meth:`SegmentIndex.exact`: the nearest wall's overlapping
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
    return nearest_below(pts, SegmentIndex(as_segments(segments)), np.full(len(pts), np.inf))

"""All metrics of a wall set: from scratch (:func:`score_walls`), or for a growing set,
the walls of the first k scans of an ordering for increasing k, from the previous set's
state and the new walls only (:class:`GrowingWalls`, same result).

Every metric is either a minimum over the walls (the samples' nearest distances), a
union of them (the bitmap, the samples within tau) or a sum over them (the length within
tau), so a larger set is scored from the smaller one's state: the bitmap metrics of
thesis section 5.1 (:mod:`floorscan.score.bitmap`) and the ISPRS-benchmark tolerance
metrics (:mod:`floorscan.score.tolerance`). The runs of every ordering of one extractor
are subsets of the same walls, so the ground-truth samples near each wall
(:class:`SamplePairs`) and each wall's bitmap cells are measured once and shared.
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from floorscan.score.bitmap import bitmap_metrics
from floorscan.core.segment_raster import Grid, segment_cells, rasterize_segments
from floorscan.score.capsule import lengths_within
from floorscan.score.nearest import grown_boxes, nearest_below, SegmentIndex
from floorscan.score.segments import row_keys
from floorscan.core.segments import MIN_SEGMENT_M, split_long, segment_lengths
from floorscan.score.tolerance import distance_bound, tolerance_from, tolerance_metrics
from floorscan.core.score_tables import tau_label


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
    """All metrics of one inferred wall set (thesis 5.1): the bitmap metrics
    (:func:`floorscan.score.bitmap.bitmap_metrics`) on ``grid`` and precision, recall
    and F1 within each tolerance (:func:`floorscan.score.tolerance.tolerance_metrics`).

    Parameters
    ----------
    inferred, ground_truth : (N, 4) and (M, 4) float ndarray
        Wall segments ``x0, y0, x1, y1``, metres, map frame.
    grid : Grid
        The raster of the bitmap metrics.
    wall_width_m : float
        Width a segment is drawn with on ``grid``, metres.
    taus : tuple of float
        Tolerances, metres.
    sample_step_m : float
        Spacing of the segments' samples, metres.
    gt_bitmap : (H, W) bool ndarray, optional
        The rasterized ground truth on ``grid``, to reuse across orderings and k.
    samples : (S, 2) float ndarray, optional
        :func:`floorscan.score.segments.gt_samples` of ``ground_truth``, likewise.

    Returns
    -------
    dict of str to float
        The bitmap metrics' keys and ``precision_<t>cm``, ``recall_<t>cm``,
        ``f1_<t>cm`` for each tolerance.
    """
    if gt_bitmap is None:
        gt_bitmap = rasterize_segments(ground_truth, grid, wall_width_m)
    bi = rasterize_segments(inferred, grid, wall_width_m)
    out = bitmap_metrics(bi, gt_bitmap)
    out.update(tolerance_metrics(inferred, ground_truth, taus, sample_step_m, samples))
    return out


#: Reach (metres) of the wall-to-sample pairs that give the samples' nearest distances
#: (:class:`SamplePairs`); samples farther from every wall are measured by
#: :func:`floorscan.score.nearest.nearest_below`.
PAIR_REACH_M = 0.1
#: Longest piece (metres) of the walls whose grown boxes find their samples in
#: :class:`SamplePairs`.
PAIR_PIECE_M = 2.0
#: Most pieces (of :data:`PAIR_PIECE_M`) of the walls measured or added at once: the
#: candidate pairs of a batch and their temporaries (about 100 bytes a candidate, some
#: hundreds of candidates a piece at 1 cm samples) are bounded by it, not by the number
#: of walls a run adds.
PAIR_BATCH_PIECES = 8192


def wall_batches(walls: np.ndarray, max_pieces: int | None = None) -> list[slice]:
    """Consecutive row ranges of ``walls`` of at most ``max_pieces`` pieces of
    :data:`PAIR_PIECE_M` each (a wall of more pieces alone).

    Parameters
    ----------
    walls : (M, 4) float64 ndarray
        Metres.
    max_pieces : int, optional
        Default :data:`PAIR_BATCH_PIECES`.

    Returns
    -------
    list of slice
        Covering ``0..M`` in order; empty for no walls.
    """
    max_pieces = PAIR_BATCH_PIECES if max_pieces is None else int(max_pieces)
    n = np.maximum(1, np.ceil(segment_lengths(walls) / PAIR_PIECE_M).astype(np.int64))
    ends = np.cumsum(n)
    out, i = [], 0
    while i < len(walls):
        j = max(int(np.searchsorted(ends, (ends[i - 1] if i else 0) + max_pieces, side="right")), i + 1)
        out.append(slice(i, j))
        i = j
    return out


class SamplePairs:
    """The ground-truth samples within ``reach`` of each wall, for walls met again and
    again: the runs of every ordering of one extractor are subsets of the same walls.

    A fixed ``(S, 2)`` sample set, an STRtree of its points and a cache ``{row key of
    a wall: (sample indices, distances)}``: every sample whose exact distance
    (numpy, :func:`floorscan.core.geometry.point_segment_dist2`) to the wall is at most
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
        """The pairs (sample, wall) within ``reach`` of the given walls, measured once per
        wall and cached.

        Parameters
        ----------
        walls : (M, 4) float64 ndarray
            Finite walls, metres.
        keys : list of bytes
            Their row keys (:func:`floorscan.score.segments.row_keys`).

        Returns
        -------
        samples : (P,) int64 ndarray
            Sample indices, concatenated over the walls; a sample may repeat.
        distances : (P,) float64 ndarray
            Metres.
        """
        cache = self.cache
        todo = [i for i, k in enumerate(keys) if k not in cache]
        if todo:
            seg, todo_keys = walls[todo], [keys[i] for i in todo]
            for b in wall_batches(seg):  # a wall's pairs do not depend on its batch
                self._measure(seg[b], todo_keys[b])
        if not keys:
            return np.zeros(0, np.int64), np.zeros(0)
        parts = [cache[k] for k in keys]
        return np.concatenate([q[0] for q in parts]), np.concatenate([q[1] for q in parts])

    def _measure(self, seg: np.ndarray, keys: list[bytes]) -> None:
        if self._tree is None:
            self._tree = shapely.STRtree(self.geoms)
        pc, owner = split_long(seg, PAIR_PIECE_M, return_owner=True)
        qi, si = self._tree.query(grown_boxes(pc, self.reach))
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


class GrowingWalls:
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
    the wall's :class:`SamplePairs` (the nearest wall of a sample within the reach
    of a wall is within it too); the samples no wall has come within reach of yet
    are measured by :func:`floorscan.score.nearest.nearest_below` up to
    :func:`~floorscan.score.tolerance.distance_bound`, not beyond it.
    ``recall_all_<tau>`` takes the pairs within the largest tau of ``all_pairs``. The
    pairs and ``raster_cache`` (``{row key: flat wall cells}``, see
    :func:`floorscan.core.segment_raster.segment_cells`) may be shared by the growing sets of
    one extractor (same samples, grid and wall width), so that a wall is measured and
    rasterized once for all orderings.

    ``samples`` (recall, distances) and ``all_samples`` (``recall_all_<tau>``, or
    None) are ground-truth samples (:func:`floorscan.score.segments.gt_samples`).

    The walls a set adds are paired, rasterized and added in batches of at most
    :data:`PAIR_BATCH_PIECES` pieces (:func:`wall_batches`), so that the memory of a
    step follows the batch, not the number of walls added (every ordering's k = all
    adds all the walls of the dataset at once).
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
        self.d_far = np.full(len(self.samples), distance_bound(self.taus))
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
            owner, flat = segment_cells(add[todo], self.grid, self.width)  # owner ascending
            bounds = np.searchsorted(owner, np.arange(len(todo) + 1))
            flat = flat.astype(np.int32 if self.grid.nx * self.grid.ny < 2**31 else np.int64)
            for j, i in enumerate(todo):
                cache[add_keys[i]] = flat[bounds[j]:bounds[j + 1]]
        return np.concatenate([cache[k] for k in add_keys])

    def _add_near(self, add: np.ndarray, add_keys: list[bytes]) -> None:
        """Add walls' pairs (nearest distances, ``recall_all`` hits) and bitmap cells."""
        si, d = self.pairs.of(add, add_keys)
        np.minimum.at(self.d_near, si, d)
        if self.all_samples is not None:
            si, d = self.all_pairs.of(add, add_keys)
            for t, tau in enumerate(self.taus):
                self.hit_all[t, si[d <= tau]] = True
        self.bitmap.reshape(-1)[self._wall_cells(add, add_keys)] = True

    def score(self, walls: np.ndarray) -> dict[str, float]:
        """:func:`score_walls` of a wall set, from the previous set's state when it is a
        superset of it.

        Parameters
        ----------
        walls : (M, 4) float64 ndarray
            Finite walls, metres.

        Returns
        -------
        dict of str to float
            :func:`score_walls`' keys, and ``recall_all_<tau>`` when ``all_samples`` is
            given.
        """
        keys = row_keys(walls)
        cur = set(keys)
        if self.keys is None or not self.keys <= cur:
            self._reset()
        new = np.fromiter((k not in self.keys for k in keys), dtype=bool, count=len(keys))
        add = walls[new]
        if len(add):
            add_keys = [k for k, n in zip(keys, new) if n]
            # In batches of walls: minima and unions, the same in any grouping; the
            # pairs and cells of all the walls of k = all are never held at once.
            for b in wall_batches(add):
                self._add_near(add[b], add_keys[b])
            far = np.flatnonzero(np.isinf(self.d_near))
            if len(far):
                self.d_far[far] = nearest_below(
                    self.samples[far], SegmentIndex(add), self.d_far[far], self.pairs.geoms[far]
                )
            self.d = np.where(np.isinf(self.d_near), self.d_far, self.d_near)
            # Measured once per wall for every tau (the caches of the taus hold the
            # same walls), in the same batches as tau by tau: a wall's covered length
            # depends, in its last bits, on its row in the batch (the sweep's offset).
            todo = [i for i, k in enumerate(add_keys) if any(k not in self.covered[tau] for tau in self.taus)]
            if todo:
                covs = lengths_within(add[todo], self.gt, self.taus)
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
        out.update(tolerance_from(len_i, self.len_g, len(self.samples), d, covered, self.taus))
        if self.all_samples is not None:
            n = len(self.all_samples)
            for t, tau in enumerate(self.taus):
                frac = float(np.mean(self.hit_all[t])) if len(walls) else 0.0
                out[f"recall_all_{tau_label(tau)}"] = frac if n else math.nan
        return out

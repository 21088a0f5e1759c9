"""Merge the wall segments that describe one wall face into one segment
(:func:`merge_segments`).

Wall extraction runs per scan, so one wall of the building is seen by many scans and
appears as many overlapping segments (the duplicate problem of thesis section 5.1).
Two segments belong to one face when they are near parallel, close to each other's
line and overlap or nearly meet along it; a face is a connected group of such pairs
(SciPy's ``connected_components``), fitted by :func:`~floorscan.floorplan.fit.fit_groups`.
The candidates come from :func:`~floorscan.floorplan.candidates.candidate_pairs`.
Source: thesis section 5.1 (the problem); the rule is ours.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_array
from scipy.sparse.csgraph import connected_components

from floorscan.floorplan.candidates import candidate_pairs, line_geometry, within_distance
from floorscan.floorplan.fit import fit_groups
from floorscan.floorplan.params import FloorplanParams


def _components(n: int, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Connected component (0..) of each of ``n`` nodes given the edges (i, j), numbered
    in the order of their smallest node: ``scipy.sparse.csgraph.connected_components``
    of the undirected graph, as an (n,) int64 ndarray."""
    graph = coo_array((np.ones(len(i)), (np.asarray(i), np.asarray(j))), shape=(n, n))
    return connected_components(graph, directed=False)[1].astype(np.int64)


#: Candidate pairs tested at once by :func:`_merge_groups`.
_MERGE_CHUNK = 1 << 15


def _merge_groups(cur: np.ndarray, i: np.ndarray, j: np.ndarray, params: FloorplanParams) -> np.ndarray | None:
    """The faces of :func:`merge_segments`: the connected groups of the candidate
    pairs (i, j) that pass its merge test, as a group per segment (numbered 0..G-1 by
    their smallest segment, as :func:`_components`), or None when no pair passes.

    The candidates (within the merge angle already) are tested a chunk at a time,
    and a pair whose two segments are already connected by the pairs passed so far
    is not tested: it could not change the groups. A wall seen by hundreds of scans
    is a stack of hundreds of segments whose pairs nearly all pass; after the first
    chunk most of them are connected. The groups, and so the merged faces, are those
    of all the passing pairs.
    """
    label = np.arange(len(cur))  # a component label per segment, of the pairs passed so far
    merged = False
    for start in range(0, len(i), _MERGE_CHUNK):
        ci, cj = i[start : start + _MERGE_CHUNK], j[start : start + _MERGE_CHUNK]
        apart = label[ci] != label[cj]
        pi, pj = _passing(cur, ci[apart], cj[apart], params)
        if len(pi):
            merged = True
            label = _components(len(cur), label[pi], label[pj])[label]
    return label if merged else None


def _passing(cur: np.ndarray, ci: np.ndarray, cj: np.ndarray, params: FloorplanParams) -> tuple[np.ndarray, np.ndarray]:
    """The candidate pairs (ci, cj) of segments ``cur`` that pass the merge test of
    :func:`merge_segments` (a test of the two segments alone)."""
    if len(ci) == 0:
        return ci, cj
    reach = max(params.merge_gap_m, params.merge_distance_m)
    a, b, d, n, length = line_geometry(cur, ci, cj)
    dist = np.maximum(
        np.abs(np.einsum("ij,ij->i", cur[b, :2] - cur[a, :2], n)),
        np.abs(np.einsum("ij,ij->i", cur[b, 2:] - cur[a, :2], n)),
    )
    ta = np.zeros(len(a)), length[a]
    tb0 = np.einsum("ij,ij->i", cur[b, :2] - cur[a, :2], d)
    tb1 = np.einsum("ij,ij->i", cur[b, 2:] - cur[a, :2], d)
    gap = np.maximum(np.minimum(tb0, tb1) - ta[1], ta[0] - np.maximum(tb0, tb1))
    ok = (dist <= params.merge_distance_m) & (gap <= params.merge_gap_m)
    # Overlapping along the line (gap <= 0), a point of the shorter projects
    # onto the longer and lies within dist of it: within reach for sure.
    sure = ok & (gap <= 0) & (dist < reach * (1 - 1e-9))
    wi, wj = within_distance(cur, ci[ok & ~sure], cj[ok & ~sure], reach)
    return np.r_[ci[sure], wi], np.r_[cj[sure], wj]


class FirstMergePass:
    """The first pass of :func:`merge_segments` for any subset of one segment set,
    prepared once: for the floor plans of many subsets of the same segments (the first
    k scans of an ordering, for many k and orderings).

    The merge test is a test of two segments alone, so the first pass's faces of a
    subset are the connected groups of the passing pairs whose two segments are both
    in it. Every candidate pair of the whole set is tested here once; :meth:`groups`
    keeps those of a subset. Later passes run on the subset's faces as before.

    Parameters
    ----------
    segments : (M, 4) float ndarray
        The whole set, metres.
    params : FloorplanParams
    max_pairs : int
        Above this many candidate pairs (16 bytes each) nothing is prepared and
        :meth:`groups` returns None.
    """

    def __init__(self, segments: np.ndarray, params: FloorplanParams = FloorplanParams(), max_pairs: int = 20_000_000):
        seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
        reach = max(params.merge_gap_m, params.merge_distance_m)
        i, j = candidate_pairs(seg, reach, np.radians(params.merge_angle_deg), exact=False)
        self.i = self.j = None
        if len(i) <= max_pairs:
            parts = [_passing(seg, i[s : s + _MERGE_CHUNK], j[s : s + _MERGE_CHUNK], params)
                     for s in range(0, len(i), _MERGE_CHUNK)]  # fmt: skip
            self.i = np.concatenate([p[0] for p in parts]) if parts else np.empty(0, np.int64)
            self.j = np.concatenate([p[1] for p in parts]) if parts else np.empty(0, np.int64)

    def groups(self, rows: np.ndarray) -> np.ndarray | None:
        """The first pass's group of each segment of a subset, numbered as
        :func:`_merge_groups` numbers them (each segment its own group when no pair passes).

        Parameters
        ----------
        rows : (M,) bool ndarray
            The subset, a mask of the whole prepared set.

        Returns
        -------
        (K,) int64 ndarray or None
            For each of the K selected segments; None when not prepared.
        """
        if self.i is None:
            return None
        inside = np.asarray(rows, dtype=bool)
        local = np.cumsum(inside) - 1
        keep = inside[self.i] & inside[self.j]
        return _components(int(inside.sum()), local[self.i[keep]], local[self.j[keep]])


def merge_segments(
    segments: np.ndarray, weights: np.ndarray, params: FloorplanParams = FloorplanParams(),
    first_groups: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Merge the segments that describe one wall face into one segment.

    Two segments belong to one face when their directions differ by at most
    ``merge_angle_deg``, both ends of the shorter are within ``merge_distance_m`` of
    the longer's line, and along that line they overlap or leave a gap of at most
    ``merge_gap_m``. Faces are the connected groups of this relation (so a chain of
    pairwise-close segments is one face) and each is fitted by :func:`fit_segments`.
    This is repeated (``max_passes``) on the merged faces until nothing changes.
    Source: the duplicate problem of thesis section 5.1; the rule is ours.

    Parameters
    ----------
    segments : (M, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    weights : (M,) float ndarray
        Weight of each segment in the fit (inlier count).
    params : FloorplanParams
    first_groups : (M,) int64 ndarray, optional
        The first pass's groups, from :meth:`FirstMergePass.groups` (the same faces).

    Returns
    -------
    faces : (F, 4) float64 ndarray
        Merged segments.
    face_weights : (F,) float64 ndarray
        Sum of the member weights.
    labels : (M,) int64 ndarray
        Face of each input segment.

    Raises
    ------
    ValueError
        When ``segments`` and ``weights`` differ in length.
    """
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    w = np.asarray(weights, dtype=np.float64).reshape(-1)
    if len(seg) != len(w):
        raise ValueError(f"{len(seg)} segments but {len(w)} weights")
    labels = np.arange(len(seg))
    cur, cur_w = seg, w
    for n_pass in range(max(1, params.max_passes)):
        if n_pass == 0 and first_groups is not None:
            group = first_groups if len(first_groups) and first_groups.max() + 1 < len(cur) else None
        else:
            reach = max(params.merge_gap_m, params.merge_distance_m)
            i, j = candidate_pairs(cur, reach, np.radians(params.merge_angle_deg), exact=False)
            group = _merge_groups(cur, i, j, params)
        if group is None:
            break
        size = np.bincount(group)
        # A group of one keeps its segment (as fit_segments would): only the others are fitted.
        new = np.empty((len(size), 4))
        new[group] = cur  # the groups of one
        several = size[group] > 1
        if several.any():
            fitted = np.flatnonzero(size > 1)
            rank = np.full(len(size), -1, dtype=np.int64)
            rank[fitted] = np.arange(len(fitted))
            new[fitted] = fit_groups(cur[several], cur_w[several], rank[group[several]], len(fitted))
        new_w = np.bincount(group, weights=cur_w)
        labels = group[labels]
        cur, cur_w = new, new_w
    return cur, cur_w, labels

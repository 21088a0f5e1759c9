"""Candidate pairs of wall segments: the pairs of segments within a distance of each
other (and within an angle in direction), which the merge
(:mod:`floorscan.floorplan.merge`) and the pairing of faces
(:mod:`floorscan.floorplan.pairing`) test further.

:func:`candidate_pairs` finds the pairs of Shapely's
``STRtree.query(predicate="dwithin")``: the bounding boxes grown by the distance from
an STRtree query, the exact segment-to-segment distance in numpy
(:func:`_segment_distance`, :func:`point_segment_dist2`) rather than a GEOS distance
per pair, because walls seen by many scans stack a hundred segments deep. Given an
angle, the segments are binned by direction first (:func:`_binned_box_pairs`), so
that the pairs of crossing walls are not made at all. :func:`point_segment_dist2` is
also the scorer's (:mod:`floorscan.score.metrics`).
"""

from __future__ import annotations

import numpy as np

from floorscan.core.geometry import point_segment_dist2


def axial_angle(seg: np.ndarray) -> np.ndarray:
    """Direction of each segment as an axial angle (a line, not a vector).

    Parameters
    ----------
    seg : (N, 4) float ndarray
        ``x0, y0, x1, y1``, metres.

    Returns
    -------
    (N,) float64 ndarray
        Radians in [0, pi).
    """
    return np.mod(np.arctan2(seg[:, 3] - seg[:, 1], seg[:, 2] - seg[:, 0]), np.pi)


def angle_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Difference of axial angles, modulo pi.

    Parameters
    ----------
    a, b : float ndarray
        Axial angles, radians, broadcastable.

    Returns
    -------
    float64 ndarray
        Radians in [0, pi/2].
    """
    d = np.abs(a - b) % np.pi
    return np.minimum(d, np.pi - d)


def candidate_pairs(
    seg: np.ndarray, distance: float, max_angle: float | None = None, exact: bool = True
) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (i < j) of segments within ``distance`` of each other, metres.

    Pairs whose bounding boxes, grown by ``distance``, meet come from Shapely
    STRtree box queries (vectorized calls); those differing in direction by more
    than ``max_angle`` (radians; the callers' own first test) are dropped, and the
    exact segment-to-segment distance of the rest is computed in numpy (0 where they
    cross, else the least of the four end-to-segment distances). The same pairs as
    ``STRtree.query(predicate="dwithin")``, without a GEOS distance per pair: walls
    seen by many scans stack a hundred segments deep. With ``max_angle``, the
    segments are first binned by direction (bins at least ``max_angle`` wide, so a
    pair within it lies in one bin or two neighbours) and only the pairs within a
    bin or two neighbouring bins are queried (:func:`_binned_box_pairs`, one
    query): the box pairs of crossing walls are not made at all. With ``exact``
    False the distance test is left to the caller (:func:`within_distance`,
    :func:`floorscan.floorplan.merge._merge_groups`), who may run its own cheaper
    tests first; the pairs are then in no particular order.

    Parameters
    ----------
    seg : (N, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    distance : float
        Metres.
    max_angle : float, optional
        Radians.
    exact : bool
        Apply the distance test (and sort the pairs by ``(i, j)``).

    Returns
    -------
    i, j : (P,) int64 ndarray
        The pairs, ``i < j``.
    """
    import shapely

    if len(seg) < 2:
        return np.empty(0, np.int64), np.empty(0, np.int64)
    lo = np.minimum(seg[:, :2], seg[:, 2:]) - distance
    hi = np.maximum(seg[:, :2], seg[:, 2:]) + distance
    ang = axial_angle(seg) if max_angle is not None else None
    # Direction bins, 1 % wider than max_angle against rounding; fewer than 3 bins: one query.
    n_bins = 1 if max_angle is None else int(min(64, np.floor(np.pi / (1.01 * max(max_angle, 1e-9)))))
    if n_bins < 3:
        lines = shapely.linestrings(np.stack([seg[:, :2], seg[:, 2:]], axis=1))
        boxes = shapely.box(lo[:, 0], lo[:, 1], hi[:, 0], hi[:, 1])
        i, j = shapely.STRtree(lines).query(boxes)
        keep = i < j
        i, j = i[keep], j[keep]
    else:
        i, j = _binned_box_pairs(seg, lo, hi, ang, n_bins)
    if max_angle is not None and len(i):
        keep = angle_diff(ang[i], ang[j]) <= max_angle
        i, j = i[keep], j[keep]
    if not exact:
        return i, j
    i, j = within_distance(seg, i, j, distance)
    order = np.lexsort((j, i))
    return i[order], j[order]


def _binned_box_pairs(seg: np.ndarray, lo: np.ndarray, hi: np.ndarray, ang: np.ndarray, n_bins: int):
    """Pairs (i < j, in no particular order) of segments in one direction bin or two
    neighbouring ones (``n_bins`` >= 3 bins over [0, pi) of ``ang``) whose boxes
    (``lo``, ``hi``: each segment's box grown by the search distance) meet its
    neighbour's bounding box, from one STRtree query.

    Each bin gets its own stretch of the x axis (bins a box width plus a margin apart),
    the tree holds every segment in its bin's stretch, and every box is queried twice:
    in its own bin's stretch (pairs within the bin) and in the next bin's (pairs
    with the next bin; bin ``n_bins - 1``'s next is bin 0). The query boxes grow by a
    relative 1e-9 more than the distance, so the shift by whole stretches cannot lose
    a pair to rounding: the pairs are the grown-box pairs of one bin or two
    neighbouring ones, and a few more at most at the distance's edge (the callers
    test the distance).
    """
    import shapely

    n = len(seg)
    in_bin = np.clip((np.nan_to_num(ang) * (n_bins / np.pi)).astype(np.int64), 0, n_bins - 1)
    finite = np.isfinite(lo).all(axis=1) & np.isfinite(hi).all(axis=1)  # others meet nothing, as in a tree
    if not finite.any():
        return np.empty(0, np.int64), np.empty(0, np.int64)
    x_min, x_max = float(lo[finite, 0].min()), float(hi[finite, 0].max())
    y_abs = float(max(np.abs(lo[finite, 1]).max(), np.abs(hi[finite, 1]).max()))
    stretch = (x_max - x_min) * 1.5 + 1.0
    eps = 1e-9 * (n_bins + 1) * (stretch + abs(x_min) + abs(x_max) + y_abs)
    shift = in_bin * stretch - x_min
    xy = seg.reshape(n, 2, 2).copy()
    xy[:, :, 0] += shift[:, None]
    tree = shapely.STRtree(shapely.linestrings(xy))
    slot = np.r_[in_bin, (in_bin + 1) % n_bins] * stretch - x_min
    qlo, qhi = np.tile(lo, (2, 1)) - eps, np.tile(hi, (2, 1)) + eps
    qi, j = tree.query(shapely.box(qlo[:, 0] + slot, qlo[:, 1], qhi[:, 0] + slot, qhi[:, 1]))
    i = qi % n
    same = qi < n
    keep = ~same | (i < j)  # a pair in one bin is found from both of its boxes
    i, j = i[keep], j[keep]
    return np.minimum(i, j), np.maximum(i, j)


def within_distance(seg: np.ndarray, i: np.ndarray, j: np.ndarray, distance: float):
    """The pairs (i, j) of segments at most ``distance`` apart (the dwithin test; 0
    where they cross).

    Parameters
    ----------
    seg : (N, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    i, j : (P,) int ndarray
        Candidate pairs.
    distance : float
        Metres.

    Returns
    -------
    i, j : (Q,) int ndarray
        The pairs kept, in their order.
    """
    if len(i) == 0:
        return i, j
    keep = _segment_distance(seg[i], seg[j]) <= distance
    return i[keep], j[keep]




def _segment_distance(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance between the matching segments of ``(P, 4)`` arrays ``a`` and ``b``, metres."""

    def orient(p, q, r):
        return (q[:, 0] - p[:, 0]) * (r[:, 1] - p[:, 1]) - (q[:, 1] - p[:, 1]) * (r[:, 0] - p[:, 0])

    a0, a1, b0, b1 = a[:, :2], a[:, 2:], b[:, :2], b[:, 2:]
    cross = (orient(a0, a1, b0) * orient(a0, a1, b1) < 0) & (orient(b0, b1, a0) * orient(b0, b1, a1) < 0)
    d2 = np.minimum.reduce([
        point_segment_dist2(a0[:, 0], a0[:, 1], b), point_segment_dist2(a1[:, 0], a1[:, 1], b),
        point_segment_dist2(b0[:, 0], b0[:, 1], a), point_segment_dist2(b1[:, 0], b1[:, 1], a),
    ])  # fmt: skip
    return np.where(cross, 0.0, np.sqrt(d2))


def line_geometry(seg: np.ndarray, i: np.ndarray, j: np.ndarray):
    """For pairs (i, j): the longer one's unit direction and normal, with the
    indices of the longer and the shorter.

    Parameters
    ----------
    seg : (N, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    i, j : (P,) int ndarray
        Pairs of segments.

    Returns
    -------
    a, b : (P,) int ndarray
        The longer and the shorter of each pair.
    d, n : (P, 2) float64 ndarray
        The longer's unit direction and normal (direction turned a quarter left).
    length : (N,) float64 ndarray
        Every segment's length, metres.
    """
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    swap = length[i] < length[j]
    a = np.where(swap, j, i)  # longer
    b = np.where(swap, i, j)  # shorter
    d = (seg[a, 2:] - seg[a, :2]) / np.maximum(length[a], 1e-12)[:, None]
    n = np.stack([-d[:, 1], d[:, 0]], axis=1)
    return a, b, d, n, length

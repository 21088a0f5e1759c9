"""Floor plan: one wall per wall from the wall segments of many scans, and its exports.

Wall extraction runs per scan, so one wall of the building is seen by many scans and
appears as many overlapping segments (thesis section 5.1 names this duplicate
problem). :func:`merge_segments` merges the segments that describe one wall face;
:func:`pair_faces` pairs the two faces of a wall (parallel, 5 to 40 cm apart,
overlapping) into one wall with its thickness; :func:`build_floorplan` does both.
The plan is written as GeoJSON (people, GIS, the scorer), SVG (a browser), DXF (CAD,
ezdxf: R12 by default, R2010 on request, see :func:`write_dxf`) and IFC (BIM,
IfcOpenShell: an ``IfcWall`` per wall in an ``IfcBuildingStorey``), the thesis's
purpose (Chapter 1). Every file is written
atomically (:func:`floorscan.io.atomic_path`).

Coordinates are metres in the map frame of the recording (a local frame, no CRS).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
import uuid
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np
import pandas as pd

from floorscan.io import atomic_path

log = logging.getLogger(__name__)

#: Columns of :attr:`FloorPlan.walls`.
WALL_COLUMNS = [
    "wall_id", "x0", "y0", "x1", "y1", "length_m", "thickness_m", "height_m",
    "paired", "n_faces", "n_segments", "n_inliers",
]  # fmt: skip
#: DXF versions :func:`write_dxf` writes.
DXF_VERSIONS = ("R12", "R2010")
#: Layers of the DXF export and their colours (AutoCAD Color Index: red, white, green).
DXF_LAYERS = {"WALL_AXIS": 1, "WALL_OUTLINE": 7, "WALL_FACE": 3}
#: Columns of :attr:`FloorPlan.faces`.
FACE_COLUMNS = ["face_id", "wall_id", "x0", "y0", "x1", "y1", "length_m", "n_segments", "n_inliers"]


@dataclass(frozen=True)
class FloorplanParams:
    """Merge and pairing parameters (config section ``floorplan``).

    Attributes
    ----------
    merge_angle_deg : float
        Segments of one face differ in direction by at most this, degrees.
    merge_distance_m : float
        ... and the ends of the shorter lie within this of the longer's line, metres.
    merge_gap_m : float
        ... and they overlap or leave a gap of at most this along the line, metres.
    max_passes : int
        Merge passes (merged faces may touch faces they did not touch before).
    pair_angle_deg : float
        Two faces of one wall differ in direction by at most this, degrees.
    pair_min_m, pair_max_m : float
        Distance between the two faces of one wall (its thickness), metres.
    pair_min_overlap : float
        The two faces overlap along the wall by at least this fraction of the
        shorter face.
    default_thickness_m : float
        Thickness of a wall of which one face was seen, metres.
    wall_height_m : float
        Height of every wall (IFC extrusion, GeoJSON ``height_m``), metres.
    min_length_m : float
        Merged faces shorter than this are dropped, metres.
    dxf_version : str
        DXF export: ``"R12"`` or ``"R2010"`` (see :func:`write_dxf`).
    """

    merge_angle_deg: float = 3.0
    merge_distance_m: float = 0.05
    merge_gap_m: float = 0.3
    max_passes: int = 3
    pair_angle_deg: float = 3.0
    pair_min_m: float = 0.05
    pair_max_m: float = 0.40
    pair_min_overlap: float = 0.5
    default_thickness_m: float = 0.10
    wall_height_m: float = 2.5
    min_length_m: float = 0.3
    dxf_version: str = "R12"

    def __post_init__(self):
        if self.dxf_version not in DXF_VERSIONS:
            raise ValueError(f"floorplan.dxf_version must be one of {list(DXF_VERSIONS)}, got {self.dxf_version!r}")
        if not self.pair_min_m < self.pair_max_m:
            raise ValueError(
                f"floorplan.pair_min_m ({self.pair_min_m}) must be below pair_max_m ({self.pair_max_m})"
            )


def params_from_config(cfg: Mapping[str, Any] | None) -> FloorplanParams:
    """:class:`FloorplanParams` of the ``floorplan`` config section.

    Raises
    ------
    KeyError
        For a key the class does not know.
    """
    from floorscan.config import dataclass_from_mapping

    return dataclass_from_mapping(FloorplanParams, cfg, "floorplan")


@dataclass
class FloorPlan:
    """A merged floor plan.

    Attributes
    ----------
    walls : pandas.DataFrame
        One row per wall (:data:`WALL_COLUMNS`): axis ``x0, y0, x1, y1`` (centre
        line, metres), ``thickness_m``, ``height_m``, ``paired`` (both faces seen).
    faces : pandas.DataFrame
        One row per merged face (:data:`FACE_COLUMNS`), ``wall_id`` of its wall.
    """

    walls: pd.DataFrame
    faces: pd.DataFrame

    def footprints(self):
        """Wall polygons (shapely), the axis buffered by half the thickness, flat ends."""
        import shapely

        lines = shapely.linestrings(
            np.stack([self.walls[["x0", "y0"]].to_numpy(), self.walls[["x1", "y1"]].to_numpy()], axis=1)
        ) if len(self.walls) else np.array([], dtype=object)
        return shapely.buffer(lines, self.walls["thickness_m"].to_numpy() / 2.0, cap_style="flat")


# --------------------------------------------------------------------------------------
# Merge
# --------------------------------------------------------------------------------------


def _axial_angle(seg: np.ndarray) -> np.ndarray:
    return np.mod(np.arctan2(seg[:, 3] - seg[:, 1], seg[:, 2] - seg[:, 0]), np.pi)


def _angle_diff(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = np.abs(a - b) % np.pi
    return np.minimum(d, np.pi - d)


def _candidate_pairs(
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
    query): the box pairs of crossing walls (two thirds of them on hallways3d) are
    not made at all. With ``exact`` False the distance
    test is left to the caller (:func:`_within_distance`, :func:`_merge_groups`),
    who may run its own cheaper tests first; the pairs are then in no particular
    order.
    """
    import shapely

    if len(seg) < 2:
        return np.empty(0, np.int64), np.empty(0, np.int64)
    lo = np.minimum(seg[:, :2], seg[:, 2:]) - distance
    hi = np.maximum(seg[:, :2], seg[:, 2:]) + distance
    ang = _axial_angle(seg) if max_angle is not None else None
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
        keep = _angle_diff(ang[i], ang[j]) <= max_angle
        i, j = i[keep], j[keep]
    if not exact:
        return i, j
    i, j = _within_distance(seg, i, j, distance)
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
    test the distance; before, a tree and a query per bin pair, 59 of each for the
    merge's 3 degrees, cost more than the queries).
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


def _within_distance(seg: np.ndarray, i: np.ndarray, j: np.ndarray, distance: float):
    """The pairs (i, j) of segments at most ``distance`` apart (the dwithin test)."""
    if len(i) == 0:
        return i, j
    keep = _segment_distance(seg[i], seg[j]) <= distance
    return i[keep], j[keep]


def point_segment_dist2(px: np.ndarray, py: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """Squared distance (square metres) from points ``(px, py)`` (P,) to the matching
    rows of segments ``seg`` (P, 4) ``x0, y0, x1, y1`` (a zero-length segment is its
    point). Used here and by :mod:`floorscan.metrics`."""
    ax, ay, bx, by = seg[:, 0], seg[:, 1], seg[:, 2], seg[:, 3]
    dx, dy = bx - ax, by - ay
    l2 = dx * dx + dy * dy
    with np.errstate(invalid="ignore", divide="ignore"):
        t = ((px - ax) * dx + (py - ay) * dy) / l2
    t = np.where(l2 > 0, np.clip(t, 0.0, 1.0), 0.0)
    ex = ax + t * dx - px
    ey = ay + t * dy - py
    return ex * ex + ey * ey


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


def _line_geometry(seg: np.ndarray, i: np.ndarray, j: np.ndarray):
    """For pairs (i, j): the longer one's unit direction/normal/midpoint, and the
    shorter one's endpoints, as arrays."""
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    swap = length[i] < length[j]
    a = np.where(swap, j, i)  # longer
    b = np.where(swap, i, j)  # shorter
    d = (seg[a, 2:] - seg[a, :2]) / np.maximum(length[a], 1e-12)[:, None]
    n = np.stack([-d[:, 1], d[:, 0]], axis=1)
    return a, b, d, n, length


def _union_find(n: int, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Connected component label (0..) of each of ``n`` nodes given edges (i, j).

    Components are numbered in the order of their smallest node (as
    ``scipy.sparse.csgraph.connected_components`` numbers them), found by hooking
    each node to the smallest label among its neighbours and pointer jumping until
    nothing changes (numpy only: importing scipy's graph module cost 0.2 s a job).
    """
    label = np.arange(n)
    i, j = np.asarray(i, dtype=np.int64), np.asarray(j, dtype=np.int64)
    while len(i):
        old = label.copy()
        li, lj = label[i], label[j]
        np.minimum.at(label, li, lj)
        np.minimum.at(label, lj, li)
        while True:  # pointer jumping: every node to its root
            nxt = label[label]
            if np.array_equal(nxt, label):
                break
            label = nxt
        if np.array_equal(label, old):
            break
    return np.unique(label, return_inverse=True)[1].reshape(-1)


def fit_segments(seg: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """One segment fitted to several (weighted total least squares over their lengths).

    Each segment counts as its weight spread evenly along it: the line minimises the
    weighted sum of squared distances of those masses (centroid ``m = sum w_i m_i /
    sum w_i``; direction the major axis of ``sum w_i [(m_i - m)(m_i - m)^T + L_i^2 / 12
    d_i d_i^T]``). The extent is the union of the segments' projections on it.

    Parameters
    ----------
    seg : (M, 4) float ndarray
        Segments ``x0, y0, x1, y1``, metres.
    weights : (M,) float ndarray
        Positive weights (e.g. inlier counts).

    Returns
    -------
    (4,) float64 ndarray
        The merged segment, metres.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    if len(seg) == 1:
        return seg[0].copy()
    return fit_groups(seg, weights, np.zeros(len(seg), dtype=np.int64), 1)[0]


def fit_groups(seg: np.ndarray, weights: np.ndarray, group: np.ndarray, n_groups: int) -> np.ndarray:
    """:func:`fit_segments` of every group at once.

    Parameters
    ----------
    seg : (M, 4) float ndarray
        Segments ``x0, y0, x1, y1``, metres.
    weights : (M,) float ndarray
        Positive weights.
    group : (M,) int ndarray
        Group of each segment, 0 .. ``n_groups`` - 1; every group has a member.
    n_groups : int

    Returns
    -------
    (n_groups, 4) float64 ndarray
        The fitted segment of each group, metres (a group of one: its segment's line
        and extent, up to rounding).
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    w = np.asarray(weights, dtype=np.float64).reshape(-1)
    g = np.asarray(group, dtype=np.int64).reshape(-1)

    def total(values):
        return np.bincount(g, weights=values, minlength=n_groups)

    mid = 0.5 * (seg[:, :2] + seg[:, 2:])
    vec = seg[:, 2:] - seg[:, :2]
    length = np.hypot(vec[:, 0], vec[:, 1])
    d = vec / np.maximum(length, 1e-12)[:, None]
    w_sum = total(w)
    m = np.stack([total(w * mid[:, 0]), total(w * mid[:, 1])], axis=1) / w_sum[:, None]
    r = mid - m[g]
    wl = w * length**2 / 12.0
    cxx = total(w * r[:, 0] * r[:, 0] + wl * d[:, 0] * d[:, 0])
    cyy = total(w * r[:, 1] * r[:, 1] + wl * d[:, 1] * d[:, 1])
    cxy = total(w * r[:, 0] * r[:, 1] + wl * d[:, 0] * d[:, 1])
    phi = 0.5 * np.arctan2(2.0 * cxy, cxx - cyy)
    u = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    t0 = np.einsum("ij,ij->i", seg[:, :2] - m[g], u[g])
    t1 = np.einsum("ij,ij->i", seg[:, 2:] - m[g], u[g])
    lo = np.full(n_groups, np.inf)
    hi = np.full(n_groups, -np.inf)
    np.minimum.at(lo, g, np.minimum(t0, t1))
    np.maximum.at(hi, g, np.maximum(t0, t1))
    a, b = m + lo[:, None] * u, m + hi[:, None] * u
    return np.concatenate([a, b], axis=1)


#: Candidate pairs tested at once by :func:`_merge_groups`.
_MERGE_CHUNK = 1 << 15


def _merge_groups(cur: np.ndarray, i: np.ndarray, j: np.ndarray, params: FloorplanParams) -> np.ndarray | None:
    """The faces of :func:`merge_segments`: the connected groups of the candidate
    pairs (i, j) that pass its merge test, as a group per segment (numbered 0..G-1 by
    their smallest segment, as :func:`_union_find`), or None when no pair passes.

    The candidates (within the merge angle already) are tested a chunk at a time,
    and a pair whose two segments are already connected by the pairs passed so far
    is not tested: it could not change the groups. A wall seen by hundreds of scans
    is a stack of hundreds of segments whose pairs nearly all pass; after the first
    chunk most of them are connected (on hallways3d, all scans: 65 % of the 730k
    candidates are skipped). The groups, and so the merged faces, are those of all
    the passing pairs.
    """
    reach = max(params.merge_gap_m, params.merge_distance_m)
    label = np.arange(len(cur))  # a component label per segment, of the pairs passed so far
    merged = False
    for start in range(0, len(i), _MERGE_CHUNK):
        ci, cj = i[start : start + _MERGE_CHUNK], j[start : start + _MERGE_CHUNK]
        apart = label[ci] != label[cj]
        ci, cj = ci[apart], cj[apart]
        if len(ci) == 0:
            continue
        a, b, d, n, length = _line_geometry(cur, ci, cj)
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
        wi, wj = _within_distance(cur, ci[ok & ~sure], cj[ok & ~sure], reach)
        pi, pj = np.r_[ci[sure], wi], np.r_[cj[sure], wj]
        if len(pi):
            merged = True
            label = _union_find(len(cur), label[pi], label[pj])[label]
    return label if merged else None


def merge_segments(
    segments: np.ndarray, weights: np.ndarray, params: FloorplanParams = FloorplanParams()
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

    Returns
    -------
    faces : (F, 4) float64 ndarray
        Merged segments.
    face_weights : (F,) float64 ndarray
        Sum of the member weights.
    labels : (M,) int64 ndarray
        Face of each input segment.
    """
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    w = np.asarray(weights, dtype=np.float64).reshape(-1)
    if len(seg) != len(w):
        raise ValueError(f"{len(seg)} segments but {len(w)} weights")
    labels = np.arange(len(seg))
    cur, cur_w = seg, w
    for _ in range(max(1, params.max_passes)):
        reach = max(params.merge_gap_m, params.merge_distance_m)
        i, j = _candidate_pairs(cur, reach, np.radians(params.merge_angle_deg), exact=False)
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


# --------------------------------------------------------------------------------------
# Pairing
# --------------------------------------------------------------------------------------


def pair_faces(
    faces: np.ndarray, weights: np.ndarray, params: FloorplanParams = FloorplanParams()
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pair the two faces of a wall into one wall with its thickness.

    Two faces are one wall when their directions differ by at most
    ``pair_angle_deg``, the distance between their lines (measured from the longer
    face's line to the shorter's midpoint) is in ``[pair_min_m, pair_max_m]``, and
    they overlap along the wall by at least ``pair_min_overlap`` of the shorter.
    Pairs are taken greedily, nearest first, each face in at most one pair. The
    wall's axis is the line halfway between the two faces (direction the
    length-weighted axial mean), its extent the union of both faces' projections,
    its thickness their distance. An unpaired face becomes a wall whose axis is the
    face itself (which side the wall body lies on is not known) with
    ``default_thickness_m``.

    Parameters
    ----------
    faces : (F, 4) float ndarray
        Merged faces ``x0, y0, x1, y1``, metres.
    weights : (F,) float ndarray
    params : FloorplanParams

    Returns
    -------
    axes : (W, 4) float64 ndarray
        Wall axes, metres.
    thickness : (W,) float64 ndarray
        Metres.
    wall_of_face : (F,) int64 ndarray
        Wall of each face.
    """
    faces = np.asarray(faces, dtype=np.float64).reshape(-1, 4)
    nf = len(faces)
    wall_of_face = np.full(nf, -1, dtype=np.int64)
    axes, thick = [], []
    i, j = _candidate_pairs(faces, params.pair_max_m, np.radians(params.pair_angle_deg))
    if len(i):  # within pair_angle_deg already (_candidate_pairs)
        a, b, d, n, length = _line_geometry(faces, i, j)
        midb = 0.5 * (faces[b, :2] + faces[b, 2:])
        dist = np.abs(np.einsum("ij,ij->i", midb - faces[a, :2], n))
        tb0 = np.einsum("ij,ij->i", faces[b, :2] - faces[a, :2], d)
        tb1 = np.einsum("ij,ij->i", faces[b, 2:] - faces[a, :2], d)
        overlap = np.minimum(length[a], np.maximum(tb0, tb1)) - np.maximum(0.0, np.minimum(tb0, tb1))
        ok = (
            (dist >= params.pair_min_m)
            & (dist <= params.pair_max_m)
            & (overlap >= params.pair_min_overlap * np.minimum(length[a], length[b]))
        )
        order = np.lexsort((j[ok], i[ok], dist[ok]))
        pairs = []
        for p, q in zip(i[ok][order].tolist(), j[ok][order].tolist()):
            if wall_of_face[p] >= 0 or wall_of_face[q] >= 0:
                continue
            wall_of_face[p] = wall_of_face[q] = len(pairs)
            pairs.append((p, q))
        if pairs:
            p, q = np.array(pairs, dtype=np.int64).T
            pair_axes, pair_thick = _axis_between(faces[p], faces[q])
            axes.extend(pair_axes)
            thick.extend(pair_thick.tolist())
    for f in range(nf):
        if wall_of_face[f] < 0:
            wall_of_face[f] = len(axes)
            axes.append(faces[f].copy())
            thick.append(params.default_thickness_m)
    return np.array(axes).reshape(-1, 4), np.array(thick, dtype=np.float64), wall_of_face


def _axis_between(f: np.ndarray, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centre lines between pairs of near-parallel faces, (P, 4) metres, and their
    distances, (P,) metres; ``f`` and ``g`` are (P, 4) faces."""
    vf, vg = f[:, 2:] - f[:, :2], g[:, 2:] - g[:, :2]
    lf, lg = np.hypot(vf[:, 0], vf[:, 1]), np.hypot(vg[:, 0], vg[:, 1])
    af, ag = np.arctan2(vf[:, 1], vf[:, 0]), np.arctan2(vg[:, 1], vg[:, 0])
    # Length-weighted axial mean of the two directions.
    phi = 0.5 * np.arctan2(lf * np.sin(2 * af) + lg * np.sin(2 * ag), lf * np.cos(2 * af) + lg * np.cos(2 * ag))
    u = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    n = np.stack([-u[:, 1], u[:, 0]], axis=1)
    of = np.einsum("ij,ij->i", n, 0.5 * (f[:, :2] + f[:, 2:]))
    og = np.einsum("ij,ij->i", n, 0.5 * (g[:, :2] + g[:, 2:]))
    t = np.stack([np.einsum("ij,ij->i", e, u) for e in (f[:, :2], f[:, 2:], g[:, :2], g[:, 2:])], axis=1)
    off = 0.5 * (of + og)
    a = off[:, None] * n + t.min(axis=1)[:, None] * u
    b = off[:, None] * n + t.max(axis=1)[:, None] * u
    return np.concatenate([a, b], axis=1), np.abs(of - og)


# --------------------------------------------------------------------------------------
# Floor plan
# --------------------------------------------------------------------------------------


def segment_arrays(segments: pd.DataFrame) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """The segments as :func:`build_floorplan` merges them: in scan order (a stable
    sort by ``scan_id``, when there is one), those with a non-finite coordinate dropped
    (with a warning).

    Returns
    -------
    seg : (M, 4) float64 ndarray
        ``x0, y0, x1, y1``, metres.
    weights : (M,) float64 ndarray or None
        ``n_inliers``, when the table has it.
    scan_ids : (M,) int64 ndarray or None
        ``scan_id``, when the table has it.

    Raises
    ------
    KeyError
        When a coordinate column is missing.
    """
    missing = [c for c in ("x0", "y0", "x1", "y1") if c not in segments.columns]
    if missing:
        raise KeyError(f"wall segments lack columns {missing}; expected x0, y0, x1, y1")
    segments = _in_scan_order(segments)
    seg = segments[["x0", "y0", "x1", "y1"]].to_numpy(dtype=np.float64)
    finite = np.isfinite(seg).all(axis=1)
    if not finite.all():
        log.warning("dropping %d wall segments with non-finite coordinates", int((~finite).sum()))

    def column(name, dtype):
        return segments[name].to_numpy(dtype=dtype)[finite] if name in segments.columns else None

    return seg[finite], column("n_inliers", np.float64), column("scan_id", np.int64)


def plan_faces(
    seg: np.ndarray, weights: np.ndarray | None = None, params: FloorplanParams = FloorplanParams()
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The wall faces of a floor plan: the segments merged (:func:`merge_segments`),
    faces shorter than ``min_length_m`` dropped (:func:`build_floorplan`'s faces).

    Parameters
    ----------
    seg : (M, 4) float ndarray
        Finite segments ``x0, y0, x1, y1``, metres, in scan order.
    weights : (M,) float ndarray, optional
        Merge weights (inlier counts); a weight that is not positive, or no weights,
        is replaced by the segment's length.
    params : FloorplanParams

    Returns
    -------
    faces : (F, 4) float64 ndarray
        Metres.
    face_weights : (F,) float64 ndarray
    n_segments : (F,) int64 ndarray
        Segments merged into each face.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    w = length if weights is None else np.asarray(weights, dtype=np.float64)
    w = np.where(w > 0, w, np.maximum(length, 1e-6))
    faces, face_w, labels = merge_segments(seg, w, params)
    n_seg = np.bincount(labels, minlength=len(faces))
    flen = np.hypot(faces[:, 2] - faces[:, 0], faces[:, 3] - faces[:, 1]) if len(faces) else np.empty(0)
    keep = flen >= params.min_length_m
    return faces[keep].reshape(-1, 4), face_w[keep], n_seg[keep]


def build_floorplan(segments: pd.DataFrame, params: FloorplanParams = FloorplanParams()) -> FloorPlan:
    """The floor plan of wall segments from many scans: merged faces, paired walls.

    Parameters
    ----------
    segments : pandas.DataFrame
        ``x0, y0, x1, y1`` (metres) and optionally ``n_inliers`` (merge weights;
        else the segment lengths are the weights), e.g. a
        ``walls/{ordering}/{extractor}/k{k}.parquet`` table. With a ``scan_id``
        column the segments are taken in scan order (a stable sort), so the plan
        depends on which scans gave them, not on the order an ordering ranked
        the scans (every ordering's ``k = all`` gives the same plan).
    params : FloorplanParams

    Returns
    -------
    FloorPlan

    Raises
    ------
    KeyError
        When a coordinate column is missing.
    """
    seg, w, _ = segment_arrays(segments)
    faces, face_w, n_seg = plan_faces(seg, w, params)
    flen = np.hypot(faces[:, 2] - faces[:, 0], faces[:, 3] - faces[:, 1])
    axes, thick, wall_of_face = pair_faces(faces, face_w, params)
    nw = len(axes)
    faces_df = pd.DataFrame(
        {
            "face_id": np.arange(len(faces), dtype=np.int32),
            "wall_id": wall_of_face.astype(np.int32),
            "x0": faces[:, 0], "y0": faces[:, 1], "x1": faces[:, 2], "y1": faces[:, 3],
            "length_m": flen,
            "n_segments": n_seg.astype(np.int32),
            "n_inliers": np.round(face_w).astype(np.int64),
        }  # fmt: skip
    )
    walls = pd.DataFrame(
        {
            "wall_id": np.arange(nw, dtype=np.int32),
            "x0": axes[:, 0], "y0": axes[:, 1], "x1": axes[:, 2], "y1": axes[:, 3],
            "length_m": np.hypot(axes[:, 2] - axes[:, 0], axes[:, 3] - axes[:, 1]),
            "thickness_m": thick,
            "height_m": np.full(nw, params.wall_height_m),
            "paired": np.bincount(wall_of_face, minlength=nw) == 2,
            "n_faces": np.bincount(wall_of_face, minlength=nw).astype(np.int32),
            "n_segments": np.bincount(wall_of_face, weights=n_seg, minlength=nw).astype(np.int32),
            "n_inliers": np.round(np.bincount(wall_of_face, weights=face_w, minlength=nw)).astype(np.int64),
        }  # fmt: skip
    )
    log.info(
        "%d segments -> %d faces -> %d walls (%d with both faces)",
        len(seg), len(faces), nw, int(walls["paired"].sum()),
    )
    return FloorPlan(walls=walls[WALL_COLUMNS], faces=faces_df[FACE_COLUMNS])


# --------------------------------------------------------------------------------------
# Exports
# --------------------------------------------------------------------------------------


def _exterior_rings(polys) -> list:
    """Exterior ring of each footprint as a list of ``[x, y]`` (closed: the first
    point repeated last), or None for a missing or empty footprint.

    The coordinates of all the rings come from one ``shapely.get_coordinates`` call
    (the same doubles as ``poly.exterior.coords``), not a coordinate sequence per wall.
    """
    import shapely

    out: list = [None] * len(polys)
    if not len(polys):
        return out
    ok = np.flatnonzero(~(shapely.is_missing(polys) | shapely.is_empty(polys)))
    if not len(ok):
        return out
    coords, index = shapely.get_coordinates(shapely.get_exterior_ring(polys[ok]), return_index=True)
    bounds = np.r_[0, np.cumsum(np.bincount(index, minlength=len(ok)))].tolist()
    pts = coords.tolist()
    for n, k in enumerate(ok.tolist()):
        out[k] = pts[bounds[n] : bounds[n + 1]]
    return out


def floorplan_geojson(plan: FloorPlan) -> dict:
    """GeoJSON FeatureCollection (metres, map frame) of a floor plan.

    Features, with property ``kind`` as in the ground truth ``walls.geojson``:
    ``axis`` (LineString centre line; ``wall_id``, ``thickness_m``, ``height_m``,
    ``length_m``, ``paired``, ``n_segments``), ``footprint`` (Polygon of the wall;
    ``wall_id``, ``thickness_m``), ``face`` (LineString merged face; ``face_id``,
    ``wall_id``, ``n_segments``, ``n_inliers``). Coordinates are rounded to 5
    decimals (10 um), thickness and length to 4.
    """
    return _floorplan_geojson(plan, plan.footprints())


def _floorplan_geojson(plan: FloorPlan, polys, rings: list | None = None) -> dict:
    """:func:`floorplan_geojson` given the plan's footprints (:meth:`FloorPlan.footprints`).

    A footprint's coordinates are its exterior ring's (:func:`_exterior_rings`),
    rounded: what ``shapely.to_geojson`` writes (shortest round-trip digits) read
    back and rounded, without the JSON text in between. A footprint that is not a
    Polygon without holes (a buffered axis always is) goes through
    ``shapely.to_geojson``.
    """
    import shapely

    floats = ("x0", "y0", "x1", "y1", "thickness_m", "height_m", "length_m")

    def col(df, c):  # floats as float64 (not DataFrame.astype: 3 ms a call)
        return df[c].to_numpy(dtype=np.float64).tolist() if c in floats else df[c].tolist()

    def line(x0, y0, x1, y1):
        return {"type": "LineString", "coordinates": [[round(x0, 5), round(y0, 5)], [round(x1, 5), round(y1, 5)]]}

    feats = []
    w = plan.walls
    if rings is None:
        rings = _exterior_rings(polys)
    plain = (
        (shapely.get_type_id(polys) == 3) & (shapely.get_num_interior_rings(polys) == 0)
        if len(polys) else np.zeros(0, bool)
    ).tolist()  # fmt: skip
    for wall_id, x0, y0, x1, y1, thick, height, length, paired, n_seg, poly, ring, simple in zip(
        col(w, "wall_id"), col(w, "x0"), col(w, "y0"), col(w, "x1"), col(w, "y1"), col(w, "thickness_m"),
        col(w, "height_m"), col(w, "length_m"), col(w, "paired"), col(w, "n_segments"), polys, rings, plain,
    ):  # fmt: skip
        thick = round(thick, 4)
        props = {
            "wall_id": int(wall_id), "thickness_m": thick, "height_m": height, "length_m": round(length, 4),
            "paired": bool(paired), "n_segments": int(n_seg),
        }  # fmt: skip
        feats.append(_feature("axis", line(x0, y0, x1, y1), props))
        if ring is not None:
            if simple:
                geom = {"type": "Polygon", "coordinates": [[[round(x, 5), round(y, 5)] for x, y in ring]]}
            else:
                geom = _round_coords(json.loads(shapely.to_geojson(poly)))
            feats.append(_feature("footprint", geom, {"wall_id": int(wall_id), "thickness_m": thick}))
    f = plan.faces
    for face_id, wall_id, x0, y0, x1, y1, n_seg, n_inl in zip(
        col(f, "face_id"), col(f, "wall_id"), col(f, "x0"), col(f, "y0"), col(f, "x1"), col(f, "y1"),
        col(f, "n_segments"), col(f, "n_inliers"),
    ):  # fmt: skip
        props = {"face_id": int(face_id), "wall_id": int(wall_id), "n_segments": int(n_seg), "n_inliers": int(n_inl)}
        feats.append(_feature("face", line(x0, y0, x1, y1), props))
    return {"type": "FeatureCollection", "features": feats}


def _feature(kind: str, geometry: dict, props: dict) -> dict:
    return {"type": "Feature", "geometry": geometry, "properties": {"kind": kind, **props}}


def _round_coords(geom: dict) -> dict:
    def r(c):
        return [r(x) for x in c] if isinstance(c, (list, tuple)) else round(float(c), 5)

    return {**geom, "coordinates": r(geom["coordinates"])}


def write_geojson(plan: FloorPlan, path: str | os.PathLike) -> None:
    """Write :func:`floorplan_geojson` atomically, one feature per line.

    The layout (a feature per line, ``json.dumps`` defaults within it) lets the C
    encoder of :mod:`json` write it: ``indent`` makes ``json`` use its pure-Python
    encoder, which took 70 % of this function's time on large plans.
    """
    _write_geojson(plan, path, plan.footprints())


def _write_geojson(plan: FloorPlan, path: str | os.PathLike, polys, rings: list | None = None) -> None:
    doc = _floorplan_geojson(plan, polys, rings)
    feats = ",\n".join(map(json.dumps, doc["features"]))
    text = f'{{"type": "FeatureCollection", "features": [\n{feats}\n]}}\n' if feats else json.dumps(doc) + "\n"
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def write_svg(plan: FloorPlan, path: str | os.PathLike, px_per_m: float = 40.0, title: str = "") -> None:
    """Write the floor plan as SVG: wall polygons (grey) and axes (red), 1 unit = 1 m.

    The y axis points up as in the map frame (a flip transform); the drawing is
    ``px_per_m`` pixels per metre.
    """
    _write_svg(plan, path, plan.footprints(), px_per_m, title)


def _write_svg(
    plan: FloorPlan, path: str | os.PathLike, polys, px_per_m: float = 40.0, title: str = "", rings: list | None = None
) -> None:
    if len(plan.walls):
        xs = plan.walls[["x0", "x1"]].to_numpy()
        ys = plan.walls[["y0", "y1"]].to_numpy()
        pad = 0.5 + float(plan.walls["thickness_m"].max())
        xmin, xmax, ymin, ymax = xs.min() - pad, xs.max() + pad, ys.min() - pad, ys.max() + pad
    else:
        xmin, xmax, ymin, ymax = 0.0, 1.0, 0.0, 1.0
    w, h = xmax - xmin, ymax - ymin
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{w * px_per_m:.0f}" height="{h * px_per_m:.0f}" '
        f'viewBox="{xmin:.3f} {-ymax:.3f} {w:.3f} {h:.3f}">',
        f"<title>{_xml(title or 'floor plan')}</title>",
        '<g transform="scale(1,-1)">',
        '<g id="walls" fill="#9a9a9a" stroke="#333" stroke-width="0.01">',
    ]
    for ring in _exterior_rings(polys) if rings is None else rings:
        if ring is None:
            continue
        pts = " ".join(f"{x:.4f},{y:.4f}" for x, y in ring[:-1])
        out.append(f'<polygon points="{pts}"/>')
    out.append("</g>")
    out.append('<g id="axes" stroke="#c00" stroke-width="0.02" fill="none">')
    walls = plan.walls
    for wall_id, x0, y0, x1, y1, length, thickness in zip(
        *(walls[c].tolist() for c in ("wall_id", "x0", "y0", "x1", "y1", "length_m", "thickness_m"))
    ):
        out.append(
            f'<line x1="{x0:.4f}" y1="{y0:.4f}" x2="{x1:.4f}" y2="{y1:.4f}">'
            f"<title>wall {wall_id}: {length:.2f} m x {thickness:.2f} m</title></line>"
        )
    out += ["</g>", "</g>", "</svg>"]
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(out) + "\n")


def _xml(s: str) -> str:
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def write_dxf(plan: FloorPlan, path: str | os.PathLike, version: str = "R12") -> None:
    """Write the floor plan as DXF (ezdxf), coordinates in metres (map frame).

    Layers (:data:`DXF_LAYERS`): ``WALL_AXIS`` (a LINE per wall centre line),
    ``WALL_OUTLINE`` (a closed polyline per wall polygon), ``WALL_FACE`` (a LINE per
    merged face).

    ``"R12"`` (default): ezdxf's stream writer (``ezdxf.addons.r12writer``) with its
    fixed tables; the outline is a closed POLYLINE, each entity carries its layer's
    colour, and a comment (group 999) says the unit. R12 has no units header
    (``$INSUNITS`` came with R2000), so CAD tools treat the drawing as unitless. The
    version every CAD tool reads, and 7-10x cheaper to write than R2010 (ezdxf 1.4,
    702 walls and 1150 faces: 0.03 against 0.20-0.33 s; the 46 distinct plans of one
    hallways3d extractor 0.4-0.55 against 2.9-3.7 CPU-s, a third of the floor-plan
    stage's CPU before; issue 8).
    ``"R2010"``: a full ezdxf document with a layer table and ``$INSUNITS`` = metres;
    the outline is an LWPOLYLINE.

    Raises
    ------
    ValueError
        For another ``version``.
    """
    _write_dxf(plan, path, plan.footprints(), version=version)


def _write_dxf(plan: FloorPlan, path: str | os.PathLike, polys, rings: list | None = None, version: str = "R12") -> None:
    """:func:`write_dxf` given the plan's footprints (:meth:`FloorPlan.footprints`)."""
    if version not in DXF_VERSIONS:
        raise ValueError(f"DXF version must be one of {list(DXF_VERSIONS)}, got {version!r}")
    w, f = plan.walls, plan.faces
    axes = zip(
        w["x0"].tolist(), w["y0"].tolist(), w["x1"].tolist(), w["y1"].tolist(),
        _exterior_rings(polys) if rings is None else rings,
    )  # fmt: skip
    faces = zip(f["x0"].tolist(), f["y0"].tolist(), f["x1"].tolist(), f["y1"].tolist())
    if version == "R12":
        from ezdxf.addons.r12writer import R12FastStreamWriter

        axis_c, outline_c, face_c = DXF_LAYERS["WALL_AXIS"], DXF_LAYERS["WALL_OUTLINE"], DXF_LAYERS["WALL_FACE"]
        with atomic_path(path) as tmp, open(tmp, "w", encoding="cp1252", newline="\n") as stream:
            stream.write("999\nfloorscan floor plan: coordinates in metres (map frame)\n")
            dxf = R12FastStreamWriter(stream, fixed_tables=True)
            for x0, y0, x1, y1, ring in axes:
                dxf.add_line((x0, y0), (x1, y1), layer="WALL_AXIS", color=axis_c)
                if ring is not None:
                    dxf.add_polyline_2d(ring[:-1], closed=True, layer="WALL_OUTLINE", color=outline_c)
            for x0, y0, x1, y1 in faces:
                dxf.add_line((x0, y0), (x1, y1), layer="WALL_FACE", color=face_c)
            dxf.close()
        return
    import ezdxf
    from ezdxf import units

    logging.getLogger("ezdxf").setLevel(logging.WARNING)  # its INFO lines would flood the stage log
    doc = ezdxf.new("R2010")
    doc.units = units.M
    for name, color in DXF_LAYERS.items():
        doc.layers.add(name, color=color)
    msp = doc.modelspace()
    for x0, y0, x1, y1, ring in axes:
        msp.add_line((x0, y0), (x1, y1), dxfattribs={"layer": "WALL_AXIS"})
        if ring is not None:
            msp.add_lwpolyline(ring[:-1], close=True, dxfattribs={"layer": "WALL_OUTLINE"})
    for x0, y0, x1, y1 in faces:
        msp.add_line((x0, y0), (x1, y1), dxfattribs={"layer": "WALL_FACE"})
    with atomic_path(path) as tmp:
        doc.saveas(tmp)


def _ifc_model(plan: FloorPlan, name: str):
    """The IFC model of ``plan`` (see :func:`write_ifc`) for a project named ``name``,
    its GlobalIds given as each entity is made, as :func:`_name_ifc` sets them."""
    try:
        import ifcopenshell.api.aggregate
        import ifcopenshell.api.context
        import ifcopenshell.api.project
        import ifcopenshell.api.root
        import ifcopenshell.api.unit
    except ImportError as e:  # pragma: no cover
        raise ImportError("writing IFC needs ifcopenshell: pip install ifcopenshell") from e

    api = ifcopenshell.api
    model = api.project.create_file(version="IFC4")
    project = api.root.create_entity(model, ifc_class="IfcProject", name=name)
    units = [api.unit.add_si_unit(model, unit_type=u) for u in ("LENGTHUNIT", "AREAUNIT", "VOLUMEUNIT")]
    api.unit.assign_unit(model, units=units)
    # assign_unit keeps the units in a set: their order changed from run to run
    model.by_type("IfcUnitAssignment")[0].Units = tuple(units)
    model3d = api.context.add_context(model, context_type="Model")
    body = api.context.add_context(
        model, context_type="Model", context_identifier="Body", target_view="MODEL_VIEW", parent=model3d
    )
    plan_ctx = api.context.add_context(model, context_type="Plan")
    axis_ctx = api.context.add_context(
        model, context_type="Plan", context_identifier="Axis", target_view="GRAPH_VIEW", parent=plan_ctx
    )
    site = api.root.create_entity(model, ifc_class="IfcSite", name="Site")
    building = api.root.create_entity(model, ifc_class="IfcBuilding", name="Building")
    storey = api.root.create_entity(model, ifc_class="IfcBuildingStorey", name="Storey 0")
    for whole, part in ((project, site), (site, building), (building, storey)):
        api.aggregate.assign_object(model, relating_object=whole, products=[part])
    storey.Elevation = 0.0
    # Stable GlobalIds (from the project name and creation order), so a rerun gives
    # the same ids and BIM tools see the same walls, not new ones: the spatial
    # structure's in creation order, then 3 a wall, then the container's.
    roots = sorted(model.by_type("IfcRoot"), key=lambda e: e.id())
    guids = iter(_ifc_guid_list(name, len(roots) + 3 * len(plan.walls) + 1))
    guid = guids.__next__
    for entity in roots:
        entity.GlobalId = guid()
    ent = _entity_maker(model)

    # The walls' entities (those ifcopenshell.api's add_wall_representation,
    # add_axis_representation, edit_object_placement, add_qto and assign_container
    # make) come from create_entity (as :func:`_entity_maker` makes them): the API
    # costs milliseconds per call, which made IFC the slowest export of thousands of
    # walls. An entity costs ~2 us and each given attribute ~1 us (ifcopenshell
    # 0.9, 20 entities and 45 attributes a wall, most of this function's time), so
    # unset (None) attributes are
    # not passed (keywords instead), and the geometric entities that many walls have
    # alike are made once: the +Z and +X directions, and per thickness the corner
    # point of the body profile and its placement (most walls have the default
    # thickness). Each wall keeps its own profile, representations, placement,
    # quantities and relations.
    z_dir = ent("IfcDirection", (0.0, 0.0, 1.0))
    x_dir = ent("IfcDirection", (1.0, 0.0, 0.0))
    solid_position: dict[float, Any] = {}  # thickness -> IfcAxis2Placement3D of the profile corner
    walls = []
    w = plan.walls
    x0, y0, x1, y1 = (w[c].to_numpy(dtype=np.float64) for c in ("x0", "y0", "x1", "y1"))
    dxy = np.stack([x1 - x0, y1 - y0], axis=1)
    for wall_id, p0x, p0y, d, thickness, height in zip(
        w["wall_id"].tolist(), x0.tolist(), y0.tolist(), dxy,
        w["thickness_m"].to_numpy(dtype=np.float64).tolist(), w["height_m"].to_numpy(dtype=np.float64).tolist(),
    ):  # fmt: skip
        length = float(np.linalg.norm(d))
        if length <= 0:
            continue
        dx, dy = (d / length).tolist()
        # Body: the rectangle length x thickness, centred on the axis, extruded up.
        outline = ent(
            "IfcCartesianPointList2D",
            ((0.0, 0.0), (0.0, thickness), (length, thickness), (length, 0.0), (0.0, 0.0)),
        )
        curve = ent("IfcIndexedPolyCurve", Points=outline, SelfIntersect=False)
        profile = ent("IfcArbitraryClosedProfileDef", ProfileType="AREA", OuterCurve=curve)
        position = solid_position.get(thickness)
        if position is None:
            corner = ent("IfcCartesianPoint", (0.0, -thickness / 2.0, 0.0))
            position = solid_position[thickness] = ent("IfcAxis2Placement3D", corner, z_dir, x_dir)
        solid = ent("IfcExtrudedAreaSolid", profile, position, z_dir, height)
        body_rep = ent("IfcShapeRepresentation", body, "Body", "SweptSolid", (solid,))
        axis_pts = ent("IfcCartesianPointList2D", ((0.0, 0.0), (length, 0.0)))
        axis_curve = ent("IfcIndexedPolyCurve", Points=axis_pts, SelfIntersect=False)
        axis_rep = ent("IfcShapeRepresentation", axis_ctx, "Axis", "Curve2D", (axis_curve,))
        start = ent("IfcCartesianPoint", (p0x, p0y, 0.0))
        along = ent("IfcDirection", (dx, dy, 0.0))
        placement = ent("IfcLocalPlacement", RelativePlacement=ent("IfcAxis2Placement3D", start, z_dir, along))
        shape = ent("IfcProductDefinitionShape", Representations=(body_rep, axis_rep))
        wall = ent(
            "IfcWall", GlobalId=guid(), Name=f"Wall {wall_id}", ObjectPlacement=placement, Representation=shape
        )
        quantities = (
            ent("IfcQuantityLength", Name="Length", LengthValue=length),
            ent("IfcQuantityLength", Name="Width", LengthValue=thickness),
            ent("IfcQuantityLength", Name="Height", LengthValue=height),
        )
        qto = ent("IfcElementQuantity", GlobalId=guid(), Name="Qto_WallBaseQuantities", Quantities=quantities)
        ent("IfcRelDefinesByProperties", GlobalId=guid(), RelatedObjects=(wall,), RelatingPropertyDefinition=qto)
        walls.append(wall)
    if walls:
        ent("IfcRelContainedInSpatialStructure", guid(), None, None, None, walls, storey)
    return model


def write_ifc(plan: FloorPlan, path: str | os.PathLike, name: str = "floorscan") -> None:
    """Write the floor plan as IFC4 (IfcOpenShell), units metres.

    IfcProject > IfcSite > IfcBuilding > IfcBuildingStorey (elevation 0) containing an
    ``IfcWall`` per wall: a body (SweptSolid, as ``geometry.add_wall_representation``
    makes it: the rectangle length x thickness centred on the axis, extruded by
    ``height_m``), an axis representation (Plan/Axis, Curve2D), its placement at the
    axis start along the axis direction, and the quantities
    ``Qto_WallBaseQuantities`` Length, Width, Height. The project, units, contexts and
    spatial structure come from ``ifcopenshell.api``; the walls' entities (those its
    per-wall calls would make) as ``file.create_entity`` makes them, because those calls,
    milliseconds each, were the stage's bottleneck (663 walls of hallways3d: 0.6 -
    0.7 s CPU per file; STEP lines written by hand took 0.19 s, but the library's
    writer is the one to keep). The units keep a fixed order (``assign_unit`` keeps
    them in a set, whose order changed from run to run).
    GlobalIds derive from ``name`` and the creation order (same plan, same ids).

    Raises
    ------
    ImportError
        When ifcopenshell is not installed (``pip install ifcopenshell``).
    """
    _save_ifc(_ifc_model(plan, name), path)


def _save_ifc(model, path: str | os.PathLike) -> None:
    """Write ``model`` to ``path`` atomically as IFC-SPF text: ``model.to_string()``
    (the text ``model.write`` writes) in one write, which took three quarters of
    ``model.write``'s time (17 against 23 ms for 205 walls, ifcopenshell 0.9)."""
    text = model.to_string()
    with atomic_path(path) as tmp:
        tmp.write_bytes(text.encode("utf-8"))


def _entity_maker(model):
    """``model.create_entity`` (same arguments, same entity), at a third of its cost.

    ``file.create_entity`` sets each given attribute through
    ``entity_instance.__setitem__``, which makes a Python ``file`` object per call
    (``entity_instance.file``) to ask it for an open undo transaction: with 20
    entities and 45 attributes a wall that was half of :func:`_ifc_model`'s time. With
    no transaction open (none is: this module begins none), the entity is made by
    ``file.create`` and its attributes set by ``entity_instance.set_attribute_value_py``,
    the two calls ``create_entity`` and ``__setitem__`` end in; keyword names map to
    attribute indices once per class. With a transaction open, or an ifcopenshell
    without those calls, this is ``model.create_entity`` itself.
    """
    import ifcopenshell

    create = getattr(model, "create", None)
    setter = getattr(ifcopenshell.entity_instance, "set_attribute_value_py", None)
    if create is None or setter is None or getattr(model, "transaction", None) is not None:
        return model.create_entity
    index: dict[tuple[str, str], int] = {}

    def ent(cls: str, *args, **kwargs):
        e = create(cls, -1)
        for i, v in enumerate(args):
            setter(e, i, v)
        for k, v in kwargs.items():
            i = index.get((cls, k))
            if i is None:
                i = e.get_argument_index(k)
                if i >= len(e):
                    raise ValueError(f"entity instance of type {cls!r} has no attribute {k!r}")
                index[(cls, k)] = i
            setter(e, i, v)
        return e

    return ent


def _name_ifc(model, name: str) -> None:
    """Name the IFC project ``name`` and derive every GlobalId from it and the
    creation order: the same plan and name give the same ids, and renaming a model
    gives the ids a fresh model of that name would have."""
    model.by_type("IfcProject")[0].Name = name
    roots = sorted(model.by_type("IfcRoot"), key=lambda e: e.id())
    for entity, guid in zip(roots, _ifc_guid_list(name, len(roots))):
        entity.GlobalId = guid


def _ifc_guid_list(name: str, n: int) -> list[str]:
    """The first ``n`` GlobalIds of the model named ``name``, in creation order:
    ``ifcopenshell.guid.compress(uuid5(ns, str(i)).hex)`` for i = 0 .. n-1, ``ns`` the
    ``uuid5`` of ``floorscan:{name}`` (URL namespace): the same plan and name give the
    same ids."""
    import ifcopenshell.guid

    ns = uuid.uuid5(uuid.NAMESPACE_URL, f"floorscan:{name}")
    compress = ifcopenshell.guid.compress
    return [compress(uuid.uuid5(ns, str(i)).hex) for i in range(n)]


FLOORPLAN_FORMATS = ("geojson", "svg", "dxf", "ifc")


class FloorplanWriter:
    """Builds and writes floor plans (stage ``floorplan``); a plan of the same segments
    as one it wrote before is copied, not built and exported again.

    A sweep writes one plan per ordering and k, and every ordering's ``k = all`` (and
    any k past the number of scans) holds the same scans: :func:`build_floorplan`
    takes segments in scan order, so those plans are the same plan. The copy's GeoJSON
    and DXF are the first file's bytes (neither names the plan; the DXF keeps the
    first file's creation time), its SVG title and IFC project name and GlobalIds are
    its own, as a fresh export would make them. On hallways3d this skips 4 of the 5
    largest plans per extractor.

    Parameters
    ----------
    cfg : mapping
        The ``floorplan`` config section.

    Raises
    ------
    KeyError
        For an unknown config key (on construction) or output format (:meth:`write`).
    """

    def __init__(self, cfg: Mapping[str, Any] | None):
        self.params = params_from_config(cfg)
        self._written: dict[bytes, tuple[FloorPlan, dict[str, str], Any]] = {}

    def write(self, segments: pd.DataFrame, outputs: Mapping[str, str | os.PathLike], name: str = "") -> tuple[FloorPlan, bool]:
        """Build the floor plan of ``segments`` and write it to ``outputs``.

        Parameters
        ----------
        segments : pandas.DataFrame
            Wall segments (``walls/{ordering}/{extractor}/k{k}.parquet``).
        outputs : mapping
            Paths by format: any of :data:`FLOORPLAN_FORMATS`.
        name : str
            Title of the SVG and name of the IFC project.

        Returns
        -------
        plan : FloorPlan
        copied : bool
            Whether the plan equals one written before (same segments), and so was copied.

        Raises
        ------
        KeyError
            For an unknown output format, or a missing coordinate column.
        """
        unknown = sorted(set(outputs) - set(FLOORPLAN_FORMATS))
        if unknown:
            raise KeyError(f"unknown floor plan formats {unknown}; expected {list(FLOORPLAN_FORMATS)}")
        segments = _in_scan_order(segments)  # as build_floorplan takes them (sorted once)
        key = _segments_key(segments)
        done = self._written.get(key)
        name = name or "floorscan"
        if done is None:
            plan = build_floorplan(segments, self.params)
            model = None
        else:
            plan, first, model = done
        polys = rings = None  # the footprints and their rings, made once for the SVG, GeoJSON and DXF
        for fmt, path in outputs.items():
            copy = fmt in ("geojson", "dxf") and done is not None and fmt in first
            if fmt != "ifc" and not copy and polys is None:
                polys = plan.footprints()
                rings = _exterior_rings(polys)
            if fmt == "svg":
                _write_svg(plan, path, polys, title=name, rings=rings)
            elif fmt == "ifc":
                if model is None:
                    model = _ifc_model(plan, name)
                else:
                    _name_ifc(model, name)
                _save_ifc(model, path)
            elif copy:
                with atomic_path(path) as tmp:
                    shutil.copyfile(first[fmt], tmp)
            elif fmt == "dxf":
                _write_dxf(plan, path, polys, rings, version=self.params.dxf_version)
            else:
                _write_geojson(plan, path, polys, rings)
        if done is None:
            self._written[key] = (plan, {f: str(p) for f, p in outputs.items()}, model)
        return plan, done is not None


def _segments_key(segments: pd.DataFrame) -> bytes:
    """Digest of the segments (in scan order: what :func:`build_floorplan` reads)."""
    h = hashlib.sha256()
    for c in segments.columns:
        h.update(c.encode() + b"\0" + np.ascontiguousarray(segments[c].to_numpy()).tobytes())
    return h.digest()


def _in_scan_order(segments: pd.DataFrame) -> pd.DataFrame:
    """``segments`` stably sorted by ``scan_id`` (unchanged without that column)."""
    if "scan_id" not in segments.columns or segments["scan_id"].is_monotonic_increasing:
        return segments
    return segments.iloc[np.argsort(segments["scan_id"].to_numpy(), kind="stable")]


def write_floorplan(
    segments: pd.DataFrame, cfg: Mapping[str, Any] | None, outputs: Mapping[str, str | os.PathLike], name: str = ""
) -> FloorPlan:
    """Build the floor plan of ``segments`` and write it: ``FloorplanWriter(cfg).write(
    segments, outputs, name)`` (see there; ``cfg`` is the ``floorplan`` config section),
    returning the :class:`FloorPlan`. Raises ``KeyError`` for an unknown output format
    or config key."""
    return FloorplanWriter(cfg).write(segments, outputs, name)[0]

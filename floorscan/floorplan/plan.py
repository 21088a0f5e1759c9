"""Floor plan: one wall per wall from the wall segments of many scans, and its exports.

Wall extraction runs per scan, so one wall of the building is seen by many scans and
appears as many overlapping segments (thesis section 5.1 names this duplicate
problem). :func:`merge_segments` merges the segments that describe one wall face;
:func:`pair_faces` pairs the two faces of a wall (parallel, 5 to 40 cm apart,
overlapping) into one wall with its thickness; :func:`build_floorplan` does both.

Exports (the thesis's purpose, Chapter 1: a plan people and their tools open). Every
file is written atomically (:func:`floorscan.core.files.atomic_path`), carries what it is a
plan of (:class:`PlanMetadata`: dataset, ordering, extractor, k, number of walls, a
time stamp) and is byte-identical when written again from the same input. The frame
is the map frame of the recording: a local engineering frame, x and y in metres, z up,
no geodetic datum; wall properties (thickness, length, height) are metres everywhere.

- GeoJSON (:func:`write_geojson`; people, GIS, the scorer): a ``FeatureCollection``
  of wall axes, wall footprints and merged faces (:func:`floorplan_geojson`).
  Polygons follow RFC 7946 section 3.1.6: counter-clockwise outer rings, clockwise
  holes. A collection-level foreign member ``floorscan`` holds the frame, units,
  plan metadata and georeference. Without a georeference the coordinates are map
  metres, which RFC 7946 allows only "by prior arrangement": GDAL (and so QGIS)
  reads a file without a ``crs`` member as WGS84 longitude/latitude, but still reads
  the GeoJSON 2008 ``crs`` member (type ``name``, its ``properties.name`` through
  ``OGRSpatialReference::SetFromUserInput``, which takes WKT; ogrgeojsonreader.cpp).
  So the file carries that member with :data:`LOCAL_FRAME_WKT`, a WKT1 ``LOCAL_CS``
  in metres: GIS tools see a local engineering frame and do not place the plan on
  a world map at (0 deg, 0 deg) as if its metres were degrees. With
  ``floorplan.georeference`` (:class:`Georeference`) the coordinates are WGS84
  longitude, latitude (:func:`map_to_lonlat`), an RFC 7946 file without ``crs``;
  the scorer (:mod:`floorscan.score.metrics`) reads coordinates as map metres, so such a
  plan is scored after :func:`lonlat_to_map`.
- SVG (:func:`write_svg`; a browser): a plain SVG (no scripts) that scales to any
  window (``viewBox``, width and height 100 %), with a title, the wall polygons (walls
  of which one face was seen drawn lighter and dashed), axes, a scale bar of a round
  length in metres, a legend and the map frame's x (right) and y (up) axes; the map's
  y is up, SVG's down: the drawing is flipped. With a georeference, a north arrow.
- DXF (:func:`write_dxf`; CAD, ezdxf): layers :data:`DXF_LAYERS` in the layer table,
  map coordinates in metres. R2010 (default): ``$INSUNITS`` 6 (metres) and
  ``$MEASUREMENT`` 1 (metric). R12 (``floorplan.dxf_version: R12``, for old tools)
  has no units header (``$INSUNITS`` came with R2000): a CAD tool takes its numbers
  as unitless. ezdxf's audit finds no error in either.
- IFC4 (:func:`write_ifc`; BIM, IfcOpenShell's API): IfcProject > IfcSite >
  IfcBuilding > IfcBuildingStorey, an ``IfcWall`` per wall placed relative to its
  storey, units metres, a STEP header naming the dataset and floorscan's version,
  a time stamp from the plan's ``timestamp``, else ``SOURCE_DATE_EPOCH``, else 0
  (:func:`export_time`: never the clock), GlobalIds from the plan's name.
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import io
import json
import logging
import math
import os
import uuid
from dataclasses import dataclass, replace
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np
import pandas as pd

from floorscan.core.files import atomic_path

log = logging.getLogger(__name__)

#: Columns of :attr:`FloorPlan.walls`.
WALL_COLUMNS = [
    "wall_id", "x0", "y0", "x1", "y1", "length_m", "thickness_m", "height_m",
    "paired", "n_faces", "n_segments", "n_inliers",
]  # fmt: skip
#: DXF versions :func:`write_dxf` writes (R2010 the default: R12 has no units header).
DXF_VERSIONS = ("R2010", "R12")
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
        DXF export: ``"R2010"`` (units header: metres) or ``"R12"`` (no units
        header; see :func:`write_dxf`).
    georeference : Georeference or None
        Where the map frame lies on the earth (a mapping ``lat``, ``lon``,
        ``heading_deg`` is converted); with one the GeoJSON coordinates are WGS84
        longitude and latitude, the SVG gets a north arrow and the IFC site its
        reference latitude, longitude and true north. None: map metres.
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
    dxf_version: str = "R2010"
    georeference: Georeference | None = None

    def __post_init__(self):
        if self.georeference is not None:  # a config mapping -> Georeference (checked)
            object.__setattr__(self, "georeference", as_georeference(self.georeference))
        if self.dxf_version not in DXF_VERSIONS:
            raise ValueError(f"floorplan.dxf_version must be one of {list(DXF_VERSIONS)}, got {self.dxf_version!r}")
        if not self.pair_min_m < self.pair_max_m:
            raise ValueError(
                f"floorplan.pair_min_m ({self.pair_min_m}) must be below pair_max_m ({self.pair_max_m})"
            )


#: Keys of the ``floorplan`` config section that the workflow reads, not the plan:
#: the recommended plan's extractor and the formats of the evaluation grid's plans.
WORKFLOW_KEYS = ("extractor", "evaluation_formats")


def params_from_config(cfg: Mapping[str, Any] | None) -> FloorplanParams:
    """:class:`FloorplanParams` of the ``floorplan`` config section (without
    :data:`WORKFLOW_KEYS`).

    Raises
    ------
    KeyError
        For a key the class does not know.
    """
    from floorscan.core.config import dataclass_from_mapping

    plan_cfg = {k: v for k, v in (cfg or {}).items() if k not in WORKFLOW_KEYS}
    return dataclass_from_mapping(FloorplanParams, plan_cfg, "floorplan")


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
    point). Used here and by :mod:`floorscan.score.metrics`."""
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


#: WGS84 ellipsoid (NIMA TR8350.2): semi-major axis, metres, and flattening.
WGS84_A = 6378137.0
WGS84_F = 1.0 / 298.257223563
#: The GeoJSON 2008 ``crs`` name of a plan in map metres (WKT1 ``LOCAL_CS``): GDAL reads
#: it as a local engineering CRS in metres (without a ``crs`` member: WGS84 degrees).
#: EAST and NORTH are WKT1's names of a local frame's x (right) and y (up) axes.
LOCAL_FRAME_WKT = (
    'LOCAL_CS["floorscan map frame",LOCAL_DATUM["map frame of the recording",32767],'
    'UNIT["metre",1],AXIS["x",EAST],AXIS["y",NORTH]]'
)
#: Decimals of GeoJSON coordinates: map metres (10 um) and WGS84 degrees (1e-10
#: degree: 11 um of latitude, the same resolution).
GEOJSON_DECIMALS = {"map": 5, "WGS84": 10}


@dataclass(frozen=True)
class Georeference:
    """Where the map frame lies on the earth (config ``floorplan.georeference``).

    The map frame is taken as the plane tangent to the WGS84 ellipsoid at its origin
    (a local east-north-up frame turned by the heading): a map point ``(x, y)`` lies
    ``east = x sin(h) - y cos(h)``, ``north = x cos(h) + y sin(h)`` metres from the
    origin (``h`` the heading). See :func:`map_to_lonlat`.

    Attributes
    ----------
    lat : float
        WGS84 latitude of the map frame's origin, degrees, in (-90, 90) (at a pole
        east is undefined).
    lon : float
        WGS84 longitude of the origin, degrees, in [-180, 180].
    heading_deg : float
        Direction of the map frame's +x axis, degrees clockwise from true north (a
        compass bearing: 0 = +x points north and +y west, 90 = +x east and +y north).

    Raises
    ------
    ValueError
        For a value that is not a finite number or out of its range.
    """

    lat: float
    lon: float
    heading_deg: float = 0.0

    def __post_init__(self):
        for name in ("lat", "lon", "heading_deg"):
            value = getattr(self, name)
            number = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
            if not number or not math.isfinite(value):
                raise ValueError(f"floorplan.georeference.{name} must be a finite number, got {value!r}")
            object.__setattr__(self, name, float(value))
        if not -90.0 < self.lat < 90.0:
            raise ValueError(f"floorplan.georeference.lat must be in (-90, 90) degrees, got {self.lat}")
        if not -180.0 <= self.lon <= 180.0:
            raise ValueError(f"floorplan.georeference.lon must be in [-180, 180] degrees, got {self.lon}")

    def radii(self) -> tuple[float, float]:
        """WGS84 radii of curvature at :attr:`lat`, metres: meridian ``M = a (1 - e^2)
        / (1 - e^2 sin^2 lat)^1.5`` and prime vertical ``N = a / (1 - e^2 sin^2 lat)^0.5``."""
        e2 = WGS84_F * (2.0 - WGS84_F)
        w2 = 1.0 - e2 * math.sin(math.radians(self.lat)) ** 2
        return WGS84_A * (1.0 - e2) / w2**1.5, WGS84_A / math.sqrt(w2)

    def as_dict(self) -> dict:
        """``lat``, ``lon``, ``heading_deg`` and the conventions, for metadata."""
        return {
            "lat": self.lat, "lon": self.lon, "heading_deg": self.heading_deg,
            "heading": "direction of the map frame's +x axis, degrees clockwise from true north",
            "model": "local tangent plane at (lat, lon): WGS84 meridian and prime-vertical radii of curvature",
        }  # fmt: skip


def as_georeference(value: Georeference | Mapping[str, Any] | None) -> Georeference | None:
    """:class:`Georeference` of a config mapping (``lat``, ``lon``, optional
    ``heading_deg``), or the value itself when a Georeference or None.

    Raises
    ------
    KeyError
        For an unknown or missing key.
    ValueError
        For a value out of range (see :class:`Georeference`).
    """
    if value is None or isinstance(value, Georeference):
        return value
    from floorscan.core.config import dataclass_from_mapping

    missing = sorted({"lat", "lon"} - set(value))
    if missing:
        raise KeyError(f"floorplan.georeference lacks {missing}; expected lat, lon and optionally heading_deg")
    return dataclass_from_mapping(Georeference, value, "floorplan.georeference")


def map_to_lonlat(x, y, georeference: Georeference) -> tuple[np.ndarray, np.ndarray]:
    """WGS84 longitude and latitude of map points, on the local tangent plane.

    ``lat = lat0 + north / M``, ``lon = lon0 + east / (N cos lat0)`` (radians; ``M``,
    ``N`` the radii of curvature at ``lat0``, :meth:`Georeference.radii`; east and
    north as in :class:`Georeference`): the first-order (tangent plane) map
    projection. The neglected curvature moves a point by about ``d^2 / R tan(lat0)``
    (``d`` its distance from the origin): under a millimetre within 100 m, about
    10 cm at 1 km at mid latitudes; a building is well inside. Longitudes are not
    wrapped at the antimeridian.

    Parameters
    ----------
    x, y : (N,) float array_like
        Map coordinates, metres.
    georeference : Georeference

    Returns
    -------
    lon, lat : (N,) float64 ndarray
        Degrees.
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    h = math.radians(georeference.heading_deg)
    east = x * math.sin(h) - y * math.cos(h)
    north = x * math.cos(h) + y * math.sin(h)
    m, n = georeference.radii()
    lat = georeference.lat + np.degrees(north / m)
    lon = georeference.lon + np.degrees(east / (n * math.cos(math.radians(georeference.lat))))
    return lon, lat


def lonlat_to_map(lon, lat, georeference: Georeference) -> tuple[np.ndarray, np.ndarray]:
    """Map coordinates (metres) of WGS84 longitudes and latitudes (degrees): the
    inverse of :func:`map_to_lonlat`, e.g. to score a georeferenced GeoJSON plan in
    the map frame. Shapes as there."""
    lon, lat = np.asarray(lon, dtype=np.float64), np.asarray(lat, dtype=np.float64)
    m, n = georeference.radii()
    north = np.radians(lat - georeference.lat) * m
    east = np.radians(lon - georeference.lon) * (n * math.cos(math.radians(georeference.lat)))
    h = math.radians(georeference.heading_deg)
    return east * math.sin(h) + north * math.cos(h), -east * math.cos(h) + north * math.sin(h)


def export_time(timestamp: float | None = None) -> int:
    """Seconds since the epoch (UTC) the exports of a plan are stamped with.

    ``timestamp`` (rounded down: e.g. the recording's first scan stamp) when given,
    else the environment variable ``SOURCE_DATE_EPOCH`` (reproducible-builds.org),
    else 0. Never the clock: the same input gives the same files.

    Raises
    ------
    ValueError
        For a ``timestamp`` that is not finite, or a ``SOURCE_DATE_EPOCH`` that is
        not an integer.
    """
    if timestamp is not None:
        t = float(timestamp)
        if not math.isfinite(t):
            raise ValueError(f"export timestamp must be finite seconds since the epoch, got {timestamp!r}")
        return math.floor(t)
    env = os.environ.get("SOURCE_DATE_EPOCH", "").strip()
    if not env:
        return 0
    try:
        return int(env)
    except ValueError:
        raise ValueError(f"SOURCE_DATE_EPOCH must be an integer number of seconds, got {env!r}") from None


@functools.lru_cache(maxsize=None)
def floorscan_version() -> str:
    """The installed floorscan's version (``"unknown"`` when not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("floorscan")
    except PackageNotFoundError:  # pragma: no cover
        return "unknown"


@dataclass(frozen=True)
class PlanMetadata:
    """What a floor plan is of: written into every one of its exports.

    Attributes
    ----------
    dataset, ordering, extractor : str
        The recording, the scan ordering and the wall extractor of the plan.
    k : str
        The number of scans, as in the file names (``"5"``, ``"all"``); an int is
        converted.
    timestamp : float or None
        Seconds since the epoch (UTC) to stamp the exports with, e.g. the
        recording's first scan stamp; None: :func:`export_time`'s fallbacks.
    name : str
        The plan's title (SVG title, IFC project name, from which the IFC GlobalIds
        derive); empty: "``dataset ordering extractor k<k>``" of the fields given.
    """

    dataset: str = ""
    ordering: str = ""
    extractor: str = ""
    k: str = ""
    timestamp: float | None = None
    name: str = ""

    def __post_init__(self):
        for f in ("dataset", "ordering", "extractor", "k", "name"):
            value = getattr(self, f)
            object.__setattr__(self, f, "" if value is None else str(value))

    @property
    def fields(self) -> tuple[tuple[str, str], ...]:
        """``(name, value)`` of dataset, ordering, extractor and k, as every export names them."""
        return ("dataset", self.dataset), ("ordering", self.ordering), ("extractor", self.extractor), ("k", self.k)

    @property
    def title(self) -> str:
        """:attr:`name`, else the fields given joined (``"intel random ransac k5"``),
        else ``"floorscan"``."""
        if self.name:
            return self.name
        parts = [self.dataset, self.ordering, self.extractor, f"k{self.k}" if self.k else ""]
        return " ".join(p for p in parts if p) or "floorscan"

    @property
    def time_stamp(self) -> str:
        """:func:`export_time` of :attr:`timestamp` in ISO 8601, UTC (``1970-01-01T00:00:00+00:00``)."""
        return datetime.fromtimestamp(export_time(self.timestamp), tz=timezone.utc).isoformat()


def _metadata(plan: FloorPlan, meta: PlanMetadata, georeference: Georeference | None = None) -> dict:
    """The plan's metadata as the GeoJSON member ``floorscan`` holds it (the DXF's
    metadata are its entries as text)."""
    return {
        "frame": "map" if georeference is None else "WGS84",
        "units": "metres" if georeference is None else "degrees",
        "crs": "local engineering frame of the recording" if georeference is None else (
            "WGS84 longitude, latitude: the map frame on the local tangent plane of the georeference"),
        **dict(meta.fields),
        "n_walls": len(plan.walls), "n_walls_both_faces": int(plan.walls["paired"].sum()), "n_faces": len(plan.faces),
        "lengths": "metres (thickness_m, height_m, length_m)",
        "time_stamp": meta.time_stamp,
        "generator": f"floorscan {floorscan_version()}",
        "georeference": None if georeference is None else georeference.as_dict(),
    }  # fmt: skip


# --------------------------------------------------------------------------------------
# Footprints
# --------------------------------------------------------------------------------------


@dataclass
class _PlanExports:
    """A plan and what its exports share, each made once, on first use: the oriented
    footprints, their rings, the extent and the IFC model (:func:`_ifc_model`, kept
    by :class:`FloorplanWriter` for a plan it writes again)."""

    plan: FloorPlan
    model: Any = None

    @functools.cached_property
    def polys(self):
        """The wall polygons (:meth:`FloorPlan.footprints`) oriented as RFC 7946 wants
        them (``shapely.orient_polygons``): counter-clockwise exterior rings, clockwise
        holes (a buffer's exterior is clockwise). Every export draws these."""
        import shapely

        return shapely.orient_polygons(self.plan.footprints(), exterior_cw=False)

    @functools.cached_property
    def rings(self) -> list:
        """:func:`_exterior_rings` of :attr:`polys`, map metres."""
        return _exterior_rings(self.polys)

    @functools.cached_property
    def extent(self) -> tuple[np.ndarray, np.ndarray]:
        """Least and greatest ``(x, y)`` of the wall axes and footprints, metres (a
        plan with walls)."""
        import shapely

        xy = self.plan.walls[["x0", "y0", "x1", "y1"]].to_numpy(dtype=np.float64).reshape(-1, 2)
        b = shapely.total_bounds(self.polys)  # NaN when every footprint is empty
        return np.fmin(xy.min(axis=0), b[:2]), np.fmax(xy.max(axis=0), b[2:])


def _exterior_rings(polys, transform: Callable[[np.ndarray], np.ndarray] | None = None) -> list:
    """Exterior ring of each footprint as a list of ``[x, y]`` (closed: the first
    point repeated last), or None for a missing or empty footprint.

    The coordinates of all the rings come from one ``shapely.get_coordinates`` call
    (the same doubles as ``poly.exterior.coords``), not a coordinate sequence per wall;
    ``transform`` ((P, 2) -> (P, 2) array, e.g. to longitude and latitude) is applied
    to all of them at once.
    """
    import shapely

    out: list = [None] * len(polys)
    ok = np.flatnonzero(~(shapely.is_missing(polys) | shapely.is_empty(polys)))
    if not len(ok):
        return out
    coords, index = shapely.get_coordinates(shapely.get_exterior_ring(polys[ok]), return_index=True)
    if transform is not None:
        coords = transform(coords)
    bounds = np.r_[0, np.cumsum(np.bincount(index, minlength=len(ok)))].tolist()
    pts = coords.tolist()
    for n, k in enumerate(ok.tolist()):
        out[k] = pts[bounds[n] : bounds[n + 1]]
    return out


def _lonlat_transform(georeference: Georeference) -> Callable[[np.ndarray], np.ndarray]:
    """(P, 2) map metres -> (P, 2) longitude, latitude degrees (:func:`map_to_lonlat`)."""
    return lambda xy: np.column_stack(map_to_lonlat(xy[:, 0], xy[:, 1], georeference))


# --------------------------------------------------------------------------------------
# GeoJSON
# --------------------------------------------------------------------------------------


def floorplan_geojson(
    plan: FloorPlan, metadata: PlanMetadata | None = None, georeference: Georeference | Mapping | None = None
) -> dict:
    """GeoJSON FeatureCollection of a floor plan.

    Features, with property ``kind`` as in the ground truth ``walls.geojson``:
    ``axis`` (LineString centre line; ``wall_id``, ``thickness_m``, ``height_m``,
    ``length_m``, ``paired``, ``n_segments``), ``footprint`` (Polygon of the wall,
    counter-clockwise; ``wall_id``, ``thickness_m``), ``face`` (LineString merged
    face; ``face_id``, ``wall_id``, ``n_segments``, ``n_inliers``). Thickness and
    length are rounded to 4 decimals (metres), coordinates to
    :data:`GEOJSON_DECIMALS`.

    Collection members: ``crs`` (only in the map frame: :data:`LOCAL_FRAME_WKT`, see
    the module docstring) and ``floorscan``: ``frame`` (``"map"``, or ``"WGS84"``
    with a georeference), ``units`` (of the coordinates: ``"metres"`` or
    ``"degrees"``), ``crs`` (in words), ``dataset``, ``ordering``, ``extractor``,
    ``k``, ``n_walls``, ``n_walls_both_faces``, ``n_faces``, ``lengths``,
    ``time_stamp`` (ISO 8601, :func:`export_time`), ``generator``, ``georeference``
    (None or :meth:`Georeference.as_dict`).

    Parameters
    ----------
    plan : FloorPlan
    metadata : PlanMetadata, optional
    georeference : Georeference or mapping, optional
        With one, coordinates are WGS84 longitude, latitude (:func:`map_to_lonlat`).
    """
    return _floorplan_geojson(_PlanExports(plan), metadata or PlanMetadata(), as_georeference(georeference))


def _floorplan_geojson(exports: _PlanExports, meta: PlanMetadata, georeference: Georeference | None) -> dict:
    """:func:`floorplan_geojson` of a plan's :class:`_PlanExports`.

    A footprint's coordinates are its exterior ring's (:func:`_exterior_rings`),
    rounded: what ``shapely.to_geojson`` writes (shortest round-trip digits) read
    back and rounded, without the JSON text in between. A footprint that is not a
    Polygon without holes (a buffered axis always is) goes through
    ``shapely.to_geojson``.
    """
    import shapely

    plan, polys = exports.plan, exports.polys
    if georeference is None:
        transform, nd, rings = None, GEOJSON_DECIMALS["map"], exports.rings
    else:
        transform = _lonlat_transform(georeference)
        nd, rings = GEOJSON_DECIMALS["WGS84"], _exterior_rings(polys, transform)
    floats = ("thickness_m", "height_m", "length_m")

    def col(df, c):  # floats as float64 (not DataFrame.astype: 3 ms a call)
        return df[c].to_numpy(dtype=np.float64).tolist() if c in floats else df[c].tolist()

    def ends(df) -> list:  # x0, y0, x1, y1 of each row, transformed
        xy = df[["x0", "y0", "x1", "y1"]].to_numpy(dtype=np.float64)
        if transform is not None:
            xy = np.column_stack([transform(xy[:, :2]), transform(xy[:, 2:])])
        return xy.tolist()

    def line(e):
        coords = [[round(e[0], nd), round(e[1], nd)], [round(e[2], nd), round(e[3], nd)]]
        return {"type": "LineString", "coordinates": coords}

    feats = []
    w = plan.walls
    plain = ((shapely.get_type_id(polys) == 3) & (shapely.get_num_interior_rings(polys) == 0)).tolist()
    for wall_id, e, thick, height, length, paired, n_seg, poly, ring, simple in zip(
        col(w, "wall_id"), ends(w), col(w, "thickness_m"), col(w, "height_m"), col(w, "length_m"),
        col(w, "paired"), col(w, "n_segments"), polys, rings, plain,
    ):  # fmt: skip
        thick = round(thick, 4)
        props = {
            "wall_id": int(wall_id), "thickness_m": thick, "height_m": height, "length_m": round(length, 4),
            "paired": bool(paired), "n_segments": int(n_seg),
        }  # fmt: skip
        feats.append(_feature("axis", line(e), props))
        if ring is not None:
            if simple:
                geom = {"type": "Polygon", "coordinates": [[[round(x, nd), round(y, nd)] for x, y in ring]]}
            else:
                shape = poly if transform is None else shapely.transform(poly, transform)
                geom = _round_coords(json.loads(shapely.to_geojson(shape)), nd)
            feats.append(_feature("footprint", geom, {"wall_id": int(wall_id), "thickness_m": thick}))
    f = plan.faces
    for face_id, wall_id, e, n_seg, n_inl in zip(
        col(f, "face_id"), col(f, "wall_id"), ends(f), col(f, "n_segments"), col(f, "n_inliers")
    ):
        props = {"face_id": int(face_id), "wall_id": int(wall_id), "n_segments": int(n_seg), "n_inliers": int(n_inl)}
        feats.append(_feature("face", line(e), props))
    doc: dict = {"type": "FeatureCollection"}
    if georeference is None:
        doc["crs"] = {"type": "name", "properties": {"name": LOCAL_FRAME_WKT}}
    doc["floorscan"] = _metadata(plan, meta, georeference)
    doc["features"] = feats
    return doc


def _feature(kind: str, geometry: dict, props: dict) -> dict:
    return {"type": "Feature", "geometry": geometry, "properties": {"kind": kind, **props}}


def _round_coords(geom: dict, decimals: int = 5) -> dict:
    def r(c):
        return [r(x) for x in c] if isinstance(c, (list, tuple)) else round(float(c), decimals)

    return {**geom, "coordinates": r(geom["coordinates"])}


def write_geojson(
    plan: FloorPlan, path: str | os.PathLike, metadata: PlanMetadata | None = None,
    georeference: Georeference | Mapping | None = None,
) -> None:  # fmt: skip
    """Write :func:`floorplan_geojson` atomically: the collection's members on the
    first line, then one feature per line.

    The layout (a feature per line, ``json.dumps`` defaults within it) lets the C
    encoder of :mod:`json` write it: ``indent`` makes ``json`` use its pure-Python
    encoder, which took 70 % of this function's time on large plans.
    """
    _write_geojson(_PlanExports(plan), path, metadata or PlanMetadata(), as_georeference(georeference))


def _write_geojson(
    exports: _PlanExports, path: str | os.PathLike, meta: PlanMetadata, georeference: Georeference | None
) -> None:
    doc = _floorplan_geojson(exports, meta, georeference)
    head = json.dumps({k: v for k, v in doc.items() if k != "features"})[:-1]
    feats = ",\n".join(map(json.dumps, doc["features"]))
    text = f'{head}, "features": [\n{feats}\n]}}\n' if feats else f'{head}, "features": []}}\n'
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


# --------------------------------------------------------------------------------------
# SVG
# --------------------------------------------------------------------------------------

#: SVG layout, pixels of the viewBox (the SVG scales to the window): the plan's longer
#: side, the least canvas width (title, scale bar and legend fit), margins and bands.
SVG_PLAN_PX, SVG_MIN_WIDTH_PX, SVG_MARGIN_PX, SVG_HEAD_PX, SVG_FOOT_PX = 1000.0, 720.0, 20.0, 56.0, 84.0


def _scale_bar_length(max_m: float) -> float:
    """The longest of 1, 2 and 5 x 10^n metres not above ``max_m`` (> 0), metres."""
    e = math.floor(math.log10(max_m))
    for m in (5, 2, 1):
        length = float(f"{m}e{e}")
        if length <= max_m * (1 + 1e-12):
            return length
    return float(f"1e{e - 1}")  # pragma: no cover (rounding of log10)


def write_svg(
    plan: FloorPlan, path: str | os.PathLike, metadata: PlanMetadata | None = None,
    georeference: Georeference | Mapping | None = None,
) -> None:  # fmt: skip
    """Write the floor plan as a plain SVG that fits any browser window.

    The viewBox is in pixels: the plan's longer side :data:`SVG_PLAN_PX`, a title
    band above (the plan's title and the number of walls), a band below with a
    scale bar (a round length in metres, :func:`_scale_bar_length`), the map frame's
    x (right) and y (up) axes (with a georeference also north) and a legend (wall;
    wall of which one face was seen, whose thickness is assumed: lighter, dashed;
    wall axis). ``width`` and ``height`` are 100 %: a browser scales the drawing to
    its window, aspect kept. The plan is drawn in map metres inside a group whose
    transform ``matrix(s 0 0 -s tx ty)`` flips y (the map's y is up, SVG's down);
    ``s`` is pixels per metre. Each axis line has a tooltip (length x thickness).
    """
    _write_svg(_PlanExports(plan), path, metadata or PlanMetadata(), as_georeference(georeference))


def _write_svg(
    exports: _PlanExports, path: str | os.PathLike, meta: PlanMetadata, georeference: Georeference | None
) -> None:
    """:func:`write_svg` of a plan's :class:`_PlanExports`."""
    walls = exports.plan.walls
    n = len(walls)
    if n:
        lo, hi = exports.extent
        (xmin, ymin), (xmax, ymax) = (lo - 0.5).tolist(), (hi + 0.5).tolist()  # a margin, metres
    else:
        xmin, ymin, xmax, ymax = 0.0, 0.0, 1.0, 1.0
    s = SVG_PLAN_PX / max(xmax - xmin, ymax - ymin)  # pixels per metre
    pw, ph = (xmax - xmin) * s, (ymax - ymin) * s
    m = SVG_MARGIN_PX
    width = max(pw + 2 * m, SVG_MIN_WIDTH_PX)
    height = SVG_HEAD_PX + ph + SVG_FOOT_PX
    tx, ty = (width - pw) / 2 - s * xmin, SVG_HEAD_PX + s * ymax
    paired = walls["paired"].to_numpy(dtype=bool)
    n_paired = int(paired.sum())
    title = meta.title
    sub = (
        f"{n} walls ({n_paired} with both faces seen, {n - n_paired} with one)"
        f" \u00b7 map frame of the recording, metres \u00b7 {meta.time_stamp}"
    )
    about = "; ".join(f"{k}: {v or '-'}" for k, v in meta.fields)
    desc = (
        f"floorscan {floorscan_version()} floor plan. {about}; walls: {n}. "
        "Coordinates: map frame of the recording (x right, y up), metres."
    )
    if georeference is not None:
        desc += (
            f" Georeference: origin lat {georeference.lat}, lon {georeference.lon} (WGS84), "
            f"+x axis at {georeference.heading_deg} degrees clockwise from north."
        )
    px = 1.0 / s  # one pixel, metres
    out = [
        '<?xml version="1.0" encoding="UTF-8"?>',
        f'<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="100%" height="100%" '
        f'viewBox="0 0 {width:.2f} {height:.2f}" preserveAspectRatio="xMidYMid meet" '
        'font-family="sans-serif">',
        f"<title>{_xml(title)}</title>",
        f"<desc>{_xml(desc)}</desc>",
        f'<rect id="background" width="{width:.2f}" height="{height:.2f}" fill="#ffffff"/>',
        f'<text id="title" x="{m:.2f}" y="26" font-size="18" font-weight="bold">{_xml(title)}</text>',
        f'<text id="subtitle" x="{m:.2f}" y="45" font-size="12" fill="#444444">{_xml(sub)}</text>',
        f'<g id="plan" transform="matrix({s:.10g} 0 0 {-s:.10g} {tx:.6f} {ty:.6f})">',
    ]
    groups = (
        ("walls", paired, f'fill="#8c8c8c" stroke="#333333" stroke-width="{0.6 * px:.6g}"'),
        ("walls-one-face", ~paired, f'fill="#dddddd" stroke="#333333" stroke-width="{0.6 * px:.6g}" '
         f'stroke-dasharray="{3 * px:.6g} {2 * px:.6g}"'),
    )  # fmt: skip
    for gid, which, style in groups:
        out.append(f'<g id="{gid}" {style}>')
        for ring, keep in zip(exports.rings, which.tolist()):
            if ring is not None and keep:
                pts = " ".join(f"{x:.4f},{y:.4f}" for x, y in ring[:-1])
                out.append(f'<polygon points="{pts}"/>')
        out.append("</g>")
    out.append(f'<g id="axes" stroke="#cc0000" stroke-width="{1.0 * px:.6g}" fill="none">')
    for wall_id, x0, y0, x1, y1, length, thickness in zip(
        *(walls[c].tolist() for c in ("wall_id", "x0", "y0", "x1", "y1", "length_m", "thickness_m"))
    ):
        out.append(
            f'<line x1="{x0:.4f}" y1="{y0:.4f}" x2="{x1:.4f}" y2="{y1:.4f}">'
            f"<title>wall {wall_id}: {length:.2f} m x {thickness:.2f} m</title></line>"
        )
    out += ["</g>", "</g>"]
    out += _svg_scale_bar(s, m, height - 30)
    out += _svg_frame_axes(m + 250, height - 30, georeference)
    out += _svg_legend(width - m - 270, height - 74)
    out.append("</svg>")
    with atomic_path(path) as tmp:
        tmp.write_text("\n".join(out) + "\n", encoding="utf-8")


def _svg_scale_bar(s: float, x: float, y: float) -> list[str]:
    """A scale bar of a round length (at most 200 px) at ``(x, y)`` px, ``s`` px a metre."""
    length = _scale_bar_length(200.0 / s)
    bar = length * s
    return [
        f'<g id="scale-bar" transform="translate({x:.2f} {y:.2f})" stroke="#000000" stroke-width="2">',
        f'<line x1="0" y1="0" x2="{bar:.4f}" y2="0"/>',
        '<line x1="0" y1="-5" x2="0" y2="5"/>',
        f'<line x1="{bar:.4f}" y1="-5" x2="{bar:.4f}" y2="5"/>',
        f'<text x="{bar / 2:.4f}" y="-8" font-size="12" text-anchor="middle" stroke="none">{length:g} m</text>',
        "</g>",
    ]


def _svg_arrow(dx: float, dy: float, label: str, colour: str) -> list[str]:
    """An arrow from the origin to ``(dx, dy)`` px with ``label`` beyond its head."""
    norm = math.hypot(dx, dy)
    ux, uy = dx / norm, dy / norm
    bx, by = dx - 7 * ux, dy - 7 * uy  # base of the head
    head = f"{dx:.2f},{dy:.2f} {bx - 4 * uy:.2f},{by + 4 * ux:.2f} {bx + 4 * uy:.2f},{by - 4 * ux:.2f}"
    lx, ly = dx + 9 * ux, dy + 9 * uy + 4
    return [
        f'<line x1="0" y1="0" x2="{bx:.2f}" y2="{by:.2f}" stroke="{colour}" stroke-width="2"/>',
        f'<polygon points="{head}" fill="{colour}"/>',
        f'<text x="{lx:.2f}" y="{ly:.2f}" font-size="12" text-anchor="middle" fill="{colour}">{label}</text>',
    ]


def _svg_frame_axes(x: float, y: float, georeference: Georeference | None) -> list[str]:
    """The map frame's x (right) and y (up) axes at ``(x, y)`` px, and with a
    georeference the direction of true north in the map frame (``(cos h, sin h)``,
    ``h`` the heading; flipped to SVG's y down)."""
    out = [f'<g id="frame-axes" transform="translate({x:.2f} {y:.2f})">']
    out += _svg_arrow(32.0, 0.0, "x", "#000000")
    out += _svg_arrow(0.0, -32.0, "y", "#000000")
    if georeference is not None:
        h = math.radians(georeference.heading_deg)
        out.append('<g id="north" transform="translate(96 -16)">')
        out += _svg_arrow(26.0 * math.cos(h), -26.0 * math.sin(h), "N", "#1f4e9c")
        out.append("</g>")
    out.append('<text x="0" y="22" font-size="11" fill="#444444">map frame (m)</text>')
    out.append("</g>")
    return out


def _svg_legend(x: float, y: float) -> list[str]:
    """The legend at ``(x, y)`` px: the three kinds of things the plan draws."""
    return [
        f'<g id="legend" transform="translate({x:.2f} {y:.2f})" font-size="12">',
        '<rect x="0" y="0" width="22" height="10" fill="#8c8c8c" stroke="#333333" stroke-width="0.6"/>',
        '<text x="30" y="10">wall (both faces seen)</text>',
        '<rect x="0" y="20" width="22" height="10" fill="#dddddd" stroke="#333333" stroke-width="0.6" '
        'stroke-dasharray="3 2"/>',
        '<text x="30" y="30">wall, one face seen (thickness assumed)</text>',
        '<line x1="0" y1="45" x2="22" y2="45" stroke="#cc0000" stroke-width="1"/>',
        '<text x="30" y="50">wall axis</text>',
        "</g>",
    ]


def _xml(s: str) -> str:
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


# --------------------------------------------------------------------------------------
# DXF
# --------------------------------------------------------------------------------------


@contextlib.contextmanager
def _reproducible_ezdxf():
    """ezdxf with ``options.write_fixed_meta_data_for_testing`` on (restored after):
    its documented switch for "the same meta data", i.e. fixed ``$TDCREATE`` /
    ``$TDUPDATE`` (2000-01-01), GUIDs and ezdxf marker instead of the clock's and
    random ones, so the same plan gives the same bytes. The plan's own time stamp
    is in the drawing's metadata."""
    import ezdxf

    logging.getLogger("ezdxf").setLevel(logging.WARNING)  # its INFO lines would flood the stage log
    old = ezdxf.options.write_fixed_meta_data_for_testing
    ezdxf.options.write_fixed_meta_data_for_testing = True
    try:
        yield ezdxf
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = old


def write_dxf(
    plan: FloorPlan, path: str | os.PathLike, version: str = "R2010", metadata: PlanMetadata | None = None,
    georeference: Georeference | Mapping | None = None,
) -> None:  # fmt: skip
    """Write the floor plan as DXF (ezdxf), coordinates in metres in the map frame.

    Layers (:data:`DXF_LAYERS`, each in the layer table with its colour; entities
    are coloured BYLAYER): ``WALL_AXIS`` (a LINE per wall centre line),
    ``WALL_OUTLINE`` (a closed polyline per wall polygon, counter-clockwise),
    ``WALL_FACE`` (a LINE per merged face). The active viewport and ``$EXTMIN`` /
    ``$EXTMAX`` frame the plan, so a CAD tool opens on it.

    ``"R2010"`` (default): ``$INSUNITS`` = 6 (metres), ``$MEASUREMENT`` = 1
    (metric), outlines as LWPOLYLINE; the metadata also as drawing properties
    (``$CUSTOMPROPERTY``, which AutoCAD shows in DWGPROPS). ``"R12"``: outlines as
    POLYLINE; R12 has no units header (``$INSUNITS`` came with R2000), so CAD tools
    take the coordinates as unitless numbers (they are metres). In both, the plan's
    metadata (:func:`_metadata`: dataset, ordering, extractor, k, walls, frame,
    units, time stamp, georeference) is ezdxf metadata (``doc.ezdxf_metadata()``).
    The coordinates stay map metres with a georeference (DXF has no CRS; the
    metadata says where the frame lies). ``ezdxf.recover`` and ``doc.audit()`` find
    no error. Creation and update dates are ezdxf's fixed ones
    (:func:`_reproducible_ezdxf`).

    Raises
    ------
    ValueError
        For another ``version``.
    """
    _write_dxf(_PlanExports(plan), path, version, metadata or PlanMetadata(), as_georeference(georeference))


def _write_dxf(
    exports: _PlanExports, path: str | os.PathLike, version: str, meta: PlanMetadata,
    georeference: Georeference | None,
) -> None:  # fmt: skip
    """:func:`write_dxf` of a plan's :class:`_PlanExports`."""
    if version not in DXF_VERSIONS:
        raise ValueError(f"DXF version must be one of {list(DXF_VERSIONS)}, got {version!r}")
    plan = exports.plan
    w, f = plan.walls, plan.faces
    axes = zip(w["x0"].tolist(), w["y0"].tolist(), w["x1"].tolist(), w["y1"].tolist(), exports.rings)
    faces = zip(f["x0"].tolist(), f["y0"].tolist(), f["x1"].tolist(), f["y1"].tolist())
    with _reproducible_ezdxf() as ezdxf:
        from ezdxf import units, zoom

        if version == "R12":
            ezdxf_log = logging.getLogger("ezdxf")
            level = ezdxf_log.level
            ezdxf_log.setLevel(logging.ERROR)  # ezdxf.new warns that R12 cannot carry $INSUNITS
            try:
                doc = ezdxf.new("R12")
            finally:
                ezdxf_log.setLevel(level)
        else:
            doc = ezdxf.new(version, units=units.M)  # $INSUNITS 6 and $MEASUREMENT 1 (metric)
        doc.header["$LUNITS"] = 2  # decimal lengths
        for name, color in DXF_LAYERS.items():
            doc.layers.add(name, color=color)
        msp = doc.modelspace()
        add_outline = msp.add_polyline2d if version == "R12" else msp.add_lwpolyline
        for x0, y0, x1, y1, ring in axes:
            msp.add_line((x0, y0), (x1, y1), dxfattribs={"layer": "WALL_AXIS"})
            if ring is not None:
                add_outline(ring[:-1], close=True, dxfattribs={"layer": "WALL_OUTLINE"})
        for x0, y0, x1, y1 in faces:
            msp.add_line((x0, y0), (x1, y1), dxfattribs={"layer": "WALL_FACE"})
        if len(w):
            lo, hi = exports.extent
            msp.dxf.extmin, msp.dxf.extmax = (*lo.tolist(), 0.0), (*hi.tolist(), 0.0)
            zoom.window(msp, (lo - 0.5).tolist(), (hi + 0.5).tolist())
        pairs = _dxf_metadata(plan, meta, georeference)
        ezdxf_meta = doc.ezdxf_metadata()
        for key, value in pairs:
            ezdxf_meta[key] = value
        if version != "R12":
            for key, value in pairs:
                doc.header.custom_vars.append(key, value)
            # ezdxf registers a CLASS per entity type in use in the order of a set
            # (ClassesSection.add_required_classes), which follows the hash seed;
            # registered all now and sorted, they keep their places when it writes
            doc.classes.add_required_classes(doc.dxfversion)
            doc.classes.classes = dict(sorted(doc.classes.classes.items()))
        stream = io.StringIO()
        doc.write(stream)
    data = doc.encode(stream.getvalue())
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def _dxf_metadata(plan: FloorPlan, meta: PlanMetadata, georeference: Georeference | None) -> list[tuple[str, str]]:
    """The DXF's metadata: :func:`_metadata` of the map frame (DXF coordinates are map
    metres), the georeference in words, all as text."""
    md = _metadata(plan, meta, None)
    md["georeference"] = "none" if georeference is None else (
        f"origin lat {georeference.lat}, lon {georeference.lon} (WGS84); map +x axis "
        f"{georeference.heading_deg} degrees clockwise from true north"
    )  # fmt: skip
    return [(f"floorscan_{k}", str(v)) for k, v in md.items()]


# --------------------------------------------------------------------------------------
# IFC
# --------------------------------------------------------------------------------------


def _ifc_model(plan: FloorPlan, georeference: Georeference | None):
    """The IFC4 model of ``plan`` (see :func:`write_ifc`), not yet named: :func:`_save_ifc`
    names it (:func:`_name_ifc`) by the metadata of each file it is saved as.

    Raises
    ------
    ImportError
        When ifcopenshell is not installed.
    """
    try:
        import ifcopenshell.api.aggregate
        import ifcopenshell.api.context
        import ifcopenshell.api.georeference
        import ifcopenshell.api.geometry
        import ifcopenshell.api.project
        import ifcopenshell.api.pset
        import ifcopenshell.api.root
        import ifcopenshell.api.spatial
        import ifcopenshell.api.unit
        import ifcopenshell.util.geolocation
    except ImportError as e:  # pragma: no cover
        raise ImportError("writing IFC needs ifcopenshell: pip install ifcopenshell") from e

    api = ifcopenshell.api
    model = api.project.create_file(version="IFC4")
    project = api.root.create_entity(model, ifc_class="IfcProject")
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
        api.geometry.edit_object_placement(model, product=part)  # identity, relative to its whole's
    storey.Elevation = 0.0
    if georeference is not None:
        dms = ifcopenshell.util.geolocation.dd2dms
        site.RefLatitude = dms(georeference.lat, use_us=True)
        site.RefLongitude = dms(georeference.lon, use_us=True)
        h = math.radians(georeference.heading_deg)
        api.georeference.edit_true_north(model, true_north=(math.cos(h), math.sin(h)))

    w = plan.walls
    rows = [
        r for r in zip(
            w["wall_id"].tolist(), w["x0"].tolist(), w["y0"].tolist(), w["x1"].tolist(), w["y1"].tolist(),
            w["thickness_m"].to_numpy(dtype=np.float64).tolist(), w["height_m"].to_numpy(dtype=np.float64).tolist(),
            w["paired"].tolist(),
        ) if math.hypot(r[3] - r[1], r[4] - r[2]) > 0
    ]  # fmt: skip
    walls = [api.root.create_entity(model, ifc_class="IfcWall", name=f"Wall {r[0]}") for r in rows]
    if walls:
        api.spatial.assign_container(model, products=walls, relating_structure=storey)
        # assign_container keeps the walls in a set: their order changed from run to run
        storey.ContainsElements[0].RelatedElements = tuple(walls)
    for wall, (wall_id, x0, y0, x1, y1, thickness, height, paired) in zip(walls, rows):
        length = math.hypot(x1 - x0, y1 - y0)
        dx, dy = (x1 - x0) / length, (y1 - y0) / length
        wall.Description = "both faces seen" if paired else "one face seen, thickness assumed"
        # Placement: at the axis start, x along the axis, relative to the storey's.
        matrix = np.array([[dx, -dy, 0.0, x0], [dy, dx, 0.0, y0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
        api.geometry.edit_object_placement(model, product=wall, matrix=matrix)
        # Body: the rectangle length x thickness centred on the axis, extruded up.
        body_rep = api.geometry.add_wall_representation(
            model, context=body, length=length, height=height, thickness=thickness, offset=-thickness / 2.0
        )
        axis_rep = api.geometry.add_axis_representation(model, context=axis_ctx, axis=[(0.0, 0.0), (length, 0.0)])
        api.geometry.assign_representation(model, product=wall, representation=body_rep)
        api.geometry.assign_representation(model, product=wall, representation=axis_rep)
        qto = api.pset.add_qto(model, product=wall, name="Qto_WallBaseQuantities")
        api.pset.edit_qto(model, qto=qto, properties={"Length": length, "Width": thickness, "Height": height})
    return model


def _name_ifc(model, plan: FloorPlan, metadata: PlanMetadata) -> None:
    """Name the IFC project by the plan's metadata and derive every GlobalId from its
    title and the creation order (:func:`_ifc_guid_list`): the same plan and title
    give the same ids (BIM tools see the same walls, not new ones), and renaming a
    model gives the ids a fresh model of that title would have."""
    project = model.by_type("IfcProject")[0]
    project.Name = metadata.title
    about = ", ".join(f"{k} {v or '-'}" for k, v in metadata.fields)
    project.Description = f"floorscan floor plan: {about}, {len(plan.walls)} walls; map frame of the recording, metres"
    roots = sorted(model.by_type("IfcRoot"), key=lambda e: e.id())
    for entity, guid in zip(roots, _ifc_guid_list(metadata.title, len(roots))):
        entity.GlobalId = guid


def _ifc_guid_list(name: str, n: int) -> list[str]:
    """The first ``n`` GlobalIds of the model named ``name``, in creation order:
    ``ifcopenshell.guid.compress(uuid5(ns, str(i)).hex)`` for i = 0 .. n-1, ``ns`` the
    ``uuid5`` of ``floorscan:{name}`` (URL namespace): the same plan and name give the
    same ids (``root.create_entity`` gives random ones)."""
    import ifcopenshell.guid

    ns = uuid.uuid5(uuid.NAMESPACE_URL, f"floorscan:{name}")
    compress = ifcopenshell.guid.compress
    return [compress(uuid.uuid5(ns, str(i)).hex) for i in range(n)]


def _mvd_text(s: str) -> str:
    """``s`` in the characters an MVD header value may hold (``[A-Za-z0-9 _.-]``,
    ifcopenshell.util.mvd_info's grammar), others as ``_``."""
    return "".join(c if (c.isascii() and c.isalnum()) or c in " _.-" else "_" for c in s)


def _save_ifc(model, plan: FloorPlan, path: str | os.PathLike, meta: PlanMetadata) -> None:
    """Name ``model`` (the IFC model of ``plan``) by the plan's metadata
    (:func:`_name_ifc`), give it the STEP header of ``path`` and write it
    atomically as IFC-SPF text: ``model.to_string()`` (the text ``model.write``
    writes) in one write, which took three quarters of ``model.write``'s time.

    Header: ``file_name.name`` the file's name, ``time_stamp`` :func:`export_time`
    of the plan (ISO 8601, UTC), author and organization ``floorscan``,
    ``originating_system`` ``floorscan <version>``, ``preprocessor_version``
    IfcOpenShell's; ``file_description`` the view definition
    (DesignTransferView) and a comment naming the dataset, ordering, extractor, k.
    """
    import ifcopenshell

    _name_ifc(model, plan, meta)
    header = model.header
    header.file_name.name = Path(path).name
    header.file_name.time_stamp = meta.time_stamp
    header.file_name.author = ("floorscan",)
    header.file_name.organization = ("floorscan",)
    header.file_name.preprocessor_version = f"IfcOpenShell {ifcopenshell.version}"
    header.file_name.originating_system = f"floorscan {floorscan_version()}"
    header.file_name.authorization = ""
    about = " ".join(f"{k} {_mvd_text(v)}" for k, v in meta.fields if v)
    header.file_description.description = (
        "ViewDefinition[DesignTransferView]",
        f"Comment[floorscan floor plan{' of ' + about if about else ''}]",
    )
    text = model.to_string()
    with atomic_path(path) as tmp:
        tmp.write_bytes(text.encode("utf-8"))


def write_ifc(
    plan: FloorPlan, path: str | os.PathLike, name: str = "", metadata: PlanMetadata | None = None,
    georeference: Georeference | Mapping | None = None,
) -> None:  # fmt: skip
    """Write the floor plan as IFC4, built with IfcOpenShell's API, units metres.

    IfcProject (named :attr:`PlanMetadata.title`, described by the metadata) >
    IfcSite > IfcBuilding > IfcBuildingStorey (elevation 0), each placed at its
    whole's origin (``aggregate.assign_object``, ``geometry.edit_object_placement``),
    the storey containing (``spatial.assign_container``) an ``IfcWall`` per wall of
    non-zero length, placed relative to the storey's placement at the axis start
    with x along the axis (``edit_object_placement``), with a body
    (``add_wall_representation``: the rectangle length x thickness centred on the
    axis, extruded by ``height_m``), an axis (``add_axis_representation``,
    Plan/Axis, Curve2D), the quantities ``Qto_WallBaseQuantities`` Length, Width,
    Height (``pset.add_qto``, ``edit_qto``) and a description (both faces seen or
    one). Units (``unit.assign_unit``): metre, square metre, cubic metre. No
    IfcOwnerHistory (optional in IFC4, and it would carry the clock). With a
    georeference the site has its reference latitude and longitude and the
    contexts the true north. The STEP header: :func:`_save_ifc`. GlobalIds:
    :func:`_name_ifc`. ``ifcopenshell.validate`` finds no issue.

    Parameters
    ----------
    plan : FloorPlan
    path : path
    name : str
        The project's name (overrides ``metadata.name``).
    metadata : PlanMetadata, optional
    georeference : Georeference or mapping, optional

    Raises
    ------
    ImportError
        When ifcopenshell is not installed (``pip install ifcopenshell``).
    """
    meta = metadata or PlanMetadata()
    if name:
        meta = replace(meta, name=name)
    _save_ifc(_ifc_model(plan, as_georeference(georeference)), plan, path, meta)


# --------------------------------------------------------------------------------------
# Writer
# --------------------------------------------------------------------------------------

FLOORPLAN_FORMATS = ("geojson", "svg", "dxf", "ifc")


class FloorplanWriter:
    """Builds and writes floor plans (stage ``floorplan``); a plan of the same segments
    as one it built before is not built again.

    A sweep writes one plan per ordering and k, and every ordering's ``k = all`` (and
    any k past the number of scans) holds the same scans: :func:`build_floorplan`
    takes segments in scan order, so those plans are the same plan. The writer keeps
    each plan it built with its footprints and IFC model; for the same segments it
    reuses them and writes the exports with the new plan's metadata (each export
    names its ordering and k): the GeoJSON, SVG and DXF anew (cheap), the IFC model
    renamed (:func:`_name_ifc`: project name, description, GlobalIds) and saved
    with its header. Every file equals a fresh export of that plan and metadata.
    On hallways3d this skips building 4 of the 5 largest plans per extractor and
    their IFC models, the slowest export.

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
        self._built: dict[bytes, _PlanExports] = {}

    def write(
        self, segments: pd.DataFrame, outputs: Mapping[str, str | os.PathLike], name: str = "", *,
        dataset: str = "", ordering: str = "", extractor: str = "", k: str | int = "",
        timestamp: float | None = None,
    ) -> tuple[FloorPlan, bool]:  # fmt: skip
        """Build the floor plan of ``segments`` and write it to ``outputs``.

        Parameters
        ----------
        segments : pandas.DataFrame
            Wall segments (``walls/{ordering}/{extractor}/k{k}.parquet``).
        outputs : mapping
            Paths by format: any of :data:`FLOORPLAN_FORMATS`.
        name : str
            Title of the plan (SVG title, IFC project name); empty: made of the
            metadata (:attr:`PlanMetadata.title`).
        dataset, ordering, extractor : str
            What the plan is of, written into every export.
        k : str or int
            Number of scans label (``"5"``, ``"all"``).
        timestamp : float, optional
            Seconds since the epoch to stamp the exports with (e.g. the
            recording's first scan stamp); None: ``SOURCE_DATE_EPOCH``, else 0
            (:func:`export_time`).

        Returns
        -------
        plan : FloorPlan
        reused : bool
            Whether the plan equals one built before (same segments), and so was
            reused rather than built.

        Raises
        ------
        KeyError
            For an unknown output format, or a missing coordinate column.
        """
        unknown = sorted(set(outputs) - set(FLOORPLAN_FORMATS))
        if unknown:
            raise KeyError(f"unknown floor plan formats {unknown}; expected {list(FLOORPLAN_FORMATS)}")
        meta = PlanMetadata(dataset, ordering, extractor, k, timestamp, name)
        export_time(timestamp)  # a bad SOURCE_DATE_EPOCH fails before anything is built
        geo = self.params.georeference
        segments = _in_scan_order(segments)  # as build_floorplan takes them (sorted once)
        key = _segments_key(segments)
        built = self._built.get(key)
        reused = built is not None
        if built is None:
            built = self._built[key] = _PlanExports(build_floorplan(segments, self.params))
        for fmt, path in outputs.items():
            if fmt == "ifc":
                if built.model is None:
                    built.model = _ifc_model(built.plan, geo)
                _save_ifc(built.model, built.plan, path, meta)
            elif fmt == "svg":
                _write_svg(built, path, meta, geo)
            elif fmt == "dxf":
                _write_dxf(built, path, self.params.dxf_version, meta, geo)
            else:
                _write_geojson(built, path, meta, geo)
        return built.plan, reused


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
    segments: pd.DataFrame, cfg: Mapping[str, Any] | None, outputs: Mapping[str, str | os.PathLike], name: str = "",
    *, dataset: str = "", ordering: str = "", extractor: str = "", k: str | int = "", timestamp: float | None = None,
) -> FloorPlan:  # fmt: skip
    """Build the floor plan of ``segments`` and write it: ``FloorplanWriter(cfg).write(
    segments, outputs, name, dataset=..., ordering=..., extractor=..., k=...,
    timestamp=...)`` (see there; ``cfg`` is the ``floorplan`` config section),
    returning the :class:`FloorPlan`. Raises ``KeyError`` for an unknown output
    format or config key."""
    return FloorplanWriter(cfg).write(
        segments, outputs, name, dataset=dataset, ordering=ordering, extractor=extractor, k=k, timestamp=timestamp
    )[0]


def recording_timestamp(index_path: str | os.PathLike) -> int:
    """The exports' time stamp: the recording's first scan stamp (``scan_index.parquet``'s
    least ``t_ns``) in whole seconds since the epoch, 0 for an empty index; the same
    recording gives the same files."""
    import pyarrow.parquet as pq

    t_ns = pq.read_table(index_path, columns=["t_ns"]).column("t_ns").to_numpy()
    return int(t_ns.min()) // 1_000_000_000 if len(t_ns) else 0


def write_recommended_floorplan(
    scans_path: str | os.PathLike,
    walls_path: str | os.PathLike,
    index_path: str | os.PathLike,
    outputs: Mapping[str, str | os.PathLike],
    cfg: Mapping[str, Any] | None,
    dataset: str,
    ordering: str,
    extractor: str,
) -> dict:
    """Write the recommended floor plan: the merged walls of the selected scans.

    Parameters
    ----------
    scans_path : path
        ``selection/scans.csv`` (:func:`floorscan.select.deliverables.write_scan_list`):
        its ``scan_id`` column names the selected scans.
    walls_path : path
        ``walls/<extractor>/per_scan.parquet``: every kept scan's wall segments.
    index_path : path
        ``scan_index.parquet``: the first scan's stamp is the exports' time stamp
        (seconds since the epoch; the same recording gives the same files).
    outputs : mapping
        Paths by format (any of :data:`FLOORPLAN_FORMATS`).
    cfg : mapping
        The ``floorplan`` config section (``georeference`` applies here).
    dataset, ordering, extractor : str
        Named in every export.

    Returns
    -------
    dict
        ``n_scans``, ``n_segments``, ``n_walls``, ``n_faces``.
    """
    from floorscan.core.io import read_table

    selected = pd.read_csv(scans_path, usecols=["rank", "scan_id"])
    ids = selected["scan_id"].astype(np.int64).to_numpy()
    walls = read_table(walls_path)
    segments = walls[walls["scan_id"].isin(ids)]
    plan, _ = FloorplanWriter(cfg).write(
        segments, outputs, dataset=dataset, ordering=ordering, extractor=extractor, k=len(ids),
        timestamp=recording_timestamp(index_path),
    )
    return {"n_scans": len(ids), "n_segments": len(segments), "n_walls": len(plan.walls), "n_faces": len(plan.faces)}

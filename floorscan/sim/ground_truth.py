"""Ground truth of a simulated recording: the walls at the scanner's height, the true poses.

The thesis scores its method against the simulated building (section 5.2). The
ground-truth walls (:func:`ground_truth_walls`) are a horizontal slice of the walls at
one height (:func:`floorscan.sim.footprint.wall_footprint`): doors are gaps there,
windows are gaps only where ``sill_m <= z < head_m``. The wall faces a scanner inside
can see (:func:`wall_faces`) are the scoring reference; the parts of them the
recording's returns lie on (:func:`observed_faces`) are the reference of recall. The
``true_poses`` table (:func:`true_poses_frame`) holds the true scanner pose of every
scan.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
import pyarrow as pa
import shapely
from shapely.geometry import Point, Polygon
from shapely.ops import unary_union

from floorscan.sim.building import Building
from floorscan.sim.footprint import wall_footprint, walls_union

if TYPE_CHECKING:
    from floorscan.sim.recording import Recording

#: Schema of ``true_poses.parquet``.
TRUE_POSES = pa.schema(
    [
        ("t_ns", pa.int64()),
        ("x", pa.float64()),
        ("y", pa.float64()),
        ("z", pa.float64()),
        ("yaw", pa.float64()),
    ]
)


def _straight_edges(ring) -> list[tuple[np.ndarray, np.ndarray]]:
    """Maximal straight edges of a closed ring (collinear vertices merged)."""
    pts = np.asarray(ring.coords)[:-1]
    if len(pts) < 3:
        return []
    keep = []
    n = len(pts)
    for i in range(n):
        a, b, c = pts[i - 1], pts[i], pts[(i + 1) % n]
        cross = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0])
        scale = np.hypot(*(b - a)) * np.hypot(*(c - b))
        if scale == 0 or abs(cross) > 1e-9 * max(scale, 1e-12):
            keep.append(b)
    keep = np.asarray(keep)
    return [(keep[i], keep[(i + 1) % len(keep)]) for i in range(len(keep))]


def wall_faces(building: Building, z: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The wall surfaces a scanner inside the building can see, at height ``z``.

    Every straight edge of :func:`wall_footprint` at ``z`` is a face, except the outside
    of the building: edges whose outward side lies outside the filled outline of a wall
    ring that encloses rooms. Door jambs (reveals) are faces.

    Parameters
    ----------
    building : Building
    z : float
        Slice height, metres.

    Returns
    -------
    list of ((2,), (2,)) float64 ndarray pairs
        Face segments (start, end), metres, map frame.
    """
    fp = wall_footprint(building, z)
    enclosing = [p for p in getattr(walls_union(building), "geoms", [walls_union(building)])
                 if len(p.interiors) > 0]
    outside_ok = unary_union([Polygon(p.exterior) for p in enclosing]) if enclosing else None
    faces = []
    for poly in getattr(fp, "geoms", [fp]):
        poly = shapely.geometry.polygon.orient(poly, 1.0)  # CCW exterior: material on the left
        for ring in [poly.exterior, *poly.interiors]:
            for a, b in _straight_edges(ring):
                d = b - a
                length = np.hypot(*d)
                if length < 1e-6:
                    continue
                normal = np.array([d[1], -d[0]]) / length  # right side: away from material
                probe = Point(*((a + b) / 2 + normal * 1e-3))
                if outside_ok is not None and not outside_ok.contains(probe):
                    continue
                faces.append((a.copy(), b.copy()))
    return faces


#: A face sample is observed when a return lies within this plan distance, metres.
OBSERVED_RADIUS_M = 0.05
#: Unobserved runs of a face shorter than this between observed samples count as
#: observed (the gaps between beams far away), metres.
OBSERVED_BRIDGE_M = 0.20
#: Spacing of the face samples tested for observation, metres.
OBSERVED_STEP_M = 0.01


def observed_faces(
    faces, points_xy: np.ndarray, radius_m: float = OBSERVED_RADIUS_M,
    bridge_m: float = OBSERVED_BRIDGE_M, step_m: float = OBSERVED_STEP_M,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The parts of the wall faces that a recording's returns lie on.

    Thesis 5.2: "some walls, although they are present in the CAD model of the
    building in simulation, are never visible from the point of view of the LIDAR".
    No method recovers a wall it never saw, so recall is scored against the observed
    parts (the denominator of completeness, as the ISPRS indoor benchmark restricts
    its reference to the surveyed area); the whole faces stay in the ground truth.

    Each face is sampled every ``step_m``; a sample is observed when a return lies
    within ``radius_m`` of it in the plan; unobserved runs shorter than ``bridge_m``
    between observed samples are filled; each remaining run is a segment.

    Parameters
    ----------
    faces : list of ((2,), (2,)) ndarray pairs
        Wall faces (:func:`wall_faces`), metres.
    points_xy : (N, 2) float ndarray
        Plan positions of the returns (map frame, metres), e.g. deduplicated on a
        1 cm grid.
    radius_m, bridge_m, step_m : float
        Metres.

    Returns
    -------
    list of ((2,), (2,)) float64 ndarray pairs
        Observed face segments, in face order.
    """
    from scipy.spatial import cKDTree

    pts = np.asarray(points_xy, dtype=np.float64).reshape(-1, 2)
    if len(pts) == 0:
        return []
    tree = cKDTree(pts)
    out = []
    for a, b in faces:
        a, b = np.asarray(a, float), np.asarray(b, float)
        length = float(np.hypot(*(b - a)))
        n = max(2, int(math.ceil(length / step_m)) + 1)
        s = np.linspace(0.0, 1.0, n)
        samples = a + s[:, None] * (b - a)
        d, _ = tree.query(samples, distance_upper_bound=radius_m)
        seen = np.isfinite(d)
        if not seen.any():
            continue
        idx = np.flatnonzero(seen)
        # fill short unobserved runs between observed samples
        gaps = np.flatnonzero(np.diff(idx) > 1)
        for g in gaps:
            if (idx[g + 1] - idx[g]) * length / (n - 1) < bridge_m:
                seen[idx[g]: idx[g + 1]] = True
        edges = np.diff(np.r_[0, seen.astype(np.int8), 0])
        for i0, i1 in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1):
            if i1 > i0:
                out.append((samples[i0].copy(), samples[i1].copy()))
    return out


def ground_truth_walls(
    building: Building, slice_height_m: float, observed_xy: np.ndarray | None = None
) -> dict:
    """The ground-truth walls as a GeoJSON FeatureCollection (metres, map frame).

    Features carry ``kind``:

    - ``face``: LineString, a straight wall surface a scanner can see at the slice
      height (:func:`wall_faces`); the scoring reference.
    - ``axis``: LineString, one per wall polyline segment: its centre line, with
      ``wall``, ``thickness_m`` and ``height_m``.
    - ``footprint``: Polygon, the walls cut at the slice height (:func:`wall_footprint`).
    - ``observed_face``: LineString, the parts of the faces the recording's returns lie
      on (:func:`observed_faces`), when ``observed_xy`` is given; the reference of
      recall in scoring.

    Parameters
    ----------
    building : Building
    slice_height_m : float
        Height of the horizontal slice, metres (the 2D scanner's height, so doors are
        gaps and windows with a sill above it are walls; thesis 5.2).
    observed_xy : (N, 2) float ndarray, optional
        Plan positions of the recording's returns (map frame, metres).

    Returns
    -------
    dict
        GeoJSON FeatureCollection with the foreign members ``building`` and
        ``slice_height_m``.

    Raises
    ------
    ValueError
        When ``slice_height_m`` is not inside (0, height_m).
    """
    if not 0 < slice_height_m < building.height_m:
        raise ValueError(
            f"slice height {slice_height_m} m must be between floor and ceiling "
            f"(0, {building.height_m}) of {building.source}"
        )
    feats: list[dict] = []
    faces = wall_faces(building, slice_height_m)
    for i, (a, b) in enumerate(faces):
        feats.append(_feature("LineString", [_xy(a), _xy(b)], kind="face", id=f"face{i}"))
    if observed_xy is not None:
        for i, (a, b) in enumerate(observed_faces(faces, observed_xy)):
            feats.append(
                _feature("LineString", [_xy(a), _xy(b)], kind="observed_face", id=f"observed{i}")
            )
    for w in building.walls:
        for k, (a, b) in enumerate(w.segments()):
            feats.append(
                _feature(
                    "LineString", [_xy(a), _xy(b)], kind="axis", wall=w.id, segment=k,
                    thickness_m=w.thickness_m, height_m=building.height_m,
                )
            )
    fp = wall_footprint(building, slice_height_m)
    for j, poly in enumerate(getattr(fp, "geoms", [fp])):
        poly = shapely.geometry.polygon.orient(poly, 1.0)
        rings = [[_xy(p) for p in r.coords] for r in [poly.exterior, *poly.interiors]]
        feats.append(_feature("Polygon", rings, kind="footprint", id=f"footprint{j}"))
    return {
        "type": "FeatureCollection",
        "building": building.name,
        "slice_height_m": float(slice_height_m),
        "features": feats,
    }


def _xy(p) -> list[float]:
    return [round(float(p[0]), 9), round(float(p[1]), 9)]


def _feature(gtype: str, coords: list, **props) -> dict:
    return {"type": "Feature", "geometry": {"type": gtype, "coordinates": coords}, "properties": props}


def true_poses_frame(rec: Recording) -> pd.DataFrame:
    """The ``true_poses`` table: ``t_ns`` and the true scanner pose of every scan."""
    return pd.DataFrame(
        {
            "t_ns": rec.scan_t_ns.astype(np.int64),
            "x": rec.scan_poses[:, 0],
            "y": rec.scan_poses[:, 1],
            "z": rec.scan_poses[:, 2],
            "yaw": rec.scan_poses[:, 3],
        }
    )

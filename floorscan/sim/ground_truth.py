"""Ground truth of a simulated recording: the walls at the scanner's height, the true poses.

The thesis scores its method against the simulated building (section 5.2). The
ground-truth walls (:func:`ground_truth_walls`) are a horizontal slice of the walls at
one height (:func:`floorscan.sim.footprint.wall_footprint`): doors are gaps there,
windows are gaps only where ``sill_m <= z < head_m``. The wall faces a scanner inside
can see (:func:`wall_faces`) are the scoring reference; the parts of them the
recording's returns lie on (:func:`observed_faces`) are the reference of recall. The
true rooms (:func:`true_rooms`: the regions the walls enclose with every door closed)
and doors (:func:`true_doors`: every opening of kind door and the rooms it joins) are
what a floor plan's rooms and doors are scored against (:mod:`floorscan.score.rooms`;
room segmentation as Bormann et al., ICRA 2016, score it). The ``true_poses`` table
(:func:`true_poses_frame`) holds the true scanner pose of every scan.
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
from floorscan.sim.footprint import building_outline, wall_footprint, walls_union

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


#: Pieces of the interior smaller than this are numerical crumbs, not rooms, m2.
MIN_ROOM_AREA_M2 = 0.01
#: A door's sides are probed this far beyond each face of its wall, metres.
DOOR_PROBE_M = 0.05
#: ``room_a`` / ``room_b`` of a door that leads outside.
EXTERIOR = -1


def true_rooms(building: Building) -> pd.DataFrame:
    """The true rooms: the regions the walls enclose with every door closed.

    A room is a connected piece of the building's interior (the filled outline of the
    walls, :func:`floorscan.sim.footprint.building_outline`) minus the full-height wall
    footprints without openings (:func:`floorscan.sim.footprint.walls_union`: doors
    closed; windows do not matter in plan). Its outline runs along the wall faces.

    Parameters
    ----------
    building : Building

    Returns
    -------
    pandas.DataFrame
        One row per room, ordered by the room's representative point (y, then x):
        ``room_id`` (int64, 0..n-1), ``area_m2``, ``perimeter_m`` (float64) and
        ``polygon`` (shapely Polygon, map frame, metres; holes where walls stand free
        inside it, e.g. the core a ring corridor runs around). Pieces under
        :data:`MIN_ROOM_AREA_M2` are dropped.
    """
    interior = building_outline(building).difference(walls_union(building))
    polys = [
        shapely.geometry.polygon.orient(p, 1.0)
        for p in getattr(interior, "geoms", [interior])
        if p.geom_type == "Polygon" and p.area >= MIN_ROOM_AREA_M2
    ]
    key = [(round(q.y, 6), round(q.x, 6)) for q in (p.representative_point() for p in polys)]
    polys = [polys[i] for i in sorted(range(len(polys)), key=key.__getitem__)]
    return pd.DataFrame({
        "room_id": np.arange(len(polys), dtype=np.int64),
        "area_m2": np.array([p.area for p in polys], dtype=np.float64),
        "perimeter_m": np.array([p.length for p in polys], dtype=np.float64),
        "polygon": pd.Series(polys, dtype=object),
    })  # fmt: skip


def true_doors(building: Building, rooms: pd.DataFrame | None = None) -> pd.DataFrame:
    """The true doors: every opening of kind ``door`` and the true rooms it joins.

    A door's side is the room a point :data:`DOOR_PROBE_M` beyond the wall's face, on
    the normal through the door's centre, lies in; outside the building that side is
    :data:`EXTERIOR` (-1); inside it but in no room (the probe in another wall), the
    nearest room.

    Parameters
    ----------
    building : Building
    rooms : pandas.DataFrame, optional
        :func:`true_rooms` of ``building`` (computed when not given).

    Returns
    -------
    pandas.DataFrame
        One row per door, in the building file's order: ``door_id`` (the opening's id),
        ``wall_id``; ``x0, y0, x1, y1`` the opening as a segment on the wall's axis
        (the line of the wall), ``x, y`` its centre, ``width_m`` (float64, metres);
        ``room_a`` <= ``room_b`` (int64, ``room_id`` of :func:`true_rooms`, -1
        outside) and ``exterior`` (bool, the door leads outside).
    """
    if rooms is None:
        rooms = true_rooms(building)
    polys = list(rooms["polygon"])
    ids = rooms["room_id"].to_numpy(np.int64)
    outline = building_outline(building)
    rows = []
    for w in building.walls:
        for op in w.openings:
            if op.kind != "door":
                continue
            a, b = (np.asarray(p, dtype=np.float64) for p in w.segments()[op.segment])
            u = (b - a) / np.hypot(*(b - a))
            p0, p1 = a + u * op.offset_m, a + u * (op.offset_m + op.width_m)
            centre = (p0 + p1) / 2
            normal = np.array([-u[1], u[0]])
            sides = []
            for sign in (-1.0, 1.0):
                probe = Point(*(centre + sign * normal * (w.thickness_m / 2 + DOOR_PROBE_M)))
                inside = [i for i, p in enumerate(polys) if p.contains(probe)]
                if inside:
                    sides.append(int(ids[inside[0]]))
                elif not outline.contains(probe) or not polys:
                    sides.append(EXTERIOR)
                else:
                    sides.append(int(ids[int(np.argmin([p.distance(probe) for p in polys]))]))
            ra, rb = sorted(sides)
            rows.append({
                "door_id": op.id, "wall_id": w.id, "x0": p0[0], "y0": p0[1], "x1": p1[0], "y1": p1[1],
                "x": centre[0], "y": centre[1], "width_m": float(op.width_m),
                "room_a": ra, "room_b": rb, "exterior": ra == EXTERIOR,
            })  # fmt: skip
    cols = ["door_id", "wall_id", "x0", "y0", "x1", "y1", "x", "y", "width_m", "room_a", "room_b", "exterior"]
    out = pd.DataFrame(rows, columns=cols)
    return out.astype({c: np.float64 for c in cols[2:9]} | {"room_a": np.int64, "room_b": np.int64, "exterior": bool})


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
    - ``room``: Polygon, a true room (:func:`true_rooms`; exterior ring
      counter-clockwise, holes clockwise), with ``room_id``, ``area_m2``,
      ``perimeter_m``.
    - ``door``: LineString, a true door (:func:`true_doors`): the opening on its wall's
      axis, with ``door_id``, ``wall_id``, ``width_m``, ``room_a``, ``room_b`` (-1:
      outside) and ``exterior``.

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
    rooms = true_rooms(building)
    for r in rooms.itertuples(index=False):
        rings = [[_xy(p) for p in ring.coords] for ring in [r.polygon.exterior, *r.polygon.interiors]]
        feats.append(_feature("Polygon", rings, kind="room", room_id=int(r.room_id),
                              area_m2=round(float(r.area_m2), 9), perimeter_m=round(float(r.perimeter_m), 9)))
    for d in true_doors(building, rooms).itertuples(index=False):
        feats.append(_feature("LineString", [_xy((d.x0, d.y0)), _xy((d.x1, d.y1))], kind="door",
                              door_id=d.door_id, wall_id=d.wall_id, width_m=float(d.width_m),
                              room_a=int(d.room_a), room_b=int(d.room_b), exterior=bool(d.exterior)))
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
    """The ``true_poses`` table: the true scanner pose of every scan.

    Parameters
    ----------
    rec : Recording

    Returns
    -------
    pandas.DataFrame
        ``t_ns`` (int64, nanoseconds), ``x``, ``y``, ``z`` (metres), ``yaw`` (radians).
    """
    return pd.DataFrame(
        {
            "t_ns": rec.scan_t_ns.astype(np.int64),
            "x": rec.scan_poses[:, 0],
            "y": rec.scan_poses[:, 1],
            "z": rec.scan_poses[:, 2],
            "yaw": rec.scan_poses[:, 3],
        }
    )

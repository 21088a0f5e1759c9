"""The GeoJSON export of a floor plan (:func:`write_geojson`; people, GIS, the scorer): a
``FeatureCollection`` of wall axes, wall footprints and merged faces, clutter,
junctions, rooms and doors (:func:`floorplan_geojson`).

Polygons follow RFC 7946 section 3.1.6: counter-clockwise outer rings, clockwise holes.
A collection-level foreign member ``floorscan`` holds the frame, units, plan metadata
(:class:`~floorscan.floorplan.metadata.PlanMetadata`) and georeference. Without a
georeference the coordinates are map metres, which RFC 7946 allows only "by prior
arrangement": GDAL (and so QGIS) reads a file without a ``crs`` member as WGS84
longitude/latitude, but still reads the GeoJSON 2008 ``crs`` member (type ``name``, its
``properties.name`` through ``OGRSpatialReference::SetFromUserInput``, which takes WKT;
ogrgeojsonreader.cpp). So the file carries that member with :data:`LOCAL_FRAME_WKT`, a
WKT1 ``LOCAL_CS`` in metres: GIS tools see a local engineering frame and do not place
the plan on a world map at (0 deg, 0 deg) as if its metres were degrees. With
``floorplan.georeference`` (:class:`~floorscan.floorplan.georeference.Georeference`) the
coordinates are WGS84 longitude, latitude
(:func:`~floorscan.floorplan.georeference.map_to_lonlat`), an RFC 7946 file without
``crs``; the scorer (:mod:`floorscan.score.metrics`) reads coordinates as map metres, so
such a plan is scored after :func:`~floorscan.floorplan.georeference.lonlat_to_map`.
The file is written atomically and is byte-identical when written again from the same
input. Source: RFC 7946 (GeoJSON) and the GeoJSON 2008 specification's ``crs``.
"""

from __future__ import annotations

import json
import os
from typing import TYPE_CHECKING, Callable, Mapping

import numpy as np

from floorscan.core.plan_tables import PLAN_DECIMALS
from floorscan.core.files import atomic_path
from floorscan.floorplan.footprints import PlanExports, exterior_rings
from floorscan.floorplan.georeference import Georeference, as_georeference, map_to_lonlat
from floorscan.floorplan.metadata import PlanMetadata, metadata_member

if TYPE_CHECKING:
    from floorscan.floorplan.params import FloorplanParams
    from floorscan.floorplan.plan import FloorPlan


#: The GeoJSON 2008 ``crs`` name of a plan in map metres (WKT1 ``LOCAL_CS``): GDAL reads
#: it as a local engineering CRS in metres (without a ``crs`` member: WGS84 degrees).
#: EAST and NORTH are WKT1's names of a local frame's x (right) and y (up) axes.
LOCAL_FRAME_WKT = (
    'LOCAL_CS["floorscan map frame",LOCAL_DATUM["map frame of the recording",32767],'
    'UNIT["metre",1],AXIS["x",EAST],AXIS["y",NORTH]]'
)


#: Decimals of GeoJSON coordinates: map metres (10 um) and WGS84 degrees (1e-10
#: degree: 11 um of latitude, the same resolution).
GEOJSON_DECIMALS = {"map": PLAN_DECIMALS, "WGS84": 10}


def floorplan_geojson(
    plan: FloorPlan, metadata: PlanMetadata | None = None, georeference: Georeference | Mapping | None = None
) -> dict:
    """GeoJSON FeatureCollection of a floor plan.

    Features, with property ``kind`` as in the ground truth ``walls.geojson``:
    ``axis`` (LineString centre line; ``wall_id``, ``thickness_m``, ``height_m``,
    ``length_m``, ``paired``, ``n_segments``), ``footprint`` (Polygon of the wall,
    counter-clockwise; ``wall_id``, ``thickness_m``), ``face`` (LineString merged
    face; ``face_id``, ``wall_id``, ``n_segments``, ``n_inliers``); after the
    structure passes also ``clutter`` (LineString of a piece that is not a wall:
    ``clutter_id``, ``length_m``, ``reason``) and ``junction`` (Point where two walls
    meet: ``junction`` L, T or X, ``wall_a``, ``wall_b``); with rooms also ``room``
    (Polygon of a room, holes allowed, exterior counter-clockwise and holes
    clockwise: ``room_id``, ``name``, ``room_kind`` ``room``, ``corridor`` or
    ``space``, ``area_m2``, ``perimeter_m``) and ``door`` (LineString of the opening
    in its wall's line: ``door_id``, ``width_m``, ``wall_id``, -1 for none, and the
    rooms it joins, ``room_a`` < ``room_b``). Thickness, length, width (metres) and
    area (m2) are rounded to 4 decimals, coordinates to :data:`GEOJSON_DECIMALS`.

    Collection members: ``crs`` (only in the map frame: :data:`LOCAL_FRAME_WKT`, see
    the module docstring) and ``floorscan``: ``frame`` (``"map"``, or ``"WGS84"``
    with a georeference), ``units`` (of the coordinates: ``"metres"`` or
    ``"degrees"``), ``crs`` (in words), ``dataset``, ``ordering``, ``extractor``,
    ``k``, ``n_walls``, ``n_walls_both_faces``, ``n_faces``, ``lengths``, (after the
    structure passes) ``n_clutter``, ``n_junctions``, (with rooms or doors)
    ``n_rooms``, ``n_doors``, ``floor_area_m2`` (the rooms' areas summed, m2),
    ``time_stamp`` (ISO 8601, :func:`~floorscan.floorplan.metadata.export_time`), ``generator``,
    ``georeference`` (None or :meth:`~floorscan.floorplan.georeference.Georeference.as_dict`).

    Parameters
    ----------
    plan : FloorPlan
    metadata : PlanMetadata, optional
    georeference : Georeference or mapping, optional
        With one, coordinates are WGS84 longitude, latitude (:func:`~floorscan.floorplan.georeference.map_to_lonlat`).

    Returns
    -------
    dict
        The FeatureCollection, ready for ``json.dumps``.
    """
    return _floorplan_geojson(PlanExports(plan), metadata or PlanMetadata(), as_georeference(georeference))


def _floorplan_geojson(exports: PlanExports, meta: PlanMetadata, georeference: Georeference | None) -> dict:
    """:func:`floorplan_geojson` of a plan's :class:`~floorscan.floorplan.footprints.PlanExports`.

    A footprint's coordinates are its exterior ring's (:func:`~floorscan.floorplan.footprints.exterior_rings`),
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
        nd, rings = GEOJSON_DECIMALS["WGS84"], exterior_rings(polys, transform)
    floats = ("thickness_m", "height_m", "length_m")

    def col(df, c):  # floats as float64 (not DataFrame.astype, slower)
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
    c = plan.clutter
    for clutter_id, e, length, reason in zip(col(c, "clutter_id"), ends(c), col(c, "length_m"), col(c, "reason")):
        props = {"clutter_id": int(clutter_id), "length_m": round(float(length), 4), "reason": str(reason)}
        feats.append(_feature("clutter", line(e), props))
    j = plan.junctions
    if len(j):
        xy = j[["x", "y"]].to_numpy(dtype=np.float64)
        xy = xy if transform is None else transform(xy)
        for (x, y), kind, a, b in zip(xy.tolist(), col(j, "kind"), col(j, "wall_a"), col(j, "wall_b")):
            geom = {"type": "Point", "coordinates": [round(x, nd), round(y, nd)]}
            feats.append(_feature("junction", geom, {"junction": str(kind), "wall_a": int(a), "wall_b": int(b)}))
    feats += _room_features(exports, transform, nd) + _door_features(plan.doors, ends, line)
    doc: dict = {"type": "FeatureCollection"}
    if georeference is None:
        doc["crs"] = {"type": "name", "properties": {"name": LOCAL_FRAME_WKT}}
    doc["floorscan"] = metadata_member(plan, meta, georeference)
    doc["features"] = feats
    return doc


def _room_features(exports: PlanExports, transform: Callable | None, nd: int) -> list[dict]:
    """A ``room`` Polygon feature per room with a polygon
    (:attr:`~floorscan.floorplan.footprints.PlanExports.room_polys`: counter-clockwise
    exterior, clockwise holes), ``transform``-ed ((P, 2) -> (P, 2), e.g. to longitude
    and latitude) and oriented again in those coordinates, rounded to ``nd``
    decimals (what ``shapely.to_geojson`` writes, read back and rounded)."""
    import shapely

    r = exports.plan.rooms
    polys = exports.room_polys
    if not len(r):
        return []
    ok = ~(shapely.is_missing(polys) | shapely.is_empty(polys))
    if transform is not None and ok.any():
        polys = polys.copy()
        polys[ok] = shapely.orient_polygons(shapely.transform(polys[ok], transform), exterior_cw=False)
    feats = []
    for room_id, name, kind, area, perimeter, poly, keep in zip(
        r["room_id"].tolist(), r["name"].tolist(), r["kind"].tolist(), r["area_m2"].to_numpy(np.float64).tolist(),
        r["perimeter_m"].to_numpy(np.float64).tolist(), polys.tolist(), ok.tolist(),
    ):  # fmt: skip
        if not keep:
            continue
        props = {
            "room_id": int(room_id), "name": str(name), "room_kind": str(kind),
            "area_m2": round(area, 4), "perimeter_m": round(perimeter, 4),
        }  # fmt: skip
        feats.append(_feature("room", _round_coords(json.loads(shapely.to_geojson(poly)), nd), props))
    return feats


def _door_features(doors, ends: Callable, line: Callable) -> list[dict]:
    """A ``door`` LineString feature per door: the opening, ``ends`` transformed,
    ``line`` rounded."""
    if not len(doors):
        return []
    d = doors
    return [
        _feature("door", line(e), {
            "door_id": int(door_id), "width_m": round(width, 4), "wall_id": int(wall_id),
            "room_a": int(a), "room_b": int(b),
        })  # fmt: skip
        for door_id, e, width, wall_id, a, b in zip(
            d["door_id"].tolist(), ends(d), d["width_m"].to_numpy(np.float64).tolist(), d["wall_id"].tolist(),
            d["room_a"].tolist(), d["room_b"].tolist(),
        )
    ]


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
    encoder of :mod:`json` write it: ``indent`` makes ``json`` use its slower
    pure-Python encoder.

    Parameters
    ----------
    plan : FloorPlan
    path : path
    metadata : PlanMetadata, optional
    georeference : Georeference or mapping, optional
        With one, coordinates are WGS84 longitude, latitude.
    """
    _write_geojson(PlanExports(plan), path, metadata or PlanMetadata(), as_georeference(georeference))


def _write_geojson(
    exports: PlanExports, path: str | os.PathLike, meta: PlanMetadata, georeference: Georeference | None
) -> None:
    write_geojson_document(_floorplan_geojson(exports, meta, georeference), path)


def write_geojson_document(doc: dict, path: str | os.PathLike) -> None:
    """Write a GeoJSON FeatureCollection atomically in the layout of
    :func:`write_geojson`: the collection's members on the first line, then one
    feature per line.

    Parameters
    ----------
    doc : dict
        The FeatureCollection (``features`` and its other members).
    path : path
    """
    head = json.dumps({k: v for k, v in doc.items() if k != "features"})[:-1]
    feats = ",\n".join(map(json.dumps, doc["features"]))
    text = f'{head}, "features": [\n{feats}\n]}}\n' if feats else f'{head}, "features": []}}\n'
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")


def _lonlat_transform(georeference: Georeference) -> Callable[[np.ndarray], np.ndarray]:
    """(P, 2) map metres -> (P, 2) longitude, latitude degrees (:func:`map_to_lonlat`)."""
    return lambda xy: np.column_stack(map_to_lonlat(xy[:, 0], xy[:, 1], georeference))


def export(exports: PlanExports, path: str | os.PathLike, meta: PlanMetadata, params: FloorplanParams) -> None:
    """The GeoJSON writer of :data:`floorscan.floorplan.EXPORT_FORMATS`:
    :func:`write_geojson` of a plan's exports, georeferenced by ``params.georeference``.

    Parameters as every writer of :data:`~floorscan.floorplan.EXPORT_FORMATS` (the
    package docstring's "add an export format": ``exports``, ``path``, ``meta``,
    ``params``).
    """
    _write_geojson(exports, path, meta, params.georeference)

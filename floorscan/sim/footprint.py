"""The walls in plan: their outlines, the openings' cutters and horizontal slices.

A wall's outline is its axis (the centre-line polyline) buffered by half its thickness
with flat ends and mitred joins; an opening's cutter is a rectangle across its wall
along one segment. The slice of the walls at a height (:func:`wall_footprint`: doors are
gaps, windows only between sill and head) is the floor plan of the thesis's ground
truth (section 5.2: "taking a slice of that model will be the equivalent of getting a
floor plan"). The geometry is Shapely's.
"""

from __future__ import annotations

import numpy as np
from shapely.geometry import LineString, LinearRing, Polygon
from shapely.ops import unary_union

from floorscan.sim.building import Building, Opening, Wall

#: How far an opening's cutter reaches beyond each face of its wall, metres. Keeps the
#: boolean away from coplanar faces; the 2D footprint uses the same cutter.
CUT_MARGIN_M = 0.01


def wall_polygon(wall: Wall) -> Polygon:
    """The full-height footprint of one wall (no openings): its axis buffered.

    Parameters
    ----------
    wall : Wall

    Returns
    -------
    shapely Polygon
        Flat ends, mitred joins, metres.
    """
    line = LinearRing(wall.points) if wall.closed else LineString(wall.points)
    return line.buffer(wall.thickness_m / 2, cap_style="flat", join_style="mitre", mitre_limit=10)


def opening_polygon(wall: Wall, op: Opening) -> Polygon:
    """The 2D cutter of an opening: a rectangle along its segment, across the wall.

    It reaches ``CUT_MARGIN_M`` beyond each face of the wall.

    Parameters
    ----------
    wall : Wall
    op : Opening
        On segment ``op.segment`` of ``wall``, from ``offset_m`` for ``width_m``.

    Returns
    -------
    shapely Polygon
        Metres.
    """
    a, b = wall.segments()[op.segment]
    u = (b - a) / np.hypot(*(b - a))
    n = np.array([-u[1], u[0]])
    half = wall.thickness_m / 2 + CUT_MARGIN_M
    p0 = a + u * op.offset_m
    p1 = a + u * (op.offset_m + op.width_m)
    return Polygon([p0 - n * half, p1 - n * half, p1 + n * half, p0 + n * half])


def walls_union(building: Building) -> Polygon:
    """Union of all wall footprints without openings.

    Parameters
    ----------
    building : Building

    Returns
    -------
    shapely Polygon or MultiPolygon
        Metres.
    """
    return unary_union([wall_polygon(w) for w in building.walls])


def wall_footprint(building: Building, z: float):
    """The walls cut by a horizontal plane at height ``z`` (metres above the floor).

    Openings with ``sill_m <= z < head_m`` are gaps.

    Parameters
    ----------
    building : Building
    z : float
        Height above the floor, metres, ``0 <= z < height_m``.

    Returns
    -------
    shapely Polygon or MultiPolygon
    """
    cuts = [
        opening_polygon(w, op)
        for w in building.walls
        for op in w.openings
        if op.sill_m <= z < op.head_m
    ]
    fp = walls_union(building)
    if cuts:
        fp = fp.difference(unary_union(cuts))
    return fp


def building_outline(building: Building):
    """The filled outline of the walls (their union with the enclosed rooms).

    Parameters
    ----------
    building : Building

    Returns
    -------
    shapely Polygon or MultiPolygon
        The exteriors of :func:`walls_union`'s parts, holes filled, metres.
    """
    parts = getattr(walls_union(building), "geoms", [walls_union(building)])
    return unary_union([Polygon(p.exterior) for p in parts])

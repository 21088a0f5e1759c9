"""The polygons of a plan's rooms (:mod:`floorscan.floorplan.rooms`, step 6): each room's
cells, without the strips of rays along its edge (:func:`without_ray_strips`), traced,
grown up to the wall faces, completed up to its walls when seen in part, and the rooms
made a coverage. Map metres; shapely geometry on the exports' precision grid
(:data:`POLYGON_GRID_M`).
"""

from __future__ import annotations

import numpy as np

from floorscan.core.geometry import OVERLAY_GRID_M, minus, polygons_of
from floorscan.floorplan.corridor_lines import wall_lines
from floorscan.floorplan.doors import wall_units
from floorscan.floorplan.room_tables import room_width
from floorscan.floorplan.room_space import (LINE_OFFSET_M, MIN_ROOM_WIDTH_M, RoomRaster, dilate, disc_opening,
                                            wall_footprints)


def room_polygons(raster: RoomRaster, labels: np.ndarray, axes: np.ndarray, thickness: np.ndarray) -> list:
    """A valid shapely Polygon per room of ``labels`` (module docstring, step 5): its
    cells without the strips of rays along its edge (:func:`without_ray_strips`), traced
    (contourpy), grown by a cell up to the wall faces and cut by the walls' footprints
    and the other rooms, simplified by half a cell; the largest part when the cut leaves
    several.

    Parameters
    ----------
    raster : RoomRaster
    labels : (H, W) int ndarray
        Rooms 1..R, 0 for none.
    axes : (N, 4) float ndarray
        Wall axes, metres.
    thickness : (N,) float ndarray
        Metres.

    Returns
    -------
    list of shapely Polygon
        R polygons in map metres, room k at index k - 1 (possibly empty).
    """
    import contourpy
    import shapely
    from scipy import ndimage

    res = raster.resolution_m
    labels = without_ray_strips(raster, labels)
    foot = wall_footprints(axes, thickness)
    walls = shapely.union_all(foot, grid_size=POLYGON_GRID_M) if len(axes) else shapely.Polygon()
    traced = []
    for k, box in enumerate(ndimage.find_objects(labels), start=1):
        if box is None:
            traced.append(shapely.Polygon())
            continue
        r0, c0 = box[0].start, box[1].start
        z = np.pad(labels[box] == k, 1).astype(np.float64)
        filled, offsets = contourpy.contour_generator(z=z, fill_type="OuterOffset").filled(0.5, 2.0)
        parts = []
        for pts, off in zip(filled, offsets):
            xy = (pts + [c0 - 1 + 0.5, r0 - 1 + 0.5]) * res + raster.origin_xy
            rings = [xy[a:b] for a, b in zip(off[:-1], off[1:])]
            parts.append(shapely.Polygon(rings[0], rings[1:]))
        traced.append(shapely.simplify(shapely.make_valid(shapely.union_all(parts, grid_size=POLYGON_GRID_M)), res / 4))
    out = []
    tree = shapely.STRtree(traced)
    for k, poly in enumerate(traced):
        near = sorted(int(j) for j in tree.query(poly, predicate="dwithin", distance=2 * res) if j != k)
        grown = minus(shapely.buffer(poly, res, join_style="mitre"), walls, *[traced[j] for j in near])
        out.append(largest_polygon(shapely.simplify(grown, res / 2)))
    # a room's completion stays in a box square to one of its walls: in the square about its
    # bounding box's centre whose half side is that box's diagonal over sqrt(2), which holds
    # every such box; only the rooms whose squares meet it matter
    b = np.array([p.bounds if not p.is_empty else (0, 0, 0, 0) for p in out], dtype=np.float64).reshape(-1, 4)
    mid, half = (b[:, :2] + b[:, 2:]) / 2, np.hypot(b[:, 2] - b[:, 0], b[:, 3] - b[:, 1]) / np.sqrt(2)
    boxes = shapely.box(mid[:, 0] - half, mid[:, 1] - half, mid[:, 0] + half, mid[:, 1] + half)
    tree = shapely.STRtree(boxes)
    for k, poly in enumerate(out):
        near = sorted(int(j) for j in tree.query(boxes[k]) if j != k and not out[j].is_empty) if not poly.is_empty else []
        others = shapely.union_all([out[j] for j in near], grid_size=POLYGON_GRID_M)
        out[k] = _bounded_by_walls(poly, axes, thickness, foot, walls, others, res)
    return out


def without_ray_strips(raster: RoomRaster, labels: np.ndarray) -> np.ndarray:
    """``labels`` without the strips of each room narrower than
    :data:`~floorscan.floorplan.room_space.MIN_ROOM_WIDTH_M` (what a disc of half that
    width inside the room does not reach) whose cells lie farther than half that width
    from any wall or seen obstacle (``raster.walls`` or ``raster.occupied``), nor what
    they alone join to the room. Such a strip is bounded by the unseen on both sides:
    the rays seen through a gap, whose limits are no room's (the narrowest walkway, 0.9
    m, is the room's own width test; a narrow passage between walls, a door between its
    jambs, the strip along a wall behind furniture lie near what bounds them and stay).

    Parameters
    ----------
    raster : RoomRaster
    labels : (H, W) int ndarray
        Rooms 1..R, 0 for none, on the raster's cells.

    Returns
    -------
    (H, W) int ndarray
        ``labels`` with those cells 0; a room without any cell wider than the strips
        (all of it narrow) unchanged.
    """
    from scipy import ndimage

    res = raster.resolution_m
    half = MIN_ROOM_WIDTH_M / 2
    seen = raster.walls | raster.occupied
    if not seen.any():
        return labels
    far = ~dilate(seen, half / res)
    out = labels.copy()
    pad = int(np.ceil(half / res)) + 1
    for k, box in enumerate(ndimage.find_objects(labels), start=1):
        if box is None:
            continue
        rows = slice(max(box[0].start - pad, 0), min(box[0].stop + pad, labels.shape[0]))
        cols = slice(max(box[1].start - pad, 0), min(box[1].stop + pad, labels.shape[1]))
        room = labels[rows, cols] == k
        wide = disc_opening(room, half / res)
        if not wide.any():
            continue
        parts, _ = ndimage.label(room & ~(far[rows, cols] & ~wide))
        keep = np.isin(parts, np.unique(parts[wide]))  # the parts that hold the room's wide floor
        out[rows, cols][room & ~keep] = 0
    return out


def disjoint_rooms(polys: list) -> list:
    """The rooms as a coverage: where two overlap (a sliver along a door or a gap in a
    wall, each grown into it), the room first in the list keeps it.

    Parameters
    ----------
    polys : list of shapely Polygon
        In reading order.

    Returns
    -------
    list of shapely Polygon
        The same rooms, each the largest part of what is left of it.
    """
    import shapely

    out: list = []
    # what the rooms before a room took, of those whose boxes meet its box
    boxes = shapely.box(*np.array([p.bounds if not p.is_empty else (0, 0, 0, 0) for p in polys]).reshape(-1, 4).T)
    tree = shapely.STRtree(shapely.buffer(boxes, POLYGON_GRID_M, join_style="mitre"))
    for k, poly in enumerate(polys):
        if not poly.is_empty:
            near = sorted(int(j) for j in tree.query(boxes[k]) if j < k and not out[j].is_empty)
            # a union on the grid may collapse a sliver to a line: only its area is taken
            taken = polygons_of(shapely.union_all([out[j] for j in near], grid_size=POLYGON_GRID_M))
            # on the exports' grid, so that no overlap comes back when they round the vertices
            if shapely.intersection(taken, poly, grid_size=POLYGON_GRID_M).area > 0:
                poly = largest_polygon(shapely.difference(poly, taken, grid_size=POLYGON_GRID_M))
        out.append(poly)
    return out


#: Rooms' vertices are snapped to this grid and their overlays run on it, metres: the
#: exports' precision, so a polygon stays valid when written.
POLYGON_GRID_M = OVERLAY_GRID_M


def largest_polygon(geom):
    """The largest polygon of a geometry made valid on the grid of
    :data:`POLYGON_GRID_M` (an empty Polygon if none)."""
    import shapely

    geom = shapely.set_precision(shapely.make_valid(geom), POLYGON_GRID_M)
    pieces = [g for g in getattr(geom, "geoms", [geom]) if isinstance(g, shapely.Polygon) and not g.is_empty]
    return max(pieces, key=lambda g: g.area) if pieces else shapely.Polygon()


def _bounded_by_walls(
    poly, axes: np.ndarray, thickness: np.ndarray, foot, walls, others, res: float, near_m: float = 0.3
):
    """A room seen only in part (through its door) completed up to its walls: the
    bounding box of its seen floor, square to the longest wall within ``near_m`` of it,
    cut by the half-plane of the room's side of each such wall (on the wall's face),
    without the wall footprints and the other rooms; taken when it keeps all but 5 %
    of the seen floor (the room is convex between its walls: an L-shaped room or a ring
    corridor keeps its traced outline), and only when those walls stand on two lines at
    least (:func:`~floorscan.floorplan.corridor_lines.wall_lines`):
    against one wall's line, three sides of the box would be the reach of the rays
    through its gap, floor nobody saw. ``foot``: the walls' footprints, ``walls`` their
    union. Metres."""
    import shapely

    if poly.is_empty or not len(axes):
        return poly
    near = np.flatnonzero(shapely.distance(foot, poly) <= near_m)
    if not len(near):
        return poly
    u, length = wall_units(axes[near])
    long = length >= 0.5
    near, u = near[long], u[long]
    if len(wall_lines(axes[near], thickness[near], u, length[long], LINE_OFFSET_M)) < 2:
        return poly  # one wall's line: three sides of the box would be the reach of the rays
    # the box square to the longest of those walls (along e, across f): the same room
    # however the building is turned (a box in the map's axes reaches past a turned
    # building's walls)
    e = u[int(np.argmax(length[long]))]
    f = np.array([-e[1], e[0]])
    ts = np.asarray(poly.exterior.coords) @ np.column_stack([e, f])  # along, across
    (t0, s0), (t1, s1) = ts.min(axis=0), ts.max(axis=0)
    region = shapely.Polygon([t * e + s * f for t, s in ((t0, s0), (t1, s0), (t1, s1), (t0, s1))])
    big = 4.0 * max(t1 - t0, s1 - s0, 1.0)
    inside = poly.representative_point()
    for i, ui in zip(near.tolist(), u):
        a = axes[i, :2]
        n = np.array([-ui[1], ui[0]])
        side = 1.0 if float((np.array(inside.coords[0]) - a) @ n) >= 0 else -1.0
        face = a + side * n * thickness[i] / 2
        c = face - ui * big
        half = shapely.Polygon([c, c + 2 * big * ui, c + 2 * big * ui + side * big * n, c + side * big * n])
        region = polygons_of(shapely.intersection(region, half, grid_size=POLYGON_GRID_M))
    region = largest_polygon(minus(region, walls, others))
    if region.is_empty or minus(poly, region).area > 0.05 * poly.area or region.area < poly.area:
        return poly
    return largest_polygon(shapely.simplify(region, res / 2))


def door_opening(p: np.ndarray, q: np.ndarray, thickness_m: float, resolution_m: float):
    """The opening of a door from ``p`` to ``q`` ((2,) metres) in a wall ``thickness_m``
    thick: the line grown by half the wall and half a cell, square ends (shapely)."""
    import shapely

    return shapely.buffer(shapely.LineString([p, q]), thickness_m / 2 + resolution_m / 2, cap_style="square")


def narrow_rooms_joined(polys: list, doors: list, thickness: np.ndarray, resolution_m: float):
    """Rooms mostly narrower than :data:`~floorscan.floorplan.room_space.MIN_ROOM_WIDTH_M`
    (their median local thickness, :func:`~floorscan.floorplan.room_tables.room_width`)
    are no rooms: each joins the
    room it shares the widest doors with (their openings with it, :func:`door_opening`), the narrowest first;
    one without a door goes. Returns the polygons (a joined room's empty) and the doors
    (``(p, q, wall, a, b)``, rooms numbered from 1) between the rooms left."""
    import shapely

    narrow = [not p.is_empty and room_width(p, resolution_m / 2, MIN_ROOM_WIDTH_M) < MIN_ROOM_WIDTH_M for p in polys]
    if not any(narrow):
        return polys, doors
    polys, doors = list(polys), list(doors)
    for k in sorted(np.flatnonzero(narrow).tolist(), key=lambda i: (polys[i].area, i)):
        room = k + 1
        widths: dict[int, float] = {}
        for p, q, _, a, b in doors:
            if room in (a, b) and a != b:
                other = b if a == room else a
                widths[other] = widths.get(other, 0.0) + float(np.hypot(*(q - p)))
        if widths:
            other = max(sorted(widths), key=widths.get)
            between = [door_opening(p, q, thickness[w], resolution_m)
                       for p, q, w, a, b in doors if {a, b} == {room, other}]
            joined = shapely.union_all([polys[other - 1], polys[k], *between], grid_size=OVERLAY_GRID_M)
            rest = [p for i, p in enumerate(polys) if i not in (k, other - 1) and not p.is_empty]
            polys[other - 1] = largest_polygon(minus(joined, *rest))  # the openings reach no third room
        else:
            other = 0
        polys[k] = shapely.Polygon()
        moved = []
        for p, q, w, a, b in doors:
            a, b = (other if a == room else a), (other if b == room else b)
            if a and b and a != b:
                moved.append((p, q, w, min(a, b), max(a, b)))
        doors = moved
    return polys, doors

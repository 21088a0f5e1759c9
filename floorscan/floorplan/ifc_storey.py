"""One storey of the IFC4 export (:mod:`floorscan.floorplan.ifc`): a plan's walls, the
connections of its junctions, its clutter, rooms and doors in an ``IfcBuildingStorey``
(:func:`add_storey`), with IfcOpenShell's API. Source: IFC4 (ISO 16739-1) and
IfcOpenShell's API documentation.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from floorscan.floorplan.footprints import PlanExports

if TYPE_CHECKING:
    from floorscan.floorplan.plan import FloorPlan


def add_storey(model, storey, exports: PlanExports, body, axis_ctx) -> None:
    """The contents of one storey of :func:`_ifc_model`: the plan of ``exports`` at the
    storey's ``Elevation`` (metres), in the plan's map frame. An ``IfcWall`` per wall
    of non-zero length contained in the storey, placed at its axis start with x along
    the axis, with a body, an axis (``axis_ctx``) and ``Qto_WallBaseQuantities``; an
    ``IfcRelConnectsPathElements`` per junction (:func:`_connect_walls`); the clutter
    (:func:`_add_clutter`), rooms (:func:`_add_spaces`) and doors (:func:`_add_doors`).
    IFC4 (ISO 16739-1), with IfcOpenShell's API.

    Parameters
    ----------
    model : ifcopenshell.file
        Changed in place.
    storey : IfcBuildingStorey
    exports : PlanExports
    body : IfcGeometricRepresentationSubContext
        The Model/Body context.
    axis_ctx : IfcGeometricRepresentationSubContext
        The Plan/Axis context.
    """
    import ifcopenshell.api

    api = ifcopenshell.api
    z = float(storey.Elevation)
    plan = exports.plan
    w = plan.walls
    rows = [
        r for r in zip(
            w["wall_id"].tolist(), w["x0"].tolist(), w["y0"].tolist(), w["x1"].tolist(), w["y1"].tolist(),
            w["thickness_m"].to_numpy(dtype=np.float64).tolist(), w["height_m"].to_numpy(dtype=np.float64).tolist(),
            w["paired"].tolist(),
        ) if math.hypot(r[3] - r[1], r[4] - r[2]) > 0
    ]  # fmt: skip
    walls = [api.root.create_entity(model, ifc_class="IfcWall", name=f"Wall {r[0]}") for r in rows]
    contain(model, storey, walls)
    for wall, (wall_id, x0, y0, x1, y1, thickness, height, paired) in zip(walls, rows):
        length = math.hypot(x1 - x0, y1 - y0)
        dx, dy = (x1 - x0) / length, (y1 - y0) / length
        wall.Description = "both faces seen" if paired else "one face seen, thickness assumed"
        # Placement: at the axis start, x along the axis, on the storey.
        api.geometry.edit_object_placement(model, product=wall, matrix=placement(x0, y0, dx, dy, z))
        # Body: the rectangle length x thickness centred on the axis, extruded up.
        body_rep = api.geometry.add_wall_representation(
            model, context=body, length=length, height=height, thickness=thickness, offset=-thickness / 2.0
        )
        axis_rep = api.geometry.add_axis_representation(model, context=axis_ctx, axis=[(0.0, 0.0), (length, 0.0)])
        api.geometry.assign_representation(model, product=wall, representation=body_rep)
        api.geometry.assign_representation(model, product=wall, representation=axis_rep)
        qto = api.pset.add_qto(model, product=wall, name="Qto_WallBaseQuantities")
        api.pset.edit_qto(model, qto=qto, properties={"Length": length, "Width": thickness, "Height": height})
    _connect_walls(model, plan, dict(zip([r[0] for r in rows], walls)), {r[0]: r[1:5] for r in rows})
    _add_clutter(model, plan, storey, body)
    heights = w["height_m"].to_numpy(dtype=np.float64)
    height = float(heights.max()) if len(heights) else _default_wall_height()
    _add_spaces(model, exports, storey, body, height)
    _add_doors(model, plan, storey, body, dict(zip([r[0] for r in rows], zip(walls, rows))))


def _default_wall_height() -> float:
    """The height of a plan without walls, metres (``floorplan.wall_height_m``'s default)."""
    from floorscan.floorplan.params import FloorplanParams

    return float(FloorplanParams().wall_height_m)


def contain(model, structure, products: list) -> None:
    """``products`` contained in ``structure`` (``spatial.assign_container``), the
    containment's elements in creation order: the API keeps them in a set, whose
    order changed from run to run, and adds to the structure's one containment (so
    setting it to ``products`` alone would drop the elements contained before).

    Parameters
    ----------
    model : ifcopenshell.file
        Changed in place.
    structure : IfcSpatialStructureElement
    products : list of IfcProduct
        Nothing is done when empty.
    """
    import ifcopenshell.api.spatial

    if not products:
        return
    ifcopenshell.api.spatial.assign_container(model, products=products, relating_structure=structure)
    for rel in structure.ContainsElements:
        rel.RelatedElements = tuple(sorted(rel.RelatedElements, key=lambda e: e.id()))


def _connect_walls(model, plan: FloorPlan, wall_of_id: dict, axis_of_id: dict) -> None:
    """An ``IfcRelConnectsPathElements`` per junction of the plan (ifcopenshell's
    ``geometry.connect_path``): ``ATSTART`` / ``ATEND`` where the junction is an end of
    a wall's axis (within 2 cm), ``ATPATH`` where it lies along it."""
    import ifcopenshell.api.geometry

    def where(wall_id, x, y):
        x0, y0, x1, y1 = axis_of_id[wall_id]
        if math.hypot(x - x0, y - y0) <= 0.02:
            return "ATSTART"
        return "ATEND" if math.hypot(x - x1, y - y1) <= 0.02 else "ATPATH"

    j = plan.junctions
    for x, y, a, b in zip(j["x"].tolist(), j["y"].tolist(), j["wall_a"].tolist(), j["wall_b"].tolist()):
        if a in wall_of_id and b in wall_of_id and a != b:
            ifcopenshell.api.geometry.connect_path(
                model, relating_element=wall_of_id[a], related_element=wall_of_id[b],
                relating_connection=where(a, x, y), related_connection=where(b, x, y),
            )


#: Clutter in IFC: an ``IfcFurniture`` per piece, a box this thick and high along it, metres.
CLUTTER_IFC_THICKNESS_M, CLUTTER_IFC_HEIGHT_M = 0.05, 0.75


def _add_clutter(model, plan: FloorPlan, storey, body) -> None:
    """An ``IfcFurniture`` (``ObjectType`` "clutter", ``Description`` the reason) per
    clutter piece of the plan, in the storey: a box :data:`CLUTTER_IFC_THICKNESS_M`
    thick and :data:`CLUTTER_IFC_HEIGHT_M` high along the piece."""
    import ifcopenshell.api

    api = ifcopenshell.api
    z = float(storey.Elevation)
    c = plan.clutter
    rows = [
        r for r in zip(c["clutter_id"].tolist(), c["x0"].tolist(), c["y0"].tolist(), c["x1"].tolist(),
                       c["y1"].tolist(), c["reason"].tolist())
        if math.hypot(r[3] - r[1], r[4] - r[2]) > 0
    ]  # fmt: skip
    items = [api.root.create_entity(model, ifc_class="IfcFurniture", name=f"Clutter {r[0]}") for r in rows]
    if not items:
        return
    contain(model, storey, items)
    for item, (_, x0, y0, x1, y1, reason) in zip(items, rows):
        length = math.hypot(x1 - x0, y1 - y0)
        dx, dy = (x1 - x0) / length, (y1 - y0) / length
        item.ObjectType, item.Description = "clutter", str(reason)
        api.geometry.edit_object_placement(model, product=item, matrix=placement(x0, y0, dx, dy, z))
        rep = api.geometry.add_wall_representation(
            model, context=body, length=length, height=CLUTTER_IFC_HEIGHT_M, thickness=CLUTTER_IFC_THICKNESS_M,
            offset=-CLUTTER_IFC_THICKNESS_M / 2.0,
        )
        api.geometry.assign_representation(model, product=item, representation=rep)


#: Doors in IFC: the height of an ``IfcDoor`` and its opening (a plan knows its doors'
#: widths, not their heights; at most the wall's height), the door leaf's thickness,
#: and how far the opening reaches past each face of its wall (so it cuts the wall
#: cleanly), metres.
DOOR_IFC_HEIGHT_M, DOOR_IFC_THICKNESS_M, OPENING_IFC_MARGIN_M = 2.1, 0.05, 0.05


def placement(x: float, y: float, dx: float = 1.0, dy: float = 0.0, z: float = 0.0) -> np.ndarray:
    """Placement matrix in the model's frame (``edit_object_placement`` makes it
    relative to the product's container); the contents of a storey are placed at its
    elevation ``z``.

    Parameters
    ----------
    x, y, z : float
        Origin, metres.
    dx, dy : float
        Unit vector of the local x axis; z is up.

    Returns
    -------
    (4, 4) float64 ndarray
    """
    return np.array([[dx, -dy, 0.0, x], [dy, dx, 0.0, y], [0.0, 0.0, 1.0, z], [0.0, 0.0, 0.0, 1.0]])


def _add_spaces(model, exports: PlanExports, storey, body, height: float) -> None:
    """An ``IfcSpace`` per room with a polygon, aggregated into the storey
    (``aggregate.assign_object``): ``Name`` the room's name, ``LongName`` its kind
    (room, corridor, space), placed at the least corner of its bounds relative to the
    storey, a body extruded ``height`` metres up from its footprint (oriented:
    :attr:`~floorscan.floorplan.footprints.PlanExports.room_polys`)
    (``profile.add_arbitrary_profile``, an ``IfcArbitraryClosedProfileDef``, or with
    holes ``add_arbitrary_profile_with_voids``, an ``IfcArbitraryProfileDefWithVoids``;
    ``geometry.add_profile_representation``) and ``Qto_SpaceBaseQuantities``
    ``NetFloorArea`` (``area_m2``), ``GrossPerimeter`` (``perimeter_m``) and ``Height``."""
    import ifcopenshell.api

    api = ifcopenshell.api
    z = float(storey.Elevation)
    r = exports.plan.rooms
    rows = [
        row for row in zip(
            r["name"].tolist(), r["kind"].tolist(), r["area_m2"].to_numpy(np.float64).tolist(),
            r["perimeter_m"].to_numpy(np.float64).tolist(), exports.room_polys.tolist(),
        ) if row[4] is not None and not row[4].is_empty
    ]  # fmt: skip
    spaces = [api.root.create_entity(model, ifc_class="IfcSpace", name=str(row[0])) for row in rows]
    if not spaces:
        return
    api.aggregate.assign_object(model, relating_object=storey, products=spaces)
    for rel in storey.IsDecomposedBy:  # a set in the API: creation order
        rel.RelatedObjects = tuple(sorted(rel.RelatedObjects, key=lambda e: e.id()))
    for space, (_, kind, area, perimeter, poly) in zip(spaces, rows):
        space.LongName = str(kind)
        x0, y0 = poly.bounds[:2]
        api.geometry.edit_object_placement(model, product=space, matrix=placement(x0, y0, z=z))
        outer = (np.asarray(poly.exterior.coords) - (x0, y0)).tolist()
        holes = [(np.asarray(ring.coords) - (x0, y0)).tolist() for ring in poly.interiors]
        if holes:
            profile = api.profile.add_arbitrary_profile_with_voids(model, outer_profile=outer, inner_profiles=holes)
            _profile_curve_2d(model, profile)
        else:
            profile = api.profile.add_arbitrary_profile(model, profile=outer)
        rep = api.geometry.add_profile_representation(
            model, context=body, profile=profile, depth=height, cardinal_point=None
        )
        api.geometry.assign_representation(model, product=space, representation=rep)
        qto = api.pset.add_qto(model, product=space, name="Qto_SpaceBaseQuantities")
        api.pset.edit_qto(
            model, qto=qto, properties={"NetFloorArea": area, "GrossPerimeter": perimeter, "Height": height}
        )


def _profile_curve_2d(model, profile) -> None:
    """The outer curve of ``profile`` (an ``IfcArbitraryProfileDefWithVoids`` of
    ``profile.add_arbitrary_profile_with_voids``) in 2D: IfcOpenShell 0.9.0 puts
    its 2D points in an ``IfcCartesianPointList3D`` (IFC4 wants a profile's curves in
    2D: WR ``IfcArbitraryClosedProfileDef.WR1``), its holes in a 2D list."""
    points = profile.OuterCurve.Points
    if points.is_a("IfcCartesianPointList3D") and all(len(p) == 2 for p in points.CoordList):
        profile.OuterCurve.Points = model.createIfcCartesianPointList2D(points.CoordList)
        model.remove(points)


def _add_doors(model, plan: FloorPlan, storey, body, wall_of_id: dict) -> None:
    """An ``IfcDoor`` per door (``OverallWidth`` its ``width_m``, ``OverallHeight``
    :data:`DOOR_IFC_HEIGHT_M` or the wall's height if lower), contained in the storey,
    placed at the opening's start with x along its wall's axis, a body
    (``add_wall_representation``: width x :data:`DOOR_IFC_THICKNESS_M`, centred on the
    axis). In a wall (``wall_of_id``: wall_id -> (IfcWall, its row)) the door sits
    on the wall's axis, in an ``IfcOpeningElement`` as wide and high as the door
    and :data:`OPENING_IFC_MARGIN_M` thicker than the wall on each side that voids
    the wall (``feature.add_feature``: ``IfcRelVoidsElement``) and that the door
    fills (``feature.add_filling``: ``IfcRelFillsElement``); a door of no plan wall
    (``wall_id`` -1) has no opening and is placed along its own segment."""
    import ifcopenshell.api

    api = ifcopenshell.api
    z = float(storey.Elevation)
    d = plan.doors
    doors = []
    for door_id, x0, y0, x1, y1, width, wall_id in zip(
        *(d[c].tolist() for c in ("door_id", "x0", "y0", "x1", "y1", "width_m", "wall_id"))
    ):
        wall_id = int(wall_id)
        wall, row = wall_of_id.get(wall_id, (None, None))
        if wall is not None:
            _, wx0, wy0, wx1, wy1, thickness, wall_height, _ = row
            length = math.hypot(wx1 - wx0, wy1 - wy0)
            ux, uy = (wx1 - wx0) / length, (wy1 - wy0) / length
            along = min((x0 - wx0) * ux + (y0 - wy0) * uy, (x1 - wx0) * ux + (y1 - wy0) * uy)
            sx, sy = wx0 + along * ux, wy0 + along * uy  # the opening's start on the axis
            height = min(DOOR_IFC_HEIGHT_M, float(wall_height))
        else:
            length = math.hypot(x1 - x0, y1 - y0)
            ux, uy = ((x1 - x0) / length, (y1 - y0) / length) if length > 0 else (1.0, 0.0)
            sx, sy, height = x0, y0, DOOR_IFC_HEIGHT_M
        matrix = placement(sx, sy, ux, uy, z)
        door = api.root.create_entity(model, ifc_class="IfcDoor", name=f"Door {int(door_id)}")
        door.OverallWidth, door.OverallHeight = float(width), height
        doors.append(door)
        api.geometry.edit_object_placement(model, product=door, matrix=matrix)
        rep = api.geometry.add_wall_representation(
            model, context=body, length=float(width), height=height, thickness=DOOR_IFC_THICKNESS_M,
            offset=-DOOR_IFC_THICKNESS_M / 2.0,
        )
        api.geometry.assign_representation(model, product=door, representation=rep)
        if wall is None:
            continue
        opening = api.root.create_entity(model, ifc_class="IfcOpeningElement", name=f"Opening {int(door_id)}")
        opening.PredefinedType = "OPENING"
        depth = float(thickness) + 2 * OPENING_IFC_MARGIN_M
        rep = api.geometry.add_wall_representation(
            model, context=body, length=float(width), height=height, thickness=depth, offset=-depth / 2.0
        )
        api.geometry.assign_representation(model, product=opening, representation=rep)
        api.geometry.edit_object_placement(model, product=opening, matrix=matrix)
        api.feature.add_feature(model, feature=opening, element=wall)
        api.feature.add_filling(model, opening=opening, element=door)
    contain(model, storey, doors)

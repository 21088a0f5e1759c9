"""The IFC4 export of a floor plan (:func:`write_ifc`; BIM, with IfcOpenShell's API):
IfcProject > IfcSite > IfcBuilding > IfcBuildingStorey, an ``IfcWall`` per wall placed
relative to its storey, an ``IfcRelConnectsPathElements`` per junction of two walls, an
``IfcFurniture`` per clutter piece, an ``IfcSpace`` per room (:func:`_add_spaces`), an
``IfcDoor`` per door in an ``IfcOpeningElement`` that voids its wall
(:func:`_add_doors`), units metres, a STEP header naming the dataset and floorscan's
version, a time stamp from the plan's ``timestamp``, else ``SOURCE_DATE_EPOCH``, else 0
(:func:`~floorscan.floorplan.metadata.export_time`: never the clock), GlobalIds from
the plan's name (:func:`_name_ifc`), so the same plan gives the same bytes.

The model is made with ``ifcopenshell.api`` (:func:`_ifc_model`) and named per file
(:func:`_save_ifc`): a plan written under several names (every ordering's ``k = all``)
builds its model once. Source: IFC4 (ISO 16739-1) and IfcOpenShell's API documentation.
"""

from __future__ import annotations

import math
import os
import uuid
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Mapping

import numpy as np

from floorscan.core.files import atomic_path
from floorscan.floorplan.footprints import PlanExports
from floorscan.floorplan.georeference import Georeference, as_georeference
from floorscan.floorplan.metadata import PlanMetadata, floorscan_version

if TYPE_CHECKING:
    from floorscan.floorplan.params import FloorplanParams
    from floorscan.floorplan.plan import FloorPlan


def _ifc_model(exports: PlanExports, georeference: Georeference | None):
    """The IFC4 model of a plan's exports (see :func:`write_ifc`), not yet named:
    :func:`_save_ifc` names it (:func:`_name_ifc`) by the metadata of each file it is
    saved as.

    Raises
    ------
    ImportError
        When ifcopenshell is not installed.
    """
    try:
        import ifcopenshell.api.aggregate
        import ifcopenshell.api.context
        import ifcopenshell.api.feature
        import ifcopenshell.api.georeference
        import ifcopenshell.api.geometry
        import ifcopenshell.api.project
        import ifcopenshell.api.profile
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
    _contain(model, storey, walls)
    for wall, (wall_id, x0, y0, x1, y1, thickness, height, paired) in zip(walls, rows):
        length = math.hypot(x1 - x0, y1 - y0)
        dx, dy = (x1 - x0) / length, (y1 - y0) / length
        wall.Description = "both faces seen" if paired else "one face seen, thickness assumed"
        # Placement: at the axis start, x along the axis, relative to the storey's.
        api.geometry.edit_object_placement(model, product=wall, matrix=_placement(x0, y0, dx, dy))
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
    return model


def _default_wall_height() -> float:
    """The height of a plan without walls, metres (``floorplan.wall_height_m``'s default)."""
    from floorscan.floorplan.params import FloorplanParams

    return float(FloorplanParams().wall_height_m)


def _contain(model, structure, products: list) -> None:
    """``products`` contained in ``structure`` (``spatial.assign_container``), the
    containment's elements in creation order: the API keeps them in a set, whose
    order changed from run to run, and adds to the structure's one containment (so
    setting it to ``products`` alone would drop the elements contained before)."""
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
    c = plan.clutter
    rows = [
        r for r in zip(c["clutter_id"].tolist(), c["x0"].tolist(), c["y0"].tolist(), c["x1"].tolist(),
                       c["y1"].tolist(), c["reason"].tolist())
        if math.hypot(r[3] - r[1], r[4] - r[2]) > 0
    ]  # fmt: skip
    items = [api.root.create_entity(model, ifc_class="IfcFurniture", name=f"Clutter {r[0]}") for r in rows]
    if not items:
        return
    _contain(model, storey, items)
    for item, (_, x0, y0, x1, y1, reason) in zip(items, rows):
        length = math.hypot(x1 - x0, y1 - y0)
        dx, dy = (x1 - x0) / length, (y1 - y0) / length
        item.ObjectType, item.Description = "clutter", str(reason)
        api.geometry.edit_object_placement(model, product=item, matrix=_placement(x0, y0, dx, dy))
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


def _placement(x: float, y: float, dx: float = 1.0, dy: float = 0.0) -> np.ndarray:
    """4 x 4 placement matrix: origin ``(x, y, 0)`` metres, local x along the unit
    vector ``(dx, dy)``, z up."""
    return np.array([[dx, -dy, 0.0, x], [dy, dx, 0.0, y], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


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
        api.geometry.edit_object_placement(model, product=space, matrix=_placement(x0, y0))
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
        matrix = _placement(sx, sy, ux, uy)
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
    _contain(model, storey, doors)


def _name_ifc(model, plan: FloorPlan, metadata: PlanMetadata) -> None:
    """Name the IFC project by the plan's metadata and derive every GlobalId from its
    title and the creation order (:func:`_ifc_guid_list`): the same plan and title
    give the same ids (BIM tools see the same walls, not new ones), and renaming a
    model gives the ids a fresh model of that title would have."""
    project = model.by_type("IfcProject")[0]
    project.Name = metadata.title
    about = ", ".join(f"{k} {v or '-'}" for k, v in metadata.fields)
    rooms = f", {len(plan.rooms)} rooms, {len(plan.doors)} doors" if len(plan.rooms) or len(plan.doors) else ""
    project.Description = (
        f"floorscan floor plan: {about}, {len(plan.walls)} walls{rooms}; map frame of the recording, metres"
    )
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
    writes) in one write, faster than ``model.write``.

    Header: ``file_name.name`` the file's name, ``time_stamp`` :func:`~floorscan.floorplan.metadata.export_time`
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

    IfcProject (named :attr:`~floorscan.floorplan.metadata.PlanMetadata.title`, described by the metadata) >
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
    _save_ifc(_ifc_model(PlanExports(plan), as_georeference(georeference)), plan, path, meta)


def export(exports: PlanExports, path: str | os.PathLike, meta: PlanMetadata, params: FloorplanParams) -> None:
    """The IFC writer of :data:`floorscan.floorplan.EXPORT_FORMATS`: :func:`write_ifc` of
    a plan's exports, georeferenced by ``params.georeference``. The model is built
    once per plan (kept in ``exports.model``) and renamed and saved for each file."""
    if exports.model is None:
        exports.model = _ifc_model(exports, params.georeference)
    _save_ifc(exports.model, exports.plan, path, meta)

"""The IFC4 export of a floor plan (:func:`write_ifc`; BIM, with IfcOpenShell's API):
IfcProject > IfcSite > IfcBuilding > IfcBuildingStorey, an ``IfcWall`` per wall placed
relative to its storey, an ``IfcRelConnectsPathElements`` per junction of two walls, an
``IfcFurniture`` per clutter piece, an ``IfcSpace`` per room (:func:`~floorscan.floorplan.ifc_storey.add_storey`), an
``IfcDoor`` per door in an ``IfcOpeningElement`` that voids its wall
(:func:`~floorscan.floorplan.ifc_storey.add_storey`), units metres, a STEP header naming the dataset and floorscan's
version, a time stamp from the plan's ``timestamp``, else ``SOURCE_DATE_EPOCH``, else 0
(:func:`~floorscan.floorplan.metadata.export_time`: never the clock), GlobalIds from
the plan's name (:func:`_name_ifc`), so the same plan gives the same bytes.
:func:`write_building_ifc` writes the plans of a building's floors as one model, a
storey per floor at its elevation, each filled as the single storey is.

The model is made with ``ifcopenshell.api`` (:func:`_ifc_model`: the spatial structure,
then each storey's contents, :func:`~floorscan.floorplan.ifc_storey.add_storey`) and named per file (:func:`_save_ifc`):
a plan written under several names (every ordering's ``k = all``) builds its model once.
Source: IFC4 (ISO 16739-1) and IfcOpenShell's API documentation.
"""

from __future__ import annotations

import math
import os
import uuid
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Mapping, Sequence

from floorscan.core.files import atomic_path
from floorscan.floorplan.footprints import PlanExports
from floorscan.floorplan.georeference import Georeference, as_georeference
from floorscan.floorplan.ifc_storey import add_storey, contain, placement
from floorscan.floorplan.metadata import PlanMetadata, floorscan_version

if TYPE_CHECKING:
    from floorscan.floorplan.params import FloorplanParams
    from floorscan.floorplan.plan import FloorPlan

#: The name of the one storey of a floor plan's IFC (:func:`write_ifc`).
STOREY_NAME = "Storey 0"


def _ifc_model(storeys: Sequence[tuple[str, float, PlanExports]], georeference: Georeference | None):
    """The IFC4 model of a building (see :func:`write_ifc`), not yet named: :func:`_save_ifc`
    names it (:func:`_name_ifc`) for each file it is saved as.

    The spatial structure first, IfcProject > IfcSite > IfcBuilding > an
    IfcBuildingStorey per ``(name, elevation_m, exports)`` of ``storeys`` (in that
    order; ``Elevation`` and placement z ``elevation_m`` metres), then each storey's
    contents (:func:`~floorscan.floorplan.ifc_storey.add_storey`): ids follow creation order, so one storey gives the
    model of a single floor plan.

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
    floors = [api.root.create_entity(model, ifc_class="IfcBuildingStorey", name=name) for name, _, _ in storeys]
    elevations = [float(elevation) for _, elevation, _ in storeys]
    for whole, parts, heights in ((project, [site], [0.0]), (site, [building], [0.0]), (building, floors, elevations)):
        api.aggregate.assign_object(model, relating_object=whole, products=parts)
        for rel in whole.IsDecomposedBy:  # a set in the API: creation order
            rel.RelatedObjects = tuple(sorted(rel.RelatedObjects, key=lambda e: e.id()))
        for part, z in zip(parts, heights):  # at its whole's origin, a storey raised to its elevation
            api.geometry.edit_object_placement(model, product=part, matrix=placement(0.0, 0.0, z=z))
    for storey, elevation in zip(floors, elevations):
        storey.Elevation = elevation
    if georeference is not None:
        dms = ifcopenshell.util.geolocation.dd2dms
        site.RefLatitude = dms(georeference.lat, use_us=True)
        site.RefLongitude = dms(georeference.lon, use_us=True)
        h = math.radians(georeference.heading_deg)
        api.georeference.edit_true_north(model, true_north=(math.cos(h), math.sin(h)))
    for storey, (_, _, exports) in zip(floors, storeys):
        add_storey(model, storey, exports, body, axis_ctx)
    return model


def _name_ifc(model, title: str, description: str) -> None:
    """Name the IFC project ``title``, describe it, and derive every GlobalId from the
    title and the creation order (:func:`_ifc_guid_list`): the same model and title
    give the same ids (BIM tools see the same walls, not new ones), ids are unique
    across a building's storeys, and renaming a model gives the ids a fresh model of
    that title would have."""
    project = model.by_type("IfcProject")[0]
    project.Name = title
    project.Description = description
    roots = sorted(model.by_type("IfcRoot"), key=lambda e: e.id())
    for entity, guid in zip(roots, _ifc_guid_list(title, len(roots))):
        entity.GlobalId = guid


def _plan_counts(plan: FloorPlan) -> str:
    """``"14 walls, 5 rooms, 5 doors"``: the walls, and the rooms and doors when there are any."""
    rooms = f", {len(plan.rooms)} rooms, {len(plan.doors)} doors" if len(plan.rooms) or len(plan.doors) else ""
    return f"{len(plan.walls)} walls{rooms}"


def _plan_texts(plan: FloorPlan, meta: PlanMetadata) -> tuple[str, str]:
    """The project description and the header comment of a floor plan's IFC
    (:func:`_save_ifc`): what it is of (``meta.fields``) and its counts."""
    about = ", ".join(f"{k} {v or '-'}" for k, v in meta.fields)
    description = f"floorscan floor plan: {about}, {_plan_counts(plan)}; map frame of the recording, metres"
    fields = " ".join(f"{k} {_mvd_text(v)}" for k, v in meta.fields if v)
    return description, f"floorscan floor plan{' of ' + fields if fields else ''}"


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


def _save_ifc(model, path: str | os.PathLike, meta: PlanMetadata, description: str, comment: str) -> None:
    """Name ``model`` ``meta.title`` with the project ``description`` (:func:`_name_ifc`),
    give it the STEP header of ``path`` and write it atomically as IFC-SPF text:
    ``model.to_string()`` (the text ``model.write`` writes) in one write, faster than
    ``model.write``.

    Header: ``file_name.name`` the file's name, ``time_stamp`` :func:`~floorscan.floorplan.metadata.export_time`
    of ``meta`` (ISO 8601, UTC), author and organization ``floorscan``,
    ``originating_system`` ``floorscan <version>``, ``preprocessor_version``
    IfcOpenShell's; ``file_description`` the view definition
    (DesignTransferView) and ``Comment[<comment>]`` (``comment`` already in MVD
    characters, :func:`_mvd_text`: e.g. :func:`_plan_texts`'s, naming the dataset,
    ordering, extractor, k).
    """
    import ifcopenshell

    _name_ifc(model, meta.title, description)
    header = model.header
    header.file_name.name = Path(path).name
    header.file_name.time_stamp = meta.time_stamp
    header.file_name.author = ("floorscan",)
    header.file_name.organization = ("floorscan",)
    header.file_name.preprocessor_version = f"IfcOpenShell {ifcopenshell.version}"
    header.file_name.originating_system = f"floorscan {floorscan_version()}"
    header.file_name.authorization = ""
    header.file_description.description = ("ViewDefinition[DesignTransferView]", f"Comment[{comment}]")
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
    model = _ifc_model([(STOREY_NAME, 0.0, PlanExports(plan))], as_georeference(georeference))
    _save_ifc(model, path, meta, *_plan_texts(plan, meta))


def write_building_ifc(
    floors: Sequence[tuple[str, float, FloorPlan]], path: str | os.PathLike, name: str = "",
    metadata: PlanMetadata | None = None,
) -> None:  # fmt: skip
    """Write the floor plans of one building as one IFC4 model, a storey per floor.

    IfcProject > IfcSite > IfcBuilding > an IfcBuildingStorey per floor, in the order
    given, named by the floor, with ``Elevation`` its elevation and placed that high
    above the building's origin; each storey holds its plan's walls, junction
    connections, clutter, rooms (IfcSpace) and doors as the one storey of
    :func:`write_ifc` does, at its elevation. The floors are not registered to each
    other: each storey is in the map frame of its recording, x and y in metres. No
    georeference. GlobalIds: :func:`_name_ifc` of the building's title (unique across
    storeys); the STEP header: :func:`_save_ifc`. ``ifcopenshell.validate`` finds no
    issue.

    Parameters
    ----------
    floors : sequence of (str, float, FloorPlan)
        Per storey: its name, its elevation (metres, z up) and its plan.
    path : path
    name : str
        The project's name (overrides ``metadata.name``).
    metadata : PlanMetadata, optional
        The building's title (``name``) and time stamp (``timestamp``).

    Raises
    ------
    ValueError
        For no floors, or an elevation that is not finite.
    ImportError
        When ifcopenshell is not installed (``pip install ifcopenshell``).
    """
    if not floors:
        raise ValueError("a building needs at least one floor")
    bad = [storey for storey, elevation, _ in floors if not math.isfinite(float(elevation))]
    if bad:
        raise ValueError(f"storeys {bad}: the elevation must be a finite number of metres")
    meta = metadata or PlanMetadata()
    if name:
        meta = replace(meta, name=name)
    model = _ifc_model([(str(storey), float(e), PlanExports(plan)) for storey, e, plan in floors], None)
    storeys = "; ".join(f"{storey} at {float(e):g} m: {_plan_counts(plan)}" for storey, e, plan in floors)
    description = (
        f"floorscan building of {len(floors)} storeys: {storeys}; each storey in the map frame of its recording, metres"
    )
    _save_ifc(model, path, meta, description, f"floorscan building {_mvd_text(meta.title)}")


def export(exports: PlanExports, path: str | os.PathLike, meta: PlanMetadata, params: FloorplanParams) -> None:
    """The IFC writer of :data:`floorscan.floorplan.EXPORT_FORMATS`: :func:`write_ifc` of
    a plan's exports, georeferenced by ``params.georeference``. The model is built
    once per plan (kept in ``exports.model``) and renamed and saved for each file.

    Parameters as every writer of :data:`~floorscan.floorplan.EXPORT_FORMATS` (the
    package docstring's "add an export format": ``exports``, ``path``, ``meta``,
    ``params``).
    """
    if exports.model is None:
        exports.model = _ifc_model([(STOREY_NAME, 0.0, exports)], params.georeference)
    _save_ifc(exports.model, path, meta, *_plan_texts(exports.plan, meta))

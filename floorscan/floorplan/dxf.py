"""The DXF export of a floor plan (:func:`write_dxf`; CAD, with ezdxf): layers
:data:`DXF_LAYERS` in the layer table, map coordinates in metres.

R2010 (the default): ``$INSUNITS`` 6 (metres) and ``$MEASUREMENT`` 1 (metric). R12
(``floorplan.dxf_version: R12``, for old tools) has no units header (``$INSUNITS`` came
with R2000): a CAD tool takes its numbers as unitless. ezdxf's audit finds no error in
either. The plan's metadata (:class:`~floorscan.floorplan.metadata.PlanMetadata`) is
ezdxf metadata; the file is written atomically and is byte-identical when written again
from the same input (:func:`_reproducible_ezdxf`). Source: Autodesk's DXF reference and
ezdxf's documentation.
"""

from __future__ import annotations

import contextlib
import io
import logging
import math
import os
from typing import TYPE_CHECKING, Mapping

import numpy as np

from floorscan.core.files import atomic_path
from floorscan.floorplan.footprints import PlanExports
from floorscan.floorplan.georeference import Georeference, as_georeference
from floorscan.floorplan.metadata import PlanMetadata, metadata_member
from floorscan.floorplan.params import DXF_VERSIONS

if TYPE_CHECKING:
    from floorscan.floorplan.params import FloorplanParams
    from floorscan.floorplan.plan import FloorPlan




#: Layers of the DXF export and their colours (AutoCAD Color Index: red, white, green,
#: grey, cyan, orange).
DXF_LAYERS = {"WALL_AXIS": 1, "WALL_OUTLINE": 7, "WALL_FACE": 3, "CLUTTER": 8, "ROOM": 4, "DOOR": 30}

#: Height of the room labels' text, metres.
DXF_ROOM_TEXT_HEIGHT_M = 0.25
#: The gap between a room label's two lines, in text heights: MTEXT's at its default line
#: spacing (baselines 5/3 of the text height apart, AutoCAD's DXF reference).
DXF_LINE_GAP = 2 / 3


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
    ``WALL_FACE`` (a LINE per merged face), ``CLUTTER`` (a LINE per piece that is not
    a wall: furniture, from the structure passes), ``ROOM`` (a closed polyline per
    ring of each room, exterior counter-clockwise and holes clockwise, and a label
    with the name and the area in m² inside it: :func:`_add_rooms`), ``DOOR`` (a LINE
    per door opening, in its wall's line). The active viewport and ``$EXTMIN`` /
    ``$EXTMAX`` frame the plan, so a CAD tool opens on it.

    ``"R2010"`` (default): ``$INSUNITS`` = 6 (metres), ``$MEASUREMENT`` = 1
    (metric), outlines as LWPOLYLINE, room labels as MTEXT; the metadata also as
    drawing properties (``$CUSTOMPROPERTY``, which AutoCAD shows in DWGPROPS).
    ``"R12"``: outlines as POLYLINE, room labels as TEXT (R12 has no MTEXT); R12 has
    no units header (``$INSUNITS`` came with R2000), so CAD tools take the
    coordinates as unitless numbers (they are metres). In both, the plan's
    metadata (:func:`~floorscan.floorplan.metadata.metadata_member`: dataset, ordering, extractor, k, walls, frame,
    units, time stamp, georeference) is ezdxf metadata (``doc.ezdxf_metadata()``).
    The coordinates stay map metres with a georeference (DXF has no CRS; the
    metadata says where the frame lies). ``ezdxf.recover`` and ``doc.audit()`` find
    no error. Creation and update dates are ezdxf's fixed ones
    (:func:`_reproducible_ezdxf`).

    Parameters
    ----------
    plan : FloorPlan
    path : path
        Output, written atomically.
    version : {"R2010", "R12"}
    metadata : PlanMetadata, optional
    georeference : Georeference or mapping, optional
        Named in the metadata; coordinates stay map metres.

    Raises
    ------
    ValueError
        For another ``version``.
    """
    _write_dxf(PlanExports(plan), path, version, metadata or PlanMetadata(), as_georeference(georeference))


def _write_dxf(
    exports: PlanExports, path: str | os.PathLike, version: str, meta: PlanMetadata,
    georeference: Georeference | None,
) -> None:  # fmt: skip
    """:func:`write_dxf` of a plan's :class:`~floorscan.floorplan.footprints.PlanExports`."""
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
        c = plan.clutter
        for x0, y0, x1, y1 in zip(c["x0"].tolist(), c["y0"].tolist(), c["x1"].tolist(), c["y1"].tolist()):
            msp.add_line((x0, y0), (x1, y1), dxfattribs={"layer": "CLUTTER"})
        _add_rooms(msp, exports, version)
        d = plan.doors
        for x0, y0, x1, y1 in zip(d["x0"].tolist(), d["y0"].tolist(), d["x1"].tolist(), d["y1"].tolist()):
            msp.add_line((x0, y0), (x1, y1), dxfattribs={"layer": "DOOR"})
        if exports.has_extent:
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


def _add_rooms(msp, exports: PlanExports, version: str) -> None:
    """Layer ``ROOM``: a closed polyline per ring of each room (exterior
    counter-clockwise, holes clockwise; LWPOLYLINE, in R12 POLYLINE) and its label, the
    name above the area in m² (MTEXT of two lines, middle centre; in R12, which has no
    MTEXT, two TEXT lines), :data:`DXF_ROOM_TEXT_HEIGHT_M` high, placed inside the room
    and clear of the other labels at the largest size that fits, level or along the room
    (:func:`~floorscan.floorplan.labels.place_room_labels`, from the room's label point
    :attr:`~floorscan.floorplan.footprints.PlanExports.room_labels`); the name alone
    where two lines do not fit."""
    from ezdxf.enums import MTextEntityAlignment, TextEntityAlignment

    from floorscan.floorplan.labels import place_room_labels, room_label_boxes

    r = exports.plan.rooms
    add_outline = msp.add_polyline2d if version == "R12" else msp.add_lwpolyline
    h = DXF_ROOM_TEXT_HEIGHT_M
    attribs = {"layer": "ROOM"}
    names, areas, full, alone = room_label_boxes(r, h, h, DXF_LINE_GAP * h)
    xy, scale, with_area, angle = place_room_labels(exports.room_polys, exports.room_labels, full, alone,
                                                    np.full(len(r), h))
    for name, area_text, poly, (x, y), f, both, turn in zip(
        names, areas, exports.room_polys.tolist(), xy.tolist(), scale.tolist(), with_area.tolist(), angle.tolist()
    ):
        if poly is None or poly.is_empty:
            continue
        for ring in (poly.exterior, *poly.interiors):
            add_outline(list(ring.coords)[:-1], close=True, dxfattribs=attribs)
        lines = [name, area_text] if both else [name]
        degrees = math.degrees(turn)  # along the room, counter-clockwise
        if version == "R12":
            step = (1 + DXF_LINE_GAP) * h * f  # baseline to baseline
            up = np.array([-math.sin(turn), math.cos(turn)])
            for i, text in enumerate(lines):
                at = np.array([x, y]) + up * step * ((len(lines) - 1) / 2 - i)
                msp.add_text(text, height=h * f, rotation=degrees, dxfattribs=attribs).set_placement(
                    tuple(at.tolist()), align=TextEntityAlignment.MIDDLE_CENTER
                )
        else:
            label = msp.add_mtext("\\P".join(lines), dxfattribs={**attribs, "char_height": h * f, "rotation": degrees})
            label.set_location((x, y), attachment_point=MTextEntityAlignment.MIDDLE_CENTER)


def _dxf_metadata(plan: FloorPlan, meta: PlanMetadata, georeference: Georeference | None) -> list[tuple[str, str]]:
    """The DXF's metadata: :func:`~floorscan.floorplan.metadata.metadata_member` of the map frame (DXF coordinates are map
    metres), the georeference in words, all as text."""
    md = metadata_member(plan, meta, None)
    md["georeference"] = "none" if georeference is None else (
        f"origin lat {georeference.lat}, lon {georeference.lon} (WGS84); map +x axis "
        f"{georeference.heading_deg} degrees clockwise from true north"
    )  # fmt: skip
    return [(f"floorscan_{k}", str(v)) for k, v in md.items()]


def export(exports: PlanExports, path: str | os.PathLike, meta: PlanMetadata, params: FloorplanParams) -> None:
    """The DXF writer of :data:`floorscan.floorplan.EXPORT_FORMATS`: :func:`write_dxf` of
    a plan's exports in ``params.dxf_version``, naming ``params.georeference``.

    Parameters as every writer of :data:`~floorscan.floorplan.EXPORT_FORMATS` (the
    package docstring's "add an export format": ``exports``, ``path``, ``meta``,
    ``params``).

    Raises
    ------
    ValueError
        For a ``dxf_version`` other than R2010 and R12.
    """
    _write_dxf(exports, path, params.dxf_version, meta, params.georeference)

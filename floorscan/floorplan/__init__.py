"""Floor plans (stage ``floorplan``): one wall per wall from the wall segments of many
scans, and its exports.

Wall extraction runs per scan, so one wall of the building is seen by many scans and
appears as many overlapping segments (thesis section 5.1 names this duplicate
problem). The segments that describe one wall face are merged, and the two faces of a
wall are paired into one wall with its thickness. The modules, in the order a plan is
made and written:

- :mod:`~floorscan.floorplan.params`: :class:`~floorscan.floorplan.params.FloorplanParams`,
  the config section ``floorplan``.
- :mod:`~floorscan.floorplan.candidates`: pairs of segments near each other in place
  and direction.
- :mod:`~floorscan.floorplan.fit`: one segment fitted to several.
- :mod:`~floorscan.floorplan.merge`: the segments of one wall face merged into one.
- :mod:`~floorscan.floorplan.pairing`: the two faces of a wall paired into one wall.
- :mod:`~floorscan.floorplan.structure`: the structure passes, when the free space of
  the plan's scans is known (an occupancy grid): walls that bound the free space,
  collinear pieces joined across unseen gaps, with :mod:`~floorscan.floorplan.clutter`
  (furniture out), :mod:`~floorscan.floorplan.junctions` (L, T and X junctions, one
  wall per wall) and :mod:`~floorscan.floorplan.free_space` (their parameters and the
  grid probes).
- :mod:`~floorscan.floorplan.rooms`: the rooms and doors, when the free space is known:
  the space bounded by the walls (:mod:`~floorscan.floorplan.room_space`) cut into
  rooms at its doors (:mod:`~floorscan.floorplan.doors`, where their jambs can stand:
  :mod:`~floorscan.floorplan.jambs`); the walls that bound no room and are tied to none
  that does are clutter (:mod:`~floorscan.floorplan.lone_walls`).
- :mod:`~floorscan.floorplan.plan`: :class:`~floorscan.floorplan.plan.FloorPlan` and
  :func:`~floorscan.floorplan.plan.build_floorplan`, the steps above in one.
- :mod:`~floorscan.floorplan.scans`: the one plan builder, the plan of any set of scans
  of a wall table (:class:`~floorscan.floorplan.scans.ScanPlans`; the evaluation grid,
  the score stage's curves and the answer build their plans there), and the plan as
  Parquet tables between stages (:mod:`floorscan.core.plan_tables`).
- :mod:`~floorscan.floorplan.grid`: the evaluation grid, the plan of the first k scans
  of every ordering and k.
- :mod:`~floorscan.floorplan.georeference`: where the map frame lies on the earth.
- :mod:`~floorscan.floorplan.metadata`: what a plan is of, its time stamp.
- :mod:`~floorscan.floorplan.footprints`: what all exports of a plan share.
- one module per export format: :mod:`~floorscan.floorplan.geojson` (people, GIS), :mod:`~floorscan.floorplan.svg` (a browser), :mod:`~floorscan.floorplan.dxf`
  (CAD), :mod:`~floorscan.floorplan.ifc` (BIM; a storey's contents:
  :mod:`~floorscan.floorplan.ifc_storey`), registered in :data:`EXPORT_FORMATS`.
- :mod:`~floorscan.floorplan.writer`: :class:`~floorscan.floorplan.writer.FloorplanWriter`
  builds plans and writes them in the formats asked for; the stage's scripts call it.
- :mod:`~floorscan.floorplan.building`: the floors of one building: one IFC with a
  storey per floor, a GeoJSON per floor and the building's page.

Exports (the thesis's purpose, Chapter 1: a plan people and their tools open). Every
file is written atomically (:func:`floorscan.core.files.atomic_path`), carries what it is
a plan of (:class:`~floorscan.floorplan.metadata.PlanMetadata`: dataset, ordering,
extractor, k, number of walls, a time stamp) and is byte-identical when written again
from the same input. The frame is the map frame of the recording: a local engineering
frame, x and y in metres, z up, no geodetic datum, unless ``floorplan.georeference``
places it on the earth; wall properties (thickness, length, height) are metres
everywhere.

Adding an export format
-----------------------
1. Write its module, ``floorscan/floorplan/<name>.py``, with a public
   ``write_<name>(plan, path, metadata=None, ...)`` for use outside the workflow and
   the writer the registry calls, ``export(exports, path, meta, params)``: it writes
   the plan ``exports.plan`` (a :class:`~floorscan.floorplan.plan.FloorPlan`; the
   oriented footprints and their rings in
   :class:`~floorscan.floorplan.footprints.PlanExports`) to ``path`` atomically
   (:func:`floorscan.core.files.atomic_path`), names ``meta``
   (:class:`~floorscan.floorplan.metadata.PlanMetadata`), reads its options from
   ``params`` (:class:`~floorscan.floorplan.params.FloorplanParams`) and gives the same
   bytes for the same input (no clock, no random ids).
2. Register it in :data:`EXPORT_FORMATS` below: ``"<name>": ExportFormat("<suffix>",
   <name>.export)``. :data:`FLOORPLAN_FORMATS` follows, and with it the formats
   :class:`~floorscan.floorplan.writer.FloorplanWriter` writes and the files of the
   recommended plan (``results/<dataset>/floorplan<suffix>``,
   workflow/rules/floorplan.smk).

tests/test_floorplan.py writes every registered format twice and compares the bytes;
add a test that opens the new format with its own tool.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, Iterable

from floorscan.floorplan import dxf, geojson, ifc, svg

if TYPE_CHECKING:
    from floorscan.floorplan.footprints import PlanExports
    from floorscan.floorplan.metadata import PlanMetadata
    from floorscan.floorplan.params import FloorplanParams


@dataclass(frozen=True)
class ExportFormat:
    """An export format of :data:`EXPORT_FORMATS`.

    Attributes
    ----------
    suffix : str
        The file name suffix, with its dot (``".geojson"``).
    write : callable
        ``write(exports, path, meta, params)``: writes ``exports.plan``
        (:class:`~floorscan.floorplan.footprints.PlanExports`) to ``path`` named by
        ``meta`` (:class:`~floorscan.floorplan.metadata.PlanMetadata`), with the
        options of ``params`` (:class:`~floorscan.floorplan.params.FloorplanParams`).
    """

    suffix: str
    write: Callable[[PlanExports, str | os.PathLike, PlanMetadata, FloorplanParams], None]


#: The export formats: name -> file suffix and writer. The one place a format is registered (see the package docstring).
EXPORT_FORMATS: dict[str, ExportFormat] = {
    "geojson": ExportFormat(".geojson", geojson.export),
    "svg": ExportFormat(".svg", svg.export),
    "dxf": ExportFormat(".dxf", dxf.export),
    "ifc": ExportFormat(".ifc", ifc.export),
}

#: Names of the export formats, in the order of :data:`EXPORT_FORMATS` (the recommended
#: plan is written in all of them; workflow/rules/floorplan.smk imports this).
FLOORPLAN_FORMATS = tuple(EXPORT_FORMATS)

#: Formats of the evaluation grid's plans for people (evaluation/floorplan/): SVG, to look at; the score
#: stage reads the grid's Parquet tables, and the recommended plan is written in every format.
EVALUATION_FORMATS = ("svg",)


def floorplan_outputs(stem: str, formats: Iterable[str]) -> dict[str, str]:
    """The files of a plan in ``formats``: format -> ``stem`` + the format's suffix.

    Parameters
    ----------
    stem : str
        Path without suffix, e.g. ``results/demo/floorplan``.
    formats : iterable of str
        Keys of :data:`EXPORT_FORMATS`.

    Returns
    -------
    dict of str to str

    Raises
    ------
    KeyError
        For a format not in :data:`EXPORT_FORMATS`.
    """
    formats = list(formats)
    unknown = [fmt for fmt in formats if fmt not in EXPORT_FORMATS]
    if unknown:
        raise KeyError(f"unknown floor plan formats {unknown}; expected {list(FLOORPLAN_FORMATS)}")
    return {fmt: f"{stem}{EXPORT_FORMATS[fmt].suffix}" for fmt in formats}

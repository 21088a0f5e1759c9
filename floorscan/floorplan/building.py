"""The floors of one building: several recordings or occupancy maps, each the floor plan
of one storey (:func:`write_building`).

A building is a list of :class:`Floor` (a recording or a map, its storey's name and
elevation) and each floor's plan (the answer of its recording or map as the floor plan
stage wrote it: :func:`floorscan.floorplan.scans.read_plan` and
:func:`~floorscan.floorplan.scans.plan_metadata` of ``results/<dataset>/plan_tables``).
It is written as one IFC4 model with an IfcBuildingStorey per floor
(:func:`floorscan.floorplan.ifc.write_building_ifc`),
a GeoJSON per floor (:func:`floorscan.floorplan.geojson.floorplan_geojson`, its
``floorscan`` member naming the building, storey and elevation) and a static page
(``index.html``) that lists the floors with their plans' SVG and links their front
pages. The floors are not registered to each other: each keeps the map frame of its
recording, and a storey is placed only by its elevation. The files of a building:
:func:`building_files` (workflow/rules/building.smk imports it).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Mapping, Sequence
from urllib.parse import quote

from floorscan.core.files import atomic_path
from floorscan.floorplan.geojson import floorplan_geojson, write_geojson_document
from floorscan.floorplan.ifc import write_building_ifc
from floorscan.floorplan.metadata import PlanMetadata, floor_area_m2
from floorscan.core.messages import count_text

if TYPE_CHECKING:
    from floorscan.floorplan.plan import FloorPlan


@dataclass(frozen=True)
class Floor:
    """A floor of a building.

    Attributes
    ----------
    dataset : str
        The recording of the floor (a dataset of the run: ``results/<dataset>/``).
    storey : str
        The storey's name (``"Ground floor"``).
    elevation_m : float
        The storey's elevation above the building's origin, metres, z up.
    """

    dataset: str
    storey: str
    elevation_m: float = 0.0


def building_files(out_dir: str | os.PathLike, datasets: Sequence[str]) -> dict:
    """The files of a building written to ``out_dir``.

    Parameters
    ----------
    out_dir : path
    datasets : sequence of str
        The building's floors' datasets.

    Returns
    -------
    dict
        ``ifc`` (``building.ifc``), ``page`` (``index.html``) and ``geojson``, a list of
        ``<dataset>.geojson`` in the order of ``datasets``; paths as strings joined with
        ``/``.
    """
    out = os.fspath(out_dir).rstrip("/")
    return {
        "ifc": f"{out}/building.ifc",
        "page": f"{out}/index.html",
        "geojson": [f"{out}/{ds}.geojson" for ds in datasets],
    }


def write_building(
    floors: Sequence[Floor], plans: Mapping[str, FloorPlan], out_dir: str | os.PathLike, name: str = "Building",
    metadata: Mapping[str, PlanMetadata] | None = None,
) -> dict:  # fmt: skip
    """Write a building: its IFC, a GeoJSON per floor and its page (:func:`building_files`).

    Parameters
    ----------
    floors : sequence of Floor
        The floors, in the order of the storeys and the page's rows.
    plans : mapping
        Each floor's plan by its dataset.
    out_dir : path
        The building's folder, beside the floors' ``results/<dataset>/`` folders: the
        page links ``../<dataset>/floorplan.svg`` and ``../<dataset>/front.html``.
    name : str
        The building's name (IFC project, page title).
    metadata : mapping, optional
        Each floor's :class:`~floorscan.floorplan.metadata.PlanMetadata` by its dataset
        (:func:`~floorscan.floorplan.scans.plan_metadata`): its GeoJSON names
        it; the building's time stamp is the least of theirs. None: the dataset only.

    Returns
    -------
    dict
        The files written, :func:`building_files`.

    Raises
    ------
    ValueError
        For no floors, or two floors of one dataset.
    KeyError
        For a floor without a plan.
    """
    datasets = [f.dataset for f in floors]
    if not floors:
        raise ValueError("a building needs at least one floor")
    if len(set(datasets)) != len(datasets):
        raise ValueError(f"a recording is one floor only; the floors' datasets are {datasets}")
    missing = [ds for ds in datasets if ds not in plans]
    if missing:
        raise KeyError(f"no plan for the floors of {missing}")
    metas = {ds: (metadata or {}).get(ds) or PlanMetadata(dataset=ds) for ds in datasets}
    stamps = [m.timestamp for m in metas.values() if m.timestamp is not None]
    files = building_files(out_dir, datasets)
    write_building_ifc(
        [(f.storey, f.elevation_m, plans[f.dataset]) for f in floors], files["ifc"],
        metadata=PlanMetadata(name=name, timestamp=min(stamps) if stamps else None),
    )  # fmt: skip
    for floor, path in zip(floors, files["geojson"]):
        doc = floorplan_geojson(plans[floor.dataset], metas[floor.dataset])
        doc["floorscan"].update(building=name, storey=floor.storey, elevation_m=float(floor.elevation_m))
        write_geojson_document(doc, path)
    with atomic_path(files["page"]) as tmp:
        tmp.write_text(building_page(floors, plans, name), encoding="utf-8")
    return files


def building_page(floors: Sequence[Floor], plans: Mapping[str, FloorPlan], name: str) -> str:
    """The building's page, static HTML: its name and a table of its floors (storey,
    elevation in metres, walls, rooms, floor area in square metres
    (:func:`~floorscan.floorplan.metadata.floor_area_m2`), doors), each with its
    plan's SVG as a thumbnail (``../<dataset>/floorplan.svg``) linking its front page
    (``../<dataset>/front.html``) and its GeoJSON (``<dataset>.geojson``): the Jinja2
    template ``templates/building_page.html.j2`` of this package, autoescaped.

    Parameters
    ----------
    floors : sequence of Floor
        In table order.
    plans : mapping of str to FloorPlan
        Each floor's plan by its dataset.
    name : str
        The building's name (the title).

    Returns
    -------
    str
        The HTML document.

    Raises
    ------
    KeyError
        A floor whose dataset has no plan in ``plans``.
    """
    from jinja2 import Environment, PackageLoader, StrictUndefined

    rows = []
    for f in floors:
        plan, ds = plans[f.dataset], quote(f.dataset)
        rows.append({
            "front": f"../{ds}/front.html", "svg": f"../{ds}/floorplan.svg", "geojson": f"{ds}.geojson",
            "dataset": f.dataset, "storey": f.storey, "elevation_m": float(f.elevation_m), "walls": len(plan.walls),
            "rooms": len(plan.rooms), "area_m2": floor_area_m2(plan), "doors": len(plan.doors),
        })  # fmt: skip
    env = Environment(loader=PackageLoader("floorscan.floorplan", "templates"), autoescape=True,
                      undefined=StrictUndefined, keep_trailing_newline=True)  # fmt: skip
    page = {"name": name, "floors_text": count_text(len(floors), "floor"), "rows": rows}
    return env.get_template("building_page.html.j2").render(page=page)

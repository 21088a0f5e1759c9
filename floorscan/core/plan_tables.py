"""A floor plan as Parquet tables: how a plan passes from the stage that builds it to the
stages that read it (the evaluation grid's plans, scored by the score stage and drawn
by the figures). GeoJSON, SVG, DXF and IFC are the plan's exports for people
(:mod:`floorscan.floorplan`); between stages a plan is this.

A plan is a folder of one Parquet file per part, each with the schema of
:data:`PLAN_SCHEMAS` (the columns of :class:`floorscan.floorplan.plan.FloorPlan`'s
tables): ``walls.parquet``, ``faces.parquet``, ``clutter.parquet`` and
``junctions.parquet`` always; ``rooms.parquet`` (the polygon as WKB, little-endian,
2D) and ``doors.parquet`` when the plan has rooms. Coordinates and lengths are map
metres rounded to :data:`PLAN_DECIMALS` decimals, as the plan's GeoJSON export
rounds them, and room polygons are oriented as it orients them (RFC 7946:
counter-clockwise exterior, clockwise holes), so the tables and the export of one plan
give the same numbers, vertex for vertex. A plan that is scored and never exported (the
answer's plans of the first k scans) may keep its numbers as computed (``rounded=False``).

:func:`write_plan_tables` writes the folder (into a temporary folder, then renamed:
a crash leaves no half plan); :func:`read_plan_tables` reads it back, any parts;
:func:`plan_faces_and_walls` and :func:`plan_rooms` read what the scores and the pages
take of it.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

from floorscan.core.io import parquet_options

_XY = [("x0", pa.float64()), ("y0", pa.float64()), ("x1", pa.float64()), ("y1", pa.float64())]

#: The Parquet schema of each part of a plan (the parts in this order).
PLAN_SCHEMAS: dict[str, pa.Schema] = {
    "walls": pa.schema(
        [("wall_id", pa.int32()), *_XY, ("length_m", pa.float64()), ("thickness_m", pa.float64()),
         ("height_m", pa.float64()), ("paired", pa.bool_()), ("n_faces", pa.int32()), ("n_segments", pa.int32()),
         ("n_inliers", pa.int64())]  # fmt: skip
    ),
    "faces": pa.schema(
        [("face_id", pa.int32()), ("wall_id", pa.int32()), *_XY, ("length_m", pa.float64()),
         ("n_segments", pa.int32()), ("n_inliers", pa.int64())]  # fmt: skip
    ),
    "clutter": pa.schema([("clutter_id", pa.int32()), *_XY, ("length_m", pa.float64()), ("reason", pa.string())]),
    "junctions": pa.schema(
        [("x", pa.float64()), ("y", pa.float64()), ("kind", pa.string()), ("wall_a", pa.int32()), ("wall_b", pa.int32())]
    ),
    "rooms": pa.schema(
        [("room_id", pa.int32()), ("name", pa.string()), ("kind", pa.string()), ("area_m2", pa.float64()),
         ("perimeter_m", pa.float64()), ("polygon", pa.binary())]  # fmt: skip
    ),
    "doors": pa.schema(
        [("door_id", pa.int32()), *_XY, ("width_m", pa.float64()), ("wall_id", pa.int32()), ("room_a", pa.int32()),
         ("room_b", pa.int32())]  # fmt: skip
    ),
}
#: Metadata key of a plan of some scans (the answer's plans of the first k scans,
#: :mod:`floorscan.floorplan.answer_plans`): the wall points of its scans, ``"0"`` when
#: they have none and so no plan could be made of them.
N_WALL_POINTS = "n_wall_points"
#: The parts every plan folder holds; rooms and doors only when the plan has rooms.
ALWAYS = ("walls", "faces", "clutter", "junctions")
#: Decimals of the coordinates (metres), 10 micrometres: the plan's GeoJSON export
#: takes its map-frame precision from here (``floorscan.floorplan.geojson.GEOJSON_DECIMALS``).
PLAN_DECIMALS = 5
#: Columns rounded to :data:`PLAN_DECIMALS` (coordinates); lengths, widths and areas
#: are rounded to 4 decimals, as the export writes them.
_COORDINATES = ("x0", "y0", "x1", "y1", "x", "y")
_MEASURES = ("length_m", "width_m", "area_m2", "perimeter_m", "thickness_m")


def _rounded(values: np.ndarray, decimals: int) -> np.ndarray:
    """Python's ``round`` of each value (correctly rounded, as the GeoJSON export:
    numpy's ``round`` can differ from it in the last digit)."""
    return np.fromiter((round(float(v), decimals) for v in values), dtype=np.float64, count=len(values))


def write_plan_tables(
    tables: Mapping[str, pd.DataFrame], folder: str | os.PathLike, metadata: Mapping[str, str] | None = None,
    rounded: bool = True,
) -> None:
    """Write a plan's tables as a plan folder, atomically (a temporary folder renamed;
    an existing folder is replaced).

    Parameters
    ----------
    tables : mapping of str to pandas.DataFrame
        Part name (:data:`PLAN_SCHEMAS`) -> its table. Every part of :data:`ALWAYS` is
        needed; ``rooms`` and ``doors`` are written when given and ``rooms`` is not
        empty. The ``polygon`` column of ``rooms`` holds shapely Polygons (map metres;
        oriented and rounded as the GeoJSON export does), None for a room without one,
        or WKB bytes (written as given).
    folder : path
        The plan folder, e.g. ``evaluation/plans/<ordering>_<extractor>_k<k>``.
    metadata : mapping of str to str, optional
        Stored in each file's schema metadata (dataset, ordering, extractor, k).
    rounded : bool
        Round coordinates and lengths as the GeoJSON export does (False: as computed,
        for a plan that is scored and never exported: a face on the reference map's
        cell lattice is 5 cm from a cell centre, where 10 micrometres move a score).

    Raises
    ------
    KeyError
        When a part of :data:`ALWAYS` is missing, a part is unknown, or a table lacks
        a column of its schema.
    """
    unknown = sorted(set(tables) - set(PLAN_SCHEMAS))
    missing = [p for p in ALWAYS if p not in tables]
    if unknown or missing:
        raise KeyError(f"plan parts: unknown {unknown}, missing {missing}; expected {list(PLAN_SCHEMAS)}")
    parts = [p for p in PLAN_SCHEMAS if p in tables]
    if "rooms" in parts and not len(tables["rooms"]):
        parts = [p for p in parts if p not in ("rooms", "doors")]
    folder = Path(folder)
    tmp = folder.with_name(folder.name + ".tmp")
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir(parents=True)
    meta = {k.encode(): str(v).encode() for k, v in (metadata or {}).items()}
    for part in parts:
        table = _arrow_table(tables[part], PLAN_SCHEMAS[part], rounded)
        if meta:
            table = table.replace_schema_metadata(meta)
        pq.write_table(table, tmp / f"{part}.parquet", **parquet_options(table.schema))
    if folder.exists():
        shutil.rmtree(folder)
    os.replace(tmp, folder)


def _arrow_table(df: pd.DataFrame, schema: pa.Schema, rounded: bool = True) -> pa.Table:
    absent = [n for n in schema.names if n not in df.columns]
    if absent:
        raise KeyError(f"plan table lacks columns {absent}; expected {schema.names}")
    columns = {}
    for field in schema:
        values = df[field.name].to_numpy()
        if field.name in _COORDINATES and rounded:
            values = _rounded(values, PLAN_DECIMALS)
        elif field.name in _MEASURES and rounded:
            values = _rounded(values, 4)
        elif field.name == "polygon":
            values = [v if isinstance(v, bytes) else _polygon_wkb(v, rounded) for v in values]
        columns[field.name] = pa.array(values, type=field.type) if len(values) else pa.array([], type=field.type)
    return pa.table(columns, schema=schema)


def _polygon_wkb(poly, rounded: bool = True) -> bytes | None:
    """A room polygon as the GeoJSON export writes it, as WKB: oriented (counter-clockwise
    exterior, clockwise holes) and, when ``rounded``, its coordinates rounded to
    :data:`PLAN_DECIMALS` (Python's ``round``); None stays None (the export skips a
    missing or empty room)."""
    import shapely

    if poly is None:
        return None
    if not poly.is_empty:
        poly = shapely.orient_polygons(poly, exterior_cw=False)
        if rounded:
            poly = shapely.transform(poly, lambda xy: _rounded(xy.ravel(), PLAN_DECIMALS).reshape(-1, 2))
    return shapely.to_wkb(poly, output_dimension=2, byte_order=1)


def read_plan_tables(
    folder: str | os.PathLike, parts: Sequence[str] = tuple(PLAN_SCHEMAS), columns: Mapping[str, list[str]] | None = None
) -> dict[str, pd.DataFrame]:
    """Read parts of a plan folder (:func:`write_plan_tables`).

    Parameters
    ----------
    folder : path
    parts : sequence of str
        The parts to read (:data:`PLAN_SCHEMAS`); a part the folder lacks (rooms,
        doors of a plan without rooms) is an empty table of its schema.
    columns : mapping of str to list of str, optional
        Per part, the columns to read (default: all).

    Returns
    -------
    dict of str to pandas.DataFrame
        Part -> table; ``rooms.polygon`` stays WKB bytes (``shapely.from_wkb``).

    Raises
    ------
    KeyError
        For an unknown part.
    FileNotFoundError
        When the folder lacks a part of :data:`ALWAYS` (not a plan folder).
    """
    folder = Path(folder)
    out = {}
    for part in parts:
        schema = PLAN_SCHEMAS[part]
        names = None if columns is None or part not in columns else list(columns[part])
        path = folder / f"{part}.parquet"
        if part not in ALWAYS and not path.is_file():
            out[part] = (schema if names is None else pa.schema([schema.field(n) for n in names])).empty_table().to_pandas()
            continue
        out[part] = pq.read_table(path, columns=names).to_pandas()
    return out


def read_plan_metadata(folder: str | os.PathLike) -> dict[str, str]:
    """What a plan folder is of: the ``metadata`` :func:`write_plan_tables` stored (its
    walls table's schema metadata).

    Parameters
    ----------
    folder : path

    Returns
    -------
    dict of str to str
        Empty when none was stored.

    Raises
    ------
    FileNotFoundError
        When the folder is not a plan folder.
    """
    path = Path(folder) / "walls.parquet"
    if not path.is_file():
        raise FileNotFoundError(f"{folder}: not a plan folder (no walls.parquet)")
    meta = pq.read_schema(path).metadata or {}
    return {k.decode(): v.decode() for k, v in meta.items() if not k.startswith(b"ARROW:")}


def plan_faces_and_walls(folder: str | os.PathLike) -> tuple[np.ndarray, int]:
    """The merged faces and the wall count of a plan folder: what a plan is scored on.

    Parameters
    ----------
    folder : path

    Returns
    -------
    faces : (F, 4) float64 ndarray
        ``x0, y0, x1, y1``, map metres.
    n_walls : int

    Raises
    ------
    FileNotFoundError
        When the folder is not a plan folder.
    """
    t = read_plan_tables(folder, ("walls", "faces"), {"walls": ["wall_id"], "faces": ["x0", "y0", "x1", "y1"]})
    return t["faces"].to_numpy(np.float64).reshape(-1, 4), len(t["walls"])


def plan_rooms(folder: str | os.PathLike) -> tuple[list[dict], pd.DataFrame]:
    """The rooms and doors of a plan folder, as the plan's exports and the room scores
    take them: a room without a polygon (missing or empty), which the exports skip, is
    left out.

    Parameters
    ----------
    folder : path

    Returns
    -------
    rooms : list of dict
        In the tables' order (the GeoJSON export's), one per room with a polygon:
        ``room_id`` (int), ``name`` (str), ``kind`` (``room``, ``corridor`` or
        ``space``), ``area_m2`` (float, square metres), ``perimeter_m`` (float, metres)
        and ``polygon`` (shapely Polygon, map metres, as stored: rounded to
        :data:`PLAN_DECIMALS`). Empty for a plan without rooms.
    doors : pandas.DataFrame
        The doors table (:data:`PLAN_SCHEMAS` ``doors``), as stored.

    Raises
    ------
    FileNotFoundError
        When the folder is not a plan folder.
    """
    import shapely

    # walls: a folder that is not a plan raises (rooms and doors may be absent)
    t = read_plan_tables(folder, ("walls", "rooms", "doors"), {"walls": ["wall_id"]})
    r = t["rooms"]
    rooms = []
    polys = shapely.from_wkb(r["polygon"].to_numpy()) if len(r) else []
    for room_id, name, kind, area, perimeter, poly in zip(
        r["room_id"].tolist(), r["name"].tolist(), r["kind"].tolist(), r["area_m2"].tolist(),
        r["perimeter_m"].tolist(), polys,
    ):  # fmt: skip
        if poly is None or poly.is_empty:
            continue
        rooms.append({"room_id": int(room_id), "name": str(name), "kind": str(kind), "area_m2": float(area),
                      "perimeter_m": float(perimeter), "polygon": poly})  # fmt: skip
    return rooms, t["doors"]

"""The floor plan of a set of scans: the one plan builder of the workflow.

:class:`ScanPlans` holds one wall table of the walls stage (every kept scan's segments
of one extractor, ``walls/<extractor>/per_scan.parquet``, or the map extractor's
``walls/map/*.parquet``) and builds the plan of any set of its scans
(:meth:`ScanPlans.plan`, :func:`~floorscan.floorplan.plan.plan_of_segments`); the
evaluation grid (the first k scans of every ordering), the score stage's curves (the
same, on a finer k grid: :meth:`ScanPlans.faces`, the merged faces alone) and the
answer (the selected scans) all build their plans here. A plan depends on which scans
gave the segments, not on the order they are named in: the segments are taken in scan
order. With ``prepared=True`` the merge's first pass is tested once for the whole
table (:class:`~floorscan.floorplan.merge.FirstMergePass`), which many plans of
subsets of it share; the plans are the same.

:func:`write_plan` and :func:`read_plan` pass a plan between stages as Parquet tables
(:mod:`floorscan.core.plan_tables`), and :func:`plan_metadata` says what it is of.
Source: the duplicate problem of thesis section 5.1.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Iterable, Mapping

import numpy as np
import pandas as pd

from floorscan.core.plan_tables import read_plan_metadata, read_plan_tables, write_plan_tables
from floorscan.floorplan.merge import FirstMergePass
from floorscan.floorplan.metadata import PlanMetadata, from_table_metadata
from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.plan import (
    CLUTTER_COLUMNS, DOOR_COLUMNS, FACE_COLUMNS, JUNCTION_COLUMNS, ROOM_COLUMNS, WALL_COLUMNS, FloorPlan, plan_faces,
    plan_of_segments, segment_arrays,
)  # fmt: skip

if TYPE_CHECKING:
    from floorscan.core.occupancy import OccupancyGrid


class ScanPlans:
    """Floor plans of sets of scans of one wall table.

    Parameters
    ----------
    walls : pandas.DataFrame
        Wall segments ``x0, y0, x1, y1`` (metres, map frame), ``n_inliers`` (merge
        weights; without it the lengths) and ``scan_id`` (schema
        :data:`floorscan.walls.tables.WALLS`); rows with a non-finite coordinate are
        dropped (:func:`~floorscan.floorplan.plan.segment_arrays`).
    params : FloorplanParams
    prepared : bool
        Test the merge's first pass once for the whole table (for many plans of
        subsets of it; a table of more than 20 million candidate pairs is not
        prepared). The plans are the same either way.

    Raises
    ------
    KeyError
        When a coordinate column is missing.
    """

    def __init__(self, walls: pd.DataFrame, params: FloorplanParams = FloorplanParams(), prepared: bool = False):
        self.params = params
        self.seg, self.weights, self.scan_ids = segment_arrays(walls)
        self._first_pass = FirstMergePass(self.seg, params) if prepared else None

    def rows(self, scan_ids: Iterable[int] | None) -> np.ndarray:
        """The segments of ``scan_ids``.

        Parameters
        ----------
        scan_ids : iterable of int or None
            The scans, in any order; None: every segment of the table.

        Returns
        -------
        (M,) bool ndarray
            A mask of the table's (finite) segments.

        Raises
        ------
        ValueError
            When scans are named and the table has no ``scan_id`` column.
        """
        if scan_ids is None:
            return np.ones(len(self.seg), dtype=bool)
        if self.scan_ids is None:
            raise ValueError("the wall table has no scan_id column: a plan of some of its scans needs one")
        return np.isin(self.scan_ids, np.fromiter((int(s) for s in scan_ids), dtype=np.int64))

    def _parts(self, rows: np.ndarray):
        weights = None if self.weights is None else self.weights[rows]
        first = None if self._first_pass is None else self._first_pass.groups(rows)
        return self.seg[rows], weights, first

    def faces(self, scan_ids: Iterable[int] | None = None) -> np.ndarray:
        """The merged wall faces of the plan of ``scan_ids`` (the faces :meth:`plan`'s
        plan has without a grid), without pairing them into walls.

        Parameters
        ----------
        scan_ids : iterable of int or None
            The scans; None: all.

        Returns
        -------
        (F, 4) float64 ndarray
            ``x0, y0, x1, y1``, metres.
        """
        seg, weights, first = self._parts(self.rows(scan_ids))
        return plan_faces(seg, weights, self.params, first)[0]

    def plan(self, scan_ids: Iterable[int] | None = None, grid: OccupancyGrid | None = None,
             with_rooms: bool = True) -> FloorPlan:  # fmt: skip
        """The floor plan of the segments of ``scan_ids``
        (:func:`~floorscan.floorplan.plan.build_floorplan` of those rows).

        Parameters
        ----------
        scan_ids : iterable of int or None
            The scans; None: every segment of the table (the map extractor's table
            of the selected scans is their plan whole).
        grid : OccupancyGrid, optional
            The free space of those scans: structure passes, junctions, rooms.
        with_rooms : bool
            Whether to segment the rooms (:func:`~floorscan.floorplan.plan.plan_of_segments`).

        Returns
        -------
        FloorPlan
        """
        seg, weights, first = self._parts(self.rows(scan_ids))
        return plan_of_segments(seg, weights, self.params, grid, first, with_rooms)


def plan_of_scans(
    walls: pd.DataFrame, scan_ids: Iterable[int] | None, params: FloorplanParams = FloorplanParams(),
    grid: OccupancyGrid | None = None,
) -> FloorPlan:
    """The floor plan of some scans of a wall table: ``ScanPlans(walls, params).plan(scan_ids, grid)``.

    Parameters
    ----------
    walls : pandas.DataFrame
        Wall segments with ``scan_id`` (:class:`ScanPlans`).
    scan_ids : iterable of int or None
        The scans; None: all rows.
    params : FloorplanParams
    grid : OccupancyGrid, optional

    Returns
    -------
    FloorPlan

    Raises
    ------
    KeyError
        When a coordinate column is missing.
    ValueError
        When scans are named and ``walls`` has no ``scan_id``.
    """
    return ScanPlans(walls, params).plan(scan_ids, grid)


def plan_tables(plan: FloorPlan) -> dict[str, pd.DataFrame]:
    """The plan's tables by part name (:data:`floorscan.core.plan_tables.PLAN_SCHEMAS`).

    Parameters
    ----------
    plan : FloorPlan

    Returns
    -------
    dict of str to pandas.DataFrame
        ``walls, faces, clutter, junctions, rooms, doors`` (``rooms.polygon``: shapely Polygons).
    """
    return {"walls": plan.walls, "faces": plan.faces, "clutter": plan.clutter, "junctions": plan.junctions,
            "rooms": plan.rooms, "doors": plan.doors}  # fmt: skip


def write_plan(
    plan: FloorPlan, folder: str | os.PathLike, metadata: Mapping[str, str] | None = None, rounded: bool = True
) -> None:
    """Write a plan as Parquet tables (:func:`floorscan.core.plan_tables.write_plan_tables`:
    coordinates rounded to 10 micrometres as its GeoJSON export rounds them, unless
    ``rounded`` is False).

    Parameters
    ----------
    plan : FloorPlan
    folder : path
        The plan folder (replaced when it exists).
    metadata : mapping of str to str, optional
        What the plan is of (dataset, ordering, extractor, k), in each file.
    rounded : bool
        False: the numbers as computed (a plan that is scored, never exported).
    """
    write_plan_tables(plan_tables(plan), folder, metadata, rounded)


def read_plan(folder: str | os.PathLike) -> FloorPlan:
    """A plan folder (:func:`write_plan`) as a :class:`FloorPlan`.

    Parameters
    ----------
    folder : path

    Returns
    -------
    FloorPlan
        Rooms' polygons as shapely Polygons; rooms and doors empty when the folder has none.

    Raises
    ------
    FileNotFoundError
        When the folder is not a plan folder.
    """
    t = read_plan_tables(folder)
    rooms = t["rooms"]
    if len(rooms):
        import shapely

        rooms = rooms.assign(polygon=list(shapely.from_wkb(rooms["polygon"].to_numpy())))
    else:
        rooms = rooms.astype({"polygon": object})
    return FloorPlan(
        walls=t["walls"][WALL_COLUMNS], faces=t["faces"][FACE_COLUMNS], clutter=t["clutter"][CLUTTER_COLUMNS],
        junctions=t["junctions"][JUNCTION_COLUMNS], rooms=rooms[ROOM_COLUMNS], doors=t["doors"][DOOR_COLUMNS],
    )


def plan_metadata(folder: str | os.PathLike) -> PlanMetadata:
    """What a plan folder (:func:`write_plan`) is of, as its exports name it: dataset,
    ordering, extractor, k and the time stamp (the recording's first scan, seconds
    since the epoch; None for a map, or a folder written without one).

    Parameters
    ----------
    folder : path

    Returns
    -------
    PlanMetadata

    Raises
    ------
    FileNotFoundError
        When the folder is not a plan folder.
    ValueError
        When its time stamp is not a number.
    """
    return from_table_metadata(read_plan_metadata(folder), os.fspath(folder))

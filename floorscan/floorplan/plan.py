"""The floor plan of the wall segments of many scans (:func:`build_floorplan`): the
segments merged into faces (:func:`~floorscan.floorplan.merge.merge_segments`), faces
shorter than ``min_length_m`` dropped, the faces paired into walls with their thickness
(:func:`~floorscan.floorplan.pairing.pair_faces`), as a :class:`FloorPlan`: a table of
walls (:data:`WALL_COLUMNS`) and one of faces (:data:`FACE_COLUMNS`).

The segments are taken in scan order, so a plan depends on which scans gave them, not
on how an ordering ranked the scans. The plan's exports: :mod:`floorscan.floorplan.writer`.
Source: the duplicate problem of thesis section 5.1.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from floorscan.core.memory import JobMemory
from floorscan.floorplan.merge import merge_segments
from floorscan.floorplan.pairing import pair_faces
from floorscan.floorplan.params import FloorplanParams

if TYPE_CHECKING:
    from floorscan.core.occupancy import OccupancyGrid

log = logging.getLogger(__name__)

#: What a cell of the free space's grid takes a job that builds a plan on it (the grid
#: read, its log-odds and masks, the structure passes' distance transforms, the rooms'
#: rasters) at the job's peak, rounded up (``benchmarks/README.md``); the grid's cells
#: are the map extractor's.
PLAN_MEMORY = JobMemory(56, "walls.map.support_cell_m")


#: Columns of :attr:`FloorPlan.walls`.
WALL_COLUMNS = [
    "wall_id", "x0", "y0", "x1", "y1", "length_m", "thickness_m", "height_m",
    "paired", "n_faces", "n_segments", "n_inliers",
]  # fmt: skip
#: Columns of :attr:`FloorPlan.faces`.
FACE_COLUMNS = ["face_id", "wall_id", "x0", "y0", "x1", "y1", "length_m", "n_segments", "n_inliers"]
#: Columns of :attr:`FloorPlan.clutter`.
CLUTTER_COLUMNS = ["clutter_id", "x0", "y0", "x1", "y1", "length_m", "reason"]
#: Columns of :attr:`FloorPlan.junctions`; ``kind`` is ``L``, ``T`` or ``X``.
JUNCTION_COLUMNS = ["x", "y", "kind", "wall_a", "wall_b"]
#: Columns of :attr:`FloorPlan.rooms`; ``kind`` is ``room``, ``corridor`` or ``space``,
#: ``polygon`` a shapely Polygon (holes allowed) in map metres.
ROOM_COLUMNS = ["room_id", "name", "kind", "area_m2", "perimeter_m", "polygon"]
#: Columns of :attr:`FloorPlan.doors`: the opening as a segment in its wall's line.
DOOR_COLUMNS = ["door_id", "x0", "y0", "x1", "y1", "width_m", "wall_id", "room_a", "room_b"]

_TEXT_COLUMNS = ("reason", "kind", "name", "polygon")


def _empty(columns: list[str]) -> pd.DataFrame:
    return pd.DataFrame({c: pd.Series(dtype=object if c in _TEXT_COLUMNS else np.float64) for c in columns})


@dataclass
class FloorPlan:
    """A merged floor plan.

    Attributes
    ----------
    walls : pandas.DataFrame
        One row per wall (:data:`WALL_COLUMNS`): axis ``x0, y0, x1, y1`` (centre
        line, metres), ``thickness_m``, ``height_m``, ``paired`` (both faces seen).
    faces : pandas.DataFrame
        One row per merged face (:data:`FACE_COLUMNS`), ``wall_id`` of its wall.
    clutter : pandas.DataFrame
        Faces that are not structure (:data:`CLUTTER_COLUMNS`: furniture, lines
        through objects, single-scan returns, with the ``reason``), from the structure
        passes (:mod:`floorscan.floorplan.structure`), and with the rooms the faces of
        the walls that bound none, tied to none that does (``bounds_no_room``); empty
        without the passes.
    junctions : pandas.DataFrame
        Where walls meet (:data:`JUNCTION_COLUMNS`: the point, metres, ``L``, ``T`` or
        ``X``, the two walls' ids); empty without the structure passes.
    rooms : pandas.DataFrame
        The rooms (:data:`ROOM_COLUMNS`): ``room_id``, ``name`` (``"Room 1"``,
        ``"Corridor 1"``, ``"Space 1"``), ``kind`` (``room``, ``corridor``, or
        ``space`` for free space that no walls close into rooms), ``area_m2``,
        ``perimeter_m`` and ``polygon`` (a valid shapely Polygon, holes allowed, map
        metres); from :mod:`floorscan.floorplan.rooms`, empty without the free space.
    doors : pandas.DataFrame
        The doors (:data:`DOOR_COLUMNS`): the opening ``x0, y0, x1, y1`` (metres) in
        the line of the wall ``wall_id`` (-1 when no plan wall lies on it), its
        ``width_m`` and the two rooms it joins (``room_a < room_b``); from
        :mod:`floorscan.floorplan.doors`.
    """

    walls: pd.DataFrame
    faces: pd.DataFrame
    clutter: pd.DataFrame = field(default_factory=lambda: _empty(CLUTTER_COLUMNS))
    junctions: pd.DataFrame = field(default_factory=lambda: _empty(JUNCTION_COLUMNS))
    rooms: pd.DataFrame = field(default_factory=lambda: _empty(ROOM_COLUMNS))
    doors: pd.DataFrame = field(default_factory=lambda: _empty(DOOR_COLUMNS))

    def footprints(self):
        """Wall polygons, the axis buffered by half the thickness, flat ends
        (:func:`floorscan.floorplan.room_space.wall_footprints`).

        Returns
        -------
        (N,) object ndarray of shapely Polygon
            One per row of ``walls``, map metres.
        """
        from floorscan.floorplan.room_space import wall_footprints

        return wall_footprints(self.walls[["x0", "y0", "x1", "y1"]].to_numpy(np.float64), self.walls["thickness_m"].to_numpy())


def segment_arrays(segments: pd.DataFrame) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """The segments as :func:`build_floorplan` merges them: in scan order (a stable
    sort by ``scan_id``, when there is one), those with a non-finite coordinate dropped
    (with a warning).

    Parameters
    ----------
    segments : pandas.DataFrame
        ``x0, y0, x1, y1`` (metres), optional ``n_inliers`` and ``scan_id``.

    Returns
    -------
    seg : (M, 4) float64 ndarray
        ``x0, y0, x1, y1``, metres.
    weights : (M,) float64 ndarray or None
        ``n_inliers``, when the table has it.
    scan_ids : (M,) int64 ndarray or None
        ``scan_id``, when the table has it.

    Raises
    ------
    KeyError
        When a coordinate column is missing.
    """
    missing = [c for c in ("x0", "y0", "x1", "y1") if c not in segments.columns]
    if missing:
        raise KeyError(f"wall segments lack columns {missing}; expected x0, y0, x1, y1")
    segments = in_scan_order(segments)
    seg = segments[["x0", "y0", "x1", "y1"]].to_numpy(dtype=np.float64)
    finite = np.isfinite(seg).all(axis=1)
    if not finite.all():
        log.warning("dropping %d wall segments with non-finite coordinates", int((~finite).sum()))

    def column(name, dtype):
        return segments[name].to_numpy(dtype=dtype)[finite] if name in segments.columns else None

    return seg[finite], column("n_inliers", np.float64), column("scan_id", np.int64)


def in_scan_order(segments: pd.DataFrame) -> pd.DataFrame:
    """``segments`` stably sorted by ``scan_id``.

    Parameters
    ----------
    segments : pandas.DataFrame

    Returns
    -------
    pandas.DataFrame
        ``segments`` itself without a ``scan_id`` column or when already sorted; else a
        reordered copy (index kept).
    """
    if "scan_id" not in segments.columns or segments["scan_id"].is_monotonic_increasing:
        return segments
    return segments.iloc[np.argsort(segments["scan_id"].to_numpy(), kind="stable")]


def plan_faces(
    seg: np.ndarray, weights: np.ndarray | None = None, params: FloorplanParams = FloorplanParams(),
    first_groups: np.ndarray | None = None, min_length_m: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The wall faces of a floor plan: the segments merged (:func:`merge_segments`),
    faces shorter than ``min_length_m`` dropped (:func:`build_floorplan`'s faces).

    Parameters
    ----------
    seg : (M, 4) float ndarray
        Finite segments ``x0, y0, x1, y1``, metres, in scan order.
    weights : (M,) float ndarray, optional
        Merge weights (inlier counts); a weight that is not positive, or no weights,
        is replaced by the segment's length.
    params : FloorplanParams
    first_groups : (M,) int64 ndarray, optional
        The merge's first pass, prepared (:class:`~floorscan.floorplan.merge.FirstMergePass`).
    min_length_m : float, optional
        Metres; None: ``params.min_length_m``. The structure passes take every face and
        drop the short ones where they meet the walls
        (:func:`~floorscan.floorplan.structure.long_enough`).

    Returns
    -------
    faces : (F, 4) float64 ndarray
        Metres.
    face_weights : (F,) float64 ndarray
    n_segments : (F,) int64 ndarray
        Segments merged into each face.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    w = length if weights is None else np.asarray(weights, dtype=np.float64)
    w = np.where(w > 0, w, np.maximum(length, 1e-6))
    faces, face_w, labels = merge_segments(seg, w, params, first_groups)
    n_seg = np.bincount(labels, minlength=len(faces))
    flen = np.hypot(faces[:, 2] - faces[:, 0], faces[:, 3] - faces[:, 1]) if len(faces) else np.empty(0)
    keep = flen >= (params.min_length_m if min_length_m is None else min_length_m)
    return faces[keep].reshape(-1, 4), face_w[keep], n_seg[keep]


def build_floorplan(
    segments: pd.DataFrame, params: FloorplanParams = FloorplanParams(), grid: OccupancyGrid | None = None
) -> FloorPlan:
    """The floor plan of wall segments from many scans: merged faces, paired walls.

    Parameters
    ----------
    segments : pandas.DataFrame
        ``x0, y0, x1, y1`` (metres) and optionally ``n_inliers`` (merge weights;
        else the segment lengths are the weights), e.g. a
        ``walls/{ordering}/{extractor}/k{k}.parquet`` table. With a ``scan_id``
        column the segments are taken in scan order (a stable sort), so the plan
        depends on which scans gave them, not on the order an ordering ranked
        the scans (every ordering's ``k = all`` gives the same plan).
    params : FloorplanParams
    grid : OccupancyGrid, optional
        The free space of the segments' scans. With it, the merged faces go through
        the structure passes (:func:`floorscan.floorplan.structure.structure_passes`:
        clutter out, collinear faces joined across gaps the free space does not pass
        through, junctions), a one-faced wall's axis lies half its thickness behind
        its face (away from the free space), the wall axes are snapped into
        junctions (:attr:`FloorPlan.junctions`), the stubs beyond the openings at the
        walls' free ends are walls (:mod:`floorscan.floorplan.door_frames`), and the
        free space is cut into rooms at its doors (:func:`~floorscan.floorplan.rooms.plan_rooms`);
        a wall that bounds no room, tied to none that does, is clutter
        (:func:`floorscan.floorplan.lone_walls.apart_from_the_rooms`); each door is cut
        back to the part of its line the free space crosses, its stubs walls too.

    Returns
    -------
    FloorPlan

    Raises
    ------
    KeyError
        When a coordinate column is missing.
    """
    seg, w, _ = segment_arrays(segments)
    return plan_of_segments(seg, w, params, grid)


def plan_of_segments(
    seg: np.ndarray, weights: np.ndarray | None = None, params: FloorplanParams = FloorplanParams(),
    grid: OccupancyGrid | None = None, first_groups: np.ndarray | None = None, with_rooms: bool = True,
) -> FloorPlan:
    """:func:`build_floorplan` of segment arrays (:func:`segment_arrays`' output): the
    faces of :func:`plan_faces`, paired into walls, with the structure passes when a
    grid is given.

    Parameters
    ----------
    seg : (M, 4) float ndarray
        Finite segments ``x0, y0, x1, y1``, metres, in scan order.
    weights : (M,) float ndarray, optional
        Merge weights (inlier counts), as :func:`plan_faces`.
    params : FloorplanParams
    grid : OccupancyGrid, optional
        The free space of the segments' scans (:func:`build_floorplan`).
    first_groups : (M,) int64 ndarray, optional
        The merge's first pass, prepared (:class:`~floorscan.floorplan.merge.FirstMergePass`):
        the same plan, sooner.
    with_rooms : bool
        Whether to segment the rooms (with a grid); without, the plan's rooms and doors
        tables are empty and its walls, faces and clutter the same but for the walls
        that bound no room and are tied to none that does
        (:func:`~floorscan.floorplan.lone_walls.apart_from_the_rooms`), which stay
        walls: for a plan scored on its walls alone.

    Returns
    -------
    FloorPlan
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    # with a grid, the structure passes drop the short faces (step 0, where they meet the walls)
    faces, face_w, n_seg = plan_faces(seg, weights, params, first_groups, None if grid is None else 0.0)
    clutter = _empty(CLUTTER_COLUMNS)
    under = None
    if grid is not None:
        from floorscan.floorplan.structure import structure_passes

        n_before = len(faces)
        faces, face_w, side, cl, reason, under = structure_passes(
            faces, face_w, grid, params.structure, params.pair_max_m, params.rooms.door_max_m, params.rooms.door_min_m,
            params.min_length_m,
        )
        n_seg = np.ones(len(faces), dtype=np.int64)
        clutter = _clutter_rows(cl, 0, reason.astype(str))
        log.info("structure passes: %d faces -> %d wall faces, %d clutter", n_before, len(faces), len(cl))
    flen = np.hypot(faces[:, 2] - faces[:, 0], faces[:, 3] - faces[:, 1])
    axes, thick, wall_of_face = pair_faces(faces, face_w, params, grid)
    junctions = _empty(JUNCTION_COLUMNS)
    if grid is not None:
        axes, thick, wall_of_face = _one_wall_per_wall(axes, thick, wall_of_face, params)
        axes, junctions = _wall_junctions(axes, thick, wall_of_face, side, params)
        # a wall whose snapped axis is short and not between two junctions is clutter,
        # unless it is the pier between two doors or between a wall and a door (the wall
        # passes can shorten a wall again: up to three rounds)
        from floorscan.floorplan.free_space import open_run
        from floorscan.floorplan.wall_pieces import loose_walls

        run = open_run(grid)
        door_widths = (params.rooms.door_min_m, params.rooms.door_max_m)
        for _ in range(3):
            junc = np.column_stack([junctions[["x", "y", "wall_a", "wall_b"]].to_numpy(np.float64), np.zeros(len(junctions))])
            loose = loose_walls(axes, faces, wall_of_face, junc, grid, params.structure, *door_widths, run)
            if not loose.any():
                break
            drop = loose[wall_of_face]
            clutter = pd.concat([clutter, _clutter_rows(faces[drop], len(clutter), "short")], ignore_index=True)
            faces, face_w, n_seg, side = faces[~drop], face_w[~drop], n_seg[~drop], side[~drop]
            flen = flen[~drop]
            axes, thick, wall_of_face = pair_faces(faces, face_w, params, grid)
            axes, thick, wall_of_face = _one_wall_per_wall(axes, thick, wall_of_face, params)
            axes, junctions = _wall_junctions(axes, thick, wall_of_face, side, params)
    rooms, doors = _empty(ROOM_COLUMNS), _empty(DOOR_COLUMNS)
    if grid is not None and len(axes) and with_rooms:
        from floorscan.floorplan.jambs import loose_furniture
        from floorscan.floorplan.lone_walls import apart_from_the_rooms
        from floorscan.floorplan.rooms import rooms_and_walls

        # an opening at a wall's free end (an entrance; a door the rooms have not cut yet): the stub beyond is a wall
        axes, thick, faces, wall_of_face, face_w, n_seg, flen, junctions, _ = _framed(
            axes, thick, faces, wall_of_face, face_w, n_seg, flen, junctions, None, grid, params)
        rooms, doors, lone = rooms_and_walls(axes, thick, grid, params.rooms, under, loose_furniture(clutter))
        on = doors["wall_id"].to_numpy(np.int64)
        lone[on[on >= 0]] = False  # never a door's wall
        lone = apart_from_the_rooms(lone, axes, thick, junctions[["wall_a", "wall_b"]].to_numpy(np.int64), params.rooms)
        if lone.any():  # a facade across the street, a stub alone in an unseen block
            drop = lone[wall_of_face]
            clutter = pd.concat([clutter, _clutter_rows(faces[drop], len(clutter), "bounds_no_room")],
                                ignore_index=True)
            faces, face_w, n_seg, flen = faces[~drop], face_w[~drop], n_seg[~drop], flen[~drop]
            new_id = np.cumsum(~lone) - 1
            wall_of_face, axes, thick = new_id[wall_of_face[~drop]], axes[~lone], thick[~lone]
            ends = junctions[["wall_a", "wall_b"]].to_numpy(np.int64)
            junctions = junctions[~lone[ends].any(axis=1)].reset_index(drop=True)
            junctions[["wall_a", "wall_b"]] = new_id[ends[~lone[ends].any(axis=1)]].astype(np.int32)
            doors["wall_id"] = np.where(on >= 0, new_id[np.maximum(on, 0)], -1).astype(np.int32)
        if len(doors):  # each door cut back to its free run; the stubs that frame it are walls
            axes, thick, faces, wall_of_face, face_w, n_seg, flen, junctions, doors = _framed(
                axes, thick, faces, wall_of_face, face_w, n_seg, flen, junctions, doors, grid, params)
    nw = len(axes)
    faces_df = pd.DataFrame(
        {
            "face_id": np.arange(len(faces), dtype=np.int32),
            "wall_id": wall_of_face.astype(np.int32),
            "x0": faces[:, 0], "y0": faces[:, 1], "x1": faces[:, 2], "y1": faces[:, 3],
            "length_m": flen,
            "n_segments": n_seg.astype(np.int32),
            "n_inliers": np.round(face_w).astype(np.int64),
        }  # fmt: skip
    )
    walls = pd.DataFrame(
        {
            "wall_id": np.arange(nw, dtype=np.int32),
            "x0": axes[:, 0], "y0": axes[:, 1], "x1": axes[:, 2], "y1": axes[:, 3],
            "length_m": np.hypot(axes[:, 2] - axes[:, 0], axes[:, 3] - axes[:, 1]),
            "thickness_m": thick,
            "height_m": np.full(nw, params.wall_height_m),
            "paired": np.bincount(wall_of_face, minlength=nw) == 2,
            "n_faces": np.bincount(wall_of_face, minlength=nw).astype(np.int32),
            "n_segments": np.bincount(wall_of_face, weights=n_seg, minlength=nw).astype(np.int32),
            "n_inliers": np.round(np.bincount(wall_of_face, weights=face_w, minlength=nw)).astype(np.int64),
        }  # fmt: skip
    )
    log.info(
        "%d segments -> %d faces -> %d walls (%d with both faces)",
        len(seg), len(faces), nw, int(walls["paired"].sum()),
    )
    return FloorPlan(
        walls=walls[WALL_COLUMNS], faces=faces_df[FACE_COLUMNS], clutter=clutter, junctions=junctions,
        rooms=rooms[ROOM_COLUMNS], doors=doors[DOOR_COLUMNS],
    )


def _framed(axes, thick, faces, wall_of_face, face_w, n_seg, flen, junctions, doors, grid, params: FloorplanParams):
    """The plan's arrays and tables with its doors cut back to the free runs of their lines, the walls of their
    lines gone on to their jambs across a crossing (the kinds of their junctions read again), and the stubs that
    frame them added as walls, each with its two faces (no segment of their own) and its junction with the wall it
    meets (:func:`~floorscan.floorplan.door_frames.framed_doors`). With ``doors`` None (before the rooms), the same
    for the openings at the walls' free ends (:func:`~floorscan.floorplan.door_frames.framed_openings`)."""
    from floorscan.floorplan.door_frames import framed_doors, framed_openings
    from floorscan.floorplan.junctions import line_crossings

    before = axes
    if doors is None:
        axes, stubs, stub_t, meets = framed_openings(axes, thick, grid, params.rooms,
                                                     params.structure.min_wall_length_m)
    else:
        xy = doors[["x0", "y0", "x1", "y1"]].to_numpy(np.float64)
        xy, axes, stubs, stub_t, meets = framed_doors(xy, doors["wall_id"].to_numpy(np.int64), axes, thick, grid,
                                                      params.rooms, params.structure.min_wall_length_m)
        doors = doors.copy()
        doors[["x0", "y0", "x1", "y1"]] = xy
        doors["width_m"] = np.hypot(xy[:, 2] - xy[:, 0], xy[:, 3] - xy[:, 1])
    if not len(stubs) and not (before != axes).any():
        return axes, thick, faces, wall_of_face, face_w, n_seg, flen, junctions, doors
    ids = np.arange(len(axes), len(axes) + len(stubs))
    d = stubs[:, 2:] - stubs[:, :2]
    length = np.hypot(d[:, 0], d[:, 1])
    nrm = np.column_stack([-d[:, 1], d[:, 0]]) / np.maximum(length, 1e-12)[:, None] * (stub_t / 2)[:, None]
    axes, thick = np.vstack([axes, stubs]), np.r_[thick, stub_t]
    if len(stubs):
        at = line_crossings(stubs, axes[meets])  # its first end, or the crossing of a wall from jamb to jamb
        met = pd.DataFrame({"x": at[:, 0], "y": at[:, 1], "kind": "T", "wall_a": meets.astype(np.int32),
                            "wall_b": ids.astype(np.int32)})  # fmt: skip
        junctions = pd.concat([junctions, met], ignore_index=True)
    # the junctions of the walls gone on (a crossing now passed) and of the stubs: L, T or X
    changed = np.r_[np.flatnonzero((before != axes[: len(before)]).any(axis=1)), ids]
    rows = np.flatnonzero(junctions[["wall_a", "wall_b"]].isin(changed).any(axis=1).to_numpy())
    junctions = junctions.copy()
    junctions.loc[rows, "kind"] = _junction_kinds(junctions.iloc[rows], axes, thick, grid.resolution_m)
    sides = np.concatenate([stubs + np.c_[nrm, nrm], stubs - np.c_[nrm, nrm]])
    return (axes, thick, np.vstack([faces, sides]), np.r_[wall_of_face, ids, ids],
            np.r_[face_w, np.zeros(2 * len(stubs))], np.r_[n_seg, np.zeros(2 * len(stubs), dtype=n_seg.dtype)],
            np.r_[flen, length, length], junctions, doors)


def _junction_kinds(junctions: pd.DataFrame, axes: np.ndarray, thick: np.ndarray, resolution_m: float) -> np.ndarray:
    """Each junction's kind from how many of its two walls end at it (within half the
    thicker and a cell): both ``L``, one ``T``, none ``X``."""
    at = junctions[["x", "y"]].to_numpy(np.float64)
    pair = junctions[["wall_a", "wall_b"]].to_numpy(np.int64)
    ends = axes[pair].reshape(len(pair), 2, 2, 2)  # junction, wall, end, xy
    ending = (np.hypot(*(ends - at[:, None, None, :]).transpose(3, 0, 1, 2)).min(axis=2)
              <= (thick[pair].max(axis=1) / 2 + resolution_m)[:, None]).sum(axis=1)
    return np.array(["X", "T", "L"], dtype=object)[ending].astype(str)


def _clutter_rows(faces: np.ndarray, first_id: int, reason: str) -> pd.DataFrame:
    """Rows of :attr:`FloorPlan.clutter` for ``faces`` ((F, 4) metres), numbered from
    ``first_id``, all for ``reason``."""
    return pd.DataFrame(
        {
            "clutter_id": np.arange(first_id, first_id + len(faces), dtype=np.int32),
            "x0": faces[:, 0], "y0": faces[:, 1], "x1": faces[:, 2], "y1": faces[:, 3],
            "length_m": np.hypot(faces[:, 2] - faces[:, 0], faces[:, 3] - faces[:, 1]),
            "reason": reason,
        }  # fmt: skip
    )


def _one_wall_per_wall(axes, thick, wall_of_face, params: FloorplanParams):
    """Near-parallel duplicate walls merged
    (:func:`floorscan.floorplan.structure.merge_parallel_duplicates`, within the
    thickest wall ``pair_max_m``); the faces follow their walls."""
    from floorscan.floorplan.junctions import merge_parallel_duplicates

    axes, thick, group = merge_parallel_duplicates(axes, thick, params.structure, params.pair_max_m)
    return axes, thick, group[wall_of_face]


def _wall_junctions(axes, thick, wall_of_face, side, params: FloorplanParams):
    """Wall axes of a plan with structure: a one-faced wall's axis moved half its
    thickness behind its face (away from the free side), then the axes snapped into
    junctions (:func:`floorscan.floorplan.structure.snap_junctions`, the tolerance
    ``snap_m`` plus the thickest wall). Returns the axes and the junction table."""
    from dataclasses import replace

    from floorscan.floorplan.junctions import snap_junctions

    axes = axes.copy()
    thick = thick.copy()
    n_faces = np.bincount(wall_of_face, minlength=len(axes))
    for f, wall in enumerate(wall_of_face.tolist()):
        if n_faces[wall] == 1 and side[f] != 0:
            d = axes[wall, 2:] - axes[wall, :2]
            n = np.array([-d[1], d[0]]) / max(float(np.hypot(*d)), 1e-12)
            shift = -float(side[f]) * 0.5 * thick[wall] * n  # away from the free side
            axes[wall] += np.r_[shift, shift]
    # the thickest wall widens the tolerance, up to ``pair_max_m``: a map's thicker walls
    # (:data:`~floorscan.floorplan.pairing.THICK_WALL_MAX_M`) do not move every other
    # junction of the plan
    thickest = min(float(thick.max()), params.pair_max_m) if len(thick) else 0.0
    tol = replace(params.structure, snap_m=params.structure.snap_m + thickest)
    axes, junc = snap_junctions(axes, tol, trim_shallow=True)
    kinds = np.array(["", "L", "T", "X"], dtype=object)
    junctions = pd.DataFrame(
        {
            "x": junc[:, 0], "y": junc[:, 1], "kind": kinds[junc[:, 4].astype(np.int64)].astype(str),
            "wall_a": junc[:, 2].astype(np.int32), "wall_b": junc[:, 3].astype(np.int32),
        }  # fmt: skip
    )
    return axes, junctions

"""Faces in the line of a wall (the structure passes' step 4,
:mod:`floorscan.floorplan.structure`): the faces that would be clutter (on an object,
or shorter than the shortest wall) but stand in the line of a wall face, a door's
width or less beyond its end, are pieces of that wall (:func:`in_wall_lines`), a
door's jambs (:func:`door_jambs`), the pier between two doors (:func:`piers`) or between
a wall and a door (:func:`corner_piers`). A door is an opening in a wall, and the wall
goes on across it: its jambs stand in one line.
"""

from __future__ import annotations

import numpy as np

from floorscan.core.occupancy import OccupancyGrid
from floorscan.floorplan.candidates import candidate_pairs
from floorscan.floorplan.free_space import StructureParams, open_run
from floorscan.floorplan.junctions import ends_on_line, junction_ends, short_loose


def in_wall_lines(seg: np.ndarray, standing: np.ndarray, cell_m: float, params: StructureParams = StructureParams(),
                  door_max_m: float = 2.0) -> np.ndarray:  # fmt: skip
    """Which faces on objects (:func:`~floorscan.floorplan.clutter.on_objects`) are
    pieces of a wall: longer than ``min_wall_length_m`` by a cell and in the line of a
    face on no object (directions within ``duplicate_angle_deg``, both ends within
    ``side_offset_m`` of its line), beyond its end by at most a door's width
    (``door_max_m``; from a cell short of the end: not alongside it, where it would only
    repeat that face). A partition's piece between two doors with a cabinet against it
    is one object with the cabinet (its inscribed disc the cabinet's); the wall it
    continues is what tells it from furniture, as a door's jambs stand in one line. The
    cell: a face traced on a raster is up to a cell shorter or longer as the raster
    turns, and a jamb as long as the shortest wall would be a wall at one pose and
    furniture at another (the rigid-motion property of the tests).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    standing : (F,) bool ndarray
        Which faces lie on objects.
    cell_m : float
        The grid's cell, metres.
    params : StructureParams
    door_max_m : float
        The widest door, metres (``floorplan.rooms.door_max_m``).

    Returns
    -------
    (F,) bool ndarray
        The faces of ``standing`` that are pieces of a wall.
    """
    return _in_line_of_others(seg, standing, params.min_wall_length_m + cell_m, -cell_m, door_max_m, params)


def piers(seg: np.ndarray, standing: np.ndarray, grid: OccupancyGrid, params: StructureParams = StructureParams(),
          door_min_m: float = 0.6, door_max_m: float = 2.0, junctions: np.ndarray | None = None,
          open_run=None) -> np.ndarray:  # fmt: skip
    """Which faces on objects, however short, are the pier between two doors: in the
    line of a wall face beyond each of their two ends (directions within
    ``duplicate_angle_deg``, both ends within ``side_offset_m`` of its line),
    ``door_min_m`` to ``door_max_m`` from it, across a gap the free space passes
    through (a run of passable cells ``min_opening_m`` long on the line between the two
    ends, the joins' opening test): two doors. A wall with two doors in it stands in
    one line across both; the piece between them, surrounded by the free space the
    doors let through, is the wall's, not a chair's. A piece with an end at one of
    ``junctions`` is no pier: it is the end face of a wall that stops at the line,
    across the wall's thickness.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    standing : (F,) bool ndarray
        Which faces lie on objects (or are too short for a wall).
    grid : OccupancyGrid
        The free space of the plan's scans.
    params : StructureParams
    door_min_m, door_max_m : float
        The narrowest and widest door, metres (``floorplan.rooms``).
    junctions : (J, 5) float ndarray, optional
        ``x, y, i, j, kind`` (:func:`~floorscan.floorplan.junctions.snap_junctions`), metres.
    open_run : callable, optional
        :func:`~floorscan.floorplan.free_space.open_run` of ``grid``, when the caller has it.

    Returns
    -------
    (F,) bool ndarray
        The faces of ``standing`` that are piers.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    i, j = _line_pairs(seg, np.asarray(standing, dtype=bool), 0.0, door_min_m, door_max_m, params)
    out = np.zeros(len(seg), dtype=bool)
    if len(i) == 0:
        return out
    opening = _passable_gaps(seg, i, j, grid, params, open_run)
    i, j = i[opening], j[opening]
    # which end of face i face j lies beyond: along i's own direction
    d = seg[i, 2:] - seg[i, :2]
    ahead = np.einsum("ij,ij->i", (seg[j, :2] + seg[j, 2:] - seg[i, :2] - seg[i, 2:]) / 2, d) > 0
    both = np.zeros((len(seg), 2), dtype=bool)
    both[i[ahead], 0] = True
    both[i[~ahead], 1] = True
    out = both.all(axis=1)
    return out if junctions is None else out & ~junction_ends(seg, junctions).any(axis=1)


def corner_piers(seg: np.ndarray, standing: np.ndarray, junctions: np.ndarray, grid: OccupancyGrid,
                 params: StructureParams = StructureParams(), door_min_m: float = 0.6, door_max_m: float = 2.0,
                 not_walls: np.ndarray | None = None, open_run=None) -> np.ndarray:  # fmt: skip
    """Which faces on objects, however short, are the pier between a wall they meet and
    a door: an end at a junction with a face not in ``standing`` (a wall: not another
    piece, as at the corner of an object), and in their line, beyond their other end,
    ``door_min_m`` to ``door_max_m`` off across a gap the free space passes (as in
    :func:`piers`), a wall face or another such pier (the two stubs of a partition with
    its door between them). Traced on a map, a stub shorter than the shortest wall is cut
    from the wall it stands on (:func:`~floorscan.floorplan.clutter.free_standing_objects`
    cuts the long walls out) and stands free; the wall it meets and the door in its line
    tell it from a chair.

    Parameters
    ----------
    seg, standing, junctions, grid, params, door_min_m, door_max_m, open_run
        As :func:`piers` (``junctions`` here required).
    not_walls : (F,) bool ndarray, optional
        Faces that are clutter for another reason (objects, fronts of furniture): no wall
        a pier meets or stands in line with.

    Returns
    -------
    (F,) bool ndarray
        The faces of ``standing`` that are such piers.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    standing = np.asarray(standing, dtype=bool)
    walls = ~standing if not_walls is None else ~standing & ~np.asarray(not_walls, dtype=bool)
    junctions = np.asarray(junctions, dtype=np.float64).reshape(-1, 5)
    pair = junctions[:, 2:4].astype(np.int64)
    with_wall = walls[pair[:, 0]] | walls[pair[:, 1]]  # the junctions a wall is in
    stub = standing & junction_ends(seg, junctions[with_wall]).any(axis=1)
    i, j = _line_pairs(seg, stub, 0.0, door_min_m, door_max_m, params, others=walls | stub)
    out = np.zeros(len(seg), dtype=bool)
    if len(i):
        out[i[_passable_gaps(seg, i, j, grid, params, open_run)]] = True
    return out


def door_jambs(seg: np.ndarray, short: np.ndarray, params: StructureParams = StructureParams(), door_min_m: float = 0.6,
               door_max_m: float = 2.0, not_walls: np.ndarray | None = None) -> np.ndarray:  # fmt: skip
    """Which short faces (step 4's, shorter than ``min_wall_length_m`` without a junction
    at both ends) are a door's jamb: in the line of a wall face (neither short nor in
    ``not_walls``; directions within ``duplicate_angle_deg``, both ends within
    ``side_offset_m`` of its line), ``door_min_m`` to ``door_max_m`` beyond its end. The
    pier between a room's corner and its door is a wall however short: a door is an
    opening in a wall, and the wall goes on across it. Measured on a raster, a pier as
    long as the shortest wall is up to a cell shorter or longer as the raster turns, so
    without this a pier of that length is a wall at one pose and clutter at another (the
    rigid-motion property of the tests); a furniture face beside a wall has no wall in
    its line a door's width away.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    short : (F,) bool ndarray
        Which faces are short.
    params : StructureParams
    door_min_m, door_max_m : float
        The narrowest and widest door, metres (``floorplan.rooms``).
    not_walls : (F,) bool ndarray, optional
        Faces that are clutter for another reason (on objects, fronts of furniture): no
        jamb's wall.

    Returns
    -------
    (F,) bool ndarray
        The faces of ``short`` that are jambs.
    """
    short = np.asarray(short, dtype=bool)
    which = short if not_walls is None else short | np.asarray(not_walls, dtype=bool)
    return _in_line_of_others(seg, which, 0.0, door_min_m, door_max_m, params) & short


def _in_line_of_others(seg: np.ndarray, which: np.ndarray, min_length_m: float, gap_min_m: float, gap_max_m: float,
                       params: StructureParams) -> np.ndarray:  # fmt: skip
    """The faces of ``which`` at least ``min_length_m`` long in the line of a face not
    in ``which``, from ``gap_min_m`` (negative: overlapping it by up to that) to
    ``gap_max_m`` past its end, metres (:func:`in_wall_lines`, :func:`door_jambs`)."""
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    i, _ = _line_pairs(seg, np.asarray(which, dtype=bool), min_length_m, gap_min_m, gap_max_m, params)
    out = np.zeros(len(seg), dtype=bool)
    out[i] = True
    return out


def _line_pairs(seg: np.ndarray, which: np.ndarray, min_length_m: float, gap_min_m: float, gap_max_m: float,
                params: StructureParams, others: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """The pairs (i, j) of :func:`_in_line_of_others`: face i of ``which``, at least
    ``min_length_m`` long, in the line of face j not in ``which`` (or in ``others``, j
    not i), ``gap_min_m`` to ``gap_max_m`` past j's end."""
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    none = np.zeros(0, dtype=np.intp)
    others = ~which if others is None else np.asarray(others, dtype=bool)
    if not (which & (length >= min_length_m)).any() or not others.any():
        return none, none
    i, j = candidate_pairs(seg, gap_max_m, np.radians(params.duplicate_angle_deg))
    i, j = np.r_[i, j], np.r_[j, i]  # face i in which, face j in others
    ok = which[i] & others[j] & (i != j) & (length[i] >= min_length_m)
    i, j = i[ok], j[ok]
    if len(i) == 0:
        return none, none
    t, off = ends_on_line(seg, j, i)
    in_line = (np.abs(off) <= params.side_offset_m).all(axis=1)
    beyond = np.maximum(t.min(axis=1) - length[j], -t.max(axis=1))  # past face j's end; < 0 alongside it
    hit = in_line & (beyond >= gap_min_m) & (beyond <= gap_max_m)
    return i[hit], j[hit]


def _passable_gaps(seg: np.ndarray, i: np.ndarray, j: np.ndarray, grid: OccupancyGrid,
                   params: StructureParams, run=None) -> np.ndarray:  # fmt: skip
    """Whether the free space passes the gap between the facing ends of faces i and j
    (pairs, (P,) each): a run of passable cells ``min_opening_m`` long on the line
    between the two ends (``run``, :func:`~floorscan.floorplan.free_space.open_run` of
    ``grid`` by default: the joins' opening test)."""
    ends_i, ends_j = seg[i].reshape(-1, 2, 2), seg[j].reshape(-1, 2, 2)
    dist = np.linalg.norm(ends_i[:, :, None, :] - ends_j[:, None, :, :], axis=-1).reshape(-1, 4)
    k = dist.argmin(axis=1)
    rows = np.arange(len(i))
    p, q = ends_i[rows, k // 2], ends_j[rows, k % 2]
    width = dist[rows, k]
    run = open_run(grid) if run is None else run
    return np.array([run(p[g], (q[g] - p[g]) / max(width[g], 1e-12), 0.0, width[g]) >= params.min_opening_m
                     for g in range(len(i))], dtype=bool)  # fmt: skip


def loose_walls(axes: np.ndarray, faces: np.ndarray, wall_of_face: np.ndarray, junctions: np.ndarray,
                grid: OccupancyGrid, params: StructureParams = StructureParams(), door_min_m: float = 0.6,
                door_max_m: float = 2.0, open_run=None) -> np.ndarray:  # fmt: skip
    """Which walls of a paired plan are clutter: an axis shorter than
    ``min_wall_length_m`` not between two junctions
    (:func:`~floorscan.floorplan.junctions.short_loose`), unless it is a pier between
    two doors or between a wall and a door (:func:`piers`, :func:`corner_piers`) by its
    axis or by one of its faces. The faces too: the axis of a wall seen from both sides
    lies in its middle, that of a wall seen from one side half the default thickness
    behind its face, so a pier and the walls in its line, all of one face in the map,
    can have axes a wall's thickness apart, beyond ``side_offset_m``.

    Parameters
    ----------
    axes : (W, 4) float ndarray
        The walls' axes, metres.
    faces : (F, 4) float ndarray
        Their faces, metres.
    wall_of_face : (F,) int ndarray
        Each face's wall (a row of ``axes``).
    junctions : (J, 5) float ndarray
        ``x, y, wall_a, wall_b, kind`` of the axes' junctions, metres.
    grid, params, door_min_m, door_max_m, open_run
        As :func:`piers`.

    Returns
    -------
    (W,) bool ndarray
    """
    loose = short_loose(axes, junctions, params.min_wall_length_m)
    loose &= ~piers(axes, loose, grid, params, door_min_m, door_max_m, junctions, open_run)
    loose &= ~corner_piers(axes, loose, junctions, grid, params, door_min_m, door_max_m, open_run=open_run)
    if loose.any() and len(faces):
        wall_of_face = np.asarray(wall_of_face, dtype=np.intp)
        by_face = piers(faces, loose[wall_of_face], grid, params, door_min_m, door_max_m, None, open_run)
        loose[wall_of_face[by_face]] = False
    return loose

"""The walls that are no walls of the building (:func:`bounding_no_room`,
:func:`apart_from_the_rooms`): once the rooms are cut, a wall that bounds none of them
and that no chain of walls ties to one that does. The floor plan
(:mod:`floorscan.floorplan.plan`) puts them in the clutter layer (``bounds_no_room``).

A wall is the boundary between two rooms or between a room and the outside (issue 44's
layout: an edge between cells of two labels), and a building's walls hold each other
up (the wall graph is connected, as :mod:`floorscan.floorplan.structure` step 6 has
it). A facade across the street, seen through a window that the building's closed
outline (:mod:`floorscan.floorplan.outline`) holds shut, or a stub of wall seen alone
inside a block the rover never entered does neither. The far walls of a space the plan
makes no room of (a room seen only past an obstacle) are in line with the walls the
rover saw, or meet them: the building's.
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.free_space import segment_samples
from floorscan.floorplan.jambs import wall_line_index
from floorscan.floorplan.room_space import RoomParams, RoomRaster


#: A room's cells come within this many cells of the faces of the walls that bound it:
#: the space ends at the cells of the walls' footprints.
ROOM_REACH_CELLS = 2


def bounding_no_room(raster: RoomRaster, rooms: np.ndarray, axes: np.ndarray, thickness: np.ndarray) -> np.ndarray:
    """(N,) bool: the walls that bound no room: no cell of a room within half the
    wall's thickness and :data:`ROOM_REACH_CELLS` cells of its axis. All False when
    there is no room.

    Parameters
    ----------
    raster : RoomRaster
    rooms : (H, W) bool ndarray
        The rooms' cells on ``raster``.
    axes : (N, 4) float ndarray
        Wall axes, metres.
    thickness : (N,) float ndarray
        Metres.

    Returns
    -------
    (N,) bool ndarray
    """
    from scipy import ndimage

    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    out = np.zeros(len(axes), dtype=bool)
    if not rooms.any() or not len(axes):
        return out
    res = raster.resolution_m
    distance = ndimage.distance_transform_edt(~rooms) * res  # metres to the nearest room cell
    points, owner, _ = segment_samples(axes, res / 2)
    nearest = np.full(len(axes), np.inf)
    np.minimum.at(nearest, owner, raster.at(distance, points, outside=np.inf))
    return nearest > np.asarray(thickness, dtype=np.float64) / 2 + ROOM_REACH_CELLS * res


def apart_from_the_rooms(lone: np.ndarray, axes: np.ndarray, thickness: np.ndarray, pairs: np.ndarray,
                         params: RoomParams) -> np.ndarray:
    """(N,) bool: the walls of ``lone`` (:func:`bounding_no_room`) that no chain of walls
    ties to a wall that bounds a room: walls in one line
    (:func:`~floorscan.floorplan.jambs.wall_line_index`) or meeting in a junction
    (``pairs``, (K, 2) int wall ids) are tied. None when no wall bounds a room: the
    plan keeps its walls rather than lose them all.

    Parameters
    ----------
    lone : (N,) bool ndarray
    axes : (N, 4) float ndarray
        Wall axes, metres.
    thickness : (N,) float ndarray
        Metres.
    pairs : (K, 2) int ndarray
        Walls that meet (the plan's junctions).
    params : RoomParams
        ``line_offset_m``, ``door_angle_deg``.

    Returns
    -------
    (N,) bool ndarray
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    lone = np.asarray(lone, dtype=bool)
    n = len(lone)
    if not lone.any() or lone.all():
        return np.zeros(n, dtype=bool)
    line_of = wall_line_index(axes, thickness, params)
    lines = np.flatnonzero(line_of >= 0)
    a = np.r_[np.asarray(pairs, dtype=np.int64).reshape(-1, 2)[:, 0], lines]
    b = np.r_[np.asarray(pairs, dtype=np.int64).reshape(-1, 2)[:, 1], n + line_of[lines]]
    m = n + int(line_of.max()) + 1
    _, part = connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(m, m)), directed=False)
    tied = np.zeros(m, dtype=bool)
    tied[part[:n][~lone]] = True
    return lone & ~tied[part[:n]]

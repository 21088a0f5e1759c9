"""Two rooms parted by a desk row, not a wall (:func:`join_desk_rows`): one room.

A row of desks or a table across an office is, among the plan's walls, a piece of wall
or two in a line across the room, with an opening a door wide beside them, and the room
step takes it for a partition with a door (step 4 of :mod:`floorscan.floorplan.rooms`).
No single feature of such a door tells it from a door in a partition: not its width,
nor the walls at its jambs, nor how continuous its line is in the map, nor the shape of
the two rooms together (the door study in ``benchmarks/README.md``). Two features taken
together pick out some of them, and no door in a partition of the study:

- the walls at its jambs (whose footprints either end of the door touches, within
  :data:`JAMB_TOUCH_M`) are all shorter than the narrowest door (``door_min_m``), there
  is at least one, and none meets another wall at an end: pieces of a desk's or a
  table's edge standing in the room. A partition holds its door in a wall that runs on
  from one jamb at least, or in a stub tied to the building's walls (a door beside a
  corner); a door with no wall at its jambs tells nothing either way (the map extractor
  misses short pieces of a partition too);
- the two rooms together are no longer than :data:`ONE_ROOM_M` (the long side of the
  smallest rectangle about their cells): one office or meeting room cut in two, where
  a short stub beside a door between two larger rooms is a partition's corner.

The doors are read once, in order, each pair judged as the doors before it have joined
the rooms (rooms only grow, so a pair too long stays too long); the room step's other
rules are not revisited.

Luperto et al. (ROSE^2, RA-L 2022) weigh a partition between two cells by the wall
evidence along its whole length; along a desk's edge that evidence is as continuous as
along a wall, so here the length of the walls at the door and the size of what it parts
stand in for it.
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.doors import footprint_distance, junction_end, wall_units
from floorscan.floorplan.room_space import RoomParams, RoomRaster

#: Metres: the longest pair of rooms a desk row is taken to part, about one office or
#: meeting room. Chosen between the two groups of the door study in
#: ``benchmarks/README.md`` (seventieth session): the pairs parted by a desk or a table
#: with jamb walls as above are at most 8.1 m long together, the pairs a partition parts
#: at least 10.3 m.
ONE_ROOM_M = 9.0

#: Metres: how close a door's end comes to the footprint of the wall it ends at; its
#: ends are centres of the room raster's cells (0.1 m), so within one and a half cells.
JAMB_TOUCH_M = 0.15


def _long_side(raster: RoomRaster, mask: np.ndarray) -> float:
    """Metres: the long side of the smallest rotated rectangle about the centres of the
    cells of ``mask`` ((H, W) bool)."""
    import shapely

    rows, cols = np.nonzero(mask)
    if len(rows) < 3:
        return 0.0
    hull = shapely.convex_hull(shapely.multipoints(raster.centres(rows, cols)))
    if hull.geom_type != "Polygon":
        return float(hull.length)
    xy = np.asarray(shapely.minimum_rotated_rectangle(hull).exterior.coords)
    return float(np.hypot(*np.diff(xy, axis=0).T).max())


def _longest_jamb_wall(p: np.ndarray, q: np.ndarray, axes: np.ndarray, thickness: np.ndarray,
                       lengths: np.ndarray) -> float:
    """Metres: the longest wall whose footprint the door ``p``-``q`` ((2,) metres each)
    touches at either end (:data:`JAMB_TOUCH_M`); infinite when none does (the door's
    jambs are no walls the plan holds: it says nothing of them) or when one meets
    another wall at an end (:func:`~floorscan.floorplan.doors.junction_end`: a piece of
    a partition tied to the building's walls)."""
    if not len(axes):
        return np.inf
    near = (footprint_distance(p, axes, thickness) <= JAMB_TOUCH_M) | (footprint_distance(q, axes, thickness)
                                                                       <= JAMB_TOUCH_M)  # fmt: skip
    if any(junction_end(axes, thickness, int(i), k) for i in np.flatnonzero(near) for k in (0, 1)):
        return np.inf  # a jamb wall meets another wall: a partition's piece
    return float(lengths[near].max()) if near.any() else np.inf


def join_desk_rows(doors: list, labels: np.ndarray, sets, axes: np.ndarray, thickness: np.ndarray,
                   raster: RoomRaster, params: RoomParams) -> None:
    """Join the rooms a desk row parts (module docstring).

    Parameters
    ----------
    doors : list of (p, q, wall, a, b)
        The room step's doors: ends ``p``, ``q`` ((2,) metres), the wall (a row of
        ``axes``), the regions ``a``, ``b`` of ``labels`` it joins.
    labels : (H, W) int ndarray
        Regions 1..n, 0 no space.
    sets : scipy.cluster.hierarchy.DisjointSet
        The rooms as sets of regions; joined in place.
    axes, thickness : (N, 4) and (N,) float ndarray
        Wall axes ``x0, y0, x1, y1`` and thickness, metres.
    raster : RoomRaster
    params : RoomParams
        ``door_min_m``.
    """
    lengths = wall_units(axes)[1] if len(axes) else np.zeros(0)
    for p, q, _, a, b in doors:
        # rooms only grow as they join, so a pair too long now stays too long: one pass
        if (not sets.connected(a, b) and _longest_jamb_wall(p, q, axes, thickness, lengths) < params.door_min_m
                and _long_side(raster, np.isin(labels, list(sets.subset(a) | sets.subset(b)))) <= ONE_ROOM_M):
            sets.merge(a, b)

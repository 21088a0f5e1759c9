"""A corridor narrowed at a passage stays one corridor (step 4 of the rooms,
:mod:`floorscan.floorplan.rooms`): two rooms that are both corridors and meet through a
narrowing, at least :data:`~floorscan.floorplan.persistence.DOOR_SHARE` of the narrower
one's width, are one room (:func:`corridor_narrowings`).

The persistence test (:mod:`floorscan.floorplan.persistence`) weighs a passage against
the widest place of the basin on each side, and a corridor's basin reaches into the
junction, hall or alcove beside it: where the corridor narrows at a jamb, a column or
a step of its side, the passage is under three quarters of that and becomes a door.
:func:`~floorscan.floorplan.corridors.across_corridor` measures such a passage against
the corridor's own width where two straight, parallel lines of wall bound it; a
corridor whose sides bend or step has no such lines. Here the width is each room's
own, its median local thickness, and a room is a corridor by the test of step 5
(:func:`~floorscan.floorplan.room_tables.long_for_width`: at least
``corridor_elongation`` times as long as wide, the more so where wider than
``corridor_max_width_m``), its width measured on the raster (:func:`raster_width`). A passage between two such rooms at
least three quarters of the narrower one's width narrows the corridor by less than a
quarter, as a jamb or a column does: no door, and the corridor is one room, as people
draw a network of corridors (Bormann et al., "Room segmentation: survey,
implementation, and analysis", ICRA 2016: lab_a, NLB, lab_intel).

The passages weighed are the narrowings, the contacts between jambs that lie in no
wall's line (:func:`~floorscan.floorplan.doors.contact_door` finds none; the plan's door
there is a :func:`~floorscan.floorplan.doors.free_door`): a door in a wall's line across
a corridor, a fire door in its frame, is an opening in a wall and parts the corridor,
as people draw it. A door into a room that is no corridor (an office, a hall) and a door
narrowing a corridor by more than a quarter are untouched.
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.persistence import DOOR_SHARE
from floorscan.floorplan.room_space import RoomParams, disc_opening
from floorscan.floorplan.room_tables import long_for_width


def raster_width(mask: np.ndarray, resolution_m: float) -> float:
    """The median local thickness of a region of cells: the diameter of the largest disc
    whose opening of the region (:func:`~floorscan.floorplan.room_space.disc_opening`)
    keeps half its cells, the measure :func:`~floorscan.floorplan.room_tables.room_width`
    takes of a polygon, to a quarter of a cell in radius.

    Parameters
    ----------
    mask : (H, W) bool ndarray
        The region.
    resolution_m : float
        Metres per cell.

    Returns
    -------
    float
        Metres; 0 for an empty region.
    """
    from scipy import ndimage

    area = int(np.count_nonzero(mask))
    if not area:
        return 0.0
    lo, hi = 0.0, float(ndimage.distance_transform_edt(np.pad(mask, 1)).max())  # the largest inscribed disc
    while hi - lo > 0.25:
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if 2 * int(np.count_nonzero(disc_opening(mask, mid))) >= area else (lo, mid)
    return 2.0 * lo * resolution_m


def corridor_narrowings(labels: np.ndarray, root: np.ndarray, narrowings: dict, params: RoomParams) -> np.ndarray:
    """The rooms joined across the narrowings of a corridor (module docstring).

    Parameters
    ----------
    labels : (H, W) int ndarray
        The regions, 0 outside the space.
    root : (R + 1,) int ndarray
        Each region's room (:func:`~floorscan.floorplan.persistence.persistent_rooms`).
    narrowings : dict
        ``{(a, b): width}``: the widest contact between regions ``a`` and ``b`` that is
        a narrowing between jambs, ``door_min_m`` to ``door_max_m`` wide and in no
        wall's line, metres.
    params : RoomParams
        ``resolution_m``, ``corridor_elongation``, ``corridor_min_length_m``,
        ``corridor_max_width_m``.

    Returns
    -------
    (R + 1,) int64 ndarray
        Each region's room: ``root``, with the rooms of a corridor joined across its
        narrowings.
    """
    from scipy import ndimage
    from scipy.cluster.hierarchy import DisjointSet

    root = np.asarray(root, dtype=np.int64)
    widest: dict[tuple[int, int], float] = {}  # between two rooms, metres
    for (a, b), w in narrowings.items():
        if root[a] != root[b]:
            key = (int(min(root[a], root[b])), int(max(root[a], root[b])))
            widest[key] = max(widest.get(key, 0.0), float(w))
    if not widest:
        return root
    rooms = root[labels]
    boxes = ndimage.find_objects(rooms)
    r = params.resolution_m
    widths: dict[int, float] = {}  # a corridor's width, metres; 0 for a room that is none

    def corridor_width(k: int) -> float:
        if k not in widths:
            mask = rooms[boxes[k - 1]] == k
            w = raster_width(mask, r)
            widths[k] = w if long_for_width(np.count_nonzero(mask) * r * r, w, params) else 0.0
        return widths[k]

    sets = DisjointSet(range(len(root)))
    for a, b in sorted(widest):
        narrower = min(corridor_width(a), corridor_width(b))
        if narrower > 0 and widest[(a, b)] >= DOOR_SHARE * narrower:
            sets.merge(a, b)
    return np.array([sets[int(k)] for k in root], dtype=np.int64)

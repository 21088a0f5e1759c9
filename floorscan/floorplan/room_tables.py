"""The rooms and doors tables of a plan (:attr:`floorscan.floorplan.plan.FloorPlan.rooms`,
``doors``) from room polygons and door openings: each room's kind and name.
"""

from __future__ import annotations

import logging

import numpy as np
import pandas as pd

from floorscan.floorplan.room_space import RoomParams

log = logging.getLogger("floorscan.floorplan.rooms")


def room_tables(
    polys: list, doors: list, resolution_m: float, params: RoomParams, divided: bool = False
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The rooms and doors tables of room polygons and door openings: each room's kind
    (a ``corridor`` when long for its width: the width the diameter of the largest
    circle inside it, its length the area over that width; ``space`` for every room
    when no door and no room's open side divides the space) and name (``Room 1``,
    ``Corridor 1``, ``Space 1`` in the order given).

    Parameters
    ----------
    polys : list of shapely.Polygon
        The rooms, map metres, in reading order.
    doors : list of (p, q, wall, room_a, room_b)
        The openings ((2,) metres) in wall ``wall``, between rooms ``room_a < room_b``
        (indices into ``polys``).
    resolution_m : float
        The tolerance of the largest inscribed circle is half of it, metres.
    params : RoomParams
    divided : bool
        Whether a room's open side (:mod:`floorscan.floorplan.mouths`) divides two
        rooms, when no door does.

    Returns
    -------
    rooms, doors : pandas.DataFrame
        As :func:`floorscan.floorplan.rooms.plan_rooms`.
    """
    import shapely

    kinds = []
    for poly in polys:
        # width: the largest circle inside the room (its radius: the circle's centre to the wall)
        width = 2.0 * float(shapely.maximum_inscribed_circle(poly, resolution_m / 2).length)
        length = poly.area / max(width, 1e-9)
        long = width <= params.corridor_max_width_m and length >= max(params.corridor_elongation * width, params.corridor_min_length_m)
        kinds.append("corridor" if long else "room")
    if polys and not doors and not divided:
        kinds = ["space"] * len(polys)
        log.info("rooms: no door divides the free space (an open hall, one corridor, a campus): %s of %.1f m2",
                 "one space" if len(polys) == 1 else f"{len(polys)} spaces apart", sum(p.area for p in polys))
    names, counts = [], {}
    for kind in kinds:
        counts[kind] = counts.get(kind, 0) + 1
        names.append(f"{kind.capitalize()} {counts[kind]}")
    rooms = pd.DataFrame(
        {
            "room_id": np.arange(len(polys), dtype=np.int32),
            "name": pd.Series(names, dtype=object),
            "kind": pd.Series(kinds, dtype=object),
            "area_m2": np.array([p.area for p in polys], dtype=np.float64),
            "perimeter_m": np.array([p.length for p in polys], dtype=np.float64),
            "polygon": pd.Series(polys, dtype=object),
        }
    )
    ends = np.array([np.r_[p, q] for p, q, *_ in doors], dtype=np.float64).reshape(-1, 4)
    doors_df = pd.DataFrame(
        {
            "door_id": np.arange(len(doors), dtype=np.int32),
            "x0": ends[:, 0], "y0": ends[:, 1], "x1": ends[:, 2], "y1": ends[:, 3],
            "width_m": np.hypot(ends[:, 2] - ends[:, 0], ends[:, 3] - ends[:, 1]),
            "wall_id": np.array([d[2] for d in doors], dtype=np.int32),
            "room_a": np.array([d[3] for d in doors], dtype=np.int32),
            "room_b": np.array([d[4] for d in doors], dtype=np.int32),
        }  # fmt: skip
    )
    return rooms, doors_df

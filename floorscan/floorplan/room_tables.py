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
    polys: list, doors: list, resolution_m: float, params: RoomParams, divided: bool = False,
    unwalled: list | None = None,
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The rooms and doors tables of room polygons and door openings: each room's kind
    (a ``corridor`` when long for its width, :func:`is_corridor`, with the objects on
    its floor filled (:func:`objects_filled`); ``space`` for every room
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
        The tolerance of a room's width is half of it, metres.
    params : RoomParams
    divided : bool
        Whether a room's open side (:mod:`floorscan.floorplan.mouths`) divides two
        rooms, when no door does.
    unwalled : list of bool, optional
        Per room, whether its outline is the reach of the scans, walled on less than
        half its edge (:func:`floorscan.floorplan.rooms.plan_rooms`: a fan of rays
        through its door, the part of an open office the scans reached): a ``room``
        however long it looks. None: none is.

    Returns
    -------
    rooms, doors : pandas.DataFrame
        As :func:`floorscan.floorplan.rooms.plan_rooms`.
    """
    unwalled = [False] * len(polys) if unwalled is None else unwalled
    kinds = ["corridor" if not open_outline and is_corridor(objects_filled(poly, params.min_room_area_m2),
                                                            resolution_m / 2, params) else "room"
             for poly, open_outline in zip(polys, unwalled)]
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


def is_corridor(floor, tolerance_m: float, params: RoomParams) -> bool:
    """Whether a room is a corridor: long for its width (Bormann et al., "Room
    segmentation: survey, implementation, and analysis", ICRA 2016, a corridor is long
    and narrow). Its width ``w`` is its median local thickness (:func:`room_width`),
    its length ``L`` its area over ``w``; it is a corridor when ``L`` is at least
    ``corridor_min_length_m`` and ``corridor_elongation`` times ``w``, the more so the
    wider it is than ``corridor_max_width_m`` (``W``): ``L >= E w max(1, w / W)``. A
    corridor up to ``W`` wide is ``E`` widths long; a main hallway twice as wide runs
    twice as many widths (a 4.5 m hall of 50 m is a corridor, a 9 m x 50 m one a hall).
    The bound on ``w`` that follows, ``w**3 <= W area / E``, caps the bisection.

    Parameters
    ----------
    floor : shapely.Polygon
        The room with the objects on its floor filled (:func:`objects_filled`), metres.
    tolerance_m : float
        Of the width (:func:`room_width`), metres.
    params : RoomParams
        ``corridor_elongation`` (E), ``corridor_min_length_m``, ``corridor_max_width_m`` (W).

    Returns
    -------
    bool
    """
    e, w_max = params.corridor_elongation, params.corridor_max_width_m
    cap = max(w_max, (w_max * floor.area / e) ** (1 / 3))
    width = room_width(floor, tolerance_m, cap)
    return width <= cap and long_for_width(floor.area, width, params)


def long_for_width(area_m2: float, width_m: float, params: RoomParams) -> bool:
    """Whether a room of ``area_m2`` (m2) and width ``width_m`` (metres, its median local
    thickness) is long for its width, as :func:`is_corridor` asks: its length, area over
    width, at least ``corridor_min_length_m`` and ``corridor_elongation`` times its width,
    the more so beyond ``corridor_max_width_m``; False for a width of 0."""
    if width_m <= 0:
        return False
    e, w_max = params.corridor_elongation, params.corridor_max_width_m
    return area_m2 / width_m >= max(e * width_m * max(1.0, width_m / w_max), params.corridor_min_length_m)


def objects_filled(poly, min_room_area_m2: float):
    """``poly`` without its holes smaller than the smallest room: such a hole holds no
    room, so it is an object on the floor (a pillar, a table island, a block of
    cabinets drawn as walls), and a room around it is no narrower for it; a larger hole
    is the core a corridor goes around (the rooms inside a ring of corridors).

    Parameters
    ----------
    poly : shapely.Polygon
        Metres.
    min_room_area_m2 : float
        The smallest room (:class:`~floorscan.floorplan.room_space.RoomParams`), square
        metres.

    Returns
    -------
    shapely.Polygon
    """
    import shapely

    if poly.is_empty or not len(poly.interiors):
        return poly
    return shapely.Polygon(poly.exterior, [h for h in poly.interiors if shapely.Polygon(h).area >= min_room_area_m2])


def room_width(poly, tolerance_m: float, cap_m: float | None = None) -> float:
    """A room's width: its median local thickness, the diameter ``w`` of the largest
    disc whose opening of the room (erosion, then dilation, by a disc of diameter
    ``w``) keeps half of its area.

    The local thickness of a point of a shape is the diameter of the largest disc
    inside the shape that covers the point (Hildebrand and Rüegsegger, "A new method
    for the model-independent assessment of thickness in three-dimensional images",
    J. Microscopy 1997); the area the opening by a disc of diameter ``w`` keeps is the
    area whose local thickness is at least ``w``, so its median is where that area is
    half. A corridor 2 m wide is 2 m wide wherever a hall or a junction widens it; a
    network of corridors is as wide as its corridors (the largest inscribed circle
    says how wide its widest crossing is); a square room is as wide as its side (the
    inscribed disc covers pi / 4 of it).

    Parameters
    ----------
    poly : shapely.Polygon
        The room, metres.
    tolerance_m : float
        The bisection stops when the bracket of ``w`` is narrower, metres.
    cap_m : float, optional
        When the room is at least this wide, the diameter of its largest inscribed
        circle (an upper bound of the width) is returned without the bisection, metres:
        a room's kind needs no more, and a hall's openings cost the most.

    Returns
    -------
    float
        Metres; 0 for an empty polygon.
    """
    import shapely

    if poly.is_empty or poly.area <= 0:
        return 0.0
    def keeps_half(w: float) -> bool:
        opened = shapely.buffer(shapely.buffer(poly, -w / 2, quad_segs=4), w / 2, quad_segs=4)
        return opened.area >= poly.area / 2.0

    # the diameter of the largest inscribed circle bounds the thickness from above
    lo, hi = 0.0, 2.0 * float(shapely.maximum_inscribed_circle(poly, tolerance_m).length) + 2 * tolerance_m
    if cap_m is not None and cap_m < hi:
        if keeps_half(cap_m):
            return hi
        hi = cap_m
    while hi - lo > tolerance_m:
        w = (lo + hi) / 2
        lo, hi = (w, hi) if keeps_half(w) else (lo, w)
    return lo

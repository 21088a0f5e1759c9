"""Small generated buildings: a rectangle of rooms on a grid, for property tests.

:func:`room_grid_building` builds a :class:`~floorscan.sim.building.Building` from a few
numbers (the widths of the columns and the depths of the rows of rooms, and where each
inner wall has its door), so that a test can draw them (Hypothesis) and know the true
rooms and doors (:func:`floorscan.sim.ground_truth.true_rooms`, ``true_doors``). The
outer wall is a closed rectangle with an entrance on its south side; between every two
neighbouring rooms an inner wall has one door. A building of 2 x 2 rooms of 3 m is about
160 x 160 cells of 5 cm as a map (:func:`floorscan.sim.occupancy_map.building_map`):
its plan takes about 0.1 s, so hundreds of cases run in a minute or two.

:func:`moved` turns, mirrors and shifts any building, so that a test can compare the
plan of a building with the plan of its image.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Sequence

import numpy as np

from floorscan.sim.building import Building, Opening, Wall

#: Thickness of the outer and of the inner walls, metres.
OUTER_THICKNESS_M = 0.25
INNER_THICKNESS_M = 0.12
#: A door's width, metres (a plan's doors are 0.6-2.0 m).
DOOR_WIDTH_M = 0.9
#: A door keeps this far from the ends of its wall segment, metres.
DOOR_MARGIN_M = 0.3


def _door(segment_m: float, fraction: float, ident: str, segment: int) -> Opening:
    room = segment_m - 2 * DOOR_MARGIN_M - DOOR_WIDTH_M
    return Opening(ident, "door", segment, DOOR_MARGIN_M + max(room, 0.0) * float(fraction), DOOR_WIDTH_M, 0.0, 2.1)


def room_grid_building(
    widths_m: Sequence[float], depths_m: Sequence[float], doors: Sequence[float] = (), name: str = "generated"
) -> Building:
    """A rectangle of ``len(widths_m)`` x ``len(depths_m)`` rooms (see the module docstring).

    Parameters
    ----------
    widths_m : sequence of float
        The columns' widths from west to east, metres between wall axes, each at least
        ``2 * DOOR_MARGIN_M + DOOR_WIDTH_M``.
    depths_m : sequence of float
        The rows' depths from south to north, metres, as ``widths_m``.
    doors : sequence of float
        Where each door lies along its wall segment, 0 (the segment's start) to 1 (its
        end); used in turn by the entrance, the north-south walls' doors (per wall,
        south to north) and the east-west walls' (west to east), repeated when short;
        0.5 each when empty.
    name : str

    Returns
    -------
    Building
        Height 2.6 m, no furniture, one waypoint at the first room's centre.

    Raises
    ------
    ValueError
        When there is no column or row, or a width or depth is below
        ``2 * DOOR_MARGIN_M + DOOR_WIDTH_M``.
    """
    w, d = [float(v) for v in widths_m], [float(v) for v in depths_m]
    least = 2 * DOOR_MARGIN_M + DOOR_WIDTH_M
    if not w or not d or min(w + d) < least:
        raise ValueError(f"widths_m and depths_m: at least one each, every one >= {least} m; got {w}, {d}")
    fractions = [float(f) for f in doors] or [0.5]
    k = iter(range(10**9))

    def frac() -> float:
        return fractions[next(k) % len(fractions)]

    xs, ys = np.concatenate([[0.0], np.cumsum(w)]), np.concatenate([[0.0], np.cumsum(d)])
    x1, y1 = float(xs[-1]), float(ys[-1])
    walls = [Wall("outer", np.array([[0.0, 0.0], [x1, 0.0], [x1, y1], [0.0, y1]]), True, OUTER_THICKNESS_M,
                  (_door(w[0], frac(), "entrance", 0),))]  # fmt: skip
    for i, x in enumerate(xs[1:-1], start=1):
        pts = np.array([[x, y] for y in ys])
        ops = tuple(_door(d[j], frac(), f"door_v{i}_{j}", j) for j in range(len(d)))
        walls.append(Wall(f"wall_v{i}", pts, False, INNER_THICKNESS_M, ops))
    for j, y in enumerate(ys[1:-1], start=1):
        pts = np.array([[x, y] for x in xs])
        ops = tuple(_door(w[i], frac(), f"door_h{j}_{i}", i) for i in range(len(w)))
        walls.append(Wall(f"wall_h{j}", pts, False, INNER_THICKNESS_M, ops))
    return Building(name=name, height_m=2.6, walls=tuple(walls), waypoints=np.array([[w[0] / 2, d[0] / 2]]),
                    source=f"<generated {name}>")  # fmt: skip


def moved(building: Building, theta: float, mirror: bool = False, shift_xy=(0.0, 0.0)) -> Building:
    """A building turned by ``theta`` about the origin, mirrored in the y axis first when
    ``mirror``, then shifted: walls, furniture and waypoints (openings keep their segment
    and offset).

    Parameters
    ----------
    building : Building
    theta : float
        Radians, counter-clockwise.
    mirror : bool
        ``x -> -x`` before the turn.
    shift_xy : (2,) float
        Metres, after the turn.

    Returns
    -------
    Building
    """
    c, s = math.cos(theta), math.sin(theta)
    rot = np.array([[c, s], [-s, c]])  # row vectors: p @ rot turns p by theta
    shift = np.asarray(shift_xy, dtype=np.float64)

    def f(p):
        p = np.array(p, dtype=np.float64)
        if mirror:
            p[..., 0] = -p[..., 0]
        return p @ rot + shift

    walls = tuple(dataclasses.replace(wl, points=f(wl.points)) for wl in building.walls)
    furniture = tuple(
        dataclasses.replace(
            fu, center=tuple(float(v) for v in f(fu.center)),
            yaw_rad=(math.pi - fu.yaw_rad if mirror else fu.yaw_rad) + theta,
        )
        for fu in building.furniture
    )  # fmt: skip
    waypoints = f(building.waypoints).reshape(-1, 2)
    return dataclasses.replace(building, walls=walls, furniture=furniture, waypoints=waypoints)


def scans_2d(
    building: Building, origins: np.ndarray, n_beams: int = 360, max_range_m: float = 20.0
) -> list[np.ndarray]:
    """What a level 2D scanner sees from each of ``origins``: the nearest wall face of
    :func:`floorscan.sim.ground_truth.wall_faces` along each of ``n_beams`` rays (no
    noise, no furniture).

    Parameters
    ----------
    building : Building
    origins : (S, 2) float ndarray
        The scanner's positions, map metres.
    n_beams : int
        Rays over the full turn, from angle 0.
    max_range_m : float
        Rays hitting nothing closer are dropped, metres.

    Returns
    -------
    list of (M, 2) float64 ndarray
        Per scan its returns in the map frame, metres.
    """
    from floorscan.sim.ground_truth import wall_faces
    from floorscan.sim.params import SimParams

    faces = np.array([np.concatenate(f) for f in wall_faces(building, SimParams().sensor_height_m)], dtype=np.float64)
    angles = np.arange(n_beams) * (2 * math.pi / n_beams)
    d = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    a, e = faces[:, :2], faces[:, 2:] - faces[:, :2]
    out = []
    for o in np.asarray(origins, dtype=np.float64).reshape(-1, 2):
        w = a - o
        den = d[:, None, 0] * e[None, :, 1] - d[:, None, 1] * e[None, :, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (w[None, :, 0] * e[None, :, 1] - w[None, :, 1] * e[None, :, 0]) / den
            u = (w[None, :, 0] * d[:, None, 1] - w[None, :, 1] * d[:, None, 0]) / den
        t = np.where((np.abs(den) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1), t, np.inf).min(axis=1)
        hit = t < max_range_m
        out.append(o + d[hit] * t[hit, None])
    return out

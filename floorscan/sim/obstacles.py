"""Where the rover cannot drive: the walls at floor level and the furniture on the floor.

Doors are open at floor level, so the rover drives through them; furniture standing on
the floor (``z_min_m`` below 0.05 m) blocks it, raised furniture does not. A waypoint or
a straight leg between two inside an obstacle (:func:`check_path`, when the building is
read) and a simulated path that enters one (:func:`check_trajectory`) are an
``InputError`` naming the file and what was hit.
"""

from __future__ import annotations

import numpy as np
import shapely
from shapely.geometry import LineString, Point
from shapely.ops import unary_union

from floorscan.core.io import InputError
from floorscan.sim.building import Building
from floorscan.sim.footprint import wall_footprint, wall_polygon
from floorscan.sim.trajectory import Trajectory


def obstacles_at_floor(building: Building):
    """What the rover cannot drive through: walls at floor level (doors open) and
    furniture standing on the floor (``z_min_m`` below 0.05 m).

    Parameters
    ----------
    building : Building

    Returns
    -------
    shapely geometry
        Their union, metres.
    """
    parts = [wall_footprint(building, 0.0)]
    parts += [f.footprint() for f in building.furniture if f.z_min_m < 0.05]
    return unary_union(parts)


def check_path(building: Building, points: np.ndarray, what: str = "waypoints") -> None:
    """Raise when a waypoint or the straight path between two lies in a wall/furniture.

    Parameters
    ----------
    building : Building
    points : (K, 2) float64 ndarray
        Path vertices in the map frame, metres.
    what : str
        Name used in the message.

    Raises
    ------
    InputError
        Naming the file, the waypoint index and the wall or furniture hit.
    """
    named = [(f"wall {w.id!r}", wall_polygon(w)) for w in building.walls]
    named += [(f"furniture {f.id!r}", f.footprint()) for f in building.furniture if f.z_min_m < 0.05]
    blocked = obstacles_at_floor(building)
    for i, p in enumerate(points):
        pt = Point(p)
        if blocked.intersects(pt):
            hit = next((n for n, g in named if g.intersects(pt)), "a wall")
            raise InputError(
                f"{building.source}: {what}[{i}] {p.tolist()} is inside {hit}"
            )
    for i in range(len(points) - 1):
        seg = LineString([points[i], points[i + 1]])
        if seg.length > 0 and blocked.intersects(seg):
            bad = blocked.intersection(seg)
            hit = next((n for n, g in named if g.intersects(bad)), "a wall")
            raise InputError(
                f"{building.source}: {what}[{i}] -> {what}[{i + 1}] "
                f"({points[i].tolist()} -> {points[i + 1].tolist()}) crosses {hit}"
            )


def check_trajectory(building: Building, traj: Trajectory) -> None:
    """Raise when the rover's simulated path (not only its waypoints and the straight
    legs between them) enters a wall or furniture standing on the floor.

    Parameters
    ----------
    building : Building
    traj : Trajectory
        The simulated path, sampled in time.

    Raises
    ------
    InputError
        Naming the file, the first point inside, its time and the nearest waypoint.
    """
    blocked = obstacles_at_floor(building)
    hit = shapely.intersects_xy(blocked, traj.xy[:, 0], traj.xy[:, 1])
    if hit.any():
        i = int(np.argmax(hit))
        x, y = traj.xy[i]
        # which waypoint leg was the rover on?
        d = np.hypot(*(building.waypoints - traj.xy[i]).T)
        raise InputError(
            f"{building.source}: the rover's path enters a wall or furniture at "
            f"({x:.2f}, {y:.2f}) m, t = {traj.t[i]:.1f} s, near waypoints[{int(np.argmin(d))}]; "
            "move the waypoints away from walls and door jambs"
        )

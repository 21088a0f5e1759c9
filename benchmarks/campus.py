"""A large synthetic building for ``benchmarks pipeline``: a square floor of ``size_m``
(200 m by default) crossed by a grid of corridors, its blocks cut into rooms, each room
with a door onto a corridor (or, at the outer wall, onto the room behind it), and a rover
that drives every corridor and into one room of each block (issue 46, item 3).

:func:`campus_building` gives the building as the mapping of a building file
(``config/buildings/<name>.yaml``, format :mod:`floorscan.sim.building`), which the
simulate stage reads like any other; :func:`write_campus` writes it.

With the defaults: corridors 3 m wide every 40 m both ways (five each), 36 blocks of two
rows of rooms 9.25 m wide (two a row in the blocks at the outer wall), 240 rooms; a
path of 2.85 km (every horizontal corridor end to end, one room of each block with a
corridor on its south side, the vertical corridors between the outermost horizontal
ones), which the rover drives in 2085 s at 1.5 m/s: 20 850 scans at 10 Hz.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

#: The rover's cruise speed on the campus, m/s (the simulate stage allows up to 3).
CAMPUS_SPEED_MPS = 1.5


def _spans(size_m: float, centres: list[float], half: float) -> list[tuple[float, float]]:
    """The stretches between corridors along one axis (0 .. size_m)."""
    edges = [0.0] + [e for c in centres for e in (c - half, c + half)] + [size_m]
    return [(edges[i], edges[i + 1]) for i in range(0, len(edges), 2)]


def campus_building(
    size_m: float = 200.0, spacing_m: float = 40.0, corridor_m: float = 3.0, room_m: float = 9.0,
    name: str = "campus200",
) -> dict:
    """The building file's mapping of the campus.

    Parameters
    ----------
    size_m : float
        Side of the square floor, metres.
    spacing_m : float
        Distance between corridor centre lines, metres (the first at ``spacing_m / 2``).
    corridor_m : float
        Corridor width, metres.
    room_m : float
        Target room width along a corridor, metres.
    name : str

    Returns
    -------
    dict
        ``name``, ``description``, ``height_m``, ``wall_thickness_m``, ``walls``,
        ``waypoints`` (format :mod:`floorscan.sim.building`).
    """
    half = corridor_m / 2
    centres = [float(c) for c in np.arange(spacing_m / 2, size_m, spacing_m)]
    spans = _spans(size_m, centres, half)
    walls = [{"id": "outer", "closed": True, "thickness_m": 0.3,
              "points": [[0, 0], [size_m, 0], [size_m, size_m], [0, size_m]]}]
    waypoints: list[list[float]] = []
    door_w = 1.0
    visits: dict[tuple[int, int], list[list[float]]] = {}
    for bi, (x0, x1) in enumerate(spans):
        for bj, (y0, y1) in enumerate(spans):
            n = max(1, round((x1 - x0) / room_m))
            xs = np.linspace(x0, x1, n + 1)
            ym = round((y0 + y1) / 2, 3)
            south, north = y0 > 0, y1 < size_m  # a corridor on that side
            # the corridor walls of the block: one polyline per side that faces a corridor
            for side, (a, b), along, faces in (
                ("s", ((x0, y0), (x1, y0)), "x", south), ("n", ((x0, y1), (x1, y1)), "x", north),
                ("w", ((x0, y0), (x0, y1)), "y", x0 > 0), ("e", ((x1, y0), (x1, y1)), "y", x1 < size_m),
            ):
                if not faces:
                    continue
                wall = {"id": f"b{bi}_{bj}_{side}", "points": [list(a), list(b)], "thickness_m": 0.15}
                if side in ("s", "n"):  # a door per room of the row that faces this corridor
                    wall["openings"] = [
                        {"id": f"d{bi}_{bj}_{side}{r}", "kind": "door", "segment": 0,
                         "offset_m": round(float((xs[r] + xs[r + 1]) / 2 - x0 - door_w / 2), 3), "width_m": door_w}
                        for r in range(n)
                    ]
                walls.append(wall)
            # the rooms: partitions across the block, and the wall between its two rows
            for r in range(1, n):
                walls.append({"id": f"b{bi}_{bj}_p{r}", "points": [[round(float(xs[r]), 3), y0], [round(float(xs[r]), 3), y1]]})
            middle = {"id": f"b{bi}_{bj}_m", "points": [[x0, ym], [x1, ym]]}
            if not (south and north):  # the row at the outer wall opens onto the other row
                middle["openings"] = [
                    {"id": f"d{bi}_{bj}_m{r}", "kind": "door", "segment": 0,
                     "offset_m": round(float((xs[r] + xs[r + 1]) / 2 - x0 - door_w / 2), 3), "width_m": door_w}
                    for r in range(n)
                ]
            walls.append(middle)
            # the rover enters the first room of the block's south row from the south corridor
            if south:
                cx = round(float((xs[0] + xs[1]) / 2), 3)
                visits[(bi, bj)] = [[cx, y0 - half], [cx, round(y0 + (ym - y0) / 2, 3)], [cx, y0 - half]]
    # the path: every horizontal corridor, west to east and back as a snake, entering one
    # room per block from the corridor; then every vertical corridor between the
    # outermost horizontal ones
    lo, hi = 2.0, size_m - 2.0
    for i, c in enumerate(centres):
        run = [[lo, c]]
        for bi in range(len(spans)):  # the blocks north of corridor i (i + 1) have it on their south side
            run += visits.get((bi, i + 1), [])
        run.append([hi, c])
        if i % 2:
            run = run[::-1]
        waypoints += run
        if i + 1 < len(centres):  # up the nearest vertical corridor to the next one
            x = centres[-1] if i % 2 == 0 else centres[0]
            waypoints += [[x, c], [x, centres[i + 1]]]
    y = centres[-1]  # the snake ended on the last corridor, at its east end when it ran east
    for x in reversed(centres) if len(centres) % 2 else centres:  # the vertical corridors, nearest first
        far = centres[0] if y == centres[-1] else centres[-1]
        waypoints += [[x, y], [x, far]]
        y = far
    return {
        "name": name,
        "description": f"benchmark campus: {size_m:g} m square, corridors every {spacing_m:g} m both ways, "
        f"{len(spans) ** 2} blocks of rooms",
        "height_m": 2.8,
        "wall_thickness_m": 0.12,
        "walls": walls,
        "waypoints": [[round(float(x), 3), round(float(y), 3)] for x, y in waypoints],
    }


def write_campus(path: str | Path, **kwargs) -> dict:
    """Write :func:`campus_building` as a building file.

    Parameters
    ----------
    path : path
        ``config/buildings/<name>.yaml``.
    **kwargs
        As :func:`campus_building`.

    Returns
    -------
    dict
        The mapping written.
    """
    building = campus_building(**kwargs)
    Path(path).write_text(yaml.safe_dump(building, sort_keys=False, default_flow_style=None, width=120))
    return building

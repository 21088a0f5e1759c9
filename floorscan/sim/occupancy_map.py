"""The simulator's own map of a building: its plan view at the scanner's height as an
occupancy map, the input a robot's SLAM map gives (:mod:`floorscan.ingest.occupancy_map`),
with the walls, rooms and doors known exactly (:mod:`floorscan.sim.ground_truth`).

The classes of a cell (:func:`building_map_classes`):

- **occupied**: its centre lies inside the walls cut at ``height_m``
  (:func:`floorscan.sim.footprint.wall_footprint`: the door openings are gaps, windows
  are wall below their sill) or, with ``furniture``, inside a piece of furniture cut at
  that height (:meth:`floorscan.sim.building.Furniture.section`: a table's legs, a
  cabinet's box; nothing of a cabinet hung above it);
- **free**: its centre lies inside the building's outline
  (:func:`floorscan.sim.footprint.building_outline`: the walls and what they enclose)
  and it is not occupied: the floor of every room and the door openings;
- **unknown**: the rest, outside the building, ``margin_m`` of it around the outline.

A cell is rasterised by its centre: in a class when its centre lies strictly inside
the class's polygon (Shapely's vectorised ``contains_xy``; a centre on an edge is
outside it). So an edge is drawn within half a cell of where it is: a 0.15 m wall at
0.05 m cells is 2 to 4 cells thick, a 0.9 m door 17 to 19 cells wide, depending on where
the cell centres fall. The map frame is the building's frame (metres, as in the building
file): the grid's origin is only where its cells start, so a plan of the map is compared
with :func:`~floorscan.sim.ground_truth.true_rooms` and
:func:`~floorscan.sim.ground_truth.true_doors` directly. By default the origin is the
outline's lower-left corner less ``margin_m``, rounded down to a whole cell; an
``origin_xy`` given moves the cells (a sub-cell shift rasterises the same building
differently).

:func:`building_map` returns the map as an
:class:`~floorscan.core.occupancy.OccupancyGrid`
(:func:`~floorscan.core.occupancy_classes.grid_of_classes`: no scan positions);
:func:`write_building_map` writes it as a ROS map_server map (``map.pgm`` and
``map.yaml``, :func:`~floorscan.core.occupancy.write_map_server`), which
:func:`floorscan.ingest.occupancy_map.read_occupancy_map` reads back.

Usage::

    building = load_building("config/buildings/demo.yaml")
    grid = write_building_map(building, "demo/map.yaml")    # and demo/map.pgm
    grid = building_map(building, furniture=False, origin_xy=(-0.513, -0.487))
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import shapely
from shapely.ops import unary_union

from floorscan.core.occupancy import OccupancyGrid, write_map_server
from floorscan.core.occupancy_classes import grid_of_classes
from floorscan.sim.building import Building
from floorscan.sim.footprint import building_outline, wall_footprint
from floorscan.sim.params import SimParams

#: Cell size of the map, metres (ROS maps' usual 5 cm).
MAP_RESOLUTION_M = 0.05
#: Unknown space drawn around the building's outline, metres.
MAP_MARGIN_M = 0.5


def _check(building: Building, resolution_m: float, height_m: float, margin_m: float) -> None:
    if not (math.isfinite(resolution_m) and resolution_m > 0):
        raise ValueError(f"resolution_m: expected a positive number of metres, got {resolution_m!r}")
    if not (math.isfinite(margin_m) and margin_m >= 0):
        raise ValueError(f"margin_m: expected >= 0 metres, got {margin_m!r}")
    if not 0 <= height_m < building.height_m:
        raise ValueError(f"height_m: expected 0 <= height < {building.height_m} (the ceiling), got {height_m!r}")


def building_map_classes(
    building: Building, resolution_m: float = MAP_RESOLUTION_M, height_m: float | None = None,
    furniture: bool = True, margin_m: float = MAP_MARGIN_M, origin_xy=None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """The occupied and free cells of a building's plan view (see the module docstring).

    Parameters
    ----------
    building : Building
    resolution_m : float
        Cell size, metres.
    height_m : float, optional
        The height of the cut, metres above the floor (default: the simulated
        scanner's, ``simulate.sensor_height_m``).
    furniture : bool
        Draw the furniture at that height occupied (False: the empty building).
    margin_m : float
        Unknown space around the outline, metres (on the upper and right sides at
        least; on the lower and left with the default origin).
    origin_xy : (2,) float, optional
        The lower-left corner of cell (0, 0) in the building's frame, metres; at most
        the outline's lower-left corner. Default: that corner less ``margin_m``,
        rounded down to a multiple of ``resolution_m``.

    Returns
    -------
    occupied, free : (H, W) bool ndarray
        Row 0 at the bottom (``y = origin_y + (i + 0.5) * resolution_m``); disjoint.
    origin_xy : (2,) float64 ndarray
        Metres.

    Raises
    ------
    ValueError
        A resolution not positive, a negative margin, a height outside floor..ceiling,
        or an origin above or right of the outline's lower-left corner.
    """
    z = SimParams().sensor_height_m if height_m is None else float(height_m)
    _check(building, float(resolution_m), z, float(margin_m))
    r = float(resolution_m)
    outline = building_outline(building)
    x0, y0, x1, y1 = outline.bounds
    if origin_xy is None:
        origin = np.floor((np.array([x0, y0]) - margin_m) / r) * r
    else:
        origin = np.asarray(origin_xy, dtype=np.float64).reshape(2)
        if not (np.isfinite(origin).all() and origin[0] <= x0 and origin[1] <= y0):
            raise ValueError(f"origin_xy: expected at most the outline's lower-left corner ({x0}, {y0}), got {tuple(origin)}")
    width = int(math.ceil((x1 + margin_m - origin[0]) / r))
    height = int(math.ceil((y1 + margin_m - origin[1]) / r))
    solid = wall_footprint(building, z)
    if furniture:
        solid = unary_union([solid] + [f.section(z) for f in building.furniture])
    cx, cy = np.meshgrid(origin[0] + (np.arange(width) + 0.5) * r, origin[1] + (np.arange(height) + 0.5) * r)
    occupied = shapely.contains_xy(solid, cx, cy)
    free = shapely.contains_xy(outline, cx, cy) & ~occupied
    return occupied, free, origin


def building_map(
    building: Building, resolution_m: float = MAP_RESOLUTION_M, height_m: float | None = None,
    furniture: bool = True, margin_m: float = MAP_MARGIN_M, origin_xy=None,
) -> OccupancyGrid:  # fmt: skip
    """A building's plan view as an occupancy map (:func:`building_map_classes`).

    Parameters
    ----------
    building : Building
    resolution_m, height_m, furniture, margin_m, origin_xy
        As :func:`building_map_classes`.

    Returns
    -------
    OccupancyGrid
        The classes as :func:`~floorscan.core.occupancy_classes.grid_of_classes`
        holds them; ``scan_xy`` None (a map has no scan positions).

    Raises
    ------
    ValueError
        As :func:`building_map_classes`.
    """
    occupied, free, origin = building_map_classes(building, resolution_m, height_m, furniture, margin_m, origin_xy)
    return grid_of_classes(occupied, free, origin, resolution_m)


def write_building_map(
    building: Building, yaml_path: str | Path, resolution_m: float = MAP_RESOLUTION_M, height_m: float | None = None,
    furniture: bool = True, margin_m: float = MAP_MARGIN_M, origin_xy=None,
) -> OccupancyGrid:  # fmt: skip
    """Write a building's plan view as a ROS map_server map (:func:`building_map`).

    Parameters
    ----------
    building : Building
    yaml_path : path
        The map's yaml (``map.yaml``); the image is written beside it with the yaml's
        stem (``map.pgm``; binary PGM, occupied 0, free 254, unknown 205), which the
        yaml names. Both written atomically.
    resolution_m, height_m, furniture, margin_m, origin_xy
        As :func:`building_map_classes`.

    Returns
    -------
    OccupancyGrid
        The map written.

    Raises
    ------
    ValueError
        As :func:`building_map_classes`.
    """
    yaml_path = Path(yaml_path)
    grid = building_map(building, resolution_m, height_m, furniture, margin_m, origin_xy)
    write_map_server(grid, yaml_path.with_suffix(".pgm"), yaml_path, title=f"map of the simulated building {building.name}")
    return grid

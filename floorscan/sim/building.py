"""Synthetic buildings: the model a building file describes.

The thesis scores its method on a CAD model of a floor whose walls are known exactly
(sections 4.1 and 5.2): doors and windows are empty space, and "taking a slice of that
model will be the equivalent of getting a floor plan". This module is that model.

A building file (``config/buildings/<name>.yaml``) looks like::

    name: demo
    height_m: 2.6              # floor to ceiling
    wall_thickness_m: 0.15     # default thickness of a wall
    walls:
      - id: outer
        closed: true           # the polyline returns to its first point
        thickness_m: 0.25
        points: [[0, 0], [12, 0], [12, 8], [0, 8]]
        openings:              # gaps along one segment of the polyline
          - {id: entrance, kind: door, segment: 0, offset_m: 1.0, width_m: 1.0}
          - {id: w1, kind: window, segment: 1, offset_m: 2, width_m: 1.5,
             sill_m: 0.9, head_m: 2.1}
    furniture:                 # clutter: boxes standing on the floor (or raised)
      - {id: desk, center: [3, 2], size: [1.6, 0.8, 0.75], yaw_deg: 0, z_min_m: 0,
         legs_m: 0.05}         # a table: a 3 cm top on four square legs
    waypoints: [[1.5, -1], [1.5, 4], [6, 4]]   # the rover's path (map frame, m)

Coordinates are metres in the map frame. A wall is a polyline (its centre line, the
"axis") with a thickness; its solid is the polyline buffered by half the thickness with
flat ends and mitred joins, from the floor to the ceiling. An opening is a gap along
segment ``segment`` (0-based) of the polyline, ``offset_m`` from the segment's first
point and ``width_m`` wide, from ``sill_m`` (0 for doors) to ``head_m`` (default 2.1 m for
doors); it cuts every wall solid it overlaps. The mesh also has a floor and a ceiling
slab under and over the building outline (``floor``/``ceiling``, default true).

The file is read and checked by :mod:`floorscan.sim.building_file`; the walls in plan
are in :mod:`floorscan.sim.footprint`, the triangle mesh in :mod:`floorscan.sim.mesh` and
the ground-truth walls in :mod:`floorscan.sim.ground_truth`. A new element or key of the
format is a field here and is read in :mod:`floorscan.sim.building_file`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from shapely.geometry import Polygon
from shapely.ops import unary_union

#: Default head height of a door, metres.
DOOR_HEAD_M = 2.1
#: Thickness of a table's top (furniture with ``legs_m``), metres.
TABLE_TOP_M = 0.03


@dataclass(frozen=True)
class Opening:
    """A door or window: a gap along one segment of a wall polyline (metres)."""

    id: str
    kind: str  # "door" or "window"
    segment: int
    offset_m: float
    width_m: float
    sill_m: float
    head_m: float


@dataclass(frozen=True)
class Wall:
    """A wall: centre-line polyline (K, 2) in metres, thickness and openings."""

    id: str
    points: np.ndarray
    closed: bool
    thickness_m: float
    openings: tuple[Opening, ...] = ()

    def segments(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """The straight segments of the axis (closing segment included for a closed wall).

        Returns
        -------
        list of ((2,) float64 ndarray, (2,) float64 ndarray)
            (start, end) of each segment, metres, in polyline order.
        """
        pts = self.points
        n = len(pts) if self.closed else len(pts) - 1
        return [(pts[i], pts[(i + 1) % len(pts)]) for i in range(n)]


@dataclass(frozen=True)
class Furniture:
    """A clutter box: centre (x, y), size (sx, sy, sz), yaw and bottom height (metres).

    With ``legs_m`` > 0 it is a table (desk, chair): a top ``TABLE_TOP_M`` thick at
    the top of the box on four square legs of side ``legs_m`` in its corners, so a 2D
    scanner below the top sees four legs, as on a real office floor, not a solid box.
    """

    id: str
    center: tuple[float, float]
    size: tuple[float, float, float]
    yaw_rad: float
    z_min_m: float
    legs_m: float = 0.0

    def _outline(self, cx: float, cy: float, sx: float, sy: float) -> Polygon:
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        corners = [(-sx, -sy), (sx, -sy), (sx, sy), (-sx, sy)]
        return Polygon(
            [(self.center[0] + c * (cx + x) - s * (cy + y),
              self.center[1] + s * (cx + x) + c * (cy + y)) for x, y in corners]
        )

    def section(self, z: float):
        """The plan outline of the furniture cut at height ``z``: the box, a table's legs
        or top, or an empty polygon outside its height.

        Parameters
        ----------
        z : float
            Height above the floor, metres.

        Returns
        -------
        shapely Polygon or MultiPolygon
            Map metres.
        """
        z0, z1 = self.z_min_m, self.z_min_m + self.size[2]
        if not z0 <= z <= z1:
            return Polygon()
        if self.legs_m > 0 and z < z1 - TABLE_TOP_M:
            return unary_union(self.legs())
        return self.footprint()

    def legs(self) -> list[Polygon]:
        """Outlines of the four legs of a table.

        Returns
        -------
        list of shapely Polygon
            Four squares of side ``legs_m`` in the box's corners, metres; empty without
            ``legs_m``.
        """
        if self.legs_m <= 0:
            return []
        h = self.legs_m / 2
        ox, oy = self.size[0] / 2 - h, self.size[1] / 2 - h
        return [self._outline(sx * ox, sy * oy, h, h) for sx in (-1, 1) for sy in (-1, 1)]

    def footprint(self) -> Polygon:
        """The box's outline on the floor plan (a table's: its top).

        Returns
        -------
        shapely Polygon
            The rotated rectangle, metres.
        """
        return self._outline(0.0, 0.0, self.size[0] / 2, self.size[1] / 2)


@dataclass(frozen=True)
class Building:
    """A parsed, validated building description (see the module docstring)."""

    name: str
    height_m: float
    walls: tuple[Wall, ...]
    furniture: tuple[Furniture, ...] = ()
    waypoints: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    floor: bool = True
    ceiling: bool = True
    source: str = "<building>"

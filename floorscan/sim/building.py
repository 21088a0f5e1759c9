"""Synthetic buildings: a YAML description, its triangle mesh and its ground-truth walls.

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

The ground truth (:func:`ground_truth_walls`) is a horizontal slice of the walls at one
height: doors are gaps there, windows are gaps only where ``sill_m <= z < head_m``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import reduce
from pathlib import Path
from typing import Any

import numpy as np
import shapely
import trimesh
import yaml
from shapely.geometry import LineString, LinearRing, MultiLineString, Point, Polygon
from shapely.ops import polygonize, unary_union

from floorscan.core.io import InputError

#: Default head height of a door, metres.
DOOR_HEAD_M = 2.1
#: How far an opening's cutter reaches beyond each face of its wall, metres. Keeps the
#: boolean away from coplanar faces; the 2D footprint uses the same cutter.
_CUT_MARGIN_M = 0.01
#: Thickness of a table's top (furniture with ``legs_m``), metres.
TABLE_TOP_M = 0.03
#: Thickness of the floor and ceiling slabs, metres.
SLAB_THICKNESS_M = 0.05
#: Wall segments shorter than this (m) are "zero length".
_MIN_LENGTH_M = 1e-6

_TOP_KEYS = {
    "name", "description", "height_m", "wall_thickness_m", "floor", "ceiling", "walls",
    "furniture", "waypoints",
}
_WALL_KEYS = {"id", "points", "closed", "thickness_m", "openings"}
_OPENING_KEYS = {"id", "kind", "segment", "offset_m", "width_m", "sill_m", "head_m"}
_FURNITURE_KEYS = {"id", "center", "size", "yaw_deg", "z_min_m", "legs_m"}


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
        """The straight segments of the axis as (start, end) (2,) arrays."""
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
        """The plan outline of the furniture cut at height ``z`` (metres): the box, a
        table's legs or top, or an empty polygon outside its height."""
        z0, z1 = self.z_min_m, self.z_min_m + self.size[2]
        if not z0 <= z <= z1:
            return Polygon()
        if self.legs_m > 0 and z < z1 - TABLE_TOP_M:
            return unary_union(self.legs())
        return self.footprint()

    def legs(self) -> list[Polygon]:
        """Outlines of the four legs of a table (empty without ``legs_m``)."""
        if self.legs_m <= 0:
            return []
        h = self.legs_m / 2
        ox, oy = self.size[0] / 2 - h, self.size[1] / 2 - h
        return [self._outline(sx * ox, sy * oy, h, h) for sx in (-1, 1) for sy in (-1, 1)]

    def footprint(self) -> Polygon:
        """The box's outline on the floor plan (a table's: its top)."""
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


# --------------------------------------------------------------------------- parsing


def load_building(path: str | Path) -> Building:
    """Read and validate a building YAML file.

    Parameters
    ----------
    path : str or Path
        The building file (format in the module docstring).

    Returns
    -------
    Building

    Raises
    ------
    InputError
        When the file is missing or not YAML, or an element is invalid: unknown keys,
        a zero-length or self-intersecting wall, an opening wider than its wall segment
        or above the ceiling, a waypoint inside a wall or furniture, a path segment
        crossing a wall. The message names the file and the element.
    """
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except FileNotFoundError:
        raise InputError(f"{path}: building file not found") from None
    except yaml.YAMLError as e:
        raise InputError(f"{path}: not valid YAML: {e}") from None
    return parse_building(data, source=str(path))


def parse_building(data: Any, source: str = "<building>") -> Building:
    """Validate a building description already loaded from YAML (a mapping).

    Parameters
    ----------
    data : dict
        The mapping described in the module docstring.
    source : str
        Name of the file it came from, used in error messages.

    Returns
    -------
    Building

    Raises
    ------
    InputError
        As :func:`load_building`.
    """
    if not isinstance(data, dict):
        raise InputError(f"{source}: expected a mapping with 'walls', 'height_m', 'waypoints'")
    _no_unknown(data, _TOP_KEYS, source, "top level")
    height = _positive(data.get("height_m"), source, "height_m")
    default_t = _positive(data.get("wall_thickness_m", 0.15), source, "wall_thickness_m")
    raw_walls = data.get("walls")
    if not isinstance(raw_walls, list) or not raw_walls:
        raise InputError(f"{source}: 'walls' must be a non-empty list")
    walls = []
    seen: set[str] = set()
    for i, rw in enumerate(raw_walls):
        wall = _parse_wall(rw, i, default_t, height, source)
        if wall.id in seen:
            raise InputError(f"{source}: walls[{i}]: duplicate wall id {wall.id!r}")
        seen.add(wall.id)
        walls.append(wall)
    furniture = [
        _parse_furniture(rf, i, height, source) for i, rf in enumerate(data.get("furniture") or [])
    ]
    waypoints = _parse_waypoints(data.get("waypoints"), source)
    b = Building(
        name=str(data.get("name", Path(source).stem)),
        height_m=height,
        walls=tuple(walls),
        furniture=tuple(furniture),
        waypoints=waypoints,
        floor=bool(data.get("floor", True)),
        ceiling=bool(data.get("ceiling", True)),
        source=source,
    )
    check_path(b, waypoints)
    return b


def _no_unknown(d: dict, allowed: set[str], source: str, where: str) -> None:
    unknown = sorted(set(d) - allowed)
    if unknown:
        raise InputError(f"{source}: {where}: unknown keys {unknown}; allowed: {sorted(allowed)}")


def _number(v: Any, source: str, where: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
        raise InputError(f"{source}: {where}: expected a finite number, got {v!r}")
    return float(v)


def _positive(v: Any, source: str, where: str) -> float:
    x = _number(v, source, where)
    if x <= 0:
        raise InputError(f"{source}: {where}: must be > 0, got {x}")
    return x


def _xy_list(v: Any, source: str, where: str, min_len: int) -> np.ndarray:
    if not isinstance(v, list) or len(v) < min_len:
        raise InputError(f"{source}: {where}: expected a list of at least {min_len} [x, y] points")
    out = np.empty((len(v), 2))
    for j, p in enumerate(v):
        if not isinstance(p, (list, tuple)) or len(p) != 2:
            raise InputError(f"{source}: {where}[{j}]: expected [x, y], got {p!r}")
        out[j] = [_number(p[0], source, f"{where}[{j}]"), _number(p[1], source, f"{where}[{j}]")]
    return out


def _parse_wall(rw: Any, i: int, default_t: float, height: float, source: str) -> Wall:
    if not isinstance(rw, dict):
        raise InputError(f"{source}: walls[{i}]: expected a mapping with 'points'")
    wid = str(rw.get("id", f"walls[{i}]"))
    where = f"walls[{i}] (id {wid!r})"
    _no_unknown(rw, _WALL_KEYS, source, where)
    closed = bool(rw.get("closed", False))
    pts = _xy_list(rw.get("points"), source, f"{where}.points", 3 if closed else 2)
    if closed and np.allclose(pts[0], pts[-1]):
        pts = pts[:-1]  # tolerate a repeated closing point
    t = _positive(rw.get("thickness_m", default_t), source, f"{where}.thickness_m")
    wall = Wall(wid, pts, closed, t)
    lengths = []
    for k, (a, b) in enumerate(wall.segments()):
        length = float(np.hypot(*(b - a)))
        if length < _MIN_LENGTH_M:
            raise InputError(
                f"{source}: {where}: segment {k} from {a.tolist()} to {b.tolist()} has zero length"
            )
        lengths.append(length)
    line = LinearRing(pts) if closed else LineString(pts)
    if not line.is_simple:
        raise InputError(f"{source}: {where}: the wall polyline intersects itself")
    openings = []
    for j, ro in enumerate(rw.get("openings") or []):
        openings.append(_parse_opening(ro, j, wall, lengths, height, source, where))
    return Wall(wid, pts, closed, t, tuple(openings))


def _parse_opening(
    ro: Any, j: int, wall: Wall, lengths: list[float], height: float, source: str, wwhere: str
) -> Opening:
    if not isinstance(ro, dict):
        raise InputError(f"{source}: {wwhere}.openings[{j}]: expected a mapping")
    oid = str(ro.get("id", f"openings[{j}]"))
    where = f"{wwhere} opening {oid!r}"
    _no_unknown(ro, _OPENING_KEYS, source, where)
    kind = ro.get("kind", "door")
    if kind not in ("door", "window"):
        raise InputError(f"{source}: {where}: kind must be 'door' or 'window', got {kind!r}")
    seg = ro.get("segment", 0)
    if isinstance(seg, bool) or not isinstance(seg, int) or not 0 <= seg < len(lengths):
        raise InputError(
            f"{source}: {where}: segment must be an index 0..{len(lengths) - 1}, got {seg!r}"
        )
    offset = _number(ro.get("offset_m", 0.0), source, f"{where}.offset_m")
    width = _positive(ro.get("width_m"), source, f"{where}.width_m")
    if offset < 0 or offset + width > lengths[seg] + 1e-9:
        raise InputError(
            f"{source}: {where}: spans {offset:.3f}..{offset + width:.3f} m along segment {seg} "
            f"of length {lengths[seg]:.3f} m: the opening is wider than its wall"
        )
    if kind == "door":
        sill = _number(ro.get("sill_m", 0.0), source, f"{where}.sill_m")
        head = _number(ro.get("head_m", min(DOOR_HEAD_M, height)), source, f"{where}.head_m")
    else:
        if "sill_m" not in ro or "head_m" not in ro:
            raise InputError(f"{source}: {where}: a window needs sill_m and head_m")
        sill = _number(ro["sill_m"], source, f"{where}.sill_m")
        head = _number(ro["head_m"], source, f"{where}.head_m")
    if not 0 <= sill < head <= height:
        raise InputError(
            f"{source}: {where}: need 0 <= sill_m < head_m <= height_m ({height}), "
            f"got sill_m={sill}, head_m={head}"
        )
    return Opening(oid, kind, seg, offset, width, sill, head)


def _parse_furniture(rf: Any, i: int, height: float, source: str) -> Furniture:
    if not isinstance(rf, dict):
        raise InputError(f"{source}: furniture[{i}]: expected a mapping with center and size")
    fid = str(rf.get("id", f"furniture[{i}]"))
    where = f"furniture[{i}] (id {fid!r})"
    _no_unknown(rf, _FURNITURE_KEYS, source, where)
    c = rf.get("center")
    if not isinstance(c, list) or len(c) != 2:
        raise InputError(f"{source}: {where}.center: expected [x, y], got {c!r}")
    s = rf.get("size")
    if not isinstance(s, list) or len(s) != 3:
        raise InputError(f"{source}: {where}.size: expected [sx, sy, sz], got {s!r}")
    center = (_number(c[0], source, where), _number(c[1], source, where))
    size = tuple(_positive(v, source, f"{where}.size") for v in s)
    z0 = _number(rf.get("z_min_m", 0.0), source, f"{where}.z_min_m")
    if z0 < 0 or z0 + size[2] > height + 1e-9:
        raise InputError(
            f"{source}: {where}: spans z {z0}..{z0 + size[2]} m, outside floor..ceiling 0..{height}"
        )
    yaw = math.radians(_number(rf.get("yaw_deg", 0.0), source, f"{where}.yaw_deg"))
    legs = _number(rf.get("legs_m", 0.0), source, f"{where}.legs_m")
    if legs < 0 or (legs > 0 and (2 * legs > min(size[:2]) or size[2] <= TABLE_TOP_M)):
        raise InputError(
            f"{source}: {where}.legs_m: expected 0 (a box) or a leg side > 0 with two legs "
            f"fitting across the {size[0]} x {size[1]} m top and a height over the "
            f"{TABLE_TOP_M} m top, got {legs}"
        )
    return Furniture(fid, center, size, yaw, z0, legs)  # type: ignore[arg-type]


def _parse_waypoints(v: Any, source: str) -> np.ndarray:
    return _xy_list(v, source, "waypoints", 2)


# --------------------------------------------------------------------------- geometry


def wall_polygon(wall: Wall) -> Polygon:
    """The full-height footprint of one wall (no openings): its axis buffered.

    Parameters
    ----------
    wall : Wall

    Returns
    -------
    shapely Polygon
        Flat ends, mitred joins, metres.
    """
    line = LinearRing(wall.points) if wall.closed else LineString(wall.points)
    return line.buffer(wall.thickness_m / 2, cap_style="flat", join_style="mitre", mitre_limit=10)


def opening_polygon(wall: Wall, op: Opening) -> Polygon:
    """The 2D cutter of an opening: a rectangle along its segment, across the wall.

    It reaches ``_CUT_MARGIN_M`` beyond each face of the wall.
    """
    a, b = wall.segments()[op.segment]
    u = (b - a) / np.hypot(*(b - a))
    n = np.array([-u[1], u[0]])
    half = wall.thickness_m / 2 + _CUT_MARGIN_M
    p0 = a + u * op.offset_m
    p1 = a + u * (op.offset_m + op.width_m)
    return Polygon([p0 - n * half, p1 - n * half, p1 + n * half, p0 + n * half])


def walls_union(building: Building) -> Polygon:
    """Union of all wall footprints without openings (metres)."""
    return unary_union([wall_polygon(w) for w in building.walls])


def wall_footprint(building: Building, z: float):
    """The walls cut by a horizontal plane at height ``z`` (metres above the floor).

    Openings with ``sill_m <= z < head_m`` are gaps.

    Parameters
    ----------
    building : Building
    z : float
        Height above the floor, metres, ``0 <= z < height_m``.

    Returns
    -------
    shapely Polygon or MultiPolygon
    """
    cuts = [
        opening_polygon(w, op)
        for w in building.walls
        for op in w.openings
        if op.sill_m <= z < op.head_m
    ]
    fp = walls_union(building)
    if cuts:
        fp = fp.difference(unary_union(cuts))
    return fp


def building_outline(building: Building):
    """The filled outline of the walls (their union with the enclosed rooms)."""
    parts = getattr(walls_union(building), "geoms", [walls_union(building)])
    return unary_union([Polygon(p.exterior) for p in parts])


def _extrude(poly, z0: float, z1: float) -> list[trimesh.Trimesh]:
    parts = getattr(poly, "geoms", [poly])
    out = []
    for p in parts:
        if p.is_empty or p.area <= 0:
            continue
        m = trimesh.creation.extrude_polygon(p, z1 - z0)
        m.apply_translation([0.0, 0.0, z0])
        out.append(m)
    return out


def _furniture_meshes(f: Furniture) -> list[trimesh.Trimesh]:
    z0, z1 = f.z_min_m, f.z_min_m + f.size[2]
    if f.legs_m <= 0:
        return _extrude(f.footprint(), z0, z1)
    top = _extrude(f.footprint(), z1 - TABLE_TOP_M, z1)
    # legs reach 1 mm into the top so the union is one solid
    return top + [m for leg in f.legs() for m in _extrude(leg, z0, z1 - TABLE_TOP_M + 1e-3)]


def wall_mesh(building: Building) -> trimesh.Trimesh:
    """The walls as one closed triangle mesh: footprints extruded, openings cut out.

    Uses manifold3d booleans (via trimesh) to subtract each opening's prism (its 2D
    cutter from :func:`opening_polygon`, from ``sill_m`` to ``head_m``; doors start
    below the floor) from the extruded wall footprints.

    Returns
    -------
    trimesh.Trimesh
        Watertight, metres, z up, floor at z = 0.
    """
    solid = _extrude(walls_union(building), 0.0, building.height_m)
    cutters = []
    for w in building.walls:
        for op in w.openings:
            z0 = -_CUT_MARGIN_M if op.sill_m <= 0 else op.sill_m
            z1 = op.head_m + (_CUT_MARGIN_M if op.head_m >= building.height_m else 0.0)
            cutters += _extrude(opening_polygon(w, op), z0, z1)
    return _boolean(solid, "add") if not cutters else _boolean(
        [_boolean(solid, "add"), *cutters], "subtract"
    )


def _boolean(meshes: list[trimesh.Trimesh], op: str) -> trimesh.Trimesh:
    """Union ("add") or difference ("subtract": head minus the rest) with manifold3d,
    in float64 (trimesh's manifold engine rounds vertices to float32)."""
    if len(meshes) == 1:
        return meshes[0]
    from manifold3d import Manifold, Mesh64, OpType

    ms = [
        Manifold(
            mesh=Mesh64(
                vert_properties=np.array(m.vertices, dtype=np.float64, order="C"),
                tri_verts=np.array(m.faces, dtype=np.uint64, order="C"),
            )
        )
        for m in meshes
    ]
    out = Manifold.batch_boolean(ms, OpType.Add if op == "add" else OpType.Subtract).to_mesh64()
    return trimesh.Trimesh(
        vertices=np.asarray(out.vert_properties)[:, :3],
        faces=np.asarray(out.tri_verts, dtype=np.int64),
        process=False,
    )


def building_mesh(building: Building) -> trimesh.Trimesh:
    """The whole building: walls with openings, furniture, floor and ceiling slabs.

    The floor slab spans z in [-SLAB_THICKNESS_M, 0] and the ceiling slab
    [height_m, height_m + SLAB_THICKNESS_M] under and over :func:`building_outline`.
    All solids are united with manifold3d, so a horizontal section gives clean
    polygons (thesis 5.2: a slice of the model is the floor plan).

    Returns
    -------
    trimesh.Trimesh
        Watertight triangle mesh, metres.
    """
    parts = [wall_mesh(building)]
    parts += [m for f in building.furniture for m in _furniture_meshes(f)]
    outline = building_outline(building)
    if building.floor:
        parts += _extrude(outline, -SLAB_THICKNESS_M, 0.0)
    if building.ceiling:
        parts += _extrude(outline, building.height_m, building.height_m + SLAB_THICKNESS_M)
    return _boolean(parts, "add")


def mesh_section(mesh: trimesh.Trimesh, z: float):
    """A horizontal section of a closed mesh at height ``z`` as 2D polygons.

    Parameters
    ----------
    mesh : trimesh.Trimesh
        A closed mesh, metres.
    z : float
        Height of the cutting plane, metres.

    Returns
    -------
    shapely Polygon or MultiPolygon
        The region inside the mesh at ``z`` (even-odd rule over the section's loops).
    """
    segs = trimesh.intersections.mesh_plane(mesh, [0.0, 0.0, 1.0], [0.0, 0.0, z])
    if len(segs) == 0:
        return Polygon()
    segs = np.round(segs[:, :, :2], 9)
    # node the segments first: a section can have T-junctions where triangles meet
    lines = unary_union(MultiLineString(list(segs)))
    loops = [Polygon(p.exterior) for p in polygonize(lines)]
    if not loops:
        return Polygon()
    return reduce(lambda a, b: a.symmetric_difference(b), loops)


# --------------------------------------------------------------------------- ground truth


def _straight_edges(ring) -> list[tuple[np.ndarray, np.ndarray]]:
    """Maximal straight edges of a closed ring (collinear vertices merged)."""
    pts = np.asarray(ring.coords)[:-1]
    if len(pts) < 3:
        return []
    keep = []
    n = len(pts)
    for i in range(n):
        a, b, c = pts[i - 1], pts[i], pts[(i + 1) % n]
        cross = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0])
        scale = np.hypot(*(b - a)) * np.hypot(*(c - b))
        if scale == 0 or abs(cross) > 1e-9 * max(scale, 1e-12):
            keep.append(b)
    keep = np.asarray(keep)
    return [(keep[i], keep[(i + 1) % len(keep)]) for i in range(len(keep))]


def wall_faces(building: Building, z: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """The wall surfaces a scanner inside the building can see, at height ``z``.

    Every straight edge of :func:`wall_footprint` at ``z`` is a face, except the outside
    of the building: edges whose outward side lies outside the filled outline of a wall
    ring that encloses rooms. Door jambs (reveals) are faces.

    Parameters
    ----------
    building : Building
    z : float
        Slice height, metres.

    Returns
    -------
    list of ((2,), (2,)) float64 ndarray pairs
        Face segments (start, end), metres, map frame.
    """
    fp = wall_footprint(building, z)
    enclosing = [p for p in getattr(walls_union(building), "geoms", [walls_union(building)])
                 if len(p.interiors) > 0]
    outside_ok = unary_union([Polygon(p.exterior) for p in enclosing]) if enclosing else None
    faces = []
    for poly in getattr(fp, "geoms", [fp]):
        poly = shapely.geometry.polygon.orient(poly, 1.0)  # CCW exterior: material on the left
        for ring in [poly.exterior, *poly.interiors]:
            for a, b in _straight_edges(ring):
                d = b - a
                length = np.hypot(*d)
                if length < 1e-6:
                    continue
                normal = np.array([d[1], -d[0]]) / length  # right side: away from material
                probe = Point(*((a + b) / 2 + normal * 1e-3))
                if outside_ok is not None and not outside_ok.contains(probe):
                    continue
                faces.append((a.copy(), b.copy()))
    return faces


#: A face sample is observed when a return lies within this plan distance, metres.
OBSERVED_RADIUS_M = 0.05
#: Unobserved runs of a face shorter than this between observed samples count as
#: observed (the gaps between beams far away), metres.
OBSERVED_BRIDGE_M = 0.20
#: Spacing of the face samples tested for observation, metres.
OBSERVED_STEP_M = 0.01


def observed_faces(
    faces, points_xy: np.ndarray, radius_m: float = OBSERVED_RADIUS_M,
    bridge_m: float = OBSERVED_BRIDGE_M, step_m: float = OBSERVED_STEP_M,
) -> list[tuple[np.ndarray, np.ndarray]]:
    """The parts of the wall faces that a recording's returns lie on.

    Thesis 5.2: "some walls, although they are present in the CAD model of the
    building in simulation, are never visible from the point of view of the LIDAR".
    No method recovers a wall it never saw, so recall is scored against the observed
    parts (the denominator of completeness, as the ISPRS indoor benchmark restricts
    its reference to the surveyed area); the whole faces stay in the ground truth.

    Each face is sampled every ``step_m``; a sample is observed when a return lies
    within ``radius_m`` of it in the plan; unobserved runs shorter than ``bridge_m``
    between observed samples are filled; each remaining run is a segment.

    Parameters
    ----------
    faces : list of ((2,), (2,)) ndarray pairs
        Wall faces (:func:`wall_faces`), metres.
    points_xy : (N, 2) float ndarray
        Plan positions of the returns (map frame, metres), e.g. deduplicated on a
        1 cm grid.
    radius_m, bridge_m, step_m : float
        Metres.

    Returns
    -------
    list of ((2,), (2,)) float64 ndarray pairs
        Observed face segments, in face order.
    """
    from scipy.spatial import cKDTree

    pts = np.asarray(points_xy, dtype=np.float64).reshape(-1, 2)
    if len(pts) == 0:
        return []
    tree = cKDTree(pts)
    out = []
    for a, b in faces:
        a, b = np.asarray(a, float), np.asarray(b, float)
        length = float(np.hypot(*(b - a)))
        n = max(2, int(math.ceil(length / step_m)) + 1)
        s = np.linspace(0.0, 1.0, n)
        samples = a + s[:, None] * (b - a)
        d, _ = tree.query(samples, distance_upper_bound=radius_m)
        seen = np.isfinite(d)
        if not seen.any():
            continue
        idx = np.flatnonzero(seen)
        # fill short unobserved runs between observed samples
        gaps = np.flatnonzero(np.diff(idx) > 1)
        for g in gaps:
            if (idx[g + 1] - idx[g]) * length / (n - 1) < bridge_m:
                seen[idx[g]: idx[g + 1]] = True
        edges = np.diff(np.r_[0, seen.astype(np.int8), 0])
        for i0, i1 in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1):
            if i1 > i0:
                out.append((samples[i0].copy(), samples[i1].copy()))
    return out


def ground_truth_walls(
    building: Building, slice_height_m: float, observed_xy: np.ndarray | None = None
) -> dict:
    """The ground-truth walls as a GeoJSON FeatureCollection (metres, map frame).

    Features carry ``kind``:

    - ``face``: LineString, a straight wall surface a scanner can see at the slice
      height (:func:`wall_faces`); the scoring reference.
    - ``axis``: LineString, one per wall polyline segment: its centre line, with
      ``wall``, ``thickness_m`` and ``height_m``.
    - ``footprint``: Polygon, the walls cut at the slice height (:func:`wall_footprint`).
    - ``observed_face``: LineString, the parts of the faces the recording's returns lie
      on (:func:`observed_faces`), when ``observed_xy`` is given; the reference of
      recall in scoring.

    Parameters
    ----------
    building : Building
    slice_height_m : float
        Height of the horizontal slice, metres (the 2D scanner's height, so doors are
        gaps and windows with a sill above it are walls; thesis 5.2).
    observed_xy : (N, 2) float ndarray, optional
        Plan positions of the recording's returns (map frame, metres).

    Returns
    -------
    dict
        GeoJSON FeatureCollection with the foreign members ``building`` and
        ``slice_height_m``.

    Raises
    ------
    ValueError
        When ``slice_height_m`` is not inside (0, height_m).
    """
    if not 0 < slice_height_m < building.height_m:
        raise ValueError(
            f"slice height {slice_height_m} m must be between floor and ceiling "
            f"(0, {building.height_m}) of {building.source}"
        )
    feats: list[dict] = []
    faces = wall_faces(building, slice_height_m)
    for i, (a, b) in enumerate(faces):
        feats.append(_feature("LineString", [_xy(a), _xy(b)], kind="face", id=f"face{i}"))
    if observed_xy is not None:
        for i, (a, b) in enumerate(observed_faces(faces, observed_xy)):
            feats.append(
                _feature("LineString", [_xy(a), _xy(b)], kind="observed_face", id=f"observed{i}")
            )
    for w in building.walls:
        for k, (a, b) in enumerate(w.segments()):
            feats.append(
                _feature(
                    "LineString", [_xy(a), _xy(b)], kind="axis", wall=w.id, segment=k,
                    thickness_m=w.thickness_m, height_m=building.height_m,
                )
            )
    fp = wall_footprint(building, slice_height_m)
    for j, poly in enumerate(getattr(fp, "geoms", [fp])):
        poly = shapely.geometry.polygon.orient(poly, 1.0)
        rings = [[_xy(p) for p in r.coords] for r in [poly.exterior, *poly.interiors]]
        feats.append(_feature("Polygon", rings, kind="footprint", id=f"footprint{j}"))
    return {
        "type": "FeatureCollection",
        "building": building.name,
        "slice_height_m": float(slice_height_m),
        "features": feats,
    }


def _xy(p) -> list[float]:
    return [round(float(p[0]), 9), round(float(p[1]), 9)]


def _feature(gtype: str, coords: list, **props) -> dict:
    return {"type": "Feature", "geometry": {"type": gtype, "coordinates": coords}, "properties": props}


# --------------------------------------------------------------------------- the rover path


def obstacles_at_floor(building: Building):
    """What the rover cannot drive through: walls at floor level (doors open) and
    furniture standing on the floor (``z_min_m`` below 0.05 m)."""
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

"""Read and check a building file (its format: :mod:`floorscan.sim.building`).

:func:`load_building` reads the YAML file; :func:`parse_building` checks a mapping
already loaded and builds the :class:`~floorscan.sim.building.Building`. Every error is
an ``InputError`` naming the file and the element (``walls[0] (id 'outer') opening
'entrance'``): unknown keys, a zero-length or self-intersecting wall, an opening wider
than its wall segment or above the ceiling, furniture outside floor..ceiling, and a
waypoint or a leg of the rover's path inside a wall or furniture
(:func:`floorscan.sim.obstacles.check_path`). A new key is added to its element's key
set below and read in its ``_parse_*`` function.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from shapely.geometry import LineString, LinearRing

from floorscan.core.io import InputError
from floorscan.sim.building import DOOR_HEAD_M, TABLE_TOP_M, Building, Furniture, Opening, Wall
from floorscan.sim.obstacles import check_path

#: Wall segments shorter than this (m) are "zero length".
_MIN_LENGTH_M = 1e-6

_TOP_KEYS = {
    "name", "description", "height_m", "wall_thickness_m", "floor", "ceiling", "walls",
    "furniture", "waypoints",
}
_WALL_KEYS = {"id", "points", "closed", "thickness_m", "openings"}
_OPENING_KEYS = {"id", "kind", "segment", "offset_m", "width_m", "sill_m", "head_m"}
_FURNITURE_KEYS = {"id", "center", "size", "yaw_deg", "z_min_m", "legs_m"}


def load_building(path: str | Path) -> Building:
    """Read and validate a building YAML file.

    Parameters
    ----------
    path : str or Path
        The building file (format: :mod:`floorscan.sim.building`).

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
        The mapping described in :mod:`floorscan.sim.building`.
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

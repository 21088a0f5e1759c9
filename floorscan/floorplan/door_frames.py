"""A door's frame (:func:`framed_doors`): a door's opening is the part of its line the
free space crosses, and the cells between a jamb and the wall the line reaches, seen
occupied, are the wall that holds the jamb.

A door is an opening in a wall, and the wall goes on across it (issue 44's layout: a
door is an opening in the edge between two rooms). The room step
(:mod:`floorscan.floorplan.rooms`) draws each door between the ends of the walls in its
line, or from a wall's end to the face of the wall its line meets. Where the piece of
wall between a jamb and that wall is shorter than the shortest wall the structure
passes keep on their own (``min_wall_length_m``), they may lose it: traced on a map
turned by any angle, a 0.3 m stub beside a door is two faces of six cells, and one of
them goes missing at some poses. The door then runs on over the stub's cells to the
wall's face, and the plan has one wall fewer (the rigid-motion property of
``tests/test_plan_properties.py``). The cells tell the two apart: a door's opening is
free, a stub's cells are occupied.

So each end of a door is cut back over the stretch of its line that is not free and
mostly occupied (a stretch only unseen, beside a jamb the rays missed, stays in the
door); a line is free where the cells across the door's wall's thickness all are, so
that a line a fit turned by a few degrees still reads the opening and the stub. Then,
from each jamb that no wall of the plan ends at or passes, the line is followed
outward: where it reaches a wall's footprint within ``min_wall_length_m`` (and
:data:`LENGTH_CELLS` cells: the structure passes may have lost a piece that long), over cells
none free and mostly occupied, that stretch is wall. A wall of the door's line that the
line reaches (the door's own wall beyond a crossing, or another piece of it), or that
ends at the crossing with the wall across the line it reaches (more than
``door_angle_deg`` off it), goes on to the jamb, as the wall runs on across the
crossing at another pose; else the stretch is a new wall of the door's wall's thickness
from the axis of the wall across to the jamb (a T or an L); two such walls that meet one
wall from its two sides in one line, a door on either side of a crossing, are one wall
from jamb to jamb across it (an X), as a map turned by another angle traces it.

An opening that is no door between two rooms has the same frame, and so has a door
before the rooms are cut (:func:`framed_openings`, the step before the room step): the
entrance in the outline, whose far side is the outside, is no door, and the stub beside
it went missing at some poses as a door's does. From each end of a wall that meets no
other wall, the wall tied into the plan at its other end (a wall free at both ends is a
piece of furniture or a fragment, whose ends frame nothing), its line is followed to the
first wall it reaches; where a free run (the opening, ``door_min_m`` to
``door_max_m``, starting at the wall's end) ends at a jamb with a stretch of wall cells
beyond, as above, that stretch is a wall. The stub is then a wall when the room step
draws the door, so the door runs from jamb to jamb, not on a slant beside the stub. A
new wall must stand out of the wall it meets by two cells beyond its face
(:data:`MIN_RUN`): a line that meets a wall at a slant crosses the wall's own cells
first. A wall goes on to a jamb only to grow longer.
"""

from __future__ import annotations

import numpy as np

from floorscan.core.geometry import point_segment_dist2
from floorscan.core.occupancy import OccupancyGrid
from floorscan.floorplan.doors import footprint_distance, junction_end, wall_units
from floorscan.floorplan.free_space import mask_at, passable, segment_samples
from floorscan.floorplan.room_space import RoomParams

#: A stretch of a door's line is cut from the door, or is a stub, when at least this many
#: half cells long (two cells): a door's end is known to a cell either way, so a shorter
#: stretch is the rounding of its jamb.
MIN_RUN = 4
#: A stub up to ``min_wall_length_m`` and this many cells longer is framed: each end of
#: a face traced on a turned map is known to a cell, so a piece of wall that long may
#: have fallen under ``min_wall_length_m`` in the structure passes.
LENGTH_CELLS = 2


def framed_doors(doors: np.ndarray, door_wall: np.ndarray, axes: np.ndarray, thickness: np.ndarray,
                 grid: OccupancyGrid, params: RoomParams, min_wall_length_m: float
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The doors cut back to the free run of their lines, and the walls that frame them
    (module docstring).

    Parameters
    ----------
    doors : (D, 4) float ndarray
        Each door's opening ``x0, y0, x1, y1``, metres.
    door_wall : (D,) int ndarray
        The wall in whose line each door lies (an index into ``axes``), -1 for none.
    axes : (N, 4) float ndarray
        The plan's wall axes, metres.
    thickness : (N,) float ndarray
        Metres.
    grid : OccupancyGrid
        The free and occupied cells of the plan's scans, or of its map.
    params : RoomParams
        ``door_min_m``: a door whose opening would be narrower stays as it is;
        ``door_angle_deg``: a wall more than this off a door's line stands across it.
    min_wall_length_m : float
        The longest stub framed, metres (the structure passes' shortest wall).

    Returns
    -------
    doors : (D, 4) float64 ndarray
        The openings, cut back.
    axes : (N, 4) float64 ndarray
        The walls, a wall of a door's line that ends at a crossing gone on across it to
        the jamb beyond.
    stubs : (K, 4) float64 ndarray
        The new walls' axes, from the axis of the wall they meet to the jamb, or from
        jamb to jamb across it (a door on either side of a crossing), metres.
    stub_thickness : (K,) float64 ndarray
        Metres (the door's wall's).
    stub_meets : (K,) int64 ndarray
        The wall each stub meets (an index into ``axes``).
    """
    doors = np.asarray(doors, dtype=np.float64).reshape(-1, 4).copy()
    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4).copy()
    thickness = np.asarray(thickness, dtype=np.float64).reshape(-1)
    none = (doors, axes, np.zeros((0, 4)), np.zeros(0), np.zeros(0, dtype=np.int64))
    if not len(doors) or not len(axes):
        return none
    free, occupied = passable(grid), grid.occupied()
    step = grid.resolution_m / 2
    u_axes, _ = wall_units(axes)
    new = []  # (axis, thickness, the wall it meets) of each new wall
    for d in range(len(doors)):
        w = int(door_wall[d])
        if w < 0:
            continue
        p, q = doors[d, :2], doors[d, 2:]
        width = float(np.hypot(*(q - p)))
        if width <= 0:
            continue
        u = (q - p) / width
        xy, _, _ = segment_samples(doors[d : d + 1], step)  # the middles of n equal pieces
        n = len(xy)
        band = _band(u, thickness[w], grid.resolution_m)
        is_free = _all_free(xy, band, grid, free)
        if not is_free.any():
            continue
        first, last = int(np.argmax(is_free)), n - 1 - int(np.argmax(is_free[::-1]))
        # a door's end is cut back over the cells of a wall only: a stretch not free that
        # is mostly occupied (a stretch only unseen, beside a jamb the rays missed, stays)
        if first < MIN_RUN or _any_occupied(xy[:first], band, grid, occupied).mean() < 0.5:
            first = 0
        if n - 1 - last < MIN_RUN or _any_occupied(xy[last + 1:], band, grid, occupied).mean() < 0.5:
            last = n - 1
        a, b = first * width / n, (last + 1) * width / n  # the opening's ends along the line
        if b - a < params.door_min_m:
            continue
        jambs = [(p + u * a, -u), (p + u * b, u)]  # each jamb, and outward from the opening
        doors[d] = np.r_[jambs[0][0], jambs[1][0]]
        for jamb, out in jambs:
            _frame(jamb, out, band, w, axes, u_axes, thickness, grid, free, occupied, min_wall_length_m,
                   params.door_angle_deg, new)
    return (doors, axes, *_across(*_arrays(new), grid.resolution_m, params.door_angle_deg))


def framed_openings(axes: np.ndarray, thickness: np.ndarray, grid: OccupancyGrid, params: RoomParams,
                    min_wall_length_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The walls that frame the openings at the walls' free ends (module docstring).

    Parameters
    ----------
    axes, thickness, grid, params, min_wall_length_m
        As :func:`framed_doors`.

    Returns
    -------
    axes, stubs, stub_thickness, stub_meets
        As :func:`framed_doors`; a stub's thickness is that of the wall whose end its
        opening starts at.
    """
    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4).copy()
    thickness = np.asarray(thickness, dtype=np.float64).reshape(-1)
    u_axes, _ = wall_units(axes)
    free, occupied = passable(grid), grid.occupied()
    new = []
    for i in range(len(axes)):
        for k in (0, 1):
            # an end that meets no wall, of a wall tied into the plan at its other end
            if junction_end(axes, thickness, i, k) or not junction_end(axes, thickness, i, 1 - k):
                continue
            u = u_axes[i] if k == 1 else -u_axes[i]
            jamb = _opening(axes[i, 2 * k: 2 * k + 2], u, i, axes, thickness, grid, free, params, min_wall_length_m)
            if jamb is not None:
                _frame(jamb, u, _band(u, thickness[i], grid.resolution_m), i, axes, u_axes, thickness, grid, free,
                       occupied, min_wall_length_m, params.door_angle_deg, new)
    return (axes, *_across(*_arrays(new), grid.resolution_m, params.door_angle_deg))


def _across(stubs, stub_t, meets, resolution_m, angle_deg):
    """The new walls (:func:`_arrays`) with each two that meet one wall at one point
    (within a cell) from its two sides, in one line (within ``angle_deg`` of it), made
    one wall from jamb to jamb across it: the wall a map turned by another angle traces
    through the crossing (module docstring)."""
    u, _ = wall_units(stubs)
    stubs, stub_t, keep = stubs.copy(), stub_t.copy(), np.ones(len(stubs), dtype=bool)
    for i in range(len(stubs)):
        for j in range(i + 1, len(stubs)):
            if (keep[i] and keep[j] and meets[j] == meets[i] and float(u[i] @ u[j]) <= -np.cos(np.radians(angle_deg))
                    and np.hypot(*(stubs[j, :2] - stubs[i, :2])) <= resolution_m):
                stubs[i], stub_t[i], keep[j] = np.r_[stubs[j, 2:], stubs[i, 2:]], max(stub_t[i], stub_t[j]), False
                break
    return stubs[keep], stub_t[keep], meets[keep]


def _arrays(new):
    """The axes (K, 4), thicknesses (K,) and walls met (K,) of :func:`_frame`'s list."""
    return (np.reshape([stub for stub, _, _ in new], (-1, 4)).astype(np.float64),
            np.array([t for _, t, _ in new], dtype=np.float64), np.array([m for _, _, m in new], dtype=np.int64))


def _frame(jamb, out, band, w, axes, u_axes, thickness, grid, free, occupied, max_m, angle_deg, new) -> None:
    """The wall between the jamb ``jamb`` of an opening in the line of wall ``w`` and
    the wall its line reaches outward along ``out`` (:func:`_stub`): a wall that goes on
    to the jamb (``axes`` changed in place), or a new wall of ``w``'s thickness appended
    to ``new`` as ``(axis, thickness, the wall it meets)``."""
    stub = _stub(jamb, out, band, axes, u_axes, thickness, grid, free, occupied, max_m, angle_deg)
    if stub is None:
        return
    if stub[2] >= 0:  # the wall beyond the crossing goes on to the jamb: longer, never turned back
        k = 2 * stub[2]
        end, other = axes[stub[1], k: k + 2], axes[stub[1], 2 - k: 4 - k]
        if (jamb - other) @ (end - other) > 0 and np.hypot(*(jamb - other)) > np.hypot(*(end - other)):
            axes[stub[1], k: k + 2] = jamb
    else:
        new.append((stub[0], float(thickness[w]), int(stub[1])))


def _opening(end, u, i, axes, thickness, grid, free, params: RoomParams, max_m: float):
    """The far jamb ((2,) metres) of the opening along wall ``i``'s line from its end
    ``end`` outward along ``u``: the run of free cells that starts at the end (to a
    :data:`MIN_RUN`) and is ``door_min_m`` to ``door_max_m`` long, the last run before
    the line reaches another wall's footprint (within ``door_max_m``, ``max_m`` and the
    thickest wall). None when there is none."""
    r = grid.resolution_m
    step = r / 2
    reach = params.door_max_m + max_m + float(thickness.max(initial=0.0))
    xy = end + u * (np.arange(1, int(np.ceil(reach / step)) + 1) * step)[:, None]
    others = np.delete(np.arange(len(axes)), i)
    # within half a cell: the samples are half a cell apart, and a line that passes a wall's end comes no closer
    reached = (_footprint_gaps(xy, axes[others], thickness[others]) <= r / 2).any(axis=1)
    if not reached.any():
        return None
    line = xy[: int(np.argmax(reached))]
    is_free = _all_free(line, _band(u, thickness[i], r), grid, free)
    if not is_free.any():
        return None
    last = len(line) - 1 - int(np.argmax(is_free[::-1]))
    first = last
    while first > 0 and is_free[first - 1]:
        first -= 1
    if first >= MIN_RUN or not params.door_min_m <= (last + 1.5) * step <= params.door_max_m:
        return None
    return end + u * (last + 1.5) * step  # between the last free sample and the next


def _footprint_gaps(xy, axes, thickness):
    """(S, N) metres from each point ``xy`` (S, 2) to each wall's footprint
    (:func:`~floorscan.floorplan.doors.footprint_distance`, all points at once)."""
    return np.sqrt(point_segment_dist2(xy[:, :1], xy[:, 1:], axes)) - thickness / 2


def _band(u, thickness_m, resolution_m):
    """(3, 2): offsets across a door's line (unit ``u``), to its wall's two faces and its
    axis, at least half a cell out: a line a fit turned by a few degrees still covers
    the opening or the stub across its wall's thickness."""
    half = max(thickness_m / 2, resolution_m / 2)
    nrm = np.array([-u[1], u[0]])
    return np.array([-half, 0.0, half])[:, None] * nrm


def _all_free(xy, band, grid, free):
    """(N,) bool: the points ``xy`` whose band is free across (the opening)."""
    return np.all([mask_at(grid, free, xy + off) for off in band], axis=0)


def _any_occupied(xy, band, grid, occupied):
    """(N,) bool: the points ``xy`` whose band holds an occupied cell (a wall's cells)."""
    return np.any([mask_at(grid, occupied, xy + off) for off in band], axis=0)


def _stub(jamb, out, band, axes, u_axes, thickness, grid, free, occupied, max_m, angle_deg):
    """The wall from the jamb ``jamb`` outward along ``out`` to the first wall whose
    footprint the line reaches: ``(axis, wall, end)``, the axis ((4,) metres) from the
    wall reached to the jamb. Where that wall is one of the door's line (the door's own
    wall beyond a crossing, or another piece of it), or where the wall is across the
    line and a wall of the line ends at that crossing on its far side, that wall and its
    end (0 or 1), which goes on to the jamb; else the wall across, which the new wall
    meets, and -1. None when a wall of the plan ends at the jamb or passes it, or when
    the run up to the wall reached is not all occupied or longer than ``max_m``."""
    r = grid.resolution_m
    if (footprint_distance(jamb, axes, thickness) <= 2 * r).any():
        return None  # a wall of the plan ends at the jamb or passes it (each known to a cell): the jamb is held
    max_m += LENGTH_CELLS * r  # a stub the structure passes may have lost, measured a cell short at each end
    across = np.abs(out[0] * u_axes[:, 1] - out[1] * u_axes[:, 0]) > np.sin(np.radians(angle_deg))
    ts = np.arange(1, int(np.ceil(max_m / (r / 2))) + 1) * (r / 2)
    xy = jamb + out * ts[:, None]
    gaps = _footprint_gaps(xy, axes, thickness)
    reaching = (gaps <= r / 4).any(axis=1)  # a quarter cell: the sampling's rounding
    if not reaching.any():
        return None
    k = int(np.argmax(reaching))  # the first sample on a wall's footprint
    reached = gaps[k] <= r / 4
    run = xy[:k]
    if (len(run) < MIN_RUN or _all_free(run, band, grid, free).any()
            or _any_occupied(run, band, grid, occupied).mean() < 0.5):
        return None
    hits = np.flatnonzero(reached & across)
    if len(hits):  # onto the axis of the wall across the line
        hit = int(hits[np.argmin(gaps[k, hits])])
        v = u_axes[hit]
        rel = axes[hit, :2] - jamb
        end = jamb + out * (rel[0] * v[1] - rel[1] * v[0]) / (out[0] * v[1] - out[1] * v[0])
    else:  # the end of a wall in the line: it goes on to the jamb
        hit = int(np.flatnonzero(reached)[0])
        ends = axes[hit].reshape(2, 2)
        e = int(np.argmin(np.hypot(*(ends - jamb).T)))
        if float(np.hypot(*(ends[e] - jamb))) > max_m + thickness[hit]:
            return None
        return np.r_[ends[e], jamb], hit, e
    if float(np.hypot(*(end - jamb))) > max_m + thickness[hit]:
        return None
    # the stub stands out of the wall across beyond its face (a line that meets the
    # wall at a slant runs over the wall's own cells first)
    if abs(float((jamb - end) @ np.array([-v[1], v[0]]))) - thickness[hit] / 2 < MIN_RUN * r / 2:
        return None
    # a wall of the door's line that ends at that crossing, beyond it, goes on to the jamb
    lined = np.flatnonzero(~across)
    if len(lined):
        ends = axes[lined].reshape(-1, 2, 2)
        gap = np.hypot(*(ends - end).transpose(2, 0, 1))
        i, e = np.unravel_index(int(np.argmin(gap)), gap.shape)
        if gap[i, e] <= thickness[hit] / 2 + r:
            return np.r_[end, jamb], int(lined[i]), int(e)
    return np.r_[end, jamb], hit, -1

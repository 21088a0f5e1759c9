"""Rooms and doors as one global layout (issue 44's candidate): the plan's walls and the
map's own wall lines extended into a cell complex, its cells labelled inside or outside
by the free space, then grouped into rooms by the evidence of a wall on the boundaries
between them.

The formulation is that of the cell-complex methods of the field: the floor partitioned
by the lines of the walls, each cell labelled, the rooms the groups of cells no wall
divides (ROSE^2: Luperto et al., "Robust structure identification and room
segmentation of cluttered indoor environments from occupancy grid maps", RA-L 2022;
Mura et al., "Automatic room detection and reconstruction in cluttered indoor
environments with complex room layouts", Computers & Graphics 2014; Ochmann et al.,
ISPRS J. 2019). :func:`layout_rooms` runs the steps in order, one module each:

1. **Hypotheses** (:mod:`floorscan.floorplan.hypotheses`): the wall axes on the
   dominant directions, junctions closed, free ends extended to the next wall; an
   extension no longer than ``door_max_m`` closes an opening. Then the grid's own
   walls (:mod:`floorscan.floorplan.representative_lines`): the lines on which its
   occupied cells gather, on the same directions, extended across the frame, and the
   openings between their runs of wall closed (the walls the plan lacks: a map's
   dashed, faint or blurred walls).
2. **Arrangement** (:mod:`floorscan.floorplan.arrangement`): the lines noded and
   polygonised on a fixed precision grid; each edge's evidence of a boundary (a wall, a
   closed opening, or the grid's occupied cells along it) and each cell's free share.
3. **Labelling** (:mod:`floorscan.floorplan.labelling`): inside or outside by the free
   share, then rooms by agglomerative merging, the longest open boundary first, while
   the boundary between two regions is more opening than wall.
4. **Rooms and doors** (here): each room the union of its cells less the wall footprints
   and the door openings (its floor area, furniture included; the walls may part a
   region into several rooms), in reading order; a door each closed opening
   ``door_min_m`` to ``door_max_m`` wide between two different rooms that the free space
   crosses.

The rooms are a coverage: cells do not overlap, so neither do rooms. Today's room step
(:mod:`floorscan.floorplan.rooms`) is still the plan's; ``python -m benchmarks rooms
--rooms layout`` measures this one beside it.
"""

from __future__ import annotations

import logging

import numpy as np

from floorscan.core.occupancy import OccupancyGrid
from floorscan.floorplan.arrangement import PRECISION_M, cell_free_share, layout_cells
from floorscan.floorplan.hypotheses import CLOSED, OPEN, layout_lines
from floorscan.floorplan.labelling import INSIDE_SHARE, group_cells
from floorscan.floorplan.representative_lines import map_hypotheses
from floorscan.floorplan.room_space import wall_footprints

log = logging.getLogger(__name__)

#: The frame around the free space, metres (the outside of every map and recording).
FRAME_MARGIN_M = 1.0


def layout_rooms(axes: np.ndarray, thickness: np.ndarray, grid: OccupancyGrid, params, hypotheses=None):
    """The rooms and doors of a plan as one layout (the module docstring).

    Parameters
    ----------
    axes : (N, 4) float ndarray
        The plan's wall axes ``x0, y0, x1, y1``, metres (a door's ``wall_id`` is a row).
    thickness : (N,) float ndarray
        Metres.
    grid : OccupancyGrid
        The free space (of the plan's scans, or a map's free cells).
    params : RoomParams
        ``door_min_m``, ``door_max_m``, ``min_room_area_m2`` and the corridor's limits.
    hypotheses : (M, 4) float ndarray, optional
        More lines for the complex, metres (e.g. the plan's clutter faces): without
        evidence of their own (:data:`~floorscan.floorplan.hypotheses.OPEN`), their
        edges weighed by the grid's occupied cells; not extended.

    Returns
    -------
    polygons : list of shapely.Polygon
        The rooms, map metres, in reading order (top to bottom, left to right).
    doors : list of (p, q, wall, room_a, room_b)
        The opening from ``p`` to ``q`` ((2,) metres) at the end of wall ``wall`` and
        the two rooms it joins (indices into ``polygons``, ``room_a < room_b``).
    """
    import shapely
    from shapely import STRtree
    from shapely.geometry import LineString, box

    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    thickness = np.asarray(thickness, dtype=np.float64).reshape(-1)
    free = grid.free()
    if not free.any():
        return [], []
    xy = grid.cell_centres(free)
    lo, hi = xy.min(axis=0) - FRAME_MARGIN_M, xy.max(axis=0) + FRAME_MARGIN_M
    frame = box(*lo, *hi)
    keep = np.array([LineString([a[:2], a[2:]]).intersects(frame) for a in axes], dtype=bool) if len(axes) else np.zeros(0, bool)
    lines, kinds, gaps = layout_lines(axes[keep], thickness[keep], frame, params.door_max_m)
    if hypotheses is not None:
        for h in np.asarray(hypotheses, dtype=np.float64).reshape(-1, 4):
            ln = LineString([h[:2], h[2:]])
            if ln.length > 0 and ln.intersects(frame):
                lines.append(ln)
                kinds.append(OPEN)
    # the map's own walls: its representative lines and the openings between their runs
    map_lines, openings = map_hypotheses(grid, axes[keep], thickness[keep], frame, params.door_max_m)
    for rows, kind in ((map_lines, OPEN), (openings, CLOSED)):
        for h in rows:
            ln = LineString([h[:2], h[2:]])
            if ln.length > 0 and ln.intersects(frame):
                lines.append(ln)
                kinds.append(kind)
    wall_rows = np.flatnonzero(keep)
    cells, edges = layout_cells(lines, kinds, grid)
    if not cells:
        return [], []
    share = cell_free_share(cells, grid)
    area = np.array([c.area for c in cells])
    inside = share >= INSIDE_SHARE
    region = group_cells(inside, edges, area, params.min_room_area_m2)
    roots = sorted(set(region[region >= 0].tolist()))
    # a room ends at the wall faces and at the door openings in them
    gap_axes = np.array([np.r_[p, q] for p, q, *_ in gaps]).reshape(-1, 4)
    gap_thickness = thickness[wall_rows[[g[2] for g in gaps]]] if gaps else np.zeros(0)
    solid = shapely.union_all([*wall_footprints(axes, thickness), *wall_footprints(gap_axes, gap_thickness)],
                              grid_size=PRECISION_M)
    polys, kept_roots = [], []
    for r in roots:
        cells_r = shapely.union_all([cells[k] for k in np.flatnonzero(region == r)], grid_size=PRECISION_M)
        poly = shapely.difference(cells_r, solid, grid_size=PRECISION_M)
        # the walls may part a region's cells into pieces: each large enough is a room
        for part in shapely.get_parts(shapely.set_precision(poly, PRECISION_M)):
            if part.geom_type == "Polygon" and part.area >= params.min_room_area_m2:
                polys.append(part)
                kept_roots.append(r)
    # reading order: top to bottom, then left to right
    order = sorted(range(len(polys)), key=lambda k: (-round(polys[k].bounds[3], 2), round(polys[k].bounds[0], 2)))
    polys = [polys[k] for k in order]
    room_at_cell = {}
    for i, k in enumerate(order):
        room_at_cell.setdefault(kept_roots[k], []).append((i, polys[i]))
    cell_tree = STRtree(cells)

    def room_at(pt) -> int:
        hit = cell_tree.query(shapely.points(pt), predicate="within")
        if not len(hit):
            return -1
        parts = room_at_cell.get(int(region[hit[0]]), [])
        if len(parts) == 1:
            return parts[0][0]
        p = shapely.points(pt)
        return min(parts, key=lambda ip: ip[1].distance(p))[0] if parts else -1

    doors = []
    res = grid.resolution_m
    for p, q, i, width in gaps:
        if not params.door_min_m <= width <= params.door_max_m:
            continue
        d = (q - p) / width
        nrm = np.array([-d[1], d[0]])
        mid = (p + q) / 2
        off = thickness[wall_rows[i]] / 2 + 2 * res
        a, b = room_at(mid + off * nrm), room_at(mid - off * nrm)
        if a < 0 or b < 0 or a == b:
            continue
        t = np.linspace(0.0, 1.0, max(int(width / res), 2))[1:-1]
        rows, cols, ok = grid.cells_of(p[None] + t[:, None] * (q - p)[None])
        seen = free[rows[ok], cols[ok]]
        if not len(seen) or seen.mean() < 0.5:
            continue  # the free space does not cross it
        if any(np.hypot(*(mid - (dp + dq) / 2)) < params.door_min_m / 2 for dp, dq, *_ in doors):
            continue  # the same opening, reached from the wall on its other side
        doors.append((p, q, int(wall_rows[i]), min(a, b), max(a, b)))
    log.info("layout: %d lines (%d walls), %d cells (%d inside), %d rooms, %d doors", len(lines), int(keep.sum()),
             len(cells), int(inside.sum()), len(polys), len(doors))
    return polys, doors


def layout_plan_rooms(axes: np.ndarray, thickness: np.ndarray, grid: OccupancyGrid, params, hypotheses=None):
    """The rooms and doors tables of a plan as one layout: :func:`layout_rooms`, then
    :func:`floorscan.floorplan.room_tables.room_tables`.

    Parameters
    ----------
    axes, thickness, grid, params, hypotheses
        As :func:`layout_rooms`.

    Returns
    -------
    rooms, doors : pandas.DataFrame
        As :func:`floorscan.floorplan.rooms.plan_rooms`.
    """
    from floorscan.floorplan.room_tables import room_tables

    polys, doors = layout_rooms(axes, thickness, grid, params, hypotheses)
    return room_tables(polys, doors, grid.resolution_m, params)

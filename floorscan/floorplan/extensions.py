"""Partitions that stop short (:func:`partition_cuts`): a wall that ends in a room's
free space, pointing at another wall, with an opening a door wide or wider between
them, divides the room on the line of the wall.

A distance-transform segmentation (:mod:`floorscan.floorplan.persistence`) parts two
spaces only where the space narrows to a door; an opening wider than a door joins
them, and so does a door where furniture keeps the distance to the nearest obstacle
as low in the rooms as in the door (the watershed finds no basin on each side: a door
beside the corner of two furnished rooms). Offices divided by partitions that end 2
to 4 m short of the corridor's wall (open-plan offices, bays of a lab, the rooms of a
robot map whose doors stood open) come out as one room. People draw the rooms' boundary on the partition's line up to
the wall it points at, as the layouts of Luperto et al. ("Robust structure
identification and room segmentation of cluttered indoor environments from occupancy
grid maps", RA-L 2022, ROSE^2) and Ochmann et al. (Computers & Graphics 2019) extend
the walls' lines into the free space and keep an extension where the walls around it
separate two rooms.

An extension is the line from a wall's free end, along its axis, through the free
space to the first wall it meets at more than ``door_angle_deg`` to its own direction
(a collinear wall is a gap in one wall: :func:`~floorscan.floorplan.doors.wall_gaps`),
at least ``door_min_m`` wide (up to ``door_max_m``: a door between the wall's end and
the face of the wall across, as :func:`~floorscan.floorplan.doors.wall_gaps` cuts the
door between two walls' ends in one line) and at most
:data:`~floorscan.floorplan.mouths.MOUTH_MAX_M`, from a wall at
least :data:`~floorscan.floorplan.mouths.MOUTH_WALL_M` long. The end is free when it
is in no L or T junction with another wall that long: a shorter one is a stub (a
jamb, the return of a cabinet), as a mouth's sides are no shorter. The opening is
measured on the raster, so to a cell at each end: at most ``MOUTH_MAX_M`` and
:data:`ENDS_CELLS` cells. It cuts the room it lies in
(the rooms of a first segmentation, shortest extension first) when:

- the wall bounds the room for at least the opening's length: the room lies along it,
  on either face, within ``close_m`` of it (the unseen strip along a wall's face),
  counted on the raster's cells, so to a cell at each end of the wall (its ends lie
  anywhere in their cells, the opening's are measured between them). A
  partition the room wraps around, or a corridor's wall that stops short of the room
  beside it (the room lies on its other face only where it reaches past the wall's
  end), is more wall than opening; a stub is not;
- the cut parts the room in two, each at least ``min_room_area_m2`` and walled along at
  least ``min_enclosure`` of its edge (as a room is, and a fan of rays seen through a
  window is not: :mod:`floorscan.floorplan.rooms`, step 4), and neither a recess: each
  at least :data:`~floorscan.floorplan.mouths.MOUTH_MIN_DEPTH` times the opening deep
  on average (its area over the opening's width), as a mouth's pocket is.

A free-standing wall whose other end also stands in the room does not part it, so it
stays inside the room.
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.doors import barrier_cells, junction_end
from floorscan.floorplan.mouths import MOUTH_MAX_M, MOUTH_MIN_DEPTH, MOUTH_WALL_M
from floorscan.floorplan.room_space import RoomParams, RoomRaster, enclosure_cells, wall_footprints

#: A length measured on the room raster is known to this many of its cells: one at each
#: end, since a wall's or an opening's end lies anywhere in its cell.
ENDS_CELLS = 2


def wall_extensions(axes: np.ndarray, thickness: np.ndarray, raster: RoomRaster, params: RoomParams):
    """The candidate extensions of the walls (the module docstring).

    Parameters
    ----------
    axes : (N, 4) float ndarray
        Wall axes ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Metres.
    raster : RoomRaster
        The space before it is cut.
    params : RoomParams

    Returns
    -------
    list of (p, q, wall)
        Each opening from ``p`` (next to the wall's end) to ``q`` (next to the wall it
        meets), (2,) metres, and the wall it extends.
    """
    import shapely

    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    thickness = np.asarray(thickness, dtype=np.float64).reshape(-1)
    if len(axes) < 2:
        return []
    ends = axes.reshape(-1, 2, 2)
    length = np.hypot(axes[:, 2] - axes[:, 0], axes[:, 3] - axes[:, 1])
    unit = (ends[:, 1] - ends[:, 0]) / np.maximum(length, 1e-12)[:, None]
    tree = shapely.STRtree(wall_footprints(axes, thickness))
    cos_tol = np.cos(np.radians(params.door_angle_deg))
    res = raster.resolution_m
    step = res / 2
    widest = MOUTH_MAX_M + ENDS_CELLS * res  # a room's widest open side, as measured on the raster
    out = []
    sides = np.flatnonzero(length >= MOUTH_WALL_M)  # a room's sides; a shorter wall is a stub
    side_axes, side_thickness = axes[sides], thickness[sides]
    for rank, i in enumerate(sides.tolist()):
        for k in (0, 1):
            if junction_end(side_axes, side_thickness, rank, k):
                continue  # in an L or T junction with another side
            u = unit[i] if k == 1 else -unit[i]
            t = np.arange(1, int(np.ceil((widest + thickness[i]) / step)) + 1) * step
            pts = ends[i, k] + np.outer(t, u)
            free = raster.at(raster.space, pts, outside=False).astype(bool)
            first = np.flatnonzero(free)
            # the space begins at the wall's end (a wall's end inside unseen space starts nothing)
            if not len(first) or t[first[0]] > thickness[i] / 2 + 2 * res:
                continue
            s0 = int(first[0])
            stop = np.flatnonzero(~free[s0:])
            if not len(stop):
                continue  # the space runs on farther than any room's open side
            e = s0 + int(stop[0])  # the first point out of the space
            near = tree.query(shapely.Point(pts[e]), predicate="dwithin", distance=2 * res)
            if not any(j != i and abs(float(unit[j] @ u)) < cos_tol for j in near):
                continue  # it ends at an obstacle or the unseen, or at a wall in its own line
            p, q = pts[s0] - u * step, pts[e - 1] + u * step
            width = float(np.hypot(*(q - p)))
            if params.door_min_m <= width <= widest:
                out.append((p, q, int(i)))
    return out


def partition_cuts(
    axes: np.ndarray, thickness: np.ndarray, raster: RoomRaster, labels: np.ndarray, params: RoomParams
) -> list[tuple[np.ndarray, np.ndarray, int]]:
    """The extensions that divide a room (the module docstring).

    Parameters
    ----------
    axes : (N, 4) float ndarray
        Wall axes ``x0, y0, x1, y1``, metres.
    thickness : (N,) float ndarray
        Metres.
    raster : RoomRaster
        The space before it is cut.
    labels : (H, W) int ndarray
        The rooms of a segmentation without these cuts (0 none, 1..R).
    params : RoomParams

    Returns
    -------
    list of (p, q, wall)
        As :func:`wall_extensions`, the ones kept, shortest first.
    """
    from scipy import ndimage
    from skimage.segmentation import expand_labels

    axes = np.asarray(axes, dtype=np.float64).reshape(-1, 4)
    thickness = np.asarray(thickness, dtype=np.float64).reshape(-1)
    exts = wall_extensions(axes, thickness, raster, params)
    if not exts:
        return []
    res = raster.resolution_m
    work = np.asarray(labels).astype(np.int64, copy=True)
    grown = expand_labels(work, int(np.ceil(params.close_m / res)))
    edge, solid = enclosure_cells(raster)
    new = int(work.max()) + 1
    kept = []
    for p, q, i in sorted(exts, key=lambda e: (float(np.hypot(*(e[1] - e[0]))), e[2], e[0][0], e[0][1])):
        d = q - p
        width = float(np.hypot(*d))
        nrm = np.array([-d[1], d[0]]) / width * 2 * res
        mid = (p + q) / 2
        sides = np.array([mid + nrm, mid - nrm])
        ra, rb = (int(v) for v in raster.at(work, sides))
        if not ra or ra != rb:
            continue
        a, b = axes[i, :2], axes[i, 2:]
        length = float(np.hypot(*(b - a)))
        u = (b - a) / length
        n = np.array([-u[1], u[0]]) * (thickness[i] / 2 + 2 * res)
        on = a + np.outer(np.arange(res / 2, length, res), u)
        along = float(((raster.at(grown, on + n) == ra) | (raster.at(grown, on - n) == ra)).sum()) * res
        if along + ENDS_CELLS * res < width:
            continue  # more opening than wall, by more than a cell at each of its ends
        rows, cols = np.nonzero(work == ra)
        r0, c0 = rows.min(), cols.min()
        box = (slice(r0, rows.max() + 1), slice(c0, cols.max() + 1))
        mask = work[box] == ra
        br, bc = barrier_cells(raster, p, q)
        br, bc = br - r0, bc - c0
        ok = (br >= 0) & (bc >= 0) & (br < mask.shape[0]) & (bc < mask.shape[1])
        mask[br[ok], bc[ok]] = False
        comp, count = ndimage.label(mask)
        sr, sc, _ = raster.cells_of(sides)
        ca, cb = (int(comp[r - r0, c - c0]) if 0 <= r - r0 < mask.shape[0] and 0 <= c - c0 < mask.shape[1] else 0
                  for r, c in zip(sr, sc))  # fmt: skip
        if not ca or not cb or ca == cb:
            continue  # the room goes on around the wall's other end
        area = np.bincount(comp.ravel(), minlength=count + 1) * res**2
        if min(area[ca], area[cb]) < max(params.min_room_area_m2, MOUTH_MIN_DEPTH * width**2):
            continue  # too small for a room, or a recess of the space it opens onto (as a mouth's)
        on_edge = np.bincount(comp[edge[box]], minlength=count + 1)
        walled = np.bincount(comp[edge[box] & solid[box]], minlength=count + 1)
        if min(walled[c] / max(on_edge[c], 1) for c in (ca, cb)) < params.min_enclosure:
            continue  # a fan of rays through a window or an open door is no room
        work[box][comp == cb] = new
        grown[box][comp == cb] = new
        new += 1
        kept.append((p, q, i))
    return kept

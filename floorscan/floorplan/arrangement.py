"""Step 2 of the global layout (:mod:`floorscan.floorplan.layout`): the cell complex
of the wall hypotheses (:mod:`floorscan.floorplan.hypotheses`) and what the grid says of
its cells and edges.

The lines are noded and polygonised (shapely's ``node`` and ``polygonize``) on a fixed
precision grid of :data:`PRECISION_M`, so that a sub-cell shift of the input cannot make
GEOS fail (:func:`layout_cells`). Each edge between two cells gets its evidence of a
boundary: all of it on a wall or a closed opening of the plan; on an open hypothesis,
the share of it that runs over the grid's occupied cells (:func:`edge_evidence`: a wall
the plan lacks, a map's faint or dashed wall, still parts two cells). Each cell gets
the share of its area that is free space (:func:`cell_free_share`).
"""

from __future__ import annotations

import math

import numpy as np

from floorscan.core.occupancy import OccupancyGrid
from floorscan.floorplan.hypotheses import CLOSED, OPEN, PRECISION_M, WALL

#: An edge of the complex is on a wall where it passes this close to an occupied cell,
#: metres: half the thickness of a common wall (the axis runs inside the wall, its faces
#: are the occupied cells) and a cell.
EVIDENCE_REACH_M = 0.15


def layout_cells(lines, kinds, grid: OccupancyGrid | None = None):
    """The cells of the complex and its edges.

    Parameters
    ----------
    lines : list of shapely.LineString
    kinds : list of int
        As :func:`layout_lines`.
    grid : OccupancyGrid, optional
        Its occupied cells are wall evidence too (:func:`edge_evidence`).

    Returns
    -------
    cells : list of shapely.Polygon
    edges : list of (a, b, length_m, closed_m)
        Each noded edge with a cell on each side (``a`` may equal ``b`` for a dangle
        inside one cell; edges on the frame have one cell and are left out), its
        length and the length of it that is closed: on a wall or a closed opening of
        the plan, or on the grid's occupied cells.
    """
    import shapely
    from shapely import STRtree

    occupied = None
    if grid is not None:
        from scipy import ndimage

        steps = max(int(round(EVIDENCE_REACH_M / grid.resolution_m)), 0)
        occupied = grid.occupied()
        occupied = ndimage.binary_dilation(occupied, np.ones((3, 3), bool), iterations=steps) if steps else occupied
    snapped = [shapely.set_precision(ln, PRECISION_M) for ln in lines]
    noded = shapely.node(shapely.MultiLineString([c for ln in snapped for c in _parts(ln)]))
    cells = [c for c in shapely.get_parts(shapely.polygonize(shapely.get_parts(noded))) if c.area > PRECISION_M**2 * 100]
    source = STRtree(snapped)
    cell_tree = STRtree(cells)
    edges = []
    for e in shapely.get_parts(noded):
        length = float(e.length)
        if length <= PRECISION_M * 10:
            continue
        mid = e.interpolate(0.5, normalized=True)
        c = shapely.get_coordinates(e)
        d = c[-1] - c[0]
        nrm = np.array([-d[1], d[0]]) / max(float(np.hypot(*d)), 1e-12) * PRECISION_M * 20
        sides = []
        for s in (1.0, -1.0):
            pt = shapely.points(shapely.get_coordinates(mid)[0] + s * nrm)
            hit = [k for k in cell_tree.query(pt, predicate="within")]
            sides.append(hit[0] if hit else -1)
        if sides[0] < 0 or sides[1] < 0:
            continue
        near = source.query(mid, predicate="dwithin", distance=PRECISION_M * 5)
        kind = min((kinds[k] for k in near), default=OPEN)  # a wall over an extension on it
        if kind in (WALL, CLOSED):
            closed = length
        elif grid is not None and kind == OPEN:
            closed = length * edge_evidence(c, occupied, grid)
        else:
            closed = 0.0
        edges.append((sides[0], sides[1], length, closed))
    return cells, edges


def edge_evidence(coords: np.ndarray, occupied: np.ndarray, grid: OccupancyGrid) -> float:
    """The share of a polyline's length over cells within :data:`EVIDENCE_REACH_M` of an
    occupied cell of ``grid`` (``occupied``: its occupied cells so grown), sampled every
    half cell: a wall the plan lacks (a map's dashed or faint wall, a wall seen in
    pieces) still divides two cells."""
    pts = [coords[0]]
    for a, b in zip(coords[:-1], coords[1:]):
        n = max(int(np.ceil(np.hypot(*(b - a)) / (grid.resolution_m / 2))), 1)
        pts.append(a + (b - a) * np.arange(1, n + 1)[:, None] / n)
    pts = np.vstack([np.atleast_2d(p) for p in pts])
    rows, cols, ok = grid.cells_of(pts)
    hit = np.zeros(len(pts), dtype=bool)
    hit[ok] = occupied[rows[ok], cols[ok]]
    return float(hit.mean())


def cell_free_share(cells, grid: OccupancyGrid) -> np.ndarray:
    """(C,) float: the share of each cell's area that is free space of ``grid`` (a cell
    smaller than four grid cells: the share of the grid cells around it)."""
    import shapely
    from skimage.draw import polygon as fill

    free = grid.free()
    h, w = free.shape
    res, (ox, oy) = grid.resolution_m, grid.origin_xy
    label = np.full((h, w), -1, dtype=np.int64)
    order = np.argsort([-c.area for c in cells], kind="stable")
    for k in order:
        ring = shapely.get_coordinates(cells[k].exterior)
        rr, cc = fill((ring[:, 1] - oy) / res - 0.5, (ring[:, 0] - ox) / res - 0.5, shape=(h, w))
        label[rr, cc] = k
    inside = label >= 0
    total = np.bincount(label[inside], minlength=len(cells)).astype(np.float64)
    n_free = np.bincount(label[inside & free], minlength=len(cells)).astype(np.float64)
    share = np.divide(n_free, total, out=np.zeros(len(cells)), where=total > 0)
    for k in np.flatnonzero(total < 4):
        x0, y0, x1, y1 = cells[k].bounds
        c0, c1 = int(math.floor((x0 - ox) / res)) - 1, int(math.ceil((x1 - ox) / res)) + 1
        r0, r1 = int(math.floor((y0 - oy) / res)) - 1, int(math.ceil((y1 - oy) / res)) + 1
        window = free[max(r0, 0):max(r1, 0), max(c0, 0):max(c1, 0)]
        share[k] = float(window.mean()) if window.size else 0.0
    return share


def _parts(line):
    import shapely

    return [p for p in shapely.get_parts(line) if not p.is_empty]

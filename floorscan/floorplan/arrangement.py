"""Step 2 of the global layout (:mod:`floorscan.floorplan.layout`): the cell complex
of the wall hypotheses (:mod:`floorscan.floorplan.hypotheses`) and what the grid says of
its cells and edges.

The lines are noded and polygonised (shapely's ``node`` and ``polygonize``) on a fixed
precision grid of :data:`PRECISION_M`, so that a sub-cell shift of the input cannot make
GEOS fail (:func:`layout_cells`). Each edge between two cells gets its evidence of a
boundary: all of it on a wall or a closed opening of the plan; on an open hypothesis,
the share of it that runs over the grid's occupied cells (:func:`edges_evidence`: a wall
the plan lacks, a map's faint or dashed wall, still parts two cells). Each cell gets
the share of its area that is free space (:func:`cell_free_share`).
"""

from __future__ import annotations

import math

import numpy as np

from floorscan.core.grid import ranks_in_runs
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
        Its occupied cells are wall evidence too (:func:`edges_evidence`).

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
    parts = shapely.get_parts(noded)
    length = shapely.length(parts)
    parts, length = parts[length > PRECISION_M * 10], length[length > PRECISION_M * 10]
    if not len(parts) or not cells:
        return cells, []
    # the cell on each side of each edge: a point just off its middle, square to it
    coords, which = shapely.get_coordinates(parts, return_index=True)
    first = np.searchsorted(which, np.arange(len(parts)))
    last = np.r_[first[1:], len(coords)] - 1
    d = coords[last] - coords[first]
    nrm = np.c_[-d[:, 1], d[:, 0]] / np.maximum(np.hypot(*d.T), 1e-12)[:, None] * PRECISION_M * 20
    mid = shapely.get_coordinates(shapely.line_interpolate_point(parts, 0.5, normalized=True))
    cell_tree = STRtree(cells)
    sides = np.full((len(parts), 2), -1, dtype=np.int64)
    for j, sgn in enumerate((1.0, -1.0)):
        e, c = cell_tree.query(shapely.points(mid + sgn * nrm), predicate="within")
        sides[e[::-1], j] = c[::-1]  # the first hit of each point
    # each edge's kind: a wall over an extension on it
    e, k = STRtree(snapped).query(shapely.points(mid), predicate="dwithin", distance=PRECISION_M * 5)
    kind = np.full(len(parts), OPEN, dtype=np.int64)
    np.minimum.at(kind, e, np.asarray(kinds, dtype=np.int64)[k])
    closed = np.where(np.isin(kind, (WALL, CLOSED)), length, 0.0)
    measure = (kind == OPEN) & (sides >= 0).all(axis=1)
    if grid is not None and measure.any():
        idx = np.flatnonzero(measure)
        closed[idx] = length[idx] * edges_evidence(coords[first[idx]], coords[last[idx]], occupied, grid)
    keep = (sides >= 0).all(axis=1)
    edges = [(int(a), int(b), float(n), float(c)) for a, b, n, c in zip(sides[keep, 0], sides[keep, 1], length[keep], closed[keep])]
    return cells, edges


def edges_evidence(p: np.ndarray, q: np.ndarray, occupied: np.ndarray, grid: OccupancyGrid) -> np.ndarray:
    """The share of each straight edge from ``p`` to ``q`` ((E, 2) float ndarrays,
    metres) that lies over ``occupied`` cells of ``grid`` (the grid's occupied cells
    grown by :data:`EVIDENCE_REACH_M`), sampled every half cell: (E,) float64. A wall
    the plan lacks (a map's dashed or faint wall, a wall seen in pieces) still divides
    two cells."""
    n = np.maximum(np.ceil(np.hypot(*(q - p).T) / (grid.resolution_m / 2)).astype(np.int64), 1) + 1
    which = np.repeat(np.arange(len(p)), n)
    t = ranks_in_runs(n) / np.repeat(n - 1, n)
    pts = p[which] + (q - p)[which] * t[:, None]
    rows, cols, ok = grid.cells_of(pts)
    hit = np.zeros(len(pts), dtype=bool)
    hit[ok] = occupied[rows[ok], cols[ok]]
    return np.bincount(which, weights=hit, minlength=len(p)) / n


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

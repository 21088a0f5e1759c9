"""Furniture out of the walls, the structure passes' clutter rules: objects standing in
the free space (:func:`free_standing_objects`, :func:`on_objects`) and fronts of desks,
cabinets and shelves in front of a wall (:func:`in_front_of_walls`). Source: the
clutter of thesis sections 1.3 and 2.3; the occupancy-grid reading of Bormann et al.,
ICRA 2016 (free space is what the robot saw); the thresholds are ours.
"""

from __future__ import annotations

import numpy as np

from floorscan.core.occupancy import OccupancyGrid
from floorscan.floorplan.candidates import candidate_pairs
from floorscan.floorplan.free_space import StructureParams, mask_at, passable, segment_samples


def free_standing_objects(
    grid: OccupancyGrid, params: StructureParams = StructureParams(), walls: np.ndarray | None = None
) -> np.ndarray:
    """Step 4's objects: the cells of things standing in the free space.

    The cells with a return (any scan) but those of ``walls`` (long faces, (A, 4)
    metres, and a cell around them: so a desk or a cabinet in front of a wall comes
    apart from it), grown by one cell so an object's returns hang together, are split into 8-connected components (SciPy's ``ndimage.label``). A
    component is a free-standing object when the free space surrounds it (at least
    ``object_free_around`` of the cells around it are :func:`passable`) and it is small: its
    extent along its principal axis is below ``clutter_max_length_m``. A thin long
    component (its area over its length below ``side_offset_m`` * 2 plus two cells, at
    least ``min_wall_length_m`` long: a wall between two doors) is not an object.

    Parameters
    ----------
    grid : OccupancyGrid
        The selected scans' grid.
    params : StructureParams
    walls : (A, 4) float ndarray, optional
        Long wall faces, metres, cut out of the returns first.

    Returns
    -------
    (H, W) bool ndarray
        The objects' cells (grown by one cell).
    """
    from scipy import ndimage

    hit = grid.n_hit_scans > 0
    if walls is not None and len(walls):
        pts, _, _ = segment_samples(np.asarray(walls, dtype=np.float64).reshape(-1, 4), grid.resolution_m / 2)
        rows, cols, inside = grid.cells_of(pts)
        on_wall = np.zeros(grid.shape, dtype=bool)
        on_wall[rows[inside], cols[inside]] = True
        hit = hit & ~ndimage.binary_dilation(on_wall, structure=np.ones((3, 3), bool), iterations=2)
    hit = ndimage.binary_dilation(hit, structure=np.ones((3, 3), bool))
    labels, n = ndimage.label(hit, structure=np.ones((3, 3), bool))
    if n == 0:
        return np.zeros(grid.shape, dtype=bool)
    ring = ndimage.binary_dilation(hit, structure=np.ones((3, 3), bool)) & ~hit
    ring_labels = ndimage.grey_dilation(labels, size=(3, 3)) * ring
    free = passable(grid)
    around = np.bincount(ring_labels[ring], minlength=n + 1).astype(np.float64)
    around_free = np.bincount(ring_labels[ring & free], minlength=n + 1)
    surrounded = around_free >= params.object_free_around * np.maximum(around, 1)
    rows, cols = np.nonzero(labels)
    lab = labels[rows, cols]
    r = grid.resolution_m
    x, y = cols * r, rows * r
    cnt = np.bincount(lab, minlength=n + 1).astype(np.float64)
    mx, my = np.bincount(lab, x, n + 1) / np.maximum(cnt, 1), np.bincount(lab, y, n + 1) / np.maximum(cnt, 1)
    dx, dy = x - mx[lab], y - my[lab]
    sxx = np.bincount(lab, dx * dx, n + 1)
    syy = np.bincount(lab, dy * dy, n + 1)
    sxy = np.bincount(lab, dx * dy, n + 1)
    phi = 0.5 * np.arctan2(2 * sxy, sxx - syy)
    u = dx * np.cos(phi[lab]) + dy * np.sin(phi[lab])  # along the principal axis
    hi, lo = np.full(n + 1, -np.inf), np.full(n + 1, np.inf)
    np.maximum.at(hi, lab, u)
    np.minimum.at(lo, lab, u)
    length = np.where(np.isfinite(hi), hi - lo + r, 0.0)
    mean_width = cnt * r * r / np.maximum(length, r)  # area over length: stray returns aside
    wall_like = (mean_width < 2 * params.side_offset_m + 2 * r) & (length >= params.min_wall_length_m)
    is_object = surrounded & (length < params.clutter_max_length_m) & ~wall_like
    is_object[0] = False
    return is_object[labels]


def on_objects(seg: np.ndarray, grid: OccupancyGrid, objects: np.ndarray) -> np.ndarray:
    """Whether most of each face lies on object cells (:func:`free_standing_objects`):
    at least half its samples, every half cell.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    grid : OccupancyGrid
    objects : (H, W) bool ndarray
        On ``grid``'s cells.

    Returns
    -------
    (F,) bool ndarray
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    if len(seg) == 0:
        return np.zeros(0, dtype=bool)
    pts, owner, _ = segment_samples(seg, grid.resolution_m / 2)
    share = np.bincount(owner, weights=mask_at(grid, objects, pts), minlength=len(seg))
    return share >= 0.5 * np.bincount(owner, minlength=len(seg))


def in_front_of_walls(seg: np.ndarray, side: np.ndarray, wall: np.ndarray, params: StructureParams = StructureParams()):
    """Step 5: faces shorter than ``clutter_max_length_m`` that stand parallel in front
    of a long wall face, on its free side, between ``front_min_m`` and ``front_max_m``
    from it and along it over ``front_overlap`` of their length: the fronts of desks,
    cabinets and shelves against a wall (the thesis's clutter, sections 1.3 and 2.3).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    side : (F,) int ndarray
        Their free sides (:func:`border_and_support`).
    wall : (F,) bool ndarray
        Which faces are long walls (the candidates behind).
    params : StructureParams

    Returns
    -------
    (F,) bool ndarray
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    out = np.zeros(len(seg), dtype=bool)
    i, j = candidate_pairs(seg, params.front_max_m, np.radians(params.join_angle_deg))
    if len(i) == 0:
        return out
    i, j = np.r_[i, j], np.r_[j, i]  # face i in front of wall j
    ok = wall[j] & ~wall[i]
    i, j = i[ok], j[ok]
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    u = (seg[j, 2:] - seg[j, :2]) / np.maximum(length[j], 1e-12)[:, None]
    n = np.column_stack([-u[:, 1], u[:, 0]]) * side[j][:, None]  # towards the wall's free side
    mid = 0.5 * (seg[i, :2] + seg[i, 2:])
    dist = np.einsum("ij,ij->i", mid - seg[j, :2], n)
    t0 = np.einsum("ij,ij->i", seg[i, :2] - seg[j, :2], u)
    t1 = np.einsum("ij,ij->i", seg[i, 2:] - seg[j, :2], u)
    overlap = np.minimum(np.maximum(t0, t1), length[j]) - np.maximum(np.minimum(t0, t1), 0.0)
    hit = (side[j] != 0) & (dist >= params.front_min_m) & (dist <= params.front_max_m) & (
        overlap >= params.front_overlap * length[i]
    )
    out[i[hit]] = True
    return out

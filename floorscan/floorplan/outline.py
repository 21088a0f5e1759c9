"""The building's closed outline in a recording: the free space the scans saw beyond
it (rays through a window, an open door or a gap between walls into the outside) is
not the building's.

The outline is the morphological closing of the walls and the obstacles the scans saw
by a disc of diameter ``D`` (Serra, *Image analysis and mathematical morphology*, 1982;
the alpha shapes of Edelsbrunner et al., IEEE Trans. Inf. Theory 1983, are the same
closing of a point set): the outside is what the raster's border reaches without
coming within ``D / 2`` of a solid cell, grown back by ``D / 2``; the inside is the
rest. Every gap narrower than ``D`` is closed, every wider one leaks. The raster is
padded first by the disc's radius at the door's width, so the border reaches around
the outermost walls: a room raster ends a few cells past what the scans saw, and a
facade seen through a window is often its outermost wall.

``D`` is chosen from the recording, not set: the smallest diameter, at least the
widest door (``door_max_m``: a room seen through its door is the building's), at
which every scan position is inside. The rover drove inside the building, so the
closing must hold it; a wider ``D`` would also close the building's concave corners
and the near ends of the fans. Where the rover drove outside too (a campus, a
forecourt) the closing grows until it holds those positions and cuts little; where
none holds them, nothing is cut. A map has no scan positions and no closing: its
outside is what it does not mark free (:mod:`floorscan.floorplan.room_space`) and what
lies beyond the convex hull of its walls (:func:`beyond_walls_hull`).

Two bounds on what the border reaches, from the walls and the scans:

- inside the convex hull of the building's own walls (the pieces of the plan's walls
  next to the space the closing holds, not a facade across the street seen through a
  window) it is not outside: a room the rover saw only through its door, whose far
  wall the scans never saw, lets the closing in, and the walls around it say it is
  the building's; beyond that hull, every part the rover never entered is outside,
  whether the closing reaches it or not (the fans a gap as wide as the closing's
  diameter lets out, which the closing's round ends leave), as for a map
  (:func:`beyond_walls_hull`);
- a part of the space the closing seals off, where the rover never was and which the
  scans saw less than half of (a courtyard, seen through the windows around it), is
  outside wherever it lies; a room seen through its door is seen for the most part.

The room step (:mod:`floorscan.floorplan.rooms`) takes :func:`building_outside`'s
outside from the space before the regions are cut, and drops the regions that lie
mostly beyond the outline where no scan was taken (:func:`regions_beyond`): the
closing's round ends reach into the building at a gap as wide as its diameter, so
cells there are only dropped with the region they belong to.

Which walls are no walls of the building once the rooms are cut:
:mod:`floorscan.floorplan.lone_walls`.
"""

from __future__ import annotations

import logging

import numpy as np

from floorscan.core.grid import unique_ints

log = logging.getLogger("floorscan.floorplan.rooms")

#: The bisection on the closing's diameter stops when its bracket is narrower than this
#: many cells of the room raster: a cell is what the raster can tell apart.
DIAMETER_TOLERANCE_CELLS = 1.0


def _outside(distance_m: np.ndarray, diameter_m: float) -> np.ndarray:
    """(H + 2, W + 2) bool: the cells the padded raster's border reaches through cells
    farther than ``diameter_m / 2`` from every solid cell (``distance_m``: the padded
    raster's distance to the nearest solid cell, metres)."""
    labels, edge = _reached(distance_m, diameter_m)
    return np.isin(labels, edge)


def _reached(distance_m: np.ndarray, diameter_m: float) -> tuple[np.ndarray, np.ndarray]:
    """The parts of the cells farther than ``diameter_m / 2`` from every solid cell
    ((H + 2, W + 2) int labels, 0 for none) and those the border reaches (their labels)."""
    from scipy import ndimage

    labels, _ = ndimage.label(distance_m > diameter_m / 2)
    edge = np.unique(np.r_[labels[0], labels[-1], labels[:, 0], labels[:, -1]])
    return labels, edge[edge > 0]


def building_outside(
    solid: np.ndarray, resolution_m: float, origin_xy: np.ndarray, scan_xy: np.ndarray | None, door_max_m: float,
    seen: np.ndarray | None = None, walls: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, float]:
    """The cells outside the building's closed outline (the module docstring).

    Parameters
    ----------
    solid : (H, W) bool ndarray
        The cells of the walls and of the obstacles the scans saw; row 0 at
        ``origin_xy``'s y.
    resolution_m : float
        Cell size, metres.
    origin_xy : (2,) float ndarray
        Map-frame corner of cell (row 0, column 0), metres.
    scan_xy : (S, 2) float ndarray or None
        The scan positions, map metres. None for a map: outside is what lies beyond
        the convex hull of ``walls`` (:func:`beyond_walls_hull`; all inside without
        ``walls``). Empty: all inside.
    door_max_m : float
        The smallest closing diameter, metres.
    seen : (H, W) bool ndarray, optional
        The cells the scans saw free: a part of the space the closing seals off (a
        courtyard seen through windows), where no scan was taken and of which the
        scans saw less than half, is outside too. None: only what the border reaches.
    walls : (H, W) bool ndarray, optional
        The plan's wall cells: what the border reaches inside the convex hull of the
        building's own walls (the connected pieces of wall next to the space the
        closing holds; not the facades across the street) is not outside (a room seen
        only through its door, whose far wall the scans did not see, lets the closing
        in). None: no such bound.

    Returns
    -------
    outside : (H, W) bool ndarray
        The cells farther than ``diameter_m / 2`` from the walls and obstacles that the
        raster's border reaches: not the building's space.
    beyond : (H, W) bool ndarray
        ``outside`` grown by ``diameter_m / 2``: the cells beyond the closed outline (at a
        gap in it, a round bulge into the building, up to ``diameter_m / 2`` deep for a
        gap as wide as the diameter).
    diameter_m : float
        The closing's diameter, metres; ``inf`` when nothing is cut.
    """
    from scipy import ndimage

    solid = np.asarray(solid, dtype=bool)
    nothing = np.zeros(solid.shape, dtype=bool)
    if scan_xy is None and walls is not None:  # a map: its rays beyond its walls' hull
        cut = beyond_walls_hull(walls)
        return cut, cut, float("inf")
    if scan_xy is None or not len(scan_xy) or not solid.any():
        return nothing, nothing, float("inf")
    # a margin as wide as the closing's disc: the border reaches around the outermost walls
    pad = int(np.ceil(door_max_m / 2 / resolution_m)) + 1
    distance = ndimage.distance_transform_edt(~np.pad(solid, pad)) * resolution_m
    # the scans' cells in the padded raster (those off the raster are left out)
    cells = np.floor((np.asarray(scan_xy, dtype=np.float64) - origin_xy) / resolution_m).astype(np.int64)[:, ::-1] + pad
    keep = ((cells >= pad) & (cells < np.array(solid.shape) + pad)).all(axis=1)
    rows, cols = cells[keep].T
    if not len(rows):
        return nothing, nothing, float("inf")

    def holds(d: float) -> bool:  # no scan's cell in a part the border reaches
        labels, edge = _reached(distance, d)
        return not np.isin(labels[rows, cols], edge).any()

    lo = float(door_max_m)
    hi = float(np.hypot(*solid.shape)) * resolution_m  # no gap is wider than the raster
    if holds(lo):
        hi = lo
    elif not holds(hi):
        log.info("rooms: no closed outline holds the %d scan positions (the rover drove outside too): nothing cut",
                 len(rows))
        return nothing, nothing, float("inf")
    else:
        while hi - lo > DIAMETER_TOLERANCE_CELLS * resolution_m:
            mid = (lo + hi) / 2
            lo, hi = (lo, mid) if holds(mid) else (mid, hi)
    flood = _outside(distance, hi)
    outside = flood.copy()
    unentered = None
    if walls is not None and np.any(walls):
        hull = _hull_of_own_walls(np.pad(np.asarray(walls, dtype=bool), pad), flood, distance, hi, resolution_m)
        outside &= ~hull
        if hull.any():  # beyond the hull, the parts the rover never entered
            parts, n = ndimage.label(~hull & (distance > 0))
            entered = np.zeros(n + 1, dtype=bool)
            entered[parts[rows, cols]] = True
            entered[0] = True
            unentered = ~entered[parts]
    if seen is not None:  # the courtyards: sealed off, not visited, mostly unseen
        parts, n = ndimage.label((distance > hi / 2) & ~flood)
        if n:
            ids = np.arange(1, n + 1)
            unseen = ndimage.sum(np.pad(np.asarray(seen, dtype=bool), pad), parts, ids) < ndimage.sum(parts > 0, parts, ids) / 2
            court = np.r_[False, unseen]
            court[parts[rows, cols]] = False
            outside |= court[parts]
    # grown back by the closing's radius: the outside ends at the walls' faces; the
    # parts beyond the hull end there already
    beyond = ndimage.distance_transform_edt(~outside) * resolution_m <= hi / 2
    if unentered is not None:
        outside |= unentered
        beyond |= unentered
    log.info("rooms: the building's outline closed by a disc of %.2f m, the smallest that holds the %d scan positions",
             hi, len(rows))
    return outside[pad:-pad, pad:-pad], beyond[pad:-pad, pad:-pad], hi


def _hull_of_own_walls(walls: np.ndarray, flood: np.ndarray, distance: np.ndarray, diameter_m: float,
                       resolution_m: float) -> np.ndarray:
    """(H, W) bool: the convex hull of the connected pieces of ``walls`` within two cells
    of the cells the closing holds (neither solid, ``distance`` 0, nor within
    ``diameter_m / 2`` of ``flood``); all False when there are none."""
    from scipy import ndimage
    from skimage.morphology import convex_hull_image

    held = (ndimage.distance_transform_edt(~flood) * resolution_m > diameter_m / 2) & (distance > 0)
    pieces, _ = ndimage.label(walls, structure=np.ones((3, 3)))
    own = unique_ints(pieces[ndimage.binary_dilation(held, structure=np.ones((3, 3)), iterations=2) & (pieces > 0)])
    if not len(own):
        return np.zeros(walls.shape, dtype=bool)
    return convex_hull_image(np.isin(pieces, own))


def beyond_walls_hull(walls: np.ndarray) -> np.ndarray:
    """(H, W) bool: the cells outside the convex hull of ``walls`` ((H, W) bool, the
    plan's wall cells); all False without walls.

    A map has no scan positions to choose a closing by, and its free space holds every
    ray its scans cast: through the windows and the glass doors of an office, a map
    marks fans of free space reaching metres into the outside. The building is what
    its walls enclose, so the space beyond the convex hull of the map's walls is not
    the building's; a fan inside the hull (at a concave corner) stays for the room
    step's enclosure test.
    """
    from skimage.morphology import convex_hull_image

    walls = np.asarray(walls, dtype=bool)
    if not walls.any():
        return np.zeros(walls.shape, dtype=bool)
    return ~convex_hull_image(walls)


def regions_beyond(labels: np.ndarray, beyond: np.ndarray) -> np.ndarray:
    """(R + 1,) bool: the regions of ``labels`` (1..R, 0 none) whose cells lie beyond
    the closed outline (``beyond``, (H, W) bool) for more than half of their area; False
    for label 0. A room's region keeps the few cells the outline's round closing takes
    at a gap; the remnant of a fan of rays between the outline and its walls goes."""
    from scipy import ndimage

    n = int(labels.max())
    out = np.zeros(n + 1, dtype=bool)
    if n:
        ids = np.arange(1, n + 1)
        out[1:] = ndimage.sum(beyond, labels, ids) > ndimage.sum(np.ones_like(beyond), labels, ids) / 2
    return out

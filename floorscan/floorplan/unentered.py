"""The watershed regions of the room space (:mod:`floorscan.floorplan.rooms`, step 4)
that no scan was taken in: how much of their edge is walled (:func:`enclosure`), which
hold a scan (:func:`visited_regions`), which are the outside seen through an opening
(:func:`outside_regions`) and which are rooms seen through their open side
(:func:`open_side_rooms`).

A scanner sees the space beyond an opening as a fan of rays. A fan of angle a seen
through an opening is walled at its far end at most, not along its two sides (the rays'
limits): at most a / (2 + a) of its edge, under one half for a < 2 rad
(:data:`~floorscan.floorplan.room_space.MIN_ENCLOSURE_UNENTERED`). A room is walled on
most of its edge. The watershed may cut a fan in pieces (a pocket beside the opening,
walled on two sides, and the open rest), so the unentered space joined through openings
no jambs frame is judged as a whole: walled on less than half its edge and meeting one
entered region alone through such openings, it is outside (a fan through a window, a
gap, the open end of a hall); and the unentered space walled on more than half its edge
that meets one entered region through its open side is a room people draw apart from
where it was seen from: the room open on its whole width onto a hall or a corridor
(:mod:`floorscan.floorplan.mouths`) whose side walls the scans saw too little of to
draw its mouth, Bormann et al.'s ground truths ("Room segmentation: survey,
implementation, and analysis", ICRA 2016) and ROSE^2's (Luperto et al., RA-L 2022)
draw it as a room.
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.mouths import MOUTH_DEPTH, MOUTH_MAX_M, MOUTH_MIN_DEPTH
from floorscan.floorplan.room_space import MIN_ENCLOSURE_UNENTERED, RoomParams, RoomRaster, enclosure_cells, surrounded


def region_sets(n: int):
    """Disjoint sets of region labels 0..n (SciPy's :class:`~scipy.cluster.hierarchy.DisjointSet`)."""
    from scipy.cluster.hierarchy import DisjointSet

    return DisjointSet(range(n + 1))


def set_roots(sets, n: int) -> np.ndarray:
    """(n + 1,) int: each label's set representative."""
    return np.array([sets[a] for a in range(n + 1)], dtype=np.int64)


def enclosure(raster: RoomRaster, labels: np.ndarray, n: int | None = None, cells=None) -> np.ndarray:
    """(n + 1,) float (n: the largest label by default): the share of each region's edge
    (its cells next to cells outside the space) that lies within two cells of a wall or
    a seen obstacle (``cells``: :func:`~floorscan.floorplan.room_space.enclosure_cells`
    of ``raster``, or another ``(edge, solid)`` pair; computed when None); 1 for label 0
    and for a region without edge."""
    from scipy import ndimage

    n = int(labels.max()) if n is None else int(n)
    if n == 0:
        return np.ones(1)
    edge, solid = enclosure_cells(raster) if cells is None else cells
    ids = np.arange(1, n + 1)
    total = ndimage.sum(edge, labels, ids)
    return np.r_[1.0, np.where(total > 0, ndimage.sum(edge & solid, labels, ids) / np.maximum(total, 1), 1.0)]


def outside_regions(
    raster: RoomRaster, labels: np.ndarray, kinds: dict, params: RoomParams, visited: np.ndarray, scanned: bool,
    cells=None,
) -> np.ndarray:
    """(R + 1,) bool: the regions that are not the building's space, where no scan was
    taken from (``visited``, (R + 1,) bool: :func:`visited_regions`): groups of regions walled
    (along walls and seen obstacles) on less than ``rooms.min_enclosure`` of their edge
    that meet the others only through openings no wider than a door (a fan of rays seen
    through a window or an open door into the outside; a room seen only through its door
    is walled on most of its edge); and in a recording (``scanned``: a map's rooms are
    all unentered), the dead ends of unentered space (its regions joined through
    openings no jambs frame, judged as a whole) walled on less than
    :data:`~floorscan.floorplan.room_space.MIN_ENCLOSURE_UNENTERED` of their edge (along
    a hole in the space too: it opens onto nothing) that meet one region alone, an
    entered one, through openings no jambs frame (a gap, a window, one wider than a
    door). ``cells``: :func:`~floorscan.floorplan.room_space.enclosure_cells` of
    ``raster`` (computed when None)."""
    n = int(labels.max())
    out = np.zeros(n + 1, dtype=bool)
    if n < 2:
        return out
    from scipy import ndimage

    edge, solid = enclosure_cells(raster) if cells is None else cells
    # never where the scanner was: an open hall whose walls are out of range is walled
    # on little of its edge, but the rover drove in it
    low = (enclosure(raster, labels, n, (edge, solid)) < params.min_enclosure) & ~visited
    out |= _seen_through(kinds, _joined(kinds, low, n), low, ("narrow", "door"))
    if scanned:  # the edge along a hole in the space is walled too
        holes, inner = surrounded(~raster.space)
        solid = solid | ndimage.binary_dilation(inner[holes], structure=np.ones((3, 3)))
        roots = _joined(kinds, ~visited, n)
        low = (enclosure(raster, roots[labels], n, (edge, solid)) < MIN_ENCLOSURE_UNENTERED)[roots] & ~visited
        out |= _seen_through(kinds, roots, low, ("narrow", "wide"), visited)
    out[0] = False
    return out


def _joined(kinds: dict, members: np.ndarray, n: int) -> np.ndarray:
    """(n + 1,) int: each region's group, the regions of ``members`` ((n + 1,) bool)
    joined through contacts of kind ``narrow`` or ``wide`` (openings no jambs frame)."""
    groups = region_sets(n)
    for (a, b), kind in kinds.items():
        if members[a] and members[b] and kind in ("narrow", "wide"):
            groups.merge(a, b)
    return set_roots(groups, n)


def _seen_through(kinds: dict, roots: np.ndarray, low: np.ndarray, through: tuple, visited=None) -> np.ndarray:
    """(n + 1,) bool: the groups (``roots``) of ``low`` regions whose every contact with
    the other regions is of a kind in ``through``; with ``visited``, only those that
    meet one region alone, an entered one (a dead end seen from it)."""
    out = np.zeros(len(roots), dtype=bool)
    for r in np.unique(roots[1:][low[1:]]):
        members = roots == r
        links, beside = _contacts(kinds, members)
        if not links or not all(kind in through for _, kind in links):
            continue
        if visited is not None and not _seen_from_one(beside, visited):
            continue
        out |= members
    return out


def _contacts(kinds: dict, members: np.ndarray) -> tuple[list, set]:
    """The contacts ``((a, b), kind)`` between the regions of ``members`` ((n + 1,)
    bool) and the others, and the other regions they meet."""
    links = [(pair, kind) for pair, kind in kinds.items() if members[pair[0]] != members[pair[1]]]
    return links, {b if members[a] else a for (a, b), _ in links}


def _seen_from_one(beside: set, visited: np.ndarray) -> bool:
    """Whether a group meets one region alone (``beside``), an entered one: a dead end
    seen from it."""
    return len(beside) == 1 and bool(visited[min(beside)])


def visited_regions(raster: RoomRaster, labels: np.ndarray, scan_xy: np.ndarray | None, n: int) -> np.ndarray:
    """(n + 1,) bool: the labels of ``labels`` that hold the origin of a scan
    (``scan_xy`` (S, 2) metres; None: none)."""
    out = np.zeros(n + 1, dtype=bool)
    if scan_xy is not None and len(scan_xy):
        out[raster.at(labels, scan_xy)] = True
    out[0] = False
    return out


def open_side_rooms(
    raster: RoomRaster, labels: np.ndarray, kinds: dict, widest: dict, visited: np.ndarray, outside: np.ndarray,
    cells=None,
) -> list[tuple[int, int]]:
    """The pairs of regions to keep apart at a room's open side, in a recording.

    A group of unentered regions (no scan taken in it, not ``outside``; joined through
    contacts of kind ``narrow`` or ``wide``) is a room of its own when it meets one
    region alone, an entered one, only through contacts wider than a door (kind
    ``wide``) and at most :data:`~floorscan.floorplan.mouths.MOUTH_MAX_M` wide; is
    walled on at least :data:`~floorscan.floorplan.room_space.MIN_ENCLOSURE_UNENTERED`
    of its edge (:func:`enclosure`: a room, not a fan of rays); and is as deep (its
    area over its widest contact) as a mouth's pocket:
    :data:`~floorscan.floorplan.mouths.MOUTH_MIN_DEPTH` to
    :data:`~floorscan.floorplan.mouths.MOUTH_DEPTH` times that width (shallower, a
    recess of the space it opens onto; deeper, a corridor going on).

    Parameters
    ----------
    raster : RoomRaster
    labels : (H, W) int ndarray
        The regions 1..n, 0 off the space.
    kinds : dict
        ``(a, b) -> "door" | "narrow" | "wide"`` (``a < b``), as
        :func:`outside_regions` takes.
    widest : dict
        ``(a, b) -> float``: the widest contact of each pair of touching regions, metres.
    visited, outside : (n + 1,) bool ndarray
        The regions a scan was taken in (:func:`visited_regions`); those outside the
        building (:func:`outside_regions`).
    cells : tuple, optional
        :func:`~floorscan.floorplan.room_space.enclosure_cells` of ``raster``
        (computed when None).

    Returns
    -------
    list of (a, b)
        The contacts between each such group and the region it is seen from.
    """
    n = int(labels.max())
    unentered = ~visited & ~outside
    unentered[0] = False
    roots = _joined(kinds, unentered, n)
    grouped = roots[labels]
    walled = enclosure(raster, grouped, n, cells)
    area = np.bincount(grouped.ravel(), minlength=n + 1) * raster.resolution_m**2
    pairs = []
    for r in np.unique(roots[1:][unentered[1:]]):
        links, beside = _contacts(kinds, roots == r)
        if not _seen_from_one(beside, visited) or walled[r] < MIN_ENCLOSURE_UNENTERED:
            continue
        if not all(kind == "wide" and widest[pair] <= MOUTH_MAX_M for pair, kind in links):
            continue
        width = max(widest[pair] for pair, _ in links)
        if MOUTH_MIN_DEPTH * width <= area[r] / width <= MOUTH_DEPTH * width:
            pairs += [pair for pair, _ in links]
    return pairs

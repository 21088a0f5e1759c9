"""Step 3 of the global layout (:mod:`floorscan.floorplan.layout`): the cells labelled,
inside or outside, then by room.

A cell is inside when at least :data:`INSIDE_SHARE` of its area is free space. The
inside cells are grouped by agglomerative merging of adjacent regions, the pair with the
longest open boundary (its length less the length of it that is evidence of a wall) first
(:func:`group_cells`; the evidence of an edge: :mod:`floorscan.floorplan.arrangement`), as
long as the evidence is below :data:`BOUNDARY_EVIDENCE` of their shared boundary. The
order matters where lines cross the complex: a line extended across a corridor may cut
a cell whose only boundary with an office is the office's door; merged first by least
evidence (both zero), that cell would join office and corridor before the corridor's own
cells, whose open boundaries are metres long, have joined each other and summed the
office's wall. So: a room cut by a hypothesis without
evidence is one room again, a corridor cut into pieces one corridor, an office whose
boundary with the corridor is wall and a door stays an office. A region below the room
area joins the neighbour it shares most boundary with, unless walls enclose it
(:data:`ENCLOSED_SHARE`). Region merging by boundary evidence follows the cell
complexes of Mura et al. (Computers & Graphics 2014) and ROSE^2 (Luperto et al., RA-L
2022).
"""

from __future__ import annotations

import heapq

import numpy as np

#: A cell is inside the building when this share of its area is free space: most of
#: it was seen free (a room seen through its door only, in part, is less).
INSIDE_SHARE = 0.5
#: Two regions stay apart when this share of their shared boundary lies on walls or
#: closed openings: the boundary is more wall than opening.
BOUNDARY_EVIDENCE = 0.5
#: A region is enclosed by walls when this share of its boundary is wall or a closed
#: opening: a closet, a shaft; kept however small.
ENCLOSED_SHARE = 0.9


class _Regions:
    """Union-find over cells: each region named by its root cell (the merge keeps the
    root it is given, whose boundaries the grouping has summed)."""

    def __init__(self, n: int):
        self.parent = list(range(n))

    def find(self, a: int) -> int:
        while self.parent[a] != a:
            self.parent[a] = self.parent[self.parent[a]]
            a = self.parent[a]
        return a


def group_cells(inside: np.ndarray, edges, area: np.ndarray, min_area_m2: float) -> np.ndarray:
    """Rooms of the inside cells (module docstring, step 3).

    Parameters
    ----------
    inside : (C,) bool ndarray
    edges : list of (a, b, length_m, closed_m)
        :func:`~floorscan.floorplan.arrangement.layout_cells`: two cells, their edge's
        length and the length of it that is evidence of a wall.
    area : (C,) float ndarray
        Cell areas, m2.
    min_area_m2 : float
        A region smaller than this joins its neighbour unless walls enclose it.

    Returns
    -------
    (C,) int ndarray
        Each cell's region (the root cell's index), -1 outside.
    """
    n = len(inside)
    nb: list[dict[int, list[float]]] = [dict() for _ in range(n)]
    perimeter_closed = np.zeros(n)
    perimeter = np.zeros(n)
    for a, b, length, closed in edges:
        if a == b:
            continue
        for x in (a, b):
            perimeter[x] += length
            perimeter_closed[x] += closed
        if inside[a] and inside[b]:
            for x, y in ((a, b), (b, a)):
                entry = nb[x].setdefault(y, [0.0, 0.0])
                entry[0] += closed
                entry[1] += length
    regions = _Regions(n)
    area = np.asarray(area, dtype=np.float64).copy()
    def key(cl: float, tl: float) -> float:
        return cl - tl  # the longest open boundary first (a heap pops the least)

    heap = [(key(*nb[a][b]), a, b) for a in range(n) for b in nb[a] if a < b]
    heapq.heapify(heap)

    def merge(a: int, b: int) -> None:
        regions.parent[b] = a
        area[a] += area[b]
        perimeter[a] += perimeter[b] - 2 * nb[a][b][1]
        perimeter_closed[a] += perimeter_closed[b] - 2 * nb[a][b][0]
        del nb[a][b], nb[b][a]
        for c, (cl, tl) in nb[b].items():
            entry = nb[a].setdefault(c, [0.0, 0.0])
            entry[0] += cl
            entry[1] += tl
            nb[c].pop(b)
            nb[c][a] = entry
            heapq.heappush(heap, (key(*entry), min(a, c), max(a, c)))
        nb[b] = {}

    while heap:
        ev, a, b = heapq.heappop(heap)
        if regions.find(a) != a or regions.find(b) != b or b not in nb[a]:
            continue
        cl, tl = nb[a][b]
        if abs(key(cl, tl) - ev) > 1e-12:
            continue  # stale: this pair's boundary grew since
        if cl / tl >= BOUNDARY_EVIDENCE:
            continue  # more wall than opening: two rooms
        merge(a, b)
    # regions below the room area join the neighbour they share most boundary with,
    # unless walls enclose them
    while True:
        roots = [r for r in range(n) if inside[r] and regions.find(r) == r]
        small = sorted((area[r], r) for r in roots if area[r] < min_area_m2 and nb[r]
                       and perimeter_closed[r] < ENCLOSED_SHARE * perimeter[r])  # fmt: skip
        if not small:
            break
        r = small[0][1]
        other = max(sorted(nb[r]), key=lambda c: nb[r][c][1])
        a, b = (other, r) if area[other] >= area[r] else (r, other)
        merge(a, b)
    return np.array([regions.find(c) if inside[c] else -1 for c in range(n)], dtype=np.int64)

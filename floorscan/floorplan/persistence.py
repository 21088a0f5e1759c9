"""Step 4 of the rooms (:mod:`floorscan.floorplan.rooms`): the watershed regions of the
space merged into rooms across every passage that is no door.

The regions are the basins of the distance to the nearest wall (step 3); two basins
meet at a saddle, the widest passage between them, of half-width ``s`` (the distance
at the saddle), and each basin has a peak ``p``, the radius of the largest disc inside
it. The passage between two basins is a door when:

- walls frame it: both ends of the contact stand near a wall or a seen obstacle that
  is no object standing free (the caller's ``framed`` pairs,
  :mod:`floorscan.floorplan.rooms`, :func:`~floorscan.floorplan.jambs.jamb_cells`): a
  narrowing that ends in unseen space (the shadow of a table) or at a desk is no door;
- it is no wider than a door: ``2 s <= door_max_m``; or, for a pair whose contact is
  an opening wider than a door between jambs and on no wall's face (the caller's
  ``wide`` pairs: a room's open side), no wider than ``wide_max_m``;
- and the space on both sides of it is wider than it: the saddle is at most
  :data:`DOOR_SHARE` of the peak of each of the two basins it joins (the widest place
  of the space beside it).

Every other pair of touching basins is one room: the rooms are the connected
components of the basins joined across the passages that are no door. A corridor cut
into basins by the noise of its walls is one corridor (its saddles are as high as its
peaks), a room behind a door stays apart, and a corridor narrowed by a jamb or a
cabinet by less than a quarter of the width of its basins beside the narrowing stays
one corridor, whatever hall or junction it leads to. Where the watershed gives the
stretch beside a passage to the junction it leads to (a corridor's even stretch has no
maximum of its own), that basin is as wide as the junction, and the passage can still
be a door; inside a corridor between two parallel walls, the caller measures it against
the corridor's width (:func:`~floorscan.floorplan.corridors.across_corridor`).

The saddle against the peaks is persistence as topological data analysis measures it
(a basin of peak ``p`` persists from ``p`` down to its saddle ``s``; Chazal, Guibas,
Oudot and Skraba, "Persistence-based clustering in Riemannian manifolds", J. ACM 60(6),
2013, ToMATo), relative to the peak. ToMATo visits the pairs from the highest saddle
down and compares a saddle with the peak of the whole cluster each side has joined so
far: a corridor's narrowing became a door as soon as each half had joined a wider hall
or junction (aces' corridors were cut where they narrow by a tenth,
``benchmarks/README.md``). Compared with the two basins it joins, each passage is
judged alone, in no order. The decision uses the distance field and where the walls
stand, nothing of the order the regions were numbered in, so it is the same under any
rigid motion of the input, up to the raster.

Bormann et al. ("Room segmentation: survey, implementation, and analysis", ICRA
2016) segment on the same distance transform by a global threshold; the saddle against
the peaks beside it makes the threshold local to each passage.
"""

from __future__ import annotations

import numpy as np

#: A door is at most this share of the width of the narrower space it joins: a 0.9 m
#: door into a 1.2 m closet is 0.75 of it, while a corridor narrowed by the end of a
#: wall, a jamb or the raster's cells by less than a quarter of its width is still one
#: corridor (the room benchmarks and the synthetic buildings: ``benchmarks/README.md``).
DOOR_SHARE = 0.75


def saddles(labels: np.ndarray, distance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The saddle between every pair of 4-adjacent regions.

    Parameters
    ----------
    labels : (H, W) int ndarray
        0 outside the space, else the region (1..R).
    distance : (H, W) float ndarray
        Distance to the nearest cell outside the space, metres.

    Returns
    -------
    pairs : (P, 2) int64 ndarray
        ``a < b``, each pair once.
    height : (P,) float64 ndarray
        The saddle: the largest, over the cells where ``a`` and ``b`` touch, of the
        smaller distance of the two touching cells, metres.
    """
    keys, heights = [], []
    n = int(labels.max()) + 1
    for a_sl, b_sl in (((slice(None), slice(0, -1)), (slice(None), slice(1, None))),
                       ((slice(0, -1), slice(None)), (slice(1, None), slice(None)))):  # fmt: skip
        la, lb = labels[a_sl], labels[b_sl]
        m = (la != lb) & (la > 0) & (lb > 0)
        lo, hi = np.minimum(la[m], lb[m]).astype(np.int64), np.maximum(la[m], lb[m]).astype(np.int64)
        keys.append(lo * n + hi)
        heights.append(np.minimum(distance[a_sl][m], distance[b_sl][m]))
    key, height = np.concatenate(keys), np.concatenate(heights)
    if not len(key):
        return np.zeros((0, 2), dtype=np.int64), np.zeros(0)
    order = np.lexsort((height, key))
    key, height = key[order], height[order]
    last = np.r_[key[1:] != key[:-1], True]
    key = key[last]
    return np.column_stack([key // n, key % n]), height[last].astype(np.float64)


def persistent_rooms(labels: np.ndarray, distance: np.ndarray, door_max_m: float, framed=None, wide=frozenset(),
                     wide_max_m: float = 0.0) -> np.ndarray:
    """The regions merged into rooms (the module docstring).

    Parameters
    ----------
    labels : (H, W) int ndarray
        0 outside the space, else the region (1..R).
    distance : (H, W) float ndarray
        Metres.
    door_max_m : float
        The widest door, metres.
    framed : set of (int, int), optional
        The pairs ``(a, b)``, ``a < b``, whose contact walls frame (a door in a wall's
        line, or a slit between wall pieces): only these can be doors. None: any pair.
    wide : set of (int, int), optional
        Pairs of ``framed`` that meet through an opening wider than a door between
        jambs (a room's open side): their passage may be up to ``wide_max_m`` wide.
    wide_max_m : float
        The widest such opening, metres.

    Returns
    -------
    (R + 1,) int64 ndarray
        Each region's room (the label of one of its regions); ``root[0] == 0`` (label 0
        touches no region, so it stays alone).
    """
    from scipy.cluster.hierarchy import DisjointSet

    n = int(labels.max())
    peak = np.zeros(n + 1)
    if n:  # each region's largest distance (SciPy's ndimage.maximum, without its sort)
        inside = labels > 0
        peak[1:] = -np.inf
        np.maximum.at(peak, labels[inside], distance[inside])
        peak[np.isneginf(peak)] = 0.0  # a label without cells, as ndimage.maximum
    pairs, height = saddles(labels, distance)
    groups = DisjointSet(range(n + 1))
    for (a, b), s in zip(pairs.tolist(), height.tolist()):
        widest = wide_max_m if (a, b) in wide else door_max_m
        if (framed is None or (a, b) in framed) and 2 * s <= widest and s <= DOOR_SHARE * min(peak[a], peak[b]):
            continue  # a door or a room's open side: the rooms on its two sides stay apart
        groups.merge(a, b)
    return np.array([groups[i] for i in range(n + 1)], dtype=np.int64)

"""Wall faces hidden behind the objects that stand against them (the structure passes,
:mod:`floorscan.floorplan.structure`, steps 2 and 5).

A cabinet, a shelf or a desk pushed against a wall hides the wall's face: the scans (and
a map's obstacle cells) show the object's front instead, parallel to the wall and
``front_min_m`` to ``front_max_m`` in front of it on its free side, while the wall's face
goes on beside the object, in the same line. A floor plan draws the wall, not the
object: the room's floor runs under its furniture, and its walls are its structure
(issue 44; the thesis's clutter, sections 1.3 and 2.3). So:

two collinear faces whose gap is covered by such fronts (:func:`covered_by_fronts`) are
one face across it, up to :data:`HIDDEN_MAX_GAP_M`
(:func:`floorscan.floorplan.structure.join_collinear`), and the fronts, now in front of
a wall, are clutter (:func:`floorscan.floorplan.clutter.in_front_of_walls`). Free space
across the gap still makes it an opening (the joins' own test): a doorway between two
cabinets stays a door. Sides of the objects are left to the other passes: a face that
runs from a wall to the end of a front may be a partition's stub as well.
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.free_space import StructureParams

#: The longest object against a wall whose hidden face is joined, metres: a row of
#: cabinets or shelves, two of the longest pieces of furniture (``clutter_max_length_m``).
HIDDEN_MAX_GAP_M = 5.0


def free_normals(seg: np.ndarray, side: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each face's direction, length and the unit normal towards its free side.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    side : (F,) int ndarray
        Free sides (+1 left, -1 right, 0 both or neither;
        :func:`~floorscan.floorplan.structure.border_and_support`).

    Returns
    -------
    u : (F, 2) float64 ndarray
    length : (F,) float64 ndarray
        Metres.
    n : (F, 2) float64 ndarray
        Zero where ``side`` is 0.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    d = seg[:, 2:] - seg[:, :2]
    length = np.hypot(d[:, 0], d[:, 1])
    u = d / np.maximum(length, 1e-12)[:, None]
    n = np.column_stack([-u[:, 1], u[:, 0]]) * np.sign(np.asarray(side, dtype=np.float64))[:, None]
    return u, length, n


def covered_by_fronts(seg: np.ndarray, side: np.ndarray, a: int, t0: float, t1: float,
                      params: StructureParams = StructureParams()) -> bool:  # fmt: skip
    """Whether the stretch ``t0..t1`` of face ``a``'s line is hidden by objects standing
    against it: faces parallel to it (within ``join_angle_deg``), with their free side
    the same way, ``front_min_m`` to ``front_max_m`` in front of it, cover at least
    ``front_overlap`` of the stretch.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    side : (F,) int ndarray
        Free sides.
    a : int
        The face whose line is tested; its free side must be known (``side[a] != 0``).
    t0, t1 : float
        The stretch along ``a``'s line from its first end, metres, ``t0 < t1``.
    params : StructureParams

    Returns
    -------
    bool
    """
    u, length, n = free_normals(seg, side)
    if side[a] == 0 or t1 <= t0:
        return False
    parallel = np.abs(u @ u[a]) >= np.cos(np.radians(params.join_angle_deg))
    same_way = (n @ n[a]) > 0
    mid = 0.5 * (seg[:, :2] + seg[:, 2:])
    depth = (mid - seg[a, :2]) @ n[a]
    front = parallel & same_way & (depth >= params.front_min_m) & (depth <= params.front_max_m)
    front[a] = False
    if not front.any():
        return False
    s = np.sort(np.column_stack([(seg[front, :2] - seg[a, :2]) @ u[a], (seg[front, 2:] - seg[a, :2]) @ u[a]]), axis=1)
    s = np.clip(s, t0, t1)
    s = s[np.argsort(s[:, 0])]
    covered, reach = 0.0, t0
    for lo, hi in s.tolist():  # the union of the fronts' stretches
        lo = max(lo, reach)
        if hi > lo:
            covered += hi - lo
            reach = hi
    return covered >= params.front_overlap * (t1 - t0)

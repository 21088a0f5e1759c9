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
(:func:`floorscan.floorplan.structure.join_collinear`); a face that ends at an object
standing in a corner runs on behind its front to the corner (:func:`into_corners`);
and the fronts, now in front of a wall, are clutter
(:func:`floorscan.floorplan.clutter.in_front_of_walls`). Free space
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
                      params: StructureParams = StructureParams(), beside_max_m: float | None = None) -> bool:  # fmt: skip
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
    beside_max_m : float, optional
        Fronts that run beside face ``a`` itself for longer than this (metres: the
        other face of its wall) do not count; None: all count.

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
    s = np.sort(np.column_stack([(seg[:, :2] - seg[a, :2]) @ u[a], (seg[:, 2:] - seg[a, :2]) @ u[a]]), axis=1)
    if beside_max_m is not None:
        front &= np.minimum(s[:, 1], length[a]) - np.maximum(s[:, 0], 0.0) <= beside_max_m
    if not front.any():
        return False
    s = s[front]
    s = np.clip(s, t0, t1)
    s = s[np.argsort(s[:, 0])]
    covered, reach = 0.0, t0
    for lo, hi in s.tolist():  # the union of the fronts' stretches
        lo = max(lo, reach)
        if hi > lo:
            covered += hi - lo
            reach = hi
    return covered >= params.front_overlap * (t1 - t0)


def into_corners(seg: np.ndarray, side: np.ndarray, open_run, params: StructureParams = StructureParams()) -> np.ndarray:
    """Faces that end at an object standing in a corner, extended to the corner.

    An object in a room's corner (a cabinet, an L of shelves) hides the two walls up to
    their corner: a wall face ends at the object's side, the object's front runs on,
    parallel, in front of the face's line up to the other wall. Face ``a``'s end is
    moved to where its line meets a face square to it (at least
    ``junction_min_angle_deg`` apart) when that point lies at most
    :data:`HIDDEN_MAX_GAP_M` beyond the end and within ``front_max_m`` of that face,
    fronts cover the stretch (:func:`covered_by_fronts`; a face running beside ``a``
    itself for more than ``front_max_m`` is the other face of its wall, not a front)
    and free space does not cross it (``open_run`` shorter than ``min_opening_m``).
    The nearest such face along the line is the corner.

    Parameters
    ----------
    seg : (F, 4) float ndarray
        Faces, metres.
    side : (F,) int ndarray
        Free sides.
    open_run : callable
        ``open_run(p, u, t0, t1)``: the longest run of free space on the stretch
        ``t0..t1`` of the line through ``p`` along ``u``, metres
        (:func:`floorscan.floorplan.structure.join_collinear`'s test).
    params : StructureParams

    Returns
    -------
    (F, 4) float64 ndarray
        The faces, some ends moved; metres.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    side = np.asarray(side)
    u, length, _ = free_normals(seg, side)
    square = np.sin(np.radians(params.junction_min_angle_deg))
    out = seg.copy()
    for a in np.flatnonzero(side != 0).tolist():
        for k in (0, 1):
            end = seg[a, 2 * k : 2 * k + 2]
            out_dir = u[a] if k == 1 else -u[a]
            # where a's line meets each other face's line, t beyond a's end
            denom = out_dir[0] * u[:, 1] - out_dir[1] * u[:, 0]
            w = seg[:, :2] - end
            with np.errstate(divide="ignore", invalid="ignore"):  # parallel lines: t inf or nan, not ok
                t = (w[:, 0] * u[:, 1] - w[:, 1] * u[:, 0]) / denom
                x = end + t[:, None] * out_dir
                s = np.einsum("ij,ij->i", x - seg[:, :2], u)
                ok = (np.abs(denom) >= square) & (t > 0) & (t <= HIDDEN_MAX_GAP_M)
                ok &= (s >= -params.front_max_m) & (s <= length + params.front_max_m)
            ok[a] = False
            if not ok.any():
                continue
            p = int(np.flatnonzero(ok)[np.argmin(t[ok])])
            t, x = float(t[p]), x[p]
            t0 = float((end - seg[a, :2]) @ u[a])
            lo, hi = (t0, t0 + t) if k == 1 else (t0 - t, t0)
            covered = covered_by_fronts(seg, side, a, lo, hi, params, beside_max_m=params.front_max_m)
            if covered and open_run(end, out_dir, 0.0, t) < params.min_opening_m:
                out[a, 2 * k : 2 * k + 2] = x
    return out

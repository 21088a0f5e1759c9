"""Step 5 of the structure passes (:mod:`floorscan.floorplan.structure`), objects in the
two corners where a partition meets a wall: their fronts, flush with the partition's end,
are one face in the map, and the partition seems to end on it.

Two cabinets (or counters) stand against a wall, one on each side of a partition that
meets it, their fronts in one line with the partition's end. The map shows the fronts
and the partition up to them; the wall behind and the partition's last metre are
hidden. Step 2 joins the two fronts across the partition's end into one face, longer
than any object (:func:`~floorscan.floorplan.clutter.in_front_of_walls` takes fronts up
to :data:`~floorscan.floorplan.hidden.HIDDEN_MAX_GAP_M`), and the wall face behind
is in two pieces, one on each side of the partition, neither covering the joined front:
so the front was a wall, the partition stopped on it, and the floor under the objects
was no room's. People draw the rooms up to the wall and the partition through to it
(the furniture-free twins of Bormann et al.'s maps, ICRA 2016).

:func:`fronts_between_partitions` judges such a face by its runs between the
partitions that meet it from its free side (square faces ending on it, on the side the
room is): where every run is an object's front against a wall face behind it (the
step's own test, :func:`~floorscan.floorplan.clutter.in_front_of_walls`), the face is
a front, each run has its floor under it, and each partition face that ended on it runs
on to the wall face behind (its line's crossing with that face's line, no farther than
an object is deep).
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.clutter import in_front_of_walls
from floorscan.floorplan.free_space import StructureParams
from floorscan.floorplan.hidden import OBJECT_MAX_DEPTH_M, free_normals
from floorscan.floorplan.params import PAIR_MAX_M


def fronts_between_partitions(seg: np.ndarray, side: np.ndarray, anchor: np.ndarray, junctions: np.ndarray,
                              front: np.ndarray, behind: np.ndarray, params: StructureParams = StructureParams(),
                              free_at=None):  # fmt: skip
    """The long faces that are fronts run by run between the partitions that meet them
    (module docstring).

    Parameters
    ----------
    seg : (F, 4) float ndarray
        The snapped faces, metres.
    side : (F,) int ndarray
        Their free sides.
    anchor : (F,) bool ndarray
        The long faces (walls a front can stand against).
    junctions : (J, 5) float ndarray
        ``x, y, i, j, kind`` (:func:`~floorscan.floorplan.junctions.snap_junctions`).
    front, behind : (F,) ndarray
        :func:`~floorscan.floorplan.clutter.in_front_of_walls` on ``seg``.
    params : StructureParams
    free_at : callable, optional
        As :func:`~floorscan.floorplan.clutter.in_front_of_walls`.

    Returns
    -------
    front : (F,) bool ndarray
        ``front`` with the faces found here.
    behind : (F,) int64 ndarray
        ``behind``; a face found here stands against its first run's wall face.
    runs : (R, 4) float64 ndarray
        The runs of the faces found here, metres.
    runs_behind : (R, 4) float64 ndarray
        The wall face behind each run, metres.
    carried : list of (int, int, (2,) ndarray)
        Each partition face run on to the wall behind: face, end (0 or 1), new end.
    """
    seg = np.asarray(seg, dtype=np.float64).reshape(-1, 4)
    front, behind = front.copy(), behind.copy()
    none = (front, behind, np.empty((0, 4)), np.empty((0, 4)), [])
    if not len(junctions):
        return none
    u, length, free_n = free_normals(seg, side)
    square = np.sin(np.radians(params.junction_min_angle_deg))
    at_face: dict[int, list] = {}  # each face's junctions: (x, y, the other face)
    for x, y, i, j, _ in junctions.tolist():
        at_face.setdefault(int(i), []).append((x, y, int(j)))
        at_face.setdefault(int(j), []).append((x, y, int(i)))
    pieces, parent, cuts_of = [], [], {}
    for f in np.flatnonzero(anchor & ~front & (side != 0)).tolist():
        cuts = []  # (t along f, partition face, its end on f)
        for x, y, g in at_face.get(f, []):
            if abs(u[f, 0] * u[g, 1] - u[f, 1] * u[g, 0]) < square:
                continue
            for k in (0, 1):  # g's end k on f, its other end on f's free side
                at_f = np.hypot(*(seg[g, 2 * k : 2 * k + 2] - (x, y))) <= 0.02  # as junction_ends
                if at_f and (seg[g, 2 - 2 * k : 4 - 2 * k] - seg[f, :2]) @ free_n[f] > 0:
                    cuts.append((float((np.array([x, y]) - seg[f, :2]) @ u[f]), g, k))
        cuts = sorted(c for c in cuts if 0.0 < c[0] < length[f])
        if not cuts:
            continue
        # the runs between the cuts, less a partition's body: a stretch no longer than the
        # thickest wall, or between two faces free away from it
        toward = [float(free_n[g] @ u[f]) for _, g, _ in cuts]  # > 0: free toward larger t
        edges = [0.0] + [t for t, _, _ in cuts] + [float(length[f])]
        runs = []
        for m in range(len(cuts) + 1):
            a, b = edges[m], edges[m + 1]
            body = 0 < m < len(cuts) and (b - a <= PAIR_MAX_M or toward[m - 1] < 0 < toward[m])
            if not body and b - a >= params.front_min_m:
                runs.append((a, b))
        if len(runs) < 2:
            continue
        cuts_of[f] = cuts
        for a, b in runs:
            pieces.append(np.r_[seg[f, :2] + a * u[f], seg[f, :2] + b * u[f]])
            parent.append(f)
    if not pieces:
        return none
    pieces, parent = np.array(pieces), np.array(parent)
    # the runs judged among all the faces (a deep front's wall is backed by its other
    # face, a face of any length); a run as long as a long face is judged as one
    n = len(seg)
    run_length = np.hypot(pieces[:, 2] - pieces[:, 0], pieces[:, 3] - pieces[:, 1])
    long_ = np.r_[anchor, run_length >= params.clutter_max_length_m]
    every, every_side = np.vstack([seg, pieces]), np.r_[side, side[parent]]
    run_front, run_behind = in_front_of_walls(every, every_side, long_, params, free_at)
    run_front, run_behind = run_front[n:], run_behind[n:]
    run_front &= (run_behind >= 0) & (run_behind < n)  # against a face of the plan, not another run
    runs_out, behind_out, carried = [], [], []
    for f in np.unique(parent).tolist():
        mine = np.flatnonzero(parent == f)
        if not run_front[mine].all():
            continue
        front[f], behind[f] = True, run_behind[mine[0]]
        runs_out.append(pieces[mine])
        behind_out.append(seg[run_behind[mine]])
        wall = seg[run_behind[mine[0]]]
        for _, g, k in cuts_of[f]:  # the partition runs on behind the fronts to the wall
            end, d = seg[g, 2 * k : 2 * k + 2], u[g] if k == 1 else -u[g]
            w = wall[2:] - wall[:2]
            denom = d[0] * w[1] - d[1] * w[0]
            if abs(denom) < 1e-9:
                continue
            t = ((wall[0] - end[0]) * w[1] - (wall[1] - end[1]) * w[0]) / denom
            if 0.0 < t <= OBJECT_MAX_DEPTH_M:
                carried.append((g, k, end + t * d))
    if not runs_out:
        return none
    return front, behind, np.vstack(runs_out), np.vstack(behind_out), carried

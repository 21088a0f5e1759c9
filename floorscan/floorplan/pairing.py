"""Pair the two faces of a wall into one wall with its thickness (:func:`pair_faces`):
two merged faces (:mod:`floorscan.floorplan.merge`) that are near parallel, a wall's
thickness apart (``pair_min_m`` to ``pair_max_m``, 5 to 40 cm by default) and overlap
along the wall are one wall, whose axis is the line halfway between them
(:func:`_axis_between`) and whose thickness is their distance; a face without a
partner is a wall of ``default_thickness_m``. In a map, whose occupied cells draw a
wall's cross-section, faces up to :data:`THICK_WALL_MAX_M` apart are one wall where
the cells between them are occupied and another wall meets it.
Source: the duplicate problem of thesis section 5.1 (a wall's two faces are two walls
to the extractor); the rule is ours.
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.candidates import candidate_pairs, line_geometry
from floorscan.floorplan.params import FloorplanParams

#: The thickest wall a map's occupied cells can show, metres: an exterior wall of
#: masonry (0.3 to 0.6 m); the maps of Bormann et al.'s room benchmark draw their walls
#: 0.5 m thick. Beyond ``pair_max_m`` a pair needs the wall's body seen occupied.
THICK_WALL_MAX_M = 0.6


def pair_faces(
    faces: np.ndarray, weights: np.ndarray, params: FloorplanParams = FloorplanParams(), grid=None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pair the two faces of a wall into one wall with its thickness.

    Two faces are one wall when their directions differ by at most
    ``pair_angle_deg``, the distance between their lines (measured from the longer
    face's line to the shorter's midpoint) is in ``[pair_min_m, pair_max_m]``, and
    they overlap along the wall by at least ``pair_min_overlap`` of the shorter. With a
    grid, two faces up to :data:`THICK_WALL_MAX_M` apart are also one wall where the
    band between them is the wall's body, seen occupied (at least half of the line
    halfway between them, over their overlap: a map that draws a thick wall's
    cross-section; a recording sees a wall's faces, never its inside), and another
    wall meets it (:func:`_structural`). Pairs are taken greedily, nearest first, each
    face in at most one pair. The
    wall's axis is the line halfway between the two faces (direction the
    length-weighted axial mean), its extent the union of both faces' projections,
    its thickness their distance. An unpaired face becomes a wall whose axis is the
    face itself (which side the wall body lies on is not known) with
    ``default_thickness_m``.

    Parameters
    ----------
    faces : (F, 4) float ndarray
        Merged faces ``x0, y0, x1, y1``, metres.
    weights : (F,) float ndarray
    params : FloorplanParams
    grid : OccupancyGrid, optional
        The occupancy grid of the faces' scans, or a map.

    Returns
    -------
    axes : (W, 4) float64 ndarray
        Wall axes, metres.
    thickness : (W,) float64 ndarray
        Metres.
    wall_of_face : (F,) int64 ndarray
        Wall of each face.
    """
    faces = np.asarray(faces, dtype=np.float64).reshape(-1, 4)
    nf = len(faces)
    wall_of_face = np.full(nf, -1, dtype=np.int64)
    axes, thick = [], []
    reach = max(params.pair_max_m, THICK_WALL_MAX_M) if grid is not None else params.pair_max_m
    i, j = candidate_pairs(faces, reach, np.radians(params.pair_angle_deg))
    if len(i):  # within pair_angle_deg already (candidate_pairs)
        a, b, d, n, length = line_geometry(faces, i, j)
        midb = 0.5 * (faces[b, :2] + faces[b, 2:])
        dist = np.abs(np.einsum("ij,ij->i", midb - faces[a, :2], n))
        tb0 = np.einsum("ij,ij->i", faces[b, :2] - faces[a, :2], d)
        tb1 = np.einsum("ij,ij->i", faces[b, 2:] - faces[a, :2], d)
        overlap = np.minimum(length[a], np.maximum(tb0, tb1)) - np.maximum(0.0, np.minimum(tb0, tb1))
        ok = (
            (dist >= params.pair_min_m)
            & (dist <= reach)
            & (overlap >= params.pair_min_overlap * np.minimum(length[a], length[b]))
        )
        body = ok & (dist > params.pair_max_m)
        if body.any():
            ok[body] = _occupied_between(faces, a[body], b[body], n[body], d[body], tb0[body], tb1[body],
                                         length[a][body], grid)  # fmt: skip
        for k in np.flatnonzero(ok & body):
            ok[k] = _structural(faces, a[k], b[k], float(dist[k]), params)
        order = np.lexsort((j[ok], i[ok], dist[ok]))
        pairs = []
        for p, q in zip(i[ok][order].tolist(), j[ok][order].tolist()):
            if wall_of_face[p] >= 0 or wall_of_face[q] >= 0:
                continue
            wall_of_face[p] = wall_of_face[q] = len(pairs)
            pairs.append((p, q))
        if pairs:
            p, q = np.array(pairs, dtype=np.int64).T
            pair_axes, pair_thick = _axis_between(faces[p], faces[q])
            axes.extend(pair_axes)
            thick.extend(pair_thick.tolist())
    for f in range(nf):
        if wall_of_face[f] < 0:
            wall_of_face[f] = len(axes)
            axes.append(faces[f].copy())
            thick.append(params.default_thickness_m)
    return np.array(axes).reshape(-1, 4), np.array(thick, dtype=np.float64), wall_of_face


def _structural(faces: np.ndarray, a: int, b: int, dist: float, params: FloorplanParams) -> bool:
    """Whether another wall meets the wall of faces ``a`` and ``b`` (``dist`` metres
    apart) in an L or T junction: a face at more than ``pair_angle_deg`` to it and
    longer than twice ``dist`` (not a wall's end face) passes within ``dist`` of its
    axis. A wall that thick is masonry, joined to the building's other walls; a block
    that thick standing free is furniture (a rack, a row of cabinets)."""
    import shapely

    axis = _axis_between(faces[[a]], faces[[b]])[0][0]
    u = axis[2:] - axis[:2]
    others = np.delete(faces, [a, b], axis=0)
    v = others[:, 2:] - others[:, :2]
    flen = np.hypot(v[:, 0], v[:, 1])
    cos = np.abs(v @ u) / np.maximum(flen * float(np.hypot(*u)), 1e-12)
    near = others[(flen > 2 * dist) & (cos < np.cos(np.radians(params.pair_angle_deg)))]
    line = shapely.LineString(axis.reshape(2, 2))
    return bool(len(near)) and bool((shapely.distance(line, shapely.linestrings(near.reshape(-1, 2, 2))) <= dist).any())


def _occupied_between(faces, a, b, n, d, tb0, tb1, length_a, grid) -> np.ndarray:
    """(P,) bool: whether at least half of the line halfway between faces ``a`` and
    ``b`` (P pairs; ``n``, ``d`` face ``a``'s unit normal and direction, ``tb0``, ``tb1``
    face ``b``'s ends along it, metres), sampled a cell apart over their overlap, lies
    on cells ``grid`` holds occupied."""
    from floorscan.floorplan.free_space import mask_at, segment_samples

    lo = np.maximum(0.0, np.minimum(tb0, tb1))
    hi = np.maximum(lo, np.minimum(length_a, np.maximum(tb0, tb1)))
    off = 0.5 * np.einsum("ij,ij->i", 0.5 * (faces[b, :2] + faces[b, 2:]) - faces[a, :2], n)
    start = faces[a, :2] + d * lo[:, None] + n * off[:, None]
    end = faces[a, :2] + d * hi[:, None] + n * off[:, None]
    pts, owner, _ = segment_samples(np.hstack([start, end]), grid.resolution_m)
    hit = mask_at(grid, grid.occupied(), pts)
    share = np.bincount(owner, weights=hit, minlength=len(a)) / np.maximum(np.bincount(owner, minlength=len(a)), 1)
    return share >= 0.5


def _axis_between(f: np.ndarray, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centre lines between pairs of near-parallel faces, (P, 4) metres, and their
    distances, (P,) metres; ``f`` and ``g`` are (P, 4) faces."""
    vf, vg = f[:, 2:] - f[:, :2], g[:, 2:] - g[:, :2]
    lf, lg = np.hypot(vf[:, 0], vf[:, 1]), np.hypot(vg[:, 0], vg[:, 1])
    af, ag = np.arctan2(vf[:, 1], vf[:, 0]), np.arctan2(vg[:, 1], vg[:, 0])
    # Length-weighted axial mean of the two directions.
    phi = 0.5 * np.arctan2(lf * np.sin(2 * af) + lg * np.sin(2 * ag), lf * np.cos(2 * af) + lg * np.cos(2 * ag))
    u = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    n = np.stack([-u[:, 1], u[:, 0]], axis=1)
    of = np.einsum("ij,ij->i", n, 0.5 * (f[:, :2] + f[:, 2:]))
    og = np.einsum("ij,ij->i", n, 0.5 * (g[:, :2] + g[:, 2:]))
    t = np.stack([np.einsum("ij,ij->i", e, u) for e in (f[:, :2], f[:, 2:], g[:, :2], g[:, 2:])], axis=1)
    off = 0.5 * (of + og)
    a = off[:, None] * n + t.min(axis=1)[:, None] * u
    b = off[:, None] * n + t.max(axis=1)[:, None] * u
    return np.concatenate([a, b], axis=1), np.abs(of - og)

"""Pair the two faces of a wall into one wall with its thickness (:func:`pair_faces`):
two merged faces (:mod:`floorscan.floorplan.merge`) that are near parallel, a wall's
thickness apart (``pair_min_m`` to ``pair_max_m``, 5 to 40 cm by default) and overlap
along the wall are one wall, whose axis is the line halfway between them
(:func:`_axis_between`) and whose thickness is their distance; a face without a
partner is a wall of ``default_thickness_m``.
Source: the duplicate problem of thesis section 5.1 (a wall's two faces are two walls
to the extractor); the rule is ours.
"""

from __future__ import annotations

import numpy as np

from floorscan.floorplan.candidates import candidate_pairs, line_geometry
from floorscan.floorplan.params import FloorplanParams


def pair_faces(
    faces: np.ndarray, weights: np.ndarray, params: FloorplanParams = FloorplanParams()
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pair the two faces of a wall into one wall with its thickness.

    Two faces are one wall when their directions differ by at most
    ``pair_angle_deg``, the distance between their lines (measured from the longer
    face's line to the shorter's midpoint) is in ``[pair_min_m, pair_max_m]``, and
    they overlap along the wall by at least ``pair_min_overlap`` of the shorter.
    Pairs are taken greedily, nearest first, each face in at most one pair. The
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
    i, j = candidate_pairs(faces, params.pair_max_m, np.radians(params.pair_angle_deg))
    if len(i):  # within pair_angle_deg already (candidate_pairs)
        a, b, d, n, length = line_geometry(faces, i, j)
        midb = 0.5 * (faces[b, :2] + faces[b, 2:])
        dist = np.abs(np.einsum("ij,ij->i", midb - faces[a, :2], n))
        tb0 = np.einsum("ij,ij->i", faces[b, :2] - faces[a, :2], d)
        tb1 = np.einsum("ij,ij->i", faces[b, 2:] - faces[a, :2], d)
        overlap = np.minimum(length[a], np.maximum(tb0, tb1)) - np.maximum(0.0, np.minimum(tb0, tb1))
        ok = (
            (dist >= params.pair_min_m)
            & (dist <= params.pair_max_m)
            & (overlap >= params.pair_min_overlap * np.minimum(length[a], length[b]))
        )
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

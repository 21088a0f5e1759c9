"""Clustering RANSAC: the wall segments of one scan (thesis section 3.4).

:func:`cluster_ransac` finds the walls of a scan in four steps:

1. a normal per point (:func:`floorscan.walls.normals.point_normals`);
2. MeanShift of the normal directions (:mod:`floorscan.walls.meanshift`);
3. within each direction cluster, the points projected along the cluster's normal
   (:func:`wall_signature`) and clustered by a 1D MeanShift: one cluster per wall
   line, parallel walls apart;
4. one RANSAC line per cluster (:func:`floorscan.walls.ransac.fit_wall`), turned into
   wall segments by the rules of :mod:`floorscan.walls.segments`.

The MeanShift is scikit-learn's algorithm vectorised over the seeds
(:func:`floorscan.walls.meanshift.mean_shift`), kept because scikit-learn's, one seed
and one neighbour query at a time, is about 30x slower on these small 1D projections.

Parameters: :class:`~floorscan.walls.params.RansacParams` (RANSAC and segments) and
:class:`~floorscan.walls.params.ClusterParams` (normals and MeanShift).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from floorscan.walls.meanshift import mean_shift_labels
from floorscan.walls.normals import point_normals
from floorscan.walls.params import ClusterParams, RansacParams
from floorscan.walls.ransac import fit_wall
from floorscan.walls.tables import segments_frame


def cluster_ransac(
    points: np.ndarray,
    params: RansacParams = RansacParams(),
    cluster: ClusterParams = ClusterParams(),
    seed=0,
) -> pd.DataFrame:
    """Wall segments of one scan by clustering RANSAC (thesis section 3.4).

    1. A normal per point (:func:`~floorscan.walls.normals.point_normals`, the
       neighbourhoods of Open3D's hybrid search).
    2. MeanShift (flat kernel, bin seeding: scikit-learn's algorithm, by default in
       its vectorised form :func:`~floorscan.walls.meanshift.mean_shift`) of the normal
       directions: each point's axial angle theta in [0, pi)
       is embedded as ``0.5 * (cos 2 theta, sin 2 theta)`` (no wrap-around at 0 / pi;
       distances are about angle differences in radians), bandwidth
       ``angle_bandwidth_rad``.
    3. Within each direction cluster, the points are projected along the cluster's
       normal to ``rho`` (:func:`wall_signature`) and clustered by a 1D MeanShift,
       bandwidth ``offset_bandwidth_m``: one cluster per wall line.
    4. One RANSAC (:func:`floorscan.walls.ransac._best_line` with the ``params`` of
       :func:`~floorscan.walls.ransac.ransac`) per cluster with at least
       ``min_cluster_points`` points, turned into segments by
       :func:`floorscan.walls.segments.claimed_segments` as in ``ransac`` (ends from
       all points of the scan near the line, so corner points with mixed normals still
       end the wall).

    Parameters
    ----------
    points : (N, 2) float ndarray
        Wall points of one scan (map frame), metres. Not modified.
    params : RansacParams
        RANSAC and segment parameters (``max_lines`` is not used).
    cluster : ClusterParams
    seed : int, sequence of int or numpy.random.Generator

    Returns
    -------
    pandas.DataFrame
        As :func:`~floorscan.walls.ransac.ransac`, ordered by cluster (direction, then
        offset).
    """
    return segments_frame(cluster_ransac_rows(points, params, cluster, seed))


def cluster_ransac_rows(points: np.ndarray, params: RansacParams, cluster: ClusterParams, seed) -> list[tuple]:
    """:func:`cluster_ransac` as a list of rows, before they become a frame (thesis
    section 3.4).

    Parameters
    ----------
    points : (N, 2) float ndarray
        Wall points of one scan (map frame), metres. Not modified.
    params : RansacParams
        RANSAC and segment settings.
    cluster : ClusterParams
        Normal and MeanShift settings.
    seed : int, sequence of int or numpy.random.Generator
        Seeds ``numpy.random.default_rng``; same seed, same rows.

    Returns
    -------
    list of tuple
        ``(x0, y0, x1, y1, n_inliers, rmse_m)`` per wall segment, metres; empty when the
        scan has fewer than ``max(params.min_points, 3)`` points.
    """
    rng = np.random.default_rng(seed)
    pts = np.asarray(points, dtype=np.float64)
    if len(pts) < max(params.min_points, 3):
        return []
    normals = point_normals(pts, cluster.normal_radius_m, cluster.normal_max_nn)
    has_normal = np.isfinite(normals[:, 0])
    labels = np.full(len(pts), -1)
    if has_normal.sum() >= cluster.min_cluster_points:
        theta2 = 2.0 * np.arctan2(normals[has_normal, 1], normals[has_normal, 0])
        emb = 0.5 * np.stack([np.cos(theta2), np.sin(theta2)], axis=1)
        labels[has_normal] = mean_shift_labels(
            emb, cluster.angle_bandwidth_rad, cluster.bin_seeding,
            max(1, cluster.min_cluster_points // 3), cluster.meanshift,
        )
    rho, _ = wall_signature(pts, normals, labels)
    rows: list[tuple] = []
    for lab in np.flatnonzero(np.bincount(labels[labels >= 0])):  # numpy.unique
        members = np.flatnonzero(labels == lab)
        if len(members) < cluster.min_cluster_points:
            continue
        sub = mean_shift_labels(
            rho[members, None], cluster.offset_bandwidth_m, cluster.bin_seeding,
            max(1, cluster.min_cluster_points // 3), cluster.meanshift,
        )
        for s in np.flatnonzero(np.bincount(sub[sub >= 0])):
            idx = members[sub == s]
            if len(idx) < cluster.min_cluster_points:
                continue
            fit = fit_wall(pts, idx, rng, params)
            if fit is not None:
                rows += fit[1]
    return rows


def import_cluster_modules(params: RansacParams, cluster: ClusterParams) -> None:
    """Import what :func:`cluster_ransac` will import, before the first scan is timed:
    SciPy's k-d tree, and scikit-learn when ``cluster`` asks for it.

    Parameters
    ----------
    params : RansacParams
        Unused: the signature of an :class:`~floorscan.walls.extractors.Extractor`'s ``prepare``.
    cluster : ClusterParams
        ``meanshift == "sklearn"`` or ``offset_bandwidth_m`` None imports scikit-learn.
    """
    import scipy.spatial  # noqa: F401

    if cluster.meanshift == "sklearn" or cluster.offset_bandwidth_m is None:
        import sklearn.cluster  # noqa: F401


def wall_signature(points: np.ndarray, normals: np.ndarray, angle_labels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The projection of cluster_ransac: each point moved along its wall's normal.

    For a direction cluster (points whose normals agree, label ``angle_labels``) with
    mean normal n_c (axial mean: half the angle of the mean of doubled angles) and
    centroid c, every point p of the cluster projects to ``rho = n_c . (p - c)``: the
    point slides along the normal onto the normal axis through c. All points of one
    straight wall land on one value of rho (the wall's signed distance from c),
    whatever their position along the wall; two parallel walls (e.g. the two faces of
    a 20 cm wall, or the two sides of a corridor) land at rho values that differ by
    their distance, so a 1D MeanShift on rho separates them; walls of other
    directions are in other direction clusters. This is the Hough (theta, rho) of
    the tangent line, with two changes against smearing: rho uses the cluster's mean
    normal instead of the point's own (with a per-point normal an angle error e moves
    rho by e times the distance of p along the wall from the foot point, e.g.
    0.02 rad * 10 m = 0.2 m, across parallel neighbours), and the origin is the
    cluster centroid, not the map origin (the lever arm of the small error left in
    the mean normal is then the scan's size, not the distance to the map origin).

    Parameters
    ----------
    points : (N, 2) float ndarray
    normals : (N, 2) float ndarray
        Unit normals (axial), NaN allowed for points without a normal.
    angle_labels : (N,) int ndarray
        Direction cluster of each point, -1 for none.

    Returns
    -------
    rho : (N,) float64 ndarray
        Offset along the cluster normal from the cluster centroid, metres (NaN where
        the label is -1).
    cluster_normals : (L, 2) float64 ndarray
        Mean unit normal of direction cluster 0..L-1.
    """
    labels = np.asarray(angle_labels)
    n_lab = int(labels.max()) + 1 if len(labels) and labels.max() >= 0 else 0
    theta2 = 2.0 * np.arctan2(normals[:, 1], normals[:, 0])
    cluster_normals = np.full((n_lab, 2), np.nan)
    rho = np.full(len(points), np.nan)
    for lab in range(n_lab):
        m = labels == lab
        t = theta2[m]
        t = t[np.isfinite(t)]
        if len(t) == 0:
            continue
        # means as np.add.reduce / count: what ndarray.mean computes, fewer calls
        phi = 0.5 * np.arctan2(np.add.reduce(np.sin(t)) / len(t), np.add.reduce(np.cos(t)) / len(t))
        cluster_normals[lab] = (np.cos(phi), np.sin(phi))
        pm = points[m]
        rho[m] = (pm - np.add.reduce(pm, axis=0) / len(pm)) @ cluster_normals[lab]
    return rho, cluster_normals

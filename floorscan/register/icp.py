"""Planar ICP and the fitness of a scan against a reference (thesis 3.2.2, Algorithm 3
steps 4-6).

Fitness and inlier RMSE are Open3D's definitions (``evaluate_registration``): the
fraction of *source* points whose nearest target point is within the correspondence
distance, and the RMS distance of those pairs (:func:`fitness_against`, on a
:class:`scipy.spatial.cKDTree` the caller builds once per target and reuses; a unit test
checks the numbers against Open3D).

ICP is constrained to the rover's planar motion (x, y, yaw; z, roll and pitch stay as
the pose says), for 2D and 3D scans (:func:`icp_planar`). Open3D's ICP estimates all six
degrees of freedom and offers no way to fix some of them; for 2D scans its
point-to-plane variant is degenerate (normals of a planar point set are vertical), and
projecting a 6-DoF result onto SE(2) is not the constrained optimum for 3D scans. So
each iteration pairs the points on the cached KD-tree and solves the planar problem in
closed form: the 2D Kabsch / Umeyama solution for point-to-point (exact for 3D pairs
too, since the z residual does not depend on x, y, yaw), a 3x3 linearised least-squares
step for point-to-plane (Chen and Medioni 1992; Low 2004). For 2D scans point-to-point
gives the same result as Open3D's ``registration_icp`` (tested).

Usage::

    pose, n_corr = icp_to_map(source, target, init_pose, cfg)   # coarse to fine
    fitness, rmse, n = fitness_against(transform_points(source, *pose), cKDTree(target), 0.15)
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from floorscan.core.geometry import transform_points, wrap_angle
from floorscan.register.params import RegistrationConfig
from floorscan.register.prepare import normals_2d, normals_3d


def fitness_against(
    source_map: np.ndarray, tree: cKDTree, max_distance: float
) -> tuple[float, float, int]:
    """Open3D-style fitness and inlier RMSE of points against a target's KD-tree.

    Parameters
    ----------
    source_map : (N, 3) float64 ndarray
        Source points already in the target's frame, metres.
    tree : scipy.spatial.cKDTree
        KD-tree of the target points (built once per target and reused).
    max_distance : float
        Maximum correspondence distance, metres.

    Returns
    -------
    fitness : float
        Fraction of source points with a target point within ``max_distance`` (0..1).
    inlier_rmse : float
        RMS distance of those pairs, metres (NaN without any).
    n_inliers : int
    """
    if len(source_map) == 0:
        return 0.0, math.nan, 0
    d, _ = tree.query(source_map, k=1, distance_upper_bound=max_distance)
    ok = d <= max_distance
    n = int(ok.sum())
    rmse = float(np.sqrt(np.mean(d[ok] ** 2))) if n else math.nan
    return n / len(source_map), rmse, n


def _kabsch_2d(src: np.ndarray, dst: np.ndarray) -> tuple[float, float, float]:
    """Rigid 2D transform (tx, ty, theta) minimising sum ||dst - (R src + t)||^2 (Umeyama)."""
    ms, md = src.mean(axis=0), dst.mean(axis=0)
    h = (src - ms).T @ (dst - md)  # 2x2 cross-covariance
    th = math.atan2(float(h[0, 1] - h[1, 0]), float(h[0, 0] + h[1, 1]))
    c, s = math.cos(th), math.sin(th)
    tx = md[0] - (c * ms[0] - s * ms[1])
    ty = md[1] - (s * ms[0] + c * ms[1])
    return tx, ty, th


def _point_to_plane_2d(src: np.ndarray, dst: np.ndarray, nrm: np.ndarray) -> tuple[float, float, float]:
    """One linearised point-to-plane step for planar motion (tx, ty, theta) (Low 2004).

    Minimises sum (n . (R src + t - dst))^2 with R ~ I + theta [[0,-1],[1,0]] (z rows of
    the rotation are identity, so z enters only through the normal's z component).
    """
    jac = np.empty((len(src), 3))
    jac[:, :2] = nrm[:, :2]
    jac[:, 2] = nrm[:, 1] * src[:, 0] - nrm[:, 0] * src[:, 1]
    r = np.einsum("ij,ij->i", nrm, dst - src)
    a = jac.T @ jac
    # Tiny Levenberg damping keeps a degenerate geometry (one straight wall) solvable:
    # the unobservable direction stays put instead of exploding.
    a[np.diag_indices(3)] += 1e-9 * max(float(np.trace(a)), 1e-12)
    tx, ty, th = np.linalg.solve(a, jac.T @ r)
    return float(tx), float(ty), float(th)


def icp_planar(
    source: np.ndarray,
    target: np.ndarray,
    tree: cKDTree,
    init: tuple[float, float, float, float],
    max_distance: float,
    *,
    method: str = "point_to_point",
    normals: np.ndarray | None = None,
    max_iterations: int = 30,
    tolerance: float = 1e-5,
) -> tuple[tuple[float, float, float, float], int]:
    """ICP constrained to x, y, yaw (planar rover; z, roll, pitch fixed), thesis 3.2.2.

    Each iteration pairs every transformed source point with its nearest target point
    within ``max_distance`` (cached KD-tree) and solves the planar problem in closed form.

    Parameters
    ----------
    source : (N, 3) float64 ndarray
        Source points in the scanner frame, metres.
    target : (M, 3) float64 ndarray
        Target points in the map frame, metres; ``tree`` is their KD-tree.
    tree : scipy.spatial.cKDTree
    init : tuple of float
        Initial pose (x, y, z, yaw): metres, radians. z is kept.
    max_distance : float
        Maximum correspondence distance, metres.
    method : {"point_to_point", "point_to_plane"}
    normals : (M, 3) float64 ndarray, optional
        Target normals, required for point-to-plane.
    max_iterations : int
    tolerance : float
        Stop when the step moves no source point (within the scan's extent) by more
        than this, metres.

    Returns
    -------
    pose : tuple of float
        Refined (x, y, z, yaw).
    n_correspondences : int
        Pairs in the last iteration (0: ICP failed, the initial pose is returned).

    Raises
    ------
    ValueError
        For point-to-plane without ``normals``.
    """
    if method == "point_to_plane" and normals is None:
        raise ValueError("point_to_plane ICP needs target normals")
    x, y, z, yaw = (float(v) for v in init)
    src = np.asarray(source, dtype=np.float64)
    extent = float(np.max(np.abs(src[:, :2]))) if len(src) else 1.0
    n_corr = 0
    for _ in range(int(max_iterations)):
        cur = transform_points(src, x, y, z, yaw)
        d, idx = tree.query(cur, k=1, distance_upper_bound=max_distance)
        ok = d <= max_distance
        n_corr = int(ok.sum())
        if n_corr < 3:
            return (float(init[0]), float(init[1]), float(init[2]), float(init[3])), 0
        q, p = cur[ok], target[idx[ok]]
        if method == "point_to_point":
            tx, ty, th = _kabsch_2d(q[:, :2], p[:, :2])
        else:
            tx, ty, th = _point_to_plane_2d(q, p, normals[idx[ok]])
        # compose the step (applied in the map frame) with the current pose
        c, s = math.cos(th), math.sin(th)
        x, y = c * x - s * y + tx, s * x + c * y + ty
        yaw = float(wrap_angle(yaw + th))
        if math.hypot(tx, ty) + abs(th) * extent < tolerance:
            break
    return (x, y, z, yaw), n_corr


def target_normals(target: np.ndarray, tree: cKDTree, cfg: RegistrationConfig) -> np.ndarray | None:
    """Normals of an ICP target for point-to-plane (2D PCA for planar targets, Open3D
    for 3D ones); None for point-to-point."""
    if cfg.icp_method != "point_to_plane":
        return None
    if np.ptp(target[:, 2]) < 1e-9:
        return normals_2d(target, tree, cfg.normal_neighbours)
    return normals_3d(target, cfg.normal_neighbours)


def icp_to_map(src: np.ndarray, target: np.ndarray, init, cfg: RegistrationConfig,
                tree: cKDTree | None = None, normals: np.ndarray | None = None,
                distances: tuple[float, ...] | None = None):
    """Coarse-to-fine planar ICP of a scan against a map (:func:`icp_planar` at each
    correspondence distance in turn, thesis 3.2.2).

    Parameters
    ----------
    src : (N, 3) float64 ndarray
        The scan's points in the scanner frame, metres.
    target : (M, 3) float64 ndarray
        The map's points in the map frame, metres.
    init : sequence of 4 float
        The starting pose (x, y, z, yaw): metres, radians.
    cfg : RegistrationConfig
        ``icp_max_correspondence_m`` (the distances, coarse to fine, metres),
        ``icp_method``, ``icp_max_iterations``, ``icp_tolerance_m``.
    tree : scipy.spatial.cKDTree, optional
        ``target``'s KD-tree (built when not given).
    normals : (M, 3) float64 ndarray, optional
        ``target``'s normals for point-to-plane (:func:`target_normals` when not given).
    distances : tuple of float, optional
        The correspondence distances instead of ``cfg``'s, metres.

    Returns
    -------
    pose : tuple of 4 float
        The refined (x, y, z, yaw), metres and radians; ``init`` when no point found a
        partner at the first distance.
    n_corr : int
        Correspondences at the last distance reached (0: ICP stopped for want of them).
    """
    ttree = cKDTree(target) if tree is None else tree
    nrm = normals if normals is not None else target_normals(target, ttree, cfg)
    pose, n_corr = tuple(float(v) for v in init), 0
    for dist in (cfg.icp_max_correspondence_m if distances is None else distances):  # coarse to fine
        pose, n_corr = icp_planar(
            src, target, ttree, pose, dist,
            method=cfg.icp_method, normals=nrm,
            max_iterations=cfg.icp_max_iterations, tolerance=cfg.icp_tolerance_m,
        )
        if n_corr == 0:
            break
    return pose, n_corr


def mean_fitness(pts_map: np.ndarray, trees: list[cKDTree], max_distance: float) -> tuple[float, float]:
    """Mean fitness over reference KD-trees and the pooled inlier RMSE."""
    fits, sq, cnt = [], 0.0, 0
    for tr in trees:
        f, r, k = fitness_against(pts_map, tr, max_distance)
        fits.append(f)
        if k:
            sq += r**2 * k
            cnt += k
    return float(np.mean(fits)), (math.sqrt(sq / cnt) if cnt else math.nan)

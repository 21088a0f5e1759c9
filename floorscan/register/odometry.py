"""Pose-free registration, ``mode: odometry``: LIDAR odometry from the first usable scan
(the issue's "scan-to-scan ICP odometry from the first scan"; not in the thesis).

It follows the practice of LIDAR odometry, KISS-ICP (Vizzo et al. 2023), in SE(2): the
first usable scan defines the map frame; every usable scan (``odometry_scans: all``;
``sampled``: only the every-n-th) is predicted by a constant-velocity model from the
last two poses and their time stamps (:func:`predict_constant_velocity`), registered
coarse to fine (an adaptive first distance, 3 sigma of the model's deviations so far,
then ``icp_max_correspondence_m``) against a local map of the last ``odometry_window``
keyframes (a scan becomes one after ``odometry_keyframe_m`` / ``odometry_keyframe_rad``
of motion; matching against the same keyframes for several scans drifts less than
against the previous scan), with point-to-line ICP (``odometry_icp_method``; PL-ICP,
Censi 2008: point-to-point is biased toward zero motion along corridors).

Fitness is measured against the local map (its union, not scan by scan: a scan at a
turn overlaps the union well and any single predecessor poorly) and never drops a scan
by itself: a scan whose ICP finds no correspondences is ``icp_failed`` and the chain
goes on from its prediction; one below ``min_icp_fitness`` is dropped as
``low_icp_fitness`` but its ICP pose carries the chain and the map (the best estimate
there is; continuing from predictions into unmapped space loses track). Not-sampled
scans get their odometry pose in the table and are not kept. The output z of every pose
is 0 (the first scan's height). With ``loop_closure`` the kept scans then go through
the pose graph (:mod:`floorscan.register.posegraph`, first scan held) so that revisits
remove drift.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np
from scipy.spatial import cKDTree

from floorscan.core.geometry import se2_between, se2_compose, transform_points, wrap_angle
from floorscan.register.icp import fitness_against, icp_to_map, target_normals
from floorscan.register.prepare import voxel_downsample
from floorscan.register.result import ScanRegistration
from floorscan.register.sampling import MotionFilter


def predict_constant_velocity(p1, t1: int, p2, t2: int, t3: int) -> tuple[float, float, float, float]:
    """Constant-velocity prediction of the pose at ``t3`` from the two last poses.

    The planar motion from ``p1`` to ``p2`` (in ``p1``'s frame, so a turning rover keeps
    turning) is scaled by ``(t3 - t2) / (t2 - t1)`` and applied to ``p2``; the motion
    prior of KISS-ICP (Vizzo et al. 2023, Sec. III-A), here in SE(2).

    Parameters
    ----------
    p1, p2 : tuple of float
        Poses (x, y, z, yaw) at ``t1`` < ``t2``: metres, radians.
    t1, t2, t3 : int
        Time stamps, ns.

    Returns
    -------
    tuple of float
        Predicted (x, y, z, yaw); ``p2`` itself when ``t2 <= t1``.
    """
    if t2 <= t1:
        return tuple(float(v) for v in p2)
    k = (t3 - t2) / (t2 - t1)
    d = se2_between(p1, p2)
    return se2_compose(p2, (k * d[0], k * d[1], k * d[2]))


def register_odometry(usable, sampled, clouds, sids, t, cfg, initial: ScanRegistration) -> ScanRegistration:
    """Pose-free registration: LIDAR odometry from the first usable scan (``mode: odometry``).

    ``usable``: index positions of the scans that passed the screening; ``sampled``:
    those of the sampled scans (``every_n``), or None to sample with the motion filter on
    the odometry's own poses as they are estimated; ``initial``: the screening's
    reasons (its poses are not used) and not changed; the other arguments as
    :func:`floorscan.register.sequential.register_sequential`. Returns ``initial`` with
    the scans registered: ``sampled`` the sampled positions, ``n_anchors`` 1 (the first
    scan; 0 without a usable scan). See the module docstring for the method.
    """
    res = initial.copy()  # filled here; ``initial`` stays as it was
    is_sampled = np.zeros(len(sids), dtype=bool)
    sampler = None
    if sampled is None:  # the motion filter on the odometry's poses, as they come
        sampler = MotionFilter(cfg.keep_distance_m, cfg.keep_angle_rad)
    else:
        is_sampled[sampled] = True
    seq = usable if cfg.odometry_scans == "all" else sampled
    if len(seq) == 0:
        res.sampled, res.n_anchors = np.zeros(0, dtype=np.int64), 0
        return res
    icp_cfg = cfg.replace(icp_method=cfg.odometry_icp_method)
    local: deque[np.ndarray] = deque(maxlen=cfg.odometry_window)  # keyframes' ICP points, map frame
    target = None  # (points, KD-tree, normals) of the local map, rebuilt after a new keyframe
    chain: deque[tuple[tuple[float, float, float, float], int]] = deque(maxlen=2)  # (pose, t_ns)
    dev_sq, n_dev = 0.0, 0  # model deviations (adaptive threshold)
    last_key = None  # pose of the last keyframe
    fine = tuple(cfg.icp_max_correspondence_m)
    for i in seq:
        src = clouds.icp(int(sids[i]))
        low = False
        if not chain:  # the first usable scan defines the map frame
            pose = (0.0, 0.0, 0.0, 0.0)
            res.reason[i] = "anchor"
            res.pose_correction[i] = 0.0
            if sampler is not None:
                is_sampled[i] = sampler.step(0.0, 0.0, 0.0)
        else:
            if i > 0 and res.reason[i - 1] == "duplicate":
                # the scan before repeats its predecessor: the sensor stood still until
                # then, so the motion model restarts from rest instead of carrying the
                # last velocity across the stop
                chain.append((chain[-1][0], int(t[i - 1])))
            if len(chain) == 2:
                pred = predict_constant_velocity(chain[0][0], chain[0][1], chain[1][0], chain[1][1], int(t[i]))
            else:
                pred = chain[-1][0]
            if target is None:
                pts = voxel_downsample(np.concatenate(local), cfg.voxel_size_m)
                tree = cKDTree(pts)
                target = (pts, tree, target_normals(pts, tree, icp_cfg))
            # adaptive threshold (Vizzo et al. 2023, Sec. III-C): 3 sigma of the model
            # deviations so far, within [finest stage, odometry_max_correspondence_m]
            tau = 3.0 * math.sqrt(dev_sq / n_dev) if n_dev else cfg.odometry_max_correspondence_m
            coarse = min(max(tau, fine[0]), cfg.odometry_max_correspondence_m)
            stages = (coarse,) + tuple(d for d in fine if d < coarse)
            fp = fitness_against(transform_points(src, *pred), target[1], cfg.fitness_max_correspondence_m)[0]
            pose, n_corr = icp_to_map(src, target[0], pred, icp_cfg, tree=target[1], normals=target[2],
                                      distances=stages)
            if sampler is not None:
                at = pose if n_corr else pred
                is_sampled[i] = sampler.step(at[0], at[1], at[3])
            fi, rm = math.nan, math.nan
            if n_corr:
                fi, rm, _ = fitness_against(transform_points(src, *pose), target[1], cfg.fitness_max_correspondence_m)
            if is_sampled[i]:
                res.fitness_prior[i], res.fitness_icp[i], res.inlier_rmse_m[i] = fp, fi, rm
                res.pose_correction[i] = (pose[0] - pred[0], pose[1] - pred[1], float(wrap_angle(pose[3] - pred[3])))
            if n_corr == 0:  # dropped; the chain goes on from the prediction
                if is_sampled[i]:
                    res.reason[i] = "icp_failed"
                chain.append((pred, int(t[i])))
                continue
            low = fi < cfg.min_icp_fitness
            if low and is_sampled[i]:
                res.reason[i] = "low_icp_fitness"
            d = se2_between(pred, pose)
            r_max = float(np.max(np.hypot(src[:, 0], src[:, 1])))
            dev_sq += (math.hypot(d[0], d[1]) + 2.0 * r_max * math.sin(abs(d[2]) / 2.0)) ** 2
            n_dev += 1
        chain.append((pose, int(t[i])))
        if not low:
            res.pose[i] = pose
            res.kept[i] = bool(is_sampled[i])
        if last_key is None or (
            math.hypot(pose[0] - last_key[0], pose[1] - last_key[1]) >= cfg.odometry_keyframe_m
            or abs(float(wrap_angle(pose[3] - last_key[3]))) >= cfg.odometry_keyframe_rad
        ):
            local.append(transform_points(src, *pose))
            last_key = pose
            target = None
    res.sampled, res.n_anchors = np.flatnonzero(is_sampled), 1
    return res

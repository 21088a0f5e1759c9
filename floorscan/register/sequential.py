"""Sequential registration, ``reference: previous``: the thesis's own step 5 (3.5,
"sequentially every two pointclouds"), each sampled scan against its predecessors.

The ICP target is the union of the previous ``n_previous`` kept scans (at their
localizer poses by default, ``reference_pose``), voxel-downsampled to ``voxel_size_m``:
a local map is denser and has fewer one-sided gaps than a single scan. Fitness (steps 4
and 6) is the mean over those scans individually, as in the thesis. References further
than ``max_reference_distance_m`` from the scan (by its pose) are ignored; a scan
without any reference is kept as a new ``anchor`` (the first one always is), so a
stretch of drops cannot lock out the rest of the recording.

The localizer's error is correlated in time, so the predecessors carry nearly the same
error as the scan and ICP cannot see it: the default is the pose graph
(:mod:`floorscan.register.posegraph`); this mode stays for comparison with the thesis.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from floorscan.core.geometry import transform_points, wrap_angle
from floorscan.register.icp import icp_to_map, mean_fitness
from floorscan.register.prepare import voxel_downsample
from floorscan.register.result import ScanRegistration


@dataclass
class _Kept:
    scan_id: int
    pose: tuple[float, float, float, float]
    points: np.ndarray  # fitness cloud, map frame, float64
    tree: cKDTree
    icp_points: np.ndarray  # ICP cloud, map frame



def register_sequential(sampled, clouds, sids, t, cfg, initial: ScanRegistration) -> ScanRegistration:
    """Sequential registration (thesis 3.5 step 5, ``reference: previous``): each sampled
    scan against the previous ``n_previous`` kept scans.

    Parameters
    ----------
    sampled : (K,) int ndarray
        Index positions of the sampled scans, ascending.
    clouds : floorscan.register.prepare.ScanStore
        The sampled scans' clouds.
    sids : (S,) int ndarray
        Scan ids of the scan index.
    t : (S,) int64 ndarray
        Scan times, ns.
    cfg : RegistrationConfig
    initial : ScanRegistration
        The screening's reasons and the localizer's poses
        (:meth:`~floorscan.register.result.ScanRegistration.before_registration`); not
        changed.

    Returns
    -------
    ScanRegistration
        ``initial`` with the sampled scans registered; ``n_anchors``: the scans kept
        without a reference.
    """
    res = initial.copy()  # filled here; ``initial`` stays as it was
    res.n_anchors = 0
    window: deque[_Kept] = deque(maxlen=cfg.n_previous)
    for i in sampled:
        sid = int(sids[i])
        cl = clouds.clouds(sid)
        pts, src = cl.fit_source, cl.icp
        prior = tuple(float(v) for v in res.pose[i])  # the localizer's
        refs = [
            r
            for r in window
            if math.hypot(r.pose[0] - prior[0], r.pose[1] - prior[1]) <= cfg.max_reference_distance_m
        ]
        pose = prior
        if refs:
            trees = [r.tree for r in refs]
            fp, _ = mean_fitness(transform_points(pts, *prior), trees, cfg.fitness_max_correspondence_m)
            res.fitness_prior[i] = fp
            if fp < cfg.min_prior_fitness:
                res.reason[i] = "low_prior_fitness"
                continue
            target = voxel_downsample(np.concatenate([r.icp_points for r in refs]), cfg.voxel_size_m)
            pose, n_corr = icp_to_map(src, target, pose, cfg)
            if n_corr == 0:
                res.reason[i] = "icp_failed"
                continue
            fi, rm = mean_fitness(transform_points(pts, *pose), trees, cfg.fitness_max_correspondence_m)
            res.fitness_icp[i], res.inlier_rmse_m[i] = fi, rm
            res.pose_correction[i] = (pose[0] - prior[0], pose[1] - prior[1], float(wrap_angle(pose[3] - prior[3])))
            if fi < cfg.min_icp_fitness:
                res.reason[i] = "low_icp_fitness"
                continue
            res.reason[i] = ""
        else:
            res.pose_correction[i] = 0.0
            res.reason[i] = "anchor"
            res.n_anchors += 1
        res.kept[i] = True
        res.pose[i] = pose
        ref_pose = prior if cfg.reference_pose == "localizer" else pose
        ref_pts = transform_points(cl.fit_target, *ref_pose)
        window.append(_Kept(sid, ref_pose, ref_pts, cKDTree(ref_pts), transform_points(cl.icp, *ref_pose)))
    res.sampled = np.array(sampled, dtype=np.int64)
    return res

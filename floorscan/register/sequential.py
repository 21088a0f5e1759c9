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


@dataclass
class _Kept:
    scan_id: int
    pose: tuple[float, float, float, float]
    points: np.ndarray  # fitness cloud, map frame, float64
    tree: cKDTree
    icp_points: np.ndarray  # ICP cloud, map frame



def register_sequential(sampled, clouds, sids, t, cfg, out) -> int:
    """Sequential registration (thesis 3.5 step 5, ``reference: previous``): each sampled
    scan against the previous ``n_previous`` kept scans.

    ``sampled``: index positions of the sampled scans; ``clouds``: a
    :class:`floorscan.register.prepare.ScanStore`; ``sids``, ``t``: scan ids and times
    (ns) of the scan index; ``out``: the per-scan output arrays ``(kept, reasons,
    fit_prior, fit_icp, rmse, corr, final)``, filled in place (``final`` holds the
    localizer's poses on entry). Returns the number of anchors."""
    kept, reasons, fit_prior, fit_icp, rmse, corr, final = out
    window: deque[_Kept] = deque(maxlen=cfg.n_previous)
    n_anchor = 0
    for i in sampled:
        sid = int(sids[i])
        cl = clouds.clouds(sid)
        pts, src = cl.fit_source, cl.icp
        prior = tuple(float(v) for v in final[i])
        refs = [
            r
            for r in window
            if math.hypot(r.pose[0] - prior[0], r.pose[1] - prior[1]) <= cfg.max_reference_distance_m
        ]
        pose = prior
        if refs:
            pts_prior = transform_points(pts, *prior)
            fit_prior[i], _ = mean_fitness(pts_prior, [r.tree for r in refs], cfg.fitness_max_correspondence_m)
            if fit_prior[i] < cfg.min_prior_fitness:
                reasons[i] = "low_prior_fitness"
                continue
            target = voxel_downsample(np.concatenate([r.icp_points for r in refs]), cfg.voxel_size_m)
            pose, n_corr = icp_to_map(src, target, pose, cfg)
            if n_corr == 0:
                reasons[i] = "icp_failed"
                continue
            pts_map = transform_points(pts, *pose)
            fit_icp[i], rmse[i] = mean_fitness(pts_map, [r.tree for r in refs], cfg.fitness_max_correspondence_m)
            corr[i] = (pose[0] - prior[0], pose[1] - prior[1], float(wrap_angle(pose[3] - prior[3])))
            if fit_icp[i] < cfg.min_icp_fitness:
                reasons[i] = "low_icp_fitness"
                continue
        else:
            corr[i] = 0.0
            reasons[i] = "anchor"
            n_anchor += 1
        kept[i] = True
        if reasons[i] != "anchor":
            reasons[i] = ""
        final[i] = pose
        ref_pose = prior if cfg.reference_pose == "localizer" else pose
        ref_pts = transform_points(cl.fit_target, *ref_pose)
        window.append(_Kept(sid, ref_pose, ref_pts, cKDTree(ref_pts), transform_points(cl.icp, *ref_pose)))
    return n_anchor

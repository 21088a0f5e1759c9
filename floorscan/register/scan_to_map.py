"""Scan-to-map registration, ``reference: map``: every sampled scan against a map of
its overlapping scans from anywhere in the recording (thesis 3.5 step 5, departing from
it).

The thesis registers each scan against its predecessors at their localizer poses
(:mod:`floorscan.register.sequential`). An AMCL-like localizer error is correlated in
time, so the predecessors carry nearly the same error as the scan and ICP cannot see
it. The field's practice is a multiway / scan-to-map alignment over the whole recording
(the thesis's own pointer, Choi et al. 2015, Open3D's multiway registration; lighter
here): every sampled scan is aligned by ICP to a map of the spatially nearby,
overlapping sampled scans, except those within ``exclude_window_s`` of it in time
(whose errors are correlated with its own), at their current estimates
(:func:`_select_references`: nearest first, ``reference_spacing_s`` apart, overlapping,
at most ``n_references``; each scan's ICP target is the union of its references,
voxel-downsampled).

Passes are Jacobi-style (all scans against the previous pass's poses, a relaxed step of
``relaxation`` toward the ICP pose), which averages independent localizer errors; the
gauge (one rigid motion of the whole map, which the scans cannot see) is fixed after
every pass by making the mean correction over all registered scans zero (mean yaw
difference, then mean x, y difference to the localizer, :func:`_fix_gauge`), so the map
does not drift and stays in the localizer's frame. Fitness (steps 4 and 6) stays the
thesis's: mean over the previous ``n_previous`` sampled scans. A scan with no reference
at all is kept at its localizer pose as an ``anchor``; a scan whose ICP fails in a pass
is dropped (``icp_failed``) and no longer a reference.
"""

from __future__ import annotations

import logging
import math

import numpy as np
from scipy.spatial import cKDTree

from floorscan.core.geometry import transform_points, wrap_angle
from floorscan.register.icp import fitness_against, icp_to_map, mean_fitness
from floorscan.register.params import RegistrationConfig
from floorscan.register.prepare import voxel_downsample
from floorscan.register.result import ScanRegistration

log = logging.getLogger(__name__)


def _select_references(
    pose: np.ndarray,
    t_s: np.ndarray,
    active: np.ndarray,
    cfg: RegistrationConfig,
    placed: list[np.ndarray | None] | None = None,
    trees: list[cKDTree | None] | None = None,
) -> tuple[list[np.ndarray], int]:
    """References of every active scan for ``reference: map`` (module docstring).

    Candidates are the other active scans within ``max_reference_distance_m`` (by the
    current poses), nearest first. Kept: those at least ``exclude_window_s`` away in time
    from the scan, greedily thinned so that any two are ``reference_spacing_s`` apart in
    time, at most ``n_references``; with ``placed`` points and their KD-``trees`` (current
    poses), a candidate must also overlap the scan: fitness of the scan against it at least
    ``min_prior_fitness`` (a scan behind a wall is no reference). A scan with no candidate
    outside the window falls back
    to its nearest candidates inside it (their errors are correlated with its own, so they
    only make the map consistent). Returns the references (indices into ``pose``) per scan
    and the number of scans that fell back.
    """
    n = len(pose)
    out = [np.empty(0, dtype=np.int64)] * n
    idx = np.flatnonzero(active)
    if len(idx) < 2:
        return out, 0
    tree = cKDTree(pose[idx, :2])
    n_fallback = 0
    for j, near in zip(idx, tree.query_ball_point(pose[idx, :2], r=cfg.max_reference_distance_m)):
        cand = idx[np.asarray(near, dtype=np.int64)]
        cand = cand[cand != j]
        if len(cand) == 0:
            continue
        d = np.hypot(pose[cand, 0] - pose[j, 0], pose[cand, 1] - pose[j, 1])
        cand = cand[np.argsort(d, kind="stable")]
        far = cand[np.abs(t_s[cand] - t_s[j]) >= cfg.exclude_window_s]
        chosen: list[int] = []
        for c in far:
            if all(abs(t_s[c] - t_s[r]) >= cfg.reference_spacing_s for r in chosen) and (
                trees is None
                or fitness_against(placed[j], trees[c], cfg.fitness_max_correspondence_m)[0] >= cfg.min_prior_fitness
            ):
                chosen.append(int(c))
                if len(chosen) == cfg.n_references:
                    break
        if not chosen:
            chosen = [int(c) for c in cand[: cfg.n_references]]
            n_fallback += 1
        out[j] = np.asarray(chosen, dtype=np.int64)
    return out, n_fallback


def _previous_references(pose: np.ndarray, active: np.ndarray, cfg: RegistrationConfig) -> list[np.ndarray]:
    """The fitness references of each active scan in ``reference: map`` mode: as in the
    thesis (Algorithm 3 steps 4 and 6), the previous ``n_previous`` active scans within
    ``max_reference_distance_m``; for a scan without any (the first), the next ones."""
    idx = np.flatnonzero(active)
    out = [np.empty(0, dtype=np.int64)] * len(pose)
    for k, j in enumerate(idx):
        for cand in (idx[max(0, k - cfg.n_previous):k][::-1], idx[k + 1:k + 1 + cfg.n_previous]):
            d = np.hypot(pose[cand, 0] - pose[j, 0], pose[cand, 1] - pose[j, 1])
            cand = cand[d <= cfg.max_reference_distance_m]
            if len(cand):
                out[j] = cand
                break
    return out


def _fix_gauge(pose: np.ndarray, localizer: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Move the poses in ``mask`` rigidly so that their mean correction against the
    localizer is zero: mean yaw difference 0 (rotation about their centroid), then mean
    x, y difference 0. Returns a new array."""
    out = pose.copy()
    if not mask.any():
        return out
    m = np.flatnonzero(mask)
    dyaw = float(np.mean(wrap_angle(out[m, 3] - localizer[m, 3])))
    c0 = out[m, :2].mean(axis=0)
    c, s = math.cos(-dyaw), math.sin(-dyaw)
    rel = out[m, :2] - c0
    out[m, 0] = c0[0] + c * rel[:, 0] - s * rel[:, 1]
    out[m, 1] = c0[1] + s * rel[:, 0] + c * rel[:, 1]
    out[m, 3] = wrap_angle(out[m, 3] - dyaw)
    out[m, :2] += (localizer[m, :2] - out[m, :2]).mean(axis=0)
    return out


def register_map(sampled, clouds, sids, t, cfg, initial: ScanRegistration) -> ScanRegistration:
    """Iterative scan-to-map registration against the whole recording (``reference: map``).

    Arguments and result as :func:`floorscan.register.sequential.register_sequential`
    (``initial`` holds the localizer's poses and is not changed; ``n_anchors``: the
    scans kept without a reference). See the module docstring for the method.
    """
    res = initial.copy()  # filled here; ``initial`` stays as it was
    res.sampled = sampled = np.array(sampled, dtype=np.int64)
    res.n_anchors = 0
    n = len(sampled)
    if n == 0:
        return res
    cls = [clouds.clouds(int(sids[i])) for i in sampled]
    pts = [c.fit_source for c in cls]
    ref = [c.fit_target for c in cls]
    src = [c.icp for c in cls]
    loc = initial.pose[sampled]  # localizer poses (a copy)
    t_s = (t[sampled] - t[sampled[0]]) * 1e-9
    status = np.full(n, "", dtype=object)
    active = np.ones(n, dtype=bool)
    pose = loc.copy()

    def mean_fit(j, refs, trees):
        pm = transform_points(pts[j], *pose[j])
        return mean_fitness(pm, [trees[r] for r in refs], cfg.fitness_max_correspondence_m)

    # step 4: fitness under the localizer's poses, against the previous scans (thesis)
    refs = _previous_references(pose, active, cfg)
    trees = {j: cKDTree(transform_points(ref[j], *pose[j])) for j in range(n)}
    fp = np.full(n, np.nan)
    for j in range(n):
        if len(refs[j]):
            fp[j] = mean_fit(j, refs[j], trees)[0]
    low = fp < cfg.min_prior_fitness
    status[low] = "low_prior_fitness"
    active &= ~low

    # step 5: Jacobi passes of scan-to-map ICP: every scan against the previous pass's
    # map, a relaxed step toward its ICP pose, then the gauge is fixed (module docstring)
    has_ref = np.zeros(n, dtype=bool)
    n_fallback = 0
    for _ in range(cfg.passes):
        placed = [transform_points(src[j], *pose[j]) if active[j] else None for j in range(n)]
        ptrees = [cKDTree(placed[j]) if active[j] else None for j in range(n)]
        refs, n_fallback = _select_references(pose, t_s, active, cfg, placed, ptrees)
        new = pose.copy()
        moved = np.zeros(n, dtype=bool)
        for j in np.flatnonzero(active):
            if not len(refs[j]):
                continue
            has_ref[j] = True
            target = voxel_downsample(np.concatenate([placed[r] for r in refs[j]]), cfg.voxel_size_m)
            q, n_corr = icp_to_map(src[j], target, pose[j], cfg)
            if n_corr == 0:
                status[j] = "icp_failed"
                continue
            a = cfg.relaxation
            new[j, 0] += a * (q[0] - pose[j, 0])
            new[j, 1] += a * (q[1] - pose[j, 1])
            new[j, 3] = wrap_angle(pose[j, 3] + a * float(wrap_angle(q[3] - pose[j, 3])))
            moved[j] = True
        pose = _fix_gauge(new, loc, moved)
        active &= status != "icp_failed"

    # step 6: fitness after ICP, against the previous scans at their final poses
    refs = _previous_references(pose, active, cfg)
    trees = {j: cKDTree(transform_points(ref[j], *pose[j])) for j in np.flatnonzero(active)}
    fi = np.full(n, np.nan)
    rm = np.full(n, np.nan)
    for j in np.flatnonzero(active):
        if has_ref[j]:
            fi[j], rm[j] = mean_fit(j, refs[j], trees)
    lowi = fi < cfg.min_icp_fitness
    status[lowi] = "low_icp_fitness"
    anchor = active & ~has_ref
    status[anchor] = "anchor"
    ok = active & ~lowi
    pose[anchor] = loc[anchor]

    res.fitness_prior[sampled] = fp
    res.fitness_icp[sampled] = fi
    res.inlier_rmse_m[sampled] = rm
    res.reason[sampled] = status
    res.kept[sampled] = ok
    res.pose[sampled[ok]] = pose[ok]
    d = pose - loc
    d[:, 3] = wrap_angle(d[:, 3])
    reg = ok | (status == "low_icp_fitness")
    res.pose_correction[sampled[reg]] = d[reg][:, [0, 1, 3]]
    res.pose_correction[sampled[anchor]] = 0.0
    res.n_anchors = int(anchor.sum())
    if n_fallback:
        log.info("register: %d of %d scans had no reference outside exclude_window_s=%.1f s",
                 n_fallback, n, cfg.exclude_window_s)
    return res

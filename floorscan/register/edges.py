"""The pose graph's edges: which scan pairs are aligned, and their planar ICP.

:func:`candidate_pairs` names the pairs (``sequential``: each scan to its next
``sequential_neighbours`` sampled scans; ``loop``: revisits, up to
``loop_max_per_scan`` nearest scans within ``loop_radius_m`` at least
``loop_min_separation_s`` apart in time, one per pass); :func:`scan_pair_edges` aligns
them with Open3D's point-to-point ``registration_icp`` on clouds projected to the xy
plane, coarse to fine, in worker processes, and measures their fitness before and
after. :func:`pair_rows` is the work of one process: a run of pairs and the clouds they
need. Usage::

    pairs = candidate_pairs(poses, t_s, params)
    edges = scan_pair_edges(clouds, poses, t_s, params)   # a table of EDGE_COLUMNS

Sources: Lu and Milios 1997 and Grisetti et al. 2010 (scan-matching constraints of
graph SLAM); Open3D's multi-scale ICP (Zhou, Park and Koltun 2018).
"""

from __future__ import annotations

import logging
import math
from concurrent.futures import Executor
from typing import Sequence

import numpy as np
import pandas as pd
from scipy.spatial import cKDTree

from floorscan.core.geometry import se2_between, se2_matrix, transform_points
from floorscan.core.runtime import map_in_processes, one_openmp_thread
from floorscan.register.params import GraphParams
from floorscan.register.prepare import plane_cloud

log = logging.getLogger(__name__)

#: Columns of the edge table of :func:`scan_pair_edges`.
EDGE_COLUMNS = [
    "i", "j", "kind", "dx_m", "dy_m", "dyaw_rad", "fitness_prior", "fitness", "inlier_rmse_m",
    "overlap_fitness_prior", "overlap_fitness",
]  # fmt: skip

#: Bearing bins of a scan's range profile (:func:`visible_to`), and the least number of
#: the other scan's points it must be able to see for an overlap fitness.
PROFILE_BINS, MIN_VISIBLE_POINTS = 360, 30


def range_profile(points: np.ndarray, bins: int = PROFILE_BINS) -> np.ndarray:
    """The farthest return of a scan per bearing bin, from its own origin: (bins,)
    float64 metres, 0 where it has none. ``points`` (N, >=2) in the scan's frame."""
    bearing = np.arctan2(points[:, 1], points[:, 0])
    b = np.minimum(((bearing + math.pi) * (bins / (2 * math.pi))).astype(np.int64), bins - 1)
    profile = np.zeros(bins)
    np.maximum.at(profile, b, np.hypot(points[:, 0], points[:, 1]))
    return profile


def visible_to(profile: np.ndarray, points: np.ndarray, margin_m: float) -> np.ndarray:
    """Which ``points`` (N, >=2, in the frame of the scan of ``profile``) that scan could
    have seen: in a bearing bin where it has returns, not farther than its farthest
    return there (plus ``margin_m``): not behind what it saw, not where it saw nothing."""
    bins = len(profile)
    bearing = np.arctan2(points[:, 1], points[:, 0])
    b = np.minimum(((bearing + math.pi) * (bins / (2 * math.pi))).astype(np.int64), bins - 1)
    reach = profile[b]
    return (reach > 0) & (np.hypot(points[:, 0], points[:, 1]) <= reach + margin_m)


def overlap_fitness(inlier: np.ndarray, visible: np.ndarray) -> float:
    """Fitness over the points the reference scan could see: inliers among the
    ``visible`` points over their number (NaN with fewer than
    :data:`MIN_VISIBLE_POINTS`). The overlap-normalised fitness of Pomerleau et al.,
    "Comparing ICP variants on real-world data sets", Autonomous Robots 2013: a scan
    in an open hall, which sees few of the other scan's walls within range, is judged
    on those it can see."""
    n = int(visible.sum())
    return float((inlier & visible).sum() / n) if n >= MIN_VISIBLE_POINTS else math.nan


def candidate_pairs(
    poses: np.ndarray, t_s: np.ndarray, params: GraphParams = GraphParams()
) -> list[tuple[int, int, str]]:
    """The scan pairs ``(i, j, kind)`` (i < j) that :func:`scan_pair_edges` aligns.

    Parameters
    ----------
    poses : (N, >=2) float ndarray
        Scan positions ``x, y`` first, metres, in time order.
    t_s : (N,) float ndarray
        Scan times, seconds.
    params : GraphParams

    Returns
    -------
    list of (int, int, str)
        ``kind`` is ``"sequential"`` or ``"loop"``; no pair twice. Loop pairs are
        taken nearest first while neither scan has ``loop_max_per_scan`` partners
        and the new partner is ``loop_partner_separation_m`` along the path from the
        scan's partners so far (ties by ``(i, j)``).
    """
    n = len(poses)
    pairs: dict[tuple[int, int], str] = {}
    for i in range(n):
        for j in range(i + 1, min(n, i + 1 + params.sequential_neighbours)):
            pairs[(i, j)] = "sequential"
    if n > 1 and params.loop_max_per_scan > 0:
        xy = np.asarray(poses)[:, :2]
        cand = cKDTree(np.asarray(xy, dtype=np.float64)).query_pairs(params.loop_radius_m, output_type="ndarray")
        i, j = cand[:, 0].astype(np.int64), cand[:, 1].astype(np.int64)  # i < j
        t = np.asarray(t_s)
        # revisits only: not within loop_min_separation_s, not a sequential pair
        ok = ~(np.abs(t[j] - t[i]) < params.loop_min_separation_s) & (j - i > params.sequential_neighbours)
        i, j = i[ok], j[ok]
        d = xy[i] - xy[j]
        order = np.lexsort((j, i, np.hypot(d[:, 0], d[:, 1])))  # nearest first, ties by (i, j)
        # keep the nearest loop_max_per_scan candidates of each scan, each at least
        # loop_partner_separation_m along the path from the scan's other partners
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))]).tolist()  # travelled, m
        sep = float(params.loop_partner_separation_m)
        partners: list[list[int]] = [[] for _ in range(n)]
        cap = params.loop_max_per_scan
        for a, b in zip(i[order].tolist(), j[order].tolist()):
            pa, pb = partners[a], partners[b]
            if len(pa) >= cap or len(pb) >= cap:
                continue
            if sep > 0 and (any(abs(s[b] - s[c]) < sep for c in pa) or any(abs(s[a] - s[c]) < sep for c in pb)):
                continue
            pairs[(a, b)] = "loop"
            pa.append(b)
            pb.append(a)
    return [(i, j, k) for (i, j), k in sorted(pairs.items())]


def scan_pair_edges(
    clouds: Sequence[np.ndarray],
    poses: np.ndarray,
    t_s: np.ndarray,
    params: GraphParams = GraphParams(),
    icp_kinds: tuple[str, ...] = ("sequential", "loop"),
    ahead=None,  # an EdgeStream, finished (edge_stream imports this module)
    scan_ids: Sequence[int] | None = None,
    pool: Executor | None = None,
) -> pd.DataFrame:
    """Relative-pose constraints between overlapping scans by planar ICP.

    Each pair of :func:`candidate_pairs` is aligned by coarse-to-fine point-to-point
    ICP, source scan ``j`` against target scan ``i`` in ``i``'s scanner frame, starting
    from the relative pose of ``poses``. The clouds are projected to the xy plane
    (z = 0) and voxel-downsampled on ``voxel_size_m``; Open3D's ``registration_icp``
    (point-to-point) on coplanar clouds stays planar (x, y, yaw), and gives the same
    result as :func:`floorscan.register.icp.icp_planar` at half the CPU time, since its
    iterations run in C++. Its convergence criteria stay tight (relative fitness and
    RMSE 1e-6): looser ones move edges by centimetres. Fitness before and after ICP uses
    a cKDTree of each target scan built once.

    Parameters
    ----------
    clouds : sequence of (N_k, 3) float ndarray
        Each scan's points in its scanner frame, metres, in time order.
    poses : (N, 4) float ndarray
        Initial scanner poses ``x, y, z, yaw`` in the map frame (metres, radians).
    t_s : (N,) float ndarray
        Scan times, seconds.
    params : GraphParams
    icp_kinds : tuple of str
        Pair kinds aligned by ICP; the others keep the relative pose of ``poses``
        with fitness 1 (odometry mode: the odometry chain is the sequential edges, ICP
        only closes the loops).
    ahead : floorscan.register.edge_stream.EdgeStream, optional
        Pairs aligned ahead (after its ``finish()``): a pair found in its
        ``rows`` (by scan ids) with the same kind takes that row (the same clouds,
        poses and parameters give the same row), the others are aligned here; its
        projected clouds (``pts``) are used, not made again.
    scan_ids : sequence of int, optional
        The scan id of each cloud (needed with ``ahead``).
    pool : concurrent.futures.Executor, optional
        Worker processes the pairs are aligned in (:func:`floorscan.core.runtime.process_pool`,
        the stage's); without, ``params.workers`` processes for this call, the first
        share here.

    Returns
    -------
    pandas.DataFrame
        :data:`EDGE_COLUMNS`, one row per pair tried: ``dx_m, dy_m, dyaw_rad`` is the
        pose of scan ``j`` in scan ``i``'s frame; ``fitness_prior`` the inlier fraction
        under the initial poses (thesis Algorithm 3 step 3), ``fitness`` the inlier
        fraction and ``inlier_rmse_m`` the RMS inlier distance after ICP (fitness 0 and the initial
        relative pose when ICP found no correspondences); ``overlap_fitness_prior`` and
        ``overlap_fitness`` the same over the points of ``j`` that ``i`` could see
        (:func:`overlap_fitness`; NaN when it could see too few), which the keep test
        reads. :func:`optimize_pose_graph` uses the pairs with ``fitness >=
        min_edge_fitness``.
    """
    poses = np.asarray(poses, dtype=np.float64)
    if ahead is not None and (scan_ids is None or len(scan_ids) != len(clouds)):
        raise ValueError("edges aligned ahead need the scan_ids of the clouds")
    ids = [int(s) for s in scan_ids] if ahead is not None else None
    pts = [
        ahead.pts[ids[k]] if ahead is not None and ids[k] in ahead.pts else plane_cloud(c, params.voxel_size_m)
        for k, c in enumerate(clouds)
    ]
    pairs = [(i, j, kind) for i, j, kind in candidate_pairs(poses, t_s, params)
             if len(pts[i]) >= 3 and len(pts[j]) >= 3]
    done: dict[int, tuple] = {}  # pair number -> row, from the rows aligned ahead
    if ahead is not None:
        for n, (i, j, kind) in enumerate(pairs):
            row = ahead.rows.get((ids[i], ids[j]))
            if row is not None and row[2] == kind:
                done[n] = (i, j, *row[2:])
    todo = [pair for n, pair in enumerate(pairs) if n not in done]
    chunks = [c for c in _chunks(todo, max(1, int(params.workers))) if c]
    computed = iter(_parallel_pair_rows(pts, poses, chunks, params, icp_kinds, pool))
    rows = [done[n] if n in done else next(computed) for n in range(len(pairs))]
    if ahead is not None:
        log.info("edges: %d of %d pairs aligned while the scans were read", len(done), len(pairs))
    return pd.DataFrame(rows, columns=EDGE_COLUMNS).astype(
        {"i": np.int64, "j": np.int64, "kind": str, "dx_m": float, "dy_m": float,
         "dyaw_rad": float, "fitness_prior": float, "fitness": float, "inlier_rmse_m": float,
         "overlap_fitness_prior": float, "overlap_fitness": float}
    )


_MIN_PAIRS_PER_WORKER = 200


def _chunks(pairs: list, n: int) -> list[list]:
    """``pairs`` cut into ``n`` contiguous runs of near-equal length (fewer when short:
    a worker costs about a second to start, so each gets at least
    :data:`_MIN_PAIRS_PER_WORKER` pairs)."""
    n = max(1, min(n, len(pairs) // _MIN_PAIRS_PER_WORKER))
    bounds = np.linspace(0, len(pairs), n + 1).round().astype(int)
    return [pairs[a:b] for a, b in zip(bounds[:-1], bounds[1:])]


def _parallel_pair_rows(pts, poses, chunks, params, icp_kinds, pool=None) -> list[tuple]:
    """:func:`pair_rows` of each chunk (:func:`floorscan.core.runtime.map_in_processes`:
    all in ``pool``, as the register stage does with the pool its workers started in
    while it read the scans, so this process never imports Open3D, a few seconds of CPU
    on the stage's critical path; without a pool the first here and the others in
    worker processes), each fed only the clouds of its pairs; rows in pair order."""
    calls = []
    for chunk in chunks:
        need = sorted({k for i, j, _ in chunk for k in (i, j)})
        calls.append(({k: pts[k] for k in need}, poses, chunk, params, icp_kinds))
    return [row for rows in map_in_processes(pair_rows, calls, len(calls), pool) for row in rows]


def pair_rows(pts, poses: np.ndarray, pairs, params: GraphParams, icp_kinds) -> list[tuple]:
    """The :data:`EDGE_COLUMNS` rows of ``pairs`` (see :func:`scan_pair_edges`);
    ``pts[k]`` is scan k's projected, downsampled cloud and ``poses[k]`` its initial
    pose (lists, arrays or dicts by scan id)."""
    import open3d as o3d

    reg = o3d.pipelines.registration
    trees: dict[int, cKDTree] = {}
    o3d_clouds: dict[int, object] = {}

    coarse_clouds: dict[int, object] = {}
    coarse_voxel = float(params.coarse_voxel_size_m)
    # the stages before the last run on coarser clouds when the size is above the
    # clouds' own voxel (voxel_size_m >= 0, so a size of 0 never is)
    coarse_stages = len(params.icp_distances_m) - 1 if coarse_voxel > params.voxel_size_m else 0

    def cloud(k: int):
        if k not in o3d_clouds:
            o3d_clouds[k] = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts[k]))
        return o3d_clouds[k]

    def stage_cloud(k: int, stage: int):
        """Scan k's cloud for ICP stage ``stage``: coarser for all but the last."""
        if stage >= coarse_stages:
            return cloud(k)
        if k not in coarse_clouds:
            coarse_clouds[k] = cloud(k).voxel_down_sample(coarse_voxel)
        return coarse_clouds[k]

    criteria = reg.ICPConvergenceCriteria(1e-6, 1e-6, int(params.icp_max_iterations))
    estimation = reg.TransformationEstimationPointToPoint()
    rows = []
    profiles: dict[int, np.ndarray] = {}
    with one_openmp_thread():
        for i, j, kind in pairs:
            if i not in trees:
                trees[i] = cKDTree(pts[i])
                profiles[i] = range_profile(np.asarray(pts[i]))
            rel = se2_between(poses[i], poses[j])
            src0 = transform_points(pts[j], rel[0], rel[1], 0.0, rel[2])
            d0, _ = trees[i].query(src0, distance_upper_bound=params.inlier_m)
            fitness_prior = float(np.isfinite(d0).mean())
            overlap_prior = overlap_fitness(np.isfinite(d0), visible_to(profiles[i], src0, params.inlier_m))
            if kind not in icp_kinds:
                rows.append((i, j, kind, rel[0], rel[1], rel[2], fitness_prior, 1.0, 0.0, overlap_prior, 1.0))
                continue
            T = se2_matrix(*rel)
            ok = True
            for stage, dist in enumerate(params.icp_distances_m):
                res = reg.registration_icp(
                    stage_cloud(j, stage), stage_cloud(i, stage), float(dist), T, estimation, criteria
                )
                if len(res.correspondence_set) < 3:
                    ok = False
                    break
                T = np.asarray(res.transformation)
            if not ok:
                rows.append((i, j, kind, rel[0], rel[1], rel[2], fitness_prior, 0.0, math.nan, overlap_prior, 0.0))
                continue
            pose = (float(T[0, 3]), float(T[1, 3]), 0.0, math.atan2(T[1, 0], T[0, 0]))
            src = transform_points(pts[j], pose[0], pose[1], 0.0, pose[3])
            d, _ = trees[i].query(src, distance_upper_bound=params.inlier_m)
            inl = np.isfinite(d)
            fitness = float(inl.mean())
            rmse = float(np.sqrt(np.mean(d[inl] ** 2))) if inl.any() else math.nan
            overlap = overlap_fitness(inl, visible_to(profiles[i], src, params.inlier_m))
            rows.append((i, j, kind, pose[0], pose[1], pose[3], fitness_prior, fitness, rmse, overlap_prior, overlap))
    return rows

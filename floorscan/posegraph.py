"""Pose-graph registration: scan-to-scan ICP constraints plus the localizer's poses as
priors, optimised together with Open3D's pose-graph optimisation.

Thesis section 3.2.2 refines each scan's pose by ICP against earlier scans (Algorithm 3)
and leaves the combination of the two pose sources open. This module does what SLAM
back ends do (Lu and Milios 1997; Grisetti et al. 2010, "A tutorial on graph-based
SLAM"): every sampled scan is a node; ICP between overlapping scans gives relative
constraints (edges), which are accurate to millimetres but drift when chained; the
localizer's poses are absolute priors, accurate to centimetres but noisy from scan to
scan. The optimum keeps the relative geometry of ICP and the mean placement of the
localizer. Without a localizer (odometry mode) the first scan is held fixed instead.

Edges (:func:`scan_pair_edges`):

- ``sequential``: each scan to the next ``sequential_neighbours`` sampled scans;
- ``loop``: each scan to up to ``loop_max_per_scan`` nearest scans (by position) within
  ``loop_radius_m`` that are at least ``loop_min_separation_s`` apart in time, the
  loop closures that make the map consistent where the path returns.

An edge enters the graph when, after coarse-to-fine planar ICP (x, y, yaw; the rover is
planar, thesis 3.2.2), at least ``min_edge_fitness`` of the source scan's points lie
within ``inlier_m`` of the target scan. Loop edges are "uncertain" in Open3D's sense: the
optimiser's line process may prune one that disagrees with the rest.

Open3D's graph is 6-DoF; z, roll and pitch get an information of ``FIXED_INFORMATION``
so the solution stays planar. The localizer priors are edges from a fixed anchor node
(the map origin) to each scan node.
"""

from __future__ import annotations

import functools

import logging
import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np
import pandas as pd
from scipy.spatial import cKDTree

log = logging.getLogger(__name__)

#: Information (1 / variance) of the degrees of freedom a planar rover does not have
#: (z, roll, pitch) in the 6-DoF graph.
FIXED_INFORMATION = 1e8

#: Columns of the edge table of :func:`scan_pair_edges`.
EDGE_COLUMNS = ["i", "j", "kind", "dx_m", "dy_m", "dyaw_rad", "fitness_prior", "fitness", "inlier_rmse_m"]


@dataclass(frozen=True)
class GraphParams:
    """Parameters of the pose graph (config ``register.graph``).

    Attributes
    ----------
    sequential_neighbours : int
        Edges from each sampled scan to this many following sampled scans.
    loop_radius_m : float
        Loop-closure candidates: scans whose positions are within this, metres.
    loop_min_separation_s : float
        ... and at least this far apart in time, seconds.
    loop_max_per_scan : int
        Nearest candidates tried per scan.
    icp_distances_m : tuple of float
        Coarse-to-fine maximum correspondence distances of the edge ICP, metres.
    icp_max_iterations : int
        Per distance.
    voxel_size_m : float
        Voxel downsampling of the scans before the edge ICP, metres (0: none).
    inlier_m : float
        A source point is an inlier when its nearest target point is this close, metres.
    min_edge_fitness : float
        Inlier fraction an edge needs after ICP.
    edge_sigma_m, edge_sigma_rad : float
        Standard deviation of an ICP edge's translation (metres) and yaw (radians).
    prior_sigma_m, prior_sigma_rad : float
        Standard deviation of a localizer pose (metres, radians).
    workers : int
        Processes for the edge ICP (the ``register`` rule passes its Snakemake
        ``threads``). The edges do not depend on it: each pair is aligned alone.
    """

    sequential_neighbours: int = 2
    loop_radius_m: float = 3.0
    loop_min_separation_s: float = 3.0
    loop_max_per_scan: int = 4
    icp_distances_m: tuple[float, ...] = (0.3, 0.1)
    icp_max_iterations: int = 20
    voxel_size_m: float = 0.05
    inlier_m: float = 0.05
    min_edge_fitness: float = 0.6
    edge_sigma_m: float = 0.005
    edge_sigma_rad: float = 0.002
    prior_sigma_m: float = 0.05
    prior_sigma_rad: float = 0.02
    workers: int = 1

    @classmethod
    def from_mapping(cls, cfg) -> "GraphParams":
        """From a config mapping (unknown keys raise ``KeyError``)."""
        from floorscan.config import dataclass_from_mapping

        values = dict(cfg or {})
        if "icp_distances_m" in values:
            values["icp_distances_m"] = tuple(float(v) for v in values["icp_distances_m"])
        return dataclass_from_mapping(cls, values, "register.graph")


def _one_openmp_thread():
    """Context: Open3D's OpenMP loops on one thread (threadpoolctl, a scikit-learn
    dependency). Its multi-threaded reductions sum in varying order, so the pose graph
    differed from run to run in the last bits (same input, same output is a house
    rule); and on the 2-core target one thread costs less CPU (1500 edge ICPs of
    hallways: 3.1 s with one thread, 4.3 s with two). The controller is made once:
    ``threadpool_limits`` scans the loaded libraries on every call (4.4 s of 1019 calls
    on hallways3d)."""
    return _openmp_controller().limit(limits=1, user_api="openmp")


@functools.lru_cache(maxsize=1)
def _openmp_controller():
    import open3d  # noqa: F401  (its OpenMP runtime must be loaded before the scan)
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


def se2_between(a, b) -> tuple[float, float, float]:
    """Planar motion (dx, dy, dyaw) from pose ``a`` to pose ``b``, in ``a``'s frame.

    Poses are ``(x, y, z, yaw)`` or ``(x, y, yaw)`` sequences; metres, radians.
    """
    ya, yb = a[-1], b[-1]
    c, s = math.cos(ya), math.sin(ya)
    dx, dy = b[0] - a[0], b[1] - a[1]
    return c * dx + s * dy, -s * dx + c * dy, _wrap(yb - ya)


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def _matrix(x: float, y: float, yaw: float) -> np.ndarray:
    c, s = math.cos(yaw), math.sin(yaw)
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    m[0, 3], m[1, 3] = x, y
    return m


def _information(sigma_m: float, sigma_rad: float) -> np.ndarray:
    # Open3D orders a pose increment as (rx, ry, rz, tx, ty, tz).
    f = FIXED_INFORMATION
    return np.diag([f, f, 1.0 / sigma_rad**2, 1.0 / sigma_m**2, 1.0 / sigma_m**2, f])


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
        ``kind`` is ``"sequential"`` or ``"loop"``; no pair twice.
    """
    n = len(poses)
    pairs: dict[tuple[int, int], str] = {}
    for i in range(n):
        for j in range(i + 1, min(n, i + 1 + params.sequential_neighbours)):
            pairs[(i, j)] = "sequential"
    if n > 1 and params.loop_max_per_scan > 0:
        tree = cKDTree(np.asarray(poses, dtype=np.float64)[:, :2])
        for i, j in sorted(tree.query_pairs(params.loop_radius_m)):
            if abs(t_s[j] - t_s[i]) < params.loop_min_separation_s or (i, j) in pairs:
                continue
            pairs.setdefault((i, j), "loop_candidate")
        # keep the nearest loop_max_per_scan candidates of each scan
        loops = [(i, j) for (i, j), k in pairs.items() if k == "loop_candidate"]
        dist = {p: float(np.hypot(*(poses[p[0], :2] - poses[p[1], :2]))) for p in loops}
        count = np.zeros(n, dtype=np.int64)
        for p in sorted(loops, key=lambda p: (dist[p], p)):
            i, j = p
            if count[i] < params.loop_max_per_scan and count[j] < params.loop_max_per_scan:
                pairs[p] = "loop"
                count[i] += 1
                count[j] += 1
            else:
                del pairs[p]
    return [(i, j, k) for (i, j), k in sorted(pairs.items())]


def scan_pair_edges(
    clouds: Sequence[np.ndarray],
    poses: np.ndarray,
    t_s: np.ndarray,
    params: GraphParams = GraphParams(),
    icp_kinds: tuple[str, ...] = ("sequential", "loop"),
) -> pd.DataFrame:
    """Relative-pose constraints between overlapping scans by planar ICP.

    Each pair of :func:`candidate_pairs` is aligned by coarse-to-fine point-to-point
    ICP, source scan ``j`` against target scan ``i`` in ``i``'s scanner frame, starting
    from the relative pose of ``poses``. The clouds are projected to the xy plane
    (z = 0) and voxel-downsampled on ``voxel_size_m``; Open3D's ``registration_icp``
    (point-to-point) on coplanar clouds stays planar (x, y, yaw), and gives the same
    result as :func:`floorscan.registration.icp_planar` (median difference 0, 95th
    percentile 0.27 mm over 1500 pairs of hallways) at half the CPU time (single
    thread: 2.7 vs 5.5 s), since its iterations run in C++. Its convergence criteria stay
    tight (relative fitness and RMSE 1e-6): 1e-4 moved 5 % of the edges by > 2 cm.
    Fitness before and after ICP uses a cKDTree of each target scan built once.

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

    Returns
    -------
    pandas.DataFrame
        :data:`EDGE_COLUMNS`, one row per pair tried: ``dx_m, dy_m, dyaw_rad`` is the
        pose of scan ``j`` in scan ``i``'s frame; ``fitness_prior`` the inlier fraction
        under the initial poses (thesis Algorithm 3 step 3), ``fitness`` the inlier
        fraction and ``inlier_rmse_m`` the RMS inlier distance after ICP (fitness 0 and the initial
        relative pose when ICP found no correspondences). :func:`optimize_pose_graph`
        uses the pairs with ``fitness >= min_edge_fitness``.
    """
    from floorscan.registration import voxel_downsample

    poses = np.asarray(poses, dtype=np.float64)
    pts = []
    for c in clouds:  # the xy projection (z = 0): Open3D's 6-DoF ICP then stays planar
        p = np.array(c, dtype=np.float64).reshape(-1, 3)
        p[:, 2] = 0.0
        pts.append(voxel_downsample(p, params.voxel_size_m))
    pairs = [(i, j, kind) for i, j, kind in candidate_pairs(poses, t_s, params)
             if len(pts[i]) >= 3 and len(pts[j]) >= 3]
    chunks = _chunks(pairs, max(1, int(params.workers)))
    if len(chunks) <= 1:
        rows = _pair_rows(pts, poses, pairs, params, icp_kinds)
    else:
        rows = _parallel_pair_rows(pts, poses, chunks, params, icp_kinds)
    return pd.DataFrame(rows, columns=EDGE_COLUMNS).astype(
        {"i": np.int64, "j": np.int64, "kind": str, "dx_m": float, "dy_m": float,
         "dyaw_rad": float, "fitness_prior": float, "fitness": float, "inlier_rmse_m": float}
    )


_MIN_PAIRS_PER_WORKER = 200


def _chunks(pairs: list, n: int) -> list[list]:
    """``pairs`` cut into ``n`` contiguous runs of near-equal length (fewer when short:
    a worker costs ~1 s to start, so each gets at least 200 pairs)."""
    n = max(1, min(n, len(pairs) // _MIN_PAIRS_PER_WORKER))
    bounds = np.linspace(0, len(pairs), n + 1).round().astype(int)
    return [pairs[a:b] for a, b in zip(bounds[:-1], bounds[1:])]


def _parallel_pair_rows(pts, poses, chunks, params, icp_kinds) -> list[tuple]:
    """:func:`_pair_rows` of ``chunks[1:]`` in worker processes and of ``chunks[0]``
    here; rows in pair order. Each worker is a fresh interpreter
    (``python -c ... _pair_rows_worker``) fed its pairs and only their clouds through a
    pipe (pickle): not forked, since Open3D's OpenMP runtime is not safe across fork,
    and not ``multiprocessing``'s spawn, which re-runs the parent's main script (a
    Snakemake stage script has no ``__main__`` guard)."""
    import pickle
    import subprocess
    import sys

    procs = []
    try:
        for chunk in chunks[1:]:
            need = sorted({k for i, j, _ in chunk for k in (i, j)})
            job = pickle.dumps(({k: pts[k] for k in need}, poses, chunk, params, icp_kinds))
            proc = subprocess.Popen(
                [sys.executable, "-c", "from floorscan.posegraph import _pair_rows_worker; _pair_rows_worker()"],
                stdin=subprocess.PIPE, stdout=subprocess.PIPE,
            )
            proc.stdin.write(job)
            proc.stdin.close()
            procs.append(proc)
        rows = _pair_rows(pts, poses, chunks[0], params, icp_kinds)
        for proc in procs:
            out = proc.stdout.read()
            if proc.wait() != 0:
                raise RuntimeError(f"edge ICP worker exited with {proc.returncode}")
            rows.extend(pickle.loads(out))
    finally:
        for proc in procs:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    return rows


def _pair_rows_worker() -> None:
    """Entry point of an edge ICP worker: a pickled ``_pair_rows`` call on stdin, its
    rows pickled on stdout."""
    import pickle
    import sys

    args = pickle.load(sys.stdin.buffer)
    sys.stdout.buffer.write(pickle.dumps(_pair_rows(*args)))
    sys.stdout.buffer.flush()


def _pair_rows(pts, poses: np.ndarray, pairs, params: GraphParams, icp_kinds) -> list[tuple]:
    """The :data:`EDGE_COLUMNS` rows of ``pairs`` (see :func:`scan_pair_edges`);
    ``pts[k]`` is scan k's projected, downsampled cloud (a list or a dict)."""
    import open3d as o3d

    from floorscan.registration import transform_points

    reg = o3d.pipelines.registration
    trees: dict[int, cKDTree] = {}
    o3d_clouds: dict[int, object] = {}

    def cloud(k: int):
        if k not in o3d_clouds:
            o3d_clouds[k] = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(pts[k]))
        return o3d_clouds[k]

    criteria = reg.ICPConvergenceCriteria(1e-6, 1e-6, int(params.icp_max_iterations))
    estimation = reg.TransformationEstimationPointToPoint()
    rows = []
    with _one_openmp_thread():
        for i, j, kind in pairs:
            if i not in trees:
                trees[i] = cKDTree(pts[i])
            rel = se2_between(poses[i], poses[j])
            d0, _ = trees[i].query(
                transform_points(pts[j], rel[0], rel[1], 0.0, rel[2]), distance_upper_bound=params.inlier_m
            )
            fitness_prior = float(np.isfinite(d0).mean())
            if kind not in icp_kinds:
                rows.append((i, j, kind, rel[0], rel[1], rel[2], fitness_prior, 1.0, 0.0))
                continue
            T = _matrix(*rel)
            ok = True
            for dist in params.icp_distances_m:
                res = reg.registration_icp(cloud(j), cloud(i), float(dist), T, estimation, criteria)
                if len(res.correspondence_set) < 3:
                    ok = False
                    break
                T = np.asarray(res.transformation)
            if not ok:
                rows.append((i, j, kind, rel[0], rel[1], rel[2], fitness_prior, 0.0, math.nan))
                continue
            pose = (float(T[0, 3]), float(T[1, 3]), 0.0, math.atan2(T[1, 0], T[0, 0]))
            src = transform_points(pts[j], pose[0], pose[1], 0.0, pose[3])
            d, _ = trees[i].query(src, distance_upper_bound=params.inlier_m)
            inl = np.isfinite(d)
            fitness = float(inl.mean())
            rmse = float(np.sqrt(np.mean(d[inl] ** 2))) if inl.any() else math.nan
            rows.append((i, j, kind, pose[0], pose[1], pose[3], fitness_prior, fitness, rmse))
    return rows


def optimize_pose_graph(
    poses: np.ndarray,
    edges: pd.DataFrame,
    priors: np.ndarray | None = None,
    params: GraphParams = GraphParams(),
) -> tuple[np.ndarray, dict]:
    """Optimise the scan poses of a pose graph (Open3D, Gauss-Newton).

    Open3D builds a dense 6N x 6N normal matrix per iteration (300 MB and ~0.1 s for
    the 1018 nodes of hallways), so iterations are what cost. Its Levenberg-Marquardt
    needed ~50 of them (9.3 s CPU on hallways); Gauss-Newton converges in a few from
    the localizer's poses, to the same poses (RMS error vs the truth 1.86 cm, 0.179 deg
    either way) in 1.1 s. Cutting LM's iterations instead loses accuracy (10: 2.37 cm,
    0.66 deg). Measured on hallways (1017 sampled scans, 3214 edges).

    Parameters
    ----------
    poses : (N, 4) float ndarray
        Initial poses ``x, y, z, yaw`` (metres, radians); z is passed through.
    edges : pandas.DataFrame
        :func:`scan_pair_edges` output; pairs below ``min_edge_fitness`` are ignored.
    priors : (N, 4) float ndarray, optional
        Absolute poses (the localizer's); each is a constraint with
        ``prior_sigma_m`` / ``prior_sigma_rad``. Without priors the first scan is
        held at its initial pose (odometry mode).
    params : GraphParams

    Returns
    -------
    poses : (N, 4) float64 ndarray
        Optimised poses.
    info : dict
        ``n_edges``, ``n_sequential``, ``n_loop``, ``n_pruned`` (loop edges the line
        process switched off) and ``n_isolated`` (scans without any edge).

    Raises
    ------
    ValueError
        When the shapes disagree or an edge names a scan out of range.
    """
    import open3d as o3d

    reg = o3d.pipelines.registration
    poses = np.asarray(poses, dtype=np.float64)
    n = len(poses)
    if poses.ndim != 2 or poses.shape[1] != 4:
        raise ValueError(f"poses: expected shape (N, 4), got {poses.shape}")
    if priors is not None and np.shape(priors) != poses.shape:
        raise ValueError(f"priors: expected shape {poses.shape}, got {np.shape(priors)}")
    if len(edges) and (edges["i"].min() < 0 or edges["j"].max() >= n):
        raise ValueError(f"edges name scans outside 0..{n - 1}")
    edges = edges[edges["fitness"] >= params.min_edge_fitness]
    info = {
        "n_edges": int(len(edges)),
        "n_sequential": int((edges["kind"] == "sequential").sum()) if len(edges) else 0,
        "n_loop": int((edges["kind"] == "loop").sum()) if len(edges) else 0,
        "n_pruned": 0,
        "n_isolated": int(n - len(np.unique(np.r_[edges["i"], edges["j"]]))) if len(edges) else n,
    }
    if n == 0:
        return poses.copy(), info
    graph = reg.PoseGraph()
    anchor = priors is not None
    offset = 1 if anchor else 0
    if anchor:
        graph.nodes.append(reg.PoseGraphNode(np.eye(4)))
    for p in poses:
        graph.nodes.append(reg.PoseGraphNode(_matrix(p[0], p[1], p[3])))
    if anchor:
        prior_info = _information(params.prior_sigma_m, params.prior_sigma_rad)
        for k, p in enumerate(np.asarray(priors, dtype=np.float64)):
            graph.edges.append(reg.PoseGraphEdge(k + 1, 0, _matrix(p[0], p[1], p[3]), prior_info, uncertain=False))
    edge_info = _information(params.edge_sigma_m, params.edge_sigma_rad)
    for e in edges.itertuples(index=False):
        # Open3D: the transformation takes the source node's frame (j) into the target's (i)
        graph.edges.append(
            reg.PoseGraphEdge(
                int(e.j) + offset, int(e.i) + offset, _matrix(e.dx_m, e.dy_m, e.dyaw_rad),
                edge_info, uncertain=e.kind == "loop",
            )
        )
    n_before = len(graph.edges)
    option = reg.GlobalOptimizationOption(
        max_correspondence_distance=params.inlier_m,
        edge_prune_threshold=0.25,
        preference_loop_closure=1.0,
        reference_node=0,
    )
    level = o3d.utility.get_verbosity_level()
    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)
    try:
        with _one_openmp_thread():
            reg.global_optimization(
                graph, reg.GlobalOptimizationGaussNewton(),
                reg.GlobalOptimizationConvergenceCriteria(), option,
            )
    finally:
        o3d.utility.set_verbosity_level(level)
    info["n_pruned"] = int(n_before - len(graph.edges))
    out = poses.copy()
    for k in range(n):
        m = np.asarray(graph.nodes[k + offset].pose)
        out[k, 0], out[k, 1] = m[0, 3], m[1, 3]
        out[k, 3] = math.atan2(m[1, 0], m[0, 0])
    return out, info


def refine_poses(
    clouds: Sequence[np.ndarray],
    initial: np.ndarray,
    t_s: np.ndarray,
    priors: np.ndarray | None,
    params: GraphParams = GraphParams(),
    icp_kinds: tuple[str, ...] = ("sequential", "loop"),
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
    """Pose-graph registration of a sequence of scans: edges, then optimisation.

    Parameters
    ----------
    clouds : sequence of (N_k, 3) float ndarray
        Scanner-frame points, metres, in time order.
    initial : (N, 4) float ndarray
        Initial poses ``x, y, z, yaw`` (metres, radians): the localizer's, or an
        odometry chain.
    t_s : (N,) float ndarray
        Scan times, seconds.
    priors : (N, 4) float ndarray or None
        The localizer's poses (None in odometry mode: the first scan is held).
    params : GraphParams
    icp_kinds : tuple of str
        See :func:`scan_pair_edges`.

    Returns
    -------
    poses : (N, 4) float64 ndarray
        Optimised poses.
    fitness_prior : (N,) float64 ndarray
        Mean fitness of each scan under the initial poses over the pairs it was tried
        in (NaN: none).
    fitness : (N,) float64 ndarray
        The same after ICP.
    inlier_rmse_m : (N,) float64 ndarray
        Mean inlier RMSE over its edges in the graph, metres (NaN: none).
    info : dict
        :func:`optimize_pose_graph`'s, plus ``n_pairs`` (pairs tried).
    """
    initial = np.asarray(initial, dtype=np.float64)
    n = len(initial)
    edges = scan_pair_edges(clouds, initial, t_s, params, icp_kinds)
    poses, info = optimize_pose_graph(initial, edges, priors, params)
    info["n_pairs"] = int(len(edges))
    both = np.r_[edges["i"].to_numpy(), edges["j"].to_numpy()]
    cnt = np.bincount(both, minlength=n)

    def per_scan(col: str) -> np.ndarray:
        v = np.r_[edges[col].to_numpy(), edges[col].to_numpy()]
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.bincount(both, weights=v, minlength=n) / cnt

    fitness_prior, fitness = per_scan("fitness_prior"), per_scan("fitness")
    good = edges["fitness"].to_numpy() >= params.min_edge_fitness
    gi = np.r_[edges["i"].to_numpy()[good], edges["j"].to_numpy()[good]]
    gr = np.r_[edges["inlier_rmse_m"].to_numpy()[good], edges["inlier_rmse_m"].to_numpy()[good]]
    gc = np.bincount(gi, minlength=n)
    with np.errstate(invalid="ignore", divide="ignore"):
        rmse = np.bincount(gi, weights=gr, minlength=n) / gc
    return poses, fitness_prior, fitness, rmse, info

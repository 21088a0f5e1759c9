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
  loop closures that make the map consistent where the path returns; a scan's loop
  partners are at least ``loop_partner_separation_m`` apart along the path, so they
  come from different revisits (passes) rather than neighbouring scans of one.

An edge enters the graph when, after coarse-to-fine planar ICP (x, y, yaw; the rover is
planar, thesis 3.2.2), at least ``min_edge_fitness`` of the source scan's points lie
within ``inlier_m`` of the target scan. Loop edges are "uncertain" in Open3D's sense: the
optimiser's line process may prune one that disagrees with the rest.

The optimiser (:func:`optimize_pose_graph`) is planar, SE(2) (x, y, yaw per scan):
Gauss-Newton on the sparse 3N x 3N normal equations (SciPy's SuperLU), so memory and
time grow with the number of edges, not with N squared. Loop edges are robust, with
the line process of Open3D's global optimisation (Choi et al. 2015), which the
``solver: open3d`` option still runs: there the graph is 6-DoF; z, roll and pitch get
an information of ``FIXED_INFORMATION`` so the solution stays planar, and the localizer
priors are edges from a fixed anchor node (the map origin) to each scan node.
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

from floorscan.register.registration import se2_between, transform_points, voxel_downsample, wrap_angle

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
    loop_partner_separation_m : float
        The loop partners of a scan are at least this far apart along the path (the
        distance travelled between them under the initial poses), metres: one per
        revisit, as a pass through the ``loop_radius_m`` disc is about twice the
        radius long; 0: the nearest candidates, however close to each other. Loop
        closure from distinct passes is what ties the passes together; neighbouring
        scans of one pass add ICP time and little information. 6 with 2 loops a scan
        against 0 with 4 (issue 8; RMS error against the simulator's truth; 3 runs of
        registration interleaved): hallways3d 2893 instead of 3999 pairs, 1.50 against
        1.47 cm, 0.135 against 0.133 deg, edge-ICP CPU 10.8-12.8 against 13.3-15.6 s,
        wall 9.2-11.4 against 10.5-12.3 s; hallways (2D) 1.79 against 1.84 cm, 0.160
        against 0.187 deg; hallways3d_6000 1.53 against 1.40 cm, 0.159 against 0.197
        deg, and scan 2755 (mean prior fitness over its pairs 0.140 against 0.153)
        fell below ``min_prior_fitness`` and is not kept (1201 of 1202). 2 loops
        without the separation: hallways3d 1.61 cm, 0.128 deg.
    icp_distances_m : tuple of float
        Coarse-to-fine maximum correspondence distances of the edge ICP, metres.
    icp_max_iterations : int
        Per distance. 10: the poses against the simulator's truth were as good as with
        20 or better (hallways3d 1.57 -> 1.55 cm, 0.120 -> 0.119 deg; hallways 1.86 ->
        1.78 cm, 0.179 -> 0.198 deg) for 2-4 CPU-s less of edge ICP; 6 was worse
        (hallways3d 1.61 cm, 0.141 deg).
    voxel_size_m : float
        Voxel downsampling of the scans before the edge ICP, metres (0: none).
    coarse_voxel_size_m : float
        Every ICP stage but the last (the coarser ``icp_distances_m``) aligns the
        clouds voxel-downsampled again on this, metres (0, or not above
        ``voxel_size_m``: the clouds themselves); the last stage and the fitness use
        the full clouds. Coarse-to-fine multi-scale ICP, as Open3D's multi-scale ICP
        (its tutorial halves the voxel with the distance). 0.1 against 0 (issue 8):
        1500 edges of hallways3d in 3.2 against 4.0 CPU-s (one process, interleaved);
        RMS error against the simulator's truth hallways3d 1.55 -> 1.47 cm (0.119 ->
        0.133 deg), hallways 1.78 -> 1.84 cm (0.198 -> 0.187 deg); 0.15 gave 1.58 cm,
        0.141 deg on hallways3d. On the real mac_ros2 recording the
        edges moved by 0 cm (median; 0.3 cm p95, 2 cm at most) and one of 283 pairs
        fell under ``min_edge_fitness`` (0.59 after the coarse stage, just above
        0.6 without), leaving one of 72 scans without an edge (on its prior).
    vertical_extent_m : float
        A 3D scan keeps the 2D cells whose points span at least this height, metres
        (floor and ceiling drop out; :func:`floorscan.register.registration.graph_cloud`).
    max_height_gap_m : float
        ... counting heights without a gap wider than this between them, metres.
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
    solver : str
        ``"sparse"`` (planar Gauss-Newton on sparse normal equations) or ``"open3d"``
        (Open3D's dense 6-DoF Gauss-Newton); see :func:`optimize_pose_graph`.
    """

    sequential_neighbours: int = 2
    loop_radius_m: float = 3.0
    loop_min_separation_s: float = 3.0
    loop_max_per_scan: int = 2
    loop_partner_separation_m: float = 6.0
    icp_distances_m: tuple[float, ...] = (0.3, 0.1)
    icp_max_iterations: int = 10
    voxel_size_m: float = 0.05
    coarse_voxel_size_m: float = 0.1
    vertical_extent_m: float = 0.2
    max_height_gap_m: float = 0.5
    inlier_m: float = 0.05
    min_edge_fitness: float = 0.6
    edge_sigma_m: float = 0.005
    edge_sigma_rad: float = 0.002
    prior_sigma_m: float = 0.05
    prior_sigma_rad: float = 0.02
    workers: int = 1
    solver: str = "sparse"

    @classmethod
    def from_mapping(cls, cfg) -> "GraphParams":
        """From a config mapping (unknown keys raise ``KeyError``)."""
        from floorscan.core.config import dataclass_from_mapping

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
    import open3d as o3d  # noqa: F401  (its OpenMP runtime must be loaded before the scan)
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


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
    ahead: "EdgeStream | None" = None,
    scan_ids: Sequence[int] | None = None,
) -> pd.DataFrame:
    """Relative-pose constraints between overlapping scans by planar ICP.

    Each pair of :func:`candidate_pairs` is aligned by coarse-to-fine point-to-point
    ICP, source scan ``j`` against target scan ``i`` in ``i``'s scanner frame, starting
    from the relative pose of ``poses``. The clouds are projected to the xy plane
    (z = 0) and voxel-downsampled on ``voxel_size_m``; Open3D's ``registration_icp``
    (point-to-point) on coplanar clouds stays planar (x, y, yaw), and gives the same
    result as :func:`floorscan.register.registration.icp_planar` (median difference 0, 95th
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
    ahead : EdgeStream, optional
        Pairs aligned ahead (after :meth:`EdgeStream.finish`): a pair found in its
        ``rows`` (by scan ids) with the same kind takes that row (the same clouds,
        poses and parameters give the same row), the others are aligned here; its
        projected clouds (``pts``) are used, not made again.
    scan_ids : sequence of int, optional
        The scan id of each cloud (needed with ``ahead``).

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
    poses = np.asarray(poses, dtype=np.float64)
    if ahead is not None and (scan_ids is None or len(scan_ids) != len(clouds)):
        raise ValueError("edges aligned ahead need the scan_ids of the clouds")
    ids = [int(s) for s in scan_ids] if ahead is not None else None
    pts = [
        ahead.pts[ids[k]] if ahead is not None and ids[k] in ahead.pts else _plane_cloud(c, params.voxel_size_m)
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
    computed = iter(_parallel_pair_rows(pts, poses, _chunks(todo, max(1, int(params.workers))), params, icp_kinds))
    rows = [done[n] if n in done else next(computed) for n in range(len(pairs))]
    if ahead is not None:
        log.info("edges: %d of %d pairs aligned while the scans were read", len(done), len(pairs))
    return pd.DataFrame(rows, columns=EDGE_COLUMNS).astype(
        {"i": np.int64, "j": np.int64, "kind": str, "dx_m": float, "dy_m": float,
         "dyaw_rad": float, "fitness_prior": float, "fitness": float, "inlier_rmse_m": float}
    )


def _plane_cloud(cloud: np.ndarray, voxel_size_m: float) -> np.ndarray:
    """A cloud as ICP aligns it: projected to xy (z = 0: Open3D's 6-DoF ICP then stays
    planar), voxel-downsampled; (M, 3) float64."""
    p = np.array(cloud, dtype=np.float64).reshape(-1, 3)
    p[:, 2] = 0.0
    return voxel_downsample(p, voxel_size_m)


class EdgeStream:
    """The ICP of :func:`scan_pair_edges`, run in worker processes while the clouds
    arrive, for the scans expected to be sampled (issue 8: the register stage reads
    and screens a 3D recording for seconds, and the edges took as long again after).

    The pairs are :func:`candidate_pairs` of the expected scans and their initial
    poses; each is sent (in batches of :data:`STREAM_BATCH`) to the least busy worker
    as soon as both its clouds are here, a worker keeping the clouds it was sent.
    :func:`scan_pair_edges` then takes the rows of its pairs and the projected
    clouds (``rows``, ``pts``) after :meth:`finish` and aligns only pairs that were
    not expected (a scan dropped after all), so the
    edges are the same as without the stream (tested).

    Parameters
    ----------
    scan_ids : (N,) int array-like
        The scans expected, in time order.
    poses : (N, 4) float ndarray
        Their initial poses ``x, y, z, yaw`` (metres, radians).
    t_s : (N,) float ndarray
        Their times, seconds.
    params : GraphParams
    icp_kinds : tuple of str
        As :func:`scan_pair_edges`.
    workers : int
        Worker processes (:class:`floorscan.core.parallel.CallStream`; ones started ahead
        by :func:`floorscan.core.parallel.prestart` first).
    """

    def __init__(self, scan_ids, poses, t_s, params: GraphParams, icp_kinds: tuple[str, ...], workers: int):
        from floorscan.core.parallel import CallStream

        ids = [int(s) for s in scan_ids]
        poses = np.asarray(poses, dtype=np.float64)
        self.params, self.icp_kinds = params, icp_kinds
        self.poses = {sid: poses[k] for k, sid in enumerate(ids)}
        self.by_later: dict[int, list[tuple[int, int, str]]] = {}
        for i, j, kind in candidate_pairs(poses, t_s, params):
            self.by_later.setdefault(ids[j], []).append((ids[i], ids[j], kind))
        self.pts: dict[int, np.ndarray] = {}
        self.stream = CallStream(workers)
        self.sent = [set() for _ in range(max(1, int(workers)))]
        self.ready: list[tuple[int, int, str]] = []
        #: After :meth:`finish`: the :data:`EDGE_COLUMNS` rows by ``(i, j)`` (scan ids).
        self.rows: dict[tuple[int, int], tuple] = {}

    def add(self, scan_id: int, cloud: np.ndarray) -> None:
        """Scan ``scan_id``'s cloud (as for :func:`scan_pair_edges`) is here: send the
        pairs it completes (with an earlier scan) once a batch is full."""
        sid = int(scan_id)
        self.pts[sid] = p = _plane_cloud(cloud, self.params.voxel_size_m)
        if len(p) < 3:
            return
        for pair in self.by_later.get(sid, ()):
            other = self.pts.get(pair[0])
            if other is not None and len(other) >= 3:
                self.ready.append(pair)
        if len(self.ready) >= STREAM_BATCH:
            self._send()

    def _send(self) -> None:
        if not self.ready:
            return
        w = self.stream.least_busy()
        scans = {k for i, j, _ in self.ready for k in (i, j)}
        new = {k: self.pts[k] for k in sorted(scans - self.sent[w])}
        self.sent[w] |= new.keys()
        poses = {k: self.poses[k] for k in sorted(scans)}
        self.stream.submit(w, _stream_pair_rows, (new, poses, self.ready, self.params, self.icp_kinds))
        self.ready = []

    def finish(self) -> "EdgeStream":
        """Send the last batch and wait for :attr:`rows` (``i, j`` are scan ids); returns self."""
        self._send()
        self.rows = {(r[0], r[1]): r for rows in self.stream.results() for r in rows}
        return self

    def close(self) -> None:
        """Stop the workers (after an error elsewhere)."""
        self.stream.close()


#: Pairs per call of :class:`EdgeStream` (~0.3 s of ICP).
STREAM_BATCH = 100

#: The clouds an :class:`EdgeStream` worker process was sent, by scan id.
_STREAM_CLOUDS: dict[int, np.ndarray] = {}


def _stream_pair_rows(new_clouds, poses, pairs, params, icp_kinds) -> list[tuple]:
    """:func:`_pair_rows` in an :class:`EdgeStream` worker: ``new_clouds`` join the
    clouds sent before; ``i, j`` and the keys of ``poses`` are scan ids."""
    _STREAM_CLOUDS.update(new_clouds)
    return _pair_rows(_STREAM_CLOUDS, poses, pairs, params, icp_kinds)


_MIN_PAIRS_PER_WORKER = 200


def _chunks(pairs: list, n: int) -> list[list]:
    """``pairs`` cut into ``n`` contiguous runs of near-equal length (fewer when short:
    a worker costs ~1 s to start, so each gets at least 200 pairs)."""
    n = max(1, min(n, len(pairs) // _MIN_PAIRS_PER_WORKER))
    bounds = np.linspace(0, len(pairs), n + 1).round().astype(int)
    return [pairs[a:b] for a, b in zip(bounds[:-1], bounds[1:])]


def _parallel_pair_rows(pts, poses, chunks, params, icp_kinds) -> list[tuple]:
    """:func:`_pair_rows` of each chunk (:func:`floorscan.core.parallel.map_in_processes`:
    the first here and the others in worker processes, or all in workers started ahead
    by :func:`floorscan.core.parallel.prestart`, as the register stage does while it reads
    the scans: this process then never imports Open3D, 1.5 - 3 s of CPU on the stage's
    critical path), each fed only the clouds of its pairs; rows in pair order."""
    from floorscan.core.parallel import map_in_processes

    calls = []
    for chunk in chunks:
        need = sorted({k for i, j, _ in chunk for k in (i, j)})
        calls.append(({k: pts[k] for k in need}, poses, chunk, params, icp_kinds))
    return [row for rows in map_in_processes(_pair_rows, calls) for row in rows]


def _pair_rows(pts, poses: np.ndarray, pairs, params: GraphParams, icp_kinds) -> list[tuple]:
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
            for stage, dist in enumerate(params.icp_distances_m):
                res = reg.registration_icp(
                    stage_cloud(j, stage), stage_cloud(i, stage), float(dist), T, estimation, criteria
                )
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


#: Line process of robust loop edges (Open3D's ``GlobalOptimizationOption`` defaults,
#: Choi et al. 2015): a loop edge's confidence is ``(mu / (mu + r2)) ** 2`` with ``r2``
#: its squared normalised residual; ``mu = LOOP_PREFERENCE_M2 / edge_sigma_m ** 2``, so an
#: edge is switched off (confidence below ``EDGE_PRUNE_THRESHOLD``) when it disagrees with
#: the graph by about sqrt(LOOP_PREFERENCE_M2) = 1 m (or 1 m / edge_sigma_m *
#: edge_sigma_rad = 0.4 rad of yaw): the misalignment Open3D's ``preference_loop_closure``
#: of 1 tolerates with information matrices counted in correspondences.
LOOP_PREFERENCE_M2 = 1.0
EDGE_PRUNE_THRESHOLD = 0.25

#: Gauss-Newton stops when no pose moves by more than this (metres or radians) ...
_GN_TOLERANCE = 1e-10
#: ... or after this many iterations per pass (6 - 8 from the localizer's poses).
_GN_MAX_ITERATIONS = 50


def optimize_pose_graph(
    poses: np.ndarray,
    edges: pd.DataFrame,
    priors: np.ndarray | None = None,
    params: GraphParams = GraphParams(),
) -> tuple[np.ndarray, dict]:
    """Optimise the scan poses of a planar pose graph.

    The model (Grisetti et al. 2010, section III): each scan is a node ``(x, y, yaw)``;
    an edge ``(i, j)`` says that scan ``j``'s pose in scan ``i``'s frame is
    ``(dx_m, dy_m, dyaw_rad)``, with standard deviations ``edge_sigma_m`` and
    ``edge_sigma_rad``; a prior says that scan ``k`` is at ``priors[k]`` with
    ``prior_sigma_m`` / ``prior_sigma_rad``. The optimum minimises the sum of squared
    normalised residuals. Loop edges (``kind == "loop"``) are robust: Open3D's line
    process (Choi et al. 2015, section 5; see :data:`LOOP_PREFERENCE_M2`) reweights them
    at every iteration, the loop edges whose confidence ends below
    :data:`EDGE_PRUNE_THRESHOLD` are removed and the graph is solved again from the
    result (as Open3D's ``global_optimization`` does).

    ``solver: sparse`` (default) runs Gauss-Newton on the sparse 3N x 3N normal equations
    (SciPy's SuperLU with a symmetric minimum-degree ordering): memory and time grow
    with the edges. ``solver: open3d`` runs Open3D's 6-DoF Gauss-Newton, which builds a
    dense 6N x 6N normal matrix per iteration. Measured on hallways (1017 sampled scans,
    3214 edges): the two differ by at most 0.07 mm and 0.0005 deg (RMS error vs the
    truth 1.86 cm, 0.179 deg either way); sparse 0.09 s CPU and +18 MB peak RSS, open3d
    1.4 - 2.4 s and +583 MB. Hallways tiled to 2034 scans: sparse 0.13 s, +24 MB; open3d
    5.7 s, +2.3 GB (quadratic: ~21 GB at 6000 scans); to 6102 scans: sparse 0.41 s,
    +57 MB.

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
        Optimised poses, yaw wrapped to [-pi, pi).
    info : dict
        ``n_edges``, ``n_sequential``, ``n_loop``, ``n_pruned`` (loop edges the line
        process switched off) and ``n_isolated`` (scans without any edge).

    Raises
    ------
    ValueError
        When the shapes disagree, an edge names a scan out of range or ``solver`` is
        unknown.
    """
    poses = np.asarray(poses, dtype=np.float64)
    n = len(poses)
    if poses.ndim != 2 or poses.shape[1] != 4:
        raise ValueError(f"poses: expected shape (N, 4), got {poses.shape}")
    if priors is not None and np.shape(priors) != poses.shape:
        raise ValueError(f"priors: expected shape {poses.shape}, got {np.shape(priors)}")
    if len(edges) and (edges["i"].min() < 0 or edges["j"].max() >= n):
        raise ValueError(f"edges name scans outside 0..{n - 1}")
    if params.solver not in ("sparse", "open3d"):
        raise ValueError(f"register.graph.solver: expected 'sparse' or 'open3d', got {params.solver!r}")
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
    if params.solver == "open3d":
        out, info["n_pruned"] = _optimize_open3d(poses, edges, priors, params)
        return out, info
    ii = edges["i"].to_numpy(np.int64)
    jj = edges["j"].to_numpy(np.int64)
    z = edges[["dx_m", "dy_m", "dyaw_rad"]].to_numpy(np.float64)
    loop = (edges["kind"] == "loop").to_numpy()
    w_edge = np.array([1 / params.edge_sigma_m, 1 / params.edge_sigma_m, 1 / params.edge_sigma_rad])
    w_prior = np.array([1 / params.prior_sigma_m, 1 / params.prior_sigma_m, 1 / params.prior_sigma_rad])
    prior = None if priors is None else np.asarray(priors, dtype=np.float64)[:, [0, 1, 3]]
    mu = LOOP_PREFERENCE_M2 / params.edge_sigma_m**2
    x, conf = _gauss_newton(poses[:, [0, 1, 3]], ii, jj, z, loop, w_edge, prior, w_prior, mu)
    keep = conf >= EDGE_PRUNE_THRESHOLD
    if not keep.all():
        x, _ = _gauss_newton(x, ii[keep], jj[keep], z[keep], loop[keep], w_edge, prior, w_prior, mu)
    info["n_pruned"] = int((~keep).sum())
    out = poses.copy()
    out[:, 0], out[:, 1], out[:, 3] = x[:, 0], x[:, 1], wrap_angle(x[:, 2])
    return out, info


def _edge_residuals(x: np.ndarray, ii: np.ndarray, jj: np.ndarray, z: np.ndarray):
    """Residuals (E, 3) of the edges at poses ``x`` (N, 3): scan j's pose in scan i's
    frame minus the measured one; and cos, sin of the yaw of i and the map-frame
    displacement (dx, dy) from i to j, which the Jacobian reuses."""
    c, s = np.cos(x[ii, 2]), np.sin(x[ii, 2])
    dx, dy = x[jj, 0] - x[ii, 0], x[jj, 1] - x[ii, 1]
    r = np.column_stack([c * dx + s * dy - z[:, 0], -s * dx + c * dy - z[:, 1], wrap_angle(x[jj, 2] - x[ii, 2] - z[:, 2])])
    return r, c, s, dx, dy


def _gauss_newton(x0, ii, jj, z, loop, w_edge, prior, w_prior, mu) -> tuple[np.ndarray, np.ndarray]:
    """Planar pose-graph Gauss-Newton with Open3D's line process on the loop edges.

    ``x0`` (N, 3) initial ``x, y, yaw``; ``ii, jj`` (E,) edge ends, ``z`` (E, 3) their
    measurements, ``loop`` (E,) bool; ``w_edge``, ``w_prior`` (3,) square roots of the
    (diagonal) information; ``prior`` (N, 3) or None (then node 0 is held); ``mu`` the
    line-process weight. Each iteration solves ``J^T W J dx = -J^T W r`` (W: information
    times the confidence of the edge) by sparse LU on the free variables; a 1e-12
    relative diagonal keeps it solvable when a scan has no constraint (its step is 0).
    Returns the poses (N, 3) and the final confidence of each edge (1 for the
    non-loop ones).
    """
    from scipy import sparse
    from scipy.sparse.linalg import splu

    n, e = len(x0), len(ii)
    x = np.array(x0, dtype=np.float64, order="C")  # a copy: the caller's array is not changed
    free = np.ones(3 * n, dtype=bool)
    if prior is None:
        free[:3] = False  # odometry mode: the first scan is held
    col = np.cumsum(free) - 1
    n_free = int(free.sum())
    k3 = 3 * np.arange(e)
    one = np.ones(e)
    # Jacobian layout: (row offset, column of i or j, which derivative) per entry
    rows = np.concatenate([k3, k3, k3, k3, k3, k3 + 1, k3 + 1, k3 + 1, k3 + 1, k3 + 1, k3 + 2, k3 + 2])
    cols = np.concatenate([3 * ii, 3 * ii + 1, 3 * ii + 2, 3 * jj, 3 * jj + 1,
                           3 * ii, 3 * ii + 1, 3 * ii + 2, 3 * jj, 3 * jj + 1, 3 * ii + 2, 3 * jj + 2])
    row_axis = rows % 3
    n_rows = 3 * e
    if prior is not None:
        rows = np.r_[rows, n_rows + np.arange(3 * n)]
        cols = np.r_[cols, np.arange(3 * n)]
        prior_vals = np.tile(w_prior, n)
        n_rows += 3 * n
    keep = free[cols]
    rows_k, cols_k = rows[keep], col[cols[keep]]
    conf = np.ones(e)
    for _ in range(_GN_MAX_ITERATIONS):
        r, c, s, dx, dy = _edge_residuals(x, ii, jj, z)
        sw = np.sqrt(conf)[:, None] * w_edge  # (E, 3) square-root weights
        vals = np.concatenate([-c, -s, -s * dx + c * dy, c, s, s, -c, -c * dx - s * dy, -s, c, -one, one])
        vals = vals * sw[rows[: 12 * e] // 3, row_axis]
        res = (r * sw).ravel()
        if prior is not None:
            rp = np.column_stack([x[:, :2] - prior[:, :2], wrap_angle(x[:, 2] - prior[:, 2])])
            vals = np.r_[vals, prior_vals]
            res = np.r_[res, (rp * w_prior).ravel()]
        jac = sparse.csr_matrix((vals[keep], (rows_k, cols_k)), shape=(n_rows, n_free))
        h = (jac.T @ jac).tocsc()
        h = h + sparse.identity(n_free, format="csc") * (1e-12 * max(1.0, float(h.diagonal().max())))
        step = splu(h, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                    options={"SymmetricMode": True}).solve(-(jac.T @ res))
        delta = np.zeros(3 * n)
        delta[free] = step
        x += delta.reshape(n, 3)
        r2 = np.sum((_edge_residuals(x, ii, jj, z)[0] * w_edge) ** 2, axis=1)
        conf = np.where(loop, (mu / (mu + r2)) ** 2, 1.0)
        if not np.all(np.isfinite(step)) or np.max(np.abs(step), initial=0.0) < _GN_TOLERANCE:
            break
    return x, conf


def _optimize_open3d(poses: np.ndarray, edges: pd.DataFrame, priors, params: GraphParams) -> tuple[np.ndarray, int]:
    """``solver: open3d``: Open3D's 6-DoF Gauss-Newton ``global_optimization`` with its
    line process on the loop edges (edge_prune_threshold 0.25, preference_loop_closure 1;
    with the information of an edge's 6 DoF set as here it prunes only far-off loop edges:
    in the L-room test a loop edge 5 m off, not one 2 m off, which ``sparse`` prunes).
    Gauss-Newton converges in a few iterations from the
    localizer's poses; its Levenberg-Marquardt needed ~50 (9.3 s CPU on hallways) to the
    same poses. Returns the poses and the number of loop edges pruned."""
    import open3d as o3d

    reg = o3d.pipelines.registration
    n = len(poses)
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
        edge_prune_threshold=EDGE_PRUNE_THRESHOLD,
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
    out = poses.copy()
    for k in range(n):
        m = np.asarray(graph.nodes[k + offset].pose)
        out[k, 0], out[k, 1] = m[0, 3], m[1, 3]
        out[k, 3] = math.atan2(m[1, 0], m[0, 0])
    return out, int(n_before - len(graph.edges))


def refine_poses(
    clouds: Sequence[np.ndarray],
    initial: np.ndarray,
    t_s: np.ndarray,
    priors: np.ndarray | None,
    params: GraphParams = GraphParams(),
    icp_kinds: tuple[str, ...] = ("sequential", "loop"),
    ahead: "EdgeStream | None" = None,
    scan_ids: Sequence[int] | None = None,
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
    icp_kinds, ahead, scan_ids
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
    edges = scan_pair_edges(clouds, initial, t_s, params, icp_kinds, ahead, scan_ids)
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

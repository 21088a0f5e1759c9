"""Pose-graph registration (``reference: graph``, the default): scan-to-scan ICP
constraints plus the localizer's poses as priors, optimised together.

Thesis section 3.2.2 refines each scan's pose by ICP against earlier scans (Algorithm 3)
and leaves the combination of the two pose sources open. This does what SLAM back ends
do (Lu and Milios 1997; Grisetti et al. 2010, "A tutorial on graph-based SLAM"): every
sampled scan is a node; ICP between overlapping scans gives relative constraints
(edges), which are accurate to millimetres but drift when chained; the localizer's
poses are absolute priors, accurate to centimetres but noisy from scan to scan. The
optimum keeps the relative geometry of ICP and the mean placement of the localizer.
Without a localizer (odometry mode) the first scan is held fixed instead.

The parts, each in its module:

- :mod:`floorscan.register.edges`: the pairs (``sequential`` and ``loop``) and their
  coarse-to-fine planar ICP; an edge enters the graph when at least
  ``min_edge_fitness`` of the source scan's points lie within ``inlier_m`` of the
  target scan after ICP; loop edges are "uncertain" in Open3D's sense;
- :mod:`floorscan.register.edge_stream`: the same ICP while the scans are read;
- :mod:`floorscan.register.solver`: the planar optimiser with robust loop edges;
- :mod:`floorscan.register.agreement`: the keep test (does ICP agree with each scan's
  registered pose? fitness thresholds only where it cannot tell);
- here, :func:`refine_poses` (edges, then optimisation, per-scan fitness) and
  :func:`register_graph`, the register stage's strategy. Usage::

    poses, fitness_prior, fitness, rmse, info = refine_poses(clouds, initial, t_s, priors, params)
"""

from __future__ import annotations

import logging
from concurrent.futures import Executor
from typing import Sequence

import numpy as np
import pandas as pd

from floorscan.core.geometry import wrap_angle
from floorscan.register.agreement import agreement_counts, keep_test, support_floor
from floorscan.register.edges import scan_pair_edges
from floorscan.register.params import GraphParams, RegistrationConfig
from floorscan.register.result import ScanRegistration
from floorscan.register.solver import optimize_pose_graph

log = logging.getLogger(__name__)


def refine_poses(
    clouds: Sequence[np.ndarray],
    initial: np.ndarray,
    t_s: np.ndarray,
    priors: np.ndarray | None,
    params: GraphParams = GraphParams(),
    icp_kinds: tuple[str, ...] = ("sequential", "loop"),
    ahead=None,
    scan_ids: Sequence[int] | None = None,
    pool: Executor | None = None,
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
    icp_kinds, ahead, scan_ids, pool
        See :func:`floorscan.register.edges.scan_pair_edges`.

    Returns
    -------
    poses : (N, 4) float64 ndarray
        Optimised poses.
    fitness_prior : (N,) float64 ndarray
        Mean fitness of each scan under the initial poses over the pairs it was tried
        in (NaN: none): the overlap fitness (over the points its partners could see,
        :func:`floorscan.register.edges.overlap_fitness`) where its pairs give one,
        else the plain one.
    fitness : (N,) float64 ndarray
        The same after ICP.
    inlier_rmse_m : (N,) float64 ndarray
        Mean inlier RMSE over its edges in the graph, metres (NaN: none).
    info : dict
        :func:`floorscan.register.solver.optimize_pose_graph`'s, plus ``n_pairs``
        (pairs tried).
    """
    poses, edges, info = graph_poses(clouds, initial, t_s, priors, params, icp_kinds, ahead, scan_ids, pool)
    fitness_prior, fitness, rmse = scan_fitness(edges, len(poses), params)
    return poses, fitness_prior, fitness, rmse, info


def graph_poses(
    clouds: Sequence[np.ndarray],
    initial: np.ndarray,
    t_s: np.ndarray,
    priors: np.ndarray | None,
    params: GraphParams = GraphParams(),
    icp_kinds: tuple[str, ...] = ("sequential", "loop"),
    ahead=None,
    scan_ids: Sequence[int] | None = None,
    pool: Executor | None = None,
) -> tuple[np.ndarray, pd.DataFrame, dict]:
    """The edges and the optimised poses of :func:`refine_poses` (same parameters):
    ``(poses, edges, info)``, ``edges`` the table of
    :func:`floorscan.register.edges.scan_pair_edges` (the keep test reads it,
    :mod:`floorscan.register.agreement`)."""
    initial = np.asarray(initial, dtype=np.float64)
    edges = scan_pair_edges(clouds, initial, t_s, params, icp_kinds, ahead, scan_ids, pool)
    poses, info = optimize_pose_graph(initial, edges, priors, params)
    info["n_pairs"] = int(len(edges))
    return poses, edges, info


def scan_fitness(edges: pd.DataFrame, n: int, params: GraphParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per scan of ``n``: mean fitness over its pairs under the initial poses and after
    ICP (the overlap fitness where its pairs give one, else the plain one; NaN: no
    pair), and the mean inlier RMSE over its edges in the graph (metres; NaN: none).
    See :func:`refine_poses`."""
    fitness_prior, fitness = _pair_mean(edges, "fitness_prior", n), _pair_mean(edges, "fitness", n)
    # judged on the points its partners could see (overlap fitness,
    # floorscan.register.edges.overlap_fitness) where they could see enough
    overlap_prior, overlap = _pair_mean(edges, "overlap_fitness_prior", n), _pair_mean(edges, "overlap_fitness", n)
    fitness_prior = np.where(np.isfinite(overlap_prior), overlap_prior, fitness_prior)
    fitness = np.where(np.isfinite(overlap), overlap, fitness)
    rmse = _pair_mean(edges, "inlier_rmse_m", n, edges["fitness"].to_numpy() >= params.min_edge_fitness)
    return fitness_prior, fitness, rmse


def _pair_mean(edges: pd.DataFrame, col: str, n: int, use: np.ndarray | None = None) -> np.ndarray:
    """Per scan of ``n``: the mean of ``col`` over the finite values of the pairs it is
    in (only the pairs where ``use`` is True, when given); NaN: none."""
    both = np.r_[edges["i"].to_numpy(), edges["j"].to_numpy()]
    v = np.r_[edges[col].to_numpy(), edges[col].to_numpy()] if col in edges else np.full(len(both), np.nan)
    ok = np.isfinite(v) if use is None else np.isfinite(v) & np.r_[use, use]
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.bincount(both[ok], weights=v[ok], minlength=n) / np.bincount(both[ok], minlength=n)


def register_graph(
    scans, clouds, sids, t, cfg: RegistrationConfig, initial: ScanRegistration, priors: bool, ahead=None, pool=None
) -> ScanRegistration:
    """Pose-graph registration (``reference: graph``, and odometry's loop closure).

    ``scans`` (indices into the scan index, time order) start at ``initial.pose`` (the
    localizer's poses, or the odometry chain). Planar ICP between each scan and its
    next sampled scans and its revisits gives relative constraints; with ``priors``
    the localizer's poses are absolute constraints, otherwise the first scan is held
    (odometry mode: the chain's own motion is the sequential edges and ICP only closes
    loops, which then remove the chain's drift). Thesis Algorithm 3
    steps 3 and 5 become the keep test of :mod:`floorscan.register.agreement`: a scan
    is kept when most of its pairs' ICP agrees with its registered pose, dropped
    (``icp_disagrees``) when most of the pairs with structure put it elsewhere, and
    otherwise judged by its mean fitness over its pairs: below ``min_prior_fitness``
    under the initial poses (``low_prior_fitness``) or below ``min_icp_fitness`` after
    ICP (``low_icp_fitness``) it is not kept. The optimisation runs once, with the
    dropped scans in it: their pairs below ``graph.min_edge_fitness`` are not edges,
    so a scan that fits nothing does not pull the others.

    ``clouds`` is a :class:`floorscan.register.prepare.ScanStore`, ``sids`` and ``t``
    the scan ids and times (ns) of the scan index, ``initial`` the screening's reasons
    and the initial poses (:func:`floorscan.register.sequential.register_sequential`;
    not changed); ``ahead`` and ``pool`` as :func:`refine_poses`.

    Returns
    -------
    ScanRegistration
        With ``priors``: ``initial`` with ``scans`` registered (``sampled``) and kept or
        dropped by the keep test, ``n_anchors`` the scans without any edge (held by
        their prior only). Without (the loop closure): ``initial`` with the optimised
        poses of ``scans``, all else as it was.
    """
    res = initial.copy()  # filled here; ``initial`` stays as it was
    scans = np.asarray(scans, dtype=np.int64)
    if priors:
        res.sampled, res.n_anchors = scans.copy(), 0
    n = len(scans)
    if n == 0:
        return res
    params = cfg.graph_params
    init = initial.pose[scans]  # a copy
    t_s = (t[scans] - t[scans[0]]) * 1e-9
    cl = [clouds.graph(int(sids[i])) for i in scans]
    kinds = ("sequential", "loop") if priors else ("loop",)
    poses, edges, info = graph_poses(
        cl, init, t_s, init if priors else None, params, icp_kinds=kinds, ahead=ahead, scan_ids=sids[scans],
        pool=pool,
    )
    res.pose[scans] = poses
    log.info("pose graph: %d scans, %s", n, info)
    if not priors:
        return res
    res.n_anchors = int(info["n_isolated"])
    fp, fi, rm = scan_fitness(edges, n, params)
    res.fitness_prior[scans] = fp
    res.fitness_icp[scans] = fi
    res.inlier_rmse_m[scans] = rm
    res.pose_correction[scans, 0] = poses[:, 0] - init[:, 0]
    res.pose_correction[scans, 1] = poses[:, 1] - init[:, 1]
    res.pose_correction[scans, 2] = wrap_angle(poses[:, 3] - init[:, 3])
    n_agree, n_supported, n_pairs = agreement_counts(edges, poses, n, params)
    why, confirmed = keep_test(fp, fi, n_agree, n_supported, n_pairs, cfg)
    res.reason[scans] = why
    res.kept[scans] = why == ""
    with np.errstate(invalid="ignore"):
        by_fitness = (fp >= cfg.min_prior_fitness) & (fi >= cfg.min_icp_fitness)
    log.info(
        "keep test: %d of %d scans confirmed by their pairs' ICP (%d of them below the fitness thresholds), "
        "%d contradicted (icp_disagrees), %d judged by fitness alone; a pair counts from fitness %.3f",
        int(confirmed.sum()), n, int((confirmed & ~by_fitness).sum()), int((why == "icp_disagrees").sum()),
        int((~confirmed & (why != "icp_disagrees")).sum()), support_floor(edges, params),
    )
    return res

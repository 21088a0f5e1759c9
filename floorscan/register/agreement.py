"""The pose graph's keep test: a scan is kept when ICP agrees with its pose, judged by
fitness only when ICP cannot tell.

Thesis Algorithm 3 steps 4 and 6 keep a scan by a fixed fitness threshold. Fitness
(Open3D's ``registration_icp`` definition: the fraction of the source's points with a
target point within the inlier distance) measures how much of a scan the other scan
explains, not whether the pose is right. A scan in an open hall whose beams mostly end
on chairs, on far walls sampled 0.3-0.9 m apart, or on nothing the partner saw, has a
low fitness at its right pose; the overlap fitness (the fraction over the points the
partner could see: Pomerleau et al., "Comparing ICP variants on real-world data sets",
Autonomous Robots 34(3), 2013; :func:`floorscan.register.edges.overlap_fitness`) lifts
part of it, not all. So the test here asks ICP itself whether the pose is right.

The rule, for the scans of the pose graph (``reference: graph``), after the
optimisation:

1. Each pair the graph aligned (:func:`floorscan.register.edges.scan_pair_edges`) is
   **supported** when its ICP converged and its overlap fitness after ICP (the plain
   fitness when the partner could see too few points) is at least
   ``graph.agreement_fitness_ratio`` times the median of that fitness over all the
   recording's converged pairs (:func:`support_floor`): there is structure to agree
   on, judged against what ICP reaches with this scanner in this building (far less
   in an open hall scanned every degree than in an office; the medians of the shared
   recordings are in ``benchmarks/README.md``), not against one number for every
   recording. ICP that found (almost) nothing stays near its start and would agree
   with any pose; the floor keeps it out. Taking the threshold from the recording's
   own statistics is KISS-ICP's adaptive threshold (Vizzo et al., "KISS-ICP: In
   Defense of Point-to-Point ICP", RA-L 8(2), 2023), which sets its correspondence
   distance from the deviations of ICP from the motion prediction seen so far.
2. A supported pair **agrees** when the relative pose ICP found is within
   ``graph.agreement_m`` (translation) and ``graph.agreement_rad`` (yaw) of the relative
   pose of the registered poses (:func:`pair_residuals`). This is the individual
   compatibility test of data association (a measurement is accepted when it lies
   within a gate around the estimate's prediction: Neira and Tardos, "Data
   association in stochastic mapping using the joint compatibility test", IEEE T-RA
   17(6), 2001), with the ICP result as the measurement and the registered poses as
   the prediction. Against the registered poses, not the localizer's: a pose the
   graph corrected agrees with the edges that corrected it.
3. A scan is **confirmed** when at least half of all the pairs it is in agree: kept,
   whatever its fitness (a corrected SLAM pose that ICP does not move is trustworthy
   even when few of its points find a partner within 5 cm).
4. A scan is **contradicted** when it has supported pairs and fewer than half of them
   agree: ICP, where it had structure, put the scan elsewhere. Dropped, reason
   ``icp_disagrees``, whatever its fitness.
5. Otherwise (too few supported pairs to confirm it, too few contradicting ones to
   drop it) the thesis's thresholds decide: ``low_prior_fitness`` below
   ``min_prior_fitness``, ``low_icp_fitness`` below ``min_icp_fitness``.

A majority of pairs, not all of them, so that one wrong neighbour does not drop a
right scan; at least half of *all* its pairs to confirm, so that one lucky pair
among pairs that found nothing does not keep a wrong one. Usage::

    n_agree, n_supported, n_pairs = agreement_counts(edges, poses, len(poses), params)
    reasons, confirmed = keep_test(fitness_prior, fitness, n_agree, n_supported, n_pairs, cfg)
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from floorscan.core.geometry import wrap_angle
from floorscan.register.params import GraphParams, RegistrationConfig


def pair_residuals(edges: pd.DataFrame, poses: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """How far each pair's ICP result is from the relative pose of ``poses``.

    Parameters
    ----------
    edges : pandas.DataFrame
        :data:`floorscan.register.edges.EDGE_COLUMNS`: ``i, j`` index ``poses``;
        ``dx_m, dy_m, dyaw_rad`` is the pose of scan ``j`` in scan ``i``'s frame that ICP
        found.
    poses : (N, 4) float ndarray
        ``x, y, z, yaw`` of each scan in the map frame (metres, radians).

    Returns
    -------
    residual_m : (E,) float64 ndarray
        Distance between ICP's position of scan ``j`` in ``i``'s frame and that of
        ``poses``, metres.
    residual_rad : (E,) float64 ndarray
        Absolute yaw difference, radians.
    """
    poses = np.asarray(poses, dtype=np.float64)
    i, j = edges["i"].to_numpy(np.int64), edges["j"].to_numpy(np.int64)
    yaw = poses[i, 3]
    c, s = np.cos(yaw), np.sin(yaw)
    dx, dy = poses[j, 0] - poses[i, 0], poses[j, 1] - poses[i, 1]
    rx, ry = c * dx + s * dy, -s * dx + c * dy
    ryaw = poses[j, 3] - yaw
    res_m = np.hypot(edges["dx_m"].to_numpy(np.float64) - rx, edges["dy_m"].to_numpy(np.float64) - ry)
    res_rad = np.abs(wrap_angle(edges["dyaw_rad"].to_numpy(np.float64) - ryaw))
    return res_m, res_rad


def agreement_counts(
    edges: pd.DataFrame, poses: np.ndarray, n: int, params: GraphParams
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per scan: the pairs that agree with ``poses``, the supported pairs, all pairs.

    Parameters
    ----------
    edges : pandas.DataFrame
        The pairs aligned by ICP (:data:`floorscan.register.edges.EDGE_COLUMNS`).
    poses : (n, 4) float ndarray
        The registered poses (``x, y, z, yaw``; metres, radians).
    n : int
        Number of scans.
    params : GraphParams
        ``agreement_fitness_ratio``, ``agreement_m``, ``agreement_rad``.

    Returns
    -------
    n_agree, n_supported, n_pairs : (n,) int64 ndarray
        See the module docstring (a pair counts for both its scans).
    """
    if len(edges) == 0:
        z = np.zeros(n, dtype=np.int64)
        return z, z.copy(), z.copy()
    fitness, converged = _pair_fitness(edges)
    supported = converged & (fitness >= support_floor(edges, params))
    res_m, res_rad = pair_residuals(edges, poses)
    agree = supported & (res_m <= params.agreement_m) & (res_rad <= params.agreement_rad)
    both = np.r_[edges["i"].to_numpy(np.int64), edges["j"].to_numpy(np.int64)]

    def count(mask: np.ndarray) -> np.ndarray:
        return np.bincount(both, weights=np.r_[mask, mask].astype(np.float64), minlength=n).astype(np.int64)

    return count(agree), count(supported), np.bincount(both, minlength=n).astype(np.int64)


def _pair_fitness(edges: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """Each pair's overlap fitness after ICP (the plain fitness where the overlap one
    is NaN), and whether its ICP converged (an inlier RMSE)."""
    fitness = edges["overlap_fitness"].to_numpy(np.float64)
    fitness = np.where(np.isfinite(fitness), fitness, edges["fitness"].to_numpy(np.float64))
    return fitness, np.isfinite(edges["inlier_rmse_m"].to_numpy(np.float64))


def support_floor(edges: pd.DataFrame, params: GraphParams) -> float:
    """The fitness a pair needs after ICP to count for or against a pose:
    ``agreement_fitness_ratio`` x the median over the converged pairs of ``edges``
    (module docstring, step 1); inf when none converged."""
    fitness, converged = _pair_fitness(edges)
    if not converged.any():
        return math.inf
    return float(params.agreement_fitness_ratio * np.median(fitness[converged]))


def keep_test(
    fitness_prior: np.ndarray,
    fitness: np.ndarray,
    n_agree: np.ndarray,
    n_supported: np.ndarray,
    n_pairs: np.ndarray,
    cfg: RegistrationConfig,
) -> tuple[np.ndarray, np.ndarray]:
    """The drop reason of each scan of the pose graph (module docstring, steps 3-5).

    Parameters
    ----------
    fitness_prior, fitness : (N,) float ndarray
        Mean fitness over each scan's pairs under the initial poses and after ICP
        (:func:`floorscan.register.posegraph.scan_fitness`; NaN: no pair, never low).
    n_agree, n_supported, n_pairs : (N,) int ndarray
        :func:`agreement_counts`.
    cfg : RegistrationConfig
        ``min_prior_fitness``, ``min_icp_fitness``.

    Returns
    -------
    reasons : (N,) object ndarray
        ``""`` (kept), ``"icp_disagrees"``, ``"low_prior_fitness"`` or
        ``"low_icp_fitness"``.
    confirmed : (N,) bool ndarray
        Kept because ICP agrees with the pose (step 3), whatever the fitness.
    """
    n_agree, n_supported, n_pairs = (np.asarray(a, dtype=np.int64) for a in (n_agree, n_supported, n_pairs))
    confirmed = (n_agree >= 1) & (2 * n_agree >= n_pairs)
    contradicted = ~confirmed & (n_supported >= 1) & (2 * n_agree < n_supported)
    # a scan in no pair (NaN fitness) has nothing to be judged on: kept, as before
    low_prior = np.asarray(fitness_prior, dtype=np.float64) < cfg.min_prior_fitness
    low_icp = np.asarray(fitness, dtype=np.float64) < cfg.min_icp_fitness
    reasons = np.full(len(n_agree), "", dtype=object)
    undecided = ~confirmed & ~contradicted
    reasons[undecided & low_icp] = "low_icp_fitness"
    reasons[undecided & low_prior] = "low_prior_fitness"
    reasons[contradicted] = "icp_disagrees"
    return reasons, confirmed

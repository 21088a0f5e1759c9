"""The pose graph's optimiser: scan poses from ICP edges and the localizer's priors.

The model (Grisetti et al. 2010, "A tutorial on graph-based SLAM", section III): each
scan is a node ``(x, y, yaw)``; an edge says where scan ``j`` lies in scan ``i``'s
frame, a prior where a scan lies in the map; the optimum minimises the sum of squared
normalised residuals. :func:`optimize_pose_graph` solves it in SE(2) by Gauss-Newton on
the sparse 3N x 3N normal equations (SciPy's SuperLU), so memory and time grow with the
number of edges, not with N squared. Loop edges are robust, with the line process of
Open3D's global optimisation (Choi et al. 2015). Usage::

    poses, info = optimize_pose_graph(initial, edges, priors, params)

One solver, not Open3D's: the same poses, 15-45x slower, memory quadratic in N (benchmarks/README.md).
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from floorscan.core.geometry import wrap_angle
from floorscan.register.params import GraphParams

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
#: ... or after this many iterations per pass (a few suffice from the localizer's poses).
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

    Gauss-Newton runs on the sparse 3N x 3N normal equations (SciPy's SuperLU with a
    symmetric minimum-degree ordering): memory and time grow with the edges.

    Parameters
    ----------
    poses : (N, 4) float ndarray
        Initial poses ``x, y, z, yaw`` (metres, radians); z is passed through.
    edges : pandas.DataFrame
        :func:`floorscan.register.edges.scan_pair_edges` output; pairs below
        ``min_edge_fitness`` are ignored.
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
        When the shapes disagree or an edge names a scan out of range.
    """
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
    if n_free == 0 or (e == 0 and prior is None):
        return x, np.ones(e)  # one scan, held; or nothing that moves a scan
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

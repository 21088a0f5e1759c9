"""A simulated recording: the scan, AMCL and odometry streams of one drive.

The thesis's rover (section 3.5) drove at about 0.3 m/s, scanned at about 10 Hz and
logged AMCL poses at about 10 Hz, not synchronized with the scans. For a drive of the
rover through a building (:mod:`floorscan.sim.trajectory`), :func:`simulate_recording`
plans:

- scans at ``scan_rate_hz``, cast on demand with :mod:`floorscan.sim.raycast`
  (:meth:`Recording.iter_scans`);
- an AMCL-like pose stream: the true ``base_link`` pose plus a first-order
  Gauss-Markov error (:func:`gauss_markov`) at ``pose_rate_hz`` with a phase offset and
  timing jitter;
- wheel odometry with scale error, noise and yaw drift.

All of it is deterministic for a seed. :mod:`floorscan.sim.writer` writes the recording.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Iterator

import numpy as np
from scipy.signal import lfilter

from floorscan.core.io import InputError
from floorscan.sim.building import Building
from floorscan.sim.mesh import building_mesh
from floorscan.sim.obstacles import check_trajectory
from floorscan.sim.params import SimParams
from floorscan.sim.raycast import RayCaster, iter_scan_batches, measure_ranges
from floorscan.sim.scanners import Scanner
from floorscan.sim.trajectory import rover_trajectory

#: Phase of the odometry stream after the first scan, seconds.
_ODOM_PHASE_S = 0.013


@dataclass
class Recording:
    """A simulated recording: the streams, and the scans cast on demand.

    Attributes
    ----------
    scan_t_ns : (S,) int64 ndarray
        Scan header stamps, ns since the epoch.
    scan_poses : (S, 4) float64 ndarray
        True scanner pose ``x, y, z, yaw`` (map frame; z = sensor height; yaw wrapped
        to (-pi, pi]).
    pose_t_ns : (P,) int64 ndarray
        AMCL pose stamps.
    amcl : (P, 3) float64 ndarray
        AMCL ``base_link`` pose ``x, y, yaw`` (true pose + error).
    amcl_error : (P, 3) float64 ndarray
        The error that was added.
    odom_t_ns : (O,) int64 ndarray
    odom : (O, 5) float64 ndarray
        ``x, y, yaw`` in the odom frame and ``v`` (m/s), ``w`` (rad/s) in base_link.
    """

    building: Building
    scanner: Scanner
    params: SimParams
    seed: int
    mesh: Any
    scan_t_ns: np.ndarray
    scan_poses: np.ndarray
    pose_t_ns: np.ndarray
    amcl: np.ndarray
    amcl_error: np.ndarray
    odom_t_ns: np.ndarray
    odom: np.ndarray

    def iter_scans(self, max_rays: int = 2_000_000) -> Iterator[tuple[int, np.ndarray]]:
        """Cast the scans, in time order.

        Rays of many scans go to Embree in one call (at most ``max_rays``); the noise
        stream is drawn in scan order, so the result does not depend on ``max_rays``.

        Parameters
        ----------
        max_rays : int
            Rays per call to the ray caster.

        Yields
        ------
        k : int
            The scan's index.
        ranges : (R,) float32 ndarray
            Its ranges, metres.
        """
        caster = RayCaster.from_mesh(self.mesh)
        rng = np.random.default_rng(np.random.SeedSequence([self.seed, 1]))
        n_rays = len(self.scanner.directions())
        for sl in iter_scan_batches(len(self.scan_t_ns), n_rays, max_rays):
            ranges = measure_ranges(caster, self.scanner, self.scan_poses[sl], rng)
            for j, r in enumerate(ranges):
                yield sl.start + j, r


def _wrap(a: np.ndarray) -> np.ndarray:
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def simulate_recording(
    building: Building, scanner: Scanner, params: SimParams, seed: int
) -> Recording:
    """Plan the rover's drive and every stream of a recording (scans are cast lazily).

    Parameters
    ----------
    building : Building
        With its waypoints.
    scanner : Scanner2D or Scanner3D
    params : SimParams
    seed : int
        Seeds the range noise, the pose error, the odometry errors and the pose
        timing jitter (independent streams of one ``SeedSequence``).

    Returns
    -------
    Recording

    Raises
    ------
    InputError
        When the rover's path (not only its waypoints) enters a wall or furniture, or
        the sensor height is not below the ceiling.
    """
    p = params
    if not 0 < p.sensor_height_m < building.height_m:
        raise InputError(
            f"config simulate.sensor_height_m: {p.sensor_height_m} m is not between the floor "
            f"and the ceiling ({building.height_m} m) of {building.source}"
        )
    traj = rover_trajectory(building.waypoints, p.speed_mps, p.max_yaw_rate_rad_s)
    check_trajectory(building, traj)
    ss = np.random.SeedSequence([int(seed), 0])
    rng_pose, rng_odom, rng_jit = (np.random.default_rng(s) for s in ss.spawn(3))

    period_ns = int(round(1e9 / p.scan_rate_hz))
    n_scans = int(math.floor(traj.duration_s * 1e9 / period_ns)) + 1
    scan_rel_ns = np.arange(n_scans, dtype=np.int64) * period_ns
    xyyaw = traj.at(scan_rel_ns / 1e9)
    scan_poses = np.column_stack(
        [xyyaw[:, 0], xyyaw[:, 1], np.full(n_scans, p.sensor_height_m), _wrap(xyyaw[:, 2])]
    )

    # AMCL: unsynchronized (phase offset + jitter), brackets every scan.
    t_end = scan_rel_ns[-1] / 1e9
    pdt = 1.0 / p.pose_rate_hz
    j = np.arange(-1, int(math.ceil((t_end - p.pose_phase_s) / pdt)) + 2)
    jitter = np.clip(rng_jit.standard_normal(len(j)) * p.pose_jitter_std_s, -0.4 * pdt, 0.4 * pdt)
    pose_rel_s = p.pose_phase_s + j * pdt + jitter
    pose_rel_ns = np.round(pose_rel_s * 1e9).astype(np.int64)
    truth = traj.at(pose_rel_ns / 1e9)
    err = np.column_stack(
        [
            gauss_markov(len(j), pdt, p.pose_position_std_m, p.pose_correlation_time_s, rng_pose),
            gauss_markov(len(j), pdt, p.pose_position_std_m, p.pose_correlation_time_s, rng_pose),
            gauss_markov(len(j), pdt, p.pose_yaw_std_rad, p.pose_correlation_time_s, rng_pose),
        ]
    )
    amcl = truth + err
    amcl[:, 2] = _wrap(amcl[:, 2])

    # Odometry: integrate noisy body-frame increments from (0, 0, 0).
    odt = 1.0 / p.odom_rate_hz
    jo = np.arange(-1, int(math.ceil((t_end - _ODOM_PHASE_S) / odt)) + 2)
    odom_rel_ns = np.round((_ODOM_PHASE_S + jo * odt) * 1e9).astype(np.int64)
    odom = _odometry(traj.at(odom_rel_ns / 1e9), odt, p, rng_odom)

    return Recording(
        building=building,
        scanner=scanner,
        params=p,
        seed=int(seed),
        mesh=building_mesh(building),
        scan_t_ns=p.start_time_ns + scan_rel_ns,
        scan_poses=scan_poses,
        pose_t_ns=p.start_time_ns + pose_rel_ns,
        amcl=amcl,
        amcl_error=err,
        odom_t_ns=p.start_time_ns + odom_rel_ns,
        odom=odom,
    )


def _odometry(truth: np.ndarray, dt: float, p: SimParams, rng: np.random.Generator) -> np.ndarray:
    n = len(truth)
    dp = np.diff(truth[:, :2], axis=0)
    c, s = np.cos(truth[:-1, 2]), np.sin(truth[:-1, 2])
    fwd = c * dp[:, 0] + s * dp[:, 1]
    lat = -s * dp[:, 0] + c * dp[:, 1]
    dyaw = np.diff(truth[:, 2])
    noise = rng.standard_normal((n - 1, 3))
    fwd_m = fwd * (1 + p.odom_scale_error) + noise[:, 0] * p.odom_noise_frac * np.abs(fwd)
    lat_m = lat + noise[:, 1] * p.odom_noise_frac * np.abs(fwd)
    dyaw_m = dyaw + noise[:, 2] * p.odom_noise_frac * np.abs(dyaw) + p.odom_yaw_drift_rad_s * dt
    yaw = np.r_[0.0, np.cumsum(dyaw_m)]
    co, so = np.cos(yaw[:-1]), np.sin(yaw[:-1])
    x = np.r_[0.0, np.cumsum(co * fwd_m - so * lat_m)]
    y = np.r_[0.0, np.cumsum(so * fwd_m + co * lat_m)]
    v = np.r_[0.0, fwd_m / dt]
    w = np.r_[0.0, dyaw_m / dt]
    return np.column_stack([x, y, _wrap(yaw), v, w])


def gauss_markov(n: int, dt: float, std: float, tau: float, rng: np.random.Generator) -> np.ndarray:
    """A stationary first-order Gauss-Markov (discrete Ornstein-Uhlenbeck) sequence.

    ``e[0] ~ N(0, std^2)``, ``e[k] = phi e[k-1] + std sqrt(1 - phi^2) w[k]`` with
    ``phi = exp(-dt / tau)``: every sample has std ``std`` and neighbours are correlated
    with time constant ``tau`` (white noise when ``tau`` is 0).

    Parameters
    ----------
    n : int
        Number of samples.
    dt : float
        Sample spacing, s.
    std : float
        Stationary standard deviation (any unit).
    tau : float
        Correlation time, s.
    rng : numpy.random.Generator
        Draws exactly ``n`` standard normals.

    Returns
    -------
    (n,) float64 ndarray
    """
    w = rng.standard_normal(n)
    phi = math.exp(-dt / tau) if tau > 0 else 0.0
    u = w * std * math.sqrt(1 - phi * phi)
    if n:
        u[0] = w[0] * std
    return lfilter([1.0], [1.0, -phi], u)

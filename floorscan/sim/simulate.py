"""Synthetic recordings: a rover drives a building and records LIDAR scans and poses.

The thesis validates its method on a simulated building whose walls are known exactly
(sections 4.1 and 5.2); its real rover (section 3.5) drove at about 0.3 m/s, scanned at
about 10 Hz and logged AMCL poses at about 10 Hz, not synchronized with the scans. This
module reproduces both kinds of data for a building of :mod:`floorscan.sim.building`:

- the rover path (:func:`rover_trajectory`): a unicycle that drives from waypoint to
  waypoint at ``speed_mps``, turning smoothly toward its direction of travel (yaw rate
  limited, slowing down while it turns);
- scans at ``scan_rate_hz`` cast with :mod:`floorscan.sim.lidar`;
- an AMCL-like pose stream: the true ``base_link`` pose plus a first-order
  Gauss-Markov error (:func:`gauss_markov`) at ``pose_rate_hz`` with a phase offset and
  timing jitter;
- wheel odometry with scale error, noise and yaw drift.

Written outputs (:func:`run_simulation`), all deterministic for a seed:

- ``recording.bag`` (ROS1): ``/scan`` (``sensor_msgs/LaserScan`` for 2D scanners,
  ``sensor_msgs/PointCloud2`` with float32 x, y, z for 3D; frame ``laser``),
  ``/amcl_pose`` (``geometry_msgs/PoseWithCovarianceStamped`` of ``base_link`` in
  ``map``), ``/odom`` (``nav_msgs/Odometry``, ``odom`` -> ``base_link``), ``/tf_static``
  (``base_link`` -> ``laser``: the scanner ``sensor_height_m`` above ``base_link``, which
  is on the floor). Message times equal header stamps.
- ``pcd/``: the thesis's layout (4.1): ``scan_00000.pcd``... one binary PCD per scan in
  the MAP frame (true pose), equal point for point to the bag's scan transformed by the
  true pose (to float32 precision), and ``locations.csv`` with ``file,t_ns,x,y,z,yaw``
  (the true scanner pose; ``file`` relative to the folder).
- ``true_poses.parquet``: ``t_ns`` (the scan's header stamp), ``x, y, z, yaw`` float64,
  the true scanner pose of every scan.
- ``building.stl`` and ``walls.geojson`` (ground truth sliced at ``sensor_height_m``).
"""

from __future__ import annotations

import logging
import math
import os
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np
import pandas as pd
import pyarrow as pa
import shapely
from scipy.signal import lfilter

from floorscan.sim import building as bld
from floorscan.sim import lidar
from floorscan.core.io import InputError, atomic_path, staged_path, write_json, write_table

log = logging.getLogger(__name__)

#: Schema of ``true_poses.parquet``.
TRUE_POSES = pa.schema(
    [
        ("t_ns", pa.int64()),
        ("x", pa.float64()),
        ("y", pa.float64()),
        ("z", pa.float64()),
        ("yaw", pa.float64()),
    ]
)
#: Phase of the odometry stream after the first scan, seconds.
_ODOM_PHASE_S = 0.013


@dataclass(frozen=True)
class SimParams:
    """Rover, timing and error parameters (the ``simulate`` section, minus ``scanners``).

    Defaults equal those of ``workflow/schemas/simulate.schema.yaml`` (a test checks).
    Units are in the names: metres, seconds, radians, hertz, nanoseconds.
    """

    speed_mps: float = 0.3
    max_yaw_rate_rad_s: float = 1.0
    scan_rate_hz: float = 10.0
    pose_rate_hz: float = 10.0
    pose_phase_s: float = 0.037
    pose_jitter_std_s: float = 0.002
    odom_rate_hz: float = 20.0
    sensor_height_m: float = 0.3
    pose_position_std_m: float = 0.05
    pose_yaw_std_rad: float = 0.02
    pose_correlation_time_s: float = 2.0
    odom_scale_error: float = 0.02
    odom_noise_frac: float = 0.01
    odom_yaw_drift_rad_s: float = 0.0002
    start_time_ns: int = 1_600_000_000_000_000_000

    @classmethod
    def from_config(cls, cfg: Mapping[str, Any], where: str = "config simulate") -> "SimParams":
        """Take the known keys of ``cfg`` (``scanners`` is ignored) and check them.

        Raises
        ------
        InputError
            Unknown key, a non-positive rate, speed or height, a negative std, naming
            ``where.<key>``.
        """
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(cfg) - names - {"scanners"})
        if unknown:
            raise InputError(f"{where}: unknown keys {unknown}; allowed {sorted(names | {'scanners'})}")
        p = cls(**{k: v for k, v in cfg.items() if k in names})
        positive = ["speed_mps", "max_yaw_rate_rad_s", "scan_rate_hz", "pose_rate_hz",
                    "odom_rate_hz", "sensor_height_m"]
        non_negative = ["pose_phase_s", "pose_jitter_std_s", "pose_position_std_m",
                        "pose_yaw_std_rad", "pose_correlation_time_s", "odom_noise_frac",
                        "start_time_ns"]
        for k in positive:
            if not getattr(p, k) > 0:
                raise InputError(f"{where}.{k}: must be > 0, got {getattr(p, k)!r}")
        for k in non_negative:
            if not getattr(p, k) >= 0:
                raise InputError(
                    f"{where}.{k}: must be >= 0 (a noise level or time), got {getattr(p, k)!r}"
                )
        return p


# --------------------------------------------------------------------------- the rover


@dataclass(frozen=True)
class Trajectory:
    """The rover's true ``base_link`` pose sampled finely in time.

    Attributes
    ----------
    t : (M,) float64 ndarray
        Seconds since the start, increasing.
    xy : (M, 2) float64 ndarray
        Position in the map frame, metres.
    yaw : (M,) float64 ndarray
        Heading, radians, unwrapped (continuous).
    """

    t: np.ndarray
    xy: np.ndarray
    yaw: np.ndarray

    @property
    def duration_s(self) -> float:
        return float(self.t[-1])

    def at(self, t: np.ndarray) -> np.ndarray:
        """(len(t), 3) ``x, y, yaw`` at times ``t`` (s), linear interpolation; the rover
        stands still before the start and after the end. ``yaw`` stays unwrapped."""
        t = np.asarray(t, dtype=np.float64)
        return np.stack(
            [np.interp(t, self.t, self.xy[:, 0]), np.interp(t, self.t, self.xy[:, 1]),
             np.interp(t, self.t, self.yaw)], axis=1,
        )


def rover_trajectory(
    waypoints: np.ndarray,
    speed_mps: float,
    max_yaw_rate_rad_s: float,
    dt: float = 0.01,
    heading_gain: float = 2.0,
    arrive_tol_m: float = 0.02,
) -> Trajectory:
    """Drive a unicycle rover through ``waypoints``.

    At each step the rover steers toward the next waypoint with yaw rate
    ``clip(heading_gain * error, +-max_yaw_rate)`` and speed
    ``speed_mps * max(cos(error), 0) ** 4`` (it slows, and turns in place for large
    heading errors), so its yaw turns smoothly toward the direction of travel. It starts
    at the first waypoint facing the second and stops at the last.

    Parameters
    ----------
    waypoints : (K, 2) float64 ndarray
        Map frame, metres; K >= 2.
    speed_mps : float
        Cruise speed, m/s (thesis 3.5: about 0.3).
    max_yaw_rate_rad_s : float
        Yaw rate limit, rad/s.
    dt : float
        Integration step, s.
    heading_gain : float
        Proportional steering gain, 1/s.
    arrive_tol_m : float
        Distance at which a waypoint counts as reached, metres.

    Returns
    -------
    Trajectory

    Raises
    ------
    ValueError
        When the rover fails to reach the waypoints in a generous time budget.
    """
    wps = np.asarray(waypoints, dtype=np.float64)
    keep = np.r_[True, np.hypot(*np.diff(wps, axis=0).T) > arrive_tol_m]
    wps = wps[keep]
    if len(wps) < 2:
        return Trajectory(np.array([0.0]), wps[:1].copy(), np.array([0.0]))
    pos = wps[0].copy()
    yaw = math.atan2(wps[1, 1] - wps[0, 1], wps[1, 0] - wps[0, 0])
    path_len = float(np.hypot(*np.diff(wps, axis=0).T).sum())
    budget = int((3 * path_len / speed_mps + len(wps) * 2 * math.pi / max_yaw_rate_rad_s + 10) / dt)
    ts, xs, ys, yaws = [0.0], [pos[0]], [pos[1]], [yaw]
    k, step = 1, 0
    while k < len(wps):
        d = wps[k] - pos
        if math.hypot(d[0], d[1]) < arrive_tol_m:
            k += 1
            continue
        err = math.atan2(d[1], d[0]) - yaw
        err = (err + math.pi) % (2 * math.pi) - math.pi
        w = max(-max_yaw_rate_rad_s, min(max_yaw_rate_rad_s, heading_gain * err))
        v = speed_mps * max(math.cos(err), 0.0) ** 4
        v = min(v, math.hypot(d[0], d[1]) / dt)  # do not overshoot the waypoint
        yaw_mid = yaw + 0.5 * w * dt
        pos = pos + v * dt * np.array([math.cos(yaw_mid), math.sin(yaw_mid)])
        yaw += w * dt
        step += 1
        ts.append(step * dt)
        xs.append(pos[0])
        ys.append(pos[1])
        yaws.append(yaw)
        if step > budget:
            raise ValueError(f"rover did not reach waypoint {k} {wps[k].tolist()} in {budget * dt:.0f} s")
    return Trajectory(np.asarray(ts), np.stack([xs, ys], axis=1), np.asarray(yaws))


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


# --------------------------------------------------------------------------- a recording


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

    building: bld.Building
    scanner: lidar.Scanner
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
        """Yield ``(scan index, ranges (R,) float32)`` in time order.

        Rays of many scans go to Embree in one call (at most ``max_rays``); the noise
        stream is drawn in scan order, so the result does not depend on ``max_rays``.
        """
        caster = lidar.RayCaster.from_mesh(self.mesh)
        rng = np.random.default_rng(np.random.SeedSequence([self.seed, 1]))
        n_rays = len(self.scanner.directions())
        for sl in lidar.iter_scan_batches(len(self.scan_t_ns), n_rays, max_rays):
            ranges = lidar.measure_ranges(caster, self.scanner, self.scan_poses[sl], rng)
            for j, r in enumerate(ranges):
                yield sl.start + j, r


def _wrap(a: np.ndarray) -> np.ndarray:
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


def simulate_recording(
    building: bld.Building, scanner: lidar.Scanner, params: SimParams, seed: int
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
    _check_trajectory(building, traj)
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
        mesh=bld.building_mesh(building),
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


def _check_trajectory(building: bld.Building, traj: Trajectory) -> None:
    blocked = bld.obstacles_at_floor(building)
    hit = shapely.intersects_xy(blocked, traj.xy[:, 0], traj.xy[:, 1])
    if hit.any():
        i = int(np.argmax(hit))
        x, y = traj.xy[i]
        # which waypoint leg was the rover on?
        d = np.hypot(*(building.waypoints - traj.xy[i]).T)
        raise InputError(
            f"{building.source}: the rover's path enters a wall or furniture at "
            f"({x:.2f}, {y:.2f}) m, t = {traj.t[i]:.1f} s, near waypoints[{int(np.argmin(d))}]; "
            "move the waypoints away from walls and door jambs"
        )


# --------------------------------------------------------------------------- writers


def _typestore():
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    if "tf2_msgs/msg/TFMessage" not in ts.types:
        ts.register(
            get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage")
        )
    return ts


class _Msgs:
    """Builds and serializes the ROS1 messages of a recording."""

    def __init__(self, rec: Recording) -> None:
        self.ts = _typestore()
        self.T = self.ts.types
        self.rec = rec
        self.seq: dict[str, int] = {}

    def header(self, topic: str, t_ns: int, frame: str):
        seq = self.seq.get(topic, 0)
        self.seq[topic] = seq + 1
        sec, nsec = divmod(int(t_ns), 1_000_000_000)
        stamp = self.T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
        return self.T["std_msgs/msg/Header"](seq=seq, stamp=stamp, frame_id=frame)

    def quat(self, yaw: float):
        q = self.T["geometry_msgs/msg/Quaternion"]
        return q(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))

    def pose(self, x: float, y: float, z: float, yaw: float, cov: np.ndarray):
        T = self.T
        return T["geometry_msgs/msg/PoseWithCovariance"](
            pose=T["geometry_msgs/msg/Pose"](
                position=T["geometry_msgs/msg/Point"](x=x, y=y, z=z), orientation=self.quat(yaw)
            ),
            covariance=cov,
        )

    def ser(self, msg, msgtype: str) -> bytes:
        return self.ts.serialize_ros1(msg, msgtype)

    def tf_static(self, t_ns: int) -> bytes:
        T = self.T
        tr = T["geometry_msgs/msg/TransformStamped"](
            header=self.header("/tf_static", t_ns, "base_link"),
            child_frame_id="laser",
            transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](
                    x=0.0, y=0.0, z=float(self.rec.params.sensor_height_m)
                ),
                rotation=self.quat(0.0),
            ),
        )
        return self.ser(T["tf2_msgs/msg/TFMessage"](transforms=[tr]), "tf2_msgs/msg/TFMessage")

    def amcl(self, i: int) -> bytes:
        r, p = self.rec, self.rec.params
        cov = np.zeros(36)
        cov[0] = cov[7] = p.pose_position_std_m**2
        cov[35] = p.pose_yaw_std_rad**2
        x, y, yaw = r.amcl[i]
        msg = self.T["geometry_msgs/msg/PoseWithCovarianceStamped"](
            header=self.header("/amcl_pose", int(r.pose_t_ns[i]), "map"),
            pose=self.pose(float(x), float(y), 0.0, float(yaw), cov),
        )
        return self.ser(msg, "geometry_msgs/msg/PoseWithCovarianceStamped")

    def odom(self, i: int) -> bytes:
        T, r = self.T, self.rec
        x, y, yaw, v, w = (float(a) for a in r.odom[i])
        cov = np.zeros(36)
        cov[0] = cov[7] = cov[35] = 1e-3
        twist = T["geometry_msgs/msg/TwistWithCovariance"](
            twist=T["geometry_msgs/msg/Twist"](
                linear=T["geometry_msgs/msg/Vector3"](x=v, y=0.0, z=0.0),
                angular=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=w),
            ),
            covariance=cov.copy(),
        )
        msg = T["nav_msgs/msg/Odometry"](
            header=self.header("/odom", int(r.odom_t_ns[i]), "odom"),
            child_frame_id="base_link",
            pose=self.pose(x, y, 0.0, yaw, cov),
            twist=twist,
        )
        return self.ser(msg, "nav_msgs/msg/Odometry")

    def scan(self, k: int, ranges: np.ndarray, points: np.ndarray) -> bytes:
        T, r, sc = self.T, self.rec, self.rec.scanner
        header = self.header("/scan", int(r.scan_t_ns[k]), "laser")
        if isinstance(sc, lidar.Scanner2D):
            msg = T["sensor_msgs/msg/LaserScan"](
                header=header,
                angle_min=sc.angle_min,
                angle_max=sc.angle_max,
                angle_increment=sc.angle_increment,
                time_increment=0.0,
                scan_time=1.0 / r.params.scan_rate_hz,
                range_min=sc.range_min_m,
                range_max=sc.range_max_m,
                ranges=np.ascontiguousarray(ranges, dtype=np.float32),
                intensities=np.zeros(0, dtype=np.float32),
            )
            return self.ser(msg, "sensor_msgs/msg/LaserScan")
        pf = T["sensor_msgs/msg/PointField"]
        fields_ = [pf(name=n, offset=4 * i, datatype=7, count=1) for i, n in enumerate("xyz")]
        msg = T["sensor_msgs/msg/PointCloud2"](
            header=header,
            height=1,
            width=len(points),
            fields=fields_,
            is_bigendian=False,
            point_step=12,
            row_step=12 * len(points),
            data=np.frombuffer(np.ascontiguousarray(points, dtype="<f4").tobytes(), dtype=np.uint8),
            is_dense=True,
        )
        return self.ser(msg, "sensor_msgs/msg/PointCloud2")


def pcd_bytes(points: np.ndarray, viewpoint: np.ndarray | None = None) -> bytes:
    """A binary PCD (v0.7) file with float32 ``x y z`` fields.

    Parameters
    ----------
    points : (N, 3) float ndarray
        Metres; written as little-endian float32.
    viewpoint : (4,) float64 ndarray, optional
        ``x, y, z, yaw`` of the scanner, stored in the VIEWPOINT header line.

    Returns
    -------
    bytes
    """
    pts = np.ascontiguousarray(points, dtype="<f4")
    vp = "0 0 0 1 0 0 0"
    if viewpoint is not None:
        x, y, z, yaw = (float(v) for v in viewpoint)
        vp = f"{x!r} {y!r} {z!r} {math.cos(yaw / 2)!r} 0 0 {math.sin(yaw / 2)!r}"
    n = len(pts)
    header = (
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\n"
        f"TYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT {vp}\nPOINTS {n}\nDATA binary\n"
    )
    return header.encode("ascii") + pts.tobytes()


def scan_file_name(k: int) -> str:
    """File name of scan ``k`` in the pcd folder (zero-padded: sorts in time order)."""
    return f"scan_{k:05d}.pcd"


def write_recording(rec: Recording, bag_path: str | os.PathLike, pcd_dir: str | os.PathLike) -> dict:
    """Cast every scan once and write the ROS1 bag and the PCD folder atomically.

    Parameters
    ----------
    rec : Recording
    bag_path : path
        The ``.bag`` to write (replaced if present).
    pcd_dir : path
        The folder of ``.pcd`` files and ``locations.csv`` (replaced if present).

    Returns
    -------
    dict
        Counts: ``n_scans``, ``n_points``, ``n_no_return`` (beams without a return),
        ``n_pose``, ``n_odom``; and ``observed_xy``, ``(C, 2)`` float64, the centres of
        the 1 cm plan cells holding a return (3D: a return in ``OBSERVED_BAND_3D_M``),
        metres, for :func:`floorscan.sim.building.observed_faces`.
    """
    from rosbags.rosbag1 import Writer

    bag_path, pcd_dir = Path(bag_path), Path(pcd_dir)
    msgs = _Msgs(rec)
    is_2d = isinstance(rec.scanner, lidar.Scanner2D)
    scan_type = "sensor_msgs/msg/LaserScan" if is_2d else "sensor_msgs/msg/PointCloud2"
    others = sorted(
        [(int(t), 1, i) for i, t in enumerate(rec.pose_t_ns)]
        + [(int(t), 2, i) for i, t in enumerate(rec.odom_t_ns)]
    )
    n_points = n_missing = 0
    cells: list[np.ndarray] = []  # 1 cm plan cells of the returns (observed faces)
    with atomic_path(bag_path) as tmp_bag, staged_path(pcd_dir) as tmp_dir:
        tmp_bag.unlink()  # rosbags refuses to overwrite
        tmp_dir.mkdir()
        with Writer(tmp_bag) as w:
            ts = msgs.ts
            c_tf = w.add_connection("/tf_static", "tf2_msgs/msg/TFMessage", typestore=ts, latching=1)
            c_scan = w.add_connection("/scan", scan_type, typestore=ts)
            c_pose = w.add_connection(
                "/amcl_pose", "geometry_msgs/msg/PoseWithCovarianceStamped", typestore=ts
            )
            c_odom = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
            t0 = min(int(rec.scan_t_ns[0]), others[0][0])
            w.write(c_tf, t0, msgs.tf_static(t0))
            o = 0

            def flush(until_ns: int) -> None:
                nonlocal o
                while o < len(others) and others[o][0] <= until_ns:
                    t, kind, i = others[o]
                    if kind == 1:
                        w.write(c_pose, t, msgs.amcl(i))
                    else:
                        w.write(c_odom, t, msgs.odom(i))
                    o += 1

            dirs = rec.scanner.directions()
            for k, ranges in rec.iter_scans():
                t = int(rec.scan_t_ns[k])
                flush(t - 1)
                pts, valid = lidar.scanner_points(rec.scanner, ranges, dirs)
                n_points += len(pts)
                n_missing += int((~valid).sum())
                w.write(c_scan, t, msgs.scan(k, ranges, pts))
                map_pts = lidar.to_map(pts, rec.scan_poses[k]).astype(np.float32)
                cells.append(_plan_cells(map_pts, is_2d))
                if len(cells) >= 256:
                    cells = [np.unique(np.concatenate(cells))]
                (tmp_dir / scan_file_name(k)).write_bytes(pcd_bytes(map_pts, rec.scan_poses[k]))
            flush(np.iinfo(np.int64).max)
        locations = pd.DataFrame(
            {
                "file": [scan_file_name(k) for k in range(len(rec.scan_t_ns))],
                "t_ns": rec.scan_t_ns.astype(np.int64),
                "x": rec.scan_poses[:, 0],
                "y": rec.scan_poses[:, 1],
                "z": rec.scan_poses[:, 2],
                "yaw": rec.scan_poses[:, 3],
            }
        )
        locations.to_csv(tmp_dir / "locations.csv", index=False, lineterminator="\n")
    keys = np.unique(np.concatenate(cells)) if cells else np.zeros(0, np.int64)
    ij = np.column_stack([keys >> 32, keys & 0xFFFFFFFF]) - 2**30
    return {
        "observed_xy": (ij + 0.5) * OBSERVED_CELL_M,
        "n_scans": len(rec.scan_t_ns),
        "n_points": n_points,
        "n_no_return": n_missing,
        "n_pose": len(rec.pose_t_ns),
        "n_odom": len(rec.odom_t_ns),
    }


#: Plan cell of the returns kept for the observed faces, metres.
OBSERVED_CELL_M = 0.01
#: 3D scanners: the returns that observe a wall face lie in this height band above the
#: floor (the walls stage's default band), metres; a 2D scanner's returns all count.
OBSERVED_BAND_3D_M = (0.5, 2.0)


def _plan_cells(map_pts: np.ndarray, is_2d: bool) -> np.ndarray:
    """Unique int64 keys of the 1 cm plan cells of one scan's map-frame returns."""
    p = map_pts
    if not is_2d:
        p = p[(p[:, 2] >= OBSERVED_BAND_3D_M[0]) & (p[:, 2] <= OBSERVED_BAND_3D_M[1])]
    ij = np.floor(p[:, :2].astype(np.float64) / OBSERVED_CELL_M).astype(np.int64) + 2**30
    return np.unique((ij[:, 0] << 32) | ij[:, 1])


def write_stl(mesh, path: str | os.PathLike) -> None:
    """Binary STL of ``mesh``, written atomically (no time stamp in the header)."""
    import trimesh

    data = trimesh.exchange.stl.export_stl(mesh)
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)


def true_poses_frame(rec: Recording) -> pd.DataFrame:
    """The ``true_poses`` table: ``t_ns`` and the true scanner pose of every scan."""
    return pd.DataFrame(
        {
            "t_ns": rec.scan_t_ns.astype(np.int64),
            "x": rec.scan_poses[:, 0],
            "y": rec.scan_poses[:, 1],
            "z": rec.scan_poses[:, 2],
            "yaw": rec.scan_poses[:, 3],
        }
    )


def run_simulation(
    building_path: str | os.PathLike,
    dataset: Mapping[str, Any],
    cfg: Mapping[str, Any],
    outputs: Mapping[str, str | os.PathLike],
) -> dict:
    """Simulate one synthetic dataset and write all its files (the ``simulate`` stage).

    Parameters
    ----------
    building_path : path
        The building YAML.
    dataset : mapping
        The dataset entry: ``scanner`` (a name under ``cfg["scanners"]``), ``seed``,
        optionally ``name``.
    cfg : mapping
        The ``simulate`` config section (``scanners`` and :class:`SimParams` keys).
    outputs : mapping
        Paths for ``bag``, ``pcd`` (folder), ``true_poses``, ``stl``, ``walls``.

    Returns
    -------
    dict
        Counts and the settings used (see :func:`write_recording`).

    Raises
    ------
    InputError
        Bad building, unknown or invalid scanner, invalid parameters.
    """
    name = dataset.get("name", "?")
    scanners = cfg.get("scanners") or {}
    sname = dataset.get("scanner")
    if sname not in scanners:
        raise InputError(
            f"config datasets.{name}.scanner: {sname!r} is not a scanner in "
            f"simulate.scanners {sorted(scanners)}"
        )
    scanner = lidar.scanner_from_config(sname, scanners[sname])
    params = SimParams.from_config(cfg)
    seed = dataset.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise InputError(f"config datasets.{name}.seed: expected an integer >= 0, got {seed!r}")
    building = bld.load_building(building_path)
    rec = simulate_recording(building, scanner, params, seed)
    log.info(
        "%s: building %s, scanner %s (%d rays), %d scans over %.1f s",
        name, building.name, sname, len(scanner.directions()), len(rec.scan_t_ns),
        (rec.scan_t_ns[-1] - rec.scan_t_ns[0]) / 1e9,
    )
    write_stl(rec.mesh, outputs["stl"])
    write_table(true_poses_frame(rec), outputs["true_poses"], schema=TRUE_POSES,
                metadata={"dataset": str(name), "frame": "map", "units": "m, rad, ns"})
    counts = write_recording(rec, outputs["bag"], outputs["pcd"])
    observed = counts.pop("observed_xy")
    write_json(bld.ground_truth_walls(building, params.sensor_height_m, observed), outputs["walls"])
    log.info("%s: wrote %s", name, counts)
    return counts

"""The rover's path: a unicycle driving from waypoint to waypoint (thesis section 3.5).

The thesis's rover drove at about 0.3 m/s. :func:`rover_trajectory` drives a unicycle
through the building's waypoints at ``speed_mps``, turning smoothly toward its direction
of travel (yaw rate limited, slowing down while it turns); the :class:`Trajectory` it
returns is sampled every ``dt`` and interpolated at any time (:meth:`Trajectory.at`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


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
        """Pose at times ``t``, linear interpolation; the rover stands still before the
        start and after the end.

        Parameters
        ----------
        t : (N,) float ndarray
            Seconds.

        Returns
        -------
        (N, 3) float64 ndarray
            ``x, y`` metres, ``yaw`` radians (unwrapped).
        """
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

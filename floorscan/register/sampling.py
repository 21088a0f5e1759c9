"""Which scans to register: a motion filter on the poses (thesis Algorithm 3 step 2).

The thesis keeps every n-th scan of a 10 Hz recording at 0.3 m/s. A fixed n fits one
recording rate and speed only: a log already thinned to a scan per metre loses 4 of 5
scans, a slow rover keeps near-copies. The field's scan matchers keep a scan when the
sensor has moved or turned enough since the last kept one (Cartographer's motion filter,
``max_distance_meters`` / ``max_angle_radians``; slam_toolbox's
``minimum_travel_distance`` / ``minimum_travel_heading``). Here:

- a scan is sampled when it is the first usable one, or its pose is at least
  ``keep_distance_m`` from the last sampled pose, or has turned by ``keep_angle_rad``;
- by default both are chosen from the recording: a point at the scanner's typical range
  ``r`` (the median horizontal range of the returns) moves by ``r * a`` when the scanner
  turns by ``a`` radians, so the two thresholds bound the same displacement of a typical
  point, a fraction ``f`` (``keep_range_fraction``, 0.1) of that range:
  ``keep_distance_m = f * r`` (within 0.05 .. 1 m) and ``keep_angle_rad = f``;
- ``every_n`` keeps the thesis's rule when a user asks for it.

Usage::

    thresholds = choose_thresholds(typical_range_m(clouds), cfg_distance, cfg_angle, 0.1)
    sampler = MotionFilter(thresholds.distance_m, thresholds.angle_rad)
    sampled = [i for i in usable if sampler.step(x[i], y[i], yaw[i])]
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

import numpy as np

#: Bounds of the chosen keep distance, metres.
MIN_KEEP_DISTANCE_M = 0.05
MAX_KEEP_DISTANCE_M = 1.0


@dataclass(frozen=True)
class MotionThresholds:
    """Thresholds of the motion filter and why they are what they are.

    Attributes
    ----------
    distance_m : float
        Keep a scan after this much travel since the last kept one, metres.
    angle_rad : float
        ... or after this much turn, radians.
    reason : str
        One sentence for the log.
    """

    distance_m: float
    angle_rad: float
    reason: str


def typical_range_m(clouds: Iterable[np.ndarray]) -> float:
    """The scanner's typical range: the median horizontal distance of the returns.

    Parameters
    ----------
    clouds : iterable of (N, >=2) float ndarray
        Points in the scanner frame, metres (a sample of the recording's scans).

    Returns
    -------
    float
        Metres; NaN when there is no point.
    """
    r = [np.hypot(c[:, 0], c[:, 1]) for c in clouds if len(c)]
    if not r:
        return math.nan
    r = np.concatenate(r)
    r = r[np.isfinite(r) & (r > 0)]
    return float(np.median(r)) if len(r) else math.nan


def choose_thresholds(
    range_m: float,
    distance_m: float | None = None,
    angle_rad: float | None = None,
    range_fraction: float = 0.1,
) -> MotionThresholds:
    """The motion filter's thresholds: the configured ones, or chosen from the range.

    Parameters
    ----------
    range_m : float
        Typical range of the scanner (:func:`typical_range_m`), metres.
    distance_m, angle_rad : float or None
        Configured thresholds (``register.keep_distance_m`` / ``keep_angle_rad``);
        None: chosen.
    range_fraction : float
        ``f`` of the module docstring.

    Returns
    -------
    MotionThresholds
    """
    parts = []
    if distance_m is None:
        r = range_m if math.isfinite(range_m) else 1.0
        distance_m = min(max(range_fraction * r, MIN_KEEP_DISTANCE_M), MAX_KEEP_DISTANCE_M)
        parts.append(
            f"keep_distance_m {distance_m:.3f} = {range_fraction} x the typical range {range_m:.2f} m "
            f"(within {MIN_KEEP_DISTANCE_M}..{MAX_KEEP_DISTANCE_M} m)"
        )
    else:
        parts.append(f"keep_distance_m {distance_m} (config)")
    if angle_rad is None:
        angle_rad = range_fraction
        parts.append(
            f"keep_angle_rad {angle_rad:.3f} ({math.degrees(angle_rad):.1f} deg: a point at the typical "
            "range moves as far as for keep_distance_m)"
        )
    else:
        parts.append(f"keep_angle_rad {angle_rad} (config)")
    return MotionThresholds(float(distance_m), float(angle_rad), "; ".join(parts))


class MotionFilter:
    """Online motion filter: :meth:`step` with each usable scan's pose, in time order,
    says whether the scan is sampled (see the module docstring)."""

    def __init__(self, distance_m: float, angle_rad: float):
        self.distance_m = float(distance_m)
        self.angle_rad = float(angle_rad)
        self.last: tuple[float, float, float] | None = None

    def step(self, x: float, y: float, yaw: float) -> bool:
        """Whether the scan at pose (x, y metres, yaw radians) is sampled."""
        last = self.last
        if last is not None:
            turn = abs((yaw - last[2] + math.pi) % (2.0 * math.pi) - math.pi)
            if math.hypot(x - last[0], y - last[1]) < self.distance_m and turn < self.angle_rad:
                return False
        self.last = (float(x), float(y), float(yaw))
        return True


class EveryN:
    """The thesis's rule (``register.every_n``): every n-th usable scan, the first one
    included; :meth:`step` ignores the pose."""

    def __init__(self, n: int):
        self.n = int(n)
        self.count = 0

    def step(self, x: float = 0.0, y: float = 0.0, yaw: float = 0.0) -> bool:
        keep = self.count % self.n == 0
        self.count += 1
        return keep


def median_step_m(x: np.ndarray, y: np.ndarray) -> float:
    """Median distance between consecutive poses (metres; NaN for fewer than two)."""
    if len(x) < 2:
        return math.nan
    return float(np.median(np.hypot(np.diff(x), np.diff(y))))

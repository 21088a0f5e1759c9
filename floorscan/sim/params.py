"""Parameters of the simulate stage: the rover, the stream rates and the error levels.

:class:`SimParams` is the ``simulate`` config section without ``scanners`` (the scanner
models are :mod:`floorscan.sim.scanners`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import Any, Mapping

from floorscan.core.io import InputError


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

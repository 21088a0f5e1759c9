"""Parameters of the simulate stage: the rover, the stream rates and the error levels.

:class:`SimParams` is the ``simulate`` config section without ``scanners`` (the scanner
models are :mod:`floorscan.sim.scanners`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

from floorscan.core.io import InputError
from floorscan.core.config import dataclass_from_mapping, schema_defaults


@dataclass(frozen=True)
@schema_defaults("simulate")
class SimParams:
    """Rover, timing and error parameters (the ``simulate`` section, minus ``scanners``).

    Defaults equal those of ``workflow/schemas/simulate.schema.yaml`` (a test checks).
    Units are in the names: metres, seconds, radians, hertz, nanoseconds.
    """

    speed_mps: float
    max_yaw_rate_rad_s: float
    scan_rate_hz: float
    pose_rate_hz: float
    pose_phase_s: float
    pose_jitter_std_s: float
    odom_rate_hz: float
    sensor_height_m: float
    pose_position_std_m: float
    pose_yaw_std_rad: float
    pose_correlation_time_s: float
    odom_scale_error: float
    odom_noise_frac: float
    odom_yaw_drift_rad_s: float
    start_time_ns: int

    @classmethod
    def from_config(cls, cfg: Mapping[str, Any], where: str = "config simulate") -> "SimParams":
        """Take the known keys of ``cfg`` (``scanners`` is ignored) and check them.

        Raises
        ------
        InputError
            Unknown key, a non-positive rate, speed or height, a negative std, naming
            ``where.<key>``.
        """
        p = dataclass_from_mapping(cls, {k: v for k, v in cfg.items() if k != "scanners"}, where.removeprefix("config "),
                                   InputError)
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

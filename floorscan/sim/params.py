"""Parameters of the simulate stage: the rover, the stream rates and the error levels.

:class:`SimParams` is the ``simulate`` config section without ``scanners`` (the scanner
models are :mod:`floorscan.sim.scanners`), built by
:func:`floorscan.core.config.stage_params`; the schema's bounds (positive rates, speed
and height; non-negative noise levels and times) are checked there.
"""

from __future__ import annotations

from dataclasses import dataclass

from floorscan.core.config import schema_defaults


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

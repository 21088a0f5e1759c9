"""Parameters of the ingest and poses stages (config sections ``ingest`` and ``poses``);
their defaults are those of ``workflow/schemas/ingest.schema.yaml`` and
``poses.schema.yaml`` (:func:`floorscan.core.config.schema_defaults`). Built from a
section by :func:`floorscan.core.config.stage_params`:
``stage_params(IngestParams, config["ingest"])``."""

from __future__ import annotations

from dataclasses import dataclass

from floorscan.core.config import schema_defaults


@dataclass(frozen=True)
@schema_defaults("ingest")
class IngestParams:
    """How a recording is read (config ``ingest``).

    Attributes
    ----------
    carmen_max_range_m : float or None
        A CARMEN log's range limit, metres (readings at or beyond it are no-returns);
        None: detected from the readings (:mod:`floorscan.ingest.carmen_ranges`).
    carmen_fov_rad : float
        A CARMEN ``FLASER``/``RAWLASER`` line's field of view, radians.
    missing_time_period_s : float
        Seconds between scans when a log's stamps are missing or repeated, seconds.
    """

    carmen_max_range_m: float | None
    carmen_fov_rad: float
    missing_time_period_s: float


@dataclass(frozen=True)
@schema_defaults("poses")
class PosesParams:
    """How scan poses are interpolated (config ``poses``).

    Attributes
    ----------
    max_gap_s : float
        A scan between two pose messages further apart than this gets no pose, seconds.
    """

    max_gap_s: float

"""Parameters of the hulls and select stages, one typed object per config section.

- :class:`HullParams`: the ``hulls`` section (``workflow/schemas/hulls.schema.yaml``),
  the clustering of thesis Algorithm 2 (:mod:`floorscan.select.hulls`);
- :class:`SelectParams`: the ``select`` section (``workflow/schemas/select.schema.yaml``)
  read by the hull orderings and the baselines (:mod:`floorscan.select.orderings`);
- :class:`CoverageParams`: its ``select.coverage`` subsection, the coverage orderings
  (:mod:`floorscan.select.coverage`).

Each is built from its config section with :func:`floorscan.core.config.stage_params`
(``stage_params(HullParams, config["hulls"])``; a bad key or value raises
:class:`~floorscan.core.config.ConfigError`) and checks its values; the defaults are the
schemas'.
"""

from __future__ import annotations

import numbers
from dataclasses import asdict, dataclass

from floorscan.core.config import schema_defaults, schema_enum

#: ``hulls.radius_rule`` values (:class:`HullParams`).
RADIUS_RULES = schema_enum("hulls", "radius_rule")


@dataclass(frozen=True)
@schema_defaults("hulls")
class HullParams:
    """Parameters of the ``hulls`` stage (``workflow/schemas/hulls.schema.yaml``).

    Attributes
    ----------
    k_clusters : int
        KMeans clusters per scan (thesis: 10).
    sample_size : int
        Points per scan drawn (seeded, without replacement) for KMeans.
    radius_factor : float
        A point is kept when within ``radius_factor * d`` of its centre (see
        ``radius_rule``).
    radius_rule : {"nearest_centre", "global_min"}
        What ``d`` is: the centre's distance to its nearest other centre, or the
        minimum distance between any two centres of the scan.
    n_init : int
        KMeans initialisations (k-means++), fixed for determinism.
    max_iter : int
        KMeans Lloyd iterations at most.
    seed : int
        Base seed of the subsample and KMeans.
    """

    k_clusters: int
    sample_size: int
    radius_factor: float
    radius_rule: str
    n_init: int
    max_iter: int
    seed: int

    def __post_init__(self) -> None:
        # scikit-learn's parameter validation is off in the loop (floorscan.select.clusters)
        for name in ("k_clusters", "sample_size", "n_init", "max_iter", "seed"):
            value = getattr(self, name)
            if not isinstance(value, numbers.Integral) or isinstance(value, bool):
                raise ValueError(f"hulls.{name} must be an integer, got {value!r}")
        if self.k_clusters < 1:
            raise ValueError(f"hulls.k_clusters must be >= 1, got {self.k_clusters}")
        if self.sample_size < 1:
            raise ValueError(f"hulls.sample_size must be >= 1, got {self.sample_size}")
        if not self.radius_factor > 0:
            raise ValueError(f"hulls.radius_factor must be > 0, got {self.radius_factor}")
        if self.radius_rule not in RADIUS_RULES:
            raise ValueError(f"hulls.radius_rule must be one of {RADIUS_RULES}, got {self.radius_rule!r}")
        if self.n_init < 1 or self.max_iter < 1:
            raise ValueError("hulls.n_init and hulls.max_iter must be >= 1")

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
@schema_defaults("select")
class SelectParams:
    """Parameters of the ``select`` stage (``workflow/schemas/select.schema.yaml``).

    The section's other keys are read by other classes: ``figure_*`` by
    :class:`floorscan.select.figure_data.FigureParams`, ``coverage`` by
    :class:`CoverageParams`, ``default_ordering``, ``k`` and ``k_coverage`` by the
    recommended selection (:mod:`floorscan.select.recommend`).

    Attributes
    ----------
    raster_m : float
        Cell side of the coverage raster, metres.
    seed : int
        Seed of the ``random`` ordering.
    motion_max_distance_m : float
        Motion filter: keep a scan once the scanner moved more than this, metres.
    motion_max_angle_deg : float
        Motion filter: ... or turned more than this, degrees.
    motion_max_time_s : float
        Motion filter: ... or more than this passed, seconds.
    """

    raster_m: float
    seed: int
    motion_max_distance_m: float
    motion_max_angle_deg: float
    motion_max_time_s: float

    def __post_init__(self) -> None:
        if not self.raster_m > 0:
            raise ValueError(f"select.raster_m must be > 0, got {self.raster_m}")
        for name in ("motion_max_distance_m", "motion_max_angle_deg", "motion_max_time_s"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"select.{name} must be >= 0, got {getattr(self, name)}")

    def as_dict(self) -> dict:
        return asdict(self)


@dataclass(frozen=True)
@schema_defaults("select.coverage")
class CoverageParams:
    """Settings of the coverage orderings (``select.coverage`` config section).

    Attributes
    ----------
    cell_m : float
        Side of the coverage cells, metres.
    min_scans : int
        A cell counts (``v`` = 1) when at least this many scans cover it.
    min_quality : float
        Least quality of a covered cell, in (0, 1].
    full_spacing_m : float
        ``surface_coverage``: return spacing at which a cell counts fully, metres.
    wall_extractor : str
        ``wall_coverage``: the extractor whose per-scan segments are used.
    wall_quality : bool
        ``wall_coverage``: weight cells by the segments' fit quality.
    """

    cell_m: float
    min_scans: int
    min_quality: float
    full_spacing_m: float
    wall_extractor: str
    wall_quality: bool

    def check(self) -> None:
        """Raise ValueError naming the key of a value out of range."""
        if not self.cell_m > 0:
            raise ValueError(f"select.coverage.cell_m: expected > 0, got {self.cell_m}")
        if int(self.min_scans) < 1:
            raise ValueError(f"select.coverage.min_scans: expected >= 1, got {self.min_scans}")
        if not 0 < self.min_quality <= 1:
            raise ValueError(f"select.coverage.min_quality: expected 0 < value <= 1, got {self.min_quality}")
        if not self.full_spacing_m > 0:
            raise ValueError(f"select.coverage.full_spacing_m: expected > 0, got {self.full_spacing_m}")

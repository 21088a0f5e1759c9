"""Parameters of the score stage (config section ``score``): :class:`ScoreParams`, with
the defaults of ``workflow/schemas/score.schema.yaml``
(:func:`floorscan.core.config.schema_defaults`); the schema describes each key. Built by
:func:`floorscan.core.config.stage_params`: ``stage_params(ScoreParams, config["score"])``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

from floorscan.core.config import schema_defaults


@dataclass(frozen=True)
@schema_defaults("score")
class ScoreParams:
    """The ``score`` section, read once per job.

    Attributes
    ----------
    cell_m, wall_width_m, margin_m : float
        The thesis's bitmap metrics (section 5.1): cell side, wall width drawn, margin
        around the walls, metres.
    taus_m : list of float
        Tolerances of completeness and correctness, metres.
    sample_step_m : float
        Spacing of the samples along walls, metres.
    summary_tau_m : float
        The tolerance of the summary (one of ``taus_m``), metres.
    summary_levels : list of float
        Fractions of the all-scan F1 the summary's k is read at (k95, k99).
    recall_reference, reference_source : str
        What recall is measured against on synthetic datasets; which walls are the
        reference of a real recording.
    figure_k, figure_orderings, figure_ordering, figure_extractor, max_plot_points,
    points_z_band_m, seed
        The figures' k, orderings, extractor, point budget, height band (metres) and
        seed of the point subsample.
    reference : mapping
        The reference map's section (:class:`floorscan.core.occupancy.OccupancyParams`).
    curve_step_fraction : float
        Step of the quality-vs-k curves, a fraction of the kept scans.
    random_seeds : int
        Seeds of the ``random`` ordering's curve.
    curve_auc_fraction : float
        The area under the curve is taken up to this fraction of the kept scans.
    """

    cell_m: float
    wall_width_m: float
    margin_m: float
    taus_m: list
    sample_step_m: float
    summary_tau_m: float
    summary_levels: list
    recall_reference: str
    reference_source: str
    figure_k: int
    figure_orderings: list
    figure_ordering: str
    figure_extractor: str
    max_plot_points: int
    points_z_band_m: list
    seed: int
    reference: Mapping[str, Any]
    curve_step_fraction: float
    random_seeds: int
    curve_auc_fraction: float

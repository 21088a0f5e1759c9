"""All figures of the scoring stage of a dataset: the thesis's Chapter 5 figures, drawn
by the modules of what they show.

- :func:`make_walls_figures` (rule ``score_walls_figures``; they need no metrics, so
  they are drawn while the runs are scored): the merged floor plans
  (:mod:`floorscan.figures.floorplans`, Fig. 5.5), the bitmap overlay
  (:mod:`floorscan.figures.bitmaps`, Fig. 5.1), the walls over the registered points
  (:mod:`floorscan.figures.maps`, Figs. 5.11, 5.12) and the wall extraction per scan
  (:mod:`floorscan.figures.wall_extraction`, Fig. 5.10);
- :func:`make_score_figures` (rule ``score_figures``, last): the metrics against k
  (:mod:`floorscan.figures.curves`, Fig. 5.4) and the time and memory per stage
  (:mod:`floorscan.figures.stage_times`, Table 5.1).

A new figure is a function in the module of what it shows, called here, with its
output in the rule's ``output:`` (``workflow/rules/score.smk``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from floorscan.core.files import atomic_path
from floorscan.figures.bitmaps import plot_bitmap_overlay
from floorscan.figures.curves import plot_metrics_vs_k
from floorscan.figures.floorplans import plot_floorplans
from floorscan.figures.maps import plot_walls_over_points, subsample_points
from floorscan.figures.stage_times import plot_stage_times, stage_times
from floorscan.figures.style import reference_name
from floorscan.figures.wall_extraction import plot_wall_extraction
from floorscan.core.config import schema_defaults, stage_params
from floorscan.core.segment_raster import grid_for
from floorscan.core.segments import as_segments


@dataclass(frozen=True)
@schema_defaults("score")
class ScoreFigureParams:
    """The keys of the ``score`` config section the figures read
    (``stage_params(ScoreFigureParams, config["score"])``: the section's other keys are
    the score stage's, :class:`floorscan.score.params.ScoreParams`).

    Attributes
    ----------
    figure_k : int
        The k of the floor plan, bitmap overlay and walls-over-points figures.
    figure_orderings : list of str
        Orderings side by side in the floor plan and bitmap overlay figures.
    figure_ordering : str
        Ordering of the walls-over-points figures.
    figure_extractor : str
        Extractor of the floor plan and bitmap overlay figures.
    cell_m, margin_m, wall_width_m : float
        The scoring grid (cell side, margin around the walls) and the wall width drawn
        on it, metres: the score stage's (thesis section 5.1).
    max_plot_points : int
        Points drawn under the walls at most.
    points_z_band_m : list of float
        Height band of the points drawn, metres.
    seed : int
        Seed of the point subsample.
    summary_tau_m : float
        The tolerance of the F1 drawn against k, metres.
    """

    figure_k: int
    figure_orderings: list
    figure_ordering: str
    figure_extractor: str
    cell_m: float
    margin_m: float
    wall_width_m: float
    max_plot_points: int
    points_z_band_m: list
    seed: int
    summary_tau_m: float


def make_walls_figures(
    *,
    dataset: str,
    reference: dict,
    reference_kind: str,
    walls: dict,
    scores,
    floorplans: dict,
    points,
    scan_status: dict,
    scan_times: dict,
    outputs: dict,
    cfg: dict,
    log=None,
) -> None:
    """Write the figures of a dataset's walls and floor plans (thesis Figs. 5.1, 5.5,
    5.10 - 5.12); they need no metrics, so they are drawn while the runs are scored.

    Parameters
    ----------
    dataset : str
        Dataset name, for titles.
    reference : dict
        ``{extractor: (M, 4) segments}`` the walls are scored against.
    reference_kind : str
        ``"ground_truth"`` or ``"reference"``.
    walls : dict
        ``{(ordering, extractor, k_label): DataFrame}`` raw wall segments for the
        figure runs (``cfg.figure_k`` and ``"all"``).
    scores : pandas.DataFrame or None
        The score stage's scores of the figure extractor's runs
        (``score/<extractor>.parquet``: ``ordering``, ``extractor``, ``k`` and the bitmap
        metrics), the numbers of the bitmap overlay's panels; None: not scored (the
        figure extractor is not one of the extractors).
    floorplans : dict
        ``{(ordering, extractor): list of geometries}`` merged floor plans at
        ``cfg.figure_k``.
    points : pandas.DataFrame or path
        Registered points (``x, y, z``), or the path of ``registered.parquet``
        (read in batches); subsampled here
        (:func:`floorscan.figures.maps.subsample_points`).
    scan_status : dict
        ``{extractor: DataFrame}`` wall extraction status per scan.
    scan_times : dict
        ``{extractor: DataFrame}`` seconds of each scan's wall extraction
        (:func:`floorscan.figures.wall_extraction.plot_wall_extraction`).
    outputs : dict
        Paths: ``floorplan``, ``bitmap_overlay``, ``walls_over_points_k``,
        ``walls_over_points_all``, ``wall_extraction``.
    cfg : ScoreFigureParams or mapping
        The ``score`` config section.
    """
    cfg = stage_params(ScoreFigureParams, cfg)
    k = str(cfg.figure_k)
    ext_fig = cfg.figure_extractor
    ordering_fig = cfg.figure_ordering
    ref_name = reference_name(reference_kind)
    extractors = sorted(scan_status) or sorted(reference)

    ref_fig = reference.get(ext_fig, next(iter(reference.values())))
    panels = [
        (f"{o}, {ext_fig}: first {k} scans", floorplans.get((o, ext_fig), []))
        for o in cfg.figure_orderings
    ]
    plot_floorplans(panels, ref_fig, reference_kind, outputs["floorplan"],
                    f"{dataset}: merged floor plans from the first {k} scans over the {ref_name}")

    all_refs = [as_segments(s) for s in reference.values() if len(as_segments(s))]
    grid = grid_for(np.vstack(all_refs), cfg.cell_m, cfg.margin_m)
    rows = [] if scores is None else scores.to_dict("records")
    scored = {(r["ordering"], r["extractor"], str(r["k"])): r for r in rows}
    panels = [
        (f"{o}, {ext_fig}, first {k} scans", walls.get((o, ext_fig, k), np.zeros((0, 4))), scored.get((o, ext_fig, k)))
        for o in cfg.figure_orderings
    ]
    plot_bitmap_overlay(panels, ref_fig, reference_kind, grid, cfg.wall_width_m,
                        outputs["bitmap_overlay"],
                        f"{dataset}: inferred walls (red) over the {ref_name} (blue)")

    xy = subsample_points(points, cfg.max_plot_points, cfg.seed, cfg.points_z_band_m)
    for key, kk, label in (
        ("walls_over_points_k", k, f"the first {k} scans ({ordering_fig})"),
        ("walls_over_points_all", "all", "all kept scans"),
    ):
        panels = [
            (f"{e}, {label}", walls.get((ordering_fig, e, kk), np.zeros((0, 4))))
            for e in extractors
        ]
        plot_walls_over_points(xy, panels, outputs[key],
                               f"{dataset}: walls from {label} over the registered points")

    plot_wall_extraction(scan_status, scan_times, outputs["wall_extraction"],
                         f"{dataset}: wall extraction per scan, ransac against cluster_ransac")
    if log is not None:
        log.info("walls figures written for %s", dataset)


def make_score_figures(*, dataset: str, metrics: pd.DataFrame, bench_dir, outputs: dict, cfg: dict, log=None) -> pd.DataFrame:
    """Write the metrics figure (thesis Fig. 5.4) and the time per stage (Table 5.1)
    of a dataset; return the stage-time table.

    Parameters
    ----------
    dataset : str
        Dataset name, for titles.
    metrics : pandas.DataFrame
        ``metrics.parquet``.
    bench_dir : path
        ``results/{dataset}/benchmarks``: every job's benchmark file there is counted
        (the rule runs last, after the other figures).
    outputs : dict
        Paths: ``metrics_vs_k``, ``stage_times_png``, ``stage_times_tsv``.
    cfg : ScoreFigureParams or mapping
        The ``score`` config section.

    Returns
    -------
    pandas.DataFrame
        :func:`floorscan.figures.stage_times.stage_times`.
    """
    cfg = stage_params(ScoreFigureParams, cfg)
    plot_metrics_vs_k(metrics, outputs["metrics_vs_k"], cfg.summary_tau_m)
    table = stage_times(bench_dir)
    with atomic_path(outputs["stage_times_tsv"]) as tmp:
        table.to_csv(tmp, sep="\t", index=False, float_format="%.3f")
    plot_stage_times(table, outputs["stage_times_png"], f"{dataset}: time and memory per stage")
    if log is not None:
        log.info("score figures written for %s (%d stages timed)", dataset, len(table))
    return table

"""Figures of the select stage: thesis Figs 5.6, 5.7 and 5.8, of the data the select
stage computes for them (floorscan.select.figure_data)."""
from pathlib import Path

from floorscan.core.config import stage_params
from floorscan.core.io import read_table
from floorscan.core.stage import stage_log
from floorscan.figures.selection import selection_figures
from floorscan.select.figure_data import FigureParams, selection_figure_data
from floorscan.select.hulls import kept_scan_ids
from floorscan.select.orderings import with_hull_coverage
from floorscan.select.params import HullParams, SelectParams

with stage_log(snakemake) as log:
    cfg = dict(snakemake.params.cfg)
    select_params = stage_params(SelectParams, cfg)
    registration = read_table(snakemake.input.registration)
    hulls = read_table(snakemake.input.hulls)
    # the coverage orderings rank by their own objective: the hull area along them here
    orderings = with_hull_coverage(
        {Path(p).stem: read_table(p) for p in snakemake.input.orderings}, hulls,
        kept_scan_ids(registration, snakemake.input.registration), select_params.raster_m,
    )
    data = selection_figure_data(
        registered=snakemake.input.registered,  # streamed scan by scan
        registration=registration,
        hulls=hulls,
        convex_hulls=read_table(snakemake.input.convex),  # the k = 1 curve
        orderings=orderings,
        hull_params=stage_params(HullParams, snakemake.params.hulls_cfg),
        select_params=select_params,
        params=stage_params(FigureParams, cfg),
    )
    selection_figures(orderings, data.k99, data.clusters, data.timing, snakemake.output.coverage,
                      snakemake.output.clusters, snakemake.output.timing, title=snakemake.wildcards.dataset)
    log.info("selection time:\n%s", data.timing.to_string(index=False))

"""Figures of the select stage: thesis Figs 5.6, 5.7 and 5.8."""
from pathlib import Path

from floorscan.core.config import stage_params
from floorscan.figures.selection import FigureParams, selection_figures
from floorscan.select.hulls import kept_scan_ids
from floorscan.core.io import read_table
from floorscan.select.orderings import with_hull_coverage
from floorscan.select.params import HullParams, SelectParams
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:
    cfg = dict(snakemake.params.cfg)
    fig_params = stage_params(FigureParams, cfg)
    select_params = stage_params(SelectParams, cfg)
    registration = read_table(snakemake.input.registration)
    hulls = read_table(snakemake.input.hulls)
    # the coverage orderings rank by their own objective: the hull area along them here
    orderings = with_hull_coverage(
        {Path(p).stem: read_table(p) for p in snakemake.input.orderings}, hulls,
        kept_scan_ids(registration, snakemake.input.registration), select_params.raster_m,
    )
    timing = selection_figures(
        registered=snakemake.input.registered,  # streamed scan by scan
        registration=registration,
        hulls=hulls,
        convex_hulls=read_table(snakemake.input.convex),  # the k = 1 curve
        orderings=orderings,
        hull_params=stage_params(HullParams, snakemake.params.hulls_cfg),
        select_params=select_params,
        params=fig_params,
        out_coverage=snakemake.output.coverage,
        out_clusters=snakemake.output.clusters,
        out_timing=snakemake.output.timing,
        title=snakemake.wildcards.dataset,
    )
    log.info("selection time:\n%s", timing.to_string(index=False))

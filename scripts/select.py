"""Stage `select`: the five scan orderings and their coverage summary (thesis Algorithm 1)."""
from pathlib import Path

from floorscan.io import read_table, write_table
from floorscan.selection import ORDERING, SUMMARY, SelectParams, select_stage
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    params = SelectParams.from_config(snakemake.params.cfg)
    orderings, summary = select_stage(
        read_table(snakemake.input.hulls),
        read_table(snakemake.input.convex),
        read_table(snakemake.input.registration),
        params,
    )
    log.info("orderings summary:\n%s", summary.to_string(index=False))
    meta = {"stage": "select", "dataset": snakemake.wildcards.dataset, "raster_m": params.raster_m}
    for path in snakemake.output.orderings:
        write_table(orderings[Path(path).stem], path, schema=ORDERING, metadata=meta)
    write_table(summary, snakemake.output.summary, schema=SUMMARY, metadata=meta)

"""Stage `select`: the hull shards concatenated in scan order (hulls.parquet and
convex_hulls.parquet, exactly the tables of one unsharded job), then the five scan
orderings and their coverage summary (thesis Algorithm 1). One job, not a merge job
and a select job: a job costs ~0.6 s to start, on the path to the walls' k tables."""
from pathlib import Path

from floorscan.select.hulls import HULLS
from floorscan.core.io import read_table, write_table
from floorscan.select.orderings import ORDERING, SUMMARY, SelectParams, select_stage
from floorscan.core.shards import plan_from_files, read_shards
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:
    # the plan the workflow named the shards by, from the register stage's files
    plan = plan_from_files(snakemake.input.registration, snakemake.input.registered, snakemake.params.shard_scans)
    cluster, counts = read_shards(snakemake.input.shard_hulls, plan, "hulls shards")
    convex, _ = read_shards(snakemake.input.shard_convex, plan, "convex hull shards")
    log.info("hulls: %s from %d shards", counts, len(plan["shards"]))
    meta = {"stage": "hulls", "dataset": snakemake.wildcards.dataset, "units": "metres, m2"}
    cluster, convex = cluster.cast(HULLS), convex.cast(HULLS)  # the frames the files read back as
    write_table(cluster, snakemake.output.hulls, metadata=meta)
    write_table(convex, snakemake.output.convex, metadata=meta)

    params = SelectParams.from_config(snakemake.params.cfg)
    orderings, summary = select_stage(
        cluster.to_pandas(),
        convex.to_pandas(),
        read_table(snakemake.input.registration),
        params,
    )
    # the seconds of each ordering go to this log, not into the summary file
    log.info("orderings summary:\n%s", summary.to_string(index=False))
    meta = {"stage": "select", "dataset": snakemake.wildcards.dataset, "raster_m": params.raster_m}
    for path in snakemake.output.orderings:
        write_table(orderings[Path(path).stem], path, schema=ORDERING, metadata=meta)
    write_table(summary, snakemake.output.summary, schema=SUMMARY, metadata=meta)

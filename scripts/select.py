"""Stage `select`: the hull shards concatenated in scan order (hulls.parquet and
convex_hulls.parquet, exactly the tables of one unsharded job), then every ordering of
floorscan.select.registry.RANKERS and their coverage summary (thesis Algorithm 1). One
job, not a merge job and a select job: a job costs ~0.6 s to start, on the path to the
walls' k tables."""
from pathlib import Path

from floorscan.core.config import stage_params
from floorscan.core.io import read_table, write_table
from floorscan.core.stage import stage_log
from floorscan.select.hulls import merge_hull_shards
from floorscan.select.orderings import ORDERING, select_stage
from floorscan.select.params import SelectParams
from floorscan.select.summary import SUMMARY

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    cluster, convex, _ = merge_hull_shards(
        smk.input.shard_hulls, smk.input.shard_convex, smk.input.registration, smk.input.registered,
        smk.params.shard_scans, smk.output.hulls, smk.output.convex, smk.wildcards.dataset, log=log,
    )
    params = stage_params(SelectParams, smk.params.cfg)
    orderings, summary = select_stage(cluster, convex, read_table(smk.input.registration), params)
    # the seconds of each ordering go to this log, not into the summary file
    log.info("orderings summary:\n%s", summary.to_string(index=False))
    meta = {"stage": "select", "dataset": smk.wildcards.dataset, "raster_m": params.raster_m}
    for path in smk.output.orderings:
        write_table(orderings[Path(path).stem], path, schema=ORDERING, metadata=meta)
    write_table(summary, smk.output.summary, schema=SUMMARY, metadata=meta)

"""Checkpoint of a per-scan stage (hulls, scan_walls): its shards by scan range."""
import pyarrow.parquet as pq

from floorscan.io import write_json
from floorscan.shards import plan_shards
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    plan = plan_shards(
        pq.read_table(snakemake.input.registration),
        pq.read_table(snakemake.input.registered, columns=["scan_id"])["scan_id"].to_numpy(),
        snakemake.params.shard_scans,
        path=snakemake.input.registration,
    )
    plan["stage"] = snakemake.params.stage
    log.info(
        "%s: %d kept scans of scans %d..%d in %d shards of <= %s: %s",
        plan["stage"], plan["n_kept"], plan["first"], plan["last"], len(plan["shards"]),
        plan["shard_scans"] or "all", [(s["label"], s["n_kept"]) for s in plan["shards"]],
    )
    write_json(plan, snakemake.output.plan)

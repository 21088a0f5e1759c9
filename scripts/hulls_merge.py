"""Stage `hulls`: the shards' cluster hulls and convex hulls concatenated in scan order,
exactly the tables of one unsharded job."""
import json

from floorscan.hulls import HULLS
from floorscan.io import write_table
from floorscan.shards import read_shards
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    with open(snakemake.input.plan) as f:
        plan = json.load(f)
    cluster, counts = read_shards(snakemake.input.hulls, plan, "hulls shards")
    convex, _ = read_shards(snakemake.input.convex, plan, "convex hull shards")
    log.info("hulls: %s from %d shards", counts, len(plan["shards"]))
    meta = {"stage": "hulls", "dataset": snakemake.wildcards.dataset, "units": "metres, m2"}
    write_table(cluster, snakemake.output.hulls, schema=HULLS, metadata=meta)
    write_table(convex, snakemake.output.convex, schema=HULLS, metadata=meta)

"""Stage `hulls`: cluster hulls and convex hulls of every kept scan (thesis Algorithm 2)."""
from floorscan.hulls import HullParams, compute_hulls, to_table
from floorscan.io import read_table, write_table
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    params = HullParams.from_config(snakemake.params.cfg)
    cluster, convex, counts = compute_hulls(
        read_table(snakemake.input.registered), read_table(snakemake.input.registration), params
    )
    log.info("hulls: %s (params %s)", counts, params.as_dict())
    meta = {"stage": "hulls", "dataset": snakemake.wildcards.dataset, "units": "metres, m2"}
    write_table(to_table(cluster), snakemake.output.hulls, metadata=meta)
    write_table(to_table(convex), snakemake.output.convex, metadata=meta)

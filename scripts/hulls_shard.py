"""Stage `hulls`, one shard: cluster hulls and convex hulls of the kept scans of a scan
range (thesis Algorithm 2), streamed scan by scan (memory holds one scan, issue 8).
scripts/select.py concatenates the shards (floorscan.select.hulls.merge_hull_shards)."""
import json

from floorscan.core.config import stage_params
from floorscan.select.hulls import compute_hulls, to_table
from floorscan.select.params import HullParams
from floorscan.core.runtime import progress
from floorscan.core.io import iter_scans, write_table
from floorscan.core.shards import parse_shard_label, read_scan_range
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:
    params = stage_params(HullParams, snakemake.params.cfg)
    shard = snakemake.wildcards.shard
    start, stop = parse_shard_label(shard)
    cluster, convex, counts = compute_hulls(
        progress(iter_scans(snakemake.input.registered, ("x", "y"), scan_range=(start, stop)), log, what="scans"),
        read_scan_range(snakemake.input.registration, start, stop),
        params,
    )
    log.info("hulls of %s: %s (params %s)", shard, counts, params.as_dict())
    meta = {"stage": "hulls", "dataset": snakemake.wildcards.dataset, "units": "metres, m2",
            "shard": shard, "counts": json.dumps(counts)}
    write_table(to_table(cluster), snakemake.output.hulls, metadata=meta)
    write_table(to_table(convex), snakemake.output.convex, metadata=meta)

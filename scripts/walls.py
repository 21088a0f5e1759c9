"""Stage walls, for one extractor: the wall segments of every kept scan (the shards of
scan_walls_shard concatenated in scan order: exactly the tables of one unsharded job)
and of the first k scans of each ordering. One job, not a merge job and a walls job:
a job costs ~0.6 s to start, on the path from the last shard to the floor plans."""
from pathlib import Path

from floorscan.io import read_table, write_table
from floorscan.shards import plan_from_files, read_shards
from floorscan.walls import SCAN_STATUS, WALLS, first_k_walls
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    run = snakemake.params.run
    dataset, extractor = snakemake.wildcards.dataset, snakemake.wildcards.extractor
    # the plan the workflow named the shards by, from the register stage's files
    plan = plan_from_files(snakemake.input.registration, snakemake.input.registered, snakemake.params.shard_scans)
    walls, _ = read_shards(snakemake.input.shard_walls, plan, f"{extractor} wall shards")
    status, _ = read_shards(snakemake.input.shard_status, plan, f"{extractor} scan status shards")
    status = status.to_pandas()
    reasons = status.query("reason != ''")["reason"].value_counts().to_dict()
    log.info("%s: %d scans, %d wall segments from %d shards, scans without walls: %s",
             extractor, len(status), walls.num_rows, len(plan["shards"]), reasons or "none")
    meta = {"dataset": dataset, "extractor": extractor, "units": "metres, map frame"}
    # through pandas, as the unsharded stage wrote them: the same file, metadata included
    per_scan = walls.cast(WALLS).to_pandas()
    write_table(per_scan, snakemake.output.walls, schema=WALLS, metadata=meta)
    write_table(status, snakemake.output.status, schema=SCAN_STATUS, metadata=meta)

    orderings = {Path(p).stem: read_table(p) for p in snakemake.input.orderings}
    runs = [(o, k) for o in run["orderings"] for k in run["k"]]  # the rule's expand order
    for (ordering, k), out in zip(runs, snakemake.output.tables, strict=True):
        assert out.endswith(f"/{ordering}/{extractor}/k{k}.parquet"), (ordering, k, out)
        segments, scan_ids = first_k_walls(per_scan, orderings[ordering], k)
        meta = {
            "dataset": dataset, "ordering": ordering, "extractor": extractor, "k": k,
            "n_scans": len(scan_ids), "units": "metres, map frame",
        }
        write_table(segments, out, schema=WALLS, metadata=meta)
        log.info("%s %s k=%s: %d scans, %d wall segments", ordering, extractor, k, len(scan_ids), len(segments))

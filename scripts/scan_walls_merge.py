"""Stage walls, for one extractor: the wall segments of every kept scan, the shards of
scan_walls_shard concatenated in scan order (exactly the tables of one unsharded job),
and the times of each scan (benchmarks folder, output `times` when the rule names one)."""
from floorscan.core.io import write_table
from floorscan.core.shards import plan_from_files, read_shards
from floorscan.walls.extract import SCAN_STATUS, SCAN_TIMES, WALLS
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    dataset, extractor = smk.wildcards.dataset, smk.wildcards.extractor
    # the plan the workflow named the shards by, from the register stage's files
    plan = plan_from_files(smk.input.registration, smk.input.registered, smk.params.shard_scans)
    walls, _ = read_shards(smk.input.shard_walls, plan, f"{extractor} wall shards")
    status, _ = read_shards(smk.input.shard_status, plan, f"{extractor} scan status shards")
    status = status.to_pandas()
    reasons = status.query("reason != ''")["reason"].value_counts().to_dict()
    log.info("%s: %d scans, %d wall segments from %d shards, scans without walls: %s",
             extractor, len(status), walls.num_rows, len(plan["shards"]), reasons or "none")
    meta = {"dataset": dataset, "extractor": extractor, "units": "metres, map frame"}
    # through pandas, as the unsharded stage wrote them: the same file, metadata included
    write_table(walls.cast(WALLS).to_pandas(), smk.output.walls, schema=WALLS, metadata=meta)
    write_table(status, smk.output.status, schema=SCAN_STATUS, metadata=meta)
    if smk.output.get("times"):
        times, _ = read_shards(smk.input.shard_times, plan, f"{extractor} scan time shards")
        write_table(times.cast(SCAN_TIMES), smk.output.times, metadata=meta)

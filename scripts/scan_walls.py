"""Stage walls, for one extractor: the wall segments of every kept scan, the shards of
scan_walls_shard concatenated in scan order (exactly the tables of one unsharded job,
floorscan.walls.shards.merge_shards), and the times of each scan (benchmarks folder,
output `times` when the rule names one)."""
from floorscan.core.io import write_table
from floorscan.core.stage import stage_log
from floorscan.walls.shards import merge_shards
from floorscan.walls.tables import SCAN_STATUS, WALLS

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    dataset, extractor = smk.wildcards.dataset, smk.wildcards.extractor
    walls, status, times = merge_shards(
        extractor, smk.input.registration, smk.input.registered, smk.params.shard_scans,
        smk.input.shard_walls, smk.input.shard_status,
        shard_times=smk.input.shard_times if smk.output.get("times") else None, log=log,
    )
    meta = {"dataset": dataset, "extractor": extractor, "units": "metres, map frame"}
    write_table(walls, smk.output.walls, schema=WALLS, metadata=meta)
    write_table(status, smk.output.status, schema=SCAN_STATUS, metadata=meta)
    if times is not None:
        write_table(times, smk.output.times, metadata=meta)

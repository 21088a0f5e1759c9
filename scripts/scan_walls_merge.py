"""Stage scan_walls: the shards' wall segments and per-scan status (drop reasons)
concatenated in scan order, exactly the tables of one unsharded job."""
import json

from floorscan.io import write_table
from floorscan.shards import read_shards
from floorscan.walls import SCAN_STATUS, WALLS
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    extractor = snakemake.wildcards.extractor
    with open(snakemake.input.plan) as f:
        plan = json.load(f)
    walls, _ = read_shards(snakemake.input.walls, plan, f"{extractor} wall shards")
    status, _ = read_shards(snakemake.input.status, plan, f"{extractor} scan status shards")
    reasons = status.to_pandas().query("reason != ''")["reason"].value_counts().to_dict()
    log.info("%s: %d scans, %d wall segments from %d shards, scans without walls: %s",
             extractor, status.num_rows, walls.num_rows, len(plan["shards"]), reasons or "none")
    meta = {"dataset": snakemake.wildcards.dataset, "extractor": extractor, "units": "metres, map frame"}
    # through pandas, as the unsharded stage wrote them: the same file, metadata included
    write_table(walls.to_pandas(), snakemake.output.walls, schema=WALLS, metadata=meta)
    write_table(status.to_pandas(), snakemake.output.status, schema=SCAN_STATUS, metadata=meta)

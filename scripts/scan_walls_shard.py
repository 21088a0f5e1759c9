"""Stage scan_walls, one shard: wall segments of the scans of a scan range with one
extractor (floorscan.walls.extract.extract_walls), streamed scan by scan (memory holds
one scan). scripts/scan_walls.py concatenates the shards. The time of each scan
goes to the benchmarks folder (output `times`, when the rule names one), not into the
status."""
from floorscan.core.io import iter_scans, write_table
from floorscan.core.runtime import progress
from floorscan.core.shards import parse_shard_label
from floorscan.core.stage import stage_log
from floorscan.walls.extract import extract_walls
from floorscan.walls.tables import SCAN_STATUS, SCAN_TIMES, WALLS

with stage_log(snakemake) as log:
    extractor = snakemake.wildcards.extractor
    shard = snakemake.wildcards.shard
    start, stop = parse_shard_label(shard)
    scans = iter_scans(snakemake.input.points, ("x", "y", "z"), scan_range=(start, stop))
    walls, status = extract_walls(progress(scans, log, what="scans"), extractor, snakemake.params.cfg)
    meta = {"dataset": snakemake.wildcards.dataset, "extractor": extractor, "units": "metres, map frame", "shard": shard}
    write_table(walls, snakemake.output.walls, schema=WALLS, metadata=meta)
    write_table(status, snakemake.output.status, schema=SCAN_STATUS, metadata=meta)
    if snakemake.output.get("times"):
        write_table(status, snakemake.output.times, schema=SCAN_TIMES, metadata=meta)

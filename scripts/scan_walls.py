"""Stage scan_walls, one shard: wall segments of the scans of a scan range with one
extractor. scripts/scan_walls_merge.py concatenates the shards."""
from floorscan.io import write_table
from floorscan.shards import parse_shard_label, read_scan_range
from floorscan.walls import SCAN_STATUS, WALLS, extract_walls
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    extractor = snakemake.wildcards.extractor
    shard = snakemake.wildcards.shard
    start, stop = parse_shard_label(shard)
    walls, status = extract_walls(read_scan_range(snakemake.input.points, start, stop), extractor, snakemake.params.cfg)
    meta = {"dataset": snakemake.wildcards.dataset, "extractor": extractor, "units": "metres, map frame", "shard": shard}
    write_table(walls, snakemake.output.walls, schema=WALLS, metadata=meta)
    write_table(status, snakemake.output.status, schema=SCAN_STATUS, metadata=meta)

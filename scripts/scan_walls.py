"""Stage scan_walls: wall segments of every kept scan with one extractor."""
from floorscan.io import read_table, write_table
from floorscan.walls import SCAN_STATUS, WALLS, extract_walls
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    extractor = snakemake.wildcards.extractor
    walls, status = extract_walls(read_table(snakemake.input.points), extractor, snakemake.params.cfg)
    meta = {"dataset": snakemake.wildcards.dataset, "extractor": extractor, "units": "metres, map frame"}
    write_table(walls, snakemake.output.walls, schema=WALLS, metadata=meta)
    write_table(status, snakemake.output.status, schema=SCAN_STATUS, metadata=meta)

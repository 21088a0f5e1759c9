"""Stage walls: the wall segments of the first k scans of each ordering, for one extractor."""
from pathlib import Path

from floorscan.io import read_table, write_table
from floorscan.walls import WALLS, first_k_walls
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:
    run = snakemake.params.run
    dataset, extractor = snakemake.wildcards.dataset, snakemake.wildcards.extractor
    per_scan = read_table(snakemake.input.walls)
    orderings = {Path(p).stem: read_table(p) for p in snakemake.input.orderings}
    for ordering in run["orderings"]:
        for k in run["k"]:
            segments, scan_ids = first_k_walls(per_scan, orderings[ordering], k)
            out = f"results/{dataset}/walls/{ordering}/{extractor}/k{k}.parquet"
            assert out in snakemake.output, out
            meta = {
                "dataset": dataset, "ordering": ordering, "extractor": extractor, "k": k,
                "n_scans": len(scan_ids), "units": "metres, map frame",
            }
            write_table(segments, out, schema=WALLS, metadata=meta)
            log.info("%s %s k=%s: %d scans, %d wall segments", ordering, extractor, k, len(scan_ids), len(segments))

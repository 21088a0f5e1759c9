"""Stage walls, for one extractor: the wall segments of the first k scans of each
ordering, cut from the per-scan walls (rule scan_walls; floorscan.walls.first_k)."""
from pathlib import Path

from floorscan.core.io import read_table, write_table
from floorscan.core.stage import stage_log
from floorscan.walls.first_k import k_walls_tables
from floorscan.walls.tables import WALLS

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    run = smk.params.run
    dataset, extractor = smk.wildcards.dataset, smk.wildcards.extractor
    per_scan = read_table(smk.input.walls)
    orderings = {Path(p).stem: read_table(p) for p in smk.input.orderings}
    tables = k_walls_tables(per_scan, orderings, run["orderings"], run["k"])  # the rule's expand order
    for (ordering, k, segments, scan_ids), out in zip(tables, smk.output.tables, strict=True):
        assert out.endswith(f"/{ordering}/{extractor}/k{k}.parquet"), (ordering, k, out)
        meta = {
            "dataset": dataset, "ordering": ordering, "extractor": extractor, "k": k,
            "n_scans": len(scan_ids), "units": "metres, map frame",
        }
        write_table(segments, out, schema=WALLS, metadata=meta)
        log.info("%s %s k=%s: %d scans, %d wall segments", ordering, extractor, k, len(scan_ids), len(segments))

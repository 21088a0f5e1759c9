"""Stage walls, for one extractor: the wall segments of the first k scans of each
ordering, cut from the per-scan walls (rule scan_walls)."""
from pathlib import Path

from floorscan.core.io import read_table, write_table
from floorscan.walls.extract import WALLS, first_k_walls
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    run = smk.params.run
    dataset, extractor = smk.wildcards.dataset, smk.wildcards.extractor
    per_scan = read_table(smk.input.walls)
    orderings = {Path(p).stem: read_table(p) for p in smk.input.orderings}
    runs = [(o, k) for o in run["orderings"] for k in run["k"]]  # the rule's expand order
    for (ordering, k), out in zip(runs, smk.output.tables, strict=True):
        assert out.endswith(f"/{ordering}/{extractor}/k{k}.parquet"), (ordering, k, out)
        segments, scan_ids = first_k_walls(per_scan, orderings[ordering], k)
        meta = {
            "dataset": dataset, "ordering": ordering, "extractor": extractor, "k": k,
            "n_scans": len(scan_ids), "units": "metres, map frame",
        }
        write_table(segments, out, schema=WALLS, metadata=meta)
        log.info("%s %s k=%s: %d scans, %d wall segments", ordering, extractor, k, len(scan_ids), len(segments))

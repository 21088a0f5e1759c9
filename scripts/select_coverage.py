"""Stage select, the coverage orderings (floorscan.select.registry.COVERAGE_SETS):
wall_coverage from the walls stage's per-scan segments, surface_coverage from the
registered points, each written with its own objective along the way
(covered_objective). The hull area they cover, to compare them with the hull
orderings, is the selection figures' work."""
from pathlib import Path

from floorscan.select.hulls import kept_scan_ids
from floorscan.core.io import iter_scans, read_table, write_table
from floorscan.select.coverage import COVERAGE_ORDERING, OBJECTIVE_COLUMN
from floorscan.select.orderings import coverage_orderings
from floorscan.select.params import CoverageParams
from floorscan.walls.params import RansacParams
from floorscan.core.wall_points import ScanParams, scan_points_2d
from floorscan.core.config import stage_params
from floorscan.core.stage import stage_log

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    params = stage_params(CoverageParams, smk.params.cfg["coverage"])
    scan_params = stage_params(ScanParams, smk.params.walls)
    ransac_params = stage_params(RansacParams, smk.params.walls.get("ransac"))
    ids = kept_scan_ids(read_table(smk.input.registration), smk.input.registration)
    kept = set(ids.tolist())  # the band cut only for the kept scans
    scans = ((s, scan_points_2d(xyz, scan_params)[0]) for s, xyz in iter_scans(smk.input.registered) if s in kept)
    orderings = coverage_orderings(read_table(smk.input.walls), scans, ids, params, ransac_params.min_inliers,
                                   ransac_params.threshold_m, log=log)
    meta = {"stage": "select", "dataset": smk.wildcards.dataset, "wall_extractor": params.wall_extractor}
    for path in smk.output.orderings:
        name = Path(path).stem
        table = orderings[name].rename(columns={"covered": OBJECTIVE_COLUMN})
        write_table(table, path, schema=COVERAGE_ORDERING, metadata={**meta, "ordering": name})

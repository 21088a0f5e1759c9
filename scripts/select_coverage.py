"""Stage select, the coverage orderings (floorscan.select.coverage): wall_coverage from
the walls stage's per-scan segments, surface_coverage from the registered points, each
written with the cluster-hull area it covers along the way (comparable with the other
orderings)."""
from pathlib import Path

from floorscan.hulls import kept_scan_ids, scan_coverage
from floorscan.io import iter_scans, read_table, write_table
from floorscan.select.coverage import CoverageParams, coverage_orderings
from floorscan.selection import ORDERING, RasterCoverage, SelectParams, coverage_along
from floorscan.walls import params_from_config, scan_points_2d
from floorscan.workflow import stage_log

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    cfg = smk.params.cfg
    params = CoverageParams.from_config(cfg["coverage"])
    scan_params, ransac_params, _ = params_from_config(smk.params.walls)
    registration = read_table(smk.input.registration)
    ids = kept_scan_ids(registration, smk.input.registration)
    kept = set(ids.tolist())  # the band cut only for the kept scans
    scans = ((s, scan_points_2d(xyz, scan_params)[0]) for s, xyz in iter_scans(smk.input.registered) if s in kept)
    orderings = coverage_orderings(read_table(smk.input.walls), scans, ids, params, ransac_params.min_inliers,
                                   ransac_params.threshold_m, log=log)
    raster_m = SelectParams.from_config(cfg).raster_m
    hull_ids, geoms = scan_coverage(read_table(smk.input.hulls), ids)
    raster = RasterCoverage(geoms, raster_m)  # once for both orderings (coverage_along empties its union)
    meta = {"stage": "select", "dataset": smk.wildcards.dataset, "raster_m": raster_m,
            "wall_extractor": params.wall_extractor}
    for path in smk.output.orderings:
        name = Path(path).stem
        table = coverage_along(hull_ids, geoms, orderings[name]["scan_id"].to_numpy(), raster_m, raster=raster)
        write_table(table, path, schema=ORDERING, metadata={**meta, "ordering": name})

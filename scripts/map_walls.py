"""Stage walls, the map extractor: the wall segments of the map of the selected scans
(or of all kept scans) and the occupancy grid of the same scans
(floorscan.walls.map_stage)."""
from floorscan.core.stage import stage_log
from floorscan.walls.map_stage import write_map_walls

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    counts = write_map_walls(
        smk.input.registered, smk.input.registration, smk.input.get("scans"), smk.params.cfg,
        smk.output.walls, smk.output.grid,
    )
    log.info("map extractor, %s scans: %d scans, %d wall segments", smk.wildcards.scans, counts["n_scans"], counts["n_segments"])

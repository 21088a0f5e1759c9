"""Stage walls, the map extractor: the wall segments of the map of the selected scans
(or of all kept scans) and the occupancy grid of the same scans
(floorscan.walls.map_stage); of all kept scans, the reference map's grid when the rule
gives it (the same cells and settings: not cast again)."""
from floorscan.core.stage import stage_log
from floorscan.walls.map_stage import write_map_walls

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    counts = write_map_walls(
        smk.input.registered, smk.input.registration, smk.input.get("scans"), smk.params.cfg,
        smk.output.walls, smk.output.grid, smk.input.get("reference"),
    )
    log.info("map extractor, %s scans: %d scans, %d wall segments%s", smk.wildcards.scans, counts["n_scans"],
             counts["n_segments"], "; the grid is the reference map's" if smk.input.get("reference") else "")

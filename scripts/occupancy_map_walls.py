"""Stage walls of an occupancy map: the map extractor's wall segments fitted on the map's
occupied cells that face its free space (floorscan.walls.map_stage.map_of_grid)."""
from floorscan.core.stage import stage_log
from floorscan.walls.map_stage import write_occupancy_map_walls

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    out = write_occupancy_map_walls(smk.input.grid, smk.params.cfg, smk.output.walls)
    log.info("%d wall segments -> %s", out["n_segments"], smk.output.walls)

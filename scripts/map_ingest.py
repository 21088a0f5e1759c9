"""Stage ingest of an occupancy map (floorscan.ingest.occupancy_map): the map_server yaml or
the image read into the grid the walls and rooms read, the map as read (map.pgm, map.yaml:
the classes the plan is built on, in the map's own frame) and what was read (map/map.json)."""
from floorscan.core.stage import stage_log
from floorscan.core.map_info import map_line
from floorscan.ingest.occupancy_map import write_map_ingest

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    info = write_map_ingest(smk.params.path, smk.params.resolution_m, smk.output.grid, smk.output.map_pgm,
                            smk.output.map_yaml, smk.output.info)
    log.info("detected: %s", map_line(info))

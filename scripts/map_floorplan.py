"""Stage floorplan of an occupancy map: the map's walls through the structure passes and the
room step on the map's grid, as results/<dataset>/floorplan.* in every export format and as
Parquet tables (plan_tables/) (floorscan.floorplan.writer.write_map_floorplan)."""
from floorscan.core.stage import stage_log
from floorscan.floorplan.writer import write_map_floorplan

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    outputs = {k: v for k, v in smk.output.items() if k != "plan"}  # by format
    plan = write_map_floorplan(smk.input.walls, smk.input.grid, outputs, smk.params.cfg, smk.wildcards.dataset,
                               plan_folder=smk.output.plan)
    log.info("floor plan of the occupancy map: %d walls, %d clutter, %d junctions, %d rooms, %d doors -> %s",
             len(plan.walls), len(plan.clutter), len(plan.junctions), len(plan.rooms), len(plan.doors),
             ", ".join(outputs.values()))

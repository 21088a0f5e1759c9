"""Stage floorplan, the evaluation's plan of all kept scans: the map extractor's walls of
every kept scan through the structure passes (floorscan.floorplan.writer), SVG for people, and
its Parquet tables, what the score stage reads (rooms as WKB; floorscan.floorplan.scans.write_plan),
with the number of kept scans: it is also the last point of the answer's curve (rule answer_floorplans)."""
from floorscan.core.io import read_metadata, read_table
from floorscan.core.occupancy import read_grid
from floorscan.core.stage import stage_log
from floorscan.floorplan.metadata import recording_timestamp
from floorscan.floorplan.plan import PLAN_MEMORY
from floorscan.floorplan.scans import write_plan
from floorscan.floorplan.writer import FloorplanWriter

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    walls = read_table(smk.input.walls)
    n_scans = read_metadata(smk.input.walls).get("n_scans", "")
    plan, _ = FloorplanWriter(smk.params.cfg).write(
        walls, {k: v for k, v in smk.output.items() if k != "plan"}, dataset=smk.wildcards.dataset, ordering="all", extractor="map", k="all",
        timestamp=recording_timestamp(smk.input.index), grid=read_grid(smk.input.grid, PLAN_MEMORY, f"the floor plan on the grid {smk.input.grid}"),
    )
    write_plan(plan, smk.output.plan, {"dataset": smk.wildcards.dataset, "ordering": "all", "extractor": "map", "k": "all",
                                       "n_scans": n_scans})
    log.info("plan of all kept scans (map extractor): %d walls, %d clutter, %d junctions",
             len(plan.walls), len(plan.clutter), len(plan.junctions))

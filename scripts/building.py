"""Building: the floors of one building (config `building`), each the recommended plan of
its recording (floorscan.floorplan.writer.recommended_plan), as one IFC with a storey per
floor, a GeoJSON per floor and the building's page (floorscan.floorplan.building)."""
from pathlib import Path

from floorscan.core.stage import stage_log
from floorscan.floorplan.building import Floor, write_building
from floorscan.floorplan.writer import recommended_plan

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    floors = [Floor(f["dataset"], f["storey"], f["elevation_m"]) for f in smk.params.floors]
    plans, metadata = {}, {}
    for i, (floor, how) in enumerate(zip(floors, smk.params.plans)):
        rec = recommended_plan(
            smk.input.scans[i], smk.input.walls[i], smk.input.index[i], how["cfg"], floor.dataset, how["ordering"],
            how["extractor"], grid_path=smk.input.grid[i],
        )
        plans[floor.dataset], metadata[floor.dataset] = rec.plan, rec.metadata
        log.info("%s (%s, %.2f m): %d walls, %d rooms, %d doors", floor.storey, floor.dataset, floor.elevation_m,
                 len(rec.plan.walls), len(rec.plan.rooms), len(rec.plan.doors))
    files = write_building(floors, plans, Path(smk.output.ifc).parent, smk.params.name, metadata)
    log.info("building %s of %d floors -> %s", smk.params.name, len(floors), ", ".join([files["ifc"], files["page"]]))

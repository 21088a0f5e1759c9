"""Building: the floors of one building (config `building`), each its dataset's answer as
the floor plan stage wrote it (results/<dataset>/plan_tables, read with
floorscan.floorplan.scans.read_plan), as one IFC with a storey per floor, a GeoJSON per
floor and the building's page (floorscan.floorplan.building)."""
from pathlib import Path

from floorscan.core.stage import stage_log
from floorscan.floorplan.building import Floor, write_building
from floorscan.floorplan.scans import plan_metadata, read_plan

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    floors = [Floor(f["dataset"], f["storey"], f["elevation_m"]) for f in smk.params.floors]
    plans, metadata = {}, {}
    for floor, folder in zip(floors, smk.input.plan):
        plan, meta = read_plan(folder), plan_metadata(folder)
        plans[floor.dataset], metadata[floor.dataset] = plan, meta
        log.info("%s (%s, %.2f m): %d walls, %d rooms, %d doors", floor.storey, floor.dataset, floor.elevation_m,
                 len(plan.walls), len(plan.rooms), len(plan.doors))
        if meta.timestamp is None and meta.ordering:  # a recording's plan (a map's has no ordering)
            log.warning("%s: %s holds no time stamp (written before floorscan stored one, or the recording has "
                        "none); the building takes the other floors' or SOURCE_DATE_EPOCH. To stamp it with the "
                        "recording's first scan: snakemake -R recommended_floorplan", floor.dataset, folder)
    files = write_building(floors, plans, Path(smk.output.ifc).parent, smk.params.name, metadata)
    log.info("building %s of %d floors -> %s", smk.params.name, len(floors), ", ".join([files["ifc"], files["page"]]))

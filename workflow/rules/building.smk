# The floors of one building (floorscan.floorplan.building): config `building` names the
# building and its floors, each a dataset of the run (resolved by
# floorscan.core.datasets.resolve_building to building.floors[i].{dataset, storey, elevation_m}).
#
#   building:   results/building/building.ifc (an IfcBuildingStorey per floor, at its
#               elevation), results/building/<dataset>.geojson per floor, and the page
#               results/building/index.html (thumbnails ../<dataset>/floorplan.svg, links
#               ../<dataset>/front.html). Each floor is its dataset's answer as the
#               recommended_floorplan (or map_floorplan) rule wrote it,
#               results/<dataset>/plan_tables/, read, not built again: a recording's
#               selected scans or an occupancy map. The floors are not registered to each other.


def building_inputs(wildcards):
    """Per floor (lists in floor order): its plan tables (results/<dataset>/plan_tables)
    and its floorplan.svg (the page's thumbnail)."""
    floors = [f["dataset"] for f in building_floors()]
    return {
        "plan": [f"results/{ds}/plan_tables" for ds in floors],
        "svg": [f"results/{ds}/floorplan.svg" for ds in floors],
    }


if building_floors():

    rule building:
        input:
            unpack(building_inputs),
        output:
            **building_files(BUILDING_DIR, [f["dataset"] for f in building_floors()]),
        params:
            floors=building_floors(),
            name=config["building"]["name"],
        log:
            f"{BUILDING_DIR}/logs/building.log",
        benchmark:
            f"{BUILDING_DIR}/benchmarks/building.tsv"
        script:
            "../../scripts/building.py"

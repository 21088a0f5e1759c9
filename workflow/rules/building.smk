# The floors of one building (floorscan.floorplan.building): config `building` names the
# building and its floors, each a dataset of the run (resolved by
# floorscan.core.datasets.resolve_building to building.floors[i].{dataset, storey, elevation_m}).
#
#   building:   results/building/building.ifc (an IfcBuildingStorey per floor, at its
#               elevation), results/building/<dataset>.geojson per floor, and the page
#               results/building/index.html (thumbnails ../<dataset>/floorplan.svg, links
#               ../<dataset>/front.html). Each floor is its dataset's recommended plan,
#               built again from the recommended_floorplan inputs; the floors are not
#               registered to each other.
from types import SimpleNamespace


def building_inputs(wildcards):
    """Per floor (lists in floor order): its recommended_floorplan inputs and its
    floorplan.svg (the page's thumbnail)."""
    inputs = {"svg": []}
    for f in building_floors():
        floor = SimpleNamespace(dataset=f["dataset"])
        for key, path in recommended_floorplan_inputs(floor).items():
            inputs.setdefault(key, []).append(path)
        inputs["svg"].append(f"results/{f['dataset']}/floorplan.svg")
    return inputs


def building_plans(wildcards):
    """Per floor, how its recommended plan is built: its dataset's floorplan section, the
    ordering and the extractor (as recommended_floorplan's params)."""
    plans = []
    for f in building_floors():
        floor = SimpleNamespace(dataset=f["dataset"])
        plans.append({
            "cfg": stage_config("floorplan")(floor),
            "ordering": select_default_ordering(floor),
            "extractor": plan_extractor(floor),
        })
    return plans


_MAP_FLOORS = [f["dataset"] for f in building_floors() if f["dataset"] in MAP_DATASETS]
if _MAP_FLOORS:
    config_error(
        f"building.floors: {', '.join(_MAP_FLOORS)} is an occupancy map; a building's floors are rebuilt from "
        "their recordings' selected scans, which a map does not have: run the maps without `building`"
    )

if building_floors():

    rule building:
        input:
            unpack(building_inputs),
        output:
            **building_files(BUILDING_DIR, [f["dataset"] for f in building_floors()]),
        params:
            floors=building_floors(),
            plans=building_plans,
            name=config["building"]["name"],
        log:
            f"{BUILDING_DIR}/logs/building.log",
        benchmark:
            f"{BUILDING_DIR}/benchmarks/building.tsv"
        script:
            "../../scripts/building.py"

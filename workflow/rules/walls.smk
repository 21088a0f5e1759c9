# Wall extraction (issue 6; thesis sections 3.4, 5.3, Algorithm 4; floorscan.walls).
#
#   scan_walls_shard: every kept scan once per extractor (walls of a scan depend only
#               on the scan, the extractor parameters and the seed, never on ordering
#               or k), in shards of scans (named once the register checkpoint ends)
#   walls:      the shards merged in scan order (the per-scan tables), and the wall
#               segments of the first k scans of each ordering (a filter)
# The floor plans made of them: floorplan.smk.

from floorscan.core.config import stage_params
from floorscan.core.occupancy import OccupancyParams
from floorscan.walls.map_stage import map_grid_params

# The evaluation's walls: the k tables of every ordering x extractor x k of the config.
EVALUATION_OUTPUTS.extend(
    expand(
        "results/{{dataset}}/walls/{ordering}/{extractor}/k{k}.parquet",
        ordering=config["walls"]["orderings"], extractor=config["walls"]["extractors"], k=walls_k_names(),
    )
)


def walls_shard_scans(wildcards):
    return stage_config("walls")(wildcards)["shard_scans"]


def scan_walls_shards(wildcards):
    """The extractor's shard files of the plan (known once the register checkpoint has
    ended), and the register stage's files the plan comes from."""
    shard = "results/{dataset}/shards/walls/{extractor}/{shard}/{name}.parquet"
    labels = shard_labels(wildcards, "walls")
    files = {
        name: [shard.format(dataset=wildcards.dataset, extractor=wildcards.extractor, shard=s, name=name) for s in labels]
        for name in ("per_scan", "scan_status")
    }
    times = "results/{dataset}/benchmarks/shards/walls/{extractor}/{shard}/times.parquet"
    return {
        "shard_walls": files["per_scan"],
        "shard_status": files["scan_status"],
        "shard_times": [times.format(dataset=wildcards.dataset, extractor=wildcards.extractor, shard=s) for s in labels],
        "registered": f"results/{wildcards.dataset}/registered.parquet",
        "registration": f"results/{wildcards.dataset}/registration.parquet",
    }


def walls_inputs(wildcards):
    """Inputs of `walls`: the extractor's per-scan walls (scan_walls) and the orderings."""
    ds, e = wildcards.dataset, wildcards.extractor
    orderings = [f"results/{ds}/orderings/{o}.parquet" for o in config["walls"]["orderings"]]
    return {"walls": f"results/{ds}/walls/{e}/per_scan.parquet", "orderings": orderings}


# Sharding (issue 8): the walls of a scan depend only on the scan and (seed, scan_id), so
# the scans are split by scan range into shards of <= walls.shard_scans kept scans, one
# job each, concatenated in scan order by `walls` into the unsharded tables. The
# shards are known once the register checkpoint has ended (shard_plan, common.smk).
rule scan_walls_shard:
    priority: shard_priority
    input:
        points="results/{dataset}/registered.parquet",
    output:
        walls="results/{dataset}/shards/walls/{extractor}/{shard}/per_scan.parquet",
        status="results/{dataset}/shards/walls/{extractor}/{shard}/scan_status.parquet",
        # the time of each scan, beside the benchmark files: it changes from run to run
        times="results/{dataset}/benchmarks/shards/walls/{extractor}/{shard}/times.parquet",
    wildcard_constraints:
        extractor=WALLS_CONSTRAINTS["extractor"],
    params:
        cfg=walls_extract_config,
    log:
        "results/{dataset}/logs/scan_walls_shard_{extractor}_{shard}.log",
    benchmark:
        "results/{dataset}/benchmarks/scan_walls_shard_{extractor}_{shard}.tsv"
    script:
        "../../scripts/scan_walls_shard.py"


def walls_run_params(wildcards):
    """What the `walls` job of an extractor writes: orderings and k labels."""
    return {"orderings": list(config["walls"]["orderings"]), "k": walls_k_names()}


# Per dataset and extractor: the shards merged into the extractor's per-scan tables
# (scan_walls, floorscan.walls.shards), then the first k scans of each ordering, a
# cheap filter (walls, floorscan.walls.first_k), so the 50 tables of an extractor
# (default config) come from one process. Per extractor, not per dataset, so that the
# faster extractor's walls, floor plans and scores run while the other's shards are
# still being extracted. The walls stage merges its own shards: the per-scan walls of
# every kept scan, which the wall_coverage ordering (select_coverage) reads before the
# k tables are cut.
rule scan_walls:
    priority: PRIORITY["scan_walls"]
    input:
        unpack(scan_walls_shards),
    output:
        walls="results/{dataset}/walls/{extractor}/per_scan.parquet",
        status="results/{dataset}/walls/{extractor}/scan_status.parquet",
        times="results/{dataset}/benchmarks/scan_walls_{extractor}_times.parquet",  # Fig. 5.10
    wildcard_constraints:
        extractor=WALLS_CONSTRAINTS["extractor"],
    params:
        shard_scans=walls_shard_scans,
    log:
        "results/{dataset}/logs/scan_walls_{extractor}.log",
    benchmark:
        "results/{dataset}/benchmarks/scan_walls_{extractor}.tsv"
    script:
        "../../scripts/scan_walls.py"


rule walls:
    priority: PRIORITY["walls"]
    input:
        unpack(walls_inputs),
    output:
        tables=expand(
            "results/{{dataset}}/walls/{ordering}/{{extractor}}/k{k}.parquet",
            ordering=config["walls"]["orderings"], k=walls_k_names(),
        ),
    wildcard_constraints:
        extractor=WALLS_CONSTRAINTS["extractor"],
    params:
        run=walls_run_params,
    log:
        "results/{dataset}/logs/walls_{extractor}.log",
    benchmark:
        "results/{dataset}/benchmarks/walls_{extractor}.tsv"
    script:
        "../../scripts/walls.py"


def map_walls_inputs(wildcards):
    """The registered scans; for the selected scans their list; for all kept scans the
    reference map (rule reference), whose grid is theirs when the reference's settings
    (score.reference) are the map extractor's (floorscan.walls.map_stage.map_grid_params):
    all kept scans are then cast once."""
    ds = wildcards.dataset
    inputs = {"registered": f"results/{ds}/registered.parquet", "registration": f"results/{ds}/registration.parquet"}
    if wildcards.scans == "selected":
        inputs["scans"] = f"results/{ds}/selection/scans.parquet"
    elif map_grid_params(stage_config("walls")(wildcards)) == stage_params(OccupancyParams, reference_config(wildcards)):
        inputs["reference"] = f"results/{ds}/reference/occupancy.parquet"
    return inputs


# The map extractor (floorscan.walls.map_lines): walls fitted on the map of the selected
# scans (the answer's floor plan) or of all kept scans (the evaluation), with the
# occupancy grid of the same scans that the floor plan's structure passes read.
rule map_walls:
    priority: PRIORITY["floorplan"]
    input:
        unpack(map_walls_inputs),
    output:
        walls="results/{dataset}/walls/map/{scans}.parquet",
        grid="results/{dataset}/walls/map/{scans}_grid.parquet",
    wildcard_constraints:
        scans="selected|all",
    params:
        cfg=walls_map_config,
    log:
        "results/{dataset}/logs/map_walls_{scans}.log",
    benchmark:
        "results/{dataset}/benchmarks/map_walls_{scans}.tsv"
    script:
        "../../scripts/map_walls.py"


# The walls of an occupancy map given as the recording (floorscan.walls.map_stage.map_of_grid).
rule occupancy_map_walls:
    wildcard_constraints:
        dataset=MAP_DATASET,
    input:
        grid="results/{dataset}/map/grid.parquet",
    output:
        walls="results/{dataset}/walls/map/map.parquet",
    params:
        cfg=walls_map_config,
    log:
        log_path("walls"),
    benchmark:
        benchmark_path("walls")
    script:
        "../../scripts/occupancy_map_walls.py"

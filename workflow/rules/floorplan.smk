# Floor plans (floorscan.floorplan; thesis Chapter 1's purpose): merged walls, one wall
# per wall with its thickness, in every export format of floorscan.floorplan.EXPORT_FORMATS
# (GeoJSON, SVG, DXF, IFC; a file's suffix is its format's).
#
#   recommended_floorplan: the answer, results/<dataset>/floorplan.* (and plan_tables/, the
#               same plan as Parquet tables for programs, floorscan.core.plan_tables): the walls of the
#               scans of selection/scans.parquet (select.default_ordering, select.k) by
#               floorplan.extractor; map.pgm + map.yaml: their occupancy grid for Nav2
#   floorplan:  the evaluation grid: the plan of the first k scans of every ordering x k
#               of walls.k, one job per extractor (floorscan.floorplan.grid), as Parquet
#               tables, evaluation/plans/<ordering>_<extractor>_k<k>/ (what the score
#               stage reads), and in the formats of floorscan.floorplan.EVALUATION_FORMATS for
#               people, evaluation/floorplan/<ordering>_<extractor>_k<k>.*
#   answer_floorplans: the answer's plan of the first k scans of the default ordering on
#               the answer curve's k grid, evaluation/answer_plans/k<k>/ (what the score
#               stage's answer_curve reads), built by ANSWER_PLAN_PARTS jobs
#               (answer_floorplans_part, a share of the k grid each) and merged
from floorscan.floorplan import EVALUATION_FORMATS, EXPORT_FORMATS, FLOORPLAN_FORMATS, floorplan_outputs
from floorscan.floorplan.answer_plans import ANSWER_PLAN_PARTS

# The file suffixes of the evaluation grid's formats (SVG, for people).
EVALUATION_SUFFIXES = [EXPORT_FORMATS[fmt].suffix for fmt in EVALUATION_FORMATS]


def floorplan_grid_inputs(wildcards):
    ds = wildcards.dataset
    return {
        "walls": f"results/{ds}/walls/{wildcards.extractor}/per_scan.parquet",
        "orderings": [f"results/{ds}/orderings/{o}.parquet" for o in config["walls"]["orderings"]],
        "index": f"results/{ds}/scan_index.parquet",
    }


def floorplan_grid_runs(wildcards):
    return [[o, k] for o in config["walls"]["orderings"] for k in walls_k_names()]


rule recommended_floorplan:
    priority: PRIORITY["floorplan"]
    wildcard_constraints:
        dataset=SCAN_DATASET,
    input:
        unpack(recommended_floorplan_inputs),
    output:
        **floorplan_outputs("results/{dataset}/floorplan", FLOORPLAN_FORMATS),
        plan=directory("results/{dataset}/plan_tables"),  # the same plan as Parquet tables, map frame
        map_pgm="results/{dataset}/map.pgm",
        map_yaml="results/{dataset}/map.yaml",
    params:
        cfg=stage_config("floorplan"),
        extractor=plan_extractor,
        ordering=select_default_ordering,
    log:
        log_path("recommended_floorplan"),
    benchmark:
        benchmark_path("recommended_floorplan")
    script:
        "../../scripts/recommended_floorplan.py"


rule floorplan:
    priority: PRIORITY["floorplan"]
    input:
        unpack(floorplan_grid_inputs),
    output:
        plans=[
            directory(p) for p in expand(
                "results/{{dataset}}/evaluation/plans/{ordering}_{{extractor}}_k{k}",
                ordering=config["walls"]["orderings"], k=walls_k_names(),
            )
        ],
        exports=expand(
            "results/{{dataset}}/evaluation/floorplan/{ordering}_{{extractor}}_k{k}{suffix}",
            ordering=config["walls"]["orderings"], k=walls_k_names(),
            suffix=EVALUATION_SUFFIXES,
        ),
    wildcard_constraints:
        extractor=WALLS_CONSTRAINTS["extractor"],
    params:
        cfg=floorplan_grid_config,
        runs=floorplan_grid_runs,
        orderings=config["walls"]["orderings"],
        formats=list(EVALUATION_FORMATS),
    log:
        "results/{dataset}/logs/floorplan_{extractor}.log",
    benchmark:
        "results/{dataset}/benchmarks/floorplan_{extractor}.tsv"
    script:
        "../../scripts/floorplan.py"


# The plan of the map of all kept scans, with the structure passes: what the recording
# can give at most (scored by score_answer, score_rooms and score_drawn beside the
# recommended plan, from its Parquet tables); SVG for people, as the grid's plans.
rule all_scans_floorplan:
    priority: PRIORITY["floorplan"]
    input:
        walls="results/{dataset}/walls/map/all.parquet",
        grid="results/{dataset}/walls/map/all_grid.parquet",
        index="results/{dataset}/scan_index.parquet",
    output:
        **floorplan_outputs("results/{dataset}/evaluation/floorplan/all_scans_map", ["svg"]),
        plan=directory("results/{dataset}/evaluation/plans/all_scans_map"),
    params:
        cfg=floorplan_grid_config,
    log:
        "results/{dataset}/logs/all_scans_floorplan.log",
    benchmark:
        "results/{dataset}/benchmarks/all_scans_floorplan.tsv"
    script:
        "../../scripts/all_scans_floorplan.py"


def answer_floorplans_inputs(wildcards):
    ds = wildcards.dataset
    return {
        "registered": f"results/{ds}/registered.parquet",
        "registration": f"results/{ds}/registration.parquet",
        "ordering": f"results/{ds}/orderings/{select_default_ordering(wildcards)}.parquet",
    }


# The answer's plans of the first k scans (floorscan.floorplan.answer_plans): the plan the
# answer is made with (the map extractor's walls, the structure passes) of the first k
# scans of the default ordering, for k on a geometric grid, as Parquet tables
# (evaluation/answer_plans/k<k>/); the occupancy grid of k + dk scans is that of k plus
# dk scans. They are the evaluation's longest job on a large recording, so
# ANSWER_PLAN_PARTS jobs build a share of the k grid each (on both cores), and
# answer_floorplans moves their plan folders into one. The last k, all kept scans, is
# the plan of all_scans_floorplan (the same plan, built once), which answer_floorplans
# copies in. The score stage's answer_curve scores them.
rule answer_floorplans_part:
    priority: PRIORITY["answer_floorplans"]
    input:
        unpack(answer_floorplans_inputs),
    output:
        plans=temp(directory("results/{dataset}/evaluation/answer_plans_parts/{part}")),
    wildcard_constraints:
        part=r"\d+",
    params:
        walls=walls_map_config,
        floorplan=floorplan_grid_config,
        ordering=select_default_ordering,
        parts=ANSWER_PLAN_PARTS,
    log:
        "results/{dataset}/logs/answer_floorplans_part{part}.log",
    benchmark:
        "results/{dataset}/benchmarks/answer_floorplans_part{part}.tsv"
    script:
        "../../scripts/answer_floorplans_part.py"


rule answer_floorplans:
    priority: PRIORITY["answer_floorplans"]
    input:
        parts=expand("results/{{dataset}}/evaluation/answer_plans_parts/{part}", part=range(ANSWER_PLAN_PARTS)),
        all_scans="results/{dataset}/evaluation/plans/all_scans_map",
    output:
        plans=directory("results/{dataset}/evaluation/answer_plans"),
    log:
        log_path("answer_floorplans"),
    benchmark:
        benchmark_path("answer_floorplans")
    script:
        "../../scripts/answer_floorplans.py"


# The plan of an occupancy map given as the recording: its walls on its grid, every
# export and the Parquet tables, as the recommended plan's (floorscan.floorplan.writer.write_map_floorplan).
rule map_floorplan:
    priority: PRIORITY["floorplan"]
    wildcard_constraints:
        dataset=MAP_DATASET,
    input:
        walls="results/{dataset}/walls/map/map.parquet",
        grid="results/{dataset}/map/grid.parquet",
    output:
        **floorplan_outputs("results/{dataset}/floorplan", FLOORPLAN_FORMATS),
        plan=directory("results/{dataset}/plan_tables"),
    params:
        cfg=stage_config("floorplan"),
    log:
        log_path("recommended_floorplan"),
    benchmark:
        benchmark_path("recommended_floorplan")
    script:
        "../../scripts/map_floorplan.py"


_PLAN_FILES = [*floorplan_outputs("results/{dataset}/floorplan", FLOORPLAN_FORMATS).values(), "results/{dataset}/plan_tables"]
MAP_PLAN_OUTPUTS.extend(_PLAN_FILES)  # map.pgm, map.yaml: map_ingest's
PLAN_OUTPUTS.extend([*_PLAN_FILES, "results/{dataset}/map.pgm", "results/{dataset}/map.yaml"])
EVALUATION_OUTPUTS.extend(floorplan_outputs("results/{dataset}/evaluation/floorplan/all_scans_map", ["svg"]).values())
EVALUATION_OUTPUTS.append("results/{dataset}/evaluation/plans/all_scans_map")
EVALUATION_OUTPUTS.extend(
    expand(
        "results/{{dataset}}/evaluation/plans/{ordering}_{extractor}_k{k}",
        ordering=config["walls"]["orderings"], extractor=config["walls"]["extractors"], k=walls_k_names(),
    )
)
EVALUATION_OUTPUTS.extend(
    expand(
        "results/{{dataset}}/evaluation/floorplan/{ordering}_{extractor}_k{k}{suffix}",
        ordering=config["walls"]["orderings"], extractor=config["walls"]["extractors"],
        k=walls_k_names(), suffix=EVALUATION_SUFFIXES,
    )
)

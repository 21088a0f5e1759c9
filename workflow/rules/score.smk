# Scoring (thesis Chapter 5): metrics of the walls of every ordering x extractor x k
# against the ground truth (synthetic datasets) or the reference (real recordings: the
# walls of the same extractor from all kept scans), and of every floor plan against the
# reference map (rule reference: the occupancy grid of all kept scans), and the
# scan-reduction summary. The Chapter 5 figures of the report: figures.smk.
import re

from floorscan.score.ground_truth import reference_label
from floorscan.score.runs import run_grid


def score_run_tables(wildcards):
    """The scores table of every extractor (rule score_runs)."""
    evaluation_grid_check()  # the summary reads the all-scan k
    return [f"results/{wildcards.dataset}/score/{e}.parquet" for e in score_extractors(wildcards)]


def score_curve_tables(wildcards):
    """The quality-vs-k curves of every extractor (rule score_curves)."""
    return [f"results/{wildcards.dataset}/score/curves_{e}.parquet" for e in score_extractors(wildcards)]


def score_extractor_runs(wildcards):
    """[ordering, extractor, k label] of the wall files of one extractor, in input order
    (floorscan.score.runs.run_grid)."""
    runs = run_grid(score_orderings(wildcards), score_extractors(wildcards), score_ks(wildcards))
    return [r for r in runs if r[1] == wildcards.extractor]


def score_reference_label(wildcards):
    """Wording for captions (floorscan.score.ground_truth.reference_label)."""
    return reference_label(score_reference_kind(wildcards))


def score_runs_inputs(wildcards):
    evaluation_grid_check()
    ds = wildcards.dataset
    runs = score_extractor_runs(wildcards)
    return {
        "walls": [f"results/{ds}/walls/{o}/{e}/k{k}.parquet" for o, e, k in runs],
        "floorplans": [f"results/{ds}/evaluation/plans/{o}_{e}_k{k}" for o, e, k in runs],
        "orderings": [f"results/{ds}/orderings/{o}.parquet" for o in score_orderings(wildcards)],
        "reference_map": f"results/{ds}/reference/occupancy.parquet",
        **score_reference_inputs(wildcards),
    }


def reference_config(wildcards):
    """The score.reference section (the occupancy grid's settings)."""
    return dict(stage_config("score")(wildcards).get("reference") or {})


def reference_inputs(wildcards):
    ds = wildcards.dataset
    inputs = {
        "registered": f"results/{ds}/registered.parquet",
        "registration": f"results/{ds}/registration.parquet",
    }
    if is_synthetic(ds):  # the reference itself is scored against the true walls
        inputs["ground_truth"] = f"results/{ds}/sim/walls.geojson"
    return inputs


# The reference map: the occupancy grid of all kept scans (floorscan.score.reference),
# what every floor plan is scored against by completeness and correctness (map_*).
rule reference:
    priority: PRIORITY["reference"]
    input:
        unpack(reference_inputs),
    output:
        pgm="results/{dataset}/reference/map.pgm",
        yaml="results/{dataset}/reference/map.yaml",
        cells="results/{dataset}/reference/occupancy.parquet",
        figure=report(
            "results/{dataset}/figures/reference_map.png",
            caption="../report/reference_map.rst",
            category="Scoring",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "Reference map (occupancy grid of all kept scans)"},
        ),
    params:
        cfg=reference_config,
        walls=stage_config("walls"),
    log:
        log_path("reference"),
    benchmark:
        benchmark_path("reference")
    script:
        "../../scripts/reference.py"


# One job per extractor scores its orderings x k as soon as its floor plans exist, while
# the other extractor's plans are still being made; `score` merges the tables (the same
# table as one job over all runs, tested) and writes the summary.
rule score_runs:
    priority: PRIORITY["score_runs"]
    input:
        unpack(score_runs_inputs),
    output:
        metrics="results/{dataset}/score/{extractor}.parquet",
    wildcard_constraints:
        extractor=WALLS_CONSTRAINTS["extractor"],
    params:
        cfg=stage_config("score"),
        runs=score_extractor_runs,
        orderings=score_orderings,
        extractors=score_extractors,
        reference_kind=score_reference_kind,
        reference_label=score_reference_label,
    # orderings scored in this many processes (capped at --cores); same table
    threads: 1
    log:
        "results/{dataset}/logs/score_runs_{extractor}.log",
    benchmark:
        "results/{dataset}/benchmarks/score_runs_{extractor}.tsv"
    script:
        "../../scripts/score_runs.py"


def score_curves_inputs(wildcards):
    evaluation_grid_check()
    ds = wildcards.dataset
    return {
        "walls": f"results/{ds}/walls/{wildcards.extractor}/per_scan.parquet",
        "orderings": [f"results/{ds}/orderings/{o}.parquet" for o in score_orderings(wildcards)],
        "reference_map": f"results/{ds}/reference/occupancy.parquet",
    }


# Quality against k (floorscan.score.curves): the plan of the first k scans of every
# ordering, random's seeds and the completeness oracle against the reference map, on a
# k grid of 2 % of the kept scans; one job per extractor.
rule score_curves:
    priority: PRIORITY["score_curves"]
    input:
        unpack(score_curves_inputs),
    output:
        curves="results/{dataset}/score/curves_{extractor}.parquet",
        oracle="results/{dataset}/score/oracle_{extractor}.parquet",
    wildcard_constraints:
        extractor=WALLS_CONSTRAINTS["extractor"],
    params:
        cfg=stage_config("score"),
        orderings=score_orderings,
        floorplan=stage_config("floorplan"),
    log:
        "results/{dataset}/logs/score_curves_{extractor}.log",
    benchmark:
        "results/{dataset}/benchmarks/score_curves_{extractor}.tsv"
    script:
        "../../scripts/score_curves.py"


rule score:
    priority: PRIORITY["score"]
    input:
        runs=score_run_tables,
        curves=score_curve_tables,
        registration="results/{dataset}/registration.parquet",
        index="results/{dataset}/scan_index.parquet",  # what ingest detected
    output:
        metrics="results/{dataset}/metrics.parquet",
        summary="results/{dataset}/summary.parquet",
        summary_html="results/{dataset}/summary.html",  # the table is on the front page
        quality_vs_k=report(
            "results/{dataset}/figures/floorplan_f1_vs_k.png",
            caption="../report/quality_vs_k.rst",
            category="Scoring",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "Floor-plan F1 against the number of scans, every ordering and the oracle"},
        ),
        summary_md="results/{dataset}/evaluation/summary.md",  # the evaluation's part of summary.md
    params:
        cfg=stage_config("score"),
        reference_kind=score_reference_kind,
        reference_label=score_reference_label,
        default_ordering=select_default_ordering,
    log:
        log_path("score"),
    benchmark:
        benchmark_path("score")
    script:
        "../../scripts/score.py"


EVALUATION_OUTPUTS.extend(
    [
        "results/{dataset}/metrics.parquet",
        "results/{dataset}/summary.parquet",
        "results/{dataset}/evaluation/summary.md",
    ]
)


def score_answer_inputs(wildcards):
    ds = wildcards.dataset
    inputs = {
        "recommended": f"results/{ds}/plan_tables",  # the plans as Parquet tables (floorscan.core.plan_tables)
        "all_scans_map": f"results/{ds}/evaluation/plans/all_scans_map",
        "reference": f"results/{ds}/reference/occupancy.parquet",
    }
    if is_synthetic(ds):
        inputs["ground_truth"] = f"results/{ds}/sim/walls.geojson"
    return inputs


# How good the answer is (floorscan.score.answer): the recommended plan and the plan of
# the map of all kept scans, against the reference map and, on a synthetic recording,
# the true walls, corners and wall count.
rule score_answer:
    priority: PRIORITY["score_runs"]
    input:
        unpack(score_answer_inputs),
    output:
        table="results/{dataset}/evaluation/answer_scores.csv",
    log:
        log_path("score_answer"),
    benchmark:
        benchmark_path("score_answer")
    script:
        "../../scripts/score_answer.py"


EVALUATION_OUTPUTS.append("results/{dataset}/evaluation/answer_scores.csv")


# The quality curve of the plan the answer is made with (floorscan.score.answer_curve):
# the answer's plans of the first k scans of the default ordering (rule
# answer_floorplans, evaluation/answer_plans/k<k>/) against the reference map; its k95 /
# k99 are what select.k: auto is measured against.
rule answer_curve:
    priority: PRIORITY["score_runs"]
    input:
        plans="results/{dataset}/evaluation/answer_plans",
        reference="results/{dataset}/reference/occupancy.parquet",
    output:
        curve="results/{dataset}/evaluation/answer_curve.csv",
    log:
        log_path("answer_curve"),
    benchmark:
        benchmark_path("answer_curve")
    script:
        "../../scripts/answer_curve.py"


EVALUATION_OUTPUTS.append("results/{dataset}/evaluation/answer_curve.csv")


# The room scores and their overlay, of every dataset: score_drawn's for the datasets
# that name a drawn plan, score_rooms' for the others.
ROOM_OUTPUTS = ["results/{dataset}/evaluation/room_scores.csv", "results/{dataset}/figures/rooms_overlay.png"]
# The datasets that name a plan drawn by people (config datasets.<name>.reference):
# score_drawn scores them, rooms included; score_rooms the others.
DRAWN_DATASETS = sorted(d for d in DATASETS if DATASETS[d].get("reference"))


def drawn_reference(wildcards):
    """The dataset's plan drawn by people (config datasets.<name>.reference)."""
    return DATASETS[wildcards.dataset].get("reference") or {}


def score_drawn_inputs(wildcards):
    ds, reference = wildcards.dataset, drawn_reference(wildcards)
    inputs = {
        "recommended": f"results/{ds}/plan_tables",  # the plans as Parquet tables (floorscan.core.plan_tables)
        "all_scans_map": f"results/{ds}/evaluation/plans/all_scans_map",
        "reference": f"results/{ds}/reference/occupancy.parquet",
        "drawn": reference["plan"],
    }
    if reference.get("rooms"):  # the rooms drawn by people, same pixel frame
        inputs["rooms"] = reference["rooms"]
    return inputs


# A plan drawn by people (floorscan.score.drawn), for the datasets that name one:
# aligned to the map frame, the recommended and the all-scan map plans scored against
# it at 10 and 20 cm, and the overlay figure; with the same alignment the plans' rooms
# against the rooms drawn by people (reference: rooms; floorscan.score.rooms), or their
# room counts alone when the dataset names no drawn rooms. The other datasets' room
# scores are score_rooms'.
rule score_drawn:
    priority: PRIORITY["score_runs"]
    input:
        unpack(score_drawn_inputs),
    output:
        table="results/{dataset}/evaluation/drawn_scores.csv",
        figure=report(
            "results/{dataset}/figures/drawn_overlay.png",
            caption="../report/drawn_overlay.rst",
            category="Scoring",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "The plan drawn by people, aligned, with the floor plan"},
        ),
        rooms="results/{dataset}/evaluation/room_scores.csv",
        rooms_figure=report(
            "results/{dataset}/figures/rooms_overlay.png",
            caption="../report/rooms_overlay.rst",
            category="Scoring",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "The floor plan's rooms over the true rooms"},
        ),
    wildcard_constraints:
        dataset="|".join(re.escape(d) for d in DRAWN_DATASETS) or "NO_DRAWN_DATASET",
    params:
        reference=drawn_reference,
    log:
        log_path("score_drawn"),
    benchmark:
        benchmark_path("score_drawn")
    script:
        "../../scripts/score_drawn.py"


def score_rooms_inputs(wildcards):
    ds = wildcards.dataset
    inputs = {
        "recommended": f"results/{ds}/plan_tables",  # the plans as Parquet tables (floorscan.core.plan_tables)
        "all_scans_map": f"results/{ds}/evaluation/plans/all_scans_map",
        "reference": f"results/{ds}/reference/occupancy.parquet",
    }
    if is_synthetic(ds):
        inputs["ground_truth"] = f"results/{ds}/sim/walls.geojson"
    return inputs


# The rooms (floorscan.score.rooms): the recommended and the all-scan map plans' rooms
# and doors against the simulator's true rooms and doors (rooms seen for at least half
# their area count; matched one-to-one at IoU >= 0.5, doors within 0.2 m), or, on a real
# recording without a drawn plan, their counts only; and the overlay figure.
rule score_rooms:
    priority: PRIORITY["score_runs"]
    input:
        unpack(score_rooms_inputs),
    output:
        table=ROOM_OUTPUTS[0],
        figure=report(
            ROOM_OUTPUTS[1],
            caption="../report/rooms_overlay.rst",
            category="Scoring",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "The floor plan's rooms over the true rooms"},
        ),
    wildcard_constraints:
        dataset="|".join(re.escape(d) for d in sorted(DATASETS) if d not in DRAWN_DATASETS) or "NO_DATASET",
    log:
        log_path("score_rooms"),
    benchmark:
        benchmark_path("score_rooms")
    script:
        "../../scripts/score_rooms.py"


EVALUATION_OUTPUTS.extend(ROOM_OUTPUTS)

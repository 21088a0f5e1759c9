# Scoring (thesis Chapter 5): metrics of the walls of every ordering x extractor x k
# against the ground truth (synthetic datasets) or the reference (real recordings: the
# walls of the same extractor from all kept scans), and of every floor plan against the
# reference map (rule reference: the occupancy grid of all kept scans), the
# scan-reduction summary, and the Chapter 5 figures for the report.
import re

stage_schema_check("score")

# The figure k is in the figure file names (floorplans_first_k15.png), so it is global
# (FILE_GRID_KEYS: a per-dataset override is refused).
SCORE_FIGURE_K = config["score"]["figure_k"]


def _walls_section(wildcards):
    return stage_config("walls")(wildcards)


def score_orderings(wildcards):
    """The orderings the walls stage extracts (walls.orderings)."""
    return list(_walls_section(wildcards)["orderings"])


def score_extractors(wildcards):
    return list(_walls_section(wildcards)["extractors"])


def score_run_tables(wildcards):
    """The scores table of every extractor (rule score_runs)."""
    return [f"results/{wildcards.dataset}/score/{e}.parquet" for e in score_extractors(wildcards)]


def score_curve_tables(wildcards):
    """The quality-vs-k curves of every extractor (rule score_curves)."""
    return [f"results/{wildcards.dataset}/score/curves_{e}.parquet" for e in score_extractors(wildcards)]


def score_ks(wildcards):
    return [str(k) for k in _walls_section(wildcards)["k"]]


def score_runs(wildcards):
    """[ordering, extractor, k label] of every wall file scored, in input order."""
    return [
        [o, e, k]
        for o in score_orderings(wildcards)
        for e in score_extractors(wildcards)
        for k in score_ks(wildcards)
    ]


def score_reference_kind(wildcards):
    return "ground_truth" if is_synthetic(wildcards.dataset) else "reference"


def score_reference_label(wildcards):
    """Wording for captions: never call a real recording's reference ground truth."""
    if is_synthetic(wildcards.dataset):
        return "the simulator's ground-truth walls (faces of sim/walls.geojson)"
    return (
        "the reference, the walls extracted by the same extractor from all kept scans "
        "(a reference, not ground truth: the building has no architectural plan)"
    )


def _score_reference_inputs(wildcards):
    ds = wildcards.dataset
    if is_synthetic(ds):
        return {"ground_truth": f"results/{ds}/sim/walls.geojson"}
    cfg = stage_config("score")(wildcards)
    if cfg["reference_source"] == "kall":
        o = cfg["figure_ordering"]
        refs = [f"results/{ds}/walls/{o}/{e}/kall.parquet" for e in score_extractors(wildcards)]
    else:
        refs = [f"results/{ds}/walls/{e}/per_scan.parquet" for e in score_extractors(wildcards)]
    return {"reference": refs}


def score_check(wildcards):
    """Fail before running when the score config disagrees with the walls config."""
    cfg = stage_config("score")(wildcards)
    taus = [float(t) for t in cfg["taus_m"]]
    if not any(abs(float(cfg["summary_tau_m"]) - t) < 1e-12 for t in taus):
        config_error(f"score.summary_tau_m {cfg['summary_tau_m']} is not in score.taus_m {taus}")
    if str(cfg["figure_k"]) not in score_ks(wildcards):
        config_error(f"score.figure_k {cfg['figure_k']} is not in walls.k {score_ks(wildcards)}")
    if "all" not in score_ks(wildcards):
        config_error("walls.k must contain 'all': the summary compares with the all-scan F1")
    return cfg


def score_extractor_runs(wildcards):
    """[ordering, extractor, k label] of the wall files of one extractor, in input order."""
    return [r for r in score_runs(wildcards) if r[1] == wildcards.extractor]


def score_runs_inputs(wildcards):
    ds = wildcards.dataset
    runs = score_extractor_runs(wildcards)
    return {
        "walls": [f"results/{ds}/walls/{o}/{e}/k{k}.parquet" for o, e, k in runs],
        "floorplans": [f"results/{ds}/evaluation/floorplan/{o}_{e}_k{k}.geojson" for o, e, k in runs],
        "orderings": [f"results/{ds}/orderings/{o}.parquet" for o in score_orderings(wildcards)],
        "reference_map": f"results/{ds}/reference/occupancy.parquet",
        **_score_reference_inputs(wildcards),
    }


def score_figure_runs(wildcards):
    """[ordering, extractor, k label] of the raw wall files the figures draw."""
    cfg = score_check(wildcards)
    k = str(cfg["figure_k"])
    orderings = list(dict.fromkeys(list(cfg["figure_orderings"]) + [cfg["figure_ordering"]]))
    runs = []
    for o in orderings:
        for e in score_extractors(wildcards):
            for kk in (k, "all"):
                runs.append([o, e, kk])
    return runs


def score_figure_floorplans(wildcards):
    """[ordering, extractor] of the merged floor plans at figure_k (Fig. 5.5)."""
    cfg = stage_config("score")(wildcards)
    return [[o, cfg["figure_extractor"]] for o in cfg["figure_orderings"]]


def score_bench_dir(wildcards):
    return f"results/{wildcards.dataset}/benchmarks"


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
        cfg=score_check,
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
        cfg=score_check,
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
        cfg=score_check,
        reference_kind=score_reference_kind,
        reference_label=score_reference_label,
        default_ordering=select_default_ordering,
    log:
        log_path("score"),
    benchmark:
        benchmark_path("score")
    script:
        "../../scripts/score.py"


def score_walls_figure_inputs(wildcards):
    ds = wildcards.dataset
    k = str(stage_config("score")(wildcards)["figure_k"])
    return {
        "walls": [f"results/{ds}/walls/{o}/{e}/k{kk}.parquet" for o, e, kk in score_figure_runs(wildcards)],
        "floorplans": [
            f"results/{ds}/evaluation/floorplan/{o}_{e}_k{k}.geojson" for o, e in score_figure_floorplans(wildcards)
        ],
        "registered": f"results/{ds}/registered.parquet",
        "scan_status": [f"results/{ds}/walls/{e}/scan_status.parquet" for e in score_extractors(wildcards)],
        "scan_times": [f"results/{ds}/benchmarks/scan_walls_{e}_times.parquet" for e in score_extractors(wildcards)],
        **_score_reference_inputs(wildcards),
    }


# The figures of walls and floor plans need no metrics: drawn while the runs are scored.
rule score_walls_figures:
    priority: PRIORITY["score_walls_figures"]
    input:
        unpack(score_walls_figure_inputs),
    output:
        floorplan=report(
            f"results/{{dataset}}/figures/floorplans_first_k{SCORE_FIGURE_K}.png",
            caption="../report/floorplan.rst",
            category="Scoring",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": f"Floor plans from the first {SCORE_FIGURE_K} scans of each ordering"},
        ),
        bitmap_overlay=report(
            f"results/{{dataset}}/figures/bitmap_overlay_first_k{SCORE_FIGURE_K}.png",
            caption="../report/bitmap_overlay.rst",
            category="Scoring",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": f"Walls of the first {SCORE_FIGURE_K} scans as a bitmap over the reference"},
        ),
        walls_over_points_k=report(
            f"results/{{dataset}}/figures/walls_over_points_first_k{SCORE_FIGURE_K}.png",
            caption="../report/walls_over_points_k.rst",
            category="Scoring",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": f"Walls from the first {SCORE_FIGURE_K} scans over the registered points"},
        ),
        walls_over_points_all=report(
            "results/{dataset}/figures/walls_over_points_all.png",
            caption="../report/walls_over_points_all.rst",
            category="Scoring",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "Walls from all kept scans over the registered points"},
        ),
        wall_extraction=report(
            "results/{dataset}/figures/wall_extraction_per_scan.png",
            caption="../report/wall_extraction.rst",
            category="Timing",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "Wall extraction per scan, ransac against cluster_ransac"},
        ),
    params:
        cfg=score_check,
        walls_runs=score_figure_runs,
        floorplan_runs=score_figure_floorplans,
        extractors=score_extractors,
        reference_kind=score_reference_kind,
    log:
        "results/{dataset}/logs/score_walls_figures.log",
    benchmark:
        "results/{dataset}/benchmarks/score_walls_figures.tsv"
    script:
        "../../scripts/score_walls_figures.py"


# Last: the time per stage counts every other job's benchmark file, so the other
# figure jobs are inputs too.
rule score_figures:
    priority: PRIORITY["score_figures"]
    input:
        metrics="results/{dataset}/metrics.parquet",
        walls_figures=f"results/{{dataset}}/figures/floorplans_first_k{SCORE_FIGURE_K}.png",
        selection_figures="results/{dataset}/figures/coverage_vs_scans.png",
    output:
        metrics_vs_k=report(
            "results/{dataset}/figures/wall_metrics_vs_k.png",
            caption="../report/metrics_vs_k.rst",
            category="Scoring",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "Wall metrics against the number of scans, per ordering"},
        ),
        stage_times_png=report(
            "results/{dataset}/figures/stage_times.png",
            caption="../report/stage_times.rst",
            category="Timing",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "Time and memory per stage"},
        ),
        stage_times_tsv=report(
            "results/{dataset}/figures/stage_times.tsv",
            caption="../report/stage_times.rst",
            category="Timing",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "Time and memory per stage (table)"},
        ),
    params:
        cfg=score_check,
        bench_dir=score_bench_dir,
    log:
        "results/{dataset}/logs/score_figures.log",
    benchmark:
        "results/{dataset}/benchmarks/score_figures.tsv"
    script:
        "../../scripts/score_figures.py"


EVALUATION_OUTPUTS.extend(
    [
        "results/{dataset}/metrics.parquet",
        "results/{dataset}/summary.parquet",
        "results/{dataset}/evaluation/summary.md",
    ]
    + [
        f"results/{{dataset}}/figures/{name}"
        for name in (
            "wall_metrics_vs_k.png",
            f"floorplans_first_k{SCORE_FIGURE_K}.png",
            f"bitmap_overlay_first_k{SCORE_FIGURE_K}.png",
            f"walls_over_points_first_k{SCORE_FIGURE_K}.png",
            "walls_over_points_all.png",
            "stage_times.png",
            "stage_times.tsv",
            "wall_extraction_per_scan.png",
        )
    ]
)


def score_answer_inputs(wildcards):
    ds = wildcards.dataset
    inputs = {
        "recommended": f"results/{ds}/floorplan.geojson",
        "all_scans_map": f"results/{ds}/evaluation/floorplan/all_scans_map.geojson",
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


def answer_curve_inputs(wildcards):
    ds = wildcards.dataset
    return {
        "registered": f"results/{ds}/registered.parquet",
        "registration": f"results/{ds}/registration.parquet",
        "ordering": f"results/{ds}/orderings/{select_default_ordering(wildcards)}.parquet",
        "reference": f"results/{ds}/reference/occupancy.parquet",
    }


# The quality curve of the plan the answer is made with (floorscan.score.answer_curve):
# the map extractor's plan of the first k scans of the default ordering against the
# reference map, on a geometric k grid; its k95 / k99 are what select.k: auto is
# measured against.
rule answer_curve:
    priority: PRIORITY["score_runs"]
    input:
        unpack(answer_curve_inputs),
    output:
        curve="results/{dataset}/evaluation/answer_curve.csv",
    params:
        walls=walls_map_config,
        floorplan=floorplan_grid_config,
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
        "recommended": f"results/{ds}/floorplan.geojson",
        "all_scans_map": f"results/{ds}/evaluation/floorplan/all_scans_map.geojson",
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


def drawn_outputs():
    """score_drawn's files for the datasets that name a drawn plan (patterns keep {dataset});
    its room scores and overlay are in EVALUATION_OUTPUTS, as every dataset's (score_rooms
    makes them for the other datasets)."""
    return ["results/{dataset}/evaluation/drawn_scores.csv", "results/{dataset}/figures/drawn_overlay.png"]


def score_rooms_inputs(wildcards):
    ds = wildcards.dataset
    inputs = {
        "recommended": f"results/{ds}/floorplan.geojson",
        "all_scans_map": f"results/{ds}/evaluation/floorplan/all_scans_map.geojson",
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

# Figures and the report (floorscan.figures): the figures of each stage, each in a job of
# its own so that the stages do not wait for them, and the front page of each dataset.
#
#   register_figure:     the registered map and the scan locations
#   selection_figures:   covered area against scans, per ordering and per KMeans k; the
#                        time to order the scans
#   score_walls_figures: walls and floor plans of the first score.figure_k scans, over
#                        the reference and the points (the bitmap overlay with the score
#                        stage's numbers); the time per scan of each extractor
#   score_figures:       wall metrics against k; the time and memory of every stage
#   front_page:          the answer on one page (floorscan.figures.report): the
#                        recommended floor plan, the selection and its size reduction,
#                        the registration's verdict, what ingest detected and (when
#                        evaluated) the summary table and the F1 curves;
#                        workflow/report/workflow.rst includes every front page, so the
#                        report opens on them
# The figures made by the jobs of a stage itself (the reference map, the F1 curves, the
# drawn and room overlays) are in its rule file.
from floorscan.score.runs import figure_floorplans, figure_runs
from floorscan.select.registry import COVERAGE_ORDERINGS
from floorscan.select.registry import ORDERINGS as SELECT_ORDERINGS

# The figure k is in the figure file names (floorplans_first_k15.png), so it is global
# (FILE_GRID_KEYS: a per-dataset override is refused).
SCORE_FIGURE_K = config["score"]["figure_k"]


# The figure in its own job: the per-scan stages start without waiting for it.
rule register_figure:
    priority: PRIORITY["register_figure"]
    input:
        registered="results/{dataset}/registered.parquet",
        registration="results/{dataset}/registration.parquet",
        index="results/{dataset}/scan_index.parquet",  # what ingest detected
    output:
        figure=report(
            "results/{dataset}/figures/registered_map.png",
            caption="../report/registered_map.rst",
            category="Registration",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "Registered map and scan locations"},
        ),
    log:
        log_path("register_figure"),
    benchmark:
        benchmark_path("register_figure")
    script:
        "../../scripts/register_figure.py"


PLAN_OUTPUTS.append("results/{dataset}/figures/registered_map.png")


rule selection_figures:
    priority: PRIORITY["selection_figures"]
    input:
        registered="results/{dataset}/registered.parquet",
        registration="results/{dataset}/registration.parquet",
        hulls="results/{dataset}/hulls.parquet",
        convex="results/{dataset}/convex_hulls.parquet",
        orderings=expand(
            "results/{{dataset}}/orderings/{ordering}.parquet", ordering=[*SELECT_ORDERINGS, *COVERAGE_ORDERINGS]
        ),
        summary="results/{dataset}/orderings/summary.parquet",
    output:
        coverage=report(
            "results/{dataset}/figures/coverage_vs_scans.png",
            caption="../report/coverage_vs_scans.rst",
            category="Selection",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "Covered area against the number of scans, per ordering"},
        ),
        clusters=report(
            "results/{dataset}/figures/coverage_vs_clusters.png",
            caption="../report/coverage_vs_clusters.rst",
            category="Selection",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "Covered area against the number of scans, per number of KMeans clusters"},
        ),
        timing=report(
            "results/{dataset}/figures/selection_time.png",
            caption="../report/selection_time.rst",
            category="Selection",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "Time to order the scans, lazy against plain greedy"},
        ),
    params:
        cfg=stage_config("select"),
        hulls_cfg=hulls_config,
    log:
        log_path("selection_figures"),
    benchmark:
        benchmark_path("selection_figures")
    script:
        "../../scripts/selection_figures.py"


EVALUATION_OUTPUTS.extend(
    [
        "results/{dataset}/figures/coverage_vs_scans.png",
        "results/{dataset}/figures/coverage_vs_clusters.png",
        "results/{dataset}/figures/selection_time.png",
    ]
)


def score_figure_runs(wildcards):
    """[ordering, extractor, k label] of the raw wall files the figures draw
    (floorscan.score.runs.figure_runs)."""
    return figure_runs(stage_config("score")(wildcards), score_extractors(wildcards))


def score_figure_floorplans(wildcards):
    """[ordering, extractor] of the merged floor plans at figure_k (Fig. 5.5;
    floorscan.score.runs.figure_floorplans)."""
    return figure_floorplans(stage_config("score")(wildcards))


def score_bench_dir(wildcards):
    return f"results/{wildcards.dataset}/benchmarks"


def score_walls_figure_inputs(wildcards):
    evaluation_grid_check()  # the walls of score.figure_k
    ds = wildcards.dataset
    cfg = stage_config("score")(wildcards)
    k = str(cfg["figure_k"])
    return {
        "walls": [f"results/{ds}/walls/{o}/{e}/k{kk}.parquet" for o, e, kk in score_figure_runs(wildcards)],
        # the bitmap overlay's numbers: the score stage's scores of the figure extractor's runs
        "scores": [f"results/{ds}/score/{e}.parquet" for e in score_extractors(wildcards) if e == cfg["figure_extractor"]],
        "floorplans": [
            f"results/{ds}/evaluation/plans/{o}_{e}_k{k}" for o, e in score_figure_floorplans(wildcards)
        ],
        "registered": f"results/{ds}/registered.parquet",
        "scan_status": [f"results/{ds}/walls/{e}/scan_status.parquet" for e in score_extractors(wildcards)],
        "scan_times": [f"results/{ds}/benchmarks/scan_walls_{e}_times.parquet" for e in score_extractors(wildcards)],
        **score_reference_inputs(wildcards),
    }


# The figures of walls and floor plans need only the figure extractor's scores: drawn
# while the other extractors' runs are scored.
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
        cfg=stage_config("score"),
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
        cfg=stage_config("score"),
        bench_dir=score_bench_dir,
    log:
        "results/{dataset}/logs/score_figures.log",
    benchmark:
        "results/{dataset}/benchmarks/score_figures.tsv"
    script:
        "../../scripts/score_figures.py"


EVALUATION_OUTPUTS.extend(
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
)


# The answer's files a front page links, under results/<dataset>/ (floorscan.figures.report.answer_files):
# inputs of its rule, so that they exist when it is written and it links them.
FRONT_PAGE_LINKED = ["floorplan.dxf", "floorplan.ifc", "map.pgm", "map.yaml"]
SCAN_FRONT_PAGE_LINKED = [f"selection/{name}" for name in ("scans.csv", "points.ply", "points.pcd", "recording")]


def front_page_inputs(wildcards):
    ds = wildcards.dataset
    inputs = {
        "floorplan_svg": f"results/{ds}/floorplan.svg",
        "plan": f"results/{ds}/plan_tables",  # its wall count and rooms (floorscan.core.plan_tables)
        # summary.md names the export with the counts of its metadata (figures.answer.plan_counts)
        "floorplan_geojson": f"results/{ds}/floorplan.geojson",
        "selection": f"results/{ds}/selection/selection.json",
        "registration": f"results/{ds}/registration.parquet",
        "index": f"results/{ds}/scan_index.parquet",
        # the answer's files the page links (figures.report.answer_files): made before it
        "linked": [f"results/{ds}/{name}" for name in FRONT_PAGE_LINKED + SCAN_FRONT_PAGE_LINKED],
    }
    if evaluate_by_default():
        inputs["summary"] = f"results/{ds}/summary.parquet"
        inputs["quality_png"] = f"results/{ds}/figures/floorplan_f1_vs_k.png"
        inputs["answer"] = f"results/{ds}/evaluation/answer_scores.csv"
        inputs["answer_curve"] = f"results/{ds}/evaluation/answer_curve.csv"
        inputs["rooms"] = f"results/{ds}/evaluation/room_scores.csv"
        inputs["evaluation_md"] = f"results/{ds}/evaluation/summary.md"
    return inputs


def dataset_description(wildcards):
    return DATASETS[wildcards.dataset].get("description", "")


rule front_page:
    priority: PRIORITY["front_page"]
    wildcard_constraints:
        dataset=SCAN_DATASET,
    input:
        unpack(front_page_inputs),
    output:
        front=report(
            "results/{dataset}/front.html",
            caption="../report/front.rst",
            category="Floor plan",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "The result on one page"},
        ),
        summary_md="results/{dataset}/summary.md",
    params:
        extractor=plan_extractor,
        description=dataset_description,
    log:
        log_path("front_page"),
    benchmark:
        benchmark_path("front_page")
    script:
        "../../scripts/front_page.py"


# The front page of an occupancy map's plan: the plan, its rooms, what was read of the map.
rule map_front_page:
    priority: PRIORITY["front_page"]
    wildcard_constraints:
        dataset=MAP_DATASET,
    input:
        floorplan_svg="results/{dataset}/floorplan.svg",
        floorplan_geojson="results/{dataset}/floorplan.geojson",
        plan="results/{dataset}/plan_tables",
        info="results/{dataset}/map/map.json",
        linked=expand("results/{{dataset}}/{name}", name=FRONT_PAGE_LINKED),  # linked by the page
    output:
        front=report(
            "results/{dataset}/front.html",
            caption="../report/front.rst",
            category="Floor plan",
            subcategory="{dataset}",
            labels={"dataset": "{dataset}", "figure": "The result on one page"},
        ),
        summary_md="results/{dataset}/summary.md",
    params:
        description=dataset_description,
    log:
        log_path("front_page"),
    benchmark:
        benchmark_path("front_page")
    script:
        "../../scripts/map_front_page.py"


REPORT_OUTPUTS += ["results/{dataset}/front.html", "results/{dataset}/summary.md"]

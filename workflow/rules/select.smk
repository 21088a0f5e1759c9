# Coverage hulls and scan orderings (issue 5; thesis section 3.3, Algorithms 1 and 2).
stage_schema_check("hulls", "../schemas/hulls.schema.yaml")
stage_schema_check("select", "../schemas/select.schema.yaml")

# Must match floorscan.selection.ORDERINGS (kept literal: no package import at parse time).
SELECT_ORDERINGS = ["cluster_hull", "convex_hull", "random", "sequential", "motion_filter"]


rule hulls:
    input:
        registered="results/{dataset}/registered.parquet",
        registration="results/{dataset}/registration.parquet",
    output:
        hulls="results/{dataset}/hulls.parquet",
        convex="results/{dataset}/convex_hulls.parquet",
    params:
        cfg=stage_config("hulls"),
    log:
        log_path("hulls"),
    benchmark:
        benchmark_path("hulls")
    script:
        "../../scripts/hulls.py"


rule select:
    input:
        hulls="results/{dataset}/hulls.parquet",
        convex="results/{dataset}/convex_hulls.parquet",
        registration="results/{dataset}/registration.parquet",
    output:
        orderings=expand(
            "results/{{dataset}}/orderings/{ordering}.parquet", ordering=SELECT_ORDERINGS
        ),
        summary="results/{dataset}/orderings/summary.parquet",
    params:
        cfg=stage_config("select"),
    log:
        log_path("select"),
    benchmark:
        benchmark_path("select")
    script:
        "../../scripts/select.py"


rule selection_figures:
    input:
        registered="results/{dataset}/registered.parquet",
        registration="results/{dataset}/registration.parquet",
        hulls="results/{dataset}/hulls.parquet",
        orderings=expand(
            "results/{{dataset}}/orderings/{ordering}.parquet", ordering=SELECT_ORDERINGS
        ),
        summary="results/{dataset}/orderings/summary.parquet",
    output:
        coverage=report(
            "results/{dataset}/figures/coverage_vs_scans.png",
            caption="../report/coverage_vs_scans.rst",
            category="Selection",
        ),
        clusters=report(
            "results/{dataset}/figures/coverage_vs_clusters.png",
            caption="../report/coverage_vs_clusters.rst",
            category="Selection",
        ),
        timing=report(
            "results/{dataset}/figures/selection_time.png",
            caption="../report/selection_time.rst",
            category="Selection",
        ),
    params:
        cfg=stage_config("select"),
        hulls_cfg=stage_config("hulls"),
    log:
        log_path("selection_figures"),
    benchmark:
        benchmark_path("selection_figures")
    script:
        "../../scripts/selection_figures.py"


FINAL_OUTPUTS.extend(
    [
        "results/{dataset}/hulls.parquet",
        "results/{dataset}/convex_hulls.parquet",
        "results/{dataset}/orderings/summary.parquet",
        *[f"results/{{dataset}}/orderings/{o}.parquet" for o in SELECT_ORDERINGS],
        "results/{dataset}/figures/coverage_vs_scans.png",
        "results/{dataset}/figures/coverage_vs_clusters.png",
        "results/{dataset}/figures/selection_time.png",
    ]
)

# The report's front page (floorscan.figures.report): per dataset, the answer on one page - the
# recommended floor plan, the selection and its size reduction, the registration's
# verdict, what ingest detected and (when evaluated) the summary table and the F1
# curves. workflow/report/workflow.rst includes every front page, so the report opens
# on them.


def front_page_inputs(wildcards):
    ds = wildcards.dataset
    inputs = {
        "floorplan_svg": f"results/{ds}/floorplan.svg",
        "floorplan_geojson": f"results/{ds}/floorplan.geojson",
        "selection": f"results/{ds}/selection/selection.json",
        "registration": f"results/{ds}/registration.parquet",
        "index": f"results/{ds}/scan_index.parquet",
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


REPORT_OUTPUTS += ["results/{dataset}/front.html", "results/{dataset}/summary.md"]

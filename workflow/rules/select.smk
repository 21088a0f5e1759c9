# Coverage hulls and scan orderings (issue 5; thesis section 3.3, Algorithms 1 and 2).
from floorscan.select.registry import COVERAGE_ORDERINGS
from floorscan.select.registry import ORDERINGS as SELECT_ORDERINGS


def select_coverage_inputs(wildcards):
    """Inputs of `select_coverage`: the per-scan walls of select.coverage.wall_extractor
    (one of walls.extractors, checked at start) and the registered points."""
    ds = wildcards.dataset
    extractor = stage_config("select")(wildcards)["coverage"]["wall_extractor"]
    return {
        "walls": f"results/{ds}/walls/{extractor}/per_scan.parquet",
        "registered": f"results/{ds}/registered.parquet",
        "registration": f"results/{ds}/registration.parquet",
    }


def hulls_shard_scans(wildcards):
    return stage_config("hulls")(wildcards)["shard_scans"]


def hulls_shards(wildcards):
    """Inputs of `select`: the hull shard files of the plan (known once the register
    checkpoint has ended), and the register stage's files the plan comes from."""
    shard = "results/{dataset}/shards/hulls/{shard}/{name}.parquet"
    labels = shard_labels(wildcards, "hulls")
    return {
        "shard_hulls": [shard.format(dataset=wildcards.dataset, shard=s, name="hulls") for s in labels],
        "shard_convex": [shard.format(dataset=wildcards.dataset, shard=s, name="convex_hulls") for s in labels],
        "registered": f"results/{wildcards.dataset}/registered.parquet",
        "registration": f"results/{wildcards.dataset}/registration.parquet",
    }


# Sharding (issue 8): the hulls of a scan depend only on the scan and (seed, scan_id), so
# the kept scans are split by scan range into shards of <= hulls.shard_scans scans, one
# job each, concatenated in scan order by `select` into the unsharded tables. The
# shards are known once the register checkpoint has ended (shard_plan, common.smk).
rule hulls_shard:
    priority: PRIORITY["hulls_shard"]
    input:
        registered="results/{dataset}/registered.parquet",
        registration="results/{dataset}/registration.parquet",
    output:
        hulls="results/{dataset}/shards/hulls/{shard}/hulls.parquet",
        convex="results/{dataset}/shards/hulls/{shard}/convex_hulls.parquet",
    params:
        cfg=hulls_config,
    log:
        "results/{dataset}/logs/hulls_shard_{shard}.log",
    benchmark:
        "results/{dataset}/benchmarks/hulls_shard_{shard}.tsv"
    script:
        "../../scripts/hulls_shard.py"


# One job merges the hull shards (hulls.parquet, convex_hulls.parquet) and orders the
# scans: the merge was a job of its own (rule hulls), and a job costs ~0.6 s to start.
rule select:
    priority: PRIORITY["select"]
    input:
        unpack(hulls_shards),
    output:
        hulls="results/{dataset}/hulls.parquet",
        convex="results/{dataset}/convex_hulls.parquet",
        orderings=expand(
            "results/{{dataset}}/orderings/{ordering}.parquet", ordering=SELECT_ORDERINGS
        ),
        summary="results/{dataset}/orderings/summary.parquet",
    params:
        cfg=stage_config("select"),
        shard_scans=hulls_shard_scans,
    log:
        log_path("select"),
    benchmark:
        benchmark_path("select")
    script:
        "../../scripts/select.py"


# The orderings by what the scans add to the walls (floorscan.select.coverage): after the
# walls stage's per-scan segments, before the k tables of every ordering are cut.
rule select_coverage:
    priority: PRIORITY["select_coverage"]
    input:
        unpack(select_coverage_inputs),
    output:
        orderings=expand("results/{{dataset}}/orderings/{ordering}.parquet", ordering=COVERAGE_ORDERINGS),
    params:
        cfg=stage_config("select"),
        walls=walls_extract_config,
    log:
        log_path("select_coverage"),
    benchmark:
        benchmark_path("select_coverage")
    script:
        "../../scripts/select_coverage.py"


def selection_inputs(wildcards):
    """Inputs of `selection`: the default ordering, the scans' stamps and poses, the
    registered points and the recording the reduced copy is cut from."""
    ds = wildcards.dataset
    return {
        "ordering": f"results/{ds}/orderings/{select_default_ordering(wildcards)}.parquet",
        "index": f"results/{ds}/scan_index.parquet",
        "registration": f"results/{ds}/registration.parquet",
        "registered": f"results/{ds}/registered.parquet",
        "recording": recording_input(wildcards),
    }


# The answer (issue 23): the first k scans of the default ordering (select.k), as a scan
# list, their registered points (PLY, PCD) and the recording cut to them
# (floorscan.select.deliverables; the recording by ingest's writer, floorscan.ingest.reduced).
rule selection:
    priority: PRIORITY["selection"]
    input:
        unpack(selection_inputs),
    output:
        scans="results/{dataset}/selection/scans.csv",
        table="results/{dataset}/selection/scans.parquet",  # the same, for the later stages
        ply="results/{dataset}/selection/points.ply",
        pcd="results/{dataset}/selection/points.pcd",
        recording=directory("results/{dataset}/selection/recording"),
        summary="results/{dataset}/selection/selection.json",
    params:
        cfg=stage_config("select"),
        ordering=select_default_ordering,
        dataset=ingest_dataset,
    log:
        log_path("selection"),
    benchmark:
        benchmark_path("selection")
    script:
        "../../scripts/selection.py"


EVALUATION_OUTPUTS.extend(
    [
        "results/{dataset}/hulls.parquet",
        "results/{dataset}/convex_hulls.parquet",
        "results/{dataset}/orderings/summary.parquet",
        *[f"results/{{dataset}}/orderings/{o}.parquet" for o in SELECT_ORDERINGS],
    ]
)

PLAN_OUTPUTS.extend(
    f"results/{{dataset}}/selection/{name}"
    for name in ("scans.csv", "scans.parquet", "points.ply", "points.pcd", "recording", "selection.json")
)

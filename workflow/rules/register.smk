# Registration (issue 4; thesis sections 3.2.2, 3.5, Algorithm 3 steps 2-6): every kept
# scan in the map frame, from the localizer's pose refined by planar ICP.


def register_inputs(wildcards):
    """Scans, index and poses (in odometry mode, auto or set, the poses are not used)."""
    return {
        "scans": f"results/{wildcards.dataset}/scans.parquet",
        "index": f"results/{wildcards.dataset}/scan_index.parquet",
        "poses": f"results/{wildcards.dataset}/poses.parquet",
    }


# A checkpoint (issue 8): the number of hulls and walls shards follows from its
# outputs (the kept scans), so Snakemake names those jobs when it has ended
# (shard_plan in common.smk).
checkpoint register:
    input:
        unpack(register_inputs),
    output:
        registered="results/{dataset}/registered.parquet",
        registration="results/{dataset}/registration.parquet",
    params:
        cfg=stage_config("register"),
    # the pose graph's edge ICP in this many processes (capped at --cores); same result
    threads: 4
    log:
        log_path("register"),
    benchmark:
        benchmark_path("register")
    script:
        "../../scripts/register.py"


PLAN_OUTPUTS.append("results/{dataset}/registration.parquet")

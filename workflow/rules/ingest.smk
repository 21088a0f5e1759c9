# Stages 1-2: read the recording (ingest) and interpolate a pose per scan (poses).


def recording_state(wildcards):
    """The recording's files' sizes and modification times
    (floorscan.core.files.recording_fingerprint): through `params:` they make ingest
    rerun when the recording is replaced, even by an older copy (`cp -p`), which
    Snakemake's time stamps miss. None for a synthetic dataset: its recording is the
    simulate rule's output, which Snakemake's time stamps track (and which does not
    exist yet when the jobs are planned)."""
    if is_synthetic(wildcards.dataset):
        return None
    from floorscan.core.files import recording_fingerprint

    return recording_fingerprint(recording_input(wildcards))


def pose_gap_limit(wildcards):
    """The poses stage's gap limit for this dataset (TF chains keep their gaps visible)."""
    return stage_config("poses")(wildcards)["max_gap_s"]


rule ingest:
    input:
        recording_input,
    output:
        scans="results/{dataset}/scans.parquet",
        index="results/{dataset}/scan_index.parquet",
        pose_stream="results/{dataset}/pose_stream.parquet",
    params:
        dataset=ingest_dataset,
        cfg=stage_config("ingest"),
        max_gap_s=pose_gap_limit,
        recording=recording_state,
    log:
        log_path("ingest"),
    benchmark:
        benchmark_path("ingest")
    script:
        "../../scripts/ingest.py"


rule poses:
    input:
        index="results/{dataset}/scan_index.parquet",
        pose_stream="results/{dataset}/pose_stream.parquet",
    output:
        poses="results/{dataset}/poses.parquet",
    params:
        cfg=stage_config("poses"),
    log:
        log_path("poses"),
    benchmark:
        benchmark_path("poses")
    script:
        "../../scripts/poses.py"


PLAN_OUTPUTS.append("results/{dataset}/poses.parquet")

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
    wildcard_constraints:
        dataset=SCAN_DATASET,
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


def map_input(wildcards):
    """The files of an occupancy map: its yaml and the image it names, or the image."""
    from floorscan.ingest.occupancy_map import map_images

    path = recording_input(wildcards)
    return [path, *[str(p) for p in map_images(path) if p.is_file()]]


def map_state(wildcards):
    """The map's files' sizes and modification times (as recording_state): a replaced
    image reruns the map's stages even when the yaml is the same."""
    from floorscan.core.files import recording_fingerprint

    return [recording_fingerprint(p) for p in map_input(wildcards)]


def map_resolution(wildcards):
    """A map image's metres a pixel (the dataset's `resolution_m`; None: 5 cm); a
    map_server yaml has its own."""
    return DATASETS[wildcards.dataset].get("resolution_m")


# An occupancy map as the recording (floorscan.ingest.occupancy_map): its grid, the map as
# read (map.pgm, map.yaml: the classes the plan is built on) and what was read.
rule map_ingest:
    wildcard_constraints:
        dataset=MAP_DATASET,
    input:
        map_input,
    output:
        grid="results/{dataset}/map/grid.parquet",
        info="results/{dataset}/map/map.json",
        map_pgm="results/{dataset}/map.pgm",
        map_yaml="results/{dataset}/map.yaml",
    params:
        path=recording_input,  # the file to read; the image a yaml names is an input too
        resolution_m=map_resolution,
        recording=map_state,
    log:
        log_path("ingest"),
    benchmark:
        benchmark_path("ingest")
    script:
        "../../scripts/map_ingest.py"


MAP_PLAN_OUTPUTS.extend(["results/{dataset}/map.pgm", "results/{dataset}/map.yaml"])

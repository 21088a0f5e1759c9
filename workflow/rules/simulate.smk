# Simulate stage: synthetic datasets (format `synthetic`) are recorded by a simulated
# rover in a building of config/buildings/ (thesis 4.1, 5.2). The recording then flows
# through ingest like a real one (sim/recording.bag, or sim/pcd for `recording: pcd`).
import re

from floorscan.core.config import BUILDINGS_DIR

SYNTHETIC_DATASETS = sorted(d for d in DATASETS if is_synthetic(d))


def simulate_building_yaml(wildcards):
    """The building file a synthetic dataset names: config/buildings/<building>.yaml
    (its existence is checked at start, floorscan.core.datasets.check_datasets)."""
    return f"{BUILDINGS_DIR}/{DATASETS[wildcards.dataset]['building']}.yaml"


rule simulate:
    input:
        building=simulate_building_yaml,
    output:
        bag="results/{dataset}/sim/recording.bag",
        pcd=directory("results/{dataset}/sim/pcd"),
        true_poses="results/{dataset}/sim/true_poses.parquet",
        stl="results/{dataset}/sim/building.stl",
        walls="results/{dataset}/sim/walls.geojson",
    params:
        cfg=stage_config("simulate"),
        dataset=dataset_config,
    wildcard_constraints:
        dataset="|".join(re.escape(d) for d in SYNTHETIC_DATASETS) or "NO_SYNTHETIC_DATASET",
    log:
        log_path("simulate"),
    benchmark:
        benchmark_path("simulate")
    script:
        "../../scripts/simulate.py"

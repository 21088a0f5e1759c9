# Helper functions shared by the rules. No lambdas inside rules: rules call these.
import copy
from pathlib import Path

from snakemake.utils import validate

DATASETS = config["datasets"]

# Each stage file appends the per-dataset outputs that `rule all` builds, as patterns
# with a {dataset} placeholder (see all_outputs).
FINAL_OUTPUTS = []

# Scheduling (issue 8): of the jobs ready at once, Snakemake starts those of higher
# priority first. On few cores the hulls go first, so select and the figures of the
# registration and selection run beside the walls shards (not alone, and not at the
# end, where the floor plans and scores of both extractors keep every core busy); then
# the chain to the floor plans and scores; the last figures wait for those anyway.
PRIORITY_HULLS = 20
PRIORITY_WALLS = 10
PRIORITY_FIGURES = 0


wildcard_constraints:
    dataset="|".join(sorted(DATASETS)) or "NO_DATASET",


def target_datasets():
    """Datasets built by `rule all`: config `target`, checked against `datasets`."""
    unknown = [d for d in config["target"] if d not in DATASETS]
    if unknown:
        raise ValueError(
            f"config 'target' names unknown datasets {unknown}; known: {sorted(DATASETS)}"
        )
    return list(config["target"])


def all_outputs():
    """Inputs of `rule all`: every registered final output for every target dataset."""
    return [p.format(dataset=d) for d in target_datasets() for p in FINAL_OUTPUTS]


def stage_schema_check(stage, schema_file):
    """Validate the `stage` section of the config against its schema (filling defaults),
    and each dataset's `params: {stage: ...}` overrides merged over it."""
    config.setdefault(stage, {})
    validate(config[stage], schema_file)
    for name, ds in DATASETS.items():
        override = (ds.get("params") or {}).get(stage)
        if override:
            merged = _deep_merge(config[stage], override)
            try:
                validate(merged, schema_file)
            except Exception as e:
                raise ValueError(f"datasets.{name}.params.{stage}: {e}") from e


def _deep_merge(base, override):
    out = copy.deepcopy(base)
    for k, v in (override or {}).items():
        if isinstance(v, dict) and isinstance(out.get(k), dict):
            out[k] = _deep_merge(out[k], v)
        else:
            out[k] = copy.deepcopy(v)
    return out


def stage_config(stage):
    """A params function: the config section of `stage` for the job's dataset, with the
    dataset's `params: {stage: ...}` overrides applied. Passing it through `params:`
    makes Snakemake rerun the stage when a value changes."""

    def _stage_config(wildcards):
        ds = DATASETS[wildcards.dataset]
        return _deep_merge(config.get(stage, {}), (ds.get("params") or {}).get(stage))

    return _stage_config


def dataset_config(wildcards):
    """The dataset's own entry (format, path, options), without `params`."""
    ds = {k: v for k, v in DATASETS[wildcards.dataset].items() if k != "params"}
    ds["name"] = wildcards.dataset
    return ds


def is_synthetic(dataset):
    return DATASETS[dataset]["format"] == "synthetic"


def log_path(stage):
    return f"results/{{dataset}}/logs/{stage}.log"


def benchmark_path(stage):
    return f"results/{{dataset}}/benchmarks/{stage}.tsv"

# Helper functions shared by the rules. No lambdas inside rules: rules call these.
import copy
from pathlib import Path

from floorscan.core.config import ConfigError, config_errors_exit, validate_config
from floorscan.core.files import writable_problem

DATASETS = config["datasets"]

# A folder the run must write in that it cannot (read-only, full, not the user's) stops
# it here with one paragraph: Snakemake would end in its own traceback making
# .snakemake/, or fail the first job making results/<dataset>/.
for _folder in ("results", ".snakemake"):
    _problem = writable_problem(_folder)
    if _problem:
        raise SystemExit(f"Cannot run: {_problem}")

# Each stage file appends its per-dataset outputs, as patterns with a {dataset}
# placeholder: PLAN_OUTPUTS are the answer (`rule plan`: the selected scans and the
# recommended floor plan), EVALUATION_OUTPUTS the grid of plans, scores and figures
# (`rule evaluation`). `rule all` builds both, or the plan alone (see all_outputs).
PLAN_OUTPUTS = []
EVALUATION_OUTPUTS = []
# The report's front pages (report.smk): they read the evaluation when there is one.
REPORT_OUTPUTS = []

# Scheduling (issue 8): of the jobs ready at once, Snakemake starts those of higher
# priority first (the greedy scheduler of workflow/profiles/default; ties go to larger
# inputs). On few cores that order decides when the last job ends, so each rule's
# priority is its "upward rank", the standard list-scheduling heuristic: the seconds of
# the longest chain of jobs from its start to the end of the workflow, measured on
# hallways3d (2 cores, a job's start-up of ~0.6 s included):
#
#   cluster_ransac shard 13 -> walls 1.2 -> floorplan 11.5
#     -> score_runs 5 -> score 0.8 -> score_figures 3                        = 34
#   hulls_shard 8.7 -> select 3.2 -> walls ...                                = 33
#   ransac shard 7.5 -> walls ...                                             = 29
#   selection_figures 10.5 -> score_figures 3                                 = 14
#   register_figure 2.7 (nothing waits for it)                                = 3
#
# The reference map and the curves came later (measured 8 s and ~20 s a job):
#
#   reference 8 -> score_curves 20 -> score 1 -> score_figures 3              = 32
#   walls ... -> score_curves 20 -> score ...                                 = 24 from walls
#
# so score_curves (24) runs beside floorplan (20) and score_runs, and the reference
# (36: it needs only the registration) starts with the shards and is ready by then.
# Every chain through the walls grew by the curves alike, so the order of the others
# stands.
#
# Walls need the orderings of select, so the hulls chain is as urgent as the walls
# shards; the cluster_ransac shards (about twice ransac's time a scan) go before
# ransac's; the figures fill the cores between the chains instead of delaying them.
# select is raised above its rank (24) to 31, over the ransac shards: both walls jobs
# wait for its orderings, and when ransac's shard went first the cluster_ransac walls
# waited 2.5 s for select after their shard ended. With the hulls chain first and the
# figures next (the order before), the cluster_ransac shard started 12 s after
# registration and the chain of floor plans and scores behind it ended the run.
# Ingest, poses and register run alone (0).
#
# A walls shard's priority is by its extractor: the chain after the shard (walls 1.2
# -> floorplan 11.5 -> score_runs 5 -> score 0.8 -> score_figures 3 = 21.5 s) plus the
# shard, ransac's 7.5 s times the extractor's relative cost (the registry of
# floorscan.walls.extractors): ransac 29, cluster_ransac 35.
from floorscan.walls.extractors import REGISTRY as WALLS_REGISTRY

PRIORITY = {
    "scan_walls_shard": {name: round(21.5 + 7.5 * e.cost) for name, e in WALLS_REGISTRY.items()},
    "hulls_shard": 33,
    "select": 31,
    "walls": 21,
    "scan_walls": 23,
    "select_coverage": 22,
    "selection": 21,
    "floorplan": 20,
    "selection_figures": 14,
    "reference": 36,
    "score_curves": 24,
    "score_runs": 9,
    "score_walls_figures": 8,
    "score": 4,
    "score_figures": 3,
    "register_figure": 3,
    "front_page": 3,
}


def shard_priority(wildcards):
    """Priority of a walls shard job: by its extractor (PRIORITY; an extractor that is
    not registered in floorscan.walls.extractors raises)."""
    by_extractor = PRIORITY["scan_walls_shard"]
    if wildcards.extractor not in by_extractor:
        raise ValueError(f"unknown extractor {wildcards.extractor!r}; expected one of {list(by_extractor)}")
    return by_extractor[wildcards.extractor]


wildcard_constraints:
    dataset="|".join(sorted(DATASETS)) or "NO_DATASET",


def config_error(message):
    """Stop the run on a config value the schemas cannot judge alone (one key against
    another): Snakemake prints the message, one paragraph, no traceback
    (floorscan.core.config.config_errors_exit)."""
    with config_errors_exit():
        raise ConfigError(message)


def target_datasets():
    """Datasets built by `rule all`: config `target`, checked against `datasets`."""
    unknown = [d for d in config["target"] if d not in DATASETS]
    if unknown:
        config_error(f"target names unknown datasets {unknown}; known: {sorted(DATASETS)}")
    return list(config["target"])


def plan_outputs():
    """Inputs of `rule plan`: the answer of every target dataset."""
    return [p.format(dataset=d) for d in target_datasets() for p in PLAN_OUTPUTS]


def evaluation_outputs():
    """Inputs of `rule evaluation`: the evaluation grid, scores and figures of every
    target dataset."""
    outputs = [p.format(dataset=d) for d in target_datasets() for p in EVALUATION_OUTPUTS]
    # a plan drawn by people, for the datasets that name one (score_drawn, score.smk)
    outputs += [p.format(dataset=d) for d in target_datasets() if DATASETS[d].get("reference") for p in drawn_outputs()]
    return outputs


def evaluate_by_default():
    """Config `evaluate`; unset: True, but False for a recording given by `path`."""
    evaluate = config.get("evaluate")
    return (not config.get("path")) if evaluate is None else bool(evaluate)


def all_outputs():
    """Inputs of `rule all` (the default target): the plan, the evaluation unless
    evaluate_by_default() says no, and the front pages."""
    outputs = plan_outputs() + (evaluation_outputs() if evaluate_by_default() else [])
    return outputs + [p.format(dataset=d) for d in target_datasets() for p in REPORT_OUTPUTS]


# The stage schemas, beside the main one (workflow/schemas/).
SCHEMA_DIR = Path(workflow.basedir) / "workflow" / "schemas"


# Keys that decide which files the workflow makes (the evaluation grid's file names):
# the same for every dataset, so a dataset's `params:` cannot override them and the
# rules read them from the global section. Every other key goes through
# stage_config(stage), with the dataset's overrides, in every rule.
FILE_GRID_KEYS = {
    "walls": ("k", "orderings", "extractors"),
    "floorplan": ("evaluation_formats",),
    "score": ("figure_k",),
}


def stage_schema_check(stage):
    """Validate the `stage` section of the config against its schema,
    workflow/schemas/<stage>.schema.yaml (filling defaults), and each dataset's
    `params: {stage: ...}` overrides merged over it.

    floorscan.core.config.validate_config: snakemake.utils.validate's checks and defaults,
    each schema parsed once (16 validations took Snakemake ~0.5 s at every start)."""
    schema = SCHEMA_DIR / f"{stage}.schema.yaml"
    config.setdefault(stage, {})
    with config_errors_exit():  # a bad value: one paragraph, no traceback
        validate_config(config[stage], schema, stage)
        for name, ds in DATASETS.items():
            override = (ds.get("params") or {}).get(stage)
            if override:
                fixed = sorted(set(override) & set(FILE_GRID_KEYS.get(stage, ())))
                if fixed:
                    raise ConfigError(
                        f"datasets.{name}.params.{stage}: {fixed} name the workflow's files "
                        f"(every dataset has the same grid of outputs), so they are set once, under `{stage}:`"
                    )
                validate_config(_deep_merge(config[stage], override), schema, f"datasets.{name}.params.{stage}")


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


# The `walls` keys that change the per-scan walls (scan_walls_shard, select_coverage):
# the scan points, the seed and the config sections of the registered extractors.
from floorscan.walls.extractors import EXTRACT_KEYS as WALLS_EXTRACT_KEYS


def walls_extract_config(wildcards):
    """The `walls` section without k/orderings/extractors: changing the k list or the
    orderings must not rerun the (expensive) per-scan extraction."""
    cfg = stage_config("walls")(wildcards)
    return {key: cfg[key] for key in WALLS_EXTRACT_KEYS if key in cfg}


def dataset_config(wildcards):
    """The dataset's own entry (format, path, options), without `params` and the drawn
    `reference` (evaluation data, read by score_drawn)."""
    ds = {k: v for k, v in DATASETS[wildcards.dataset].items() if k not in ("params", "reference")}
    ds["name"] = wildcards.dataset
    return ds


def is_synthetic(dataset):
    return DATASETS[dataset].get("format") == "synthetic"


def log_path(stage):
    return f"results/{{dataset}}/logs/{stage}.log"


def benchmark_path(stage):
    return f"results/{{dataset}}/benchmarks/{stage}.tsv"


# Shard plans (issue 8; floorscan.core.shards): `register` is a checkpoint, and once it has
# ended the shard jobs of a per-scan stage are named from its files. Input functions
# run several times per job; the plan is read once per file version and shard size.
_SHARD_PLANS = {}


def shard_plan(wildcards, stage):
    """The shard plan (floorscan.core.shards.plan_shards) of per-scan stage `stage` (`hulls`
    or `walls`, whose config holds shard_scans) from the register checkpoint's files.
    Before `register` has run this raises Snakemake's IncompleteCheckpointException,
    which defers the jobs that depend on it until then."""
    out = checkpoints.register.get(dataset=wildcards.dataset).output
    shard_scans = int(stage_config(stage)(wildcards)["shard_scans"])
    key = (
        str(out.registration), Path(out.registration).stat().st_mtime_ns,
        str(out.registered), Path(out.registered).stat().st_mtime_ns, shard_scans,
    )
    if key not in _SHARD_PLANS:
        from floorscan.core.shards import plan_from_files

        _SHARD_PLANS[key] = plan_from_files(out.registration, out.registered, shard_scans)
    return _SHARD_PLANS[key]


def shard_labels(wildcards, stage):
    """The shard labels (scans_<first>-<last>) of `stage`'s plan, in scan order."""
    return [s["label"] for s in shard_plan(wildcards, stage)["shards"]]

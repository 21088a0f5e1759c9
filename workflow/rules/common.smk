# Helper functions shared by the rules, and the config checks that run once, when the
# config is loaded. No lambdas inside rules: rules call these. What needs no Snakemake
# global (config, wildcards, checkpoints) lives in the package.
import re
from pathlib import Path

from floorscan.core.config import ConfigError, config_errors_exit, validate_config
from floorscan.core.files import writable_problem
from floorscan.core.sections import check_sections, dataset_section, evaluation_grid_errors, merge_override
from floorscan.core.shards import SHARD_LABEL
from floorscan.floorplan.building import building_files
from floorscan.core.score_tables import GROUND_TRUTH, REFERENCE
from floorscan.walls.extractors import EXTRACT_KEYS as WALLS_EXTRACT_KEYS
from floorscan.walls.extractors import REGISTRY as WALLS_REGISTRY

DATASETS = config["datasets"]


def is_map_dataset(dataset):
    """Whether a dataset is an occupancy map (floorscan.ingest.occupancy_map), not a
    recording of scans: `format: map`, or, without a format, a path to a map_server
    yaml or a .pgm/.png image."""
    from floorscan.ingest.occupancy_map import is_map_path

    ds = DATASETS[dataset]
    if ds.get("format"):
        return ds["format"] == "map"
    return bool(ds.get("path")) and is_map_path(ds["path"])


def _names_regex(names):
    return "|".join(re.escape(n) for n in sorted(names))


# Maps and recordings take different rules to the same outputs (floorplan.*, map.pgm,
# front.html): each such rule is constrained to its kind of dataset.
MAP_DATASETS = [d for d in DATASETS if is_map_dataset(d)]
MAP_DATASET = _names_regex(MAP_DATASETS) or "NO_MAP_DATASET"
SCAN_DATASET = _names_regex(set(DATASETS) - set(MAP_DATASETS)) or "NO_SCAN_DATASET"

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
# The answer of an occupancy map: its plan and the map as read (nothing needs scans).
MAP_PLAN_OUTPUTS = []
# The report's front pages (figures.smk): they read the evaluation when there is one.
REPORT_OUTPUTS = []

# Rule priorities: of the jobs ready at once, Snakemake starts those of higher priority
# first. Each rule's priority is its upward rank (list scheduling): the seconds of the
# longest chain of jobs from its start to the end of the workflow; a walls shard's is
# the 21.5 s of the chain after it plus ransac's 7.5 s times its extractor's relative
# cost (floorscan.walls.extractors). The measured chains and why select is raised above
# its rank: benchmarks/README.md, "Rule priorities". The answer's plans of the first k
# scans are the longest chain of a large recording's evaluation (acapulco), so the
# short jobs before them (the coverage extractor's shard, scan_walls, select_coverage:
# "coverage_chain") go first and the plans before the hulls and select.
PRIORITY = {
    "scan_walls_shard": {name: round(21.5 + 7.5 * e.cost) for name, e in WALLS_REGISTRY.items()},
    "coverage_chain": 37,
    "hulls_shard": 33,
    "select": 31,
    "walls": 21,
    "scan_walls": 37,
    "select_coverage": 37,
    "selection": 21,
    "floorplan": 20,
    "answer_floorplans": 34,
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
    not registered in floorscan.walls.extractors raises); the dataset's coverage
    extractor's (select.coverage.wall_extractor) at least the coverage chain's."""
    by_extractor = PRIORITY["scan_walls_shard"]
    if wildcards.extractor not in by_extractor:
        raise ValueError(f"unknown extractor {wildcards.extractor!r}; expected one of {list(by_extractor)}")
    if wildcards.extractor == stage_config("select")(wildcards)["coverage"]["wall_extractor"]:
        return max(by_extractor[wildcards.extractor], PRIORITY["coverage_chain"])
    return by_extractor[wildcards.extractor]


# The shard jobs (hulls_shard, scan_walls_shard) are named by floorscan.core.shards.shard_label.
wildcard_constraints:
    dataset="|".join(sorted(DATASETS)) or "NO_DATASET",
    shard=SHARD_LABEL,


# ---------------------------------------------------------------------------------------
# Config checks, once, when the config is loaded (before any job is planned): the
# schemas (stage_schema_check) and one key against another (check_sections)

# The stage schemas, beside the main one (workflow/schemas/).
SCHEMA_DIR = Path(workflow.basedir) / "workflow" / "schemas"


# Keys that decide which files the workflow makes (the evaluation grid's file names):
# the same for every dataset, so a dataset's `params:` cannot override them and the
# rules read them from the global section. Every other key goes through
# stage_config(stage), with the dataset's overrides, in every rule.
FILE_GRID_KEYS = {
    "walls": ("k", "orderings", "extractors"),
    "score": ("figure_k",),
}


def config_error(message):
    """Stop the run on a config value the schemas cannot judge alone (one key against
    another): Snakemake prints the message, one paragraph, no traceback
    (floorscan.core.config.config_errors_exit)."""
    with config_errors_exit():
        raise ConfigError(message)


def stage_schema_check(stage):
    """Validate the `stage` section of the config against its schema,
    workflow/schemas/<stage>.schema.yaml (filling defaults), and each dataset's
    `params: {stage: ...}` overrides merged over it.

    floorscan.core.config.validate_config: snakemake.utils.validate (checks, defaults),
    with the --config strings typed and a message naming the key."""
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
                validate_config(merge_override(config[stage], override), schema, f"datasets.{name}.params.{stage}")


for _stage in ("simulate", "ingest", "poses", "register", "hulls", "select", "walls", "floorplan", "score"):
    stage_schema_check(_stage)
# One key against another (a registered extractor, select.default_ordering in
# walls.orderings, ...), for every dataset, once: so the rules' params are the plain
# sections (floorscan.core.sections).
with config_errors_exit():
    check_sections(config, WALLS_REGISTRY)
# What the evaluation needs of walls.k (score.figure_k and all; global keys): found now,
# reported by the evaluation's input functions (evaluation_grid_check), as a run that
# narrows walls.k to build some plans needs neither.
EVALUATION_GRID_ERRORS = evaluation_grid_errors(config["score"], config["walls"]["k"])


def evaluation_grid_check():
    """Stop the run when an evaluation job is planned and walls.k lacks score.figure_k
    or all (EVALUATION_GRID_ERRORS)."""
    if EVALUATION_GRID_ERRORS:
        config_error(EVALUATION_GRID_ERRORS[0])


# ---------------------------------------------------------------------------------------
# What the run builds

def target_datasets():
    """Datasets built by `rule all`: config `target`, checked against `datasets`."""
    unknown = [d for d in config["target"] if d not in DATASETS]
    if unknown:
        config_error(f"target names unknown datasets {unknown}; known: {sorted(DATASETS)}")
    return list(config["target"])


def plan_outputs():
    """Inputs of `rule plan`: the answer of every target dataset (of a map: its plan)."""
    return [p.format(dataset=d) for d in target_datasets() for p in (MAP_PLAN_OUTPUTS if d in MAP_DATASETS else PLAN_OUTPUTS)]


def drawn_outputs():
    """score_drawn's files for the datasets that name a drawn plan (patterns keep {dataset});
    its room scores and overlay are in EVALUATION_OUTPUTS, as every dataset's (score_rooms
    makes them for the other datasets)."""
    return ["results/{dataset}/evaluation/drawn_scores.csv", "results/{dataset}/figures/drawn_overlay.png"]


def evaluation_outputs():
    """Inputs of `rule evaluation`: the evaluation grid, scores and figures of every
    target dataset that is a recording (a map has no scans to order and select)."""
    scanned = [d for d in target_datasets() if d not in MAP_DATASETS]
    outputs = [p.format(dataset=d) for d in scanned for p in EVALUATION_OUTPUTS]
    # a plan drawn by people, for the datasets that name one (score_drawn, score.smk)
    outputs += [p.format(dataset=d) for d in scanned if DATASETS[d].get("reference") for p in drawn_outputs()]
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


# The floors of one building (building.smk; floorscan.core.datasets.resolve_building).
BUILDING_DIR = "results/building"


def building_floors():
    """The building's floors, {dataset, storey, elevation_m} each; [] without a building."""
    floors = (config.get("building") or {}).get("floors") or []
    return [{"dataset": f["dataset"], "storey": f["storey"], "elevation_m": float(f["elevation_m"])} for f in floors]


def building_outputs():
    """The building's files (floorscan.floorplan.building.building_files); [] without a building."""
    floors = building_floors()
    if not floors:
        return []
    files = building_files(BUILDING_DIR, [f["dataset"] for f in floors])
    return [files["ifc"], files["page"], *files["geojson"]]


# ---------------------------------------------------------------------------------------
# A job's config: params functions (a changed value reruns the job)

def stage_config(stage):
    """A params function: the config section of `stage` for the job's dataset, with the
    dataset's `params: {stage: ...}` overrides applied
    (floorscan.core.sections.dataset_section). Passing it through `params:` makes
    Snakemake rerun the stage when a value changes."""

    def _stage_config(wildcards):
        return dataset_section(config, wildcards.dataset, stage)

    return _stage_config


def walls_extract_config(wildcards):
    """The `walls` section without k/orderings/extractors: changing the k list or the
    orderings must not rerun the (expensive) per-scan extraction."""
    cfg = stage_config("walls")(wildcards)
    return {key: cfg[key] for key in WALLS_EXTRACT_KEYS if key in cfg}


def walls_map_config(wildcards):
    """The `walls` keys the map extractor reads: the scan points, the seed, `map`."""
    cfg = stage_config("walls")(wildcards)
    return {key: cfg[key] for key in ("seed", "height_band_m", "map") if key in cfg}


def hulls_config(wildcards):
    """The hulls section without shard_scans: how the scans are split into jobs changes
    no hull, so it must not rerun the shards (and HullParams does not know it)."""
    return {k: v for k, v in stage_config("hulls")(wildcards).items() if k != "shard_scans"}


def floorplan_grid_config(wildcards):
    """The floorplan section for the evaluation grid: never georeferenced (its plans
    are scored in the map frame)."""
    return {**stage_config("floorplan")(wildcards), "georeference": None}


def select_default_ordering(wildcards):
    """select.default_ordering (one of walls.orderings, checked at start: its plans are made)."""
    return stage_config("select")(wildcards)["default_ordering"]


def plan_extractor(wildcards):
    """floorplan.extractor: map (the map extractor, floorscan.walls.map_lines) or one of
    walls.extractors (checked at start)."""
    return stage_config("floorplan")(wildcards)["extractor"]


def score_orderings(wildcards):
    """The orderings the walls stage extracts (walls.orderings)."""
    return list(stage_config("walls")(wildcards)["orderings"])


def score_extractors(wildcards):
    """The extractors the walls stage runs (walls.extractors)."""
    return list(stage_config("walls")(wildcards)["extractors"])


def score_ks(wildcards):
    """The k labels of walls.k, as strings ("5", "all")."""
    return [str(k) for k in stage_config("walls")(wildcards)["k"]]


def score_reference_kind(wildcards):
    """What the walls are scored against (floorscan.score.ground_truth): the simulator's
    ground truth on a synthetic dataset, the reference on a real recording."""
    return GROUND_TRUTH if is_synthetic(wildcards.dataset) else REFERENCE


def dataset_config(wildcards):
    """The dataset's own entry (format, path, options), without `params` and the drawn
    `reference` (evaluation data, read by score_drawn)."""
    ds = {k: v for k, v in DATASETS[wildcards.dataset].items() if k not in ("params", "reference")}
    ds["name"] = wildcards.dataset
    return ds


def ingest_dataset(wildcards):
    """The dataset entry as ingest reads it; synthetic datasets read their simulation."""
    ds = dataset_config(wildcards)
    if ds.get("format") == "synthetic":
        if ds.get("recording", "bag") == "pcd":
            ds.update(format="pcd", path=recording_input(wildcards), locations="locations.csv")
        else:
            ds.update(
                format="rosbag",
                path=recording_input(wildcards),
                scan_topic="/scan",
                pose={"source": "topic", "topic": "/amcl_pose", "base_frame": "base_link"},
            )
    return ds


# ---------------------------------------------------------------------------------------
# Files: input functions of several rule files, logs and benchmarks

def is_synthetic(dataset):
    return DATASETS[dataset].get("format") == "synthetic"


def log_path(stage):
    return f"results/{{dataset}}/logs/{stage}.log"


def benchmark_path(stage):
    return f"results/{{dataset}}/benchmarks/{stage}.tsv"


def recording_input(wildcards):
    """The recording a dataset reads: its path, or the simulated one for synthetic data."""
    ds = DATASETS[wildcards.dataset]
    if ds.get("format") == "synthetic":
        if ds.get("recording", "bag") == "pcd":
            return f"results/{wildcards.dataset}/sim/pcd"
        return f"results/{wildcards.dataset}/sim/recording.bag"
    return ds["path"]


def recommended_floorplan_inputs(wildcards):
    """Inputs of `recommended_floorplan` (and of each floor of `building`)."""
    ds = wildcards.dataset
    extractor = plan_extractor(wildcards)
    walls = f"results/{ds}/walls/map/selected.parquet" if extractor == "map" else f"results/{ds}/walls/{extractor}/per_scan.parquet"
    return {
        "scans": f"results/{ds}/selection/scans.parquet",
        "walls": walls,
        "grid": f"results/{ds}/walls/map/selected_grid.parquet",
        "index": f"results/{ds}/scan_index.parquet",
    }


def score_reference_inputs(wildcards):
    """What the walls are scored against (score_runs, score_walls_figures): the
    simulator's walls, or the walls of every extractor from all kept scans
    (score.reference_source: the kall table of score.figure_ordering, or the per-scan
    table)."""
    ds = wildcards.dataset
    if is_synthetic(ds):
        return {"ground_truth": f"results/{ds}/sim/walls.geojson"}
    cfg = stage_config("score")(wildcards)
    if cfg["reference_source"] == "kall":
        o = cfg["figure_ordering"]
        refs = [f"results/{ds}/walls/{o}/{e}/kall.parquet" for e in score_extractors(wildcards)]
    else:
        refs = [f"results/{ds}/walls/{e}/per_scan.parquet" for e in score_extractors(wildcards)]
    return {"reference": refs}


# The file grid of the walls stage (walls.k, walls.orderings, walls.extractors: global,
# FILE_GRID_KEYS): the k wildcard values and the wildcards' constraints.
def _alternatives(values):
    return "|".join(re.escape(str(v)) for v in values)


def walls_k_names():
    """k wildcard values of config walls.k: 5 -> "5", "all" -> "all" (files k5 ... kall)."""
    return [str(k) for k in config["walls"]["k"]]


WALLS_CONSTRAINTS = dict(
    ordering=_alternatives(config["walls"]["orderings"]),
    extractor=_alternatives(config["walls"]["extractors"]),
)


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

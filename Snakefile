# floorscan: scan selection and wall extraction for indoor floor plans.
# Run: snakemake --cores 2            (default target: the datasets in config `target`)
#      snakemake --cores 2 --config target='[intel]'
#      snakemake --cores 2 --config path=/data/run.bag   (a recording of your own)
#      snakemake --cores 2 --config path=/data/survey/   (a folder of recordings: one answer each)
import functools
import os
import sys
import time
from pathlib import Path

from snakemake.utils import min_version

from floorscan.core.config import ConfigError, config_errors_exit, validate_config
from floorscan.core.datasets import (
    SHIPPED_CONFIG, add_path_datasets, check_datasets, config_paths, resolve_building, shipped_datasets,
)
from floorscan.core.io import InputError
from floorscan.figures.run_end import MANIFEST_ENV, failed_since, report_command, run_answer, write_manifest
from floorscan.ingest.detect import recordings_in

min_version("9.14.8")


configfile: "config/config.yaml"


report: "workflow/report/workflow.rst"


# A bad config stops the run here with one paragraph naming the key (config_errors_exit)
with config_errors_exit():
    validate_config(config, workflow.basedir + "/workflow/schemas/config.schema.yaml")
    check_datasets(config)  # empty paths, unknown buildings
    # `--config path=/data/run.bag`: that recording, detected, is the dataset to build;
    # a folder of recordings: each one is (floorscan.ingest.detect.recordings_in)
    # several paths (a list, `floorscan run A B`): one run of the recordings of all of them
    if config_paths(config):
        _recordings, _skipped = [], []
        for _path in config_paths(config):
            try:
                _found, _left_out = recordings_in(_path)
            except InputError as e:
                raise ConfigError(f"path: {e}") from None
            _recordings += [r for r in _found if r not in _recordings]
            _skipped += _left_out
        # each named after its file; a shipped example of that name gives way
        add_path_datasets(config, _recordings, shipped_datasets(Path(workflow.basedir) / SHIPPED_CONFIG))
        # the datasets made of the paths, with path_options: checked as a config file's
        # (the building, checked above, now names its floors' datasets: left out)
        validate_config({k: v for k, v in config.items() if k != "building"},
                        workflow.basedir + "/workflow/schemas/config.schema.yaml")
        if len(_recordings) > 1 or _skipped:  # what a folder held that is no recording: always said
            _one = "1 recording, one dataset" if len(_recordings) == 1 else f"{len(_recordings)} recordings, one dataset each"
            print(f"{', '.join(config_paths(config))}: {_one}: {', '.join(config['target'])}"
                  + (f" (not recordings, left out: {', '.join(_skipped)})" if _skipped else ""), file=sys.stderr)
    else:
        resolve_building(config)


include: "workflow/rules/common.smk"
include: "workflow/rules/simulate.smk"
include: "workflow/rules/ingest.smk"
include: "workflow/rules/register.smk"
include: "workflow/rules/select.smk"
include: "workflow/rules/walls.smk"
include: "workflow/rules/floorplan.smk"
include: "workflow/rules/building.smk"
include: "workflow/rules/score.smk"
include: "workflow/rules/figures.smk"


# The three target rules run a command that does nothing and have no output: Snakemake
# always runs such a rule when it is a target ("Rules with a run or shell declaration but
# no output are always executed"), so a run with nothing else to do still ends in
# onsuccess, which prints the answer (below). A file target that is up to date is
# "Nothing to be done": Snakemake runs no handler then (the `floorscan` command prints
# the answer all the same).
rule all:
    default_target: True
    localrule: True
    input:
        all_outputs() + building_outputs(),
    shell:
        ":"


# The answer alone: the selected scans and the recommended floor plan.
rule plan:
    localrule: True
    input:
        plan_outputs() + building_outputs(),
    shell:
        ":"


# The evaluation grid, the reference map, the scores, curves and figures, with the
# answer they score.
rule evaluation:
    localrule: True
    input:
        plan_outputs() + evaluation_outputs(),
    shell:
        ":"


# The answer of the run's datasets (floorscan.figures.run_end), from public API only:
# Snakemake's onsuccess / onerror handlers, which read the run's files (a dataset ran when
# its stage logs were written since the Snakefile was read, failed when one of them holds
# an error; the others go on: `keep-going` in the profile), and rewrite results/index.html
# (every dataset results/ holds, this run's first). The `floorscan` command asks for a
# manifest of the run instead (MANIFEST_ENV) and prints the answer itself after Snakemake
# ends, a file target with nothing to be done included.
_RUN_START_NS = time.time_ns()
_MANIFEST = os.environ.get(MANIFEST_ENV)


def building_answer():
    """The building's page, IFC and number of storeys, for the answer; None without one."""
    files = building_outputs()
    return {"ifc": files[0], "page": files[1], "storeys": len(building_floors())} if files else None


if _MANIFEST:
    write_manifest(_MANIFEST, target_datasets(), building_answer())


def print_answer(log, error):
    if _MANIFEST:
        return  # the floorscan command prints it
    command = functools.partial(report_command, sys.argv)  # (a line may not begin with the keyword `report`)
    for line in run_answer(target_datasets(), DATASETS, _RUN_START_NS, "results", (), command, building_answer()):
        print(line)
    if error and not any(failed_since(ds, _RUN_START_NS) for ds in DATASETS):  # no stage logged its error
        print(f"a job failed (killed, or an output missing); Snakemake's log: {log}")


onsuccess:
    print_answer(log, error=False)


onerror:
    print_answer(log, error=True)

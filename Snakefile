# floorscan: scan selection and wall extraction for indoor floor plans.
# Run: snakemake --cores 2            (default target: the datasets in config `target`)
#      snakemake --cores 2 --config target='[intel]'
#      snakemake --cores 2 --config path=/data/run.bag   (a recording of your own)
#      snakemake --cores 2 --config path=/data/survey/   (a folder of recordings: one answer each)
import atexit
import os
import sys
from pathlib import Path

from snakemake_interface_executor_plugins.settings import ExecMode
from snakemake.utils import min_version

from floorscan.core.config import ConfigError, config_errors_exit, validate_config
from floorscan.core.datasets import (
    SHIPPED_CONFIG, add_path_datasets, check_datasets, config_paths, resolve_building, shipped_datasets,
)
from floorscan.core.io import InputError
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


rule all:
    default_target: True
    input:
        all_outputs() + building_outputs(),


# The answer alone: the selected scans and the recommended floor plan.
rule plan:
    input:
        plan_outputs() + building_outputs(),


# The evaluation grid, the reference map, the scores, curves and figures, with the
# answer they score.
rule evaluation:
    input:
        plan_outputs() + evaluation_outputs(),


# The answer, wherever the run starts (floorscan.figures.answer): the datasets of the
# run's targets, when it ends, when it fails (each failed recording's error; the others
# go on: `keep-going` in the profile) and when there was nothing to be done (Snakemake
# runs no hook then, so an exit handler of the main process prints it). Every run
# rewrites results/index.html: its datasets, then the others results/ holds.
_ANSWER = {"printed": False}
_WORKDIR = Path.cwd()  # the working directory: an exit handler runs after Snakemake has left it


def print_answer(failed_jobs=()):
    from floorscan.figures.answer import answer_lines, run_datasets
    from floorscan.figures.index_page import dataset_status, failure_text, write_index

    if _ANSWER["printed"]:
        return
    _ANSWER["printed"] = True
    datasets = run_datasets(workflow.dag_settings.targets, DATASETS, target_datasets())
    failed = {}  # several recordings: each error again at the end; one: where it is
    for job in failed_jobs:
        ds = dict(job.wildcards_dict).get("dataset")
        if ds in datasets and ds not in failed:
            where = f"rule {job.rule.name} failed; its log: {', '.join(map(str, job.log))}"
            failed[ds] = (failure_text(ds) or where) if len(datasets) > 1 else f"{where} (the error is above)"
    # results/index.html: this run's datasets, then every other one results/ holds a page of
    statuses = [{**dataset_status(ds), "failed": failed[ds]} if ds in failed else dataset_status(ds) for ds in datasets]
    earlier = sorted({p.parent.name for p in Path("results").glob("*/front.html")} - set(datasets))
    write_index(statuses + [dataset_status(ds) for ds in earlier], "results/index.html")
    command = ""
    if isinstance(config.get("path"), str):  # the run's own paths and config files, quoted for a shell
        import shlex

        files = [str(f) for f in (workflow.config_settings.configfiles or []) if Path(str(f)).name != "config.yaml"]
        words = [sys.argv[0], "--cores", "2", "--config", f"path={config['path']}"]
        command = shlex.join(words + (["--configfile", *files] if files else []))
    for line in answer_lines(datasets, failed=failed, command=command):
        print(line)
    building = building_outputs()  # building.ifc, its page, the floors' GeoJSON
    if building and Path(building[1]).is_file():
        print(f"building: {building[1]}, {building[0]} ({len(building_floors())} storeys)")
    if failed:
        print(f"{len(failed)} of {len(datasets)} recordings failed: {', '.join(failed)}")


def _answer_if_nothing_was_done():
    ran = getattr(workflow, "scheduler", None) is not None and workflow.dag is not None
    if ran and len(workflow.dag) == 0 and not workflow.dryrun:
        os.chdir(_WORKDIR)  # `--directory` (floorscan run from another folder): results/ is here
        print_answer()


if workflow.exec_mode == ExecMode.DEFAULT:
    atexit.register(_answer_if_nothing_was_done)


onsuccess:
    print_answer()


onerror:
    print_answer(workflow.scheduler.failed)

# floorscan: scan selection and wall extraction for indoor floor plans.
# Run: snakemake --cores 2            (default target: the datasets in config `target`)
#      snakemake --cores 2 --config target='[intel]'
#      snakemake --cores 2 --config path=/data/run.bag   (a recording of your own)
from snakemake.utils import min_version

from floorscan.core.config import add_path_dataset, check_datasets, config_errors_exit, validate_config

min_version("9.14.8")


configfile: "config/config.yaml"


report: "workflow/report/workflow.rst"


# A bad config stops the run here with one paragraph naming the key (config_errors_exit)
with config_errors_exit():
    validate_config(config, workflow.basedir + "/workflow/schemas/config.schema.yaml")
    check_datasets(config)  # empty paths, unknown buildings
    # `--config path=/data/run.bag`: that recording, detected, is the dataset to build
    add_path_dataset(config)


include: "workflow/rules/common.smk"
include: "workflow/rules/simulate.smk"
include: "workflow/rules/ingest.smk"
include: "workflow/rules/register.smk"
include: "workflow/rules/select.smk"
include: "workflow/rules/walls.smk"
include: "workflow/rules/floorplan.smk"
include: "workflow/rules/score.smk"
include: "workflow/rules/report.smk"


rule all:
    default_target: True
    input:
        all_outputs(),


# The answer alone: the selected scans and the recommended floor plan.
rule plan:
    input:
        plan_outputs(),


# The evaluation grid, the reference map, the scores, curves and figures.
rule evaluation:
    input:
        evaluation_outputs(),


# The answer: where the floor plan, the scan list and the reduced recording are.
onsuccess:
    from floorscan.figures.answer import answer_lines

    for _line in answer_lines(target_datasets()):
        print(_line)

"""Stage floorplan, the answer's plans of the first k scans: the jobs' shares
(rule answer_floorplans_part) moved into one folder, evaluation/answer_plans/k<k>/, and
the plan of all kept scans (rule all_scans_floorplan) copied in as the last k
(floorscan.floorplan.answer_plans.merge_answer_plans)."""
from floorscan.core.stage import stage_log
from floorscan.floorplan.answer_plans import merge_answer_plans

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    ks = merge_answer_plans(smk.input.parts, smk.output.plans, smk.input.all_scans)
    log.info("the answer's plans of the first k scans: k %s (the last: the plan of all kept scans)", " ".join(map(str, ks)))

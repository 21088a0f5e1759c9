"""Stage floorplan, the evaluation grid: the plan of the first k scans of every ordering
and k of one extractor (floorscan.floorplan.grid), as Parquet tables for the score stage
and in the formats of floorscan.floorplan.EVALUATION_FORMATS for people, in the map frame."""
from floorscan.core.io import read_table
from floorscan.core.stage import stage_log
from floorscan.floorplan import floorplan_outputs
from floorscan.floorplan.grid import write_plan_grid
from floorscan.floorplan.metadata import recording_timestamp

with stage_log(snakemake):  # noqa: F821
    smk = snakemake  # noqa: F821
    wc = smk.wildcards
    runs = [tuple(r) for r in smk.params.runs]
    stems = [f"results/{wc.dataset}/evaluation/floorplan/{o}_{wc.extractor}_k{k}" for o, k in runs]
    write_plan_grid(
        read_table(smk.input.walls), {o: read_table(p) for o, p in zip(smk.params.orderings, smk.input.orderings)},
        runs, list(smk.output.plans), [floorplan_outputs(stem, smk.params.formats) for stem in stems],
        smk.params.cfg, wc.dataset, wc.extractor, recording_timestamp(smk.input.index),
    )

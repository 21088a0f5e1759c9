"""Stage `score`, the figures of the walls and floor plans of a dataset (thesis Figs.
5.1, 5.5, 5.10 - 5.12): they need the figure extractor's scores alone, so they are
drawn while the other runs are scored. The floor plans are drawn as their exports draw
them (the floorplan stage's footprints)."""

from floorscan.core.io import read_table
from floorscan.core.stage import stage_log
from floorscan.figures.scoring import make_walls_figures
from floorscan.floorplan.footprints import read_plan_footprints
from floorscan.score.ground_truth import load_references

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    kind = smk.params.reference_kind
    extractors = list(smk.params.extractors)
    reference = load_references(
        kind, extractors, smk.input.get("ground_truth"), smk.input.get("reference", [])
    )
    walls = {tuple(r): read_table(p) for r, p in zip(smk.params.walls_runs, smk.input.walls)}
    floorplans = {
        tuple(r): read_plan_footprints(p)
        for r, p in zip(smk.params.floorplan_runs, smk.input.floorplans)
    }
    make_walls_figures(
        dataset=smk.wildcards.dataset,
        reference=reference,
        reference_kind=kind,
        walls=walls,
        scores=read_table(smk.input.scores[0]) if smk.input.scores else None,  # the figure extractor's
        floorplans=floorplans,
        points=str(smk.input.registered),  # read in batches, not held whole
        scan_status={e: read_table(p) for e, p in zip(extractors, smk.input.scan_status)},
        scan_times={e: read_table(p) for e, p in zip(extractors, smk.input.scan_times)},
        outputs=dict(smk.output.items()),
        cfg=smk.params.cfg,
        log=log,
    )

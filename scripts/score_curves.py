"""Stage score, the curves of one extractor: the floor plan of the first k scans of
every ordering (the workflow's, seeded random ones, and the completeness oracle)
against the reference map, on a k grid of 2 % of the kept scans (every k up to 20 %,
beyond it where the levels of the all-scan F1 are crossed: floorscan.score.curves). The
plans are the floorplan stage's builder's (floorscan.floorplan.scans.ScanPlans)."""
from floorscan.core.config import stage_params
from floorscan.core.io import read_table, write_table
from floorscan.core.stage import stage_log
from floorscan.floorplan.params import FloorplanParams
from floorscan.floorplan.scans import ScanPlans
from floorscan.score.params import ScoreParams
from floorscan.score import curves as C

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    cfg = stage_params(ScoreParams, smk.params.cfg)
    per_scan = read_table(smk.input.walls)
    # the one plan builder, its merge's first pass tested once for every subset
    plans = ScanPlans(per_scan, stage_params(FloorplanParams, smk.params.floorplan), prepared=True)
    curves, oracle = C.score_curves(
        per_scan=per_scan,
        orderings={o: read_table(p) for o, p in zip(smk.params.orderings, smk.input.orderings)},
        reference_path=smk.input.reference_map,
        plan_faces=plans.faces,
        taus_m=tuple(cfg.taus_m),
        oracle_tau_m=float(cfg.summary_tau_m),
        step_fraction=float(cfg.curve_step_fraction),
        random_seeds=int(cfg.random_seeds),
        dense_fraction=float(cfg.curve_auc_fraction),
        levels=tuple(float(v) for v in cfg.summary_levels),
        log=log,
    )
    meta = {"dataset": smk.wildcards.dataset, "extractor": smk.wildcards.extractor,
            "n_kept": str(int(curves["n_kept"].iloc[0])) if len(curves) else "0"}
    write_table(curves, smk.output.curves, metadata=meta)
    write_table(oracle, smk.output.oracle, metadata=meta)

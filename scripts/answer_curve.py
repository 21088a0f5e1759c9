"""Stage score, the answer's quality curve: the answer's plans of the first k scans of the
default ordering (built by the floorplan stage, evaluation/answer_plans) against the
reference map (floorscan.score.answer_curve)."""
from floorscan.core.files import atomic_path
from floorscan.core.score_tables import k_reaching
from floorscan.core.stage import stage_log
from floorscan.score.against_reference import read_reference
from floorscan.score.answer_curve import answer_curve

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    curve = answer_curve(smk.input.plans, read_reference(smk.input.reference))
    with atomic_path(smk.output.curve) as tmp:
        curve.to_csv(tmp, index=False, float_format="%.4f")
    log.info("the answer's plan against the reference map: F1 at 5 cm %s; k95 %s, k99 %s of %d kept scans",
             " ".join(f"{k}:{f:.3f}" for k, f in zip(curve["k"], curve["f1_5cm"])),
             k_reaching(curve, 0.95), k_reaching(curve, 0.99), int(curve["k"].iloc[-1]) if len(curve) else 0)

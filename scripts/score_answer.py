"""Stage score, the answer: the recommended plan and the plan of all kept scans scored
as plans a person opens (floorscan.score.answer), one row per plan."""
from floorscan.core.files import atomic_path
from floorscan.core.stage import stage_log
from floorscan.score.answer import score_answer

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    table = score_answer(
        {"recommended": smk.input.recommended, "all_scans_map": smk.input.all_scans_map},
        smk.input.reference, smk.input.get("ground_truth"),
    )
    with atomic_path(smk.output.table) as tmp:
        table.to_csv(tmp, index=False, float_format="%.4f")
    for row in table.to_dict("records"):
        log.info("%s", ", ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}" for k, v in row.items()))

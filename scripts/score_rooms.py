"""Stage score, the rooms: the recommended and the all-scan map plans' rooms and doors
against the simulator's true rooms and doors (floorscan.score.rooms), or, on a real
recording without a drawn segmentation, their counts; and the rooms overlay."""
from floorscan.core.files import atomic_path
from floorscan.core.stage import stage_log
from floorscan.figures.rooms import rooms_overlay_figure
from floorscan.score.against_reference import read_reference
from floorscan.score.rooms import score_room_plans

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    table, overlay = score_room_plans(
        {"recommended": smk.input.recommended, "all_scans_map": smk.input.all_scans_map},
        read_reference(smk.input.reference), smk.input.get("ground_truth"),
    )
    with atomic_path(smk.output.table) as tmp:
        table.to_csv(tmp, index=False, float_format="%.4f")
    rooms_overlay_figure(overlay, smk.wildcards.dataset, smk.output.figure)
    for row in table.to_dict("records"):
        log.info("%s", ", ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}" for k, v in row.items()))

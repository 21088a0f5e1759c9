"""Stage score, the plan drawn by people: aligned to the map frame, the recommended and
the all-scan map plans scored against it (floorscan.score.drawn), and the overlay."""
from floorscan.core.files import atomic_path
from floorscan.core.occupancy import read_grid
from floorscan.core.stage import stage_log
from floorscan.figures.drawn import drawn_overlay_figure
from floorscan.score.drawn import score_drawn_plans

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    table, info, overlay = score_drawn_plans(
        {"recommended": smk.input.recommended, "all_scans_map": smk.input.all_scans_map},
        smk.input.drawn, read_grid(smk.input.reference), smk.params.reference,
    )
    with atomic_path(smk.output.table) as tmp:
        table.to_csv(tmp, index=False, float_format="%.4f")
    drawn_overlay_figure(overlay, info, smk.wildcards.dataset, smk.output.figure)
    log.info("drawn plan aligned (%s): scale %.4f m/px, %.2f deg; residual median %.3f m, 90 %% %.3f m",
             info["start"], info["scale_m_per_px"], info["angle_deg"], info["residual_median_m"], info["residual_p90_m"])
    for row in table.to_dict("records"):
        log.info("%s: %s", row["plan"], ", ".join(f"{k} {v:.3f}" for k, v in row.items() if k.startswith(("compl", "corr", "f1"))))

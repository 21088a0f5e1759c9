"""Stage score, the plan drawn by people: aligned to the map frame, the recommended and
the all-scan map plans scored against it (floorscan.score.drawn), and the overlay; with
the same alignment their rooms against the rooms drawn by people, when the dataset's
reference names them (floorscan.score.rooms), and the rooms overlay."""
from floorscan.core.files import atomic_path
from floorscan.core.stage import stage_log
from floorscan.figures.drawn import drawn_overlay_figure
from floorscan.figures.rooms import rooms_overlay_figure
from floorscan.score.against_reference import read_reference
from floorscan.score.drawn import score_drawn_plans
from floorscan.score.drawn_rooms import read_drawn_rooms, score_drawn_rooms
from floorscan.score.rooms import score_room_plans

with stage_log(snakemake) as log:  # noqa: F821
    smk = snakemake  # noqa: F821
    plans = {"recommended": smk.input.recommended, "all_scans_map": smk.input.all_scans_map}
    grid = read_reference(smk.input.reference)
    table, info, overlay = score_drawn_plans(plans, smk.input.drawn, grid, smk.params.reference)
    with atomic_path(smk.output.table) as tmp:
        table.to_csv(tmp, index=False, float_format="%.4f")
    drawn_overlay_figure(overlay, info, smk.wildcards.dataset, smk.output.figure)
    log.info("drawn plan aligned (%s): scale %.4f m/px, %.2f deg; residual median %.3f m, 90 %% %.3f m",
             info["start"], info["scale_m_per_px"], info["angle_deg"], info["residual_median_m"], info["residual_p90_m"])
    for row in table.to_dict("records"):
        log.info("%s: %s", row["plan"], ", ".join(f"{k} {v:.3f}" for k, v in row.items() if k.startswith(("compl", "corr", "f1"))))
    if smk.input.get("rooms"):
        transform = overlay["transform"]
        labels = read_drawn_rooms(smk.input.rooms, transform.scale)
        log.info("%s: %d drawn rooms", smk.input.rooms, labels.max())
        rooms, rooms_overlay = score_drawn_rooms(plans, labels, transform, grid)
    else:  # no drawn rooms: the plans' room and door counts only
        rooms, rooms_overlay = score_room_plans(plans, grid)
    with atomic_path(smk.output.rooms) as tmp:
        rooms.to_csv(tmp, index=False, float_format="%.4f")
    rooms_overlay_figure(rooms_overlay, smk.wildcards.dataset, smk.output.rooms_figure)
    for row in rooms.to_dict("records"):
        log.info("rooms %s", ", ".join(f"{k}={v:.3f}" if isinstance(v, float) else f"{k}={v}" for k, v in row.items()))

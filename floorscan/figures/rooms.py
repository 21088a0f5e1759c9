"""The overlay of a floor plan's rooms on the true rooms (:mod:`floorscan.score.rooms`):
the true rooms filled (the simulator's, or a segmentation drawn by people, aligned;
those the recording saw too little of hatched), the plan's rooms outlined over them,
matched pairs joined and labelled with their IoU, unmatched true rooms labelled with
why (:func:`floorscan.score.segmentation.room_errors`); on a synthetic recording also
the doors."""

from __future__ import annotations

import os

#: Colours: matched (green), unmatched plan room (red), left out of precision (grey).
MATCHED, FALSE_ROOM, LEFT_OUT = "#16a34a", "#dc2626", "#6b7280"
#: Fills of the true rooms: matched, unmatched, not scored.
TRUE_MATCHED, TRUE_MISSED, TRUE_UNSCORED = "#bfdbfe", "#fde68a", "#e5e7eb"


def _polygons(geom):
    for g in getattr(geom, "geoms", [geom]):
        if g.geom_type == "Polygon" and not g.is_empty:
            yield g


def rooms_overlay_figure(overlay: dict, dataset: str, path: str | os.PathLike, plan: str = "recommended") -> None:
    """Write the rooms overlay (PNG) of :func:`floorscan.score.rooms.score_room_plans`'s
    or :func:`floorscan.score.drawn_rooms.score_drawn_rooms`'s ``overlay`` for ``plan``
    (map frame, metres).

    Parameters
    ----------
    overlay : dict
        ``structure``, ``plans`` (per plan its ``rooms``, ``doors_xy``,
        ``rooms_detail``), ``true_rooms``, ``counted``, ``true_doors_xy``,
        ``true_doors_counted`` and ``truth``; map metres.
    dataset : str
    path : path
        PNG output, written atomically (:func:`~floorscan.figures.style.save_figure`).
    plan : str
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    from matplotlib.patches import Patch

    from floorscan.figures.style import save_figure

    entry = overlay["plans"].get(plan, {"rooms": [], "doors_xy": np.empty((0, 2))})
    detail = entry.get("rooms_detail")
    pairs = detail["pairs"] if detail is not None else np.empty((0, 2), int)
    pair_iou = detail["pair_iou"] if detail is not None else np.empty(0)
    left_out = detail["left_out"] if detail is not None else np.zeros(len(entry["rooms"]), bool)
    true_matched, plan_matched = set(pairs[:, 0].tolist()), set(pairs[:, 1].tolist())
    st = overlay["structure"]
    fig, ax = plt.subplots(figsize=_figsize(st, overlay["true_rooms"], entry["rooms"]), layout="constrained")
    ax.scatter(st[:, 0], st[:, 1], s=0.3, c="#9ca3af", zorder=1)
    for t, room in enumerate(overlay["true_rooms"]):
        counted = bool(overlay["counted"][t])
        colour = TRUE_MATCHED if t in true_matched else (TRUE_MISSED if counted else TRUE_UNSCORED)
        for g in _polygons(room):
            x, y = g.exterior.xy
            ax.fill(x, y, facecolor=colour, edgecolor="#1e3a8a", lw=0.6, hatch=None if counted else "//", zorder=2)
            for hole in g.interiors:
                hx, hy = hole.xy
                ax.fill(hx, hy, facecolor="white", edgecolor="#1e3a8a", lw=0.6, zorder=2)
    for p, room in enumerate(entry["rooms"]):
        colour = MATCHED if p in plan_matched else (LEFT_OUT if left_out[p] else FALSE_ROOM)
        for g in _polygons(room):
            for ring in [g.exterior, *g.interiors]:
                x, y = ring.xy
                ax.plot(x, y, color=colour, lw=1.4, ls="--" if left_out[p] else "-", zorder=3)
    for (t, p), iou in zip(pairs.tolist(), pair_iou.tolist()):
        a, b = overlay["true_rooms"][t].representative_point(), entry["rooms"][p].representative_point()
        ax.plot([a.x, b.x], [a.y, b.y], color=MATCHED, lw=0.8, zorder=4)
        ax.text(b.x, b.y, f"{iou:.2f}", fontsize=7, color="#14532d", ha="center", va="center", zorder=5)
    cause = detail["true_cause"] if detail is not None else np.full(len(overlay["true_rooms"]), "", dtype=object)
    for t, room in enumerate(overlay["true_rooms"]):
        if overlay["counted"][t] and t not in true_matched:
            c = room.representative_point()
            ax.text(c.x, c.y, cause[t] or "unmatched", fontsize=7, color="#92400e", ha="center", va="center", zorder=5)
    txy, tc = overlay["true_doors_xy"], overlay["true_doors_counted"]
    if len(txy):
        ax.scatter(txy[tc, 0], txy[tc, 1], s=40, marker="s", facecolors="none", edgecolors="#1e3a8a", zorder=6)
        ax.scatter(txy[~tc, 0], txy[~tc, 1], s=40, marker="s", facecolors="none", edgecolors="#9ca3af", zorder=6)
    pxy = entry["doors_xy"]
    if len(pxy):
        ax.scatter(pxy[:, 0], pxy[:, 1], s=14, marker="o", c="#7c3aed", zorder=7)
    handles = [
        Patch(facecolor=TRUE_MATCHED, edgecolor="#1e3a8a", label="true room, matched"),
        Patch(facecolor=TRUE_MISSED, edgecolor="#1e3a8a", label="true room, unmatched (labelled why)"),
        Patch(facecolor=TRUE_UNSCORED, edgecolor="#1e3a8a", hatch="//", label="true room seen too little (not scored)"),
        Patch(facecolor="none", edgecolor=MATCHED, label=f"{plan} plan's room, matched (IoU)"),
        Patch(facecolor="none", edgecolor=FALSE_ROOM, label=f"{plan} plan's room, unmatched"),
        Patch(facecolor="none", edgecolor=LEFT_OUT, ls="--", label=f"{plan} plan's room in unscored true rooms"),
    ]  # fmt: skip
    if len(txy) or len(pxy):
        handles.append(Patch(facecolor="none", edgecolor="#7c3aed", label="true door (square), plan door (dot)"))
    fig.legend(handles=handles, loc="outside lower center", ncols=2, fontsize=7, frameon=False)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m, map frame)")
    ax.set_ylabel("y (m, map frame)")
    ax.set_title(_title(overlay, dataset, plan), fontsize=10)
    save_figure(fig, path)


def _figsize(structure, true_rooms, plan_rooms) -> tuple[float, float]:
    """Width and height of the figure, inches (:func:`~floorscan.figures.style.map_figsize`):
    the extent of ``structure`` ((N, 2) metres) and of the rooms' bounds."""
    import numpy as np

    from floorscan.figures.style import map_figsize

    bounds = [g.bounds for g in [*true_rooms, *plan_rooms] if not g.is_empty]
    pts = np.asarray(structure, dtype=np.float64).reshape(-1, 2)
    if len(pts):
        bounds.append((*pts.min(axis=0), *pts.max(axis=0)))
    if not bounds:
        return map_figsize(1.0, 1.0, margin_in=2.6)
    b = np.asarray(bounds, dtype=np.float64)
    return map_figsize(b[:, 2].max() - b[:, 0].min(), b[:, 3].max() - b[:, 1].min(), margin_in=2.6)


def _title(overlay: dict, dataset: str, plan: str) -> str:
    truth = {"ground_truth": "the simulator's rooms", "drawn": "the rooms drawn by people", "none": "no true rooms"}
    head = f"{dataset}: {plan} plan's rooms against {truth[overlay['truth']]}"
    table = overlay.get("scores")
    if table is None or plan not in set(table["plan"]):
        return head
    r = table[table["plan"] == plan].iloc[0]
    if overlay["truth"] == "none":
        return f"{head}; {int(r.n_plan_rooms)} rooms, {int(r.n_plan_doors)} doors"
    text = (f"{head}\nrooms: precision {r.room_precision:.2f}, recall {r.room_recall:.2f} at IoU 0.5, "
            f"mean IoU {r.room_mean_iou:.2f} ({int(r.n_matched_rooms)} of {int(r.n_true_rooms)} seen true rooms, "
            f"{int(r.n_plan_rooms_scored)} plan rooms)")  # fmt: skip
    if r.n_matched_rooms < max(r.n_true_rooms, r.n_plan_rooms_scored):
        text += (f"\nunmatched true rooms: {int(r.n_true_merged)} merged, {int(r.n_true_split)} split, "
                 f"{int(r.n_true_uncovered)} uncovered\nunmatched plan rooms: {int(r.n_plan_pieces)} a piece of one, "
                 f"{int(r.n_plan_spanning)} across several, {int(r.n_plan_extra)} where none is drawn")  # fmt: skip
    if overlay["truth"] == "ground_truth":
        text += (f"\ndoors: recall {r.door_recall:.2f}, precision {r.door_precision:.2f}, "
                 f"centre error {r.door_centre_error_m:.2f} m")  # fmt: skip
    return text

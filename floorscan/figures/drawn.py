"""The overlay of a floor plan on the plan drawn by people, aligned to the map frame
(:mod:`floorscan.score.drawn`): the drawn walls (the parts the recording saw, and the
rest lighter), the reference map's structure and the recommended plan's faces."""

from __future__ import annotations

import os


def drawn_overlay_figure(overlay: dict, info: dict, dataset: str, path: str | os.PathLike, plan: str = "recommended") -> None:
    """Write the overlay figure (PNG) of :func:`floorscan.score.drawn.score_drawn_plans`'s
    ``overlay`` and alignment ``info``.

    Parameters
    ----------
    overlay : dict
        ``drawn_xy``, ``seen``, ``structure``, ``faces`` (map metres).
    info : dict
        :func:`floorscan.score.drawn.align_drawn`'s info.
    dataset : str
    path : path
        PNG output, written atomically (:func:`~floorscan.figures.style.save_figure`).
    plan : str
        Which plan's faces are drawn.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    import numpy as np

    from floorscan.figures.style import map_figsize, save_figure

    xy, seen, st = overlay["drawn_xy"], overlay["seen"], overlay["structure"]
    every = np.concatenate([np.asarray(xy, np.float64).reshape(-1, 2), np.asarray(st, np.float64).reshape(-1, 2)])
    span = np.ptp(every, axis=0) if len(every) else np.ones(2)
    fig, ax = plt.subplots(figsize=map_figsize(*span), layout="constrained")
    ax.scatter(xy[~seen, 0], xy[~seen, 1], s=0.4, c="#c7d2fe", label="drawn walls, not seen by the recording")
    ax.scatter(xy[seen, 0], xy[seen, 1], s=0.6, c="#4338ca", label="drawn walls the recording saw")
    ax.scatter(st[:, 0], st[:, 1], s=0.3, c="#9ca3af", label="reference map structure (all kept scans)")
    faces = overlay["faces"].get(plan)
    if faces is not None and len(faces):
        ax.add_collection(LineCollection(faces.reshape(-1, 2, 2), colors="#dc2626", linewidths=1.0,
                                         label=f"{plan} plan's wall faces"))  # fmt: skip
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m, map frame)")
    ax.set_ylabel("y (m, map frame)")
    ax.set_title(
        f"{dataset}: the plan drawn by people, aligned (scale {info['scale_m_per_px'] * 100:.2f} cm/px, "
        f"{info['angle_deg']:.1f} deg);\nresidual median {info['residual_median_m']:.3f} m, "
        f"90 % {info['residual_p90_m']:.3f} m ({info['start']})", fontsize=10,
    )
    fig.legend(loc="outside lower center", ncols=2, fontsize=7, markerscale=8, frameon=False)
    save_figure(fig, path)

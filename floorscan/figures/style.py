"""What the scoring figures share: resolution, the colour of each ordering and
extractor, the name of what walls are scored against, and the atomic save.

Matplotlib with the Agg backend; every figure is written atomically
(:func:`floorscan.core.files.atomic_path`) by :func:`_save`. On real recordings the walls
scored against are a *reference* (walls from all kept scans), never called ground truth
(:func:`reference_name`). A new ordering or extractor gets its colour in
:data:`ORDERING_COLOURS` or :data:`EXTRACTOR_COLOURS`.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402

from floorscan.core.files import atomic_path  # noqa: E402
from floorscan.score.ground_truth import GROUND_TRUTH  # noqa: E402
from floorscan.score.segments import as_segments  # noqa: E402

DPI = 110
ORDERING_COLOURS = {
    "cluster_hull": "tab:red",
    "convex_hull": "tab:orange",
    "random": "tab:green",
    "sequential": "tab:blue",
    "motion_filter": "tab:purple",
    "wall_coverage": "tab:brown",
    "surface_coverage": "tab:pink",
}
EXTRACTOR_COLOURS = {"ransac": "tab:blue", "cluster_ransac": "tab:red"}


def reference_name(reference_kind: str) -> str:
    """``"ground truth"`` or ``"reference (all scans)"`` for titles and legends."""
    return "ground truth" if reference_kind == GROUND_TRUTH else "reference (all scans)"


def _save(fig, path, dpi=DPI) -> None:
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, format=path.suffix.lstrip(".") or "png")
    plt.close(fig)


def _segments_collection(segments, **kw) -> LineCollection:
    seg = as_segments(segments)
    return LineCollection(seg.reshape(-1, 2, 2), **kw)


def _square(ax) -> None:
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")

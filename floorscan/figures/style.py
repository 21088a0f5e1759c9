"""What every figure shares: resolution and the atomic save, the colour of each ordering
and extractor, the name of what walls are scored against.

Matplotlib with the Agg backend; every figure module writes its figures by
:func:`save_figure` (at :data:`DPI`, atomically: :func:`floorscan.core.files.atomic_path`).
On real recordings the walls scored against are a *reference* (walls from all kept
scans), never called ground truth (:func:`reference_name`). An ordering's colour follows
its place in the schema's enum of orderings (``walls.orderings``, which lists the
ordering registry's, :mod:`floorscan.select.registry`, in its order: a test checks), so
a new ordering needs no edit here; a new extractor gets its colour in
:data:`EXTRACTOR_COLOURS`.
"""

from __future__ import annotations

import itertools
import os
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402

from floorscan.core.files import atomic_path  # noqa: E402
from floorscan.core.score_tables import GROUND_TRUTH  # noqa: E402
from floorscan.core.segments import as_segments  # noqa: E402
from floorscan.core.config import schema_enum  # noqa: E402

#: Resolution of every figure, dots per inch.
DPI = 110
#: Tableau 10, matplotlib's default colours, in its order.
_TABLEAU = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple",
            "tab:brown", "tab:pink", "tab:gray", "tab:olive", "tab:cyan")
#: One colour per ordering, by its place in the schema's enum of orderings (the
#: registry's: the select job's, then the select_coverage job's); a line that is not
#: an ordering of the registry (``oracle``) has none.
ORDERING_COLOURS = dict(zip(schema_enum("walls", "orderings"), itertools.cycle(_TABLEAU)))
EXTRACTOR_COLOURS = {"ransac": "tab:blue", "cluster_ransac": "tab:red"}


#: The shortest and the tallest a map's axes are for their width, at equal scale: a
#: building 4 times as long as it is wide is drawn in a frame 0.3 as tall (its long
#: side across the page), a tall one no taller than 1.2 times the width.
MAP_ASPECT_RANGE = (0.3, 1.2)
#: The share of a map figure's width its axes take (the rest: the y axis' label and
#: ticks, the margins).
MAP_AXES_SHARE = 0.85


def map_figsize(width_m: float, height_m: float, width_in: float = 10.0, margin_in: float = 2.0) -> tuple[float, float]:
    """The size of a figure of one map at equal scale, inches: ``width_in`` wide, the
    axes as tall as the map's extent makes them (``height_m`` over ``width_m``, within
    :data:`MAP_ASPECT_RANGE`) plus ``margin_in`` for the title, the axis labels and
    what goes below them (a legend, colour bars), so that a long building fills the
    page instead of a strip in a square.

    Parameters
    ----------
    width_m, height_m : float
        The extent drawn, metres (any unit: only their ratio counts).
    width_in, margin_in : float
        Inches.

    Returns
    -------
    (float, float)
        Width and height, inches.
    """
    lo, hi = MAP_ASPECT_RANGE
    ratio = height_m / width_m if width_m > 0 else 1.0
    return float(width_in), float(width_in * MAP_AXES_SHARE * min(max(ratio, lo), hi) + margin_in)


def reference_name(reference_kind: str) -> str:
    """``"ground truth"`` or ``"reference (all scans)"`` for titles and legends.

    Parameters
    ----------
    reference_kind : str

    Returns
    -------
    str
    """
    return "ground truth" if reference_kind == GROUND_TRUTH else "reference (all scans)"


def save_figure(fig, path: str | os.PathLike) -> None:
    """Write ``fig`` at :data:`DPI` (format by the suffix, PNG without one),
    atomically, and close it.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : path
    """
    path = Path(path)
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=DPI, format=path.suffix.lstrip(".") or "png")
    plt.close(fig)


def segments_collection(segments, **kw) -> LineCollection:
    """Segments as a matplotlib collection (non-finite rows dropped).

    Parameters
    ----------
    segments : (M, 4) array_like
        ``x0, y0, x1, y1``, metres.
    **kw
        Passed to ``LineCollection``.

    Returns
    -------
    matplotlib.collections.LineCollection
    """
    seg = as_segments(segments)
    return LineCollection(seg.reshape(-1, 2, 2), **kw)


def square_axes(ax) -> None:
    """Equal aspect (by the data limits) and x, y labels in metres.

    Parameters
    ----------
    ax : matplotlib.axes.Axes
        Changed in place.
    """
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")

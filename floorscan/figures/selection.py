"""Figures of the scan selection (thesis Figs 5.6, 5.7, 5.8), matplotlib Agg, of the data
the select stage computes for them (:mod:`floorscan.select.figure_data`, which the
figure job's script hands over):

- :func:`plot_coverage_vs_scans`: covered area against number of scans, per ordering
  (Fig. 5.6), with the 99 % point of each ordering marked.
- :func:`plot_coverage_vs_clusters`: the greedy ``cluster_hull`` coverage curve for
  several numbers of KMeans clusters (Fig. 5.7).
- :func:`plot_selection_time`: time to order n scans, the lazy greedy against the
  reference Algorithm 1 (Fig. 5.8).
- :func:`selection_figures`: the three.
"""

from __future__ import annotations

import os
from typing import Mapping

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from floorscan.figures.style import ORDERING_COLOURS, save_figure  # noqa: E402

#: Line width of the greedy orderings in Fig. 5.6 (the baselines: 1.2).
_LINE_WIDTHS = {"cluster_hull": 2.0, "convex_hull": 1.5, "wall_coverage": 2.0, "surface_coverage": 1.5}


def _finish(fig, ax, dataset: str, what: str, path: str | os.PathLike) -> None:
    """Title (``"<dataset>: <what it shows>"``; what, capitalised, alone), grid and legend
    of a selection figure, then save it."""
    ax.set_title(f"{dataset}: {what}" if dataset else what[:1].upper() + what[1:], fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    save_figure(fig, path)


def plot_coverage_vs_scans(
    orderings: Mapping[str, pd.DataFrame], k99: Mapping[str, int], path: str | os.PathLike, title: str = ""
) -> None:
    """Thesis Fig. 5.6: cumulative covered area against number of scans per ordering;
    the point where each ordering reaches 99 % of its final area is marked.

    Parameters
    ----------
    orderings : mapping of str to pandas.DataFrame
        Ordering name -> ``rank``, ``covered_area_m2`` (square metres).
    k99 : mapping of str to int
        Ordering name -> the fewest scans reaching 99 % of its final area
        (:func:`floorscan.select.figure_data.k99`); 0: none marked.
    path : path
        PNG output, written atomically (:func:`~floorscan.figures.style.save_figure`).
    title : str
    """
    fig, ax = plt.subplots(figsize=(7, 4.5))
    # the registry's orderings in its order (their colours'), then any other
    for name in [o for o in ORDERING_COLOURS if o in orderings] + [o for o in orderings if o not in ORDERING_COLOURS]:
        o = orderings[name].sort_values("rank")
        cov = o["covered_area_m2"].to_numpy()
        n = np.arange(1, len(cov) + 1)
        k = int(k99[name])
        colour = ORDERING_COLOURS.get(name)
        ax.plot(n, cov, label=f"{name} (99 % at {k})", color=colour, lw=_LINE_WIDTHS.get(name, 1.2))
        if k:
            ax.plot([k], [cov[k - 1]], "o", color=colour, ms=5)
    ax.set_xscale("log")
    ax.set_xlabel("number of scans")
    ax.set_ylabel("covered area (cluster hulls), m²")
    _finish(fig, ax, title, "covered area against the number of scans, per ordering", path)


def plot_coverage_vs_clusters(curves: Mapping[int, pd.DataFrame], path: str | os.PathLike, title: str = "") -> None:
    """Thesis Fig. 5.7: covered area against number of scans, one curve per cluster
    count.

    Parameters
    ----------
    curves : mapping of int to pandas.DataFrame
        Cluster count -> ``covered_area_m2`` (square metres) in rank order.
    path : path
        PNG output, written atomically (:func:`~floorscan.figures.style.save_figure`).
    title : str
    """
    fig, ax = plt.subplots(figsize=(7, 4.5))
    cmap = plt.get_cmap("viridis")
    for i, (k, o) in enumerate(sorted(curves.items())):
        cov = o["covered_area_m2"].to_numpy()
        label = f"k = {k}" + (" (convex hull)" if k == 1 else "") + f", final {cov[-1]:.0f} m²" if len(cov) else ""
        ax.plot(np.arange(1, len(cov) + 1), cov, color=cmap(i / max(len(curves) - 1, 1)), label=label)
    ax.set_xscale("log")
    ax.set_xlabel("number of scans (greedy cluster_hull ordering)")
    ax.set_ylabel("covered area, m²")
    _finish(fig, ax, title, "covered area against the number of scans, per number of KMeans clusters", path)


def plot_selection_time(timing: pd.DataFrame, path: str | os.PathLike, title: str = "") -> None:
    """Thesis Fig. 5.8: selection time against number of scans, lazy vs reference
    greedy.

    Parameters
    ----------
    timing : pandas.DataFrame
        :func:`floorscan.select.figure_data.selection_timing`: ``n_scans``, ``fast_s``,
        ``reference_s`` (seconds).
    path : path
        PNG output, written atomically (:func:`~floorscan.figures.style.save_figure`).
    title : str
    """
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(timing["n_scans"], timing["fast_s"], "o-", label="lazy greedy (production)")
    ref = timing.dropna(subset=["reference_s"])
    ax.plot(ref["n_scans"], ref["reference_s"], "s-", label="Algorithm 1 reference")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("number of scans")
    ax.set_ylabel("selection time, s")
    _finish(fig, ax, title, "time to order the scans, lazy against plain greedy", path)


def selection_figures(
    orderings: Mapping[str, pd.DataFrame],
    k99: Mapping[str, int],
    clusters: Mapping[int, pd.DataFrame],
    timing: pd.DataFrame,
    out_coverage: str | os.PathLike,
    out_clusters: str | os.PathLike,
    out_timing: str | os.PathLike,
    title: str = "",
) -> None:
    """Write the three selection figures (thesis Figs. 5.6 to 5.8) of the select stage's
    data (:func:`floorscan.select.figure_data.selection_figure_data`).

    Parameters
    ----------
    orderings : mapping of str to pandas.DataFrame
        Ordering name -> ``rank``, ``covered_area_m2`` (Fig. 5.6).
    k99 : mapping of str to int
        Their 99 % points (Fig. 5.6).
    clusters : mapping of int to pandas.DataFrame
        The ``cluster_hull`` curve per number of clusters (Fig. 5.7).
    timing : pandas.DataFrame
        The time to order the scans (Fig. 5.8).
    out_coverage, out_clusters, out_timing : path
        PNG outputs of Figs. 5.6, 5.7, 5.8.
    title : str
    """
    plot_coverage_vs_scans(orderings, k99, out_coverage, title)
    plot_coverage_vs_clusters(clusters, out_clusters, title)
    plot_selection_time(timing, out_timing, title)

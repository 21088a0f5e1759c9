"""Wall extraction per scan (thesis Fig. 5.10): the time of each scan's extraction and
the walls it gave, cumulative and per scan, one line per extractor.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from floorscan.figures.style import EXTRACTOR_COLOURS, save_figure  # noqa: E402


def plot_wall_extraction(status: dict, times: dict, out, title: str = "") -> None:
    """Fig. 5.10: wall extraction time per scan and cumulative walls, per extractor.

    Parameters
    ----------
    status : dict
        ``{extractor: DataFrame}`` of ``walls/{extractor}/scan_status.parquet``
        (``scan_id``, ``n_walls``, ``reason``); scans in recording order.
    times : dict
        ``{extractor: DataFrame}`` of ``benchmarks/scan_walls_{extractor}_times.parquet``
        (``scan_id``, ``time_s``, :data:`floorscan.walls.tables.SCAN_TIMES`), the seconds of
        each scan's extraction; a scan without a time is drawn without one.
    """
    fig, axes = plt.subplots(1, 3, figsize=(15, 4))
    for ext, df in sorted(status.items()):
        df = df.sort_values("scan_id")
        t_ext = times.get(ext, pd.DataFrame({"scan_id": [], "time_s": []}))[["scan_id", "time_s"]]
        df = df.merge(t_ext, on="scan_id", how="left")
        colour = EXTRACTOR_COLOURS.get(ext)
        t = pd.to_numeric(df["time_s"], errors="coerce").to_numpy() * 1e3
        n = pd.to_numeric(df["n_walls"], errors="coerce").fillna(0).to_numpy()
        axes[0].plot(df["scan_id"], t, ".", ms=2, color=colour,
                     label=f"{ext} (median {np.nanmedian(t) if len(t) else np.nan:.1f} ms)")
        axes[1].plot(df["scan_id"], np.cumsum(n), color=colour,
                     label=f"{ext} ({int(n.sum())} walls)")
        axes[2].plot(df["scan_id"], n, ".", ms=2, color=colour, label=ext)
    axes[0].set_ylabel("extraction time per scan (ms)")
    axes[0].set_yscale("log")
    axes[1].set_ylabel("cumulative walls extracted")
    axes[2].set_ylabel("walls per scan")
    for ax in axes:
        ax.set_xlabel("scan id (recording order)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, out)

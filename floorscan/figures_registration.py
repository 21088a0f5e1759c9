"""Figure of the registration stage: the registered map and the scan locations (thesis Fig. 5.9)."""

from __future__ import annotations

import os

import numpy as np
import pandas as pd


def plot_registered_map(
    registered: pd.DataFrame,
    registration: pd.DataFrame,
    path: str | os.PathLike,
    *,
    title: str = "",
    density_radius_m: float = 1.0,
    cell_m: float = 0.05,
) -> None:
    """Plot the registered map coloured by point density, with the scan locations.

    As thesis Fig. 5.9: points of the kept scans on a grid of ``cell_m`` cells, shaded by
    how many points fall in each cell (log scale); scan locations coloured by how many
    kept scans lie within ``density_radius_m`` (darker blue: more scans there, e.g. at
    doorways and turns). Written atomically as PNG (matplotlib, Agg backend).

    Parameters
    ----------
    registered : pandas.DataFrame
        ``scan_id, x, y, z``: points in the map frame, metres (``registered.parquet``).
    registration : pandas.DataFrame
        ``kept, x_m, y_m`` per scan (``registration.parquet``).
    path : path-like
        Output PNG.
    title : str
    density_radius_m, cell_m : float
        Metres.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    from scipy.spatial import cKDTree

    from floorscan.io import atomic_path

    xy = registered[["x", "y"]].to_numpy(np.float64)
    kept = registration[registration["kept"].to_numpy(bool)]
    loc = kept[["x_m", "y_m"]].to_numpy(np.float64)
    fig, ax = plt.subplots(figsize=(8, 8), dpi=120)
    if len(xy):
        lo, hi = xy.min(axis=0), xy.max(axis=0)
        bins = np.maximum(((hi - lo) / cell_m).astype(int), 1)
        h, ex, ey = np.histogram2d(xy[:, 0], xy[:, 1], bins=bins.tolist(), range=[[lo[0], hi[0]], [lo[1], hi[1]]])
        h = np.ma.masked_equal(h.T, 0)
        im = ax.pcolormesh(ex, ey, h, cmap="Greys", norm=LogNorm(vmin=1, vmax=max(h.max(), 2)), shading="flat", rasterized=True)
        fig.colorbar(im, ax=ax, shrink=0.6, label=f"points per {cell_m * 100:.0f} cm cell")
    if len(loc):
        counts = np.array([len(n) for n in cKDTree(loc).query_ball_point(loc, density_radius_m)])
        sc = ax.scatter(loc[:, 0], loc[:, 1], c=counts, cmap="Blues", vmin=0, s=14, edgecolors="k", linewidths=0.3, zorder=3)
        fig.colorbar(sc, ax=ax, shrink=0.6, label=f"kept scans within {density_radius_m:g} m")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, map frame)")
    ax.set_ylabel("y (m, map frame)")
    n_scans = len(registration)
    ax.set_title(f"{title}  {len(kept)} of {n_scans} scans kept".strip())
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png")
    plt.close(fig)

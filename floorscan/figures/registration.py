"""Figure of the registration stage: the registered map and the scan locations (thesis Fig. 5.9)."""

from __future__ import annotations

import math
import os

import numpy as np
import pandas as pd

#: Largest raster (cells) of :class:`DensityRaster`; a larger extent coarsens the cell.
MAX_CELLS = 40_000_000


class DensityRaster:
    """Points per cell of a map, accumulated scan by scan (the registered map's figure
    without holding all its points: issue 8, memory follows the largest scan).

    Parameters
    ----------
    lo, hi : (2,) float array-like
        Corners of the extent, metres (map frame); points outside are clipped to it.
    cell_m : float
        Cell side, metres; doubled until the raster has at most :data:`MAX_CELLS` cells.
    """

    def __init__(self, lo, hi, cell_m: float = 0.05):
        self.lo = np.asarray(lo, dtype=np.float64)
        hi = np.asarray(hi, dtype=np.float64)
        cell = float(cell_m)
        while True:
            shape = np.maximum(np.ceil((hi - self.lo) / cell).astype(np.int64), 1)
            if shape[0] * shape[1] <= MAX_CELLS:
                break
            cell *= 2
        self.cell_m = cell
        self.nx, self.ny = int(shape[0]), int(shape[1])
        self.counts = np.zeros(self.nx * self.ny, dtype=np.int64)
        self._buf: list[np.ndarray] = []
        self._n = 0

    def add(self, xy: np.ndarray) -> None:
        """Count points (in place).

        Parameters
        ----------
        xy : (N, 2+) float ndarray
            Metres, x and y first; not modified. Points outside the extent count in the
            border cells.
        """
        xy = np.asarray(xy, dtype=np.float64)
        ix = np.clip(((xy[:, 0] - self.lo[0]) / self.cell_m).astype(np.int64), 0, self.nx - 1)
        iy = np.clip(((xy[:, 1] - self.lo[1]) / self.cell_m).astype(np.int64), 0, self.ny - 1)
        self._buf.append(iy * self.nx + ix)
        self._n += len(ix)
        if self._n >= 4_000_000:
            self._flush()

    def _flush(self) -> None:
        if self._buf:
            self.counts += np.bincount(np.concatenate(self._buf), minlength=len(self.counts))
            self._buf, self._n = [], 0

    def grid(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The counts, cropped to the occupied cells.

        Returns
        -------
        ex : (nx+1,) float64 ndarray
            Cell edges in x, metres.
        ey : (ny+1,) float64 ndarray
            Cell edges in y, metres.
        counts : (ny, nx) ndarray
            Points per cell; (0, 0) when none.
        """
        self._flush()
        h = self.counts.reshape(self.ny, self.nx)
        ex = self.lo[0] + np.arange(self.nx + 1) * self.cell_m
        ey = self.lo[1] + np.arange(self.ny + 1) * self.cell_m
        cols, rows = np.flatnonzero(h.any(axis=0)), np.flatnonzero(h.any(axis=1))
        if len(cols) == 0:
            return ex[:1], ey[:1], h[:0, :0]
        return (ex[cols[0]:cols[-1] + 2], ey[rows[0]:rows[-1] + 2],
                h[rows[0]:rows[-1] + 1, cols[0]:cols[-1] + 1])

    @classmethod
    def of_points(cls, xy: np.ndarray, cell_m: float = 0.05) -> "DensityRaster":
        """The raster of all points over their extent.

        Parameters
        ----------
        xy : (N, 2+) float ndarray
            Metres, x and y first.
        cell_m : float
            Metres.

        Returns
        -------
        DensityRaster
        """
        xy = np.asarray(xy, dtype=np.float64)
        lo = xy[:, :2].min(axis=0) if len(xy) else np.zeros(2)
        hi = xy[:, :2].max(axis=0) if len(xy) else np.zeros(2)
        r = cls(lo, hi, cell_m)
        if len(xy):
            r.add(xy)
        return r


def density_of_file(path: str | os.PathLike, cell_m: float = 0.05) -> DensityRaster:
    """The :class:`DensityRaster` of a points table (``registered.parquet``: ``scan_id,
    x, y, z``, map frame, metres), streamed scan by scan (memory: one row group and
    the raster). The extent is the points' own, from the file's column statistics
    (a first pass over x, y when a row group has none).

    Parameters
    ----------
    path : path
    cell_m : float
        Metres.

    Returns
    -------
    DensityRaster

    Raises
    ------
    floorscan.core.io.InputError
        When ``x`` or ``y`` is missing (naming the file).
    """
    import pyarrow.parquet as pq

    from floorscan.core.io import iter_scans

    md = pq.ParquetFile(path).metadata
    names = [md.schema.column(i).name for i in range(md.num_columns)]
    lo, hi = np.full(2, np.inf), np.full(2, -np.inf)
    stats_ok = all(c in names for c in ("x", "y"))
    for g in range(md.num_row_groups) if stats_ok else ():
        for a, c in enumerate(("x", "y")):
            st = md.row_group(g).column(names.index(c)).statistics
            if st is None or not st.has_min_max:
                stats_ok = False
                break
            lo[a], hi[a] = min(lo[a], float(st.min)), max(hi[a], float(st.max))
    if not stats_ok:
        for _, xy in iter_scans(path, ("x", "y")):  # also raises on missing columns
            if len(xy):
                lo, hi = np.minimum(lo, xy.min(axis=0)), np.maximum(hi, xy.max(axis=0))
    if not np.isfinite(lo).all():
        lo = hi = np.zeros(2)
    raster = DensityRaster(lo, hi, cell_m)
    for _, xy in iter_scans(path, ("x", "y")):
        raster.add(xy)
    return raster


#: Most cells across the registered map figure (about its axes' width in pixels).
FIGURE_CELLS = 500


def coarsen_counts(ex: np.ndarray, ey: np.ndarray, h: np.ndarray, max_cells: int):
    """Counts summed over square blocks of ``factor`` cells so that neither side
    exceeds ``max_cells``; the blocks at the far edges may be partial.

    Parameters
    ----------
    ex : (nx+1,) float ndarray
        Cell edges in x, metres.
    ey : (ny+1,) float ndarray
        Cell edges in y, metres.
    h : (ny, nx) ndarray
        Counts.
    max_cells : int

    Returns
    -------
    ex, ey : float ndarray
        The blocks' edges, metres.
    h : ndarray
        The summed counts.
    factor : int
    """
    ny, nx = h.shape
    factor = max(1, math.ceil(max(nx, ny) / max_cells))
    if factor == 1:
        return ex, ey, h, 1
    py, px = -ny % factor, -nx % factor
    padded = np.pad(h, ((0, py), (0, px)))
    out = padded.reshape((ny + py) // factor, factor, (nx + px) // factor, factor).sum(axis=(1, 3))
    step = ex[1] - ex[0]
    ex2 = ex[0] + np.arange(out.shape[1] + 1) * step * factor
    ey2 = ey[0] + np.arange(out.shape[0] + 1) * step * factor
    return ex2, ey2, out, factor


def plot_registered_map(
    registered: "pd.DataFrame | DensityRaster",
    registration: pd.DataFrame,
    path: str | os.PathLike,
    *,
    title: str = "",
    subtitle: tuple[str, ...] = (),
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
    registered : pandas.DataFrame or DensityRaster
        ``scan_id, x, y, z``: points in the map frame, metres (``registered.parquet``),
        or their :class:`DensityRaster` (accumulated while writing them; its cell
        replaces ``cell_m``).
    registration : pandas.DataFrame
        ``kept, x_m, y_m`` per scan (``registration.parquet``).
    path : path-like
        Output PNG.
    title : str
        The dataset, leading the title (which says what the figure shows).
    subtitle : tuple of str
        Lines under the title (the registration's verdict, what ingest detected).
    density_radius_m, cell_m : float
        Metres.
    """
    import textwrap

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.colors import LogNorm
    from scipy.spatial import cKDTree

    from floorscan.figures.style import map_figsize, save_figure

    raster = (registered if isinstance(registered, DensityRaster)
              else DensityRaster.of_points(registered[["x", "y"]].to_numpy(np.float64), cell_m))
    cell_m = raster.cell_m
    kept = registration[registration["kept"].to_numpy(bool)]
    loc = kept[["x_m", "y_m"]].to_numpy(np.float64)
    ex, ey, h = raster.grid()
    # a map wider than the figure's pixels would lose its thin walls when drawn, one
    # cell per pixel picked: cells are summed into blocks, at most FIGURE_CELLS across
    ex, ey, h, factor = coarsen_counts(ex, ey, h, FIGURE_CELLS)
    span = (float(np.ptp(ex)), float(np.ptp(ey))) if len(ex) > 1 and len(ey) > 1 else (1.0, 1.0)
    fig, ax = plt.subplots(figsize=map_figsize(*span, margin_in=3.2), layout="constrained")
    fig.get_layout_engine().set(h_pad=0.1)  # the lower colour bar's label clear of the edge
    cell_m = cell_m * factor
    if h.size and h.max() > 0:
        h = np.ma.masked_equal(h, 0)
        # vmin below 1: a cell of one point (a sparse scanner's far wall) is grey, not white
        im = ax.pcolormesh(ex, ey, h, cmap="Greys", norm=LogNorm(vmin=0.5, vmax=max(h.max(), 2)), shading="flat", rasterized=True)
        fig.colorbar(im, ax=ax, location="bottom", shrink=0.5, aspect=40,
                     label=f"points per {cell_m * 100:.0f} cm cell")
    if len(loc):
        counts = np.array([len(n) for n in cKDTree(loc).query_ball_point(loc, density_radius_m)])
        sc = ax.scatter(loc[:, 0], loc[:, 1], c=counts, cmap="Blues", vmin=0, s=14, edgecolors="k", linewidths=0.3, zorder=3)
        fig.colorbar(sc, ax=ax, location="bottom", shrink=0.5, aspect=40,
                     label=f"kept scans within {density_radius_m:g} m")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x (m, map frame)")
    ax.set_ylabel("y (m, map frame)")
    n_scans = len(registration)
    what = f"registered map and scan locations, {len(kept)} of {n_scans} scans kept"
    lines = [f"{title}: {what}" if title else what[:1].upper() + what[1:], *subtitle]
    ax.set_title("\n".join(textwrap.fill(line, 110) for line in lines), fontsize=9 if subtitle else None)
    save_figure(fig, path)

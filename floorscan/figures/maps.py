"""Map views: the reference map of a recording and wall segments over the registered
points (thesis Figs. 5.11, 5.12).

- :func:`plot_reference_map`: the occupancy grid of all kept scans
  (:class:`floorscan.core.occupancy.OccupancyGrid`), its structure, single-scan, free
  and unknown cells, optionally a floor plan's faces over it;
- :func:`plot_walls_over_points`: wall segments over a subsample of the registered
  points (:func:`subsample_points`, seeded, cut to the walls' height band on 3D data).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from floorscan.figures.style import (DPI, MAP_AXES_SHARE, map_figsize, segments_collection, square_axes,  # noqa: E402
                                     save_figure)
from floorscan.core.segments import as_segments  # noqa: E402


def plot_reference_map(grid, out, title: str = "", faces=None) -> None:
    """The reference map (:class:`floorscan.core.occupancy.OccupancyGrid`): free
    cells white, unknown grey, structure black, occupied cells hit by a single scan
    red; optionally a floor plan's faces ((F, 4) segments, metres) in blue over it.
    The view is the free and structure cells, 1 m around them.

    Parameters
    ----------
    grid : OccupancyGrid
    out : path
        PNG output.
    title : str
    faces : (F, 4) float ndarray, optional
        ``x0, y0, x1, y1``, metres.
    """
    # RGBA bytes, not float RGB: matplotlib copies the image and makes it RGBA (4 bytes
    # a cell instead of 24 + 32 of float64); 204 / 255 and 255 / 255 are the greys
    # 0.80 and 1.0 exactly in the bytes it draws
    rgb = np.full(grid.shape + (4,), 255, dtype=np.uint8)
    rgb[..., :3] = 204
    rgb[grid.free(), :3] = 255
    h, w = grid.shape
    x0, y0 = grid.origin_xy
    r = grid.resolution_m
    counts = grid.counts()
    # the view: what the scans saw free and the structure, 1 m around; a stray
    # single-scan return tens of metres out would shrink the building to a strip
    seen = grid.cell_centres(grid.free() | grid.structure())
    view = ((seen.min(axis=0) - 1.0, seen.max(axis=0) + 1.0) if len(seen)
            else (np.array([x0, y0]), np.array([x0 + w * r, y0 + h * r])))
    fig, ax = plt.subplots(figsize=map_figsize(*(view[1] - view[0]), margin_in=1.6), layout="constrained")
    ax.imshow(rgb, origin="lower", extent=(x0, x0 + w * r, y0, y0 + h * r), interpolation="nearest")
    # occupied cells as markers of at least one and a half pixels (marker area in
    # points squared): at a building's scale a 5 cm cell is less than a pixel, and
    # the image alone, or smaller markers, would hide the walls
    axes_in = fig.get_figwidth() * MAP_AXES_SHARE  # the axes' width, about: the view's longer side spans it
    size = max((1.5 * 72.0 / DPI) ** 2, (72.0 * axes_in * r / float(max(view[1] - view[0]))) ** 2)
    for mask, colour in ((grid.single_scan(), (0.85, 0.1, 0.1)), (grid.structure(), "black")):  # structure on top
        xy = grid.cell_centres(mask)
        ax.scatter(xy[:, 0], xy[:, 1], s=size, c=[colour], marker="s", linewidths=0)
    if faces is not None and len(faces):
        ax.add_collection(segments_collection(faces, colors="tab:blue", linewidths=0.8))
    ax.set_xlim(view[0][0], view[1][0])
    ax.set_ylim(view[0][1], view[1][1])
    ax.set_aspect("equal", adjustable="datalim")  # the axes fill their place; the view grows to keep the scale
    ax.set_facecolor((0.8, 0.8, 0.8))  # beyond the grid, where the view grew: unknown, as the grid's unknown cells
    ax.set_xlabel("x (m, map frame)")
    ax.set_ylabel("y (m, map frame)")
    ax.set_title(
        f"{title}\n{counts['structure']} structure cells (black: occupied, >= {grid.params.min_scans} scans), "
        f"{counts['single_scan']} single-scan (red)\n{counts['free']} free (white), "
        f"{counts['unknown']} unknown (grey); {r * 100:.0f} cm cells",
        fontsize=9,
    )
    save_figure(fig, out)


def plot_walls_over_points(points, panels, out, title: str = "", max_points: int = 200_000) -> None:
    """Figs. 5.11 and 5.12: wall segments over the registered points, one panel each.

    The points are drawn first, grey and half transparent, so that the walls lie on
    them and the points show around and between the walls: returns that no wall
    explains are seen.

    Parameters
    ----------
    points : (N, 2) float ndarray
        Registered points (map frame, metres), usually already subsampled
        (:func:`subsample_points`).
    panels : list of (str, (M, 4) segments)
        Panel title and wall segments, metres.
    max_points : int
        At most this many points are drawn: beyond, every n-th (deterministic).
    """
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    if len(pts) > max_points:
        pts = pts[np.linspace(0, len(pts) - 1, max_points).astype(np.int64)]
    n = max(1, len(panels))
    fig, axes = plt.subplots(1, n, figsize=(6 * n, 5), squeeze=False)
    for ax, (name, seg) in zip(axes[0], panels):
        ax.scatter(pts[:, 0], pts[:, 1], s=1.5, c="0.45", alpha=0.5, linewidths=0, rasterized=True,
                   zorder=1, label=f"registered points ({len(pts)} drawn)")
        ax.add_collection(segments_collection(seg, colors="tab:red", linewidths=0.8, zorder=2,
                                               label="wall segments"))
        ax.set_title(f"{name} ({len(as_segments(seg))} segments)", fontsize=10)
        ax.autoscale()
        square_axes(ax)
        ax.legend(fontsize=7, loc="upper right", markerscale=4)
    fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, out)


def subsample_points(
    points, max_points: int, seed: int, z_band=None, batch_rows: int = 1 << 20, planar_tolerance_m: float | None = None
):
    """``(N, 2)`` x, y of at most ``max_points`` points (seeded), optionally only those
    with z inside ``z_band`` when the points are 3D.

    2D against 3D as the walls stage decides it (:func:`floorscan.core.wall_points.scan_points_2d`):
    points whose z spans at most ``planar_tolerance_m`` (default
    :attr:`floorscan.core.wall_points.ScanParams.planar_tolerance_m`) came from a 2D scanner, at
    whatever height it was mounted (the simulated rovers' 0.3 m), and are all kept;
    here the span is the whole table's, not each scan's.

    ``points`` is a frame (``x, y, z``) or the path of a Parquet points table, which is
    read in batches of ``batch_rows`` (with ``z_band``, first z to count, then x, y of
    the drawn rows):
    the same points as from the whole frame, in memory one batch at a time.

    Parameters
    ----------
    points : pandas.DataFrame or path
    max_points : int
    seed : int
        Seeds ``numpy.random.default_rng``.
    z_band : (float, float), optional
        Lowest and highest z kept, metres.
    batch_rows : int
    planar_tolerance_m : float, optional
        Metres.

    Returns
    -------
    (N, 2) float64 ndarray
        ``x, y``, metres, in table order.

    Raises
    ------
    KeyError
        A points file without ``x``, ``y`` or ``z``.
    """
    if planar_tolerance_m is None:
        from floorscan.core.wall_points import ScanParams

        planar_tolerance_m = ScanParams.planar_tolerance_m
    if isinstance(points, (str, Path)):
        return _subsample_file(points, max_points, seed, z_band, batch_rows, planar_tolerance_m)
    xyz = points[["x", "y", "z"]].to_numpy(dtype=np.float64)
    if z_band is not None and len(xyz) and _z_span(xyz[:, 2]) > planar_tolerance_m:
        xyz = xyz[(xyz[:, 2] >= z_band[0]) & (xyz[:, 2] <= z_band[1])]
    if len(xyz) > max_points:
        idx = np.random.default_rng(seed).choice(len(xyz), max_points, replace=False)
        xyz = xyz[np.sort(idx)]
    return xyz[:, :2].copy()


def _z_span(z: np.ndarray) -> float:
    z = z[np.isfinite(z)]
    return float(z.max() - z.min()) if len(z) else 0.0


def _subsample_file(path, max_points: int, seed: int, z_band, batch_rows: int, planar_tolerance_m: float) -> np.ndarray:
    import pyarrow.parquet as pq

    pf = pq.ParquetFile(path)
    missing = [c for c in ("x", "y", "z") if c not in pf.schema_arrow.names]
    if missing:
        raise KeyError(f"{path}: columns {missing} missing; expected x, y, z")
    total, three_d = pf.metadata.num_rows, False
    if z_band is not None:  # one pass over z: its span (is the table 3D), and how many are in the band
        n_band, z_lo, z_hi = 0, np.inf, -np.inf
        for b in pf.iter_batches(batch_size=batch_rows, columns=["z"]):
            z = b.column(0).to_numpy(zero_copy_only=False).astype(np.float64)
            finite = z[np.isfinite(z)]
            if len(finite):
                z_lo, z_hi = min(z_lo, float(finite.min())), max(z_hi, float(finite.max()))
            n_band += int(np.count_nonzero((z >= z_band[0]) & (z <= z_band[1])))
        three_d = z_hi - z_lo > planar_tolerance_m
        if three_d:
            total = n_band
    band = (lambda z: (z >= z_band[0]) & (z <= z_band[1])) if three_d else (lambda z: np.ones(len(z), bool))
    chosen = None
    if total > max_points:
        chosen = np.sort(np.random.default_rng(seed).choice(total, max_points, replace=False))
    out, seen = [], 0
    for b in pf.iter_batches(batch_size=batch_rows, columns=["x", "y", "z"]):
        x, y, z = (b.column(i).to_numpy(zero_copy_only=False).astype(np.float64) for i in range(3))
        m = band(z)
        xy = np.column_stack([x[m], y[m]])
        if chosen is not None:
            lo, hi = np.searchsorted(chosen, [seen, seen + len(xy)])
            xy = xy[chosen[lo:hi] - seen]
        seen += int(m.sum())
        out.append(xy)
    return np.concatenate(out) if out else np.zeros((0, 2))

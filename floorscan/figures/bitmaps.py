"""The bitmap metrics drawn (thesis Fig. 5.1): the inferred wall bitmap over the ground
truth's (reference's), ground truth only blue (false negative), inferred only red
(false positive), both purple (correct match).

The bitmaps are the walls rasterized on the scoring grid
(:mod:`floorscan.core.segment_raster`), as the score stage compares them; each panel's
numbers are the score stage's (its table ``score/<extractor>.parquet``, the same grid).
:func:`block_any` reduces a large grid for display without losing one-cell walls.
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from floorscan.figures.style import DPI, square_axes, reference_name, save_figure  # noqa: E402
from floorscan.core.segment_raster import Grid, rasterize_segments  # noqa: E402


def overlay_image(inferred: np.ndarray, ground_truth: np.ndarray) -> np.ndarray:
    """RGB image of two bitmaps (Fig. 5.1): ground truth only blue (false negative),
    inferred only red (false positive), both purple (correct match), neither white.

    Parameters
    ----------
    inferred, ground_truth : (ny, nx) bool ndarray

    Returns
    -------
    (ny, nx, 3) float ndarray
    """
    bi = np.asarray(inferred, bool)
    bg = np.asarray(ground_truth, bool)
    img = np.ones(bi.shape + (3,))
    img[bg & ~bi] = (0.1, 0.2, 1.0)
    img[bi & ~bg] = (1.0, 0.1, 0.1)
    img[bi & bg] = (0.55, 0.0, 0.65)
    return img


def block_any(bitmap: np.ndarray, factor: int) -> np.ndarray:
    """Downsample a bool bitmap by ``factor`` (a cell is set if any of its block is), so
    that walls one cell wide stay visible in a figure.

    Parameters
    ----------
    bitmap : (ny, nx) bool ndarray
    factor : int
        1 or less returns a copy.

    Returns
    -------
    (ceil(ny / factor), ceil(nx / factor)) bool ndarray
    """
    b = np.asarray(bitmap, bool)
    if factor <= 1:
        return b.copy()
    ny, nx = b.shape
    py, px = (-ny) % factor, (-nx) % factor
    b = np.pad(b, ((0, py), (0, px)))
    return b.reshape(b.shape[0] // factor, factor, b.shape[1] // factor, factor).any(axis=(1, 3))


def plot_bitmap_overlay(
    panels, reference, reference_kind: str, grid: Grid, wall_width_m: float, out,
    title: str = "",
) -> None:
    """Fig. 5.1: the inferred bitmap overlaid on the ground-truth (reference) bitmap.

    Parameters
    ----------
    panels : list of (str, (M, 4) segments, mapping or None)
        Panel title, inferred wall segments (metres) and their scores: the score
        stage's row of that run (``correct_match``, ``false_positive``,
        ``false_negative``, ``wall_correct_match``; fractions), or None when the run
        was not scored.
    reference : (K, 4) segments
        Ground truth or reference, metres.
    grid : floorscan.core.segment_raster.Grid
        The scoring grid (the same as ``metrics.parquet``'s).
    wall_width_m : float
        Drawn wall width, metres.
    """
    bg = rasterize_segments(reference, grid, wall_width_m)
    # About 900 pixels across a panel: larger grids are shown block-reduced (any).
    factor = max(1, int(np.ceil(max(grid.nx, grid.ny) / 900)))
    n = max(1, len(panels))
    fig, axes = plt.subplots(1, n, figsize=(1050 * n / DPI, 900 / DPI), squeeze=False)
    ref = reference_name(reference_kind)
    for ax, (name, seg, m) in zip(axes[0], panels):
        bi = rasterize_segments(seg, grid, wall_width_m)
        img = overlay_image(block_any(bi, factor), block_any(bg, factor))
        x0, _, y0, _ = grid.extent
        step = grid.cell_m * factor
        extent = (x0, x0 + img.shape[1] * step, y0, y0 + img.shape[0] * step)
        ax.imshow(img, origin="lower", extent=extent, interpolation="nearest")
        scores = (
            f"CM {m['correct_match']:.4f}  FP {m['false_positive']:.4f}  FN {m['false_negative']:.4f}  "
            f"wall-cell CM {m['wall_correct_match']:.3f}" if m is not None else "not scored"
        )
        ax.set_title(f"{name}\n{scores}", fontsize=9)
        square_axes(ax)
    handles = [
        plt.Rectangle((0, 0), 1, 1, color=(0.1, 0.2, 1.0), label=f"{ref} only (FN)"),
        plt.Rectangle((0, 0), 1, 1, color=(1.0, 0.1, 0.1), label="inferred only (FP)"),
        plt.Rectangle((0, 0), 1, 1, color=(0.55, 0.0, 0.65), label="both (correct match)"),
    ]
    axes[0, -1].legend(handles=handles, fontsize=7, loc="upper right")
    if factor > 1:
        title += f" (shown in blocks of {factor} x {factor} cells)"
    fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, out)

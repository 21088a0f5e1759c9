"""Bitmap metrics of walls (thesis section 5.1): correct match, false positive, false
negative of a rasterized wall map against the ground truth's.

Both segment sets are rasterized on the same grid
(:mod:`floorscan.core.segment_raster`: :class:`~floorscan.core.segment_raster.Grid`,
:func:`~floorscan.core.segment_raster.grid_for`): a cell is 1 when its centre lies
within ``wall_width_m / 2`` of a segment, else 0
(:func:`~floorscan.core.segment_raster.rasterize_segments`). With the error map
``B_E = B_I - B_GT`` (values -1, 0, 1; :func:`error_map`) the thesis defines::

    CorrectMatch  = #[B_E = 0]  / |B_E|
    FalsePositive = #[B_E = 1]  / |B_E|
    FalseNegative = #[B_E = -1] / |B_E|

normalized by the number of cells of the map ``|B_E|``. These follow the thesis exactly,
but *CorrectMatch counts the empty cells that both maps leave empty*, which are the vast
majority (a 50 x 30 m map at 5 cm has 600 000 cells, its walls perhaps 20 000), so
CorrectMatch stays near 1 even with no inferred wall at all. :func:`bitmap_metrics`
therefore also reports the wall-cell-only versions, normalized by the cells that either
map marks as wall, ``U = B_I | B_GT``::

    wall_correct_match  = |B_I & B_GT|  / |U|   (intersection over union)
    wall_false_positive = |B_I & ~B_GT| / |U|
    wall_false_negative = |~B_I & B_GT| / |U|

(each triple sums to 1), and the cell precision ``|B_I & B_GT| / |B_I|`` and cell
recall ``|B_I & B_GT| / |B_GT|``.

On real recordings the ground truth is the reference (the walls of all kept scans, as
the thesis does in section 5.4), of which the walls of the first k scans are a subset:
the false-positive fraction is 0 there by construction.
"""

from __future__ import annotations

import math

import numpy as np


def error_map(inferred: np.ndarray, ground_truth: np.ndarray) -> np.ndarray:
    """The thesis's error map ``B_E = B_I - B_GT`` (section 5.1).

    Parameters
    ----------
    inferred, ground_truth : (ny, nx) bool ndarray
        Wall bitmaps (:func:`floorscan.core.segment_raster.rasterize_segments`).

    Returns
    -------
    (ny, nx) int8 ndarray
        In {-1, 0, 1}.

    Raises
    ------
    ValueError
        When the two bitmaps differ in shape.
    """
    bi = np.asarray(inferred, dtype=bool)
    bg = np.asarray(ground_truth, dtype=bool)
    if bi.shape != bg.shape:
        raise ValueError(f"bitmaps differ in shape: {bi.shape} vs {bg.shape}")
    return bi.astype(np.int8) - bg.astype(np.int8)


def bitmap_metrics(inferred: np.ndarray, ground_truth: np.ndarray) -> dict[str, float]:
    """Thesis section 5.1 fractions, and their wall-cell-only versions.

    Parameters
    ----------
    inferred, ground_truth : (ny, nx) bool ndarray
        ``B_I`` and ``B_GT`` on the same grid.

    Returns
    -------
    dict
        ``correct_match``, ``false_positive``, ``false_negative``: the thesis's
        fractions of all map cells (``|B_E|``) with ``B_E`` = 0, 1, -1; they sum to 1 and
        ``correct_match`` is dominated by cells empty in both maps.
        ``wall_correct_match`` (IoU), ``wall_false_positive``, ``wall_false_negative``:
        the same counts over the wall cells ``B_I | B_GT`` only (NaN when neither map has
        a wall cell). ``cell_precision`` ``|B_I & B_GT| / |B_I|`` and ``cell_recall``
        ``|B_I & B_GT| / |B_GT|`` (NaN on an empty denominator). ``n_cells``,
        ``n_inferred_cells``, ``n_gt_cells``, ``n_both_cells`` (counts, as floats).
    """
    be = error_map(inferred, ground_truth)
    n = be.size
    fp = int(np.count_nonzero(be == 1))
    fn = int(np.count_nonzero(be == -1))
    both = int(np.count_nonzero(np.asarray(inferred, bool) & np.asarray(ground_truth, bool)))
    union = both + fp + fn
    n_i = both + fp
    n_g = both + fn

    def ratio(a: int, b: int) -> float:
        return a / b if b else math.nan

    return {
        "correct_match": ratio(n - fp - fn, n),
        "false_positive": ratio(fp, n),
        "false_negative": ratio(fn, n),
        "wall_correct_match": ratio(both, union),
        "wall_false_positive": ratio(fp, union),
        "wall_false_negative": ratio(fn, union),
        "cell_precision": ratio(both, n_i),
        "cell_recall": ratio(both, n_g),
        "n_cells": float(n),
        "n_inferred_cells": float(n_i),
        "n_gt_cells": float(n_g),
        "n_both_cells": float(both),
    }

"""Correlative matching (floorscan.score.correlative): the coarse raster bounds the fine
correlation at every shift, and the branch and bound returns the exhaustive search's
answer while correlating few grid points at full resolution."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import fft

from floorscan.score.correlative import coarse_bound, correlative_search
from floorscan.score.drawn import Similarity, drawn_faces


def _counts(cells, n):
    img = np.zeros((n, n))
    np.add.at(img, (cells[:, 1], cells[:, 0]), 1.0)
    return img


@pytest.mark.parametrize("n", [12, 13, 17])
@pytest.mark.parametrize("factor", [1, 2, 3, 5])
def test_the_coarse_raster_bounds_every_fine_shift(n, factor):
    """Brute force on random rasters, also where the coarse cells overrun the fine ones
    (13 = 5 x 3 - 2): the bound of coarse shift D is at least the circular correlation at
    every fine shift of its block, and equals it somewhere (the bound is attained)."""
    rng = np.random.default_rng(n * 10 + factor)
    ref = rng.random((n, n)) ** 4
    cells = rng.integers(0, n, (7, 2))
    bound = coarse_bound(ref, factor)
    m = -(-n // factor)
    assert bound.shape == (m, m)
    ub = fft.irfft2(fft.rfft2(bound) * np.conj(fft.rfft2(_counts(cells // factor, m))), s=(m, m))
    slack = np.array([[ub[dy // factor, dx // factor] - sum(ref[(r + dy) % n, (c + dx) % n] for c, r in cells)
                       for dx in range(n)] for dy in range(n)])  # fmt: skip
    assert slack.min() >= -1e-12
    if factor == 1:
        np.testing.assert_array_equal(bound, ref)
        assert np.abs(slack).max() < 1e-12


def test_coarse_bound_refuses_a_bad_raster():
    with pytest.raises(ValueError, match="square"):
        coarse_bound(np.zeros((4, 5)), 2)
    with pytest.raises(ValueError, match="factor"):
        coarse_bound(np.zeros((4, 4)), 0)


def _drawing():
    """A 400 x 300 px drawing: two rooms and a corridor (as tests/test_drawn.py)."""
    img = np.full((300, 400), 0.8, dtype=np.float32)
    img[40:140, 40:180] = 1.0
    img[40:140, 190:360] = 1.0
    img[150:200, 40:360] = 1.0
    img[140:150, 100:120] = 1.0
    img[140:150, 260:280] = 1.0
    return img


def test_branch_and_bound_is_the_exhaustive_search():
    """The drawing's faces put at 0.052 m/px and 99 degrees: the grid (9 scales
    0.001875 m/px apart x 120 angles of 3 degrees) finds 0.051875 m/px and 99 degrees
    with and without the bound, the same floats, and the bound correlates fewer than 20
    of the 1080 grid points at full resolution."""
    faces_px, _ = drawn_faces(_drawing())
    truth = Similarity(scale=0.052, angle=math.radians(99.0), tx=12.0, ty=-4.0)
    rng = np.random.default_rng(1)
    dst = truth.apply(faces_px) + rng.normal(0, 0.01, (len(faces_px), 2))
    dst = dst[rng.random(len(dst)) < 0.7]
    src = np.column_stack([faces_px[:, 0], -faces_px[:, 1]])  # (col, -row), as align_drawn
    src = src - src.mean(axis=0)
    scales = 0.05 * np.linspace(0.85, 1.15, 9)
    angles = [math.radians(d) for d in np.arange(0.0, 360.0, 3.0)]
    exhaustive = correlative_search(src, dst, scales, angles, factor=1)
    pruned = correlative_search(src, dst, scales, angles)
    assert pruned[0] == exhaustive[0] == scales[5] == pytest.approx(0.051875)
    assert pruned[1] == exhaustive[1] == pytest.approx(math.radians(99.0))
    np.testing.assert_array_equal(pruned[2], exhaustive[2])
    assert pruned[3]["score"] == exhaustive[3]["score"]
    assert exhaustive[3]["n_fine"] == exhaustive[3]["n_grid"] == 1080
    assert pruned[3]["n_fine"] < 20  # 5 of the 1080
    # the shift puts the source's centre on the truth's within a cell and a half
    centre = truth.apply(faces_px).mean(axis=0)
    assert np.abs(pruned[2] - centre).max() < 0.3


def test_correlative_search_refuses_empty_input():
    with pytest.raises(ValueError, match="no source point"):
        correlative_search(np.empty((0, 2)), np.ones((3, 2)), [1.0], [0.0])
    with pytest.raises(ValueError, match="empty grid"):
        correlative_search(np.ones((3, 2)), np.ones((3, 2)), [], [0.0])

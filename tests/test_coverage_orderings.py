"""The coverage orderings: what one scan alone sees is worth nothing, the scan that
adds most comes first, and the lazy greedy takes the plain greedy's scans."""

import numpy as np
import pandas as pd
import pytest

from floorscan.core.greedy import lazy_greedy, plain_greedy
from floorscan.select.coverage import segment_quality, surface_cells, wall_cells
from floorscan.select.orderings import coverage_orderings
from floorscan.select.params import CoverageParams

A = (0.0, 0.0, 6.0, 0.0)  # 6 m
B = (6.0, 0.0, 6.0, 3.0)  # 3 m
C = (0.0, 5.0, 4.0, 5.0)  # 4 m
D = (10.0, 10.0, 12.0, 10.0)  # seen by one scan only


def _order(sets, scan_ids):
    cover, quality, value = sets
    return lazy_greedy(cover, scan_ids, quality, value)


def _per_scan(rows, n_inliers=40, rmse=0.005):
    return pd.DataFrame(
        [(s, *w, n_inliers, rmse) for s, w in rows], columns=["scan_id", "x0", "y0", "x1", "y1", "n_inliers", "rmse_m"]
    )


def test_wall_coverage_takes_the_scan_that_adds_most_confirmed_wall():
    # scan 1: A and B; 3: B and C; 2: A; 4: C and D (D nobody else sees: worth 0)
    per_scan = _per_scan([(1, A), (1, B), (2, A), (3, B), (3, C), (4, C), (4, D)])
    cover, quality, value = wall_cells(per_scan, CoverageParams())
    order = lazy_greedy(cover, [1, 2, 3, 4, 5], quality, value)
    assert order["scan_id"].tolist() == [1, 3, 2, 4, 5]  # 2, 4 add nothing; 5 has no walls
    # gains in cells of 10 cm: A 60 + B 30 (+ the shared corner cell), then C 40 (+1)
    assert order["gain"].tolist()[:2] == pytest.approx([91, 41], abs=2)
    assert order["gain"].tolist()[2:] == [0, 0, 0]
    # D's 20 cells (one scan) are not structure
    assert value.sum() == pytest.approx(len(value) - 21, abs=1)


def test_wall_quality_prefers_the_better_fit_of_the_same_wall():
    good, poor = _per_scan([(1, A), (2, C), (4, A)]), _per_scan([(3, A), (5, C)], n_inliers=16, rmse=0.025)
    per_scan = pd.concat([good, poor], ignore_index=True)
    plain = _order(wall_cells(per_scan, CoverageParams()), [1, 2, 3, 4, 5])
    weighted = _order(wall_cells(per_scan, CoverageParams(wall_quality=True)), [1, 2, 3, 4, 5])
    assert plain["scan_id"].tolist()[:2] == [1, 2]  # A is longer; ties to the smaller id
    assert weighted["scan_id"].tolist()[:2] == [1, 2]
    assert weighted["gain"].iloc[0] < plain["gain"].iloc[0]  # a quality below 1
    q = segment_quality(np.array([15, 45, 40]), np.array([0.0, 0.0, 0.03]), 15, 0.03)
    np.testing.assert_allclose(q, [0.5, 0.75, 0.05])  # half at the minimum; nothing at the threshold


def test_surface_coverage_counts_density_and_confirmed_cells():
    line = np.column_stack([np.arange(200) * 0.01 + 0.005, np.zeros(200)])  # 1 cm spacing: 20 full cells
    sparse = line[::5]  # 5 cm: 2 returns a cell, 0.4 of full
    far = np.column_stack([np.arange(100) * 0.01 + 5.005, np.zeros(100)])  # seen by one scan
    scans = [(1, sparse), (2, line), (3, np.vstack([line, far]))]
    cover, quality, value = surface_cells(scans, CoverageParams())
    assert quality[2].tolist() == [1.0] * 20 and quality[1].tolist() == pytest.approx([0.4] * 20)
    assert value.sum() == 20 and len(value) == 30
    order = lazy_greedy(cover, [1, 2, 3], quality, value)
    # 2 and 3 fill the line's 20 cells fully (3's far cells count 0): 2 first by id, then nothing
    assert order["scan_id"].tolist() == [2, 1, 3]
    assert order["gain"].tolist() == pytest.approx([20, 0, 0])


@pytest.mark.parametrize("seed", range(5))
def test_coverage_orderings_are_the_plain_greedy(seed):
    rng = np.random.default_rng(seed)
    walls = rng.uniform(0, 20, size=(12, 4))
    rows = [(int(s), tuple(walls[w] + rng.normal(0, 0.02, 4))) for s in range(40) for w in rng.choice(12, 3)]
    per_scan = _per_scan(rows).assign(n_inliers=rng.integers(15, 80, len(rows)),
                                      rmse_m=rng.uniform(0, 0.02, len(rows)))
    for params in (CoverageParams(), CoverageParams(wall_quality=True)):
        cover, quality, value = wall_cells(per_scan, params)
        ids = list(range(40))
        lazy = lazy_greedy(cover, ids, quality, value)
        pd.testing.assert_frame_equal(lazy, plain_greedy(cover, ids, quality, value))


def test_coverage_orderings_rank_every_kept_scan_and_skip_the_others():
    per_scan = _per_scan([(1, A), (2, A), (9, B)])  # 9 is not kept
    pts = np.column_stack([np.linspace(0, 6, 601), np.zeros(601)])
    out = coverage_orderings(per_scan, [(1, pts), (2, pts), (9, pts)], [1, 2, 3])
    for name in ("wall_coverage", "surface_coverage"):
        assert sorted(out[name]["scan_id"]) == [1, 2, 3]
    assert out["wall_coverage"]["scan_id"].tolist() == [1, 2, 3]


def test_bad_coverage_settings_name_the_key():
    with pytest.raises(ValueError, match="select.coverage.cell_m"):
        wall_cells(_per_scan([(1, A)]), CoverageParams(cell_m=0))
    from floorscan.core.config import ConfigError, stage_params

    with pytest.raises(ConfigError, match=r"select\.coverage\.cell: unknown key"):
        stage_params(CoverageParams, {"cell": 0.1})

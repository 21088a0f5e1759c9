"""Quality-vs-k curves, the oracle ordering and the curve summary (issue 21, parts 3-5)."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from floorscan.core.score_tables import beats_random_line
from floorscan.score import curve_summary as CS
from floorscan.score import curves as C
from floorscan.score.against_reference import Structure
from floorscan.core.occupancy import occupancy_grid
from test_reference import WALLS, _scans


def test_k_grid_steps_two_percent_of_the_kept_scans():
    assert C.k_grid(76) == list(range(1, 77))
    g = C.k_grid(893)
    assert g[0] == 17 and g[-1] == 893 and max(np.diff(g)) == 17 and len(g) == 53
    assert C.k_grid(1) == [1]
    with pytest.raises(ValueError, match="no kept scan"):
        C.k_grid(0)
    with pytest.raises(ValueError, match="curve_step_fraction"):
        C.k_grid(10, 0)


def test_oracle_takes_the_scan_whose_walls_reach_most_structure_first():
    """Scan 7 sees four walls, scan 3 one of them, scan 5 the other walls: the oracle
    takes 7, then 5 (new walls), then 3 (nothing new); scan 9 has no walls, last."""
    structure = Structure(occupancy_grid(_scans()))
    rows = [(7, w) for w in WALLS[:4]] + [(3, WALLS[0])] + [(5, w) for w in WALLS[4:]]
    per_scan = pd.DataFrame([(s, *w) for s, w in rows], columns=["scan_id", "x0", "y0", "x1", "y1"])
    oracle = C.oracle_ordering(per_scan, [3, 5, 7, 9], structure, 0.05)
    assert oracle["scan_id"].tolist() == [7, 5, 3, 9]
    assert oracle["gain_cells"].tolist()[2:] == [0, 0]
    assert oracle["covered_cells"].iloc[-1] == pytest.approx(len(structure.xy), rel=0.05)


def test_area_under_the_curve_and_the_first_k_reaching_a_level():
    k = np.arange(1, 101)
    # F1 1 from the first scan: the area from (0, 0) to (0.01, 1), then 1 up to 0.2
    assert CS.area_under_curve(k, np.ones(100), 100) == pytest.approx((0.2 - 0.005) / 0.2)
    # F1 = k / 100: the mean of a line from 0 to 0.2 over [0, 0.2] is 0.1
    assert CS.area_under_curve(k, k / 100, 100) == pytest.approx(0.1)
    # a curve on a coarser grid is interpolated at 0.2
    assert CS.area_under_curve(np.array([10, 30, 100]), np.array([0.1, 0.3, 1.0]), 100) == pytest.approx(0.1)
    f1 = np.array([0.2, 0.5, 0.96, 0.9, 0.99, 1.0])
    assert CS.first_k_reaching(np.arange(1, 7), f1, 0.95) == 3
    assert math.isnan(CS.first_k_reaching(np.arange(1, 7), f1, 1.01))


def test_adaptive_curve_reads_the_first_k_as_the_full_grid_with_fewer_plans():
    """A curve rising slowly to its end: the dense part (20 %) and the coarse tail
    until the targets are reached, then the step before the crossing refined: the same
    first k as on the full grid, from about a third of the plans."""
    n = 500
    calls = []

    def evaluate(k):
        calls.append(k)
        return {"f1_5cm": 1 - math.exp(-k / 120)}

    full = C.k_grid(n)
    f1_all = evaluate(n)["f1_5cm"]
    calls.clear()
    targets = (0.95 * f1_all, 0.99 * f1_all)
    curve = C.adaptive_curve(evaluate, n, targets=targets)
    for t in targets:
        exact = CS.first_k_reaching(np.array(full), np.array([evaluate(k)["f1_5cm"] for k in full]), t)
        assert CS.first_k_reaching(curve["k"].to_numpy(), curve["f1_5cm"].to_numpy(), t) == exact
    assert curve["k"].is_monotonic_increasing and curve["k"].iloc[-1] == n
    assert (curve["k"] <= 100).sum() == 10  # every k of the grid up to 20 %
    assert len(curve) < 0.6 * len(full)


def test_adaptive_curve_reads_an_exact_target_to_one_scan_in_the_dense_part():
    """k95 at 3 % of 500 scans (between grid k 10 and 20): bisected to the first k, in
    a handful of plans more; a target first reached beyond the dense part is not."""
    n = 500

    def evaluate(k):
        return {"f1_5cm": min(1.0, k / 14.3)}  # reaches 0.95 at k 13.6: first k 14

    grid_only = C.adaptive_curve(evaluate, n, targets=(0.95,))
    curve = C.adaptive_curve(evaluate, n, targets=(0.95,), exact_targets=(0.95,))
    assert CS.first_k_reaching(grid_only["k"].to_numpy(), grid_only["f1_5cm"].to_numpy(), 0.95) == 20
    assert CS.first_k_reaching(curve["k"].to_numpy(), curve["f1_5cm"].to_numpy(), 0.95) == 14
    assert 1 <= len(curve) - len(grid_only) <= 4  # log2 of the step of 10
    assert curve["k"].is_monotonic_increasing

    def late(k):
        return {"f1_5cm": k / n}

    late_curve = C.adaptive_curve(late, n, targets=(0.95,), exact_targets=(0.95,))
    assert late_curve.equals(C.adaptive_curve(late, n, targets=(0.95,)))


def _curves(ordering, seed, f1s, n_kept=100):
    k = np.array([10, 20, 50, 100])
    return pd.DataFrame({"extractor": "ransac", "ordering": ordering, "seed": seed, "n_kept": n_kept, "k": k,
                         "f1_5cm": f1s})


def test_curve_summary_averages_random_seeds_and_compares_with_the_oracle():
    curves = pd.concat([
        _curves("cluster_hull", -1, [0.5, 0.96, 0.97, 1.0]),
        _curves("oracle", -1, [0.96, 0.98, 0.99, 1.0]),
        _curves("random", 0, [0.3, 0.6, 0.96, 1.0]),
        _curves("random", 1, [0.4, 0.96, 0.97, 1.0]),
    ], ignore_index=True)
    s = CS.curve_summary(curves, n_kept=100, n_recorded=400).set_index("ordering")
    assert s.loc["cluster_hull", "k_95"] == 20 and s.loc["oracle", "k_95"] == 10
    assert s.loc["random", "k_95"] == 35 and s.loc["random", "k_95_seed_sd"] == 15  # seeds: 50 and 20
    assert s.loc["random", "n_seeds"] == 2 and math.isnan(s.loc["cluster_hull", "k_95_seed_sd"])
    assert s.loc["cluster_hull", "fraction_kept_95"] == 0.2 and s.loc["cluster_hull", "fraction_recorded_95"] == 0.05
    assert s.loc["cluster_hull", "k95_over_oracle"] == 2.0 and s.loc["oracle", "k95_over_oracle"] == 1.0
    assert s.loc["oracle", "k_99"] == 50 and s.loc["cluster_hull", "k_99"] == 100
    # areas to 20 %: trapezoids from (0, 0)
    assert s.loc["cluster_hull", "auc"] == pytest.approx((0.1 * 0.5 / 2 + 0.1 * (0.5 + 0.96) / 2) / 0.2)
    line = beats_random_line(s.reset_index(), "cluster_hull", "ransac")
    assert line.startswith("cluster_hull beats random with ransac") and "k95 20 against 35" in line
    worse = beats_random_line(s.reset_index(), "random", "ransac")
    assert "random does not beat random" in worse


def test_curve_summary_markdown_gives_a_row_per_ordering_with_the_seeds_spread():
    curves = pd.concat([_curves("cluster_hull", -1, [0.5, 0.96, 0.97, 1.0]),
                        _curves("oracle", -1, [0.96, 0.98, 0.99, 1.0]),
                        _curves("random", 0, [0.3, 0.6, 0.96, 1.0]),
                        _curves("random", 1, [0.4, 0.96, 0.97, 1.0])], ignore_index=True)
    s = CS.curve_summary(curves, n_kept=100, n_recorded=400)
    md = CS.curve_summary_markdown(s, 0.05, 100, 400, "LINE")
    rows = [r for r in md.splitlines() if r.startswith("| ransac")]
    assert len(rows) == 3 and "LINE" in md and "100 kept of 400 recorded" in md
    assert rows[2].split(" | ")[3] == "35 +- 15" and rows[0].split(" | ")[-1] == "2.00 |"


def test_curve_summary_markdown_warns_of_an_f1_from_few_scans():
    curves = pd.concat([_curves("cluster_hull", -1, [0.5, 0.96, 0.97, 1.0], n_kept=8),
                        _curves("oracle", -1, [0.96, 0.98, 0.99, 1.0], n_kept=8)], ignore_index=True)
    curves["k"] = curves["k"].map({10: 1, 20: 2, 50: 4, 100: 8})  # 8 kept scans
    md = CS.curve_summary_markdown(CS.curve_summary(curves, n_kept=8, n_recorded=20), 0.05, 8, 20, "LINE")
    assert md.count("1.000 (warning: from 8 scans)") == 2

"""The lazy greedy on a weighted coverage takes the plain greedy's scans, in its order
(plain_greedy: every gain recomputed at every step, written apart from the lazy one)."""

import numpy as np
import pandas as pd
import pytest

from floorscan.core.greedy import lazy_greedy, plain_greedy


def _system(seed, weighted):
    rng = np.random.default_rng(seed)
    ids = sorted(rng.choice(1000, size=int(rng.integers(5, 60)), replace=False).tolist())
    universe = int(rng.integers(10, 200))
    cover = {s: np.unique(rng.integers(0, universe, size=int(rng.integers(0, 25)))) for s in ids}
    if not weighted:
        return ids, cover, None, None
    # few distinct qualities and values: many exact ties, as on real scans
    quality = {s: rng.choice([0.25, 0.5, 1.0], size=len(c)) for s, c in cover.items()}
    value = rng.choice([0.0, 1.0, 2.0], size=universe)
    return ids, cover, quality, value


@pytest.mark.parametrize("weighted", [False, True])
@pytest.mark.parametrize("seed", range(20))
def test_lazy_greedy_orders_as_the_plain_greedy(seed, weighted):
    ids, cover, quality, value = _system(seed, weighted)
    lazy = lazy_greedy(cover, ids, quality, value)
    plain = plain_greedy(cover, ids, quality, value)
    pd.testing.assert_frame_equal(lazy, plain)
    assert sorted(lazy["scan_id"]) == ids
    if not weighted:
        assert lazy["covered"].iloc[-1] == len(np.unique(np.concatenate(list(cover.values()))))


def test_quality_and_value_change_the_choice():
    cover = {1: np.array([0, 1, 2]), 2: np.array([3, 4]), 3: np.array([0, 1])}
    assert lazy_greedy(cover, [1, 2, 3])["scan_id"].tolist() == [1, 2, 3]
    # cells 3 and 4 worth 2 each: scan 2 first
    assert lazy_greedy(cover, [1, 2, 3], value=np.array([1, 1, 1, 2, 2.0]))["scan_id"].tolist() == [2, 1, 3]
    # scan 1 sees cells 0 and 1 poorly (0.25): scan 3's good view of them still adds 1.5
    order = lazy_greedy(cover, [1, 2, 3], quality={1: np.array([0.25, 0.25, 1.0]), 2: np.ones(2), 3: np.ones(2)})
    assert order["scan_id"].tolist() == [2, 3, 1]
    assert order["gain"].tolist() == [2.0, 2.0, 1.0]
    assert order["covered"].iloc[-1] == 5.0


def test_bad_weights_are_refused():
    cover = {1: np.array([0, 1])}
    with pytest.raises(ValueError, match="2 cells"):
        lazy_greedy(cover, [1], quality={1: np.ones(3)})
    with pytest.raises(ValueError, match=r"\(0, 1\]"):
        lazy_greedy(cover, [1], quality={1: np.array([0.5, 1.5])})
    with pytest.raises(ValueError, match=">= 0"):
        lazy_greedy(cover, [1], value=np.array([1.0, -1.0]))

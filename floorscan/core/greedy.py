"""Lazy greedy maximisation of a weighted coverage, the ordering of scans by what they add.

A scan ``s`` covers cells ``C_s`` with qualities ``q(s, c)`` in (0, 1]; a cell is worth
``v(c)`` >= 0. The coverage of a set of scans ``S`` is

    f(S) = sum over cells c of v(c) * max over s in S of q(s, c)

(the weighted set cover of Nemhauser, Wolsey and Fisher 1978 when every ``q`` is 1; a
facility-location function otherwise). ``f`` is monotone and submodular, so the greedy
that takes at each step the scan of the largest gain ``f(S + s) - f(S)`` is within
``1 - 1/e`` of the best set of every size, and the lazy greedy of Minoux (1978) takes
the same scans: a scan's gain only shrinks as others are taken, so a stale gain in
the heap is an upper bound, and a scan whose refreshed gain still tops the heap is the
plain greedy's choice. Ties go to the smaller scan id; scans that add nothing follow
in scan id order.

Usage::

    order = lazy_greedy({7: cells7, 9: cells9}, [7, 9])                 # set cover
    order = lazy_greedy(cover, ids, quality={7: q7, 9: q9}, value=v)  # weighted

:func:`plain_greedy` recomputes every gain at every step: the reference the lazy
greedy is tested and benchmarked against (``benchmarks selection``).
"""

from __future__ import annotations

import heapq
from typing import Mapping, Sequence

import numpy as np
import pandas as pd


def lazy_greedy(
    cover: Mapping[int, np.ndarray],
    scan_ids: Sequence[int],
    quality: Mapping[int, np.ndarray] | None = None,
    value: np.ndarray | None = None,
) -> pd.DataFrame:
    """Order scans by the lazy greedy on the coverage ``f`` (module docstring).

    Parameters
    ----------
    cover : mapping of int to (M_s,) int ndarray
        Per scan the distinct cell indices (>= 0) it covers; a scan of ``scan_ids``
        missing here covers nothing.
    scan_ids : sequence of int
        The scans to order.
    quality : mapping of int to (M_s,) float ndarray, optional
        ``q(s, c)`` in (0, 1] of each scan's cells, in the order of ``cover``; all 1
        when omitted.
    value : (N,) float ndarray, optional
        ``v(c)`` >= 0 per cell index; all 1 when omitted.

    Returns
    -------
    pandas.DataFrame
        ``rank`` (0 ..), ``scan_id``, ``gain`` (``f(S + s) - f(S)``, float64) and
        ``covered`` (``f`` of the first rank + 1 scans), a row per scan of ``scan_ids``.

    Raises
    ------
    ValueError
        When a scan's quality and cover differ in length, or a quality is not in
        (0, 1], or a value is negative.
    """
    ids = [int(s) for s in scan_ids]
    sets = {s: np.asarray(cover.get(s, np.empty(0, np.int64)), dtype=np.int64) for s in ids}
    n_cells = 1 + max((int(c.max()) for c in sets.values() if len(c)), default=-1)
    if value is None:
        v = np.ones(n_cells)
    else:
        v = np.zeros(n_cells)
        given = np.asarray(value, dtype=np.float64)
        if (given < 0).any() or not np.isfinite(given).all():
            raise ValueError("lazy_greedy: cell values must be finite and >= 0")
        v[: min(n_cells, len(given))] = given[:n_cells]
    q = {}
    for s in ids:
        if quality is None or s not in quality:
            q[s] = np.ones(len(sets[s]))
            continue
        q[s] = np.asarray(quality[s], dtype=np.float64)
        if len(q[s]) != len(sets[s]):
            raise ValueError(f"lazy_greedy: scan {s}: {len(q[s])} qualities for {len(sets[s])} cells")
        if len(q[s]) and not ((q[s] > 0).all() and (q[s] <= 1).all()):
            raise ValueError(f"lazy_greedy: scan {s}: qualities must be in (0, 1]")
    best = np.zeros(n_cells)

    def gain(s: int) -> float:
        c = sets[s]
        return float(np.sum(v[c] * np.maximum(q[s] - best[c], 0.0)))

    heap = [(-gain(s), s) for s in ids]
    heapq.heapify(heap)
    rows, total, taken = [], 0.0, set()
    while heap:
        _, s = heapq.heappop(heap)
        g = gain(s)
        if heap and (g < -heap[0][0] or (g == -heap[0][0] and heap[0][1] < s)):
            heapq.heappush(heap, (-g, s))  # stale: refreshed, back in line
            continue
        if g <= 0.0:  # no scan adds anything any more
            break
        c = sets[s]
        best[c] = np.maximum(best[c], q[s])
        total += g
        taken.add(s)
        rows.append((len(rows), s, g, total))
    for s in sorted(x for x in ids if x not in taken):
        rows.append((len(rows), s, 0.0, total))
    return pd.DataFrame(rows, columns=["rank", "scan_id", "gain", "covered"])


def plain_greedy(
    cover: Mapping[int, np.ndarray],
    scan_ids: Sequence[int],
    quality: Mapping[int, np.ndarray] | None = None,
    value: np.ndarray | None = None,
) -> pd.DataFrame:
    """The greedy of :func:`lazy_greedy` with every gain recomputed at every step
    (O(steps x scans) gains; the gains summed as there, so equal to the last bit); no
    input checks.

    Parameters
    ----------
    cover : mapping of int to (K,) int ndarray
        Cell indices each scan covers.
    scan_ids : sequence of int
        The candidate scans.
    quality : mapping of int to (K,) float ndarray, optional
        Per covered cell, how well the scan sees it (default 1).
    value : (C,) float ndarray, optional
        Weight per cell (default 1).

    Returns
    -------
    pandas.DataFrame
        ``rank``, ``scan_id``, ``gain``, ``covered`` (cumulative gain) in greedy order;
        the scans with no gain last, smallest id first, gain 0.
    """
    ids = sorted(int(s) for s in scan_ids)
    sets = {s: np.asarray(cover.get(s, np.empty(0, np.int64)), dtype=np.int64) for s in ids}
    n_cells = 1 + max((int(c.max()) for c in sets.values() if len(c)), default=-1)
    v = np.ones(n_cells) if value is None else np.asarray(value, dtype=np.float64)[:n_cells]
    q = {s: np.ones(len(sets[s])) if quality is None or s not in quality else np.asarray(quality[s], np.float64)
         for s in ids}
    best = np.zeros(n_cells)
    rows, total = [], 0.0
    while ids:
        gains = [float(np.sum(v[sets[s]] * np.maximum(q[s] - best[sets[s]], 0.0))) for s in ids]
        i = int(np.argmax(gains))  # the first maximum: the smallest scan id
        if gains[i] <= 0.0:
            break
        s = ids.pop(i)
        best[sets[s]] = np.maximum(best[sets[s]], q[s])
        total += gains[i]
        rows.append((len(rows), s, gains[i], total))
    rows += [(len(rows) + n, s, 0.0, total) for n, s in enumerate(ids)]
    return pd.DataFrame(rows, columns=["rank", "scan_id", "gain", "covered"])

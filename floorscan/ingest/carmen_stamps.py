"""The stamps of a CARMEN log's laser lines: recorded, spread or made up.

Stamps (:func:`classify_stamps`), one of:

- ``recorded``: strictly increasing once the few lines that step back in time are
  sorted by stamp (a stable sort; each line carries its own pose, so nothing is lost);
- ``spread``: some stamps repeat but at most half of the lines repeat an earlier one
  (stamps printed with too few digits): the scans keep line order and each run of equal
  stamps is spread evenly between its value and the next distinct one (the last run
  over the median positive step);
- ``made_up``: every stamp is 0, or more than half of the lines repeat an earlier stamp
  (a log printed with 6 significant digits): the scans in line order are stamped at
  their index times ``missing_time_period_s`` from the first stamp.

Zero stamps among non-zero ones mean a corrupt log and are rejected.
"""

from __future__ import annotations

import numpy as np


def classify_stamps(t_s: np.ndarray) -> tuple[str, int]:
    """The class of a log's laser stamps (see the module docstring) and its repeat count.

    Parameters
    ----------
    t_s : (S,) float ndarray
        ipc timestamps of the laser lines in line order, seconds.

    Returns
    -------
    kind : str
        ``"recorded"``, ``"spread"`` or ``"made_up"``.
    n_repeated : int
        Lines whose stamp equals an earlier line's.

    Raises
    ------
    ValueError
        Some stamps are 0 but not all (a corrupt log; :func:`floorscan.ingest.carmen.open_carmen` reports it as
        an ``InputError`` naming the lines).
    """
    t = np.asarray(t_s, dtype=np.float64)
    if t.size and np.all(t == 0):
        return "made_up", int(t.size) - 1
    if np.any(t == 0):
        raise ValueError("zero stamps among non-zero ones")
    n_rep = int(t.size - np.unique(np.round(t * 1e9)).size)
    if n_rep > t.size / 2:
        return "made_up", n_rep
    return ("spread" if n_rep else "recorded"), n_rep


def spread_stamps(t_ns: np.ndarray) -> np.ndarray:
    """Spread runs of equal stamps evenly up to the next distinct stamp.

    Parameters
    ----------
    t_ns : (S,) int64 ndarray
        Non-decreasing stamps, nanoseconds, with some runs of equal values.

    Returns
    -------
    (S,) int64 ndarray
        A run of ``k`` lines at ``v`` followed by ``v'`` gets ``v + j (v' - v) / k``,
        j = 0..k-1 (rounded to ns); the last run uses ``v' = v +`` the median positive
        step of ``t_ns`` (1 s when there is none).
    """
    t = np.asarray(t_ns, dtype=np.int64)
    out = t.copy()
    if t.size < 2:
        return out
    steps = np.diff(t)
    pos = steps[steps > 0]
    last_step = int(np.median(pos)) if pos.size else 1_000_000_000
    starts = np.r_[0, np.flatnonzero(steps) + 1]
    ends = np.r_[starts[1:], t.size]
    for a, b in zip(starts, ends):
        k = b - a
        if k < 2:
            continue
        nxt = t[b] if b < t.size else t[a] + last_step
        out[a:b] = t[a] + np.round(np.arange(k) * ((nxt - t[a]) / k)).astype(np.int64)
    return out

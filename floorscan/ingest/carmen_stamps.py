"""The stamps of a CARMEN log's laser lines: recorded, spread or made up.

A stamp (``ipc_timestamp``, seconds) is *out of range* when it is not a finite number
0 or more and below :data:`WRAP_S` (a negative stamp, ``nan``, ``inf``, or one at or
past the 32-bit wrap, as a converter writes ``-0.45`` in an unsigned 32-bit count of
seconds: 4294967295.55). A line is *out of time order* when its stamp, in range, is off
the longest run of non-decreasing stamps in line order (a longest non-decreasing
subsequence: the fewest lines to take out for the rest to be in time order; a line
that steps back and the one it swapped with count once).

The rule (:func:`stamp_class`): the stamps are unusable for the whole recording when
more than half of the laser lines are out of range or out of time order; then they are
made up. Otherwise a single stamp out of range is a malformed line (the caller names
``file:line`` and the field), and the lines out of time order are sorted by stamp. So a
log whose every stamp is junk is read in line order, and one bad stamp in a good log is
an error, never silently replaced.

Stamp classes, one of:

- ``recorded``: strictly increasing once the few lines that step back in time are
  sorted by stamp (a stable sort; each line carries its own pose, so nothing is lost);
- ``spread``: some stamps repeat but at most half of the lines repeat an earlier one
  (stamps printed with too few digits): the scans keep line order and each run of equal
  stamps is spread evenly between its value and the next distinct one (the last run
  over the median positive step);
- ``made_up``: more than half of the stamps out of range or out of time order (above),
  every stamp 0, or more than half of the lines repeating an earlier stamp (a log
  printed with 6 significant digits): the scans in line order are stamped at their
  index times ``missing_time_period_s`` from the first stamp (from 0 when the first
  stamp is out of range). :attr:`StampClass.why` says which, with the counts, for the
  ingest log and the registration's verdict.

Zero stamps among non-zero ones mean a corrupt log and are rejected.

Two logs in one file (two recordings concatenated) are found before the class
(:func:`log_starts`): where the stamps step back by more than
:data:`floorscan.ingest.recording.MAX_STEP_BACK_S` and stay back for at least
:data:`MIN_LOG_LINES` lines, another log starts; the reader refuses the file, naming
the lines, rather than sorting two recordings into one trajectory.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass

import numpy as np

from floorscan.ingest.recording import MAX_STEP_BACK_S

#: Stamps at or past this are out of range, seconds: 2^31 s (2038-01-19), where a
#: signed 32-bit count of seconds wraps; a negative stamp written as an unsigned 32-bit
#: count (``-0.45`` -> 4294967295.55) lands between it and 2^32. Below it a stamp's
#: nanoseconds fit in int64.
WRAP_S = 2.0**31


#: A part of a log shorter than this many laser lines (a second at 10 Hz) is no second
#: recording: a stray line or a few stamped far back are broken stamps, refused one by one.
MIN_LOG_LINES = 10


@dataclass(frozen=True)
class StampClass:
    """The class of a log's laser stamps and its counts.

    Attributes
    ----------
    kind : str
        ``"recorded"``, ``"spread"`` or ``"made_up"`` (see the module docstring).
    n_repeated : int
        Lines whose stamp equals an earlier line's.
    n_out_of_range : int
        Stamps not finite, negative, or at or past :data:`WRAP_S`.
    n_out_of_order : int
        Stamps in range off the longest non-decreasing run (see the module docstring).
    why : str
        For ``made_up``, why, with the counts (e.g. ``958 of 958 laser stamps out of
        range (negative or past the 32-bit wrap)``); ``""`` otherwise.
    """

    kind: str
    n_repeated: int = 0
    n_out_of_range: int = 0
    n_out_of_order: int = 0
    why: str = ""


class StampsOutOfRange(ValueError):
    """A few stamps out of range in a log whose stamps are otherwise usable.

    Attributes
    ----------
    index : int
        Position (0-based, line order) of the first stamp out of range.
    n_bad, n : int
        Stamps out of range, and all stamps.
    """

    def __init__(self, index: int, n_bad: int, n: int):
        super().__init__(f"{n_bad} of {n} stamps out of range, the first at {index}")
        self.index, self.n_bad, self.n = index, n_bad, n


def out_of_range(t_s: np.ndarray) -> np.ndarray:
    """Which stamps are out of range: not finite, negative, or at or past :data:`WRAP_S`.

    Parameters
    ----------
    t_s : (S,) float ndarray
        Stamps, seconds.

    Returns
    -------
    (S,) bool ndarray
    """
    t = np.asarray(t_s, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        return ~((t >= 0.0) & (t < WRAP_S))  # NaN fails both


def n_out_of_time_order(t_s: np.ndarray) -> int:
    """Stamps off the longest non-decreasing subsequence of ``t_s``: the fewest to take
    out for the rest to be in time order.

    Parameters
    ----------
    t_s : (S,) float ndarray
        Finite stamps in line order, seconds.

    Returns
    -------
    int
        0 when ``t_s`` is non-decreasing; ``S - L`` where ``L`` is the length of the
        longest non-decreasing subsequence (patience sorting, O(S log S)).
    """
    t = np.asarray(t_s, dtype=np.float64)
    if t.size < 2 or bool(np.all(np.diff(t) >= 0)):
        return 0
    tails: list[float] = []
    for v in t.tolist():
        i = bisect.bisect_right(tails, v)
        if i == len(tails):
            tails.append(v)
        else:
            tails[i] = v
    return int(t.size - len(tails))


def log_starts(t_s: np.ndarray) -> np.ndarray:
    """Where another log starts in a file of several concatenated logs.

    A log starts at line ``k`` when its stamp is more than :data:`MAX_STEP_BACK_S`
    before the line before it and the next :data:`MIN_LOG_LINES` lines (those there
    are) stay that far back. Only when every such step back starts a log, and every
    part holds at least :data:`MIN_LOG_LINES` lines, are the parts logs; otherwise (a
    stray stamp, junk stamps stepping back everywhere) none is returned and the stamp
    class (:func:`stamp_class`) decides.

    Parameters
    ----------
    t_s : (S,) float ndarray
        ipc timestamps of the laser lines in line order, seconds (out-of-range values
        allowed: a file with any is left to :func:`stamp_class`).

    Returns
    -------
    (P-1,) int ndarray
        Positions (0-based, line order) where the second, third, ... log starts; empty:
        one log.
    """
    t = np.asarray(t_s, dtype=np.float64)
    none = np.zeros(0, dtype=np.int64)
    if t.size < 2 * MIN_LOG_LINES or out_of_range(t).any():
        return none
    steps = np.flatnonzero(np.diff(t) < -MAX_STEP_BACK_S) + 1
    if steps.size == 0:
        return none
    for k in steps:
        if not np.all(t[k:k + MIN_LOG_LINES] < t[k - 1] - MAX_STEP_BACK_S):
            return none
    bounds = np.r_[0, steps, t.size]
    if np.any(np.diff(bounds) < MIN_LOG_LINES):
        return none
    return steps.astype(np.int64)


def _out_of_range_kinds(t: np.ndarray) -> str:
    """What the stamps out of range are, e.g. ``negative or past the 32-bit wrap``."""
    kinds = [
        name
        for name, hit in (
            ("not a number", np.isnan(t).any()),
            ("negative", (t < 0).any()),
            ("infinite", np.isinf(t).any()),
            ("past the 32-bit wrap", (np.isfinite(t) & (t >= WRAP_S)).any()),
        )
        if hit
    ]
    return ", ".join(kinds[:-1]) + " or " + kinds[-1] if len(kinds) > 1 else kinds[0]


def _why_unusable(t: np.ndarray, bad: np.ndarray, n_order: int) -> str:
    n, n_out = t.size, int(bad.sum())
    order = "out of time order (off the longest run of non-decreasing stamps)"
    if n_out and not n_order:
        what = f"{n_out} of {n} laser stamps out of range ({_out_of_range_kinds(t[bad])})"
        return what if n_out == n else f"{what}, more than half"
    if n_order and not n_out:
        return f"{n_order} of {n} laser stamps {order}, more than half"
    return (
        f"{n_out + n_order} of {n} laser stamps unusable, more than half: {n_out} out of range "
        f"({_out_of_range_kinds(t[bad])}), {n_order} {order}"
    )


def stamp_class(t_s: np.ndarray) -> StampClass:
    """The class of a log's laser stamps, by the rule of the module docstring.

    Parameters
    ----------
    t_s : (S,) float ndarray
        ipc timestamps of the laser lines in line order as written, seconds (any value:
        NaN, inf and negative included).

    Returns
    -------
    StampClass

    Raises
    ------
    StampsOutOfRange
        Some stamps out of range, but at most half of the lines out of range or out of
        time order (the caller names the first line; a ``ValueError``).
    ValueError
        Some stamps are 0 but not all, the others usable (a corrupt log;
        :func:`floorscan.ingest.carmen.open_carmen` reports it as an ``InputError``
        naming the lines).
    """
    t = np.asarray(t_s, dtype=np.float64)
    n = int(t.size)
    with np.errstate(invalid="ignore"):
        n_rep = int(n - np.unique(np.round(t * 1e9)).size)
    bad = out_of_range(t)
    n_out = int(bad.sum())
    n_order = n_out_of_time_order(t[~bad])
    if n and n_out + n_order > n / 2:
        return StampClass("made_up", n_rep, n_out, n_order, _why_unusable(t, bad, n_order))
    if n_out:
        raise StampsOutOfRange(int(np.flatnonzero(bad)[0]), n_out, n)
    if n and np.all(t == 0):
        return StampClass("made_up", n_rep, 0, 0, "every laser timestamp is 0")
    if np.any(t == 0):
        raise ValueError("zero stamps among non-zero ones")
    if n_rep > n / 2:
        why = (
            f"{n_rep} of {n} laser lines repeat an earlier timestamp ({len(np.unique(t))} distinct values), "
            "more than half"
        )
        return StampClass("made_up", n_rep, 0, n_order, why)
    return StampClass("spread" if n_rep else "recorded", n_rep, 0, n_order)


def classify_stamps(t_s: np.ndarray) -> tuple[str, int]:
    """The class of a log's laser stamps (:func:`stamp_class`) and its repeat count.

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
        As :func:`stamp_class` (:class:`StampsOutOfRange` is one).
    """
    c = stamp_class(t_s)
    return c.kind, c.n_repeated


def made_up_stamps_ns(t_s: np.ndarray, period_s: float) -> np.ndarray:
    """Made-up stamps: line index times ``period_s`` from the first stamp.

    Parameters
    ----------
    t_s : (S,) float ndarray
        The laser lines' stamps as written, seconds.
    period_s : float
        ``ingest.missing_time_period_s``, seconds.

    Returns
    -------
    (S,) int64 ndarray
        Nanoseconds: ``t0 + i x period_s``, ``t0`` the first stamp, or 0 when it is out
        of range (:func:`out_of_range`).
    """
    t = np.asarray(t_s, dtype=np.float64)
    t0_ns = 0 if (t.size == 0 or out_of_range(t[:1])[0]) else int(round(float(t[0]) * 1e9))
    return t0_ns + np.round(np.arange(t.size) * period_s * 1e9).astype(np.int64)


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

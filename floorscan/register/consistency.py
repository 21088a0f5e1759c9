"""Does the registered map agree with itself? The verdict on a registration.

A map registered from drifting poses (wheel odometry taken for the map pose, a
localizer that lost track) looks locally sharp, since consecutive scans agree, and
doubles its walls where the rover passes a place again. So the check looks where the
rover passed twice. Two scans are of different passes when the rover travelled at
least ``min_separation_m`` between them and at least ``path_ratio`` times the straight
distance between their poses (it went away and came back: the loop-closure candidate
test of SLAM front ends; scans along one corridor are of one pass, however far apart).
For a sample of map points, those with a point of another pass within
``revisit_radius_m`` are revisited; of them, the fraction with such a point within
``tau_m`` is the map's *consistency* (the cloud-to-cloud agreement of Cloud
Compare's C2C distance, restricted to revisits; the same idea as a loop closure's
inlier fraction in SLAM back ends). A well-registered map scores high but below 1
(the scanner's noise and the sampling of a wall by another scan), a doubled one low
(the figures of the shared recordings are in ``benchmarks/README.md``). When too few
points are revisited (a one-way corridor) it is undefined (NaN) and judges nothing.

:func:`verdict` joins it with the fraction of sampled scans kept, the scans the
recording lost before registration (:mod:`floorscan.register.losses`: scans without a
pose, ingest's losses) counted against all its scans, why the scans were placed by
LIDAR odometry when the user did not ask for it, and whether the recording's stamps
were made up (:func:`stamps_warning`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np
from scipy.spatial import cKDTree

from floorscan.core.grid import cell_means
from floorscan.core.score_tables import FEW_SCANS
from floorscan.register.losses import Losses, percent

#: Fewer revisited sample points than this: consistency undefined.
MIN_REVISITED = 300


def map_consistency(
    clouds: list[np.ndarray],
    path_m: np.ndarray,
    positions: np.ndarray,
    tau_m: float = 0.05,
    revisit_radius_m: float = 0.3,
    min_separation_m: float = 3.0,
    path_ratio: float = 2.0,
    cell_m: float = 0.05,
    max_points: int = 50_000,
    neighbours: int = 48,
    seed: int = 0,
) -> tuple[float, int]:
    """Fraction of revisited map points that another pass confirms within ``tau_m``.

    Parameters
    ----------
    clouds : list of (N_i, >=2) float ndarray
        Each kept scan's points in the map frame (x, y used), metres, in time order.
    path_m : (K,) float ndarray
        Distance travelled along the kept poses up to each scan, metres.
    positions : (K, 2) float ndarray
        Each scan's position (x, y) in the map frame, metres.
    tau_m, revisit_radius_m, min_separation_m, cell_m : float
        See the module docstring; each scan is reduced to one point per ``cell_m`` cell
        first. Metres.
    path_ratio : float
        See the module docstring.
    max_points : int
        Sample size (points drawn with ``seed``; the same input gives the same number).
    neighbours : int
        Nearest points examined per sample point.

    Returns
    -------
    consistency : float
        In [0, 1]; NaN when fewer than :data:`MIN_REVISITED` sample points are revisited.
    n_revisited : int
        Sample points that another pass has within ``revisit_radius_m``.
    """
    parts, labels = [], []
    for i, c in enumerate(clouds):
        if len(c) == 0:
            continue
        xy = cell_means(np.asarray(c, dtype=np.float64)[:, :2], cell_m)[0]
        parts.append(xy)
        labels.append(np.full(len(xy), i, dtype=np.int64))
    if not parts:
        return math.nan, 0
    pts = np.concatenate(parts)
    lab = np.concatenate(labels)
    s = np.asarray(path_m, dtype=np.float64)[lab]
    pos = np.asarray(positions, dtype=np.float64)[lab, :2]
    rng = np.random.default_rng(seed)
    idx = np.arange(len(pts)) if len(pts) <= max_points else np.sort(rng.choice(len(pts), max_points, replace=False))
    tree = cKDTree(pts)
    d, j = tree.query(pts[idx], k=min(neighbours, len(pts)), distance_upper_bound=revisit_radius_m)
    d, j = d.reshape(len(idx), -1), j.reshape(len(idx), -1)
    found = np.isfinite(d)
    j = np.minimum(j, len(pts) - 1)
    travel = np.abs(s[idx][:, None] - s[j])
    straight = np.hypot(pos[idx, 0][:, None] - pos[j, 0], pos[idx, 1][:, None] - pos[j, 1])
    other = found & (travel >= min_separation_m) & (travel >= path_ratio * straight)
    revisited = other.any(axis=1)
    n_rev = int(revisited.sum())
    if n_rev < MIN_REVISITED:
        return math.nan, n_rev
    confirmed = (other & (d <= tau_m)).any(axis=1)
    return float(confirmed[revisited].mean()), n_rev


def path_length_m(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Cumulative distance along poses (x, y metres), 0 at the first: (K,) metres."""
    if len(x) == 0:
        return np.zeros(0)
    return np.r_[0.0, np.cumsum(np.hypot(np.diff(x), np.diff(y)))]


@dataclass
class Verdict:
    """The verdict on a registration.

    Attributes
    ----------
    n_sampled, n_kept : int
        Scans sampled for registration and kept.
    kept_fraction : float
        ``n_kept / n_sampled``.
    consistency : float
        :func:`map_consistency` (NaN: undefined).
    n_revisited : int
    problems : list of str
        Why the result is poor (each names its numbers and the option); empty when good.
    warnings : list of str
        What a reader should know although the stage goes on (few scans, no revisits,
        each loss, a fall-back to LIDAR odometry).
    notes : list of str
        Facts in the line that do not make it a warning (a few scans without a pose at
        the recording's ends: :meth:`floorscan.register.losses.Losses.notes`).
    losses : Losses or None
        The scans lost before registration, against all the recording's scans; None:
        not counted.
    """

    n_sampled: int
    n_kept: int
    kept_fraction: float
    consistency: float
    n_revisited: int
    problems: list[str] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    losses: Losses | None = None

    @property
    def ok(self) -> bool:
        return not self.problems

    def line(self) -> str:
        """One line for logs, the summary and the report: the verdict, the scans kept, the
        scans lost before registration when several causes add up to them (one cause's
        line, among the warnings or notes, gives its count itself), the map consistency,
        then the problems, warnings and notes."""
        head = "GOOD" if self.ok and not self.warnings else ("POOR" if not self.ok else "WARNING")
        cons = "undefined (no place passed twice)" if math.isnan(self.consistency) else f"{self.consistency:.2f}"
        lost = ""
        if self.losses is not None and sum(n > 0 for n in self.losses.counts.values()) > 1:
            n, total = self.losses.n_lost, self.losses.n_recording
            lost = f", {n} of the recording's {total} scans ({percent(n, total)}) lost before registration"
        text = (
            f"{head}: kept {self.n_kept} of {self.n_sampled} sampled scans ({100 * self.kept_fraction:.0f} %){lost}; "
            f"map consistency {cons} ({self.n_revisited} revisited points)"
        )
        return "; ".join([text, *self.problems, *self.warnings, *self.notes])

    def as_dict(self) -> dict:
        return {
            "ok": self.ok,
            "line": self.line(),
            "n_sampled": self.n_sampled,
            "n_kept": self.n_kept,
            "kept_fraction": self.kept_fraction,
            "consistency": None if math.isnan(self.consistency) else self.consistency,
            "n_revisited": self.n_revisited,
            "problems": list(self.problems),
            "warnings": list(self.warnings),
            "notes": list(self.notes),
            "losses": self.losses.as_dict() if self.losses is not None else None,
        }


#: A pause in the scans is worth a warning when it is longer than this, seconds, and than
#: :data:`PAUSE_PERIODS` of their median period: the shared recordings pause at most 38 s
#: (aces, a corrected log with a scan every 2.2 s), while a second recording appended to
#: the first (the next day, the next floor) pauses for as long as it was not recording.
PAUSE_S = 60.0
#: ... and than this many of the scans' median periods.
PAUSE_PERIODS = 20


def pause_warning(t_ns: np.ndarray) -> str:
    """The verdict's warning for scans whose stamps pause: two recordings in one file, or a
    scanner stopped and started again; ``""`` when they do not.

    Parameters
    ----------
    t_ns : (N,) int64 ndarray
        The scans' stamps, nanoseconds, in scan order.

    Returns
    -------
    str
        E.g. ``the scans pause for 26.4 h after scan 499 (49.9 s into the scans): two
        recordings in one file? ...``, naming the three longest pauses.
    """
    t = np.asarray(t_ns, dtype=np.int64)
    if len(t) < 3:
        return ""
    dt = np.diff(t) * 1e-9
    positive = dt[dt > 0]
    if not len(positive):
        return ""
    limit = max(PAUSE_S, PAUSE_PERIODS * float(np.median(positive)))
    at = np.flatnonzero(dt > limit)
    if not len(at):
        return ""

    def span(sec: float) -> str:
        return f"{sec / 3600:.1f} h" if sec >= 3600 else (f"{sec / 60:.1f} min" if sec >= 60 else f"{sec:.0f} s")

    longest = sorted(at[np.argsort(-dt[at], kind="stable")[:3]].tolist())
    where = "; ".join(f"for {span(float(dt[k]))} after scan {k} ({(t[k] - t[0]) * 1e-9:.1f} s into the scans)"
                      for k in longest)
    more = f" (and {len(at) - len(longest)} more)" if len(at) > len(longest) else ""
    return (f"the scans pause {where}{more}: two recordings in one file? If so, their maps need not agree: split "
            "the file where the second starts; a scanner stopped and started again in one place needs nothing")


def stamps_warning(recording: Mapping[str, str] | None, t_ns: np.ndarray | None = None) -> str:
    """The verdict's warning on a recording's stamps: made up by ingest, or (its own)
    pausing (:func:`pause_warning`); ``""`` otherwise.

    Parameters
    ----------
    recording : mapping of str to str, or None
        The scan index's schema metadata (:func:`floorscan.core.io.read_metadata`): keys
        ``stamps`` (``made_up``: made up) and ``stamps_reason`` (why, with the counts).
    t_ns : (N,) int64 ndarray, optional
        The scans' stamps, nanoseconds, in scan order; None: no pause is looked for.

    Returns
    -------
    str
        E.g. ``stamps made up: 958 of 958 laser stamps out of range (negative or past the
        32-bit wrap); the scans keep the recording's order, ingest.missing_time_period_s
        apart, so the checks on speed and turn rate are off``.
    """
    rec = dict(recording or {})
    if rec.get("stamps") != "made_up":
        return "" if t_ns is None else pause_warning(t_ns)
    why = str(rec.get("stamps_reason") or "").strip()
    return (
        f"stamps made up{': ' + why if why else ''}; the scans keep the recording's order, "
        "ingest.missing_time_period_s apart, so the checks on speed and turn rate are off"
    )


def verdict(
    n_sampled: int,
    n_kept: int,
    consistency: float,
    n_revisited: int,
    min_kept_fraction: float,
    min_consistency: float,
    worst_reason: str = "",
    worst_option: str = "",
    losses: Losses | None = None,
    max_lost_fraction: float = 1.0,
    fallback: str = "",
    stamps: str = "",
) -> Verdict:
    """Judge a registration by its kept fraction, its map consistency and the scans the
    recording lost before it.

    Parameters
    ----------
    n_sampled, n_kept : int
    consistency : float
        NaN: undefined, not judged.
    n_revisited : int
    min_kept_fraction, min_consistency : float
        ``register.min_kept_fraction`` / ``register.min_consistency``.
    worst_reason, worst_option : str
        The drop reason behind most lost scans and the option that sets it, for the
        message.
    losses : Losses, optional
        The scans lost before registration (:mod:`floorscan.register.losses`): each
        cause is a warning with its count; more than ``max_lost_fraction`` of the
        recording's scans lost is a problem naming them.
    max_lost_fraction : float
        ``register.max_lost_fraction`` (1: losses are only warned about).
    fallback : str
        Why the scans were placed by LIDAR odometry without the user asking (the
        recording has no map poses); a warning, first. ``""``: no fall-back.
    stamps : str
        :func:`stamps_warning` of the recording: a warning, after the fall-back. ``""``:
        the stamps are the recording's own.

    Returns
    -------
    Verdict
    """
    frac = n_kept / n_sampled if n_sampled else 0.0
    v = Verdict(n_sampled, n_kept, frac, consistency, n_revisited, losses=losses)
    if fallback:
        v.warnings.append(fallback)
    if stamps:
        v.warnings.append(stamps)
    if losses is not None:
        problem = losses.problem(max_lost_fraction)
        if problem:
            v.problems.append(problem)
        v.warnings.extend(losses.warnings())
        v.notes.extend(losses.notes())
    if frac < min_kept_fraction:
        why = f"; most were dropped as '{worst_reason}' ({worst_option})" if worst_reason else ""
        v.problems.append(
            f"only {100 * frac:.0f} % of the sampled scans were kept, below register.min_kept_fraction "
            f"{min_kept_fraction}{why}"
        )
    if math.isfinite(consistency) and consistency < min_consistency:
        v.problems.append(
            f"where the rover passed twice only {100 * consistency:.0f} % of the map's points agree within "
            f"5 cm, below register.min_consistency {min_consistency}: the poses drift (register.mode: odometry "
            "registers without them; register.min_consistency 0 accepts the map)"
        )
    if n_kept < FEW_SCANS:
        v.warnings.append(f"only {n_kept} scan{'' if n_kept == 1 else 's'} kept: the recording is too short (or the "
                          "scanner too still) for a map; scores from so few scans mean little")
    if math.isnan(consistency):
        v.warnings.append("no place was passed twice, so the map's consistency could not be checked")
    return v

"""Scans of a recording that never reach registration, counted for the verdict (issue 35).

A registration judged only on the scans it sampled reads "kept 14 of 14 sampled scans
(100 %)" when the localizer stopped after a third of the recording and two thirds of
the scans had no pose. So the verdict (:func:`floorscan.register.consistency.verdict`)
counts the scans lost before registration against all the recording's scans, by cause
(:data:`CAUSES`, in the order the verdict names them):

- ``no_pose``: the poses stage gave the scan no pose (before the first pose, after the
  last, in a gap; pose mode only: LIDAR odometry does not use the poses);
- ``pose_jump``: the localizer's pose jumped (moved or turned faster than
  ``register.max_speed_m_s`` / ``max_turn_rate_rad_s`` since the last plausible pose,
  :class:`floorscan.register.screening.Screener`); the warning says where (scan, time)
  and by how much, per jump (:func:`pose_jump_episodes`);
- ``too_few_points``: scans with some points but fewer than ``register.min_points``
  (a scan without any is ``lost_no_points``);
- ``lost_bad_frames``: frames ingest could not read and skipped;
- ``lost_no_points``: scans without a valid return: those ingest skipped, and the scan
  index's scans with ``n_points`` 0 (such a scan is not counted again as without a
  pose);
- ``lost_unlisted_files``: PCD files not in the locations CSV;
- ``lost_unknown_lines``: CARMEN lines of an unknown type.

A scan dropped as a ``duplicate`` (the stamp or the very returns of the scan before it, as a
simulator or a stopped driver repeats them) is not counted: nothing of the recording is
lost with it. Ingest's counts are in the scan index's schema metadata (``Recording.detected``, read by
:func:`floorscan.core.io.read_metadata`); a missing key counts 0. The recording's scans
(the denominator) are ``n_frames_read`` (every frame ingest read, lost or not; at least
the scan index's scans and the frames ingest skipped, its only count when the key is
missing), plus the unlisted files and the unknown lines, which were never read as
frames.
Each loss is a warning of the verdict; more than ``register.max_lost_fraction`` of the
recording's scans lost stops the stage (:meth:`Losses.problem`).
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from dataclasses import dataclass
from typing import Mapping

import numpy as np
import pandas as pd

from floorscan.core.io import InputError
from floorscan.core.messages import quoted
from floorscan.core.io import AFTER, BEFORE, GAP, NO_POSE_SOURCE

#: Scans without a pose (poses stage), a cause of :data:`CAUSES`.
NO_POSE = "no_pose"
#: Ingest's loss counts: key in the scan index's metadata -> what the verdict says of those scans.
INGEST_LOSSES = {
    "lost_bad_frames": "were bad frames, skipped at ingest",
    "lost_no_points": "have no valid point (every return invalid or out of range)",
    "lost_unlisted_files": "are files not in the locations CSV, never read",
    "lost_unknown_lines": "are lines of an unknown type, never read",
}
#: Every frame ingest read, lost or not (scan index metadata).
N_FRAMES_READ = "n_frames_read"
#: Scans the register stage's screening drops before registration (its reasons).
POSE_JUMP, TOO_FEW_POINTS = "pose_jump", "too_few_points"
#: The causes, in the order the verdict names them.
CAUSES = (NO_POSE, POSE_JUMP, TOO_FEW_POINTS, *INGEST_LOSSES)
#: Pose jumps named one by one in the warning, the largest first.
MAX_JUMPS_NAMED = 3
#: Short names of the causes, for the one-line total.
SHORT = {
    NO_POSE: "without a pose",
    POSE_JUMP: "pose jumps",
    TOO_FEW_POINTS: "with too few points",
    "lost_bad_frames": "bad frames",
    "lost_no_points": "without a valid point",
    "lost_unlisted_files": "files not in the locations CSV",
    "lost_unknown_lines": "lines of an unknown type",
}
#: The poses stage's reasons (:mod:`floorscan.ingest.poses`) in words.
POSE_REASONS = {
    BEFORE: "before the first pose",
    AFTER: "after the last pose",
    GAP: "in a gap between poses longer than poses.max_gap_s",
    NO_POSE_SOURCE: "no pose source",
}


def percent(n: int, total: int) -> str:
    """``n / total`` as a percentage for people: ``67 %``, ``<1 %`` (never 0 % for a loss)."""
    if total <= 0:
        return "0 %"
    p = 100.0 * n / total
    return "<1 %" if 0 < p < 0.5 else f"{p:.0f} %"


#: Scans without a pose under this share of the recording's are a note of the verdict,
#: not a warning: a localizer that starts a moment after the scanner, or stops a moment
#: before it, leaves a scan or two at the ends (issue 47: 1 of trace0's 958).
NOTE_SHARE = 0.01


@dataclass(frozen=True)
class Losses:
    """The scans of a recording lost before registration.

    Attributes
    ----------
    n_recording : int
        The recording's scans (see the module docstring), the denominator.
    counts : dict of str to int
        Cause (:data:`CAUSES`) -> scans lost, the non-zero ones in that order.
    no_pose_detail : str
        Why the scans without a pose have none (reasons, counts and when the poses
        start and end), for the warning.
    details : dict of str to str
        Cause -> what the warning says after the count: ``pose_jump``: the jumps (where
        and by how much), ``too_few_points``: the option.
    empty_ids : (E,) int ndarray
        ``scan_id`` of the scan index's scans without points (counted under
        ``lost_no_points``, not again under ``no_pose``).
    """

    n_recording: int
    counts: dict[str, int] = dataclasses.field(default_factory=dict)
    no_pose_detail: str = ""
    empty_ids: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, np.int64))
    details: dict[str, str] = dataclasses.field(default_factory=dict)

    @property
    def n_lost(self) -> int:
        """Scans lost, all causes."""
        return int(sum(self.counts.values()))

    @property
    def fraction(self) -> float:
        """``n_lost / n_recording`` (0 for an empty recording)."""
        return self.n_lost / self.n_recording if self.n_recording else 0.0

    def warnings(self) -> list[str]:
        """One line per cause with its count, e.g. ``201 of the recording's 300 scans
        (67 %) have no pose (after_pose_stream 201: after the last pose; ...)``; the
        scans without a pose under :data:`NOTE_SHARE` of the recording are a note
        (:meth:`notes`), not a warning."""
        return [text for cause, text in self.lines() if not self.is_note(cause)]

    def notes(self) -> list[str]:
        """The lines of :meth:`lines` that are facts, not warnings: scans without a pose,
        fewer than :data:`NOTE_SHARE` of the recording's (a localizer that starts a
        moment after the scanner)."""
        return [text for cause, text in self.lines() if self.is_note(cause)]

    def is_note(self, cause: str) -> bool:
        """Whether the loss of ``cause`` is a note (:meth:`notes`)."""
        return cause == NO_POSE and self.counts.get(cause, 0) < NOTE_SHARE * self.n_recording

    def lines(self) -> list[tuple[str, str]]:
        """``(cause, line)`` per cause, in :data:`CAUSES` order (:meth:`warnings`)."""
        out = []
        for cause, n in self.counts.items():
            head = f"{n} of the recording's {self.n_recording} scans ({percent(n, self.n_recording)})"
            if cause == NO_POSE:
                text = f"{head} have no pose ({self.no_pose_detail})" if self.no_pose_detail else f"{head} have no pose"
            elif cause == POSE_JUMP:
                text = (f"{head} were dropped where the localizer's pose jumped (pose_jump"
                        + (f": {self.details[POSE_JUMP]})" if self.details.get(POSE_JUMP) else ")"))
            elif cause == TOO_FEW_POINTS:
                text = (f"{head} have too few points (too_few_points"
                        + (f": {self.details[TOO_FEW_POINTS]})" if self.details.get(TOO_FEW_POINTS) else ")"))
            else:
                text = f"{head} {INGEST_LOSSES[cause]} ({cause})"
            out.append((cause, text))
        return out

    def problem(self, max_lost_fraction: float) -> str:
        """``""`` when at most ``max_lost_fraction`` of the recording's scans are lost,
        else why the stage stops: the total, each cause and the option."""
        if self.fraction <= max_lost_fraction:
            return ""
        parts = ", ".join(f"{n} {SHORT[c]}" for c, n in self.counts.items())
        return (
            f"{self.n_lost} of the recording's {self.n_recording} scans ({percent(self.n_lost, self.n_recording)}) "
            f"never reached registration ({parts}), more than register.max_lost_fraction {max_lost_fraction}: "
            "the plan would show only part of what was recorded (register.max_lost_fraction 1 accepts it)"
        )

    def as_dict(self) -> dict:
        return {"n_recording": self.n_recording, "counts": dict(self.counts), "fraction": self.fraction}


def _count(detected: Mapping[str, str], key: str) -> int:
    value = detected.get(key)
    if value is None or str(value).strip() == "":
        return 0
    try:
        number = float(value)
    except ValueError:
        number = -1.0
    if not (number >= 0 and number.is_integer()):
        raise InputError(
            f"scan_index.parquet: metadata {key}={quoted(value, 40)} is not a count of scans; expected a whole "
            "number >= 0, as ingest writes it (rerun ingest)"
        )
    return int(number)


def ingest_losses(scan_index: pd.DataFrame, detected: Mapping[str, str] | None) -> Losses:
    """The scans ingest lost, from the scan index and its metadata.

    Parameters
    ----------
    scan_index : DataFrame
        ``scan_id`` and, when present, ``n_points`` (scans without points are losses).
    detected : mapping of str to str, or None
        The scan index's schema metadata: ``n_frames_read`` and the keys of
        :data:`INGEST_LOSSES` (string counts); missing keys count 0.

    Returns
    -------
    Losses
        Without ``no_pose`` (:func:`with_pose_losses` adds it).

    Raises
    ------
    InputError
        A count in the metadata that is not a whole number >= 0.
    """
    det = dict(detected or {})
    counts = {k: _count(det, k) for k in INGEST_LOSSES}
    if "n_points" in scan_index.columns:
        empty = scan_index["n_points"].to_numpy() == 0
        empty_ids = scan_index["scan_id"].to_numpy(np.int64)[empty]
    else:
        empty_ids = np.zeros(0, np.int64)
    skipped = counts["lost_bad_frames"] + counts["lost_no_points"]  # not in the index
    counts["lost_no_points"] += len(empty_ids)
    read = len(scan_index) + skipped
    n_read = max(read, _count(det, N_FRAMES_READ))
    n_recording = n_read + counts["lost_unlisted_files"] + counts["lost_unknown_lines"]
    return Losses(n_recording, {k: v for k, v in counts.items() if v}, empty_ids=empty_ids)


def with_pose_losses(losses: Losses, scan_ids: np.ndarray, t_ns: np.ndarray, reasons: np.ndarray) -> Losses:
    """``losses`` with the scans the poses stage gave no pose (``no_pose``).

    Parameters
    ----------
    scan_ids : (S,) int ndarray
    t_ns : (S,) int64 ndarray
        Scan stamps, nanoseconds, in scan order.
    reasons : (S,) str ndarray
        The register table's reasons: ``no_pose:<reason>`` for a scan without a pose.

    Returns
    -------
    Losses
        ``counts["no_pose"]`` first, and ``no_pose_detail``: the reasons with their
        counts and, when the poses start late or end early, when, e.g.
        ``after_pose_stream 201: after the last pose; the poses end 10.0 s into the
        29.9 s of scans``.
    """
    reasons = np.asarray(reasons).astype(str)
    t = np.asarray(t_ns, dtype=np.int64)
    no_pose = np.char.startswith(reasons, "no_pose:")
    lost = no_pose & ~np.isin(np.asarray(scan_ids, dtype=np.int64), losses.empty_ids)
    n = int(lost.sum())
    if n == 0:
        return losses
    by = Counter(r.split(":", 1)[1] for r in reasons[lost])
    detail = ", ".join(f"{r} {c}: {POSE_REASONS.get(r, r)}" for r, c in by.most_common())
    if (~no_pose).any() and len(t):
        t0, span = t.min(), (t.max() - t.min()) * 1e-9
        first, last = (t[~no_pose].min() - t0) * 1e-9, (t[~no_pose].max() - t0) * 1e-9
        when = []
        if BEFORE in by:
            when.append(f"the poses start {first:.1f} s")
        if AFTER in by:
            when.append(f"end {last:.1f} s" if when else f"the poses end {last:.1f} s")
        if when:
            detail += f"; {' and '.join(when)} into the {span:.1f} s of scans"
    counts = _ordered({**losses.counts, NO_POSE: n})
    return dataclasses.replace(losses, counts=counts, no_pose_detail=detail)


def _ordered(counts: Mapping[str, int]) -> dict[str, int]:
    """The non-zero counts in the order of :data:`CAUSES`."""
    return {c: int(counts[c]) for c in CAUSES if counts.get(c)}


def with_screening_losses(losses: Losses, scan_ids: np.ndarray, t_ns: np.ndarray, reasons: np.ndarray,
                          poses: pd.DataFrame | None, max_speed: str = "", min_points: int | None = None) -> Losses:
    """``losses`` with the scans the register stage's screening dropped before
    registration: ``pose_jump`` (with :func:`pose_jump_episodes`) and ``too_few_points``
    (without the scans of ``losses.empty_ids``, counted as ``lost_no_points``).

    Parameters
    ----------
    scan_ids : (S,) int ndarray
    t_ns : (S,) int64 ndarray
        Scan stamps, nanoseconds, in scan order.
    reasons : (S,) str ndarray
        The screening's reasons (:class:`floorscan.register.screening.Screener`).
    poses : pandas.DataFrame or None
        The localizer's poses aligned with the scans (``x, y, yaw``); None in odometry
        mode (no pose jumps).
    max_speed : str
        The options of the speed check, for the warning (e.g.
        ``register.max_speed_m_s 2.0, max_turn_rate_rad_s 3.0``).
    min_points : int, optional
        ``register.min_points``, for the warning.
    """
    reasons = np.asarray(reasons).astype(str)
    jump = reasons == POSE_JUMP
    few = (reasons == TOO_FEW_POINTS) & ~np.isin(np.asarray(scan_ids, dtype=np.int64), losses.empty_ids)
    if not jump.any() and not few.any():
        return losses
    counts = dict(losses.counts)
    details = dict(losses.details)
    if jump.any():
        counts[POSE_JUMP] = int(jump.sum())
        if poses is not None:
            xyyaw = poses[["x", "y", "yaw"]].to_numpy(np.float64)
            t = np.asarray(t_ns, np.int64)
            details[POSE_JUMP] = describe_jumps(pose_jump_episodes(reasons, t, xyyaw), np.asarray(scan_ids), t,
                                                max_speed)
    if few.any():
        counts[TOO_FEW_POINTS] = int(few.sum())
        if min_points is not None:
            details[TOO_FEW_POINTS] = f"fewer than register.min_points {min_points}"
    return dataclasses.replace(losses, counts=_ordered(counts), details=details)


#: An offset of the map pose that stays after a jump (the pose where the scans resume,
#: against the way the rover was going before it) at least this large is a
#: relocalisation, not an outlier that came back, metres: half a metre between the
#: scans before and after it is a second wall; a localizer's noise and the
#: extrapolation of a rover's way over the seconds of a jump are centimetres to
#: decimetres.
RELOCALISED_M = 0.5


@dataclass(frozen=True)
class PoseJump:
    """A jump of the localizer's pose: the scans dropped as ``pose_jump`` after one
    plausible pose (index positions; ``last`` -1: no plausible pose before).

    Attributes
    ----------
    first, n_scans, last : int
        The first jumped scan, how many were dropped, the last plausible scan before.
    distance_m, turn_rad, dt_s : float
        The first jumped pose from the last plausible one: metres, radians, seconds.
    back : int
        The next plausible scan, -1: none (the poses never came back).
    offset_m : float
        Metres between the pose at ``back`` and where the rover would be then, going on
        as it went between the two plausible poses before the jump (NaN without
        ``back`` or ``last``): about 0 when the pose came back, the jump's size when it
        stayed (:attr:`relocalised`).
    """

    first: int
    n_scans: int
    last: int
    distance_m: float
    turn_rad: float
    dt_s: float
    back: int
    offset_m: float = float("nan")

    @property
    def relocalised(self) -> bool:
        """The pose jumped and stayed: the scans resumed at least :data:`RELOCALISED_M`
        and half the first jump away from the way before it (a localizer that
        relocalised: the map of the scans after it is shifted from the map before)."""
        return bool(math.isfinite(self.offset_m) and self.offset_m >= max(RELOCALISED_M, 0.5 * self.distance_m))

    @property
    def size_m(self) -> float:
        """How far the map pose jumped: the offset that stayed (a relocalisation), else
        the first jumped pose's distance, metres (NaN: no pose before)."""
        return self.offset_m if self.relocalised else self.distance_m


def pose_jump_episodes(reasons: np.ndarray, t_ns: np.ndarray, xyyaw: np.ndarray) -> list[PoseJump]:
    """The jumps of the localizer's pose: the ``pose_jump`` scans grouped by the last
    plausible pose before them (as :class:`floorscan.register.screening.Screener` checks
    them: a scan with a pose that is neither a jump nor a duplicate is plausible), each
    with the first jumped pose's distance and turn from it and the offset at which the
    scans resumed (:attr:`PoseJump.offset_m`).

    Parameters
    ----------
    reasons : (S,) str ndarray
        The screening's reasons, in scan order.
    t_ns : (S,) int64 ndarray
    xyyaw : (S, 3) float ndarray
        The localizer's pose of each scan (metres, radians).

    Returns
    -------
    list of PoseJump
        In scan order.
    """
    reasons = np.asarray(reasons).astype(str)
    plausible = ~np.char.startswith(reasons, "no_pose") & (reasons != "duplicate") & (reasons != POSE_JUMP)
    out: list[PoseJump] = []
    before, last, group = -1, -1, None
    for i, r in enumerate(reasons):
        if r == POSE_JUMP:
            if group is not None and group[1] == last:
                group[3] += 1
            else:
                if group is not None:
                    out.append(_jump(group, t_ns, xyyaw, i))
                group = [before, last, i, 1]
        elif plausible[i]:
            if group is not None:
                out.append(_jump(group, t_ns, xyyaw, i))
                group = None
            before, last = last, i
    if group is not None:
        out.append(_jump(group, t_ns, xyyaw, -1))
    return out


def _jump(group: list[int], t_ns: np.ndarray, xyyaw: np.ndarray, back: int) -> PoseJump:
    before, last, first, n = group
    if last < 0:
        return PoseJump(first, n, last, float("nan"), float("nan"), float("nan"), back)
    d = xyyaw[first] - xyyaw[last]
    turn = abs(math.remainder(float(d[2]), 2 * math.pi))
    offset = float("nan")
    if back >= 0:
        expected = xyyaw[last, :2].astype(np.float64)
        if before >= 0 and t_ns[last] > t_ns[before]:
            velocity = (xyyaw[last, :2] - xyyaw[before, :2]) / float(t_ns[last] - t_ns[before])
            expected = expected + velocity * float(t_ns[back] - t_ns[last])
        offset = float(np.hypot(*(xyyaw[back, :2] - expected)))
    return PoseJump(first, n, last, float(math.hypot(d[0], d[1])), turn, float((t_ns[first] - t_ns[last]) * 1e-9),
                    back, offset)


def describe_jumps(jumps: list[PoseJump], scan_ids: np.ndarray, t_ns: np.ndarray, max_speed: str = "") -> str:
    """The jumps in words, the largest (:attr:`PoseJump.size_m`) first, at most
    :data:`MAX_JUMPS_NAMED` of them, each where (scan id, seconds into the scans) and by
    how much: e.g. ``2 jumps: at scan 120 (12.0 s into the scans) 500.30 m and 1 deg in
    0.10 s, 14 scans until the pose came back; ...``; a relocalisation
    (:attr:`PoseJump.relocalised`) says that the map pose jumped and stayed, e.g. ``at
    scan 50 (5.0 s into the scans) the map pose jumped 3.00 m and stayed there (a
    relocalisation: ...)``."""
    if not jumps:
        return ""
    t = np.asarray(t_ns, dtype=np.int64)
    parts = []
    for j in sorted(jumps, key=lambda j: -(j.size_m if math.isfinite(j.size_m) else 0.0))[:MAX_JUMPS_NAMED]:
        n = f"{j.n_scans} scan{'s' if j.n_scans != 1 else ''}"
        into = (t[j.first] - t.min()) * 1e-9
        where = f"at scan {int(scan_ids[j.first])} ({into:.1f} s into the scans)"
        if j.relocalised:
            parts.append(
                f"{where} the map pose jumped {j.offset_m:.2f} m and stayed there (a relocalisation: walls seen "
                f"before and after it may be doubled), {n} dropped until the new pose fit the speed limit"
            )
            continue
        until = "until the pose came back" if j.back >= 0 else "to the end of the recording (the poses never came back)"
        by = (f"{j.distance_m:.2f} m and {math.degrees(j.turn_rad):.0f} deg in {j.dt_s:.2f} s"
              if math.isfinite(j.distance_m) else "from the first pose")
        parts.append(f"{where} {by}, {n} {until}")
    head = f"{len(jumps)} jump{'s' if len(jumps) != 1 else ''}"
    more = f"; and {len(jumps) - MAX_JUMPS_NAMED} more" if len(jumps) > MAX_JUMPS_NAMED else ""
    return f"{head}: {'; '.join(parts)}{more}" + (f"; faster than {max_speed}" if max_speed else "")

"""CARMEN log reader: ``FLASER`` and ``ROBOTLASER1`` lines with their corrected poses.

Line formats (CARMEN logger documentation, as in the Radish datasets)::

    FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
    ROBOTLASER1 laser_type start_angle fov angular_resolution max_range accuracy
        remission_mode n r1..rn n_remissions v1..vm laser_x laser_y laser_theta
        robot_x robot_y robot_theta tv rv forward_safety side_safety turn_axis
        ipc_timestamp ipc_hostname logger_timestamp

``x y theta`` (FLASER) and ``laser_x laser_y laser_theta`` (ROBOTLASER1) are the laser's
corrected pose in the map frame: the pose source of a CARMEN dataset (pose kind ``map``,
source ``embedded``).

FLASER beams span the field of view (default 180 degrees) starting at -fov/2. With an
even beam count (180, 360) the increment is fov/n; with an odd one (181, 361) both ends
are included and it is fov/(n-1): the convention of the Radish logs' readers.

No-return range. FLASER carries no range limits: a scanner logs "no return" as a fixed
value at the top of its range (SICK LMS 81.91 m, with error codes from 81.83 m; others
32.767 m, the largest signed 16-bit millimetre count, with codes a few millimetres
below; a log clipped to a round limit), repeated in many scans, while the farthest
genuine wall of a log is read a few times at most. Unless ``ingest.carmen_max_range_m``
is set, the no-return value is detected (:func:`no_return_range`): the log's largest
reading, when that exact value carries at least ``NO_RETURN_MIN_FRACTION`` of all
readings (and at least ``NO_RETURN_MIN_COUNT``); readings within ``NO_RETURN_BAND_M``
below it are the same code family and are dropped with it. Without such a value the
SICK LMS limit ``FALLBACK_MAX_RANGE_M`` applies. Returns at or beyond the limit, or at
or below zero, are dropped and counted.

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

Malformed lines (issue 24). A laser line is read only when it has exactly the fields its
counts imply: ``2 + n + 9`` for FLASER, ``24 + n + m`` for ROBOTLASER1 (n beams, m
remissions); a field too many or too few would shift every later field (a range read as
the pose, the pose as the stamp), so it is an ``InputError`` naming ``file:line``, the
counts and the layout, never parsed from shifted positions. Every numeric field must be a
number; the corrected pose, ROBOTLASER1's ``start_angle``, ``angular_resolution`` and
``maximum_range`` must be finite; ``ipc_timestamp`` must be finite, 0 or more and below
:data:`MAX_STAMP_S`. The error names the line and the field. Non-finite *ranges* are not
errors: they are "no return", dropped and counted like the others.
"""

from __future__ import annotations

import dataclasses
import gzip
import logging
import math
import re
import zlib
from pathlib import Path
from typing import Any, Iterator, Mapping, Sequence

import numpy as np

from floorscan.ingest import Recording, Scan, laser_scan_points, parse_number, parse_numbers, pose_stream_frame
from floorscan.core.io import InputError

log = logging.getLogger(__name__)

LASER_TYPES = ("FLASER", "ROBOTLASER1")
#: The field layout of each laser line, for error messages.
LAYOUTS = {
    "FLASER": "FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp",
    "ROBOTLASER1": (
        "ROBOTLASER1 laser_type start_angle fov angular_resolution maximum_range accuracy remission_mode "
        "n r1..rn m v1..vm laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv forward_safety "
        "side_safety turn_axis ipc_timestamp ipc_hostname logger_timestamp"
    ),
}
#: Fields of a FLASER line besides its n ranges.
FLASER_FIXED_FIELDS = 11
#: Fields of a ROBOTLASER1 line besides its n ranges and m remissions.
ROBOTLASER1_FIXED_FIELDS = 24
#: Largest ``ipc_timestamp`` read, seconds: its nanoseconds still fit in int64 (2261).
MAX_STAMP_S = 9.2e9


def _open_text(path: Path):
    with open(path, "rb") as f:
        magic = f.read(2)
    if magic == b"\x1f\x8b":
        return gzip.open(path, "rt", encoding="ascii", errors="replace")
    return open(path, "rt", encoding="ascii", errors="replace")


#: A log's largest reading is its no-return value when that exact value carries at
#: least this fraction of all its readings ...
NO_RETURN_MIN_FRACTION = 0.001
#: ... and at least this many readings.
NO_RETURN_MIN_COUNT = 10
#: Readings this close below the no-return value (metres) are dropped with it: a
#: scanner's no-return and error codes sit together at the top of its range.
NO_RETURN_BAND_M = 0.1
#: Drop limit of a log without a frequent largest reading: SICK LMS report no return
#: at 81.91 m or 80 m; no indoor wall is that far.
FALLBACK_MAX_RANGE_M = 80.0


@dataclasses.dataclass(frozen=True)
class NoReturn:
    """The range limit of a CARMEN log and how it was chosen.

    Attributes
    ----------
    max_range_m : float
        Returns at or beyond this are dropped, metres.
    how : str
        ``"detected"``, ``"fallback"`` (no frequent largest reading) or ``"configured"``.
    value_m : float
        The log's largest finite reading, metres (NaN for an empty log).
    count : int
        Readings exactly at ``value_m``.
    fraction : float
        ``count`` over all readings.
    n_dropped : int
        Readings at or beyond ``max_range_m``.
    """

    max_range_m: float
    how: str
    value_m: float
    count: int
    fraction: float
    n_dropped: int

    def note(self) -> str:
        """One line for the stage log: the limit and why."""
        head = f"largest reading {self.value_m:g} m carries {self.count} of the readings ({100 * self.fraction:.2f} %)"
        if self.how == "configured":
            why = f"ingest.carmen_max_range_m {self.max_range_m:g} m (configured; {head})"
        elif self.how == "detected":
            why = (
                f"no-return value detected: {head}, at least {100 * NO_RETURN_MIN_FRACTION:g} % and "
                f"{NO_RETURN_MIN_COUNT}; readings from {self.max_range_m:g} m ({NO_RETURN_BAND_M:g} m below it) "
                "on are no return"
            )
        else:
            why = (
                f"no frequent largest reading ({head}, under {100 * NO_RETURN_MIN_FRACTION:g} % or "
                f"{NO_RETURN_MIN_COUNT}): the SICK LMS limit {self.max_range_m:g} m applies"
            )
        return f"max range {self.max_range_m:g} m: {why}; {self.n_dropped} readings dropped at or beyond it"


def no_return_range(ranges: Sequence[np.ndarray] | np.ndarray, max_range_m: float | None = None) -> NoReturn:
    """The range at or beyond which a log's readings are "no return".

    Parameters
    ----------
    ranges : sequence of (B,) float ndarray, or (R,) float ndarray
        The range readings of the log's laser lines, metres.
    max_range_m : float, optional
        A limit set by the user (``ingest.carmen_max_range_m``): used as it is.

    Returns
    -------
    NoReturn
        The limit: ``max_range_m`` when given; else the largest reading minus
        ``NO_RETURN_BAND_M`` when that exact value carries at least
        ``NO_RETURN_MIN_FRACTION`` of the readings and ``NO_RETURN_MIN_COUNT`` of them;
        else ``FALLBACK_MAX_RANGE_M``.
    """
    r = np.concatenate([np.asarray(a, dtype=np.float64).ravel() for a in ranges]) if len(ranges) else np.zeros(0)
    finite = r[np.isfinite(r)]
    total = max(int(r.size), 1)
    value = float(finite.max()) if finite.size else math.nan
    count = int(np.count_nonzero(finite == value)) if finite.size else 0
    fraction = count / total
    if max_range_m is not None:
        limit, how = float(max_range_m), "configured"
    elif count >= NO_RETURN_MIN_COUNT and fraction >= NO_RETURN_MIN_FRACTION:
        limit, how = round(value - NO_RETURN_BAND_M, 6), "detected"
    else:
        limit, how = FALLBACK_MAX_RANGE_M, "fallback"
    return NoReturn(limit, how, value, count, fraction, int(np.count_nonzero(finite >= limit)))


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
        Some stamps are 0 but not all (a corrupt log; :func:`open_carmen` reports it as
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


def parse_carmen(
    path: str | Path,
    max_range_m: float | None = None,
    fov_rad: float = math.pi,
) -> tuple[list[dict], dict[str, int]]:
    """Parse the laser lines of a CARMEN log.

    Parameters
    ----------
    path : path
        ``.log`` or ``.log.gz`` file.
    max_range_m : float, optional
        Returns at or beyond this range (metres) are "no return" and dropped; None:
        detected from the log's readings (:func:`no_return_range`).
    fov_rad : float
        FLASER field of view, radians.

    Returns
    -------
    scans : list of dict
        Per laser line, in file order: ``t_s`` (float, seconds, ipc timestamp),
        ``points`` ((N, 3) float32, scanner frame, metres), ``n_dropped``,
        ``pose`` ((3,) x, y, theta of the laser in the map frame), ``line`` (1-based).
    counts : dict
        Lines seen per message type.

    Raises
    ------
    InputError
        Unreadable or truncated file; a malformed laser line: a field count other than
        its layout's, a field that is not a number, a non-finite pose, angle or maximum
        range, a stamp not finite and in [0, ``MAX_STAMP_S``) (names ``file:line``, the
        field and the layout); or no laser lines at all.
    """
    scans, counts, _ = _parse(Path(path), max_range_m, fov_rad)
    return scans, counts


def _parse(path: Path, max_range_m: float | None, fov_rad: float) -> tuple[list[dict], dict[str, int], NoReturn]:
    lines: list[dict] = []
    counts: dict[str, int] = {}
    try:
        with _open_text(path) as f:
            for lineno, line in enumerate(f, 1):
                tok = line.split()
                if not tok or tok[0].startswith("#"):
                    continue
                kind = tok[0]
                counts[kind] = counts.get(kind, 0) + 1
                if kind not in LASER_TYPES:
                    continue
                try:
                    lines.append(_parse_laser_line(kind, tok, fov_rad, lineno))
                except _Malformed as e:
                    raise InputError(f"{path}:{lineno}: malformed {kind} line: {e} ('{LAYOUTS[kind]}')") from None
    except (EOFError, OSError, zlib.error) as e:
        raise InputError(f"{path}: cannot read the log, truncated or corrupt ({e})") from None
    if not lines:
        raise InputError(
            f"{path}: no laser lines; expected FLASER or ROBOTLASER1 lines "
            f"(message types found: {dict(sorted(counts.items())) or 'none'})"
        )
    limit = no_return_range([s["ranges"] for s in lines], max_range_m)
    scans = []
    for s in lines:
        ranges = s.pop("ranges")
        rmax = min(limit.max_range_m, s.pop("rmax"))
        # at or beyond the limit: no return (laser_scan_points keeps [min, max) only)
        s["points"], s["n_dropped"] = laser_scan_points(ranges, s.pop("start"), s.pop("inc"), 1e-9, rmax)
        scans.append(s)
    return scans, counts, limit


_INTEGER = re.compile(r"\+?[0-9]+")


class _Malformed(ValueError):
    """A laser line that does not follow its layout (the message says how)."""


def _number(tok: list[str], i: int, name: str) -> float:
    v = parse_number(tok[i])
    if v is None:
        raise _Malformed(f"field {i + 1} ({name}) is {tok[i]!r}; expected a number")
    return v


def _finite(tok: list[str], i: int, name: str) -> float:
    v = _number(tok, i, name)
    if not math.isfinite(v):
        raise _Malformed(f"field {i + 1} ({name}) is {tok[i]}; expected a finite number")
    return v


def _count(tok: list[str], i: int, name: str, minimum: int) -> int:
    t = tok[i]
    if not _INTEGER.fullmatch(t) or int(t) < minimum:
        raise _Malformed(f"field {i + 1} ({name}) is {t!r}; expected an integer >= {minimum}")
    return int(t)


def _numbers(tok: list[str], a: int, b: int, what: str) -> np.ndarray:
    """Fields ``a:b`` as float64, any value (NaN and inf included)."""
    values = parse_numbers(tok[a:b])
    if values is None:  # name the field (one by one: slow, but only on a bad line)
        values = np.array([_number(tok, i, f"{what} {i - a + 1}") for i in range(a, b)], dtype=np.float64)
    return values


def _stamp(tok: list[str], i: int) -> float:
    t = _number(tok, i, "ipc_timestamp")
    if not 0.0 <= t < MAX_STAMP_S:  # NaN fails too
        raise _Malformed(
            f"field {i + 1} (ipc_timestamp) is {tok[i]}; expected a finite time in seconds, "
            f"0 or more and below {MAX_STAMP_S:g}"
        )
    return t


def _parse_laser_line(kind: str, tok: list[str], fov_rad: float, lineno: int) -> dict:
    """One laser line's fields, read only when their count is exactly the layout's.

    Raises
    ------
    _Malformed
        A field count other than the layout's (FLASER ``2 + n + 9``, ROBOTLASER1
        ``24 + n + m``), a non-numeric field, a non-finite pose, angle or maximum
        range, a stamp that is not finite and >= 0.
    """
    rmax = math.inf
    if kind == "FLASER":
        if len(tok) < 2:
            raise _Malformed(f"{len(tok)} fields; expected 2 + n + 9")
        n = _count(tok, 1, "n, the beam count", 1)
        need = n + FLASER_FIXED_FIELDS
        if len(tok) != need:
            raise _Malformed(f"{len(tok)} fields for n = {n} beams; expected 2 + n + 9 = {need}")
        ranges = _numbers(tok, 2, 2 + n, "range")
        k = 2 + n
        names = ("x", "y", "theta")
        inc = fov_rad / (n - 1) if n % 2 == 1 and n > 1 else fov_rad / n
        start = -fov_rad / 2.0
        others = ("odom_x", "odom_y", "odom_theta")
        stamp_at = k + 6
    else:
        if len(tok) < 9:
            raise _Malformed(f"{len(tok)} fields; expected 24 + n + m (n at field 9)")
        n = _count(tok, 8, "n, the beam count", 1)
        if len(tok) < 10 + n:
            raise _Malformed(
                f"{len(tok)} fields for n = {n} beams; expected 24 + n + m, at least {ROBOTLASER1_FIXED_FIELDS + n}"
            )
        m = _count(tok, 9 + n, "m, the remission count", 0)
        need = ROBOTLASER1_FIXED_FIELDS + n + m
        if len(tok) != need:
            raise _Malformed(
                f"{len(tok)} fields for n = {n} beams and m = {m} remissions; expected 24 + n + m = {need}"
            )
        _number(tok, 1, "laser_type")
        start = _finite(tok, 2, "start_angle")
        _number(tok, 3, "fov")
        inc = _finite(tok, 4, "angular_resolution")
        line_rmax = _finite(tok, 5, "maximum_range")
        _number(tok, 6, "accuracy")
        _number(tok, 7, "remission_mode")
        ranges = _numbers(tok, 9, 9 + n, "range")
        _numbers(tok, 10 + n, 10 + n + m, "remission")
        k = 10 + n + m
        names = ("laser_x", "laser_y", "laser_theta")
        others = ("robot_x", "robot_y", "robot_theta", "tv", "rv", "forward_safety", "side_safety", "turn_axis")
        stamp_at = k + 11
        if line_rmax > 0:
            rmax = line_rmax
    pose = np.array([_finite(tok, k + j, name) for j, name in enumerate(names)])
    for j, name in enumerate(others):
        _number(tok, k + 3 + j, name)
    t_s = _stamp(tok, stamp_at)
    _number(tok, stamp_at + 2, "logger_timestamp")
    return {
        "t_s": t_s, "ranges": ranges, "start": start, "inc": inc, "rmax": rmax, "pose": pose, "line": lineno, "kind": kind,
    }


def open_carmen(path: Path, dataset: Mapping[str, Any], cfg: Mapping[str, Any]) -> Recording:
    """Open a CARMEN log as a :class:`~floorscan.ingest.Recording`.

    The pose stream holds the corrected laser pose of every laser line (z = 0; the
    ingest writer adds the dataset's ``sensor_height_m``). The range limit
    (``ingest.carmen_max_range_m``, detected when null) and the stamp class are
    chosen as the module docstring says, noted and stored in ``Recording.detected``.

    Raises
    ------
    InputError
        See :func:`parse_carmen`; also zero stamps among non-zero ones (a corrupt log).
    """
    cfg_max = cfg.get("carmen_max_range_m")
    scans, counts, limit = _parse(
        path,
        max_range_m=None if cfg_max is None else float(cfg_max),
        fov_rad=float(cfg.get("carmen_fov_rad", math.pi)),
    )
    notes = [f"message types: {dict(sorted(counts.items()))}", limit.note()]
    t = np.array([s["t_s"] for s in scans])
    try:
        stamps, n_rep = classify_stamps(t)
    except ValueError:
        bad = [s["line"] for s in scans if s["t_s"] == 0][:5]
        raise InputError(
            f"{path}: laser lines with timestamp 0 among stamped ones (lines {bad}); expected all stamped or all 0"
        ) from None
    n = len(scans)
    if stamps == "made_up":
        period = float(cfg.get("missing_time_period_s", 0.1))
        why = "every laser timestamp is 0" if np.all(t == 0) else (
            f"{n_rep} of {n} laser lines repeat an earlier timestamp ({len(np.unique(t))} distinct values), "
            "more than half"
        )
        t0_ns = int(round(float(t[0]) * 1e9))
        t_ns = t0_ns + np.round(np.arange(n) * period * 1e9).astype(np.int64)
        notes.append(
            f"stamps made up: {why}; scans in line order stamped at index x {period} s "
            "(ingest.missing_time_period_s)"
        )
    else:
        t_ns = np.round(t * 1e9).astype(np.int64)
        back = np.flatnonzero(np.diff(t_ns) < 0)
        if back.size:
            # Each line carries its own corrected pose, so order by time without losing one.
            lines = [scans[i + 1]["line"] for i in back[:5]]
            notes.append(
                f"{back.size} laser lines earlier than the line before them (lines {lines}...): "
                "scans sorted by ipc_timestamp"
            )
            order = np.argsort(t_ns, kind="stable")
            scans = [scans[i] for i in order]
            t_ns = t_ns[order]
        if stamps == "spread":
            runs = np.diff(np.r_[0, np.flatnonzero(np.diff(t_ns)) + 1, n])
            t_ns = spread_stamps(t_ns)
            notes.append(
                f"stamps spread: {n_rep} of {n} laser lines repeat the stamp before them "
                f"({int(np.count_nonzero(runs > 1))} runs, the longest {int(runs.max())} lines); "
                "each run spread evenly up to the next stamp, in line order"
            )
    poses = np.array([s["pose"] for s in scans])
    stream = pose_stream_frame(t_ns, poses[:, 0], poses[:, 1], np.zeros(len(t_ns)), poses[:, 2])
    kinds = sorted({s["kind"] for s in scans})
    detected = {
        "scan_topic": ", ".join(kinds),
        "pose_source": f"embedded (corrected pose on each {'/'.join(kinds)} line)",
        "pose_kind": "map",
        "stamps": stamps,
        "max_range_m": f"{limit.max_range_m:.10g}",
    }

    def _scans() -> Iterator[Scan]:
        for ti, s in zip(t_ns, scans):
            yield Scan(int(ti), "laser", s["points"], s["n_dropped"])

    return Recording(scans=_scans(), pose_stream=stream, source=str(path), notes=notes, detected=detected)

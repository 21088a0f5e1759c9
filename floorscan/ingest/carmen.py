"""CARMEN log reader: ``FLASER`` and ``ROBOTLASER1`` lines with their corrected poses.

``x y theta`` (FLASER) and ``laser_x laser_y laser_theta`` (ROBOTLASER1) are the laser's
corrected pose in the map frame: the pose source of a CARMEN dataset (pose kind ``map``,
source ``embedded``).

Each line is read and checked against its layout by :mod:`floorscan.ingest.carmen_lines`
(a malformed line is an ``InputError`` naming ``file:line`` and the field). Returns at or
beyond the log's no-return range (:mod:`floorscan.ingest.carmen_ranges`: configured as
``ingest.carmen_max_range_m``, else detected from the readings), or at or below zero,
are dropped and counted. The stamps are recorded, spread or made up
(:mod:`floorscan.ingest.carmen_stamps`); the few lines that step back in time are
sorted by stamp (a stable sort; each line carries its own pose, so nothing is lost),
but never a line more than :data:`~floorscan.ingest.recording.MAX_STEP_BACK_S` back
(an error naming it), and a file holding several logs (two recordings concatenated:
:func:`~floorscan.ingest.carmen_stamps.log_starts`) is refused naming the lines where
each starts and their scans, never merged by stamp into one trajectory.
A log whose stamps are junk (more than half out of range or out of time order) keeps
its line order with made-up stamps, said in a warning (``stamps made up: ...``) and in
``detected["stamps_reason"]``; a few stamps out of range in a good log are an error
naming the first line. Made-up stamps are the pose stream's too (each line's own pose),
so the poses match the scans one to one.

A laser line whose ROBOTLASER1 geometry is broken
(:func:`floorscan.ingest.carmen_lines.robotlaser_geometry_problem`) or without a valid
return is skipped and counted (``lost_bad_frames``, ``lost_no_points``; its pose stays
in the pose stream), the first named in a note; more than half of the lines broken, or
none usable, is an ``InputError`` (:class:`~floorscan.ingest.points.ScanLosses`). Lines
of a type CARMEN does not define (:data:`~floorscan.ingest.carmen_lines.CARMEN_TYPES`)
are counted (``lost_unknown_lines``) and the first few named in a note.

Units: a log whose ranges are not metres (millimetres, centimetres) or whose laser
headings are not radians (degrees) is refused naming the field
(:mod:`floorscan.ingest.units`); the ranges are checked before the no-return limit,
which would drop every reading of a log in millimetres.
"""

from __future__ import annotations

import logging
import math
import zlib
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np

from floorscan.core.config import stage_params
from floorscan.core.io import InputError
from floorscan.core.messages import quoted
from floorscan.ingest.carmen_lines import (
    CARMEN_TYPES, LASER_TYPES, LAYOUTS, MalformedLine, parse_laser_line, stamp_problem,
)
from floorscan.ingest.carmen_ranges import NoReturn, no_return_range
from floorscan.ingest.carmen_stamps import (
    StampClass, StampsOutOfRange, log_starts, made_up_stamps_ns, spread_stamps, stamp_class,
)
from floorscan.ingest.params import IngestParams
from floorscan.ingest.points import FrameError, ScanLosses, laser_scan_points, no_return_reason
from floorscan.ingest.recording import MAX_STEP_BACK_S, Recording, Scan, pose_stream_frame
from floorscan.ingest.text import open_text
from floorscan.ingest.units import MedianReturn, range_units_problem, yaw_units_problem

log = logging.getLogger(__name__)


def _found_types(counts: dict[str, int], most: int = 10) -> str:
    """The line types of a log that holds no laser line, for its error: at most ``most``,
    each cut to 20 characters; a file of binary data is said to be one."""
    if any(not k.isprintable() or "\ufffd" in k for k in counts):
        return "the file is not a text log: its bytes are binary (a ROS bag, a PCD file?); set format to what it is, or leave format unset for ingest to detect it"
    top = sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))
    shown = ", ".join(f"{k[:20]}{'...' if len(k) > 20 else ''} ({n})" for k, n in top[:most])
    more = f" and {len(top) - most} more" if len(top) > most else ""
    return f"message types found: {shown or 'none'}{more}"


def parse_carmen(
    path: str | Path,
    max_range_m: float | None = None,
    fov_rad: float | None = None,
) -> tuple[list[dict], dict[str, int]]:
    """Parse the laser lines of a CARMEN log.

    Parameters
    ----------
    path : path
        ``.log`` or ``.log.gz`` file.
    max_range_m : float, optional
        Returns at or beyond this range (metres) are "no return" and dropped; None:
        detected from the log's readings (:func:`no_return_range`).
    fov_rad : float, optional
        FLASER field of view, radians; None: ``ingest.carmen_fov_rad``'s default.

    Returns
    -------
    scans : list of dict
        Per laser line, in file order: ``t_s`` (float, seconds, ipc timestamp as
        written: out of range when the log's stamps are made up; ``stamp_field`` and
        ``stamp_text`` its field, 1-based, and text), ``points`` ((N, 3) float32,
        scanner frame, metres), ``n_dropped``, ``pose`` ((3,) x, y, theta of the laser
        in the map frame), ``line`` (1-based), ``ordinal`` (0-based, among the laser
        lines in file order: the scan's ``source_ordinal``), ``kind``, ``problem``
        (None, or what is wrong with a ROBOTLASER1 line's beam geometry: ingest skips
        its scan).
    counts : dict
        Lines seen per message type.

    Raises
    ------
    InputError
        Unreadable or truncated file; a malformed laser line: a field count other than
        its layout's, a field that is not a number, a non-finite pose, angle or maximum
        range (names ``file:line``, the field and the layout); a stamp out of range in a
        log whose stamps are not junk (:mod:`floorscan.ingest.carmen_stamps`: names the
        first such line); zero stamps among non-zero ones; no laser lines at all; or
        ranges that are not metres (:func:`floorscan.ingest.units.range_units_problem`).
    """
    fov = IngestParams().carmen_fov_rad if fov_rad is None else fov_rad
    scans, counts, _, _, _ = _parse(Path(path), max_range_m, fov)
    return scans, counts


def _parse(
    path: Path, max_range_m: float | None, fov_rad: float
) -> tuple[list[dict], dict[str, int], NoReturn, list[tuple[int, str]], StampClass]:
    """The laser lines (as :func:`parse_carmen`), the count of each line type, the range
    limit, the first few lines of an unknown type (line number, type), and the class of
    the stamps (:func:`_stamp_class`)."""
    lines: list[dict] = []
    counts: dict[str, int] = {}
    unknown: list[tuple[int, str]] = []
    try:
        # plain or gzip, a byte-order mark dropped, trailing garbage after the gzip data
        # left out with a warning, as ``gzip -d`` does
        with open_text(path) as f:
            for lineno, line in enumerate(f, 1):
                tok = line.split()
                if not tok or tok[0].startswith("#"):
                    continue
                kind = tok[0]
                counts[kind] = counts.get(kind, 0) + 1
                if kind not in LASER_TYPES:
                    if kind not in CARMEN_TYPES and len(unknown) < 5:
                        unknown.append((lineno, kind))
                    continue
                try:
                    lines.append(parse_laser_line(kind, tok, fov_rad, lineno))
                except MalformedLine as e:
                    raise InputError(f"{path}:{lineno}: malformed {kind} line: {e} ('{LAYOUTS[kind]}')") from None
    except (EOFError, OSError, zlib.error) as e:
        raise InputError(f"{path}: cannot read the log, truncated or corrupt ({e})") from None
    if not lines:
        raise InputError(f"{path}: no laser lines; expected FLASER or ROBOTLASER1 lines ({_found_types(counts)})")
    stamps = _stamp_class(path, lines)
    limit = no_return_range([s["ranges"] for s in lines], max_range_m)
    _check_range_units(path, lines, limit)
    scans = []
    for ordinal, s in enumerate(lines):
        s["ordinal"] = ordinal
        ranges = s.pop("ranges")
        rmax = min(limit.max_range_m, s.pop("rmax"))
        # at or beyond the limit: no return (laser_scan_points keeps [min, max) only)
        s["points"], s["n_dropped"] = laser_scan_points(ranges, s.pop("start"), s.pop("inc"), 1e-9, rmax)
        if not len(s["points"]):
            s["no_return"] = no_return_reason(ranges, 1e-9, rmax)
        scans.append(s)
    return scans, counts, limit, unknown, stamps


def _check_range_units(path: Path, lines: list[dict], limit: NoReturn) -> None:
    """Refuse a log whose ranges are not metres (:func:`floorscan.ingest.units.range_units_problem`),
    before the no-return limit would drop every reading of a log in millimetres: the
    median return of the readings above zero (and below a detected or configured limit).

    Raises
    ------
    InputError
        Naming the file, the lines' range field and the median return.
    """
    cap = math.inf if limit.how == "fallback" else limit.max_range_m
    median = MedianReturn()
    for s in lines:
        r = np.asarray(s["ranges"], dtype=np.float64)
        with np.errstate(invalid="ignore"):
            median.add_distances(r[(r > 0) & (r < cap)])
    problem = range_units_problem(median.value, median.n_scans)
    if problem:
        kinds = "/".join(sorted({s["kind"] for s in lines}))
        raise InputError(f"{path}: the ranges r1..rn of the {kinds} lines {problem}")


def _check_yaw_units(path: Path, scans: list[dict], t_ns: np.ndarray) -> None:
    """Refuse a log whose laser headings are not radians (:func:`floorscan.ingest.units.yaw_units_problem`).

    Raises
    ------
    InputError
        Naming the file and the lines' heading field.
    """
    problem = yaw_units_problem(t_ns, np.array([s["pose"][2] for s in scans], dtype=np.float64))
    if problem:
        kinds = sorted({s["kind"] for s in scans})
        field = " and ".join(f"{'theta' if k == 'FLASER' else 'laser_theta'} of the {k} lines" for k in kinds)
        raise InputError(f"{path}: the laser heading ({field}) {problem}")


def _stamp_class(path: Path, lines: list[dict]) -> StampClass:
    """The class of the laser lines' stamps (:func:`~floorscan.ingest.carmen_stamps.stamp_class`).

    Raises
    ------
    InputError
        A few stamps out of range (names the first line, its field and the layout, and
        how many), or zero stamps among non-zero ones (names the lines).
    """
    t = np.array([s["t_s"] for s in lines], dtype=np.float64)
    starts = log_starts(t)
    if starts.size:
        raise InputError(_several_logs(path, lines, t, starts))
    try:
        return stamp_class(t)
    except StampsOutOfRange as e:
        s = lines[e.index]
        raise InputError(
            f"{path}:{s['line']}: malformed {s['kind']} line: {stamp_problem(s['stamp_field'], s['stamp_text'])} "
            f"('{LAYOUTS[s['kind']]}'); {e.n_bad} of the {e.n} laser stamps are out of range, so the line is "
            "broken (made-up stamps only when more than half of them are unusable)"
        ) from None
    except ValueError:
        bad = [s["line"] for s in lines if s["t_s"] == 0][:5]
        raise InputError(
            f"{path}: laser lines with timestamp 0 among stamped ones (lines {bad}); expected all stamped or all 0"
        ) from None


def _several_logs(path: Path, lines: list[dict], t: np.ndarray, starts: np.ndarray) -> str:
    """The message of a file holding several logs (:func:`~floorscan.ingest.carmen_stamps.log_starts`):
    where each starts (line numbers), how far back its stamps step, and each part's scans."""
    bounds = np.r_[0, starts, len(lines)]
    parts = ", ".join(
        f"lines {lines[a]['line']}-{lines[b - 1]['line']} hold {b - a} scans" for a, b in zip(bounds[:-1], bounds[1:])
    )
    steps = "; ".join(
        f"at line {lines[k]['line']} the laser stamps step back {t[k - 1] - t[k]:.1f} s "
        f"(from {t[k - 1]:.3f} s on line {lines[k - 1]['line']} to {t[k]:.3f} s)"
        for k in starts
    )
    at = ", ".join(str(lines[k]["line"]) for k in starts)
    return (
        f"{path}: holds {len(starts) + 1} logs, not one: {steps}, and stay back, so another log starts there; "
        f"{parts}. Sorting them by stamp would merge several recordings into one trajectory; expected one recording "
        f"per file: split the file before line {at} and give each part as its own dataset"
    )


def open_carmen(path: Path, dataset: Mapping[str, Any], cfg: "IngestParams | Mapping[str, Any] | None") -> Recording:
    """Open a CARMEN log as a :class:`~floorscan.ingest.recording.Recording`.

    The pose stream holds the corrected laser pose of every laser line (z = 0; the
    ingest writer adds the dataset's ``sensor_height_m``). The range limit
    (``ingest.carmen_max_range_m``, detected when null) and the stamp class are
    chosen as :mod:`floorscan.ingest.carmen_ranges` and
    :mod:`floorscan.ingest.carmen_stamps` say, noted and stored in ``Recording.detected``.

    Parameters
    ----------
    path : Path
        The ``.log`` or ``.log.gz`` file.
    dataset : mapping
        The dataset's config entry (``range_min_m``, ``range_max_m``, ...).
    cfg : IngestParams, mapping or None
        The ``ingest`` config section (``carmen_max_range_m``, ``carmen_fov_rad``).

    Returns
    -------
    Recording
        Its scans are read lazily, as ``Recording.scans`` is iterated.

    Raises
    ------
    InputError
        See :func:`parse_carmen`; also more than half of the laser lines with broken
        geometry, or no line with a valid return (names the first line and field), or
        laser headings that are not radians (:func:`floorscan.ingest.units.yaw_units_problem`).
    """
    params = stage_params(IngestParams, cfg)
    cfg_max = params.carmen_max_range_m
    scans, counts, limit, unknown, cls = _parse(
        path,
        max_range_m=None if cfg_max is None else float(cfg_max),
        fov_rad=float(params.carmen_fov_rad),
    )
    notes = [f"message types: {dict(sorted(counts.items()))}", limit.note()]
    n_unknown = sum(k for kind, k in counts.items() if kind not in CARMEN_TYPES)
    if n_unknown:
        named = ", ".join(f"line {i} {quoted(kind, 40)}" for i, kind in unknown)
        line = (
            f"{path}: {n_unknown} lines of a message type CARMEN does not define were not read "
            f"(lost_unknown_lines; {named}{', ...' if n_unknown > len(unknown) else ''}); expected "
            "FLASER or ROBOTLASER1 for scans"
        )
        notes.append(line)
        log.warning("%s", line)
    t = np.array([s["t_s"] for s in scans], dtype=np.float64)
    stamps, n_rep = cls.kind, cls.n_repeated
    n = len(scans)
    if stamps == "made_up":
        period = float(params.missing_time_period_s)
        t_ns = made_up_stamps_ns(t, period)
        line = (
            f"{path}: stamps made up: {cls.why}; scans in line order stamped at index x {period} s "
            f"(ingest.missing_time_period_s) from {'the first stamp' if t_ns[0] else '0 s'}"
        )
        notes.append(line)
        log.warning("%s", line)
    else:
        t_ns = np.round(t * 1e9).astype(np.int64)
        far = np.flatnonzero(np.diff(t_ns) < -MAX_STEP_BACK_S * 1e9)
        if far.size:
            prev, s = scans[far[0]], scans[far[0] + 1]
            raise InputError(
                f"{path}:{s['line']}: {s['kind']} line stamped {(t_ns[far[0]] - t_ns[far[0] + 1]) * 1e-9:.1f} s earlier "
                f"than the laser line before it (line {prev['line']}, {t[far[0]]:.3f} s); lines a little out of order "
                f"(up to {MAX_STEP_BACK_S:g} s back) are sorted by stamp, one this far back is a broken ipc_timestamp or a "
                "second recording: fix the stamp, or split the file where the other recording starts"
            )
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
    _check_yaw_units(path, scans, t_ns)
    poses = np.array([s["pose"] for s in scans])
    stream = pose_stream_frame(t_ns, poses[:, 0], poses[:, 1], np.zeros(len(t_ns)), poses[:, 2])
    kinds = sorted({s["kind"] for s in scans})
    detected = {
        "scan_topic": ", ".join(kinds),
        "pose_source": f"embedded (corrected pose on each {'/'.join(kinds)} line)",
        "pose_kind": "map",
        "stamps": stamps,
        **({"stamps_reason": cls.why} if cls.why else {}),
        "max_range_m": f"{limit.max_range_m:.10g}",
    }
    if n_unknown:
        detected["lost_unknown_lines"] = str(n_unknown)
    keep = _usable_lines(path, scans, detected, notes)

    def _scans() -> Iterator[Scan]:
        for ti, s, ok in zip(t_ns, scans, keep):
            if ok:
                yield Scan(int(ti), "laser", s["points"], s["n_dropped"], s["ordinal"])

    return Recording(scans=_scans(), pose_stream=stream, source=str(path), notes=notes, detected=detected)


def _usable_lines(path: Path, scans: list[dict], detected: dict, notes: list[str]) -> list[bool]:
    """Which laser lines give a scan: not broken (ROBOTLASER1 geometry) and with a valid
    return. The losses go into ``detected`` and ``notes``; their ordinals in
    ``skipped_frames`` are the lines' in file order.

    Raises
    ------
    InputError
        More than half of the lines broken, or none usable (names the first).
    """
    losses = ScanLosses("laser lines", n_read=len(scans))
    for s in sorted(scans, key=lambda s: s["ordinal"]):  # the first in the file named first
        where = f"{path}:{s['line']}"
        if s["problem"]:
            losses.skip(s["ordinal"], FrameError(where, f"{s['kind']} line {s['problem']}"))
        elif not len(s["points"]):
            what = f"{s['kind']} line has no valid return: {s['no_return']}"
            losses.skip(s["ordinal"], FrameError(where, what, loss="no_points"))
    losses.report(detected, notes, str(path))
    skipped = set(losses.skipped)
    return [s["ordinal"] not in skipped for s in scans]

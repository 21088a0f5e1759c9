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
sorted by stamp (a stable sort; each line carries its own pose, so nothing is lost).
"""

from __future__ import annotations

import gzip
import zlib
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np

from floorscan.core.io import InputError
from floorscan.ingest.carmen_lines import LASER_TYPES, LAYOUTS, MalformedLine, parse_laser_line
from floorscan.ingest.carmen_ranges import NoReturn, no_return_range
from floorscan.ingest.carmen_stamps import classify_stamps, spread_stamps
from floorscan.ingest.params import IngestParams
from floorscan.ingest.points import laser_scan_points
from floorscan.ingest.recording import Recording, Scan, pose_stream_frame


def _open_text(path: Path):
    """The log as text; a UTF-8 byte-order mark before its first line is dropped (an
    editor's: read as ASCII it made the first line's type unknown, and its scan was lost)."""
    with open(path, "rb") as f:
        magic = f.read(2)
    if magic == b"\x1f\x8b":
        return gzip.open(path, "rt", encoding="utf-8-sig", errors="replace")
    return open(path, "rt", encoding="utf-8-sig", errors="replace")


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
    fov = IngestParams().carmen_fov_rad if fov_rad is None else fov_rad
    scans, counts, _ = _parse(Path(path), max_range_m, fov)
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
                    lines.append(parse_laser_line(kind, tok, fov_rad, lineno))
                except MalformedLine as e:
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


def open_carmen(path: Path, dataset: Mapping[str, Any], cfg: "IngestParams | Mapping[str, Any] | None") -> Recording:
    """Open a CARMEN log as a :class:`~floorscan.ingest.recording.Recording`.

    The pose stream holds the corrected laser pose of every laser line (z = 0; the
    ingest writer adds the dataset's ``sensor_height_m``). The range limit
    (``ingest.carmen_max_range_m``, detected when null) and the stamp class are
    chosen as :mod:`floorscan.ingest.carmen_ranges` and
    :mod:`floorscan.ingest.carmen_stamps` say, noted and stored in ``Recording.detected``.

    Raises
    ------
    InputError
        See :func:`parse_carmen`; also zero stamps among non-zero ones (a corrupt log).
    """
    params = IngestParams.from_config(cfg)
    cfg_max = params.carmen_max_range_m
    scans, counts, limit = _parse(
        path,
        max_range_m=None if cfg_max is None else float(cfg_max),
        fov_rad=float(params.carmen_fov_rad),
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
        period = float(params.missing_time_period_s)
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

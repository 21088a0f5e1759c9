"""CARMEN log reader: ``FLASER`` and ``ROBOTLASER1`` lines with their corrected poses.

Line formats (CARMEN logger documentation, as in the Radish datasets)::

    FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp ipc_hostname logger_timestamp
    ROBOTLASER1 laser_type start_angle fov angular_resolution max_range accuracy
        remission_mode n r1..rn n_remissions v1..vm laser_x laser_y laser_theta
        robot_x robot_y robot_theta tv rv forward_safety side_safety turn_axis
        ipc_timestamp ipc_hostname logger_timestamp

``x y theta`` (FLASER) and ``laser_x laser_y laser_theta`` (ROBOTLASER1) are the laser's
corrected pose in the map frame: the pose source of a CARMEN dataset.

FLASER beams span the field of view (default 180 degrees) starting at -fov/2. With an
even beam count (180, 360) the increment is fov/n; with an odd one (181, 361) both ends
are included and it is fov/(n-1): the convention of the Radish logs' readers.
FLASER carries no range limits: returns at or beyond ``carmen_max_range_m`` (SICK
scanners log 81.91 m or similar for "no return") or at or below zero are dropped.

Some logs (e.g. Orebro) have every timestamp zero. Then scans are stamped at their
index times ``missing_time_period_s`` and the log says so; a log with some but not all
stamps missing, or two laser lines with the same stamp, is rejected. Lines out of time
order (Intel has 4, up to 0.9 s back) are sorted by stamp, and the log counts them:
each line carries its own pose, so nothing is lost.
"""

from __future__ import annotations

import gzip
import logging
import math
import zlib
from pathlib import Path
from typing import Any, Iterator, Mapping

import numpy as np

from floorscan.ingest import Recording, Scan, laser_scan_points, pose_stream_frame
from floorscan.io import InputError

log = logging.getLogger(__name__)

LASER_TYPES = ("FLASER", "ROBOTLASER1")


def _open_text(path: Path):
    with open(path, "rb") as f:
        magic = f.read(2)
    if magic == b"\x1f\x8b":
        return gzip.open(path, "rt", encoding="ascii", errors="replace")
    return open(path, "rt", encoding="ascii", errors="replace")


def parse_carmen(
    path: str | Path,
    max_range_m: float = 50.0,
    fov_rad: float = math.pi,
) -> tuple[list[dict], dict[str, int]]:
    """Parse the laser lines of a CARMEN log.

    Parameters
    ----------
    path : path
        ``.log`` or ``.log.gz`` file.
    max_range_m : float
        Returns at or beyond this range (metres) are "no return" and dropped.
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
        Unreadable or truncated file, a malformed laser line (names the line), or no
        laser lines at all.
    """
    path = Path(path)
    scans: list[dict] = []
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
                    scans.append(_parse_laser_line(kind, tok, max_range_m, fov_rad, lineno))
                except (ValueError, IndexError) as e:
                    raise InputError(
                        f"{path}:{lineno}: malformed {kind} line ({e}); expected "
                        + ("'FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp host logger_timestamp'"
                           if kind == "FLASER" else "the ROBOTLASER1 field layout")
                    ) from None
    except (EOFError, OSError, zlib.error) as e:
        raise InputError(f"{path}: cannot read the log, truncated or corrupt ({e})") from None
    if not scans:
        raise InputError(
            f"{path}: no laser lines; expected FLASER or ROBOTLASER1 lines "
            f"(message types found: {dict(sorted(counts.items())) or 'none'})"
        )
    return scans, counts


def _parse_laser_line(kind, tok, max_range_m, fov_rad, lineno) -> dict:
    if kind == "FLASER":
        n = int(tok[1])
        if n <= 0:
            raise ValueError(f"beam count {n}")
        need = 2 + n + 6 + 3
        if len(tok) < need:
            raise ValueError(f"{len(tok)} fields, {need} needed for {n} beams")
        ranges = np.array(tok[2 : 2 + n], dtype=np.float64)
        pose = np.array(tok[2 + n : 5 + n], dtype=np.float64)
        t_s = float(tok[8 + n])
        inc = fov_rad / (n - 1) if n % 2 == 1 and n > 1 else fov_rad / n
        start = -fov_rad / 2.0
    else:
        start, _fov, inc, rmax = (float(v) for v in tok[2:6])
        n = int(tok[8])
        ranges = np.array(tok[9 : 9 + n], dtype=np.float64)
        if len(ranges) != n:
            raise ValueError(f"{len(ranges)} ranges for {n} beams")
        m = int(tok[9 + n])
        k = 10 + n + m
        pose = np.array(tok[k : k + 3], dtype=np.float64)
        t_s = float(tok[k + 11])
        max_range_m = min(max_range_m, rmax) if rmax > 0 else max_range_m
    if not np.isfinite(pose).all():
        raise ValueError(f"non-finite pose {pose}")
    # "no return" readings sit at the maximum: drop at or beyond it (strictly inside kept)
    r = np.where(ranges >= max_range_m, np.nan, ranges)
    pts, dropped = laser_scan_points(r, start, inc, 1e-9, max_range_m)
    return {"t_s": t_s, "points": pts, "n_dropped": dropped, "pose": pose, "line": lineno}


def open_carmen(path: Path, dataset: Mapping[str, Any], cfg: Mapping[str, Any]) -> Recording:
    """Open a CARMEN log as a :class:`~floorscan.ingest.Recording`.

    The pose stream holds the corrected laser pose of every laser line (z = 0; the
    ingest writer adds the dataset's ``sensor_height_m``).

    Raises
    ------
    InputError
        See :func:`parse_carmen`; also timestamps going backwards, or some but not
        all of them missing.
    """
    scans, counts = parse_carmen(
        path,
        max_range_m=float(cfg.get("carmen_max_range_m", 50.0)),
        fov_rad=float(cfg.get("carmen_fov_rad", math.pi)),
    )
    notes = [f"message types: {dict(sorted(counts.items()))}"]
    t = np.array([s["t_s"] for s in scans])
    if np.all(t == 0):
        period = float(cfg.get("missing_time_period_s", 0.1))
        t = np.arange(len(scans)) * period
        notes.append(
            f"every laser timestamp is 0: scans stamped at index x {period} s "
            "(ingest.missing_time_period_s)"
        )
    elif np.any(t == 0):
        bad = [s["line"] for s in scans if s["t_s"] == 0][:5]
        raise InputError(f"{path}: laser lines with timestamp 0 among stamped ones (lines {bad})")
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
        t, t_ns = t[order], t_ns[order]
    dup = np.flatnonzero(np.diff(t_ns) == 0)
    if dup.size:
        line = scans[dup[0] + 1]["line"]
        raise InputError(
            f"{path}:{line}: duplicate laser timestamp {t[dup[0]]} s; expected strictly increasing ipc_timestamp"
        )
    poses = np.array([s["pose"] for s in scans])
    stream = pose_stream_frame(t_ns, poses[:, 0], poses[:, 1], np.zeros(len(t_ns)), poses[:, 2])

    def _scans() -> Iterator[Scan]:
        for ti, s in zip(t_ns, scans):
            yield Scan(int(ti), "laser", s["points"], s["n_dropped"])

    return Recording(scans=_scans(), pose_stream=stream, source=str(path), notes=notes)

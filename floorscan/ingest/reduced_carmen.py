"""The reduced recording of a CARMEN ``.log`` / ``.log.gz``.

Written with the input's compression (gzip with mtime 0, so the same selection gives
the same bytes). Kept:

- comment (``#``) and ``PARAM`` lines (:data:`CARMEN_KEPT_LINES`);
- the selected laser lines (``FLASER`` / ``ROBOTLASER1``): scan ``i`` is the laser line
  the scan index's ``source_ordinal[i]`` counts in file order; an index without it is
  numbered as :mod:`floorscan.ingest.carmen` numbered scans: file order, stable-sorted
  by stamp when some lines step back in time, unless the stamps are made up, without
  the lines it skipped;
- pose lines (:data:`CARMEN_POSE_LINES`) whose ``ipc_timestamp`` lies within
  ``window_s`` of a selected scan's, or, when their stamp is unusable (0, or the log's
  stamps are made up), that sit next to a selected laser line (no other laser line
  between them).

Other lines (other laser types, ``NEFF``, ``SYNC``, ...) are dropped. Re-ingesting the
reduced log gives the same points when ``ingest.carmen_max_range_m`` is set to the
original's detected ``max_range_m`` (the no-return range is detected from the log's
readings, and fewer readings may detect another).
"""

from __future__ import annotations

import gzip
import io
from collections import Counter
from pathlib import Path

import numpy as np

from floorscan.core.io import InputError
from floorscan.core.files import atomic_path
from floorscan.ingest.reduced_checks import check_count, check_stamps, scan_frames, size_of

#: CARMEN pose lines kept within the window. Their ``ipc_timestamp`` is the third field
#: from the end (``ODOM x y theta tv rv accel ipc_timestamp host logger_timestamp``), as
#: in every CARMEN message, the laser lines too (:data:`floorscan.ingest.carmen_lines.LAYOUTS`).
CARMEN_POSE_LINES = ("ODOM", "TRUEPOS")
#: CARMEN lines always kept (besides ``#`` comments).
CARMEN_KEPT_LINES = ("PARAM",)


def _read_lines(path: Path) -> tuple[list[str], bool]:
    """The log's lines with their line ends, as latin-1 text (byte for byte), split as
    ingest splits them (universal newlines), read as ingest reads the file
    (:func:`floorscan.ingest.text.open_binary`: gzip members, trailing garbage left out);
    and whether it is gzip."""
    import zlib

    from floorscan.ingest.text import is_gzip, open_binary

    gz = is_gzip(path)
    try:
        with io.TextIOWrapper(open_binary(path, warn=False), encoding="latin-1", newline="") as f:
            return f.readlines(), gz
    except (EOFError, OSError, zlib.error) as e:
        raise InputError(f"{path}: cannot read the log, truncated or corrupt ({e})") from None


def reduce_carmen(source: Path, ids, out_path: Path, detection, t_ns, window_s: float) -> dict:
    """The reduced copy of a CARMEN log (module docstring).

    Parameters
    ----------
    source, ids, out_path, detection, t_ns
        As :func:`floorscan.ingest.reduced_bag.reduce_bag`.
    window_s : float
        Pose lines within this many seconds of a selected scan are kept.

    Returns
    -------
    dict
        As :func:`floorscan.ingest.reduced.write_reduced_recording`, ``format``
        ``carmen``.

    Raises
    ------
    InputError
        The log is unreadable, a laser line malformed, its stamp class changed since
        ingest, or the laser count or a stamp differs from ingest's.
    """
    from floorscan.ingest.carmen_lines import LASER_TYPES
    from floorscan.ingest.carmen_stamps import classify_stamps, spread_stamps

    lines, gz = _read_lines(source)
    # split as ingest reads the log: a UTF-8 byte-order mark before the first line is not
    # part of its type (floorscan.ingest.text.open_text drops it); the copy keeps the bytes
    tokens = [ln.encode("latin-1").decode("ascii", errors="replace").split()
              for ln in ([lines[0].removeprefix("\xef\xbb\xbf")] + lines[1:] if lines else [])]
    laser_line, t_s = [], []  # laser ordinal -> line index, ipc stamp
    for i, tok in enumerate(tokens):
        if tok and tok[0] in LASER_TYPES:
            # ingest checked each laser line's layout; a log changed since fails the count
            # and stamp checks against the scan index below
            try:
                t_s.append(float(tok[-3]))
            except (ValueError, IndexError) as e:
                raise InputError(f"{source}:{i + 1}: malformed {tok[0]} line ({e}); expected ingest's field layout") from None
            laser_line.append(i)
    n = len(laser_line)
    t = np.asarray(t_s, dtype=np.float64)
    try:
        stamps, _ = classify_stamps(t)
    except ValueError:
        raise InputError(f"{source}: laser lines with timestamp 0 among stamped ones; expected the log ingest read") from None
    if detection.get("stamps") not in (None, stamps):
        raise InputError(
            f"{source}: its laser stamps are now {stamps!r}, ingest found {detection['stamps']!r}; "
            "expected the log ingest read (it changed since ingest: rerun ingest)"
        )
    # ingest's order and stamps of the laser lines (floorscan.ingest.carmen.open_carmen)
    order = np.arange(n)
    if stamps != "made_up":
        stamp_ns = np.round(t * 1e9).astype(np.int64)
        if np.any(np.diff(stamp_ns) < 0):
            order = np.argsort(stamp_ns, kind="stable")
        stamp_ns = stamp_ns[order]
        if stamps == "spread":
            stamp_ns = spread_stamps(stamp_ns)
    frames = scan_frames(source, ids, detection, order)  # laser ordinals in file order
    check_count(source, n, ids, t_ns, "laser lines", frames, detection)
    if stamps != "made_up":
        by_frame = np.empty(n, dtype=np.int64)
        by_frame[order] = stamp_ns
        check_stamps(source, ids, by_frame[frames], t_ns)
    chosen = np.zeros(n, dtype=bool)
    chosen[frames] = True
    sel_t = np.sort(t[chosen])
    # laser ordinal of the last laser line at or before each line (-1: none yet)
    is_laser = np.zeros(len(lines), dtype=bool)
    is_laser[laser_line] = True
    before = np.cumsum(is_laser) - 1
    usable = stamps != "made_up"
    keep, counts, n_in = [], Counter(), 0
    for i, tok in enumerate(tokens):
        if not tok:
            continue
        n_in += 1
        head = tok[0]
        if head.startswith("#") or head in CARMEN_KEPT_LINES:
            ok = True
        elif is_laser[i]:
            ok = bool(chosen[before[i]])
        elif head in CARMEN_POSE_LINES:
            try:
                ts = float(tok[-3])
            except (ValueError, IndexError):
                ts = 0.0
            if usable and np.isfinite(ts) and ts > 0:
                j = int(np.searchsorted(sel_t, ts))
                ok = (j < len(sel_t) and sel_t[j] - ts <= window_s) or (j > 0 and ts - sel_t[j - 1] <= window_s)
            else:  # no usable stamp: the pose lines between a selected laser line and its neighbours
                b = int(before[i])
                ok = (b >= 0 and chosen[b]) or (b + 1 < n and chosen[b + 1])
        else:
            ok = False
        if ok:
            keep.append(lines[i])
            counts["#" if head.startswith("#") else head] += 1
    data = "".join(keep).encode("latin-1")
    with atomic_path(out_path) as tmp:
        if gz:
            with open(tmp, "wb") as f, gzip.GzipFile(filename="", mode="wb", fileobj=f, mtime=0) as g:
                g.write(data)
        else:
            tmp.write_bytes(data)
    return {
        "format": "carmen",
        "path": str(out_path),
        "bytes_in": size_of(source),
        "bytes_out": size_of(out_path),
        "messages_in": n_in,
        "messages_out": len(keep),
        "scan_messages_out": int(sum(counts[k] for k in LASER_TYPES)),
        "topics": dict(sorted(counts.items())),
    }

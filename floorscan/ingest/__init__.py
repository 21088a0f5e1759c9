"""Ingest: read a recording into the scan and pose tables (thesis sections 3.2 and 3.5).

Three formats are read, each by its own module:

- ``rosbag`` (:mod:`floorscan.ingest.rosbag`): ROS1 ``.bag`` files and ROS2 bag folders
  through rosbags' ``AnyReader``; scans from ``sensor_msgs/LaserScan`` or
  ``sensor_msgs/PointCloud2``; poses from a pose topic, odometry or the TF tree.
- ``carmen`` (:mod:`floorscan.ingest.carmen`): ``FLASER`` and ``ROBOTLASER1`` lines of a
  CARMEN log (plain or gzip), with the corrected pose on each line.
- ``pcd`` (:mod:`floorscan.ingest.pcd`): a folder of ``.pcd`` scans in the map frame plus
  a CSV of scan locations (the thesis's synthetic layout, section 4.1).

A dataset may name only its ``path``: the format is then detected from it
(:func:`floorscan.ingest.detect.detect_format`), a bag's scan topic and pose source from
its topics and TF tree, a CARMEN log's no-return range and the kind of its stamps from
its readings. What was found travels with the data as :attr:`Recording.detected`, stored
in the schema metadata of ``scan_index.parquet`` and ``pose_stream.parquet``.

Every reader keeps the same returns (:func:`laser_scan_points`, :func:`filter_points`):
finite, at or beyond the minimum range and strictly short of the maximum range; a return
at the maximum is the scanner's "no return" and would draw an arc of fake wall. The
text formats (a CARMEN log, an ascii PCD, the locations CSV) read a number field the
same way (:func:`parse_number`, :func:`parse_numbers`).

Every reader yields :class:`Scan` records in recording order plus a pose stream; the
writer :func:`write_recording` streams the points to ``scans.parquet`` one batch at a
time, so memory grows with the largest scan, not with the recording.
"""

from __future__ import annotations

import dataclasses
import logging
from pathlib import Path
from typing import Any, Iterable, Iterator, Mapping, Sequence

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from floorscan.core.runtime import progress
from floorscan.core.io import POSE_STREAM, SCAN_INDEX, SCANS, InputError, atomic_path, parquet_options, ScanRowGroups, write_table

log = logging.getLogger(__name__)


@dataclasses.dataclass(frozen=True)
class Scan:
    """One scan of a recording.

    Attributes
    ----------
    t_ns : int
        Time of the scan, nanoseconds since the Unix epoch (header stamp).
    frame : str
        Frame of the points (the scanner frame).
    points : (N, 3) float32 ndarray
        Valid returns in the scanner frame, metres.
    n_dropped : int
        Returns dropped as invalid (NaN, inf, or outside the range limits).
    """

    t_ns: int
    frame: str
    points: np.ndarray
    n_dropped: int


#: Keys of :attr:`Recording.detected`, in the order they are logged.
DETECTED_KEYS = ("format", "scan_topic", "pose_source", "stamps", "pose_kind", "max_range_m")
#: Pose kinds: ``map`` poses (a localizer, the TF chain from ``map``, a log's corrected
#: poses, a PCD folder's locations, or a pose source set in the dataset), or ``none``.
POSE_KINDS = ("map", "none")
#: Stamp classes: ``recorded`` (strictly increasing, after sorting the few lines out of
#: order), ``spread`` (some repeated stamps spread in line order), ``made_up`` (all zero
#: or mostly repeated: index x period).
STAMP_CLASSES = ("recorded", "spread", "made_up")


@dataclasses.dataclass
class Recording:
    """A recording opened for ingest: a scan iterator and its pose stream.

    ``scans`` is consumed once. ``pose_stream`` is filled by the time ``scans`` is
    exhausted (a bag reader may read poses first); it has the columns of
    :data:`floorscan.core.io.POSE_STREAM`, and is empty when ``detected["pose_kind"]`` is
    ``"none"`` (no map pose source: the register stage runs LIDAR odometry).

    Attributes
    ----------
    detected : dict of str to str
        What the reader found or was told (keys of :data:`DETECTED_KEYS`): ``format``
        (rosbag, carmen, pcd), ``scan_topic`` (a bag's topic, a CARMEN log's laser line
        type, ``pcd files``), ``pose_source`` (a readable phrase), ``pose_kind``
        (:data:`POSE_KINDS`), ``stamps`` (:data:`STAMP_CLASSES`) and, for CARMEN,
        ``max_range_m`` (returns at or beyond it were dropped, metres).
    notes : list of str
        What the reader noticed and did about it, one line each, for the stage log.
    """

    scans: Iterator[Scan]
    pose_stream: pd.DataFrame | None = None
    source: str = ""
    notes: list[str] = dataclasses.field(default_factory=list)
    detected: dict[str, str] = dataclasses.field(default_factory=dict)


def open_recording(dataset: Mapping[str, Any], cfg: Mapping[str, Any], max_gap_s: float) -> Recording:
    """Open the recording a dataset entry names.

    The format is the dataset's ``format`` when given, else detected from ``path``
    (:func:`floorscan.ingest.detect.detect_format`); ``Recording.detected["format"]``
    holds it either way.

    Parameters
    ----------
    dataset : mapping
        The dataset's config entry: ``path``, optional ``format`` (rosbag, carmen, pcd)
        and the format's options (see ``workflow/schemas/config.schema.yaml``).
    cfg : mapping
        The ``ingest`` config section.
    max_gap_s : float
        The pose stage's gap limit; a TF chain leaves out samples inside a longer gap
        of any of its links, so the gap stays visible in the pose stream.

    Raises
    ------
    InputError
        The path is missing, its format cannot be detected (without ``format``), or the
        recording cannot be read (message names the file).
    """
    fmt = dataset.get("format")
    path = Path(dataset["path"])
    if not path.exists():
        raise InputError(f"{path}: recording not found (dataset format {fmt or 'to be detected'!r})")
    how = "set in the dataset"
    if fmt is None:
        from floorscan.ingest.detect import detect_format

        fmt, how = detect_format(path), "detected from the path"
    if fmt == "rosbag":
        from floorscan.ingest.rosbag import open_bag

        rec = open_bag(path, dataset, max_gap_s=max_gap_s)
    elif fmt == "carmen":
        from floorscan.ingest.carmen import open_carmen

        rec = open_carmen(path, dataset, cfg)
    elif fmt == "pcd":
        from floorscan.ingest.pcd import open_pcd_folder

        rec = open_pcd_folder(path, dataset, cfg)
    else:
        raise InputError(f"{path}: unsupported dataset format {fmt!r}; expected rosbag, carmen or pcd")
    rec.detected = {"format": fmt, **{k: v for k, v in rec.detected.items() if k != "format"}}
    rec.notes.insert(0, f"format {fmt} ({how})")
    return rec


def detected_line(detected: Mapping[str, str]) -> str:
    """One log line of what ingest detected: ``format=..., scan_topic=..., ...``."""
    keys = [k for k in DETECTED_KEYS if k in detected] + sorted(k for k in detected if k not in DETECTED_KEYS)
    return ", ".join(f"{k}={detected[k]}" for k in keys)


def describe_recording(detected: Mapping[str, str], mode: str = "") -> str:
    """What a recording was found to be and how it was registered, for people (the
    report's figure title, ``summary.md``): ``format rosbag, scan_topic /scan,
    pose_source ..., stamps recorded; registered in odometry mode``.

    ``detected``: the scan index's schema metadata (:func:`floorscan.core.io.read_metadata`);
    ``mode``: the register mode used (``pose`` when not given).
    """
    found = ", ".join(f"{k} {detected[k]}" for k in ("format", "scan_topic", "pose_source", "stamps") if k in detected)
    return f"{found or 'as configured'}; registered in {mode or 'pose'} mode"


def write_recording(
    recording: Recording,
    scans_path: str | Path,
    index_path: str | Path,
    pose_stream_path: str | Path,
    sensor_height_m: float = 0.0,
    metadata: Mapping[str, str] | None = None,
) -> pd.DataFrame:
    """Stream a recording's scans to Parquet and write its index and pose stream.

    Scans get ``scan_id`` 0..N-1 in recording order. ``sensor_height_m`` is added to
    the pose stream's z. All three files are written atomically: on any error none
    of them is left behind. ``recording.detected`` (string values) and ``metadata`` are
    stored in the schema metadata of the scan index and the pose stream; the register
    stage reads ``pose_kind`` and ``stamps`` from the scan index's.

    Returns
    -------
    pandas.DataFrame
        The scan index (columns of :data:`floorscan.core.io.SCAN_INDEX`).

    Raises
    ------
    InputError
        No scans, scan timestamps going backwards, or no poses while the pose kind is
        not ``none`` (a map pose source was found or set but has no poses).
    """
    rows: list[tuple[int, int, int, int, str]] = []
    table_meta = {**{k: str(v) for k, v in recording.detected.items()}, **(metadata or {})}
    meta = {k.encode(): str(v).encode() for k, v in (metadata or {}).items()}
    with atomic_path(scans_path) as tmp:
        with pq.ParquetWriter(tmp, SCANS.with_metadata(meta), **parquet_options(SCANS, ["scan_id"])) as writer:
            with ScanRowGroups(writer) as batch:  # row groups written in a thread
                last_t = None
                for scan_id, scan in enumerate(progress(recording.scans, log, what="scans read")):
                    if last_t is not None and scan.t_ns < last_t:
                        raise InputError(
                            f"{recording.source}: scan timestamps go backwards at scan {scan_id} "
                            f"({scan.t_ns} ns after {last_t} ns); expected non-decreasing stamps"
                        )
                    last_t = scan.t_ns
                    pts = np.asarray(scan.points, dtype=np.float32).reshape(-1, 3)
                    n = len(pts)
                    rows.append((scan_id, int(scan.t_ns), n, int(scan.n_dropped), scan.frame))
                    if n:
                        batch.add(scan_id, pts)
        if not rows:
            raise InputError(f"{recording.source}: no scans found")
        index = pd.DataFrame(rows, columns=["scan_id", "t_ns", "n_points", "n_dropped", "frame"])
        stream = recording.pose_stream
        if stream is None or stream.empty:
            if recording.detected.get("pose_kind") != "none":
                what = recording.detected.get("pose_source", "the pose source")
                raise InputError(f"{recording.source}: no poses found for the pose source ({what})")
            stream = pose_stream_frame([], [], [], [], [])  # no map pose: LIDAR odometry
        stream = stream.copy()
        stream["z"] = stream["z"].astype(np.float64) + float(sensor_height_m)
        write_table(index, index_path, schema=SCAN_INDEX, metadata=table_meta)
        write_table(stream, pose_stream_path, schema=POSE_STREAM, metadata=table_meta)
    return index


def laser_scan_points(
    ranges: np.ndarray,
    angle_min: float,
    angle_increment: float,
    range_min: float,
    range_max: float,
) -> tuple[np.ndarray, int]:
    """Convert a planar range scan to points in the scanner frame.

    Parameters
    ----------
    ranges : (B,) float ndarray
        Range of each beam, metres; beam i points at ``angle_min + i * angle_increment``
        radians, counter-clockwise from the scanner's +x.
    range_min, range_max : float
        Valid range interval ``[range_min, range_max)``, metres: a return at
        ``range_max`` is the scanner's "no return" (the Stage simulator, for one,
        reports every beam that hits nothing at exactly ``range_max``).

    Returns
    -------
    points : (N, 3) float32 ndarray
        Valid returns (z = 0), metres.
    n_dropped : int
        Beams dropped: NaN, inf, below ``range_min``, at or beyond ``range_max``.
    """
    r = np.asarray(ranges, dtype=np.float64)
    angles = angle_min + angle_increment * np.arange(r.size)
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(r) & (r >= range_min) & (r < range_max)
    pts = np.zeros((int(ok.sum()), 3), dtype=np.float32)
    pts[:, 0] = r[ok] * np.cos(angles[ok])
    pts[:, 1] = r[ok] * np.sin(angles[ok])
    return pts, int(r.size - ok.sum())


def filter_points(
    points: np.ndarray, range_min: float | None = None, range_max: float | None = None
) -> tuple[np.ndarray, int]:
    """Drop non-finite points and points outside a range interval (distance from origin).

    The same rule as :func:`laser_scan_points`: a point is kept when its distance ``d``
    satisfies ``range_min <= d < range_max`` (each bound only when given).

    Parameters
    ----------
    points : (N, 3) float ndarray
        Points in the scanner frame, metres.
    range_min, range_max : float, optional
        Range interval ``[range_min, range_max)``, metres.

    Returns
    -------
    points : (M, 3) float32 ndarray
        ``points`` itself when it is float32 and every point is kept (no copy).
    n_dropped : int
        Points dropped: non-finite or outside the range interval.
    """
    p = np.asarray(points)
    if p.dtype != np.float32:  # float32 input (PointCloud2) is checked as it is: no copy
        p = p.astype(np.float64)
    p = p.reshape(-1, 3)
    ok = np.isfinite(p[:, 0]) & np.isfinite(p[:, 1]) & np.isfinite(p[:, 2])  # 10x all(axis=1)
    if range_min is not None or range_max is not None:
        q = p.astype(np.float64)  # distances in float64, whatever the input
        with np.errstate(invalid="ignore"):
            d = np.sqrt(q[:, 0] ** 2 + q[:, 1] ** 2 + q[:, 2] ** 2)
        if range_min is not None:
            ok &= d >= range_min
        if range_max is not None:
            ok &= d < range_max
    n_ok = int(np.count_nonzero(ok))
    kept = p.astype(np.float32, copy=False) if n_ok == len(p) else p[ok].astype(np.float32, copy=False)
    return kept, len(p) - n_ok


def parse_number(text: str) -> float | None:
    """A number field of a text recording, or None when ``text`` is not a number.

    Python's ``float`` (``nan`` and ``inf`` included, for the caller to judge), except
    for ``1_0``: Python reads 10, the C readers of these formats (``strtod``) read 1.
    """
    if "_" in text:
        return None
    try:
        return float(text)
    except ValueError:
        return None


def parse_numbers(texts: Sequence[str]) -> np.ndarray | None:
    """:func:`parse_number` of every text as a (N,) float64 ndarray, parsed by numpy in
    one call (it reads what ``float`` reads); None when one of them is not a number
    (the caller finds which, one by one, for its message)."""
    if "_" in "".join(texts):
        return None
    try:
        return np.array(texts, dtype=np.float64)
    except ValueError:
        return None


def yaw_from_quaternion(qx, qy, qz, qw):
    """Yaw (rotation about +z, radians in (-pi, pi]) of quaternions (x, y, z, w)."""
    qx, qy, qz, qw = (np.asarray(v, dtype=np.float64) for v in (qx, qy, qz, qw))
    return np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


def pose_stream_frame(t_ns: Iterable[int], x, y, z, yaw) -> pd.DataFrame:
    """Build a pose stream table (columns of :data:`floorscan.core.io.POSE_STREAM`)."""
    return pd.DataFrame(
        {
            "t_ns": np.asarray(list(t_ns) if not isinstance(t_ns, np.ndarray) else t_ns, dtype=np.int64),
            "x": np.asarray(x, dtype=np.float64),
            "y": np.asarray(y, dtype=np.float64),
            "z": np.asarray(z, dtype=np.float64),
            "yaw": np.asarray(yaw, dtype=np.float64),
        }
    )

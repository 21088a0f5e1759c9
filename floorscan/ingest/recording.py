"""What a reader hands to ingest: a recording's scans, its pose stream, what was detected.

A reader (:mod:`floorscan.ingest.rosbag`, :mod:`floorscan.ingest.carmen`,
:mod:`floorscan.ingest.pcd`) returns a :class:`Recording`: an iterator of :class:`Scan`
records in recording order, the pose stream (:func:`pose_stream_frame`: the columns of
:data:`floorscan.core.io.POSE_STREAM`), notes for the stage log and what it detected
(:data:`DETECTED_KEYS`; one log line by :func:`detected_line`, a phrase for people by
:func:`floorscan.core.io.describe_recording`).
"""

from __future__ import annotations

import dataclasses
from typing import Iterable, Iterator, Mapping

import numpy as np
import pandas as pd


#: Scans stamped at most this many seconds before the scan before them are sorted by
#: stamp (a logger that writes a line late, a publisher's jitter: the shared CARMEN
#: logs step back at most 0.86 s, intel's); a step back by more is never sorted into
#: one trajectory: it is a second recording appended (it steps back by the length of
#: the first, minutes), a clock reset or a broken stamp, and the readers refuse it.
MAX_STEP_BACK_S = 5.0


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
    source_ordinal : int or None
        0-based ordinal of the frame the scan was read from, as ``skipped_frames``
        numbers them (:data:`DETECTED_KEYS`): a bag's message on the scan topic, a CARMEN
        log's laser line in file order, the locations CSV's row. The scan index's
        ``source_ordinal`` (:data:`floorscan.core.io.SCAN_INDEX`): the select stage finds
        the scan in the recording by it. None: the reader does not number its frames.
    """

    t_ns: int
    frame: str
    points: np.ndarray
    n_dropped: int
    source_ordinal: int | None = None


#: What a reader lost on the way, in :attr:`Recording.detected` (decimal strings; each
#: ``lost_*`` key only when non-zero): ``n_frames_read`` (scan frames the reader saw:
#: a bag's messages on the scan topic, a CARMEN log's laser lines, the PCD files listed
#: in the locations CSV), ``lost_bad_frames`` (skipped: broken scan geometry or a message
#: that cannot be decoded), ``lost_no_points`` (skipped: no valid return),
#: ``lost_unlisted_files`` (``.pcd`` files in the folder that the locations CSV does not
#: list, not read) and ``lost_unknown_lines`` (CARMEN lines of a message type CARMEN
#: does not define, not read). Complete once ``Recording.scans`` is exhausted.
LOSS_KEYS = ("n_frames_read", "lost_bad_frames", "lost_no_points", "lost_unlisted_files", "lost_unknown_lines")
#: Keys of :attr:`Recording.detected`, in the order they are logged. ``skipped_frames``:
#: where the skipped frames were, as ranges of 0-based ordinals (``"3,17-19"``): a bag's
#: message index on the scan topic (in reading order), a CARMEN log's laser line (in file
#: order), the locations CSV's row; only when a frame was skipped. The scans' own frames
#: are numbered the same way (:attr:`Scan.source_ordinal`). ``stamps_reason``: why the
#: stamps are made up, with the counts (a CARMEN log's; only when they are).
DETECTED_KEYS = (
    "format", "scan_topic", "pose_source", "stamps", "stamps_reason", "pose_kind", "max_range_m",
) + LOSS_KEYS + ("skipped_frames",)
#: Pose kinds: ``map`` poses (a localizer, the TF chain from ``map``, a log's corrected
#: poses, a PCD folder's locations, or a pose source set in the dataset), or ``none``.
POSE_KINDS = ("map", "none")
#: Stamp classes: ``recorded`` (strictly increasing, after sorting the few lines out of
#: order), ``spread`` (some repeated stamps spread in line order), ``made_up`` (all zero,
#: mostly repeated, or mostly out of range or out of time order: index x period).
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
        ``stamps_reason`` (why they are made up, when they are) and ``max_range_m`` (returns at or beyond it were dropped, metres); what was lost
        (:data:`LOSS_KEYS`, ``skipped_frames``). A lazy reader (bags, PCD folders) adds
        the loss keys as ``scans`` is consumed, to this same dict.
    notes : list of str
        What the reader noticed and did about it, one line each, for the stage log; a
        lazy reader appends what it skipped as ``scans`` is consumed (and logs it as a
        warning).
    """

    scans: Iterator[Scan]
    pose_stream: pd.DataFrame | None = None
    source: str = ""
    notes: list[str] = dataclasses.field(default_factory=list)
    detected: dict[str, str] = dataclasses.field(default_factory=dict)


def detected_line(detected: Mapping[str, str]) -> str:
    """One log line of what ingest detected: ``format=..., scan_topic=..., ...``.

    Parameters
    ----------
    detected : mapping of str to str
        ``Recording.detected``.

    Returns
    -------
    str
        The keys of :data:`DETECTED_KEYS` first, in their order, then the others sorted.
    """
    keys = [k for k in DETECTED_KEYS if k in detected] + sorted(k for k in detected if k not in DETECTED_KEYS)
    return ", ".join(f"{k}={detected[k]}" for k in keys)


def yaw_from_quaternion(qx, qy, qz, qw):
    """Yaw (rotation about +z) of quaternions.

    Parameters
    ----------
    qx, qy, qz, qw : float or ndarray
        Quaternion components (x, y, z, w), of one shape.

    Returns
    -------
    float64 ndarray
        That shape (0-d for scalars), radians in [-pi, pi] (``numpy.arctan2``: +pi and
        -pi both occur, as the sign of zero gives them;
        :func:`floorscan.core.geometry.wrap_angle` maps to [-pi, pi)).
    """
    qx, qy, qz, qw = (np.asarray(v, dtype=np.float64) for v in (qx, qy, qz, qw))
    return np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


def pose_stream_frame(t_ns: Iterable[int], x, y, z, yaw) -> pd.DataFrame:
    """Build a pose stream table.

    Parameters
    ----------
    t_ns : (N,) iterable of int
        Stamps, nanoseconds.
    x, y, z : (N,) array_like
        Position, metres.
    yaw : (N,) array_like
        Heading, radians.

    Returns
    -------
    pandas.DataFrame
        The columns of :data:`floorscan.core.io.POSE_STREAM`: ``t_ns`` int64, the others
        float64.
    """
    return pd.DataFrame(
        {
            "t_ns": np.asarray(list(t_ns) if not isinstance(t_ns, np.ndarray) else t_ns, dtype=np.int64),
            "x": np.asarray(x, dtype=np.float64),
            "y": np.asarray(y, dtype=np.float64),
            "z": np.asarray(z, dtype=np.float64),
            "yaw": np.asarray(yaw, dtype=np.float64),
        }
    )

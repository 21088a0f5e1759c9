"""Pose streams and the scanner's mount from the TF chains of a bag.

A chain's pose composes its links (:mod:`floorscan.ingest.tf_chains`), each
interpolated at the union of the moving links' stamps, linearly in translation and by
slerp in rotation, as tf2 does (:func:`tf_pose_stream`); samples inside a gap of a
moving link are left out. The mount of the scanner on the base is the chain of static
links between them (:func:`static_transform`). A link with a bad sample
(:func:`floorscan.ingest.ros_messages.pose_problem`) is refused only when a chain uses
it. A pose stream whose scanner is tilted more than :data:`MAX_TILT_DEG` from level is
refused (:func:`planar_pose_stream`), unless it is upside down (rolled or pitched half a
turn, within :data:`MAX_TILT_DEG`: a scanner mounted under a robot or on a ceiling): its
scans are level scans seen from below, mirrored, and the reader turns their points over
(:func:`turn_over`, ``y`` and ``z`` negated: a rotation of half a turn about the
scanner's x axis) so that the pose stream's level pose places them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from floorscan.core.io import InputError
from floorscan.ingest.recording import pose_stream_frame
from floorscan.ingest.tf_chains import TfChainError, TfLink, tf_chain, tf_chain_from_root


#: A scanner tilted more than this (degrees) cannot be treated as planar.
MAX_TILT_DEG = 10.0


def planar_pose_stream(t, rot: Rotation, trans, what: str):
    """Pose stream of a chain of 3D poses, refusing a tilted scanner.

    A scanner upside down (its z axis within :data:`MAX_TILT_DEG` of straight down at
    every pose) is accepted: the stream is the pose of the level frame ``rot`` x (half a
    turn about x), whose heading is the scanner's x axis, and
    ``stream.attrs["upside_down"]`` is True: the scans' points are to be turned over
    (:func:`turn_over`) before this pose places them.

    Parameters
    ----------
    t : (N,) int ndarray
        Stamps, nanoseconds.
    rot, trans : scipy.spatial.transform.Rotation, (N, 3) float ndarray
        N rotations and translations (metres).
    what : str
        The chain, for the message.

    Returns
    -------
    pandas.DataFrame
        :func:`~floorscan.ingest.recording.pose_stream_frame` (yaw of the rotated x axis),
        with ``attrs["upside_down"]`` (bool).

    Raises
    ------
    InputError
        A pose's z axis tilts more than :data:`MAX_TILT_DEG` degrees from vertical (up or
        down), or the scanner is upside down at some poses and level at others.
    """
    mat = rot.as_matrix()
    tilt = np.degrees(np.arccos(np.clip(mat[:, 2, 2], -1.0, 1.0)))  # 0: level, 180: upside down
    level, down = tilt <= MAX_TILT_DEG, tilt >= 180.0 - MAX_TILT_DEG
    if not np.all(level | down):
        worst = float(np.max(np.minimum(tilt, 180.0 - tilt)))
        raise InputError(
            f"{what}: the scanner is tilted {worst:.1f} deg from level; floorscan expects a level "
            f"scanner (tilt under {MAX_TILT_DEG} deg, or upside down within {MAX_TILT_DEG} deg)"
        )
    if np.any(level) and np.any(down):
        i = int(np.flatnonzero(down != down[0])[0])
        raise InputError(
            f"{what}: the scanner is {'upside down' if down[0] else 'level'} at first and "
            f"{'upside down' if down[i] else 'level'} from pose {i} ({int(t[i])} ns); expected one mount"
        )
    yaw = np.arctan2(mat[:, 1, 0], mat[:, 0, 0])  # the x axis: the same turned over about it
    stream = pose_stream_frame(t, trans[:, 0], trans[:, 1], trans[:, 2], yaw)
    stream.attrs["upside_down"] = bool(down.size and down[0])
    return stream


def is_upside_down(rot: Rotation) -> bool:
    """Whether a mount's rotation points the scanner's z axis down, within
    :data:`MAX_TILT_DEG` (a single rotation)."""
    return bool(rot.as_matrix().reshape(-1, 3, 3)[0, 2, 2] <= np.cos(np.radians(180.0 - MAX_TILT_DEG)))


def turn_over(points: np.ndarray) -> np.ndarray:
    """The points of an upside-down scanner in the level frame of its pose: ``y`` and
    ``z`` negated (half a turn about the scanner's x axis); a new array.

    Parameters
    ----------
    points : (N, 3) float ndarray
        Points in the scanner frame, metres.
    """
    return points * np.array([1.0, -1.0, -1.0], dtype=points.dtype)


def _check_links(chain: list[TfLink]) -> None:
    """Refuse a chain with a link that had a bad sample (its message names it)."""
    for e in chain:
        if e.bad is not None:
            raise InputError(e.bad)


def static_transform(edges, base: str, frame: str, path: Path | str = ""):
    """The mount of ``frame`` on ``base``: the composed (rotation, translation) of the
    static chain ``base`` -> ``frame`` (identity when they are one frame), or None when
    there is no such chain or a link of it moves.

    Parameters
    ----------
    edges : mapping of (str, str) to TfLink
    base, frame : str
    path : path

    Returns
    -------
    (scipy.spatial.transform.Rotation, (3,) float64 ndarray) or None
        Translation in metres.

    Raises
    ------
    TfChainError
        A frame on the way up from ``frame`` has several parents, or the way loops (a
        broken tree is never taken for a missing mount).
    InputError
        A link of the chain had a bad sample.
    """
    if base == frame:
        return Rotation.identity(), np.zeros(3)
    try:
        chain = tf_chain(edges, base, frame, path)
    except TfChainError as e:
        if e.kind in ("several_parents", "loop"):
            raise
        return None
    _check_links(chain)
    if not all(e.static for e in chain):
        return None
    return _compose_static(chain)


def static_between(edges, target: str, frame: str):
    """The rigid transform taking points of ``frame`` into ``target`` when both hang
    from a common frame by static links only (two scanners' mounts on ``base_link``),
    or None.

    Parameters
    ----------
    edges : mapping of (str, str) to TfLink
    target, frame : str

    Returns
    -------
    (scipy.spatial.transform.Rotation, (3,) float64 ndarray) or None
        ``p_target = R p_frame + t`` (metres). None: a frame is not in the TF tree, they
        have no common frame, a link between them moves, or the tree is broken on the
        way (several parents, a loop).

    Raises
    ------
    InputError
        A link on the way had a bad sample.
    """
    if target == frame:
        return Rotation.identity(), np.zeros(3)
    if not edges:
        return None
    above_frame = set(tf_chain_from_root(edges, frame))
    for common in reversed(tf_chain_from_root(edges, target)):  # the nearest common frame
        if common not in above_frame:
            continue
        try:
            to_target, to_frame = static_transform(edges, common, target), static_transform(edges, common, frame)
        except TfChainError:
            return None
        if to_target is None or to_frame is None:
            return None
        inv = to_target[0].inv()
        return inv * to_frame[0], inv.apply(to_frame[1] - to_target[1])
    return None


def _compose_static(chain: list[TfLink]):
    """The (rotation, translation) of a chain of links that do not move, each at its one
    sample, composed from the chain's fixed frame down."""
    rot, trans = Rotation.identity(), np.zeros(3)
    for e in chain:
        trans = trans + rot.apply(e.trans_arr[0])
        rot = rot * e.rot[0]
    return rot, trans


def tf_pose_stream(edges, path: Path, fixed: str, frame: str, max_gap_s: float):
    """Pose stream of the TF chain ``fixed`` -> ``frame`` and the chain's links: the
    moving links interpolated (:meth:`TfLink.at`) at their stamps where all overlap,
    but inside a gap longer than ``max_gap_s`` of any; a chain that never changes (a
    scanner that does not move) gives its one pose at every stamp its links were sent.

    Parameters
    ----------
    edges : mapping of (str, str) to TfLink
    path : Path
    fixed, frame : str
    max_gap_s : float
        Seconds.

    Returns
    -------
    stream : pandas.DataFrame
        :func:`planar_pose_stream`'s table.
    chain : list of TfLink

    Raises
    ------
    InputError
        No TF messages; a static chain sent once; moving links that do not overlap in
        time; a bad sample on a link; a tilted scanner.
    TfChainError
        As :func:`tf_chain`.
    """
    if not edges:
        raise InputError(f"{path}: pose.source is 'tf' but the bag has no /tf or /tf_static messages")
    chain = tf_chain(edges, fixed, frame, path)
    _check_links(chain)
    moving = [e for e in chain if not e.static]
    if not moving:  # the scanner does not move: the chain's one pose, at every stamp its links were sent
        t = np.unique(np.concatenate([e.t_sent for e in chain]))
        if t.size < 2:
            raise InputError(
                f"{path}: the TF chain {fixed!r} -> {frame!r} never changes and was sent once; expected it over the "
                "recording's time (a stationary scanner's pose published on /tf as the recording goes)"
            )
        rot, trans = _compose_static(chain)
        n = len(t)
        rots = Rotation.from_quat(np.repeat(rot.as_quat()[None], n, axis=0))
        return planar_pose_stream(t, rots, np.repeat(trans[None], n, axis=0), f"{path}: TF chain {fixed!r} -> {frame!r}"), chain
    lo = max(e.t_arr[0] for e in moving)
    hi = min(e.t_arr[-1] for e in moving)
    t = np.unique(np.concatenate([e.t_arr for e in moving]))
    keep = (t >= lo) & (t <= hi)
    gap_ns = int(max_gap_s * 1e9)
    for e in moving:
        d = np.diff(e.t_arr)
        for i in np.flatnonzero(d > gap_ns):
            keep &= ~((t > e.t_arr[i]) & (t < e.t_arr[i + 1]))
    t = t[keep]
    if t.size == 0:
        raise InputError(f"{path}: the moving TF links {[(e.parent, e.child) for e in moving]} do not overlap in time")
    rot, trans = Rotation.identity(len(t)), np.zeros((len(t), 3))
    for e in chain:
        r_e, t_e = e.at(t)
        trans = trans + rot.apply(t_e)
        rot = rot * r_e
    return planar_pose_stream(t, rot, trans, f"{path}: TF chain {fixed!r} -> {frame!r}"), chain

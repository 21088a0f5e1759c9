"""Decode the ROS messages ingest reads: LaserScan, PointCloud2, header stamps, pose values.

A message's time is its header stamp (the bag's receive time when the stamp is zero:
:func:`stamp_ns`). A ``sensor_msgs/LaserScan`` gives the points of its beams
(:func:`laser_scan_xyz`), a ``sensor_msgs/PointCloud2`` its ``x, y, z`` fields, whatever
their layout (:func:`pointcloud2_xyz`).

Bad values are an ``InputError`` naming the file, the topic, the message
(:func:`message_label`) and the field, never a wrong pose or point. A bad *scan* message
raises a :class:`~floorscan.ingest.points.FrameError` (an ``InputError``), which the bag
reader skips and counts when only a few are bad
(:class:`~floorscan.ingest.points.ScanLosses`): a LaserScan whose geometry is broken
(:func:`laser_scan_problem`: a field not finite, ``angle_increment`` zero or against
``angle_max - angle_min``, a ranges count that does not match the angles, angles wider
than a full turn (degrees), ``range_min`` not below ``range_max``); a PointCloud2 whose
layout does not hold its points (a field beyond ``point_step``, ``row_step`` short of a
row, data not ``row_step x height`` bytes) or with no finite point at all. A pose
message's position or orientation not finite, or its quaternion not a unit one
(``|q|^2`` off 1 by more than :data:`QUATERNION_TOLERANCE`, the bound tf2 applies to the
transforms it accepts: :func:`pose_problem`; a TF transform the same, when its link is
in the chain the poses come from, :mod:`floorscan.ingest.tf_chains`) is an error.
Non-finite *ranges* and single non-finite *points* are not errors: they are "no return",
dropped and counted.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from floorscan.ingest.points import FrameError, angle_span_problem, laser_scan_points


#: A quaternion whose squared norm is off 1 by more than this is not a rotation (tf2's
#: ``BufferCore::setTransform`` rejects such transforms with the same bound).
QUATERNION_TOLERANCE = 0.01


def bag_messages(reader, connections):
    """The messages of ``connections`` in the bag of ``reader``, in time order: (connection,
    bag time in ns, raw bytes). Every read of a bag's messages goes through here.

    rosbags' ``AnyReader.messages(connections=[])`` yields *every* message of the bag (an
    empty list reads as "no filter"), so a bag without a topic asked for (no ``/tf``, no
    ``/tf_static``) would have its scans read as transforms. An empty ``connections``
    yields nothing here.

    Parameters
    ----------
    reader : rosbags.highlevel.AnyReader
        An open reader.
    connections : sequence of rosbags connections
        The connections to read; empty: none.
    """
    connections = list(connections)
    if not connections:
        return iter(())
    return reader.messages(connections=connections)


def stamp_ns(header, bag_t: int) -> int:
    """A header's stamp; the bag's receive time when the stamp is zero.

    Parameters
    ----------
    header : std_msgs/Header
        Its ``stamp.sec`` and ``stamp.nanosec``.
    bag_t : int
        The message's receive time in the bag, nanoseconds.

    Returns
    -------
    int
        Nanoseconds.
    """
    t = int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)
    return t if t > 0 else int(bag_t)


def message_label(path: Path | str, topic: str, index: int, t_ns: int) -> str:
    """How an error names one message: ``file: 'topic' message i (t ... ns)``.

    Parameters
    ----------
    path : path
    topic : str
    index : int
        The message's index on the topic.
    t_ns : int
        Its stamp, nanoseconds.

    Returns
    -------
    str
    """
    return f"{path}: {topic!r} message {index} (t {t_ns} ns)"


def laser_scan_xyz(
    msg,
    path: Path | str = "",
    topic: str = "",
    index: int = 0,
    t_ns: int = 0,
    range_min_m: float | None = None,
    range_max_m: float | None = None,
) -> tuple[np.ndarray, int]:
    """Points of a ``sensor_msgs/LaserScan`` in the scanner frame.

    Beam ``i`` points at ``angle_min + i * angle_increment``; returns are kept in
    ``[max(range_min, range_min_m), min(range_max, range_max_m))``
    (:func:`floorscan.ingest.points.laser_scan_points`).

    Parameters
    ----------
    msg : sensor_msgs/LaserScan
        ``angle_min``, ``angle_increment``, ``range_min``, ``range_max`` (radians,
        metres) and ``ranges`` ((B,) float32, metres).
    path, topic, index, t_ns
        The bag, topic, message index and stamp, for error messages.
    range_min_m, range_max_m : float, optional
        The dataset's limits, metres: they only tighten the message's.

    Returns
    -------
    points : (N, 3) float32 ndarray
        Valid returns, z = 0, metres.
    n_dropped : int
        Beams dropped: NaN, inf (no return) or out of the range limits.

    Raises
    ------
    FrameError
        ``angle_min``, ``angle_increment``, ``range_min`` or ``range_max`` is not finite
        (names the file, topic, message and field). The rest of the geometry is
        :func:`laser_scan_problem`'s.
    """
    values = (float(msg.angle_min), float(msg.angle_increment), float(msg.range_min), float(msg.range_max))
    for name, v in zip(("angle_min", "angle_increment", "range_min", "range_max"), values):
        if not math.isfinite(v):
            raise FrameError(message_label(path, topic, index, t_ns), f"LaserScan {name} is {v}; expected a finite number")
    rmin, rmax = laser_scan_limits(msg, range_min_m, range_max_m)
    return laser_scan_points(np.asarray(msg.ranges), values[0], values[1], rmin, rmax)


def laser_scan_limits(msg, range_min_m: float | None = None, range_max_m: float | None = None) -> tuple[float, float]:
    """The valid interval ``[rmin, rmax)`` of a ``sensor_msgs/LaserScan``'s returns: the
    message's ``range_min``, ``range_max`` tightened by the dataset's.

    Parameters
    ----------
    msg : sensor_msgs/LaserScan
    range_min_m, range_max_m : float or None
        The dataset's limits, metres; None: not set.

    Returns
    -------
    rmin, rmax : float
        Metres.
    """
    rmin = max(float(msg.range_min), range_min_m if range_min_m is not None else 0.0)
    rmax = min(float(msg.range_max), range_max_m if range_max_m is not None else math.inf)
    return rmin, rmax


def laser_scan_problem(msg) -> str | None:
    """What is wrong with a ``sensor_msgs/LaserScan``'s geometry, or None.

    Checked in this order, each naming the field and what was expected:

    - ``angle_min``, ``angle_max``, ``angle_increment``, ``range_min``, ``range_max``
      finite (radians, metres);
    - ``angle_max - angle_min`` at most a full turn (2 pi plus
      :data:`~floorscan.ingest.points.ANGLE_SPAN_TOLERANCE_RAD`): wider is taken to be
      degrees;
    - ``angle_increment`` non-zero, with the sign of ``angle_max - angle_min`` (beam ``i``
      points at ``angle_min + i * angle_increment``, and the last at ``angle_max``);
    - the number of ``ranges`` within one of ``(angle_max - angle_min) / angle_increment + 1``
      (drivers differ by one on whether the beam at ``angle_max`` is included);
    - ``range_min < range_max``.

    The ROS message definition (``sensor_msgs/LaserScan.msg``) states this geometry; a
    scan that breaks it would draw its beams at wrong angles (e.g. twice the ranges wrap
    round the full circle).

    Parameters
    ----------
    msg : sensor_msgs/LaserScan

    Returns
    -------
    str or None
        The first problem found, or None for a sound geometry.
    """
    names = ("angle_min", "angle_max", "angle_increment", "range_min", "range_max")
    values = [float(getattr(msg, n)) for n in names]
    for name, v in zip(names, values):
        if not math.isfinite(v):
            return f"LaserScan {name} is {v}; expected a finite number"
    angle_min, angle_max, inc, range_min, range_max = values
    span = angle_max - angle_min
    bad = angle_span_problem(span, f"LaserScan angle_max - angle_min = {angle_max:g} - {angle_min:g}")
    if bad:
        return bad
    if inc == 0.0 or (span != 0.0 and (inc > 0) != (span > 0)):
        return (
            f"LaserScan angle_increment is {inc:g}; expected a non-zero step with the sign of "
            f"angle_max - angle_min = {span:g} rad"
        )
    n = len(msg.ranges)
    expected = span / inc + 1.0
    if abs(n - expected) > 1.0 + 1e-6:
        return (
            f"LaserScan ranges has {n} values; expected (angle_max - angle_min) / angle_increment + 1 = "
            f"{span:g} / {inc:g} + 1 = {expected:.6g}, within one"
        )
    if not range_min < range_max:
        return f"LaserScan range_min is {range_min:g} m, range_max {range_max:g} m; expected range_min < range_max"
    return None


_PC2_DTYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}


def pointcloud2_xyz(msg, path: Path | str = "", topic: str = "", index: int | None = None, t_ns: int = 0) -> np.ndarray:
    """The ``x, y, z`` fields of a ``sensor_msgs/PointCloud2``.

    Handles any point step, field offsets, endianness, row padding (``row_step`` beyond
    ``width x point_step``; 0 is taken as unpadded) and organised clouds (height > 1).

    Parameters
    ----------
    msg : sensor_msgs/PointCloud2
    path : path
        The recording, named in error messages.
    topic : str
        The message's topic, named in error messages.
    index, t_ns : int, optional
        The message's index on the topic and stamp (nanoseconds), named in error
        messages.

    Returns
    -------
    (N, 3) float32 or float64 ndarray
        Metres in the message's frame. float32 when the three fields are little-endian
        float32 (the usual LIDAR driver layout: the values as they are, without a float64
        copy that the float32 scan table would round back), else float64. Non-finite
        points are returned as they are (the caller drops and counts them).

    Raises
    ------
    FrameError
        The message has no x, y or z field, one of unknown datatype or ending beyond
        ``point_step``; ``row_step`` is short of ``width x point_step``; the data is not
        ``row_step x height`` bytes (loss ``bad_frame``); or no point is finite (the cloud
        holds nothing: loss ``no_points``).
    """
    where = f"{path}" if index is None else message_label(path, topic, index, t_ns)
    what = "PointCloud2" if index is not None else f"PointCloud2 on {topic!r}"
    fields = {f.name: f for f in msg.fields}
    missing = [n for n in "xyz" if n not in fields]
    if missing:
        raise FrameError(
            where, f"{what} lacks fields {missing}; expected x, y, z "
            f"(fields: {sorted(fields)})"
        )
    order = ">" if msg.is_bigendian else "<"
    step, width, height, row_step = int(msg.point_step), int(msg.width), int(msg.height), int(msg.row_step)
    names, formats, offsets = [], [], []
    for n in "xyz":
        f = fields[n]
        if f.datatype not in _PC2_DTYPES:
            raise FrameError(where, f"{what} field {n!r} has unknown datatype {f.datatype}")
        size = np.dtype(_PC2_DTYPES[f.datatype]).itemsize
        if not 0 <= int(f.offset) <= step - size:
            raise FrameError(
                where, f"{what} field {n!r} (offset {int(f.offset)}, {size} bytes) ends beyond point_step {step}"
            )
        names.append(n)
        formats.append(order + _PC2_DTYPES[f.datatype])
        offsets.append(int(f.offset))
    if row_step and row_step < width * step:
        raise FrameError(
            where, f"{what} row_step {row_step} is less than width x point_step = {width} x {step} = {width * step}"
        )
    rs = row_step or width * step  # 0: a driver that left it unset, rows packed
    data = np.asarray(msg.data, dtype=np.uint8)
    if data.size != rs * height:
        raise FrameError(
            where, f"{what} has {data.size} bytes of data; "
            f"expected row_step x height = {rs} x {height} = {rs * height}"
        )
    n_points = width * height
    out_dtype = np.float32 if all(f == "<f4" for f in formats) else np.float64
    if n_points == 0:
        return np.zeros((0, 3), dtype=out_dtype)
    if rs != width * step:
        data = np.ascontiguousarray(data.reshape(height, rs)[:, : width * step]).reshape(-1)
    dt = np.dtype({"names": names, "formats": formats, "offsets": offsets, "itemsize": step})
    arr = np.frombuffer(data, dtype=dt, count=n_points)  # a view: count bounds it
    out = np.empty((n_points, 3), dtype=out_dtype)
    for i, n in enumerate("xyz"):
        out[:, i] = arr[n]
    if not (np.isfinite(out[:, 0]) & np.isfinite(out[:, 1]) & np.isfinite(out[:, 2])).any():
        raise FrameError(
            where, f"{what} has no finite point ({n_points} points); expected a cloud with at least one return",
            loss="no_points",
        )
    return out


def pose_problem(
    position: tuple[float, float, float],
    quat: tuple[float, float, float, float],
    prefix: str,
    parts: tuple[str, str] = ("position", "orientation"),
) -> str | None:
    """What is wrong with a pose's values (``prefix.position.x is nan; ...``), or None:
    a non-finite component of ``position`` (x, y, z) or ``quat`` (x, y, z, w), or a
    quaternion off unit length by more than :data:`QUATERNION_TOLERANCE` (in ``|q|^2``,
    as tf2 requires).

    Called for every pose and TF message: a good pose costs one test (a NaN or inf
    component fails it); the loops below only explain a bad one.

    Parameters
    ----------
    position : (3,) tuple of float
        Metres.
    quat : (4,) tuple of float
        Quaternion (x, y, z, w).
    prefix : str
        The message field, for the message.
    parts : (str, str)
        The names of the position and orientation fields.

    Returns
    -------
    str or None
    """
    n2 = quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]
    if abs(n2 - 1.0) <= QUATERNION_TOLERANCE and math.isfinite(position[0] + position[1] + position[2]):
        return None
    (p_name, q_name) = parts
    for part, values in ((p_name, position), (q_name, quat)):
        for c, v in zip("xyzw", values):
            if not math.isfinite(v):
                return f"{prefix}.{part}.{c} is {float(v)}; expected a finite number"
    if abs(n2 - 1.0) > QUATERNION_TOLERANCE:
        return (
            f"{prefix}.{q_name} is {tuple(map(float, quat))}, |q|^2 = {n2:g}; expected a unit quaternion "
            f"(|q|^2 within {QUATERNION_TOLERANCE} of 1, as tf2 requires)"
        )
    return None  # finite values whose sum overflowed

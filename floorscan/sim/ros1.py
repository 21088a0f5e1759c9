"""The ROS1 messages of a simulated recording (rosbags' Noetic typestore).

A recording's bag (:func:`floorscan.sim.writer.write_recording`) carries:

- ``/scan``: ``sensor_msgs/LaserScan`` for 2D scanners, ``sensor_msgs/PointCloud2`` with
  float32 x, y, z for 3D; frame ``laser``;
- ``/amcl_pose``: ``geometry_msgs/PoseWithCovarianceStamped`` of ``base_link`` in ``map``;
- ``/odom``: ``nav_msgs/Odometry``, ``odom`` -> ``base_link``;
- ``/tf_static``: ``base_link`` -> ``laser``, the scanner ``sensor_height_m`` above
  ``base_link``, which is on the floor.

:class:`Ros1Messages` builds each message with its header (a ``seq`` per topic) and
serializes it.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from floorscan.sim.scanners import Scanner2D

if TYPE_CHECKING:
    from floorscan.sim.recording import Recording


def ros1_typestore():
    """rosbags' ROS1 Noetic typestore, with ``tf2_msgs/msg/TFMessage`` registered.

    Returns
    -------
    rosbags.typesys.store.Typestore
    """
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    if "tf2_msgs/msg/TFMessage" not in ts.types:
        ts.register(
            get_types_from_msg("geometry_msgs/TransformStamped[] transforms", "tf2_msgs/msg/TFMessage")
        )
    return ts


class Ros1Messages:
    """Builds and serializes the ROS1 messages of a recording."""

    def __init__(self, rec: Recording) -> None:
        self.ts = ros1_typestore()
        self.T = self.ts.types
        self.rec = rec
        self.seq: dict[str, int] = {}

    def header(self, topic: str, t_ns: int, frame: str):
        """A ``std_msgs/Header``, with the next ``seq`` of ``topic``.

        Parameters
        ----------
        topic : str
        t_ns : int
            Stamp, nanoseconds since the epoch.
        frame : str
            ``frame_id``.

        Returns
        -------
        std_msgs/msg/Header
        """
        seq = self.seq.get(topic, 0)
        self.seq[topic] = seq + 1
        sec, nsec = divmod(int(t_ns), 1_000_000_000)
        stamp = self.T["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
        return self.T["std_msgs/msg/Header"](seq=seq, stamp=stamp, frame_id=frame)

    def quat(self, yaw: float):
        """The quaternion of a rotation about +z.

        Parameters
        ----------
        yaw : float
            Radians.

        Returns
        -------
        geometry_msgs/msg/Quaternion
        """
        q = self.T["geometry_msgs/msg/Quaternion"]
        return q(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))

    def pose(self, x: float, y: float, z: float, yaw: float, cov: np.ndarray):
        """A ``geometry_msgs/PoseWithCovariance``.

        Parameters
        ----------
        x, y, z : float
            Metres.
        yaw : float
            Radians.
        cov : (36,) float ndarray
            Row-major 6 x 6 covariance (x, y, z, roll, pitch, yaw).

        Returns
        -------
        geometry_msgs/msg/PoseWithCovariance
        """
        T = self.T
        return T["geometry_msgs/msg/PoseWithCovariance"](
            pose=T["geometry_msgs/msg/Pose"](
                position=T["geometry_msgs/msg/Point"](x=x, y=y, z=z), orientation=self.quat(yaw)
            ),
            covariance=cov,
        )

    def ser(self, msg, msgtype: str) -> bytes:
        """Serialize a message as ROS1 bytes.

        Parameters
        ----------
        msg : rosbags message
        msgtype : str
            E.g. ``"sensor_msgs/msg/LaserScan"``.

        Returns
        -------
        bytes
        """
        return self.ts.serialize_ros1(msg, msgtype)

    def tf_static(self, t_ns: int) -> bytes:
        """The ``/tf_static`` message: ``base_link`` -> ``laser``, the sensor height up.

        Parameters
        ----------
        t_ns : int
            Stamp, nanoseconds since the epoch.

        Returns
        -------
        bytes
            Serialized ``tf2_msgs/TFMessage``.
        """
        T = self.T
        tr = T["geometry_msgs/msg/TransformStamped"](
            header=self.header("/tf_static", t_ns, "base_link"),
            child_frame_id="laser",
            transform=T["geometry_msgs/msg/Transform"](
                translation=T["geometry_msgs/msg/Vector3"](
                    x=0.0, y=0.0, z=float(self.rec.params.sensor_height_m)
                ),
                rotation=self.quat(0.0),
            ),
        )
        return self.ser(T["tf2_msgs/msg/TFMessage"](transforms=[tr]), "tf2_msgs/msg/TFMessage")

    def amcl(self, i: int) -> bytes:
        """The ``/amcl_pose`` message of AMCL pose ``i`` (map frame; variances from the
        simulation's ``pose_position_std_m`` and ``pose_yaw_std_rad``).

        Parameters
        ----------
        i : int
            Index into ``rec.amcl`` / ``rec.pose_t_ns``.

        Returns
        -------
        bytes
            Serialized ``geometry_msgs/PoseWithCovarianceStamped``.
        """
        r, p = self.rec, self.rec.params
        cov = np.zeros(36)
        cov[0] = cov[7] = p.pose_position_std_m**2
        cov[35] = p.pose_yaw_std_rad**2
        x, y, yaw = r.amcl[i]
        msg = self.T["geometry_msgs/msg/PoseWithCovarianceStamped"](
            header=self.header("/amcl_pose", int(r.pose_t_ns[i]), "map"),
            pose=self.pose(float(x), float(y), 0.0, float(yaw), cov),
        )
        return self.ser(msg, "geometry_msgs/msg/PoseWithCovarianceStamped")

    def odom(self, i: int) -> bytes:
        """The ``/odom`` message of odometry sample ``i`` (``odom`` -> ``base_link``).

        Parameters
        ----------
        i : int
            Index into ``rec.odom`` / ``rec.odom_t_ns``.

        Returns
        -------
        bytes
            Serialized ``nav_msgs/Odometry``.
        """
        T, r = self.T, self.rec
        x, y, yaw, v, w = (float(a) for a in r.odom[i])
        cov = np.zeros(36)
        cov[0] = cov[7] = cov[35] = 1e-3
        twist = T["geometry_msgs/msg/TwistWithCovariance"](
            twist=T["geometry_msgs/msg/Twist"](
                linear=T["geometry_msgs/msg/Vector3"](x=v, y=0.0, z=0.0),
                angular=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=w),
            ),
            covariance=cov.copy(),
        )
        msg = T["nav_msgs/msg/Odometry"](
            header=self.header("/odom", int(r.odom_t_ns[i]), "odom"),
            child_frame_id="base_link",
            pose=self.pose(x, y, 0.0, yaw, cov),
            twist=twist,
        )
        return self.ser(msg, "nav_msgs/msg/Odometry")

    def scan(self, k: int, ranges: np.ndarray, points: np.ndarray) -> bytes:
        """The ``/scan`` message of scan ``k``, frame ``laser``: a ``LaserScan`` for a 2D
        scanner, else a ``PointCloud2`` of little-endian float32 ``x, y, z``.

        Parameters
        ----------
        k : int
            Index into ``rec.scan_t_ns``.
        ranges : (R,) float ndarray
            The 2D scanner's ranges, metres.
        points : (N, 3) float ndarray
            The 3D scanner's points in the scanner frame, metres.

        Returns
        -------
        bytes
            Serialized message.
        """
        T, r, sc = self.T, self.rec, self.rec.scanner
        header = self.header("/scan", int(r.scan_t_ns[k]), "laser")
        if isinstance(sc, Scanner2D):
            msg = T["sensor_msgs/msg/LaserScan"](
                header=header,
                angle_min=sc.angle_min,
                angle_max=sc.angle_max,
                angle_increment=sc.angle_increment,
                time_increment=0.0,
                scan_time=1.0 / r.params.scan_rate_hz,
                range_min=sc.range_min_m,
                range_max=sc.range_max_m,
                ranges=np.ascontiguousarray(ranges, dtype=np.float32),
                intensities=np.zeros(0, dtype=np.float32),
            )
            return self.ser(msg, "sensor_msgs/msg/LaserScan")
        pf = T["sensor_msgs/msg/PointField"]
        fields_ = [pf(name=n, offset=4 * i, datatype=7, count=1) for i, n in enumerate("xyz")]
        msg = T["sensor_msgs/msg/PointCloud2"](
            header=header,
            height=1,
            width=len(points),
            fields=fields_,
            is_bigendian=False,
            point_step=12,
            row_step=12 * len(points),
            data=np.frombuffer(np.ascontiguousarray(points, dtype="<f4").tobytes(), dtype=np.uint8),
            is_dense=True,
        )
        return self.ser(msg, "sensor_msgs/msg/PointCloud2")

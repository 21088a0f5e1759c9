"""Registration: every kept scan in one map frame, refined by planar ICP (thesis 3.2.2, 3.5).

Algorithm 3 of the thesis, steps 2-6 (step 1, pose interpolation, is the ``poses`` stage):

2. keep every n-th scan (``every_n``) among the scans that pass the per-scan checks;
3. apply the localizer's pose (``map_point = Rz(yaw) @ p + (x, y, z)``);
4. fitness of the scan against each of the previous ``n_previous`` kept scans under the
   pose alone; drop the scan when the mean is below ``min_prior_fitness``;
5. refine the pose by ICP against a reference map (merged, voxel-downsampled scans);
6. drop the scan when the mean fitness after ICP is below ``min_icp_fitness``.

Step 5 departs from the thesis. The default, ``reference: graph``, is a pose graph of
scan-to-scan ICP edges with the localizer's poses as priors (:func:`_register_graph`,
:mod:`floorscan.register.posegraph`). The older ``reference: map`` works as follows. The thesis registers
"sequentially every two pointclouds" (3.5), i.e. each scan against its predecessors at
their localizer poses (kept as ``reference: previous``). An AMCL-like localizer error is
correlated in time (simulated: Gauss-Markov, 2 s correlation time, scans 0.5 s apart),
so the predecessors carry nearly the same error as the scan and ICP cannot see it
(measured on the synthetic demo: RMS position error 7.58 -> 7.43 cm). The field's
practice for this is a multiway / scan-to-map alignment over the whole recording (the
thesis's own pointer, Choi et al. 2015 [9], Open3D multiway registration; lighter here):
every sampled scan is aligned by ICP to a map of the spatially nearby, overlapping
sampled scans from anywhere in the recording, except those within ``exclude_window_s``
of it in time (whose errors are correlated with its own), at their current estimates.
Passes are Jacobi-style (all scans against the previous pass's poses, a relaxed step of
``relaxation`` toward the ICP pose), which averages independent localizer errors; the
gauge (one rigid motion of the whole map, which the scans cannot see) is fixed after
every pass by making the mean correction over all registered scans zero (mean yaw
difference, then mean x, y difference to the localizer), so the map does not drift and
stays in the localizer's frame. Measured (RMS position / yaw error of kept scans vs the
simulator's truth): demo 7.58 -> 4.26 cm, 1.08 -> 0.82 deg; hallways (5000 scans)
6.92 -> 4.18 cm, 1.15 -> 0.74 deg. Fitness (steps 4 and 6) stays the thesis's: mean over
the previous ``n_previous`` sampled scans.

Fitness and inlier RMSE are Open3D's definitions (``evaluate_registration``): the
fraction of *source* points whose nearest target point is within the correspondence
distance, and the RMS distance of those pairs. They are computed here with one
:class:`scipy.spatial.cKDTree` per kept scan, built once and reused by the next
``n_previous`` scans (Open3D rebuilds its KD-tree on every call); a unit test checks the
numbers against ``open3d.pipelines.registration.evaluate_registration``.

ICP is constrained to the rover's planar motion (x, y, yaw; z, roll and pitch stay as the
pose says) for 2D and 3D scans. Open3D's ICP estimates all six degrees of freedom and
offers no way to fix some of them; for 2D scans its point-to-plane variant is degenerate
(normals of a planar point set are vertical), and projecting a 6-DoF result onto SE(2)
is not the constrained optimum for 3D scans. So correspondences come from the cached
KD-tree and each iteration solves the planar problem in closed form: the 2D Kabsch /
Umeyama solution for point-to-point (exact for 3D pairs too, since the z residual does
not depend on x, y, yaw), a 3x3 linearised least-squares step for point-to-plane
(Chen & Medioni 1992; Low 2004). For 2D scans point-to-point gives the same result as
Open3D's ``registration_icp`` (tested).

3D scans (thesis: 2D only; choices made here, see :func:`scan_clouds` and
:func:`graph_cloud`): horizontal surfaces (floor, ceiling) are dropped from ICP, since
they say nothing about x, y, yaw and bias planar point-to-point ICP toward zero motion;
``map``, ``previous`` and odometry also run ICP on a coarse voxel grid
(``icp_voxel_size_3d_m``), fitness on the coarse grid against references on the fine
one (``voxel_size_m``). Measured on hallways3d (1017 sampled scans, RMS position / yaw
error against the truth; localizer 6.92 cm, 1.15 deg): ``graph`` with floor and
ceiling 8.59 cm, 0.39 deg at 1.4 scans/s, without 1.75 cm, 0.12 deg at 2.8 scans/s;
``map`` before 4.11 cm, 0.62 deg at 0.7 scans/s (first 150 scans: 1.0 -> 10 scans/s,
4.2 -> 4.0 cm). Since issue 8 the pose graph aligns the points projected to the xy plane
on a 5 cm 2D grid (:func:`graph_cloud`, the ``pointcloud_to_laserscan`` practice),
first without the horizontal surfaces by their normals: 1.86 cm, 0.18 deg at 29 scans/s
(35 s CPU for the stage); now keeping the grid cells whose points span 0.2 m of height
(the 2.5D elevation map's obstacle test, no normals): 1.57 cm, 0.12 deg, 11 -> 4 ms
per scan.

Issue 8 (speed and scale): the stage streams its points (:func:`register_recording`):
memory follows the largest scan, not the recording. Measured (register stage, one
thread, CPU time / peak RSS, before -> after): hallways3d (5081 x 14400 points) 569 s /
6.4 GB -> 35 s / 1.0 GB; hallways 2D (5081 x 1081) 34 s / 1.8 GB -> 13 s / 1.0 GB;
demo 5.6 s -> 2.7 s; RMS errors unchanged within 0.1 cm (hallways 1.87 -> 1.86 cm).

Pose-free mode (``mode: odometry``; the issue's "scan-to-scan ICP odometry from the
first scan", not in the thesis) follows the practice of LIDAR odometry, KISS-ICP
(Vizzo et al. 2023) in SE(2): the first usable scan defines the map frame; every usable
scan (``odometry_scans: all``; ``sampled``: only the every-n-th) is predicted by a
constant-velocity model from the last two poses and their time stamps, registered
coarse to fine (an adaptive first distance, 3 sigma of the model's deviations so far,
then ``icp_max_correspondence_m``) against a local map of the last ``odometry_window``
keyframes (a scan becomes one after ``odometry_keyframe_m`` / ``odometry_keyframe_rad``
of motion; matching against the same keyframes for several scans drifts less than
against the previous scan), with point-to-line ICP (``odometry_icp_method``; PL-ICP,
Censi 2008: point-to-point is biased toward zero motion along corridors). Fitness is
measured against the local map (its union, not scan by scan: a scan at a turn overlaps
the union well and any single predecessor poorly) and never drops a scan by itself: a
scan whose ICP finds no correspondences is ``icp_failed`` and the chain goes on from
its prediction; one below ``min_icp_fitness`` is dropped as ``low_icp_fitness`` but its
ICP pose carries the chain and the map (the best estimate there is; continuing from
predictions into unmapped space loses track). Not-sampled scans get their odometry
pose in the table and are not kept. With ``loop_closure`` the kept scans then go
through the pose graph (first scan held) so that revisits remove drift. Measured (all
sampled scans kept; drift after aligning the first pose, median / final; without
loop closure in brackets): trace0 0.23 / 0.19 m of 32.8 m, 0.6 % (0.25 / 0.32 m)
against its localizer; mac_ros2 0.09 / 0.22 m of 8.3 m (0.11 / 0.20 m) against its
wheel odometry; demo 1.2 / 4.8 cm (1.5 / 1.7 cm) against the truth. The
previous scan-to-scan version kept 27 of 72 scans on mac_ros2 and drifted 1.9 m
(median) on trace0. Part of trace0's figure is its localizer's: pairwise ICP of
scans 2 s apart disagrees with the localizer's relative yaw by up to 5 degrees and
with the odometry's by under 1 degree mostly.

Drop reasons (``reason`` column; kept scans have ``""``, or ``"anchor"`` for a scan kept
without a reference, and the first scan in odometry mode):

- ``no_pose:<reason>``: the poses table has no valid pose (reason from ``poses``);
- ``duplicate``: same timestamp as the previous scan, or exactly the same points;
- ``too_few_points``: fewer than ``min_points`` points;
- ``pose_jump``: the pose moved faster than ``max_speed_m_s`` or turned faster than
  ``max_turn_rate_rad_s`` since the last plausible pose;
- ``not_sampled``: skipped by the every-n-th rule (not a failure);
- ``low_prior_fitness`` / ``low_icp_fitness``: steps 4 and 6 (odometry mode: no prior
  check; ``fitness_prior`` is then the fitness at the constant-velocity prediction);
- ``icp_failed``: ICP found fewer than 3 correspondences.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import os
from collections import Counter, deque
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, NamedTuple

import numpy as np
import pandas as pd
import pyarrow as pa
from scipy.spatial import cKDTree

from floorscan.core.runtime import progress
from floorscan.core.grid import cell_groups, cell_keys, cell_means
from floorscan.core.io import InputError
from floorscan.register.sampling import EveryN, MotionFilter, median_step_m

log = logging.getLogger(__name__)

#: 3D scans: ICP points whose normal has |z| above this (within 45 degrees of vertical,
#: floor and ceiling) are dropped (:func:`scan_clouds`).
_MAX_NORMAL_Z = 0.7

#: One row per scan of ``scan_index`` (``registration.parquet``).
REGISTRATION = pa.schema(
    [
        ("scan_id", pa.int32()),
        ("t_ns", pa.int64()),
        ("kept", pa.bool_()),
        ("reason", pa.string()),
        ("fitness_prior", pa.float64()),
        ("fitness_icp", pa.float64()),
        ("inlier_rmse_m", pa.float64()),
        ("dx_m", pa.float64()),
        ("dy_m", pa.float64()),
        ("dyaw_rad", pa.float64()),
        ("x_m", pa.float64()),
        ("y_m", pa.float64()),
        ("z_m", pa.float64()),
        ("yaw_rad", pa.float64()),
    ]
)

#: Config key behind each failure reason, for the "every scan dropped" error.
REASON_THRESHOLD = {
    "too_few_points": "min_points",
    "pose_jump": "max_speed_m_s / max_turn_rate_rad_s",
    "low_prior_fitness": "min_prior_fitness",
    "low_icp_fitness": "min_icp_fitness",
    "icp_failed": "icp_max_correspondence_m",
    "duplicate": "(duplicate scans: no threshold)",
    "no_pose": "(poses stage: no valid pose)",
}


class RegistrationError(ValueError):
    """No scan could be registered; the message counts the drops per reason and names
    the config threshold responsible for most of them."""


@dataclass(frozen=True)
class RegistrationConfig:
    """Parameters of the ``register`` stage; keys and defaults match
    ``workflow/schemas/register.schema.yaml`` (a test checks they agree).

    See the schema for each key's description, bounds and the reasons for the defaults.
    """

    mode: str = "auto"
    reference: str = "graph"
    every_n: int | None = None
    keep_distance_m: float | None = None
    keep_angle_rad: float | None = None
    keep_range_fraction: float = 0.1
    min_kept_fraction: float = 0.2
    min_consistency: float = 0.3
    n_previous: int = 5
    min_points: int = 30
    fitness_max_correspondence_m: float = 0.15
    min_prior_fitness: float = 0.15
    min_icp_fitness: float = 0.25
    icp_method: str = "point_to_point"
    icp_max_correspondence_m: tuple[float, ...] = (0.3, 0.15)
    icp_max_iterations: int = 30
    icp_tolerance_m: float = 1e-5
    voxel_size_m: float = 0.05
    normal_neighbours: int = 10
    max_reference_distance_m: float = 8.0
    reference_pose: str = "localizer"
    n_references: int = 8
    exclude_window_s: float = 3.0
    reference_spacing_s: float = 1.0
    passes: int = 3
    relaxation: float = 0.5
    max_speed_m_s: float = 2.0
    max_turn_rate_rad_s: float = 3.0
    pose_jump_slack_m: float = 0.1
    pose_jump_slack_rad: float = 0.1
    icp_voxel_size_3d_m: float = 0.2
    odometry_scans: str = "all"
    odometry_icp_method: str = "point_to_plane"
    odometry_window: int = 20
    odometry_keyframe_m: float = 0.25
    odometry_keyframe_rad: float = 0.2
    odometry_max_correspondence_m: float = 1.0
    graph: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    loop_closure: bool = True

    @classmethod
    def from_mapping(cls, cfg: Mapping[str, Any] | None) -> "RegistrationConfig":
        """Build from a config dict (the ``register`` section), rejecting unknown keys.

        Raises
        ------
        InputError
            On an unknown key or a value outside its range.
        """
        cfg = dict(cfg or {})
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(cfg) - names)
        if unknown:
            raise InputError(f"config register: unknown keys {unknown}; known: {sorted(names)}")
        if "icp_max_correspondence_m" in cfg and not isinstance(cfg["icp_max_correspondence_m"], (int, float)):
            cfg["icp_max_correspondence_m"] = tuple(float(v) for v in cfg["icp_max_correspondence_m"])
        out = cls(**cfg)
        out.check()
        return out

    def check(self) -> None:
        """Raise :class:`InputError` naming the key when a value is out of range."""
        if self.mode not in ("auto", "pose", "odometry"):
            raise InputError(f"config register.mode: expected 'auto', 'pose' or 'odometry', got {self.mode!r}")
        if self.every_n is not None and int(self.every_n) < 1:
            raise InputError(f"config register.every_n: expected >= 1 or null, got {self.every_n}")
        for key in ("keep_distance_m", "keep_angle_rad"):
            v = getattr(self, key)
            if v is not None and not (math.isfinite(v) and v >= 0):
                raise InputError(f"config register.{key}: expected >= 0 or null (chosen from the recording), got {v}")
        if not 0.0 < self.keep_range_fraction <= 1.0:
            raise InputError(f"config register.keep_range_fraction: expected 0 < value <= 1, got {self.keep_range_fraction}")
        for key in ("min_kept_fraction", "min_consistency"):
            if not 0.0 <= getattr(self, key) <= 1.0:
                raise InputError(f"config register.{key}: expected 0..1, got {getattr(self, key)}")
        if self.reference not in ("graph", "map", "previous"):
            raise InputError(
                f"config register.reference: expected 'graph', 'map' or 'previous', got {self.reference!r}"
            )
        from floorscan.register.posegraph import GraphParams

        try:
            GraphParams.from_mapping(self.graph)
        except (KeyError, TypeError) as exc:
            raise InputError(f"config register.graph: {exc}") from None
        if not 0.0 < self.relaxation <= 1.0:
            raise InputError(f"config register.relaxation: expected 0 < value <= 1, got {self.relaxation}")
        if self.reference_pose not in ("localizer", "registered"):
            raise InputError(
                "config register.reference_pose: expected 'localizer' or 'registered', "
                f"got {self.reference_pose!r}"
            )
        if self.icp_method not in ("point_to_point", "point_to_plane"):
            raise InputError(
                "config register.icp_method: expected 'point_to_point' or 'point_to_plane', "
                f"got {self.icp_method!r}"
            )
        if self.odometry_scans not in ("all", "sampled"):
            raise InputError(
                f"config register.odometry_scans: expected 'all' or 'sampled', got {self.odometry_scans!r}"
            )
        if self.odometry_icp_method not in ("point_to_point", "point_to_plane"):
            raise InputError(
                "config register.odometry_icp_method: expected 'point_to_point' or 'point_to_plane', "
                f"got {self.odometry_icp_method!r}"
            )
        for key in ("n_previous", "n_references", "passes", "icp_max_iterations", "odometry_window"):
            if int(getattr(self, key)) < 1:
                raise InputError(f"config register.{key}: expected >= 1, got {getattr(self, key)}")
        if self.normal_neighbours < 3:
            raise InputError(f"config register.normal_neighbours: expected >= 3, got {self.normal_neighbours}")
        for key in ("min_prior_fitness", "min_icp_fitness"):
            v = getattr(self, key)
            if not 0.0 <= v <= 1.0:
                raise InputError(f"config register.{key}: expected 0..1, got {v}")
        for key in (
            "fitness_max_correspondence_m",
            "icp_tolerance_m",
            "max_reference_distance_m",
            "max_speed_m_s",
            "max_turn_rate_rad_s",
            "odometry_max_correspondence_m",
            "icp_voxel_size_3d_m",
        ):
            if not getattr(self, key) > 0:
                raise InputError(f"config register.{key}: expected > 0, got {getattr(self, key)}")
        d = self.icp_max_correspondence_m
        if isinstance(d, (int, float)) or len(d) == 0 or any(not v > 0 for v in d):
            raise InputError(
                f"config register.icp_max_correspondence_m: expected a non-empty list of "
                f"distances > 0 (metres, coarse to fine), got {d!r}"
            )
        for key in ("voxel_size_m", "pose_jump_slack_m", "pose_jump_slack_rad", "min_points",
                    "exclude_window_s", "reference_spacing_s",
                    "odometry_keyframe_m", "odometry_keyframe_rad"):
            if getattr(self, key) < 0:
                raise InputError(f"config register.{key}: expected >= 0, got {getattr(self, key)}")


@dataclass
class RegistrationResult:
    """Output of :func:`register_scans`.

    Attributes
    ----------
    registered : pandas.DataFrame
        ``scan_id`` int32, ``x, y, z`` float32: points of the kept scans in the map frame
        (metres), in scan order.
    table : pandas.DataFrame
        One row per scan of the scan index, columns of :data:`REGISTRATION`.
    summary : dict
        Counts per reason, drop fractions per threshold, median corrections.
    """

    registered: pd.DataFrame | None
    table: pd.DataFrame
    summary: dict


# --------------------------------------------------------------------------- geometry


def wrap_angle(a: np.ndarray | float) -> np.ndarray | float:
    """Wrap angles (radians) to [-pi, pi)."""
    return (np.asarray(a) + np.pi) % (2.0 * np.pi) - np.pi


def se2_between(a, b) -> tuple[float, float, float]:
    """Planar motion (dx, dy, dyaw) from pose ``a`` to pose ``b``, in ``a``'s frame.

    Poses are ``(x, y, z, yaw)`` or ``(x, y, yaw)`` sequences; metres, radians.
    """
    ya, yb = a[-1], b[-1]
    c, s = math.cos(ya), math.sin(ya)
    dx, dy = b[0] - a[0], b[1] - a[1]
    return c * dx + s * dy, -s * dx + c * dy, float(wrap_angle(yb - ya))


def transform_points(points: np.ndarray, x: float, y: float, z: float, yaw: float) -> np.ndarray:
    """Apply a planar pose to points: ``Rz(yaw) @ p + (x, y, z)``.

    Parameters
    ----------
    points : (N, 3) float ndarray
        Points in the scanner frame, metres.
    x, y, z : float
        Scanner position in the map frame, metres.
    yaw : float
        Heading, radians CCW from +x.

    Returns
    -------
    (N, 3) float64 ndarray
        New array of points in the map frame.
    """
    c, s = math.cos(yaw), math.sin(yaw)
    p = np.asarray(points, dtype=np.float64)
    out = np.empty((len(p), 3), dtype=np.float64)
    out[:, 0] = c * p[:, 0] - s * p[:, 1] + x
    out[:, 1] = s * p[:, 0] + c * p[:, 1] + y
    out[:, 2] = p[:, 2] + z
    return out


def voxel_downsample(points: np.ndarray, voxel_size: float) -> np.ndarray:
    """Mean of the points in each occupied voxel (cubes of side ``voxel_size``).

    Deterministic (voxels in lexicographic order of their integer keys), same result as
    Open3D's ``voxel_down_sample`` up to point order. ``voxel_size <= 0`` returns a copy.

    Parameters
    ----------
    points : (N, 3) float ndarray
        Metres.
    voxel_size : float
        Voxel side, metres.

    Returns
    -------
    (M, 3) float64 ndarray, M <= N
    """
    p = np.asarray(points, dtype=np.float64)
    if voxel_size <= 0 or len(p) == 0:
        return p.copy()
    return cell_means(p, voxel_size)[0]


def normals_2d(points: np.ndarray, tree: cKDTree, k: int) -> np.ndarray:
    """Unit normals in the xy plane of a 2D scan or map, from PCA of k nearest neighbours.

    Open3D's ``estimate_normals`` returns the plane normal (z) for coplanar points, which
    is useless for 2D point-to-plane ICP; this is its 2D counterpart.

    Parameters
    ----------
    points : (N, 3) float64 ndarray
        Points (z ignored), metres; ``tree`` is built on their xy (or xyz with z = 0).
    tree : scipy.spatial.cKDTree
    k : int
        Neighbours per point (including itself).

    Returns
    -------
    (N, 3) float64 ndarray
        Normals with z = 0.
    """
    k = int(min(k, len(points)))
    _, idx = tree.query(points, k=k)
    nb = points[np.asarray(idx).reshape(len(points), k)][:, :, :2]
    nb = nb - nb.mean(axis=1, keepdims=True)
    cov = np.einsum("nki,nkj->nij", nb, nb)
    _, vecs = np.linalg.eigh(cov)
    n = np.zeros((len(points), 3))
    n[:, :2] = vecs[:, :, 0]
    return n


def normals_3d(points: np.ndarray, k: int) -> np.ndarray:
    """Unit normals of a 3D point cloud (Open3D ``estimate_normals``, k nearest neighbours).

    Returns
    -------
    (N, 3) float64 ndarray
    """
    import open3d as o3d

    from floorscan.register.posegraph import _one_openmp_thread

    pc = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(np.asarray(points, dtype=np.float64)))
    with _one_openmp_thread():  # deterministic, and less CPU time on shared cores
        pc.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=int(k)))
    return np.asarray(pc.normals).copy()


class ScanClouds(NamedTuple):
    """The clouds of one scan used by registration (scanner frame, float64 metres):
    ``fit_source`` is the scan whose fitness is measured, ``fit_target`` the scan as a
    fitness reference, ``icp`` the ICP source and, placed, the material of the ICP
    targets of other scans."""

    fit_source: np.ndarray
    fit_target: np.ndarray
    icp: np.ndarray


def scan_clouds(points: np.ndarray, cfg: RegistrationConfig) -> ScanClouds:
    """The clouds of a scan used for fitness and ICP (see :class:`ScanClouds`).

    2D scans (z constant): all points for fitness (source and reference), the points on
    the ``voxel_size_m`` grid for ICP, as the thesis (3.5) fits raw 2D scans.

    3D scans (a 16-beam scan has ~14k points): as fitness reference the scan on the
    ``voxel_size_m`` grid; as fitness source and for ICP the coarser
    ``icp_voxel_size_3d_m`` grid. A coarse source against a fine reference keeps the
    fitness unbiased (a voxel centroid of a surface lies on it, and the fine reference
    has a point near it) while the KD-tree queries drop from ~6k to ~1k per scan; the
    fitness becomes the fraction of occupied voxels, not of points, so near ranges weigh
    less. ICP also drops horizontal surfaces: points whose normal (Open3D,
    ``normal_neighbours``) is within 45 degrees of vertical (|n_z| > 0.7). The ICP is
    planar (x, y, yaw) and floor and ceiling carry no information about it: a floor point
    matched to the nearest floor point of another scan only pulls the pose toward zero
    motion (the sampling bias of point-to-point ICP) and costs a query per iteration.
    ICP targets are the other scans' ICP clouds, placed and merged: on hallways3d (300
    sampled scans) more accurate and faster than targets on the fine grid (RMS 3.75 vs
    4.01 cm, 11 vs 7.6 scans/s). None of this is in the thesis (its scans are 2D);
    LOAM-style odometry likewise
    registers selected geometric features only (Zhang and Singh 2014), KISS-ICP a
    voxel-downsampled scan (Vizzo et al. 2023).

    Parameters
    ----------
    points : (N, 3) float ndarray
        Scanner frame, metres.
    cfg : RegistrationConfig

    Returns
    -------
    ScanClouds
        New arrays; for a 2D scan ``fit_source`` and ``fit_target`` are one array.
    """
    p = np.array(points, dtype=np.float64)
    if len(p) == 0 or np.ptp(p[:, 2]) == 0:
        return ScanClouds(p, p, voxel_downsample(p, cfg.voxel_size_m))
    coarse, vertical, _ = _vertical_voxels(p, cfg)
    return ScanClouds(coarse, voxel_downsample(p, cfg.voxel_size_m), coarse[vertical])


def _vertical_voxels(p: np.ndarray, cfg: RegistrationConfig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A 3D scan on the ``icp_voxel_size_3d_m`` grid: voxel centroids, which voxels are
    not horizontal surfaces (normal |z| <= 0.7; all when too few are), and each point's
    voxel (index into the centroids)."""
    coarse, inverse = cell_means(p, cfg.icp_voxel_size_3d_m)
    vertical = np.ones(len(coarse), dtype=bool)
    if len(coarse) > cfg.normal_neighbours:
        v = np.abs(normals_3d(coarse, cfg.normal_neighbours)[:, 2]) <= _MAX_NORMAL_Z
        if v.sum() >= 3:
            vertical = v
    return coarse, vertical, inverse


def graph_cloud(points: np.ndarray, cfg: RegistrationConfig) -> np.ndarray:
    """The points of a scan the pose graph (``reference: graph``) aligns, in the xy plane.

    A 2D scan: all its points. A 3D scan: projected to the xy plane (z = 0) on a 2D grid
    of ``graph.voxel_size_m``, keeping the cells whose points span at least
    ``graph.vertical_extent_m`` in height without a gap wider than
    ``graph.max_height_gap_m`` (the vertical structures: walls, furniture sides), each
    as the mean of its points. The pose refinement is planar (x, y, yaw),
    so the walls' heights carry nothing for it, and the projection is the standard
    practice of 2D SLAM on a 3D LIDAR (``pointcloud_to_laserscan``). Floor and ceiling
    drop out: a floor cell holds the returns of one beam ring at one height, while the
    beams stacked at one azimuth hit a wall cell at many heights (a 16-beam scanner's
    2-degree spacing is 3.5 cm of height per metre of range). They must drop out,
    because a floor point matched to the nearest floor point of another scan pulls the
    planar ICP toward zero motion. The gap limit keeps out the cells where a ring of
    floor returns and a ring of ceiling returns happen to meet in xy (their extent is
    the room height: a ring of such cells would move with the scanner and pull the ICP
    toward zero motion as the floor does) and doorways (floor and lintel), and keeps a
    box side with the ceiling above it. The 0.5 m default keeps a wall of a 2-degree
    16-beam scanner to 14 m range. This height-extent
    test is the obstacle test of 2.5D elevation maps, a cell's max minus min height
    (e.g. Fankhauser et al. 2014). The edge ICP then runs as for a 2D scan.

    Measured on hallways3d (1017 sampled scans of 5081; RMS position / yaw error of the
    kept scans against the simulator's truth; whole stage):

    - raw 3D points: 1.75 cm, 0.12 deg, 569 s CPU, 6.4 GB RSS;
    - projected after dropping the horizontal surfaces by their Open3D normals on a
      0.2 m voxel grid (the previous version): 1.86 cm, 0.18 deg, ~11 ms per scan;
    - projected with the height-extent test: 1.57 cm, 0.12 deg, ~1.7 ms per scan, ~570
      cells of ~1k before (without the gap limit 1.55 cm, 0.16 deg, within 0.01 cm for
      a 0.1, 0.2 or 0.3 m extent);
    - the localizer: 6.92 cm, 1.15 deg.

    Parameters
    ----------
    points : (N, 3) float ndarray
        Scanner frame, metres.
    cfg : RegistrationConfig

    Returns
    -------
    (M, 3) float64 ndarray
        New array: a 2D scan's points (M = N), or a 3D scan's kept cell means with
        z = 0 (M much smaller than N: ~14k points -> ~570 on hallways3d), cells in
        lexicographic order; with ``graph.voxel_size_m`` 0 the points of the kept
        0.05 m cells themselves.
    """
    p = np.array(points, dtype=np.float64)
    if len(p) == 0 or np.ptp(p[:, 2]) == 0:
        return p
    from floorscan.register.posegraph import GraphParams

    params = GraphParams.from_mapping(cfg.graph)
    cell = params.voxel_size_m if params.voxel_size_m > 0 else 0.05
    xy_cells = np.floor(p[:, :2] / cell).astype(np.int64)
    key = cell_keys(xy_cells)
    if key is None:  # an extent beyond the int64 key: the cells' ranks instead
        key = cell_groups(xy_cells)[0]
    order = _cell_height_order(key, p[:, 2])
    z, ks = p[order, 2], key[order]
    new_cell = np.ones(len(ks), dtype=bool)
    new_cell[1:] = ks[1:] != ks[:-1]
    cells = np.cumsum(new_cell) - 1
    inverse = np.empty(len(p), dtype=np.intp)
    inverse[order] = cells
    counts = np.diff(np.append(np.flatnonzero(new_cell), len(ks)))
    g = len(counts)
    # runs: the heights of a cell without a gap wider than max_height_gap_m
    start = np.ones(len(z), dtype=bool)
    start[1:] = (cells[1:] != cells[:-1]) | (np.diff(z) > params.max_height_gap_m)
    first = np.flatnonzero(start)
    last = np.append(first[1:] - 1, len(z) - 1)
    extent = np.zeros(g)
    np.maximum.at(extent, cells[first], z[last] - z[first])
    vertical = extent >= params.vertical_extent_m
    if params.voxel_size_m <= 0:
        q = p[vertical[inverse]]
        q[:, 2] = 0.0
        return q
    xy = np.column_stack([np.bincount(inverse, weights=p[:, i], minlength=g) for i in (0, 1)]) / counts[:, None]
    return np.column_stack([xy[vertical], np.zeros(int(vertical.sum()))])


def _cell_height_order(key: np.ndarray, z: np.ndarray) -> np.ndarray:
    """The order of the points by cell key, then height: ``numpy.lexsort((z, key))``
    up to the order of equal heights in a cell. Heights that are float32 values (as
    ``scans.parquet`` stores them) and keys below 2**31 make one int64 key, the cell
    above the float32 bits mapped to an order-preserving unsigned integer, sorted in
    one argsort: 0.2 instead of 2.1 ms for a 14k-point scan (the lexsort was most of
    :func:`graph_cloud`'s time)."""
    z32 = z.astype(np.float32)
    if len(key) == 0 or int(key.max()) >= 2**31 or not np.array_equal(z32, z):
        return np.lexsort((z, key))
    bits = z32.view(np.uint32).astype(np.int64)
    # IEEE order: negative floats reversed below the positive ones
    ordered = np.where(bits >= 2**31, 2**32 - 1 - bits, bits + 2**31)
    return np.argsort((key.astype(np.int64) << 32) | ordered)


def fitness_against(
    source_map: np.ndarray, tree: cKDTree, max_distance: float
) -> tuple[float, float, int]:
    """Open3D-style fitness and inlier RMSE of points against a target's KD-tree.

    Parameters
    ----------
    source_map : (N, 3) float64 ndarray
        Source points already in the target's frame, metres.
    tree : scipy.spatial.cKDTree
        KD-tree of the target points (built once per target and reused).
    max_distance : float
        Maximum correspondence distance, metres.

    Returns
    -------
    fitness : float
        Fraction of source points with a target point within ``max_distance`` (0..1).
    inlier_rmse : float
        RMS distance of those pairs, metres (NaN without any).
    n_inliers : int
    """
    if len(source_map) == 0:
        return 0.0, math.nan, 0
    d, _ = tree.query(source_map, k=1, distance_upper_bound=max_distance)
    ok = d <= max_distance
    n = int(ok.sum())
    rmse = float(np.sqrt(np.mean(d[ok] ** 2))) if n else math.nan
    return n / len(source_map), rmse, n


def _kabsch_2d(src: np.ndarray, dst: np.ndarray) -> tuple[float, float, float]:
    """Rigid 2D transform (tx, ty, theta) minimising sum ||dst - (R src + t)||^2 (Umeyama)."""
    ms, md = src.mean(axis=0), dst.mean(axis=0)
    h = (src - ms).T @ (dst - md)  # 2x2 cross-covariance
    th = math.atan2(float(h[0, 1] - h[1, 0]), float(h[0, 0] + h[1, 1]))
    c, s = math.cos(th), math.sin(th)
    tx = md[0] - (c * ms[0] - s * ms[1])
    ty = md[1] - (s * ms[0] + c * ms[1])
    return tx, ty, th


def _point_to_plane_2d(src: np.ndarray, dst: np.ndarray, nrm: np.ndarray) -> tuple[float, float, float]:
    """One linearised point-to-plane step for planar motion (tx, ty, theta) (Low 2004).

    Minimises sum (n . (R src + t - dst))^2 with R ~ I + theta [[0,-1],[1,0]] (z rows of
    the rotation are identity, so z enters only through the normal's z component).
    """
    jac = np.empty((len(src), 3))
    jac[:, :2] = nrm[:, :2]
    jac[:, 2] = nrm[:, 1] * src[:, 0] - nrm[:, 0] * src[:, 1]
    r = np.einsum("ij,ij->i", nrm, dst - src)
    a = jac.T @ jac
    # Tiny Levenberg damping keeps a degenerate geometry (one straight wall) solvable:
    # the unobservable direction stays put instead of exploding.
    a[np.diag_indices(3)] += 1e-9 * max(float(np.trace(a)), 1e-12)
    tx, ty, th = np.linalg.solve(a, jac.T @ r)
    return float(tx), float(ty), float(th)


def icp_planar(
    source: np.ndarray,
    target: np.ndarray,
    tree: cKDTree,
    init: tuple[float, float, float, float],
    max_distance: float,
    *,
    method: str = "point_to_point",
    normals: np.ndarray | None = None,
    max_iterations: int = 30,
    tolerance: float = 1e-5,
) -> tuple[tuple[float, float, float, float], int]:
    """ICP constrained to x, y, yaw (planar rover; z, roll, pitch fixed), thesis 3.2.2.

    Each iteration pairs every transformed source point with its nearest target point
    within ``max_distance`` (cached KD-tree) and solves the planar problem in closed form.

    Parameters
    ----------
    source : (N, 3) float64 ndarray
        Source points in the scanner frame, metres.
    target : (M, 3) float64 ndarray
        Target points in the map frame, metres; ``tree`` is their KD-tree.
    tree : scipy.spatial.cKDTree
    init : tuple of float
        Initial pose (x, y, z, yaw): metres, radians. z is kept.
    max_distance : float
        Maximum correspondence distance, metres.
    method : {"point_to_point", "point_to_plane"}
    normals : (M, 3) float64 ndarray, optional
        Target normals, required for point-to-plane.
    max_iterations : int
    tolerance : float
        Stop when the step moves no source point (within the scan's extent) by more
        than this, metres.

    Returns
    -------
    pose : tuple of float
        Refined (x, y, z, yaw).
    n_correspondences : int
        Pairs in the last iteration (0: ICP failed, the initial pose is returned).

    Raises
    ------
    ValueError
        For point-to-plane without ``normals``.
    """
    if method == "point_to_plane" and normals is None:
        raise ValueError("point_to_plane ICP needs target normals")
    x, y, z, yaw = (float(v) for v in init)
    src = np.asarray(source, dtype=np.float64)
    extent = float(np.max(np.abs(src[:, :2]))) if len(src) else 1.0
    n_corr = 0
    for _ in range(int(max_iterations)):
        cur = transform_points(src, x, y, z, yaw)
        d, idx = tree.query(cur, k=1, distance_upper_bound=max_distance)
        ok = d <= max_distance
        n_corr = int(ok.sum())
        if n_corr < 3:
            return (float(init[0]), float(init[1]), float(init[2]), float(init[3])), 0
        q, p = cur[ok], target[idx[ok]]
        if method == "point_to_point":
            tx, ty, th = _kabsch_2d(q[:, :2], p[:, :2])
        else:
            tx, ty, th = _point_to_plane_2d(q, p, normals[idx[ok]])
        # compose the step (applied in the map frame) with the current pose
        c, s = math.cos(th), math.sin(th)
        x, y = c * x - s * y + tx, s * x + c * y + ty
        yaw = float(wrap_angle(yaw + th))
        if math.hypot(tx, ty) + abs(th) * extent < tolerance:
            break
    return (x, y, z, yaw), n_corr


# --------------------------------------------------------------------------- screening


def _check_columns(df: pd.DataFrame, name: str, columns: list[str]) -> None:
    missing = [c for c in columns if c not in df.columns]
    if missing:
        raise InputError(f"{name}: columns {missing} missing; expected {columns}")


def screen_scans(
    index: pd.DataFrame,
    clouds: Mapping[int, np.ndarray],
    poses: pd.DataFrame | None,
    cfg: RegistrationConfig,
) -> np.ndarray:
    """Per-scan checks before sampling: missing pose, duplicate, too few points, pose jump.

    Parameters
    ----------
    index : pandas.DataFrame
        ``scan_id``, ``t_ns`` sorted by ``scan_id`` (recording order).
    clouds : mapping of int to (N, 3) ndarray
        Points of each scan (scanner frame); absent scans have no points.
    poses : pandas.DataFrame or None
        Aligned with ``index`` (same order): ``x, y, z, yaw, valid, reason``. None in
        odometry mode (no pose checks).
    cfg : RegistrationConfig

    Returns
    -------
    (S,) object ndarray
        Reason per scan, ``""`` for scans that pass.
    """
    screen = _Screener(index, poses, cfg)
    for i, sid in enumerate(index["scan_id"].to_numpy()):
        screen.step(i, clouds.get(int(sid)))
    return screen.reasons


class _Screener:
    """The per-scan checks of :func:`screen_scans`, one scan at a time in recording
    order: every check depends on the scan and the scans before it only, so
    :func:`register_recording` screens while it streams the points."""

    def __init__(self, index: pd.DataFrame, poses: pd.DataFrame | None, cfg: RegistrationConfig):
        n = len(index)
        self.cfg = cfg
        self.reasons = np.full(n, "", dtype=object)
        self.t = index["t_ns"].to_numpy(np.int64)
        self.poses = poses
        if poses is not None:
            valid = poses["valid"].to_numpy(bool)
            for i in np.flatnonzero(~valid):
                r = str(poses["reason"].iloc[i]) or "invalid"
                self.reasons[i] = f"no_pose:{r}"
            self.px, self.py, self.pyaw = (poses[c].to_numpy(np.float64) for c in ("x", "y", "yaw"))
        self.prev = None  # the previous scan's points (duplicate check)
        self.last = None  # last plausible pose (pose-jump check)

    def step(self, i: int, pts: np.ndarray | None, points_unseen: bool = False) -> str:
        """Screen scan ``i`` (index position) with its points (None: no points);
        returns its reason (``""``: usable). ``points_unseen``: the points are not
        known yet and taken to pass (the scans expected to be usable, from the
        index and poses alone)."""
        cfg, reasons, t = self.cfg, self.reasons, self.t
        size = 0 if pts is None else len(pts)
        if reasons[i] == "":
            if i > 0 and t[i] == t[i - 1]:
                reasons[i] = "duplicate"
            elif points_unseen:
                pass
            elif size < max(cfg.min_points, 1):
                reasons[i] = "too_few_points"
            elif self.prev is not None and np.array_equal(pts, self.prev):
                reasons[i] = "duplicate"  # the same returns as the scan before
        self.prev = pts if size else None
        if self.poses is None or reasons[i].startswith("no_pose") or reasons[i] == "duplicate":
            return reasons[i]
        # pose jump: against the last plausible pose (a single outlier drops one scan; after
        # a relocalisation the scans resume once the jump fits the speed limit)
        last = self.last
        if last is not None:
            dt = (t[i] - t[last]) * 1e-9
            dist = math.hypot(self.px[i] - self.px[last], self.py[i] - self.py[last])
            turn = abs(float(wrap_angle(self.pyaw[i] - self.pyaw[last])))
            if (
                dt < 0
                or dist > cfg.max_speed_m_s * dt + cfg.pose_jump_slack_m
                or turn > cfg.max_turn_rate_rad_s * dt + cfg.pose_jump_slack_rad
            ):
                if reasons[i] == "":
                    reasons[i] = "pose_jump"
                return reasons[i]
        self.last = i
        return reasons[i]


class _ScanStore:
    """The clouds registration needs per scan (:func:`graph_cloud`, :func:`scan_clouds`
    and its ICP cloud), from the raw points (``raw``, computed on demand) or stored by
    :meth:`add` while streaming, which keeps only these small clouds (issue 8: memory
    follows the largest scan, not the recording)."""

    def __init__(self, cfg: RegistrationConfig, raw: Mapping[int, np.ndarray] | None = None):
        self.cfg = cfg
        self.raw = raw if raw is not None else {}
        self.stored: dict[str, dict[int, Any]] = {"graph": {}, "clouds": {}, "icp": {}}

    def add(self, sid: int, points: np.ndarray, needs: tuple[str, ...]) -> None:
        for kind in needs:
            self.stored[kind][sid] = self._compute(kind, points)

    def _compute(self, kind: str, points: np.ndarray):
        if kind == "graph":
            return graph_cloud(points, self.cfg)
        if kind == "clouds":
            return scan_clouds(points, self.cfg)
        return scan_clouds(points, self.cfg).icp

    def _get(self, kind: str, sid: int):
        got = self.stored[kind].get(sid)
        return got if got is not None else self._compute(kind, self.raw[sid])

    def graph(self, sid: int) -> np.ndarray:
        return self._get("graph", sid)

    def clouds(self, sid: int) -> ScanClouds:
        return self._get("clouds", sid)

    def icp(self, sid: int) -> np.ndarray:
        return self._get("icp", sid)

    def map_cloud(self, sid: int) -> np.ndarray:
        """The cloud the map's consistency is measured on: the graph cloud, or else the
        stored cloud there is (fitness reference, ICP cloud), or the graph cloud of the
        raw points."""
        for kind in ("graph", "clouds", "icp"):
            got = self.stored[kind].get(sid)
            if got is not None:
                return got.fit_target if kind == "clouds" else got
        return self.graph(sid)


# --------------------------------------------------------------------------- main loop


@dataclass
class _Kept:
    scan_id: int
    pose: tuple[float, float, float, float]
    points: np.ndarray  # fitness cloud, map frame, float64
    tree: cKDTree
    icp_points: np.ndarray  # ICP cloud, map frame


def _mean_fitness(
    pts_map: np.ndarray, refs: list[_Kept], max_distance: float
) -> tuple[float, float]:
    """Mean fitness over the references and the pooled inlier RMSE."""
    fits, sq, cnt = [], 0.0, 0
    for r in refs:
        f, rmse, k = fitness_against(pts_map, r.tree, max_distance)
        fits.append(f)
        if k:
            sq += rmse**2 * k
            cnt += k
    return float(np.mean(fits)), (math.sqrt(sq / cnt) if cnt else math.nan)


def _align_poses(index: pd.DataFrame, poses: pd.DataFrame) -> pd.DataFrame:
    _check_columns(poses, "poses.parquet", ["scan_id", "x", "y", "z", "yaw", "valid", "reason"])
    if poses["scan_id"].duplicated().any():
        raise InputError("poses.parquet: scan_id is not unique")
    p = poses.set_index("scan_id").reindex(index["scan_id"].to_numpy())
    missing = p["valid"].isna()
    if missing.any():
        raise InputError(
            f"poses.parquet: no row for {int(missing.sum())} scans of scan_index.parquet "
            f"(first scan_id {int(p.index[missing.to_numpy()][0])}); expected one row per scan"
        )
    p = p.reset_index()
    p["valid"] = p["valid"].astype(bool) & np.isfinite(p[["x", "y", "z", "yaw"]].to_numpy(float)).all(axis=1)
    p["reason"] = p["reason"].fillna("").astype(str)
    return p



def _register_sequential(sampled, clouds, sids, t, cfg, out) -> int:
    """Sequential registration (thesis 3.5 step 5, ``reference: previous``): each sampled
    scan against the previous ``n_previous`` kept scans. Fills the per-scan output arrays
    ``out`` in place; returns the number of anchors."""
    kept, reasons, fit_prior, fit_icp, rmse, corr, final = out
    window: deque[_Kept] = deque(maxlen=cfg.n_previous)
    n_anchor = 0
    for i in sampled:
        sid = int(sids[i])
        cl = clouds.clouds(sid)
        pts, src = cl.fit_source, cl.icp
        prior = tuple(float(v) for v in final[i])
        refs = [
            r
            for r in window
            if math.hypot(r.pose[0] - prior[0], r.pose[1] - prior[1]) <= cfg.max_reference_distance_m
        ]
        pose = prior
        if refs:
            pts_prior = transform_points(pts, *prior)
            fit_prior[i], _ = _mean_fitness(pts_prior, refs, cfg.fitness_max_correspondence_m)
            if fit_prior[i] < cfg.min_prior_fitness:
                reasons[i] = "low_prior_fitness"
                continue
            target = voxel_downsample(np.concatenate([r.icp_points for r in refs]), cfg.voxel_size_m)
            pose, n_corr = _icp_to_map(src, target, pose, cfg)
            if n_corr == 0:
                reasons[i] = "icp_failed"
                continue
            pts_map = transform_points(pts, *pose)
            fit_icp[i], rmse[i] = _mean_fitness(pts_map, refs, cfg.fitness_max_correspondence_m)
            corr[i] = (pose[0] - prior[0], pose[1] - prior[1], float(wrap_angle(pose[3] - prior[3])))
            if fit_icp[i] < cfg.min_icp_fitness:
                reasons[i] = "low_icp_fitness"
                continue
        else:
            corr[i] = 0.0
            reasons[i] = "anchor"
            n_anchor += 1
        kept[i] = True
        if reasons[i] != "anchor":
            reasons[i] = ""
        final[i] = pose
        ref_pose = prior if cfg.reference_pose == "localizer" else pose
        ref_pts = transform_points(cl.fit_target, *ref_pose)
        window.append(_Kept(sid, ref_pose, ref_pts, cKDTree(ref_pts), transform_points(cl.icp, *ref_pose)))
    return n_anchor


def _select_references(
    pose: np.ndarray,
    t_s: np.ndarray,
    active: np.ndarray,
    cfg: RegistrationConfig,
    placed: list[np.ndarray | None] | None = None,
    trees: list[cKDTree | None] | None = None,
) -> tuple[list[np.ndarray], int]:
    """References of every active scan for ``reference: map`` (see :func:`register_scans`).

    Candidates are the other active scans within ``max_reference_distance_m`` (by the
    current poses), nearest first. Kept: those at least ``exclude_window_s`` away in time
    from the scan, greedily thinned so that any two are ``reference_spacing_s`` apart in
    time, at most ``n_references``; with ``placed`` points and their KD-``trees`` (current
    poses), a candidate must also overlap the scan: fitness of the scan against it at least
    ``min_prior_fitness`` (a scan behind a wall is no reference). A scan with no candidate
    outside the window falls back
    to its nearest candidates inside it (their errors are correlated with its own, so they
    only make the map consistent). Returns the references (indices into ``pose``) per scan
    and the number of scans that fell back.
    """
    n = len(pose)
    out = [np.empty(0, dtype=np.int64)] * n
    idx = np.flatnonzero(active)
    if len(idx) < 2:
        return out, 0
    tree = cKDTree(pose[idx, :2])
    n_fallback = 0
    for j, near in zip(idx, tree.query_ball_point(pose[idx, :2], r=cfg.max_reference_distance_m)):
        cand = idx[np.asarray(near, dtype=np.int64)]
        cand = cand[cand != j]
        if len(cand) == 0:
            continue
        d = np.hypot(pose[cand, 0] - pose[j, 0], pose[cand, 1] - pose[j, 1])
        cand = cand[np.argsort(d, kind="stable")]
        far = cand[np.abs(t_s[cand] - t_s[j]) >= cfg.exclude_window_s]
        chosen: list[int] = []
        for c in far:
            if all(abs(t_s[c] - t_s[r]) >= cfg.reference_spacing_s for r in chosen) and (
                trees is None
                or fitness_against(placed[j], trees[c], cfg.fitness_max_correspondence_m)[0] >= cfg.min_prior_fitness
            ):
                chosen.append(int(c))
                if len(chosen) == cfg.n_references:
                    break
        if not chosen:
            chosen = [int(c) for c in cand[: cfg.n_references]]
            n_fallback += 1
        out[j] = np.asarray(chosen, dtype=np.int64)
    return out, n_fallback


def _previous_references(pose: np.ndarray, active: np.ndarray, cfg: RegistrationConfig) -> list[np.ndarray]:
    """The fitness references of each active scan in ``reference: map`` mode: as in the
    thesis (Algorithm 3 steps 4 and 6), the previous ``n_previous`` active scans within
    ``max_reference_distance_m``; for a scan without any (the first), the next ones."""
    idx = np.flatnonzero(active)
    out = [np.empty(0, dtype=np.int64)] * len(pose)
    for k, j in enumerate(idx):
        for cand in (idx[max(0, k - cfg.n_previous):k][::-1], idx[k + 1:k + 1 + cfg.n_previous]):
            d = np.hypot(pose[cand, 0] - pose[j, 0], pose[cand, 1] - pose[j, 1])
            cand = cand[d <= cfg.max_reference_distance_m]
            if len(cand):
                out[j] = cand
                break
    return out


def _fix_gauge(pose: np.ndarray, localizer: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Move the poses in ``mask`` rigidly so that their mean correction against the
    localizer is zero: mean yaw difference 0 (rotation about their centroid), then mean
    x, y difference 0. Returns a new array."""
    out = pose.copy()
    if not mask.any():
        return out
    m = np.flatnonzero(mask)
    dyaw = float(np.mean(wrap_angle(out[m, 3] - localizer[m, 3])))
    c0 = out[m, :2].mean(axis=0)
    c, s = math.cos(-dyaw), math.sin(-dyaw)
    rel = out[m, :2] - c0
    out[m, 0] = c0[0] + c * rel[:, 0] - s * rel[:, 1]
    out[m, 1] = c0[1] + s * rel[:, 0] + c * rel[:, 1]
    out[m, 3] = wrap_angle(out[m, 3] - dyaw)
    out[m, :2] += (localizer[m, :2] - out[m, :2]).mean(axis=0)
    return out


def _target_normals(target: np.ndarray, tree: cKDTree, cfg: RegistrationConfig) -> np.ndarray | None:
    """Normals of an ICP target for point-to-plane (2D PCA for planar targets, Open3D
    for 3D ones); None for point-to-point."""
    if cfg.icp_method != "point_to_plane":
        return None
    if np.ptp(target[:, 2]) < 1e-9:
        return normals_2d(target, tree, cfg.normal_neighbours)
    return normals_3d(target, cfg.normal_neighbours)


def _icp_to_map(src: np.ndarray, target: np.ndarray, init, cfg: RegistrationConfig,
                tree: cKDTree | None = None, normals: np.ndarray | None = None,
                distances: tuple[float, ...] | None = None):
    """Coarse-to-fine planar ICP of ``src`` (scanner frame) against ``target`` (map frame),
    at the correspondence ``distances`` (default ``cfg.icp_max_correspondence_m``);
    ``tree`` and ``normals`` of the target are computed unless given."""
    ttree = cKDTree(target) if tree is None else tree
    nrm = normals if normals is not None else _target_normals(target, ttree, cfg)
    pose, n_corr = tuple(float(v) for v in init), 0
    for dist in (cfg.icp_max_correspondence_m if distances is None else distances):  # coarse to fine
        pose, n_corr = icp_planar(
            src, target, ttree, pose, dist,
            method=cfg.icp_method, normals=nrm,
            max_iterations=cfg.icp_max_iterations, tolerance=cfg.icp_tolerance_m,
        )
        if n_corr == 0:
            break
    return pose, n_corr


# --------------------------------------------------------------------------- odometry


def _se2_compose(a, d) -> tuple[float, float, float, float]:
    """Pose ``a`` (x, y, z, yaw) followed by the planar motion ``d`` in its frame."""
    c, s = math.cos(a[3]), math.sin(a[3])
    return (a[0] + c * d[0] - s * d[1], a[1] + s * d[0] + c * d[1], a[2], float(wrap_angle(a[3] + d[2])))


def predict_constant_velocity(p1, t1: int, p2, t2: int, t3: int) -> tuple[float, float, float, float]:
    """Constant-velocity prediction of the pose at ``t3`` from the two last poses.

    The planar motion from ``p1`` to ``p2`` (in ``p1``'s frame, so a turning rover keeps
    turning) is scaled by ``(t3 - t2) / (t2 - t1)`` and applied to ``p2``; the motion
    prior of KISS-ICP (Vizzo et al. 2023, Sec. III-A), here in SE(2).

    Parameters
    ----------
    p1, p2 : tuple of float
        Poses (x, y, z, yaw) at ``t1`` < ``t2``: metres, radians.
    t1, t2, t3 : int
        Time stamps, ns.

    Returns
    -------
    tuple of float
        Predicted (x, y, z, yaw); ``p2`` itself when ``t2 <= t1``.
    """
    if t2 <= t1:
        return tuple(float(v) for v in p2)
    k = (t3 - t2) / (t2 - t1)
    d = se2_between(p1, p2)
    return _se2_compose(p2, (k * d[0], k * d[1], k * d[2]))


def _register_odometry(usable, sampled, clouds, sids, t, cfg, out) -> tuple[int, np.ndarray]:
    """Pose-free registration: LIDAR odometry from the first usable scan (``mode: odometry``).

    ``sampled``: index positions of the sampled scans (``every_n``), or None to sample
    with the motion filter on the odometry's own poses as they are estimated. Fills the
    per-scan output arrays ``out`` in place; returns the number of anchors (1, the first
    scan) and the sampled positions. See :func:`register_scans` (Notes) for the method.
    """
    kept, reasons, fit_prior, fit_icp, rmse, corr, final = out
    is_sampled = np.zeros(len(sids), dtype=bool)
    sampler = None
    if sampled is None:  # the motion filter on the odometry's poses, as they come
        sampler = MotionFilter(cfg.keep_distance_m, cfg.keep_angle_rad)
    else:
        is_sampled[sampled] = True
    seq = usable if cfg.odometry_scans == "all" else sampled
    if len(seq) == 0:
        return 0, np.zeros(0, dtype=np.int64)
    icp_cfg = dataclasses.replace(cfg, icp_method=cfg.odometry_icp_method)
    local: deque[np.ndarray] = deque(maxlen=cfg.odometry_window)  # keyframes' ICP points, map frame
    target = None  # (points, KD-tree, normals) of the local map, rebuilt after a new keyframe
    chain: deque[tuple[tuple[float, float, float, float], int]] = deque(maxlen=2)  # (pose, t_ns)
    dev_sq, n_dev = 0.0, 0  # model deviations (adaptive threshold)
    last_key = None  # pose of the last keyframe
    fine = tuple(cfg.icp_max_correspondence_m)
    for i in seq:
        src = clouds.icp(int(sids[i]))
        low = False
        if not chain:  # the first usable scan defines the map frame
            pose = (0.0, 0.0, 0.0, 0.0)
            reasons[i] = "anchor"
            corr[i] = 0.0
            if sampler is not None:
                is_sampled[i] = sampler.step(0.0, 0.0, 0.0)
        else:
            if i > 0 and reasons[i - 1] == "duplicate":
                # the scan before repeats its predecessor: the sensor stood still until
                # then, so the motion model restarts from rest instead of carrying the
                # last velocity across the stop
                chain.append((chain[-1][0], int(t[i - 1])))
            if len(chain) == 2:
                pred = predict_constant_velocity(chain[0][0], chain[0][1], chain[1][0], chain[1][1], int(t[i]))
            else:
                pred = chain[-1][0]
            if target is None:
                pts = voxel_downsample(np.concatenate(local), cfg.voxel_size_m)
                tree = cKDTree(pts)
                target = (pts, tree, _target_normals(pts, tree, icp_cfg))
            # adaptive threshold (Vizzo et al. 2023, Sec. III-C): 3 sigma of the model
            # deviations so far, within [finest stage, odometry_max_correspondence_m]
            tau = 3.0 * math.sqrt(dev_sq / n_dev) if n_dev else cfg.odometry_max_correspondence_m
            coarse = min(max(tau, fine[0]), cfg.odometry_max_correspondence_m)
            stages = (coarse,) + tuple(d for d in fine if d < coarse)
            fp = fitness_against(transform_points(src, *pred), target[1], cfg.fitness_max_correspondence_m)[0]
            pose, n_corr = _icp_to_map(src, target[0], pred, icp_cfg, tree=target[1], normals=target[2],
                                       distances=stages)
            if sampler is not None:
                at = pose if n_corr else pred
                is_sampled[i] = sampler.step(at[0], at[1], at[3])
            fi, rm = math.nan, math.nan
            if n_corr:
                fi, rm, _ = fitness_against(transform_points(src, *pose), target[1], cfg.fitness_max_correspondence_m)
            if is_sampled[i]:
                fit_prior[i], fit_icp[i], rmse[i] = fp, fi, rm
                corr[i] = (pose[0] - pred[0], pose[1] - pred[1], float(wrap_angle(pose[3] - pred[3])))
            if n_corr == 0:  # dropped; the chain goes on from the prediction
                if is_sampled[i]:
                    reasons[i] = "icp_failed"
                chain.append((pred, int(t[i])))
                continue
            low = fi < cfg.min_icp_fitness
            if low and is_sampled[i]:
                reasons[i] = "low_icp_fitness"
            d = se2_between(pred, pose)
            r_max = float(np.max(np.hypot(src[:, 0], src[:, 1])))
            dev_sq += (math.hypot(d[0], d[1]) + 2.0 * r_max * math.sin(abs(d[2]) / 2.0)) ** 2
            n_dev += 1
        chain.append((pose, int(t[i])))
        if not low:
            final[i] = pose
            kept[i] = bool(is_sampled[i])
        if last_key is None or (
            math.hypot(pose[0] - last_key[0], pose[1] - last_key[1]) >= cfg.odometry_keyframe_m
            or abs(float(wrap_angle(pose[3] - last_key[3]))) >= cfg.odometry_keyframe_rad
        ):
            local.append(transform_points(src, *pose))
            last_key = pose
            target = None
    return 1, np.flatnonzero(is_sampled)


def _register_map(sampled, clouds, sids, t, cfg, out) -> int:
    """Iterative scan-to-map registration against the whole recording (``reference: map``).

    Fills the per-scan output arrays ``out`` in place; returns the number of anchors.
    See :func:`register_scans` (Notes) for the method.
    """
    kept, reasons, fit_prior, fit_icp, rmse, corr, final = out
    n = len(sampled)
    if n == 0:
        return 0
    cls = [clouds.clouds(int(sids[i])) for i in sampled]
    pts = [c.fit_source for c in cls]
    ref = [c.fit_target for c in cls]
    src = [c.icp for c in cls]
    loc = final[sampled].copy()  # localizer poses
    t_s = (t[sampled] - t[sampled[0]]) * 1e-9
    status = np.full(n, "", dtype=object)
    active = np.ones(n, dtype=bool)
    pose = loc.copy()

    def mean_fit(j, refs, trees):
        pm = transform_points(pts[j], *pose[j])
        return _mean_fitness_trees(pm, [trees[r] for r in refs], cfg.fitness_max_correspondence_m)

    # step 4: fitness under the localizer's poses, against the previous scans (thesis)
    refs = _previous_references(pose, active, cfg)
    trees = {j: cKDTree(transform_points(ref[j], *pose[j])) for j in range(n)}
    fp = np.full(n, np.nan)
    for j in range(n):
        if len(refs[j]):
            fp[j] = mean_fit(j, refs[j], trees)[0]
    low = fp < cfg.min_prior_fitness
    status[low] = "low_prior_fitness"
    active &= ~low

    # step 5: Jacobi passes of scan-to-map ICP: every scan against the previous pass's
    # map, a relaxed step toward its ICP pose, then the gauge is fixed (Notes)
    has_ref = np.zeros(n, dtype=bool)
    n_fallback = 0
    for _ in range(cfg.passes):
        placed = [transform_points(src[j], *pose[j]) if active[j] else None for j in range(n)]
        ptrees = [cKDTree(placed[j]) if active[j] else None for j in range(n)]
        refs, n_fallback = _select_references(pose, t_s, active, cfg, placed, ptrees)
        new = pose.copy()
        moved = np.zeros(n, dtype=bool)
        for j in np.flatnonzero(active):
            if not len(refs[j]):
                continue
            has_ref[j] = True
            target = voxel_downsample(np.concatenate([placed[r] for r in refs[j]]), cfg.voxel_size_m)
            q, n_corr = _icp_to_map(src[j], target, pose[j], cfg)
            if n_corr == 0:
                status[j] = "icp_failed"
                continue
            a = cfg.relaxation
            new[j, 0] += a * (q[0] - pose[j, 0])
            new[j, 1] += a * (q[1] - pose[j, 1])
            new[j, 3] = wrap_angle(pose[j, 3] + a * float(wrap_angle(q[3] - pose[j, 3])))
            moved[j] = True
        pose = _fix_gauge(new, loc, moved)
        active &= status != "icp_failed"

    # step 6: fitness after ICP, against the previous scans at their final poses
    refs = _previous_references(pose, active, cfg)
    trees = {j: cKDTree(transform_points(ref[j], *pose[j])) for j in np.flatnonzero(active)}
    fi = np.full(n, np.nan)
    rm = np.full(n, np.nan)
    for j in np.flatnonzero(active):
        if has_ref[j]:
            fi[j], rm[j] = mean_fit(j, refs[j], trees)
    lowi = fi < cfg.min_icp_fitness
    status[lowi] = "low_icp_fitness"
    anchor = active & ~has_ref
    status[anchor] = "anchor"
    ok = active & ~lowi
    pose[anchor] = loc[anchor]

    fit_prior[sampled] = fp
    fit_icp[sampled] = fi
    rmse[sampled] = rm
    reasons[sampled] = status
    kept[sampled] = ok
    final[sampled[ok]] = pose[ok]
    d = pose - loc
    d[:, 3] = wrap_angle(d[:, 3])
    reg = ok | (status == "low_icp_fitness")
    corr[sampled[reg]] = d[reg][:, [0, 1, 3]]
    corr[sampled[anchor]] = 0.0
    if n_fallback:
        log.info("register: %d of %d scans had no reference outside exclude_window_s=%.1f s",
                 n_fallback, n, cfg.exclude_window_s)
    return int(anchor.sum())


def _mean_fitness_trees(pts_map: np.ndarray, trees: list[cKDTree], max_distance: float) -> tuple[float, float]:
    """Mean fitness over reference KD-trees and the pooled inlier RMSE."""
    fits, sq, cnt = [], 0.0, 0
    for tr in trees:
        f, r, k = fitness_against(pts_map, tr, max_distance)
        fits.append(f)
        if k:
            sq += r**2 * k
            cnt += k
    return float(np.mean(fits)), (math.sqrt(sq / cnt) if cnt else math.nan)


def register_scans(
    scans: pd.DataFrame,
    scan_index: pd.DataFrame,
    poses: pd.DataFrame | None = None,
    config: RegistrationConfig | Mapping[str, Any] | None = None,
    recording: Mapping[str, str] | None = None,
) -> RegistrationResult:
    """Register the scans of a recording into the map frame (thesis Algorithm 3, steps 2-6).

    Parameters
    ----------
    scans : pandas.DataFrame
        ``scan_id, x, y, z``: points in the scanner frame, metres (``scans.parquet``).
    scan_index : pandas.DataFrame
        ``scan_id, t_ns``: one row per scan (``scan_index.parquet``).
    poses : pandas.DataFrame, optional
        ``scan_id, x, y, z, yaw, valid, reason`` (``poses.parquet``): scanner pose in the
        map frame per scan. Required in ``mode="pose"``, ignored in ``mode="odometry"``
        (scan-to-scan ICP from the first usable scan, which defines the map frame).
    config : RegistrationConfig or mapping, optional
        The ``register`` config section; defaults from :class:`RegistrationConfig`.
    recording : mapping of str to str, optional
        What ingest found in the recording (``scan_index.parquet``'s schema metadata:
        ``pose_kind``, ``stamps``), for :func:`resolve_config`.

    Returns
    -------
    RegistrationResult
        Registered points of the kept scans, one table row per scan, a summary (its
        ``verdict``: :class:`floorscan.register.consistency.Verdict` as a dict).

    Raises
    ------
    InputError
        When a table lacks a column, a point is not finite, the poses do not cover the scan
        index, or poses are missing in pose mode.
    RegistrationError
        When no scan could be registered (the message gives the count per reason and the
        threshold that dropped most scans), or the result is poor: fewer than
        ``min_kept_fraction`` of the sampled scans kept, or a map consistency below
        ``min_consistency`` (:mod:`floorscan.register.consistency`).

    Notes
    -----
    ``reference: map`` (default): see the module docstring; references per scan are
    chosen by :func:`_select_references` (nearest first, outside ``exclude_window_s``,
    ``reference_spacing_s`` apart, overlapping, at most ``n_references``), per pass the
    scans are placed once and their KD-trees built once; each scan's ICP target is the
    union of its references, voxel-downsampled. A scan with no reference at all is kept
    at its localizer pose as an ``anchor``; a scan whose ICP fails in a pass is dropped
    (``icp_failed``) and no longer a reference.

    ``reference: previous``: the ICP target is the union of the previous ``n_previous``
    kept scans (at their localizer poses by default, ``reference_pose``),
    voxel-downsampled to ``voxel_size_m``: a local map is denser and has fewer
    one-sided gaps than a single scan. Fitness (steps 4 and 6) is the mean over those
    scans individually, as in the thesis. References further than
    ``max_reference_distance_m`` from the scan (by its pose) are ignored; a scan without
    any reference is kept as a new ``anchor`` (the first one always is), so a stretch of
    drops cannot lock out the rest of the recording.

    ``mode: odometry``: see the module docstring (KISS-ICP-style odometry against a
    local map of keyframes). The output z of every pose is 0 (the first scan's height).

    The clouds of each scan (2D: all points for fitness, the ``voxel_size_m`` grid for
    ICP; 3D: coarse grids without floor and ceiling for ICP) are described in
    :func:`scan_clouds`. There is no randomness: the same input gives the same output.
    """
    cfg = _config(config)
    _check_columns(scans, "scans.parquet", ["scan_id", "x", "y", "z"])
    index = _prepare_index(scan_index)
    from floorscan.core.io import split_by_scan

    bad = ~np.isfinite(scans[["x", "y", "z"]].to_numpy(np.float64)).all(axis=1)
    if bad.any():
        raise InputError(
            f"scans.parquet: {int(bad.sum())} points with non-finite x, y or z (first in scan "
            f"{int(scans['scan_id'].to_numpy()[bad][0])}); expected finite metres"
        )
    clouds = split_by_scan(scans)
    cfg = resolve_config(cfg, recording, math.nan if cfg.every_n else _range_sample(clouds))
    aligned = _aligned_poses(index, poses, cfg)
    reasons = screen_scans(index, clouds, aligned, cfg)
    table, summary = _register_screened(index, aligned, reasons, _ScanStore(cfg, clouds), cfg)
    sids = table["scan_id"].to_numpy()
    final = table[["x_m", "y_m", "z_m", "yaw_rad"]].to_numpy(np.float64)
    kept = table["kept"].to_numpy(bool)
    keep_ids = sids[kept]
    parts = [transform_points(clouds[int(s)], *f) for s, f in zip(keep_ids, final[kept])]
    registered = pd.DataFrame(
        {
            "scan_id": np.repeat(keep_ids.astype(np.int32), [len(p) for p in parts]),
            **{
                c: (np.concatenate(parts)[:, k] if parts else np.empty(0)).astype(np.float32)
                for k, c in enumerate("xyz")
            },
        }
    )
    return RegistrationResult(registered=registered, table=table, summary=summary)


def _config(config) -> RegistrationConfig:
    cfg = config if isinstance(config, RegistrationConfig) else RegistrationConfig.from_mapping(config)
    cfg.check()
    return cfg


def resolve_config(
    cfg: RegistrationConfig, recording: Mapping[str, str] | None, range_m: float
) -> RegistrationConfig:
    """The settings a recording needs, from what ingest found in it (logged with why).

    - ``mode: auto``: ``pose`` when the recording has map poses (``pose_kind`` ``map``:
      a localizer topic, the TF chain from ``map``, a log's corrected poses), else
      ``odometry`` (LIDAR odometry: wheel odometry alone is never the map pose);
    - made-up stamps (``stamps`` ``made_up``: all zero, or mostly repeated) carry no
      speed, so the pose-jump checks (``max_speed_m_s``, ``max_turn_rate_rad_s``) are off;
    - without ``every_n``, the motion filter's thresholds not configured are chosen from
      the scanner's typical range ``range_m`` (:mod:`floorscan.register.sampling`).

    Parameters
    ----------
    cfg : RegistrationConfig
    recording : mapping of str to str, or None
        The schema metadata of ``scan_index.parquet`` (keys ``pose_kind``, ``stamps``);
        None or missing keys: map poses, recorded stamps.
    range_m : float
        Typical range of the scanner, metres (:func:`floorscan.register.sampling.typical_range_m`).

    Returns
    -------
    RegistrationConfig
        With ``mode`` ``pose`` or ``odometry`` and the sampling thresholds set.

    Raises
    ------
    InputError
        ``mode: pose`` on a recording without map poses, or ``odometry_scans: sampled``
        without ``every_n``.
    """
    from floorscan.register.sampling import choose_thresholds

    rec = dict(recording or {})
    pose_kind = rec.get("pose_kind", "map")
    changes: dict[str, Any] = {}
    if cfg.mode == "auto":
        changes["mode"] = "pose" if pose_kind == "map" else "odometry"
        log.info(
            "register.mode auto -> %s (pose source: %s)", changes["mode"], rec.get("pose_source", "map poses")
        )
    elif cfg.mode == "pose" and pose_kind != "map":
        raise InputError(
            f"register.mode 'pose' needs map poses, but the recording has none ({rec.get('pose_source', pose_kind)}); "
            "use register.mode auto or odometry, or name a pose source (dataset 'pose')"
        )
    if rec.get("stamps") == "made_up":
        changes.update(max_speed_m_s=math.inf, max_turn_rate_rad_s=math.inf)
        log.info("the scan stamps are made up (%s): pose-jump checks on speed and turn rate are off", rec.get("stamps"))
    if cfg.every_n:
        log.info("sampling: every %d-th usable scan (register.every_n)", cfg.every_n)
    else:
        th = choose_thresholds(range_m, cfg.keep_distance_m, cfg.keep_angle_rad, cfg.keep_range_fraction)
        changes.update(keep_distance_m=th.distance_m, keep_angle_rad=th.angle_rad)
        log.info("sampling: motion filter, %s", th.reason)
        if changes.get("mode", cfg.mode) == "odometry" and cfg.odometry_scans == "sampled":
            raise InputError("register.odometry_scans 'sampled' needs register.every_n (the motion filter samples the odometry's own poses)")
    return dataclasses.replace(cfg, **changes)


def _range_sample(clouds: Mapping[int, np.ndarray], n: int = 200) -> float:
    """Typical range of a recording from up to ``n`` of its scans, evenly spread."""
    from floorscan.register.sampling import typical_range_m

    ids = sorted(clouds)
    pick = ids[:: max(1, len(ids) // n)]
    return typical_range_m(clouds[i] for i in pick)


def _range_of_file(scans_path, max_points: int = 400_000) -> float:
    """Typical range of a recording from a points file (``scans.parquet``): up to 8 of
    its row groups, evenly spread, every k-th point of them."""
    import pyarrow.parquet as pq

    from floorscan.register.sampling import typical_range_m

    pf = pq.ParquetFile(scans_path)
    n_groups = pf.metadata.num_row_groups
    if n_groups == 0:
        return math.nan
    groups = sorted(set(np.linspace(0, n_groups - 1, min(8, n_groups)).round().astype(int).tolist()))
    table = pf.read_row_groups(groups, columns=["x", "y"])
    step = max(1, table.num_rows // max_points)
    xy = np.column_stack([table.column(c).to_numpy()[::step] for c in ("x", "y")])
    return typical_range_m([xy])


def _judge(table: pd.DataFrame, clouds: "_ScanStore", cfg: RegistrationConfig, summary: dict):
    """The verdict on the registration (:func:`floorscan.register.consistency.verdict`)."""
    from floorscan.register.consistency import map_consistency, path_length_m, verdict

    kept = table["kept"].to_numpy(bool)
    sids = table["scan_id"].to_numpy()[kept]
    final = table[["x_m", "y_m", "z_m", "yaw_rad"]].to_numpy(np.float64)[kept]
    parts = [transform_points(clouds.map_cloud(int(s)), *f) for s, f in zip(sids, final)]
    cons, n_rev = map_consistency(parts, path_length_m(final[:, 0], final[:, 1]), final[:, :2])
    worst, option = _worst_drop({k: v for k, v in summary["drops"].items() if k != "not_sampled"}, cfg)
    return verdict(
        summary["n_sampled"], summary["n_kept"], cons, n_rev, cfg.min_kept_fraction, cfg.min_consistency,
        worst, option,
    )


def _prepare_index(scan_index: pd.DataFrame) -> pd.DataFrame:
    _check_columns(scan_index, "scan_index.parquet", ["scan_id", "t_ns"])
    index = scan_index[["scan_id", "t_ns"]].sort_values("scan_id", kind="stable").reset_index(drop=True)
    if index["scan_id"].duplicated().any():
        raise InputError("scan_index.parquet: scan_id is not unique")
    return index


def _aligned_poses(index: pd.DataFrame, poses: pd.DataFrame | None, cfg: RegistrationConfig):
    if cfg.mode == "odometry":
        return None
    if poses is None:
        raise InputError("register: mode 'pose' needs poses.parquet (or set mode: odometry)")
    return _align_poses(index, poses)


def _register_screened(index, aligned, reasons, clouds: "_ScanStore", cfg, ahead=None) -> tuple[pd.DataFrame, dict]:
    """Algorithm 3 steps 2-6 after the per-scan checks: sampling, then the registration
    of the configured mode (``ahead``: pose-graph edges aligned ahead, a finished
    :class:`floorscan.register.posegraph.EdgeStream`). Returns
    the :data:`REGISTRATION` table and the summary; raises :class:`RegistrationError`
    when nothing could be registered."""
    n = len(index)
    odometry = cfg.mode == "odometry"
    usable = np.flatnonzero(reasons == "")
    if odometry:  # sampled on the odometry's own poses unless every_n is set
        sampled = usable[:: cfg.every_n] if cfg.every_n else None
    else:
        sampled = _sample(usable, aligned, cfg)

    kept = np.zeros(n, dtype=bool)
    fit_prior = np.full(n, np.nan)
    fit_icp = np.full(n, np.nan)
    rmse = np.full(n, np.nan)
    corr = np.full((n, 3), np.nan)
    final = np.full((n, 4), np.nan)
    if aligned is not None:
        ok = aligned["valid"].to_numpy(bool)
        final[ok] = aligned.loc[ok, ["x", "y", "z", "yaw"]].to_numpy(np.float64)

    t = index["t_ns"].to_numpy(np.int64)
    sids = index["scan_id"].to_numpy()
    out = (kept, reasons, fit_prior, fit_icp, rmse, corr, final)
    if odometry:
        n_anchor, sampled = _register_odometry(usable, sampled, clouds, sids, t, cfg, out)
        if cfg.loop_closure:
            _register_graph(np.flatnonzero(kept), clouds, sids, t, cfg, out, priors=False)
    elif cfg.reference == "graph":
        n_anchor = _register_graph(sampled, clouds, sids, t, cfg, out, priors=True, ahead=ahead)
    elif cfg.reference == "previous":
        n_anchor = _register_sequential(sampled, clouds, sids, t, cfg, out)
    else:
        n_anchor = _register_map(sampled, clouds, sids, t, cfg, out)
    reasons[np.setdiff1d(usable, sampled)] = "not_sampled"
    if not cfg.every_n and len(usable) > 1:
        at = final[usable] if odometry else aligned[["x", "y"]].to_numpy(np.float64)[usable]
        at = at[np.isfinite(at[:, 0])]
        log.info(
            "sampling: %d of %d usable scans (the recording's median step between scans %.3f m; "
            "keep_distance_m %.3f, keep_angle_rad %.3f)",
            len(sampled), len(usable), median_step_m(at[:, 0], at[:, 1]), cfg.keep_distance_m, cfg.keep_angle_rad,
        )

    table = pd.DataFrame(
        {
            "scan_id": sids.astype(np.int32),
            "t_ns": t,
            "kept": kept,
            "reason": reasons.astype(str),
            "fitness_prior": fit_prior,
            "fitness_icp": fit_icp,
            "inlier_rmse_m": rmse,
            "dx_m": corr[:, 0],
            "dy_m": corr[:, 1],
            "dyaw_rad": corr[:, 2],
            "x_m": final[:, 0],
            "y_m": final[:, 1],
            "z_m": final[:, 2],
            "yaw_rad": final[:, 3],
        }
    )
    summary = summarize(table, cfg)
    _raise_if_nothing_registered(table, cfg, summary)
    judged = _judge(table, clouds, cfg, summary)
    summary["verdict"] = judged.as_dict()
    log.info(
        "register (%s): %d scans, %d sampled, %d kept (%d anchors); drops %s",
        cfg.mode, n, len(sampled), int(kept.sum()), n_anchor, summary["drops"],
    )
    (log.info if judged.ok and not judged.warnings else log.warning)("verdict: %s", judged.line())
    if not judged.ok:
        raise RegistrationError(f"register: the result is poor: {judged.line()}")
    return table, summary


def register_recording(
    scans_path: str | os.PathLike,
    scan_index: pd.DataFrame,
    poses: pd.DataFrame | None,
    config: RegistrationConfig | Mapping[str, Any] | None,
    registered_path: str | os.PathLike,
    metadata: Mapping[str, str] | None = None,
    recording: Mapping[str, str] | None = None,
) -> RegistrationResult:
    """:func:`register_scans` on a points file, streamed: memory follows the largest scan.

    Issue 8 ("Speed and scale"): the whole ``scans.parquet`` of a 3D recording is 73 M
    points (hallways3d; 6.4 GB RSS when loaded as a table). Here it is read once in
    record batches (:func:`floorscan.core.io.iter_scans`): each scan is screened as it
    arrives (every check of :func:`screen_scans` depends on the scan and the ones before
    it only) and the sampled ones keep only the small clouds registration needs
    (:func:`graph_cloud` for ``reference: graph``, ~570 points of a 14k-point 3D scan),
    their points going to a temporary Parquet file beside ``registered_path`` (the kept
    scans are sampled ones: 1 in ``every_n``). After registration that file is read
    back and each kept scan's points are transformed into the map frame and written to
    ``registered_path`` (a Parquet writer on :func:`floorscan.core.files.atomic_path`, a row group
    per ~1 M points). Same output as :func:`register_scans` (tested), given the same
    input. The figure of the registered map is drawn from that file
    (:func:`floorscan.figures.registration.density_of_file`, rule ``register_figure``).

    Parameters
    ----------
    scans_path : path
        ``scans.parquet``: ``scan_id, x, y, z`` in the scanner frame, metres, rows
        grouped by scan in ascending ``scan_id``.
    scan_index, poses, config
        As for :func:`register_scans`.
    registered_path : path
        Output ``registered.parquet`` (schema :data:`floorscan.core.io.REGISTERED`).
    metadata : mapping, optional
        Key/value strings stored in the output's schema metadata.
    recording : mapping, optional
        As for :func:`register_scans`.

    Returns
    -------
    RegistrationResult
        ``registered`` is None: the points are in ``registered_path``.

    Raises
    ------
    InputError
        As :func:`register_scans`; also when the file's scans are not in ascending
        ``scan_id`` order or a point is not finite (naming the file and the scan).
    RegistrationError
        When no scan could be registered.
    """
    import pyarrow.parquet as pq

    from floorscan.core.io import SCANS, ScanRowGroups, iter_scans, parquet_options

    cfg = _config(config)
    cfg = resolve_config(cfg, recording, math.nan if cfg.every_n else _range_of_file(scans_path))
    n_workers = 0
    if cfg.reference == "graph" or (cfg.mode == "odometry" and cfg.loop_closure):
        from floorscan.core.parallel import prestart
        from floorscan.register.posegraph import GraphParams

        # the edge ICP's worker processes import Open3D while the scans are read, on
        # the core this reading leaves idle (with one worker the ICP runs here); as
        # many as the edges will need (posegraph._chunks: >= 200 pairs a worker; at
        # most ~3 pairs a sampled scan are counted here, so small recordings get one)
        workers = GraphParams.from_mapping(cfg.graph).workers
        pairs = 3 * len(scan_index) // max(1, cfg.every_n or 5)
        n_workers = min(workers, max(1, pairs // 200)) if workers > 1 else 0
        prestart(n_workers, preload=("open3d", "floorscan.register.posegraph"))
    index = _prepare_index(scan_index)
    aligned = _aligned_poses(index, poses, cfg)
    sids = index["scan_id"].to_numpy()
    n = len(sids)
    screen = _Screener(index, aligned, cfg)
    store = _ScanStore(cfg)
    edges = None
    if cfg.mode == "pose" and cfg.reference == "graph" and n_workers and aligned is not None:
        # the pose graph's edges are aligned in the workers while the scans are read
        # (posegraph.EdgeStream), for the scans that the index and poses say will be
        # sampled; a scan the points drop after all only costs its pairs again
        from floorscan.register.posegraph import EdgeStream

        expected = _expected_sampled(index, aligned, cfg)
        if len(expected):
            t = index["t_ns"].to_numpy(np.int64)[expected]
            init = aligned.iloc[expected][["x", "y", "z", "yaw"]].to_numpy(np.float64)
            edges = EdgeStream(
                sids[expected], init, (t - t[0]) * 1e-9, GraphParams.from_mapping(cfg.graph),
                ("sequential", "loop"), n_workers,
            )  # fmt: skip

    def walk():
        """(index position, points) in index order; the file's scans are ascending."""
        k, last = 0, None
        # float32 as stored: most scans are only screened; _first_pass widens the
        # scans it keeps to float64
        for sid, pts in iter_scans(scans_path, dtype=np.float32):
            if last is not None and sid <= last:
                raise InputError(
                    f"{scans_path}: scan {sid} follows scan {last}; expected the scans in "
                    "ascending scan_id order, as the ingest stage writes them"
                )
            last = sid
            while k < n and sids[k] < sid:
                yield k, None
                k += 1
            if k < n and sids[k] == sid:
                if not np.isfinite(pts).all():
                    raise InputError(
                        f"{scans_path}: scan {sid} has non-finite x, y or z; expected finite metres"
                    )
                yield k, pts
                k += 1
        while k < n:
            yield k, None
            k += 1

    # The sampled scans' points (the kept scans are among them) are copied to a
    # temporary file as they pass, so the second pass reads them, not the whole
    # recording again (1 in every_n scans; hallways3d 14.5 of 72 M points).
    sampled_path = Path(registered_path).with_name(f".{Path(registered_path).name}.sampled.parquet")
    try:
        with pq.ParquetWriter(sampled_path, SCANS, **parquet_options(SCANS, ["scan_id"])) as sampled_writer:
            with ScanRowGroups(sampled_writer) as sampled_out:
                _first_pass(progress(walk(), log, total=n, what="scans screened"), sids, screen, store, cfg,
                            sampled_out, edges)
        ahead = edges.finish() if edges is not None else None
        table, summary = _register_screened(index, aligned, screen.reasons, store, cfg, ahead)
        store = None
        _second_pass(table, sids, sampled_path, registered_path, metadata)
    finally:
        if edges is not None:
            edges.close()
        sampled_path.unlink(missing_ok=True)
    return RegistrationResult(registered=None, table=table, summary=summary)


def _expected_sampled(index: pd.DataFrame, aligned: pd.DataFrame, cfg) -> np.ndarray:
    """Index positions of the scans that will be sampled if every scan's points pass
    the screening (the checks of the index and poses only: as _register_screened samples)."""
    screen = _Screener(index, aligned, cfg)
    for i in range(len(index)):
        screen.step(i, None, points_unseen=True)
    return _sample(np.flatnonzero(screen.reasons == ""), aligned, cfg)


def _sampler(cfg: RegistrationConfig):
    """The sampling rule of Algorithm 3 step 2: ``every_n`` when set, else the motion
    filter (:mod:`floorscan.register.sampling`; thresholds resolved by
    :func:`resolve_config`)."""
    if cfg.every_n:
        return EveryN(cfg.every_n)
    if cfg.keep_distance_m is None or cfg.keep_angle_rad is None:
        raise ValueError("register: the motion filter's thresholds are not resolved (resolve_config)")
    return MotionFilter(cfg.keep_distance_m, cfg.keep_angle_rad)


def _sample(usable: np.ndarray, aligned: pd.DataFrame, cfg: RegistrationConfig) -> np.ndarray:
    """Index positions of the sampled scans among ``usable`` (pose modes)."""
    sampler = _sampler(cfg)
    x, y, yaw = (aligned[c].to_numpy(np.float64) for c in ("x", "y", "yaw"))
    return np.asarray([i for i in usable if sampler.step(x[i], y[i], yaw[i])], dtype=np.int64)


def _first_pass(scans, sids, screen, store, cfg, sampled_out, edges=None) -> None:
    """Screen the scans as they stream by; keep the sampled ones' registration clouds
    (``store``) and points (``sampled_out``); hand the graph clouds to ``edges``
    (a :class:`floorscan.register.posegraph.EdgeStream`)."""
    odometry = cfg.mode == "odometry"
    # sampled as _register_screened samples; odometry without every_n samples on its
    # own poses later, so every usable scan may be sampled
    sampler = _sampler(cfg) if not odometry or cfg.every_n else None
    for k, pts in scans:
        if screen.step(k, pts) != "":
            continue
        if sampler is None:
            is_sampled = True
        elif odometry:
            is_sampled = sampler.step()
        else:
            is_sampled = sampler.step(screen.px[k], screen.py[k], screen.pyaw[k])
        if odometry:
            needs = ("icp",) if cfg.odometry_scans == "all" or is_sampled else ()
            if is_sampled and cfg.loop_closure:
                needs += ("graph",)
        elif is_sampled:
            needs = ("graph",) if cfg.reference == "graph" else ("clouds",)
        else:
            needs = ()
        if needs:
            store.add(int(sids[k]), pts.astype(np.float64), needs)
            if edges is not None and "graph" in needs:
                edges.add(int(sids[k]), store.graph(int(sids[k])))
        if is_sampled:
            sampled_out.add(int(sids[k]), pts)


def _second_pass(table, sids, sampled_path, registered_path, metadata) -> None:
    """The kept scans, read back from ``sampled_path``, into the map frame: ``registered_path``."""
    import pyarrow.parquet as pq

    from floorscan.core.io import REGISTERED, ScanRowGroups, iter_scans, parquet_options
    from floorscan.core.files import atomic_path

    kept = table["kept"].to_numpy(bool)
    final = table[["x_m", "y_m", "z_m", "yaw_rad"]].to_numpy(np.float64)
    pose_of = {int(s): final[k] for k, s in enumerate(sids) if kept[k]}
    schema = REGISTERED
    if metadata:
        schema = schema.with_metadata({str(k): str(v) for k, v in metadata.items()})
    with atomic_path(registered_path) as tmp:
        # x, y statistics: the register figure's raster extent (density_of_file)
        with pq.ParquetWriter(tmp, schema, **parquet_options(schema, ["scan_id", "x", "y"])) as writer:
            with ScanRowGroups(writer) as out:  # row groups written in a thread
                for sid, pts in iter_scans(sampled_path):
                    pose = pose_of.get(int(sid))
                    if pose is not None:
                        out.add(sid, transform_points(pts, *pose))


def summarize(table: pd.DataFrame, cfg: RegistrationConfig | None = None) -> dict:
    """Counts per reason (``counts``: every scan, ``""`` and ``"anchor"`` are kept;
    ``drops``: the scans not kept), fraction dropped by each threshold, median corrections.

    Drop fractions are given twice: of all scans (``fraction_of_scans``) and of the
    scans that reached the check (``fraction_of_checked``: sampled scans for the fitness
    thresholds, i.e. those passing the prior check for ``low_icp_fitness``).

    Returns
    -------
    dict
        JSON-serialisable.
    """
    reasons = table["reason"].str.replace(r"^no_pose:.*", "no_pose", regex=True)
    counts = dict(sorted(Counter(reasons).items()))
    drops = dict(sorted(Counter(reasons[~table["kept"].to_numpy(bool)]).items()))
    n = len(table)
    sampled = int(table["kept"].sum() + reasons.isin(["low_prior_fitness", "low_icp_fitness", "icp_failed"]).sum())
    n_prior = int((reasons == "low_prior_fitness").sum())
    n_icp = int((reasons == "low_icp_fitness").sum())
    checked_prior = int(table["fitness_prior"].notna().sum())
    checked_icp = int(table["fitness_icp"].notna().sum())
    registered = table["kept"] & table["fitness_icp"].notna()
    dxy = np.hypot(table.loc[registered, "dx_m"], table.loc[registered, "dy_m"])
    dyaw = np.abs(table.loc[registered, "dyaw_rad"])
    out = {
        "n_scans": n,
        "n_sampled": sampled,
        "n_kept": int(table["kept"].sum()),
        "n_registered": int(registered.sum()),
        "counts": counts,
        "drops": drops,
        "fraction_of_scans": {k: v / n for k, v in counts.items()} if n else {},
        "fraction_of_checked": {
            "low_prior_fitness": n_prior / checked_prior if checked_prior else 0.0,
            "low_icp_fitness": n_icp / checked_icp if checked_icp else 0.0,
        },
        "median_fitness_prior": float(table["fitness_prior"].median()) if checked_prior else math.nan,
        "median_fitness_icp": float(table["fitness_icp"].median()) if checked_icp else math.nan,
        "median_correction_m": float(np.median(dxy)) if len(dxy) else math.nan,
        "median_correction_rad": float(np.median(dyaw)) if len(dyaw) else math.nan,
        "p90_correction_m": float(np.percentile(dxy, 90)) if len(dxy) else math.nan,
    }
    if cfg is not None:
        out["config"] = dataclasses.asdict(cfg)
    return out


def _raise_if_nothing_registered(table: pd.DataFrame, cfg: RegistrationConfig, summary: dict) -> None:
    counts = summary["counts"]
    failures = {k: v for k, v in counts.items() if k not in ("", "anchor", "not_sampled")}
    n_kept = summary["n_kept"]
    checked = int(table["fitness_icp"].notna().sum() + (table["reason"] == "low_prior_fitness").sum())
    if n_kept > 0 and not (summary["n_registered"] == 0 and checked > 0):
        return
    if not failures:
        raise RegistrationError(f"register: no scans to register ({len(table)} scans in the index)")
    worst, option = _worst_drop(failures, cfg)
    raise RegistrationError(
        f"register: no scan could be registered ({n_kept} kept without a reference) of "
        f"{len(table)}; drops per reason {failures}; most were dropped by '{worst}' (threshold {option})"
    )


def _worst_drop(failures: Mapping[str, int], cfg: RegistrationConfig) -> tuple[str, str]:
    """The drop reason behind most lost scans and the option(s) that set it with their
    values (``register.min_prior_fitness=0.15``); ``("", "")`` without drops."""
    if not failures:
        return "", ""
    worst = max(failures, key=lambda k: failures[k])
    parts = REASON_THRESHOLD.get(worst, worst).split(" / ")
    return worst, " / ".join(f"register.{p}={getattr(cfg, p)}" if hasattr(cfg, p) else p for p in parts)


# --------------------------------------------------------------------------- pose graph


def _register_graph(scans, clouds, sids, t, cfg, out, priors: bool, ahead=None) -> int:
    """Pose-graph registration (``reference: graph``, :mod:`floorscan.register.posegraph`).

    ``scans`` (indices into the scan index, time order) start at ``final`` (the
    localizer's poses, or the odometry chain). Planar ICP between each scan and its
    next sampled scans and its revisits gives relative constraints; with ``priors``
    the localizer's poses are absolute constraints, otherwise the first scan is held
    (odometry mode: the chain's own motion is the sequential edges and ICP only closes
    loops, which then remove the chain's drift). Thesis Algorithm 3
    steps 3 and 5 become the drops: a scan whose mean fitness over its pairs is below
    ``min_prior_fitness`` under the initial poses (``low_prior_fitness``) or below
    ``min_icp_fitness`` after ICP (``low_icp_fitness``) is not kept. The optimisation
    runs once, with those scans in it: their pairs below ``graph.min_edge_fitness``
    are not edges, so a scan that fits nothing does not pull the others. Fills ``out``
    in place; returns the number of scans without any edge (held by their prior only).
    """
    from floorscan.register import posegraph

    kept, reasons, fit_prior, fit_icp, rmse, corr, final = out
    scans = np.asarray(scans, dtype=np.int64)
    n = len(scans)
    if n == 0:
        return 0
    params = posegraph.GraphParams.from_mapping(cfg.graph)
    init = final[scans].copy()
    t_s = (t[scans] - t[scans[0]]) * 1e-9
    cl = [clouds.graph(int(sids[i])) for i in scans]
    kinds = ("sequential", "loop") if priors else ("loop",)
    poses, fp, fi, rm, info = posegraph.refine_poses(
        cl, init, t_s, init if priors else None, params, icp_kinds=kinds, ahead=ahead, scan_ids=sids[scans]
    )
    final[scans] = poses
    log.info("pose graph: %d scans, %s", n, info)
    if not priors:
        return int(info["n_isolated"])
    fit_prior[scans] = fp
    fit_icp[scans] = fi
    rmse[scans] = rm
    corr[scans, 0] = poses[:, 0] - init[:, 0]
    corr[scans, 1] = poses[:, 1] - init[:, 1]
    corr[scans, 2] = wrap_angle(poses[:, 3] - init[:, 3])
    low_prior = fp < cfg.min_prior_fitness
    low_icp = ~low_prior & (fi < cfg.min_icp_fitness)
    reasons[scans[low_prior]] = "low_prior_fitness"
    reasons[scans[low_icp]] = "low_icp_fitness"
    kept[scans] = ~(low_prior | low_icp)
    return int(info["n_isolated"])

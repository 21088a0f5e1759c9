"""LIDAR models: 2D and 3D scanners casting rays against a building mesh.

The thesis simulates its scans with BlenSor on a CAD model, with Gaussian range noise
of 1 cm standard deviation (section 4.1); openings are empty space, so rays pass
through doors and windows. Here rays are cast with Open3D's
``o3d.t.geometry.RaycastingScene`` (Embree), many scans in one call.

Conventions
-----------
- Scanner frame: x forward, y left, z up; the scanner pose in the map frame is
  ``(x, y, z, yaw)``: ``map_point = Rz(yaw) @ p + (x, y, z)``.
- A 2D scanner's beam ``i`` points at ``angle_min + i * angle_increment`` in the
  scanner's xy plane, like ``sensor_msgs/LaserScan``; the two angles are float32
  (as in the message), so points rebuilt from a LaserScan agree with the simulation.
- A 3D scanner fires all its elevation beams at each azimuth (azimuth-major order,
  like a spinning multi-beam LIDAR).
- All rays of a scan are cast at the scan's time stamp (no motion skew).
- Ranges: measured = exact distance + N(0, range_noise_std_m). A ray that hits
  nothing, or whose measured range exceeds ``range_max_m``, has no return (``+inf``);
  one below ``range_min_m`` is ``-inf`` (REP 117: "too close").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any, Iterator

import numpy as np

from floorscan.core.io import InputError


@dataclass(frozen=True)
class Scanner2D:
    """A planar scanner (Hokuyo UST-20LX-like defaults: 270 deg, 0.25 deg, 0.06-20 m).

    Attributes
    ----------
    fov_deg : float
        Field of view, degrees, centred on the scanner's +x axis.
    angular_resolution_deg : float
        Angle between beams, degrees.
    range_min_m, range_max_m : float
        Valid range limits, metres.
    range_noise_std_m : float
        Standard deviation of the Gaussian range noise, metres (thesis 4.1: 1 cm).
    """

    fov_deg: float = 270.0
    angular_resolution_deg: float = 0.25
    range_min_m: float = 0.06
    range_max_m: float = 20.0
    range_noise_std_m: float = 0.01
    kind: str = "2d"

    @property
    def angle_min(self) -> float:
        """First beam angle, radians (float32-representable, as in a LaserScan)."""
        return float(np.float32(-math.radians(self.fov_deg) / 2))

    @property
    def angle_increment(self) -> float:
        """Angle between beams, radians (float32-representable)."""
        return float(np.float32(math.radians(self.angular_resolution_deg)))

    @property
    def n_beams(self) -> int:
        """Number of beams: every resolution step across the field of view, both ends."""
        n = int(math.floor(self.fov_deg / self.angular_resolution_deg + 1e-6))
        return n if self.fov_deg >= 360 else n + 1  # a full circle does not repeat -180/180

    @property
    def angle_max(self) -> float:
        """Last beam angle, radians."""
        return float(np.float32(self.angle_min + (self.n_beams - 1) * self.angle_increment))

    def angles(self) -> np.ndarray:
        """(R,) float64 beam angles, radians, from the float32 angle_min/increment."""
        return self.angle_min + np.arange(self.n_beams) * self.angle_increment

    def directions(self) -> np.ndarray:
        """(R, 3) float64 unit ray directions in the scanner frame."""
        a = self.angles()
        return np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], axis=1)


@dataclass(frozen=True)
class Scanner3D:
    """A spinning multi-beam scanner (Velodyne VLP-16-like defaults).

    Attributes
    ----------
    n_beams : int
        Number of vertical beams, evenly spaced from ``elevation_min_deg`` to
        ``elevation_max_deg`` (unless ``elevations_deg`` is given).
    elevation_min_deg, elevation_max_deg : float
        Elevation of the lowest and highest beam, degrees.
    elevations_deg : tuple of float, optional
        Explicit beam elevations, degrees (overrides the three above).
    horizontal_resolution_deg : float
        Azimuth step over the full 360 degrees, degrees.
    range_min_m, range_max_m : float
        Valid range limits, metres.
    range_noise_std_m : float
        Gaussian range noise, metres.
    """

    n_beams: int = 16
    elevation_min_deg: float = -15.0
    elevation_max_deg: float = 15.0
    elevations_deg: tuple[float, ...] | None = None
    horizontal_resolution_deg: float = 0.4
    range_min_m: float = 0.5
    range_max_m: float = 100.0
    range_noise_std_m: float = 0.01
    kind: str = "3d"

    def elevations(self) -> np.ndarray:
        """(B,) float64 beam elevations, radians."""
        if self.elevations_deg is not None:
            return np.radians(np.asarray(self.elevations_deg, dtype=float))
        if self.n_beams == 1:
            return np.radians([(self.elevation_min_deg + self.elevation_max_deg) / 2])
        return np.radians(np.linspace(self.elevation_min_deg, self.elevation_max_deg, self.n_beams))

    def azimuths(self) -> np.ndarray:
        """(A,) float64 azimuths over 360 degrees, radians."""
        n = int(round(360.0 / self.horizontal_resolution_deg))
        return np.arange(n) * (2 * math.pi / n)

    def directions(self) -> np.ndarray:
        """(A * B, 3) float64 unit ray directions, azimuth-major."""
        az = self.azimuths()[:, None]
        el = self.elevations()[None, :]
        d = np.stack(
            np.broadcast_arrays(np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)),
            axis=-1,
        )
        return d.reshape(-1, 3)


Scanner = Scanner2D | Scanner3D


def scanner_from_config(name: str, cfg: dict[str, Any], where: str = "simulate.scanners") -> Scanner:
    """Build and check a scanner model from its config entry.

    Parameters
    ----------
    name : str
        The scanner's name (key under ``simulate.scanners``).
    cfg : dict
        Its settings; ``kind`` is "2d" or "3d" (default: the name when it is one of
        those). Missing keys take the dataclass defaults (the schema's defaults).
    where : str
        Config path used in error messages.

    Returns
    -------
    Scanner2D or Scanner3D

    Raises
    ------
    InputError
        Unknown kind or key, zero beams, a non-positive resolution or field of view,
        range limits out of order, a negative noise level. Names ``where.name.field``.
    """
    if not isinstance(cfg, dict):
        raise InputError(f"config {where}.{name}: expected a mapping, got {cfg!r}")
    here = f"config {where}.{name}"
    kind = cfg.get("kind", name if name in ("2d", "3d") else None)
    cls = {"2d": Scanner2D, "3d": Scanner3D}.get(kind)
    if cls is None:
        raise InputError(f"{here}.kind: expected '2d' or '3d', got {kind!r}")
    allowed = {f.name for f in fields(cls)}
    unknown = sorted(set(cfg) - allowed)
    if unknown:
        raise InputError(
            f"{here}: unknown keys {unknown} for a {kind} scanner; allowed {sorted(allowed)}"
        )
    kw = {k: v for k, v in cfg.items() if k != "kind"}
    if kw.get("elevations_deg") is not None:
        kw["elevations_deg"] = tuple(float(e) for e in kw["elevations_deg"])
    scanner = cls(**kw)

    def bad(field: str, msg: str) -> InputError:
        return InputError(f"{here}.{field}: {msg}, got {getattr(scanner, field)!r}")

    if not scanner.range_noise_std_m >= 0:
        raise bad("range_noise_std_m", "the range noise std must be >= 0 metres")
    if not 0 <= scanner.range_min_m < scanner.range_max_m:
        raise bad("range_max_m", f"need 0 <= range_min_m ({scanner.range_min_m}) < range_max_m")
    if isinstance(scanner, Scanner2D):
        if not 0 < scanner.fov_deg <= 360:
            raise bad("fov_deg", "the field of view must be in (0, 360] degrees")
        if not 0 < scanner.angular_resolution_deg <= scanner.fov_deg:
            raise bad("angular_resolution_deg", "need 0 < resolution <= fov_deg (at least one beam)")
    else:
        if scanner.elevations_deg is not None:
            if len(scanner.elevations_deg) == 0:
                raise bad("elevations_deg", "a 3D scanner needs at least one beam")
            if any(abs(e) >= 90 for e in scanner.elevations_deg):
                raise bad("elevations_deg", "elevations must be within (-90, 90) degrees")
        else:
            nb = scanner.n_beams
            if isinstance(nb, bool) or not isinstance(nb, int) or nb < 1:
                raise bad("n_beams", "a 3D scanner needs at least one beam (n_beams >= 1)")
            if not -90 < scanner.elevation_min_deg <= scanner.elevation_max_deg < 90:
                raise bad("elevation_max_deg", "need -90 < elevation_min_deg <= elevation_max_deg < 90")
        if not 0 < scanner.horizontal_resolution_deg <= 360:
            raise bad("horizontal_resolution_deg", "need 0 < resolution <= 360 degrees")
    return scanner


class RayCaster:
    """Ray casting against a triangle mesh with Open3D's RaycastingScene (Embree).

    Parameters
    ----------
    vertices : (V, 3) float ndarray
        Mesh vertices, metres (map frame).
    triangles : (T, 3) int ndarray
        Vertex indices of each triangle.
    """

    def __init__(self, vertices: np.ndarray, triangles: np.ndarray) -> None:
        import open3d as o3d

        self._o3d = o3d
        self.scene = o3d.t.geometry.RaycastingScene()
        self.scene.add_triangles(
            o3d.core.Tensor(np.ascontiguousarray(vertices, dtype=np.float32)),
            o3d.core.Tensor(np.ascontiguousarray(triangles, dtype=np.uint32)),
        )

    @classmethod
    def from_mesh(cls, mesh) -> "RayCaster":
        """From a ``trimesh.Trimesh``."""
        return cls(np.asarray(mesh.vertices), np.asarray(mesh.faces))

    def cast(self, rays: np.ndarray) -> np.ndarray:
        """Distance to the first hit of each ray.

        Parameters
        ----------
        rays : (..., 6) float32 ndarray
            Origin (x, y, z) and unit direction (dx, dy, dz), metres, map frame.

        Returns
        -------
        (...) float32 ndarray
            Distance along the ray, metres; ``inf`` where the ray hits nothing.
        """
        rays = np.ascontiguousarray(rays, dtype=np.float32)
        out = self.scene.cast_rays(self._o3d.core.Tensor(rays))
        return out["t_hit"].numpy()


def scan_rays(scanner: Scanner, poses: np.ndarray) -> np.ndarray:
    """The rays of scans taken at ``poses``.

    Parameters
    ----------
    scanner : Scanner2D or Scanner3D
    poses : (S, 4) float64 ndarray
        Scanner poses ``x, y, z, yaw`` in the map frame (metres, radians).

    Returns
    -------
    (S, R, 6) float32 ndarray
        Origins and unit directions in the map frame.
    """
    poses = np.asarray(poses, dtype=np.float64)
    d = scanner.directions()  # (R, 3)
    c, s = np.cos(poses[:, 3])[:, None], np.sin(poses[:, 3])[:, None]
    rays = np.empty((len(poses), len(d), 6), dtype=np.float32)
    rays[:, :, 0:3] = poses[:, None, 0:3]
    rays[:, :, 3] = c * d[None, :, 0] - s * d[None, :, 1]
    rays[:, :, 4] = s * d[None, :, 0] + c * d[None, :, 1]
    rays[:, :, 5] = d[None, :, 2]
    return rays


def measure_ranges(
    caster: RayCaster,
    scanner: Scanner,
    poses: np.ndarray,
    rng: np.random.Generator,
    return_exact: bool = False,
) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
    """Simulate the ranges of scans at ``poses`` (one Embree call for all of them).

    Parameters
    ----------
    caster : RayCaster
        The building.
    scanner : Scanner2D or Scanner3D
    poses : (S, 4) float64 ndarray
        Scanner poses ``x, y, z, yaw``, map frame.
    rng : numpy.random.Generator
        Draws the range noise: exactly S * R standard normals, in scan order, so the
        result does not depend on how scans are grouped into calls.
    return_exact : bool
        Also return the exact (noise-free) distances.

    Returns
    -------
    ranges : (S, R) float32 ndarray
        Measured ranges, metres; ``+inf`` no return, ``-inf`` closer than range_min.
    exact : (S, R) float32 ndarray, only with ``return_exact``
        Exact hit distances (``inf`` on a miss).

    Notes
    -----
    Thesis 4.1: Gaussian range noise, 1 cm standard deviation by default.
    """
    rays = scan_rays(scanner, poses)
    exact = caster.cast(rays)
    noise = rng.standard_normal(exact.shape, dtype=np.float32)
    ranges = exact + np.float32(scanner.range_noise_std_m) * noise
    ranges[~np.isfinite(exact) | (ranges > scanner.range_max_m)] = np.inf
    ranges[ranges < scanner.range_min_m] = -np.inf
    if return_exact:
        return ranges, exact
    return ranges


def scanner_points(
    scanner: Scanner, ranges: np.ndarray, directions: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Points of one scan in the scanner frame, valid returns only.

    Parameters
    ----------
    scanner : Scanner2D or Scanner3D
    ranges : (R,) float32 ndarray
        Ranges from :func:`measure_ranges` (non-finite = no return).
    directions : (R, 3) float64 ndarray, optional
        ``scanner.directions()``, when the caller already has it (saves recomputing).

    Returns
    -------
    points : (N, 3) float32 ndarray
        ``range * direction`` in the scanner frame, metres (z = 0 for 2D), computed in
        float64 from the float32 range (as a LaserScan reader would) and rounded.
    valid : (R,) bool ndarray
        Which beams gave a return.
    """
    valid = np.isfinite(ranges)
    d = (scanner.directions() if directions is None else directions)[valid]
    pts = ranges[valid].astype(np.float64)[:, None] * d
    return pts.astype(np.float32), valid


def to_map(points: np.ndarray, pose: np.ndarray) -> np.ndarray:
    """Scanner-frame points to the map frame: ``Rz(yaw) @ p + (x, y, z)``.

    Parameters
    ----------
    points : (N, 3) float ndarray
        Points in the scanner frame, metres.
    pose : (4,) float64 ndarray
        ``x, y, z, yaw`` (metres, radians).

    Returns
    -------
    (N, 3) float64 ndarray
    """
    p = np.asarray(points, dtype=np.float64)
    c, s = math.cos(pose[3]), math.sin(pose[3])
    out = np.empty_like(p)
    out[:, 0] = c * p[:, 0] - s * p[:, 1] + pose[0]
    out[:, 1] = s * p[:, 0] + c * p[:, 1] + pose[1]
    out[:, 2] = p[:, 2] + pose[2]
    return out


def iter_scan_batches(n_scans: int, n_rays: int, max_rays: int = 2_000_000) -> Iterator[slice]:
    """Slices of scan indices so that one batch casts at most ``max_rays`` rays."""
    step = max(1, max_rays // max(1, n_rays))
    for s in range(0, n_scans, step):
        yield slice(s, min(n_scans, s + step))

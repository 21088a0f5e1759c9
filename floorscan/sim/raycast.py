"""Ray casting: the ranges a scanner measures in the building mesh, and their points.

The thesis simulates its scans with BlenSor on a CAD model, with Gaussian range noise
of 1 cm standard deviation (section 4.1); openings are empty space, so rays pass
through doors and windows. Here rays are cast with Open3D's
``o3d.t.geometry.RaycastingScene`` (Embree), many scans in one call
(:func:`iter_scan_batches`).

Conventions
-----------
- The scanner pose in the map frame is ``(x, y, z, yaw)``:
  ``map_point = Rz(yaw) @ p + (x, y, z)`` (:func:`to_map`).
- All rays of a scan are cast at the scan's time stamp (no motion skew).
- Ranges: measured = exact distance + N(0, range_noise_std_m). A ray that hits
  nothing, or whose measured range exceeds ``range_max_m``, has no return (``+inf``);
  one below ``range_min_m`` is ``-inf`` (REP 117: "too close").
"""

from __future__ import annotations

import math
from typing import Iterator

import numpy as np

from floorscan.sim.scanners import Scanner


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
        """A caster of a mesh's triangles.

        Parameters
        ----------
        mesh : trimesh.Trimesh
            Metres.

        Returns
        -------
        RayCaster
        """
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
    """Slices of scan indices so that one batch casts at most ``max_rays`` rays (at
    least one scan per batch).

    Parameters
    ----------
    n_scans : int
    n_rays : int
        Rays per scan.
    max_rays : int

    Yields
    ------
    slice
        Consecutive, covering ``0..n_scans``.
    """
    step = max(1, max_rays // max(1, n_rays))
    for s in range(0, n_scans, step):
        yield slice(s, min(n_scans, s + step))

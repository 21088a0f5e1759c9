"""Scanner models: a planar (2D) and a spinning multi-beam (3D) LIDAR, and their config.

Conventions
-----------
- Scanner frame: x forward, y left, z up.
- A 2D scanner's beam ``i`` points at ``angle_min + i * angle_increment`` in the
  scanner's xy plane, like ``sensor_msgs/LaserScan``; the two angles are float32
  (as in the message), so points rebuilt from a LaserScan agree with the simulation.
- A 3D scanner fires all its elevation beams at each azimuth (azimuth-major order,
  like a spinning multi-beam LIDAR).

A scanner is a frozen dataclass whose fields are the keys of its config entry
(``simulate.scanners.<name>``, defaults equal to the schema's) with ``directions()``, the
unit rays in its frame, and ``range_min_m``, ``range_max_m``, ``range_noise_std_m``. To
add a kind, write its dataclass here and add it to :data:`Scanner`, to the ``kind`` map
of :func:`scanner_from_config` and to the schema's ``kind`` enum; the bag writes a
``Scanner2D`` as LaserScan and any other as PointCloud2 (:mod:`floorscan.sim.ros1`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

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

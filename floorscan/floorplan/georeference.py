"""The map frame on the earth: :class:`Georeference` (config ``floorplan.georeference``)
and the conversions between map metres and WGS84 longitude and latitude
(:func:`map_to_lonlat`, :func:`lonlat_to_map`).

The map frame of a recording is a local engineering frame (x and y in metres, z up,
no geodetic datum). Given the latitude and longitude of its origin and the compass
bearing of its +x axis, it is taken as the plane tangent to the WGS84 ellipsoid at the
origin (a local east-north-up frame turned by the heading): the first-order map
projection, within a millimetre of the ellipsoid within 100 m of the origin
(:func:`map_to_lonlat`). With a georeference the GeoJSON export writes longitude and
latitude, the SVG draws north and the IFC site carries its reference latitude,
longitude and true north (:mod:`floorscan.floorplan.geojson`, :mod:`~floorscan.floorplan.svg`,
:mod:`~floorscan.floorplan.ifc`). Source: the WGS84 ellipsoid (NIMA TR8350.2) and its
meridian and prime-vertical radii of curvature.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from floorscan.core.config import schema_defaults


#: WGS84 ellipsoid (NIMA TR8350.2): semi-major axis, metres, and flattening.
WGS84_A = 6378137.0
WGS84_F = 1.0 / 298.257223563


@dataclass(frozen=True)
@schema_defaults("floorplan.georeference")
class Georeference:
    """Where the map frame lies on the earth (config ``floorplan.georeference``).

    The map frame is taken as the plane tangent to the WGS84 ellipsoid at its origin
    (a local east-north-up frame turned by the heading): a map point ``(x, y)`` lies
    ``east = x sin(h) - y cos(h)``, ``north = x cos(h) + y sin(h)`` metres from the
    origin (``h`` the heading). See :func:`map_to_lonlat`.

    Attributes
    ----------
    lat : float
        WGS84 latitude of the map frame's origin, degrees, in (-90, 90) (at a pole
        east is undefined).
    lon : float
        WGS84 longitude of the origin, degrees, in [-180, 180].
    heading_deg : float
        Direction of the map frame's +x axis, degrees clockwise from true north (a
        compass bearing: 0 = +x points north and +y west, 90 = +x east and +y north).

    Raises
    ------
    ValueError
        For a value that is not a finite number or out of its range.
    """

    lat: float
    lon: float
    heading_deg: float

    def __post_init__(self):
        for name in ("lat", "lon", "heading_deg"):
            value = getattr(self, name)
            number = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
            if not number or not math.isfinite(value):
                raise ValueError(f"floorplan.georeference.{name} must be a finite number, got {value!r}")
            object.__setattr__(self, name, float(value))
        if not -90.0 < self.lat < 90.0:
            raise ValueError(f"floorplan.georeference.lat must be in (-90, 90) degrees, got {self.lat}")
        if not -180.0 <= self.lon <= 180.0:
            raise ValueError(f"floorplan.georeference.lon must be in [-180, 180] degrees, got {self.lon}")

    def radii(self) -> tuple[float, float]:
        """WGS84 radii of curvature at :attr:`lat`: meridian ``M = a (1 - e^2) /
        (1 - e^2 sin^2 lat)^1.5`` and prime vertical ``N = a / (1 - e^2 sin^2 lat)^0.5``.

        Returns
        -------
        m, n : float
            Metres.
        """
        e2 = WGS84_F * (2.0 - WGS84_F)
        w2 = 1.0 - e2 * math.sin(math.radians(self.lat)) ** 2
        return WGS84_A * (1.0 - e2) / w2**1.5, WGS84_A / math.sqrt(w2)

    def as_dict(self) -> dict:
        """``lat``, ``lon``, ``heading_deg`` and the conventions, for metadata.

        Returns
        -------
        dict
            Also ``heading`` and ``model``: the conventions in words.
        """
        return {
            "lat": self.lat, "lon": self.lon, "heading_deg": self.heading_deg,
            "heading": "direction of the map frame's +x axis, degrees clockwise from true north",
            "model": "local tangent plane at (lat, lon): WGS84 meridian and prime-vertical radii of curvature",
        }  # fmt: skip


def as_georeference(value: Georeference | Mapping[str, Any] | None) -> Georeference | None:
    """:class:`Georeference` of a config mapping (``lat``, ``lon``, optional
    ``heading_deg``), or the value itself when a Georeference or None.

    Parameters
    ----------
    value : Georeference, mapping or None
        ``lat``, ``lon`` degrees; ``heading_deg`` degrees clockwise from north.

    Returns
    -------
    Georeference or None

    Raises
    ------
    floorscan.core.config.ConfigError
        For an unknown or missing key, or a value the schema refuses
        (:func:`floorscan.core.config.stage_params`).
    ValueError
        For a value out of range (see :class:`Georeference`).
    """
    if value is None:
        return None
    from floorscan.core.config import stage_params

    return stage_params(Georeference, value, "floorplan.georeference")


def map_to_lonlat(x, y, georeference: Georeference) -> tuple[np.ndarray, np.ndarray]:
    """WGS84 longitude and latitude of map points, on the local tangent plane.

    ``lat = lat0 + north / M``, ``lon = lon0 + east / (N cos lat0)`` (radians; ``M``,
    ``N`` the radii of curvature at ``lat0``, :meth:`Georeference.radii`; east and
    north as in :class:`Georeference`): the first-order (tangent plane) map
    projection. The neglected curvature moves a point by about ``d^2 / R tan(lat0)``
    (``d`` its distance from the origin): under a millimetre within 100 m, about
    10 cm at 1 km at mid latitudes; a building is well inside. Longitudes are not
    wrapped at the antimeridian.

    Parameters
    ----------
    x, y : (N,) float array_like
        Map coordinates, metres.
    georeference : Georeference

    Returns
    -------
    lon, lat : (N,) float64 ndarray
        Degrees.
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    h = math.radians(georeference.heading_deg)
    east = x * math.sin(h) - y * math.cos(h)
    north = x * math.cos(h) + y * math.sin(h)
    m, n = georeference.radii()
    lat = georeference.lat + np.degrees(north / m)
    lon = georeference.lon + np.degrees(east / (n * math.cos(math.radians(georeference.lat))))
    return lon, lat


def lonlat_to_map(lon, lat, georeference: Georeference) -> tuple[np.ndarray, np.ndarray]:
    """Map coordinates of WGS84 longitudes and latitudes: the inverse of
    :func:`map_to_lonlat` (local tangent plane), e.g. to score a georeferenced GeoJSON
    plan in the map frame.

    Parameters
    ----------
    lon, lat : float or ndarray
        Degrees, one shape.
    georeference : Georeference

    Returns
    -------
    x, y : float64 ndarray
        Map metres, that shape.
    """
    lon, lat = np.asarray(lon, dtype=np.float64), np.asarray(lat, dtype=np.float64)
    m, n = georeference.radii()
    north = np.radians(lat - georeference.lat) * m
    east = np.radians(lon - georeference.lon) * (n * math.cos(math.radians(georeference.lat)))
    h = math.radians(georeference.heading_deg)
    return east * math.sin(h) + north * math.cos(h), -east * math.cos(h) + north * math.sin(h)

"""Plane geometry shared by the stages: points along wall segments, and the planar
rigid motions (SE(2)) of a rover's poses.

Usage::

    samples = sample_segments(segments, 0.02)        # (N, 2), segment after segment
    per_segment = samples_per_segment(segments, 0.02)
    dx, dy, dyaw = se2_between(pose_a, pose_b)       # b in a's frame
    pose_b = se2_compose(pose_a, (dx, dy, dyaw))
    in_map = transform_points(points, x, y, z, yaw)  # Rz(yaw) @ p + (x, y, z)

SE(2) as in Lynch and Park, "Modern Robotics" (2017), ch. 3, and the relative-pose
convention of graph SLAM (Grisetti et al. 2010).

Overlay operations on polygons (union, difference, intersection) that floating-point
precision can make fail (a GEOS TopologyException) run on the fixed precision grid
:data:`OVERLAY_GRID_M`: shapely's ``grid_size``, GEOS's OverlayNG with snap-rounding,
which is robust by construction (Hobby 1999; the JTS/GEOS OverlayNG documentation):
``shapely.difference(a, b, grid_size=OVERLAY_GRID_M)``. Such a result may hold parts of
lower dimension where areas meet in a line; keep its polygons before the next overlay.
"""

from __future__ import annotations

import math

import numpy as np

from floorscan.core.grid import ranks_in_runs

#: The fixed precision grid of polygon overlays, metres: the exports' precision
#: (GeoJSON's 5 decimals), far below a map cell and far above the floating-point
#: trouble of coordinates of a building's size.
OVERLAY_GRID_M = 1e-5


def samples_per_segment(segments: np.ndarray, sample_m: float) -> np.ndarray:
    """How many samples :func:`sample_segments` puts on each segment:
    ``ceil(length / sample_m) + 1``, at least 2 (its ends).

    Parameters
    ----------
    segments : (F, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    sample_m : float
        Sample spacing, metres.

    Returns
    -------
    (F,) int64 ndarray
    """
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    return np.maximum(np.ceil(length / sample_m).astype(np.int64), 1) + 1


def sample_segments(segments: np.ndarray, sample_m: float) -> np.ndarray:
    """Points every ``sample_m`` (at most) along each segment, ends included.

    Parameters
    ----------
    segments : (F, 4) float ndarray
        x0, y0, x1, y1 per segment, metres.
    sample_m : float
        Largest spacing, metres.

    Returns
    -------
    (N, 2) float64 ndarray
        The samples, segment after segment (:func:`samples_per_segment` of each),
        each standing for ``length / n`` metres of its segment (equal weights within a
        segment); see :func:`segment_weights`.
    """
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    if len(seg) == 0:
        return np.empty((0, 2))
    n = samples_per_segment(seg, sample_m)
    t = ranks_in_runs(n) / np.repeat(n - 1, n)
    out = np.repeat(seg[:, 2:] - seg[:, :2], n, axis=0)  # a + (b - a) t, each segment's b - a once
    out *= t[:, None]
    out += np.repeat(seg[:, :2], n, axis=0)
    return out


def sample_spacing(segments: np.ndarray, sample_m: float) -> np.ndarray:
    """Length each sample of :func:`sample_segments` stands for, once per segment.

    Parameters
    ----------
    segments : (F, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    sample_m : float
        Sample spacing, metres.

    Returns
    -------
    (F,) float64 ndarray
        Metres per sample: each segment's length divided by its
        :func:`samples_per_segment`.
    """
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    if len(seg) == 0:
        return np.empty(0)
    return np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1]) / samples_per_segment(seg, sample_m)


def segment_weights(segments: np.ndarray, sample_m: float) -> np.ndarray:
    """Length each sample of :func:`sample_segments` stands for.

    Parameters
    ----------
    segments : (F, 4) float ndarray
        ``x0, y0, x1, y1``, metres.
    sample_m : float
        Sample spacing, metres.

    Returns
    -------
    (N,) float64 ndarray
        Metres per sample, segment after segment: a segment's length divided by its
        :func:`samples_per_segment`; N is their sum.
    """
    seg = np.asarray(segments, dtype=np.float64).reshape(-1, 4)
    if len(seg) == 0:
        return np.empty(0)
    return np.repeat(sample_spacing(seg, sample_m), samples_per_segment(seg, sample_m))


# --------------------------------------------------------------------------- SE(2)
# A planar pose is ``(x, y, z, yaw)`` (metres, radians CCW from +x): the rover moves in
# x, y, yaw; z rides along unchanged.


def wrap_angle(a: np.ndarray | float) -> np.ndarray | float:
    """Wrap angles to [-pi, pi).

    Parameters
    ----------
    a : float or ndarray
        Angles, radians.

    Returns
    -------
    float64 ndarray
        Same shape as ``a`` (0-d for a scalar), radians.
    """
    return (np.asarray(a, dtype=np.float64) + np.pi) % (2.0 * np.pi) - np.pi


def axial_mean(angle: np.ndarray, weight: np.ndarray) -> float:
    """The weighted mean of axial directions (a line's direction, mod pi), on the
    doubled-angle circle (Mardia and Jupp, "Directional Statistics", 2000, sec. 9.1):
    walls fitted a fraction of a degree either way average to their common line, and a
    wall drawn end to start counts as one drawn start to end.

    Parameters
    ----------
    angle : (N,) float ndarray
        Directions, radians.
    weight : (N,) float ndarray
        Their weights (lengths, metres).

    Returns
    -------
    float
        Radians, in (-pi/2, pi/2].
    """
    angle, weight = np.asarray(angle, dtype=np.float64), np.asarray(weight, dtype=np.float64)
    return float(0.5 * np.arctan2((weight * np.sin(2 * angle)).sum(), (weight * np.cos(2 * angle)).sum()))


def se2_between(a, b) -> tuple[float, float, float]:
    """Planar motion from pose ``a`` to pose ``b``, in ``a``'s frame (Lynch and Park
    2017, ch. 3).

    Parameters
    ----------
    a, b : sequence of float
        Poses ``(x, y, z, yaw)`` or ``(x, y, yaw)``: metres, the last item the yaw in
        radians.

    Returns
    -------
    dx, dy : float
        Metres, in ``a``'s frame.
    dyaw : float
        Radians, wrapped to [-pi, pi).
    """
    ya, yb = a[-1], b[-1]
    c, s = math.cos(ya), math.sin(ya)
    dx, dy = b[0] - a[0], b[1] - a[1]
    return c * dx + s * dy, -s * dx + c * dy, float(wrap_angle(yb - ya))


def se2_compose(a, d) -> tuple[float, float, float, float]:
    """Pose ``a`` followed by the planar motion ``d`` in its frame: the inverse of
    :func:`se2_between`.

    Parameters
    ----------
    a : sequence of float
        ``(x, y, z, yaw)``, metres and radians.
    d : sequence of float
        ``(dx, dy, dyaw)`` in ``a``'s frame, metres and radians.

    Returns
    -------
    tuple of float
        ``(x, y, z, yaw)``: ``z`` is ``a``'s, yaw wrapped to [-pi, pi).
    """
    c, s = math.cos(a[3]), math.sin(a[3])
    return (a[0] + c * d[0] - s * d[1], a[1] + s * d[0] + c * d[1], a[2], float(wrap_angle(a[3] + d[2])))


def se2_matrix(x: float, y: float, yaw: float) -> np.ndarray:
    """Homogeneous transform of a planar pose (z 0), as Open3D takes it.

    Parameters
    ----------
    x, y : float
        Translation, metres.
    yaw : float
        Rotation about +z, radians counter-clockwise.

    Returns
    -------
    (4, 4) float64 ndarray
    """
    c, s = math.cos(yaw), math.sin(yaw)
    m = np.eye(4)
    m[:2, :2] = [[c, -s], [s, c]]
    m[0, 3], m[1, 3] = x, y
    return m


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

def point_segment_dist2(px: np.ndarray, py: np.ndarray, seg: np.ndarray) -> np.ndarray:
    """Squared distance from each point to the matching row of ``seg`` (a zero-length
    segment is its point): the floor plan's candidate pairs and the scores' nearest
    distances.

    Parameters
    ----------
    px, py : (P,) float ndarray
        Point coordinates, metres.
    seg : (P, 4) float ndarray
        ``x0, y0, x1, y1`` per point, metres.

    Returns
    -------
    (P,) float64 ndarray
        Square metres.
    """
    ax, ay, bx, by = seg[:, 0], seg[:, 1], seg[:, 2], seg[:, 3]
    dx, dy = bx - ax, by - ay
    l2 = dx * dx + dy * dy
    with np.errstate(invalid="ignore", divide="ignore"):
        t = ((px - ax) * dx + (py - ay) * dy) / l2
    t = np.where(l2 > 0, np.clip(t, 0.0, 1.0), 0.0)
    ex = ax + t * dx - px
    ey = ay + t * dy - py
    return ex * ex + ey * ey


def ray_meets_lines(origin: np.ndarray, u: np.ndarray, p0: np.ndarray, dirs: np.ndarray):
    """Where the ray ``origin + t u`` meets each line ``p0 + s dirs``: the floor plan's
    wall ends run on to the walls ahead of them.

    Parameters
    ----------
    origin, u : (2,) float ndarray
        The ray's start, metres, and unit direction.
    p0, dirs : (N, 2) float ndarray
        A point of each line, metres, and its unit direction.

    Returns
    -------
    cross : (N,) float64 ndarray
        The sine of the angle from ``u`` to each line.
    t, s : (N,) float64 ndarray
        Where they meet, metres along the ray and along the line from ``p0``; NaN for a
        line parallel to the ray (``|cross| < 1e-6``).
    off : (N,) float64 ndarray
        Each line's point ``p0``'s distance from the ray's line, metres.
    """
    d = p0 - origin
    cross = u[0] * dirs[:, 1] - u[1] * dirs[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(np.abs(cross) >= 1e-6, (d[:, 0] * dirs[:, 1] - d[:, 1] * dirs[:, 0]) / cross, np.nan)
        s = np.where(np.abs(cross) >= 1e-6, (d[:, 0] * u[1] - d[:, 1] * u[0]) / cross, np.nan)
    off = np.abs(d[:, 0] * u[1] - d[:, 1] * u[0])
    return cross, t, s, off


def polygons_of(geom):
    """The polygons of a geometry (an overlay's result on :data:`OVERLAY_GRID_M`, where two
    areas may also meet in a line or a point), as one polygonal geometry on that grid.

    Parameters
    ----------
    geom : shapely geometry

    Returns
    -------
    shapely Polygon, MultiPolygon or empty GeometryCollection
        Map metres.
    """
    import shapely

    parts = shapely.get_parts(shapely.get_parts(geom))
    return shapely.union_all([g for g in parts if g.geom_type == "Polygon"], grid_size=OVERLAY_GRID_M)


def minus(geom, *others):
    """``geom`` without each of ``others``, on :data:`OVERLAY_GRID_M` (GEOS overlays
    that cannot fail on precision); of a geometry of mixed dimensions, its polygons.

    Parameters
    ----------
    geom : shapely geometry
    *others : shapely geometry

    Returns
    -------
    shapely geometry
        Map metres.
    """
    import shapely

    for other in others:  # one by one: a union of a large one with each small one costs more
        geom = shapely.difference(_areas(geom), _areas(other), grid_size=OVERLAY_GRID_M)
    return geom


def _areas(geom):
    """A polygonal geometry as it is; any other (a GeometryCollection of make_valid or of
    an overlay on the grid, which OverlayNG refuses as input) as :func:`polygons_of`."""
    return geom if geom.is_empty or geom.geom_type in ("Polygon", "MultiPolygon") else polygons_of(geom)

"""Wall extraction: wall segments of one scan by iterative RANSAC or clustering RANSAC.

A scan's registered points (map frame, metres, ``z`` = height above the floor) are
reduced to 2D wall points (:func:`scan_points_2d`) and then fitted with lines:

* :func:`ransac`, thesis section 5.3 / Algorithm 4: fit a line by RANSAC, remove its
  inliers, repeat until fewer than ``min_points`` points remain or ``max_lines``
  lines were found. It tends to find several candidates for one wall (section 5.3).
* :func:`cluster_ransac`, thesis section 3.4: a normal for every point, a projection
  along the normals under which the points of one wall fall together, MeanShift
  clustering of the projection, and a single RANSAC per cluster.

Both turn a fitted line into wall segments with the same rules
(:func:`_claimed_segments`): the ends are the extent of the inliers along the line,
a line is split where its inliers leave a gap wider than ``max_gap_m`` (a wall with
a door is two segments), and segments with fewer than ``min_inliers`` points or
shorter than ``min_length_m`` are dropped.

The walls of a scan depend only on its points, the extractor parameters and the
seed: the random generator of scan ``s`` is ``numpy.random.default_rng((seed, s))``,
so the walls of a scan do not change with the ordering or the number of scans used.

Per-scan problems never raise: :func:`extract_walls` returns no walls for such a scan
and a reason in its status table (see :data:`REASONS`).

Speed (issue 8). Shortcuts that give the same walls bit for bit (checked on every
scan of hallways and hallways3d against the plain forms, and in the tests):

- RANSAC inlier counts in cache-sized blocks of hypotheses (:func:`_inlier_counts`),
  with the same BLAS products;
- the grid thinning of 3D scans and the MeanShift bins with a 1D int64 cell key
  instead of ``numpy.unique(axis=0)``, and ``bincount`` sums in point order;
- the neighbourhood covariances of the normals computed as Open3D computes them
  (:func:`neighbourhood_covariances`, SciPy k-d tree), so a job does not import
  Open3D (2.5 s, as Open3D imports scikit-learn); scikit-learn is imported only
  for ``meanshift: sklearn`` or an estimated bandwidth;
- no pandas frame per scan: segments stay tuples until one frame per job, and
  :func:`extract_walls` takes scans streamed from the file (memory: one scan);
- fewer passes and fewer small numpy calls per scan (issue 8, second round; same
  floats, checked table for table on hallways3d shard 0, trace0, intel and demo, and
  in the tests): the RANSAC distances and the MeanShift squared distances as one
  BLAS product each (offsets and norms as extra terms of the product), counts as
  byte sums, MeanShift iterating only its moving seeds, bin seeding without the
  inverse, each line's points sorted and split at its gaps once
  (:func:`_claimed_segments`) and fast paths for a wall without gaps;
- third round (same floats: walls and scan status tables equal on hallways3d scans
  0..1694 and 3390..5080, hallways, trace0, intel, aces, freiburg101, orebro,
  mac_ros2 and demo, both extractors; and in the tests): MeanShift's 1D bin seeds by
  a sort, its sums of two squares term by term instead of reductions over a short
  axis (:func:`_row_squares`, :func:`_pair_squares`), :func:`fit_line`'s three sums
  in one reduction, the covariances' non-neighbours zeroed by a product, and
  ``integers(n)`` for ``integers(0, n)``;
- fourth round (same floats: walls and scan status tables equal on hallways3d scans
  0..5080, hallways, trace0, intel, aces, freiburg101, orebro, mac_ros2 and demo,
  both extractors; and in the tests): the k-d tree of the normals unbalanced (split
  at the middle of the cell, not the median: ~20 % quicker to build and search; the
  same neighbours in the same order unless two distinct points lie at exactly the
  same distance, as on a lattice, where the order of the tied ones may differ), the
  RANSAC hypotheses built on coordinate columns straight into the rows of the
  distance product (:func:`_hypothesis_counts`), the 3D band cut and grid thinning
  on contiguous columns (:func:`floorscan.core.grid.cell_means`), MeanShift's kernel weights in
  place, and fewer temporaries in :func:`neighbourhood_covariances`.
"""

from __future__ import annotations

import logging
import math
import time
import warnings
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

import numpy as np
import pandas as pd
import pyarrow as pa

from floorscan.core.grid import cell_groups, cell_means

log = logging.getLogger(__name__)

#: Extractor names (config ``walls.extractors``, wildcard ``{extractor}``).
EXTRACTORS = ("ransac", "cluster_ransac")

#: Wall segments of scans (``walls/{extractor}/per_scan.parquet`` and
#: ``walls/{ordering}/{extractor}/k{k}.parquet``).
WALLS = pa.schema(
    [
        ("scan_id", pa.int32()),
        ("x0", pa.float64()),
        ("y0", pa.float64()),
        ("x1", pa.float64()),
        ("y1", pa.float64()),
        ("n_inliers", pa.int32()),
        ("rmse_m", pa.float64()),
    ]
)
#: One row per scan of ``registered.parquet`` (``walls/{extractor}/scan_status.parquet``).
#: No timing: the same input gives the same file (the times: :data:`SCAN_TIMES`).
SCAN_STATUS = pa.schema(
    [
        ("scan_id", pa.int32()),
        ("n_points", pa.int32()),
        ("n_walls", pa.int32()),
        ("reason", pa.string()),
    ]
)
#: The wall-clock seconds of each scan's extraction
#: (``benchmarks/scan_walls_{extractor}_times.parquet``, thesis Fig. 5.10): beside the
#: benchmark files, since they change from run to run.
SCAN_TIMES = pa.schema([("scan_id", pa.int32()), ("time_s", pa.float64())])
#: Reasons a scan gives no walls ("" when it gave walls).
REASONS = (
    "non_finite_coordinates",  # a NaN/inf coordinate: the scan is corrupt, not used
    "no_points_in_height_band",  # 3D scan with no point between the band's heights
    "too_few_points",  # fewer than min_points wall points
    "no_wall_found",  # no line with min_inliers inliers and min_length_m
)

_SEGMENT_COLUMNS = ["x0", "y0", "x1", "y1", "n_inliers", "rmse_m"]


@dataclass(frozen=True)
class RansacParams:
    """RANSAC and segment parameters (config ``walls.ransac``), used by both extractors.

    Attributes
    ----------
    threshold_m : float
        A point is an inlier of a line when closer than this, metres.
    iterations : int
        Line hypotheses (pairs of points) tried per RANSAC run.
    refine_iterations : int
        Least-squares refits of the best hypothesis on its inliers.
    min_points : int
        Iterative RANSAC stops when fewer points remain; a scan with fewer wall
        points gives no walls (reason ``too_few_points``).
    max_lines : int
        Iterative RANSAC stops after this many lines (``ransac`` only).
    min_inliers : int
        Fewest inliers of a line and of each of its segments.
    min_length_m : float
        Shortest wall segment kept, metres.
    max_gap_m : float
        A line is split into segments where consecutive inliers (along the line)
        are further apart than this, metres.
    min_coverage : float
        A segment is kept when its inliers cover at least this fraction of its length:
        gaps between consecutive inliers wider than ``coverage_gap_m`` count as
        uncovered. Rejects "walls" through a few isolated objects, e.g. the legs of a
        table or chairs (clutter, thesis 2.3), which RANSAC lines up as readily as a
        wall; a wall is covered nearly everywhere it is seen. Our rule; 0 disables it.
    coverage_gap_m : float
        A gap between consecutive inliers is uncovered when wider than this and than
        3 times both neighbouring gaps, metres: a jump, as between table legs, not the
        spacing that grows smoothly along a wall seen at a grazing angle.
    """

    threshold_m: float = 0.03
    iterations: int = 200
    refine_iterations: int = 2
    min_points: int = 20
    max_lines: int = 30
    min_inliers: int = 15
    min_length_m: float = 0.3
    max_gap_m: float = 0.5
    min_coverage: float = 0.6
    coverage_gap_m: float = 0.10


@dataclass(frozen=True)
class ClusterParams:
    """Clustering parameters of :func:`cluster_ransac` (config ``walls.cluster_ransac``).

    Attributes
    ----------
    normal_radius_m : float
        Neighbourhood radius of the normal estimation, metres.
    normal_max_nn : int
        At most this many neighbours within the radius (Open3D hybrid search).
    angle_bandwidth_rad : float
        MeanShift bandwidth of the normal direction, radians.
    offset_bandwidth_m : float or None
        MeanShift bandwidth of the offset along the normal, metres; None estimates it
        per direction with :func:`sklearn.cluster.estimate_bandwidth`.
    min_cluster_points : int
        Clusters with fewer points are not fitted; MeanShift seeds need a third of it
        (``min_bin_freq = min_cluster_points // 3``).
    bin_seeding : bool
        Seed MeanShift on a grid of the bandwidth's size (much faster).
    meanshift : {"numpy", "sklearn"}
        MeanShift implementation: :func:`mean_shift` (same algorithm vectorised,
        needs ``bin_seeding``) or :class:`sklearn.cluster.MeanShift`.
    """

    normal_radius_m: float = 0.25
    normal_max_nn: int = 20
    angle_bandwidth_rad: float = 0.1
    offset_bandwidth_m: float | None = 0.05
    min_cluster_points: int = 15
    bin_seeding: bool = True
    meanshift: str = "numpy"

    def __post_init__(self):
        if self.meanshift not in ("numpy", "sklearn"):
            raise ValueError(f"cluster_ransac.meanshift must be 'numpy' or 'sklearn', got {self.meanshift!r}")
        if self.meanshift == "numpy" and not self.bin_seeding:
            raise ValueError("cluster_ransac.meanshift 'numpy' needs bin_seeding true")


@dataclass(frozen=True)
class ScanParams:
    """How a scan becomes 2D wall points (config ``walls``: height band and grid).

    Attributes
    ----------
    min_height_m, max_height_m : float
        Height band (above the floor) kept of 3D scans, metres.
    planar_tolerance_m : float
        A scan whose finite ``z`` values span at most this is 2D and passes unchanged
        (a 2D scanner has one height whatever it is); otherwise it is 3D.
    grid_m : float
        3D scans only: after the band cut and the projection to (x, y), keep one
        point (the mean) per grid cell of this size, metres; 0 keeps all points.
    """

    min_height_m: float = 0.5
    max_height_m: float = 2.0
    planar_tolerance_m: float = 0.01
    grid_m: float = 0.02


def params_from_config(cfg: Mapping[str, Any]) -> tuple[ScanParams, RansacParams, ClusterParams]:
    """The parameter objects of the ``walls`` config section (defaults filled in).

    Raises
    ------
    KeyError
        When the section has a key the parameter classes do not know.
    ValueError
        For a height band that is not [min, max] with min < max.
    """
    band = cfg.get("height_band_m", [ScanParams.min_height_m, ScanParams.max_height_m])
    if len(band) != 2 or not float(band[0]) < float(band[1]):
        raise ValueError(f"walls.height_band_m must be [min, max] with min < max, got {band!r}")
    scan = ScanParams(
        min_height_m=float(band[0]),
        max_height_m=float(band[1]),
        planar_tolerance_m=float(cfg.get("planar_tolerance_m", ScanParams.planar_tolerance_m)),
        grid_m=float(cfg.get("grid_m", ScanParams.grid_m)),
    )
    from floorscan.core.config import dataclass_from_mapping

    return (
        scan,
        dataclass_from_mapping(RansacParams, cfg.get("ransac"), "RansacParams"),
        dataclass_from_mapping(ClusterParams, cfg.get("cluster_ransac"), "ClusterParams"),
    )


# --------------------------------------------------------------------------------------
# Scan points
# --------------------------------------------------------------------------------------


def scan_points_2d(xyz: np.ndarray, params: ScanParams = ScanParams()) -> tuple[np.ndarray, str]:
    """The 2D wall points of one scan, or a reason why it has none.

    Rule for 2D against 3D: a scan whose ``z`` values span at most
    ``planar_tolerance_m`` came from a 2D scanner and passes unchanged (its single
    height may be anywhere, e.g. 0.3 m). Otherwise the scan is 3D: points with
    ``min_height_m <= z <= max_height_m`` are kept (above furniture, below the
    ceiling), projected to (x, y) and thinned to one mean point per ``grid_m`` cell.

    Parameters
    ----------
    xyz : (N, 3) float ndarray
        Scan points in the map frame, metres; ``z`` is height above the floor.
    params : ScanParams

    Returns
    -------
    points : (M, 2) float64 ndarray
        Wall points (x, y), metres; empty when ``reason`` is not "".
    reason : str
        "" or one of :data:`REASONS` (``non_finite_coordinates``,
        ``no_points_in_height_band``).
    """
    xyz = np.asarray(xyz, dtype=np.float64)
    if xyz.ndim != 2 or xyz.shape[1] < 2:
        raise ValueError(f"scan points must be (N, 3), got shape {xyz.shape}")
    empty = np.empty((0, 2))
    if len(xyz) == 0:
        return empty, ""
    if not np.isfinite(xyz).all():
        return empty, "non_finite_coordinates"
    if xyz.shape[1] == 2:
        return xyz.copy(), ""
    z = xyz[:, 2].copy()  # contiguous: min, max and the band cut are 4x faster
    if float(z.max() - z.min()) <= params.planar_tolerance_m:
        return xyz[:, :2].copy(), ""
    band = np.flatnonzero((z >= params.min_height_m) & (z <= params.max_height_m))
    if len(band) == 0:
        return empty, "no_points_in_height_band"
    if params.grid_m > 0:
        return cell_means(xyz[band, :2], params.grid_m)[0], ""  # one mean point per occupied cell
    return xyz[band, :2], ""


# --------------------------------------------------------------------------------------
# Lines and segments
# --------------------------------------------------------------------------------------


def fit_line(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Total least squares line through 2D points (principal axis of their covariance).

    Parameters
    ----------
    points : (N, 2) float ndarray, N >= 2
        Points, metres.

    Returns
    -------
    centroid : (2,) float64 ndarray
        A point of the line (the points' mean), metres.
    direction : (2,) float64 ndarray
        Unit direction of the line; the normal is ``(-direction[1], direction[0])``.
    """
    c = np.add.reduce(points, axis=0) / len(points)  # points.mean(axis=0), fewer calls
    d = (points - c).T  # rows dx, dy
    prod = np.empty((3, len(points)))  # rows dx * dx, dy * dy, dx * dy
    np.multiply(d, d, out=prod[:2])
    np.multiply(d[0], d[1], out=prod[2])
    # one reduction along the rows: each row is summed as np.add.reduce sums it alone
    # (checked for every length up to 20000 and for sampled lengths up to 10**6)
    sxx, syy, sxy = np.add.reduce(prod, axis=1)
    phi = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)  # angle of the major axis
    return c, np.array([np.cos(phi), np.sin(phi)])


def _best_line(points: np.ndarray, rng: np.random.Generator, params: RansacParams):
    """One RANSAC run: the line with most inliers among ``iterations`` point pairs,
    refit by total least squares on its inliers. Returns (inlier mask, centroid,
    direction) or None when no hypothesis is possible.

    The hypotheses are built on contiguous coordinate columns, straight into the rows
    ``(nx, ny, -offset)`` of :func:`_hypothesis_counts` (issue 8): the same floats as
    ``normals = (-dy, dx) / length`` and ``offsets = einsum("ij,ij->i", normals,
    start)`` (a sum of two products, rounded term by term: checked on 10**7 random
    pairs, and in the tests)."""
    n = len(points)
    if n < 2:
        return None
    # integers(n) is integers(0, n) (the same draws), without the checks of low
    i = rng.integers(n, size=params.iterations)
    j = rng.integers(n - 1, size=params.iterations)
    j += j >= i  # j != i
    pt = np.empty((3, n))  # rows x, y, 1 (the columns of _hypothesis_counts)
    pt[:2] = points.T
    pt[2] = 1.0
    sx, sy = pt[0, i], pt[1, i]
    dx, dy = pt[0, j], pt[1, j]
    dx -= sx
    dy -= sy
    length = np.hypot(dx, dy)
    ok = length > 1e-9
    if not ok.all():
        if not ok.any():
            return None
        dx, dy, length, sx, sy = dx[ok], dy[ok], length[ok], sx[ok], sy[ok]
    hyp = np.empty((3, len(length)))  # rows nx = -dy / length, ny = dx / length, offset
    np.negative(dy, out=dy)
    np.divide(dy, length, out=hyp[0])
    np.divide(dx, length, out=hyp[1])
    np.multiply(hyp[0], sx, out=sx)
    np.multiply(hyp[1], sy, out=sy)
    np.add(sx, sy, out=hyp[2])  # the offsets
    best = int(np.argmax(_hypothesis_counts(pt, hyp.T, params.threshold_m, negate=True)))
    return _refine_line(points, hyp[:2, best].copy(), hyp[2, best], params)


def _refine_line(points: np.ndarray, normal: np.ndarray, offset: float, params: RansacParams):
    """The inliers of the line ``points @ normal == offset`` refitted (least squares)
    to their own inliers up to ``params.refine_iterations`` times, until they no longer
    change: ``(mask, centre, direction)`` as :func:`_best_line` returns them."""
    mask = np.abs(points @ normal - offset) < params.threshold_m
    n_mask = np.count_nonzero(mask)
    c, direction = None, np.array([normal[1], -normal[0]])
    for _ in range(params.refine_iterations):
        if n_mask < 2:
            break
        c, direction = fit_line(points[mask])
        normal = np.array([-direction[1], direction[0]])
        new = np.abs((points - c) @ normal) < params.threshold_m
        n_new = np.count_nonzero(new)
        if n_new < 2 or (n_new == n_mask and (new == mask).all()):
            mask = new if n_new >= 2 else mask
            break
        mask, n_mask = new, n_new
    if c is None:  # no refit: the line through the inliers' mean
        c = points[mask].mean(axis=0)
    return mask, c, direction


def _inlier_counts(points: np.ndarray, normals: np.ndarray, offsets: np.ndarray, threshold: float) -> np.ndarray:
    """Points closer than ``threshold`` to each line ``normals[h] . p = offsets[h]``
    (:func:`_hypothesis_counts` of the points and hypotheses)."""
    n = len(points)
    pt = np.empty((3, n))
    pt[:2] = points.T
    pt[2] = 1.0
    hyp = np.empty((len(normals), 3))
    hyp[:, :2] = normals
    np.negative(offsets, out=hyp[:, 2])
    return _hypothesis_counts(pt, hyp, threshold)


def _hypothesis_counts(pt: np.ndarray, hyp: np.ndarray, threshold: float, negate: bool = False) -> np.ndarray:
    """Columns ``pt`` (3, N) = (x, y, 1) closer than ``threshold`` to each line ``hyp``
    (H, 3) = (nx, ny, -offset), or (nx, ny, offset) with ``negate`` (the offsets are
    negated in a copy; ``hyp`` is not modified).

    Hypotheses in blocks of about 64k distances (at least 4; the block stays in the CPU cache;
    16 MB blocks were 3x slower), laid out (hypothesis, point) so the count runs
    along contiguous memory, into reused buffers. The signed distance is one BLAS
    product of ``(nx, ny, -offset)`` with ``(x, y, 1)``: the kernel accumulates along
    the 3 terms in order with fused multiply-adds, so it rounds as ``points @ normals.T``
    then ``- offsets`` (checked bit for bit on every RANSAC run of hallways3d,
    trace0, intel and demo, and in the tests); it saves a pass over the block
    (issue 8). The count sums the bytes of the boolean block (exact; 3x faster than
    ``count_nonzero(axis=1)``).
    """
    n = pt.shape[1]
    if negate:
        hyp = hyp * np.array([1.0, 1.0, -1.0])  # a C-ordered copy, exact
    counts = np.empty(len(hyp), dtype=np.int64)
    block = max(4, 65536 // max(n, 1))
    dist = np.empty((min(block, len(hyp)), n))
    inlier = np.empty(dist.shape, dtype=bool)
    count_type = np.uint16 if n < 2**16 else np.int64
    for s in range(0, len(hyp), block):
        e = min(s + block, len(hyp))
        d, m = dist[: e - s], inlier[: e - s]
        np.matmul(hyp[s:e], pt, out=d)
        np.abs(d, out=d)
        np.less(d, threshold, out=m)
        counts[s:e] = m.view(np.uint8).sum(axis=1, dtype=count_type)
    return counts


def _uncovered_length(t: np.ndarray, min_gap: float) -> float:
    """Summed length of the jumps between sorted positions ``t`` (metres): gaps wider
    than ``min_gap`` and 3 times both neighbouring gaps (see ``RansacParams``)."""
    g = t[1:] - t[:-1]  # numpy.diff
    if len(g) == 0 or not (g > min_gap).any():  # no jump: the usual case
        return 0.0
    near = np.zeros(len(g))  # the larger neighbouring gap (0 beyond the ends)
    near[1:] = g[:-1]
    np.maximum(near[:-1], g[1:], out=near[:-1])
    jump = (g > min_gap) & (g > 3.0 * near)
    return float(g[jump].sum())


def _piece_segment(points: np.ndarray, direction: np.ndarray, params: RansacParams) -> tuple | None:
    """The wall segment of one piece of a line's inliers (no gap wider than
    ``max_gap_m``, :func:`_claimed_segments`), or None.

    A piece with at least ``min_inliers`` points is refit by total least squares;
    its ends are the extent of its points along the refit line; it is kept when at
    least ``min_length_m`` long and covered by its inliers over ``min_coverage`` of
    its length. Returns (x0, y0, x1, y1, n_inliers, rmse_m).
    """
    if len(points) < max(params.min_inliers, 2):
        return None
    c, d = fit_line(points)
    if d @ direction < 0:
        d = -d
    pc = points - c
    u = pc @ d
    lo, hi = float(np.minimum.reduce(u)), float(np.maximum.reduce(u))
    if hi - lo < params.min_length_m:
        return None
    if params.min_coverage > 0:
        uncovered = _uncovered_length(np.sort(u), params.coverage_gap_m)
        if 1.0 - uncovered / (hi - lo) < params.min_coverage:
            return None
    resid = pc @ np.array([-d[1], d[0]])
    a, b = c + lo * d, c + hi * d
    rmse = math.sqrt(np.add.reduce(resid * resid) / len(resid))  # sqrt(mean(resid**2))
    return (a[0], a[1], b[0], b[1], len(points), rmse)


def _frame(rows: list[tuple]) -> pd.DataFrame:
    df = pd.DataFrame(rows, columns=_SEGMENT_COLUMNS)
    return df.astype({c: "float64" for c in _SEGMENT_COLUMNS if c != "n_inliers"} | {"n_inliers": "int32"})


def ransac(points: np.ndarray, params: RansacParams = RansacParams(), seed=0) -> pd.DataFrame:
    """Wall segments of one scan by iterative RANSAC (thesis section 5.3, Algorithm 4).

    Repeat: the best of ``iterations`` lines through two random points (most points
    closer than ``threshold_m``), refit by total least squares on its inliers
    (``refine_iterations`` times), split into segments (:func:`_claimed_segments`),
    remove its inliers. The segment ends come from all points of the scan near the
    line (:func:`_claimed_segments`), so a corner point claimed by the first of two
    walls still ends the second one. Stop when fewer than ``min_points`` points
    remain, the best line has fewer than ``min_inliers`` inliers, or ``max_lines``
    lines were found.
    Fischler and Bolles (1981), Random sample consensus.

    Parameters
    ----------
    points : (N, 2) float ndarray
        Wall points of one scan (map frame), metres. Not modified.
    params : RansacParams
    seed : int, sequence of int or numpy.random.Generator
        Seeds the generator (``numpy.random.default_rng(seed)``); same seed, same walls.

    Returns
    -------
    pandas.DataFrame
        One row per wall segment: ``x0, y0, x1, y1`` (metres), ``n_inliers`` (int32),
        ``rmse_m`` (RMS distance of its inliers to it, metres); in order of discovery.
    """
    return _frame(_ransac_rows(points, params, seed))


def _ransac_rows(points: np.ndarray, params: RansacParams, seed) -> list[tuple]:
    """:func:`ransac` as a list of (x0, y0, x1, y1, n_inliers, rmse_m) tuples."""
    rng = np.random.default_rng(seed)
    all_pts = np.asarray(points, dtype=np.float64)
    alive = np.arange(len(all_pts))  # indices of the points not yet claimed by a line
    rows: list[tuple] = []
    n_lines = 0
    while len(alive) >= params.min_points and n_lines < params.max_lines:
        fit = _fit_wall(all_pts, alive, rng, params)
        if fit is None:
            break
        mask, segments = fit
        rows += segments
        alive = alive[~mask]
        n_lines += 1
    return rows


# --------------------------------------------------------------------------------------
# Clustering RANSAC (section 3.4)
# --------------------------------------------------------------------------------------


def point_normals(points: np.ndarray, radius_m: float = 0.25, max_nn: int = 20) -> np.ndarray:
    """In-plane unit normals of 2D points from their neighbourhoods.

    Open3D's ``estimate_normals`` on points embedded at z = 0 returns the z axis for
    every point (for planar data the smallest-variance direction is always z; checked
    with Open3D 0.19 and tested). So the normal comes from the neighbourhood
    covariance of Open3D's ``estimate_covariances`` with ``KDTreeSearchParamHybrid(
    radius_m, max_nn)`` (:func:`neighbourhood_covariances`, the same numbers computed
    with SciPy's k-d tree: importing Open3D costs 2.5 s per job, as it imports
    scikit-learn) and is the eigenvector of the smallest eigenvalue of the 2x2
    covariance (closed form).

    Normals are axial (a line has no preferred side): they are folded into the
    canonical half-plane, angle in [0, pi). The clustering of :func:`cluster_ransac`
    only uses sign-free quantities, so no scanner position is needed.

    Parameters
    ----------
    points : (N, 2) float ndarray
        Points, metres.
    radius_m : float
        Neighbourhood radius, metres.
    max_nn : int
        At most this many neighbours.

    Returns
    -------
    (N, 2) float64 ndarray
        Unit normals with angle in [0, pi); NaN for points with fewer than 3
        neighbours or an isotropic neighbourhood.
    """
    sxx, syy, sxy = neighbourhood_covariances(points, radius_m, max_nn)
    # Major axis angle phi of the 2x2 covariance; the normal is perpendicular to it.
    phi = 0.5 * np.arctan2(2.0 * sxy, sxx - syy)
    theta = np.mod(phi + 0.5 * np.pi, np.pi)
    normals = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    spread = np.hypot(sxx - syy, 2.0 * sxy)  # eigenvalue difference
    normals[spread <= 1e-12] = np.nan
    return normals


def neighbourhood_covariances(
    points: np.ndarray, radius_m: float = 0.25, max_nn: int = 20
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Covariance of each point's neighbourhood, as Open3D's ``estimate_covariances``.

    The neighbourhood of a point is its ``max_nn`` nearest points (itself included)
    closer than ``radius_m`` (squared distance ``< radius_m**2``), nearest first, as
    Open3D's hybrid search; the covariance is Open3D's ``ComputeCovariance``: sums
    of x, y, x*x, x*y, y*y accumulated neighbour by neighbour in that order, divided
    by the count, ``E[xy] - E[x] E[y]``; with fewer than 3 neighbours it is the
    identity. The same floats as Open3D 0.19 (tested), without importing it.

    Parameters
    ----------
    points : (N, 2) float ndarray
        Points, metres.
    radius_m : float
        Neighbourhood radius, metres.
    max_nn : int
        At most this many neighbours.

    Returns
    -------
    sxx, syy, sxy : (N,) float64 ndarray
        Covariance entries, square metres.
    """
    from scipy.spatial import cKDTree

    pts = np.asarray(points, dtype=np.float64)
    n = len(pts)
    if n == 0:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    k = int(min(max_nn, n))
    # slightly wider bound, then the exact rule on squared distances
    # an unbalanced tree (split at the midpoint of the cell, not the median) is ~20 %
    # quicker to build and to search here (issue 8); the neighbours and their order are
    # the same but for distinct points at exactly equal distances (lattices)
    _, idx = cKDTree(pts, balanced_tree=False).query(pts, k=k, distance_upper_bound=radius_m * (1 + 1e-9))
    # (k, N) layout: a sum over axis 0 adds neighbour after neighbour for every point,
    # in order, as Open3D does (no pairwise summation: that is for the inner axis);
    # "+ 0.0" as Open3D's sums start from +0.0 (only the sign of a zero sum differs)
    idx = np.ascontiguousarray(np.asarray(idx).reshape(n, k).T)
    ok = idx < n
    idx *= ok  # missing neighbours (index n) -> 0
    px, py = pts[:, 0].copy(), pts[:, 1].copy()
    x, y = px[idx], py[idx]
    d2, dy = x - px, y - py  # dx * dx + dy * dy in place
    d2 *= d2
    dy *= dy
    d2 += dy
    ok &= d2 < radius_m * radius_m
    cnt = ok.view(np.uint8).sum(axis=0, dtype=np.int64)
    # the points that are no neighbours become zeros (-0.0 for a negative coordinate:
    # no matter, a non-zero sum is unchanged by it and the "+ 0.0" makes a zero sum +0.0)
    x *= ok
    y *= ok
    sxy = np.multiply(x, y, out=d2).sum(axis=0) + 0.0  # x * y into a dead buffer
    sx, sy = x.sum(axis=0) + 0.0, y.sum(axis=0) + 0.0
    x *= x
    y *= y
    sxx, syy = x.sum(axis=0) + 0.0, y.sum(axis=0) + 0.0
    m = np.maximum(cnt, 1).astype(np.float64)
    sx, sy, sxx, sxy, syy = sx / m, sy / m, sxx / m, sxy / m, syy / m
    cxx, cyy, cxy = sxx - sx * sx, syy - sy * sy, sxy - sx * sy
    few = cnt < 3
    cxx[few], cyy[few], cxy[few] = 1.0, 1.0, 0.0
    return cxx, cyy, cxy


def mean_shift(x: np.ndarray, bandwidth: float, min_bin_freq: int = 1, max_iter: int = 300) -> np.ndarray:
    """Flat-kernel mean shift with bin seeding, vectorised over the seeds.

    The algorithm of :class:`sklearn.cluster.MeanShift` with ``bin_seeding=True,
    cluster_all=True`` (Comaniciu and Meer 2002), step for step: seeds are the grid
    cells of size ``bandwidth`` holding at least ``min_bin_freq`` points (all points
    when every point has its own cell); each seed moves to the mean of the points
    within ``bandwidth`` until it moves less than ``1e-3 * bandwidth``; the modes,
    by decreasing number of points within, drop any later mode within ``bandwidth``;
    each point gets the label of its nearest mode. scikit-learn does the same one
    seed and one neighbour query at a time, with about 1 ms of input validation per
    query: 30 to 150 ms per scan here against about 1 ms (benchmarks/bench_walls.py);
    a test checks that both give the same clusters.

    Parameters
    ----------
    x : (N, d) float ndarray
    bandwidth : float
        Kernel radius, in the units of ``x``.
    min_bin_freq : int
    max_iter : int

    Returns
    -------
    (N,) int64 ndarray
        Cluster labels 0.. (most populated mode first); all -1 when no cell holds
        ``min_bin_freq`` points.
    """
    x = np.asarray(x, dtype=np.float64)
    if x.ndim == 1:
        x = x[:, None]
    if len(x) == 0:
        return np.empty(0, dtype=np.int64)
    means = _bin_seeds(x, bandwidth, min_bin_freq)
    if len(means) == len(x):
        means = x.copy()
    if len(means) == 0:
        return np.full(len(x), -1, dtype=np.int64)
    r2, stop = bandwidth**2, 1e-3 * bandwidth
    within = np.zeros(len(means), dtype=np.int64)
    n, dim = x.shape
    # Squared distances of seeds m to points x, (m**2).sum(1)[:, None] - 2.0 * m @ x.T
    # + (x**2).sum(1)[None, :], as one BLAS product of rows (-2 m, (m**2).sum(), 1) with
    # columns (x, 1, (x**2).sum()): the kernel accumulates the terms in this order with
    # fused multiply-adds, so it rounds as the three steps (scaling by -2 is exact;
    # checked bit for bit on every MeanShift of the wall benchmarks, and in the tests).
    xa = np.empty((dim + 2, n))
    xa[:dim] = x.T
    xa[dim] = 1.0
    xa[dim + 1] = _row_squares(x)
    act = np.arange(len(means))  # the seeds still moving, in seed order
    m = means.copy()  # their means
    for _ in range(max_iter):
        if len(act) == 0:
            break
        ma = np.empty((len(m), dim + 2))
        np.multiply(m, -2.0, out=ma[:, :dim])
        ma[:, dim] = _row_squares(m)
        ma[:, dim + 1] = 1.0
        # the flat kernel's weights (d2 <= r2) written as 1.0 / 0.0, and their counts
        # (sums of ones: exact integers, as w.sum(axis=1))
        w = ma @ xa
        np.less_equal(w, r2, out=w)  # in place: one (seeds, points) temporary fewer
        cnt = w.sum(axis=1)
        within[act] = cnt
        moved = cnt > 0
        if moved.all():  # the usual case: no boolean indexing
            new = (w @ x) / cnt[:, None]
            shift = np.sqrt(_row_squares(new - m))
            means[act] = new
            going = shift > stop
            if going.all():
                m = new
                continue
        else:
            new = (w[moved] @ x) / cnt[moved, None]
            shift = np.sqrt(_row_squares(new - m[moved]))
            means[act[moved]] = new
            going = np.zeros(len(act), dtype=bool)
            going[np.flatnonzero(moved)[shift > stop]] = True
        act = act[going]
        m = means[act]
    keep = within > 0
    if not keep.any():
        return np.full(len(x), -1, dtype=np.int64)
    centers, n_in = means[keep], within[keep]
    # Decreasing (points within, centre) as sklearn sorts its (centre, count) items.
    order = np.lexsort(tuple(centers[:, k] for k in range(centers.shape[1] - 1, -1, -1)) + (n_in,))[::-1]
    centers = centers[order]
    nc = len(centers)
    # row i: ((centers - centers[i]) ** 2).sum(axis=1) <= r2, for all i at once when few
    near = _pair_squares(centers, centers) <= r2 if nc <= 256 else None
    unique = np.ones(nc, dtype=bool)
    for i in range(nc):
        if unique[i]:
            unique[_row_squares(centers - centers[i]) <= r2 if near is None else near[i]] = False
            unique[i] = True
    centers = centers[unique]
    if len(centers) == 1:  # every point is nearest to it
        return np.zeros(n, dtype=np.int64)
    return np.argmin(_pair_squares(x, centers), axis=1).astype(np.int64)


def _bin_seeds(x: np.ndarray, bandwidth: float, min_bin_freq: int) -> np.ndarray:
    """MeanShift's bin seeds of (N, d) ``x``: the grid cells ``round(x / bandwidth)``
    holding at least ``min_bin_freq`` points, times ``bandwidth``, in lexicographic
    order of the cells, (S, d). In 1D (the offsets: most calls) by a sort and a
    comparison of neighbours instead of :func:`floorscan.core.grid.cell_groups` (same
    cells, fewer calls)."""
    cells = np.round(x / bandwidth)
    if x.shape[1] == 1:
        c = np.sort(cells[:, 0])
        new = np.empty(len(c), dtype=bool)
        new[0] = True
        np.not_equal(c[1:], c[:-1], out=new[1:])
        start = np.flatnonzero(new)
        counts = np.empty(len(start), dtype=np.intp)  # numpy.diff(start, append=len(c))
        np.subtract(start[1:], start[:-1], out=counts[:-1])
        counts[-1] = len(c) - start[-1]
        return c[start[counts >= min_bin_freq], None] * bandwidth
    counts, first = cell_groups(cells, first=True, inverse=False)
    return cells[first[counts >= min_bin_freq]] * bandwidth


def _row_squares(a: np.ndarray) -> np.ndarray:
    """``(a**2).sum(axis=1)`` of (N, d) ``a``, for d <= 2 without the reduction (slow on
    a short axis): a sum of one or two terms is the same float whatever the order."""
    if a.shape[1] == 1:
        return a[:, 0] * a[:, 0]
    if a.shape[1] == 2:
        return a[:, 0] * a[:, 0] + a[:, 1] * a[:, 1]
    return (a**2).sum(axis=1)


def _pair_squares(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Squared distances (N, M) of the rows of (N, d) ``a`` to those of (M, d) ``b``,
    ``((a[:, None, :] - b[None, :, :]) ** 2).sum(axis=2)``; for d <= 2 term by term (the
    same floats, without the 3D temporary and the reduction over a short axis)."""
    if a.shape[1] > 2:
        return ((a[:, None, :] - b[None, :, :]) ** 2).sum(axis=2)
    d = a[:, 0, None] - b[:, 0]
    out = d * d
    if a.shape[1] == 2:
        d = a[:, 1, None] - b[:, 1]
        out += d * d
    return out


def _mean_shift(
    x: np.ndarray, bandwidth: float | None, bin_seeding: bool, min_bin_freq: int, backend: str = "numpy"
) -> np.ndarray:
    """MeanShift labels of ``x`` (N, d) (flat kernel, every point labelled).

    ``backend`` "numpy" is :func:`mean_shift` (needs ``bin_seeding``), "sklearn" is
    :class:`sklearn.cluster.MeanShift`. ``bandwidth`` None estimates it with
    ``sklearn.cluster.estimate_bandwidth(quantile=0.1)``. With ``bin_seeding`` the
    seeds are the grid cells (size ``bandwidth``) holding at least ``min_bin_freq``
    points; when there is none, every label is -1.
    """
    # scikit-learn only when used: importing it costs ~1.8 s per job (measured)
    if bandwidth is None:
        from sklearn.cluster import estimate_bandwidth

        bandwidth = float(estimate_bandwidth(x, quantile=0.1)) if len(x) > 1 else 0.0
        if not bandwidth > 0:
            return np.zeros(len(x), dtype=np.int64)
    if backend == "numpy" and bin_seeding:
        return mean_shift(x, bandwidth, min_bin_freq)
    from sklearn.cluster import MeanShift, get_bin_seeds
    from threadpoolctl import threadpool_limits

    # One thread: the nearest-neighbour queries of MeanShift on a few hundred points
    # were 20x slower with a thread pool on a shared 2-core machine (measured).
    with warnings.catch_warnings(), threadpool_limits(1):
        warnings.simplefilter("ignore")  # "binning data failed ... using all points"
        seeds = None
        if bin_seeding:
            # sklearn's MeanShift fails ("max() arg is an empty sequence") when no bin
            # holds min_bin_freq points: then no cluster is dense enough.
            seeds = get_bin_seeds(x, bandwidth, min_bin_freq)
            if len(seeds) == 0:
                return np.full(len(x), -1, dtype=np.int64)
        return MeanShift(bandwidth=bandwidth, seeds=seeds, cluster_all=True).fit_predict(x)


def wall_signature(points: np.ndarray, normals: np.ndarray, angle_labels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The projection of cluster_ransac: each point moved along its wall's normal.

    For a direction cluster (points whose normals agree, label ``angle_labels``) with
    mean normal n_c (axial mean: half the angle of the mean of doubled angles) and
    centroid c, every point p of the cluster projects to ``rho = n_c . (p - c)``: the
    point slides along the normal onto the normal axis through c. All points of one
    straight wall land on one value of rho (the wall's signed distance from c),
    whatever their position along the wall; two parallel walls (e.g. the two faces of
    a 20 cm wall, or the two sides of a corridor) land at rho values that differ by
    their distance, so a 1D MeanShift on rho separates them; walls of other
    directions are in other direction clusters. This is the Hough (theta, rho) of
    the tangent line, with two changes against smearing: rho uses the cluster's mean
    normal instead of the point's own (with a per-point normal an angle error e moves
    rho by e times the distance of p along the wall from the foot point, e.g.
    0.02 rad * 10 m = 0.2 m, across parallel neighbours), and the origin is the
    cluster centroid, not the map origin (the lever arm of the small error left in
    the mean normal is then the scan's size, not the distance to the map origin).

    Parameters
    ----------
    points : (N, 2) float ndarray
    normals : (N, 2) float ndarray
        Unit normals (axial), NaN allowed for points without a normal.
    angle_labels : (N,) int ndarray
        Direction cluster of each point, -1 for none.

    Returns
    -------
    rho : (N,) float64 ndarray
        Offset along the cluster normal from the cluster centroid, metres (NaN where
        the label is -1).
    cluster_normals : (L, 2) float64 ndarray
        Mean unit normal of direction cluster 0..L-1.
    """
    labels = np.asarray(angle_labels)
    n_lab = int(labels.max()) + 1 if len(labels) and labels.max() >= 0 else 0
    theta2 = 2.0 * np.arctan2(normals[:, 1], normals[:, 0])
    cluster_normals = np.full((n_lab, 2), np.nan)
    rho = np.full(len(points), np.nan)
    for lab in range(n_lab):
        m = labels == lab
        t = theta2[m]
        t = t[np.isfinite(t)]
        if len(t) == 0:
            continue
        # means as np.add.reduce / count: what ndarray.mean computes, fewer calls
        phi = 0.5 * np.arctan2(np.add.reduce(np.sin(t)) / len(t), np.add.reduce(np.cos(t)) / len(t))
        cluster_normals[lab] = (np.cos(phi), np.sin(phi))
        pm = points[m]
        rho[m] = (pm - np.add.reduce(pm, axis=0) / len(pm)) @ cluster_normals[lab]
    return rho, cluster_normals


def cluster_ransac(
    points: np.ndarray,
    params: RansacParams = RansacParams(),
    cluster: ClusterParams = ClusterParams(),
    seed=0,
) -> pd.DataFrame:
    """Wall segments of one scan by clustering RANSAC (thesis section 3.4).

    1. A normal per point (:func:`point_normals`, the neighbourhoods of Open3D's hybrid search).
    2. MeanShift (flat kernel, bin seeding: scikit-learn's algorithm, by default in
       its vectorised form :func:`mean_shift`) of the normal directions: each point's axial angle theta in [0, pi)
       is embedded as ``0.5 * (cos 2 theta, sin 2 theta)`` (no wrap-around at 0 / pi;
       distances are about angle differences in radians), bandwidth
       ``angle_bandwidth_rad``.
    3. Within each direction cluster, the points are projected along the cluster's
       normal to ``rho`` (:func:`wall_signature`) and clustered by a 1D MeanShift,
       bandwidth ``offset_bandwidth_m``: one cluster per wall line.
    4. One RANSAC (:func:`_best_line` with the ``params`` of :func:`ransac`) per
       cluster with at least ``min_cluster_points`` points, turned into segments by
       :func:`_claimed_segments` as in :func:`ransac` (ends from all points of the
       scan near the line, so corner points with mixed normals still end the wall).

    Parameters
    ----------
    points : (N, 2) float ndarray
        Wall points of one scan (map frame), metres. Not modified.
    params : RansacParams
        RANSAC and segment parameters (``max_lines`` is not used).
    cluster : ClusterParams
    seed : int, sequence of int or numpy.random.Generator

    Returns
    -------
    pandas.DataFrame
        As :func:`ransac`, ordered by cluster (direction, then offset).
    """
    return _frame(_cluster_ransac_rows(points, params, cluster, seed))


def _cluster_ransac_rows(points: np.ndarray, params: RansacParams, cluster: ClusterParams, seed) -> list[tuple]:
    """:func:`cluster_ransac` as a list of (x0, y0, x1, y1, n_inliers, rmse_m) tuples."""
    rng = np.random.default_rng(seed)
    pts = np.asarray(points, dtype=np.float64)
    if len(pts) < max(params.min_points, 3):
        return []
    normals = point_normals(pts, cluster.normal_radius_m, cluster.normal_max_nn)
    has_normal = np.isfinite(normals[:, 0])
    labels = np.full(len(pts), -1)
    if has_normal.sum() >= cluster.min_cluster_points:
        theta2 = 2.0 * np.arctan2(normals[has_normal, 1], normals[has_normal, 0])
        emb = 0.5 * np.stack([np.cos(theta2), np.sin(theta2)], axis=1)
        labels[has_normal] = _mean_shift(
            emb, cluster.angle_bandwidth_rad, cluster.bin_seeding,
            max(1, cluster.min_cluster_points // 3), cluster.meanshift,
        )
    rho, _ = wall_signature(pts, normals, labels)
    rows: list[tuple] = []
    for lab in np.flatnonzero(np.bincount(labels[labels >= 0])):  # numpy.unique
        members = np.flatnonzero(labels == lab)
        if len(members) < cluster.min_cluster_points:
            continue
        sub = _mean_shift(
            rho[members, None], cluster.offset_bandwidth_m, cluster.bin_seeding,
            max(1, cluster.min_cluster_points // 3), cluster.meanshift,
        )
        for s in np.flatnonzero(np.bincount(sub[sub >= 0])):
            idx = members[sub == s]
            if len(idx) < cluster.min_cluster_points:
                continue
            fit = _fit_wall(pts, idx, rng, params)
            if fit is not None:
                rows += fit[1]
    return rows


def _fit_wall(pts: np.ndarray, idx: np.ndarray, rng: np.random.Generator, params: RansacParams):
    """One RANSAC line on ``pts[idx]``: its inlier mask over ``idx`` and its wall segments.

    Returns None when no line has at least ``params.min_inliers`` inliers. The
    segments' ends and gaps come from all of ``pts`` near the line (see
    :func:`_claimed_segments`).
    """
    found = _best_line(pts[idx], rng, params)
    if found is None:
        return None
    mask, c, direction = found
    if np.count_nonzero(mask) < params.min_inliers:
        return None
    claimed = np.zeros(len(pts), dtype=bool)
    claimed[idx[mask]] = True
    return mask, _claimed_segments(pts, c, direction, claimed, params)


def _claimed_segments(pts, c, direction, claimed, params) -> list[tuple]:
    """Segments of a line found by RANSAC, with ends from all points of the scan.

    The points of the whole scan within ``threshold_m`` of the line (centroid ``c``,
    unit ``direction``) are split at gaps wider than ``max_gap_m``; a piece is this
    line's when at least ``min_inliers`` of its points were ``claimed`` by it (its
    RANSAC inliers). Points near a corner, claimed by the other wall or left out of a
    cluster for their mixed normal, so still extend the segment to the corner.
    """
    normal = np.array([-direction[1], direction[0]])
    cand = np.flatnonzero(np.abs((pts - c) @ normal) < params.threshold_m)
    t = pts[cand] @ direction
    order = np.argsort(t, kind="stable")
    bounds = _piece_bounds(t[order], params.max_gap_m)
    cand = cand[order]
    rows = []
    for a, b in zip(bounds[:-1], bounds[1:]):
        piece = cand[a:b]
        if b - a >= params.min_inliers and np.count_nonzero(claimed[piece]) >= params.min_inliers:
            row = _piece_segment(pts[piece], direction, params)
            if row is not None:
                rows.append(row)
    return rows


def _piece_bounds(ts: np.ndarray, max_gap: float) -> list[int]:
    """Start of each piece of sorted positions ``ts`` split at gaps wider than
    ``max_gap``, and the end: pieces are ``ts[b[i]:b[i+1]]`` (as ``numpy.split``)."""
    wide = (ts[1:] - ts[:-1]) > max_gap  # numpy.diff
    if not wide.any():  # one piece: the usual case
        return [0, len(ts)]
    return [0, *(np.flatnonzero(wide) + 1).tolist(), len(ts)]


# --------------------------------------------------------------------------------------
# All scans of a dataset
# --------------------------------------------------------------------------------------


def extract_scan(
    xyz: np.ndarray,
    extractor: str,
    scan: ScanParams,
    params: RansacParams,
    cluster: ClusterParams,
    seed,
) -> tuple[pd.DataFrame, str, int]:
    """Wall segments of one scan with ``extractor``; never raises on bad points.

    Returns
    -------
    segments : pandas.DataFrame
        As :func:`ransac`.
    reason : str
        "" when segments were found, else one of :data:`REASONS`.
    n_points : int
        Wall points the extractor saw.
    """
    rows, reason, n_pts = _extract_scan_rows(xyz, extractor, scan, params, cluster, seed)
    return _frame(rows), reason, n_pts


def _extract_scan_rows(xyz, extractor, scan, params, cluster, seed) -> tuple[list[tuple], str, int]:
    """:func:`extract_scan` with the segments as a list of tuples (no frame per scan)."""
    if extractor not in EXTRACTORS:
        raise ValueError(f"unknown extractor {extractor!r}; expected one of {EXTRACTORS}")
    pts, reason = scan_points_2d(xyz, scan)
    if reason:
        return [], reason, 0
    if len(pts) < params.min_points:
        return [], "too_few_points", len(pts)
    if extractor == "ransac":
        rows = _ransac_rows(pts, params, seed)
    else:
        rows = _cluster_ransac_rows(pts, params, cluster, seed)
    return rows, ("" if rows else "no_wall_found"), len(pts)


def extract_walls(
    points: pd.DataFrame | Iterable[tuple[int, np.ndarray]], extractor: str, cfg: Mapping[str, Any]
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """Wall segments of every scan of a registered points table (stage ``scan_walls``).

    Parameters
    ----------
    points : pandas.DataFrame or iterable of (int, (n, 3) float ndarray)
        ``registered.parquet``: ``scan_id, x, y, z`` (map frame, metres, z above
        floor) as a frame, or streamed scan by scan as ``(scan_id, xyz)``
        (:func:`floorscan.core.io.iter_scans`; memory then holds one scan, issue 8).
    extractor : {"ransac", "cluster_ransac"}
    cfg : mapping
        The ``walls`` config section (``seed``, ``height_band_m``, ``planar_tolerance_m``,
        ``grid_m``, ``ransac``, ``cluster_ransac``). Scan ``s`` uses the generator
        ``numpy.random.default_rng((seed, s))``, independent of the other scans.

    Returns
    -------
    walls : pandas.DataFrame
        Schema :data:`WALLS`, rows ordered by scan_id then discovery.
    status : pandas.DataFrame
        The columns of :data:`SCAN_STATUS` and ``time_s`` (:data:`SCAN_TIMES`): one
        row per scan, ``reason`` "" or one of :data:`REASONS`, ``time_s`` wall-clock
        seconds of the extraction. Written as two tables: ``write_table(status, path,
        schema=SCAN_STATUS)`` leaves the time out.

    Raises
    ------
    KeyError
        When ``points`` lacks a column or ``cfg`` has an unknown key.
    ValueError
        For an unknown extractor, or a streamed scan id that comes twice.
    """
    if isinstance(points, pd.DataFrame):
        from floorscan.core.io import split_by_scan

        scans: Iterable[tuple[int, np.ndarray]] = split_by_scan(points).items()
    else:
        scans = points
    if extractor not in EXTRACTORS:
        raise ValueError(f"unknown extractor {extractor!r}; expected one of {EXTRACTORS}")
    scan_p, ransac_p, cluster_p = params_from_config(cfg)
    seed = int(cfg.get("seed", 0))
    if extractor == "cluster_ransac":  # import before timing the first scan
        import scipy.spatial  # noqa: F401

        if cluster_p.meanshift == "sklearn" or cluster_p.offset_bandwidth_m is None:
            import sklearn.cluster  # noqa: F401
    per_scan: dict[int, list[tuple]] = {}
    status = []
    for scan_id, xyz in scans:
        scan_id = int(scan_id)
        if scan_id in per_scan:
            raise ValueError(f"scan {scan_id}: its points come in two separate runs; expected them together")
        t0 = time.perf_counter()
        rows, reason, n_pts = _extract_scan_rows(xyz, extractor, scan_p, ransac_p, cluster_p, (seed, scan_id))
        dt = time.perf_counter() - t0
        per_scan[scan_id] = rows
        status.append((scan_id, n_pts, len(rows), reason, dt))
    ids = sorted(per_scan)
    rows = [r for s in ids for r in per_scan[s]]
    n_rows = [len(per_scan[s]) for s in ids]
    walls_df = _frame(rows)
    walls_df.insert(0, "scan_id", np.repeat(np.asarray(ids, dtype=np.int32), n_rows))
    walls_df = walls_df[WALLS.names]
    status.sort(key=lambda r: r[0])
    status_df = pd.DataFrame(status, columns=[*SCAN_STATUS.names, "time_s"]).astype(
        {"scan_id": "int32", "n_points": "int32", "n_walls": "int32", "reason": "str", "time_s": "float64"}
    )
    counts = status_df.loc[status_df.reason != "", "reason"].value_counts().to_dict()
    log.info(
        "%s: %d scans, %d wall segments, %.3f s/scan, scans without walls: %s",
        extractor, len(status_df), len(walls_df), status_df.time_s.mean() if len(status_df) else 0.0,
        counts or "none",
    )
    return walls_df, status_df


def parse_k(k: str | int) -> int | None:
    """``"all"`` -> None, ``"15"`` or 15 -> 15.

    Raises
    ------
    ValueError
        For anything else or k < 1.
    """
    if str(k) == "all":
        return None
    try:
        v = int(k)
    except (TypeError, ValueError):
        raise ValueError(f"k must be a positive integer or 'all', got {k!r}") from None
    if v < 1:
        raise ValueError(f"k must be a positive integer or 'all', got {k!r}")
    return v


def first_k_walls(walls: pd.DataFrame, ordering: pd.DataFrame, k: str | int) -> tuple[pd.DataFrame, list[int]]:
    """The wall segments of the first ``k`` scans of an ordering (stage ``walls``).

    Parameters
    ----------
    walls : pandas.DataFrame
        Per-scan wall segments (schema :data:`WALLS`).
    ordering : pandas.DataFrame
        ``orderings/{ordering}.parquet``: ``rank`` (0-based), ``scan_id``.
    k : int, str
        Number of scans; ``"all"`` or a k larger than the number of ranked scans
        takes all of them.

    Returns
    -------
    segments : pandas.DataFrame
        Rows of ``walls`` whose scan is among the first k, in rank order (then the
        per-scan order).
    scan_ids : list of int
        The first k scans, in rank order.

    Raises
    ------
    KeyError
        When ``ordering`` lacks ``rank`` or ``scan_id``.
    """
    for c in ("rank", "scan_id"):
        if c not in ordering.columns:
            raise KeyError(f"ordering lacks column {c!r}; expected rank, scan_id")
    kk = parse_k(k)
    ids = ordering.sort_values("rank", kind="stable")["scan_id"].astype(int).tolist()
    ids = ids if kk is None else ids[:kk]
    pos = {s: i for i, s in enumerate(ids)}
    sel = walls[walls["scan_id"].isin(pos)].copy()
    sel["_pos"] = sel["scan_id"].map(pos)
    sel = sel.sort_values("_pos", kind="stable").drop(columns="_pos").reset_index(drop=True)
    return sel[WALLS.names], ids

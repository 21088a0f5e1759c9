"""Parameters of the wall extraction (config section ``walls``), with their defaults.

* :class:`RansacParams` (``walls.ransac``): RANSAC and the wall segment rules, shared
  by every extractor (thesis section 5.3, Algorithm 4);
* :class:`ClusterParams` (``walls.cluster_ransac``): the clustering of
  :func:`floorscan.walls.cluster.cluster_ransac` (thesis section 3.4).

Each is built from its section with :func:`floorscan.core.config.stage_params`
(``stage_params(RansacParams, cfg["ransac"])``); the defaults are written once, in
``workflow/schemas/walls.schema.yaml`` (:func:`floorscan.core.config.schema_defaults`).
How a scan becomes 2D wall points (the section's height band, 2D rule and grid) is
shared with the reference map and the coverage orderings:
:class:`floorscan.core.wall_points.ScanParams`.
"""

from __future__ import annotations

from dataclasses import dataclass

from floorscan.core.config import schema_defaults, schema_enum

#: The MeanShift implementations (config ``walls.cluster_ransac.meanshift``; the schema's enum).
MEANSHIFT_METHODS = schema_enum("walls.cluster_ransac", "meanshift")


@dataclass(frozen=True)
@schema_defaults("walls.ransac")
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

    threshold_m: float
    iterations: int
    refine_iterations: int
    min_points: int
    max_lines: int
    min_inliers: int
    min_length_m: float
    max_gap_m: float
    min_coverage: float
    coverage_gap_m: float


@dataclass(frozen=True)
@schema_defaults("walls.cluster_ransac")
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

    normal_radius_m: float
    normal_max_nn: int
    angle_bandwidth_rad: float
    offset_bandwidth_m: float | None
    min_cluster_points: int
    bin_seeding: bool
    meanshift: str

    def __post_init__(self):
        if self.meanshift not in MEANSHIFT_METHODS:
            raise ValueError(f"cluster_ransac.meanshift must be one of {list(MEANSHIFT_METHODS)}, got {self.meanshift!r}")
        if self.meanshift == "numpy" and not self.bin_seeding:
            raise ValueError("cluster_ransac.meanshift 'numpy' needs bin_seeding true")

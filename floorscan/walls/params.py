"""Parameters of the wall extraction (config section ``walls``), with their defaults.

* :class:`RansacParams`: RANSAC and the wall segment rules, shared by every extractor
  (thesis section 5.3, Algorithm 4);
* :class:`ClusterParams`: the clustering of :func:`floorscan.walls.cluster.cluster_ransac`
  (thesis section 3.4).

Neither is an option of the config: their defaults are the constants below, each with
its reason, and code or a test that needs other values builds the class with keywords
(``RansacParams(threshold_m=0.05)``). :func:`floorscan.core.config.stage_params`
builds them from ``None`` (the defaults) as it builds the classes of the schema's
sections. How a scan becomes 2D wall points (the section's height band) is shared with
the reference map and the coverage orderings:
:class:`floorscan.core.wall_points.ScanParams`.
"""

from __future__ import annotations

from dataclasses import dataclass

#: The MeanShift implementations of :class:`ClusterParams` (``meanshift``).
MEANSHIFT_METHODS = ("numpy", "sklearn")

# RansacParams (thesis section 5.3, Algorithm 4; Fischler and Bolles 1981)
#: Inlier distance to a line, metres: three times the ~1 cm range noise of a 2D LIDAR.
THRESHOLD_M = 0.03
#: Hypotheses per RANSAC run: a pair inside a wall of a fifth of the points is drawn with p = 1 - 0.96**200 > 0.999.
ITERATIONS = 200
#: Least-squares refits of the best line on its inliers: the second settles the inliers the first one moved.
REFINE_ITERATIONS = 2
#: Iterative RANSAC stops below this many points left: too few for a line of MIN_INLIERS among outliers.
MIN_POINTS = 20
#: Iterative RANSAC stops after this many lines: more than the wall faces one scan of a room and its corridor sees.
MAX_LINES = 30
#: Fewest inliers of a line and of each segment: a 0.3 m face 3 m away holds ~20 beams of a 0.25-degree scanner.
MIN_INLIERS = 15
#: Shortest wall segment kept, metres: shorter faces are jambs, legs of furniture or noise.
MIN_LENGTH_M = 0.3
#: A line splits into segments at gaps between inliers wider than this, metres: below the narrowest door.
MAX_GAP_M = 0.5
#: A segment's inliers cover at least this fraction of it: a wall is seen throughout, a line of table legs not (thesis 2.3).
MIN_COVERAGE = 0.6
#: A gap between inliers wider than this and 3x both neighbours is an uncovered jump, metres: legs, not grazing beams.
COVERAGE_GAP_M = 0.10

# ClusterParams (thesis section 3.4: normals, MeanShift on direction then offset, Comaniciu and Meer 2002)
#: Neighbourhood radius of a normal, metres: a wall is flat over a quarter metre, which holds enough beams.
NORMAL_RADIUS_M = 0.25
#: At most this many neighbours per normal (Open3D hybrid search): a stable fit at a bounded cost.
NORMAL_MAX_NN = 20
#: MeanShift bandwidth of the normal direction, radians (~6 degrees): one wall's normal noise, far below a corner.
ANGLE_BANDWIDTH_RAD = 0.1
#: MeanShift bandwidth of the offset along the normal, metres: one face; a wall's two faces lie further apart.
OFFSET_BANDWIDTH_M = 0.05
#: Clusters with fewer points are not fitted: as many as a line's inliers (MIN_INLIERS).
MIN_CLUSTER_POINTS = MIN_INLIERS
#: Seed MeanShift on a grid of the bandwidth (scikit-learn's bin_seeding): the same modes from fewer seeds.
BIN_SEEDING = True
#: MeanShift implementation: scikit-learn's algorithm vectorised over the seeds (floorscan.walls.meanshift).
MEANSHIFT = "numpy"


@dataclass(frozen=True)
class RansacParams:
    """RANSAC and segment parameters, used by both extractors (defaults: the module's
    constants).

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

    threshold_m: float = THRESHOLD_M
    iterations: int = ITERATIONS
    refine_iterations: int = REFINE_ITERATIONS
    min_points: int = MIN_POINTS
    max_lines: int = MAX_LINES
    min_inliers: int = MIN_INLIERS
    min_length_m: float = MIN_LENGTH_M
    max_gap_m: float = MAX_GAP_M
    min_coverage: float = MIN_COVERAGE
    coverage_gap_m: float = COVERAGE_GAP_M


@dataclass(frozen=True)
class ClusterParams:
    """Clustering parameters of :func:`cluster_ransac` (defaults: the module's constants).

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

    normal_radius_m: float = NORMAL_RADIUS_M
    normal_max_nn: int = NORMAL_MAX_NN
    angle_bandwidth_rad: float = ANGLE_BANDWIDTH_RAD
    offset_bandwidth_m: float | None = OFFSET_BANDWIDTH_M
    min_cluster_points: int = MIN_CLUSTER_POINTS
    bin_seeding: bool = BIN_SEEDING
    meanshift: str = MEANSHIFT

    def __post_init__(self):
        if self.meanshift not in MEANSHIFT_METHODS:
            raise ValueError(f"ClusterParams.meanshift must be one of {list(MEANSHIFT_METHODS)}, got {self.meanshift!r}")
        if self.meanshift == "numpy" and not self.bin_seeding:
            raise ValueError("ClusterParams.meanshift 'numpy' needs bin_seeding True")

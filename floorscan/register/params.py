"""The parameters of the register stage: :class:`RegistrationConfig` (config section
``register``) and :class:`GraphParams` (its ``graph`` subsection, the pose graph).

Keys and defaults match ``workflow/schemas/register.schema.yaml`` (a test checks they
agree); the schema documents each key, its bounds and the reasons for the defaults. A
new key goes into the schema and the dataclass with the same default, and into
:meth:`RegistrationConfig.check` when it has bounds. The stage parses its section once::

    cfg = RegistrationConfig.from_mapping(config["register"])   # InputError on a bad key
    cfg.graph_params.loop_radius_m                               # the graph section, parsed once
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import Any, Mapping

from floorscan.core.config import dataclass_from_mapping, schema_defaults
from floorscan.core.io import InputError


@dataclass(frozen=True)
@schema_defaults("register.graph", icp_distances_m=lambda d: tuple(d["icp_distances_m"]))
class GraphParams:
    """Parameters of the pose graph (config ``register.graph``).

    Attributes
    ----------
    sequential_neighbours : int
        Edges from each sampled scan to this many following sampled scans.
    loop_radius_m : float
        Loop-closure candidates: scans whose positions are within this, metres.
    loop_min_separation_s : float
        ... and at least this far apart in time, seconds.
    loop_max_per_scan : int
        Nearest candidates tried per scan.
    loop_partner_separation_m : float
        The loop partners of a scan are at least this far apart along the path (the
        distance travelled between them under the initial poses), metres: one per
        revisit, as a pass through the ``loop_radius_m`` disc is about twice the
        radius long; 0: the nearest candidates, however close to each other. Loop
        closure from distinct passes is what ties the passes together; neighbouring
        scans of one pass add ICP time and little information.
    icp_distances_m : tuple of float
        Coarse-to-fine maximum correspondence distances of the edge ICP, metres.
    icp_max_iterations : int
        Per distance.
    voxel_size_m : float
        Voxel downsampling of the scans before the edge ICP, metres (0: none).
    coarse_voxel_size_m : float
        Every ICP stage but the last (the coarser ``icp_distances_m``) aligns the
        clouds voxel-downsampled again on this, metres (0, or not above
        ``voxel_size_m``: the clouds themselves); the last stage and the fitness use
        the full clouds. Coarse-to-fine multi-scale ICP, as Open3D's multi-scale ICP
        (its tutorial halves the voxel with the distance).
    vertical_extent_m : float
        A 3D scan keeps the 2D cells whose points span at least this height, metres
        (floor and ceiling drop out; :func:`floorscan.register.prepare.graph_cloud`).
    max_height_gap_m : float
        ... counting heights without a gap wider than this between them, metres.
    inlier_m : float
        A source point is an inlier when its nearest target point is this close, metres.
    min_edge_fitness : float
        Inlier fraction an edge needs after ICP.
    agreement_m, agreement_rad : float
        The keep test (:mod:`floorscan.register.agreement`): a pair agrees with the
        registered poses when its ICP relative pose is within this translation
        (metres) and yaw (radians) of theirs.
    agreement_fitness_ratio : float
        ... and it counts (has structure to agree on) when its overlap fitness after
        ICP is at least this times the median over the recording's pairs.
    edge_sigma_m, edge_sigma_rad : float
        Standard deviation of an ICP edge's translation (metres) and yaw (radians).
    prior_sigma_m, prior_sigma_rad : float
        Standard deviation of a localizer pose (metres, radians).
    workers : int
        Processes for the edge ICP (the ``register`` rule passes its Snakemake
        ``threads``). The edges do not depend on it: each pair is aligned alone.
    """

    sequential_neighbours: int
    loop_radius_m: float
    loop_min_separation_s: float
    loop_max_per_scan: int
    loop_partner_separation_m: float
    icp_distances_m: tuple[float, ...]
    icp_max_iterations: int
    voxel_size_m: float
    coarse_voxel_size_m: float
    vertical_extent_m: float
    max_height_gap_m: float
    inlier_m: float
    min_edge_fitness: float
    agreement_m: float
    agreement_rad: float
    agreement_fitness_ratio: float
    edge_sigma_m: float
    edge_sigma_rad: float
    prior_sigma_m: float
    prior_sigma_rad: float
    workers: int = 1

    @classmethod
    def from_mapping(cls, cfg) -> "GraphParams":
        """From a config mapping (unknown keys raise ``KeyError``)."""
        values = dict(cfg or {})
        if "icp_distances_m" in values:
            values["icp_distances_m"] = tuple(float(v) for v in values["icp_distances_m"])
        return dataclass_from_mapping(cls, values, "register.graph")


@dataclass(frozen=True)
@schema_defaults("register", icp_max_correspondence_m=lambda d: tuple(d["icp_max_correspondence_m"]))
class RegistrationConfig:
    """Parameters of the ``register`` stage; keys and defaults are those of
    ``workflow/schemas/register.schema.yaml`` (:func:`floorscan.core.config.schema_defaults`).

    See the schema for each key's description, bounds and the reasons for the defaults.
    The ``graph`` section is parsed once per config into :attr:`graph_params`.
    """

    mode: str
    reference: str
    every_n: int | None
    keep_distance_m: float | None
    keep_angle_rad: float | None
    keep_range_fraction: float
    min_kept_fraction: float
    min_consistency: float
    max_lost_fraction: float
    n_previous: int
    min_points: int
    fitness_max_correspondence_m: float
    min_prior_fitness: float
    min_icp_fitness: float
    icp_method: str
    icp_max_correspondence_m: tuple[float, ...]
    icp_max_iterations: int
    icp_tolerance_m: float
    voxel_size_m: float
    normal_neighbours: int
    max_reference_distance_m: float
    reference_pose: str
    n_references: int
    exclude_window_s: float
    reference_spacing_s: float
    passes: int
    relaxation: float
    max_speed_m_s: float
    max_turn_rate_rad_s: float
    pose_jump_slack_m: float
    pose_jump_slack_rad: float
    icp_voxel_size_3d_m: float
    odometry_scans: str
    odometry_icp_method: str
    odometry_window: int
    odometry_keyframe_m: float
    odometry_keyframe_rad: float
    odometry_max_correspondence_m: float
    graph: Mapping[str, Any]
    loop_closure: bool

    @classmethod
    def from_mapping(cls, cfg: Mapping[str, Any] | None) -> "RegistrationConfig":
        """Build from a config dict (the ``register`` section), rejecting unknown keys.

        Raises
        ------
        InputError
            On an unknown key or a value outside its range.
        """
        cfg = dict(cfg or {})
        if "icp_max_correspondence_m" in cfg and not isinstance(cfg["icp_max_correspondence_m"], (int, float)):
            cfg["icp_max_correspondence_m"] = tuple(float(v) for v in cfg["icp_max_correspondence_m"])
        out = dataclass_from_mapping(cls, cfg, "register", InputError)
        out.check()
        return out

    @functools.cached_property
    def graph_params(self) -> GraphParams:
        """The ``graph`` section as :class:`GraphParams`, parsed on first use and kept.

        Raises
        ------
        InputError
            On an unknown key or a value of the wrong type in ``graph``.
        """
        try:
            return GraphParams.from_mapping(self.graph)
        except (KeyError, TypeError) as exc:
            raise InputError(f"config register.graph: {exc}") from None

    def replace(self, **changes: Any) -> "RegistrationConfig":
        """:func:`dataclasses.replace` that keeps the parsed :attr:`graph_params` when
        ``graph`` is not among the ``changes``."""
        out = dataclasses.replace(self, **changes)
        if "graph" not in changes and "graph_params" in self.__dict__:
            out.__dict__["graph_params"] = self.__dict__["graph_params"]
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
        for key in ("min_kept_fraction", "min_consistency", "max_lost_fraction"):
            if not 0.0 <= getattr(self, key) <= 1.0:
                raise InputError(f"config register.{key}: expected 0..1, got {getattr(self, key)}")
        if self.reference not in ("graph", "map", "previous"):
            raise InputError(
                f"config register.reference: expected 'graph', 'map' or 'previous', got {self.reference!r}"
            )
        self.graph_params  # parsed once, here: an error names the key
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

"""The parameters of the register stage: :class:`RegistrationConfig` (config section
``register``) and :class:`GraphParams` (its ``graph`` subsection, the pose graph).

Keys and defaults are those of ``workflow/schemas/register.schema.yaml``
(:func:`floorscan.core.config.schema_defaults`); the schema documents each key, its
bounds, its allowed values (``enum``) and the reasons for the defaults, and is the one
place they are written: :func:`floorscan.core.config.stage_params` checks a section
against it. A new key goes into the schema and the dataclass (a field without a
default). The stage parses its section once::

    cfg = stage_params(RegistrationConfig, config["register"])  # ConfigError naming a bad key
    cfg.graph_params.loop_radius_m                               # the graph section, parsed once
"""

from __future__ import annotations

import copy
import dataclasses
import functools
from dataclasses import dataclass
from typing import Any, Mapping

from floorscan.core.config import schema_defaults, stage_params


@dataclass(frozen=True)
@schema_defaults("register.graph", icp_distances_m=lambda d: tuple(float(v) for v in d["icp_distances_m"]))
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


@dataclass(frozen=True)
@schema_defaults("register", icp_max_correspondence_m=lambda d: tuple(float(v) for v in d["icp_max_correspondence_m"]))
class RegistrationConfig:
    """Parameters of the ``register`` stage; keys and defaults are those of
    ``workflow/schemas/register.schema.yaml`` (:func:`floorscan.core.config.schema_defaults`).

    See the schema for each key's description, bounds and the reasons for the defaults.
    The ``graph`` section is parsed on construction, once, into :attr:`graph_params`.

    Raises
    ------
    floorscan.core.config.ConfigError
        On construction, for a bad key or value of ``graph`` (naming
        ``register.graph.<key>``).
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

    def __post_init__(self):
        self.graph_params  # parsed once, here: an error names the key

    @functools.cached_property
    def graph_params(self) -> GraphParams:
        """The ``graph`` section as :class:`GraphParams`, parsed on first use and kept.

        Raises
        ------
        floorscan.core.config.ConfigError
            For a bad key or value of ``graph``.
        """
        return stage_params(GraphParams, self.graph, "register.graph")

    def replace(self, **changes: Any) -> "RegistrationConfig":
        """A copy with ``changes`` (as :func:`dataclasses.replace`) that keeps the parsed
        :attr:`graph_params` when ``graph`` is not among the ``changes``.

        Raises
        ------
        TypeError
            A change that names no field.
        """
        unknown = sorted(set(changes) - {f.name for f in dataclasses.fields(self)})
        if unknown:
            raise TypeError(f"RegistrationConfig has no fields {unknown}")
        out = copy.copy(self)  # no __post_init__: graph_params copied with the rest
        for name, value in changes.items():
            object.__setattr__(out, name, value)
        if "graph" in changes:
            del out.__dict__["graph_params"]
            out.graph_params  # parsed anew
        return out

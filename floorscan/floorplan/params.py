"""Parameters of the floor plan, config section ``floorplan``: :class:`FloorplanParams`
(merge, pairing, wall height, DXF version, georeference, and the structure passes'
and rooms' parameters), built from the section by
:func:`floorscan.core.config.stage_params` (``stage_params(FloorplanParams, cfg)``).

The options a user sets (``wall_height_m``, ``georeference``, ``rooms``) have their
defaults in workflow/schemas/floorplan.schema.yaml
(:func:`floorscan.core.config.schema_defaults`); every other field's default is a
constant below (merge and pairing, thesis Chapter 1's purpose: one wall with its
thickness), in :mod:`~floorscan.floorplan.free_space` (structure passes) or in
:mod:`~floorscan.floorplan.room_space` (rooms), each with its reason. The section's
keys that the workflow reads, not the plan, are :data:`WORKFLOW_KEYS`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from floorscan.core.config import schema_defaults, stage_params
from floorscan.floorplan.georeference import Georeference, as_georeference
from floorscan.floorplan.free_space import StructureParams
from floorscan.floorplan.room_space import RoomParams


#: DXF versions :func:`write_dxf` writes: R2010 has a units header (metres), R12 (old CAD tools) none.
DXF_VERSIONS = ("R2010", "R12")
#: DXF version of the exports: R2010, read by the CAD tools of the last fifteen years, says its unit is the metre.
DXF_VERSION = "R2010"

#: Segments of one face differ in direction by at most this, degrees: registration's heading error between scans.
MERGE_ANGLE_DEG = 3.0
#: ... and the ends of the shorter lie within this of the longer's line, metres: below the thinnest wall (PAIR_MIN_M).
MERGE_DISTANCE_M = 0.05
#: ... and they overlap or leave at most this gap along the line, metres: half the narrowest door, an occlusion.
MERGE_GAP_M = 0.3
#: Merge passes: a merged face may reach faces it did not reach before; each pass sweeps all faces once more.
MAX_PASSES = 3
#: The two faces of a wall differ in direction by at most this, degrees: as MERGE_ANGLE_DEG.
PAIR_ANGLE_DEG = 3.0
#: Thinnest wall, metres: a plasterboard partition on studs.
PAIR_MIN_M = 0.05
#: Thickest wall, metres: a load-bearing masonry wall; faces further apart are two walls with a room between.
PAIR_MAX_M = 0.40
#: Paired faces overlap by at least this fraction of the shorter: the two faces of one wall run side by side.
PAIR_MIN_OVERLAP = 0.5
#: Thickness of a wall with one face seen, metres: an interior partition.
DEFAULT_THICKNESS_M = 0.10
#: Merged faces shorter than this are dropped, metres: the shortest wall segment of the extractors (RANSAC's).
MIN_LENGTH_M = 0.3


@dataclass(frozen=True)
@schema_defaults("floorplan")
class FloorplanParams:
    """Merge and pairing parameters (config section ``floorplan``).

    Attributes
    ----------
    merge_angle_deg : float
        Segments of one face differ in direction by at most this, degrees.
    merge_distance_m : float
        ... and the ends of the shorter lie within this of the longer's line, metres.
    merge_gap_m : float
        ... and they overlap or leave a gap of at most this along the line, metres.
    max_passes : int
        Merge passes (merged faces may touch faces they did not touch before).
    pair_angle_deg : float
        Two faces of one wall differ in direction by at most this, degrees.
    pair_min_m, pair_max_m : float
        Distance between the two faces of one wall (its thickness), metres.
    pair_min_overlap : float
        The two faces overlap along the wall by at least this fraction of the
        shorter face.
    default_thickness_m : float
        Thickness of a wall of which one face was seen, metres.
    wall_height_m : float
        Height of every wall (IFC extrusion, GeoJSON ``height_m``), metres.
    min_length_m : float
        Merged faces shorter than this are dropped, metres; with a grid, measured from
        the corners they stop short of (:func:`~floorscan.floorplan.structure.long_enough`).
    dxf_version : str
        DXF export: ``"R2010"`` (units header: metres) or ``"R12"`` (no units
        header; see :func:`~floorscan.floorplan.dxf.write_dxf`).
    georeference : ~floorscan.floorplan.georeference.Georeference or None
        Where the map frame lies on the earth (a mapping ``lat``, ``lon``,
        ``heading_deg`` is converted); with one the GeoJSON coordinates are WGS84
        longitude and latitude, the SVG gets a north arrow and the IFC site its
        reference latitude, longitude and true north. None: map metres.
    structure : ~floorscan.floorplan.free_space.StructureParams
        The structure passes (no option: the constants of
        :mod:`~floorscan.floorplan.free_space`).
    rooms : ~floorscan.floorplan.rooms.RoomParams
        The rooms and doors (config ``floorplan.rooms``).
    """

    merge_angle_deg: float = MERGE_ANGLE_DEG
    merge_distance_m: float = MERGE_DISTANCE_M
    merge_gap_m: float = MERGE_GAP_M
    max_passes: int = MAX_PASSES
    pair_angle_deg: float = PAIR_ANGLE_DEG
    pair_min_m: float = PAIR_MIN_M
    pair_max_m: float = PAIR_MAX_M
    pair_min_overlap: float = PAIR_MIN_OVERLAP
    default_thickness_m: float = DEFAULT_THICKNESS_M
    wall_height_m: float
    min_length_m: float = MIN_LENGTH_M
    dxf_version: str = DXF_VERSION
    structure: StructureParams = field(default_factory=StructureParams)
    rooms: RoomParams
    georeference: Georeference | None = None

    def __post_init__(self):
        for name, cls in (("structure", StructureParams), ("rooms", RoomParams)):
            if not isinstance(getattr(self, name), cls):  # a mapping given to the constructor
                object.__setattr__(self, name, stage_params(cls, getattr(self, name), f"floorplan.{name}"))
        if self.georeference is not None:  # a config mapping -> Georeference (checked)
            object.__setattr__(self, "georeference", as_georeference(self.georeference))
        if self.dxf_version not in DXF_VERSIONS:
            raise ValueError(f"floorplan.dxf_version must be one of {list(DXF_VERSIONS)}, got {self.dxf_version!r}")
        if not self.pair_min_m < self.pair_max_m:
            raise ValueError(
                f"floorplan.pair_min_m ({self.pair_min_m}) must be below pair_max_m ({self.pair_max_m})"
            )


#: Keys of the ``floorplan`` config section that the workflow reads, not the plan:
#: the recommended plan's extractor.
WORKFLOW_KEYS = ("extractor",)

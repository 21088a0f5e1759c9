"""Parameters of the floor plan, config section ``floorplan``: :class:`FloorplanParams`
(merge, pairing, wall height, DXF version, georeference, and the subsections
``structure`` and ``rooms``), built from the section by
:func:`floorscan.core.config.stage_params` (``stage_params(FloorplanParams, cfg)``).

The defaults are written once, in workflow/schemas/floorplan.schema.yaml
(:func:`floorscan.core.config.schema_defaults`). The section's keys that the workflow reads, not the plan, are
:data:`WORKFLOW_KEYS`.
"""

from __future__ import annotations

from dataclasses import dataclass

from floorscan.core.config import schema_defaults, schema_enum, stage_params
from floorscan.floorplan.georeference import Georeference, as_georeference
from floorscan.floorplan.free_space import StructureParams
from floorscan.floorplan.room_space import RoomParams


#: DXF versions :func:`write_dxf` writes (R2010 the default: R12 has no units header).
DXF_VERSIONS = schema_enum("floorplan", "dxf_version")


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
        Merged faces shorter than this are dropped, metres.
    dxf_version : str
        DXF export: ``"R2010"`` (units header: metres) or ``"R12"`` (no units
        header; see :func:`~floorscan.floorplan.dxf.write_dxf`).
    georeference : ~floorscan.floorplan.georeference.Georeference or None
        Where the map frame lies on the earth (a mapping ``lat``, ``lon``,
        ``heading_deg`` is converted); with one the GeoJSON coordinates are WGS84
        longitude and latitude, the SVG gets a north arrow and the IFC site its
        reference latitude, longitude and true north. None: map metres.
    structure : ~floorscan.floorplan.free_space.StructureParams
        The structure passes (config ``floorplan.structure``).
    rooms : ~floorscan.floorplan.rooms.RoomParams
        The rooms and doors (config ``floorplan.rooms``).
    """

    merge_angle_deg: float
    merge_distance_m: float
    merge_gap_m: float
    max_passes: int
    pair_angle_deg: float
    pair_min_m: float
    pair_max_m: float
    pair_min_overlap: float
    default_thickness_m: float
    wall_height_m: float
    min_length_m: float
    dxf_version: str
    structure: StructureParams
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
#: the recommended plan's extractor and the formats of the evaluation grid's plans.
WORKFLOW_KEYS = ("extractor", "evaluation_formats")

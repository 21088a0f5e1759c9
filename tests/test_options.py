"""Few, named parameters (issue 44, item 3): the `walls` and `floorplan` config sections
hold the options a user sets, at most 15, each documented; every other threshold is a
named constant of the code, and a setting that names one stops naming it (a config
file that does: tests/test_config.py)."""

from __future__ import annotations

import pytest
import yaml

from conftest import REPO

SCHEMAS = REPO / "workflow" / "schemas"

#: The options of the two sections, as dotted keys (a subsection's leaves counted one by one).
OPTIONS = {
    "walls.k", "walls.orderings", "walls.extractors", "walls.shard_scans", "walls.seed", "walls.height_band_m",
    "walls.map.support_cell_m",
    "floorplan.extractor", "floorplan.wall_height_m", "floorplan.georeference.lat", "floorplan.georeference.lon",
    "floorplan.georeference.heading_deg", "floorplan.rooms.door_min_m", "floorplan.rooms.door_max_m",
    "floorplan.rooms.min_room_area_m2",
}  # fmt: skip


def leaves(node: dict, prefix: str) -> dict[str, dict]:
    """Every leaf property of a schema object, by its dotted key."""
    found = {}
    for key, prop in (node.get("properties") or {}).items():
        if "properties" in prop:
            found.update(leaves(prop, f"{prefix}.{key}"))
        else:
            found[f"{prefix}.{key}"] = prop
    return found


def test_the_walls_and_floorplan_sections_have_at_most_15_documented_options():
    options = {}
    for stage in ("walls", "floorplan"):
        options.update(leaves(yaml.safe_load((SCHEMAS / f"{stage}.schema.yaml").read_text()), stage))
    assert len(options) <= 15 and set(options) == OPTIONS
    for key, prop in options.items():
        # what it does, in a sentence or more; a number says its unit
        assert len(prop.get("description", "")) > 40, key
        if prop.get("type") == "number" or (prop.get("items") or {}).get("type") == "number":
            assert any(u in prop["description"] for u in ("metres", "degrees", "square metres")), key


def test_the_parameter_classes_keep_their_fields_with_the_constants_as_defaults():
    """The thresholds are no options but stay fields of the parameter classes: code
    and tests set them by keyword; their defaults are the named constants."""
    from floorscan.floorplan import free_space, params, room_space
    from floorscan.floorplan.params import FloorplanParams
    from floorscan.walls import map_lines
    from floorscan.walls import params as walls_params

    plan = FloorplanParams()
    assert (plan.merge_gap_m, plan.pair_max_m, plan.dxf_version) == (params.MERGE_GAP_M, params.PAIR_MAX_M, "R2010")
    assert plan.structure.snap_m == free_space.SNAP_M and plan.rooms.close_m == room_space.CLOSE_M
    assert FloorplanParams(structure={"snap_m": 0.2}, rooms={"close_m": 0.5}).structure.snap_m == 0.2
    assert walls_params.RansacParams().threshold_m == walls_params.THRESHOLD_M == 0.03
    assert map_lines.MapParams().iterations == map_lines.MAP_ITERATIONS
    assert map_lines.MapParams(threshold_m=0.05).ransac().threshold_m == 0.05


@pytest.mark.parametrize(
    "section, values, message",
    [
        ("walls", {"ransac": {"threshold_m": 0.05}}, r"^walls: unknown keys \['ransac'\]; expected one of \['extractors', "),
        ("walls", {"map": {"threshold_m": 0.05}}, r"^walls\.map: unknown keys \['threshold_m'\]; expected one of \['support_cell_m'\]"),
        ("floorplan", {"structure": {"snap_m": 0.3}}, r"^floorplan: unknown keys \['structure'\]; expected one of \['extractor', "),
        ("floorplan", {"dxf_version": "R12"}, r"^floorplan: unknown keys \['dxf_version'\]"),
        ("floorplan", {"rooms": {"close_m": 0.3}}, r"^floorplan\.rooms: unknown keys \['close_m'\]; expected one of \['door_max_m', "),
    ],
    ids=["walls.ransac", "walls.map.threshold_m", "floorplan.structure", "floorplan.dxf_version", "floorplan.rooms.close_m"],
)  # fmt: skip
def test_a_key_that_is_no_option_is_one_error_naming_it(section, values, message):
    from floorscan.core.config import ConfigError, validate_config
    from floorscan.core.settings import setting

    with pytest.raises(ConfigError, match=message):
        validate_config(values, SCHEMAS / f"{section}.schema.yaml", section)
    key, value = next(iter(values.items()))
    dotted = f"{section}.{key}.{next(iter(value))}" if isinstance(value, dict) else f"{section}.{key}"
    with pytest.raises(ConfigError, match=r"unknown key; expected one of"):  # floorscan run --set
        setting(dotted, "0.3")

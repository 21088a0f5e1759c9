"""The config schema rejects bad values before any job starts, naming the field."""
import copy
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

REPO = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")


def dry_run(*config):
    return subprocess.run(
        [str(SNAKEMAKE), "-n", "--forceall", "--cores", "1", "--config", *config],
        cwd=REPO, capture_output=True, text=True, timeout=120,
    )


@pytest.mark.workflow
@pytest.mark.parametrize(
    "override, field",
    [
        ("poses={'max_gap_s': 'soon'}", "max_gap_s"),
        ("poses={'max_gap_s': -1}", "max_gap_s"),
        ("ingest={'carmen_max_range_m': 'far'}", "carmen_max_range_m"),
        ("target=['nowhere']", "nowhere"),
    ],
)
def test_bad_config_value_is_rejected(override, field):
    res = dry_run(override)
    assert res.returncode != 0
    assert field in (res.stdout + res.stderr)


@pytest.mark.workflow
def test_default_config_dry_run_plans_every_stage():
    res = dry_run()
    assert res.returncode == 0, res.stderr[-2000:]
    assert "ingest" in res.stdout and "poses" in res.stdout


SCHEMAS = sorted((REPO / "workflow" / "schemas").glob("*.schema.yaml"))


@pytest.mark.parametrize("schema", SCHEMAS, ids=lambda p: p.name.split(".")[0])
def test_validate_config_fills_the_defaults_snakemake_validate_fills(schema):
    import copy

    import yaml
    from snakemake.utils import validate

    from floorscan.core.config import validate_config

    cfg = yaml.safe_load((REPO / "config" / "config.yaml").read_text())
    stage = schema.name.split(".")[0]
    data = cfg if stage == "config" else (cfg.get(stage) or {})
    ours, theirs = copy.deepcopy(data), copy.deepcopy(data)
    validate_config(ours, schema, stage)
    validate(theirs, str(schema))
    assert ours == theirs
    props = yaml.safe_load(schema.read_text()).get("properties", {})
    assert all(name in ours for name, prop in props.items() if "default" in prop)  # defaults filled


def test_validate_config_names_the_field_and_copies_defaults():
    from floorscan.core.config import ConfigError, validate_config

    schema = REPO / "workflow" / "schemas" / "walls.schema.yaml"
    with pytest.raises(ConfigError, match=r"datasets\.x\.params\.walls\.k\.0: .*schema .*walls\.schema\.yaml"):
        validate_config({"k": ["many"]}, schema, "datasets.x.params.walls")
    a, b = validate_config({}, schema, "walls"), validate_config({}, schema, "walls")
    assert a == b and a["k"] == b["k"] and a["k"] is not b["k"]  # no shared mutable default


def test_a_path_alone_is_a_dataset():
    """`--config path=...`: the recording becomes a dataset named after the file, with
    nothing but its path, and the only target; the schema accepts it."""
    from floorscan.core.config import ConfigError, validate_config
    from floorscan.core.datasets import add_path_datasets

    def add_path_dataset(cfg):
        names = add_path_datasets(cfg, [cfg["path"]] if cfg.get("path") else [])
        return names[0] if names else None

    schema = REPO / "workflow" / "schemas" / "config.schema.yaml"
    cfg = {"datasets": {"demo": {"format": "synthetic", "building": "demo", "scanner": "2d", "seed": 1}},
           "path": "/data/my-run.2024.bag"}
    validate_config(cfg, schema)
    assert add_path_dataset(cfg) == "my-run_2024"
    assert cfg["datasets"]["my-run_2024"]["path"] == "/data/my-run.2024.bag"
    assert cfg["target"] == ["my-run_2024"]
    validate_config(cfg, schema)  # format, scan topic and pose are detected by ingest
    # the same path again: the same dataset; another file of the same name is not renamed
    assert add_path_dataset(cfg) == "my-run_2024"
    cfg["path"] = "/other/my-run.2024.bag"
    with pytest.raises(ConfigError, match=r"datasets\.my-run_2024 names /data/my-run\.2024\.bag; the recording "
                                          r"/other/my-run\.2024\.bag would be the dataset 'my-run_2024' too"):
        add_path_dataset(cfg)
    for path, name in (("/d/intel-corrected.log.gz", "intel-corrected"), ("/d/ros2_run/", "ros2_run"),
                       ("/d/2024.bag", "2024"), ("/d/lab run (2).bag", "lab_run__2_")):
        assert add_path_dataset({"path": path}) == name
    assert add_path_dataset({"datasets": {}}) is None


def test_a_path_to_a_shipped_recording_reuses_its_dataset(tmp_path, monkeypatch):
    """The shipped config names recordings by relative paths; the same file given by
    its absolute path (or through a symbolic link) is that dataset; another file of
    that name replaces the shipped example in the run and keeps its own name."""
    from floorscan.core.config import ConfigError
    from floorscan.core.datasets import add_path_datasets

    shipped = {"simpath2": {"description": "Stage", "path": "data/simpath2.bag"}}

    def add_path_dataset(cfg):
        return add_path_datasets(cfg, [cfg["path"]], shipped)[0]

    (tmp_path / "data").mkdir()
    bag = tmp_path / "data" / "simpath2.bag"
    bag.write_bytes(b"")
    (tmp_path / "link").symlink_to(tmp_path / "data")
    monkeypatch.chdir(tmp_path)
    for given in (str(bag), str(tmp_path / "link" / "simpath2.bag"), "./data/simpath2.bag"):
        cfg = {"datasets": {"simpath2": {"description": "Stage", "path": "data/simpath2.bag"}}, "path": given}
        assert add_path_dataset(cfg) == "simpath2" and cfg["target"] == ["simpath2"]
        assert cfg["datasets"]["simpath2"]["path"] == "data/simpath2.bag"
    other = tmp_path / "simpath2.bag"
    other.write_bytes(b"")
    cfg = {"datasets": {"simpath2": {"description": "Stage", "path": "data/simpath2.bag", "format": "rosbag"}},
           "path": str(other)}  # the schema filled in a default: still the shipped example
    assert add_path_dataset(cfg) == "simpath2"
    assert cfg["datasets"]["simpath2"] == {"description": f"{other} (--config path)", "path": str(other)}
    # the user's own dataset of that name (here: the shipped one given another path) is not replaced
    cfg = {"datasets": {"simpath2": {"description": "Stage", "path": "mine/simpath2.bag"}}, "path": str(other)}
    with pytest.raises(ConfigError, match=r"datasets\.simpath2 names mine/simpath2\.bag; .* rename the dataset or the file"):
        add_path_dataset(cfg)


def test_a_users_trace0_is_trace0(tmp_path):
    """Issue 47, item 3: trace0.bag of the user's is the dataset trace0 (it was trace0_2:
    the shipped config has a trace0), and demo.bag is demo, with their own paths."""
    from floorscan.core.datasets import add_path_datasets, shipped_datasets

    shipped = shipped_datasets(REPO / "config" / "config.yaml")
    assert {"demo", "trace0", "intel"} <= set(shipped)
    for name in ("trace0", "demo"):
        bag = tmp_path / f"{name}.bag"
        bag.write_bytes(b"")
        config = {"target": ["demo"], "datasets": copy.deepcopy(shipped)}
        assert add_path_datasets(config, [bag], shipped) == [name] and config["target"] == [name]
        assert config["datasets"][name] == {"description": f"{bag} (--config path)", "path": str(bag)}
        assert config["datasets"]["intel"] == shipped["intel"]  # the other examples stay as they are


def test_two_recordings_of_one_name_are_one_line():
    from floorscan.core.config import ConfigError
    from floorscan.core.datasets import add_path_datasets

    with pytest.raises(ConfigError, match=r"^path: /a/run\.bag and /b/run\.log\.gz would both be the dataset 'run' "
                                          r"\(a recording's dataset is named after its file\): rename one"):
        add_path_datasets({}, [Path("/a/run.bag"), Path("/b/run.log.gz")])


def test_a_folder_of_recordings_is_a_dataset_each(tmp_path):
    """A folder that is not itself a recording: each recording in it is a dataset (files
    by suffix, ROS2 bag and PCD folders), named after its file, all of them the targets;
    other entries are skipped; the building's floors resolve by file name."""
    from floorscan.core.config import ConfigError
    from floorscan.core.datasets import add_path_datasets
    from floorscan.core.io import InputError
    from floorscan.ingest.detect import recordings_in

    folder = tmp_path / "survey"
    folder.mkdir()
    for name in ("floor0.bag", "floor1.log.gz", "notes.txt", ".hidden.bag"):
        (folder / name).write_bytes(b"x")
    (folder / "ros2").mkdir()
    (folder / "ros2" / "metadata.yaml").write_text("x")
    (folder / "pcd").mkdir()
    (folder / "pcd" / "000.pcd").write_text("x")
    (folder / "empty").mkdir()
    recordings, skipped = recordings_in(folder)
    assert [p.name for p in recordings] == ["floor0.bag", "floor1.log.gz", "pcd", "ros2"]
    assert skipped == ["empty", "notes.txt"]
    assert recordings_in(folder / "ros2") == ([folder / "ros2"], [])  # a ROS2 bag folder is one recording
    shipped = {"floor0": {"path": "/elsewhere/floor0.bag"}}  # an example of that name gives way
    cfg = {"datasets": copy.deepcopy(shipped),
           "building": {"name": "HQ", "floors": [{"recording": "floor1.log.gz", "elevation_m": 3.5},
                                                 {"recording": "floor0.bag", "storey": "Ground"}]}}
    names = add_path_datasets(cfg, recordings, shipped)
    assert names == ["floor0", "floor1", "pcd", "ros2"] and cfg["target"] == names
    assert cfg["datasets"]["floor0"]["path"] == str(folder / "floor0.bag")
    assert cfg["building"]["floors"] == [
        {"recording": "floor1.log.gz", "elevation_m": 3.5, "dataset": "floor1", "storey": "Floor 0"},
        {"recording": "floor0.bag", "storey": "Ground", "dataset": "floor0", "elevation_m": 0.0},
    ]
    bad = {"building": {"floors": [{"recording": "floor9.bag"}]}}
    with pytest.raises(ConfigError, match=r"building.floors\[0\].recording: 'floor9.bag' is neither"):
        add_path_datasets(bad, recordings)
    with pytest.raises(InputError, match="a folder with no recording in it .it holds: 'x.txt'"):
        (tmp_path / "none").mkdir()
        (tmp_path / "none" / "x.txt").write_text("")
        recordings_in(tmp_path / "none")
    with pytest.raises(InputError, match="no such file or folder"):
        recordings_in(tmp_path / "missing.bag")


def test_a_dataset_needs_a_path_unless_synthetic():
    from floorscan.core.config import ConfigError, validate_config

    schema = REPO / "workflow" / "schemas" / "config.schema.yaml"
    with pytest.raises(ConfigError, match=r"datasets\.x: 'path' is a required property"):
        validate_config({"datasets": {"x": {"format": "rosbag"}}}, schema)
    with pytest.raises(ConfigError, match=r"datasets\.x: 'building' is a required property"):
        validate_config({"datasets": {"x": {"format": "synthetic"}}}, schema)
    validate_config({"datasets": {"x": {"path": "/d/run.bag"}}}, schema)


# ------------------------------------------ issue 24: what a schema lets through


SCHEMA = REPO / "workflow" / "schemas" / "config.schema.yaml"


@pytest.mark.parametrize("value", [float("nan"), float("inf"), -float("inf")])
def test_a_number_that_is_not_finite_is_rejected_naming_its_key(value):
    """NaN passes a JSON schema's `type: number` and every bound (it compares false);
    infinity passes `minimum`. Anywhere in the config, the key is named."""
    from floorscan.core.config import ConfigError, validate_config

    with pytest.raises(ConfigError, match=r"^poses\.max_gap_s: (nan|inf|-inf): expected a finite number"):
        validate_config({"datasets": {"x": {"path": "/d/r.bag"}}, "poses": {"max_gap_s": value}}, SCHEMA)
    cfg = {"datasets": {"x": {"path": "/d/r.bag", "params": {"walls": {"k": [5, value]}}}}}
    with pytest.raises(ConfigError, match=r"^datasets\.x\.params\.walls\.k\.1: "):
        validate_config(cfg, SCHEMA)
    with pytest.raises(ConfigError, match=r"^walls\.map\.support_cell_m: "):
        validate_config({"map": {"support_cell_m": value}}, REPO / "workflow" / "schemas" / "walls.schema.yaml", "walls")


def test_a_misspelt_stage_under_params_lists_the_stages():
    from floorscan.core.config import ConfigError, validate_config

    cfg = {"datasets": {"x": {"path": "/d/r.bag", "params": {"registr": {"every_n": 5}}}}}
    with pytest.raises(ConfigError, match=r"datasets\.x\.params: unknown keys \['registr'\]; expected one of "
                                          r"\['floorplan', 'hulls', 'ingest', 'poses', 'register', 'score', "
                                          r"'select', 'simulate', 'walls'\]"):
        validate_config(cfg, SCHEMA)
    stages = {p.name.split(".")[0] for p in SCHEMAS} - {"config"}
    validate_config({"datasets": {"x": {"path": "/d/r.bag", "params": {s: {} for s in stages}}}}, SCHEMA)


def test_an_empty_path_and_an_unknown_building_say_what_is_expected(tmp_path):
    from floorscan.core.config import ConfigError
    from floorscan.core.datasets import check_datasets

    (tmp_path / "demo.yaml").write_text("")
    (tmp_path / "office.yaml").write_text("")
    for cfg, where in (({"datasets": {"x": {"path": ""}}}, r"datasets\.x\.path"),
                       ({"datasets": {"x": {"path": None}}}, r"datasets\.x\.path"),
                       ({"path": " ", "datasets": {}}, r"path \(--config path=\.\.\.\)")):
        with pytest.raises(ConfigError, match=where + r" is empty; expected the path of a recording: a ROS1 \.bag"):
            check_datasets(cfg, tmp_path)
    synthetic = {"format": "synthetic", "building": "ofice", "scanner": "2d", "seed": 1}
    with pytest.raises(ConfigError, match=r"datasets\.s\.building: no building 'ofice'; expected one of \['demo', 'office'\]"):
        check_datasets({"datasets": {"s": synthetic}}, tmp_path)
    check_datasets({"datasets": {"s": {**synthetic, "building": "office"}, "r": {"path": "/d/r.bag"}}}, tmp_path)


@pytest.mark.parametrize(
    "text, message",
    [
        ("poses: {max_gap_s: .nan}\n", "Config error: poses.max_gap_s: nan: expected a finite number"),
        ("datasets:\n  demo:\n    params: {registr: {every_n: 5}}\n",
         "Config error: datasets.demo.params: unknown keys ['registr']; expected one of ['floorplan',"),
        ("target: [x]\ndatasets:\n  x: {path: ''}\n", "Config error: datasets.x.path is empty; expected the path"),
        ("target: [x]\ndatasets:\n  x: {format: synthetic, building: hallway, scanner: 2d, seed: 1}\n",
         "Config error: datasets.x.building: no building 'hallway'; expected one of ['demo', 'hallways']"),
        ("target: [nowhere]\n", "Config error: target names unknown datasets ['nowhere']"),
        ("register: {every_nn: 3}\n", "Config error: register: unknown keys ['every_nn']; expected one of"),
        # an option that is a constant of the code now (issue 44): named, with the options left
        ("floorplan:\n  structure: {snap_m: 0.3}\n",
         "Config error: floorplan: unknown keys ['structure']; expected one of "
         "['extractor', 'georeference', 'rooms', 'wall_height_m']"),
    ],
    ids=["nan", "params_typo", "empty_path", "unknown_building", "unknown_target", "stage_key_typo", "removed_option"],
)
def test_a_bad_config_file_stops_the_run_with_one_paragraph(tmp_path, text, message):
    """`--configfile`: the run stops before any job with the message alone, no
    traceback and no rule file (Snakemake prints a SystemExit's message as it is)."""
    (tmp_path / "my.yaml").write_text(text)
    res = subprocess.run(
        [str(SNAKEMAKE), "-n", "--cores", "1", "--configfile", str(tmp_path / "my.yaml")],
        cwd=REPO, capture_output=True, text=True, timeout=120,
    )
    out = res.stdout + res.stderr
    assert res.returncode == 1, out[-2000:]
    errors = [line for line in out.splitlines() if "error" in line.lower()]
    assert len(errors) == 1 and errors[0].startswith(message), out[-2000:]
    assert 'File "' not in out and "Traceback" not in out


def test_schema_defaults_give_a_dataclass_the_schema_defaults_once():
    """A field without a default takes the schema's; a list default is a fresh copy per
    instance; a default written in the class and the schema, or in neither, is refused."""
    import dataclasses

    from floorscan.core.config import schema_defaults, schema_section_defaults

    assert schema_section_defaults("walls.map") == {"support_cell_m": 0.05}

    @dataclasses.dataclass(frozen=True)
    @schema_defaults("walls", low_m=lambda d: d["height_band_m"][0])
    class Walls:
        seed: int
        height_band_m: list
        low_m: float
        extra: int = 7  # not config: the class's own default

    a, b = Walls(), Walls(seed=3)
    assert (a.seed, b.seed, a.extra, a.low_m) == (0, 3, 7, a.height_band_m[0])
    assert a.height_band_m == schema_section_defaults("walls")["height_band_m"]
    assert a.height_band_m is not b.height_band_m

    with pytest.raises(TypeError, match="written in the class and in schema walls"):
        @schema_defaults("walls")
        class Twice:
            seed: int = 1

    with pytest.raises(TypeError, match="no default in schema walls"):
        @schema_defaults("walls")
        class Neither:
            not_a_key: int

    with pytest.raises(KeyError, match="no property 'nope'"):
        schema_section_defaults("walls.nope")


@pytest.mark.slow
def test_a_per_dataset_override_of_a_file_grid_key_is_refused_at_start(tmp_path):
    """walls.k names the evaluation files of every dataset: a dataset's override of it
    would be half applied (the rules' file grid is global), so the run refuses it before
    any job, naming the dataset and the key; an override of any other key is applied."""

    def run(params):
        demo = {"format": "synthetic", "building": "demo", "scanner": "2d", "seed": 1, "params": params}
        f = tmp_path / "overlay.yaml"
        f.write_text(yaml.safe_dump({"datasets": {"demo": demo}}))
        return subprocess.run([str(SNAKEMAKE), "-n", "--forceall", "--cores", "1", "--configfile",
                               "config/config.yaml", str(f)], cwd=REPO, capture_output=True, text=True, timeout=120)

    res = run({"walls": {"k": [5, "all"]}})
    assert res.returncode == 1
    out = res.stdout + res.stderr
    assert "Config error: datasets.demo.params.walls: ['k'] name the workflow's files" in out
    assert "Traceback" not in out
    res = run({"walls": {"seed": 3}})
    assert res.returncode == 0, res.stderr[-2000:]


def test_command_line_strings_reach_the_schema_with_their_types():
    """Snakemake's --config gives strings (evaluate=true, poses={'max_gap_s': 0.7}): they
    are read as YAML where the schema wants a boolean, a number, a list or a mapping; a
    string the schema allows stays one; a string that is no such value is refused."""
    from floorscan.core.config import ConfigError, validate_config

    schemas = REPO / "workflow" / "schemas"
    cfg = {"evaluate": "true", "datasets": {"x": {"path": "1.5", "seed": "3", "description": "0.7"}}}
    validate_config(cfg, schemas / "config.schema.yaml")
    assert cfg["evaluate"] is True and cfg["datasets"]["x"]["seed"] == 3
    assert cfg["datasets"]["x"]["path"] == "1.5" and cfg["datasets"]["x"]["description"] == "0.7"
    poses = {"max_gap_s": "0.7"}
    validate_config(poses, schemas / "poses.schema.yaml", "poses")
    assert poses["max_gap_s"] == 0.7
    with pytest.raises(ConfigError, match="max_gap_s"):
        validate_config({"max_gap_s": "soon"}, schemas / "poses.schema.yaml", "poses")


# ------------------------------------------ issue 37, item 1: one way to read a section


@pytest.mark.parametrize(
    "module, cls, section, message",
    [
        ("floorscan.walls.map_lines", "MapParams", {"max_iterations": 50},
         r"walls\.map\.max_iterations: unknown key; expected one of \['grid_m', 'iterations', "),
        ("floorscan.register.params", "RegistrationConfig", {"graph": {"loop_radius": 3.0}},
         r"register\.graph\.loop_radius: unknown key; expected one of \['agreement_fitness_ratio', "),
        ("floorscan.floorplan.params", "FloorplanParams", {"structure": {"snap": 0.1}},
         r"floorplan\.structure\.snap: unknown key; expected one of \['clutter_max_length_m', "),
        ("floorscan.floorplan.params", "FloorplanParams", {"rooms": {"door_width_m": 0.8}},
         r"floorplan\.rooms\.door_width_m: unknown key; expected one of \['close_m', "),
        ("floorscan.score.params", "ScoreParams", {"tau_m": 0.1},
         r"score\.tau_m: unknown key; expected one of \['cell_m', "),
        ("floorscan.ingest.params", "IngestParams", {"carmen_fov": 3.14},
         r"ingest\.carmen_fov: unknown key; expected one of \['carmen_fov_rad', "),
        ("floorscan.select.figure_data", "FigureParams", {"figure_k": [1, 5]},
         r"select\.figure_k: unknown key; expected one of \['coverage', "),
    ],
    ids=["walls.map", "register.graph", "floorplan.structure", "floorplan.rooms", "score", "ingest", "select(figures)"],
)
def test_an_unknown_key_is_one_config_error_naming_it_in_every_stage(module, cls, section, message):
    """Every stage builds its parameters with stage_params: an unknown key, top-level or
    in a subsection, is the same ConfigError, naming the key and the known ones."""
    import importlib

    from floorscan.core.config import ConfigError, stage_params

    with pytest.raises(ConfigError, match="^" + message):
        stage_params(getattr(importlib.import_module(module), cls), section)


def test_stage_params_checks_values_against_the_schema_and_builds_subsections():
    """A wrong type, a value out of bounds or of no enum, NaN: a ConfigError naming the
    key, in the schema's words; the allowed values are the schema's (register's enums
    are written there alone); subsections become their classes; the section's keys of
    other classes are left to them; derived fields follow the section."""
    from floorscan.core.config import ConfigError, stage_params
    from floorscan.floorplan.free_space import StructureParams
    from floorscan.floorplan.params import FloorplanParams
    from floorscan.register.params import RegistrationConfig
    from floorscan.select.params import SelectParams
    from floorscan.walls.map_lines import MapParams
    from floorscan.walls.params import RansacParams
    from floorscan.core.wall_points import ScanParams

    with pytest.raises(ConfigError, match=r"^walls\.map\.support_cell_m: 'fine' is not of type 'number'"):
        stage_params(MapParams, {"support_cell_m": "fine"})
    enum = yaml.safe_load((REPO / "workflow/schemas/register.schema.yaml").read_text())["properties"]["mode"]["enum"]
    with pytest.raises(ConfigError, match=rf"^register\.mode: 'bogus' is not one of {enum!r}".replace("[", r"\[")):
        stage_params(RegistrationConfig, {"mode": "bogus"})
    with pytest.raises(ConfigError, match=r"^register\.max_lost_fraction: 1\.5 is greater than the maximum of 1"):
        stage_params(RegistrationConfig, {"max_lost_fraction": 1.5})
    with pytest.raises(ConfigError, match=r"^floorplan\.rooms\.door_min_m: nan: expected a finite number"):
        stage_params(FloorplanParams, {"rooms": {"door_min_m": float("nan")}})
    with pytest.raises(ConfigError, match=r"^floorplan\.georeference\.lon: missing"):
        stage_params(FloorplanParams, {"georeference": {"lat": 50.0}})
    plan = stage_params(FloorplanParams, {"extractor": "map", "structure": {"snap_m": 0.2}, "georeference": {"lat": 50, "lon": 8}})
    assert isinstance(plan.structure, StructureParams) and plan.structure.snap_m == 0.2
    assert (plan.georeference.lat, plan.georeference.heading_deg) == (50.0, 0.0)
    assert stage_params(SelectParams, {"raster_m": 0.2, "k": "auto", "figure_max_scans": 9}) == SelectParams(raster_m=0.2)
    scan = stage_params(ScanParams, {"height_band_m": [0.5, 1.5], "grid_m": 0})
    assert (scan.min_height_m, scan.max_height_m, scan.grid_m) == (0.5, 1.5, 0.0)
    reg = stage_params(RegistrationConfig, {"graph": {"icp_distances_m": [1, 0.5], "workers": 3}})
    assert reg.graph_params.icp_distances_m == (1.0, 0.5) and reg.graph_params.workers == 3
    assert stage_params(RegistrationConfig, reg) is reg and stage_params(RansacParams, None) == RansacParams()


def test_a_null_subsection_the_schema_allows_is_none():
    """The evaluation grid's floorplan section sets georeference to None (its plans stay
    in the map frame): allowed by the schema, so stage_params keeps None; a subsection
    the schema does not allow to be null is named."""
    from floorscan.core.config import ConfigError, stage_params
    from floorscan.floorplan.params import FloorplanParams

    assert stage_params(FloorplanParams, {"georeference": None}).georeference is None
    with pytest.raises(ConfigError, match=r"floorplan\.rooms: None is not of type 'object'"):
        stage_params(FloorplanParams, {"rooms": None})


def test_schema_enum_is_the_schemas_own_list():
    from floorscan.core.config import schema_enum
    from floorscan.floorplan.params import DXF_VERSIONS
    from floorscan.select.params import RADIUS_RULES
    from floorscan.walls.params import MEANSHIFT_METHODS

    assert schema_enum("walls", "extractors") == ("ransac", "cluster_ransac")  # an array's items
    assert (DXF_VERSIONS, RADIUS_RULES, MEANSHIFT_METHODS) == (
        ("R2010", "R12"), ("nearest_centre", "global_min"), ("numpy", "sklearn"))
    with pytest.raises(KeyError, match="no enum"):
        schema_enum("walls", "seed")
    with pytest.raises(KeyError, match="no property 'nope'"):
        schema_enum("hulls", "nope")


def test_a_value_of_none_of_the_alternatives_says_what_each_is():
    """``select.k: five`` names the three things k may be (issue 47, item 7 of the user's
    list), not jsonschema's "is not valid under any of the given schemas"."""
    from floorscan.core.config import ConfigError, validate_config

    schema = REPO / "workflow" / "schemas" / "select.schema.yaml"
    with pytest.raises(ConfigError) as info:
        validate_config({"k": "five"}, schema, "select")
    assert str(info.value).startswith(
        "select.k: got 'five'; expected 'auto', an integer >= 1 or a number > 0 and < 1 (schema "
    )
    with pytest.raises(ConfigError, match=r"^select\.k: got 0; expected 'auto', an integer >= 1 or a number > 0 and < 1"):
        validate_config({"k": 0}, schema, "select")


def test_a_path_with_braces_gets_one_line_naming_it_and_the_link_that_works(tmp_path):
    """Snakemake reads { } in an input path as a wildcard, even escaped: a WildcardError
    ('b') before issue 45, item 6. Square brackets are no wildcard and run."""
    from floorscan.core.config import ConfigError
    from floorscan.core.datasets import brace_problem, check_datasets
    from floorscan.core.io import InputError
    from floorscan.ingest.detect import recordings_in

    folder = tmp_path / "survey{2}"
    folder.mkdir()
    one = folder / "run{1}.bag"
    one.write_bytes(b"")
    with pytest.raises(InputError, match=r"run\{1\}\.bag: the path holds \{ or \}, which Snakemake reads as a wildcard"):
        recordings_in(one)
    assert f"(ln -s '{one}' run1.bag) and give the link" in brace_problem(one)
    assert brace_problem(tmp_path / "run[1].bag") is None
    # a folder of recordings: the entry with a brace is left out, and said why
    plain = tmp_path / "plain"
    plain.mkdir()
    (plain / "good.log").write_text("FLASER 0\n")
    (plain / "x{1}.log").write_text("FLASER 0\n")
    found, skipped = recordings_in(plain)
    assert found == [plain / "good.log"]
    assert skipped == ["x{1}.log (holds { or }, which Snakemake reads as a wildcard: rename or link it)"]
    # a folder whose own path holds one: its recordings could not be inputs either
    with pytest.raises(InputError, match=r"survey\{2\}: the path holds"):
        recordings_in(folder)
    with pytest.raises(ConfigError, match=r"datasets\.mine\.path: .*run\{1\}\.bag: the path holds"):
        check_datasets({"datasets": {"mine": {"path": str(one)}}})

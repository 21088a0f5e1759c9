"""The config schema rejects bad values before any job starts, naming the field."""
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
SNAKEMAKE = Path(sys.executable).with_name("snakemake")


def dry_run(*config):
    return subprocess.run(
        [str(SNAKEMAKE), "-n", "--forceall", "--cores", "1", "--config", *config],
        cwd=REPO, capture_output=True, text=True, timeout=120,
    )


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

    from floorscan.config import validate_config

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
    from floorscan.config import ConfigError, validate_config

    schema = REPO / "workflow" / "schemas" / "walls.schema.yaml"
    with pytest.raises(ConfigError, match=r"datasets\.x\.params\.walls\.k\.0: .*schema .*walls\.schema\.yaml"):
        validate_config({"k": ["many"]}, schema, "datasets.x.params.walls")
    a, b = validate_config({}, schema, "walls"), validate_config({}, schema, "walls")
    assert a == b and a["k"] == b["k"] and a["k"] is not b["k"]  # no shared mutable default


def test_a_path_alone_is_a_dataset():
    """`--config path=...`: the recording becomes a dataset named after the file, with
    nothing but its path, and the only target; the schema accepts it."""
    from floorscan.config import add_path_dataset, validate_config

    schema = REPO / "workflow" / "schemas" / "config.schema.yaml"
    cfg = {"datasets": {"demo": {"format": "synthetic", "building": "demo", "scanner": "2d", "seed": 1}},
           "path": "/data/my-run.2024.bag"}
    validate_config(cfg, schema)
    assert add_path_dataset(cfg) == "my_run_2024"
    assert cfg["datasets"]["my_run_2024"]["path"] == "/data/my-run.2024.bag"
    assert cfg["target"] == ["my_run_2024"]
    validate_config(cfg, schema)  # format, scan topic and pose are detected by ingest
    # the same path again: the same dataset; another file of the same name: a new one
    assert add_path_dataset(cfg) == "my_run_2024"
    cfg["path"] = "/other/my-run.2024.bag"
    assert add_path_dataset(cfg) == "my_run_2024_2"
    for path, name in (("/d/intel.log.gz", "intel"), ("/d/ros2_run/", "ros2_run"), ("/d/2024.bag", "r_2024")):
        assert add_path_dataset({"path": path}) == name
    assert add_path_dataset({"datasets": {}}) is None


def test_a_path_to_a_shipped_recording_reuses_its_dataset(tmp_path, monkeypatch):
    """The shipped config names recordings by relative paths; the same file given by
    its absolute path (or through a symbolic link) is that dataset, not simpath2_2."""
    from floorscan.config import add_path_dataset

    (tmp_path / "data").mkdir()
    bag = tmp_path / "data" / "simpath2.bag"
    bag.write_bytes(b"")
    (tmp_path / "link").symlink_to(tmp_path / "data")
    monkeypatch.chdir(tmp_path)
    for given in (str(bag), str(tmp_path / "link" / "simpath2.bag"), "./data/simpath2.bag"):
        cfg = {"datasets": {"simpath2": {"path": "data/simpath2.bag"}}, "path": given}
        assert add_path_dataset(cfg) == "simpath2" and cfg["target"] == ["simpath2"]
        assert cfg["datasets"]["simpath2"]["path"] == "data/simpath2.bag"
    other = tmp_path / "simpath2.bag"
    other.write_bytes(b"")
    assert add_path_dataset({"datasets": {"simpath2": {"path": "data/simpath2.bag"}}, "path": str(other)}) == "simpath2_2"


def test_a_dataset_needs_a_path_unless_synthetic():
    from floorscan.config import ConfigError, validate_config

    schema = REPO / "workflow" / "schemas" / "config.schema.yaml"
    with pytest.raises(ConfigError, match=r"datasets\.x: 'path' is a required property"):
        validate_config({"datasets": {"x": {"format": "rosbag"}}}, schema)
    with pytest.raises(ConfigError, match=r"datasets\.x: 'building' is a required property"):
        validate_config({"datasets": {"x": {"format": "synthetic"}}}, schema)
    validate_config({"datasets": {"x": {"path": "/d/run.bag"}}}, schema)

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

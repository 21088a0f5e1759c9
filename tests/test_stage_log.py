"""floorscan.core.stage.stage_log: the stage's log file, failures, and the profile option."""

import pstats
from types import SimpleNamespace

import pytest

from floorscan.core.stage import stage_log


def _work(n):
    return sum(i * i for i in range(n))


def _smk(tmp_path):
    return SimpleNamespace(rule="hulls_shard", log=[str(tmp_path / "stage.log")],
                           wildcards={"dataset": "demo", "shard": "scans_0-9"})


def test_stage_log_writes_start_done_and_cpu(tmp_path, monkeypatch):
    monkeypatch.delenv("FLOORSCAN_PROFILE", raising=False)
    with stage_log(_smk(tmp_path)) as log:
        log.info("working")
    text = (tmp_path / "stage.log").read_text()
    assert "start hulls_shard {'dataset': 'demo', 'shard': 'scans_0-9'}" in text
    assert "s CPU before the stage" in text and "working" in text
    assert "done hulls_shard in" in text and " s CPU)" in text
    assert not list(tmp_path.glob("*.prof"))


def test_stage_log_profiles_the_stage_into_the_given_directory(tmp_path, monkeypatch):
    monkeypatch.setenv("FLOORSCAN_PROFILE", str(tmp_path / "prof"))
    with stage_log(_smk(tmp_path)):
        _work(10_000)
    stats = pstats.Stats(str(tmp_path / "prof" / "hulls_shard_demo_scans_0-9.prof"))
    assert any(fn[2] == "_work" for fn in stats.stats)


def test_stage_log_logs_and_reraises_a_failure(tmp_path, monkeypatch):
    monkeypatch.setenv("FLOORSCAN_PROFILE", str(tmp_path / "prof"))
    with pytest.raises(ValueError, match="bad scan"):
        with stage_log(_smk(tmp_path)):
            raise ValueError("bad scan")
    assert "stage hulls_shard failed" in (tmp_path / "stage.log").read_text()
    assert (tmp_path / "prof" / "hulls_shard_demo_scans_0-9.prof").exists()


@pytest.mark.parametrize("how", ["SIGINT", "SIGTERM"])
def test_an_interrupted_stage_says_so_in_its_log(tmp_path, monkeypatch, how):
    """Ctrl-C or Snakemake stopping its jobs (SIGTERM): the log's last line says the stage
    was interrupted, by what and after how long, not a bare 'start' line; the handler
    SIGTERM had before is back afterwards."""
    import os
    import signal

    from floorscan.core.stage import Interrupted

    monkeypatch.delenv("FLOORSCAN_PROFILE", raising=False)
    before = signal.getsignal(signal.SIGTERM)
    # a process started in the background (`nohup`, `cmd &`) inherits SIGINT ignored;
    # in a terminal Ctrl-C meets Python's own handler, as here
    sigint = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        with pytest.raises(KeyboardInterrupt if how == "SIGINT" else Interrupted):
            with stage_log(_smk(tmp_path)):
                os.kill(os.getpid(), getattr(signal, how))
                _work(10_000_000)  # the signal arrives before this ends
    finally:
        signal.signal(signal.SIGINT, sigint)
    last = (tmp_path / "stage.log").read_text().splitlines()[-1]
    want = "SIGINT (Ctrl-C)" if how == "SIGINT" else "SIGTERM"
    assert f"hulls_shard interrupted by {want} after " in last and "run the workflow again" in last, last
    assert signal.getsignal(signal.SIGTERM) is before

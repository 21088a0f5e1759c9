"""floorscan.core.parallel: calls in fresh worker processes, started on demand or ahead."""

import os
import sys

import pytest

from floorscan.core import parallel


def _whoami(x):
    return x * 2, os.getpid(), "colorsys" in sys.modules


@pytest.fixture(autouse=True)
def _workers_find_this_module(monkeypatch):
    """Workers import ``_whoami`` by module name: this folder on their path."""
    here = os.path.dirname(__file__)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([here, os.environ.get("PYTHONPATH", "")]))


def test_map_in_processes_runs_the_calls_in_order_in_other_processes():
    out = parallel.map_in_processes(_whoami, [(1,), (2,), (3,)])
    assert [r[0] for r in out] == [2, 4, 6]
    assert out[0][1] == os.getpid() and len({r[1] for r in out}) == 3
    assert not out[1][2]  # a worker started on demand imports only what the call needs


def test_prestarted_workers_are_used_first_and_have_their_modules_loaded():
    assert parallel.prestart(1, preload=("colorsys",)) == 1
    out = parallel.map_in_processes(_whoami, [(1,), (2,)])
    assert out[1][0] == 4 and out[1][1] != os.getpid()
    assert out[1][2]  # colorsys was imported by the prestarted worker before its call
    assert parallel._READY == []


def test_a_prestarted_worker_that_failed_is_reported():
    parallel.prestart(1, preload=("no_such_module_floorscan",))
    with pytest.raises(RuntimeError, match="no_such_module_floorscan"):
        parallel.map_in_processes(_whoami, [(1,), (2,)])
    assert parallel._READY == []


def test_without_local_first_every_call_runs_in_a_worker():
    out = parallel.map_in_processes(_whoami, [(1,), (2,)], local_first=False)
    assert [r[0] for r in out] == [2, 4]
    assert os.getpid() not in {r[1] for r in out} and out[0][1] != out[1][1]
    assert parallel.map_in_processes(_whoami, [], local_first=False) == []


_SEEN: list = []


def _remember(x):
    """Keeps what it was given before (a worker keeps its module state between calls)."""
    if x == "fail":
        raise ValueError("asked to fail")
    _SEEN.append(x)
    return list(_SEEN), os.getpid()


def test_call_stream_workers_take_many_calls_and_keep_their_state():
    stream = parallel.CallStream(2)
    for k in range(6):
        stream.submit(k % 2, _remember, (k,))
    out = stream.results()
    assert [seen for seen, _ in out] == [[0], [1], [0, 2], [1, 3], [0, 2, 4], [1, 3, 5]]
    pids = [pid for _, pid in out]
    assert len(set(pids)) == 2 and os.getpid() not in pids and pids[0::2] == [pids[0]] * 3
    assert stream.pending == [0, 0]


def test_call_stream_reports_a_failed_call():
    stream = parallel.CallStream(1)
    stream.submit(0, _remember, (1,))
    stream.submit(0, _remember, ("fail",))
    stream.submit(0, _remember, (2,))
    with pytest.raises(RuntimeError, match="asked to fail"):
        stream.results()

"""floorscan.core.runtime's worker processes (the standard library's ProcessPoolExecutor,
spawned): results in order, a worker's exception at the caller, the worker count, the
first call of a map here."""

import multiprocessing
import os
import sys

import pytest

from floorscan.core import runtime


def _whoami(x):
    return x * 2, os.getpid(), "colorsys" in sys.modules


def _fail_on(x, bad):
    if x == bad:
        raise ValueError(f"asked to fail on {x}")
    return x


def _meet(barrier):
    """Returns only when as many calls wait at ``barrier`` as it has parties: the calls
    run at the same time, each in its own process."""
    barrier.wait(timeout=60)
    return os.getpid()


def test_map_in_processes_keeps_the_order_and_runs_the_first_call_here():
    out = runtime.map_in_processes(_whoami, [(k,) for k in range(6)], workers=3)
    assert [r[0] for r in out] == [0, 2, 4, 6, 8, 10]
    assert out[0][1] == os.getpid()  # the first call here, the others in workers
    others = {r[1] for r in out[1:]}
    assert os.getpid() not in others and 1 <= len(others) <= 2  # at most workers - 1 processes
    assert not out[1][2]  # a worker imports only what the call needs


def test_map_in_processes_with_one_worker_or_one_call_stays_here():
    assert runtime.map_in_processes(_whoami, [(1,), (2,)], workers=1) == [_whoami(1), _whoami(2)]
    assert runtime.map_in_processes(_whoami, [(5,)], workers=4)[0][1] == os.getpid()
    assert runtime.map_in_processes(_whoami, [], workers=4) == []


def test_an_exception_in_a_worker_reaches_the_caller_with_its_message():
    with pytest.raises(ValueError, match="asked to fail on 2"):
        runtime.map_in_processes(_fail_on, [(1, 2), (2, 2), (3, 2)], workers=3)
    with runtime.process_pool(1) as pool:
        with pytest.raises(ValueError, match="asked to fail on 7"):
            runtime.map_in_processes(_fail_on, [(6, 7), (7, 7)], pool=pool)
        assert runtime.map_in_processes(_fail_on, [(6, 7)], pool=pool) == [6]  # the pool goes on


def test_a_pool_has_its_worker_count_and_preloads_its_modules():
    with multiprocessing.get_context("spawn").Manager() as manager, runtime.process_pool(
        2, preload=("colorsys",)
    ) as pool:
        runtime.start_workers(pool, 2)
        # two calls that wait for each other: both run at once, in two processes
        barrier = manager.Barrier(2)
        pids = runtime.map_in_processes(_meet, [(barrier,), (barrier,)], pool=pool)
        assert len(set(pids)) == 2 and os.getpid() not in pids
        # every call in the pool, in order, and no third process
        out = runtime.map_in_processes(_whoami, [(k,) for k in range(8)], pool=pool)
        assert [r[0] for r in out] == [2 * k for k in range(8)]
        assert {r[1] for r in out} <= set(pids)
        assert all(r[2] for r in out)  # colorsys imported by each worker as it started

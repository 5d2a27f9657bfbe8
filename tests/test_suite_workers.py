"""How many worker processes the suite starts (``tests/conftest.py``'s ``pytest_xdist_auto_num_workers``): no
more than the cores this process may use, nor than the test files asked for by name; 0 (no worker, this process
alone) where that is one."""

import os
from types import SimpleNamespace

import conftest

CORES = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
HERE = os.path.dirname(os.path.abspath(__file__))


def _workers(*args):
    return conftest.pytest_xdist_auto_num_workers(SimpleNamespace(args=list(args)))


def _expected(n):
    n = min(CORES, n)
    return n if n > 1 else 0


def test_the_whole_suite_gets_a_worker_a_core():
    assert _workers(HERE) == _expected(CORES)
    assert _workers() == _expected(CORES)  # no argument: pytest's testpaths


def test_named_files_get_no_more_workers_than_files():
    one = os.path.join(HERE, "test_suite_workers.py")
    two = os.path.join(HERE, "conftest.py")
    assert _workers(one) == 0
    assert _workers(one + "::test_the_whole_suite_gets_a_worker_a_core", one) == 0  # the same file twice
    assert _workers(one, two) == _expected(2)
    assert _workers(one, HERE) == _expected(CORES)  # a folder among them: as many as the cores

"""A result that takes longer to arrive than one bounded wait for it is still fetched (runner._fetch).

The runner waits for a finished batch's result in bounded waits
(``_FETCH_S``, 1 s) so that it can look at the workers in between.  Waiting
with ``Future.result(timeout=...)`` cancelled the client's gather when the
wait ended first, and distributed shares one pending gather among all callers:
every later fetch then joined the cancelled one and failed with
``UnboundLocalError`` (dask/distributed#8514), so the run failed with "the
Dask cluster failed".  Seen on a loaded 2-core machine during a 10^4-point
sweep under tracemalloc; here made certain by waits of 1 ms for 1 MB results
(a transfer takes far longer than 1 ms between processes: the pickled megabyte
is copied through a TCP socket and unpickled).
"""

from __future__ import annotations

import pytest

import simgrip.parallel.runner as runner
from simgrip.parallel.runner import RunnerOptions, run_tasks

pytest.importorskip("distributed")

PAYLOAD = 1_000_000  # bytes per result
ITEMS = 4


def _payload(i):
    return bytes([i]) * PAYLOAD


def test_results_slower_than_one_wait_are_fetched(monkeypatch):
    monkeypatch.setattr(runner, "_FETCH_S", 0.001)
    got = {}
    run_tasks(_payload, range(ITEMS), options=RunnerOptions(jobs=2, progress=False), batch_size=1,
              collect=False, total=ITEMS, on_result=lambda i, r: got.__setitem__(i, r))
    assert sorted(got) == list(range(ITEMS))
    assert all(got[i] == _payload(i) for i in range(ITEMS))

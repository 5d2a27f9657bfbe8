"""A ``dask scheduler`` + ``dask worker`` cluster started from the dask command line, on 127.0.0.1 only.

What a user does to run ``simgrip sweep --scheduler ...`` on their own
machines, done here for the scale measurement (:mod:`simgrip.sweep.profile`)
and the tests: the scheduler and the workers (and their nannies) listen on
127.0.0.1 with no dashboard.  ``--host`` alone is not enough: ``dask scheduler``
and ``dask worker`` also serve HTTP (health, metrics) on all interfaces even
with ``--no-dashboard`` unless ``--dashboard-address`` names 127.0.0.1.  The processes are
stopped (SIGTERM, then SIGKILL after a grace period) when the context exits.
"""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

__all__ = ["dask_cli_cluster"]

#: Seconds allowed for the scheduler to write its file and the workers to register.
START_TIMEOUT_S = 60.0


def _dask_command() -> list[str]:
    exe = shutil.which("dask")
    return [exe] if exe else [sys.executable, "-m", "dask"]


def _stop(proc: subprocess.Popen, grace: float = 3.0) -> None:
    if proc.poll() is not None:
        return
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGTERM)
    try:
        proc.wait(grace)
    except subprocess.TimeoutExpired:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
        proc.wait(grace)


@contextlib.contextmanager
def dask_cli_cluster(workers: int = 2, *, env: dict | None = None, log_dir=None):
    """Start ``dask scheduler`` and ``dask worker --nworkers workers --nthreads 1`` on 127.0.0.1.

    Yields ``(address, scheduler_file, worker_process)``; ``worker_process`` is
    the ``dask worker`` command's process (its worker processes are its
    descendants), ``None`` for ``workers=0`` (a scheduler without workers).
    ``env`` adds environment variables of the workers (e.g. ``PYTHONPATH``).
    Each command runs in its own process group, which is stopped on exit.  Raises ``RuntimeError`` if the cluster does not come up
    within :data:`START_TIMEOUT_S`.
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 0:
        raise ValueError(f"workers must be an integer >= 0, got {workers!r}")
    tmp = Path(tempfile.mkdtemp(prefix="simgrip-dask-"))
    logs = Path(log_dir) if log_dir is not None else tmp
    sfile = tmp / "scheduler.json"
    # as the runner's local cluster: glibc's adaptive malloc trimming, not the nanny's MALLOC_TRIM_THRESHOLD_=65536
    # (~10 % slower settles); an explicit variable wins over dask's setting, and 64 MiB is the adaptive ceiling
    penv = dict(os.environ, MALLOC_TRIM_THRESHOLD_=str(64 << 20), **(env or {}))
    dask = _dask_command()
    procs = []
    try:
        with open(logs / "scheduler.log", "wb") as log:
            procs.append(subprocess.Popen(
                dask + ["scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                        "--dashboard-address", "127.0.0.1:0", "--scheduler-file", str(sfile)],
                stdout=log, stderr=subprocess.STDOUT, env=penv, start_new_session=True))
        deadline = time.monotonic() + START_TIMEOUT_S
        while not sfile.is_file():
            if procs[0].poll() is not None or time.monotonic() > deadline:
                raise RuntimeError(f"dask scheduler did not start (see {logs / 'scheduler.log'})")
            time.sleep(0.05)
        time.sleep(0.1)  # the file is written whole before this is needed, but be safe
        address = json.loads(sfile.read_text())["address"]
        if workers == 0:
            yield address, str(sfile), None
            return
        with open(logs / "worker.log", "wb") as log:
            procs.append(subprocess.Popen(
                dask + ["worker", "--scheduler-file", str(sfile), "--nworkers", str(workers), "--nthreads", "1",
                        "--host", "127.0.0.1", "--no-dashboard", "--dashboard-address", "127.0.0.1:0",
                        "--death-timeout", "30"],
                stdout=log, stderr=subprocess.STDOUT, env=penv, start_new_session=True))
        from distributed import Client

        with Client(address, timeout=START_TIMEOUT_S, set_as_default=False) as client:
            client.wait_for_workers(workers, timeout=max(1.0, deadline - time.monotonic()))
        yield address, str(sfile), procs[1]
    finally:
        for p in reversed(procs):
            _stop(p)
        shutil.rmtree(tmp, ignore_errors=True)

"""The Dask clusters of the runner (:mod:`simgrip.parallel.runner`): start, reach and stop them, and own their processes.

* :class:`LocalDask`: a ``LocalCluster`` of single-threaded worker processes on
  127.0.0.1 (no dashboard; the scheduler's HTTP server on 127.0.0.1 and a free
  port), started in a helper thread with SIGINT blocked, so that the workers
  inherit the block (they leave a terminal's Ctrl-C to the runner) while the
  calling thread stays interruptible; :meth:`LocalDask.stop` closes it, and
  after an interrupt kills its processes first (found in ``/proc`` as the
  descendants this process gained since the start).
* :class:`RemoteDask`: a ``Client`` of an existing cluster; :meth:`RemoteDask.stop`
  cancels this run's tasks and disconnects, leaving the cluster running.
* :func:`quiet_dask_logs`: distributed logs a lost scheduler or worker with
  tracebacks; the runner reports it once, as a ``RunnerError``.

``distributed`` is imported inside the functions: importing this module costs nothing.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading

__all__ = ["LocalDask", "RemoteDask", "descendants", "quiet_dask_logs"]

#: Seconds allowed to reach a remote scheduler.
CONNECT_TIMEOUT_S = 10.0
#: Seconds allowed to close the local cluster after an interrupt before its processes are killed.
CLOSE_TIMEOUT_S = 1.0
#: Seconds allowed to close it after a normal end (a busy machine needs several).
CLOSE_GRACEFUL_S = 15.0


def _in_blocked_thread(make):
    """``make()`` run in a helper thread with SIGINT blocked; this thread waits, interruptibly.

    Threads and processes that ``make`` starts inherit the blocked mask (across
    exec too): the cluster's worker processes leave a terminal's Ctrl-C (sent to
    the whole process group) to this process, which stops them; and this
    thread, not blocking it, raises KeyboardInterrupt at once, even while the
    cluster is still starting.
    """
    box = {}

    def target():
        if hasattr(signal, "pthread_sigmask"):
            signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            box["value"] = make()
        except BaseException as exc:  # handed to the waiting thread
            box["error"] = exc

    helper = threading.Thread(target=target, name="simgrip-cluster-start", daemon=True)
    helper.start()
    while helper.is_alive():
        helper.join(0.05)
    if "error" in box:
        raise box["error"]
    return box["value"]


def _start_local(workers: int):
    """``(LocalCluster, Client)``: ``workers`` processes of one thread on 127.0.0.1, no dashboard."""
    import dask
    from distributed import Client, LocalCluster

    # distributed's nannies set MALLOC_TRIM_THRESHOLD_=65536 in their workers: glibc then trims (and stops
    # adapting its mmap threshold) so often that a settle costs ~10 % more CPU (measured: 30 vs 27 ms per
    # point at n = 32); the workers keep glibc's adaptive default, and the single-threaded BLAS variables
    with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}):
        cluster = LocalCluster(
            n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
            # the scheduler always serves HTTP (/health, /metrics): on 127.0.0.1 and a free port, so
            # that a busy 8787 (another cluster) neither fails the start nor warns; no dashboard on it
            dashboard_address="127.0.0.1:0", scheduler_kwargs={"dashboard": False},
            worker_dashboard_address=None, silence_logs=50,
        )
    try:
        return cluster, Client(cluster, set_as_default=False)
    except BaseException:
        cluster.close(timeout=CLOSE_TIMEOUT_S)
        raise


def _children() -> dict[int, int]:
    """``{pid: ppid}`` of every process (from /proc; empty where there is none)."""
    out = {}
    try:
        names = os.listdir("/proc")
    except OSError:  # pragma: no cover - not Linux
        return out
    for name in names:
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat", "rb") as fh:
                stat = fh.read().decode(errors="replace")
            out[int(name)] = int(stat.rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):
            continue
    return out


def descendants(pid: int | None = None) -> set[int]:
    """Process ids of every descendant of ``pid`` (default: this process), from /proc."""
    pid = os.getpid() if pid is None else pid
    table = _children()
    kids: dict[int, list[int]] = {}
    for c, p in table.items():
        kids.setdefault(p, []).append(c)
    out, todo = set(), [pid]
    while todo:
        for c in kids.get(todo.pop(), ()):
            if c not in out:
                out.add(c)
                todo.append(c)
    return out


def _kill(pids) -> None:
    for pid in pids:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(pid, signal.SIGKILL)


class LocalDask:
    """A LocalCluster of ``workers`` processes and its Client, for one run; :meth:`stop` closes it (and kills its
    processes if need be)."""

    def __init__(self, workers: int):
        # multiprocessing starts its resource tracker with the first worker and then UNBLOCKS SIGINT in the
        # spawning thread (resource_tracker.ensure_running): start it first, so the workers' block holds
        from multiprocessing import resource_tracker

        resource_tracker.ensure_running()
        self.before = descendants()
        spec = sys.modules.get("distributed.deploy.spec")
        self.known = {id(c) for c in spec.SpecCluster._instances} if spec else set()
        try:
            self.cluster, self.client = _in_blocked_thread(lambda: _start_local(workers))
        except BaseException:  # Ctrl-C or a failure while starting: no worker may outlive it
            self._abandon()
            raise

    def _abandon(self) -> None:
        """After a failed start: close what was started (briefly), kill its processes, and keep distributed's
        exit handler from waiting for it again."""
        spec = sys.modules.get("distributed.deploy.spec")
        started = [c for c in (list(spec.SpecCluster._instances) if spec else []) if id(c) not in self.known]

        def close():
            for c in started:
                with contextlib.suppress(Exception):
                    c.close(timeout=CLOSE_TIMEOUT_S)

        closer = threading.Thread(target=close, daemon=True)
        closer.start()
        closer.join(CLOSE_TIMEOUT_S)
        _kill(self.spawned())
        for c in started:
            spec.SpecCluster._instances.discard(c)

    def spawned(self) -> set[int]:
        """Processes started since the cluster was (its workers), except multiprocessing's resource
        tracker (shared by the whole process; killing it only makes multiprocessing warn)."""
        out = set()
        for pid in descendants() - self.before:
            try:
                with open(f"/proc/{pid}/cmdline", "rb") as fh:
                    if b"resource_tracker" in fh.read():
                        continue
            except OSError:
                continue
            out.add(pid)
        return out

    def stop(self, interrupted: bool) -> None:
        if interrupted:
            # no restarts: the nannies are told the workers may go away, then the workers are killed
            for nanny in list(self.cluster.workers.values()):
                with contextlib.suppress(Exception):
                    nanny.close_gracefully(reason="simgrip interrupted")
            _kill(self.spawned())
        timeout = CLOSE_TIMEOUT_S if interrupted else CLOSE_GRACEFUL_S
        closer = threading.Thread(target=self._close, args=(timeout,), daemon=True)
        closer.start()
        closer.join(2 * timeout)
        _kill(self.spawned())  # whatever is still alive (a worker stuck in C code, a restarted one)
        if closer.is_alive() or getattr(getattr(self.cluster, "status", None), "name", "") != "closed":
            # its processes are gone: distributed's own exit handler must not wait for it again (10 s)
            with contextlib.suppress(Exception):
                from distributed.deploy.spec import SpecCluster

                SpecCluster._instances.discard(self.cluster)

    def _close(self, timeout: float) -> None:
        with contextlib.suppress(Exception):
            self.client.close(timeout=timeout)
        with contextlib.suppress(Exception):
            self.cluster.close(timeout=timeout)


class RemoteDask:
    """A Client of an existing cluster (``scheduler`` address or ``scheduler_file``); :meth:`stop` cancels this
    call's work (``futures``) and disconnects."""

    def __init__(self, scheduler: str | None = None, scheduler_file: str | None = None):
        from distributed import Client

        from simgrip.parallel.runner import RunnerError

        self.where = scheduler if scheduler is not None else f"scheduler file {scheduler_file}"
        try:
            if scheduler is not None:
                self.client = Client(scheduler, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
            else:
                self.client = Client(scheduler_file=scheduler_file, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
        except (OSError, TimeoutError) as exc:
            raise RunnerError(f"cannot reach the Dask scheduler at {self.where}: {exc}") from None
        self.futures = []

    def stop(self, interrupted: bool) -> None:
        def close():
            with contextlib.suppress(Exception):
                if interrupted and self.futures:
                    self.client.cancel(self.futures, force=True)
            with contextlib.suppress(Exception):
                self.client.close(timeout=CLOSE_TIMEOUT_S)

        closer = threading.Thread(target=close, daemon=True)
        closer.start()
        closer.join(2 * CLOSE_TIMEOUT_S)


@contextlib.contextmanager
def quiet_dask_logs():
    """distributed logs a lost scheduler or worker with tracebacks; the runner says it once (RunnerError).

    The levels come back when the block ends normally.  When it ends with an
    exception (Ctrl-C, a failed task, a lost cluster) they stay quiet: the
    cluster's event-loop thread may still be closing its connections after the
    block and would log each one (``Batched Comm Closed`` with a traceback)
    under the one line the command prints.
    """
    import logging

    loggers = [logging.getLogger(name) for name in ("distributed", "distributed.client", "distributed.nanny",
                                                     "distributed.scheduler", "distributed.worker",
                                                     "distributed.batched", "distributed.core", "distributed.comm")]
    saved = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL)
    yield  # an exception propagates from here and leaves the loggers quiet
    for lg, level in zip(loggers, saved):
        lg.setLevel(level)



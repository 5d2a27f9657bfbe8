"""The local Dask cluster of the runner (:mod:`simgrip.parallel.runner`): start it, stop it, and own its processes.

* :class:`LocalDask`: a ``LocalCluster`` of single-threaded worker processes on
  127.0.0.1 (no dashboard; the scheduler's HTTP server on 127.0.0.1 and a free
  port), never more of them than :func:`worker_cap` allows (a stated multiple
  of the cores, and the number of tasks).  It is started in a helper thread
  with SIGINT blocked, so that the workers inherit the block (they leave a
  terminal's Ctrl-C to the runner) while the calling thread stays
  interruptible; :meth:`LocalDask.stop` closes it, and after an interrupt kills
  its processes first (found in ``/proc`` as the descendants this process
  gained since the start).
* The cluster is one that distributed's exit handler leaves alone
  (``shutdown_on_close`` false): the runner closes or kills its own
  processes.  Otherwise, after a Ctrl-C during the start, that handler closed
  the cluster at exit (waiting up to 10 s) while the abandoned start closed it
  too; whichever finished first stopped the event loop under the other, whose
  ``distributed.utils.sync`` then ended in ``UnboundLocalError`` (a cancelled
  wait leaves its ``result`` unset): the ``Exception ignored in atexit
  callback ... UnboundLocalError`` of issue 16.
* :func:`quiet_dask_logs`: distributed logs a lost scheduler or worker with
  tracebacks; the runner reports it once, as a ``RunnerError``.

The remote cluster (``--scheduler``) is :mod:`simgrip.parallel.remote`.
``distributed`` is imported inside the functions: importing this module costs nothing.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading

from simgrip.parallel.helper_thread import call_in_helper
from simgrip.parallel.remote import RemoteDask, close_client, forget_client  # RemoteDask: its old home was here

__all__ = ["LocalDask", "RemoteDask", "MAX_WORKERS_PER_CORE", "available_cores", "worker_cap", "descendants", "quiet_dask_logs"]

#: Seconds allowed to close the local cluster after an interrupt before its processes are killed.
CLOSE_TIMEOUT_S = 1.0
#: Seconds allowed to close it after a normal end (a busy machine needs several).
CLOSE_GRACEFUL_S = 15.0
#: Seconds an interrupted start is given to end (what it made is then closed by its own thread).
START_ABORT_S = 1.0
#: Seconds allowed at exit for worker spawns in progress to hand their children the start-up data (see _kill_left).
SPAWN_FINISH_S = 0.5
#: Seconds an abandoned cluster's event loop is held at exit (longer than any exit takes; see _freeze_loops).
FROZEN_FOR_S = 30.0
#: Local worker processes per core at most.  A task (a settle, a BVP solve) is one CPU-bound thread, so more
#: processes than cores only share the cores (and cost ~150 MB each); two per core still lets a task that waits
#: (I/O, a figure's file) overlap with one that computes.  ``--jobs`` above this is capped, not refused.
MAX_WORKERS_PER_CORE = 2
#: Entries of the local cluster's low-level logs (transition log, each connection's recent messages, events) in
#: place of distributed's 1000: they hold whole messages, i.e. batches of items and results (see _start_local).
LOW_LEVEL_LOG_LENGTH = 32


def available_cores() -> int:
    """Cores this process may run on (its CPU affinity; ``os.cpu_count()`` where there is none), at least 1."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def worker_cap(requested: int, tasks: int | None = None) -> int:
    """Worker processes to start for ``requested`` (``--jobs``) and ``tasks`` tasks.

    ``min(requested, tasks, MAX_WORKERS_PER_CORE * available_cores())``, at
    least 1: a worker without a task, or beyond what the cores can run, only
    costs memory and start-up time.
    """
    if isinstance(requested, bool) or not isinstance(requested, int) or requested < 1:
        raise ValueError(f"jobs must be a positive integer, got {requested!r}")
    n = min(requested, MAX_WORKERS_PER_CORE * available_cores())
    if tasks is not None:
        n = min(n, max(1, int(tasks)))
    return n


def _owned_local_cluster():
    """``LocalCluster`` that distributed's exit handler (``close_clusters``) leaves alone: the runner closes it."""
    from distributed import LocalCluster

    class OwnedLocalCluster(LocalCluster):
        """A LocalCluster closed (or killed) by :class:`LocalDask` only, never again at interpreter exit."""

        # SpecCluster.__init__ sets shutdown_on_close=True; atexit's close_clusters closes such clusters
        shutdown_on_close = property(lambda self: False, lambda self, value: None)

    return OwnedLocalCluster


def _start_local(cls, workers: int):
    """``(cluster, Client)``: a ``cls`` (:func:`_owned_local_cluster`) of ``workers`` processes of one thread on
    127.0.0.1, no dashboard."""
    import dask
    from distributed import Client

    # distributed's nannies set MALLOC_TRIM_THRESHOLD_=65536 in their workers: glibc then trims (and stops
    # adapting its mmap threshold) so often that a settle costs ~10 % more CPU (measured: 30 vs 27 ms per
    # point at n = 32); the workers keep glibc's adaptive default, and the single-threaded BLAS variables
    # distributed.admin.low-level-log-length (1000) bounds the debugging logs the in-process scheduler and the
    # client keep: each BatchedSend's recent_message_log holds its last 1000 messages WHOLE (a batch's pickled
    # items going to a worker, its results coming back), so a sweep's client grew by a batch's messages per batch
    # until ~1000 were held (tens of MB); LOW_LEVEL_LOG_LENGTH keeps the last few for a post-mortem.
    # distributed.admin.system-monitor.log-length (7200) is the history of the scheduler's system monitor (in
    # this process: cpu, memory, time, net and disk rates, one sample each 0.5 s, only the dashboard reads it):
    # the client grew ~0.5 kB a second for the first hour of any run, i.e. per batch on a slow machine
    with dask.config.set({"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None,
                          "distributed.admin.low-level-log-length": LOW_LEVEL_LOG_LENGTH,
                          "distributed.admin.system-monitor.log-length": LOW_LEVEL_LOG_LENGTH}):
        cluster = cls(
            n_workers=workers, threads_per_worker=1, processes=True, host="127.0.0.1",
            # the scheduler always serves HTTP (/health, /metrics): on 127.0.0.1 and a free port, so
            # that a busy 8787 (another cluster) neither fails the start nor warns; no dashboard on it
            dashboard_address="127.0.0.1:0", scheduler_kwargs={"dashboard": False},
            worker_dashboard_address=None, silence_logs=50,
        )
    try:
        with dask.config.set({"distributed.admin.low-level-log-length": LOW_LEVEL_LOG_LENGTH}):
            return cluster, Client(cluster, set_as_default=False)
    except BaseException:
        with contextlib.suppress(Exception):
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


def _freeze_loops(clusters, timeout: float) -> None:
    """Hold each cluster's event loop in a callback that waits (until this process has exited), so that no
    coroutine of the abandoned start goes on to create and spawn another worker.

    Returns once every loop is inside the callback (the step it was running has ended), or after ``timeout``
    seconds.  Only for the exit: the loops are never let go.
    """
    held = []
    for cluster in clusters:
        with contextlib.suppress(Exception):
            entered = threading.Event()

            def hold(entered=entered):
                entered.set()
                threading.Event().wait(FROZEN_FOR_S)

            cluster.loop.add_callback(hold)
            held.append(entered)
    for entered in held:
        entered.wait(timeout)


def _finish_spawns(timeout: float) -> None:
    """Let distributed's process threads end what they hold, within ``timeout`` seconds in all.

    distributed runs every start, terminate and kill of a worker process in one thread per process
    (``AsyncProcess``'s message-queue thread), in the order asked.  A ``stop`` message queued behind them
    ends that thread once the ops before it are done, so joining it waits for a spawn in progress to have
    written its child the start-up data (a few ms; the child is then killed whole, without a word).  The
    threads are found by name (a closed nanny no longer refers to its process).
    """
    import time

    threads = []
    for thread in threading.enumerate():
        name = thread.name or ""
        if not (name.startswith("AsyncProcess ") and name.endswith(" watch message queue")) or not thread.is_alive():
            continue
        with contextlib.suppress(Exception):
            thread._args[4].put_nowait({"op": "stop"})  # (selfref, process, loop, state, queue, exit_future)
            threads.append(thread)
    end = time.monotonic() + timeout
    for thread in threads:
        thread.join(max(0.0, end - time.monotonic()))


def _kill(pids) -> None:
    for pid in pids:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.kill(pid, signal.SIGKILL)


class LocalDask:
    """A LocalCluster of at most ``workers`` processes (:func:`worker_cap`, given ``tasks``) and its Client, for one
    run; :meth:`stop` closes it (and kills its processes if need be).

    ``workers`` is the number of processes actually started.  Ctrl-C or
    SIGTERM (as ``KeyboardInterrupt``) during the start kills the processes
    started so far and re-raises within ~:data:`START_ABORT_S`; the start's
    own thread closes whatever it still makes.
    """

    def __init__(self, workers: int, tasks: int | None = None):
        # multiprocessing starts its resource tracker with the first worker and then UNBLOCKS SIGINT in the
        # spawning thread (resource_tracker.ensure_running): start it first, so the workers' block holds
        from multiprocessing import resource_tracker

        self.workers = worker_cap(workers, tasks)
        resource_tracker.ensure_running()
        self.before = descendants()
        self.cluster = self.client = None
        self._held: list = []
        self._exit_kill = None
        self._cls = _owned_local_cluster()  # a class of its own: this run's cluster is found even mid-start
        self.cluster, self.client = call_in_helper(
            lambda: _start_local(self._cls, self.workers), name="simgrip-cluster-start", block_sigint=True,
            discard=self._discard, on_give_up=self._end_workers, settle=START_ABORT_S)

    def _clusters(self) -> list:
        """This run's cluster objects, also one still starting (``SpecCluster._instances`` holds it from its start)."""
        spec = sys.modules.get("distributed.deploy.spec")
        return [c for c in list(spec.SpecCluster._instances) if type(c) is self._cls] if spec else []

    def _nannies(self) -> list:
        """The nannies of this run's cluster, also those still starting (distributed keeps them in ``_created``)."""
        out = []
        for c in self._clusters():
            with contextlib.suppress(Exception):
                out.extend(list(getattr(c, "_created", ())) + list(c.workers.values()))
        return out

    def _end_workers(self) -> None:
        """Tell the nannies not to restart their workers (a restart spawned while this process exits prints a
        multiprocessing traceback), then kill the worker processes; and once more at exit (see below)."""
        if self._exit_kill is None:
            # A start given up on may still spawn a worker (its nanny was mid-start).  At exit multiprocessing
            # unlinks its semaphores first (finalizers of priority 0) and only then ends its children: a child
            # still unpickling them printed "FileNotFoundError" with a traceback.  This finalizer runs before.
            from multiprocessing import util

            self._exit_kill = util.Finalize(None, self._kill_left, exitpriority=100)
        for nanny in self._nannies():
            with contextlib.suppress(Exception):
                nanny.close_gracefully(reason="simgrip interrupted")
            # held here, so that their multiprocessing queues are not freed in a closing thread that the exit
            # then stops half-way (after unlinking a semaphore, before telling the resource tracker, which then
            # warned of a "leaked semaphore" at exit): they go with this object, or at exit, in the main thread
            self._held.append((nanny, getattr(nanny, "process", None)))
        _kill(self.spawned())

    def _kill_left(self) -> None:
        """Kill this cluster's worker processes still alive: those its nannies started, and its descendants.

        At exit a nanny's start may still be handing its new worker the start-up data: multiprocessing
        spawns the child, then writes it the pickled process over a pipe, in the nanny's own (daemon)
        thread.  Exiting between the two closed the pipe under the child, which printed spawn's
        ``EOFError: Ran out of input`` with a traceback under the command's one line.  So each such
        thread is first let finish what it holds (:func:`_finish_spawns`), then every child is killed.
        """
        _freeze_loops(self._clusters(), SPAWN_FINISH_S)
        _finish_spawns(SPAWN_FINISH_S)
        pids = set(self.spawned())
        for nanny in self._nannies():
            pid = getattr(getattr(getattr(nanny, "process", None), "process", None), "pid", None)
            if isinstance(pid, int):
                pids.add(pid)
        _kill(pids)

    def _discard(self, made) -> None:
        """In the start's thread, after the caller gave up: close what the start made, kill its processes."""
        cluster, client = made
        close_client(client, CLOSE_TIMEOUT_S)
        self._end_workers()
        with contextlib.suppress(Exception):
            cluster.close(timeout=CLOSE_TIMEOUT_S)

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

    def trim(self) -> None:
        """Drop what the in-process scheduler keeps of every submitted batch and would keep for ever.

        The local cluster's scheduler runs in this process (on the client's
        event loop).  Two of its records grow with every ``client.submit``
        and are never emptied while it lives: each span's metadata appends
        one ``{"type": "Future"}`` per submit (``Span.add_metadata``; the
        dashboard's list of computed collections), and
        ``dask.utils.key_split``'s cache (100 000 entries) keeps every
        batch's unique key.  Measured with a trivial task, one batch per item
        (``tests/test_runner_memory.py``), the client grew 450-650 traced
        bytes per batch, ~150 with the trim.  Both are
        diagnostics or pure caches: emptying them changes no result.  Runs on
        the event loop (the scheduler's thread); a no-op once closed.
        """
        scheduler = getattr(self.cluster, "scheduler", None)
        loop = getattr(self.client, "loop", None)
        if scheduler is None or loop is None:
            return
        with contextlib.suppress(Exception):
            loop.add_callback(_trim_scheduler, scheduler)

    def stop(self, interrupted: bool) -> None:
        """Close the cluster: after an interrupt or failure within ~2 s, its worker processes killed first."""
        if interrupted:
            self._end_workers()  # no restarts: the nannies are told the workers may go away, then they are killed
        timeout = CLOSE_TIMEOUT_S if interrupted else CLOSE_GRACEFUL_S
        closer = threading.Thread(target=self._close, args=(timeout,), name="simgrip-cluster-close", daemon=True)
        closer.start()
        closer.join(2 * timeout)
        _kill(self.spawned())  # whatever is still alive (a worker stuck in C code, a restarted one)
        if getattr(self.client, "status", None) != "closed":
            forget_client(self.client)  # its close timed out: Client.__del__ must not wait for it again (2 x 30 s)

    def _close(self, timeout: float) -> None:
        with contextlib.suppress(Exception):
            self.client.close(timeout=timeout)
        with contextlib.suppress(Exception):
            self.cluster.close(timeout=timeout)


def _trim_scheduler(scheduler) -> None:
    """On the scheduler's event loop: empty its spans' lists of computed collections and ``key_split``'s cache."""
    from dask.utils import key_split

    spans = getattr(scheduler, "extensions", {}).get("spans")
    for span in list(getattr(spans, "spans", {}).values()):
        meta = getattr(span, "_metadata", None)
        if isinstance(meta, dict) and isinstance(meta.get("collections"), list):
            del meta["collections"][:]
    key_split.cache_clear()


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



"""The one parallel runner: apply a function to many items, in-process or on a Dask cluster.

:func:`run_tasks` is what ``bench``, ``stress``, ``figures`` and ``sweep`` use
to spread independent work (settles, solves, figures) over processes:

* ``jobs=1`` (and no scheduler): a plain in-process loop; Dask is not imported.
* otherwise a :mod:`dask.distributed` cluster: by default a ``LocalCluster`` of
  ``jobs`` worker processes (one thread each) on 127.0.0.1 with no dashboard,
  started for the call and closed after it -- never more processes than there
  are tasks, nor than :data:`~simgrip.parallel.dask_cluster.MAX_WORKERS_PER_CORE`
  per core (:func:`~simgrip.parallel.dask_cluster.worker_cap`; a larger
  ``jobs`` is capped, not refused); or an existing cluster reached by
  ``scheduler`` (address, e.g. ``tcp://127.0.0.1:8786``) or ``scheduler_file``
  (``dask scheduler --scheduler-file``), which is left running
  (:mod:`simgrip.parallel.dask_cluster` starts and stops the local one,
  :mod:`simgrip.parallel.remote` reaches the existing one).

An existing cluster is reached within ``connect_timeout`` (10 s,
``--connect-timeout``) or not at all: a bad address or scheduler file,
nothing listening, a server that is not a Dask scheduler, each raise a named
:class:`SchedulerError` (a ``ValueError``: the command exits with status 2)
within that time, and no traceback follows at exit.  A scheduler that has had
no worker for ``worker_wait`` seconds (30 s, ``--worker-wait``) while the run
waits for results raises :class:`RunnerError` (exit status 1) instead of
waiting at 0 % forever; so does a local cluster whose workers all died and
stayed dead for 30 s.

Items are grouped into contiguous batches, one Dask task per batch, so that the
scheduler's per-task overhead (~ms) stays small against the work; results come
back in item order whatever the batch size.  Workers compute with one BLAS
thread (:class:`simgrip.threads.blas_threads`).  A worker process that dies is
replaced and its batch recomputed by the scheduler (Dask's own retry of lost
tasks); an exception raised by ``fn`` propagates unchanged (callers that must
not stop catch inside ``fn`` and return an error record).  A cluster that goes
away (scheduler gone, a batch killing its workers again and again) raises
:class:`RunnerError`.

Interrupts: Ctrl-C (SIGINT) or SIGTERM during :func:`run_tasks` cancels what is
pending, kills the local cluster's worker processes, closes the cluster and
re-raises :class:`KeyboardInterrupt` (within ~2 s), also while the cluster is
still starting.  Worker processes of the local cluster start with SIGINT
blocked, so a Ctrl-C at a terminal (sent to the whole process group) is handled
once, by this process.  Scripts that start a local cluster need the
``if __name__ == "__main__":`` guard (worker processes are spawned and import
the main module).  The runner writes no files; its workers' MuJoCo warnings go
to their stderr, not into ``MUJOCO_LOG.TXT``.
"""

from __future__ import annotations

import contextlib
import itertools
import math
import os
import signal
import threading
import time
from dataclasses import dataclass
from typing import Callable, Iterable

from simgrip.parallel.dask_cluster import MAX_WORKERS_PER_CORE, available_cores, worker_cap
from simgrip.parallel.errors import RunnerError, SchedulerError
from simgrip.parallel.remote import (
    DEFAULT_CONNECT_TIMEOUT_S,
    DEFAULT_WORKER_WAIT_S,
    MAX_CONNECT_TIMEOUT_S,
    check_address,
    check_seconds,
    read_scheduler_file,
)
from simgrip.threads import blas_threads

__all__ = [
    "RunnerOptions",
    "RunnerError",
    "SchedulerError",
    "MAX_WORKERS_PER_CORE",
    "worker_cap",
    "add_runner_arguments",
    "runner_options",
    "run_tasks",
    "default_batch_size",
]

#: Largest default batch: bounds the work lost with a killed worker and keeps the progress bar moving.
MAX_BATCH = 32
#: Default batches per worker (load balance: the last batches of a run finish at different times).
BATCHES_PER_WORKER = 4
#: Batches submitted ahead per worker: the client holds at most this many batches (items and results) per worker.
IN_FLIGHT_PER_WORKER = 4


@dataclass(frozen=True)
class RunnerOptions:
    """How :func:`run_tasks` runs.

    Attributes
    ----------
    jobs : int or None
        Local worker processes (default: all cores available to this process);
        ``1`` runs a plain in-process loop without Dask.  Capped at
        :data:`MAX_WORKERS_PER_CORE` per core and at the number of tasks.
        Unused with a scheduler.
    scheduler : str or None
        Address of an existing ``dask.distributed`` scheduler, e.g. ``"tcp://127.0.0.1:8786"``
        (checked here, without the network: :class:`SchedulerError` when malformed).
    scheduler_file : str or None
        Or the scheduler file it wrote (``dask scheduler --scheduler-file FILE``; read here:
        :class:`SchedulerError` when missing, not JSON or without an address).
    progress : bool
        One tqdm progress bar on stderr.
    connect_timeout : float
        Seconds allowed to reach the scheduler, in (0, 3600] [default 10].
    worker_wait : float
        Seconds the scheduler may have no worker while the run waits before it fails;
        ``inf`` waits for ever [default 30].
    """

    jobs: int | None = None
    scheduler: str | None = None
    scheduler_file: str | None = None
    progress: bool = True
    connect_timeout: float = DEFAULT_CONNECT_TIMEOUT_S
    worker_wait: float = DEFAULT_WORKER_WAIT_S

    def __post_init__(self):
        if self.jobs is not None:
            if isinstance(self.jobs, bool) or not isinstance(self.jobs, int) or self.jobs < 1:
                raise ValueError(f"jobs must be a positive integer, got {self.jobs!r}")
        if self.scheduler is not None and self.scheduler_file is not None:
            raise ValueError("scheduler and scheduler_file are exclusive: give one of --scheduler, --scheduler-file")
        check_seconds(self.connect_timeout, "connect-timeout", upper=MAX_CONNECT_TIMEOUT_S)
        check_seconds(self.worker_wait, "worker-wait", allow_inf=True)
        if self.scheduler is not None:
            check_address(self.scheduler)
        if self.scheduler_file is not None:
            read_scheduler_file(self.scheduler_file)

    @property
    def remote(self) -> bool:
        """True when an existing cluster is used."""
        return self.scheduler is not None or self.scheduler_file is not None

    @property
    def local_workers(self) -> int:
        """Worker processes of the local cluster: ``jobs`` (default all available cores), at most
        :data:`MAX_WORKERS_PER_CORE` per core (a run with fewer tasks starts fewer)."""
        return worker_cap(self.jobs if self.jobs is not None else available_cores())

    @property
    def in_process(self) -> bool:
        """True for the plain loop (``jobs=1`` and no scheduler)."""
        return not self.remote and self.local_workers == 1


def add_runner_arguments(parser) -> None:
    """Add ``--jobs N``, ``--scheduler ADDRESS``, ``--scheduler-file FILE``, ``--connect-timeout SECONDS``,
    ``--worker-wait SECONDS`` and ``--no-progress`` to ``parser``."""
    g = parser.add_argument_group("parallel runner (Dask)")
    g.add_argument("--jobs", type=int, default=None,
                   help=f"local worker processes [default: all cores]; 1 = in-process, no Dask; at most "
                        f"{MAX_WORKERS_PER_CORE} per core and one per task are started")
    g.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on an existing dask.distributed cluster, e.g. tcp://127.0.0.1:8786")
    g.add_argument("--scheduler-file", default=None, metavar="FILE",
                   help="or reach it through its scheduler file (dask scheduler --scheduler-file FILE)")
    g.add_argument("--connect-timeout", type=float, default=None, metavar="SECONDS",
                   help=f"with --scheduler/--scheduler-file: give up (exit 2) when no Dask scheduler answers "
                        f"within this time [default {DEFAULT_CONNECT_TIMEOUT_S:g}]")
    g.add_argument("--worker-wait", type=float, default=None, metavar="SECONDS",
                   help=f"with --scheduler/--scheduler-file: fail (exit 1) when the scheduler has had no worker "
                        f"for this long; inf waits for ever [default {DEFAULT_WORKER_WAIT_S:g}]")
    g.add_argument("--no-progress", action="store_true", help="no progress bar")


def runner_options(args) -> RunnerOptions:
    """:class:`RunnerOptions` from arguments parsed with :func:`add_runner_arguments`.

    Raises ``ValueError`` naming the option (``jobs``, ``scheduler``,
    ``scheduler-file``, ``connect-timeout``, ``worker-wait``), before any work.
    """
    jobs = getattr(args, "jobs", None)
    scheduler = getattr(args, "scheduler", None)
    scheduler_file = getattr(args, "scheduler_file", None)
    remote = scheduler is not None or scheduler_file is not None
    if jobs is not None and remote:
        raise ValueError("jobs is not used with --scheduler/--scheduler-file (the cluster's workers run the tasks)")
    extra = {}
    for attr, option in (("connect_timeout", "connect-timeout"), ("worker_wait", "worker-wait")):
        value = getattr(args, attr, None)
        if value is not None:
            if not remote:
                raise ValueError(f"{option} is used only with --scheduler/--scheduler-file")
            extra[attr] = value
    return RunnerOptions(jobs=jobs, scheduler=scheduler, scheduler_file=scheduler_file,
                         progress=not getattr(args, "no_progress", False), **extra)


def default_batch_size(n_items: int, workers: int) -> int:
    """Items per task: about :data:`BATCHES_PER_WORKER` batches per worker, at most :data:`MAX_BATCH`."""
    return max(1, min(MAX_BATCH, math.ceil(n_items / (BATCHES_PER_WORKER * max(1, workers)))))


def _run_batch(fn, chunk):
    """Worker side: ``[fn(x) for x in chunk]`` with one BLAS thread, MuJoCo's warnings on the worker's stderr (not
    into ``MUJOCO_LOG.TXT`` in its working folder, the user's)."""
    from simgrip.sim.checks import warnings_to_stderr

    with blas_threads(1), warnings_to_stderr(f"simgrip worker {os.getpid()}"):
        return [fn(x) for x in chunk]


def _check_batch_size(batch_size):
    if batch_size is None:
        return None
    if isinstance(batch_size, bool) or not isinstance(batch_size, int) or batch_size < 1:
        raise ValueError(f"batch_size must be a positive integer, got {batch_size!r}")
    return batch_size


def run_tasks(fn: Callable, items: Iterable, *, options: RunnerOptions = RunnerOptions(), desc: str = "",
              batch_size: int | None = None, on_result: Callable | None = None, collect: bool = True,
              total: int | None = None) -> list | None:
    """Apply ``fn`` to every item and return the results in item order (``None`` with ``collect=False``).

    Parameters
    ----------
    fn : callable
        A picklable top-level function of one item (Dask pickles it by reference,
        so a remote worker needs simgrip installed).
    items : iterable
        The inputs: materialised into a list when ``collect``; otherwise consumed
        lazily, at most :data:`IN_FLIGHT_PER_WORKER` batches per worker ahead of
        the results (a generator of any length keeps this process's memory flat).
    options : RunnerOptions
        In-process loop, local cluster or existing cluster (see the module docstring).
    desc : str
        Label of the progress bar.
    batch_size : int, optional
        Items per Dask task (default :func:`default_batch_size`).  Does not change
        the results.
    on_result : callable, optional
        Called in this process as ``on_result(index, result)`` for every item as
        its batch completes (completion order, not item order): the hook for
        saving partial results.
    collect : bool
        Keep the results and return them (default).  ``False`` keeps none (each
        goes to ``on_result`` and is dropped, and each finished Dask batch is
        released at once) and returns ``None``: memory does not grow with the items.
    total : int, optional
        The number of items when ``items`` has no ``len`` and ``collect=False``
        (progress bar, batch size, workers); required then.

    Raises
    ------
    Exception
        Whatever ``fn`` raised, unchanged (the other tasks are cancelled).
    RunnerError
        The cluster could not be reached or went away.
    KeyboardInterrupt
        On Ctrl-C or SIGTERM, after the pending work is cancelled and the local
        cluster is closed and its processes killed.
    """
    if not isinstance(options, RunnerOptions):
        raise ValueError(f"options must be a RunnerOptions, got {type(options).__name__}")
    batch_size = _check_batch_size(batch_size)
    if collect:
        items = list(items)
        n = len(items)
    else:
        n = len(items) if hasattr(items, "__len__") else total
        if isinstance(n, bool) or not isinstance(n, int) or n < 0:
            raise ValueError(f"total must be the number of items (an int >= 0) when items has no len and "
                             f"collect=False, got {total!r}")
    if n == 0:
        return [] if collect else None
    from tqdm import tqdm

    with _sigterm_as_interrupt(), tqdm(total=n, desc=desc or None, unit="task",
                                       disable=not options.progress) as bar:
        if options.in_process:
            out = [] if collect else None
            with blas_threads(1):
                for i, item in enumerate(items):
                    res = fn(item)
                    if collect:
                        out.append(res)
                    if on_result is not None:
                        on_result(i, res)
                    bar.update(1)
            return out
        return _run_dask(fn, iter(items), n, options, batch_size, on_result, bar, collect)


@contextlib.contextmanager
def _sigterm_as_interrupt():
    """Within the block, SIGTERM raises KeyboardInterrupt (main thread only; elsewhere a no-op).

    A Python handler already installed for SIGTERM runs first (the command
    line's records that the signal was handled, so that its watchdog does not
    take the main thread for stuck and end the process the hard way).
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.getsignal(signal.SIGTERM)

    def handler(signum, frame):
        if callable(previous):
            previous(signum, frame)  # may raise KeyboardInterrupt itself
        raise KeyboardInterrupt(f"signal {signum}")

    old = signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


def _run_dask(fn, items, n, options, batch_size, on_result, bar, collect) -> list | None:
    from simgrip.parallel.dask_cluster import quiet_dask_logs

    with quiet_dask_logs():
        return _run_dask_quietly(fn, items, n, options, batch_size, on_result, bar, collect)


def _run_dask_quietly(fn, items, n, options, batch_size, on_result, bar, collect) -> list | None:
    from distributed import KilledWorker, as_completed

    from simgrip.parallel.dask_cluster import LocalDask
    from simgrip.parallel.remote import RemoteDask, WorkerWatch

    interrupted = False
    watch = None
    if options.remote:
        env = RemoteDask(options.scheduler, options.scheduler_file, timeout=options.connect_timeout)
        workers = max(1, len(env.identity.get("workers", {})))
    else:
        workers = min(options.local_workers, n)
    if batch_size is None:
        batch_size = default_batch_size(n, workers)
    tasks = math.ceil(n / batch_size)
    if not options.remote:
        env = LocalDask(workers, tasks=tasks)  # no more processes than tasks
    try:
        client = env.client
        if options.remote:
            watch = WorkerWatch(client, f"the Dask scheduler at {env.where}", options.worker_wait,
                                workers=len(env.identity.get("workers", {})))
        else:  # its nannies restart a worker that dies within ~1 s; none for this long: they died and stayed dead
            watch = WorkerWatch(client, "the local Dask cluster", DEFAULT_WORKER_WAIT_S, hint="its worker processes "
                                "died and were not restarted (out of memory? killed?); run again, or with --jobs 1")
        # collect=False: batches are cut from the items and submitted as earlier ones finish, at most `limit` in
        # flight, so the items, futures and results held here are bounded whatever the number of items; collect:
        # the items and results are all held anyway, and every batch is submitted at once (as always)
        limit = IN_FLIGHT_PER_WORKER * max(1, workers) if not collect else tasks
        batches = _batches(items, batch_size)
        env.futures = []
        start_of = {}
        out = [None] * n if collect else None
        losses = {}
        pending = as_completed([], loop=client.loop)
        done = 0

        def submit_more():
            while len(start_of) < limit:
                nxt = next(batches, None)
                if nxt is None:
                    return
                s, chunk = nxt
                f = client.submit(_run_batch, fn, chunk, pure=False, key=f"simgrip-batch-{s}-{_token()}")
                start_of[f.key] = s
                env.futures.append(f)
                pending.add(f)

        submit_more()
        while True:
            fut = _next_done(pending, watch)
            if fut is None:
                break
            if fut.status == "error":
                exc = fut.exception()
                if isinstance(exc, KilledWorker):  # the scheduler gave up: the batch crashed workers again and again
                    raise RunnerError(f"a batch killed its worker process each time it ran (a crash or out of memory "
                                      f"in the task): {exc}") from None
                raise exc.with_traceback(fut.traceback())
            chunk = _fetch(fut, watch) if fut.status == "finished" else _LOST
            if chunk is _LOST:
                if fut.status in ("lost", "pending", "finished") and _connected(client) \
                        and losses.get(fut.key, 0) < _MAX_LOSSES:
                    # its result sat on a worker that died after the batch finished (before or while it was
                    # fetched): the scheduler recomputes it, and it is waited for again
                    losses[fut.key] = losses.get(fut.key, 0) + 1
                    pending.add(fut)
                    continue
                where = f"at {env.where} " if options.remote else ""
                raise RunnerError(f"the Dask cluster {where}went away (scheduler gone or its workers lost: a batch "
                                  f"was {fut.status})")
            s = start_of.pop(fut.key)
            env.futures.remove(fut)
            for j, res in enumerate(chunk):
                if collect:
                    out[s + j] = res
                if on_result is not None:
                    on_result(s + j, res)
            bar.update(len(chunk))
            fut.release()
            del chunk
            done += 1
            if not collect and not options.remote and done % _TRIM_EVERY == 0:
                env.trim()  # the in-process scheduler's per-submit records (LocalDask.trim)
            submit_more()
        return out
    except BaseException:  # Ctrl-C, fn failed or the cluster did: stop the rest now
        interrupted = True
        raise
    finally:
        env.stop(interrupted)


#: Seconds between checks while no batch is done (signals are handled at once; this only paces the worker watch).
_POLL_S = 0.05


_LOST = object()  # a batch whose result went away with its worker
#: Seconds one wait for a finished batch's result lasts before its status and the workers are looked at again.
_FETCH_S = 1.0


def _fetch(fut, watch):
    """The result of the finished future ``fut``, or :data:`_LOST` if it went with its worker while fetched.

    A result lives on the worker that computed it; a worker that dies before
    the client has it turns the future back to lost/pending, and a plain
    ``result()`` would then wait for its recomputation for ever -- also on a
    cluster with no worker left (``watch`` fails the run then).

    One gather is started on the client's event loop and each wait for it is
    bounded, but a wait that ends never cancels it: ``Future.result(timeout=...)``
    cancels the client's gather when it times out, and distributed shares one
    pending gather among all callers (``Client._gather_future``), so a
    transfer slower than the wait (a 2 MB result with a 1 ms wait, or a
    sweep's batch on a loaded machine) left a cancelled gather that every
    later fetch joined: each then failed with ``UnboundLocalError`` from
    ``distributed.utils.sync`` and the run with "the Dask cluster failed"
    (dask/distributed#8514; ``tests/test_runner_fetch.py``).  A gather left
    behind (its result lost with a worker) ends on its own, or when the client
    closes.
    """
    import asyncio

    gather = asyncio.run_coroutine_threadsafe(_gathered(fut), fut.client.loop.asyncio_loop)
    while True:
        try:
            return gather.result(timeout=_FETCH_S)
        except TimeoutError:
            if fut.status != "finished":
                return _LOST
            if watch is not None:
                watch.check()
        except Exception as exc:  # cancelled/lost: the cluster's failure, not fn's
            raise RunnerError(f"the Dask cluster failed: {type(exc).__name__}: {exc}") from None


async def _gathered(fut):
    """On the client's event loop: ``fut``'s result (raises what the gather raises)."""
    return await fut.client.gather(fut, asynchronous=True)


def _next_done(pending, watch):
    """The next completed future of ``pending`` (``None`` when all are done), checking ``watch`` while waiting."""
    while not pending.has_ready():
        if pending.is_empty():
            return None
        if watch is not None:
            watch.check()
        time.sleep(_POLL_S)
    return next(pending)


#: Finished batches between two trims of the local scheduler's per-submit records (collect=False).
_TRIM_EVERY = 64

_MAX_LOSSES = 5  # times one batch's result may be lost with its worker before the run gives up


def _connected(client) -> bool:
    """Whether the client still talks to its scheduler (a lost result is then recomputed)."""
    return getattr(client, "status", None) == "running"


def _batches(items, batch_size: int):
    """``(start, [items])`` of consecutive batches of ``batch_size``, cut lazily from the iterator ``items``."""
    start = 0
    while True:
        chunk = list(itertools.islice(items, batch_size))
        if not chunk:
            return
        yield start, chunk
        start += len(chunk)


def _token() -> str:
    return f"{os.getpid()}-{time.monotonic_ns()}"

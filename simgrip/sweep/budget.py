"""What a sweep or a stress run will cost, estimated from its options before anything is allocated or computed.

A design grid of ``10^10`` points, ``--jobs 100000`` or ``stress --cases 10^9``
cannot finish on any machine; they are refused (``ValueError`` naming the
option, exit 2 on the command line) with the estimate that rules them out,
before any array, file or worker process exists.  Counts are Python ints
(exact for any size, ``1e300`` included) and costs Python floats.

The cost model (stated; the estimates are rough, the bounds generous):

* **time**: a point costs :func:`seconds_per_point` of one worker,
  ``T0 + T1 * links`` (settle + BVP), measured on a shared 2-core machine
  (Grip I, -7 <= kappa <= -3, M in {2, 8}): Newton 39, 41, 57, 58, 91 and
  154 ms at n = 8, 16, 32, 64, 128, 256 links; dynamics 0.24, 0.21, 0.22,
  0.16, 0.28 and 0.60 s.  Wall time = points x that / workers;
* **client memory** (the process that runs the sweep): with an output folder
  rows go to disk as they arrive, and the client keeps one byte per point
  (which points are done), the axis values and the points in flight
  (:data:`CHUNK_BYTES`); without one it keeps every record
  (:data:`RECORD_BYTES` each);
* **disk**: :data:`CSV_ROW_BYTES` per row, twice (the saved batches and
  ``sweep.csv`` exist together until the batches are deleted).

The bounds come from the machine: at most :data:`MEMORY_FRACTION` of the
memory available now (``MemAvailable`` in ``/proc/meminfo``), the free space
of the output folder's file system, :data:`MAX_WALL_DAYS` of wall time on the
local workers, and never more than :data:`MAX_POINTS` points or
:data:`MAX_AXIS_VALUES` values on one axis (the axes are listed in
``sweep.json``).  Worker processes: at most :data:`JOBS_PER_CORE` (2) per core
and no more than there are tasks, and no more than fit in memory at
:data:`WORKER_BYTES` each (a note says so when ``--jobs`` is lowered); a
``--jobs`` above :data:`MAX_JOBS` is refused.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

from simgrip.parallel.dask_cluster import MAX_WORKERS_PER_CORE, available_cores

__all__ = [
    "MAX_POINTS", "MAX_AXIS_VALUES", "MAX_WALL_DAYS", "MAX_JOBS", "JOBS_PER_CORE", "MAX_CASES",
    "Machine", "machine", "seconds_per_point", "SweepEstimate", "estimate_sweep", "check_sweep",
    "cap_jobs", "check_stress", "count_text", "human_bytes", "human_seconds",
]

#: Most points of one sweep on any machine (a 10^8-row table is ~40 GB; split bigger maps along an axis).
MAX_POINTS = 10**8
#: Most values of one axis (each is listed in spec.json and sweep.json, ~25 bytes apiece).
MAX_AXIS_VALUES = 10**6
#: Longest estimated wall time accepted (days): a sweep that needs longer is split or given a cluster.
MAX_WALL_DAYS = 7.0
#: Share of the memory available now that the client (the sweep's own process) may plan to use.
MEMORY_FRACTION = 0.5
#: Settle + BVP time of one point on one worker: T0 + T1 * links [s] (see the module docstring).
SECONDS_PER_POINT = {"newton": (0.025, 0.0005), "dynamics": (0.2, 0.0016)}
#: A record in memory: a dict of 22 fields (~1.3 kB by sys.getsizeof, with its floats and strings), rounded up.
RECORD_BYTES = 2_000
#: A point in memory (a SweepPoint of 10 fields, ~0.35 kB measured with tracemalloc), rounded up.
POINT_BYTES = 500
#: A row of sweep.csv: ~220 bytes measured; messages (warnings, errors) make some longer.
CSV_ROW_BYTES = 400
#: An axis value in memory and in the JSON files (a float in a tuple, a list, a JSON number).
AXIS_VALUE_BYTES = 100
#: Points in flight (sent, results not yet saved): in-process one segment (:data:`simgrip.sweep.grid.SEGMENT_POINTS`);
#: on Dask at most IN_FLIGHT_PER_WORKER (4) batches of at most 32 segments of 32 points per worker
#: (:func:`simgrip.parallel.runner.run_tasks` with ``collect=False``): 8192 for the default 2 workers.  Each local
#: worker also costs :data:`WORKER_BYTES`, 30x what its points in flight cost this process.
CHUNK_IN_PROCESS = 256
CHUNK_DASK = 8192
#: Client memory of the points in flight of 2 workers (points and records).
CHUNK_BYTES = CHUNK_DASK * (POINT_BYTES + RECORD_BYTES)
#: Settles are CPU-bound single-threaded tasks: beyond one worker per core nothing is gained; up to this many per
#: core are started (the runner's own cap, :data:`simgrip.parallel.dask_cluster.MAX_WORKERS_PER_CORE`), more are
#: capped with a note.
JOBS_PER_CORE = MAX_WORKERS_PER_CORE
#: Wall time a local Dask cluster costs before its first point and at its close [s]: a sweep whose whole work
#: in-process is shorter than what parallel workers would save of it minus this runs in-process
#: (:func:`worth_a_cluster`).  Measured with ``simgrip sweep I --kappa -7 -3 3 --links 16 --jobs 2`` against
#: ``--jobs 1`` on an idle 2-core machine (see the note of issue 16).
LOCAL_CLUSTER_START_S = 3.0
#: A --jobs above this is refused: no machine this runs on has use for more local worker processes.
MAX_JOBS = 1024
#: Memory of one local worker process with simgrip, MuJoCo, SciPy and distributed imported (~250 MB), rounded up.
WORKER_BYTES = 300 * 2**20
#: Most stress cases (each is kept with its outcome and listed in stress.json).
MAX_CASES = 10**6
#: Mean time of a stress case on one worker [s] (500 cases + 10 K-finger cases: 38 s on 2 workers = 0.15 s) ...
STRESS_SECONDS_PER_CASE = 0.15
#: ... and its memory: the case, its record and its share of stress.json being written (~4 kB), rounded up.
STRESS_CASE_BYTES = 10_000


@dataclass(frozen=True)
class Machine:
    """What the bounds are made from: memory available now [bytes], cores, and free disk [bytes] (None: unknown)."""

    memory: int
    cores: int
    disk: int | None = None


def _available_memory() -> int:
    """``MemAvailable`` of /proc/meminfo [bytes], else free physical pages (os.sysconf)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (OSError, ValueError, AttributeError):  # pragma: no cover - not POSIX
        return 2**30


def _free_disk(path) -> int | None:
    """Free bytes of the file system that holds ``path`` (its nearest existing parent); None if unknown."""
    if path is None:
        return None
    p = os.path.abspath(os.fspath(path))
    while not os.path.exists(p) and os.path.dirname(p) != p:
        p = os.path.dirname(p)
    try:
        st = os.statvfs(p)
    except (OSError, AttributeError):
        return None
    return int(st.f_bavail) * int(st.f_frsize)


def machine(out=None) -> Machine:
    """This machine now: available memory, cores, and the free disk of ``out``'s file system."""
    return Machine(memory=_available_memory(), cores=available_cores(), disk=_free_disk(out))


def _f(x) -> float:
    """An int (possibly huge) as a float; ``inf`` beyond float range."""
    try:
        return float(x)
    except OverflowError:
        return math.inf


def count_text(n: int) -> str:
    """A count in words: exact up to 10^12 (``10000000000 (1e+10)``), else its magnitude (``~1e+300``)."""
    if n < 10**12:
        return f"{n} ({_f(n):.3g})" if n >= 10**5 else str(n)
    return f"~{_f(n):.3g}"


def human_bytes(b: float) -> str:
    """``b`` bytes in words (``~12 GB``)."""
    if not math.isfinite(b):
        return "more bytes than a float holds"
    for unit, size in (("EB", 2**60), ("PB", 2**50), ("TB", 2**40), ("GB", 2**30), ("MB", 2**20), ("kB", 2**10)):
        if b >= size:
            return f"{b / size:.3g} {unit}"
    return f"{b:.0f} bytes"


def human_seconds(s: float) -> str:
    """``s`` seconds in words (``~3.2 days``)."""
    if not math.isfinite(s):
        return "forever"
    for unit, size in (("years", 365.25 * 86400), ("days", 86400), ("hours", 3600), ("minutes", 60)):
        if s >= size:
            return f"{s / size:.3g} {unit}"
    return f"{s:.3g} s"


def seconds_per_point(links: int, method: str = "newton") -> float:
    """Estimated time of one point on one worker [s]: ``T0 + T1 * links`` (:data:`SECONDS_PER_POINT`)."""
    t0, t1 = SECONDS_PER_POINT.get(method, SECONDS_PER_POINT["newton"])
    return t0 + t1 * float(links)


@dataclass(frozen=True)
class SweepEstimate:
    """The cost of a sweep and the most points this machine allows for it.

    Attributes
    ----------
    points : int
        Points of the grid (exact).
    workers : int or None
        Workers the time is estimated for (None: a remote cluster, size unknown before it is reached).
    seconds_per_point : float
        Of one worker [s].
    memory_bytes, disk_bytes : float
        Client memory and disk the sweep needs.
    seconds : float or None
        Estimated wall time [s] (None with ``workers`` None).
    max_points : int
        The most points the bounds allow here; ``limits`` says which bound gives it.
    limits : dict
        ``{bound name: most points it allows}``.
    """

    points: int
    workers: int | None
    seconds_per_point: float
    memory_bytes: float
    disk_bytes: float
    seconds: float | None
    max_points: int
    limits: dict

    @property
    def fits(self) -> bool:
        return self.points <= self.max_points

    def describe(self) -> str:
        """One phrase: memory, disk and time (what the refusal prints)."""
        parts = [f"~{human_bytes(self.memory_bytes)} of memory", f"~{human_bytes(self.disk_bytes)} of disk"]
        if self.seconds is not None:
            parts.append(f"~{human_seconds(self.seconds)} on {self.workers} worker{'s' * (self.workers != 1)} "
                         f"at {1.0 / self.seconds_per_point:.3g} points/s each")
        else:
            parts.append(f"~{human_seconds(_f(self.points) * self.seconds_per_point)} of worker time")
        return ", ".join(parts)


def estimate_sweep(counts, links: int, method: str = "newton", *, workers: int | None = 1, to_disk: bool = True,
                   here: Machine | None = None) -> SweepEstimate:
    """Estimate a sweep of ``counts`` values per axis (ints) from the counts alone; nothing is allocated.

    ``workers``: local workers the time is estimated for (None for a remote
    cluster: no time bound).  ``to_disk``: rows streamed to an output folder
    (else kept in memory).  ``here``: the machine (default :func:`machine`,
    without a disk figure unless given).
    """
    here = machine() if here is None else here
    counts = [int(c) for c in counts]
    points = math.prod(counts)
    axis_values = sum(counts)
    sec = seconds_per_point(links, method)
    per_point_mem = 1 if to_disk else RECORD_BYTES
    fixed_mem = CHUNK_BYTES + AXIS_VALUE_BYTES * axis_values
    memory = fixed_mem + per_point_mem * _f(points)
    disk = 2 * CSV_ROW_BYTES * _f(points) if to_disk else 0.0
    limits = {"points": MAX_POINTS}
    budget = MEMORY_FRACTION * here.memory - CHUNK_BYTES  # the axes have their own bound (MAX_AXIS_VALUES)
    limits["memory"] = max(0, int(budget // per_point_mem))
    if to_disk and here.disk is not None:
        limits["disk"] = max(0, int(here.disk // (2 * CSV_ROW_BYTES)))
    seconds = None
    if workers is not None:
        seconds = _f(points) * sec / workers
        limits["time"] = int(MAX_WALL_DAYS * 86400 * workers / sec)
    return SweepEstimate(points=points, workers=workers, seconds_per_point=sec, memory_bytes=memory, disk_bytes=disk,
                         seconds=seconds, max_points=min(limits.values()), limits=limits)


def check_sweep(counts: dict, links: int, method: str = "newton", *, workers: int | None = 1, to_disk: bool = True,
                here: Machine | None = None) -> SweepEstimate:
    """Refuse a grid this machine cannot sweep; returns the estimate when it can.

    ``counts`` maps each axis (``kappa``, ``D``, ...) to its number of values.
    Raises ``ValueError`` naming the option(s) that make the grid (``--kappa``,
    or ``--kappa x --M`` ...), the estimate and the most points allowed, e.g.
    ``kappa: 10000000000 points (1e+10) would need ~9.3 GB of memory, ~7.3 TB
    of disk, ~12 years on 2 workers ...; at most 100000000 points here (the
    points bound)``.  An axis above :data:`MAX_AXIS_VALUES` is refused naming it.
    """
    est = estimate_sweep(list(counts.values()), links, method, workers=workers, to_disk=to_disk, here=here)
    if not est.fits:
        swept = [a for a, c in counts.items() if c > 1] or list(counts)[:1]
        what = " x ".join(f"{a} ({counts[a]})" for a in swept) if len(swept) > 1 else swept[0]
        binding = [k for k, v in est.limits.items() if v == est.max_points]
        why = {"points": f"the bound of {MAX_POINTS} points", "memory": f"{MEMORY_FRACTION:.0%} of the "
               f"{human_bytes((here or machine()).memory)} of memory available", "disk": "the free disk of --out",
               "time": f"{MAX_WALL_DAYS:g} days on {workers} worker{'s' * (workers != 1)}"}
        raise ValueError(f"{what}: {count_text(est.points)} points would need {est.describe()}; "
                         f"at most {est.max_points} points here ({why[binding[0]]}): sweep fewer values, or "
                         "split the grid into several sweeps")
    for name, c in counts.items():
        if c > MAX_AXIS_VALUES:
            raise ValueError(f"{name}: {count_text(c)} values on one axis; at most {MAX_AXIS_VALUES} "
                             f"(every value is listed in sweep.json; the grid's {count_text(est.points)} points "
                             f"would need {est.describe()})")
    return est


def worth_a_cluster(points: int, links: int, method: str, jobs: int) -> bool:
    """Whether ``jobs`` local workers finish ``points`` sooner than one process does.

    In-process the work takes ``T = points * seconds_per_point``; ``jobs`` workers save at most
    ``T (1 - 1/jobs)`` of it and cost :data:`LOCAL_CLUSTER_START_S` to start and stop.
    """
    work = max(0, int(points)) * seconds_per_point(links, method)
    return jobs > 1 and work * (1.0 - 1.0 / jobs) > LOCAL_CLUSTER_START_S


def cap_jobs(jobs, tasks: int, *, option: str = "jobs", here: Machine | None = None) -> tuple[int | None, str | None]:
    """The number of local workers to start for ``jobs`` requested and ``tasks`` to run, and a note if lowered.

    ``jobs=None`` (the default: all cores) becomes at most ``tasks``, quietly.
    An explicit ``jobs`` is lowered to the smallest of ``tasks``,
    :data:`JOBS_PER_CORE` x cores and the workers that fit in half the
    available memory (:data:`WORKER_BYTES` each); the note says so.  Raises
    ``ValueError`` naming ``option`` for a value that is not an integer >= 1 or
    is above :data:`MAX_JOBS`.
    """
    here = machine() if here is None else here
    tasks = max(1, int(tasks))
    if jobs is None:
        return (None if tasks >= here.cores else tasks), None
    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise ValueError(f"{option} must be a positive integer, got {jobs!r}")
    if jobs > MAX_JOBS:
        raise ValueError(f"{option}: {jobs} worker processes is above the bound of {MAX_JOBS}; this machine has "
                         f"{here.cores} core{'s' * (here.cores != 1)} (at most {JOBS_PER_CORE} workers per core "
                         "are started)")
    by_cores = JOBS_PER_CORE * here.cores
    by_memory = max(1, int(MEMORY_FRACTION * here.memory // WORKER_BYTES))
    capped = min(jobs, tasks, by_cores, by_memory)
    if capped == jobs:
        return jobs, None
    why = []
    if capped == tasks:
        why.append(f"{tasks} task{'s' * (tasks != 1)} to run")
    if capped == by_cores:
        why.append(f"{JOBS_PER_CORE} per core on {here.cores} core{'s' * (here.cores != 1)}")
    if capped == by_memory:
        why.append(f"{human_bytes(here.memory)} of memory available, ~{human_bytes(WORKER_BYTES)} per worker")
    return capped, f"{option} {jobs} lowered to {capped} ({'; '.join(why)})"


#: a full-contact stress case's cost in point-contact cases (0.5-4 s against 0.15 s)
FULL_CASE_WEIGHT = 20


def check_stress(cases: int, gripper_cases: int = 0, *, full_cases: int = 0, workers: int | None = 1,
                 here: Machine | None = None) -> float:
    """Refuse a stress run this machine cannot finish; returns its estimated wall time [s].

    Raises ``ValueError`` naming ``cases``, ``gripper_cases`` or ``full_cases`` (the largest share) with the
    estimate: memory at :data:`STRESS_CASE_BYTES` a case, time at :data:`STRESS_SECONDS_PER_CASE` a case and
    worker (a full-contact case counts :data:`FULL_CASE_WEIGHT` cases: 0.5-4 s against 0.15 s), at most
    :data:`MAX_CASES` cases, half the available memory, :data:`MAX_WALL_DAYS`.
    """
    here = machine() if here is None else here
    w = workers or here.cores
    limit_mem = int(MEMORY_FRACTION * here.memory // STRESS_CASE_BYTES)
    limit_time = int(MAX_WALL_DAYS * 86400 * w / STRESS_SECONDS_PER_CASE)
    limit = min(MAX_CASES, limit_mem, limit_time)
    parts = [("cases", int(cases), "cases"), ("gripper_cases", int(gripper_cases), "K-finger cases"),
             ("full_cases", FULL_CASE_WEIGHT * int(full_cases), "full-contact cases")]
    total = sum(v for _, v, _ in parts)
    seconds = _f(total) * STRESS_SECONDS_PER_CASE / w
    if total > limit:
        name = max(parts, key=lambda part: part[1])[0]
        what = " + ".join(f"{count_text(int(full_cases))} {label} (as {count_text(v)})" if key == "full_cases"
                          else f"{count_text(v)} {label}" for key, v, label in parts if v or key == "cases")
        raise ValueError(f"{name}: {what} would need ~{human_bytes(_f(total) * STRESS_CASE_BYTES)}"
                         f" of memory and ~{human_seconds(seconds)} on {w} worker{'s' * (w != 1)}; at most {limit} "
                         f"cases here (bounds: {MAX_CASES} cases, {MEMORY_FRACTION:.0%} of "
                         f"{human_bytes(here.memory)} of memory, {MAX_WALL_DAYS:g} days)")
    return seconds

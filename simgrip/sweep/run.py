"""Design sweeps: the settled simulation and the elastica BVP over a grid of designs (``simgrip sweep``).

For every point of a :class:`~simgrip.sweep.grid.SweepGrid` (the full
grid of ``kappa, D, M, mu, b, gamma``) a worker settles the MuJoCo fingers and
solves the BVP (:func:`~simgrip.sweep.point.evaluate_point`); the
points run through the one parallel runner (:func:`simgrip.parallel.runner.run_tasks`):
in-process (``jobs=1``), on a local Dask cluster, or on an existing one
(``--scheduler``), batched so that Dask's per-task overhead stays small.  Every
point is settled from scratch, like ``simgrip simulate`` at the same values:
warm starts of the settle along the kappa axis (:func:`simgrip.settle.settle_sweep`)
are not used, because they change the answer (a warm-started release can stay
on another equilibrium branch, or hold where the closing procedure drops).
The BVP reference is warm-started: the grid is cut into continuation segments
by the grid alone (:meth:`~simgrip.sweep.grid.SweepGrid.segments`: runs of at
most :data:`~simgrip.sweep.grid.SEGMENT_POINTS` points along the fastest swept
axis), each a unit of work (:func:`~simgrip.sweep.point.evaluate_segment`:
cold at its first point, warm along it, re-solved cold where a warm start
jumps branch), so a point's reference does not depend on the workers or the
batch size either.  Hence the rows (all columns but the times,
:data:`~simgrip.sweep.point.TIME_COLUMNS`) are the same for any runner and
batch size.  ``reference="none"`` (``--reference none``) solves no BVP.

With an output folder the sweep writes ``sweep.csv`` (one row per point, grid
order, :data:`~simgrip.sweep.point.COLUMNS`), ``sweep.json``
(arguments, versions, counts) and ``map.png`` (:mod:`~simgrip.sweep.map`),
each atomically, after saving finished points in ``.partial/`` as they arrive
(:mod:`~simgrip.sweep.store`): an interrupted sweep is completed by
``resume=True`` (``--resume``) without recomputing saved points (damaged
batch files are set aside and recomputed).  Dask recomputes the batch of a
worker that dies, so no point is lost or doubled.

Bounded: the grid is estimated and checked before anything is allocated
(:mod:`~simgrip.sweep.budget`: points, memory, disk, time at the stated
points/s; ``--jobs`` capped); segments go to the runner from a generator, a
few batches per worker in flight (:func:`simgrip.parallel.runner.run_tasks`
with ``collect=False``: one local cluster for the whole sweep, no result
kept), rows are saved as they arrive and merged into ``sweep.csv`` by
streaming, the counts, the medians of the times and the map are made on the
way: with an output folder this process keeps one byte per point.
``sweep.json`` reports the throughput (points/s and points/s per core of the
computing phase, wall per point, the median settle and the median of each
point's time over its settle).
"""

from __future__ import annotations

import argparse

import json
import math
import sys
import time
from dataclasses import dataclass, field, replace
from pathlib import Path

from simgrip.parallel.runner import RunnerOptions, add_runner_arguments, run_tasks, runner_options
from simgrip.sweep.budget import cap_jobs, check_sweep, machine, worth_a_cluster
from simgrip.sweep.grid import SEGMENT_POINTS, SweepGrid, make_grid
from simgrip.sweep.map import check_map
from simgrip.sweep.point import COLUMNS, evaluate_segment
from simgrip.sweep.versions import versions  # re-exported
from simgrip.sweep.store import PARTIAL, PartialStore, Tally, counts, iter_csv

__all__ = ["SweepResult", "run_sweep", "add_arguments", "cli_sweep", "versions", "stderr_note"]


@dataclass
class SweepResult:
    """A finished sweep.

    Attributes
    ----------
    grid : SweepGrid
    counts : dict
        Points per status, held, feasible, agreeing, ... (:func:`~simgrip.sweep.store.counts`).
    computed, resumed : int
        Points computed by this call and points taken from an interrupted run's saved results.
    wall_time_s : float
        Time of the whole call [s] (cluster start-up included).
    paths : dict
        ``{"csv", "json", "map"}`` file paths, empty without an output folder.
    records : list of dict or None
        The table in memory, for a sweep without an output folder; ``None``
        when it was streamed to ``sweep.csv`` (read it with :meth:`iter_rows`
        or :attr:`rows`).
    throughput : dict
        How fast the points ran (:func:`throughput`; also in ``sweep.json``).
    """

    grid: SweepGrid
    counts: dict
    computed: int
    resumed: int
    wall_time_s: float
    paths: dict = field(default_factory=dict)
    records: list | None = None
    throughput: dict = field(default_factory=dict)

    def iter_rows(self):
        """Every record, in grid order, keys ``index`` and :data:`~simgrip.sweep.point.COLUMNS`, one at a time
        (read from ``sweep.csv`` when the sweep wrote one: memory does not grow with the table)."""
        if self.records is not None:
            yield from self.records
            return
        for i, r in enumerate(iter_csv(self.paths["csv"])):
            yield {"index": i, **r}

    @property
    def rows(self) -> list:
        """Every record in a list (reads the whole ``sweep.csv`` into memory when the sweep wrote one)."""
        return self.records if self.records is not None else list(self.iter_rows())

    def column(self, name: str) -> list:
        """The values of one column, in grid order."""
        if name not in COLUMNS and name != "index":
            raise ValueError(f"column must be one of {COLUMNS}, got {name!r}")
        return [r[name] for r in self.iter_rows()]


def stderr_note(line: str) -> None:
    """The default ``note`` of :func:`run_sweep`: one line on stderr."""
    print(f"simgrip sweep: {line}", file=sys.stderr, flush=True)


def _workers(options: RunnerOptions) -> int | None:
    """Workers the time estimate is made for (None: a remote cluster, unknown before it is reached)."""
    return None if options.remote else (1 if options.in_process else options.local_workers)


def _cap(options: RunnerOptions, todo: int, batch_size, note, grid: SweepGrid | None = None) -> RunnerOptions:
    """``options`` with ``jobs`` capped for ``todo`` points (:func:`simgrip.sweep.budget.cap_jobs`).

    With ``grid`` and the default ``jobs`` (None: all cores), a sweep whose work a local cluster would not
    shorten (:func:`simgrip.sweep.budget.worth_a_cluster`) runs in-process; an explicit ``jobs`` is honoured
    up to the caps.
    """
    if options.remote:
        return options
    tasks = todo if batch_size is None else math.ceil(todo / batch_size)
    jobs, why = cap_jobs(options.jobs, tasks)
    if (grid is not None and options.jobs is None
            and not worth_a_cluster(todo, grid.links, grid.method, jobs or machine().cores)):
        return replace(options, jobs=1)
    if why and note is not None:
        note(why)
    return options if jobs == options.jobs else replace(options, jobs=jobs)


def run_sweep(grid: SweepGrid, *, out=None, options: RunnerOptions = RunnerOptions(), batch_size: int | None = None,
              resume: bool = False, write_map: bool = True, on_record=None, note=stderr_note) -> SweepResult:
    """Run every point of ``grid``; returns the counts (and writes the files when ``out`` is given).

    Parameters
    ----------
    grid : SweepGrid
        The sweep (:func:`~simgrip.sweep.grid.make_grid`).
    out : path, optional
        Output folder (checked, and created, before any work; ``ValueError``
        naming ``--out`` when it cannot be written, or when ``sweep.csv``,
        ``sweep.json``, ``map.png`` or ``.partial`` in it is of the wrong kind).
        Rows are streamed to it: the memory of this process does not grow with
        the number of points (one byte per point).  Without it nothing is
        written, nothing can be resumed, and the records are kept in memory
        (:attr:`SweepResult.records`).
    options : RunnerOptions
        In-process, local Dask cluster or existing cluster.  A local ``jobs``
        is capped (:func:`simgrip.sweep.budget.cap_jobs`: the tasks, 2 per
        core, memory; a note says so) and refused above
        :data:`~simgrip.sweep.budget.MAX_JOBS`.
    batch_size : int, optional
        Points per Dask task (default: the runner's); does not change the rows.
    resume : bool
        Complete the unfinished sweep saved in ``out/.partial`` (must be the same
        grid; damaged batch files are set aside and their points recomputed);
        without it an unfinished sweep in ``out`` is refused.  On a finished
        sweep of the same grid nothing is computed.
    write_map : bool
        Draw ``map.png`` (refused before any work above
        :data:`~simgrip.sweep.map.MAX_MAP_CELLS` cells).
    on_record : callable, optional
        Called with each point's record as it arrives (completion order).
    note : callable, optional
        Receives one-line notes (jobs lowered, a damaged batch set aside, a
        finished sweep); default :func:`stderr_note`, ``None`` for silence.

    Raises
    ------
    ValueError
        A grid this machine cannot sweep (:func:`simgrip.sweep.budget.check_sweep`),
        a bad output folder, too many jobs, or a ``.partial`` folder that does not fit ``resume``.
    RunnerError
        The cluster failed (finished points stay saved for ``resume``).
    KeyboardInterrupt
        Ctrl-C / SIGTERM (finished points stay saved for ``resume``).
    """
    if not isinstance(grid, SweepGrid):
        raise ValueError(f"grid must be a SweepGrid, got {type(grid).__name__}")
    t0 = time.perf_counter()
    planned = _cap(options, grid.size, batch_size, None)  # refuses a --jobs above the bound, before anything
    check_sweep({a: len(v) for a, v in grid.axes.items()}, grid.links, grid.method, workers=_workers(planned),
                to_disk=out is not None, here=machine(out))
    if out is not None and write_map:
        check_map(grid)
    store = None
    resumed = 0
    if out is not None:
        from simgrip.io import check_output_dir

        out = check_output_dir(out, "--out")
        from simgrip.io import check_output_files_in  # _write's files: a folder at sweep.csv is refused now

        check_output_files_in(out, ("sweep.csv", "sweep.json") + (("map.png",) if write_map else ()), "--out")
        store = PartialStore(out, grid)
        store.check()
        if resume and not store.exists() and (out / "sweep.csv").exists():
            return _finished(out, grid, note, t0)
        resumed = store.open(resume, note)
    options = _cap(options, grid.size - resumed, batch_size, note, grid)
    done = store.done if store is not None else bytearray(grid.size)
    records = None if store is not None else [None] * grid.size
    computed = 0

    from tqdm import tqdm

    bar = tqdm(total=grid.size - resumed, desc="sweep", unit="point", disable=not options.progress)

    def arrived(_, recs):
        nonlocal computed
        for rec in recs:
            if done[rec["index"]]:  # saved by the interrupted run (its segment is recomputed whole)
                continue
            computed += 1
            bar.update(1)
            if store is not None:
                store.add(rec)
            else:
                records[rec["index"]] = rec
            if on_record is not None:
                on_record(rec)

    quiet = replace(options, progress=False)
    todo = [0]
    for a, b in grid.segments():  # one pass over the segments, nothing kept but the count
        todo[0] += not all(done[a:b])
    t1 = time.perf_counter()
    try:
        try:
            run_tasks(evaluate_segment, _pending_segments(grid, done), options=quiet, desc="sweep",
                      batch_size=_segments_per_task(grid, batch_size), on_result=arrived, collect=False,
                      total=todo[0])
        finally:
            bar.close()
            if store is not None:
                store.flush()
    except BaseException:
        if store is not None and resumed == 0 and not store.batch_files():
            store.remove()  # nothing saved (e.g. the scheduler unreachable): no unfinished sweep to resume
        raise
    compute_s = time.perf_counter() - t1
    result = SweepResult(grid=grid, counts={}, computed=computed, resumed=resumed, wall_time_s=0.0, records=records)
    cores = 1 if options.in_process else (None if options.remote else min(options.local_workers, max(1, todo[0])))
    if out is None:
        tally = Tally()
        for r in records:
            tally.add(r)
        result.counts = tally.as_dict()
        result.wall_time_s = time.perf_counter() - t0
        result.throughput = throughput(computed, compute_s, result.wall_time_s, cores, tally.timing())
        return result
    result.paths = _write(out, result, store, options, batch_size, write_map, t0, compute_s, cores)
    store.remove()
    return result


def _pending_segments(grid: SweepGrid, done):
    """The points of every segment not wholly saved, one segment (a list) at a time, in grid order."""
    for a, b in grid.segments():
        if not all(done[a:b]):
            yield [grid.point(i) for i in range(a, b)]


def _segments_per_task(grid: SweepGrid, batch_size):
    """``batch_size`` (points per Dask task) in whole segments of this grid, at least one (None: the runner's)."""
    if batch_size is None:
        return None
    a, b = next(grid.segments())  # the first is the longest: every line is cut the same way from its start
    return max(1, batch_size // (b - a))


def throughput(points: int, compute_s: float, wall_s: float, cores, timing: dict) -> dict:
    """How fast a sweep ran: ``points_per_s`` and ``points_per_s_per_core`` over the computing phase
    (``compute_s``: from the first point sent to the last result, a local cluster's start included),
    ``wall_per_point_s`` (the whole call: imports, checks, cluster, merge and map included, over ``points``),
    ``settle_median_s`` (median ``wall_time_s``), ``point_over_settle_median`` (median of each point's
    ``point_time_s`` over its ``wall_time_s``, from :meth:`simgrip.sweep.store.Tally.timing`) and
    ``wall_per_point_over_settle`` (``wall_per_point_s / settle_median_s``).  ``cores`` is the number of
    worker processes (1 in-process; ``None`` on an existing cluster, whose size is its own: per core then
    ``None``).  Values are ``None`` where nothing was computed."""
    pps = points / compute_s if points and compute_s > 0 else None
    per_point = wall_s / points if points else None
    settle = timing.get("settle_median_s")
    return {
        "points": points, "compute_s": compute_s, "cores": cores, "points_per_s": pps,
        "points_per_s_per_core": pps / cores if pps is not None and cores else None,
        "wall_per_point_s": per_point, "settle_median_s": settle,
        "point_over_settle_median": timing.get("point_over_settle_median"),
        "wall_per_point_over_settle": per_point / settle if per_point is not None and settle else None,
    }


def _finished(out: Path, grid: SweepGrid, note, t0: float) -> SweepResult:
    """``--resume`` on a folder that holds a finished sweep: computes nothing when it is this sweep."""
    try:
        meta = json.loads((out / "sweep.json").read_text(encoding="utf-8"))
        args = meta["arguments"]
        from simgrip.sweep.grid import default_contact

        same = ({k: args.get(k) for k in grid.spec()} == json.loads(json.dumps(grid.spec()))
                and args.get("reference", "bvp") == grid.reference
                and args.get("contact", default_contact(args["method"])) == grid.contact
                and args.get("box_depth") == grid.box_depth)
    except (OSError, ValueError, KeyError, TypeError):
        raise ValueError(f"--resume: {str(out)!r} holds a sweep.csv but no unfinished sweep ({PARTIAL}/) and no "
                         "readable sweep.json saying which sweep it is: drop --resume to compute it again") from None
    if not same:
        raise ValueError(f"--resume: {str(out)!r} holds a finished sweep of a different grid (grip, axes, links, "
                         "method, reference, contact or box depth differ): drop --resume to replace it, or choose "
                         "another --out")
    tally = Tally()
    try:
        for r in iter_csv(out / "sweep.csv"):
            tally.add(r)
    except (OSError, ValueError) as exc:
        raise ValueError(f"--resume: {str(out / 'sweep.csv')!r} cannot be read back ({exc}): drop --resume to "
                         "compute the sweep again") from None
    c = tally.as_dict()
    if c["points"] != grid.size:
        raise ValueError(f"--resume: {str(out / 'sweep.csv')!r} has {c['points']} rows, the grid {grid.size} "
                         "points: drop --resume to compute the sweep again")
    if note is not None:
        note(f"{out} holds this sweep, finished ({grid.size} points): nothing to compute")
    paths = {k: str(out / name) for k, name in (("csv", "sweep.csv"), ("json", "sweep.json"), ("map", "map.png"))
             if (out / name).is_file()}
    return SweepResult(grid=grid, counts=c, computed=0, resumed=grid.size, wall_time_s=time.perf_counter() - t0,
                       paths=paths)


def _write(out: Path, result: SweepResult, store: PartialStore, options: RunnerOptions, batch_size, draw: bool,
           t0: float, compute_s: float, cores) -> dict:
    paths = {"csv": out / "sweep.csv", "json": out / "sweep.json"}
    result.counts = store.merge(paths["csv"])  # streamed, in grid order, counted on the way
    if draw:
        from simgrip.sweep.map import write_map

        paths["map"] = out / "map.png"
        write_map(paths["map"], result.grid, iter_csv(paths["csv"]))
    from simgrip.io import write_json

    result.wall_time_s = time.perf_counter() - t0
    result.throughput = throughput(result.computed, compute_s, result.wall_time_s, cores, store.timing)
    write_json(paths["json"], {
        "command": "sweep",
        "arguments": {**result.grid.spec(), "reference": result.grid.reference, "contact": result.grid.contact,
                      "box_depth": result.grid.box_depth, "jobs": options.jobs, "scheduler": options.scheduler,
                      "scheduler_file": options.scheduler_file, "batch_size": batch_size},
        "columns": list(COLUMNS),
        "versions": versions(),
        "counts": {**result.counts, "computed": result.computed, "resumed": result.resumed},
        "wall_time_s": result.wall_time_s,
        "throughput": result.throughput,
        "files": {k: v.name for k, v in paths.items() if k != "json"},
    })
    return {k: str(v) for k, v in paths.items()}


# command line ---------------------------------------------------------------

def add_arguments(p) -> None:
    """Options of ``simgrip sweep`` (the CLI registers them on its ``sweep`` sub-parser)."""
    p.add_argument("grip", help="I, II or III")
    g = p.add_argument_group("grid: each option one value or START STOP NUM (inclusive linspace)")
    g.add_argument("--kappa", nargs="+", required=True, metavar="V",
                   help="uniform intrinsic curvature kappa_bar = l*kappa0 (required)")
    g.add_argument("--D", nargs="+", default=None, metavar="V", help="bending stiffness EI/(rho g l^3) [default 1]")
    g.add_argument("--M", nargs="+", default=None, metavar="V", help="workpiece mass per finger m/(rho l) [default 5]")
    g.add_argument("--mu", nargs="+", default=None, metavar="V", help="static friction coefficient mu_s [default 1]")
    g.add_argument("--b", nargs="+", default=None, metavar="V", help="workpiece width b/l [default 0.6]")
    g.add_argument("--gamma", nargs="+", default=None, metavar="V", help="Grip III contact arc length gamma/l [default 0.8]")
    p.add_argument("--links", type=int, required=True, help="links per finger")
    p.add_argument("--method", default="newton", help="settle method: newton or dynamics [default newton]")
    p.add_argument("--reference", default=None, metavar="{bvp,none}",
                   help="bvp: the elastica BVP beside every point, warm-started along the grid (bvp_* and agree "
                   "columns); none: the simulation only (those columns empty) [default bvp; none with --contact "
                   "full, which has no per-point reference]")
    p.add_argument("--contact", default=None, metavar="{point,surface,full}",
                   help="the settle's contact: point (the paper's, newton's default), surface (MuJoCo's contact "
                   "point on the tip; the dynamics' only one) or full (every link and the tip touch the box and "
                   "the finger itself: Grips I/II, over-damped dynamics, ~1-4 s a point at n = 16) [default: the "
                   "method's own]; recorded in sweep.json, --resume refuses another")
    p.add_argument("--box-depth", type=float, default=None, metavar="D",
                   help="with --contact full: grasp the box with the tip D (over l, in (0, 1]) below its top edge "
                   "(II: above its bottom edge), as simulate --box-depth [default: the box stays below the palm]")
    p.add_argument("--out", required=True, help="output folder (sweep.csv, sweep.json, map.png)")
    p.add_argument("--resume", action="store_true", help=f"complete an interrupted sweep saved in OUT/{PARTIAL} (damaged batch files are set aside "
                   "and recomputed; a finished sweep computes nothing)")
    p.add_argument("--batch-size", type=int, default=None, help="points per Dask task, in whole continuation "
                   f"segments (at most {SEGMENT_POINTS} points each; at least one) [default: automatic]")
    p.add_argument("--no-map", action="store_true", help="do not draw map.png")
    p.add_argument("--throughput", action="store_true",
                   help="measure points/s instead: plain loop, local cluster and dask-CLI cluster (no files but "
                   "OUT/throughput.json)")
    # solve/simulate/compare's --profile is the curvature profile: here it would mean something else, so it is
    # refused by name (it was this command's throughput run until the rename)
    p.add_argument("--profile", action=_RenamedOption, nargs=0, help=argparse.SUPPRESS)
    add_runner_arguments(p)


class _RenamedOption(argparse.Action):
    """``sweep --profile``: an error saying it is ``--throughput`` now (``--profile`` is a curvature profile elsewhere)."""

    def __call__(self, parser, namespace, values, option_string=None):
        parser.error("sweep has no --profile: the points/s measurement is --throughput (--profile names the "
                     "curvature profile of solve, simulate and compare; a sweep's curvature is uniform)")


def grid_from_args(args) -> SweepGrid:
    """The :class:`SweepGrid` of parsed ``simgrip sweep`` arguments (``ValueError`` naming the option)."""
    try:
        return make_grid(args.grip, kappa=args.kappa, D=args.D, M=args.M, mu=args.mu, b=args.b, gamma=args.gamma,
                         links=args.links, method=args.method, reference=args.reference,
                         contact=getattr(args, "contact", None), box_depth=getattr(args, "box_depth", None))
    except ValueError as exc:  # the grid's names as the options': --contact, --box-depth, --reference
        msg = str(exc)
        for name in ("contact", "box_depth", "reference"):
            if msg.startswith(name):
                raise ValueError("--" + name.replace("_", "-") + msg[len(name):]) from None
        raise


def cli_sweep(args):
    """``simgrip sweep``: run the sweep, print the files written and a one-line summary."""
    grid = grid_from_args(args)
    options = runner_options(args)
    if args.batch_size is not None and args.batch_size < 1:
        raise ValueError(f"batch-size must be a positive integer, got {args.batch_size!r}")
    if args.throughput:
        from simgrip.sweep.profile import cli_profile

        for flag, given in (("--resume", args.resume), ("--no-map", args.no_map)):
            if given:  # (the measurement writes throughput.json only: an audit found them accepted and ignored)
                raise ValueError(f"{flag}: not with --throughput (it measures the grid and writes throughput.json "
                                 f"only)")

        return cli_profile(args, grid, _cap(options, grid.size, args.batch_size, stderr_note))
    try:
        res = run_sweep(grid, out=args.out, options=options, batch_size=args.batch_size, resume=args.resume,
                        write_map=not args.no_map)
    except KeyboardInterrupt:  # the CLI's one line says it: "interrupted; finished points are saved ..."
        hint = _partial_hint(args.out)
        if hint:
            raise KeyboardInterrupt(hint) from None
        raise
    except RuntimeError:
        hint = _partial_hint(args.out)
        if hint:
            print(f"simgrip sweep: {hint}", file=sys.stderr)
        raise
    for k in ("csv", "json", "map"):
        if k in res.paths:
            print(res.paths[k])
    c = res.counts
    print(f"{c['points']} points ({res.computed} computed, {res.resumed} resumed): {c['settled']} settled, "
          f"{c['unsettled']} unsettled, {c['rejected']} rejected, {c['error']} failed; "
          f"{c['feasible']} held and feasible, "
          + (f"{c['agree']} agree with the BVP, {c['disagree']} disagree; " if grid.reference == "bvp" else
             "no BVP reference (--reference none); ")
          + f"{res.wall_time_s:.1f} s", file=sys.stderr)
    return None


def _partial_hint(out) -> str | None:
    """Where a stopped sweep's finished points are and how to complete it; None when none was saved."""
    part = Path(out) / PARTIAL
    n = sum(1 for _ in part.glob("batch-*.csv")) if part.is_dir() else 0
    return (f"finished points are saved in {part}; run the same command with --resume to complete the sweep"
            if n else None)

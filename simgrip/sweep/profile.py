"""Scale of a sweep, measured: points per second in-process, on local Dask workers and on a dask-CLI cluster.

``simgrip sweep ... --throughput`` runs the same grid several ways in one process
and reports, for each, the wall time, points/s, and whether the rows are
identical to the plain loop's (every column but the times).  Each run starts
with one point per worker (not timed: a fresh worker process pays its imports
once, which is not a per-point cost); cluster start-up is timed apart.

* ``loop``: ``jobs=1``, the in-process loop (run twice, before and after the
  Dask runs, and averaged, so that a drifting machine load shows as the
  difference of the two);
* ``dask_1_worker``: the same points through the Dask path on one local
  worker: ``overhead_vs_loop_*`` compares it with the loop;
* ``local_N_workers``: a local cluster of ``N`` workers (what ``--jobs N`` starts);
* ``dask_cli_N_workers``: ``dask scheduler`` + ``dask worker --nworkers N``
  started from the command line on 127.0.0.1 (:mod:`simgrip.parallel.cli_cluster`),
  reached with ``--scheduler``;
* ``given_cluster``: the cluster named by ``--scheduler``/``--scheduler-file``, if any.

``runner_overhead_*`` is measured within each run and is less sensitive to a
busy machine than a comparison of two runs: wall time times workers minus the
time spent inside the tasks (timed on the workers), per point.

Points/s per worker times the workers gives the rate of a bigger cluster as
long as the scheduler keeps up (batches of :data:`~simgrip.parallel.runner.MAX_BATCH`
points make a few hundred tasks/s enough for ~10^4 points/s).
"""

from __future__ import annotations

import sys
import time

from simgrip.parallel.runner import RunnerOptions, default_batch_size, run_tasks
from simgrip.sweep.point import evaluate_point
from simgrip.sweep.store import same_results

__all__ = ["profile_sweep", "cli_profile", "format_profile"]


def timed_point(point):
    """Worker side: ``(record, seconds)``, the record of :func:`evaluate_point` and the time it took."""
    t0 = time.perf_counter()
    rec = evaluate_point(point)
    return rec, time.perf_counter() - t0


def _timed(points, options, batch_size):
    """``(wall seconds, rows, seconds inside the tasks)``."""
    t0 = time.perf_counter()
    out = run_tasks(timed_point, points, options=options, desc="profile", batch_size=batch_size)
    wall = time.perf_counter() - t0
    return wall, [r for r, _ in out], sum(t for _, t in out)


def _entry(name, seconds, rows, reference, n, workers, task_s, **extra):
    return {"run": name, "workers": workers, "seconds": seconds, "points_per_s": n / seconds,
            "points_per_s_per_worker": n / seconds / workers,
            # what the runner adds: wall time x workers not spent inside the tasks, per point
            "runner_overhead_per_point_s": (seconds * workers - task_s) / n,
            "runner_overhead_fraction": seconds * workers / task_s - 1.0,
            "identical_to_loop": same_results(rows, reference), **extra}


def _warm(points, options, workers):
    """One point per worker first: imports and first-call costs are a worker's, not a point's."""
    run_tasks(timed_point, points[: max(1, workers)], options=options, batch_size=1)


def profile_sweep(grid, *, workers: int = 2, batch_size: int | None = None, progress: bool = False,
                  cli_cluster: bool = True, remote: RunnerOptions | None = None) -> dict:
    """Measure the runs of the module docstring on ``grid``; returns a JSON-able dict.

    ``remote`` (options naming an existing cluster, ``--scheduler``) adds a run
    ``given_cluster`` on it.
    """
    from simgrip.parallel.dask_cluster import LocalDask

    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be a positive integer, got {workers!r}")
    k_remote = 0
    if remote is not None and remote.remote:  # reached first: a wrong address fails before the minutes of timing
        from simgrip.parallel.dask_cluster import RemoteDask

        probe = RemoteDask(remote.scheduler, remote.scheduler_file, timeout=remote.connect_timeout)
        try:
            k_remote = max(1, len(probe.client.scheduler_info()["workers"]))
        finally:
            probe.stop(False)
    points = list(grid.points())
    n = len(points)
    bs = batch_size or default_batch_size(n, workers)
    loop = RunnerOptions(jobs=1, progress=False)
    _warm(points, loop, 1)
    t_a, ref, task_a = _timed(points, loop, None)

    def on_cluster(k, start_s, options, name):
        _warm(points, options, k)
        t, rows, task = _timed(points, options, batch_size or default_batch_size(n, k))
        return _entry(name, t, rows, ref, n, k, task, cluster_start_s=start_s)

    t0 = time.perf_counter()
    one = LocalDask(1)
    try:
        d1 = on_cluster(1, time.perf_counter() - t0, RunnerOptions(scheduler=one.cluster.scheduler_address,
                                                                   progress=progress), "dask_1_worker")
    finally:
        one.stop(False)
    t_b, rows_b, task_b = _timed(points, loop, None)
    t_loop = 0.5 * (t_a + t_b)
    runs = [_entry("loop", t_loop, rows_b, ref, n, 1, 0.5 * (task_a + task_b), first_s=t_a, second_s=t_b)]
    d1.update(overhead_vs_loop_per_point_s=(d1["seconds"] - t_loop) / n,
              overhead_vs_loop_fraction=d1["seconds"] / t_loop - 1.0)
    runs.append(d1)

    t0 = time.perf_counter()
    loc = LocalDask(workers)
    try:
        runs.append(on_cluster(workers, time.perf_counter() - t0, RunnerOptions(
            scheduler=loc.cluster.scheduler_address, progress=progress), f"local_{workers}_workers"))
    finally:
        loc.stop(False)
    if cli_cluster:
        from simgrip.parallel.cli_cluster import dask_cli_cluster

        t0 = time.perf_counter()
        with dask_cli_cluster(workers) as (address, _, _):
            runs.append(on_cluster(workers, time.perf_counter() - t0, RunnerOptions(scheduler=address, progress=progress),
                                   f"dask_cli_{workers}_workers"))
    if remote is not None and remote.remote:
        runs.append(on_cluster(k_remote, 0.0, remote, "given_cluster"))
    return {"grid": grid.spec(), "points": n, "batch_size": bs, "settle_s_per_point": t_loop / n, "runs": runs}


def format_profile(prof: dict) -> str:
    """A small text table of :func:`profile_sweep`'s result."""
    lines = [f"{prof['points']} points, n = {prof['grid']['links']} links, Grip {prof['grid']['grip']}, "
             f"batch {prof['batch_size']}; plain loop {1e3 * prof['settle_s_per_point']:.1f} ms per point",
             f"{'run':24s} {'s':>8s} {'points/s':>9s} {'/worker':>8s}  identical  notes"]
    for r in prof["runs"]:
        notes = [f"runner {1e3 * r['runner_overhead_per_point_s']:+.2f} ms/point ({100 * r['runner_overhead_fraction']:+.1f} %)"]
        if "overhead_vs_loop_fraction" in r:
            notes.append(f"vs loop {1e3 * r['overhead_vs_loop_per_point_s']:+.2f} ms/point "
                         f"({100 * r['overhead_vs_loop_fraction']:+.1f} %)")
        if "cluster_start_s" in r:
            notes.append(f"cluster start {r['cluster_start_s']:.1f} s")
        if r["run"] == "loop":
            notes.append(f"two passes {r['first_s']:.2f} / {r['second_s']:.2f} s")
        lines.append(f"{r['run']:24s} {r['seconds']:8.2f} {r['points_per_s']:9.1f} {r['points_per_s_per_worker']:8.1f}"
                     f"  {str(r['identical_to_loop']):9s}  {'; '.join(notes)}")
    return "\n".join(lines)


def cli_profile(args, grid, options: RunnerOptions):
    """``simgrip sweep ... --throughput``: print the table, write ``OUT/throughput.json``."""
    from pathlib import Path

    from simgrip.io import check_output_dir, check_output_files_in, write_json

    out = check_output_dir(args.out, "--out")
    check_output_files_in(out, ("throughput.json",), "--out")  # before the timing runs
    workers = options.jobs if options.jobs is not None and options.jobs > 1 else 2
    prof = profile_sweep(grid, workers=workers, batch_size=args.batch_size, progress=options.progress,
                         remote=options if options.remote else None)
    from simgrip.sweep.versions import versions

    prof["versions"] = versions()
    write_json(Path(out) / "throughput.json", prof)
    print(format_profile(prof))
    print(Path(out) / "throughput.json", file=sys.stderr)
    return None

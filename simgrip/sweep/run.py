"""Design sweeps: the settled simulation and the elastica BVP over a grid of designs (``simgrip sweep``).

For every point of a :class:`~simgrip.sweep.grid.SweepGrid` (the full
grid of ``kappa, D, M, mu, b, gamma``) a worker settles the MuJoCo fingers and
solves the BVP (:func:`~simgrip.sweep.point.evaluate_point`); the
points run through the one parallel runner (:func:`simgrip.parallel.runner.run_tasks`):
in-process (``jobs=1``), on a local Dask cluster, or on an existing one
(``--scheduler``), batched so that Dask's per-task overhead stays small.  Every
point is settled from scratch, like ``simgrip simulate`` at the same values:
warm starts along the kappa axis (:func:`simgrip.settle.settle_sweep`) are not
used, because they change the answer (a warm-started release can stay on
another equilibrium branch, or hold where the closing procedure drops), so a
point's row would depend on its neighbours and on how the grid was cut into
batches.  Hence the rows (all columns but ``wall_time_s``) are the same for
any runner and batch size.

With an output folder the sweep writes ``sweep.csv`` (one row per point, grid
order, :data:`~simgrip.sweep.point.COLUMNS`), ``sweep.json``
(arguments, versions, counts) and ``map.png`` (:mod:`~simgrip.sweep.map`),
each atomically, after saving finished points in ``.partial/`` as they arrive
(:mod:`~simgrip.sweep.store`): an interrupted sweep is completed by
``resume=True`` (``--resume``) without recomputing saved points.  Dask
recomputes the batch of a worker that dies, so no point is lost or doubled.
"""

from __future__ import annotations

import platform
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from simgrip.parallel.runner import RunnerOptions, add_runner_arguments, run_tasks, runner_options
from simgrip.sweep.grid import SweepGrid, make_grid
from simgrip.sweep.point import COLUMNS, evaluate_point
from simgrip.sweep.store import PARTIAL, PartialStore, counts, write_csv

__all__ = ["SweepResult", "run_sweep", "add_arguments", "cli_sweep", "versions"]


@dataclass
class SweepResult:
    """A finished sweep.

    Attributes
    ----------
    grid : SweepGrid
    rows : list of dict
        One record per point in grid order, keys :data:`~simgrip.sweep.point.COLUMNS`
        (plus ``index``).
    counts : dict
        Points per status, held, feasible, agreeing, ... (:func:`~simgrip.sweep.store.counts`).
    computed, resumed : int
        Points computed by this call and points taken from an interrupted run's saved results.
    wall_time_s : float
        Time of the whole call [s] (cluster start-up included).
    paths : dict
        ``{"csv", "json", "map"}`` file paths, empty without an output folder.
    """

    grid: SweepGrid
    rows: list
    counts: dict
    computed: int
    resumed: int
    wall_time_s: float
    paths: dict = field(default_factory=dict)

    def column(self, name: str) -> list:
        """The values of one column, in grid order."""
        if name not in COLUMNS and name != "index":
            raise ValueError(f"column must be one of {COLUMNS}, got {name!r}")
        return [r[name] for r in self.rows]


def versions() -> dict:
    """Versions of Python and of the packages that decide a sweep's numbers and how it ran."""
    from importlib import metadata

    out = {"python": platform.python_version()}
    for pkg in ("simgrip", "mujoco", "numpy", "scipy", "dask", "distributed"):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = None
    return out


def run_sweep(grid: SweepGrid, *, out=None, options: RunnerOptions = RunnerOptions(), batch_size: int | None = None,
              resume: bool = False, write_map: bool = True, on_record=None) -> SweepResult:
    """Run every point of ``grid``; returns the table (and writes the files when ``out`` is given).

    Parameters
    ----------
    grid : SweepGrid
        The sweep (:func:`~simgrip.sweep.grid.make_grid`).
    out : path, optional
        Output folder (checked, and created, before any work; ``ValueError``
        naming ``--out`` when it cannot be written).  Without it nothing is
        written and nothing can be resumed.
    options : RunnerOptions
        In-process, local Dask cluster or existing cluster.
    batch_size : int, optional
        Points per Dask task (default: the runner's); does not change the rows.
    resume : bool
        Complete the unfinished sweep saved in ``out/.partial`` (must be the same
        grid); without it an unfinished sweep in ``out`` is refused.
    write_map : bool
        Draw ``map.png``.
    on_record : callable, optional
        Called with each point's record as it arrives (completion order).

    Raises
    ------
    ValueError
        Bad output folder, or a ``.partial`` folder that does not fit ``resume``.
    RunnerError
        The cluster failed (finished points stay saved for ``resume``).
    KeyboardInterrupt
        Ctrl-C / SIGTERM (finished points stay saved for ``resume``).
    """
    if not isinstance(grid, SweepGrid):
        raise ValueError(f"grid must be a SweepGrid, got {type(grid).__name__}")
    t0 = time.perf_counter()
    store = None
    done: dict[int, dict] = {}
    if out is not None:
        from simgrip.io import check_output_dir

        out = check_output_dir(out, "--out")
        store = PartialStore(out, grid.spec())
        done = store.open(resume)
    todo = [p for p in grid.points() if p.index not in done]
    fresh: dict[int, dict] = {}

    def arrived(_, rec):
        fresh[rec["index"]] = rec
        if store is not None:
            store.add(rec)
        if on_record is not None:
            on_record(rec)

    try:
        run_tasks(evaluate_point, todo, options=options, desc="sweep", batch_size=batch_size, on_result=arrived)
    finally:
        if store is not None:
            store.flush()
    rows = [done[i] if i in done else fresh[i] for i in range(grid.size)]
    result = SweepResult(grid=grid, rows=rows, counts=counts(rows), computed=len(fresh), resumed=len(done),
                         wall_time_s=time.perf_counter() - t0)
    if out is not None:
        result.paths = _write(out, result, options, batch_size, write_map)
        store.remove()
    return result


def _write(out: Path, result: SweepResult, options: RunnerOptions, batch_size, draw: bool) -> dict:
    paths = {"csv": out / "sweep.csv", "json": out / "sweep.json"}
    write_csv(paths["csv"], result.rows)
    if draw:
        from simgrip.sweep.map import write_map

        paths["map"] = out / "map.png"
        write_map(paths["map"], result.grid, result.rows)
    from simgrip.io import write_json

    write_json(paths["json"], {
        "command": "sweep",
        "arguments": {**result.grid.spec(), "jobs": options.jobs, "scheduler": options.scheduler,
                      "scheduler_file": options.scheduler_file, "batch_size": batch_size},
        "columns": list(COLUMNS),
        "versions": versions(),
        "counts": {**result.counts, "computed": result.computed, "resumed": result.resumed},
        "wall_time_s": result.wall_time_s,
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
    p.add_argument("--out", required=True, help="output folder (sweep.csv, sweep.json, map.png)")
    p.add_argument("--resume", action="store_true", help=f"complete an interrupted sweep saved in OUT/{PARTIAL}")
    p.add_argument("--batch-size", type=int, default=None, help="points per Dask task [default: automatic]")
    p.add_argument("--no-map", action="store_true", help="do not draw map.png")
    p.add_argument("--profile", action="store_true",
                   help="measure points/s instead: plain loop, local cluster and dask-CLI cluster (no files but OUT/profile.json)")
    add_runner_arguments(p)


def grid_from_args(args) -> SweepGrid:
    """The :class:`SweepGrid` of parsed ``simgrip sweep`` arguments (``ValueError`` naming the option)."""
    return make_grid(args.grip, kappa=args.kappa, D=args.D, M=args.M, mu=args.mu, b=args.b, gamma=args.gamma,
                     links=args.links, method=args.method)


def cli_sweep(args):
    """``simgrip sweep``: run the sweep, print the files written and a one-line summary."""
    grid = grid_from_args(args)
    options = runner_options(args)
    if args.batch_size is not None and args.batch_size < 1:
        raise ValueError(f"batch-size must be a positive integer, got {args.batch_size!r}")
    if args.profile:
        from simgrip.sweep.profile import cli_profile

        return cli_profile(args, grid, options)
    try:
        res = run_sweep(grid, out=args.out, options=options, batch_size=args.batch_size, resume=args.resume,
                        write_map=not args.no_map)
    except KeyboardInterrupt:
        _say_partial(args.out)
        raise
    except RuntimeError:
        _say_partial(args.out)
        raise
    for k in ("csv", "json", "map"):
        if k in res.paths:
            print(res.paths[k])
    c = res.counts
    print(f"{c['points']} points ({res.computed} computed, {res.resumed} resumed): {c['settled']} settled, "
          f"{c['unsettled']} unsettled, {c['rejected']} rejected, {c['error']} failed; "
          f"{c['feasible']} held and feasible, {c['agree']} agree with the BVP, {c['disagree']} disagree; "
          f"{res.wall_time_s:.1f} s", file=sys.stderr)
    return None


def _say_partial(out) -> None:
    part = Path(out) / PARTIAL
    n = sum(1 for _ in part.glob("batch-*.csv")) if part.is_dir() else 0
    if n:
        print(f"simgrip sweep: finished points are saved in {part}; run the same command with --resume to "
              "complete the sweep", file=sys.stderr)


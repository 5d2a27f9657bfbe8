"""``simgrip bench``: run time against error, what skipping buys, and the sweep timing.

For the free rod and Grips I, II and III at the paper's standard parameters
(``D = 1, M = 5, mu_s = 1, b/l = 0.6, gamma/l = 0.8``) and the curvatures of
:data:`STANDARD_CASES`, over ``n`` links (:data:`N_FULL`, or :data:`N_QUICK`
with ``quick=True``), the bench times the static settle against the naive
MuJoCo relaxation, the chain's energy minimiser and the elastica BVP, each at
its error against the converged BVP of the same state
(:mod:`simgrip.harness.methods`); it times what each shortcut of simgrip buys
(:mod:`simgrip.harness.skips`), the Fig. 7 sweep with and without warm starts,
and the Gymnasium environment's overhead over raw ``mj_step``.

How it runs: every task (one grip at one ``n``, the sweep, one skipping row)
is independent and deterministic, one task of
:func:`simgrip.parallel.runner.run_tasks`; the errors written do not depend on
``jobs`` (the naive run's budget is a step count, not a wall time); wall times
do (concurrent processes share cores), and ``jobs`` is written next to them.
A task that raises becomes a row with the error in its note.

Files written (atomically) to ``out_dir``, which is checked before any work:
``bench.csv``, ``bench.json``, ``pareto.png`` (:mod:`simgrip.harness.plots`),
``summary.md``, ``skips.md`` (:mod:`simgrip.harness.tables`), ``sweep.json``, and the
settle's targets ``settle_targets.json``/``.md`` (:mod:`simgrip.harness.bench_settle`), and the
K-finger settles ``gripper.json``/``.md`` (:mod:`simgrip.harness.bench_gripper`; their rows also
under ``"gripper"`` in ``bench.json``), and the modes' run time and frequency error against ``n``
``modes.json``/``.md``/``.png`` (:mod:`simgrip.harness.bench_modes`).

Command line: ``simgrip bench [--quick] [--out DIR] [--repeats R]`` and the
runner's options (``--jobs``, ``--scheduler``, ``--scheduler-file``,
``--no-progress``); see :func:`add_arguments` and :func:`cli_bench`.
"""

from __future__ import annotations

import csv
import io
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from simgrip.harness.methods import BVP_TOLS, STANDARD_CASES, bench_task
from simgrip.harness.skips import SKIPS, skip_task, sweep_task, warm_start_row
from simgrip.harness.tables import GRIP_ORDER, ratios, skips_md, summary_md
from simgrip.io import atomic_write, check_output_dir, check_output_files_in, write_json
from simgrip.params import STANDARD, DimensionlessParams

__all__ = [
    "STANDARD_CASES",
    "N_FULL",
    "N_QUICK",
    "BVP_TOLS",
    "BenchResult",
    "run_bench",
    "add_arguments",
    "cli_bench",
]

#: Links per finger in the full and the quick bench.
N_FULL = (8, 16, 32, 64, 128, 256)
N_QUICK = (8, 16, 32)
#: Columns of ``bench.csv``.
COLUMNS = (
    "grip", "kappa", "n", "method", "tol", "time_s", "time_min_s", "repeats", "steps", "converged",
    "matched", "extrapolated", "lower_bound", "tip_err", "force_err", "settle_vs_min_tip", "settle_vs_min_force",
    "gamma", "contact_moment", "residual", "build_s", "settle_same_start_s", "dt", "time_to_tol_s", "steps_to_tol",
    "note",
)
#: The kinds of bench task: kind -> function of the task's arguments.
TASKS = {"case": bench_task, "sweep": sweep_task, "skip": skip_task}


@dataclass
class BenchResult:
    """What :func:`run_bench` measured.

    Attributes
    ----------
    rows : list of dict
        One row per (grip, n, method) (and per BVP tolerance, ``n = 0``); see :data:`COLUMNS`.
    ratios : list of dict
        Per grip and ``n``: settle / naive, settle / minimiser, settle / BVP at matched error.
    skips : list of dict
        The skipping table.
    sweep : dict
        The Fig. 7 sweep timing (simulation warm, cold, BVP).
    env : dict
        The Gymnasium envs' speed: every registered id's overhead over bare ``mj_step`` and the claws' validity check
        (:func:`simgrip.harness.bench_envs.env_speed`).
    settle_targets : dict
        The settle's speed and accuracy targets, name -> met (:mod:`simgrip.harness.bench_settle`).
    files : dict
        name -> path of every file written.
    jobs, quick, elapsed_s
    """

    rows: list
    ratios: list
    skips: list
    sweep: dict
    env: dict = field(default_factory=dict)
    settle_targets: dict = field(default_factory=dict)
    #: K-finger settles against K single fingers and the symmetry skip (:mod:`simgrip.harness.bench_gripper`).
    gripper: dict = field(default_factory=dict)
    #: The modes' run time and frequency error against n (:mod:`simgrip.harness.bench_modes`).
    modes: dict = field(default_factory=dict)
    #: simgrip's free-rod settle against MuJoCo's cable at matched error (:mod:`simgrip.harness.bench_cable`).
    cable: dict = field(default_factory=dict)
    #: What surrounds the settle: sweep point, simulate call, settle/chain (:mod:`simgrip.harness.bench_overhead`).
    overhead: dict = field(default_factory=dict)
    #: The full-contact settle against the point-contact settle and the free-boundary BVP
    #: (:mod:`simgrip.harness.bench_full`).
    full: dict = field(default_factory=dict)
    files: dict = field(default_factory=dict)
    jobs: int | None = 1
    quick: bool = False
    elapsed_s: float = 0.0

    def select(self, **match) -> list[dict]:
        """Rows whose fields equal ``match`` (e.g. ``grip="I", method="settle"``)."""
        return [r for r in self.rows if all(r.get(k) == v for k, v in match.items())]


def _call(spec):
    """Run one task ``(kind, args)``; an unexpected error becomes a recorded row."""
    kind, args = spec
    try:
        return TASKS[kind](*args)
    except Exception as exc:  # noqa: BLE001 - reported in the outputs
        err = f"{type(exc).__name__}: {exc}"
        if kind == "case":
            return [{"grip": args[0], "kappa": STANDARD_CASES[args[0]], "n": args[1], "method": "settle",
                     "converged": False, "note": err}]
        if kind == "sweep":
            return {"error": err, "n": args[0], "kappas": list(args[1])}
        return {"skip": args[0], "n": args[1], "error": err, "note": err}


#: the most timing repeats (the median of 3 already steadies a noisy machine; each repeat reruns every timing)
MAX_REPEATS = 100


def _check_count(name, value, most: int = MAX_REPEATS):
    if value is not None and (isinstance(value, bool) or int(value) != value or not 1 <= int(value) <= most):
        raise ValueError(f"{name} must be an integer in [1, {most}], got {value!r}")


def run_bench(
    out_dir,
    *,
    quick: bool = False,
    jobs: int | None = None,
    repeats: int | None = None,
    progress: bool = True,
    params: DimensionlessParams = STANDARD,
    naive_budget_s: float | None = None,
    grips=GRIP_ORDER,
    skips: bool = True,
    sweep: bool = True,
    options=None,
) -> BenchResult:
    """Measure run time against error and write the bench files (see the module docstring).

    Parameters
    ----------
    out_dir : path
        Destination folder (created; checked before any work).
    quick : bool
        ``n`` in :data:`N_QUICK`, one repeat, short naive budgets, a 4-point sweep.
    jobs : int, optional
        Worker processes (default: all cores); 1 runs in this process.
    repeats : int, optional
        Timing repeats (median); default 1 quick, 3 full.
    progress : bool
        Progress bar.
    naive_budget_s : float, optional
        Budget of each naive relaxation before extrapolation, as about that
        many seconds of stepping: a deterministic step count ``2e5 * budget / n``
        (default 0.5 quick, 10 full), so the results do not depend on ``jobs``.
    grips, skips, sweep
        What to run (all by default).
    options : simgrip.parallel.runner.RunnerOptions, optional
        How to run (e.g. on an existing Dask cluster); replaces ``jobs`` and ``progress``.
    """
    from simgrip.harness.bench_envs import env_speed
    from simgrip.parallel.runner import RunnerOptions, run_tasks

    _check_count("repeats", repeats)
    options = RunnerOptions(jobs=jobs, progress=progress) if options is None else options
    out = check_output_dir(out_dir, option="out_dir")
    check_output_files_in(out, OUTPUT_FILES, "out_dir")  # before the minutes of work, not at the end
    t_start = time.perf_counter()
    ns = N_QUICK if quick else N_FULL
    reps = int(repeats or (1 if quick else 3))
    budget = float(naive_budget_s if naive_budget_s is not None else (0.5 if quick else 10.0))
    n_skip = 16 if quick else 32
    kappas = tuple(float(x) for x in (np.linspace(-6.0, -4.8, 4) if quick else np.linspace(-6.0, 0.0, 13)))
    specs = [("case", (g, 0, reps, budget, params)) for g in grips]
    specs += [("case", (g, n, reps, budget, params)) for n in reversed(ns) for g in grips]
    if sweep:
        specs.append(("sweep", (n_skip, kappas, params)))
    if skips:
        specs += [("skip", (w, n_skip, reps, params, budget)) for w in SKIPS]
    results = run_tasks(_call, specs, options=options, desc="bench", batch_size=1)
    rows, skip_rows, sweep_rec = [], [], {}
    for (kind, _), res in zip(specs, results):  # the order of ``specs``: independent of jobs
        if kind == "case":
            rows.extend(res)
        elif kind == "sweep":
            sweep_rec = res
        else:
            skip_rows.append(res)
    rows.sort(key=lambda r: (GRIP_ORDER.index(r["grip"]), r["n"], r["method"], -(r.get("tol") or 0)))
    for r in rows:
        for c in COLUMNS:
            r.setdefault(c, None)
    if sweep_rec and "error" not in sweep_rec:
        skip_rows.append(warm_start_row(sweep_rec))
    env = env_speed(quick=quick)  # issue 18, item 5: every registered env against bare mj_step
    workers = 1 if options.in_process else (None if options.remote else options.local_workers)
    result = BenchResult(rows=rows, ratios=ratios(rows), skips=skip_rows, sweep=sweep_rec, env=env,
                         jobs=workers, quick=bool(quick), elapsed_s=time.perf_counter() - t_start)
    from simgrip.harness.bench_settle import write_settle_targets  # the settle's issue-9 targets, one run

    result.settle_targets = write_settle_targets(out, quick=quick)["checks"]
    from simgrip.harness.bench_gripper import write_gripper_bench  # issue 13's K-finger ratios, one run

    result.gripper = write_gripper_bench(out, quick=quick)
    from simgrip.harness.bench_modes import write_modes_bench  # issue 20's modes: run time and error against n

    result.modes = write_modes_bench(out, quick=quick, repeats=repeats)
    from simgrip.harness.bench_cable import write_cable_bench  # issue 19: MuJoCo's cable as the settle's peer

    result.cable = write_cable_bench(out, quick=quick, repeats=repeats)
    from simgrip.harness.bench_overhead import write_overhead_bench  # issue 19: the ratios around the settle

    result.overhead = write_overhead_bench(out, quick=quick, repeats=repeats)
    from simgrip.harness.bench_full import write_full_bench  # issue 17: the full-contact settle's speed

    result.full = write_full_bench(out, quick=quick, repeats=repeats)
    result.files = {**_write(out, result), **{name: out / name for name in ("settle_targets.json", "settle_targets.md",
                                                                            "gripper.json", "gripper.md", "modes.json",
                                                                            "modes.md", "modes.png", "cable.json",
                                                                            "cable.md", "overhead.json",
                                                                            "overhead.md", "full.json", "full.md")}}
    return result


#: The files run_bench writes into its folder (_write's, then write_settle_targets', write_gripper_bench's and
#: write_modes_bench's).
OUTPUT_FILES = ("bench.csv", "bench.json", "sweep.json", "skips.md", "summary.md", "pareto.png",
                "settle_targets.json", "settle_targets.md", "gripper.json", "gripper.md", "modes.json", "modes.md",
                "modes.png", "cable.json", "cable.md", "overhead.json", "overhead.md", "full.json", "full.md")


def _loadavg():
    try:
        return list(os.getloadavg())
    except OSError:  # pragma: no cover
        return None


def _write(out: Path, res: BenchResult) -> dict:
    from simgrip.harness.plots import pareto_plot

    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(COLUMNS), extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in res.rows:
        w.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in COLUMNS})
    with atomic_write(out / "bench.csv") as fh:
        fh.write(buf.getvalue())
    meta = {"quick": res.quick, "jobs": res.jobs, "elapsed_s": res.elapsed_s, "params": vars(STANDARD),
            "standard_cases": STANDARD_CASES, "cpu_count": os.cpu_count(), "load_avg": _loadavg()}
    write_json(out / "bench.json", {"meta": meta, "rows": res.rows, "ratios": res.ratios, "env": res.env,
                                    "gripper": res.gripper.get("rows", []), "overhead": res.overhead.get("rows", [])})
    write_json(out / "sweep.json", res.sweep)
    with atomic_write(out / "skips.md") as fh:
        fh.write(skips_md(res.skips))
    with atomic_write(out / "summary.md") as fh:
        fh.write(summary_md(res, _loadavg()))
    pareto_plot(res, STANDARD_CASES, out / "pareto.png")
    names = ("bench.csv", "bench.json", "sweep.json", "skips.md", "summary.md", "pareto.png")
    return {name: out / name for name in names}


def add_arguments(p) -> None:
    """Add the options of ``simgrip bench`` (and the runner's) to an argparse parser."""
    from simgrip.parallel.runner import add_runner_arguments

    p.add_argument("--quick", action="store_true", help="n in {8, 16, 32}, one repeat, short naive budgets")
    p.add_argument("--out", default="bench_out", help="output folder [default bench_out]")
    p.add_argument("--repeats", type=int, default=None, help="timing repeats (median) [default 1 quick, 3 full]")
    add_runner_arguments(p)


def cli_bench(args) -> dict:
    """Run the bench from parsed arguments; returns a small record for the CLI (which checked ``--out`` first)."""
    from simgrip.parallel.runner import runner_options

    res = run_bench(args.out, quick=args.quick, repeats=args.repeats, options=runner_options(args))
    return {"out": str(args.out), "files": sorted(str(p) for p in res.files.values()),
            "elapsed_s": res.elapsed_s, "ratios": res.ratios}

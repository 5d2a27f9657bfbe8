"""What surrounds the settle (issue 19), measured in one run: each ratio against the settle it wraps.

=================================================  ============================================  ======
ratio                                              how                                           target
=================================================  ============================================  ======
free rod, n = 16..256: settle / the chain's        fastest CPU time of interleaved runs          <= 2.5
tridiagonal Newton                                 (:func:`simgrip.reference.solve_chain`)
``simulate("free", ..., links=256)``, 12 calls     median over the calls of each call's wall     <= 3
with different kappa_bar: call / its settle        time over its own ``wall_time_s``
``simgrip sweep I --kappa -7 -3 300 --links 32      the whole sweep's wall per point over the     <= 2
--jobs 1``: wall per point / the median settle     median ``wall_time_s`` (``sweep.json``'s
                                                   throughput), the command itself run in a
                                                   fresh process (imports, map and merge
                                                   included), with ``--reference none`` and
                                                   with the BVP reference; beside it the median
                                                   over the points of ``point_time_s /
                                                   wall_time_s`` (the point in the worker)
=================================================  ============================================  ======

Ratios of two times taken in the same process, the same seconds apart, hold
on a busy machine where absolute times do not: the settle / chain ratio takes
the fastest CPU time of each (:func:`simgrip.harness.timing.fastest_cpu_times`),
the others divide each call's wall time by the settle's own wall time inside
it.  Only the targets of the table are checked here, the sweep's with and without the reference; the
ratio with the BVP reference counts the reference's solve in the point (the warm-started BVP
alone costs ~0.35x the settle at n = 32: chord steps of a banded collocation
Newton on a mesh sized once per 32-point segment, a cubic predictor, one cold
path a segment,
:mod:`simgrip.reference.collocation`, :mod:`simgrip.sweep.reference`).  The sweep is the issue's command as a user runs
it (:data:`SWEEP_COMMAND`, 300 points), timed by :func:`simgrip.sweep.run.run_sweep`
itself (``sweep.json``'s ``wall_time_s``): from the call's start to ``sweep.json``,
so the imports the sweep makes (the settle's and the reference's; neither
imports ``scipy.linalg``, ``.optimize`` or ``.interpolate``: their compiled
routines come through :mod:`simgrip.lapack`), the first compile, the merge into ``sweep.csv`` and
``map.png`` (~0.05 s, Pillow) are in the ratio, while what precedes the call
(the interpreter, ``simgrip.cli`` and MuJoCo's import, argument parsing:
~0.5 s) is not.  Those fixed costs weigh ~0.3-0.5 in the ratio at 300 points
(more as the settle gets faster; a shorter sweep weighs them more): the quick
bench runs :data:`QUICK_SWEEP_POINTS` as a smoke run, its ratio not the
issue's figure.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from simgrip.harness.tables import checks_md, ratio_lines, write_record
from simgrip.params import STANDARD
from simgrip.profiles import Uniform

__all__ = ["overhead_ratios", "overhead_md", "write_overhead_bench", "TARGETS"]

#: Targets of issue 19 (upper bounds of the ratios).
TARGETS = {"settle/chain": 2.5, "call/settle n=256": 3.0, "sweep point/settle": 2.0}
#: kappa_bar of the free rod (bench_settle's standard case).
FREE_KAPPA = -3.0
#: The sweep of issue 19's table (``--out`` and ``--reference`` are added; ``--no-progress``: no bar in a log).
SWEEP_COMMAND = ("sweep", "I", "--kappa", "-7", "-3", "300", "--links", "32", "--jobs", "1")
#: Points of the sweep in the quick bench (a smoke run of the same command; the full bench runs 300).
QUICK_SWEEP_POINTS = 60
#: Seconds one such sweep may take before the bench gives up on it (~4 s at 300 points on one core).
SWEEP_TIMEOUT_S = 600


def _settle_over_chain(ns, reps) -> list[dict]:
    from simgrip.harness.timing import fastest_cpu_times, settle_from_start
    from simgrip.reference import solve_chain

    rows = []
    for n in ns:
        t = fastest_cpu_times({"settle": settle_from_start("free", FREE_KAPPA, n),
                               "chain": lambda n=n: solve_chain("free", STANDARD, Uniform(FREE_KAPPA), n)}, reps)
        rows.append({"case": f"free n={n}: settle/chain", "settle_s": t["settle"], "chain_s": t["chain"],
                     "ratio": t["settle"] / t["chain"]})
    return rows


def _call_over_settle(calls: int, links: int = 256) -> dict:
    from simgrip.compare import simulate

    kappas = [FREE_KAPPA - 0.1 * i for i in range(calls)]
    simulate("free", STANDARD, Uniform(FREE_KAPPA + 0.05), links)  # first call: imports and caches, not counted
    ratios, walls, settles = [], [], []
    for k in kappas:
        t0 = time.perf_counter()
        st = simulate("free", STANDARD, Uniform(k), links)
        wall = time.perf_counter() - t0
        walls.append(wall)
        settles.append(st.wall_time_s)
        ratios.append(wall / st.wall_time_s)
    return {"case": f"simulate free n={links} x{calls}: call/settle", "call_s": statistics.median(walls),
            "settle_s": statistics.median(settles), "ratio": statistics.median(ratios)}


def _sweep_over_settle(points: int, reference: str) -> dict:
    """The issue's sweep with ``points`` kappa values (:data:`SWEEP_COMMAND`: 300) and ``--reference reference``,
    run as the command in a fresh process; its ``sweep.json`` throughput.  ``ratio`` is the whole sweep's wall
    per point over the median settle (the issue's figure), ``point/settle`` the median of each point's
    ``point_time_s / wall_time_s``."""
    cmd = list(SWEEP_COMMAND)
    cmd[cmd.index("--kappa") + 3] = str(int(points))
    with tempfile.TemporaryDirectory(prefix="simgrip-bench-sweep-") as tmp:
        out = Path(tmp) / "sweep"
        argv = cmd + ["--out", str(out), "--reference", reference, "--no-progress"]
        import os

        import simgrip

        env = dict(os.environ)  # the child imports this simgrip (a checkout run in place, or the installed one)
        here = str(Path(simgrip.__file__).resolve().parents[1])
        env["PYTHONPATH"] = os.pathsep.join([here] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else []))
        proc = subprocess.run([sys.executable, "-c", "import sys; from simgrip.cli import main; sys.exit(main())",
                               *argv], capture_output=True, text=True, timeout=SWEEP_TIMEOUT_S, env=env)
        if proc.returncode != 0:
            raise RuntimeError(f"simgrip {' '.join(argv)} failed (exit {proc.returncode}): "
                               f"{proc.stderr.strip().splitlines()[-1:] or ''}")
        t = json.loads((out / "sweep.json").read_text(encoding="utf-8"))["throughput"]
    return {"case": f"simgrip {' '.join(cmd)} --reference {reference}: wall per point/settle",
            "settle_s": t["settle_median_s"], "points_per_s_per_core": t["points_per_s_per_core"],
            "wall_per_point_s": t["wall_per_point_s"], "point/settle": t["point_over_settle_median"],
            "ratio": t["wall_per_point_over_settle"]}


def overhead_ratios(*, quick: bool = False, repeats: int | None = None) -> dict:
    """Measure the ratios of the module docstring; returns ``{"rows": [...], "checks": {...}, "repeats": r}``
    (every row has ``case`` and ``ratio``).  One BLAS thread throughout."""
    from simgrip.threads import blas_threads

    reps = int(repeats or (3 if quick else 5))
    with blas_threads(1):
        rows = _settle_over_chain((16, 32, 64, 128, 256), reps)
        rows.append(_call_over_settle(6 if quick else 12))
        # the command as it is (see the module docstring); quick (a smoke run, not the published
        # figure): 60 points, where the process's fixed costs weigh ~5x more in the ratio
        pts = QUICK_SWEEP_POINTS if quick else 300
        rows.append(_sweep_over_settle(pts, "none"))
        rows.append(_sweep_over_settle(pts, "bvp"))
    checks = {}
    for r in rows:
        if r["case"].startswith("free n="):
            checks[f"{r['case']} <= {TARGETS['settle/chain']}"] = r["ratio"] <= TARGETS["settle/chain"]
        elif r["case"].startswith("simulate"):
            checks[f"{r['case']} <= {TARGETS['call/settle n=256']}"] = r["ratio"] <= TARGETS["call/settle n=256"]
        elif "--reference" in r["case"]:  # both: the command runs the BVP reference by default
            checks[f"{r['case']} <= {TARGETS['sweep point/settle']}"] = r["ratio"] <= TARGETS["sweep point/settle"]
    return {"rows": rows, "checks": checks, "repeats": reps}


def overhead_md(rec: dict) -> str:
    """Markdown of :func:`overhead_ratios`: one line per ratio, then the checks."""
    out = ["# What surrounds the settle (issue 19)", "",
           f"settle/chain: fastest CPU time of {rec['repeats']} interleaved runs; the others: medians of each "
           "call's wall time over its own settle.", ""]
    out += ratio_lines(rec["rows"])
    out += checks_md(rec["checks"])
    return "\n".join(out) + "\n"


def write_overhead_bench(out_dir, *, quick: bool = False, repeats: int | None = None) -> dict:
    """Measure and write ``overhead.json`` and ``overhead.md`` into ``out_dir``; returns the record."""
    rec = overhead_ratios(quick=quick, repeats=repeats)
    write_record(out_dir, "overhead", rec, overhead_md(rec))
    return rec


if __name__ == "__main__":  # pragma: no cover - manual run: python -m simgrip.harness.bench_overhead
    print(overhead_md(overhead_ratios()))

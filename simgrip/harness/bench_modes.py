"""The modes in ``simgrip bench``: run time and frequency error against ``n``.

For the three cases of issue 20 (:data:`CASES`: the straight weightless-limit
cantilever against Euler-Bernoulli, the curled heavy free rod and Grip I at the
standard case against the linearised elastica, :mod:`simgrip.modes.rod`), at each
``n`` of :data:`N_FULL` (:data:`N_QUICK` with ``quick``) one run measures the
settle, the linearisation (stiffness by central differences of MuJoCo's forces and
the mass matrix) and the eigensolve, each the fastest of ``repeats`` in CPU time
(``time.process_time``; the scene is built outside the timed region), and the
relative error of the first three frequencies.  Between successive ``n`` it
reports the observed order ``log2(e(n) / e(2n))`` (2 expected,
:mod:`simgrip.modes`).  The reference (the rod's collocation) is solved once per
case and timed too.

Files: ``modes.json``, ``modes.md`` and ``modes.png`` (error against run time, one
line per case and mode, beside the statics' ``pareto.png``).
"""

from __future__ import annotations

import math
import time

import numpy as np

from simgrip.harness.tables import write_record
from simgrip.harness.timing import fastest_cpu_times
from simgrip.params import STANDARD, DimensionlessParams
from simgrip.profiles import Uniform

__all__ = ["CASES", "N_FULL", "N_QUICK", "modes_bench", "modes_bench_md", "write_modes_bench"]

#: name -> (grip, params, kappa_bar) of the bench (issue 20's three cases).
CASES = {
    "euler-bernoulli": ("free", DimensionlessParams(D=1e4), 0.0),
    "curled free": ("free", DimensionlessParams(D=1.0), -3.0),
    "grip I": ("I", STANDARD, -6.0),
}
#: Links per finger of the full and the quick bench.
N_FULL = (16, 32, 64, 128)
N_QUICK = (8, 16, 32)
#: Modes compared.
COUNT = 3


def _euler_bernoulli(D: float) -> np.ndarray:
    """``(beta l)^2 sqrt(D)`` of the first :data:`COUNT` cantilever modes (``1 + cos x cosh x = 0``)."""
    from scipy.optimize import brentq

    x = [brentq(lambda v: 1 + math.cos(v) * math.cosh(v), a, b, xtol=1e-14) for a, b in
         [(1, 2.5), (4, 5.5), (7, 8.5)]]
    return np.array(x[:COUNT]) ** 2 * math.sqrt(D)


def _reference(name):
    grip, params, kappa = CASES[name]
    t0 = time.process_time()
    if name == "euler-bernoulli":
        return _euler_bernoulli(params.D), "Euler-Bernoulli (closed form)", 0.0
    from simgrip.modes import reference_modes

    ref = reference_modes(grip, params, Uniform(kappa), COUNT).omega
    return ref, "linearised elastica (simgrip.modes.rod)", time.process_time() - t0


def _case(name, n, repeats):
    import mujoco

    from simgrip.modes import eigen, linearise, sticks_of
    from simgrip.scenes import build_scene
    from simgrip.settle import settle

    grip, params, kappa = CASES[name]
    scene = build_scene(grip, params, Uniform(kappa), n)
    start = np.array(scene.data.qpos)
    box = {}

    def run_settle():
        scene.data.qpos[:] = start
        scene.data.qvel[:] = 0.0
        mujoco.mj_forward(scene.model, scene.data)
        box["state"] = settle(scene)

    def run_linearise():
        d = mujoco.MjData(scene.model)
        d.qpos[:] = box["state"].qpos
        mujoco.mj_kinematics(scene.model, d)
        box["lin"] = linearise(scene, d, sticks=sticks_of(scene, box["state"], d))

    def run_eigen():
        lin = box["lin"]
        box["w"] = eigen(lin.M, lin.K, lin.basis, COUNT)[0]

    times = {}
    for key, fn in (("settle", run_settle), ("linearise", run_linearise), ("eigen", run_eigen)):
        times.update(fastest_cpu_times({key: fn}, repeats))
    return np.sqrt(box["w"]), times


def modes_bench(*, quick: bool = False, repeats: int | None = None) -> dict:
    """Run time and frequency error of the modes against ``n`` (see the module docstring); a JSON-able record."""
    from simgrip.threads import blas_threads

    ns = N_QUICK if quick else N_FULL
    reps = int(repeats or (1 if quick else 3))
    rows, refs = [], {}
    with blas_threads(1):
        for name in CASES:
            try:
                ref, source, t_ref = _reference(name)
            except Exception as exc:  # noqa: BLE001 - recorded in the outputs
                refs[name] = {"error": f"{type(exc).__name__}: {exc}"}
                continue
            refs[name] = {"frequencies": [float(x) for x in ref], "source": source, "cpu_s": t_ref}
            prev = None
            for n in ns:
                try:
                    freq, times = _case(name, n, reps)
                except Exception as exc:  # noqa: BLE001
                    rows.append({"case": name, "n": n, "error": f"{type(exc).__name__}: {exc}"})
                    prev = None
                    continue
                err = freq / ref - 1.0
                order = None if prev is None else [float(math.log2(abs(a / b))) if a and b else None
                                                   for a, b in zip(prev, err)]
                rows.append({"case": name, "n": n, "frequencies": [float(x) for x in freq],
                             "relative_error": [float(x) for x in err], "order": order,
                             "cpu_s": {k: float(v) for k, v in times.items()},
                             "modes_cpu_s": float(times["linearise"] + times["eigen"])})
                prev = err
    return {"quick": bool(quick), "repeats": reps, "links": list(ns), "count": COUNT, "references": refs,
            "rows": rows}


def modes_bench_md(rec: dict) -> str:
    """The bench record as a Markdown table."""
    lines = ["# Modes: run time and frequency error against n", "",
             "Relative error of the first three frequencies (omega sqrt(l/g)) against the reference; observed order "
             "log2(e(n/2)/e(n)); CPU seconds (fastest of the repeats): the settle, then the modes (linearisation + "
             "eigensolve). The scenes are the default ones (r_link = 2e-3 l): the capsules' rotary inertia lowers "
             "mode k by ~(beta_k r_link)^2 / 8 (<= 3e-5), which bends the observed order where the O(ds^2) error "
             "falls to that level (mode 1 of the curled rod at n >= 64); tests/test_modes.py measures the order "
             "with r_link = 1e-5 (2.00 +- 0.03).", "",
             "| case | n | error 1 | error 2 | error 3 | order 1 | order 2 | order 3 | settle s | modes s |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rec["rows"]:
        if "error" in r:
            lines.append(f"| {r['case']} | {r['n']} | {r['error']} |||||||")
            continue
        e = " | ".join(f"{x:+.3e}" for x in r["relative_error"])
        o = " | ".join("-" if x is None else f"{x:.2f}" for x in (r["order"] or [None] * len(r["relative_error"])))
        lines.append(f"| {r['case']} | {r['n']} | {e} | {o} | {r['cpu_s']['settle']:.3g} | {r['modes_cpu_s']:.3g} |")
    lines += ["", "References:"]
    for name, ref in rec["references"].items():
        if "error" in ref:
            lines.append(f"- {name}: failed ({ref['error']})")
        else:
            lines.append(f"- {name}: {ref['source']}: " + ", ".join(f"{x:.6g}" for x in ref["frequencies"])
                         + f" ({ref['cpu_s']:.3g} s)")
    return "\n".join(lines) + "\n"


def modes_plot(rec: dict, path) -> None:
    """``modes.png``: |relative error| against the modes' CPU time, one line per case and mode."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from simgrip.io import atomic_write

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for name in CASES:
        rows = [r for r in rec["rows"] if r["case"] == name and "error" not in r]
        for k in range(rec["count"]):
            t = [r["modes_cpu_s"] for r in rows]
            e = [abs(r["relative_error"][k]) for r in rows]
            if t:
                ax.loglog(t, e, marker="o", label=f"{name}, mode {k + 1}")
    ax.set_xlabel("CPU s (linearisation + eigensolve)")
    ax.set_ylabel("|relative frequency error|")
    ax.set_title("Modes: error against run time (n doubling along each line)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=6, ncol=2)
    fig.tight_layout()
    with atomic_write(path, mode="wb") as fh:
        fig.savefig(fh, format="png", dpi=110)
    plt.close(fig)


def write_modes_bench(out_dir, *, quick: bool = False, repeats: int | None = None) -> dict:
    """Measure and write ``modes.json``, ``modes.md`` and ``modes.png`` into ``out_dir``; returns the record."""
    from pathlib import Path

    rec = modes_bench(quick=quick, repeats=repeats)
    write_record(out_dir, "modes", rec, modes_bench_md(rec))
    modes_plot(rec, Path(out_dir) / "modes.png")
    return rec


if __name__ == "__main__":  # pragma: no cover - manual run: python -m simgrip.harness.bench_modes
    print(modes_bench_md(modes_bench(quick=True)))

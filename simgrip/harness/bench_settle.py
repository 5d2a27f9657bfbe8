"""The settle's targets (issue 9) measured in one run: speed ratios, accuracy, order, error targets.

Every time is the fastest of ``repeats`` runs in this process's CPU time
(``time.process_time``: on a shared machine wall time also counts the slices
other processes take, and a 20 ms task is preempted where a 1 ms one is not),
the methods of one case interleaved run by run, so the ratios hold on a busy
machine where absolute times do not.  The settle runs with one BLAS thread.  Scenes are built outside the timed
region; a settle rebuilds nothing (``settle(scene)`` on a fresh copy of the start
state each run).

========================================  ===============================================
target                                    measured
========================================  ===============================================
free rod, n = 64 and 256                  default settle / tridiagonal Newton on the chain
                                          (:func:`simgrip.reference.solve_chain`) <= 5
free rod, n = 32..256                     growth exponent of the settle time <= 1.2
Grips I, II, III standard cases, n = 32   settle / BVP (default tolerance) <= 1,
                                          settle / hinge-chain minimiser <= 5,
                                          dynamics / settle <= 2
Grip I, n = 32                            settle / the free rod's settle at n = 32 <= 3
                                          (issue 19)
Grips I, II at n = 64                     normal force within 1e-3 (relative), tip height
                                          within 5e-4 l of the point-contact BVP;
                                          order 2 +- 0.2 over n = 16..128
Grip III, n = 32                          forces within 1 % of the BVP at the
                                          simulation's own gamma
``target_error=1e-5`` (free, I, II)       error <= 1e-5, time <= BVP at default tolerance
========================================  ===============================================
"""

from __future__ import annotations

import math

import numpy as np

from simgrip.harness.tables import checks_md, write_record
from simgrip.harness.timing import fastest_cpu_times, settle_from_start
from simgrip.params import STANDARD
from simgrip.profiles import Uniform

__all__ = ["settle_targets", "settle_targets_md", "write_settle_targets"]

#: Standard cases (kappa_bar) of the settle targets.
CASES = {"free": -3.0, "I": -6.0, "II": 5.0, "III": -4.0}
#: Tolerance of the converged reference BVP.
REF_TOL = 1e-10


def _settler(grip, n, **kw):
    """The settle of ``grip``'s standard case (:data:`CASES`) with ``n`` links, from the same start each run."""
    return settle_from_start(grip, CASES[grip], n, **kw)


def settle_targets(*, quick: bool = False, repeats: int | None = None) -> dict:
    """Measure the targets of the module docstring; returns ``{"rows": [...], "checks": {...}}``.

    Everything runs with one BLAS thread, so CPU time is one core's work for every method.
    """
    from simgrip.threads import blas_threads

    with blas_threads(1):
        return _settle_targets(quick, repeats)


def _settle_targets(quick: bool, repeats: int | None) -> dict:
    from simgrip.compare import reference_for
    from simgrip.reference import elastica, solve_chain

    reps = int(repeats or (3 if quick else 7))
    rows, checks = [], {}
    # -- free rod: settle vs the tridiagonal Newton of the same chain ------------------
    ns = (32, 64, 128, 256)
    free_t = {}
    for n in ns:
        t = fastest_cpu_times({"settle": _settler("free", n),
                          "chain": lambda n=n: solve_chain("free", STANDARD, Uniform(CASES["free"]), n)}, reps)
        free_t[n] = t["settle"]
        rows.append({"case": f"free n={n}", "settle_s": t["settle"], "chain_s": t["chain"],
                     "settle/chain": t["settle"] / t["chain"]})
        if n in (64, 256):
            checks[f"free n={n}: settle/chain <= 5"] = t["settle"] / t["chain"] <= 5.0
    slope = float(np.polyfit(np.log(ns), np.log([free_t[n] for n in ns]), 1)[0])
    rows.append({"case": "free n=32..256 growth exponent", "value": slope})
    checks["free: growth <= n^1.2"] = slope <= 1.2
    # -- grips at n = 32: settle vs BVP, chain minimiser, dynamics ----------------------
    for grip in ("I", "II", "III"):
        k = CASES[grip]
        t = fastest_cpu_times({
            "settle": _settler(grip, 32),
            "dynamics": _settler(grip, 32, method="dynamics"),
            "bvp": lambda g=grip, k=k: elastica.solve(g, STANDARD, Uniform(k)),
            "chain": lambda g=grip, k=k: solve_chain(g, STANDARD, Uniform(k), 32),
        }, reps)
        rows.append({"case": f"{grip} n=32", "settle_s": t["settle"], "bvp_s": t["bvp"], "chain_s": t["chain"],
                     "dynamics_s": t["dynamics"], "settle/bvp": t["settle"] / t["bvp"],
                     "settle/chain": t["settle"] / t["chain"], "dynamics/settle": t["dynamics"] / t["settle"]})
        checks[f"{grip} n=32: settle <= BVP"] = t["settle"] <= t["bvp"]
        checks[f"{grip} n=32: settle <= 5x chain"] = t["settle"] <= 5.0 * t["chain"]
        checks[f"{grip} n=32: dynamics <= 2x settle"] = t["dynamics"] <= 2.0 * t["settle"]
        if grip == "I":  # issue 19: a grip's settle against the free rod's at the same n, interleaved run by run
            tf = fastest_cpu_times({"I": _settler("I", 32), "free": _settler("free", 32)}, reps)
            rows.append({"case": "I n=32 / free n=32", "I_settle_s": tf["I"], "free_settle_s": tf["free"],
                         "ratio": tf["I"] / tf["free"]})
            checks["I n=32: settle <= 3x free rod's settle"] = tf["I"] <= 3.0 * tf["free"]
    # -- accuracy and order against the point-contact BVP -------------------------------
    for grip in ("I", "II"):
        ref = elastica.solve(grip, STANDARD, Uniform(CASES[grip]), tol=REF_TOL)
        errs = {}
        for n in (16, 32, 64, 128):
            st = _settler(grip, n)()
            errs[n] = (abs(st.N1 / ref.N1 - 1.0), abs(float(st.tip[0][1]) - float(ref.tip[1])))
        orders = [math.log2(errs[a][i] / errs[2 * a][i]) for a in (16, 32, 64) for i in (0, 1)]
        rows.append({"case": f"{grip} accuracy n=64", "N_rel_err": errs[64][0], "tip_height_err": errs[64][1],
                     "order_min": min(orders), "order_max": max(orders)})
        checks[f"{grip} n=64: N within 1e-3"] = errs[64][0] <= 1e-3
        checks[f"{grip} n=64: tip height within 5e-4"] = errs[64][1] <= 5e-4
        checks[f"{grip}: order 2 +- 0.2 (16..128)"] = all(abs(o - 2.0) <= 0.2 for o in orders)
    st = _settler("III", 32)()
    ref = reference_for(st, STANDARD, Uniform(CASES["III"]))
    rel = max(abs(st.contact.normal / ref.n - 1.0), abs(st.contact.friction / ref.f - 1.0))
    rows.append({"case": "III n=32 forces vs BVP at gamma_sim", "rel_err": rel})
    checks["III: forces within 1 % at gamma_sim"] = rel <= 0.01
    # -- error-targeted settle ----------------------------------------------------------
    for grip in ("free", "I", "II"):
        k = CASES[grip]
        ref = elastica.solve(grip, STANDARD, Uniform(k), tol=REF_TOL)
        t = fastest_cpu_times({"target": _settler(grip, 16, target_error=1e-5),
                          "bvp": lambda g=grip, k=k: elastica.solve(g, STANDARD, Uniform(k))}, reps)
        st = _settler(grip, 16, target_error=1e-5)()
        tip_err = float(np.max(np.abs(st.tip[0] - ref.tip)))
        force_err = 0.0 if grip == "free" else float(
            max(abs(st.N1 - ref.N1), abs(st.N2 - ref.N2)) / max(abs(ref.N1), abs(ref.N2)))
        rows.append({"case": f"{grip} target_error=1e-5", "links": st.links, "tip_err": tip_err,
                     "force_err": force_err, "estimate": st.error_estimate, "target_s": t["target"],
                     "bvp_s": t["bvp"], "target/bvp": t["target"] / t["bvp"]})
        checks[f"{grip} target 1e-5: met"] = max(tip_err, force_err) <= 1e-5
        checks[f"{grip} target 1e-5: time <= BVP"] = t["target"] <= t["bvp"]
    return {"rows": rows, "checks": checks, "repeats": reps}


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.3g}"
    if isinstance(v, dict):
        return ", ".join(f"{k} {_fmt(x)}" for k, x in v.items())
    return str(v)


def settle_targets_md(rec: dict) -> str:
    """Markdown of :func:`settle_targets`: one line per measurement, then the checks."""
    out = ["# Settle targets (issue 9)", "", f"Fastest CPU time of {rec['repeats']} interleaved runs.", ""]
    for r in rec["rows"]:
        out.append("- " + r["case"] + ": " + "; ".join(f"{k} {_fmt(v)}" for k, v in r.items() if k != "case"))
    out += checks_md(rec["checks"])
    return "\n".join(out) + "\n"


def write_settle_targets(out_dir, *, quick: bool = False, repeats: int | None = None) -> dict:
    """Measure and write ``settle_targets.json`` and ``settle_targets.md`` into ``out_dir``."""
    rec = settle_targets(quick=quick, repeats=repeats)
    write_record(out_dir, "settle_targets", rec, settle_targets_md(rec))
    return rec


if __name__ == "__main__":  # pragma: no cover - manual run: python -m simgrip.harness.bench_settle
    print(settle_targets_md(settle_targets()))

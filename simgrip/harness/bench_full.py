"""The full-contact settle's speed (issue 17 s.5), measured in one run.

==========================================================  ===========================================  ======
ratio                                                       how                                          target
==========================================================  ===========================================  ======
where point contact applies (Grip I kappa -6, Grip II 4,    median CPU time of interleaved repeats,      <= 3
the free rod -4; n = 32): full-contact settle / the         each settle from the built start (the scene
point-contact settle of the same grip                       built outside the timed region)
past the onset (Grip I kappa -10 grasped at depth 0.4):     the settle at n against the BVP's cheapest   <= 1
full-contact settle / the free-boundary BVP at matched      ``solve_bvp`` tolerance whose error in the
error                                                       tip's N is at most the chain's at n
==========================================================  ===========================================  ======

Each row also times the guarded dynamics alone (``static=False`` of :func:`~simgrip.settle.full_contact.settle_full`,
the full-contact settle before the static route) in the same interleaved loop.  The BVP's error is
``|N(tol) - N(1e-10)|``; the chain's ``|N_n - N_BVP|`` (:data:`~simgrip.reference.free_boundary.GRIP_I_KAPPA_M10`).
The BVP's time is ``solve_corner`` from the constrained chain at n = 16 (its guess, timed apart as ``guess_s``,
wall seconds: ``simgrip solve --contact full`` computes one too), in the same interleaved loop as the settle.
Where even the coarsest tolerance beats the chain's error, that one is timed (``bvp_error_N`` says by how much).
"""

from __future__ import annotations

import statistics
import time

from simgrip.harness.tables import checks_md, ratio_lines, write_record

__all__ = ["POINT_CASES", "TARGETS", "full_md", "full_speed", "write_full_bench"]

#: Targets of issue 17 s.5 (upper bounds of the ratios).
TARGETS = {"full/point": 3.0, "full/BVP": 1.0}
#: (grip, kappa_bar) where both settles apply (point contact valid, the extra pairs inactive).
POINT_CASES = (("I", -6.0), ("II", 4.0), ("free", -4.0))
#: The past-the-onset case: Grip I at kappa -10, box depth 0.4 (the free-boundary reference's).
PAST_KAPPA, PAST_DEPTH = -10.0, 0.4
#: solve_bvp tolerances tried for the matched error, coarse to fine.
BVP_TOLS = (1e-1, 3e-2, 1e-2, 3e-3, 1e-3, 1e-4, 1e-6)


def _settle_fn(grip, kappa, n, *, contact=None, static=True, **kw):
    """A function settling the standard case from the same built start on every call (the scene built once)."""
    from simgrip.params import STANDARD
    from simgrip.profiles import Uniform
    from simgrip.settle import settle
    from simgrip.sim.scene import build_scene

    sc = build_scene(grip, STANDARD, Uniform(kappa), n, contact=contact, **kw)
    q0, bp = sc.data.qpos.copy(), sc.model.body_pos.copy()

    def run():
        sc.data.qpos[:] = q0
        sc.data.qvel[:] = 0.0
        sc.model.body_pos[:] = bp
        if static:
            return settle(sc)
        return _dynamics_only(sc)

    return run


def _dynamics_only(sc):
    """The full-contact settle without its static route (the guarded dynamics alone), as :func:`settle` wraps it."""
    from simgrip.settle import _finish
    from simgrip.settle.dynamics import DYN_TOL, dynamics_tolerance
    from simgrip.settle.full_contact import settle_full
    from simgrip.settle.statics import restore_options, save_options, sync_scene

    tol = dynamics_tolerance(sc) if sc.has_workpiece else DYN_TOL
    saved = save_options(sc.model)
    try:
        st = settle_full(sc, tol, 20_000, False, time.perf_counter(), static=False)
        return _finish(sc, st, tol, False, "full-contact settle", f"{st.steps} steps")
    finally:
        restore_options(sc.model, saved)
        sc.data.qfrc_applied[:] = 0.0
        sc.data.qvel[:] = 0.0
        sync_scene(sc)


def _median_cpu(fns: dict, repeats: int) -> dict:
    """Median CPU seconds (``time.process_time``, one BLAS thread: the settle's own work, not the other jobs of
    a busy machine) of each ``fn()``, the functions run in turn ``repeats`` times (interleaved)."""
    from simgrip.harness.timing import interleaved_cpu_times

    return {k: statistics.median(v) for k, v in interleaved_cpu_times(fns, repeats).items()}


def _tip_normal(st, n: int) -> float:
    return sum(c["normal_force"] for c in st.contact_set if c["with"] == "workpiece" and c["link"] == n - 1)


def _point_rows(n: int, reps: int, before: bool) -> list[dict]:
    rows = []
    for grip, kappa in POINT_CASES:
        full = _settle_fn(grip, kappa, n, contact="full")
        st = full()  # warm (imports, caches) and the route taken
        fns = {"full": full, "point": _settle_fn(grip, kappa, n)}
        if before:
            fns["dynamics"] = _settle_fn(grip, kappa, n, contact="full", static=False)
        t = _median_cpu(fns, reps)
        row = {"case": f"{grip} kappa {kappa:g} n={n}: full/point", "method": st.method, "held": st.held,
               "full_s": t["full"], "point_s": t["point"], "ratio": t["full"] / t["point"]}
        if before:
            row.update(dynamics_s=t["dynamics"], before=t["dynamics"] / t["point"])
        rows.append(row)
    return rows


def _bvp_errors() -> tuple[list[dict], float]:
    """The BVP at each of :data:`BVP_TOLS`: ``[{tol, N, error, run}]`` (``run()`` solves it again) and the
    guess's wall time [s]."""
    from simgrip.params import STANDARD
    from simgrip.profiles import Uniform
    from simgrip.reference.constrained import Box, solve_constrained
    from simgrip.reference.free_boundary import GRIP_I_KAPPA_M10, FreeBoundaryError, solve_corner

    exact = float(GRIP_I_KAPPA_M10["bvp"]["N"])
    t0 = time.perf_counter()
    guess = None
    for k in (-7.0, -8.0, -9.0, PAST_KAPPA):  # continued from the point-contact range (test_free_boundary's path)
        guess = solve_constrained("I", STANDARD, Uniform(k), 16, box=Box(depth=PAST_DEPTH), guess=guess)
    guess_s = time.perf_counter() - t0
    out = []
    for tol in BVP_TOLS:
        def run(tol=tol):
            return solve_corner("I", STANDARD, Uniform(PAST_KAPPA), guess, depth=PAST_DEPTH, tol=tol)

        try:
            b = run()
        except FreeBoundaryError:
            continue
        out.append({"tol": tol, "N": b.N, "error": abs(b.N - exact), "run": run})
    return out, guess_s


def _past_rows(ns, reps: int, before: bool) -> list[dict]:
    from simgrip.reference.free_boundary import GRIP_I_KAPPA_M10

    exact = float(GRIP_I_KAPPA_M10["bvp"]["N"])
    bvp, guess_s = _bvp_errors()
    rows = []
    for n in ns:
        full = _settle_fn("I", PAST_KAPPA, n, contact="full", box_depth=PAST_DEPTH)
        st = full()
        err = abs(_tip_normal(st, n) - exact)
        match = next((b for b in bvp if b["error"] <= err), bvp[-1] if bvp else None)
        fns = {"full": full}
        if match is not None:
            fns["bvp"] = match["run"]
        if before:
            fns["dynamics"] = _settle_fn("I", PAST_KAPPA, n, contact="full", box_depth=PAST_DEPTH, static=False)
        t = _median_cpu(fns, reps)
        row = {"case": f"I kappa {PAST_KAPPA:g} depth {PAST_DEPTH:g} n={n}: full/BVP", "method": st.method,
               "held": st.held, "chain_error_N": err, "full_s": t["full"]}
        if match is not None:
            row.update(bvp_tol=match["tol"], bvp_error_N=match["error"], bvp_s=t["bvp"], guess_s=guess_s,
                       ratio=t["full"] / t["bvp"])
        if before:
            row["dynamics_s"] = t["dynamics"]
            if match is not None:
                row["before"] = t["dynamics"] / t["bvp"]
        rows.append(row)
    return rows


def full_speed(*, quick: bool = False, repeats: int | None = None) -> dict:
    """Measure the ratios of the module docstring; ``{"rows": [...], "checks": {...}, "repeats": r}``.
    ``quick``: no dynamics column, the past-the-onset row at n = 16 once."""
    from simgrip.threads import blas_threads

    reps = int(repeats or (3 if quick else 5))
    with blas_threads(1):  # quick: without the dynamics' "before" column (seconds per run), one past-onset n
        rows = _point_rows(32, reps, not quick)
        rows += _past_rows((16,) if quick else (16, 32, 64), 1 if quick else reps, not quick)
    checks = {}
    for r in rows:
        key = "full/point" if r["case"].endswith("full/point") else "full/BVP"
        if "ratio" in r:
            checks[f"{r['case']} <= {TARGETS[key]:g}"] = r["ratio"] <= TARGETS[key]
    return {"rows": rows, "checks": checks, "repeats": reps}


def full_md(rec: dict) -> str:
    """Markdown of :func:`full_speed`: one line per ratio (``before``: the dynamics alone), then the checks."""
    out = ["# The full-contact settle's speed (issue 17 s.5)", "",
           f"Medians of {rec['repeats']} interleaved runs (CPU seconds); `before`: the guarded dynamics alone "
           "over the same denominator.", ""]
    out += ratio_lines(rec["rows"])
    out += checks_md(rec["checks"])
    return "\n".join(out) + "\n"


def write_full_bench(out_dir, *, quick: bool = False, repeats: int | None = None) -> dict:
    """Measure and write ``full.json`` and ``full.md`` into ``out_dir``; returns the record."""
    rec = full_speed(quick=quick, repeats=repeats)
    write_record(out_dir, "full", rec, full_md(rec))
    return rec


if __name__ == "__main__":  # pragma: no cover - manual run: python -m simgrip.harness.bench_full
    print(full_md(full_speed()))

"""K-finger settles in ``simgrip bench``: the coupled settle against K single fingers, and the symmetry skip.

Issue 13's speed target: a K-finger settle at ``n = 32`` costs at most ``K``
times the single-finger settle of the same per-finger problem (plus the
workpiece's 6 dofs).  For Grips I and II at the standard cases
(:data:`CASES`), for the box (``K`` = 2, 4) and the cylinder (``K`` = 2, 3, 4),
one run measures, interleaved run by run:

========================  =====================================================
``full``                  the coupled K-finger dynamics
                          (:func:`simgrip.gripper.settle.settle_gripper`,
                          ``method="dynamics"``)
``single_dyn``            the planar one-finger dynamic settle of the same
                          per-finger problem (``settle(method="dynamics")`` of
                          the symmetric reduction: the same method)
``single_newton``         the planar one-finger default settle (Newton in link
                          angles, point contact)
``skip``                  the symmetry skip
                          (:func:`simgrip.gripper.symmetry.settle_symmetric`:
                          one planar Newton settle, its scene's build included,
                          replicated to K fingers)
``skip_reuse``            the same with its planar scene built once
                          (``planar=``), as a sweep would
========================  =====================================================

(these scenes are exactly symmetric, so ``settle_gripper``'s default,
``method="auto"``, is the skip) and reports ``full / (K single_dyn)`` (the
target: <= 1; also per physics step, to tell more steps from dearer ones),
``full / (K single_newton)``, ``full / skip`` and ``full / skip_reuse`` (what
the skip saves).  As
in :mod:`simgrip.harness.bench_settle`: every time is the fastest of
``repeats`` runs in CPU time (``time.process_time``), one BLAS thread, the
methods of one case run in turn; scenes are built outside the timed region
(the skip's own planar scene is built inside it: it is part of the skip).
The answers are compared too (largest per-finger ``|N1|`` difference of the
skip against the dynamics, over ``N1``: the point contact against MuJoCo's
surface contact differ by the tip couple, ~0.3 %).
"""

from __future__ import annotations

from simgrip.harness.tables import checks_md, write_record
from simgrip.harness.timing import fastest_cpu_times, settle_from_start
from simgrip.params import STANDARD
from simgrip.profiles import Uniform

__all__ = ["CASES", "SHAPES", "gripper_bench", "gripper_bench_md", "write_gripper_bench"]

#: Grip -> standard curvature kappa_bar of the gripper bench.
CASES = {"I": -6.0, "II": 5.0}
#: (K, workpiece) of the gripper bench.
SHAPES = ((2, "box"), (4, "box"), (2, "cylinder"), (3, "cylinder"), (4, "cylinder"))
#: Links per finger.
N_LINKS = 32


def _gripper(grip, kappa, n, K, shape, method):
    from simgrip.gripper.settle import settle_gripper
    from simgrip.gripper.symmetry import planar_scene, settle_symmetric
    from simgrip.gripper.scene import build_gripper

    sc = build_gripper(grip, STANDARD, Uniform(kappa), n, fingers=K, workpiece=shape)
    if method == "skip":
        return lambda: settle_symmetric(sc)
    if method == "skip_reuse":
        planar = planar_scene(sc)
        return lambda: settle_symmetric(sc, planar=planar)
    return lambda: settle_gripper(sc, method="dynamics")


def gripper_bench(*, quick: bool = False, repeats: int | None = None, n: int = N_LINKS) -> dict:
    """Measure the table of the module docstring; returns ``{"rows": [...], "checks": {...}, "repeats": R}``."""
    from simgrip.threads import blas_threads

    reps = int(repeats or (3 if quick else 7))
    rows, checks = [], {}
    with blas_threads(1):
        for grip, kappa in CASES.items():
            single = {"single_dyn": settle_from_start(grip, kappa, n, method="dynamics"),
                      "single_newton": settle_from_start(grip, kappa, n)}
            for K, shape in SHAPES:
                fns = {"full": _gripper(grip, kappa, n, K, shape, "full"),
                       "skip": _gripper(grip, kappa, n, K, shape, "skip"),
                       "skip_reuse": _gripper(grip, kappa, n, K, shape, "skip_reuse"), **single}
                t = fastest_cpu_times(fns, reps)
                full, skip, one = fns["full"](), fns["skip"](), fns["single_dyn"]()
                dN = max(abs(a.N1 - b.N1) for a, b in zip(full.records, skip.records)) / abs(full.records[0].N1) \
                    if full.held and skip.held else None
                row = {"grip": grip, "kappa": kappa, "n": n, "fingers": K, "workpiece": shape,
                       "full_s": t["full"], "skip_s": t["skip"], "single_dyn_s": t["single_dyn"],
                       "single_newton_s": t["single_newton"],
                       "full/(K single_dyn)": t["full"] / (K * t["single_dyn"]),
                       "full/(K single_newton)": t["full"] / (K * t["single_newton"]),
                       "skip_reuse_s": t["skip_reuse"], "full/skip": t["full"] / t["skip"],
                       "full/skip_reuse": t["full"] / t["skip_reuse"],
                       "skip/single_newton": t["skip"] / t["single_newton"],
                       "full_steps": full.steps, "single_dyn_steps": one.steps,
                       "full/(K single_dyn) per step": t["full"] * one.steps / (K * t["single_dyn"] * full.steps),
                       "held": [full.held, skip.held], "N1_rel_diff": dN}
                rows.append(row)
                checks[f"{grip} K={K} {shape}: full <= K x single (dynamics)"] = row["full/(K single_dyn)"] <= 1.0
    return {"rows": rows, "checks": checks, "repeats": reps, "n": n}


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.3g}"
    if v is None:
        return "-"
    return str(v)


def gripper_bench_md(rec: dict) -> str:
    """Markdown table of :func:`gripper_bench`."""
    cols = ("grip", "fingers", "workpiece", "full_s", "single_dyn_s", "single_newton_s", "skip_s", "skip_reuse_s",
            "full/(K single_dyn)", "full/(K single_newton)", "full/skip", "full/skip_reuse", "full_steps",
            "single_dyn_steps", "full/(K single_dyn) per step", "N1_rel_diff")
    out = ["# K-finger settles (issue 13)", "",
           f"n = {rec['n']}; fastest CPU time of {rec['repeats']} interleaved runs, one BLAS thread.  full: the "
           "coupled K-finger dynamics; single_dyn / single_newton: the planar one-finger dynamic / default "
           "(Newton) settle of the same per-finger problem; skip: the symmetry skip (one planar Newton settle, "
           "its scene's build included, replicated; skip_reuse: the same with the planar scene built once).  "
           "full_steps, single_dyn_steps: physics steps of the two dynamic settles; per step: the time ratio per "
           "physics step.  N1_rel_diff: skip (point contact) against the dynamics "
           "(MuJoCo's surface contact).", "",
           "| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for r in rec["rows"]:
        out.append("| " + " | ".join(_fmt(r.get(c)) for c in cols) + " |")
    out += checks_md(rec["checks"])
    return "\n".join(out) + "\n"


def write_gripper_bench(out_dir, *, quick: bool = False, repeats: int | None = None) -> dict:
    """Measure and write ``gripper.json`` and ``gripper.md`` into ``out_dir``; returns the record."""
    rec = gripper_bench(quick=quick, repeats=repeats)
    write_record(out_dir, "gripper", rec, gripper_bench_md(rec))
    return rec


if __name__ == "__main__":  # pragma: no cover - manual run: python -m simgrip.harness.bench_gripper
    print(gripper_bench_md(gripper_bench()))

"""Do the Newton settle, the dynamics and the BVP give one hold/drop verdict over the accepted parameter box?

Issue 16 §6's audit.  At every corner and edge of the accepted box
(:mod:`simgrip.params`: ``D`` in ``{1e-2, 1, 1e4}``, ``M`` in ``{0, 5, 1e4}``,
``mu_s`` in ``{0, 1, 100}``: the 3 x 3 x 3 grid holds the box's 8 corners, the
12 edge midpoints, the face centres and the centre), at curvatures across each
grip's range (:data:`KAPPAS`, the paper's ranges of Figs. 7-9 and a wrong-way
curl for Grips I/II), and near the limits of ``b`` and ``gamma`` (:data:`EDGES`,
at the standard ``M``, ``mu_s`` and the three ``D``), every grip is settled with
``K`` = 2, 3, 4 fingers (:data:`VARIANTS`):

``K = 2``
    the planar symmetric reduction (``simgrip simulate``/``compare``); for
    Grips I/II also the K-finger box of two fingers;
``K = 3``
    Grips I/II: the K-finger cylinder (Grip III has no 3-finger cradle: the
    builder refuses it, naming ``workpiece``/``fingers``; listed as refused);
``K = 4``
    Grips I/II: the K-finger box; Grip III: the four-finger cradle.

Each row compares three verdicts, ``"held"`` or ``"dropped"`` (``feasible``:
held and, Grip III, condition (23) met):

``default``
    the method a user gets: the planar settle's default
    (:func:`simgrip.compare.simulate` without ``method``: Newton, and where it
    fails, the dynamics with a warning), the K-finger ``settle_gripper`` with
    ``method="auto"`` (the symmetry skip: the planar Newton replicated; where
    it fails, the dynamics, with a warning);
``dynamics``
    the over-damped MuJoCo dynamics (planar ``method="dynamics"``; K-finger
    ``method="dynamics"``; the cradle: one finger's planar dynamics,
    replicated, :func:`~simgrip.gripper.symmetry.settle_cradle_dynamics`);
``bvp``
    the elastica BVP of the state the planar default describes
    (:func:`simgrip.compare.reference_of`: started from the settled chain's
    shape, its contact couple, Grip III its own ``gamma``; the BVP at the
    parameters where the settle drops or fails), as ``simgrip compare`` reports
    it, with its warnings (a reference on another branch, one at the friction
    cone's edge as the chain resolves it).  Its ``feasible`` includes the grip's
    shape (Grips I/II: a solution in the other grip's shape is not feasible).
    A Grip III contact at the tip has no reference (no verdict, named).

A row is an **agreement** when the three verdicts are one; a **warned
disagreement** when they differ and a simulated state (default or dynamics)
or the reference carries a warning (``warnings``: the other grip's shape,
condition (23), the skip's fallback, a finger that does not reach the face, the
friction cone's edge, a reference on another branch, ...) that says why (the
comparison's bare "verdicts disagree" is not one); a **silent disagreement** otherwise.  A
row where a method raised a named error (``SettleError``, ``ElasticaError``)
has **no verdict** from it: listed apart (the default's own failures are the
ones that matter: the default must answer where another method does).  Any
other exception is a bug: the row is no verdict too, its error marked
``CRASH`` and counted (``crashed``), so that one bad point does not end the
audit.

Run: ``python -m simgrip.harness.verdict_audit --out DIR [--jobs N] [--quick]``
writes ``DIR/verdict_audit.json`` (every row) and ``DIR/verdict_audit.md``
(the table, the silent disagreements listed).  :func:`quick_points` is the
representative subset the test suite runs (``tests/test_verdict_audit.py``).
"""

from __future__ import annotations

import itertools
import sys
import time
import traceback

from simgrip.command_parser import CommandParser

__all__ = ["D_VALUES", "M_VALUES", "MU_VALUES", "KAPPAS", "EDGES", "VARIANTS", "LINKS", "audit_points",
           "quick_points", "audit_point", "summarise", "run_audit", "format_table", "main"]

#: Corners and edges of the accepted box (simgrip.params: D in [1e-2, 1e4], M in [0, 1e4], mu_s in [0, 100]).
D_VALUES = (1e-2, 1.0, 1e4)
M_VALUES = (0.0, 5.0, 1e4)
MU_VALUES = (0.0, 1.0, 100.0)
#: Curvatures per grip: across the paper's range (Fig. 7: I in [-6, 0], Fig. 8: II in [0, 6], Fig. 9: III in
#: [-10, 0]) and, Grips I/II, a curl the wrong way (the other grip's shape).
KAPPAS = {"I": (-1.0, -3.5, -6.0, 5.0), "II": (1.0, 3.5, 6.0, -5.0), "III": (-2.0, -4.0, -7.0, -10.0)}
#: Near the limits of b (0 < b < 2; the K-finger tips need b > 2 r_tip = 0.004, the Grip III start b > ~0.02
#: and b/2 < gamma: b < 1.6 at the standard gamma = 0.8) and gamma (Grip III's start contact, b/2 < gamma < 1:
#: 0.3 < gamma at the standard b = 0.6), at the standard M and mu_s.
EDGES = {"I": ({"b": 0.02}, {"b": 1.9}), "II": ({"b": 0.02}, {"b": 1.9}),
         "III": ({"b": 0.05}, {"b": 1.55}, {"gamma": 0.31}, {"gamma": 0.97})}
#: (name, fingers, workpiece) per grip; ``workpiece`` None is the planar symmetric reduction.
VARIANTS = {
    "I": (("planar", 2, None), ("box2", 2, "box"), ("cyl3", 3, "cylinder"), ("box4", 4, "box")),
    "II": (("planar", 2, None), ("box2", 2, "box"), ("cyl3", 3, "cylinder"), ("box4", 4, "box")),
    "III": (("planar", 2, None), ("cradle4", 4, "box")),
}
#: Grip III with K = 3: refused by the builder (the cradle is a box with one finger per face).
REFUSED = {"III": ((3, "box"),)}
#: Links per finger (the command line's default).
LINKS = 32


def _point(grip, kappa, D, M, mu_s, b=0.6, gamma=0.8, where="grid") -> dict:
    return {"grip": grip, "kappa": float(kappa), "D": float(D), "M": float(M), "mu_s": float(mu_s), "b": float(b),
            "gamma": float(gamma), "where": where}


def audit_points() -> list[dict]:
    """Every parameter point of the full audit: the D x M x mu_s grid at each grip's curvatures, then the edges."""
    pts = []
    for grip, kappas in KAPPAS.items():
        for kappa, D, M, mu in itertools.product(kappas, D_VALUES, M_VALUES, MU_VALUES):
            pts.append(_point(grip, kappa, D, M, mu))
        for edge, kappa, D in itertools.product(EDGES[grip], kappas, D_VALUES):
            pts.append(_point(grip, kappa, D, 5.0, 1.0, where="edge", **edge))
    return pts


def quick_points() -> list[dict]:
    """The test suite's subset: each grip's corners of D x M x mu_s that have answered differently, the
    standard case, a wrong-way curl, the issue's reproductions (each grip at one paper curvature) and one
    point of each group of the full audit's former silent disagreements (see the comments)."""
    pts = []
    for grip, kappa in (("I", -6.0), ("II", 6.0), ("III", -4.0)):
        pts.append(_point(grip, kappa, 1.0, 5.0, 1.0))  # the paper's standard case
        pts.append(_point(grip, kappa, 1.0, 0.0, 0.0))  # weightless, frictionless: the cone's boundary
        pts.append(_point(grip, kappa, 1e-2, 0.0, 100.0))  # the softest finger, weightless
        pts.append(_point(grip, kappa, 1.0, 1e4, 100.0))  # the heaviest workpiece
        pts.append(_point(grip, kappa, 1e4, 5.0, 1.0))  # the stiffest finger
    pts.append(_point("I", 5.0, 1.0, 5.0, 1.0))  # wrong-way curls (issue 16 §6, third bullet)
    pts.append(_point("II", -5.0, 1.0, 5.0, 1.0))
    pts.append(_point("III", -4.0, 1.0, 5.0, 1.0, b=0.1, where="edge"))  # issue 16 §6, second bullet
    # the full audit's planar groups, one representative each:
    pts.append(_point("I", -1.0, 1.0, 1e4, 100.0))  # the unloaded finger does not reach the face (warned)
    pts.append(_point("II", 3.5, 1e-2, 5.0, 100.0))  # the BVP in the other grip's shape (not feasible)
    pts.append(_point("I", -6.0, 1e4, 5.0, 1.0, b=0.02, where="edge"))  # the reference on the settled branch
    pts.append(_point("III", -10.0, 1e-2, 5.0, 100.0))  # the same, Grip III at its own gamma
    pts.append(_point("III", -4.0, 1.0, 0.0, 1.0))  # Grip III at the friction cone's edge (warned)
    pts.append(_point("III", -7.0, 1e-2, 1e4, 1.0))  # Newton fails: the default falls back to the dynamics
    pts.append(_point("III", -7.0, 1.0, 5.0, 1.0, gamma=0.97, where="edge"))  # a contact at the tip: no reference
    return pts


def _verdict(held: bool, clear: bool = True) -> str:
    return "held" if held and clear else "dropped"


def _run(fn):
    """``{verdict, warnings, method, error, refused, time_s}`` of one settle or solve.

    A named solver error (``SettleError``, ``ElasticaError``) is no verdict; a ``ValueError`` (an input the
    builder or solver refuses, naming it) is ``refused``.
    """
    from simgrip.reference.bvp import ElasticaError
    from simgrip.settle import SettleError

    t0 = time.perf_counter()
    res = {"verdict": None, "warnings": [], "method": None, "error": None, "refused": False, "crashed": False}
    try:
        res["verdict"], warnings, res["method"] = fn()
        res["warnings"] = list(warnings)
    except (SettleError, ElasticaError, ValueError) as exc:
        res["error"] = f"{type(exc).__name__}: {exc}"
        res["refused"] = isinstance(exc, ValueError)
    except Exception as exc:  # a bug, not a named answer: the row says so and the audit goes on (counted apart)
        where = traceback.extract_tb(exc.__traceback__)[-1]
        res["error"] = f"CRASH {type(exc).__name__}: {exc} ({where.filename.rsplit('/', 1)[-1]}:{where.lineno})"
        res["crashed"] = True
    res["time_s"] = time.perf_counter() - t0
    return res


def _planar(grip, params, prof, n, method):
    """The planar settle as ``simgrip simulate`` runs it (:func:`simgrip.compare.simulate`; ``method`` None: the
    default, Newton with the dynamics as its fallback)."""
    from simgrip.compare import simulate

    return simulate(grip, params, prof, n, method=method)


def _gripper_scene(grip, params, prof, n, K, workpiece):
    """The K-finger scene as :func:`simgrip.gripper.simulate_gripper` builds it (Grip III from the theory's start)."""
    from simgrip.scenes import start_angles
    from simgrip.gripper.scene import build_gripper

    start = {"initial_angles": start_angles("III", params, prof, n)} if grip == "III" else {}
    return build_gripper(grip, params, prof, n, fingers=K, workpiece=workpiece, **start)


def audit_point(point: dict, links: int = LINKS) -> list[dict]:
    """Settle one parameter point every way (:data:`VARIANTS`); one row per variant (see the module docstring)."""
    from simgrip.compare import reference_of
    from simgrip.params import DimensionlessParams
    from simgrip.profiles import Uniform
    from simgrip.gripper.settle import settle_gripper
    from simgrip.gripper.symmetry import settle_cradle_dynamics

    grip = point["grip"]
    params = DimensionlessParams(D=point["D"], M=point["M"], b=point["b"], mu_s=point["mu_s"], gamma=point["gamma"])
    prof = Uniform(point["kappa"])
    planar = {}

    def planar_default():
        st = _planar(grip, params, prof, links, None)
        planar["state"] = st
        return _verdict(st.held, st.tip_clear), st.warnings, st.method

    def planar_dynamics():
        st = _planar(grip, params, prof, links, "dynamics")
        return _verdict(st.held, st.tip_clear), st.warnings, "dynamics"

    def bvp():
        from simgrip.reference import elastica
        from simgrip.reference.bvp import ElasticaError

        st = planar.get("state")
        sol, warnings = reference_of(st, params, prof) if st is not None else (elastica.solve(grip, params, prof), [])
        if sol is None:  # no reference (a Grip III contact at the tip): no verdict, the reason named
            raise ElasticaError(warnings[0])
        return _verdict(sol.feasible), warnings, "bvp"

    newton = _run(planar_default)
    ref = _run(bvp)
    rows = []
    for name, K, workpiece in VARIANTS[grip]:
        if workpiece is None:
            default, dyn = newton, _run(planar_dynamics)
        else:
            def k_default(K=K, workpiece=workpiece):
                st = settle_gripper(_gripper_scene(grip, params, prof, links, K, workpiece))
                return _verdict(st.held, st.tip_clear), st.warnings, st.method

            def k_dynamics(K=K, workpiece=workpiece):
                sc = _gripper_scene(grip, params, prof, links, K, workpiece)
                st = settle_cradle_dynamics(sc) if grip == "III" else settle_gripper(sc, method="dynamics")
                return _verdict(st.held, st.tip_clear), st.warnings, "dynamics"

            default, dyn = _run(k_default), _run(k_dynamics)
        rows.append(_classify({**point, "variant": name, "fingers": K, "workpiece": workpiece or "planar",
                               "links": links}, default, dyn, ref))
    for K, workpiece in REFUSED.get(grip, ()):
        rows.append({**point, "variant": f"{workpiece}{K}", "fingers": K, "workpiece": workpiece, "links": links,
                     "outcome": "refused", "default_error": _run(
                         lambda: settle_gripper(_gripper_scene(grip, params, prof, links, K, workpiece)))["error"]})
    return rows


def _classify(row: dict, default: dict, dyn: dict, ref: dict) -> dict:
    """The row's three answers and its outcome: agree, warned, silent or no_verdict."""
    for name, res in (("default", default), ("dynamics", dyn), ("bvp", ref)):
        row[name] = res["verdict"]
        row[f"{name}_error"] = res["error"]
        row[f"{name}_warnings"] = res["warnings"]
        row[f"time_{name}_s"] = res["time_s"]
    row["default_method"] = default["method"]
    row["crashed"] = any(res.get("crashed") for res in (default, dyn, ref))
    verdicts = [default["verdict"], dyn["verdict"], ref["verdict"]]
    if default["refused"] and dyn["refused"]:  # the simulation refuses the input (named): not a case
        row["outcome"] = "refused"
    elif None in verdicts:
        row["outcome"] = "no_verdict"
    elif len(set(verdicts)) == 1:
        row["outcome"] = "agree"
    elif default["warnings"] or dyn["warnings"] or ref["warnings"]:
        row["outcome"] = "warned"
    else:
        row["outcome"] = "silent"
    return row


def _point_task(point: dict) -> list[dict]:
    """:func:`audit_point` for the parallel runner (top level: picklable)."""
    return audit_point(point)


def summarise(rows: list[dict]) -> dict:
    """Counts: ``cases`` (rows settled), ``agree``, ``warned``, ``silent``, ``no_verdict`` (and by whom),
    ``refused``; the silent disagreements and the no-verdict rows listed."""
    settled = [r for r in rows if r["outcome"] != "refused"]
    count = {k: sum(r["outcome"] == k for r in settled) for k in ("agree", "warned", "silent", "no_verdict")}
    failed_by = {m: sum(1 for r in settled if r.get(f"{m}_error")) for m in ("default", "dynamics", "bvp")}
    default_alone = [r for r in settled if r.get("default_error") and (r.get("dynamics") or r.get("bvp"))]
    return {"cases": len(settled), **count, "refused": len(rows) - len(settled), "no_verdict_by": failed_by,
            "crashed": sum(1 for r in settled if r.get("crashed")),
            "default_failed_where_another_answered": len(default_alone),
            "silent_rows": [r for r in settled if r["outcome"] == "silent"],
            "no_verdict_rows": [r for r in settled if r["outcome"] == "no_verdict"]}


def run_audit(points: list[dict], *, jobs: int = 1, progress: bool = False) -> dict:
    """:func:`audit_point` over ``points`` (``jobs`` processes, :func:`simgrip.parallel.runner.run_tasks`);
    ``{"summary": summarise(rows), "rows": rows, "wall_time_s"}``."""
    from simgrip.parallel.runner import RunnerOptions, run_tasks

    t0 = time.perf_counter()
    per_point = run_tasks(_point_task, points, options=RunnerOptions(jobs=jobs, progress=progress),
                          desc="verdict audit", batch_size=1)
    rows = [r for pr in per_point for r in pr]
    return {"summary": summarise(rows), "rows": rows, "wall_time_s": time.perf_counter() - t0}


def _brief(r: dict) -> str:
    keys = ("grip", "variant", "kappa", "D", "M", "mu_s", "b", "gamma")
    head = ", ".join(f"{k}={r[k]:g}" if isinstance(r[k], float) else f"{k}={r[k]}" for k in keys)
    answers = "; ".join(f"{m}: {r[m] or r[f'{m}_error']}" for m in ("default", "dynamics", "bvp"))
    return f"- {head} -- {answers}"


def format_table(result: dict, command: str = "") -> str:
    """The audit's table (Markdown) with the silent disagreements and the no-verdict rows listed."""
    s = result["summary"]
    lines = ["# Verdict audit (issue 16 section 6)", ""]
    if command:
        lines += [f"Command: `{command}`", ""]
    lines += ["| cases | agreements | warned disagreements | silent disagreements | no verdict (named error) | "
              "refused inputs |", "|---|---|---|---|---|---|",
              f"| {s['cases']} | {s['agree']} | {s['warned']} | {s['silent']} | {s['no_verdict']} | {s['refused']} |",
              "", f"No verdict by method: {s['no_verdict_by']}; the default failed where another method answered: "
              f"{s['default_failed_where_another_answered']}; rows where a method crashed (an unnamed exception, "
              f"a bug; counted as no verdict, marked CRASH below): {s.get('crashed', 0)}.",
              f"Wall time: {result['wall_time_s']:.0f} s.", ""]
    by = {}
    for r in result["rows"]:
        if r["outcome"] != "refused":
            key = (r["grip"], r["variant"])
            by.setdefault(key, {"agree": 0, "warned": 0, "silent": 0, "no_verdict": 0})[r["outcome"]] += 1
    lines += ["| grip | variant | agree | warned | silent | no verdict |", "|---|---|---|---|---|---|"]
    lines += [f"| {g} | {v} | {c['agree']} | {c['warned']} | {c['silent']} | {c['no_verdict']} |"
              for (g, v), c in sorted(by.items())]
    lines += ["", "## Silent disagreements", ""] + ([_brief(r) for r in s["silent_rows"]] or ["none"])
    lines += ["", "## No verdict (a method raised a named error)", ""] + ([_brief(r) for r in s["no_verdict_rows"]]
                                                                          or ["none"])
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    """``python -m simgrip.harness.verdict_audit --out DIR [--jobs N] [--quick] [--no-progress]``."""
    from simgrip.io import atomic_write, check_output_dir, check_output_files_in, write_json

    ap = CommandParser(prog="python -m simgrip.harness.verdict_audit",
                                 description="hold/drop verdicts of the Newton settle, the dynamics and the BVP "
                                             "over the accepted parameter box (issue 16 section 6)")
    ap.add_argument("--out", required=True, help="folder for verdict_audit.json and verdict_audit.md")
    ap.add_argument("--jobs", type=int, default=1, help="worker processes [default 1]")
    ap.add_argument("--quick", action="store_true", help="the test suite's subset only")
    ap.add_argument("--no-progress", action="store_true")
    a = ap.parse_args(argv)
    try:
        if a.jobs < 1:
            raise ValueError(f"jobs must be a positive integer, got {a.jobs}")
        out = check_output_dir(a.out)
        json_path, md_path = check_output_files_in(out, ("verdict_audit.json", "verdict_audit.md"))
    except ValueError as exc:
        print(f"verdict_audit: {exc}", file=sys.stderr)
        return 2
    points = quick_points() if a.quick else audit_points()
    try:
        res = run_audit(points, jobs=a.jobs, progress=not a.no_progress)
    except KeyboardInterrupt:
        print("verdict_audit: interrupted", file=sys.stderr)
        return 130
    command = "python -m simgrip.harness.verdict_audit " + " ".join(sys.argv[1:] if argv is None else argv)
    write_json(json_path, res)
    with atomic_write(md_path) as fh:
        fh.write(format_table(res, command))
    s = res["summary"]
    print(f"cases {s['cases']}, agreements {s['agree']}, warned disagreements {s['warned']}, silent disagreements "
          f"{s['silent']}, no verdict {s['no_verdict']} (refused inputs {s['refused']}); {md_path}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

"""Numerical stress tests of the MuJoCo settle: every run ends settled or with a named error.

:func:`run_stress` builds and settles many scenes over the whole parameter box
(:mod:`simgrip.harness.stress_cases`: a grid and low-discrepancy draws, any
prefix spread over the box), one task of :func:`simgrip.parallel.runner.run_tasks`
per case; each case is self-contained, so its outcome does not depend on ``jobs``.

Each case ends as exactly one of

``settled``
    a finite state with ``converged = True`` and a static residual at most
    :data:`RESIDUAL_CAP` (``residual_above_tol`` records whether it is above
    settle's own tolerance, i.e. stopped at its noise floor);
``rejected``
    a ``ValueError`` whose message names the offending input (one of
    :data:`INPUT_NAMES`; e.g. a Grip III curvature that gives no starting
    shape); a ``ValueError`` that names no input is a failure;
``unsettled``
    a :class:`simgrip.settle.SettleError`: non-convergence reported loudly
    within the step budget (a named error, listed with its inputs);
``failed``
    anything else: another exception (NumPy's RuntimeWarnings are raised), a
    ValueError naming no input, a non-finite state, a returned state that is
    not converged (silent non-convergence), or a time-out (:data:`CASE_TIMEOUT_S`,
    a hang).

A settled state is also checked for physically invalid configurations, which
are reported as flags rather than returned quietly:

``self_intersection``
    the centreline crosses itself or two of its links are closer than their
    capsules allow (a rod curled beyond a full turn passes through itself: the
    point-contact chain has no self-collision);
``workpiece_entry``
    a link or the tip inside the held workpiece; ``fingers_cross``: two
    fingers through each other (all three: :func:`simgrip.validity.state_violations`,
    the one implementation every path runs, recomputed here from the returned
    geometry);
``tip_touches_workpiece``
    Grip III: the rod beyond the contact reaches the box's bottom face (the
    settle's own check, :func:`simgrip.validity.check_condition_23`: MuJoCo has
    no contact pair there); also ``tip_above_contact`` (the tip higher than
    the contact: the paper's condition 23 violated);
``wrong_grip``
    Grips I/II: the finger settled in the other grip's shape
    (:func:`simgrip.validity.check_grip_shape`);
``penetration``
    contact penetration above :data:`PENETRATION_TOL` (over ``l``).

A state the checks find impossible must come back reported so (``valid``
False, :func:`simgrip.validity.check_valid`); ``counts["invalid_returned_as_valid"]``
counts those that did not (any of the physical flags :data:`PHYSICAL_FLAGS`
set on a state whose ``valid`` is True): it must be 0.  (A rod beyond a full
turn is not in itself impossible: a spiral whose turns do not touch is a
state; the capsule distances decide.)

Full-contact cases (``contact="full"``, :func:`~simgrip.harness.stress_cases.make_full_cases`: Grips I, II
and the free rod past the point-contact onset, ``n <= 16``) run alongside too: the same outcomes and flags,
except that a settled state's residual is capped by the settle's own tolerance (the over-damped dynamics' creep
floor, :func:`simgrip.settle.dynamics.dynamics_tolerance`, not :data:`RESIDUAL_CAP`, which is the Newton
settle's); ``stress.json`` lists them under ``full`` with their own ``counts`` (``invalid_returned_as_valid``
included: must be 0) and ``max_penetration`` (over ``l``; flagged above :data:`PENETRATION_TOL`).

K-finger cases (off-centre, turned workpieces, unequal fingers;
:mod:`simgrip.harness.stress_gripper`) run alongside and are checked for
balance, finiteness and determinism; ``stress.json`` lists them under
``gripper``.

Outputs: ``stress.json`` (counts, every case with inputs and outcome, the
failures listed) and ``stability_map.png`` (per grip, ``kappa`` against
``log10 D``: easy, slow, dropped, rejected, unsettled, failed).
"""

from __future__ import annotations

import dataclasses
import math
import sys
import time
import traceback
import warnings
from dataclasses import dataclass, field

import numpy as np

from simgrip.harness.case_guard import INPUT_NAMES, names_an_input  # re-exported
from simgrip.harness.case_guard import CaseTimeout as _Timeout
from simgrip.harness.case_guard import deadline as _deadline
from simgrip.harness.stress_cases import BOX, FULL_BOX, GRIPS, make_cases, make_full_cases, stress_profile
from simgrip.io import check_output_dir, check_output_files_in, write_json

__all__ = [
    "StressResult",
    "run_stress",
    "make_cases",
    "run_case",
    "self_intersects",
    "invalid_state_flags",
    "PHYSICAL_FLAGS",
    "PENETRATION_TOL",
    "CASE_TIMEOUT_S",
    "MAX_STEPS",
    "RESIDUAL_CAP",
    "names_an_input",
    "add_arguments",
    "cli_stress",
    "default_full_cases",
    "full_summary",
]

#: The files run_stress writes into its folder (checked before any case runs).
OUTPUT_FILES = ("stress.json", "stability_map.png")
#: Contact penetration (over l) above which a settled state is flagged.
PENETRATION_TOL = 1e-3
#: Wall-clock guard of one case (s); a case that runs longer is a failure (hang).
CASE_TIMEOUT_S = 60.0
#: Step budget handed to settle (``None``: settle's own default budget).
MAX_STEPS = None
#: A "converged" state whose static residual exceeds this is a silent non-convergence (failure).
RESIDUAL_CAP = 1e-6
#: A settled case that needed more steps (settle's own count) than this is "slow".
SLOW_STEPS = 5000
OUTCOMES = ("settled", "rejected", "unsettled", "failed")
# ---------------------------------------------------------------------------
# invalid-state checks


#: The flags that make a state impossible (issue 17): a state with any of them must be reported ``valid`` False.
#: (Condition (23)'s, ``tip_touches_workpiece`` and ``tip_above_contact``, are the paper's verdict on the shape,
#: reported by ``tip_clear``: not feasible; a rod through the box beyond the contact is ``workpiece_entry`` too.)
PHYSICAL_FLAGS = ("self_intersection", "workpiece_entry", "fingers_cross")


def self_intersects(nodes) -> bool:
    """Whether the planar centreline ``nodes`` ``(n+1, 2)`` crosses itself (a proper crossing of two non-adjacent
    links; :func:`simgrip.intersection.crossing_pairs`, the one implementation)."""
    from simgrip.intersection import crossing_pairs

    return bool(crossing_pairs(np.asarray(nodes, dtype=float))[0].size)


def invalid_state_flags(scene, state, *, penetration_tol: float = PENETRATION_TOL) -> dict:
    """Physically invalid features of a settled state: name -> bool (see the module docstring).

    The geometric ones are :func:`simgrip.validity.state_violations` recomputed from the returned state
    (not read from its ``valid``), so that a state the settle failed to mark is counted.
    """
    from simgrip.validity import state_violations

    kinds = {k for k, _ in state_violations(scene, state)}
    flags = {
        "self_intersection": bool(kinds & {"self_crossing", "self_overlap"}),
        "workpiece_entry": "workpiece" in kinds,
        "fingers_cross": "fingers" in kinds,
        "penetration": bool(state.penetration > penetration_tol),
        "tip_touches_workpiece": not state.tip_clear,  # the settle's own check (simgrip.validity)
        "tip_above_contact": False,
        "wrong_grip": not state.grip_matched,
    }
    if scene.grip == "III" and state.contact is not None:
        flags["tip_above_contact"] = bool(state.tip[0][1] >= state.contact.point[1])
    return flags


# ---------------------------------------------------------------------------
# one case


def run_case(case: dict, *, timeout_s: float = CASE_TIMEOUT_S, max_steps: int | None = MAX_STEPS) -> dict:
    """Build and settle one case; return the case with ``outcome``, ``error``, ``steps``, flags..."""
    from simgrip.params import DimensionlessParams
    from simgrip.settle import DEFAULT_TOL, SettleError, settle
    from simgrip.sim.reuse import build_scene  # one compile per structure (grip, n), set in place

    rec = dict(case)
    rec.update(outcome=None, error=None, error_type=None, steps=None, newton=None, time_s=None,
               residual=None, held=None, penetration=None, flags={})
    t0 = time.perf_counter()
    try:
        # a NaN/overflow inside the solvers is a failure with a name, whatever the caller's warning filters
        with warnings.catch_warnings(), _deadline(timeout_s):
            warnings.simplefilter("error", RuntimeWarning)
            params = DimensionlessParams(D=case["D"], M=case["M"], b=case["b"], mu_s=case["mu_s"])
            prof = stress_profile(case["profile"], case["kappa"], case.get("alpha", 0.0))
            full = case.get("contact") == "full"
            scene = build_scene(case["grip"], params, prof, case["n"], **({"contact": "full"} if full else {}))
            st = settle(scene) if max_steps is None else settle(scene, max_steps=max_steps)
            cap = _full_residual_cap(scene) if full else RESIDUAL_CAP
        rec.update(steps=int(st.steps), newton=int(st.newton_iterations), residual=float(st.residual),
                   held=bool(st.held), penetration=float(st.penetration))
        finite = (np.all(np.isfinite(st.qpos)) and np.all(np.isfinite(st.tip)) and math.isfinite(st.residual)
                  and all(math.isfinite(c.N1) and math.isfinite(c.N2) for c in st.contacts))
        if not finite:
            rec.update(outcome="failed", error="non-finite settled state returned", error_type="NaN")
        elif not st.converged:
            rec.update(outcome="failed", error="state returned with converged=False", error_type="silent")
        elif not st.residual <= cap:
            rec.update(outcome="failed", error=f"converged=True with static residual {st.residual:.3g} > {cap:g}",
                       error_type="silent")
        else:
            rec["outcome"] = "settled"
            rec["flags"] = invalid_state_flags(scene, st)
            rec["valid"] = bool(getattr(st, "valid", True))
            # above the settle's own tolerance (Newton's DEFAULT_TOL; a full-contact state is already within its cap)
            rec["residual_above_tol"] = bool(st.residual > (cap if full else DEFAULT_TOL))
    except _Timeout:
        rec.update(outcome="failed", error=f"no answer within {timeout_s:g} s (hang)", error_type="Timeout")
    except ValueError as exc:
        if names_an_input(str(exc)):
            rec.update(outcome="rejected", error=str(exc), error_type=type(exc).__name__)
        else:  # a ValueError from inside the solver, not a rejected input
            rec.update(outcome="failed", error=f"unnamed ValueError: {exc}\n{traceback.format_exc(limit=4)}",
                       error_type=type(exc).__name__)
    except SettleError as exc:
        rec.update(outcome="unsettled", error=str(exc), error_type=type(exc).__name__)
    except Exception as exc:  # noqa: BLE001 - every other error (RuntimeWarning: NaN) is a failure, recorded
        rec.update(outcome="failed", error=f"{exc}\n{traceback.format_exc(limit=4)}", error_type=type(exc).__name__)
    rec["time_s"] = time.perf_counter() - t0
    return rec


def _full_residual_cap(scene) -> float:
    """The full-contact settle's own tolerance (its default ``tol``: the dynamics' creep floor,
    ``max(DYN_TOL, 2e-6 M)`` with a workpiece, ``DYN_TOL`` without): a converged state above it is silent."""
    from simgrip.settle.dynamics import DYN_TOL, dynamics_tolerance

    return float(dynamics_tolerance(scene) if scene.has_workpiece else DYN_TOL)


def default_full_cases(cases: int) -> int:
    """Full-contact cases in a stress run of ``cases`` planar cases: one per 100, at least 1, at most 5 (each is
    ~10-20 point-contact cases' time: the default 500-case run grows by about a tenth)."""
    return min(5, max(1, int(cases) // 100))


def full_summary(recs: list) -> dict:
    """The full-contact cases' ``counts`` (as :func:`_counts`), ``max_penetration`` over the settled ones (over
    ``l``; ``None`` if none settled), ``failures`` and ``cases``."""
    pens = [c["penetration"] for c in recs if c["outcome"] == "settled"]
    return {"counts": _counts(recs), "max_penetration": max(pens) if pens else None,
            "penetration_tol": PENETRATION_TOL, "box": FULL_BOX,
            "failures": [c for c in recs if c["outcome"] == "failed"], "cases": recs}


def _case_task(task: tuple) -> dict:
    """Runner task: ``task = (case, timeout_s, max_steps)``."""
    case, timeout_s, max_steps = task
    if case.get("kind") == "gripper":  # a K-finger case (simgrip.harness.stress_gripper)
        from simgrip.harness.stress_gripper import run_gripper_case

        return run_gripper_case(case, timeout_s=timeout_s)
    return run_case(case, timeout_s=timeout_s, max_steps=max_steps)


# ---------------------------------------------------------------------------
# driver


@dataclass
class StressResult:
    """What :func:`run_stress` found.

    Attributes
    ----------
    cases : list of dict
        Every case with its inputs, ``outcome`` (one of :data:`OUTCOMES`),
        ``error``, ``steps``, ``held``, ``penetration`` and ``flags``.
    counts : dict
        outcome -> number of cases, plus ``flagged`` (settled with any flag)
        and one count per flag.
    failures : list of dict
        The ``failed`` cases (inputs and error).
    files : dict
    """

    cases: list
    counts: dict
    failures: list
    files: dict = field(default_factory=dict)
    elapsed_s: float = 0.0
    #: The K-finger cases: ``counts``, ``cases``, ``failures`` (:mod:`simgrip.harness.stress_gripper`).
    gripper: dict = field(default_factory=dict)
    jobs: int = 1
    #: The full-contact cases: ``counts``, ``max_penetration``, ``failures``, ``cases`` (:func:`full_summary`).
    full: dict = field(default_factory=dict)

    @property
    def unsettled(self) -> list:
        return [c for c in self.cases if c["outcome"] == "unsettled"]

    @property
    def rejected(self) -> list:
        return [c for c in self.cases if c["outcome"] == "rejected"]


def _counts(cases) -> dict:
    counts = {k: 0 for k in OUTCOMES}
    flag_counts: dict = {}
    flagged = 0
    dropped = 0
    for c in cases:
        counts[c["outcome"]] += 1
        if c["outcome"] == "settled":
            if any(c["flags"].values()):
                flagged += 1
            for k, v in c["flags"].items():
                flag_counts[k] = flag_counts.get(k, 0) + int(bool(v))
            if c["grip"] != "free" and c["held"] is False:
                dropped += 1
    counts["total"] = len(cases)
    counts["flagged"] = flagged
    counts["dropped"] = dropped
    counts["flags"] = flag_counts
    counts["residual_above_tol"] = sum(1 for c in cases if c.get("residual_above_tol"))
    counts["invalid_returned_as_valid"] = sum(
        1 for c in cases if c["outcome"] == "settled" and c.get("valid", True)
        and any(c["flags"].get(k) for k in PHYSICAL_FLAGS))
    return counts


def run_stress(
    out_dir,
    *,
    cases: int = 500,
    seed: int = 0,
    jobs: int | None = None,
    progress: bool = True,
    timeout_s: float = CASE_TIMEOUT_S,
    max_steps: int | None = MAX_STEPS,
    grid_cases: int | None = None,
    max_links: int = 256,
    options=None,
    gripper_cases: int | None = None,
    full_cases: int | None = None,
) -> StressResult:
    """Run the stress cases of :func:`make_cases` and write ``stress.json`` and ``stability_map.png``.

    Parameters
    ----------
    out_dir : path
        Destination folder (created; checked before any work).
    cases : int
        Number of cases (grid and random draws, see :mod:`simgrip.harness.stress_cases`); with
        ``gripper_cases`` bounded before any case is made (:func:`simgrip.sweep.budget.check_stress`:
        at most 10^6, half the available memory, 7 days at 0.15 s a case and worker; ValueError naming it).
    seed : int
        Seed of the random draws.
    jobs : int, optional
        Worker processes (default: all cores); 1 runs in this process.
        The outcome of every case does not depend on ``jobs``.  Capped at the
        number of cases, 2 per core and what memory holds (a note on stderr),
        refused above :data:`simgrip.sweep.budget.MAX_JOBS`.
    progress : bool
        Progress bar.
    timeout_s, max_steps
        Per-case guards: wall clock (a hang is a failure) and settle's step budget.
    grid_cases : int, optional
        Use only this many grid cases (the first in their spread-out order).
    max_links : int
        Largest ``n`` (256 by default; smaller for quick runs).
    options : simgrip.parallel.runner.RunnerOptions, optional
        How to run (e.g. on an existing Dask cluster); replaces ``jobs`` and ``progress``.
    gripper_cases : int, optional
        K-finger cases run alongside (default :func:`~simgrip.harness.stress_gripper.default_gripper_cases`).
    full_cases : int, optional
        Full-contact cases run alongside (default :func:`default_full_cases`;
        :func:`~simgrip.harness.stress_cases.make_full_cases`, ``n <= min(16, max_links)``).
    """
    from simgrip.harness.plots import stability_map
    from simgrip.parallel.runner import RunnerOptions, run_tasks

    from simgrip.sweep.budget import cap_jobs, check_stress

    options = RunnerOptions(jobs=jobs, progress=progress) if options is None else options
    if isinstance(cases, bool) or not isinstance(cases, (int, np.integer)) or cases < 1:
        raise ValueError(f"cases must be an integer >= 1, got {cases!r}")
    from simgrip.harness import stress_gripper as sg

    n_gripper = sg.default_gripper_cases(cases) if gripper_cases is None else gripper_cases
    if isinstance(n_gripper, bool) or not isinstance(n_gripper, (int, np.integer)) or n_gripper < 0:
        raise ValueError(f"gripper_cases must be an integer >= 0, got {gripper_cases!r}")
    n_full = default_full_cases(cases) if full_cases is None else full_cases
    if isinstance(n_full, bool) or not isinstance(n_full, (int, np.integer)) or n_full < 0:
        raise ValueError(f"full_cases must be an integer >= 0, got {full_cases!r}")
    if not options.remote:  # jobs: at most the tasks, 2 per core, what memory holds; refused above MAX_JOBS
        capped, why = cap_jobs(options.jobs, int(cases) + int(n_gripper) + int(n_full))
        if why:
            print(f"simgrip stress: {why}", file=sys.stderr, flush=True)
        if capped != options.jobs:
            options = dataclasses.replace(options, jobs=capped)
    workers = None if options.remote else (1 if options.in_process else options.local_workers)
    # before any case is made: memory and time bounded (a full-contact case counted as FULL_CASE_WEIGHT cases)
    check_stress(int(cases), int(n_gripper), full_cases=int(n_full), workers=workers)
    todo = make_cases(cases, seed, grid_cases, max_links)
    g_todo = sg.make_gripper_cases(n_gripper, seed, max_links=min(32, max_links))
    f_todo = make_full_cases(int(n_full), seed, max_links=min(16, max_links))
    out = check_output_dir(out_dir, option="out_dir")
    check_output_files_in(out, OUTPUT_FILES, "out_dir")  # refused before the cases run
    t0 = time.perf_counter()
    heavy_first = sorted(todo, key=lambda c: -c["n"])  # large n first: the last batches finish together
    # one run: the K-finger and full-contact cases (the slow ones) first
    tasks = [(c, timeout_s, max_steps) for c in g_todo + f_todo + heavy_first]
    done, g_done, f_done = {}, {}, {}
    for rec in run_tasks(_case_task, tasks, options=options, desc="stress"):
        kind = "gripper" if rec.get("kind") == "gripper" else rec.get("contact")
        {"gripper": g_done, "full": f_done}.get(kind, done)[rec["id"]] = rec
    recs = [done[c["id"]] for c in todo]
    full = full_summary([f_done[c["id"]] for c in f_todo])
    g_recs = [g_done[c["id"]] for c in g_todo]
    gripper = {"counts": sg.gripper_counts(g_recs), "failures": [c for c in g_recs if c["outcome"] == "failed"],
               "cases": g_recs}
    counts = _counts(recs)
    failures = [c for c in recs if c["outcome"] == "failed"]
    workers = 1 if options.in_process else (options.local_workers if not options.remote else None)
    res = StressResult(cases=recs, counts=counts, failures=failures, elapsed_s=time.perf_counter() - t0, jobs=workers,
                       gripper=gripper, full=full)
    write_json(out / "stress.json", {
        "meta": {"cases": len(recs), "seed": seed, "jobs": workers, "elapsed_s": res.elapsed_s,
                 "timeout_s": timeout_s, "max_steps": max_steps, "penetration_tol": PENETRATION_TOL,
                 "residual_cap": RESIDUAL_CAP, "max_links": max_links, "grid_cases": grid_cases,
                 "slow_steps": SLOW_STEPS, "box": BOX},
        "counts": counts,
        "failures": failures,
        "unsettled": res.unsettled,
        "flagged": [c for c in recs if c["outcome"] == "settled" and any(c["flags"].values())],
        "cases": recs,
        "gripper": gripper,
        "full": full,
    })
    stability_map([{**c, "category": _category(c)} for c in recs], GRIPS, SLOW_STEPS, out / "stability_map.png")
    res.files = {"stress.json": out / "stress.json", "stability_map.png": out / "stability_map.png"}
    return res


def _category(c) -> str:
    if c["outcome"] != "settled":
        return c["outcome"]
    if any(c["flags"].values()):  # before "dropped": an invalid state's verdict means nothing (stress.json's count)
        return "flagged"
    if c["grip"] != "free" and c["held"] is False:
        return "dropped"
    return "slow" if (c["steps"] or 0) > SLOW_STEPS else "easy"


def add_arguments(p) -> None:
    """Add the options of ``simgrip stress`` (and the runner's) to an argparse parser."""
    from simgrip.parallel.runner import add_runner_arguments

    p.add_argument("--cases", type=int, default=500, help="number of cases [default 500]")
    p.add_argument("--seed", type=int, default=0, help="seed of the random cases [default 0]")
    p.add_argument("--out", default="stress_out", help="output folder [default stress_out]")
    p.add_argument("--gripper-cases", type=int, default=None,
                   help="K-finger cases (off-centre, turned, unequal fingers) [default: one per 50 cases, 1..8]")
    p.add_argument("--full-cases", type=int, default=None,
                   help="full-contact cases (contact='full': Grips I, II and the free rod past the point-contact "
                   "onset, n <= 16, ~0.5-4 s each) [default: one per 100 cases, 1..5]")
    add_runner_arguments(p)


def cli_stress(args) -> dict:
    """Run the stress test from parsed arguments; returns the counts and the failures (the CLI checked ``--out`` first)."""
    from simgrip.parallel.runner import runner_options

    full_cases = getattr(args, "full_cases", None)
    if full_cases is not None and full_cases < 0:
        raise ValueError(f"--full-cases must be an integer >= 0, got {full_cases!r}")
    res = run_stress(args.out, cases=args.cases, seed=args.seed, options=runner_options(args),
                     gripper_cases=args.gripper_cases, full_cases=full_cases)
    return {"out": str(args.out), "counts": res.counts, "gripper_counts": res.gripper["counts"],
            "gripper_failures": [{k: c[k] for k in ("id", "grip", "workpiece", "fingers", "error")}
                                 for c in res.gripper["failures"]],
            "full_counts": res.full["counts"], "full_max_penetration": res.full["max_penetration"],
            "full_failures": [{k: c[k] for k in ("id", "grip", "D", "kappa", "M", "mu_s", "b", "n", "error")}
                              for c in res.full["failures"]],
            "failures": [{k: c[k] for k in ("id", "grip", "D", "kappa", "M", "mu_s", "b", "n", "profile", "error")}
                         for c in res.failures]}

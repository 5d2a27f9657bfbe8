"""One point of a design sweep: the settled simulation beside the elastica BVP at the same parameters.

:func:`evaluate_point` is the function the sweep's workers run.  It never
raises for a point's sake: a point the grip cannot build (``ValueError``) is
``rejected``, a settle that fails (``SettleError`` or any solver's
``RuntimeError``) is ``unsettled``, anything else is ``error``, each with its
message; the BVP is solved independently of the simulation
(:func:`simgrip.reference.elastica.solve` at the point's own parameters,
uniform curvature) and its failure leaves the ``bvp_*`` columns empty with
``bvp_message``.  All the physics comes from the library's public functions
(:func:`simgrip.compare.simulate`, :func:`simgrip.compare.settled_record`,
:func:`simgrip.reference.elastica.solve`).

The reference at the cost of a continuation (:func:`evaluate_segment`): along
a segment of the grid (:meth:`simgrip.sweep.grid.SweepGrid.segments`, fixed by
the grid alone) the first point's BVP is solved cold, exactly as
:func:`evaluate_point` does, and each next one by one ``solve_bvp`` run at the
final tolerance started from its predecessor's solution and mesh
(:func:`warm_bvp`, ~4x cheaper than the cold start at n = 32).  A warm start
that does not converge is replaced by the cold solve.  A warm start whose
``theta`` moves by more than the solver's own branch-jump bound
(:data:`simgrip.reference.continuation.MAX_JUMP`) is checked against the cold
solve: when they are different equilibria the cold one is kept (the point's
reference is then exactly the per-point one) and ``bvp_warning`` says so.
The verdicts are those of cold solves at every point (tested on grids that
cross the hold/drop boundary); the references agree to the solver's tolerance.
With ``reference="none"`` no BVP is solved: ``bvp_*`` and ``agree`` are empty,
``bvp_message`` and ``bvp_warning`` too (a failed BVP always has a message).

Columns (:data:`COLUMNS`, dimensionless: lengths over ``l``, forces over
``rho g l``):

* the parameters, :data:`simgrip.sweep.grid.AXES`;
* ``status`` (settled / unsettled / rejected / error), ``held`` (the
  simulation holds the workpiece), ``feasible`` (held and, Grip III, condition
  (23): the simulation's hold/drop verdict), ``valid`` (no link through itself or the
  workpiece, :func:`simgrip.validity.check_valid`), ``normal_force``, ``required_mu``
  (``|friction| / normal`` at the contact, 0 when dropped), ``tip_x``,
  ``tip_z`` (finger 0's tip in its base frame, z up), ``penetration``;
* ``bvp_normal_force``, ``bvp_feasible``, ``bvp_required_mu`` (``inf`` when the
  normal force is not positive);
* ``agree``: ``feasible == bvp_feasible`` (empty when either is missing);
* ``wall_time_s`` (the settle's own time) and ``point_time_s`` (the whole
  point in the worker: build, settle, record and BVP); the only columns that
  change from run to run (:data:`TIME_COLUMNS`);
* ``message``, ``bvp_message``: why a point has no result, or the settled
  state's warnings;
* ``bvp_warning``: the warm-started reference jumped branch and was solved
  cold (empty otherwise).
"""

from __future__ import annotations

import math
import time

import numpy as np

from simgrip.sweep.grid import AXES, SweepPoint

__all__ = ["COLUMNS", "TIME_COLUMNS", "STATUSES", "SAME_BRANCH_RAD", "evaluate_point", "evaluate_segment",
           "warm_bvp"]

SIM_COLUMNS = ("status", "held", "feasible", "valid", "normal_force", "required_mu", "tip_x", "tip_z", "penetration")
BVP_COLUMNS = ("bvp_normal_force", "bvp_feasible", "bvp_required_mu")
#: Every column of ``sweep.csv``, in order.
COLUMNS = AXES + SIM_COLUMNS + BVP_COLUMNS + ("agree", "wall_time_s", "point_time_s", "message", "bvp_message",
                                              "bvp_warning")
#: Columns that are timings (they differ between runs; everything else is reproducible).
TIME_COLUMNS = ("wall_time_s", "point_time_s")
#: Two converged references (tolerance 1e-8) whose ``theta`` differ by less than this [rad] are one equilibrium:
#: the same branch solved twice agrees to ~1e-7 rad (the collocation tolerance carried through the mesh), while
#: distinct equilibria of a grip differ by O(0.1-1) rad; 1e-3 sits far from both.
SAME_BRANCH_RAD = 1e-3
#: A warm start may reuse its predecessor's mesh up to this many nodes (solve_bvp only adds nodes; above it the
#: mesh is thinned as the solver's own continuation does, so meshes do not grow along a segment).
_WARM_NODES = 1200
#: Values of ``status``.
STATUSES = ("settled", "unsettled", "rejected", "error")


def _message(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}".replace("\n", " ")


def _simulation(point: SweepPoint) -> dict:
    from simgrip.compare import settled_record, simulate
    from simgrip.profiles import Uniform

    out = {c: None for c in SIM_COLUMNS}
    out.update(wall_time_s=None, message="")
    try:
        params = point.params()
        state = simulate(point.grip, params, Uniform(point.kappa), point.links, method=point.method)
        rec = settled_record(state, params)
    except ValueError as exc:
        out.update(status="rejected", message=_message(exc))
        return out
    except RuntimeError as exc:  # SettleError, DiscreteError, ...: a solver that could not, said so
        out.update(status="unsettled", message=_message(exc))
        return out
    except Exception as exc:  # noqa: BLE001 - a failing point is recorded, never stops the sweep
        out.update(status="error", message=_message(exc))
        return out
    out.update(
        status="settled" if rec["converged"] else "unsettled",
        held=bool(rec["held"]),
        feasible=bool(rec["feasible"]),
        valid=bool(rec.get("valid", True)),
        normal_force=float(rec["normal_force"]),
        required_mu=float(rec["required_mu"]),
        tip_x=float(rec["tip"][0]),
        tip_z=float(rec["tip"][1]),
        penetration=float(rec["penetration"]),
        wall_time_s=float(rec["wall_time_s"]),
        message="; ".join(str(w) for w in rec.get("warnings", ())),
    )
    return out


def _cold(point: SweepPoint):
    from simgrip.profiles import Uniform
    from simgrip.reference import elastica

    return elastica.solve(point.grip, point.params(), Uniform(point.kappa))


def warm_bvp(point: SweepPoint, guess):
    """The BVP of ``point`` by one ``solve_bvp`` run at the final tolerance (1e-8, :func:`elastica.solve`'s)
    from the converged ``guess`` (an :class:`~simgrip.reference.elastica.ElasticaSolution` of a neighbouring
    point: its mesh, states and unknown parameters); ``None`` when that run does not converge."""
    from simgrip.profiles import Uniform
    from simgrip.reference import elastica
    from simgrip.reference.bvp import run_bvp
    from simgrip.reference.continuation import _mesh_guess

    grip, params, P = elastica.checked_problem(point.grip, point.params(), Uniform(point.kappa))
    raw = guess._raw
    if raw.prob.two_seg == P.two_seg and raw.prob.constrained == P.constrained and raw.x.size <= _WARM_NODES \
            and (not P.two_seg or raw.prob.gamma == P.gamma):
        x, y, p = raw.x, raw.y, (raw.p if P.constrained else None)
    else:
        x, y, p = _mesh_guess(raw, P)
    r = run_bvp(P, x, y, p, 1e-8)
    return None if r is None else elastica.ElasticaSolution.from_bvp(grip, params, r)


def _theta_gap(a, b) -> float:
    """Largest difference of ``theta`` between two references on the solver's branch-jump grid [rad]."""
    from simgrip.reference.continuation import _JUMP_GRID

    return float(np.max(np.abs(a._raw.states(_JUMP_GRID)[0] - b._raw.states(_JUMP_GRID)[0])))


def _reference(point: SweepPoint, guess):
    """``(solution, warning)`` of ``point``'s BVP: cold without ``guess``, else warm (see the module docstring)."""
    from simgrip.reference.continuation import MAX_JUMP

    if guess is None:
        return _cold(point), ""
    sol = warm_bvp(point, guess)
    if sol is None:
        return _cold(point), ""
    jump = _theta_gap(guess, sol)
    if jump <= MAX_JUMP:
        return sol, ""
    cold = _cold(point)  # a large step: the branch is checked against the per-point solve
    gap = _theta_gap(cold, sol)
    if gap <= SAME_BRANCH_RAD:
        return cold, ""
    return cold, (f"the warm-started BVP jumped branch (theta moved {jump:.3g} rad from the previous point, "
                  f"{gap:.3g} rad from the cold solve): solved cold")


def _bvp(point: SweepPoint, guess=None) -> tuple[dict, object]:
    out = {c: None for c in BVP_COLUMNS}
    out.update(bvp_message="", bvp_warning="")
    if point.reference == "none":
        return out, None
    try:
        sol, warning = _reference(point, guess)
    except Exception as exc:  # noqa: BLE001 - ElasticaError, ValueError, ...: recorded with the point
        out["bvp_message"] = _message(exc)
        return out, None
    out.update(bvp_normal_force=float(sol.normal_force), bvp_feasible=bool(sol.feasible),
               bvp_required_mu=float(sol.required_mu), bvp_warning=warning)
    return out, sol


def _evaluate(point: SweepPoint, guess) -> tuple[dict, object]:
    t0 = time.perf_counter()
    rec = {"index": int(point.index)}
    rec.update(point.values())
    sim = _simulation(point)
    bvp, sol = _bvp(point, guess)
    rec.update(sim)
    rec.update(bvp)
    if sim["feasible"] is None or bvp["bvp_feasible"] is None:
        rec["agree"] = None
    else:
        rec["agree"] = bool(sim["feasible"] == bvp["bvp_feasible"])
    for k in ("normal_force", "required_mu", "tip_x", "tip_z", "penetration", "bvp_normal_force"):
        v = rec[k]
        if v is not None and math.isnan(v):
            rec[k] = None
    rec["point_time_s"] = time.perf_counter() - t0
    return {"index": rec["index"], **{c: rec[c] for c in COLUMNS}}, sol


def evaluate_point(point: SweepPoint) -> dict:
    """Settle and solve ``point`` (its BVP cold); returns a record with ``index`` and every one of :data:`COLUMNS`.

    Never raises for the point's sake (see the module docstring); floats are
    plain Python floats, flags plain bools, a missing value ``None``.
    """
    return _evaluate(point, None)[0]


def evaluate_segment(points) -> list[dict]:
    """Records of consecutive ``points`` of one segment (:meth:`~simgrip.sweep.grid.SweepGrid.segments`), in
    order: the first point's BVP solved cold, each next warm-started from the last converged one (see the
    module docstring).  Every point is settled from scratch, as by :func:`evaluate_point`."""
    out, guess = [], None
    for p in points:
        rec, sol = _evaluate(p, guess)
        out.append(rec)
        if sol is not None:
            guess = sol
    return out

"""One point of a design sweep: the settled simulation beside the elastica BVP at the same parameters.

:func:`evaluate_segment` is the function the sweep's workers run
(:func:`evaluate_point`: one point alone).  It never raises for a point's
sake: a point the grip cannot build (``ValueError``) is
``rejected``, a settle that fails (``SettleError`` or any solver's
``RuntimeError``) is ``unsettled``, anything else is ``error``, each with its
message; the BVP is solved independently of the simulation
(:func:`simgrip.reference.elastica.solve` at the point's own parameters,
uniform curvature; none for a full-contact sweep,
:mod:`simgrip.sweep.grid`) and its failure leaves the ``bvp_*`` columns empty with
``bvp_message``.  All the physics comes from the library's public functions
(:func:`simgrip.compare.simulate`, :func:`simgrip.settled.verdict_fields`,
:func:`simgrip.reference.elastica.solve`).

The reference at the cost of a continuation (:func:`evaluate_segment`): along
a segment of the grid (:meth:`simgrip.sweep.grid.SweepGrid.segments`, fixed by
the grid alone) the references are warm-started from their neighbours (a
predictor and chord Newton steps on the collocation equations of ``solve_bvp``)
and checked against the cold solve's path at the ends, where the walk is kept
only when it ends on the cold solve's branch (:mod:`simgrip.sweep.reference`): each equals
the point's cold solve (:func:`evaluate_point`) to the solver's tolerance, so
the verdicts are those of cold solves.  A point whose warm start reached
another branch is solved cold and ``bvp_warning`` says so.
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
* ``bvp_warning``: the warm-started reference reached another branch than
  the cold solve and was solved cold (empty otherwise).
"""

from __future__ import annotations

import math
import time

from simgrip.sweep.grid import AXES, SweepPoint

__all__ = ["COLUMNS", "TIME_COLUMNS", "STATUSES", "evaluate_point", "evaluate_segment"]

SIM_COLUMNS = ("status", "held", "feasible", "valid", "normal_force", "required_mu", "tip_x", "tip_z", "penetration")
BVP_COLUMNS = ("bvp_normal_force", "bvp_feasible", "bvp_required_mu")
#: Every column of ``sweep.csv``, in order.
COLUMNS = AXES + SIM_COLUMNS + BVP_COLUMNS + ("agree", "wall_time_s", "point_time_s", "message", "bvp_message",
                                              "bvp_warning")
#: Columns that are timings (they differ between runs; everything else is reproducible).
TIME_COLUMNS = ("wall_time_s", "point_time_s")
#: Values of ``status``.
STATUSES = ("settled", "unsettled", "rejected", "error")


def _message(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}".replace("\n", " ")


def _simulation(point: SweepPoint) -> dict:
    from simgrip.compare import simulate
    from simgrip.profiles import Uniform
    from simgrip.settled import verdict_fields  # (settled_record's fields, less its node/contact lists)

    out = {c: None for c in SIM_COLUMNS}
    out.update(wall_time_s=None, message="")
    try:
        params = point.params()
        state = simulate(point.grip, params, Uniform(point.kappa), point.links, method=point.method,
                         **point.settle_options())
        rec = verdict_fields(state)
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
        valid=bool(rec["valid"]),
        normal_force=float(rec["normal_force"]),
        required_mu=float(rec["required_mu"]),
        tip_x=float(rec["tip"][0]),
        tip_z=float(rec["tip"][1]),
        penetration=float(rec["penetration"]),
        wall_time_s=float(rec["wall_time_s"]),
        message="; ".join(str(w) for w in rec["warnings"]),
    )
    return out


def _bvp_columns(sol, error: str, warning: str) -> dict:
    out = {c: None for c in BVP_COLUMNS}
    out.update(bvp_message=error, bvp_warning=warning)
    if sol is not None:
        out.update(bvp_normal_force=float(sol.normal_force), bvp_feasible=bool(sol.feasible),
                   bvp_required_mu=float(sol.required_mu))
    return out


def _record(point: SweepPoint, bvp: dict, bvp_seconds: float) -> dict:
    t0 = time.perf_counter()
    rec = {"index": int(point.index)}
    rec.update(point.values())
    sim = _simulation(point)
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
    rec["point_time_s"] = time.perf_counter() - t0 + bvp_seconds
    return {"index": rec["index"], **{c: rec[c] for c in COLUMNS}}


def _references(points: list) -> list[tuple]:
    """``(bvp columns, seconds)`` of each point: none, or the segment's references (:mod:`simgrip.sweep.reference`)."""
    from simgrip.sweep.reference import segment_references

    if not points or points[0].reference == "none":
        return [(_bvp_columns(None, "", ""), 0.0) for _ in points]
    return [(_bvp_columns(sol, err, warn), sec) for sol, err, warn, sec in segment_references(points)]


def evaluate_point(point: SweepPoint) -> dict:
    """Settle and solve ``point`` (its BVP cold); returns a record with ``index`` and every one of :data:`COLUMNS`.

    Never raises for the point's sake (see the module docstring); floats are
    plain Python floats, flags plain bools, a missing value ``None``.
    """
    return evaluate_segment([point])[0]


def evaluate_segment(points) -> list[dict]:
    """Records of consecutive ``points`` of one segment (:meth:`~simgrip.sweep.grid.SweepGrid.segments`), in
    order: every point settled from scratch, as by :func:`evaluate_point`; the BVP references of the segment
    at the cost of a continuation, each equal to the point's cold solve to the solver's tolerance
    (:func:`simgrip.sweep.reference.segment_references`)."""
    points = list(points)
    return [_record(p, bvp, sec) for p, (bvp, sec) in zip(points, _references(points))]

"""One point of a design sweep: the settled simulation beside the elastica BVP at the same parameters.

:func:`evaluate_point` is the function the sweep's workers run.  It never
raises for a point's sake: a point the grip cannot build (``ValueError``) is
``rejected``, a settle that fails (``SettleError`` or any solver's
``RuntimeError``) is ``unsettled``, anything else is ``error``, each with its
message; the BVP is solved independently (:func:`simgrip.reference.elastica.solve`
at the point's own parameters, uniform curvature) and its failure leaves the
``bvp_*`` columns empty with ``bvp_message``.  All the physics comes from the
library's public functions (:func:`simgrip.compare.simulate`,
:func:`simgrip.compare.settled_record`, :func:`simgrip.reference.elastica.solve`).

Columns (:data:`COLUMNS`, dimensionless: lengths over ``l``, forces over
``rho g l``):

* the parameters, :data:`simgrip.sweep.grid.AXES`;
* ``status`` (settled / unsettled / rejected / error), ``held`` (the
  simulation holds the workpiece), ``feasible`` (held and, Grip III, condition
  (23): the simulation's hold/drop verdict), ``normal_force``, ``required_mu``
  (``|friction| / normal`` at the contact, 0 when dropped), ``tip_x``,
  ``tip_z`` (finger 0's tip in its base frame, z up), ``penetration``;
* ``bvp_normal_force``, ``bvp_feasible``, ``bvp_required_mu`` (``inf`` when the
  normal force is not positive);
* ``agree``: ``feasible == bvp_feasible`` (empty when either is missing);
* ``wall_time_s`` (the settle's own time; the only column that changes from run to run);
* ``message``, ``bvp_message``: why a point has no result, or the settled
  state's warnings.
"""

from __future__ import annotations

import math

from simgrip.sweep.grid import AXES, SweepPoint

__all__ = ["COLUMNS", "TIME_COLUMNS", "STATUSES", "evaluate_point"]

SIM_COLUMNS = ("status", "held", "feasible", "normal_force", "required_mu", "tip_x", "tip_z", "penetration")
BVP_COLUMNS = ("bvp_normal_force", "bvp_feasible", "bvp_required_mu")
#: Every column of ``sweep.csv``, in order.
COLUMNS = AXES + SIM_COLUMNS + BVP_COLUMNS + ("agree", "wall_time_s", "message", "bvp_message")
#: Columns that are timings (they differ between runs; everything else is reproducible).
TIME_COLUMNS = ("wall_time_s",)
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
        normal_force=float(rec["normal_force"]),
        required_mu=float(rec["required_mu"]),
        tip_x=float(rec["tip"][0]),
        tip_z=float(rec["tip"][1]),
        penetration=float(rec["penetration"]),
        wall_time_s=float(rec["wall_time_s"]),
        message="; ".join(str(w) for w in rec.get("warnings", ())),
    )
    return out


def _bvp(point: SweepPoint) -> dict:
    from simgrip.profiles import Uniform
    from simgrip.reference import elastica

    out = {c: None for c in BVP_COLUMNS}
    out["bvp_message"] = ""
    try:
        sol = elastica.solve(point.grip, point.params(), Uniform(point.kappa))
    except Exception as exc:  # noqa: BLE001 - ElasticaError, ValueError, ...: recorded with the point
        out["bvp_message"] = _message(exc)
        return out
    out.update(bvp_normal_force=float(sol.normal_force), bvp_feasible=bool(sol.feasible),
               bvp_required_mu=float(sol.required_mu))
    return out


def evaluate_point(point: SweepPoint) -> dict:
    """Settle and solve ``point``; returns a record with ``index`` and every one of :data:`COLUMNS`.

    Never raises for the point's sake (see the module docstring); floats are
    plain Python floats, flags plain bools, a missing value ``None``.
    """
    rec = {"index": int(point.index)}
    rec.update(point.values())
    sim = _simulation(point)
    bvp = _bvp(point)
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
    return {"index": rec["index"], **{c: rec[c] for c in COLUMNS}}

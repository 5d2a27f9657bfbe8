"""Flat records of settled states for the command line and results files.

A record is a plain ``dict`` with the same keys whether it comes from the
elastica reference or from a simulation, so the two can be printed side by
side and differenced.  All values are dimensionless: lengths over ``l``,
forces on the rod over ``rho g l``, z up, the finger's base at the origin.

Keys common to every grip: ``grip``, ``tip`` ``[x, z]``, ``normal_force``,
``friction_force``, ``required_mu``, ``feasible``, ``min_eigenvalue``, ``N1``,
``N2``; Grip III adds ``contact`` ``[x, z]``, ``gamma``, ``n``, ``f`` and
``tip_clear``.
"""

from __future__ import annotations

import math
import time

import numpy as np

from simgrip.params import DimensionlessParams

__all__ = ["elastica_record", "solve_record", "format_table", "format_comparison", "difference"]

#: Keys printed first, in this order, by :func:`format_table`.
_ORDER = (
    "source",
    "grip",
    "tip",
    "contact",
    "gamma",
    "normal_force",
    "friction_force",
    "N1",
    "N2",
    "n",
    "f",
    "required_mu",
    "feasible",
    "tip_clear",
    "min_eigenvalue",
)


def _params_record(params: DimensionlessParams) -> dict:
    return {"D": params.D, "M": params.M, "b": params.b, "mu_s": params.mu_s, "gamma": params.gamma}


def elastica_record(sol, min_eigenvalue: float | None = None) -> dict:
    """Record of an :class:`~simgrip.reference.elastica.ElasticaSolution` (plus the discrete stability eigenvalue)."""
    rec = {
        "source": "elastica",
        "grip": sol.grip,
        "tip": [float(sol.tip[0]), float(sol.tip[1])],
        "normal_force": float(sol.normal_force),
        "friction_force": float(sol.friction_force),
        "required_mu": float(sol.required_mu),
        "feasible": bool(sol.feasible),
        "min_eigenvalue": None if min_eigenvalue is None else float(min_eigenvalue),
        "N1": float(sol.N1),
        "N2": float(sol.N2),
        "residual": float(sol.residual),
        "success": bool(sol.success),
        "params": _params_record(sol.params),
        "profile": repr(sol.profile),
    }
    if sol.grip == "III":
        rec.update(
            contact=[float(sol.contact[0]), float(sol.contact[1])],
            gamma=float(sol.gamma),
            n=float(sol.n),
            f=float(sol.f),
            tip_clear=bool(sol.feasibility.get("tip_clear", True)),
        )
    return rec


def solve_record(grip: str, params: DimensionlessParams, profile, *, K: int = 128) -> dict:
    """Solve the elastica BVP and the paper's discrete stability problem; return the record.

    ``min_eigenvalue`` is :func:`simgrip.reference.stability_eigenvalue` of the
    paper's nodal scheme with ``K`` elements at the BVP solution: the smallest
    eigenvalue of the projected Hessian in the ``L^2`` metric (over ``rho g l``),
    the same normalisation as the hinge chain's.  ``wall_time_s`` is the BVP solve alone
    (no start-up, no stability check), comparable with ``simulate``'s settle time.
    """
    from simgrip.reference import DiscreteError, elastica, stability_eigenvalue

    t0 = time.perf_counter()
    sol = elastica.solve(grip, params, profile)
    wall = time.perf_counter() - t0
    try:
        lam = stability_eigenvalue(sol, K)
    except DiscreteError:
        lam = math.nan
    rec = elastica_record(sol, lam)
    rec["wall_time_s"] = wall
    return rec


def _fmt(value) -> str:
    if isinstance(value, (list, tuple, np.ndarray)):
        return "[" + ", ".join(_fmt(v) for v in value) + "]"
    if isinstance(value, bool) or value is None:
        return str(value)
    if isinstance(value, float):
        if math.isinf(value):  # e.g. required_mu when the normal force is not positive
            return "unbounded" if value > 0 else "-unbounded"
        return f"{value:.8g}"
    return str(value)


def format_table(record: dict) -> str:
    """A two-column, human-readable table of a record."""
    keys = [k for k in _ORDER if k in record] + [k for k in record if k not in _ORDER and k != "params"]
    width = max(len(k) for k in keys)
    lines = [f"{k:<{width}}  {_fmt(record[k])}" for k in keys]
    if "params" in record:
        lines.append(f"{'params':<{width}}  " + ", ".join(f"{k}={_fmt(v)}" for k, v in record["params"].items()))
    return "\n".join(lines)


def format_comparison(result: dict) -> str:
    """Simulation, reference and their difference side by side (from :func:`simgrip.compare.compare`)."""
    sim, ref, diff = result["simulation"], result["reference"], result["difference"]
    keys = [k for k in _ORDER if k in sim or k in ref] + [
        k for k in sim if k not in _ORDER and k not in ("params", "profile")
    ]
    keys = [k for k in keys if k not in ("source",)]
    width = max(len(k) for k in keys)
    rows = [f"{'':<{width}}  {'simulation':>26}  {'reference':>26}  {'difference':>26}"]
    for k in keys:
        cells = [_fmt(sim.get(k, "")), _fmt(ref.get(k, "")), _fmt(diff.get(k, ""))]
        rows.append(f"{k:<{width}}  " + "  ".join(f"{c:>26}" for c in cells))
    return "\n".join(rows)


def difference(a: dict, b: dict) -> dict:
    """``a - b`` for every numeric (or numeric-list) key both records share."""
    out = {}
    for k in a:
        if k not in b or k in ("params", "source", "grip", "residual", "profile"):
            continue
        va, vb = a[k], b[k]
        if isinstance(va, bool) or isinstance(vb, bool) or va is None or vb is None:
            continue
        if isinstance(va, (int, float)) and isinstance(vb, (int, float)):
            out[k] = float(va) - float(vb)
        elif isinstance(va, list) and isinstance(vb, list) and len(va) == len(vb):
            out[k] = [float(x) - float(y) for x, y in zip(va, vb)]
    return out

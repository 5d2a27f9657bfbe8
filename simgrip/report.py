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

__all__ = ["elastica_record", "solve_record", "format_table", "format_comparison", "difference", "reference_validity"]

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
    warnings = reference_validity(rec, sol)  # a rod through itself or the workpiece is no grip (as compare's)
    if warnings:
        rec["warnings"] = warnings
    return rec


def reference_validity(ref: dict, sol) -> list[str]:
    """Mark the reference record ``valid`` (:func:`simgrip.validity_shapes.reference_violations`); the messages.

    The BVP allows the rod to pass through itself and the workpiece: an impossible reference gets
    ``valid: False`` and ``feasible: False`` (it holds nothing) and a warning saying why.
    """
    from simgrip.validity_shapes import reference_violations

    found = reference_violations(sol)
    ref["valid"] = not found
    if not found:
        return []
    ref["feasible"] = False
    return [f"the reference itself crosses itself / enters the workpiece (the BVP allows it): {m}; the reference "
            f"is reported not feasible" for m in found]


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
    """A two-column, human-readable table of a record: five significant digits,
    ``-`` for a missing value (``None``), ``unbounded`` for an infinite one; its ``warnings`` after it, one
    ``WARNING:`` line each (as :func:`format_comparison`'s)."""

    def cell(v) -> str:
        if v is None:
            return "-"
        if isinstance(v, float) and math.isfinite(v):
            return f"{v:.5g}"
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(cell(x) for x in v) + "]"
        return _fmt(v)

    keys = [k for k in _ORDER if k in record] + [k for k in record if k not in _ORDER and k not in ("params", "warnings")]
    width = max(len(k) for k in keys)
    lines = [f"{k:<{width}}  {cell(record[k])}" for k in keys]
    if "params" in record:
        lines.append(f"{'params':<{width}}  " + ", ".join(f"{k}={cell(v)}" for k, v in record["params"].items()))
    return "\n".join(lines + [f"WARNING: {w}" for w in record.get("warnings") or []])


def format_comparison(result: dict) -> str:
    """Simulation, reference and their difference side by side (from :func:`simgrip.compare.compare`).

    Physical quantities first, five significant digits, ``-`` where a side has no
    value.  The difference column is absolute for lengths (``ℓ``) and relative for
    forces and ``μ`` (absolute where the reference is 0).  ``N1``/``N2`` appear for
    Grip III only (for Grips I/II they are the normal and friction forces again).
    Diagnostics (method, steps, time, residuals, ...) go on footer lines; any key
    not placed in a row goes there too, so nothing of the record is lost.  The
    simulation's warnings and the comparison's (``result["warnings"]``: verdicts
    that disagree) are printed as ``WARNING:`` lines.
    """
    sim, ref = result["simulation"], result["reference"]

    def num(v, digits=5, fmt="#") -> str:
        if v is None:
            return "-"
        if isinstance(v, bool):
            return "yes" if v else "no"
        if isinstance(v, float):
            if math.isnan(v):
                return "nan"
            if math.isinf(v):
                return "unbounded" if v > 0 else "-unbounded"
            return f"{v:{fmt}.{digits}g}".rstrip(".")
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(num(x, digits, fmt) for x in v) + "]" if v else "none"
        return str(v)

    def rel(a, b) -> str:
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in (a, b)):
            return ""
        d = float(a) - float(b)
        if d == 0.0:
            return "0"
        pct = 100.0 * d / abs(b) if b != 0.0 else 0.0
        if abs(pct) < 1e-4:  # reference 0, or a round-off difference: absolute only
            return f"{d:+.2g}"
        return f"{d:+.2g} ({pct:+.0f} %)" if abs(pct) >= 10 else f"{d:+.2g} ({pct:+.2g} %)"

    def absdiff(a, b) -> str:
        if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in (a, b)):
            return ""
        d = float(a) - float(b)
        return "0" if d == 0.0 else f"{d:+.2g}"

    def vec(key, i):
        return lambda r: (r.get(key) or [None, None])[i]

    grip = sim.get("grip", ref.get("grip"))
    three = grip == "III"
    rows: list[tuple[str, object, object, str]] = []
    used = {"source", "grip", "params", "profile"}

    def row(label, get, diff=None, keys=()):
        a, b = get(sim), get(ref)
        used.update(keys)
        if a is None and b is None:
            return
        rows.append((label, a, b, "" if diff is None else diff(a, b)))

    row("tip x", vec("tip", 0), absdiff, ("tip",))
    row("tip y", vec("tip", 1), absdiff)
    if three:
        row("contact x", vec("contact", 0), absdiff, ("contact",))
        row("contact y", vec("contact", 1), absdiff)
        row("gamma", lambda r: r.get("gamma"), absdiff, ("gamma",))
    row("normal force", lambda r: r.get("normal_force"), rel, ("normal_force", "n"))
    row("friction force", lambda r: r.get("friction_force"), rel, ("friction_force", "f"))
    used.update(("N1", "N2"))
    if three:
        row("N1", lambda r: r.get("N1"), rel)
        row("N2", lambda r: r.get("N2"), rel)
    row("required mu", lambda r: r.get("required_mu"), rel, ("required_mu",))
    row("feasible", lambda r: r.get("feasible"), None, ("feasible",))
    if three:
        row("tip clear", lambda r: r.get("tip_clear"), None, ("tip_clear",))
    row("held", lambda r: r.get("held"), None, ("held",))
    row("min eigenvalue", lambda r: r.get("min_eigenvalue"), rel, ("min_eigenvalue",))

    width = max(len(r[0]) for r in rows)
    cols = [max(10, *(len(num(r[i])) for r in rows)) for i in (1, 2)]
    lines = []
    prof = sim.get("profile", ref.get("profile"))
    p = sim.get("params") or ref.get("params") or {}
    head = f"Grip {grip}" + (f", {prof}" if prof else "")
    if p:
        head += ", " + ", ".join(f"{k}={num(v, fmt='')}" for k, v in p.items() if three or k != "gamma")
    if sim.get("links") is not None:
        head += f", {sim['links']} links"
    used.add("links")
    lines.append(head)
    lines.append(f"{'':<{width}}  {'simulation':>{cols[0]}}  {'reference':>{cols[1]}}  difference (sim - ref)")
    for label, a, b, d in rows:
        lines.append(f"{label:<{width}}  {num(a):>{cols[0]}}  {num(b):>{cols[1]}}  {d}".rstrip())

    warnings = sim.get("warnings")
    used.add("warnings")
    for w in warnings or []:
        lines.append(f"WARNING: {w}")
    for w in result.get("warnings") or []:  # the comparison's own: verdicts that disagree (simgrip.compare)
        lines.append(f"WARNING: {w}")

    def footer(name, rec):
        times = {"wall_time_s": "time", "build_time_s": "build"}
        items = [f"{times[k]} {num(v, 2, '')} s" if k in times else f"{k.replace('_', ' ')} {num(v, 2, '')}"
                 for k, v in rec.items() if k not in used and k not in ("nodes", "contacts") and v is not None]
        if rec.get("contacts") is not None:  # (the centreline and each contact: --json's, not a footer's)
            items.append(f"contacts {len(rec['contacts'])} (--json lists them and the centreline)")
        if name == "simulation":
            items.append("warnings " + ("none" if not warnings else str(len(warnings))))
        return f"{name}: " + ", ".join(items) if items else ""

    lines.extend(x for x in (footer("simulation", sim), footer("reference", ref)) if x)
    return "\n".join(lines)


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

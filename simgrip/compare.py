"""A simulated settled state next to its elastica reference.

The reference is solved for exactly the state the simulation describes:

* the couple the finite-radius contact geoms apply (``contact.moment``) is
  passed as ``contact_moment``;
* Grip III is solved at the simulation's own contact arc length ``gamma`` and
  its own ``X(gamma)`` (NOTES: gamma is not prescribed in a simulation).

All numbers are dimensionless (lengths over ``l``, forces on the rod over
``rho g l``).
"""

from __future__ import annotations

import math
import time

from simgrip.params import DimensionlessParams, check_grip
from simgrip.profiles import as_profile
from simgrip.report import difference, elastica_record

__all__ = ["simulate", "settled_record", "reference_for", "compare", "verdict_warnings"]


def simulate(grip: str, params: DimensionlessParams, profile, links: int, *, progress=None, **settle_kw):
    """Build the symmetric-reduction scene of ``grip`` with ``links`` links per finger and settle it.

    Returns the :class:`~simgrip.settle.SettledState`, its ``build_time_s`` the
    build and compile of the model [s] (``wall_time_s`` is the settle alone).
    ``progress`` (:mod:`simgrip.progress`; None: silent) is told the phases.
    Extra keywords go to :func:`~simgrip.settle.settle`.
    """
    from simgrip.progress import phase
    from simgrip.scenes import build_scene
    from simgrip.settle import settle

    grip = check_grip(grip)
    t0 = time.perf_counter()
    with phase(progress, f"building the model ({links} links per finger)"):
        scene = build_scene(grip, params, as_profile(profile), links)
    build_time_s = time.perf_counter() - t0
    with phase(progress, "settling"):
        state = settle(scene, **settle_kw)
    state.build_time_s = build_time_s
    return state


def _stability(state, grip, params, profile) -> float:
    """Smallest eigenvalue of the hinge chain's projected Hessian at the settled shape."""
    from simgrip import reference as discrete

    try:
        if grip == "III" and state.contact is not None:
            p = params.replace(b=2.0 * float(state.contact.point[0]))
            ch = discrete.solve_chain(
                grip, p, profile, state.links, gamma=state.contact.gamma,
                contact_moment=state.contact.moment, guess=state.link_angles[0],
            )
        else:
            C = float(state.contact.moment) if state.contact is not None and state.held else 0.0
            ch = discrete.solve_chain(grip, params, profile, state.links, contact_moment=C,
                                      guess=state.link_angles[0])
        return float(ch.min_eigenvalue)
    except (discrete.DiscreteError, ValueError):
        return math.nan


def settled_record(state, params: DimensionlessParams, profile=None) -> dict:
    """Record of a settled state in the fields of :func:`simgrip.report.elastica_record`.

    Adds ``wall_time_s`` (the settle alone), ``build_time_s`` (the model's build and compile),
    ``steps``, ``held``, ``penetration`` (over ``l``),
    ``residual``, ``links`` (the finest used), ``method``, ``warnings``, ``extrapolated`` and
    ``error_estimate`` (``settle(..., target_error=E)``: tip over ``l``, forces relative; else None).  ``feasible`` is the
    simulation's verdict: the workpiece is held, its contacts are surface contacts
    (``contact_ok``: none deeper than half the finger's radius, no Grip I/II tip past
    the face; the record then carries ``contact_ok: False``) and, Grip III, condition
    (23) holds (``tip_clear``: the tip below the contact, no part of the rod beyond the
    contact in the workpiece).  ``min_eigenvalue`` is the hinge chain's stability
    eigenvalue at this shape when ``profile`` is given.
    """
    c = state.contact
    grip = state.grip
    rec = {
        "source": "simulation",
        "grip": grip,
        "links": int(state.links),
        "tip": [float(state.tip[0][0]), float(state.tip[0][1])] if state.tip.ndim == 2 else [float(v) for v in state.tip],
        "normal_force": float(state.normal_force),
        "friction_force": float(state.friction_force),
        "required_mu": float(state.required_mu) if c is not None else 0.0,
        "feasible": bool(state.held and state.tip_clear and getattr(state, "contact_ok", True)) if grip != "free" else True,
        "min_eigenvalue": None if profile is None else _stability(state, grip, params, as_profile(profile)),
        "N1": float(state.N1),
        "N2": float(state.N2),
        **settle_fields(state),
        "method": state.method,
        "warnings": list(state.warnings),
        "extrapolated": bool(state.extrapolated),
        "error_estimate": state.error_estimate,
        "params": {"D": params.D, "M": params.M, "b": params.b, "mu_s": params.mu_s, "gamma": params.gamma},
    }
    if grip == "III" and c is not None:
        rec.update(
            contact=[float(c.point[0]), float(c.point[1])],
            gamma=float(c.gamma),
            n=float(c.normal),
            f=float(c.friction),
            contact_moment=float(c.moment),
        )
    if grip == "III" and c is not None and state.held:
        rec["tip_clear"] = bool(state.tip_clear)  # condition (23) (simgrip.validity), beside the reference's
    if not getattr(state, "contact_ok", True):
        rec["contact_ok"] = False  # a contact too deep or a tip past the face (simgrip.validity.check_contact_depth)
    if grip != "III" and c is not None:
        rec["contact_moment"] = float(c.moment)
    return rec


def settle_fields(state) -> dict:
    """The fields every simulation record shares: held, wall time [s] (the settle), build time [s] (the model's
    build and compile; None when the state was settled from a scene built elsewhere), steps, penetration [m],
    residual, converged."""
    build = getattr(state, "build_time_s", None)
    return {
        "held": bool(state.held),
        "wall_time_s": float(state.wall_time_s),
        "build_time_s": None if build is None else float(build),
        "steps": int(state.steps),
        "penetration": float(state.penetration),
        "residual": float(state.residual),
        "converged": bool(state.converged),
    }


def reference_for(state, params: DimensionlessParams, profile):
    """The elastica solution of the state ``state`` describes (see the module docstring)."""
    from simgrip.reference import elastica

    grip = state.grip
    c = state.contact
    if grip == "free" or c is None or not state.held:
        return elastica.solve(grip, params, profile)
    if grip == "III":
        p = params.replace(b=2.0 * float(c.point[0]))
        return elastica.solve(grip, p, profile, gamma=float(c.gamma), contact_moment=float(c.moment))
    return elastica.solve(grip, params, profile, contact_moment=float(c.moment))


def compare(grip: str, params: DimensionlessParams, profile, links: int, **settle_kw) -> dict:
    """Simulate, solve the matching reference, and return ``{"simulation", "reference", "difference"}``.

    ``difference`` is simulation minus reference for every shared numeric field.
    Extra keywords (e.g. ``method="dynamics"``) go to :func:`~simgrip.settle.settle`.
    """
    profile = as_profile(profile)
    state = simulate(grip, params, profile, links, **settle_kw)
    sim = settled_record(state, params, profile)
    ref = elastica_record(reference_for(state, params, profile))
    return {"simulation": sim, "reference": ref, "difference": difference(sim, ref),
            "warnings": verdict_warnings(sim, ref)}


def verdict_warnings(sim: dict, ref: dict) -> list[str]:
    """Messages for every verdict on which a simulation record and its reference record disagree.

    ``feasible`` and (Grip III) ``tip_clear``; each message names the
    quantities that decide the verdict on both sides (friction: the required
    ``mu`` against ``mu_s``; condition (23): ``Y(l) - Y(gamma)``), so that a
    disagreement at the edge of the feasible region (within the chain's
    discretisation error) reads as such and no disagreement is silent.  Empty
    when they agree (or the grip is ``free``).
    """
    out: list[str] = []
    if sim.get("grip") == "free" or ref.get("grip") == "free":
        return out

    def yn(v) -> str:
        return "yes" if v else "no"

    if "tip_clear" in sim and "tip_clear" in ref and bool(sim["tip_clear"]) != bool(ref["tip_clear"]):
        hs = float(sim["tip"][1]) - float(sim["contact"][1]) if "contact" in sim else math.nan
        hr = float(ref["tip"][1]) - float(ref["contact"][1]) if "contact" in ref else math.nan
        out.append(f"condition (23) disagrees: simulation tip clear {yn(sim['tip_clear'])} "
                   f"(Y(l) - Y(gamma) = {hs:.3g}), reference {yn(ref['tip_clear'])} ({hr:.3g})")
    if bool(sim.get("feasible")) != bool(ref.get("feasible")):
        why = []
        if not sim.get("held", True):
            why.append("the simulation dropped the workpiece")
        if sim.get("contact_ok") is False:
            why.append("the simulation's contact is not a surface contact (see its warnings)")
        mu = (sim.get("params") or ref.get("params") or {}).get("mu_s")
        if mu is not None:
            at = (f"simulation {float(sim.get('required_mu', math.nan)):.4g}, " if sim.get("held", True)
                  else "")  # a dropped state has no contact to need friction at
            why.append(f"required mu: {at}reference {float(ref.get('required_mu', math.nan)):.4g}, mu_s {float(mu):.4g}")
        out.append(f"verdicts disagree: simulation feasible {yn(sim.get('feasible'))}, reference feasible "
                   f"{yn(ref.get('feasible'))}" + (" (" + "; ".join(why) + ")" if why else ""))
    return out

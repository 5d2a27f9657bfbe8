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

import numpy as np

from simgrip.params import DimensionlessParams, as_dimensionless
from simgrip.profiles import as_profile
from simgrip.report import difference, elastica_record, reference_validity  # (the last re-exported)
from simgrip.settled import settle_fields, settled_record, simulate  # re-exported (__all__)

__all__ = ["BRANCH_LINKS", "simulate", "settled_record", "settle_fields", "reference_for", "reference_of", "chain_reference",
           "branch_warnings", "cone_warnings", "compare", "reference_validity", "verdict_warnings"]

#: A reference whose tip lies farther than this many link lengths (``BRANCH_LINKS / n`` over ``l``) from the
#: simulated tip describes another equilibrium.  The settled ``n``-link chain is the midpoint discretisation of
#: the elastica, whose tip it matches to ``O(1/n^2)`` (``~3e-4 l`` at ``n = 32`` in the standard case, see
#: :data:`simgrip.validity.DEPTH_FRACTION`): a whole link, ``1/n``, is ``n`` times the ``1/n^2`` scale (32 at the
#: default), so a tip that far off is not the chain's discretisation error but another branch of the BVP.
BRANCH_LINKS = 1.0


def reference_of(state, params: DimensionlessParams, profile):
    """``(solution, warnings)``: the elastica solution of the state ``state`` describes (see the module docstring).

    A held state's reference is on the branch the settled chain lies on
    (:func:`chain_reference`: cold, and where that lands on another branch,
    from the chain's own shape).  ``warnings``
    names a reference on another branch (:func:`branch_warnings`) and a Grip III
    reference at the friction cone's edge as the chain resolves it
    (:func:`cone_warnings`): why the verdicts may differ.  A Grip III
    contact at the tip (``gamma = 1``) has no reference: ``(None, [why])``.
    A dropped state (or the free rod) is referenced at ``params``, cold.
    """
    from simgrip.reference import elastica

    grip = state.grip
    c = state.contact
    profile = as_profile(profile)
    # an impossible state (``valid`` False, :func:`simgrip.validity.check_valid`) is reported not held, but the
    # solve held it (it has a contact): its reference is the BVP on the branch it lies on, as for a held one
    if grip == "free" or c is None or not (state.held or not getattr(state, "valid", True)):
        sol = elastica.solve(grip, params, profile)
        return sol, cone_warnings(sol, state.links)
    kw = {"contact_moment": float(c.moment)}
    p = params
    if grip == "III":
        if float(c.gamma) >= 1.0:
            return None, [f"no reference: the simulation's contact is at the tip (gamma = {float(c.gamma):.4g}), "
                          f"Grip III degenerated to a tip contact, which the Grip III BVP (0 < gamma < 1) does not "
                          f"describe"]
        p = params.replace(b=2.0 * float(c.point[0]))
        kw["gamma"] = float(c.gamma)
    sol = chain_reference(grip, p, profile, state.link_angles[0], float(c.N1), state.nodes[0], **kw)
    return sol, branch_warnings(state.tip, state.links, sol) + cone_warnings(sol, state.links, c)


def chain_reference(grip: str, params: DimensionlessParams, profile, link_angles, N1: float, nodes=None, *,
                    contact_moment: float = 0.0, gamma: float | None = None):
    """The elastica solution of ``grip`` on the branch a settled chain lies on.

    ``link_angles`` (rad) and ``nodes`` (over ``l``; None: from the angles) of
    the chain, ``N1`` its horizontal contact force on the rod (over ``rho g l``).
    The BVP is solved as always (:func:`simgrip.reference.elastica.solve`, cold);
    where that lands on another branch (its tip more than :data:`BRANCH_LINKS`
    links from the chain's) or fails, it is solved again from the chain's own
    shape (:func:`simgrip.reference.chain_guess.chain_guess`), and the solution
    nearer the chain is returned.  ``ElasticaError`` when both fail.
    """
    from simgrip.reference import elastica
    from simgrip.reference.bvp import ElasticaError
    from simgrip.reference.chain_guess import chain_guess

    kw = {"contact_moment": float(contact_moment)} | ({} if gamma is None else {"gamma": float(gamma)})
    angles = np.asarray(link_angles, dtype=float).ravel()
    cold = error = None
    try:
        cold = elastica.solve(grip, params, profile, **kw)
    except ElasticaError as exc:
        error = exc
    try:
        _, _, problem = elastica.checked_problem(grip, params, profile, **kw)
        guess = chain_guess(problem, angles, nodes, float(N1), float(contact_moment))
    except ValueError:
        guess = None
    tip = guess.states(np.array([1.0]))[2:, 0] if guess is not None else None
    if guess is None or (cold is not None and not branch_warnings(tip, angles.size, cold)):
        if cold is None:
            raise error
        return cold
    try:
        warm = elastica.solve(grip, params, profile, guess=guess, fallback=False, **kw)
    except ElasticaError:
        warm = None
    if warm is None or cold is None:
        if warm is None and cold is None:
            raise error
        return cold if warm is None else warm
    def gap(sol) -> float:
        return float(np.hypot(*(tip - np.asarray(sol.tip, dtype=float))))

    return warm if gap(warm) <= gap(cold) else cold


def reference_for(state, params: DimensionlessParams, profile):
    """The elastica solution of the state ``state`` describes (:func:`reference_of` without its warnings).

    ``ElasticaError`` when there is none (a Grip III contact at the tip)."""
    from simgrip.reference.bvp import ElasticaError

    sol, warnings = reference_of(state, params, profile)
    if sol is None:
        raise ElasticaError(warnings[0])
    return sol


def branch_warnings(tip, links: int, sol) -> list[str]:
    """A reference on another equilibrium branch than the held simulated state says so.

    ``tip``: the simulated tip ``(X, Y)`` over ``l`` (or one per finger: finger
    0's is used), ``links`` the chain's ``n``.  The tips further apart than
    :data:`BRANCH_LINKS` link lengths (``1/n``): beyond the chain's ``O(1/n^2)``
    discretisation error, so the two are different equilibria and their
    verdicts need not agree.  Empty when ``sol`` is None.
    """
    if sol is None:
        return []
    tip = np.asarray(tip, dtype=float)
    tip = tip[0] if tip.ndim == 2 else tip
    gap = float(np.hypot(*(tip - np.asarray(sol.tip, dtype=float))))
    limit = BRANCH_LINKS / int(links)
    if not gap > limit:
        return []
    return [f"the reference converged to another equilibrium branch: its tip ({sol.tip[0]:.4g}, {sol.tip[1]:.4g}) l "
            f"is {gap:.3g} l from the simulation's ({tip[0]:.4g}, {tip[1]:.4g}) l, more than a link (1/n = "
            f"{limit:.3g} l; the chain's own error is O(1/n^2)); the verdicts compare different equilibria"]


def cone_warnings(sol, links: int, contact=None) -> list[str]:
    """A Grip III reference within the chain's frame error of the friction cone says so.

    The simulated corner rests on one link, whose normal is MuJoCo's contact
    frame (the one the settles' friction cone uses); the rod's normal at
    ``gamma`` (the BVP's frame) differs from it.  With the simulated ``contact``
    (a held state's :class:`~simgrip.settle.FingerContact`) the difference is
    measured: the friction angles ``atan(required_mu)`` in the two frames.
    Without one (a dropped state) it is bounded by half a link's turn,
    ``|theta'(gamma)| / (2 n)`` (the contact anywhere on the link).  A reference
    whose friction angle ``atan(|f| / n)`` lies within that of ``atan(mu_s)`` is
    at the cone's edge as the chain resolves it: the settles may slip where the
    BVP holds, or hold where it does not.
    """
    if sol is None or sol.grip != "III" or not sol.normal_force > 0.0:
        return []
    if contact is not None:
        turn = abs(math.atan(float(contact.required_mu)) - math.atan(float(contact.required_mu_contact)))
        how = "the corner's link turns the contact frame by"
    else:
        g = float(sol.gamma)
        curvature = float(sol.profile(np.array([g]))[0]) + float(sol.moment_at(np.array([g]))[0]) / sol.params.D
        turn = abs(curvature) / (2.0 * int(links))
        how = "the corner's link can turn the contact frame by up to |theta'(gamma)| / (2 n) ="
    if not math.isfinite(turn):
        return []
    mu = float(sol.params.mu_s)
    gap = math.atan(float(sol.required_mu)) - math.atan(mu)
    if abs(gap) > turn:
        return []
    return [f"the reference is at the friction cone's edge as the {int(links)}-link chain resolves it: it needs mu = "
            f"{float(sol.required_mu):.4g} of mu_s = {mu:g} (friction angles {abs(gap):.3g} rad apart) while {how} "
            f"{turn:.3g} rad from the rod's; the settles may slip where the BVP holds, or hold where it does not"]


def compare(grip: str, params: DimensionlessParams, profile, links: int, **settle_kw) -> dict:
    """Simulate, solve the matching reference, and return ``{"simulation", "reference", "difference", "warnings"}``.

    ``difference`` is simulation minus reference for every shared numeric field;
    ``warnings`` names the verdicts that disagree (:func:`verdict_warnings`), a
    reference on another branch (:func:`branch_warnings`) and one at the friction
    cone's edge as the chain resolves it (:func:`cone_warnings`).  A state without a
    reference (a Grip III contact at the tip) has ``reference`` ``{"source":
    "elastica", "grip", "available": False, "why"}`` and an empty difference.
    Extra keywords (e.g. ``method="dynamics"``) go to :func:`simulate`.
    """
    params = as_dimensionless(params)  # PhysicalParams too, as simulate (before any work)
    profile = as_profile(profile)
    if settle_kw.get("contact") == "full" and settle_kw.get("box_depth") is not None:
        from simgrip.compare_full import compare_full  # grasped at a depth: the free-boundary reference

        return compare_full(grip, params, profile, links, **settle_kw)
    state = simulate(grip, params, profile, links, **settle_kw)
    sim = settled_record(state, params, profile)
    sol, ref_warnings = reference_of(state, params, profile)
    if settle_kw.get("contact") == "full":  # every link touches; the reference below is the point-contact BVP
        ref_warnings = ["contact 'full': the reference is the point-contact BVP (tip on the face, the rod free to "
                        "pass through itself and the workpiece), not the full-contact problem; the difference "
                        "measures the full-contact state against that idealisation (--box-depth D compares a grasp "
                        "at a depth with the free-boundary reference)"] + ref_warnings
    if sol is None:
        ref = {"source": "elastica", "grip": state.grip, "available": False, "why": ref_warnings[0]}
        return {"simulation": sim, "reference": ref, "difference": {}, "warnings": ref_warnings}
    ref = elastica_record(sol)
    ref_warnings = ref_warnings + reference_validity(ref, sol)
    return {"simulation": sim, "reference": ref, "difference": difference(sim, ref),
            "warnings": ref_warnings + verdict_warnings(sim, ref)}


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
        if sim.get("valid") is False:
            why.append("the simulation's state is not physical (see its warnings: invalid state)")
        if ref.get("valid") is False:
            why.append("the reference is not physical (it crosses itself or enters the workpiece)")
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

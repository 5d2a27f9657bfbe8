"""Getting ``solve_bvp`` to converge: warm starts, natural continuation and cold starts.

A cold start is never handed to Newton directly (it fails with singular
Jacobians).  For a grip, :func:`cold_start` begins at the exact unloaded
circular arc that puts the contact at ``X = b/2`` curling the grip's way (down
for I and III, up for II: this picks the branch, e.g. Grip II's finger wraps the
workpiece from above-outside), blends the profile into the requested one, then
ramps gravity and loads in (fallbacks: loads before profile; the other curl;
the straight rod with curvature and loads ramped together, then the width
target moved from where the free rod puts it to ``b/2``).  The free rod ramps
curvature and loads from the straight rod.  Steps are solved at a loose
tolerance (cheap failures); the end point of a path is polished to the requested
one a decade at a time (:func:`polish`); meshes handed on are thinned so they do
not grow along sweeps.

The work is bounded: each ``solve_bvp`` run by its node limit
(``bvp._MAX_NODES``), each continuation by ``max_tries`` steps and ``h_min``,
and one whole solve by :data:`MAX_BVP_RUNS` runs (a :class:`Budget`), past which
it raises :class:`~simgrip.reference.bvp.ElasticaError` instead of searching on.
"""

from __future__ import annotations

import math
from dataclasses import replace as _dc_replace
from typing import Callable

import numpy as np

from simgrip.profiles import Uniform
from simgrip.reference.bvp import TOL_MID, Blend, BvpProblem, BvpSolution, ElasticaError, run_bvp
from simgrip.reference.extensions import brentq  # scipy.optimize.brentq without scipy.optimize's import cost

__all__ = ["MAX_BVP_RUNS", "MAX_JUMP", "Budget", "cold_start", "continue_along", "linear_path", "solve_from"]

MAX_JUMP = 0.75  # radians: largest change of theta accepted in one step along a branch
_H_MIN = 2.0**-12  # smallest continuation step (fraction of the path)
_MAX_TRIES = 80  # solve_bvp runs allowed to one continuation
_GUESS_NODES = 301  # largest mesh handed to solve_bvp as a starting guess
_JUMP_GRID = np.linspace(0.0, 1.0, 41)
_H_MIN_SCOUT = 2.0**-7  # smallest step of the first cold-start strategy (it has fallbacks)

#: Most ``solve_bvp`` runs one :func:`~simgrip.reference.elastica.solve` may spend
#: (each run is itself bounded by ``bvp._MAX_NODES`` mesh nodes); past it the
#: solve raises :class:`~simgrip.reference.bvp.ElasticaError` rather than search on.
MAX_BVP_RUNS = 200


class Budget:
    """The ``solve_bvp`` runs left to one solve: :meth:`run` spends one, and raises
    :class:`ElasticaError` once ``limit`` runs are spent."""

    def __init__(self, limit: int = MAX_BVP_RUNS):
        self.limit, self.used = int(limit), 0

    def run(self, P: BvpProblem, x, y, p, tol: float) -> BvpSolution | None:
        """:func:`~simgrip.reference.bvp.run_bvp`, counted."""
        if self.used >= self.limit:
            raise ElasticaError(
                f"elastica BVP gave up after {self.used} solve_bvp runs (the limit per solve, MAX_BVP_RUNS = "
                f"{self.limit}): no continuation path converged"
            )
        self.used += 1
        return run_bvp(P, x, y, p, tol)


def _budget(budget: Budget | None) -> Budget:
    return Budget() if budget is None else budget


def _mesh_guess(raw: BvpSolution, P: BvpProblem) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Initial mesh, states and parameters for problem ``P`` taken from ``raw``."""
    same_layout = raw.prob.two_seg == P.two_seg and (not P.two_seg or raw.prob.gamma == P.gamma)
    if same_layout:
        x = raw.x
        if x.size > _GUESS_NODES:
            # solve_bvp only ever adds nodes: thin the guess so that meshes do not
            # grow along a continuation (it refines again where it needs to).
            keep = np.unique(np.round(np.linspace(0, x.size - 1, _GUESS_NODES)).astype(int))
            x = x[keep]
    else:
        x = np.linspace(0.0, 1.0, min(max(raw.x.size, 61), _GUESS_NODES))
    if P.two_seg:
        sa, sb = P.gamma * x, P.gamma + (1.0 - P.gamma) * x
        ya, yb = raw.states(sa), raw.states(sb)
        ya[0] -= P.K(sa)
        yb[0] -= P.K(sb)
        y = np.vstack((ya, yb))
    else:
        y = raw.states(x)
        y[0] -= P.K(x)
    p = np.array([raw.N1]) if P.constrained else None
    return x, y, p


def polish(r: BvpSolution, tol: float, budget: Budget | None = None) -> BvpSolution | None:
    """Tighten a converged solution ``r`` to tolerance ``tol`` a decade at a time.

    One jump from ``TOL_MID`` to ``tol`` can make ``solve_bvp`` refine a coarse
    mesh where the residual sits at its round-off floor (stiff rods, large contact
    forces) until it hits the node limit, seconds per try; a decade at a time each
    run starts from a mesh already fitted to the previous tolerance.
    """
    budget = _budget(budget)
    t = max(tol, TOL_MID)
    while r is not None and t > tol:
        t = max(t / 10.0, tol)
        r = budget.run(r.prob, r.x, r.y, r.p if r.prob.constrained else None, t)
    return r


def solve_from(raw: BvpSolution, P: BvpProblem, tol: float, budget: Budget | None = None) -> BvpSolution | None:
    """Solve ``P`` from the guess ``raw``: first at the loose intermediate tolerance
    (a failure is cheap there), then polished to ``tol`` (:func:`polish`)."""
    budget = _budget(budget)
    x, y, p = _mesh_guess(raw, P)
    r = budget.run(P, x, y, p, max(tol, TOL_MID))
    if r is None or tol >= TOL_MID:
        return r
    return polish(r, tol, budget)


def _theta_jump(a: BvpSolution, b: BvpSolution) -> float:
    """Largest change of ``theta`` between two solutions (branch-jump detector)."""
    return float(np.max(np.abs(a.states(_JUMP_GRID)[0] - b.states(_JUMP_GRID)[0])))


def continue_along(
    path: Callable[[float], BvpProblem],
    raw: BvpSolution,
    tol: float,
    h: float = 1.0,
    max_jump: float | None = None,
    h_min: float = _H_MIN,
    max_tries: int = _MAX_TRIES,
    budget: Budget | None = None,
) -> BvpSolution | None:
    """Natural-parameter continuation along ``path(w)``, ``w: 0 -> 1``, from ``raw``
    (a solution at ``w = 0``); adaptive step, halved on failure.  Returns the
    solution at ``w = 1`` (at tolerance ``tol``) or ``None``.  With ``max_jump``,
    a step whose ``theta`` moves by more than that many radians counts as a
    failure: the solver has left the branch (natural continuation cannot pass
    a fold, so the path then fails, as it should).  At most ``max_tries`` steps
    (tried or taken); every ``solve_bvp`` run is charged to ``budget``."""
    budget = _budget(budget)
    w = 0.0
    tries = 0
    while w < 1.0:
        tries += 1
        if tries > max_tries:
            return None
        h = min(h, 1.0 - w)
        wn = 1.0 if 1.0 - (w + h) < 1e-12 else w + h
        r = solve_from(raw, path(wn), TOL_MID, budget)
        if r is not None and max_jump is not None and _theta_jump(raw, r) > max_jump:
            r = None
        if r is None:
            h *= 0.5
            if h < h_min:
                return None
            continue
        raw, w = r, wn
        h *= 2.0
    # The end point is polished once: a polish that fails is not cured by smaller steps.
    return polish(raw, tol, budget) if tol < TOL_MID else raw


def linear_path(P0: BvpProblem, P1: BvpProblem) -> Callable[[float], BvpProblem] | None:
    """Linear path from ``P0`` to ``P1`` (``D`` geometric), when both share a layout."""
    if P0.two_seg != P1.two_seg or P0.constrained != P1.constrained:
        return None

    def lerp(a, b, w):
        return (1.0 - w) * a + w * b

    def path(w):
        if w == 1.0:
            return P1
        return _dc_replace(
            P1,
            D=P0.D ** (1.0 - w) * P1.D**w,
            g=lerp(P0.g, P1.g, w),
            profile=Blend(P0.profile, P1.profile, w),
            t1=lerp(P0.t1, P1.t1, w),
            t2=lerp(P0.t2, P1.t2, w),
            N1=lerp(P0.N1, P1.N1, w),
            N2=lerp(P0.N2, P1.N2, w),
            C=lerp(P0.C, P1.C, w),
            gamma=lerp(P0.gamma, P1.gamma, w),
            target=None if P1.target is None else lerp(P0.target, P1.target, w),
        )

    return path


# --------------------------------------------------------------------------- cold starts


def _straight(P: BvpProblem) -> BvpSolution:
    """The straight unloaded rod: the exact solution when curvature and loads vanish."""
    x = np.linspace(0.0, 1.0, 21)

    def sol(t, _two=P.two_seg, _g=P.gamma):
        t = np.asarray(t, dtype=float)
        z = np.zeros_like(t)
        if _two:
            return np.vstack((z, z, _g * t, z, z, z, _g + (1.0 - _g) * t, z))
        return np.vstack((z, z, t, z))

    P0 = _dc_replace(P, target=None, N1=0.0)
    return BvpSolution(P0, x, sol(x), np.zeros(0), sol, 0.0, "straight rod")


def _scaled(P: BvpProblem, lam: float, curvature: bool = True, loads: bool = True) -> BvpProblem:
    kc = lam if curvature else 1.0
    kl = lam if loads else 1.0
    return _dc_replace(
        P,
        profile=P.profile.scaled(kc) if kc != 1.0 else P.profile,
        g=P.g * kl,
        t1=P.t1 * kl,
        t2=P.t2 * kl,
        N1=P.N1 * kl,
        N2=P.N2 * kl,
        C=P.C * kl,
    )


def _arc(P: BvpProblem, budget: Budget) -> BvpSolution | None:
    """The unloaded circular arc that puts the contact exactly at ``X = P.target``.

    Uniform curvature ``sigma k`` with ``sin(k g) / k = target`` (``g`` the contact
    arc length), ``k g`` in ``(0, pi)``: curling down (``sigma = -1``, Grips I and
    III) or up (``sigma = +1``, Grip II).  It solves the constrained problem with
    that profile, no loads and ``N1 = 0`` exactly, and fixes the branch: the
    finger wraps the workpiece from the side it curls to.
    """
    gam = P.gamma
    ratio = P.target / gam
    if not 0.0 < ratio < 1.0:
        return None
    u = brentq(lambda u: math.sin(u) / u - ratio, 1e-9, math.pi)  # u = k * gamma
    kap = P.sigma * u / gam
    P0 = _dc_replace(P, profile=Uniform(kap), g=0.0, t1=0.0, t2=0.0, N1=0.0, N2=0.0, C=0.0)
    x = np.linspace(0.0, 1.0, 41)

    def arc(s):
        # phi = theta - K = 0 for the uniform profile
        return np.vstack((0.0 * s, 0.0 * s, np.sin(kap * s) / kap, (1.0 - np.cos(kap * s)) / kap))

    y = np.vstack((arc(gam * x), arc(gam + (1.0 - gam) * x))) if P.two_seg else arc(x)
    return budget.run(P0, x, y, np.array([0.0]), TOL_MID)


def _to_target(base: BvpSolution, Pc: BvpProblem, tol: float, budget: Budget) -> BvpSolution | None:
    """Move the contact's width target from where ``base`` has it to ``Pc.target``."""
    X0 = float(base.contact_state()[2])
    start = _dc_replace(base.prob, target=X0, N1=0.0)
    # ``base`` solves ``start`` exactly (N1 = base.N1 at X = X0).
    base = BvpSolution(start, base.x, base.y, np.array([base.N1]), base.sol, base.rms, base.message)
    return continue_along(lambda w: _dc_replace(Pc, target=(1.0 - w) * X0 + w * Pc.target), base, tol,
                          budget=budget)


def _cold_grip_from_arcs(P: BvpProblem, tol: float, budget: Budget) -> BvpSolution | None:
    """Strategy 1 (grips): the unloaded arc through the contact, curling the grip's
    way, then the profile (unloaded), then the loads.  Strategy 1b: the arc, then
    the loads, then the profile (heavy loads on a soft rod straighten it; curling it
    first and unwinding it under load meets folds).  As a last resort both again
    from an arc curling the other way.  Their steps stop at ``_H_MIN_SCOUT``: a
    path that meets a fold fails after a few halvings, not a dozen, and the
    next strategy takes over."""
    kw = dict(h_min=_H_MIN_SCOUT, budget=budget)
    for sigma in (P.sigma, -P.sigma):
        arc = _arc(_dc_replace(P, sigma=sigma), budget)
        if arc is None:
            return None
        unloaded = _scaled(P, 0.0, curvature=False)
        raw = continue_along(linear_path(arc.prob, unloaded), arc, TOL_MID, **kw)
        if raw is not None:
            raw = continue_along(lambda lam: _scaled(P, lam, curvature=False), raw, tol, **kw)
            if raw is not None:
                return raw
        loaded = _dc_replace(P, profile=arc.prob.profile)
        raw = continue_along(linear_path(arc.prob, loaded), arc, TOL_MID, **kw)
        if raw is not None:
            raw = continue_along(linear_path(loaded, P), raw, tol, **kw)
            if raw is not None:
                return raw
    return None


def cold_start(P: BvpProblem, tol: float, budget: Budget | None = None) -> BvpSolution | None:
    """Solve ``P`` from nothing by continuation from an exactly known solution;
    every ``solve_bvp`` run is charged to ``budget``."""
    budget = _budget(budget)
    free = _dc_replace(P, target=None, N1=0.0 if P.constrained else P.N1)
    straight = _straight(P)
    if P.constrained:
        raw = _cold_grip_from_arcs(P, tol, budget)
        if raw is not None:
            return raw

    # Strategy 2: curvature and loads together from the straight rod, then width.
    raw = continue_along(lambda lam: _scaled(free, lam), straight, tol if not P.constrained else TOL_MID,
                         budget=budget)
    if raw is not None:
        if not P.constrained:
            return raw
        out = _to_target(raw, P, tol, budget)
        if out is not None:
            return out
    if not P.constrained:
        # Strategy 3 (free): loads first, then curvature.
        raw = continue_along(lambda lam: _scaled(free, lam, curvature=False), straight, TOL_MID, h=0.25,
                             budget=budget)
        if raw is None:
            return None
        return continue_along(lambda lam: _scaled(free, lam, loads=False) if lam > 0 else raw.prob, raw, tol,
                              budget=budget)
    # Strategy 3 (grips): loads without curvature, then width, then curvature.
    flat = _scaled(P, 0.0, loads=False)
    raw = continue_along(
        lambda lam: _scaled(_dc_replace(flat, target=None, N1=0.0), lam, curvature=False), straight, TOL_MID,
        budget=budget,
    )
    if raw is None:
        return None
    raw = _to_target(raw, flat, tol, budget)
    if raw is None:
        return None
    return continue_along(lambda lam: _dc_replace(P, profile=P.profile.scaled(lam)), raw, tol, budget=budget)

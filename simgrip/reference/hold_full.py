"""Hold or drop past the onset (issue 17 s.4): the least friction coefficient that holds a box grasped at a depth.

Grips I/II with every contact unilateral, the box grasped ``depth`` below its top edge (Grip I; above its
bottom edge, Grip II): past the onset the rod meets the box's corner as well as its side face
(:mod:`simgrip.reference.free_boundary`).  The theory's assumptions: the box hangs on the tip, which sticks to
the side face; the corner is frictionless (its force ``F_gamma`` is normal to the rod, the natural condition
of the free contact point).  Forces on the rod over ``rho g l``, one finger (the other is its mirror image).

The box's vertical balance (weight ``M``, the tip's friction ``F_f`` and the corner's force, both on the rod,
act on the box reversed)::

    F_f = -M - F_gamma,2

so the friction the tip must carry is the weight *plus* the corner's push on the box: Grip I's corner force on
the rod points up and out (``F_gamma,2 > 0``, e.g. (5.54, 9.61) at kappa = -10), so on the box it points down
and hinders the hold; the corner carries none of the weight.  The tip sticks iff ``|F_f| <= mu_s N`` with
``N > 0``: the box is held at this grasp iff

    mu_s >= mu* = |F_f| / N = (M + F_gamma,2) / N          (Grip I; the point-contact range: M / N)

The shape does not depend on ``mu_s`` while the tip sticks (the corner is frictionless, the box's height is
fixed by the depth), so ``mu*`` is one free-boundary solve.  Below ``mu*`` the tip slides along the face and
the box moves down relative to it (the grasp gets shallower); ``mu*`` falls with the depth (Grip I at
kappa = -10: 0.735 at 0.4, 0.686 at 0.38, 0.654 at 0.35), so a quasi-static slide stops at the depth where
``mu*(depth) = mu_s`` when there is one on the valid branch (:func:`slip_depth`: 0.390 at mu_s = 0.709, 0.376
at 0.68, none at 0.62, where the branch turns invalid first), and the box is not held at the asked grasp.

Standard case (D = 1, M = 5, b = 0.6), uniform kappa, depth 0.4, Grip I (``simgrip solve I --kappa K
--contact full``): ``mu*`` = 0.4900 (kappa -9), 0.7347 (-10), 0.9671 (-11).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from simgrip.params import DimensionlessParams
from simgrip.reference.arguments import check_params

__all__ = ["HoldThreshold", "hold_threshold", "threshold_sensitivities", "slip_depth"]

#: Links of the constrained chain that finds the contact set and starts the free-boundary solve.
GUESS_LINKS = 16


@dataclass(frozen=True)
class HoldThreshold:
    """The theory's hold verdict at one grasp.

    ``least_mu``: ``|F_f| / N`` (``inf`` where the state cannot hold at any friction: ``N <= 0`` or the
    solution is physically invalid); ``N`` the tip's normal force and ``friction`` its vertical force on the rod
    (``F_f``, over ``rho g l``); ``corner_force`` [E1, E2] on the rod (``None`` in the point-contact range);
    ``contact_set`` ``"tip"`` or ``"tip + corner"``; ``valid``/``violations`` of the reference solution;
    ``solution`` the :class:`~simgrip.reference.free_boundary.CornerSolution` (or the point-contact
    :class:`~simgrip.reference.elastica.ElasticaSolution`); ``profile`` the curvature profile solved for."""

    grip: str
    params: DimensionlessParams
    profile: object
    depth: float
    contact_set: str
    least_mu: float
    N: float
    friction: float
    corner_force: tuple | None
    valid: bool
    violations: tuple
    solution: object

    def held(self, mu_s: float) -> bool:
        """Whether friction ``mu_s`` holds the box at this grasp: ``mu_s >= least_mu`` (finite)."""
        mu_s = float(mu_s)
        if not (math.isfinite(mu_s) and mu_s >= 0.0):
            raise ValueError(f"mu_s must be finite and >= 0, got {mu_s!r}")
        return math.isfinite(self.least_mu) and mu_s >= self.least_mu


def _least(N: float, friction: float, valid: bool) -> float:
    return abs(friction) / N if (valid and N > 0.0) else math.inf


def hold_threshold(grip: str, params, profile, *, depth: float = 0.4, guess=None) -> HoldThreshold:
    """The least ``mu_s`` that holds the box at a grasp ``depth`` below its top edge (Grip I) / above its bottom
    edge (Grip II), over ``l`` (module docstring).

    The contact set is found by the constrained chain (:func:`~simgrip.reference.constrained.solve_constrained`,
    :data:`GUESS_LINKS` links): the tip alone gives the paper's point-contact BVP, the tip and the corner the
    free-boundary BVP.  ``guess``: a :class:`~simgrip.reference.free_boundary.CornerSolution` to continue from
    instead (the corner branch).  ``params.mu_s`` plays no part in the threshold.

    Raises
    ------
    ValueError
        Bad arguments (grip not I/II, depth outside (0, 2)).
    FreeBoundaryError, ConstrainedError, ElasticaError
        A solver failed, or the contact set is one with no smooth reference here (a contact interval, a
        second corner, self-contact): FreeBoundaryError naming it.
    """
    from simgrip.profiles import as_profile
    from simgrip.reference.constrained import Box, solve_constrained
    from simgrip.reference.elastica import solve
    from simgrip.reference.free_boundary import CornerSolution, FreeBoundaryError, solve_corner

    if grip not in ("I", "II"):
        raise ValueError(f"grip must be 'I' or 'II' for a hold at a grasp depth, got {grip!r}")
    params = check_params(params)
    profile = as_profile(profile)
    if isinstance(depth, bool) or not isinstance(depth, (int, float)) or not (0.0 < float(depth) < 2.0):
        raise ValueError(f"depth must be a number in (0, 2) (over l), got {depth!r}")
    depth = float(depth)
    if guess is not None and not isinstance(guess, CornerSolution):
        raise ValueError("guess must be a CornerSolution (or None)")
    if guess is None:
        ch = solve_constrained(grip, params, profile, GUESS_LINKS, box=Box(depth=depth))
        kinds = ch.kinds()
        if not kinds:
            sol = solve(grip, params, profile)
            N, F = float(sol.normal_force), float(sol.friction_force)
            ok = bool(sol.feasibility.get("grip_shape", True))
            return HoldThreshold(grip, params, profile, depth, "tip", _least(N, F, ok and N > 0), N, F, None, ok,
                                 () if ok else ("the solution has the other grip's shape",), sol)
        if kinds != {"corner": 1}:
            raise FreeBoundaryError(f"contact set {kinds}: no smooth reference for the hold (only the tip, or "
                                    "the tip and the box's corner)")
        guess = ch
    b = solve_corner(grip, params, profile, guess, depth=depth)
    return HoldThreshold(grip, params, profile, depth, "tip + corner", _least(b.N, b.friction, b.valid), b.N,
                         b.friction, (float(b.corner_force[0]), float(b.corner_force[1])), b.valid, b.violations, b)


def threshold_sensitivities(th: HoldThreshold, h: float = 1e-3, tol: float = 1e-8) -> dict:
    """Central differences (step ``h``) of ``mu* = |F_f| / N`` on the corner branch: ``"tilt"`` (per radian of
    the corner's force turned off the rod's normal), ``"depth"`` (per ``l`` of grasp depth), ``"tip_moment"``
    (per ``rho g l^2`` of a couple at the tip), and ``"kappa_gamma"``, the rod's curvature ``theta'(gamma)``
    at the corner [1/l].  What a discretisation's band is built from (tests/test_hold_full.py).  ``tol``: the
    perturbed solves' ``solve_bvp`` tolerance (1e-8 moves the differences by ~1e-12 against 1e-10, at a sixth of
    the time).

    Raises ValueError outside the corner branch; FreeBoundaryError if a perturbed solve fails.
    """
    import numpy as np

    from simgrip.reference.free_boundary import solve_corner

    if th.contact_set != "tip + corner":
        raise ValueError(f"threshold_sensitivities: needs the corner branch, got contact set {th.contact_set!r}")
    if not (isinstance(h, (int, float)) and 0.0 < h < 0.1):
        raise ValueError(f"h must lie in (0, 0.1), got {h!r}")
    if not (isinstance(tol, (int, float)) and 0.0 < tol < 1e-4):
        raise ValueError(f"tol must lie in (0, 1e-4), got {tol!r}")
    b = th.solution

    def mu(**kw):
        s = solve_corner(th.grip, th.params, th.profile, b, depth=kw.pop("depth", th.depth), tol=tol, **kw)
        return abs(s.friction) / s.N

    out = {
        "tilt": (mu(tilt=h) - mu(tilt=-h)) / (2 * h),
        "depth": (mu(depth=th.depth + h) - mu(depth=th.depth - h)) / (2 * h),
        "tip_moment": (mu(tip_moment=h) - mu(tip_moment=-h)) / (2 * h),
    }
    i = int(np.argmin(np.abs(b.s - b.gamma)))
    out["kappa_gamma"] = float(th.profile(b.gamma) + b.moment[i] / th.params.D)
    return {k: float(v) for k, v in out.items()}


def slip_depth(th: HoldThreshold, mu_s: float, *, step: float = 0.01, tol: float = 1e-10) -> float | None:
    """Where a tip that cannot stick at ``th.depth`` stops sliding, over ``l``.

    The box slides down relative to the tip: Grip I's depth (the tip below the top edge) shrinks, Grip II's
    (the tip above the bottom edge) grows.  Continued in steps of ``step`` from ``th.depth`` until ``mu*`` has
    fallen to ``mu_s``, then the root of ``mu*(depth) = mu_s`` (``brentq``, to 1e-7 l): the first depth at which
    the tip sticks.  ``th.depth`` itself if ``mu_s >= mu*``; ``None`` if the valid corner branch ends first (a
    solve fails, a force turns negative, the rod enters the box, or the depth leaves (0.05, 1.95)): the theory
    then has no rest with this contact set (the box falls, or another contact set takes over).  ``tol``: the
    ``solve_bvp`` tolerance of each solve.
    """
    from scipy.optimize import brentq

    from simgrip.reference.free_boundary import FreeBoundaryError, solve_corner

    mu_s = float(mu_s)
    if not (math.isfinite(mu_s) and mu_s >= 0.0):
        raise ValueError(f"mu_s must be finite and >= 0, got {mu_s!r}")
    if not (isinstance(step, (int, float)) and 0.0 < step <= 0.1):
        raise ValueError(f"step must lie in (0, 0.1], got {step!r}")
    if th.held(mu_s):
        return th.depth
    if th.contact_set != "tip + corner":
        return None
    sign = -1.0 if th.grip == "I" else 1.0
    cache = {th.depth: th.solution}

    def mu_at(d, start):
        sol = solve_corner(th.grip, th.params, th.profile, start, depth=d, tol=tol)
        if not sol.valid or sol.N <= 0:
            raise FreeBoundaryError(f"the corner branch is invalid at depth {d:.4g}: {sol.violations}")
        cache[d] = sol
        return abs(sol.friction) / sol.N

    d_prev, start = th.depth, th.solution
    try:
        while True:
            d = d_prev + sign * step
            if not 0.05 < d < 1.95:
                return None
            if mu_at(d, start) <= mu_s:
                near = cache[d_prev]
                return float(brentq(lambda x: mu_at(x, near) - mu_s, min(d, d_prev), max(d, d_prev), xtol=1e-7))
            d_prev, start = d, cache[d]
    except FreeBoundaryError:
        return None

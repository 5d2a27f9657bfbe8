"""The free-boundary elastica of Grips I/II past the point-contact range: the tip on the side face and the
box's corner on the rod at an unknown arc length ``gamma``.

Model (the box of :mod:`simgrip.reference.constrained`, centreline terms, dimensionless: ``l = 1``,
``rho g = 1``, ``EI = D``): the box occupies ``X < b/2`` beyond its top face ``Y = Y(1) + depth`` (Grip I,
``sd = +1``; Grip II: below ``Y(1) - depth``, ``sd = -1``); it hangs on the tip (the tip sticks to the
face), so it moves with it; the corner ``(b/2, Y(1) + sd depth)`` is frictionless.

Balance laws (the paper's eq. 7 with two singular forces).  With ``n(s)`` the force the part beyond ``s``
exerts on the part before it, ``n' = E2`` (the rod's weight), the tip force ``n(1) = N E1 + F_f E2``, the
corner force ``F_gamma = P e_out`` with ``e_out = sd (-sin theta_g, cos theta_g)`` (normal to the rod at
``gamma``, pointing out of the box: frictionless) and the jump ``[[n]]_gamma + F_gamma = 0``::

    n = N E1 + (F_f - (1 - s)) E2                        on (gamma, 1)
    n = (N + P e_out,1) E1 + (F_f + P e_out,2 - (1 - s)) E2   on (0, gamma)
    m = D (theta' - kappa0),   m' = n1 sin theta - n2 cos theta,   X' = cos theta,  Y' = sin theta

The box's vertical balance (weight ``M``, the tip's friction, the corner) gives ``F_f = -M - P e_out,2``:
on ``(0, gamma)`` the vertical force is just ``-M - (1 - s)``.

Boundary and matching conditions (12 for 8 states on two segments mapped to ``[0, 1]`` and the four
parameters ``N, P, gamma, theta_g``)::

    theta(0) = X(0) = Y(0) = 0                         clamp
    theta, m, X, Y continuous at gamma                 (a point force: no couple, no kink)
    m(1) = 0,  X(1) = b/2                              moment-free tip on the face
    X(gamma) = b/2,  Y(gamma) = Y(1) + sd depth        the corner on the rod
    theta(gamma) = theta_g

Natural boundary condition at the free contact point.  ``gamma`` (the material point that meets the
corner) is unknown; varying it at fixed shape moves the contact along the rod, and stationarity of the
energy with respect to that variation requires the contact force to do no work along the rod:
``F_gamma . r'(gamma) = 0``, i.e. the corner's force is normal to the rod (no friction).  With that the
two geometric conditions fix ``P`` and ``gamma``.  (For a contact *interval* on a flat face the same
variation of its end points gives continuity of the curvature there, ``theta' = kappa_face = 0`` at the
ends, i.e. a continuous moment; on a cylinder of radius ``R``, ``theta' = -+1/R`` at the ends of the
wrapped arc; a second point contact carries a jump in the shear.  The cases below did not need them:
at kappa = -10 Grip I's contact set is {tip, corner}, found by the constrained chain.)

Order (derived; checked in ``tests/test_free_boundary.py``).  The hinge chain is second order on smooth
segments, but it touches the corner with a straight link: the corner's force is along that link's normal,
off the rod's normal at ``gamma`` by the rod's turning over at most one link, ``|theta'(gamma)| ds``.  So
the contact force, and everything it loads, is first order: ``|N_n - N| <= |dN/dtilt| |theta'(gamma)| ds``
with ``dN/dtilt`` the BVP's sensitivity to turning the corner's force off the normal (``tilt``); the
coefficient depends on where in its link the corner falls (``gamma n mod 1``), so the error is not a
smooth function of ``n`` (no clean Richardson ratio).  Measured at kappa = -10: ``|N_n - N| n`` = 0.43,
0.25, 0.54, 0.61 at n = 16, 32, 64, 128 against the bound's 1.73.

Reference values (standard case D = 1, M = 5, b = 0.6, mu_s = 1; uniform kappa = -10; default
``depth = 0.4``): :data:`GRIP_I_KAPPA_M10` -- BVP N = 19.88035, gamma = 0.31334, tip (0.3, -0.478353),
tip friction -14.6054, corner force (5.5377, 9.6054); the chain at n = 32: N = 19.87244, n = 64:
19.87183 (4.3e-4 off), n = 128: 19.87557.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_bvp

from simgrip.params import DimensionlessParams
from simgrip.profiles import as_profile
from simgrip.reference.arguments import check_params
from simgrip.reference.bvp import antiderivative
from simgrip.reference.contact_geometry import self_crossing

__all__ = ["CornerSolution", "FreeBoundaryError", "GRIP_I_KAPPA_M10", "solve_corner"]


class FreeBoundaryError(RuntimeError):
    """The free-boundary BVP did not converge (or converged to an invalid state)."""


#: Grip I, standard case (D = 1, M = 5, b = 0.6, mu_s = 1), uniform kappa = -10, box depth 0.4: the
#: free-boundary BVP (n -> inf, solve_bvp tol 1e-10) and the constrained chain (continued from kappa = -7;
#: ``simgrip solve I --kappa -10 --contact full``).  Contact set: the tip on the side face X = b/2 and the
#: box's top corner (b/2, Y(1) + 0.4) on the rod at gamma; forces on the rod over rho g l.
#: Checked by tests/test_free_boundary.py.
GRIP_I_KAPPA_M10 = {
    "bvp": dict(N=19.880350, gamma=0.313340, P=11.087395, tip_y=-0.478353, friction=-14.605403,
                corner_force=(5.537739, 9.605403)),
    "chain": {
        16: dict(N=19.907435, tip_y=-0.477339, friction=-14.364080, gamma=0.312789),
        32: dict(N=19.872440, tip_y=-0.477951, friction=-14.552688, gamma=0.313159),
        64: dict(N=19.871835, tip_y=-0.478185, friction=-14.595590, gamma=0.313276),
        128: dict(N=19.875570, tip_y=-0.478284, friction=-14.604307, gamma=0.313317),
    },
}


@dataclass(frozen=True)
class CornerSolution:
    """The free-boundary equilibrium: ``N`` the tip's normal force, ``friction`` its vertical force on the
    rod (``F_f``), ``P`` the corner's normal force and ``corner_force`` its E1/E2 components (on the rod),
    ``gamma`` where the corner touches, ``tip`` [X, Y], ``s, theta, x, y, moment`` on a fine grid
    (a node at ``gamma``), ``valid`` and ``violations`` (what a point of the rod does wrong, if anything)."""

    grip: str
    params: DimensionlessParams
    depth: float
    N: float
    friction: float
    P: float
    corner_force: np.ndarray
    gamma: float
    theta_gamma: float
    tip: np.ndarray
    s: np.ndarray
    theta: np.ndarray
    x: np.ndarray
    y: np.ndarray
    moment: np.ndarray
    valid: bool
    violations: tuple
    residual: float


def _e_out(sd, th, tilt=0.0):
    """The corner's push direction: the rod's normal at ``theta_g`` out of the box (turned by ``tilt``)."""
    return sd * np.array([-np.sin(th + tilt), np.cos(th + tilt)])


def _system(D, M, prof, K, xb, sd, depth, tilt=0.0, tip_moment=0.0):
    def fun(t, y, p):
        N, P, gam, thg = p
        e = _e_out(sd, thg, tilt)
        out = np.empty_like(y)
        for seg, (s0, L) in enumerate(((0.0, gam), (gam, 1.0 - gam))):
            th, m = y[4 * seg], y[4 * seg + 1]
            s = s0 + L * t
            if seg == 0:
                n1, n2 = N + P * e[0], -M - (1.0 - s)
            else:
                n1, n2 = N, -M - P * e[1] - (1.0 - s)
            out[4 * seg] = L * (prof(s) + m / D)
            out[4 * seg + 1] = L * (n1 * np.sin(th) - n2 * np.cos(th))
            out[4 * seg + 2] = L * np.cos(th)
            out[4 * seg + 3] = L * np.sin(th)
        return out

    def bc(ya, yb, p):
        N, P, gam, thg = p
        return np.array([
            ya[0], ya[2], ya[3],
            ya[4] - yb[0], ya[5] - yb[1], ya[6] - yb[2], ya[7] - yb[3],
            yb[5] - tip_moment, yb[6] - xb,
            yb[2] - xb, yb[3] - yb[7] - sd * depth,
            yb[0] - thg,
        ])

    return fun, bc


def _validity(grip, xb, sd, depth, s, x, y, gamma, N, P):
    """What the solution does wrong: a negative force, a point inside the box (beyond the corner's
    neighbourhood), left of the mirror plane X = 0, or the centreline crossing itself."""
    bad = []
    if N < 0:
        bad.append(f"tip normal force N = {N:.4g} < 0")
    if P < 0:
        bad.append(f"corner force P = {P:.4g} < 0 (the corner would pull)")
    top = y[-1] + sd * depth
    inside = (x < xb - 1e-9) & (sd * (y - top) < -1e-9)
    if np.any(inside):
        bad.append(f"the rod enters the box at s = {float(s[np.argmax(inside)]):.4g}")
    if np.min(x[1:]) < -1e-9:
        bad.append(f"the rod crosses the mirror plane X = 0 (min X = {float(np.min(x)):.4g})")
    if self_crossing(np.stack([x, y], axis=1), 0.0):
        bad.append("the centreline crosses itself")
    return tuple(bad)


def solve_corner(grip, params, profile, guess, *, depth=0.4, tol=1e-10, tilt=0.0,
                 tip_moment=0.0) -> CornerSolution:
    """Solve the tip + corner free-boundary BVP of Grip I/II (see the module docstring).

    Parameters
    ----------
    grip : {"I", "II"}
    params : DimensionlessParams
    profile : CurvatureProfile, float or callable
    guess : ConstrainedEquilibrium or CornerSolution
        A start on this branch: the constrained chain (:func:`~simgrip.reference.constrained.solve_constrained`)
        with exactly one corner contact, or a previous solution (continuation).
    depth : float
        The tip's distance below the top face (I) / above the bottom face (II), over ``l``.
    tol : float
        ``solve_bvp`` tolerance.
    tilt : float
        Turn the corner's force by this angle [rad] off the rod's normal (0: the frictionless corner; a
        sensitivity for the discretisation-error bound, see the module docstring).
    tip_moment : float
        A couple at the tip, ``m(1)``, over ``rho g l^2`` (0: the paper's moment-free tip; a sensitivity for a
        model whose tip force acts off the centreline, :mod:`simgrip.reference.hold_full`).

    Raises
    ------
    ValueError
        Bad arguments, or a guess without a single corner contact.
    FreeBoundaryError
        ``solve_bvp`` did not converge.
    """
    if grip not in ("I", "II"):
        raise ValueError(f"grip must be 'I' or 'II' for the corner free-boundary problem, got {grip!r}")
    params = check_params(params)
    prof = as_profile(profile)
    depth = float(depth)
    if not (math.isfinite(depth) and 0.0 < depth < 2.0):
        raise ValueError(f"depth must lie in (0, 2), got {depth!r}")
    sd = 1 if grip == "I" else -1
    xb = 0.5 * params.b
    t = np.linspace(0.0, 1.0, 81)
    if isinstance(guess, CornerSolution):
        gam, thg, N, P = guess.gamma, guess.theta_gamma, guess.N, guess.P
        sA, sB = gam * t, gam + (1 - gam) * t

        def state(ss):
            return [np.interp(ss, guess.s, v) for v in (guess.theta, guess.moment, guess.x, guess.y)]
    elif hasattr(guess, "contacts") and hasattr(guess, "link_angles"):
        corners = [c for c in guess.contacts if c.kind == "corner"]
        if len(corners) != 1 or len(guess.contacts) != 1:
            raise ValueError("guess: the constrained chain must touch the box at its corner only (besides "
                             f"the tip), got {guess.kinds()}")
        c = corners[0]
        n = guess.n
        ds = 1.0 / n
        j = c.index
        gam = (j + np.linalg.norm(c.point - guess.nodes[j]) / ds) * ds
        thg = float(guess.link_angles[j])
        N = guess.N
        P = float(np.linalg.norm(c.force))
        sm = (np.arange(n) + 0.5) * ds
        sn = np.arange(n + 1) * ds
        q = np.diff(guess.link_angles)
        mom = np.concatenate([[0.0], guess.params.D * (q / ds - prof(sn[1:-1])), [0.0]])
        sA, sB = gam * t, gam + (1 - gam) * t

        def state(ss):
            return [np.interp(ss, sm, guess.link_angles), np.interp(ss, sn, mom),
                    np.interp(ss, sn, guess.nodes[:, 0]), np.interp(ss, sn, guess.nodes[:, 1])]
    else:
        raise ValueError("guess must be a ConstrainedEquilibrium (one corner contact) or a CornerSolution")
    y0 = np.vstack(state(sA) + state(sB))
    tip_moment = float(tip_moment)
    if not math.isfinite(tip_moment):
        raise ValueError(f"tip_moment must be finite, got {tip_moment!r}")
    fun, bc = _system(params.D, params.M, prof, antiderivative(prof), xb, sd, depth, float(tilt), tip_moment)
    r = solve_bvp(fun, bc, t, y0, p=np.array([N, P, gam, thg]), tol=tol, max_nodes=20000, bc_tol=tol)
    if r.status != 0 or not np.all(np.isfinite(r.p)):
        raise FreeBoundaryError(f"solve_bvp: {r.message}")
    N, P, gam, thg = (float(v) for v in r.p)
    if not 0.0 < gam < 1.0:
        raise FreeBoundaryError(f"the corner left the rod (gamma = {gam:.4g})")
    tf = np.linspace(0.0, 1.0, 401)
    ya, yb = r.sol(tf), r.sol(tf)
    s = np.concatenate([gam * tf, gam + (1 - gam) * tf[1:]])
    ys = np.concatenate([ya[:4], yb[4:, 1:]], axis=1)
    e = _e_out(sd, thg, float(tilt))
    F = P * e
    bad = _validity(grip, xb, sd, depth, s, ys[2], ys[3], gam, N, P)
    return CornerSolution(grip=grip, params=params, depth=depth, N=N, friction=-params.M - F[1], P=P,
                          corner_force=F, gamma=gam, theta_gamma=thg, tip=np.array([ys[2, -1], ys[3, -1]]),
                          s=s, theta=ys[0], x=ys[2], y=ys[3], moment=ys[1], valid=not bad, violations=bad,
                          residual=float(np.max(r.rms_residuals)))

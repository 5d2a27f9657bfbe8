"""Continuous reference: planar elastica boundary-value problems (free rod, Grips I-III).

Everything is dimensionless (``l = 1``, ``rho g = 1``, so ``EI = D`` and the
per-finger workpiece weight is ``M``); conventions are those of ``NOTES.md``:
``E1`` horizontal from the palm centre towards the finger, ``E2`` up, gravity
``-E2`` per unit length, ``theta`` counter-clockwise from ``E1``, forces named in
results are forces the workpiece exerts **on the rod**.

Balance laws
------------
Let ``n(s)`` be the force and ``m(s)`` the moment (``E3`` component) that the
part of the rod beyond ``s`` exerts on the part before ``s``.  Balancing the piece
``[s, 1]`` gives (paper eq. 7)::

    n' = g E2,        m' + (r' x n) . E3 = 0,        m = D (theta' - kappa0)

so with the state ``y = (theta, m, X, Y)``::

    theta' = kappa0(s) + m / D
    m'     = n1 sin(theta) - n2 cos(theta)
    X'     = cos(theta),   Y' = sin(theta)

and ``theta(0) = X(0) = Y(0) = 0``.  Using ``m`` as a state avoids ``kappa0'``,
so profiles need only be integrable, not differentiable.

* **free** rod (Fig. 6): ``n(s) = F_tip - g (1 - s) E2`` with ``F_tip = tip_load``;
  ``m(1) = contact_moment`` (a tip couple, 0 by default).
* **Grips I and II** (Figs. 4, 7, 8): the workpiece pushes on the tip with
  ``N E1 + F_f E2``, ``F_f = -M`` known, ``N`` unknown (a ``solve_bvp``
  parameter) fixed by ``X(1) = b/2``; ``n(s) = (N + t1) E1 + (F_f + t2 - g(1-s)) E2``
  and ``m(1) = contact_moment``.  I curls down (``kappa0 < 0``, palm down), II up
  (``kappa0 > 0``, palm up); the equations are the same.
* **Grip III** (Figs. 5, 9): the workpiece's corner pushes on the rod at
  ``s = gamma`` with ``F = N1 E1 + N2 E2``, ``N2 = -M``, ``N1`` fixed by
  ``X(gamma) = b/2``.  The jump condition ``[[n]]_gamma + F = 0`` gives::

      n(s) = (N1 + t1) E1 + (N2 + t2 - g(1-s)) E2     on (0, gamma)
      n(s) =        t1 E1 + (     t2 - g(1-s)) E2     on (gamma, 1)

  i.e. the contact terms act on the segment **between the clamp and the
  contact** (the paper's eq. 21 prints them on ``(gamma, 1)``: an erratum).
  A couple ``C E3`` applied to the rod at the contact (``contact_moment``) gives,
  from the moment balance of an infinitesimal piece around ``gamma``
  (``m(gamma+) - m(gamma-) + C = 0``), the jump ``m(gamma+) - m(gamma-) = -C``;
  the tip is moment free, ``m(1) = 0``.  The two segments are mapped onto
  ``t in [0, 1]`` (``s = gamma t`` and ``s = gamma + (1 - gamma) t``), giving an
  8-state problem with continuity of ``theta, X, Y`` at ``gamma``.
  With ``e1 = (cos th_g, sin th_g)``, ``e2 = (-sin th_g, cos th_g)``:
  ``f = F . e1`` (friction), ``n = F . e2`` (normal).

For the grips, a nonzero ``tip_load`` is an extra force on the tip (``t1, t2``
above), in addition to the contact force; it is zero in the paper.

Solving
-------
``scipy.integrate.solve_bvp`` with analytic Jacobians; the first state of each
segment is ``phi = theta - int_0^s kappa0`` (exact antiderivatives for the
uniform and eq. 34 profiles), so non-smooth profiles do not stall the residual
control.  A cold start is never handed to Newton directly (it fails with
singular Jacobians, see NOTES).  For a grip, the solve starts from the exact
unloaded circular arc that puts the contact at ``X = b/2`` curling the grip's
way (down for I and III, up for II: this picks the branch, e.g. Grip II's
finger wraps the workpiece from above-outside), blends the profile into the
requested one, then ramps gravity and loads in (fallbacks: loads before profile;
the other curl; the straight rod with curvature and loads ramped together, then
the width target moved from where the free rod puts it to ``b/2``).  The free
rod ramps curvature and loads from the straight rod.  A warm start
(``guess=``) is tried directly, then by continuation from the guess's problem to
the requested one, then cold.  Each step is first solved at a loose tolerance
(cheap failures), then polished to ``tol``; meshes handed on are thinned so they
do not grow along sweeps.

Default ``tol = 1e-8`` (``solve_bvp``'s relative residual): the tip then agrees
with a ``tol = 1e-11`` solution to ~1e-12, while ``tol = 1e-10`` costs 3-10x
more time for nothing visible.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from dataclasses import replace as _dc_replace
from typing import Callable, Sequence

import numpy as np
from scipy import special as _sp
from scipy.integrate import solve_bvp
from scipy.optimize import brentq

from simgrip.params import DimensionlessParams, _finite, check_grip
from simgrip.profiles import Concentrated, CurvatureProfile, Uniform, as_profile

__all__ = [
    "ElasticaError",
    "ElasticaSolution",
    "solve",
    "sweep",
    "kappa_sweep",
    "least_mu",
    "max_load",
    "FINE_POINTS",
]

#: Number of points of the fine output grid of every solution.
FINE_POINTS = 201

_TOL_MID = 1e-6  # tolerance of intermediate continuation steps
_MAX_NODES = 6000  # per solve_bvp run at the final tolerance (tol 1e-8 needs ~1000)
_MAX_NODES_MID = 1000  # per run at the intermediate tolerance
_H_MIN = 2.0**-12  # smallest continuation step (fraction of the path)
_MAX_TRIES = 80  # solve_bvp runs allowed to one continuation
_GUESS_NODES = 301  # largest mesh handed to solve_bvp as a starting guess


class ElasticaError(RuntimeError):
    """The elastica BVP could not be solved, even by continuation."""


# --------------------------------------------------------------------------- internals


class _Blend(CurvatureProfile):
    """``(1 - w) p0 + w p1``: a path between two profiles (continuation only)."""

    def __init__(self, p0: CurvatureProfile, p1: CurvatureProfile, w: float):
        self.p0, self.p1, self.w = p0, p1, float(w)

    def _eval(self, s):
        if self.w == 0.0:
            return self.p0(s)
        if self.w == 1.0:
            return self.p1(s)
        return (1.0 - self.w) * self.p0(s) + self.w * self.p1(s)

    def __repr__(self):
        return f"_Blend({self.p0!r}, {self.p1!r}, {self.w:g})"


def _antiderivative(profile: CurvatureProfile) -> Callable[[np.ndarray], np.ndarray]:
    """``K(s) = int_0^s kappa_bar``, exact where a closed form exists.

    Uniform: ``kappa s``; the concentrated profile (eq. 34):
    ``p kappa_max 4^alpha B(alpha+1, alpha+1) I_s(alpha+1, alpha+1)`` (regularised
    incomplete beta function); otherwise the profile's own ``integral``.
    """
    if isinstance(profile, Uniform):
        k = profile.kappa
        return lambda s: k * np.asarray(s, dtype=float)
    if isinstance(profile, Concentrated):
        a = profile.alpha + 1.0
        c = profile.p * profile.kappa_max * 4.0**profile.alpha * _sp.beta(a, a)
        return lambda s: c * _sp.betainc(a, a, np.clip(np.asarray(s, dtype=float), 0.0, 1.0))
    if isinstance(profile, _Blend):
        K0, K1, w = _antiderivative(profile.p0), _antiderivative(profile.p1), profile.w
        return lambda s: (1.0 - w) * K0(s) + w * K1(s)
    return lambda s: profile.integral(np.zeros_like(np.asarray(s, dtype=float)), s)


@dataclass(frozen=True)
class _Problem:
    """One BVP.  ``target is None``: contact force ``N1`` is given; else ``N1`` is the
    unknown parameter and the contact must sit at ``X = target``."""

    two_seg: bool  # True: contact at interior gamma (Grip III); False: at the tip
    D: float
    g: float  # 1 with gravity, 0 without (ramped by continuation)
    profile: CurvatureProfile
    t1: float  # extra tip load
    t2: float
    N1: float  # contact force E1 component (used when target is None)
    N2: float  # contact force E2 component
    C: float  # contact couple
    gamma: float  # contact arc length (1.0 when not two_seg)
    target: float | None  # X of the contact, or None
    sigma: int = -1  # curl direction of the grip's branch: -1 down (I, III), +1 up (II)

    @property
    def K(self) -> Callable[[np.ndarray], np.ndarray]:
        """Integrated intrinsic curvature ``K(s)``; ``theta = phi + K``."""
        k = self.__dict__.get("_K")
        if k is None:
            k = _antiderivative(self.profile)
            object.__setattr__(self, "_K", k)
        return k

    @property
    def constrained(self) -> bool:
        return self.target is not None

    @property
    def n(self) -> int:
        return 8 if self.two_seg else 4


@dataclass
class _Raw:
    """A converged ``solve_bvp`` result together with its problem."""

    prob: _Problem
    x: np.ndarray
    y: np.ndarray
    p: np.ndarray
    sol: Callable
    rms: float
    message: str

    @property
    def N1(self) -> float:
        return float(self.p[0]) if self.prob.constrained else self.prob.N1

    def states(self, s) -> np.ndarray:
        """``(theta, m, X, Y)`` at arc lengths ``s`` (shape ``(4,) + s.shape``)."""
        s = np.asarray(s, dtype=float)
        flat = np.clip(s.ravel(), 0.0, 1.0)
        if not self.prob.two_seg:
            out = np.array(self.sol(flat), dtype=float)
        else:
            gam = self.prob.gamma
            out = np.empty((4, flat.size))
            a = flat <= gam
            if np.any(a):
                out[:, a] = self.sol(flat[a] / gam)[:4]
            if np.any(~a):
                out[:, ~a] = self.sol((flat[~a] - gam) / (1.0 - gam))[4:]
        out[0] += self.prob.K(flat)
        return out.reshape((4,) + s.shape)

    def contact_state(self) -> np.ndarray:
        """``(theta, m, X, Y)`` at the contact (``m`` on the clamp side)."""
        out = (self.y[:4, -1] if self.prob.two_seg else self.y[:, -1]).astype(float)
        out[0] += float(self.prob.K(np.array([self.prob.gamma]))[0])
        return out


def _system(P: _Problem):
    """``fun, bc, fun_jac, bc_jac`` for ``solve_bvp``, vectorised over the mesh.

    The first state of each segment is ``phi = theta - K(s)`` with
    ``K = int_0^s kappa_bar``, so ``phi' = m / D`` is as smooth as ``m``: profiles
    with singular derivatives (eq. 34 at the ends for non-integer ``alpha``) do
    not stall the residual control.  ``theta(0) = 0`` is ``phi(0) = 0`` and the
    continuity of ``theta`` at ``gamma`` is that of ``phi``.
    """
    D, g, K = P.D, P.g, P.K
    t1, t2, N2, C = P.t1, P.t2, P.N2, P.C
    con = P.constrained
    N1fix = P.N1

    if not P.two_seg:

        def fun(t, y, p=None):
            N1 = p[0] if con else N1fix
            th, m = y[0] + K(t), y[1]
            n1 = N1 + t1
            n2 = N2 + t2 - g * (1.0 - t)
            c, sn = np.cos(th), np.sin(th)
            return np.vstack((m / D, n1 * sn - n2 * c, c, sn))

        def fun_jac(t, y, p=None):
            N1 = p[0] if con else N1fix
            th = y[0] + K(t)
            n1 = N1 + t1
            n2 = N2 + t2 - g * (1.0 - t)
            c, sn = np.cos(th), np.sin(th)
            k = t.size
            J = np.zeros((4, 4, k))
            J[0, 1] = 1.0 / D
            J[1, 0] = n1 * c + n2 * sn
            J[2, 0] = -sn
            J[3, 0] = c
            if not con:
                return J
            Jp = np.zeros((4, 1, k))
            Jp[1, 0] = sn
            return J, Jp

        def bc(ya, yb, p=None):
            r = [ya[0], ya[2], ya[3], yb[1] - C]
            if con:
                r.append(yb[2] - P.target)
            return np.array(r)

        def bc_jac(ya, yb, p=None):
            nb = 5 if con else 4
            A = np.zeros((nb, 4))
            B = np.zeros((nb, 4))
            A[0, 0] = A[1, 2] = A[2, 3] = 1.0
            B[3, 1] = 1.0
            if not con:
                return A, B
            B[4, 2] = 1.0
            return A, B, np.zeros((nb, 1))

        return fun, bc, fun_jac, bc_jac

    gam = P.gamma
    ga, gb = gam, 1.0 - gam

    def fun(t, y, p=None):
        N1 = p[0] if con else N1fix
        sa = gam * t
        sb = gam + gb * t
        tha, thb = y[0] + K(sa), y[4] + K(sb)
        ca, sna = np.cos(tha), np.sin(tha)
        cb, snb = np.cos(thb), np.sin(thb)
        n1a = N1 + t1
        n2a = N2 + t2 - g * (1.0 - sa)
        n2b = t2 - g * (1.0 - sb)
        return np.vstack(
            (
                ga * y[1] / D,
                ga * (n1a * sna - n2a * ca),
                ga * ca,
                ga * sna,
                gb * y[5] / D,
                gb * (t1 * snb - n2b * cb),
                gb * cb,
                gb * snb,
            )
        )

    def fun_jac(t, y, p=None):
        N1 = p[0] if con else N1fix
        sa = gam * t
        sb = gam + gb * t
        tha, thb = y[0] + K(sa), y[4] + K(sb)
        ca, sna = np.cos(tha), np.sin(tha)
        cb, snb = np.cos(thb), np.sin(thb)
        n1a = N1 + t1
        n2a = N2 + t2 - g * (1.0 - sa)
        n2b = t2 - g * (1.0 - sb)
        k = t.size
        J = np.zeros((8, 8, k))
        J[0, 1] = ga / D
        J[1, 0] = ga * (n1a * ca + n2a * sna)
        J[2, 0] = -ga * sna
        J[3, 0] = ga * ca
        J[4, 5] = gb / D
        J[5, 4] = gb * (t1 * cb + n2b * snb)
        J[6, 4] = -gb * snb
        J[7, 4] = gb * cb
        if not con:
            return J
        Jp = np.zeros((8, 1, k))
        Jp[1, 0] = ga * sna
        return J, Jp

    def bc(ya, yb, p=None):
        r = [
            ya[0],
            ya[2],
            ya[3],
            yb[5],  # moment-free tip
            ya[4] - yb[0],
            ya[5] - yb[1] + C,  # m(gamma+) - m(gamma-) = -C
            ya[6] - yb[2],
            ya[7] - yb[3],
        ]
        if con:
            r.append(yb[2] - P.target)
        return np.array(r)

    def bc_jac(ya, yb, p=None):
        nb = 9 if con else 8
        A = np.zeros((nb, 8))
        B = np.zeros((nb, 8))
        A[0, 0] = A[1, 2] = A[2, 3] = 1.0
        B[3, 5] = 1.0
        for i, (ia, ib) in enumerate(((4, 0), (5, 1), (6, 2), (7, 3))):
            A[4 + i, ia] = 1.0
            B[4 + i, ib] = -1.0
        if not con:
            return A, B
        B[8, 2] = 1.0
        return A, B, np.zeros((nb, 1))

    return fun, bc, fun_jac, bc_jac


def _mesh_guess(raw: _Raw, P: _Problem) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
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


def _bvp(P: _Problem, x, y, p, tol: float) -> _Raw | None:
    """One ``solve_bvp`` run; ``None`` unless it converged to a finite solution."""
    fun, bc, fun_jac, bc_jac = _system(P)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            r = solve_bvp(
                fun, bc, x, y, p=p, fun_jac=fun_jac, bc_jac=bc_jac, tol=tol,
                max_nodes=_MAX_NODES if tol < _TOL_MID else _MAX_NODES_MID,
            )
        except (np.linalg.LinAlgError, ValueError, FloatingPointError, ZeroDivisionError):
            return None
    if r.status != 0 or not np.all(np.isfinite(r.y)):
        return None
    if r.p is not None and not np.all(np.isfinite(r.p)):
        return None
    rp = np.asarray(r.p, dtype=float) if r.p is not None else np.zeros(0)
    return _Raw(P, r.x, r.y, rp, r.sol, float(np.max(r.rms_residuals)), r.message)


def _from(raw: _Raw, P: _Problem, tol: float) -> _Raw | None:
    """Solve ``P`` from the guess ``raw``: first at the loose intermediate tolerance
    (a failure is cheap there), then polished to ``tol``."""
    x, y, p = _mesh_guess(raw, P)
    r = _bvp(P, x, y, p, max(tol, _TOL_MID))
    if r is None or tol >= _TOL_MID:
        return r
    return _bvp(P, r.x, r.y, r.p if P.constrained else None, tol)


_MAX_JUMP = 0.75  # radians: largest change of theta accepted in one continuation step
_JUMP_GRID = np.linspace(0.0, 1.0, 41)


def _theta_jump(a: _Raw, b: _Raw) -> float:
    """Largest change of ``theta`` between two solutions (branch-jump detector)."""
    return float(np.max(np.abs(a.states(_JUMP_GRID)[0] - b.states(_JUMP_GRID)[0])))


def _continue(
    path: Callable[[float], _Problem],
    raw: _Raw,
    tol: float,
    h: float = 1.0,
    max_jump: float | None = None,
    h_min: float = _H_MIN,
    max_tries: int = _MAX_TRIES,
) -> _Raw | None:
    """Natural-parameter continuation along ``path(w)``, ``w: 0 -> 1``, from ``raw``
    (a solution at ``w = 0``); adaptive step, halved on failure.  Returns the
    solution at ``w = 1`` (at tolerance ``tol``) or ``None``.  With ``max_jump``,
    a step whose ``theta`` moves by more than that many radians counts as a
    failure: the solver has left the branch (natural continuation cannot pass
    a fold, so the path then fails, as it should)."""
    w = 0.0
    tries = 0
    while w < 1.0:
        tries += 1
        if tries > max_tries:
            return None
        h = min(h, 1.0 - w)
        wn = 1.0 if 1.0 - (w + h) < 1e-12 else w + h
        r = _from(raw, path(wn), _TOL_MID if wn < 1.0 else tol)
        if r is not None and max_jump is not None and _theta_jump(raw, r) > max_jump:
            r = None
        if r is None:
            h *= 0.5
            if h < h_min:
                return None
            continue
        raw, w = r, wn
        h *= 2.0
    return raw


def _straight(P: _Problem) -> _Raw:
    """The straight unloaded rod: the exact solution when curvature and loads vanish."""
    x = np.linspace(0.0, 1.0, 21)
    z = np.zeros_like(x)
    if P.two_seg:
        y = np.vstack((z, z, P.gamma * x, z, z, z, P.gamma + (1.0 - P.gamma) * x, z))
    else:
        y = np.vstack((z, z, x, z))

    def sol(t, _n=y.shape[0], _two=P.two_seg, _g=P.gamma):
        t = np.asarray(t, dtype=float)
        zz = np.zeros_like(t)
        if _two:
            return np.vstack((zz, zz, _g * t, zz, zz, zz, _g + (1.0 - _g) * t, zz))
        return np.vstack((zz, zz, t, zz))

    P0 = _dc_replace(P, target=None, N1=0.0)
    return _Raw(P0, x, y, np.zeros(0), sol, 0.0, "straight rod")


def _scaled(P: _Problem, lam: float, curvature: bool = True, loads: bool = True) -> _Problem:
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


def _arc(P: _Problem) -> _Raw | None:
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
    return _bvp(P0, x, y, np.array([0.0]), _TOL_MID)


def _cold(P: _Problem, tol: float) -> _Raw | None:
    """Solve ``P`` from nothing by continuation from an exactly known solution."""
    free = _dc_replace(P, target=None, N1=0.0 if P.constrained else P.N1)
    straight = _straight(P)

    def to_target(base: _Raw, Pc: _Problem) -> _Raw | None:
        """Move the contact's width target from where ``base`` has it to ``Pc.target``."""
        X0 = float(base.contact_state()[2])
        start = _dc_replace(base.prob, target=X0, N1=0.0)
        # ``base`` solves ``start`` exactly (N1 = base.N1 at X = X0).
        base = _Raw(start, base.x, base.y, np.array([base.N1]), base.sol, base.rms, base.message)
        return _continue(lambda w: _dc_replace(Pc, target=(1.0 - w) * X0 + w * Pc.target), base, tol)

    if P.constrained:
        # Strategy 1 (grips): the unloaded arc through the contact, curling the
        # grip's way, then the profile (unloaded), then the loads.  Strategy 1b:
        # the arc, then the loads, then the profile (heavy loads on a soft rod
        # straighten it; curling it first and unwinding it under load meets
        # folds).  As a last resort both again from an arc curling the other way.
        for sigma in (P.sigma, -P.sigma):
            arc = _arc(_dc_replace(P, sigma=sigma))
            if arc is None:
                break
            unloaded = _scaled(P, 0.0, curvature=False)
            raw = _continue(_between(arc.prob, unloaded), arc, _TOL_MID)
            if raw is not None:
                raw = _continue(lambda lam: _scaled(P, lam, curvature=False), raw, tol)
                if raw is not None:
                    return raw
            loaded = _dc_replace(P, profile=arc.prob.profile)
            raw = _continue(_between(arc.prob, loaded), arc, _TOL_MID)
            if raw is not None:
                raw = _continue(_between(loaded, P), raw, tol)
                if raw is not None:
                    return raw

    # Strategy 2: curvature and loads together from the straight rod, then width.
    raw = _continue(lambda lam: _scaled(free, lam), straight, tol if not P.constrained else _TOL_MID)
    if raw is not None:
        if not P.constrained:
            return raw
        out = to_target(raw, P)
        if out is not None:
            return out
    if not P.constrained:
        # Strategy 3 (free): loads first, then curvature.
        raw = _continue(lambda lam: _scaled(free, lam, curvature=False), straight, _TOL_MID, h=0.25)
        if raw is None:
            return None
        return _continue(lambda lam: _scaled(free, lam, loads=False) if lam > 0 else raw.prob, raw, tol)
    # Strategy 3 (grips): loads without curvature, then width, then curvature.
    flat = _scaled(P, 0.0, loads=False)
    raw = _continue(
        lambda lam: _scaled(_dc_replace(flat, target=None, N1=0.0), lam, curvature=False), straight, _TOL_MID
    )
    if raw is None:
        return None
    raw = to_target(raw, flat)
    if raw is None:
        return None
    return _continue(lambda lam: _dc_replace(P, profile=P.profile.scaled(lam)), raw, tol)


def _between(P0: _Problem, P1: _Problem) -> Callable[[float], _Problem] | None:
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
            profile=_Blend(P0.profile, P1.profile, w),
            t1=lerp(P0.t1, P1.t1, w),
            t2=lerp(P0.t2, P1.t2, w),
            N1=lerp(P0.N1, P1.N1, w),
            N2=lerp(P0.N2, P1.N2, w),
            C=lerp(P0.C, P1.C, w),
            gamma=lerp(P0.gamma, P1.gamma, w),
            target=None if P1.target is None else lerp(P0.target, P1.target, w),
        )

    return path


# --------------------------------------------------------------------------- results


@dataclass(frozen=True, eq=False)
class ElasticaSolution:
    """An equilibrium of the free rod or of one grip, dimensionless.

    Attributes
    ----------
    grip : str
        ``"free"``, ``"I"``, ``"II"`` or ``"III"``.
    params, profile
        The inputs (``params.M`` is ignored by the free rod).
    s, theta, x, y, moment : ndarray
        Fine grid (:data:`FINE_POINTS` points, ``s`` in ``[0, 1]``, Grip III has a
        node at ``gamma``) with the tangent angle, position and bending moment
        ``m = D (theta' - kappa0)``.  At ``gamma`` (Grip III) ``moment`` is the
        clamp-side value ``m(gamma-)``.
    tip : ndarray
        ``[X(1), Y(1)]``.
    contact : ndarray or None
        ``[x, y]`` of the contact point: the tip for Grips I/II, ``r(gamma)`` for
        Grip III, ``None`` for the free rod.
    gamma : float or None
        Contact arc length: 1.0 for Grips I/II, the one used for III, ``None`` free.
    N1, N2 : float
        Contact force on the rod, ``E1`` and ``E2`` components (I/II: ``N1 = N``,
        ``N2 = F_f = -M``).  0 for the free rod.
    n, f : float
        Normal and tangential (friction) components of the contact force in the
        workpiece's frame: Grip III along ``e2`` and ``e1`` at ``gamma``; Grips I/II
        the face is vertical, so ``n = N1``, ``f = N2``.  0 for the free rod.
    normal_force, friction_force : float
        ``n`` and ``f`` again, by role (I/II: ``N`` and ``F_f``).
    required_mu : float
        ``|friction_force| / normal_force``, the least friction coefficient that
        holds this configuration; ``inf`` when ``normal_force <= 0``; 0 for the
        free rod (nothing to hold).
    feasible : bool
        All of ``feasibility``'s entries (``True`` for the free rod).
    feasibility : dict
        ``"contact"``: normal force > 0; ``"friction"``: ``|f| <= mu_s n``; Grip III
        also ``"tip_clear"``: ``Y(1) < Y(gamma)`` (paper's condition 23).  Empty for
        the free rod.
    residual : float
        Largest relative rms collocation residual of ``solve_bvp``.
    success, message
        Convergence flag (always ``True`` for a returned solution) and solver message.
    gravity, tip_load, contact_moment
        The loading options the solution was computed with.
    """

    grip: str
    params: DimensionlessParams
    profile: CurvatureProfile
    s: np.ndarray
    theta: np.ndarray
    x: np.ndarray
    y: np.ndarray
    moment: np.ndarray
    tip: np.ndarray
    contact: np.ndarray | None
    gamma: float | None
    N1: float
    N2: float
    n: float
    f: float
    normal_force: float
    friction_force: float
    required_mu: float
    feasible: bool
    feasibility: dict
    residual: float
    success: bool
    message: str
    gravity: bool = True
    tip_load: tuple = (0.0, 0.0)
    contact_moment: float = 0.0
    _raw: _Raw | None = field(default=None, repr=False)

    def theta_at(self, s) -> np.ndarray:
        """Tangent angle at arc lengths ``s`` (array of ``s``'s shape), from the
        solver's C1 cubic interpolant."""
        return self._raw.states(s)[0]

    def moment_at(self, s) -> np.ndarray:
        """Bending moment at arc lengths ``s`` (Grip III: ``m(gamma-)`` at ``gamma``)."""
        return self._raw.states(s)[1]

    def position_at(self, s) -> np.ndarray:
        """Centreline position at arc lengths ``s``: shape ``s.shape + (2,)``, ``[..., 0] = X``."""
        st = self._raw.states(s)
        return np.moveaxis(st[2:4], 0, -1)

    @property
    def mesh_size(self) -> int:
        """Number of collocation nodes ``solve_bvp`` ended with."""
        return int(self._raw.x.size)


def _fine_grid(gamma: float | None) -> np.ndarray:
    k = FINE_POINTS - 1
    if gamma is None or gamma >= 1.0:
        return np.linspace(0.0, 1.0, FINE_POINTS)
    ka = min(max(1, int(round(k * gamma))), k - 1)
    return np.concatenate((np.linspace(0.0, gamma, ka + 1), np.linspace(gamma, 1.0, k - ka + 1)[1:]))


def _package(grip, params, profile, raw: _Raw, gravity, tip_load, contact_moment) -> ElasticaSolution:
    P = raw.prob
    s = _fine_grid(P.gamma if grip == "III" else None)
    th, m, X, Y = raw.states(s)
    tip = np.array([X[-1], Y[-1]])
    mu = params.mu_s
    if grip == "free":
        contact, gamma = None, None
        N1 = N2 = n = f = 0.0
        req = 0.0
        feas: dict = {}
    else:
        cs = raw.contact_state()
        contact = cs[2:4].copy()
        N1, N2 = raw.N1, P.N2
        if grip == "III":
            gamma = P.gamma
            thg = cs[0]
            f = N1 * math.cos(thg) + N2 * math.sin(thg)
            n = -N1 * math.sin(thg) + N2 * math.cos(thg)
        else:
            gamma = 1.0
            n, f = N1, N2
        req = abs(f) / n if n > 0 else math.inf
        feas = {"contact": bool(n > 0), "friction": bool(n > 0 and abs(f) <= mu * n)}
        if grip == "III":
            feas["tip_clear"] = bool(tip[1] < contact[1])
    return ElasticaSolution(
        grip=grip,
        params=params,
        profile=profile,
        s=s,
        theta=th,
        x=X,
        y=Y,
        moment=m,
        tip=tip,
        contact=contact,
        gamma=gamma,
        N1=float(N1),
        N2=float(N2),
        n=float(n),
        f=float(f),
        normal_force=float(n),
        friction_force=float(f),
        required_mu=float(req),
        feasible=all(feas.values()),
        feasibility=feas,
        residual=raw.rms,
        success=True,
        message=raw.message,
        gravity=bool(gravity),
        tip_load=tuple(float(v) for v in tip_load),
        contact_moment=float(contact_moment),
        _raw=raw,
    )


def _check_tip_load(tip_load) -> tuple[float, float]:
    try:
        t = np.asarray(tip_load, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"tip_load must be a pair of real numbers, got {tip_load!r}") from None
    if t.shape != (2,) or not np.all(np.isfinite(t)):
        raise ValueError(f"tip_load must be a pair of finite numbers, got {tip_load!r}")
    return float(t[0]), float(t[1])


def _problem(grip, params, profile, gravity, tip_load, contact_moment, gamma) -> _Problem:
    t1, t2 = _check_tip_load(tip_load)
    C = _finite("contact_moment", contact_moment)
    if grip == "III":
        gam = params.gamma if gamma is None else params.replace(gamma=gamma).gamma
        if gam <= params.b / 2.0:
            raise ValueError(
                f"gamma = {gam!r} must exceed b/2 = {params.b / 2.0!r} for Grip III "
                "(the contact at arc length gamma cannot reach X = b/2)"
            )
    else:
        gam = 1.0
    return _Problem(
        two_seg=grip == "III",
        D=params.D,
        g=1.0 if gravity else 0.0,
        profile=profile,
        t1=t1,
        t2=t2,
        N1=0.0,
        N2=0.0 if grip == "free" else -params.M,
        C=C,
        gamma=gam,
        target=None if grip == "free" else params.b / 2.0,
        sigma=1 if grip == "II" else -1,
    )


# --------------------------------------------------------------------------- public API


def solve(
    grip: str,
    params: DimensionlessParams,
    profile,
    *,
    gravity: bool = True,
    tip_load=(0.0, 0.0),
    contact_moment: float = 0.0,
    gamma: float | None = None,
    guess: ElasticaSolution | None = None,
    tol: float = 1e-8,
    fallback: bool = True,
) -> ElasticaSolution:
    """Solve the free rod or one grip for ``params`` and curvature ``profile``.

    Parameters
    ----------
    grip : {"free", "I", "II", "III"}
    params : DimensionlessParams
        ``D, M, b, mu_s, gamma`` (``M, b, mu_s, gamma`` unused by the free rod).
    profile : CurvatureProfile, float or callable
        Intrinsic curvature ``kappa_bar(s_bar)`` (see :func:`~simgrip.profiles.as_profile`).
    gravity : bool
        Include the rod's own weight (``-E2`` per unit length).
    tip_load : (float, float)
        Extra force ``(E1, E2)`` on the tip (over ``rho g l``), e.g. for the
        Bisshopp-Drucker cantilever; in addition to any contact force.
    contact_moment : float
        Couple (``E3``, over ``rho g l^2``) the workpiece applies to the rod at the
        contact: the tip couple ``m(1)`` for the free rod and Grips I/II, the jump
        ``m(gamma+) - m(gamma-) = -contact_moment`` for Grip III.
    gamma : float, optional
        Grip III contact arc length; ``params.gamma`` when ``None``.
    guess : ElasticaSolution, optional
        A solution to start from (any grip); continuation from its problem to this
        one is used if the direct start fails.
    tol : float
        ``solve_bvp`` tolerance (relative collocation residual and boundary residual).
    fallback : bool
        With ``False`` and a ``guess``, try only the direct warm start (one Newton
        run of ``solve_bvp``): fast and deterministic, for tracking a branch up to
        its fold, where the fallbacks would search for a distant branch.

    Returns
    -------
    ElasticaSolution

    Raises
    ------
    ValueError
        Unknown ``grip`` or invalid inputs.
    ElasticaError
        When neither the warm start nor the continuation strategies converge.

    Examples
    --------
    >>> from simgrip import STANDARD, Uniform
    >>> sol = solve("I", STANDARD, Uniform(-5.5))
    >>> bool(abs(sol.tip[0] - 0.3) < 1e-9), sol.feasible, round(sol.N1, 3)
    (True, True, 6.656)
    """
    grip = check_grip(grip)
    if not isinstance(params, DimensionlessParams):
        raise ValueError(f"params must be a DimensionlessParams, got {type(params).__name__}")
    profile = as_profile(profile)
    tol = _finite("tol", tol)
    if not 1e-13 <= tol <= 1e-2:
        raise ValueError(f"tol must lie in [1e-13, 1e-2], got {tol!r}")
    if guess is not None and not isinstance(guess, ElasticaSolution):
        raise ValueError(f"guess must be an ElasticaSolution or None, got {type(guess).__name__}")
    P = _problem(grip, params, profile, gravity, tip_load, contact_moment, gamma)

    raw = None
    if guess is not None and guess._raw is not None:
        g_raw = guess._raw
        raw = _from(g_raw, P, tol)
        if raw is None and not fallback:
            raise ElasticaError(f"warm start of grip {grip!r} from the guess did not converge (fallback=False)")
        if raw is None:
            path = _between(g_raw.prob, P)
            if path is not None:
                raw = _continue(path, g_raw, tol, h=0.5)
    if raw is None:
        raw = _cold(P, tol)
    if raw is None:
        raise ElasticaError(
            f"elastica BVP failed for grip {grip!r}: D={params.D:g}, M={params.M:g}, b={params.b:g}, "
            f"gamma={P.gamma:g}, profile={profile!r}, gravity={gravity}, tip_load={tip_load}, "
            f"contact_moment={contact_moment:g}"
        )
    return _package(grip, params, profile, raw, gravity, (P.t1, P.t2), P.C)


def sweep(
    grip: str,
    params: DimensionlessParams,
    profiles: Sequence,
    *,
    start: ElasticaSolution | None = None,
    **kw,
) -> list[ElasticaSolution]:
    """Solve along a sequence of profiles, each warm-started from the previous one.

    A failed step is subdivided (continuation along the blend of the two
    profiles) before falling back to a cold start; ``start`` warm-starts the first.
    Keyword arguments go to :func:`solve`.
    """
    out: list[ElasticaSolution] = []
    prev = start
    for prof in profiles:
        sol = solve(grip, params, prof, guess=prev, **kw)
        out.append(sol)
        prev = sol
    return out


def kappa_sweep(grip: str, params: DimensionlessParams, kappas, profile_of=Uniform, **kw) -> list[ElasticaSolution]:
    """:func:`sweep` over ``profile_of(kappa)`` for each ``kappa`` in ``kappas``."""
    return sweep(grip, params, [profile_of(float(k)) for k in np.atleast_1d(kappas)], **kw)


def least_mu(grip: str, params: DimensionlessParams, profile, **kw) -> float:
    """Least friction coefficient that holds ``params.M`` (paper Fig. 16a).

    ``|friction| / normal`` of the equilibrium; ``inf`` where the configuration
    cannot hold at any friction (contact lost, or Grip III's tip touching the
    workpiece).
    """
    grip = check_grip(grip)
    if grip == "free":
        raise ValueError("grip must be one of 'I', 'II', 'III' for least_mu, got 'free'")
    sol = solve(grip, params, profile, **kw)
    if not sol.feasibility["contact"] or not sol.feasibility.get("tip_clear", True):
        return math.inf
    return sol.required_mu


def _margin(sol: ElasticaSolution) -> float:
    """Continuous feasibility margin: >= 0 iff feasible (up to the strict ``n > 0``)."""
    terms = [sol.params.mu_s * sol.normal_force - abs(sol.friction_force), sol.normal_force]
    if sol.grip == "III":
        terms.append(sol.contact[1] - sol.tip[1])
    return float(min(terms))


def max_load(
    grip: str,
    params: DimensionlessParams,
    profile,
    *,
    M_max: float = 200.0,
    xtol: float = 1e-8,
    **kw,
) -> float:
    """Largest workpiece load ``M`` held at ``params.mu_s`` (paper Fig. 16b).

    The contact force depends on ``M``, so ``M`` is marched up from 0 along the
    equilibrium branch of ``solve(grip, params.replace(M=0), profile)`` (natural
    continuation that refuses jumps of ``theta`` to another branch).  The march
    stops at the first feasible-to-infeasible transition, located with Brent's
    method on the margin ``min(mu_s n - |f|, n[, Y(gamma) - Y(1)])``, or at a fold
    of the branch (the grip snaps through beyond it), located by bisection.
    If ``M = 0`` is infeasible, the first feasible ``M`` of the march is the
    starting point (0.0 is returned when none is met below ``M_max``);
    ``inf`` when the grip still holds at ``M_max``.
    """
    grip = check_grip(grip)
    if grip == "free":
        raise ValueError("grip must be one of 'I', 'II', 'III' for max_load, got 'free'")
    M_max = _finite("M_max", M_max)
    if M_max <= 0:
        raise ValueError(f"M_max must be positive, got {M_max!r}")
    profile = as_profile(profile)
    guess = kw.pop("guess", None)
    sol = solve(grip, params.replace(M=0.0), profile, guess=guess, **kw)
    opts = dict(kw)
    opts.pop("tol", None)
    tol = kw.get("tol", 1e-8)

    def follow(prev: ElasticaSolution, M: float) -> ElasticaSolution | None:
        """Continue ``prev`` to load ``M`` along its own branch, or ``None`` at a fold."""
        P = _problem(
            grip,
            params.replace(M=M),
            profile,
            opts.get("gravity", True),
            opts.get("tip_load", (0.0, 0.0)),
            opts.get("contact_moment", 0.0),
            opts.get("gamma", None),
        )
        raw = _continue(_between(prev._raw.prob, P), prev._raw, tol, max_jump=_MAX_JUMP, h_min=1 / 8, max_tries=12)
        if raw is None:
            return None
        return _package(grip, params.replace(M=M), profile, raw, P.g > 0, (P.t1, P.t2), P.C)

    # March M up along the branch; stop at the first infeasible point or fold.
    M, step = 0.0, 0.25
    last_ok = sol if sol.feasible else None
    lo = hi = None
    prev = sol
    while True:
        if M >= M_max:
            return math.inf if prev.feasible else (0.0 if last_ok is None else last_ok.params.M)
        Mn = min(M_max, M + step)
        nxt = follow(prev, Mn)
        if nxt is None:  # fold: the grip snaps beyond it
            lo, hi, fold = prev, Mn, True
            break
        if prev.feasible and not nxt.feasible:
            lo, hi, fold = prev, Mn, False
            hi_sol = nxt
            break
        if nxt.feasible:
            last_ok = nxt
        prev, M = nxt, Mn
        step = max(0.25, 0.2 * M)
    if not lo.feasible:
        return 0.0 if last_ok is None else last_ok.params.M
    a = lo.params.M
    if fold:
        # Bisect the fold on M (continuation from the last solution that exists).
        b = hi
        while b - a > max(xtol, 1e-5 * b):
            mid = 0.5 * (a + b)
            s = follow(lo, mid)
            if s is None:
                b = mid
            elif not s.feasible:
                hi_sol, fold = s, False
                b = mid
                break
            else:
                lo, a = s, mid
        if fold:
            return a
    # Friction / contact / tip boundary between a (feasible) and b: root of the margin.
    b = hi_sol.params.M

    def phi(Mv):
        s = follow(lo, Mv)
        if s is None:
            raise ElasticaError("fold inside the feasibility bracket")
        return _margin(s)

    fa, fb = _margin(lo), _margin(hi_sol)
    if fa >= 0 > fb:
        try:
            return float(brentq(phi, a, b, xtol=xtol))
        except ElasticaError:
            pass
    while b - a > xtol:  # strict n > 0 corner, or a fold inside: bisect the flag
        mid = 0.5 * (a + b)
        s = follow(lo, mid)
        if s is not None and s.feasible:
            lo, a = s, mid
        else:
            b = mid
    return a

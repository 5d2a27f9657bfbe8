"""Discrete finger models: the paper's nodal scheme and the hinge chain, with stability.

Two discretisations of the same dimensionless potential energy (``l = 1``,
``rho g = 1``, ``EI = D``, per-finger workpiece weight ``M``)::

    V = int_0^1 D/2 (theta' - kappa0)^2 ds + int_0^1 (1 - s) sin(theta) ds - F . r(s_c)

(the gravity term is ``int Y ds`` after the change of order of integration of
eq. 12; ``F`` is the force the workpiece exerts on the rod at the contact
point ``s_c``) are minimised here subject to the width constraint
``X(s_c) = b/2``:

=========  ======================  =====================  ===================
grip       contact ``s_c``         known load             multiplier
=========  ======================  =====================  ===================
``free``   none                    none                   none
``I/II``   tip, ``s_c = 1``        ``F_f = N2 = -M``      ``N = N1``
``III``    ``s_c = gamma``         ``N2 = -M``            ``N1``
=========  ======================  =====================  ===================

Grips I and II are the same equations (II simply has ``kappa0 > 0``).  For
Grip III the load acts on the part ``(0, gamma)`` of the rod (the paper's
eq. 21 swaps the segments; eq. 32 is right and is what is implemented).

The paper's nodal scheme (Section 4, eqs. 25-33) -- :func:`solve_discrete`
    Nodes ``s_i = i ds``, ``ds = 1/K``, angles ``theta_0 .. theta_K`` with
    ``theta_0 = 0`` imposed; unknowns ``theta_1 .. theta_K``.  Strain energy
    ``D/2 sum_i ((theta_i - theta_{i-1})/ds - kbar_i)^2 ds`` with ``kbar_i`` the
    *element average* ``int_{s_{i-1}}^{s_i} kappa0 / ds`` (so the curvature term
    ``int kappa0 theta'`` is exact for piecewise-linear ``theta`` and
    non-uniform profiles stay second order); every other integral is the
    trapezoid rule on the nodes (gravity ``(1 - s_i) sin(theta_i)``, the loads
    and the constraint ``X``).  The moment-free tip condition is natural: the
    half-weight of node ``K`` makes its equation a second-order one-sided
    approximation of ``theta'(1) = kappa0(1)``, so the paper's ghost node of
    eq. (26)_3 is not needed.  Checked against eq. (11)/(19): eq. (25) is
    right (its ``theta_0`` terms are constants once ``theta_0 = 0``); eq. (32)
    writes ``sin(theta_n)`` for ``sin(theta_K)``.
    Grip III contact node: ``I = round(gamma/ds)``; the scheme is second order
    only when ``gamma`` is a node (choose ``K`` with ``gamma*K`` an integer, e.g.
    ``K`` a multiple of 5 for ``gamma = 0.8``); otherwise the contact sits at
    ``I ds`` (reported as ``solution.gamma``), an ``O(ds)`` shift.

The hinge chain -- :func:`solve_chain`
    ``n`` rigid links with absolute angles ``phi_0 .. phi_{n-1}``, hinge angles
    ``q_j = phi_j - phi_{j-1}`` (``phi_{-1} = 0``) and springs from
    :func:`simgrip.chain.chain_springs` (``2/ds`` at the clamp with half the
    rest angle span, ``1/ds`` elsewhere, in units of ``EI/l``).  Link masses
    ``ds`` act at the link midpoints, which gives the separable gravity energy
    ``sum_i ds (1 - s_{i+1/2}) sin(phi_i)`` (exactly ``sum_i ds Y_mid,i``).  The
    tip is the end of the last link.  The Grip III contact is the material point
    at arc length ``gamma`` inside link ``m = floor(gamma/ds)``, linear along
    it: ``X(gamma) = sum_{i<m} ds cos(phi_i) + (gamma - m ds) cos(phi_m)``; an
    optional point moment ``M_c`` (E3 component) at the contact adds the
    potential ``-M_c phi_m``.  This is the exact settled state the MuJoCo chain
    built from the same springs must reach.  (The couple loads every hinge up to
    ``m``, i.e. the continuous moment jump is moved to the end of link ``m``'s
    cell; that is second order only when ``gamma`` is a link midpoint and costs
    ``O(|M_c| ds)`` otherwise.  The contact force is second order anywhere.)

Order of accuracy (derived; measured in ``tests/test_discrete.py``)
    Both schemes are ``O(ds^2)`` in the tip/contact position, the angles and the
    contact force: the nodal scheme is the standard symmetric three-point scheme
    with a half-cell Neumann end; the chain samples ``theta`` at link midpoints,
    its hinge is the central difference there, its clamp hinge owns the half
    cell ``[0, ds/2]`` (hence ``2/ds``), and ``X``, ``Y`` and the gravity energy
    are midpoint rules.  With ``1/ds`` at the clamp the first link angle is off
    by ``O(ds)`` and the whole chain converges at first order only.

Multiplier and stability (eqs. 29-31)
    With the constraint ``c(x) = X(s_c) - b/2`` and ``V0`` the energy without the
    multiplier term, the Lagrangian is ``Lag = V0 + chi c``; stationarity
    ``grad V0 + chi grad c = 0`` gives ``chi = -N1`` (the constraint force on the
    rod is ``-chi grad X``, i.e. ``N1 E1`` at the contact).  Therefore
    ``L = grad^2 V0 + chi grad^2 c`` is the Hessian of the paper's ``V_dis``
    *including* its ``-N (...)`` terms at the converged ``N``.  With ``E`` an
    orthonormal basis of the null space of ``grad c``, ``min_eigenvalue`` is the
    smallest eigenvalue of ``E^T L E`` (independent of the choice of ``E``); for
    the free rod it is the smallest eigenvalue of the Hessian.  The solvers get
    it in O(K) by bisection on Sylvester inertia counts of the tridiagonal ``L``
    bordered by ``grad c``; :func:`min_eigenvalue` is the dense version (a
    Householder basis), for any matrix.  It is the
    raw eigenvalue of the paper (Euclidean norm on the angles), which scales like
    ``ds``; ``min_eigenvalue / ds`` approximates the continuum Rayleigh quotient
    and is exposed as ``.min_eigenvalue_continuum``.

Convergence
    Newton stops when the relative gradient norm of the Lagrangian,
    ``max_i |dLag/dx_i|`` over the largest sum of magnitudes of the terms that
    make up one component (spring moments ``D k_j (|q_j| + |r_j|)``, loads,
    multiplier term), is at most :data:`GRADIENT_TOL` = 1e-12.  Steps are
    null-space Newton steps on the (tridiagonal) Lagrangian Hessian, shifted
    Levenberg-Marquardt style until the reduced Hessian is positive definite
    and the step fits a trust region of at most a few radians, so each
    iteration costs O(K).  Every iterate is put back on the constraint, the
    energy is the merit function.  Cold starts use a uniform-curvature shape
    that meets the width constraint exactly (sign from the profile, else I/III
    down, II up); if Newton fails from there, a homotopy from that arc's own
    rest shape (an exact, unloaded equilibrium) to the target is followed.
    A state that has not converged is never returned: :class:`DiscreteError`.

Energies reported are the full potential ``V0 - N1 X(s_c)`` (the paper's
``V_dis``) at the converged multiplier.

Examples
--------
>>> from simgrip import STANDARD, Uniform
>>> sol = solve_discrete("I", STANDARD, Uniform(-4.0), 64)
>>> bool(sol.success and sol.min_eigenvalue > 0 and abs(sol.tip[0] - 0.3) < 1e-12)
True
>>> eq = solve_chain("III", STANDARD, Uniform(-6.0), 40)
>>> bool(abs(eq.contact[0] - 0.3) < 1e-12)
True
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import scipy.linalg as sla
from scipy.optimize import brentq

from simgrip.chain import ChainSprings, chain_springs, link_positions
from simgrip.params import DimensionlessParams, check_grip
from simgrip.profiles import CurvatureProfile, as_profile

__all__ = [
    "DiscreteError",
    "DiscreteSolution",
    "ChainEquilibrium",
    "EnergyTerms",
    "solve_discrete",
    "discrete_from_continuous",
    "discrete_energy",
    "solve_chain",
    "chain_energy",
    "min_eigenvalue",
    "GRADIENT_TOL",
]

#: Relative gradient norm at which Newton stops (see :func:`_relative_gradient`).
GRADIENT_TOL = 1e-12


class DiscreteError(RuntimeError):
    """Newton could not bring a discrete model to equilibrium."""


# ----------------------------------------------------------------------------
# The common algebraic problem
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class _Problem:
    """``V0(x) = D/2 sum k_j (q_j - r_j)^2 + sum a_i sin x_i + lin . x``, ``q = diff(x, prepend=0)``.

    Constraint (when ``w`` is not None): ``c(x) = sum w_i cos x_i + c0``, with
    ``X(s_c) = c(x) + b/2``.
    """

    D: float
    k: np.ndarray
    rest: np.ndarray
    a: np.ndarray
    lin: np.ndarray
    w: np.ndarray | None
    c0: float
    half_b: float

    @property
    def size(self) -> int:
        return self.k.size

    @property
    def constrained(self) -> bool:
        return self.w is not None

    def with_(self, rest=None, a=None, lin=None) -> "_Problem":
        return _Problem(
            self.D,
            self.k,
            self.rest if rest is None else rest,
            self.a if a is None else a,
            self.lin if lin is None else lin,
            self.w,
            self.c0,
            self.half_b,
        )

    # -- energy and derivatives -------------------------------------------------
    def moments(self, x):
        q = np.diff(x, prepend=0.0)
        return q, self.D * self.k * (q - self.rest)

    def energy(self, x) -> float:
        q, m = self.moments(x)
        return float(0.5 * np.dot(m, q - self.rest) + np.dot(self.a, np.sin(x)) + np.dot(self.lin, x))

    def gradient(self, x) -> np.ndarray:
        _, m = self.moments(x)
        g = m.copy()
        g[:-1] -= m[1:]
        return g + self.a * np.cos(x) + self.lin

    def hessian(self, x) -> np.ndarray:
        dk = self.D * self.k
        main = dk.copy()
        main[:-1] += dk[1:]
        h = np.diag(main - self.a * np.sin(x))
        idx = np.arange(self.size - 1)
        h[idx, idx + 1] = -dk[1:]
        h[idx + 1, idx] = -dk[1:]
        return h

    def c(self, x) -> float:
        return float(np.dot(self.w, np.cos(x)) + self.c0)

    def c_gradient(self, x) -> np.ndarray:
        return -self.w * np.sin(x)

    def c_hessian_diag(self, x) -> np.ndarray:
        return -self.w * np.cos(x)

    def scale(self, x, chi) -> float:
        """Magnitude of the terms that make up the gradient (for the relative norm)."""
        q, _ = self.moments(x)
        t = self.D * self.k * (np.abs(q) + np.abs(self.rest))
        s = t.copy()
        s[:-1] += t[1:]
        s += np.abs(self.a) + np.abs(self.lin)
        if self.constrained:
            s += abs(chi) * np.abs(self.w)
        return max(float(np.max(s)), 1e-300)

    def lagrange_gradient(self, x):
        """``(r, chi)``: gradient of the Lagrangian with the least-squares multiplier."""
        g = self.gradient(x)
        if not self.constrained:
            return g, 0.0
        a = self.c_gradient(x)
        aa = float(np.dot(a, a))
        chi = -float(np.dot(a, g)) / aa if aa > 0 else 0.0
        return g + chi * a, chi

    def lagrange_tridiag(self, x, chi):
        """Diagonal and off-diagonal of the (tridiagonal) Hessian of the Lagrangian."""
        dk = self.D * self.k
        main = dk.copy()
        main[:-1] += dk[1:]
        main -= self.a * np.sin(x)
        if self.constrained:
            main += chi * self.c_hessian_diag(x)
        return main, -dk[1:]

    def lagrange_hessian(self, x, chi) -> np.ndarray:
        h = self.hessian(x)
        if self.constrained and chi != 0.0:
            h[np.diag_indices_from(h)] += chi * self.c_hessian_diag(x)
        return h


def _null_basis(a: np.ndarray) -> np.ndarray:
    """Orthonormal basis (columns) of ``{u : a . u = 0}`` from a Householder reflection."""
    m = a.size
    na = float(np.linalg.norm(a))
    if na == 0.0:
        return np.eye(m)
    v = a / na
    # reflect v onto -sign(v0) e0 (stable choice)
    sgn = 1.0 if v[0] >= 0 else -1.0
    u = v.copy()
    u[0] += sgn
    u /= np.linalg.norm(u)
    hmat = np.eye(m) - 2.0 * np.outer(u, u)
    return hmat[:, 1:]


def min_eigenvalue(hessian: np.ndarray, constraint_gradient: np.ndarray | None = None) -> float:
    """Smallest eigenvalue of ``E^T L E`` (eqs. 29-31), or of ``L`` when unconstrained.

    Parameters
    ----------
    hessian : ndarray (m, m)
        ``L``, the Hessian of the Lagrangian at the equilibrium (for the models of
        this module, the Hessian of the energy including the converged multiplier
        term; see the module docstring for the sign convention).
    constraint_gradient : ndarray (m,), optional
        ``grad c``; ``E`` is an orthonormal basis of its orthogonal complement.
    """
    h = np.asarray(hessian, dtype=float)
    if constraint_gradient is None:
        return float(sla.eigvalsh(h, subset_by_index=[0, 0])[0])
    z = _null_basis(np.asarray(constraint_gradient, dtype=float))
    hr = z.T @ h @ z
    return float(sla.eigvalsh(0.5 * (hr + hr.T), subset_by_index=[0, 0])[0])


def _count_below(diag, off, a, lam: float) -> int:
    """Number of eigenvalues below ``lam`` of a tridiagonal ``H`` (``a`` None) or of ``Z^T H Z``.

    One ``L D L^T`` sweep of ``H - lam I`` (Sylvester): negative pivots count the
    eigenvalues of ``H`` below ``lam``; with a constraint gradient ``a`` the
    bordered matrix ``[[H - lam, a], [a^T, 0]]`` has one more pivot,
    ``-a^T (H - lam)^{-1} a = -sum z_i^2 / d_i`` (``z = L^{-1} a``), and its inertia is
    that of ``Z^T (H - lam) Z`` plus one positive and one negative eigenvalue.
    """
    tiny = 1e-300
    neg = 0
    q = 0.0
    d = diag[0] - lam
    if d == 0.0:
        d = -tiny
    z = a[0] if a is not None else 0.0
    if d < 0:
        neg += 1
    q += z * z / d
    for i in range(1, len(diag)):
        li = off[i - 1] / d
        d = diag[i] - lam - li * off[i - 1]
        if d == 0.0:
            d = -tiny
        if d < 0:
            neg += 1
        if a is not None:
            z = a[i] - li * z
            q += z * z / d
    if a is None:
        return neg
    return neg + (1 if q > 0 else 0) - 1


def _tri_min_eigenvalue(diag: np.ndarray, off: np.ndarray, a: np.ndarray | None) -> float:
    """Smallest eigenvalue of a tridiagonal ``H`` or of ``Z^T H Z`` (``Z`` spans ``a``'s complement).

    Unconstrained: LAPACK bisection (:func:`scipy.linalg.eigvalsh_tridiagonal`).
    Constrained: bisection on the inertia count of :func:`_count_below`, to the
    absolute accuracy ``~ eps |H|`` that a dense symmetric eigensolver also has.
    O(m) per step, about 60 steps.
    """
    if a is None:
        if diag.size == 1:
            return float(diag[0])
        return float(sla.eigvalsh_tridiagonal(diag, off, select="i", select_range=(0, 0))[0])
    dl, ol, al = diag.tolist(), off.tolist(), np.asarray(a, float).tolist()
    rad = np.abs(np.concatenate([[0.0], off])) + np.abs(np.concatenate([off, [0.0]]))
    lo = float(np.min(diag - rad))
    hi = float(np.max(diag + rad))
    span = max(abs(lo), abs(hi), 1e-300)
    lo -= 1e-12 * span
    hi += 1e-12 * span
    while hi - lo > 4.0 * np.finfo(float).eps * span:
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        if _count_below(dl, ol, al, mid) >= 1:
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


class _Result(NamedTuple):
    x: np.ndarray
    chi: float
    gnorm: float
    iterations: int
    success: bool
    message: str


def _relative_gradient(prob: _Problem, x) -> tuple[np.ndarray, float, float]:
    r, chi = prob.lagrange_gradient(x)
    return r, chi, float(np.max(np.abs(r))) / prob.scale(x, chi)


def _restore(prob: _Problem, x: np.ndarray, maxiter: int = 40):
    """Move ``x`` along ``grad c`` onto ``c = 0``; ``None`` if that fails."""
    if not prob.constrained:
        return x
    d = prob.c_gradient(x)
    nd = float(np.linalg.norm(d))
    if nd == 0.0 or not np.all(np.isfinite(x)):
        return None
    d = d / nd
    tol = 1e-15 * (float(np.sum(np.abs(prob.w))) + abs(prob.c0) + prob.half_b)
    t = 0.0
    for _ in range(maxiter):
        y = x + t * d
        cv = prob.c(y)
        if abs(cv) <= tol:
            return y
        dc = float(np.dot(prob.c_gradient(y), d))
        if dc == 0.0:
            return None
        step = -cv / dc
        t += step
        if abs(t) > 2.0:
            return None
    y = x + t * d
    return y if abs(prob.c(y)) <= 100 * tol else None


def _tri_factor(diag: np.ndarray, off: np.ndarray):
    """``L D L^T`` of a symmetric tridiagonal matrix without pivoting: ``(pivots, multipliers)``.

    The signs of the pivots give the inertia (Sylvester's law).
    """
    dl = diag.tolist()
    ol = off.tolist()
    m = len(dl)
    piv = [0.0] * m
    mult = [0.0] * (m - 1)
    d = dl[0]
    piv[0] = d
    for i in range(1, m):
        li = ol[i - 1] / d if d != 0.0 else math.inf
        mult[i - 1] = li
        d = dl[i] - li * ol[i - 1]
        piv[i] = d
    return np.array(piv), np.array(mult)


def _tri_solve(piv: np.ndarray, mult: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve with the factors of :func:`_tri_factor`; ``b`` of shape ``(m,)`` or ``(m, k)``."""
    b = np.asarray(b, dtype=float)
    cols = [b] if b.ndim == 1 else [b[:, j] for j in range(b.shape[1])]
    ml = mult.tolist()
    pl = piv.tolist()
    m = len(pl)
    out = []
    for col in cols:
        z = col.tolist()
        for i in range(1, m):
            z[i] -= ml[i - 1] * z[i - 1]
        for i in range(m):
            z[i] /= pl[i]
        for i in range(m - 2, -1, -1):
            z[i] -= ml[i] * z[i + 1]
        out.append(z)
    res = np.array(out)
    return res[0] if b.ndim == 1 else res.T


def _newton_step(prob: _Problem, x, r, chi, scale, radius, shift0):
    """Shifted null-space Newton step ``p`` with ``max|p| <= radius`` (Levenberg-Marquardt).

    Solves ``(H + tau I) p = -r`` on the constraint tangent space for the
    smallest ``tau >= 0`` (searched geometrically from ``shift0``) that makes the
    reduced Hessian positive definite and keeps the step inside the trust
    radius.  Everything is O(m): the Lagrangian Hessian ``H`` is tridiagonal, its
    inertia comes from the pivots of ``L D L^T``, and with one constraint ``a``
    the reduced Hessian ``Z^T H Z`` is positive definite iff ``H`` is, or ``H``
    has exactly one negative eigenvalue and ``a^T H^{-1} a < 0`` (Haynsworth
    inertia additivity on the KKT matrix).  Returns ``(p, tau, predicted change
    of the Lagrangian)``.
    """
    diag, off = prob.lagrange_tridiag(x, chi)
    a = prob.c_gradient(x) if prob.constrained else None
    tiny = 1e-13 * scale
    tau = 0.0
    floor = max(shift0, 1e-9 * scale)
    for _ in range(400):
        piv, mult = _tri_factor(diag + tau, off)
        p = None
        if np.all(np.isfinite(piv)) and np.min(np.abs(piv)) > tiny:
            nneg = int(np.count_nonzero(piv < 0))
            if a is None:
                if nneg == 0:
                    p = -_tri_solve(piv, mult, r)
            elif nneg <= 1:
                yu = _tri_solve(piv, mult, np.stack([r, a], axis=1))
                y, u = yu[:, 0], yu[:, 1]
                au = float(np.dot(a, u))
                if (nneg == 0 and au > 0) or (nneg == 1 and au < 0):
                    p = -y + (float(np.dot(a, y)) / au) * u
                    p -= (np.dot(a, p) / np.dot(a, a)) * a  # tangent to roundoff
        if p is not None and np.all(np.isfinite(p)) and float(np.max(np.abs(p))) <= radius:
            hp = diag * p
            hp[:-1] += off * p[1:]
            hp[1:] += off * p[:-1]
            pred = float(np.dot(r, p) + 0.5 * np.dot(p, hp))
            return p, tau, pred
        tau = floor if tau == 0.0 else 2.0 * tau
    raise DiscreteError("could not regularise the Newton system")


def _newton(prob: _Problem, x0: np.ndarray, *, tol: float = GRADIENT_TOL, maxiter: int = 2000) -> _Result:
    """Feasible null-space Newton, globalised by a Levenberg-Marquardt trust region on ``V0``.

    Every iterate satisfies the constraint (restoration along ``grad c``), so the
    energy ``V0`` itself is the merit function; near the solution the full step
    plus restoration is Newton with a second-order correction (quadratic).  A
    step is accepted when the energy drops by at least 1e-4 of the predicted
    drop, or, once close (relative gradient < 1e-5), when an unshifted Newton step
    halves the gradient (energy differences are then lost in roundoff).
    """
    x = _restore(prob, np.array(x0, dtype=float))
    if x is None:
        return _Result(np.array(x0, dtype=float), 0.0, math.inf, 0, False, "infeasible start")
    r, chi, gn = _relative_gradient(prob, x)
    v = prob.energy(x)
    radius, shift = 1.0, 0.0
    for it in range(1, maxiter + 1):
        if gn <= tol:
            return _Result(x, chi, gn, it - 1, True, "converged")
        scale = prob.scale(x, chi)
        try:
            p, tau, pred = _newton_step(prob, x, r, chi, scale, radius, shift / 8.0)
        except DiscreteError as exc:
            return _Result(x, chi, gn, it, False, str(exc))
        size = float(np.max(np.abs(p)))
        xt = _restore(prob, x + p)
        accepted = False
        if xt is not None:
            vt = prob.energy(xt)
            rt, chit, gnt = _relative_gradient(prob, xt)
            rho = (vt - v) / pred if pred < 0 else -1.0
            close = tau == 0.0 and gn < 1e-5 and gnt <= 0.5 * gn
            if np.isfinite(vt) and (rho > 1e-4 or close):
                x, v, r, chi, gn = xt, vt, rt, chit, gnt
                accepted = True
                if rho > 0.75 and size > 0.5 * radius:
                    radius = min(2.0 * radius, 4.0)
                elif rho < 0.25 and not close:
                    radius = 0.5 * size
        if not accepted:
            radius = 0.25 * size
            if radius < 1e-14:
                return _Result(x, chi, gn, it, gn <= tol, "trust region collapsed")
        shift = tau
    return _Result(x, chi, gn, maxiter, gn <= tol, "converged" if gn <= tol else "iteration limit")


def _arc_start(prob: _Problem, unit_rest: np.ndarray, sign: float) -> tuple[np.ndarray, np.ndarray]:
    """A uniform-curvature shape (and its rest angles) satisfying the constraint exactly."""

    def shape(kap):
        return np.cumsum(kap * unit_rest)

    if not prob.constrained:
        return shape(0.0), 0.0 * unit_rest
    # scan outwards for the first sign change of c along kappa = sign * t
    c_prev = prob.c(shape(0.0))
    if c_prev <= 0:
        raise ValueError(
            "b: the contact point cannot reach X = b/2 (the straight finger is already inside it)"
        )
    t_prev = 0.0
    t = 0.25
    while t < 200.0:
        ct = prob.c(shape(sign * t))
        if ct <= 0:
            root = brentq(lambda u: prob.c(shape(sign * u)), t_prev, t, xtol=1e-15, rtol=1e-15)
            x = shape(sign * root)
            return x, sign * root * unit_rest
        t_prev, c_prev = t, ct
        t += 0.25
    raise DiscreteError("no uniform-curvature shape satisfies the width constraint")


def _solve(prob: _Problem, unit_rest: np.ndarray, sign: float, guess: np.ndarray | None) -> _Result:
    """Newton from the guess, else from the constrained arc, else a homotopy from the arc."""
    tried = []
    if guess is not None:
        res = _newton(prob, guess)
        if res.success:
            return res
        tried.append(res.message)
    if prob.constrained:
        x_arc, rest_arc = _arc_start(prob, unit_rest, sign)
    else:
        x_arc, rest_arc = np.cumsum(prob.rest), prob.rest
    res = _newton(prob, x_arc)
    if res.success:
        return res
    tried.append(res.message)
    # homotopy: rest angles from the arc's to the target, loads from 0 to full
    x = x_arc
    t, dt = 0.0, 0.1
    total = 0
    while t < 1.0:
        tn = min(1.0, t + dt)
        sub = prob.with_(
            rest=(1.0 - tn) * rest_arc + tn * prob.rest,
            a=tn * prob.a,
            lin=tn * prob.lin,
        )
        r = _newton(sub, x, maxiter=60)
        total += r.iterations
        if r.success:
            x, t = r.x, tn
            dt = min(0.25, 1.5 * dt)
        else:
            dt *= 0.5
            if dt < 1e-4:
                tried.append(f"homotopy stalled at t = {t:.4g}")
                break
    else:
        res = _newton(prob, x)
        if res.success:
            return res._replace(iterations=res.iterations + total)
        tried.append(res.message)
    raise DiscreteError("Newton did not converge (" + "; ".join(tried) + ")")


def _grip_sign(grip: str, prof: CurvatureProfile) -> float:
    mean = float(prof.integral(0.0, 1.0))
    if mean != 0.0:
        return math.copysign(1.0, mean)
    return 1.0 if grip == "II" else -1.0


def _check_count(name: str, value) -> int:
    try:
        v = int(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an integer >= 2, got {value!r}") from None
    if v != value or v < 2:
        raise ValueError(f"{name} must be an integer >= 2, got {value!r}")
    return v


def _check_params(params) -> DimensionlessParams:
    if not isinstance(params, DimensionlessParams):
        raise ValueError(f"params must be a DimensionlessParams, got {type(params).__name__}")
    return params


def _check_gamma(gamma, params: DimensionlessParams) -> float:
    if gamma is None:
        return params.gamma
    g = float(gamma)
    if not (math.isfinite(g) and 0.0 < g < 1.0):
        raise ValueError(f"gamma must lie in (0, 1), got {gamma!r}")
    return g


def _check_gravity(gravity) -> float:
    try:
        g = float(gravity)
    except (TypeError, ValueError):
        raise ValueError(f"gravity must be a real factor >= 0, got {gravity!r}") from None
    if not (math.isfinite(g) and g >= 0):
        raise ValueError(f"gravity must be a finite factor >= 0, got {gravity!r}")
    return g


def _angles_from_guess(guess, s_eval: np.ndarray, size: int, name: str) -> np.ndarray | None:
    """Angles at ``s_eval`` from an array, a solution with ``theta_at`` or ``(s, theta)`` data."""
    if guess is None:
        return None
    if hasattr(guess, "theta_at"):
        return np.asarray(guess.theta_at(s_eval), dtype=float).reshape(size)
    if hasattr(guess, "s") and hasattr(guess, "theta"):
        return np.interp(s_eval, np.asarray(guess.s, float), np.asarray(guess.theta, float))
    arr = np.asarray(guess, dtype=float)
    if arr.ndim == 1 and arr.size == size:
        return arr.copy()
    raise ValueError(f"guess must be {name}, a solution with theta_at(s), or None; got shape {arr.shape}")


class EnergyTerms(NamedTuple):
    """Energy ``V0 - N1 X(s_c)``, its gradient and Hessian in the model's unknowns."""

    value: float
    gradient: np.ndarray
    hessian: np.ndarray | None


def _terms(prob: _Problem, x, N1: float, hessian: bool) -> EnergyTerms:
    x = np.asarray(x, dtype=float)
    if x.shape != (prob.size,):
        raise ValueError(f"angles must have shape ({prob.size},), got {x.shape}")
    chi = -float(N1) if prob.constrained else 0.0
    val = prob.energy(x)
    grad = prob.gradient(x)
    if prob.constrained:
        val += chi * (prob.c(x) + prob.half_b)  # -N1 * X(s_c)
        grad = grad + chi * prob.c_gradient(x)
    hess = prob.lagrange_hessian(x, chi) if hessian else None
    return EnergyTerms(val, grad, hess)


# ----------------------------------------------------------------------------
# The paper's nodal scheme
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class DiscreteSolution:
    """Equilibrium of the paper's nodal scheme (eqs. 25-33).

    Attributes
    ----------
    grip : str
        ``"free"``, ``"I"``, ``"II"`` or ``"III"``.
    K : int
        Number of elements; ``ds = 1/K``.
    params : DimensionlessParams
    s, theta, x, y : ndarray, shape (K+1,)
        Nodes, nodal angles (``theta[0] = 0``) and trapezoid-rule positions.
    tip : ndarray (2,)
        ``(x[K], y[K])``.
    contact : ndarray (2,) or None
        Contact point (the tip for I/II, node ``I`` for III, None for free).
    N1, N2 : float
        Force of the workpiece on the rod at the contact, ``E1`` and ``E2``
        components over ``rho g l`` (``N1`` is the multiplier; ``N2 = -M``); 0 for
        the free rod.
    energy : float
        ``V_dis`` including the ``-N1 X`` term.
    min_eigenvalue : float
        Smallest eigenvalue of ``E^T L E`` (free rod: of the Hessian).
    gradient_norm : float
        Final relative gradient norm of the Lagrangian.
    iterations : int
    success : bool
    gamma : float or None
        Grip III: the contact arc length actually used, ``I ds``.
    gravity : float
        Factor on the rod's weight the solution was computed with.
    """

    grip: str
    K: int
    params: DimensionlessParams
    s: np.ndarray
    theta: np.ndarray
    x: np.ndarray
    y: np.ndarray
    tip: np.ndarray
    contact: np.ndarray | None
    N1: float
    N2: float
    energy: float
    min_eigenvalue: float
    gradient_norm: float
    iterations: int
    success: bool
    gamma: float | None = None
    gravity: float = 1.0

    @property
    def ds(self) -> float:
        return 1.0 / self.K

    @property
    def min_eigenvalue_continuum(self) -> float:
        """``min_eigenvalue / ds``: the eigenvalue in the ``L^2`` metric (resolution independent)."""
        return self.min_eigenvalue / self.ds

    @property
    def contact_theta(self) -> float | None:
        """Tangent angle at the contact (None for the free rod)."""
        if self.contact is None:
            return None
        if self.grip == "III":
            return float(self.theta[int(round(self.gamma * self.K))])
        return float(self.theta[-1])

    def theta_at(self, s) -> np.ndarray:
        """Piecewise-linear interpolation of the nodal angles."""
        return np.interp(s, self.s, self.theta)


def _nodal_problem(grip, params, prof, K, gamma, gravity=1.0):
    ds = 1.0 / K
    s = np.arange(K + 1) * ds
    wt = np.full(K + 1, ds)
    wt[0] = wt[-1] = 0.5 * ds
    rest = np.asarray(prof.integral(s[:-1], s[1:]), dtype=float)  # = kbar_i ds
    k = np.full(K, 1.0 / ds)
    a = gravity * wt[1:] * (1.0 - s[1:])
    lin = np.zeros(K)
    w = None
    c0 = 0.0
    I = None
    if grip in ("I", "II"):
        a = a + params.M * wt[1:]
        w = wt[1:].copy()
        c0 = wt[0] - 0.5 * params.b
    elif grip == "III":
        I = int(round(gamma * K))
        if I < 1:
            raise ValueError(f"K = {K} is too coarse for gamma = {gamma!r} (the contact node would be the clamp)")
        wc = np.zeros(K + 1)
        wc[:I] = ds
        wc[0] = wc[I] = 0.5 * ds
        a = a + params.M * wc[1:]
        w = wc[1:].copy()
        c0 = wc[0] - 0.5 * params.b
    prob = _Problem(params.D, k, rest, a, lin, w, c0, 0.5 * params.b)
    unit_rest = np.full(K, ds)
    return prob, unit_rest, s, I


def discrete_energy(grip, params, profile, K, theta, N1=0.0, *, gamma=None, gravity=1.0, hessian=True) -> EnergyTerms:
    """The paper's ``V_dis`` (eq. 27/32) in ``theta_1 .. theta_K`` with the multiplier fixed at ``N1``.

    ``theta`` may hold ``K`` values (``theta_1..theta_K``) or ``K+1`` (``theta_0`` is
    then dropped; it must be 0).  Returns :class:`EnergyTerms` (value, gradient
    and, if ``hessian``, the Hessian ``L``).
    """
    grip = check_grip(grip)
    params = _check_params(params)
    K = _check_count("K", K)
    prof = as_profile(profile)
    th = np.asarray(theta, dtype=float)
    if th.shape == (K + 1,):
        th = th[1:]
    prob, _, _, _ = _nodal_problem(grip, params, prof, K, _check_gamma(gamma, params), _check_gravity(gravity))
    return _terms(prob, th, N1, hessian)


def solve_discrete(grip, params, profile, K, *, guess=None, gamma=None, gravity=1.0) -> DiscreteSolution:
    """Minimise the paper's discrete energy for one grip.

    Parameters
    ----------
    grip : {"free", "I", "II", "III"}
    params : DimensionlessParams
    profile : CurvatureProfile, float or callable
        Intrinsic curvature ``kappa_bar(s_bar)``.
    K : int
        Number of elements (>= 2).  For Grip III pick ``K`` so that ``gamma K`` is
        an integer (the contact node is ``round(gamma K)``).
    guess : optional
        Start for Newton: ``theta_1..theta_K`` (or ``theta_0..theta_K``), any object
        with ``theta_at(s)`` (e.g. an elastica solution), a solution of another
        resolution, or None (a uniform-curvature shape meeting the constraint,
        with a homotopy fallback).
    gamma : float, optional
        Grip III contact arc length; default ``params.gamma``.
    gravity : float
        Factor on the rod's own weight (1 physical, 0 gravity free).

    Raises
    ------
    ValueError
        Bad ``grip``, ``K``, ``gamma`` or ``guess``.
    DiscreteError
        Newton failed to converge.
    """
    grip = check_grip(grip)
    params = _check_params(params)
    K = _check_count("K", K)
    prof = as_profile(profile)
    gam = _check_gamma(gamma, params)
    grav = _check_gravity(gravity)
    prob, unit_rest, s, I = _nodal_problem(grip, params, prof, K, gam, grav)
    g0 = _angles_from_guess(guess, s, K + 1, "K or K+1 nodal angles")
    if g0 is not None:
        g0 = g0[1:] if g0.size == K + 1 else g0
    res = _solve(prob, unit_rest, _grip_sign(grip, prof), g0)
    return dataclasses.replace(_nodal_solution(grip, params, K, prob, s, I, res), gravity=grav)


def _nodal_solution(grip, params, K, prob, s, I, res: _Result) -> DiscreteSolution:
    ds = 1.0 / K
    theta = np.concatenate([[0.0], res.x])
    wseg = 0.5 * ds
    x = np.concatenate([[0.0], np.cumsum(wseg * (np.cos(theta[1:]) + np.cos(theta[:-1])))])
    y = np.concatenate([[0.0], np.cumsum(wseg * (np.sin(theta[1:]) + np.sin(theta[:-1])))])
    tip = np.array([x[-1], y[-1]])
    if grip == "free":
        contact, N1, N2, gam = None, 0.0, 0.0, None
        lam = _tri_min_eigenvalue(*prob.lagrange_tridiag(res.x, 0.0), None)
    else:
        N1, N2 = -res.chi, -params.M
        lam = _tri_min_eigenvalue(*prob.lagrange_tridiag(res.x, res.chi), prob.c_gradient(res.x))
        if grip == "III":
            contact = np.array([x[I], y[I]])
            gam = I * ds
        else:
            contact, gam = tip.copy(), None
    energy = _terms(prob, res.x, N1, False).value
    return DiscreteSolution(
        grip=grip,
        K=K,
        params=params,
        s=s,
        theta=theta,
        x=x,
        y=y,
        tip=tip,
        contact=contact,
        N1=float(N1),
        N2=float(N2),
        energy=float(energy),
        min_eigenvalue=lam,
        gradient_norm=res.gnorm,
        iterations=res.iterations,
        success=bool(res.success),
        gamma=gam,
    )


def discrete_from_continuous(continuous, grip, params, profile, K, *, gamma=None) -> DiscreteSolution:
    """:func:`solve_discrete` started from a continuous solution (anything with ``theta_at(s)``).

    Useful to get the paper's stability eigenvalue at a BVP solution: Newton
    then converges in a few steps to the discrete equilibrium nearest to it.
    For Grip III, ``gamma`` defaults to ``continuous.gamma`` when it has one;
    the contact node is ``round(gamma K)``, so pick ``K`` with ``gamma K`` an
    integer (e.g. a multiple of 5 for 0.8) to keep the contact where the BVP has it.
    """
    if not hasattr(continuous, "theta_at"):
        raise ValueError("continuous must have a theta_at(s) method")
    if gamma is None and check_grip(grip) == "III":
        g = getattr(continuous, "gamma", None)
        gamma = g if g is not None and 0.0 < g < 1.0 else None
    return solve_discrete(grip, params, profile, K, guess=continuous, gamma=gamma)


# ----------------------------------------------------------------------------
# The hinge chain
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class ChainEquilibrium:
    """Settled state of the hinge chain.

    Attributes
    ----------
    grip : str
    n : int
        Number of links; ``ds = 1/n``.
    params : DimensionlessParams
    link_angles : ndarray (n,)
        Absolute link angles ``phi_i`` [rad].
    joint_angles : ndarray (n,)
        Hinge angles ``q_j = phi_j - phi_{j-1}`` (``q_0 = phi_0``).
    nodes : ndarray (n+1, 2)
        Hinge positions and the tip.
    tip : ndarray (2,)
    contact : ndarray (2,) or None
        Tip for I/II, the material point at ``gamma`` for III, None for free.
    N1, N2 : float
        Force of the workpiece on the rod at the contact over ``rho g l``
        (``N1`` is the multiplier, ``N2 = -M``).
    energy : float
        Chain potential including ``-N1 X`` and ``-M_c phi_m``.
    min_eigenvalue : float
        Smallest eigenvalue of the Hessian projected on the constraint tangent space.
    gradient_norm, iterations, success
    gamma : float or None
        Grip III contact arc length used.
    contact_moment : float
        The point moment ``M_c`` applied at the contact.
    gravity : float
        Factor on the rod's weight the solution was computed with.
    """

    grip: str
    n: int
    params: DimensionlessParams
    link_angles: np.ndarray
    joint_angles: np.ndarray
    nodes: np.ndarray
    tip: np.ndarray
    contact: np.ndarray | None
    N1: float
    N2: float
    energy: float
    min_eigenvalue: float
    gradient_norm: float
    iterations: int
    success: bool
    gamma: float | None = None
    contact_moment: float = 0.0
    gravity: float = 1.0

    @property
    def ds(self) -> float:
        return 1.0 / self.n

    @property
    def min_eigenvalue_continuum(self) -> float:
        """``min_eigenvalue / ds``: the eigenvalue in the ``L^2`` metric."""
        return self.min_eigenvalue / self.ds

    @property
    def contact_link(self) -> int | None:
        """Index of the link carrying the Grip III contact."""
        if self.gamma is None:
            return None
        return min(int(math.floor(self.gamma * self.n)), self.n - 1)

    @property
    def contact_theta(self) -> float | None:
        """Tangent angle at the contact (the carrying link's angle); None for the free rod."""
        if self.contact is None:
            return None
        if self.grip == "III":
            return float(self.link_angles[self.contact_link])
        return float(self.link_angles[-1])

    def theta_at(self, s) -> np.ndarray:
        """Link angles, read as samples at link midpoints, interpolated linearly (``theta(0) = 0``)."""
        sm = np.concatenate([[0.0], (np.arange(self.n) + 0.5) / self.n, [1.0]])
        th = np.concatenate([[0.0], self.link_angles, [self.link_angles[-1]]])
        return np.interp(s, sm, th)


def _chain_problem(grip, params, springs: ChainSprings, gamma, contact_moment, gravity):
    n = springs.n
    ds = springs.ds
    smid = (np.arange(n) + 0.5) * ds
    a = gravity * ds * (1.0 - smid)
    lin = np.zeros(n)
    w, c0, m = None, 0.0, None
    if grip in ("free", "I", "II"):
        lin[n - 1] = -float(contact_moment)  # a tip couple turns the last link: potential -C phi_{n-1}
    if grip in ("I", "II"):
        w = np.full(n, ds)
        a = a + params.M * w
        c0 = -0.5 * params.b
    elif grip == "III":
        m = min(int(math.floor(gamma * n)), n - 1)
        w = np.zeros(n)
        w[:m] = ds
        w[m] = gamma - m * ds
        a = a + params.M * w
        lin[m] = -float(contact_moment)
        c0 = -0.5 * params.b
    prob = _Problem(params.D, np.asarray(springs.stiffness, float), np.asarray(springs.rest, float), a, lin, w, c0, 0.5 * params.b)
    unit_rest = np.full(n, ds)
    unit_rest[0] = 0.5 * ds
    return prob, unit_rest, m


def _springs_for(profile, n, springs):
    if springs is None:
        return chain_springs(as_profile(profile), n)
    if not isinstance(springs, ChainSprings) or springs.n != n:
        raise ValueError(f"springs must be a ChainSprings with n = {n}")
    return springs


def chain_energy(
    grip,
    params,
    profile,
    n,
    link_angles,
    N1=0.0,
    *,
    gamma=None,
    contact_moment=0.0,
    gravity=1.0,
    springs=None,
    hessian=True,
) -> EnergyTerms:
    """Chain potential ``V0 - N1 X(s_c)`` with gradient and Hessian in the link angles.

    ``V0`` = springs + gravity on link midpoints + ``M Y(s_c)`` (``N2 = -M``)
    ``- M_c phi_m``.  ``gravity`` scales the rod's weight (1 = physical; 0 for
    gravity-free checks); ``springs`` overrides :func:`simgrip.chain.chain_springs`.
    """
    grip = check_grip(grip)
    params = _check_params(params)
    n = _check_count("n", n)
    sp = _springs_for(profile, n, springs)
    prob, _, _ = _chain_problem(grip, params, sp, _check_gamma(gamma, params), float(contact_moment), _check_gravity(gravity))
    return _terms(prob, link_angles, N1, hessian)


def solve_chain(
    grip,
    params,
    profile,
    n,
    *,
    gamma=None,
    contact_moment=0.0,
    guess=None,
    gravity=1.0,
    springs=None,
) -> ChainEquilibrium:
    """Static equilibrium of the ``n``-link hinge chain (the MuJoCo finger's settled state).

    Parameters
    ----------
    grip : {"free", "I", "II", "III"}
    params : DimensionlessParams
    profile : CurvatureProfile, float or callable
    n : int
        Number of links (>= 2).
    gamma : float, optional
        Grip III contact arc length (any value in (0, 1); default ``params.gamma``).
    contact_moment : float
        Point moment ``M_c`` (E3 component, over ``rho g l^2``) applied by the
        workpiece at the contact (finite-radius contact geoms): on the link
        carrying ``gamma`` for Grip III, on the last link (a tip couple) for the
        free rod and Grips I/II; potential ``-M_c phi``.
    guess : optional
        Link angles, a solution with ``theta_at(s)`` (sampled at link midpoints),
        or None.
    gravity : float
        Factor on the rod's own weight (1 physical, 0 gravity free).
    springs : ChainSprings, optional
        Override the springs (for convergence studies of other hinge rules).

    Raises
    ------
    ValueError
        Bad ``grip``, ``n``, ``gamma`` or ``guess``.
    DiscreteError
        Newton failed to converge.
    """
    grip = check_grip(grip)
    params = _check_params(params)
    n = _check_count("n", n)
    prof = as_profile(profile)
    gam = _check_gamma(gamma, params)
    sp = _springs_for(prof, n, springs)
    cm = float(contact_moment)
    if not math.isfinite(cm):
        raise ValueError(f"contact_moment must be finite, got {contact_moment!r}")
    prob_gravity = _check_gravity(gravity)
    prob, unit_rest, m = _chain_problem(grip, params, sp, gam, cm, prob_gravity)
    smid = (np.arange(n) + 0.5) / n
    g0 = _angles_from_guess(guess, smid, n, "n link angles")
    res = _solve(prob, unit_rest, _grip_sign(grip, prof), g0)
    phi = res.x
    nodes = link_positions(phi, sp.ds)
    tip = nodes[-1].copy()
    if grip == "free":
        contact, N1, N2, gam_out = None, 0.0, 0.0, None
        lam = _tri_min_eigenvalue(*prob.lagrange_tridiag(phi, 0.0), None)
    else:
        N1, N2 = -res.chi, -params.M
        lam = _tri_min_eigenvalue(*prob.lagrange_tridiag(phi, res.chi), prob.c_gradient(phi))
        if grip == "III":
            frac = gam - m * sp.ds
            contact = nodes[m] + frac * np.array([math.cos(phi[m]), math.sin(phi[m])])
            gam_out = gam
        else:
            contact, gam_out = tip.copy(), None
    energy = _terms(prob, phi, N1, False).value
    return ChainEquilibrium(
        grip=grip,
        n=n,
        params=params,
        link_angles=phi,
        joint_angles=np.diff(phi, prepend=0.0),
        nodes=nodes,
        tip=tip,
        contact=contact,
        N1=float(N1),
        N2=float(N2),
        energy=float(energy),
        min_eigenvalue=lam,
        gradient_norm=res.gnorm,
        iterations=res.iterations,
        success=bool(res.success),
        gamma=gam_out,
        contact_moment=cm if grip == "III" else 0.0,
        gravity=prob_gravity,
    )

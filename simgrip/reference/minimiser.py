"""The discrete energy shared by the paper's nodal scheme and the hinge chain, and its constrained Newton.

Both discretisations (:mod:`simgrip.reference.nodal`, :mod:`simgrip.reference.hinge_chain`)
reduce to one algebraic problem in the angles ``x`` (:class:`DiscreteEnergy`)::

    V0(x) = D/2 sum_j k_j (q_j - r_j)^2 + sum_i a_i sin(x_i) + lin . x,     q = diff(x, prepend=0)

(springs, gravity and known vertical loads, point couples) subject, for the
grips, to the width constraint ``c(x) = sum_i w_i cos(x_i) + c0 = X(s_c) - b/2 = 0``.
With the Lagrangian ``Lag = V0 + chi c``, stationarity gives ``chi = -N1`` (the
constraint force on the rod is ``N1 E1`` at the contact), so the Hessian of the
Lagrangian is the Hessian of the paper's ``V_dis`` including its ``-N1 X`` term.

Newton (:func:`newton`)
    Feasible null-space Newton steps on the tridiagonal Lagrangian Hessian,
    shifted Levenberg-Marquardt style until the reduced Hessian is positive
    definite and the step fits a trust region of at most a few radians, so each
    iteration costs O(K).  Every iterate is put back on the constraint, so the
    energy is the merit function.  It stops when the relative gradient norm of
    the Lagrangian, ``max_i |dLag/dx_i|`` over the largest sum of magnitudes of
    the terms that make up one component (spring moments
    ``D k_j (|q_j| + |r_j|)``, loads, multiplier term), is at most
    :data:`GRADIENT_TOL`.

Starts (:func:`minimise`)
    The caller's guess; else a uniform-curvature shape that meets the width
    constraint exactly (sign from the profile, else I/III down, II up); if Newton
    fails from there, a homotopy from that arc's own rest shape (an exact,
    unloaded equilibrium) to the target.  A state that has not converged is
    never returned: :class:`DiscreteError`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from simgrip.profiles import CurvatureProfile
from simgrip.reference.stability import tri_factor, tri_solve, tridiagonal_min_eigenvalue

__all__ = [
    "GRADIENT_TOL",
    "DiscreteEnergy",
    "DiscreteEquilibrium",
    "DiscreteError",
    "EnergyTerms",
    "NewtonResult",
    "angles_from_guess",
    "energy_terms",
    "equilibrium_fields",
    "grip_sign",
    "minimise",
    "newton",
]

#: Relative gradient norm at which Newton stops (see :func:`_relative_gradient`).
GRADIENT_TOL = 1e-12


class DiscreteError(RuntimeError):
    """Newton could not bring a discrete model to equilibrium."""


@dataclass(frozen=True)
class DiscreteEnergy:
    """``V0(x) = D/2 sum k_j (q_j - r_j)^2 + sum a_i sin x_i + lin . x``, ``q = diff(x, prepend=0)``.

    Constraint (when ``w`` is not None): ``c(x) = sum w_i cos x_i + c0``, with
    ``X(s_c) = c(x) + b/2``.  ``metric``: the quadrature weight of each angle in
    ``int theta^2 ds`` (see :mod:`simgrip.reference.stability`).
    """

    D: float
    k: np.ndarray
    rest: np.ndarray
    a: np.ndarray
    lin: np.ndarray
    w: np.ndarray | None
    c0: float
    half_b: float
    metric: np.ndarray

    @property
    def size(self) -> int:
        return self.k.size

    @property
    def constrained(self) -> bool:
        return self.w is not None

    def with_(self, rest=None, a=None, lin=None) -> "DiscreteEnergy":
        return dataclasses.replace(
            self,
            rest=self.rest if rest is None else rest,
            a=self.a if a is None else a,
            lin=self.lin if lin is None else lin,
        )

    # -- energy and derivatives -------------------------------------------------
    def moments(self, x):
        xa = np.asarray(x, dtype=float)
        q = xa.copy()  # np.diff(x, prepend=0.0) without its concatenation: the same differences, x_0 - 0 is x_0
        q[1:] -= xa[:-1]
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


class NewtonResult(NamedTuple):
    x: np.ndarray
    chi: float
    gnorm: float
    iterations: int
    success: bool
    message: str


def _relative_gradient(prob: DiscreteEnergy, x) -> tuple[np.ndarray, float, float]:
    r, chi = prob.lagrange_gradient(x)
    return r, chi, float(np.max(np.abs(r))) / prob.scale(x, chi)


def _restore(prob: DiscreteEnergy, x: np.ndarray, maxiter: int = 40):
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


def _newton_step(prob: DiscreteEnergy, x, r, chi, scale, radius, shift0):
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
        piv, mult = tri_factor(diag + tau, off)
        p = None
        if np.all(np.isfinite(piv)) and np.min(np.abs(piv)) > tiny:
            nneg = int(np.count_nonzero(piv < 0))
            if a is None:
                if nneg == 0:
                    p = -tri_solve(piv, mult, r)
            elif nneg <= 1:
                yu = tri_solve(piv, mult, np.stack([r, a], axis=1))
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


def newton(prob: DiscreteEnergy, x0: np.ndarray, *, tol: float = GRADIENT_TOL, maxiter: int = 2000) -> NewtonResult:
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
        return NewtonResult(np.array(x0, dtype=float), 0.0, math.inf, 0, False, "infeasible start")
    r, chi, gn = _relative_gradient(prob, x)
    v = prob.energy(x)
    radius, shift = 1.0, 0.0
    for it in range(1, maxiter + 1):
        if gn <= tol:
            return NewtonResult(x, chi, gn, it - 1, True, "converged")
        scale = prob.scale(x, chi)
        try:
            p, tau, pred = _newton_step(prob, x, r, chi, scale, radius, shift / 8.0)
        except DiscreteError as exc:
            return NewtonResult(x, chi, gn, it, False, str(exc))
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
                return NewtonResult(x, chi, gn, it, gn <= tol, "trust region collapsed")
        shift = tau
    return NewtonResult(x, chi, gn, maxiter, gn <= tol, "converged" if gn <= tol else "iteration limit")


def _arc_start(prob: DiscreteEnergy, unit_rest: np.ndarray, sign: float) -> tuple[np.ndarray, np.ndarray]:
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
            from scipy.optimize import brentq  # here, not with the module: SciPy's optimize costs ~0.15 s to import

            root = brentq(lambda u: prob.c(shape(sign * u)), t_prev, t, xtol=1e-15, rtol=1e-15)
            x = shape(sign * root)
            return x, sign * root * unit_rest
        t_prev, c_prev = t, ct
        t += 0.25
    raise DiscreteError("no uniform-curvature shape satisfies the width constraint")


def minimise(prob: DiscreteEnergy, unit_rest: np.ndarray, sign: float, guess: np.ndarray | None) -> NewtonResult:
    """Newton from the guess, else from the constrained arc, else a homotopy from the arc."""
    tried = []
    if guess is not None:
        res = newton(prob, guess)
        if res.success:
            return res
        tried.append(res.message)
    if prob.constrained:
        x_arc, rest_arc = _arc_start(prob, unit_rest, sign)
    else:
        x_arc, rest_arc = np.cumsum(prob.rest), prob.rest
    res = newton(prob, x_arc)
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
        r = newton(sub, x, maxiter=60)
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
        res = newton(prob, x)
        if res.success:
            return res._replace(iterations=res.iterations + total)
        tried.append(res.message)
    raise DiscreteError("Newton did not converge (" + "; ".join(tried) + ")")


def grip_sign(grip: str, prof: CurvatureProfile) -> float:
    mean = float(prof.integral(0.0, 1.0))
    if mean != 0.0:
        return math.copysign(1.0, mean)
    return 1.0 if grip == "II" else -1.0


def angles_from_guess(guess, s_eval: np.ndarray, size: int, name: str) -> np.ndarray | None:
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


def energy_terms(prob: DiscreteEnergy, x, N1: float, hessian: bool) -> EnergyTerms:
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


@dataclass(frozen=True, kw_only=True)
class DiscreteEquilibrium:
    """What every discrete equilibrium reports (the nodal scheme's and the hinge chain's).

    Attributes
    ----------
    N1, N2 : float
        Force of the workpiece on the rod at the contact, ``E1`` and ``E2``
        components over ``rho g l`` (``N1`` is the multiplier, ``N2 = -M``); 0 for
        the free rod.
    energy : float
        The potential ``V0 - N1 X(s_c)`` at the converged multiplier (the paper's
        ``V_dis``; the chain's includes ``-M_c phi`` of a contact couple).
    min_eigenvalue : float
        Smallest eigenvalue of the Hessian of the Lagrangian on the constraint's
        tangent space (free rod: of the Hessian) in the ``L^2`` metric of the
        scheme's quadrature, over ``rho g l``.  It converges at second order to
        the smallest eigenvalue of the continuous second variation; ``> 0``:
        stable (:mod:`simgrip.reference.stability`).
    gradient_norm : float
        Final relative gradient norm of the Lagrangian (at most :data:`GRADIENT_TOL`).
    iterations : int
        Newton iterations.
    success : bool
        Always ``True`` for a returned state (a failure raises :class:`DiscreteError`).
    """

    N1: float
    N2: float
    energy: float
    min_eigenvalue: float
    gradient_norm: float
    iterations: int
    success: bool


def equilibrium_fields(prob: DiscreteEnergy, res: NewtonResult, M: float, stability: str = "value") -> dict:
    """The fields of :class:`DiscreteEquilibrium` for the converged ``res`` of ``prob`` (load ``M``).

    ``stability``: ``"value"`` the smallest eigenvalue; ``"sign"`` a value of its sign only
    (``tridiagonal_min_eigenvalue(sign_only=True)``); ``"none"`` NaN (not computed).
    """
    if prob.constrained:
        N1, N2, a = -res.chi, -M, prob.c_gradient(res.x)
    else:
        N1, N2, a = 0.0, 0.0, None
    if stability == "none":
        lam = math.nan
    else:
        lam = tridiagonal_min_eigenvalue(*prob.lagrange_tridiag(res.x, res.chi if prob.constrained else 0.0), a,
                                         prob.metric, sign_only=stability == "sign")
    return dict(
        N1=float(N1),
        N2=float(N2),
        energy=float(energy_terms(prob, res.x, N1, False).value),
        min_eigenvalue=lam,
        gradient_norm=res.gnorm,
        iterations=res.iterations,
        success=bool(res.success),
    )

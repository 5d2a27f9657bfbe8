"""Planar dynamics of the inextensible elastica: a spectral Galerkin rod independent of the hinge chain.

The dynamic reference of issue 20 (item 4): a clamped rod of length ``l``, bending stiffness ``EI``, mass
``rho`` per length and intrinsic curvature ``kappa0(s)``, moving in the vertical plane under gravity, with
Kelvin-Voigt internal damping (bending moment ``EI (theta' - kappa0) + EI tau theta_t'``).  It shares no code
with :mod:`simgrip.chain` or MuJoCo: it is the continuous rod, discretised differently.

Model (dimensionless: ``l = rho = g = 1``, ``EI = D``, time in ``sqrt(l/g)``).  The tangent angle
``theta(s, t)`` is the only field; inextensibility holds exactly (``r(s) = int_0^s (cos theta, sin theta)``),
there is no shear and no rotary inertia (a line of mass).  The kinetic and potential energies are

    T = 1/2 int_0^1 int_0^1 theta_t(u) theta_t(v) cos(theta(u) - theta(v)) (1 - max(u, v)) du dv,
    V = D/2 int_0^1 (theta' - kappa0)^2 ds + int_0^1 (1 - s) sin theta ds,

(``|r_t(s)|^2`` integrated over ``s > max(u, v)``; the height integrated by parts).  The kernel's kink at
``u = v`` would spoil a product Gauss rule (algebraic convergence), so ``T`` is evaluated as written first,
``1/2 int |r_t|^2 ds`` with ``r_t(s_i)`` from the spectral integration matrix ``S`` on the Gauss points: the
weights become ``m = S' W S`` (smooth integrands only, spectral accuracy).  Galerkin: ``theta(s, t) =
sum_k a_k(t) phi_k(s)``, ``phi_k(s) = P_k(2s - 1) - P_k(-1)`` (shifted Legendre polynomials, ``k = 1..N``:
the clamp ``theta(0) = 0`` holds, the free end's ``theta'(1) = kappa0(1)`` is natural), every integral by
Gauss-Legendre quadrature on ``Q`` points.  Lagrange's equations, in the quadrature points' angles
``theta_i``, ``omega_i = theta_t(s_i)`` and the weights ``m_ij``, are those of a multi-pendulum,

    Phi' [ (m o cos(theta_i - theta_j)) Phi a_tt + (m o sin(theta_i - theta_j)) omega^2 ] = -dV/da - tau K_b a_t,

``K_b = D Phi_s' W Phi_s`` the bending stiffness.  The Galerkin error decays faster than any power of ``N``
for a smooth solution; time is integrated by the implicit midpoint rule (:func:`simulate`: second order,
A-stable, as the high Galerkin modes are stiff), which returns the tip ``(X, Y)`` over time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.polynomial import legendre as _leg

__all__ = ["RodDynamics", "equilibrium", "linear_poles", "rod_dynamics", "simulate"]


@dataclass(frozen=True)
class RodDynamics:
    """A discretised rod (dimensionless).

    Attributes
    ----------
    D, tau : float
        Bending stiffness ``EI/(rho g l^3)`` and Kelvin-Voigt time over ``sqrt(l/g)``.
    s, w : ndarray (Q,)
        Gauss-Legendre points and weights on ``[0, 1]``.
    Phi, dPhi : ndarray (Q, N)
        Basis functions and their arc-length derivatives at the points.
    kappa0 : ndarray (Q,)
        Intrinsic curvature ``l kappa0`` at the points.
    kernel : ndarray (Q, Q)
        ``m = S' W S`` with ``S`` the spectral integration matrix (``(S f)_i = int_0^{s_i} f``): the kinetic
        energy's weights (module docstring).
    """

    D: float
    tau: float
    s: np.ndarray
    w: np.ndarray
    Phi: np.ndarray
    dPhi: np.ndarray
    kappa0: np.ndarray
    kernel: np.ndarray

    @property
    def Kb(self) -> np.ndarray:
        """Bending stiffness matrix ``D int phi_k' phi_l' ds`` (N, N)."""
        return self.D * (self.dPhi.T * self.w) @ self.dPhi

    def angles(self, a) -> np.ndarray:
        """Tangent angles at the quadrature points for coefficients ``a`` (N,)."""
        return self.Phi @ a

    def tip(self, a) -> np.ndarray:
        """Tip position ``(X, Y)`` over ``l`` (the base at the origin, ``X`` along the clamp)."""
        th = self.Phi @ a
        return np.array([self.w @ np.cos(th), self.w @ np.sin(th)])

    def mass(self, a) -> np.ndarray:
        """The mass matrix ``Phi' (m o cos(theta_i - theta_j)) Phi`` at coefficients ``a`` (N, N)."""
        th = self.Phi @ a
        return self.Phi.T @ (self._kernel * np.cos(th[:, None] - th[None, :])) @ self.Phi

    def rhs(self, t, y) -> np.ndarray:
        """``d/dt (a, a_t)`` (the equations of motion of the module docstring)."""
        n = self.Phi.shape[1]
        a, v = y[:n], y[n:]
        th, om = self.Phi @ a, self.Phi @ v
        diff = th[:, None] - th[None, :]
        mw = self._kernel
        mass = self.Phi.T @ (mw * np.cos(diff)) @ self.Phi
        centripetal = self.Phi.T @ ((mw * np.sin(diff)) @ (om * om))
        bending = self.D * self.dPhi.T @ (self.w * (self.dPhi @ a - self.kappa0))
        gravity = self.Phi.T @ (self.w * (1.0 - self.s) * np.cos(th))
        force = -bending - gravity - self.tau * (self.Kb @ v) - centripetal
        return np.concatenate([v, np.linalg.solve(mass, force)])

    @property
    def _kernel(self) -> np.ndarray:
        return self.kernel


def _positive(name: str, value, *, zero: bool = False) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v) or v < 0 or (v == 0 and not zero):
        raise ValueError(f"{name} must be a finite number {'>= 0' if zero else '> 0'}, got {value!r}")
    return v


def rod_dynamics(D: float, kappa0, *, modes: int = 12, points: int | None = None, tau: float = 0.0) -> RodDynamics:
    """The Galerkin rod of ``modes`` Legendre modes and ``points`` Gauss points (default ``modes + 8``).

    ``kappa0`` is ``l kappa0`` as a number (uniform) or a callable of ``s/l`` (vectorised); ``tau`` >= 0 the
    Kelvin-Voigt time over ``sqrt(l/g)`` (a hinge chain with hinge damping ``tau * stiffness`` discretises it).
    ValueError naming the argument on bad input.
    """
    D = _positive("D", D)
    tau = _positive("tau", tau, zero=True)
    if isinstance(modes, bool) or not isinstance(modes, (int, np.integer)) or not 2 <= modes <= 64:
        raise ValueError(f"modes must be an integer in [2, 64], got {modes!r}")
    q = modes + 8 if points is None else points
    if isinstance(q, bool) or not isinstance(q, (int, np.integer)) or q < modes + 1:
        raise ValueError(f"points must be an integer > modes, got {points!r}")
    x, wx = _leg.leggauss(int(q))
    s, w = 0.5 * (x + 1.0), 0.5 * wx
    phi = np.empty((q, modes))
    dphi = np.empty((q, modes))
    for k in range(1, modes + 1):
        c = np.zeros(k + 1)
        c[k] = 1.0
        phi[:, k - 1] = _leg.legval(x, c) - (-1.0) ** k
        dphi[:, k - 1] = 2.0 * _leg.legval(x, _leg.legder(c))  # d/ds = 2 d/dx
    k0 = np.broadcast_to(np.asarray(kappa0(s) if callable(kappa0) else kappa0, dtype=float), s.shape).copy()
    if not np.all(np.isfinite(k0)):
        raise ValueError("kappa0 must be finite on [0, 1]")
    # spectral integration on the Gauss points: interpolate (Legendre series of degree q - 1), integrate from -1
    coef = np.linalg.inv(_leg.legvander(x, int(q) - 1))  # values -> Legendre coefficients
    S = 0.5 * np.stack([_leg.legval(x, _leg.legint(coef[:, j], lbnd=-1.0)) for j in range(int(q))], axis=1)
    return RodDynamics(D=D, tau=tau, s=s, w=w, Phi=phi, dPhi=dphi, kappa0=k0, kernel=(S.T * w) @ S)


def _stiffness(rod: RodDynamics, a) -> np.ndarray:
    """``d^2 V / da^2`` at ``a``: bending plus gravity's geometric stiffness."""
    th = rod.Phi @ a
    return rod.Kb - (rod.Phi.T * (rod.w * (1.0 - rod.s) * np.sin(th))) @ rod.Phi


def equilibrium(rod: RodDynamics, a0=None, *, tol: float = 1e-13, max_iter: int = 50) -> np.ndarray:
    """The static equilibrium's coefficients by Newton on ``dV/da = 0`` from ``a0`` (default: the weightless
    shape ``theta' = kappa0``, projected).  RuntimeError if Newton does not converge."""
    n = rod.Phi.shape[1]
    if a0 is None:
        a0 = np.linalg.lstsq(rod.dPhi * np.sqrt(rod.w)[:, None], np.sqrt(rod.w) * rod.kappa0, rcond=None)[0]
    a = np.asarray(a0, dtype=float).copy()
    if a.shape != (n,):
        raise ValueError(f"a0 must have shape ({n},), got {a.shape}")
    for _ in range(max_iter):
        th = rod.Phi @ a
        grad = rod.D * rod.dPhi.T @ (rod.w * (rod.dPhi @ a - rod.kappa0)) + rod.Phi.T @ (rod.w * (1.0 - rod.s)
                                                                                         * np.cos(th))
        da = np.linalg.solve(_stiffness(rod, a), grad)
        a -= da
        if np.linalg.norm(da) <= tol * (1.0 + np.linalg.norm(a)):
            return a
    raise RuntimeError("rod_dynamics.equilibrium: Newton did not converge")


def linear_poles(rod: RodDynamics, a) -> np.ndarray:
    """Poles ``s`` [over ``sqrt(g/l)``] of the small vibrations about the equilibrium ``a``: ``det(s^2 M + s C +
    K) = 0`` with ``M = rod.mass(a)``, ``K`` the Hessian of ``V``, ``C = tau K_b``; one of each complex pair
    (``Im s > 0``) and the real ones, slowest decay first, then lowest ``|s|`` (undamped: by frequency)."""
    n = rod.Phi.shape[1]
    M, K, C = rod.mass(a), _stiffness(rod, a), rod.tau * rod.Kb
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    s = np.linalg.eigvals(A)
    s = s[s.imag >= -1e-9 * np.abs(s)]
    decay = np.round(-s.real / (1e-9 * np.abs(s).max()))  # equal decay rates (undamped: 0) up to round-off
    return s[np.lexsort((np.abs(s), decay))]


def simulate(rod: RodDynamics, times, a0=None, *, dt: float = 2e-3, tol: float = 1e-12,
             max_iter: int = 30) -> np.ndarray:
    """The tip ``(X, Y)`` over ``l`` at ``times`` (over ``sqrt(l/g)``, increasing from 0, on the grid of
    ``dt``) for a rod released at rest from coefficients ``a0`` (default 0: straight along the clamp); returns
    ``(len(times), 2)``.

    Implicit midpoint rule, step ``dt``: second order, symplectic without damping (no numerical damping of the
    rod's modes), A-stable (the stiff high Galerkin modes need no small step); the phase error of a mode of
    angular frequency ``omega`` is ``(omega dt)^2 / 24`` per unit phase.  Each step is a simplified Newton
    solve for the new velocity, its Jacobian ``I + M^-1 (dt^2/4 + tau dt/2) K_b`` (the stiff part), to ``tol``
    (relative).  RuntimeError if a step does not converge (a solver failure, never a partial answer).
    """
    times = np.asarray(times, dtype=float)
    dt = _positive("dt", dt)
    if times.ndim != 1 or times.size < 1 or times[0] < 0 or np.any(np.diff(times) <= 0):
        raise ValueError("times must be a non-empty increasing 1-D array from >= 0")
    k = np.rint(times / dt)
    if np.any(np.abs(k * dt - times) > 1e-9 * np.maximum(1.0, times)):
        raise ValueError(f"times must lie on the grid of dt = {dt}")
    n = rod.Phi.shape[1]
    a = np.zeros(n) if a0 is None else np.asarray(a0, dtype=float).copy()
    if a.shape != (n,):
        raise ValueError(f"a0 must have shape ({n},), got {a.shape}")
    v = np.zeros(n)
    stiff = (0.25 * dt * dt + 0.5 * rod.tau * dt) * rod.Kb
    out, step = [], 0
    wanted = iter(k.astype(int))
    nxt = next(wanted)
    while True:
        while nxt == step:
            out.append(rod.tip(a))
            nxt = next(wanted, None)
        if nxt is None:
            return np.asarray(out)
        mass = rod.mass(0.5 * (a + a + dt * v))  # the midpoint's mass (frozen for the Newton iteration)
        jac = np.eye(n) + np.linalg.solve(mass, stiff)
        v1 = v.copy()
        for _ in range(max_iter):
            am, vm = a + 0.25 * dt * (v + v1), 0.5 * (v + v1)
            res = v1 - v - dt * rod.rhs(0.0, np.concatenate([am, vm]))[n:]
            dv = np.linalg.solve(jac, res)
            v1 -= dv
            if np.linalg.norm(dv) <= tol * (1.0 + np.linalg.norm(v1)):
                break
        else:
            raise RuntimeError(f"rod_dynamics.simulate: Newton did not converge at t = {step * dt:.6g}")
        a = a + 0.5 * dt * (v + v1)
        v = v1
        step += 1

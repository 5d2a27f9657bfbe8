"""Small planar vibrations of the inextensible elastica about an equilibrium: the rod's own eigenvalue problem.

Dimensionless (``l = rho = g = 1``, ``EI = D``, time over ``sqrt(l/g)``, so
``omega`` is ``omega sqrt(l/g)``).  The balance laws of the rod (``n(s)``: the force
the part beyond ``s`` exerts on the part before it; ``m`` its moment, ``E3``)::

    n' = r_tt + g E2,     m' + E3 . (r' x n) = 0,     m = D (theta' - kappa0),     r' = (cos theta, sin theta)

(no rotary inertia: Euler-Bernoulli).  About an equilibrium ``(theta0, n0, r0)``
put ``theta = theta0 + phi e^{i omega t}``, ``n = n0 + N e^{i omega t}``,
``r = r0 + u e^{i omega t}``, ``m = m0 + mu e^{i omega t}`` and keep first order
(``lambda = omega^2``)::

    phi' = mu / D
    mu'  = N1 sin theta0 - N2 cos theta0 + phi (n01 cos theta0 + n02 sin theta0)
    u1'  = -phi sin theta0,      u2' = phi cos theta0
    N1'  = -lambda u1,           N2' = -lambda u2

with ``n0(s) = F - (1 - s) E2``, ``F`` the static tip force (0 for the free rod,
``(N1, -M)`` for Grips I/II).  The last term of ``mu'`` is the geometric stiffness
of the static force (gravity's and the workpiece's).  Boundary conditions:

* clamp ``s = 0``: ``phi = u1 = u2 = 0`` (``x1 = y1 = theta1 = 0`` of the perturbation);
* free tip ``s = 1``: ``mu = 0``, ``N1 = N2 = 0``;
* Grips I/II, sticking tip in the symmetric reduction: ``mu(1) = 0`` (a point contact
  carries no couple), ``u1(1) = 0`` (the face does not move sideways: in the
  symmetric modes both fingers mirror each other, so the workpiece can neither
  translate horizontally nor rock; those motions are the antisymmetric modes,
  outside the reduction) and the workpiece, of inertial mass ``Mi`` per finger,
  moves vertically with the tip: ``Mi w_tt = -N2(1)`` with ``w = u2(1)``, i.e.
  ``N2(1) = lambda Mi u2(1)``; ``N1(1)`` (the change of the normal force) is free.
  A fixed workpiece has ``u2(1) = 0`` instead; a point mass on a free tip ``N(1) = lambda Mi u(1)``.

The problem is solved by Chebyshev collocation (Gauss-Lobatto, ``nodes + 1``
points per field, one collocation row of each field replaced by its boundary
condition) as a generalised eigenproblem ``A y = lambda B y`` (``B`` singular: the
infinite eigenvalues are dropped); the equilibrium enters through ``theta0(s)``
only.  :func:`refine` polishes one eigenpair with ``solve_bvp`` (``lambda`` an
unknown parameter, normalised by ``int |u|^2 = 1``): an independent second
solution of the same problem, used to cross-check.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.linalg as sla
from scipy.integrate import solve_bvp
from scipy.interpolate import BarycentricInterpolator

__all__ = ["AGREE", "DEFAULT_NODES", "MAX_NODES", "RodModes", "RodProblem", "cheb", "problem_of", "refine", "rod_modes"]

#: Chebyshev intervals of the collocation (the smooth equilibria of uniform profiles converge to ~1e-10 well
#: before this; the cost is a dense eigenproblem of size 6 (nodes + 1)).
DEFAULT_NODES = 40
#: Tip conditions (see the module docstring; ``mass``: a point mass ``tip_mass`` on an otherwise free tip).
TIPS = ("free", "stick", "fixed", "mass")
#: Most Chebyshev intervals: the collocation of this sixth-order system loses ~nodes^6 of round-off.
MAX_NODES = 64
#: The second collocation has this many intervals fewer (:func:`rod_modes`).
RESOLUTION_STEP = 6
#: Eigenvalues of the two collocations that agree to this (relative, or absolute below 1) are kept.
AGREE = 1e-6


@dataclass(frozen=True)
class RodProblem:
    """The linearised rod about an equilibrium (dimensionless).

    Attributes
    ----------
    theta0 : callable
        Equilibrium tangent angle ``theta0(s)`` [rad], vectorised.
    D : float
        Bending stiffness ``EI / (rho g l^3)``.
    tip_force : (float, float)
        Static force on the tip ``F`` (over ``rho g l``): ``n0(s) = F - gravity (1 - s) E2``.
    gravity : float
        Weight per length (1, or 0 for the weightless rod).
    tip : {"free", "stick", "fixed", "mass"}
        Free tip, tip sticking to a workpiece free to move vertically (mass ``tip_mass`` per finger),
        tip pinned to a fixed workpiece, or a free tip carrying a point mass ``tip_mass``.  A straight
        horizontal rod with ``stick`` or ``fixed`` is degenerate (``N1`` decouples: a singular pencil).
    tip_mass : float
        Inertial mass of the workpiece per finger over ``rho l`` (``tip="stick"``).
    """

    theta0: Callable
    D: float
    tip_force: tuple = (0.0, 0.0)
    gravity: float = 1.0
    tip: str = "free"
    tip_mass: float = 0.0


@dataclass
class RodModes:
    """Eigenpairs of a :class:`RodProblem`, lowest first.

    ``omega`` (``sqrt(lambda)``, over ``sqrt(g/l)``; NaN where ``lambda < 0``), ``lam`` (``omega^2``),
    ``s`` (collocation points), ``states`` (count, 6, points: ``phi, mu, u1, u2, N1, N2``) normalised to
    ``int |u|^2 ds = 1`` with the largest ``|u|`` positive; ``error_estimate`` the largest relative
    difference of ``lam`` between two collocations (:func:`rod_modes`).
    """

    lam: np.ndarray
    s: np.ndarray
    states: np.ndarray
    problem: RodProblem
    error_estimate: float = 0.0

    @property
    def omega(self) -> np.ndarray:
        return np.sqrt(np.where(self.lam >= 0, self.lam, np.nan))

    def displacement(self, k: int, s) -> np.ndarray:
        """Displacement ``u(s)`` of mode ``k``, shape ``s.shape + (2,)`` (Chebyshev interpolation)."""
        s = np.asarray(s, dtype=float)
        u1 = BarycentricInterpolator(self.s, self.states[k, 2])(s)
        u2 = BarycentricInterpolator(self.s, self.states[k, 3])(s)
        return np.stack([u1, u2], axis=-1)


def cheb(N: int) -> tuple[np.ndarray, np.ndarray]:
    """Chebyshev differentiation matrix on ``s in [0, 1]`` (``N + 1`` Gauss-Lobatto points, ``s[0] = 0``)."""
    x = np.cos(np.pi * np.arange(N + 1) / N)
    c = np.hstack([2.0, np.ones(N - 1), 2.0]) * (-1.0) ** np.arange(N + 1)
    X = np.tile(x, (N + 1, 1)).T
    dX = X - X.T
    Dx = np.outer(c, 1.0 / c) / (dX + np.eye(N + 1))
    Dx -= np.diag(Dx.sum(axis=1))
    # s = (1 - x) / 2 runs from 0 (x = 1) to 1 (x = -1): d/ds = -2 d/dx
    return (1.0 - x) / 2.0, -2.0 * Dx


def _check(P: RodProblem) -> None:
    if not (math.isfinite(P.D) and P.D > 0):
        raise ValueError(f"D must be positive and finite, got {P.D!r}")
    if P.tip not in TIPS:
        raise ValueError(f"tip must be one of {', '.join(TIPS)}, got {P.tip!r}")
    if not (math.isfinite(P.tip_mass) and P.tip_mass >= 0):
        raise ValueError(f"tip_mass must be non-negative and finite, got {P.tip_mass!r}")


def _coefficients(P: RodProblem, s):
    th = np.asarray(P.theta0(s), dtype=float)
    n1 = np.full_like(s, float(P.tip_force[0]))
    n2 = float(P.tip_force[1]) - P.gravity * (1.0 - s)
    return np.sin(th), np.cos(th), n1, n2


def rod_modes(P: RodProblem, count: int = 3, nodes: int = DEFAULT_NODES) -> RodModes:
    """The ``count`` lowest eigenpairs of the linearised rod ``P`` by Chebyshev collocation.

    Collocation of a high-order system makes spurious eigenvalues (huge, of either sign, moving with
    ``nodes``); the problem is solved at ``nodes`` and at ``nodes - RESOLUTION_STEP`` and only eigenvalues
    found at both (to :data:`AGREE` relative) are kept; their largest difference is
    :attr:`RodModes.error_estimate`.

    Raises ValueError for bad arguments, ``RuntimeError`` when fewer than ``count``
    eigenvalues are resolved.
    """
    _check(P)
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise ValueError(f"count must be a positive integer, got {count!r}")
    if isinstance(nodes, bool) or not isinstance(nodes, (int, np.integer)) or not 16 <= nodes <= MAX_NODES:
        raise ValueError(f"nodes must be an integer in [16, {MAX_NODES}], got {nodes!r}")
    w, V, s = _collocation(P, int(nodes))
    w2 = _collocation(P, int(nodes) - RESOLUTION_STEP)[0]
    gap = np.array([np.min(np.abs(w2 - x)) if w2.size else np.inf for x in w]) / np.maximum(1.0, np.abs(w))
    keep = gap <= AGREE
    w, V, gap = w[keep], V[:, keep], gap[keep]
    if w.size < count:
        raise RuntimeError(f"the rod's collocation resolved {w.size} eigenvalues, fewer than count = {count}; "
                           f"raise nodes ({nodes})")
    w, V, gap = w[:count], V[:, :count], gap[:count]
    p = s.size
    states = np.stack([_normalise(V[:, k].reshape(6, p), s) for k in range(count)])
    return RodModes(lam=w, s=s, states=states, problem=P, error_estimate=float(np.max(gap)))


def _collocation(P: RodProblem, nodes: int):
    """All finite real eigenvalues (ascending), their vectors and the points of one collocation."""
    s, Ds = cheb(int(nodes))
    p = s.size
    sn, cs, n1, n2 = _coefficients(P, s)
    I = np.eye(p)
    dg = np.diag
    PHI, MU, U1, U2, N1, N2 = range(6)
    A = np.zeros((6 * p, 6 * p))
    B = np.zeros((6 * p, 6 * p))

    def blk(M, r, c, val):
        M[r * p:(r + 1) * p, c * p:(c + 1) * p] += val

    # rows: field' - (rhs without lambda) = lambda (lambda part)
    blk(A, PHI, PHI, Ds)
    blk(A, PHI, MU, -I / P.D)
    blk(A, MU, MU, Ds)
    blk(A, MU, N1, -dg(sn))
    blk(A, MU, N2, dg(cs))
    blk(A, MU, PHI, -dg(n1 * cs + n2 * sn))
    blk(A, U1, U1, Ds)
    blk(A, U1, PHI, dg(sn))
    blk(A, U2, U2, Ds)
    blk(A, U2, PHI, -dg(cs))
    blk(A, N1, N1, Ds)
    blk(B, N1, U1, -I)
    blk(A, N2, N2, Ds)
    blk(B, N2, U2, -I)

    def bc(field_row, at, coeffs_a, coeffs_b=()):
        """Replace the collocation row of ``field_row`` at point ``at`` by sum(c y) = lambda sum(c' y)."""
        r = field_row * p + at
        A[r, :] = 0.0
        B[r, :] = 0.0
        for fld, pt, c in coeffs_a:
            A[r, fld * p + pt] = c
        for fld, pt, c in coeffs_b:
            B[r, fld * p + pt] = c

    first, last = 0, p - 1
    bc(PHI, first, [(PHI, first, 1.0)])
    bc(U1, first, [(U1, first, 1.0)])
    bc(U2, first, [(U2, first, 1.0)])
    bc(MU, last, [(MU, last, 1.0)])
    if P.tip == "free":
        bc(N1, last, [(N1, last, 1.0)])
        bc(N2, last, [(N2, last, 1.0)])
    elif P.tip == "stick":
        bc(N1, last, [(U1, last, 1.0)])
        bc(N2, last, [(N2, last, 1.0)], [(U2, last, float(P.tip_mass))])
    elif P.tip == "mass":
        bc(N1, last, [(N1, last, 1.0)], [(U1, last, float(P.tip_mass))])
        bc(N2, last, [(N2, last, 1.0)], [(U2, last, float(P.tip_mass))])
    else:
        bc(N1, last, [(U1, last, 1.0)])
        bc(N2, last, [(U2, last, 1.0)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        w, V = sla.eig(A, B)
    ok = np.isfinite(w) & (np.abs(w.imag) <= 1e-8 * np.maximum(1.0, np.abs(w.real)))
    w, V = w[ok].real, V[:, ok].real
    order = np.argsort(w)
    return w[order], V[:, order], s


def _weights(s) -> np.ndarray:
    """Clenshaw-Curtis quadrature weights on the Gauss-Lobatto points ``s`` in [0, 1]."""
    N = s.size - 1
    theta = np.pi * np.arange(N + 1) / N
    w = np.zeros(N + 1)
    v = np.ones(N - 1)
    if N % 2 == 0:
        w[0] = w[N] = 1.0 / (N * N - 1)
        for k in range(1, N // 2):
            v -= 2.0 * np.cos(2 * k * theta[1:-1]) / (4 * k * k - 1)
        v -= np.cos(N * theta[1:-1]) / (N * N - 1)
    else:
        w[0] = w[N] = 1.0 / (N * N)
        for k in range(1, (N - 1) // 2 + 1):
            v -= 2.0 * np.cos(2 * k * theta[1:-1]) / (4 * k * k - 1)
    w[1:-1] = 2.0 * v / N
    return 0.5 * w


def _normalise(y, s) -> np.ndarray:
    """Scale a mode so that ``int |u|^2 ds = 1`` and its largest displacement component is positive."""
    u2 = y[2] ** 2 + y[3] ** 2
    y = y / math.sqrt(float(_weights(s) @ u2))
    big = np.unravel_index(np.argmax(np.abs(y[2:4])), y[2:4].shape)
    return -y if y[2:4][big] < 0 else y


def problem_of(solution, *, tip_mass: float | None = None, fixed: bool = False) -> RodProblem:
    """The :class:`RodProblem` about an :class:`~simgrip.reference.elastica.ElasticaSolution`.

    Free rod: free tip.  Grips I/II: the tip sticks to the workpiece (symmetric reduction), whose inertial
    mass per finger is ``tip_mass`` (default the solution's ``params.M``; ``fixed=True``: a fixed workpiece).
    Grip III is not covered (ValueError).
    """
    if solution.grip == "III":
        raise ValueError("grip: the rod's vibration problem covers the free rod and Grips I/II (not III)")
    if solution.contact_moment != 0.0 or tuple(solution.tip_load) != (0.0, 0.0):
        raise ValueError("solution: modes need the point-contact equilibrium without extra tip loads")
    g = 1.0 if solution.gravity else 0.0
    if solution.grip == "free":
        return RodProblem(theta0=solution.theta_at, D=solution.params.D, gravity=g)
    mi = solution.params.M if tip_mass is None else float(tip_mass)
    return RodProblem(theta0=solution.theta_at, D=solution.params.D, tip_force=(solution.N1, solution.N2),
                      gravity=g, tip="fixed" if fixed else "stick", tip_mass=mi)


def refine(P: RodProblem, modes: RodModes, k: int, tol: float = 1e-8) -> tuple[float, object]:
    """Polish eigenpair ``k`` of ``modes`` with ``solve_bvp`` (``lambda`` a parameter; ``int |u|^2 = 1``).

    Returns ``(lambda, solve_bvp result)``; raises RuntimeError when ``solve_bvp`` does not converge.
    """
    _check(P)
    D = P.D

    def fun(s, y, p):
        lam = p[0]
        sn, cs, n1, n2 = _coefficients(P, s)
        phi, mu, u1, u2, N1, N2, _ = y
        return np.vstack([mu / D, N1 * sn - N2 * cs + phi * (n1 * cs + n2 * sn), -phi * sn, phi * cs,
                          -lam * u1, -lam * u2, u1 ** 2 + u2 ** 2])

    def bc(ya, yb, p):
        lam = p[0]
        rows = [ya[0], ya[2], ya[3], ya[6], yb[6] - 1.0, yb[1]]
        if P.tip == "free":
            rows += [yb[4], yb[5]]
        elif P.tip == "stick":
            rows += [yb[2], yb[5] - lam * P.tip_mass * yb[3]]
        elif P.tip == "mass":
            rows += [yb[4] - lam * P.tip_mass * yb[2], yb[5] - lam * P.tip_mass * yb[3]]
        else:
            rows += [yb[2], yb[3]]
        return np.array(rows)

    s = np.linspace(0.0, 1.0, 101)
    interp = [BarycentricInterpolator(modes.s, modes.states[k, i])(s) for i in range(6)]
    y = np.vstack(interp + [np.zeros_like(s)])
    y[6] = np.concatenate([[0.0], np.cumsum(0.5 * np.diff(s) * (y[2, 1:] ** 2 + y[3, 1:] ** 2
                                                                   + y[2, :-1] ** 2 + y[3, :-1] ** 2))])
    res = solve_bvp(fun, bc, s, y, p=[modes.lam[k]], tol=tol, max_nodes=20000)
    if not res.success:
        raise RuntimeError(f"solve_bvp did not refine mode {k}: {res.message}")
    return float(res.p[0]), res

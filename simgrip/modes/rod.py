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
* Grip III, the workpiece's corner sticking to the rod's point at ``gamma`` (the
  static contact force ``F = (N1, -M)`` acts there: ``n0 = F - (1 - s) E2`` on
  ``(0, gamma)``, ``-(1 - s) E2`` beyond): ``phi, u, mu`` continuous at ``gamma`` (a
  point contact, no couple), ``u1(gamma) = 0`` and ``N2(gamma+) - N2(gamma-) =
  -lambda Mi u2(gamma)`` (the workpiece moving vertically with that point),
  ``N1`` jumps freely; the tip beyond is free (``mu = N = 0``).  Two Chebyshev
  segments.

Which box motions the reduction allows: only the vertical translation; the
sway, rocking and (K fingers) turning modes need both or all fingers
(:mod:`simgrip.modes.gripper`).  A straight rod whose tip is pinned or sticks
is degenerate (its axial force perturbation decouples, the pencil is singular):
the grips' curled equilibria are not.

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
    contact : float
        Arc length ``gamma`` of a sticking contact (``tip`` "stick" or "fixed"): 1 at the tip (Grips I/II);
        below 1 (Grip III) ``tip_force`` acts at ``gamma`` (``n0 = F - (1 - s) E2`` on ``(0, gamma)``, ``-(1 - s)
        E2`` beyond) and the tip is free.
    """

    theta0: Callable
    D: float
    tip_force: tuple = (0.0, 0.0)
    gravity: float = 1.0
    tip: str = "free"
    tip_mass: float = 0.0
    contact: float = 1.0


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
    sizes: tuple = ()

    @property
    def omega(self) -> np.ndarray:
        return np.sqrt(np.where(self.lam >= 0, self.lam, np.nan))

    def displacement(self, k: int, s) -> np.ndarray:
        """Displacement ``u(s)`` of mode ``k``, shape ``s.shape + (2,)`` (Chebyshev interpolation)."""
        s = np.asarray(s, dtype=float)
        sizes = self.sizes or (self.s.size,)
        out = np.zeros(s.shape + (2,))
        at = 0
        for i, p in enumerate(sizes):
            seg = self.s[at:at + p]
            where = (s >= seg[0]) & ((s <= seg[-1]) if i == len(sizes) - 1 else (s < seg[-1]))
            for c in (0, 1):
                out[..., c][where] = BarycentricInterpolator(seg, self.states[k, 2 + c, at:at + p])(s[where])
            at += p
        return out


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
    if not (0.0 < P.contact <= 1.0) or (P.contact < 1.0 and P.tip not in ("stick", "fixed")):
        raise ValueError(f"contact must lie in (0, 1] (below 1 only with tip 'stick' or 'fixed'), got {P.contact!r}")


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
    :attr:`RodModes.error_estimate`.  An interior contact (``P.contact < 1``) splits the rod into two
    Chebyshev segments, ``nodes`` intervals each.

    Raises ValueError for bad arguments, ``RuntimeError`` when fewer than ``count``
    eigenvalues are resolved.
    """
    _check(P)
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise ValueError(f"count must be a positive integer, got {count!r}")
    if isinstance(nodes, bool) or not isinstance(nodes, (int, np.integer)) or not 16 <= nodes <= MAX_NODES:
        raise ValueError(f"nodes must be an integer in [16, {MAX_NODES}], got {nodes!r}")
    w, V, s, sizes = _collocation(P, int(nodes))
    w2 = _collocation(P, int(nodes) - RESOLUTION_STEP)[0]
    gap = np.array([np.min(np.abs(w2 - x)) if w2.size else np.inf for x in w]) / np.maximum(1.0, np.abs(w))
    keep = gap <= AGREE
    w, V, gap = w[keep], V[:, keep], gap[keep]
    if w.size < count:
        raise RuntimeError(f"the rod's collocation resolved {w.size} eigenvalues, fewer than count = {count}; "
                           f"raise nodes ({nodes})")
    w, V, gap = w[:count], V[:, :count], gap[:count]
    states = np.stack([_normalise(_fields(V[:, k], sizes), s, sizes) for k in range(count)])
    return RodModes(lam=w, s=s, states=states, problem=P, error_estimate=float(np.max(gap)), sizes=tuple(sizes))


def _fields(v, sizes) -> np.ndarray:
    """A collocation vector (segment by segment, 6 fields each) as ``(6, points)``, segments side by side."""
    out, at = [], 0
    for p in sizes:
        out.append(v[at:at + 6 * p].reshape(6, p))
        at += 6 * p
    return np.concatenate(out, axis=1)


def _collocation(P: RodProblem, nodes: int):
    """All finite real eigenvalues (ascending), their vectors, the points and the segments' point counts."""
    gam = float(P.contact)
    bounds = [(0.0, 1.0)] if gam >= 1.0 else [(0.0, gam), (gam, 1.0)]
    x, Dx = cheb(int(nodes))
    p = x.size
    nseg = len(bounds)
    size = 6 * p * nseg
    A = np.zeros((size, size))
    B = np.zeros((size, size))
    I = np.eye(p)
    dg = np.diag
    PHI, MU, U1, U2, N1, N2 = range(6)

    def idx(seg, field, pt=None):
        base = (seg * 6 + field) * p
        return base if pt is None else base + pt

    def blk(M, seg, r, c, val):
        M[idx(seg, r):idx(seg, r) + p, idx(seg, c):idx(seg, c) + p] += val

    points = []
    for seg, (a, b) in enumerate(bounds):
        s = a + (b - a) * x
        points.append(s)
        Ds = Dx / (b - a)
        th = np.asarray(P.theta0(s), dtype=float)
        sn, cs = np.sin(th), np.cos(th)
        # the contact load acts on the clamp side of the contact (gamma included; all of it for a tip contact)
        F = P.tip_force if seg == 0 else (0.0, 0.0)
        n1 = np.full(p, float(F[0]))
        n2 = float(F[1]) - P.gravity * (1.0 - s)
        # rows: field' - (rhs without lambda) = lambda (lambda part)
        blk(A, seg, PHI, PHI, Ds)
        blk(A, seg, PHI, MU, -I / P.D)
        blk(A, seg, MU, MU, Ds)
        blk(A, seg, MU, N1, -dg(sn))
        blk(A, seg, MU, N2, dg(cs))
        blk(A, seg, MU, PHI, -dg(n1 * cs + n2 * sn))
        blk(A, seg, U1, U1, Ds)
        blk(A, seg, U1, PHI, dg(sn))
        blk(A, seg, U2, U2, Ds)
        blk(A, seg, U2, PHI, -dg(cs))
        blk(A, seg, N1, N1, Ds)
        blk(B, seg, N1, U1, -I)
        blk(A, seg, N2, N2, Ds)
        blk(B, seg, N2, U2, -I)

    def bc(row, coeffs_a, coeffs_b=()):
        """Replace collocation row ``row`` by sum(c y[i]) = lambda sum(c' y[i]) (``(index, c)`` pairs)."""
        A[row, :] = 0.0
        B[row, :] = 0.0
        for i, c in coeffs_a:
            A[row, i] = c
        for i, c in coeffs_b:
            B[row, i] = c

    first, last, end = 0, p - 1, nseg - 1
    for f in (PHI, U1, U2):  # the clamp
        bc(idx(0, f, first), [(idx(0, f, first), 1.0)])
    mi = float(P.tip_mass)
    if nseg == 2:
        # continuity of phi, u and mu at gamma; u1(gamma) = 0 (the workpiece does not move sideways); the
        # workpiece's vertical motion: N2(gamma+) - N2(gamma-) = -F2 = -lambda Mi u2(gamma); N1 jumps freely
        for f in (PHI, U1, U2):
            bc(idx(1, f, first), [(idx(1, f, first), 1.0), (idx(0, f, last), -1.0)])
        bc(idx(0, MU, last), [(idx(0, MU, last), 1.0), (idx(1, MU, first), -1.0)])
        if P.tip == "stick":
            bc(idx(0, N1, last), [(idx(0, U1, last), 1.0)])
            bc(idx(0, N2, last), [(idx(1, N2, first), 1.0), (idx(0, N2, last), -1.0)],
               [(idx(0, U2, last), -mi)])
        else:  # fixed
            bc(idx(0, N1, last), [(idx(0, U1, last), 1.0)])
            bc(idx(0, N2, last), [(idx(0, U2, last), 1.0)])
        for f in (MU, N1, N2):  # the free tip beyond the contact
            bc(idx(1, f, last), [(idx(1, f, last), 1.0)])
    else:
        bc(idx(end, MU, last), [(idx(end, MU, last), 1.0)])
        rn1, rn2 = idx(end, N1, last), idx(end, N2, last)
        u1, u2, n1i, n2i = (idx(end, f, last) for f in (U1, U2, N1, N2))
        if P.tip == "free":
            bc(rn1, [(n1i, 1.0)])
            bc(rn2, [(n2i, 1.0)])
        elif P.tip == "stick":
            bc(rn1, [(u1, 1.0)])
            bc(rn2, [(n2i, 1.0)], [(u2, mi)])
        elif P.tip == "mass":
            bc(rn1, [(n1i, 1.0)], [(u1, mi)])
            bc(rn2, [(n2i, 1.0)], [(u2, mi)])
        else:
            bc(rn1, [(u1, 1.0)])
            bc(rn2, [(u2, 1.0)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        w, V = sla.eig(A, B)
    ok = np.isfinite(w) & (np.abs(w.imag) <= 1e-8 * np.maximum(1.0, np.abs(w.real)))
    w, V = w[ok].real, V[:, ok].real
    order = np.argsort(w)
    return w[order], V[:, order], np.concatenate(points), [p] * nseg


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


def _normalise(y, s, sizes) -> np.ndarray:
    """Scale a mode so that ``int |u|^2 ds = 1`` and its largest displacement component is positive."""
    u2 = y[2] ** 2 + y[3] ** 2
    total, at = 0.0, 0
    for p in sizes:
        seg = s[at:at + p]
        total += (seg[-1] - seg[0]) * float(_weights(np.linspace(0, 1, p)) @ u2[at:at + p])
        at += p
    y = y / math.sqrt(total)
    big = np.unravel_index(np.argmax(np.abs(y[2:4])), y[2:4].shape)
    return -y if y[2:4][big] < 0 else y


def problem_of(solution, *, tip_mass: float | None = None, fixed: bool = False) -> RodProblem:
    """The :class:`RodProblem` about an :class:`~simgrip.reference.elastica.ElasticaSolution`.

    Free rod: free tip.  Grips I/II: the tip sticks to the workpiece (symmetric reduction), whose inertial
    mass per finger is ``tip_mass`` (default the solution's ``params.M``; ``fixed=True``: a fixed workpiece).
    Grip III: the rod's point at ``gamma`` sticks to the workpiece's corner the same way; the tip is free.
    The point contact carries no couple: a solution with a ``contact_moment`` or a tip load is refused.
    """
    if solution.contact_moment != 0.0 or tuple(solution.tip_load) != (0.0, 0.0):
        raise ValueError("solution: modes need the point-contact equilibrium without extra tip loads")
    g = 1.0 if solution.gravity else 0.0
    if solution.grip == "free":
        return RodProblem(theta0=solution.theta_at, D=solution.params.D, gravity=g)
    mi = solution.params.M if tip_mass is None else float(tip_mass)
    return RodProblem(theta0=solution.theta_at, D=solution.params.D, tip_force=(solution.N1, solution.N2),
                      gravity=g, tip="fixed" if fixed else "stick", tip_mass=mi,
                      contact=float(solution.gamma) if solution.grip == "III" else 1.0)


def refine(P: RodProblem, modes: RodModes, k: int, tol: float = 1e-6) -> tuple[float, object]:
    """Polish eigenpair ``k`` of ``modes`` with ``solve_bvp`` (``lambda`` a parameter; ``int |u|^2 = 1``).

    Tip contacts only (``P.contact == 1``).  Returns ``(lambda, solve_bvp result)``; raises RuntimeError when
    ``solve_bvp`` does not converge.
    """
    _check(P)
    if P.contact < 1.0:
        raise ValueError("contact: refine covers tip contacts only (contact = 1)")
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

"""The elastica boundary-value problems: ODE systems, boundary conditions, one ``solve_bvp`` run.

Everything is dimensionless (``l = 1``, ``rho g = 1``, so ``EI = D`` and the
per-finger workpiece weight is ``M``).  Let ``n(s)`` be the force and ``m(s)``
the moment (``E3`` component) that the part of the rod beyond ``s`` exerts on the
part before ``s``.  Balancing the piece ``[s, 1]`` gives (paper eq. 7)::

    n' = g E2,        m' + (r' x n) . E3 = 0,        m = D (theta' - kappa0)

so with the state ``y = (theta, m, X, Y)``::

    theta' = kappa0(s) + m / D
    m'     = n1 sin(theta) - n2 cos(theta)
    X'     = cos(theta),   Y' = sin(theta)

and ``theta(0) = X(0) = Y(0) = 0``.  Using ``m`` as a state avoids ``kappa0'``,
so profiles need only be integrable, not differentiable.

* **free** rod: ``n(s) = F_tip - g (1 - s) E2`` with ``F_tip = (t1, t2)``;
  ``m(1) = C`` (a tip couple).
* **Grips I and II**: the workpiece pushes on the tip with ``N1 E1 + N2 E2``,
  ``N2 = -M`` known, ``N1`` unknown (a ``solve_bvp`` parameter) fixed by
  ``X(1) = b/2``; ``n(s) = (N1 + t1) E1 + (N2 + t2 - g (1 - s)) E2``, ``m(1) = C``.
* **Grip III**: the workpiece's corner pushes on the rod at ``s = gamma`` with
  ``N1 E1 + N2 E2``, ``N2 = -M``, ``N1`` fixed by ``X(gamma) = b/2``.  The jump
  condition ``[[n]]_gamma + F = 0`` gives::

      n(s) = (N1 + t1) E1 + (N2 + t2 - g(1-s)) E2     on (0, gamma)
      n(s) =        t1 E1 + (     t2 - g(1-s)) E2     on (gamma, 1)

  i.e. the contact terms act on the segment **between the clamp and the
  contact** (the paper's eq. 21 prints them on ``(gamma, 1)``: an erratum).  A
  couple ``C E3`` applied at the contact gives the jump
  ``m(gamma+) - m(gamma-) = -C``; the tip is moment free.  The two segments are
  mapped onto ``t in [0, 1]`` (``s = gamma t`` and ``s = gamma + (1 - gamma) t``):
  an 8-state problem with continuity of ``theta, X, Y`` at ``gamma``.

The first state of each segment is ``phi = theta - K(s)`` with
``K = int_0^s kappa0`` (exact antiderivatives for the uniform and eq. 34
profiles), so ``phi' = m / D`` is as smooth as ``m``: profiles with singular
derivatives do not stall ``solve_bvp``'s residual control.  Jacobians are
analytic.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Callable

import numpy as np

from simgrip.params import check_grip_iii_reach
from simgrip.profiles import Concentrated, CurvatureProfile, Uniform
from simgrip.reference.collocation import continue_collocation, solve_collocation

__all__ = ["Blend", "BvpProblem", "ElasticaError", "BvpSolution", "TOL_MID", "antiderivative", "grip_problem", "run_bvp", "system", "warm_bvp", "mesh_bvp"]

TOL_MID = 1e-6  # tolerance of intermediate continuation steps
_MAX_NODES = 6000  # per solve_bvp run at the final tolerance (tol 1e-8 needs ~1000)
_MAX_NODES_MID = 1000  # per run at the intermediate tolerance


class ElasticaError(RuntimeError):
    """The elastica BVP could not be solved, even by continuation (also reachable
    as ``simgrip.elastica.ElasticaError``)."""


class Blend(CurvatureProfile):
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
        return f"Blend({self.p0!r}, {self.p1!r}, {self.w:g})"


def antiderivative(profile: CurvatureProfile) -> Callable[[np.ndarray], np.ndarray]:
    """``K(s) = int_0^s kappa_bar``, exact where a closed form exists.

    Uniform: ``kappa s``; the concentrated profile (eq. 34):
    ``p kappa_max 4^alpha B(alpha+1, alpha+1) I_s(alpha+1, alpha+1)`` (regularised
    incomplete beta function); otherwise the profile's own ``integral``.
    """
    if isinstance(profile, Uniform):
        k = profile.kappa
        return lambda s: k * np.asarray(s, dtype=float)
    if isinstance(profile, Concentrated):
        from scipy import special as _sp  # lazily: ~0.1 s of CPU, needed by this profile only

        a = profile.alpha + 1.0
        c = profile.p * profile.kappa_max * 4.0**profile.alpha * _sp.beta(a, a)
        return lambda s: c * _sp.betainc(a, a, np.clip(np.asarray(s, dtype=float), 0.0, 1.0))
    if isinstance(profile, Blend):
        K0, K1, w = antiderivative(profile.p0), antiderivative(profile.p1), profile.w
        return lambda s: (1.0 - w) * K0(s) + w * K1(s)
    return lambda s: profile.integral(np.zeros_like(np.asarray(s, dtype=float)), s)


@dataclass(frozen=True)
class BvpProblem:
    """One elastica BVP.  ``target is None``: the contact force ``N1`` is given; else
    ``N1`` is the unknown parameter and the contact must sit at ``X = target``."""

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
            k = antiderivative(self.profile)
            object.__setattr__(self, "_K", k)
        return k

    @property
    def constrained(self) -> bool:
        return self.target is not None


def grip_problem(grip: str, params, profile: CurvatureProfile, *, gravity: bool, tip_load, C: float,
                 gamma: float) -> BvpProblem:
    """The BVP of ``grip`` (already checked) for ``params`` and ``profile``.

    ``tip_load = (t1, t2)`` and ``C`` are checked floats; ``gamma`` is the Grip III
    contact arc length (ignored by the other grips).
    """
    if grip == "III":
        check_grip_iii_reach(gamma, params.b)
    return BvpProblem(
        two_seg=grip == "III",
        D=params.D,
        g=1.0 if gravity else 0.0,
        profile=profile,
        t1=tip_load[0],
        t2=tip_load[1],
        N1=0.0,
        N2=0.0 if grip == "free" else -params.M,
        C=C,
        gamma=gamma if grip == "III" else 1.0,
        target=None if grip == "free" else params.b / 2.0,
        sigma=1 if grip == "II" else -1,
    )


@dataclass
class BvpSolution:
    """A converged ``solve_bvp`` result together with its problem."""

    prob: BvpProblem
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


def _segment_rhs(y, N1, P: BvpProblem, s, i, loaded: bool):
    """Right-hand side pieces of one segment: ``theta, cos, sin, n1, n2`` at ``s(t)``.

    ``i`` is the segment's first state index; ``loaded``: the contact force acts on it.
    """
    th = y[i] + P.K(s)
    n1 = (N1 if loaded else 0.0) + P.t1
    n2 = (P.N2 if loaded else 0.0) + P.t2 - P.g * (1.0 - s)
    return np.cos(th), np.sin(th), n1, n2


def _tip_system(P: BvpProblem):
    """Free rod and Grips I/II: one segment, contact (if any) at the tip."""
    D, con = P.D, P.constrained
    K, t1, N2t2, g = P.K, P.t1, P.N2 + P.t2, P.g

    memo = []  # (t, K(t), n2(t)) of the last two arrays t: a Newton run alternates the nodes and the midpoints

    def fun(t, y, p=None):
        # _segment_rhs's operations, in its order, written into the rows (np.vstack's checks cost as much as
        # the rest): the same values; K(t) and the force's t-dependent part taken from the memo when t is the
        # same array object (the collocation's meshes are never written to once made)
        out = np.empty((4, t.size))
        for m in memo:
            if m[0] is t:
                kt, n2 = m[1], m[2]
                break
        else:
            kt, n2 = K(t), N2t2 - g * (1.0 - t)
            memo.insert(0, (t, kt, n2))
            del memo[2:]
        th = y[0] + kt
        c = np.cos(th, out=out[2])
        sn = np.sin(th, out=out[3])
        n1 = (p[0] if con else P.N1) + t1
        np.divide(y[1], D, out=out[0])
        np.subtract(n1 * sn, n2 * c, out=out[1])
        return out

    def fun_jac(t, y, p=None):
        c, sn, n1, n2 = _segment_rhs(y, p[0] if con else P.N1, P, t, 0, True)
        J = np.zeros((4, 4, t.size))
        J[0, 1] = 1.0 / D
        J[1, 0] = n1 * c + n2 * sn
        J[2, 0] = -sn
        J[3, 0] = c
        if not con:
            return J
        Jp = np.zeros((4, 1, t.size))
        Jp[1, 0] = sn
        return J, Jp

    # clamp theta = X = Y = 0; tip moment m(1) = C; [contact X(1) = target]
    A, B, c = _clamp_rows(4, con)
    B[3, 1], c[3] = 1.0, P.C
    if con:
        B[4, 2], c[4] = 1.0, P.target
    return fun, fun_jac, A, B, c


def _two_segment_system(P: BvpProblem):
    """Grip III: segments ``(0, gamma)`` (states 0-3) and ``(gamma, 1)`` (states 4-7)."""
    D, con = P.D, P.constrained
    ga, gb = P.gamma, 1.0 - P.gamma

    def pieces(t, y, p):
        N1 = p[0] if con else P.N1
        a = _segment_rhs(y, N1, P, ga * t, 0, True)
        b = _segment_rhs(y, N1, P, ga + gb * t, 4, False)
        return a, b

    def fun(t, y, p=None):
        (ca, sa, n1a, n2a), (cb, sb, n1b, n2b) = pieces(t, y, p)
        out = np.empty((8, t.size))  # filled in place (see _tip_system)
        out[0], out[1], out[2], out[3] = ga * y[1] / D, ga * (n1a * sa - n2a * ca), ga * ca, ga * sa
        out[4], out[5], out[6], out[7] = gb * y[5] / D, gb * (n1b * sb - n2b * cb), gb * cb, gb * sb
        return out

    def fun_jac(t, y, p=None):
        (ca, sa, n1a, n2a), (cb, sb, n1b, n2b) = pieces(t, y, p)
        J = np.zeros((8, 8, t.size))
        for i, h, c, sn, n1, n2 in ((0, ga, ca, sa, n1a, n2a), (4, gb, cb, sb, n1b, n2b)):
            J[i, i + 1] = h / D
            J[i + 1, i] = h * (n1 * c + n2 * sn)
            J[i + 2, i] = -h * sn
            J[i + 3, i] = h * c
        if not con:
            return J
        Jp = np.zeros((8, 1, t.size))
        Jp[1, 0] = ga * sa
        return J, Jp

    # clamp theta = X = Y = 0; moment-free tip; continuity of phi, X, Y at gamma and the moment
    # jump m(gamma+) - m(gamma-) = -C; [contact X(gamma) = target]
    A, B, c = _clamp_rows(8, con)
    B[3, 5] = 1.0
    for i in range(4):
        A[4 + i, 4 + i], B[4 + i, i] = 1.0, -1.0
    c[5] = -P.C
    if con:
        B[8, 2], c[8] = 1.0, P.target
    return fun, fun_jac, A, B, c


def _clamp_rows(n: int, con: bool):
    """``A, B, c`` of linear boundary conditions ``A ya + B yb = c`` with the clamp rows filled."""
    nb = n + 1 if con else n
    A, B, c = np.zeros((nb, n)), np.zeros((nb, n)), np.zeros(nb)
    A[0, 0] = A[1, 2] = A[2, 3] = 1.0
    return A, B, c


def _with_bc(fun, fun_jac, A, B, c, con: bool):
    """``fun, bc, fun_jac, bc_jac`` with the linear boundary conditions ``A ya + B yb = c``."""
    dp = np.zeros((c.size, 1))

    def bc(ya, yb, p=None):
        return A @ ya + B @ yb - c

    def bc_jac(ya, yb, p=None):
        return (A, B, dp) if con else (A, B)

    return fun, bc, fun_jac, bc_jac


def linear_system(P: BvpProblem):
    """``fun, fun_jac, A, B, c``: the ODE and its Jacobian, vectorised over the mesh, and the linear boundary
    conditions ``A y(0) + B y(1) = c`` (``(n + k, n)``, ``k = 1`` parameter ``N1`` when constrained)."""
    return _two_segment_system(P) if P.two_seg else _tip_system(P)


def system(P: BvpProblem):
    """``fun, bc, fun_jac, bc_jac`` for ``solve_bvp``, vectorised over the mesh."""
    fun, fun_jac, A, B, c = linear_system(P)
    return _with_bc(fun, fun_jac, A, B, c, P.constrained)


def run_bvp(P: BvpProblem, x, y, p, tol: float) -> BvpSolution | None:
    """One ``solve_bvp`` run (:func:`simgrip.reference.collocation.solve_collocation`: SciPy's algorithm step for
    step, its Jacobian factored as a band matrix); ``None`` unless it converged to a finite solution."""
    return _finished(P, _collocation_run(P, x, y, p, tol, None))


def warm_bvp(P: BvpProblem, x, y, p, tol: float, factor=None) -> tuple[BvpSolution | None, object]:
    """``P`` solved from a close start ``(x, y, p)`` (a continuation's predictor on a neighbour's mesh):
    chord Newton steps with ``factor``, the neighbour's Jacobian factorisation
    (:func:`~simgrip.reference.collocation.continue_collocation`, accepted only by ``solve_bvp``'s own tests
    at ``tol``), else one :func:`run_bvp` from the same start.  Returns the solution (or ``None``) and the
    factorisation to hand to the next point."""
    r = _collocation_run(P, x, y, p, tol, factor, chord=True)
    if r is None:
        r = _collocation_run(P, x, y, p, tol, None)
    sol = _finished(P, r)
    return sol, (None if sol is None else r.factor)


def mesh_bvp(P: BvpProblem, x, y, p, tol: float, factor=None) -> tuple[BvpSolution | None, object]:
    """``P``'s collocation equations solved on the mesh ``x`` as it is from a close start ``(y, p)``: the
    chord Newton steps of :func:`warm_bvp` (with ``factor``, a neighbour's factorisation on ``x``, or a fresh
    one) stopped by ``solve_bvp``'s Newton and boundary tests at ``tol``, no node inserted (``refine=False``
    of :func:`~simgrip.reference.collocation.continue_collocation`): the mesh's own discretisation, which
    the caller sizes.  Returns the solution (its ``rms`` NaN: not estimated, see ``refine=False``) or ``None``,
    and the factorisation."""
    r = _collocation_run(P, x, y, p, tol, factor, chord=True, refine=False)
    sol = _finished(P, r)
    return sol, (None if sol is None else r.factor)


def _collocation_run(P: BvpProblem, x, y, p, tol: float, factor, chord: bool = False, refine: bool = True):
    fun, fun_jac, A, B, c = linear_system(P)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        try:
            max_nodes = _MAX_NODES if tol < TOL_MID else _MAX_NODES_MID
            if chord:
                return continue_collocation(fun, fun_jac, A, B, c, x, y, p, tol=tol, factor=factor,
                                            max_nodes=max_nodes, refine=refine)
            return solve_collocation(fun, fun_jac, A, B, c, x, y, p, tol=tol, max_nodes=max_nodes)
        except (np.linalg.LinAlgError, ValueError, FloatingPointError, ZeroDivisionError):
            return None


def _finished(P: BvpProblem, r) -> BvpSolution | None:
    """The converged, finite run ``r`` as a :class:`BvpSolution`; ``None`` otherwise."""
    if r is None or r.status != 0 or not np.isfinite(r.y).all():
        return None
    if r.p is not None and not np.isfinite(r.p).all():
        return None
    rp = np.asarray(r.p, dtype=float) if r.p is not None else np.zeros(0)
    return BvpSolution(P, r.x, r.y, rp, r.sol, float(np.max(r.rms_residuals)), r.message)

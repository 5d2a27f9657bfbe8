"""The settle's start shapes from the hinge chain, at the cost of a few LAPACK calls (issue 19).

:func:`free_start_angles` is the free chain's equilibrium (:func:`~simgrip.reference.hinge_chain.chain_angles`'s
answer) and :func:`grip_start` the Grip I/II chain equilibrium with the workpiece at the tip
(:func:`~simgrip.reference.hinge_chain.solve_chain`'s link angles, ``N1`` and stability sign),
computed by the *same* Newton iteration as :func:`simgrip.reference.minimiser.newton` for as long as
that iteration takes plain steps, with everything per iteration fused and the tridiagonal
factorisation done by LAPACK (``dpttrf``/``dpttrs``) instead of Python loops.

Same iteration, same answer
    The minimiser's step is ``(H + tau I) p = -r`` on the constraint's tangent space with the
    smallest ``tau >= 0`` that makes the reduced Hessian positive definite and keeps ``max |p|``
    within the trust radius; the step is accepted on the energy's actual-over-predicted decrease
    (or, close to the solution, on the gradient halving).  :func:`fast_newton` takes exactly those
    steps while ``tau = 0`` is the minimiser's choice with ``H`` itself positive definite (the
    pivots of ``dpttrf``: Sylvester) and the step is accepted; the moment the minimiser would do
    anything else (shift, shrink the radius after a rejection, ``H`` with one negative eigenvalue
    and a negative ``a^T H^{-1} a``), it returns None and the caller runs the minimiser itself from
    the same start.  The iterates therefore are the minimiser's up to round-off (LAPACK's ``L D L^T``
    instead of the same recursion in Python), and the answer meets the same stopping test
    (:data:`~simgrip.reference.minimiser.GRADIENT_TOL` on the relative Lagrangian gradient): the two
    equilibria agree to that tolerance's conditioning, ``|dtheta| ~ GRADIENT_TOL * scale / lambda_min``
    (measured ``<= 1e-12`` rad over the grid of ``tests/test_chain_start.py``), not bit for bit.
    The settle polishes either in MuJoCo to its own tolerance (``1e-10``), so settled states move by
    round-off of that solve only.

Stability sign (:func:`grip_start`)
    The reduced Hessian ``Z^T H Z`` is positive definite iff ``H`` has no negative eigenvalue and
    ``a^T H^{-1} a > 0``, or one and ``a^T H^{-1} a < 0`` (Haynsworth, as in the minimiser).  A
    ``dpttrf`` that succeeds says ``H`` is positive definite, hence (``a != 0``) stable; otherwise
    the inertia count of :mod:`simgrip.reference.stability` (the one the ``sign_only`` bisection
    evaluates) decides at zero.  The sign is the bisection's except within its round-off bracket
    (``|lambda_min| <~ 4 eps |H|``).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from simgrip.lapack import dgtsv, dpttrf, dpttrs  # LAPACK without scipy.linalg's import cost

from simgrip.params import Grip
from simgrip.reference.minimiser import GRADIENT_TOL, DiscreteEnergy, NewtonResult, grip_sign, minimise
from simgrip.reference.stability import tri_factor

__all__ = ["GripStart", "fast_newton", "free_start_angles", "grip_start", "reduced_definite"]

#: Plain Newton iterations :func:`fast_newton` takes before it hands over (quadratic convergence: the standard
#: cases need 2 to 4).
FAST_ITERS = 25


class _Fused:
    """The problem's per-iterate quantities in one pass (what ``_relative_gradient``, ``energy``, ``scale`` and
    ``lagrange_tridiag`` of :class:`DiscreteEnergy` compute, the same formulas)."""

    def __init__(self, prob: DiscreteEnergy):
        self.p = prob
        dk = prob.D * prob.k
        self.dk = dk
        main = dk.copy()
        main[:-1] += dk[1:]
        self.main0 = main
        self.off = -dk[1:]
        self.alin = np.abs(prob.a) + np.abs(prob.lin)
        self.absrest = np.abs(prob.rest)
        self.absw = None if prob.w is None else np.abs(prob.w)
        #: _restore's tolerance on c
        self.ctol = 0.0 if prob.w is None else 1e-15 * (float(np.sum(self.absw)) + abs(prob.c0) + prob.half_b)

    def restore(self, x):
        """``(y, cos y, sin y or None)``: :func:`~simgrip.reference.minimiser._restore`'s move of ``x`` along ``grad c``
        onto ``c = 0`` (the same Newton in the step length, each iterate's ``cos`` computed once); None if it fails.

        The first iterate is ``x`` itself (``t = 0``: ``x + 0 d`` is ``x``), whose ``cos`` is computed and whose
        slope ``grad c . d`` is the direction's own ``(-w sin x) . d`` (the same products, no second ``sin``);
        ``sin y`` is returned where ``y`` is that first iterate (it was computed for ``d``), else None."""
        p = self.p
        if p.w is None:
            return x, np.cos(x), None
        w = p.w
        sx = np.sin(x)
        du = -w * sx
        nd = math.sqrt(float(du.dot(du)))
        if nd == 0.0 or not math.isfinite(float(x.sum())):
            return None
        d = du / nd
        t = 0.0
        for it in range(40):
            y = x + t * d if it else x
            cy = np.cos(y)
            cv = float(w.dot(cy)) + p.c0
            if abs(cv) <= self.ctol:
                return y, cy, (sx if not it else None)
            # (the first slope: -(w sin x) . d is du . d, du's elements the negated products, bit for bit)
            dc = -float((w * np.sin(y)).dot(d)) if it else float(du.dot(d))
            if dc == 0.0:
                return None
            t += -cv / dc
            if abs(t) > 2.0:
                return None
        y = x + t * d
        cy = np.cos(y)
        return (y, cy, None) if abs(float(w.dot(cy)) + p.c0) <= 100 * self.ctol else None

    def at(self, x, cx, sx=None):
        """``(energy, r, chi, gn, scale, sin x)`` at ``x`` (``cx = cos x``; ``sx = sin x`` where known)."""
        p = self.p
        if sx is None:
            sx = np.sin(x)
        q = x.copy()
        q[1:] -= x[:-1]
        dq = q - p.rest
        m = self.dk * dq
        g = m.copy()
        g[:-1] -= m[1:]
        g += p.a * cx
        g += p.lin
        v = float(0.5 * m.dot(dq) + p.a.dot(sx) + p.lin.dot(x))
        t = self.dk * (np.abs(q) + self.absrest)
        s = t.copy()
        s[:-1] += t[1:]
        s += self.alin
        chi = 0.0
        if p.w is not None:
            a = -p.w * sx
            aa = float(a.dot(a))
            chi = -float(a.dot(g)) / aa if aa > 0 else 0.0
            g += chi * a
            s += abs(chi) * self.absw
        scale = max(float(s.max()), 1e-300)
        return v, g, chi, float(np.abs(g).max()) / scale, scale, sx

    def tridiag(self, chi, cx, sx):
        d = self.main0 - self.p.a * sx
        if self.p.w is not None:
            d += chi * (-self.p.w * cx)
        return d


def fast_newton(prob: DiscreteEnergy, x0, *, tol: float = GRADIENT_TOL, max_iter: int = FAST_ITERS):
    """:func:`simgrip.reference.minimiser.newton`'s iteration while its steps are plain (``tau = 0``, ``H``
    positive definite, accepted); a converged :class:`NewtonResult`, or None where the minimiser would
    shift, reject or need more than ``max_iter`` iterations (see the module docstring)."""
    f = _Fused(prob)
    got = f.restore(np.array(x0, dtype=float))
    if got is None:
        return None
    x, cx, sx0 = got
    con = prob.w is not None
    n = x.size
    rhs = np.empty((n, 2)) if con else None
    v, r, chi, gn, scale, sx = f.at(x, cx, sx0)
    radius = 1.0
    for it in range(1, max_iter + 1):
        if gn <= tol:
            return NewtonResult(x, chi, gn, it - 1, True, "converged")
        diag = f.tridiag(chi, cx, sx)
        piv, e, info = dpttrf(diag, f.off)
        definite = info == 0
        if definite and not float(piv.min()) > 1e-13 * scale:
            return None  # pivots the minimiser would call singular: its own search decides
        if con:
            a = -prob.w * sx
            rhs[:, 0] = r
            rhs[:, 1] = a
            if definite:
                yu, info = dpttrs(piv, e, rhs)
            else:  # H indefinite: the minimiser's plain step needs exactly one negative pivot and a^T H^-1 a < 0
                pl, _ = tri_factor(diag, f.off)
                if not (np.all(np.isfinite(pl)) and float(np.min(np.abs(pl))) > 1e-13 * scale
                        and int(np.count_nonzero(pl < 0)) == 1):
                    return None
                _, _, _, yu, info = dgtsv(f.off, diag, f.off, rhs)
            if info != 0:
                return None
            y, u = yu[:, 0], yu[:, 1]
            au = float(a.dot(u))
            if not (au > 0 if definite else au < 0):
                return None
            p = -y + (float(a.dot(y)) / au) * u
            p -= (a.dot(p) / a.dot(a)) * a  # tangent to round-off (as the minimiser)
        else:
            if not definite:
                return None
            p, info = dpttrs(piv, e, r)
            if info != 0:
                return None
            p = -p
        size = float(np.abs(p).max())
        if not size <= radius:  # (NaN too)
            return None
        hp = diag * p
        hp[:-1] += f.off * p[1:]
        hp[1:] += f.off * p[:-1]
        pred = float(r.dot(p) + 0.5 * p.dot(hp))
        got = f.restore(x + p)
        if got is None:
            return None
        xt, cxt, sxt0 = got
        vt, rt, chit, gnt, scalet, sxt = f.at(xt, cxt, sxt0)
        rho = (vt - v) / pred if pred < 0 else -1.0
        close = gn < 1e-5 and gnt <= 0.5 * gn
        if not (math.isfinite(vt) and (rho > 1e-4 or close)):
            return None
        if rho > 0.75 and size > 0.5 * radius:
            radius = min(2.0 * radius, 4.0)
        elif rho < 0.25 and not close:
            radius = 0.5 * size
        x, v, r, chi, gn, scale, cx, sx = xt, vt, rt, chit, gnt, scalet, cxt, sxt
    return None


def _arc_start(prob: DiscreteEnergy, unit_rest, sign: float):
    """A uniform-curvature shape ``x = kappa cumsum(unit_rest)`` on the constraint (the minimiser's arc start:
    its first sign change of ``c`` along ``kappa = sign t``, scanned in steps of 0.25, then the root), or None."""
    us = np.asarray(unit_rest, dtype=float).cumsum()  # (np.cumsum's and np.sum's reductions, without their wrappers)
    w, c0 = prob.w, prob.c0
    if float(np.add.reduce(w)) + c0 <= 0:
        return None  # the straight finger is already inside (the minimiser says so)
    t_prev = 0.0
    for block in range(50):  # t = 0.25 ... 200 in blocks of 16 steps (the minimiser's scan, vectorised)
        ts = 0.25 * np.arange(16 * block + 1, 16 * block + 17)
        ts = ts[ts < 200.0]
        if ts.size == 0:
            return None
        cs = np.cos(np.multiply.outer(sign * ts, us)) @ w + c0  # (np.outer's products)
        hit = (cs <= 0).nonzero()[0]
        if hit.size:
            j = int(hit[0])
            lo = ts[j - 1] if j > 0 else t_prev
            hi = ts[j]
            break
        t_prev = float(ts[-1])
    else:
        return None
    # safeguarded Newton on c(sign t) in [lo, hi] (c(lo) > 0 >= c(hi))
    t = 0.5 * (lo + hi)
    tol = 1e-15 * (float(np.add.reduce(np.abs(w))) + abs(c0) + prob.half_b)
    for _ in range(100):
        ang = sign * t * us
        c = float(w.dot(np.cos(ang))) + c0
        if abs(c) <= tol or hi - lo <= 1e-15 * max(1.0, hi):
            break
        if c > 0:
            lo = t
        else:
            hi = t
        dc = -float(w.dot(np.sin(ang) * us)) * sign
        tn = t - c / dc if dc != 0 else 0.5 * (lo + hi)
        t = tn if lo < tn < hi else 0.5 * (lo + hi)
    return sign * t * us


def _problem(grip, params, profile, n, gravity):
    from simgrip.reference.hinge_chain import _chain_problem, _springs_for, check_load
    from simgrip.reference.arguments import check_discrete

    grip, params, prof, n, gam, grav = check_discrete(grip, params, profile, "n", n, None, gravity)
    sp = _springs_for(prof, n, None)
    prob, unit_rest, _ = _chain_problem(grip, params, sp, gam, 0.0, grav, check_load(None, grip, params))
    return grip, params, prof, n, prob, unit_rest


def free_start_angles(params, profile, n, *, gravity=1.0, guess=None) -> np.ndarray:
    """The free chain's link angles ``phi`` [rad] (``chain_angles("free", ...)``'s equilibrium, see the module
    docstring for how close): from ``guess`` (link angles) or the rest shape, by :func:`fast_newton`, else by
    :func:`~simgrip.reference.hinge_chain.chain_angles` itself.  Raises as it does."""
    from simgrip.reference.hinge_chain import chain_angles

    _, params, prof, n, prob, _ = _problem(Grip.FREE, params, profile, n, gravity)
    x0 = np.cumsum(prob.rest) if guess is None else np.asarray(guess, dtype=float)
    res = fast_newton(prob, x0) if x0.shape == (n,) else None
    if res is not None:
        return res.x
    return chain_angles("free", params, prof, n, guess=guess, gravity=gravity)


class GripStart(NamedTuple):
    """The Grip I/II chain equilibrium with the workpiece at the tip: link and joint angles [rad], the tip
    ``(X, Y)`` over ``l``, ``N1`` over ``rho g l`` (the force on the rod along ``E1``) and its stability."""

    link_angles: np.ndarray
    joint_angles: np.ndarray
    tip: np.ndarray
    N1: float
    stable: bool


def reduced_definite(diag, off, a) -> bool:
    """Whether ``Z^T H Z`` is positive definite (``H`` the symmetric tridiagonal ``diag``/``off``, ``Z`` spanning
    the complement of ``a != 0``): ``dpttrf`` succeeding (``H`` positive definite) says yes, else the inertia
    count of :func:`simgrip.reference.stability._count_below` at zero decides (Haynsworth)."""
    from simgrip.reference.stability import _count_below

    piv, _, info = dpttrf(diag, off)
    if info == 0 and bool(np.all(piv > 0)):
        return True  # H positive definite, a != 0: a^T H^-1 a > 0
    return _count_below(np.asarray(diag, float).tolist(), np.asarray(off, float).tolist(),
                        np.asarray(a, float).tolist(), 0.0) == 0


def grip_start(grip, params, profile, n, *, gravity=1.0) -> GripStart:
    """Grip I/II: ``solve_chain(grip, params, profile, n, gravity=gravity)``'s link angles, tip, ``N1`` and
    stability sign (``min_eigenvalue > 0``), by :func:`fast_newton` from the minimiser's arc start, else by
    the minimiser itself (same starts, same errors: :class:`~simgrip.reference.minimiser.DiscreteError`,
    ``ValueError``)."""
    if grip not in ("I", "II"):
        raise ValueError(f"grip must be 'I' or 'II' for a grip start, got {grip!r}")
    grip, params, prof, n, prob, unit_rest = _problem(grip, params, profile, n, gravity)
    sign = grip_sign(grip, prof)
    x0 = _arc_start(prob, unit_rest, sign)
    res = fast_newton(prob, x0) if x0 is not None else None
    if res is None:
        res = minimise(prob, unit_rest, sign, None)
    x = res.x
    ds = 1.0 / n
    tip = np.array([ds * float(np.add.reduce(np.cos(x))), ds * float(np.add.reduce(np.sin(x)))])  # (np.sum's)
    q = x.copy()
    q[1:] -= x[:-1]
    diag, off = prob.lagrange_tridiag(x, res.chi)
    return GripStart(x, q, tip, float(-res.chi), reduced_definite(diag, off, prob.c_gradient(x)))

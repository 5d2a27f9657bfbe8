"""A rod wrapping a cylinder in its plane: the free-boundary elastica with a contact arc and a tip contact.

The free rod (clamped at the origin, ``theta(0) = 0``, its weight ``-E2`` per length, uniform ``kappa0 < 0``:
curling clockwise) closes on a fixed, frictionless cylinder (centre ``c``, radius ``R`` in centreline terms,
:class:`~simgrip.reference.constrained.Cylinder`).  Contact set (what the constrained chain finds for a rod
curled tighter than the surface, ``|kappa0| > 1/R``): an arc ``[s1, s2]`` where the rod lies on the
cylinder, and the tip on it.

Balance laws (paper eq. 7).  On the free pieces ``n' = E2``, ``m = D (theta' - kappa0)``, ``m' = n1 sin theta
- n2 cos theta``.  On the arc the rod follows the circle, ``r = c + R (cos psi, sin psi)``, ``psi = psi1 -
(s - s1)/R``, ``theta = psi - pi/2``, so ``theta' = -1/R`` and ``m = D (-1/R - kappa0)`` is constant: the
shear ``n . nu = -m'`` vanishes, ``n = T t``, and the balance with the pressure ``p`` (pushing along the
outward normal ``nu``) gives ``T' = sin theta``, ``p = T/R + cos theta`` (must be ``>= 0``).  At the arc's ends
point forces ``f1 nu(s1)``, ``f2 nu(s2)`` (``>= 0``) are allowed (jumps of the shear); at the tip the
cylinder pushes with ``Q nu_tip`` along its radius, ``n(1) = Q (r(1) - c)/R``.

Natural boundary conditions at the free ends of the contact arc: varying ``s1`` (``s2``) at a fixed shape
moves where the rod leaves the surface; stationarity requires the curvature to be continuous there,
``theta'(s1-) = -1/R`` and ``theta'(s2+) = -1/R`` (the moment continuous, no concentrated couple).

The BVP: the free pieces ``[0, s1]`` and ``[s2, 1]`` mapped to ``[0, 1]`` (8 states), parameters
``Q, s1, s2, f1, psi1, psi_t``, 14 conditions: the clamp (3); at ``s1`` the rod on the circle at ``psi1``
(2), tangent to it (1), curvature continuous (1); the same at ``s2`` with ``psi2 = psi1 - (s2 - s1)/R``
(4); the tip moment-free (1) and on the circle at ``psi_t`` (2).  ``n`` on ``[s2, 1]`` is ``Q e_t - (1 -
s) E2``; across the arc ``T(s2-) = n(s2+) . t(s2)`` (``f2`` is normal) and ``T(s1+) = T(s2-) - int sin
theta`` (closed form on the arc); on ``[0, s1]``, ``n = T(s1+) t(s1) + f1 nu(s1) - (s1 - s) E2``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_bvp

from simgrip.profiles import Uniform, as_profile
from simgrip.reference.arguments import check_params
from simgrip.reference.contact_geometry import self_crossing

__all__ = ["WrapError", "WrapSolution", "solve_wrap"]


class WrapError(RuntimeError):
    """The wrap BVP did not converge."""


@dataclass(frozen=True)
class WrapSolution:
    """The wrap: arc ``[s1, s2]`` (``arc = s2 - s1``), its end forces ``f1, f2`` and least pressure
    ``p_min``, the tip force ``Q`` (on the rod, along the cylinder's radius), ``tip`` [X, Y]; the free
    pieces sampled (``s, theta, x, y, moment``, the arc between them); ``valid``/``violations``."""

    s1: float
    s2: float
    arc: float
    f1: float
    f2: float
    p_min: float
    Q: float
    tip: np.ndarray
    s: np.ndarray
    theta: np.ndarray
    x: np.ndarray
    y: np.ndarray
    moment: np.ndarray
    valid: bool
    violations: tuple
    residual: float


def _frame(th):
    return np.array([np.cos(th), np.sin(th)]), np.array([-np.sin(th), np.cos(th)])


def _forces(p, R, D, k):
    """``n(s1-)``, ``n(s2+)`` and ``f2`` from the parameters (see the module docstring)."""
    Q, s1, s2, f1, psi1, psit = p
    th1 = psi1 - 0.5 * np.pi
    L = s2 - s1
    th2 = th1 - L / R
    t2, nu2 = _frame(th2)
    t1, nu1 = _frame(th1)
    n2p = Q * np.array([np.cos(psit), np.sin(psit)]) - (1.0 - s2) * np.array([0.0, 1.0])
    T2 = float(n2p @ t2)
    f2 = -float(n2p @ nu2)
    # int_{s1}^{s2} sin(theta) ds with theta = th1 - (s - s1)/R
    I = R * (np.cos(th2) - np.cos(th1))
    T1 = T2 - I
    n1m = T1 * t1 + f1 * nu1
    return n1m, n2p, f2, T1, th1, th2


def solve_wrap(params, profile, cylinder, guess, *, tol=1e-10) -> WrapSolution:
    """Solve the wrap BVP (free rod, uniform ``kappa0 < 0``; see the module docstring).

    ``guess``: the constrained chain (:func:`~simgrip.reference.constrained.solve_constrained` with this
    ``cylinder``) with two or more wrapped links and the tip on the cylinder.

    Raises
    ------
    ValueError
        A non-uniform or non-negative profile, or a guess without that contact set.
    WrapError
        ``solve_bvp`` failed.
    """
    params = check_params(params)
    prof = as_profile(profile)
    if not all(hasattr(cylinder, a) for a in ("x", "y", "radius")):
        raise ValueError(f"cylinder must be a Cylinder, got {type(cylinder).__name__}")
    if not hasattr(guess, "contact_links"):
        raise ValueError("guess must be a ConstrainedEquilibrium with this cylinder")
    if not isinstance(prof, Uniform) or not prof.kappa < 0:
        raise ValueError("profile: the wrap BVP takes a uniform kappa < 0 (curling clockwise onto the cylinder)")
    k, D, R = float(prof.kappa), params.D, cylinder.radius
    c = np.array([cylinder.x, cylinder.y])
    links = np.array(guess.contact_links("cylinder"))
    n = guess.n
    ds = 1.0 / n
    if links.size == 0 or links[-1] != n - 1:
        raise ValueError("guess: the chain's tip must rest on the cylinder")
    body = links[links < n - 1]  # the wrapped part: every contact but the tip's (a polygon on a circle
    if body.size < 2:            # touches it at some links only; its first ones carry the end force f1)
        raise ValueError("guess: no wrapped arc (two or more links on the cylinder besides the tip)")
    run = np.split(body, np.nonzero(np.diff(body) != 1)[0] + 1)[0]
    s1, s2 = (body[0] + 0.5) * ds, (body[-1] + 0.5) * ds
    P = guess.nodes
    psi1 = float(guess.link_angles[body[0]] + 0.5 * np.pi)
    psit = float(np.arctan2(P[-1, 1] - c[1], P[-1, 0] - c[0]))
    psit += 2 * np.pi * np.round((guess.link_angles[-1] + 0.5 * np.pi - psit) / (2 * np.pi))
    tipf = [q for q in guess.contacts if q.kind == "cylinder" and q.index == n - 1]
    Q = float(np.linalg.norm(tipf[0].force)) if tipf else 1.0
    f1 = float(sum(np.linalg.norm(q.force) for q in guess.contacts if q.kind == "cylinder" and q.index < run[0]))
    p0 = np.array([Q, s1, s2, f1, psi1, psit])
    t = np.linspace(0.0, 1.0, 81)
    sm = (np.arange(n) + 0.5) * ds
    sn = np.arange(n + 1) * ds
    mom = np.concatenate([[0.0], D * (np.diff(guess.link_angles) / ds - k), [0.0]])

    def state(ss):
        return [np.interp(ss, sm, guess.link_angles), np.interp(ss, sn, mom),
                np.interp(ss, sn, P[:, 0]), np.interp(ss, sn, P[:, 1])]

    y0 = np.vstack(state(s1 * t) + state(s2 + (1 - s2) * t))
    e2 = np.array([0.0, 1.0])

    def fun(tt, y, p):
        n1m, n2p, _, _, _, _ = _forces(p, R, D, k)
        s1, s2 = p[1], p[2]
        out = np.empty_like(y)
        for seg, (s0, L) in enumerate(((0.0, s1), (s2, 1.0 - s2))):
            th, m = y[4 * seg], y[4 * seg + 1]
            s = s0 + L * tt
            if seg == 0:
                nv = n1m[:, None] - (s1 - s)[None, :] * e2[:, None]
            else:
                nv = n2p[:, None] + (s - s2)[None, :] * e2[:, None]
            out[4 * seg] = L * (k + m / D)
            out[4 * seg + 1] = L * (nv[0] * np.sin(th) - nv[1] * np.cos(th))
            out[4 * seg + 2] = L * np.cos(th)
            out[4 * seg + 3] = L * np.sin(th)
        return out

    def bc(ya, yb, p):
        Q, s1, s2, f1, psi1, psit = p
        psi2 = psi1 - (s2 - s1) / R
        mc = D * (-1.0 / R - k)
        return np.array([
            ya[0], ya[2], ya[3],
            yb[2] - c[0] - R * np.cos(psi1), yb[3] - c[1] - R * np.sin(psi1), yb[0] - (psi1 - 0.5 * np.pi),
            yb[1] - mc,
            ya[6] - c[0] - R * np.cos(psi2), ya[7] - c[1] - R * np.sin(psi2), ya[4] - (psi2 - 0.5 * np.pi),
            ya[5] - mc,
            yb[5], yb[6] - c[0] - R * np.cos(psit), yb[7] - c[1] - R * np.sin(psit),
        ])

    r = solve_bvp(fun, bc, t, y0, p=p0, tol=tol, bc_tol=tol, max_nodes=20000)
    if r.status != 0 or not np.all(np.isfinite(r.p)):
        raise WrapError(f"solve_bvp: {r.message}")
    Q, s1, s2, f1, psi1, psit = (float(v) for v in r.p)
    n1m, n2p, f2, T1, th1, th2 = _forces(r.p, R, D, k)
    sa = np.linspace(s1, s2, 201)
    tha = th1 - (sa - s1) / R
    T = T1 + R * (np.cos(tha) - np.cos(th1))  # T(s) = T(s1+) + int_{s1}^{s} sin theta
    p_arc = T / R + np.cos(tha)
    tf = np.linspace(0.0, 1.0, 401)
    y = r.sol(tf)
    s = np.concatenate([s1 * tf, sa[1:-1], s2 + (1 - s2) * tf])
    psia = tha[1:-1] + 0.5 * np.pi
    x = np.concatenate([y[2], c[0] + R * np.cos(psia), y[6]])
    yy = np.concatenate([y[3], c[1] + R * np.sin(psia), y[7]])
    th = np.concatenate([y[0], tha[1:-1], y[4]])
    mom = np.concatenate([y[1], np.full(psia.size, D * (-1.0 / R - k)), y[5]])
    bad = []
    if not 0.0 < s1 < s2 < 1.0:
        bad.append(f"the arc [{s1:.4g}, {s2:.4g}] is not inside the rod")
    for name, v in (("f1", f1), ("f2", f2), ("Q", Q)):
        if v < -1e-9:
            bad.append(f"{name} = {v:.4g} < 0 (the cylinder would pull)")
    if float(np.min(p_arc)) < -1e-9:
        bad.append(f"negative pressure on the arc (min {float(np.min(p_arc)):.4g})")
    gap = np.hypot(x - c[0], yy - c[1]) - R
    if float(np.min(gap)) < -1e-7:
        bad.append(f"the rod enters the cylinder (depth {-float(np.min(gap)):.3g})")
    if self_crossing(np.stack([x, yy], axis=1), 0.0):
        bad.append("the centreline crosses itself")
    return WrapSolution(s1=s1, s2=s2, arc=s2 - s1, f1=f1, f2=f2, p_min=float(np.min(p_arc)), Q=Q,
                        tip=np.array([y[6, -1], y[7, -1]]), s=s, theta=th, x=x, y=yy, moment=mom,
                        valid=not bad, violations=tuple(bad), residual=float(np.max(r.rms_residuals)))

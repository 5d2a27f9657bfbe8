"""One finger on a workpiece that does not turn (the Grip I/II pinch): a state's terms with its trigonometry shared.

At every state of its inner solve :class:`~simgrip.settle.chain_newton.ChainNewton` evaluates the nodes, the
spring and gravity forces and, per contact pair and stick, a :class:`~simgrip.settle.chain_model.Term`
(:meth:`ChainModel.dot_term`).  Each of these computes ``cos`` and ``sin`` of the link angles anew (the nodes,
the forces, and every term through :meth:`ChainModel._link`), and every term reads the workpiece's pose and builds
the same ``(n, 2)`` normal and tangent arrays for a product with a 2-vector ``v``.  Here one finger's
state computes ``cos phi`` and ``sin phi`` once, and a term whose vector is one of the plane's axes --
the tip sphere's pair on the box face (``v = (1, 0)``, the face normal of a workpiece that does not turn) and a
stick whose tangent turns with that workpiece and has no ``x`` part (``v = (0, v_1)``, the face's tangent) --
takes its gradient and Hessian diagonal as the one product that is not a zero (issue 19: the Grip I settle's
per-state cost).

Bit for bit the same numbers: ``np.cos``/``np.sin`` are elementwise (an element's value does not depend on the
array it sits in), so the shared arrays hold what each function computed for itself; the scalar parts are
:meth:`ChainModel.dot_term`'s own formulas on the same floats; and for ``v = (1, 0)`` the row products
``nk @ v = -sin phi_k * 1 + cos phi_k * 0`` and ``tk @ v = cos phi_k * 1 + sin phi_k * 0`` are ``-sin phi_k``
and ``cos phi_k`` exactly (a product with 1 is exact, one with 0 a zero that leaves a nonzero sum as it is),
likewise ``v = (0, v_1)`` gives ``cos phi_k v_1`` and ``sin phi_k v_1`` rounded once, with or without a fused
multiply-add.  Only the sign of a zero could differ (an exactly zero ``sin phi_k``), which no sum or product
with a nonzero number sees.  Any other pair or stick (a capsule, a stick turning with its link, a tangent with an
``x`` part) is :class:`ChainModel`'s own term.  ``tests/test_settle_pinch.py`` holds these terms to
:class:`ChainModel`'s, and whole settles to settles with the generic terms, bit for bit.
"""

from __future__ import annotations

import math

import numpy as np

from simgrip.settle.chain_model import ChainModel, Term

__all__ = ["Pinch", "evaluators"]


def evaluators(cm: ChainModel) -> tuple:
    """``(nodes, internal, pair_term, stick_term)`` of ``cm``'s interface: :class:`Pinch`'s for one finger on a
    workpiece that does not turn, else ``cm``'s own methods."""
    if cm.fingers != 1 or cm._turns or cm.nw != 1:
        return cm.nodes, cm.internal, cm.pair_term, cm.stick_term
    p = Pinch(cm)
    return p.nodes, p.internal, p.pair_term, p.stick_term


class Pinch:
    """:class:`ChainModel`'s state functions for one finger (see the module docstring); ``cos`` and ``sin`` of the
    last state's link angles kept (keyed on the array itself: a state's arrays are never written in place)."""

    def __init__(self, cm: ChainModel):
        self.cm = cm
        self._trig = None  # (phi, cos phi, sin phi)

    def trig(self, phi) -> tuple[np.ndarray, np.ndarray]:
        t = self._trig
        if t is not None and t[0] is phi:
            return t[1], t[2]
        c, s = np.cos(phi), np.sin(phi)
        self._trig = (phi, c, s)
        return c, s

    def nodes(self, phi) -> np.ndarray:
        """:meth:`ChainModel.nodes` (the same sums of the same products)."""
        cm = self.cm
        c, s = self.trig(phi)
        out = np.zeros((1, cm.nl + 1, 2))
        (cm.ds * c).cumsum(out=out[0, 1:, 0])
        (cm.ds * s).cumsum(out=out[0, 1:, 1])
        return out

    def internal(self, phi) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`ChainModel.internal` (:meth:`ChainModel._force_diag`'s arithmetic)."""
        cm = self.cm
        c, s = self.trig(phi)
        rest = cm.m.qpos_spring[cm.jq]  # (read each time, as internal does)
        q = phi.copy()
        q[1:] -= phi[:-1]
        q[cm._first_at] = phi[cm._first_at]
        sp = cm.k * (q - rest)
        sn = np.empty_like(sp)
        sn[:-1] = sp[1:]
        sn[cm._last_at] = 0.0
        return sn - sp - cm.c * c, cm._k_diag + cm.c * s, cm._k_next[:-1].copy()

    def pair_term(self, p, phi, nodes, y) -> Term:
        """:meth:`ChainModel.pair_term`: the tip sphere on the face here, any other pair there."""
        cm = self.cm
        f, i, sphere = cm.pair_link[p]
        if not sphere or type(phi) is not np.ndarray:
            return cm.pair_term(p, phi, nodes, y)
        return self._axis_term(phi, nodes, i, nodes[f, i + 1], cm._face_at[p], y, (1.0, 0.0), -cm.radius[p])

    def stick_term(self, s, phi, nodes, y) -> Term:
        """:meth:`ChainModel.stick_term`: a stick whose tangent turns with the workpiece and has no ``x`` part here,
        any other there."""
        cm = self.cm
        if s.t_body == s.body_f or type(phi) is not np.ndarray:
            return cm.stick_term(s, phi, nodes, y)
        f, i = cm.link_index[s.body_f]
        L = cm.L
        gi = f * cm.nl + i
        ct, st = math.cos(float(phi[gi])), math.sin(float(phi[gi]))  # (stick_term's own, not the array's)
        lf0, lf2 = float(s.local_f[0]), float(s.local_f[2])
        nd = nodes[f, i]
        pf = (float(nd[0]) + (lf0 * ct - lf2 * st) / L, float(nd[1]) + (lf0 * st + lf2 * ct) / L)
        mf = float(cm.mir[f])
        pw_loc = (mf * (float(s.local_w[0]) / L), float(s.local_w[2]) / L)
        v_loc = (mf * float(s.t_local[0]), float(s.t_local[2]))
        t = self._axis_term(phi, nodes, i, pf, pw_loc, y, v_loc, s.offset / L)
        return cm.stick_term(s, phi, nodes, y) if t is None else t

    def _axis_term(self, phi, nodes, i, p, c_loc, y, v_loc, add):
        """:meth:`ChainModel.dot_term` of kind ``"work"`` (finger 0, no turn) plus ``add`` on its value, where ``v``
        is ``(1, 0)`` or ``(0, v_1)``; None for any other ``v``."""
        cm = self.cm
        n, ds = cm.n, cm.ds
        O, alpha, dO, da = cm.pose(0, y)
        ca, sa = math.cos(alpha), math.sin(alpha)
        cl0, cl1 = float(c_loc[0]), float(c_loc[1])
        rc0, rc1 = ca * cl0 - sa * cl1, sa * cl0 + ca * cl1  # R(alpha) c_loc
        o0, o1 = float(O[0]), float(O[1])
        pc0, pc1 = float(p[0]) - (o0 + rc0), float(p[1]) - (o1 + rc1)  # p - c
        nd = nodes[0, i]
        rel0, rel1 = float(p[0]) - float(nd[0]), float(p[1]) - float(nd[1])  # p - node_i
        vl0, vl1 = float(v_loc[0]), float(v_loc[1])
        v0, v1 = ca * vl0 - sa * vl1, sa * vl0 + ca * vl1
        normal = v0 == 1.0 and v1 == 0.0
        if not (normal or v0 == 0.0):
            return None
        c, s = self.trig(phi)
        grad = np.zeros(n + cm.nw)
        diag = np.zeros(n)
        if normal:  # v = (1, 0): nk @ v = -sin, tk @ v = cos
            grad[:i] = -ds * s[:i]
            diag[:i] = -ds * c[:i]
        else:  # v = (0, v1): nk @ v = cos v1, tk @ v = sin v1
            grad[:i] = ds * (c[:i] * v1)
            diag[:i] = -ds * (s[:i] * v1)
        grad[i] = v1 * rel0 - v0 * rel1  # v . perp(rel)
        grad[n:] = -(dO @ np.array([v0, v1]) + da * (v1 * rc0 - v0 * rc1))  # -(d c / d y . v)
        diag[i] = -(v0 * rel0 + v1 * rel1)
        return Term((v0 * pc0 + v1 * pc1) + add, grad, diag, *cm._no_rank)

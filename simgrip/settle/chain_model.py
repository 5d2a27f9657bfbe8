"""The statics of a one-finger scene in the chain's own coordinates, with exact derivatives.

Unknowns: the link angles ``phi_0 .. phi_{n-1}`` (MuJoCo's hinge angles are
``q_j = phi_j - phi_{j-1}``) and the workpiece's height ``w`` when it slides in
``z``.  Everything is dimensionless (lengths over ``l``, forces over ``rho g l``,
moments over ``rho g l^2``) and read from the compiled model, so it is the
MuJoCo chain itself, not a copy of the theory:

* springs ``V_s = sum_j k_j/2 (q_j - r_j)^2`` (``jnt_stiffness``,
  ``qpos_spring``): force ``-dV_s/dphi_i = s_{i+1} - s_i`` with hinge moments
  ``s_j = k_j (q_j - r_j)``; Hessian tridiagonal (``k_i + k_{i+1}`` on the
  diagonal, ``-k_{i+1}`` beside it);
* gravity ``V_g = sum_k c_k sin(phi_k)`` with ``c_k = g (m_k a_k + ds sum_{i>k}
  m_i)`` (``a_k`` the centre of mass along link ``k``): diagonal Hessian;
* a generalised force ``Q_q`` on the hinges is ``Q_q_j = sum_{i >= j} F_i`` of the
  link-angle force ``F`` (``phi = cumsum(q)``); the residual is reported in ``q``.

Contact and stick terms are all of one form, ``f = v . (p - c)`` with ``p`` a
point fixed on link ``i`` (``node_i + a_x t_i + a_z n_i``, ``t_i = (cos, sin)``,
``n_i = (-sin, cos)``), ``c`` a point on the workpiece (``dc/dw = e_z``) and
``v`` either fixed in the world or turning with link ``i``.  With
``dp/dphi_k = ds n_k`` (``k < i``), ``dp/dphi_i = perp(p - node_i)``::

    df/dphi_k = v . ds n_k                (k < i)
    df/dphi_i = v . perp(p - node_i) [+ perp(v) . (p - c)]
    df/dw     = -v . e_z
    d2f/dphi_k^2  = -v . ds t_k           (k < i)
    d2f/dphi_i^2  = -v . (p - node_i)     [turning v: + 2 v.(p - node_i) - v.(p - c)]
    d2f/dphi_k dphi_i = perp(v) . ds n_k, d2f/dphi_i dw = -perp(v) . e_z   (turning v only)

so its Hessian is a diagonal plus an "arrow" on index ``i``, written as the
rank-2 term ``U S U'`` with ``U = [e_i, h]``, ``S = [[0, 1], [1, 0]]``.  A
capsule end cap (Grip III corner beyond a node) is ``f = |c - p|``: gradient
``e . de/dx``, Hessian ``(1/|e|) u u' + diag(e . d2e)`` with ``u = e_perp . de/dx``.
These are the sphere--face (Grips I/II) and capsule--capsule (Grip III)
distances of MuJoCo's collision functions, and the sticking constraints of
:class:`~simgrip.settle.statics.Stick`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from simgrip.sim.scene import Scene

__all__ = ["ChainModel", "Term", "eligible", "gravity_factor", "model_gravity"]

_EZ = np.array([0.0, 1.0])


def _perp(v):
    return np.array([-v[1], v[0]])


def model_gravity(m) -> float:
    """Downward gravity [m/s^2] as MuJoCo applies it: ``-opt.gravity[2]``, or 0 under ``mjDSBL_GRAVITY``."""
    if int(m.opt.disableflags) & int(mujoco.mjtDisableBit.mjDSBL_GRAVITY):
        return 0.0
    return -float(m.opt.gravity[2])


def gravity_factor(scene: Scene) -> float:
    """The scene's gravity over the physical ``g`` it was built with (1 physical, 0 gravity free).

    Read from the compiled model as MuJoCo applies it (:func:`model_gravity`):
    both a zeroed ``opt.gravity`` and the ``mjDSBL_GRAVITY`` flag switch it off.
    This is the ``gravity`` factor of :func:`simgrip.reference.solve_chain`.
    """
    return model_gravity(scene.model) / scene.physical.g


def eligible(scene: Scene) -> bool:
    """The chain-coordinate solve covers one-finger scenes whose workpiece slides in z or is fixed."""
    return scene.fingers == 1 and tuple(scene.workpiece_joints) in ((), ("z",)) and scene.mirror[0] == 1.0


@dataclass
class Term:
    """A scalar function of ``x = (phi, w)``: value, gradient, diagonal + low-rank Hessian."""

    value: float
    grad: np.ndarray  # (n + nw,)
    diag: np.ndarray  # (n,)  phi-phi diagonal
    U: np.ndarray  # (n + nw, r)
    S: np.ndarray  # (r, r)


class ChainModel:
    """Analytic statics of a one-finger scene (see the module docstring)."""

    def __init__(self, scene: Scene):
        m = scene.model
        self.scene, self.m = scene, m
        L, W = scene.length, scene.force_scale
        self.L, self.W = L, W
        n = scene.n
        self.n = n
        self.jq = np.asarray(scene.joint_qpos[0], int)
        self.jd = np.asarray(scene.joint_dof[0], int)
        self.k = m.jnt_stiffness[m.dof_jntid[self.jd]] / (W * L)
        bodies = np.asarray(scene.link_body[0], int)
        self.link_index = {int(b): i for i, b in enumerate(bodies)}
        self.ds = float(m.body_pos[bodies[1]][0]) / L
        g = model_gravity(m)
        mass = m.body_mass[bodies]
        arm = m.body_ipos[bodies][:, 0] / L
        beyond = np.concatenate([np.cumsum(mass[::-1])[::-1][1:], [0.0]])
        self.c = g * (mass * arm + self.ds * beyond) * L / (W * L)
        self.nw = 1 if tuple(scene.workpiece_joints) == ("z",) else 0
        self.wq = int(scene.workpiece_qpos[0]) if self.nw else -1
        self.wd = int(scene.workpiece_dof[0]) if self.nw else -1
        self.weight = float(m.body_mass[scene.workpiece_body]) * g / W if scene.has_workpiece else 0.0
        self.pairs = [(int(m.pair_geom1[i]), int(m.pair_geom2[i])) for i in range(m.npair)]
        #: for each pair: (link index of geom1, is the tip sphere) and the radii to subtract
        self.pair_link, self.radius = [], []
        for g1, g2 in self.pairs:
            sphere = int(m.geom_type[g1]) == int(mujoco.mjtGeom.mjGEOM_SPHERE)
            self.pair_link.append((self.link_index[int(m.geom_bodyid[g1])], sphere))
            self.radius.append((m.geom_size[g1][0] + (0.0 if sphere else m.geom_size[g2][0])) / L)

    # -- kinematics -------------------------------------------------------------
    def split(self, q) -> tuple[np.ndarray, float]:
        """Link angles and the workpiece height coordinate (over l) from MuJoCo's ``qpos``."""
        phi = np.cumsum(np.asarray(q)[self.jq])
        w = float(q[self.wq]) / self.L if self.nw else 0.0
        return phi, w

    def join(self, q, phi, w) -> np.ndarray:
        """``q`` with the link angles ``phi`` and the workpiece height ``w`` (over l) written in."""
        qq = np.array(q, dtype=float)
        qq[self.jq] = np.diff(phi, prepend=0.0)
        if self.nw:
            qq[self.wq] = w * self.L
        return qq

    def nodes(self, phi) -> np.ndarray:
        ds = self.ds
        return np.vstack([np.zeros(2), np.cumsum(ds * np.stack([np.cos(phi), np.sin(phi)], 1), 0)])

    def workpiece_origin(self, w) -> np.ndarray:
        """World (x, z) over l of the workpiece body at height coordinate ``w``."""
        sc = self.scene
        p = self.m.body_pos[sc.workpiece_body] / self.L
        return np.array([p[0], p[2] + w])

    def geom_point(self, g, w) -> np.ndarray:
        """Centre (x, z) over l of a workpiece geom (the body does not turn)."""
        gp = self.m.geom_pos[g] / self.L
        return self.workpiece_origin(w) + np.array([gp[0], gp[2]])

    # -- internal forces --------------------------------------------------------
    def internal(self, phi) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Spring and gravity force on the link angles, and its tridiagonal Jacobian (diag, off)."""
        q = np.diff(phi, prepend=0.0)
        s = self.k * (q - self.m.qpos_spring[self.jq])
        F = np.append(s[1:], 0.0) - s - self.c * np.cos(phi)
        kk = np.append(self.k[1:], 0.0)
        diag = -(self.k + kk) + self.c * np.sin(phi)
        off = self.k[1:].copy()
        return F, diag, off

    def free_equilibrium(self, phi0, tol: float = 1e-12, max_iter: int = 50):
        """The finger alone (no contact) at equilibrium, by Newton from ``phi0``; None if it fails.

        The tridiagonal Jacobian of :meth:`internal` is exact, so a start near the
        equilibrium (e.g. the grip's shape) converges in a few ``O(n)`` steps; a
        backtracking line search on ``|F|`` guards the rest.  Not checked for
        stability: callers use it near a known stable branch.
        """
        from scipy.linalg import solve_banded

        phi = np.array(phi0, dtype=float)
        F, diag, off = self.internal(phi)
        res = float(np.max(np.abs(self.to_q(F))))
        for _ in range(max_iter):
            if res < tol:
                return phi
            ab = np.zeros((3, self.n))
            ab[0, 1:], ab[1], ab[2, :-1] = off, diag, off
            try:
                d = solve_banded((1, 1), ab, -F, check_finite=False)
            except (np.linalg.LinAlgError, ValueError):
                return None
            step = 1.0
            for _ls in range(30):
                Fn, dn, on = self.internal(phi + step * d)
                rn = float(np.max(np.abs(self.to_q(Fn))))
                if rn < res or rn < tol:
                    break
                step *= 0.5
            else:
                return None
            phi, F, diag, off, res = phi + step * d, Fn, dn, on, rn
        return phi if res < tol else None

    def workpiece_force(self) -> float:
        """Weight plus applied force on the workpiece's z dof (0 without one)."""
        if not self.nw:
            return 0.0
        return -self.weight + float(self.scene.data.qfrc_applied[self.wd]) / self.W

    def to_q(self, F) -> np.ndarray:
        """Link-angle force -> hinge force (suffix sums)."""
        return np.cumsum(F[::-1])[::-1]

    # -- terms ------------------------------------------------------------------
    def dot_term(self, phi, nodes, i, p, c, v, turning: bool) -> Term:
        """``f = v . (p - c)``: ``p`` on link ``i``, ``c`` on the workpiece, ``v`` fixed or turning with link ``i``."""
        n, nw, ds = self.n, self.nw, self.ds
        nk = np.stack([-np.sin(phi[:i]), np.cos(phi[:i])], 1)
        tk = np.stack([np.cos(phi[:i]), np.sin(phi[:i])], 1)
        rel = p - nodes[i]
        grad = np.zeros(n + nw)
        grad[:i] = ds * (nk @ v)
        grad[i] = float(v @ _perp(rel))
        diag = np.zeros(n)
        diag[:i] = -ds * (tk @ v)
        diag[i] = -float(v @ rel)
        if nw:
            grad[n] = -float(v[1])
        if not turning:
            return Term(float(v @ (p - c)), grad, diag, np.zeros((n + nw, 0)), np.zeros((0, 0)))
        pv = _perp(v)
        grad[i] += float(pv @ (p - c))
        diag[i] += 2.0 * float(v @ rel) - float(v @ (p - c))
        h = np.zeros(n + nw)
        h[:i] = ds * (nk @ pv)
        if nw:
            h[n] = -float(pv[1])
        U = np.zeros((n + nw, 2))
        U[i, 0] = 1.0
        U[:, 1] = h
        return Term(float(v @ (p - c)), grad, diag, U, np.array([[0.0, 1.0], [1.0, 0.0]]))

    def norm_term(self, phi, nodes, i, p, c) -> Term:
        """``f = |c - p|``: ``p`` on link ``i``, ``c`` on the workpiece."""
        n, nw, ds = self.n, self.nw, self.ds
        e = c - p
        rho = float(np.hypot(*e))
        eh = e / rho
        ep = _perp(eh)
        nk = np.stack([-np.sin(phi[:i]), np.cos(phi[:i])], 1)
        tk = np.stack([np.cos(phi[:i]), np.sin(phi[:i])], 1)
        rel = p - nodes[i]
        de = np.zeros((n + nw, 2))  # d e / d x
        de[:i] = -ds * nk
        de[i] = -_perp(rel)
        if nw:
            de[n] = _EZ
        diag = np.zeros(n)
        diag[:i] = ds * (tk @ eh)
        diag[i] = float(eh @ rel)
        return Term(rho, de @ eh, diag, (de @ ep)[:, None], np.array([[1.0 / rho]]))

    # -- contacts ---------------------------------------------------------------
    def pair_term(self, p, phi, nodes, w) -> Term:
        """Signed distance of contact pair ``p`` (MuJoCo's geometry) as a :class:`Term`."""
        i, sphere = self.pair_link[p]
        g1, g2 = self.pairs[p]
        R = self.radius[p]
        if sphere:  # tip sphere on the box's outer face x = face (box not turning)
            c = self.geom_point(g2, w)
            face = c[0] + self.m.geom_size[g2][0] / self.L
            t = self.dot_term(phi, nodes, i, nodes[i + 1], np.array([face, 0.0]), np.array([1.0, 0.0]), False)
            t.value -= R
            return t
        c = self.geom_point(g2, w)  # corner capsule axis (along y)
        a, b = nodes[i], nodes[i + 1]
        tvec = np.array([math.cos(phi[i]), math.sin(phi[i])])
        u = float((c - a) @ tvec)
        if u <= 0.0 or u >= self.ds:
            t = self.norm_term(phi, nodes, i, a if u <= 0.0 else b, c)
        else:
            nvec = _perp(tvec)
            sigma = 1.0 if float((c - a) @ nvec) >= 0.0 else -1.0
            t = self.dot_term(phi, nodes, i, a, c, -sigma * nvec, True)
        t.value -= R
        return t

    def pair_distances(self, phi, nodes, w) -> np.ndarray:
        """All pairs' signed distances (vectorised; same geometry as :meth:`pair_term`)."""
        if not self.pairs:
            return np.zeros(0)
        if not hasattr(self, "_pl"):
            m, L = self.m, self.L
            self._pl = np.array([i for i, _ in self.pair_link])
            self._sph = np.array([sp for _, sp in self.pair_link])
            g2 = np.array([g for _, g in self.pairs])
            self._gp = np.stack([m.geom_pos[g2][:, 0], m.geom_pos[g2][:, 2]], 1) / L
            self._hx = m.geom_size[g2][:, 0] / L
            self._rad = np.array(self.radius)
        c = self.workpiece_origin(w)[None, :] + self._gp
        a, b = nodes[self._pl], nodes[self._pl + 1]
        seg = b - a
        u = np.clip(np.einsum("ij,ij->i", c - a, seg) / np.einsum("ij,ij->i", seg, seg), 0.0, 1.0)
        caps = np.hypot(*(c - a - u[:, None] * seg).T) - self._rad
        face = b[:, 0] - (c[:, 0] + self._hx) - self._rad  # tip sphere (the end of its link) on the face
        return np.where(self._sph, face, caps)

    def stick_term(self, s, phi, nodes, w) -> Term:
        """Sticking constraint ``t . (p_f - p_w) + offset`` (over l) of a :class:`Stick`."""
        i = self.link_index[s.body_f]
        L = self.L
        ti = np.array([math.cos(phi[i]), math.sin(phi[i])])
        ni = _perp(ti)
        pf = nodes[i] + (s.local_f[0] * ti + s.local_f[2] * ni) / L
        pw = self.workpiece_origin(w) + np.array([s.local_w[0], s.local_w[2]]) / L
        turning = s.t_body == s.body_f
        if turning:
            v = s.t_local[0] * ti + s.t_local[2] * ni
        else:
            v = np.array([s.t_local[0], s.t_local[2]])
        t = self.dot_term(phi, nodes, i, pf, pw, v, turning)
        t.value += s.offset / L
        return t

"""MuJoCo's own linearisation of a settled scene: mass matrix, stiffness, sticking constraints, eigenpairs.

Small motions ``q = q* + dq`` about a static equilibrium ``q*`` of the chain obey

    M(q*) ddq = dQ/dq dq + sum_k lambda_k H_k dq + J^T dlambda,        J dq = 0,

where ``Q(q) = qfrc_passive - qfrc_bias`` at ``qvel = 0`` is MuJoCo's generalised
force of the springs (``qpos_spring``), gravity and the workpiece's gravity
compensation, ``g(q) = 0`` are the sticking contacts (a material point of the
finger moves with a material point of the workpiece: two rows per contact in the
plane of the fingers), ``J = dg/dq`` and ``H_k = d^2 g_k / dq^2``.  The
multipliers ``lambda`` (the contact forces on the finger, world ``x`` and ``z``)
are those of the equilibrium, ``Q(q*) + J^T lambda = 0``, read back by least
squares from MuJoCo's own forces (their misfit is the settle's residual).

With ``dq = N eta`` and ``N`` an orthonormal basis of ``ker J``, premultiplying by
``N^T`` removes ``dlambda``:

    (N^T M N) ddeta + (N^T K N) eta = 0,    K = -d/dq [Q(q) + J(q)^T lambda]  (lambda fixed),

i.e. ``K`` is the Hessian of the Lagrangian ``V(q) - lambda . g(q)`` with the
multipliers frozen: the springs' stiffness, gravity's geometric stiffness and the
constraint force's geometric stiffness (the rotation of the links carrying the
contact force).  ``K`` is formed by central differences of MuJoCo's own forces
(``mj_passive``, ``mj_rne``, ``mj_applyFT`` for ``J(q)^T lambda`` at the moving
material points): step ``h = 1e-5`` rad (or ``1e-5 l``), truncation
``O(h^2) ~ 1e-10`` of the gravity and contact terms (the springs are linear, so
exact), round-off ``eps |Q| / h`` far below that.  It is symmetric up to those
errors (:attr:`Linearisation.asymmetry`) and symmetrised.

``M`` is ``mj_fullM`` at ``q*`` (link masses, their inertias, armature, the
workpiece).  Everything is in the model's units (SI for ``PhysicalParams``, ``l =
rho = g = 1`` for ``DimensionlessParams``): eigenvalues are ``omega^2`` [1/s^2].
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np
import scipy.linalg as sla

__all__ = ["FD_STEP", "Linearisation", "Stick", "eigen", "linearise", "sticks_of"]

#: Central-difference step of the stiffness, rad (hinges) or over ``l`` (slides).
FD_STEP = 1e-5


@dataclass(frozen=True)
class Stick:
    """A sticking contact: the material point ``point_a`` of body ``body_a`` (a finger's link) moves with the
    material point ``point_b`` of body ``body_b`` (the workpiece; 0, the world, for a fixed one).  Points are in
    the bodies' local frames [m]; they coincide at the equilibrium."""

    body_a: int
    point_a: np.ndarray
    body_b: int
    point_b: np.ndarray
    #: World components constrained: ``"xz"`` (the planar scenes) or ``"xyz"`` (a K-finger gripper in 3-D).
    rows: str = "xz"


@dataclass
class Linearisation:
    """The linearised dynamics of a settled scene (model units; ``nv`` dofs, ``c`` constraint rows).

    Attributes
    ----------
    M, K : ndarray (nv, nv)
        Mass matrix (``mj_fullM``) and stiffness (symmetrised, see the module docstring).
    jacobian : ndarray (c, nv)
        Constraint Jacobian ``J`` (world ``x`` and ``z`` rows of each stick, or ``x, y, z``: :attr:`Stick.rows`).
    basis : ndarray (nv, nv - rank J)
        Orthonormal basis ``N`` of ``ker J`` (the identity without constraints).
    multipliers : ndarray (c,)
        Contact forces on the finger at the equilibrium, the world components of :attr:`Stick.rows` [N].
    misfit : float
        ``max |Q(q*) + J^T lambda|`` over the force scale of each dof: how far ``q*`` is from the equilibrium
        the linearisation assumes (the settle's residual).
    asymmetry : float
        ``|K - K^T|_max / |K|_max`` before symmetrising (finite-difference error).
    qpos : ndarray
        The equilibrium.
    sticks : tuple of Stick
    """

    M: np.ndarray
    K: np.ndarray
    jacobian: np.ndarray
    basis: np.ndarray
    multipliers: np.ndarray
    misfit: float
    asymmetry: float
    qpos: np.ndarray
    sticks: tuple

    def reduced(self) -> tuple[np.ndarray, np.ndarray]:
        """``(N^T M N, N^T K N)``: mass and stiffness on the constraints' null space."""
        N = self.basis
        return N.T @ self.M @ N, N.T @ self.K @ N

    @property
    def dofs(self) -> int:
        """Degrees of freedom left by the constraints (``nv - rank J``)."""
        return int(self.basis.shape[1])


def sticks_of(scene, state, data=None) -> tuple:
    """The sticking contacts of a settled ``state`` of ``scene`` (a :class:`~simgrip.sim.scene.Scene`).

    Grips I/II: each finger's tip (the end of its last link, the centreline: the point contact) sticks to
    the workpiece.  Grip III: the finger's centreline point at the contact (``contact.point``, arc length
    ``gamma``) sticks to the workpiece.  Empty for the free rod or a dropped workpiece.  ``data`` (default
    ``scene.data``) holds the positions of the equilibrium (``mj_kinematics`` done).
    """
    if not scene.has_workpiece or not state.held:
        return ()
    d = scene.data if data is None else data
    out = []
    wb = int(scene.workpiece_body)
    body_b = wb if len(scene.workpiece_dof) else 0
    for f, c in enumerate(state.contacts):
        if scene.grip in ("I", "II"):
            link = scene.n - 1
            local = np.array([scene.length / scene.n, 0.0, 0.0])
        else:
            link = min(int(c.gamma * scene.n), scene.n - 1)
            local = np.array([(c.gamma - link / scene.n) * scene.length, 0.0, 0.0])
        body_a = int(scene.link_body[f, link])
        world = d.xpos[body_a] + d.xmat[body_a].reshape(3, 3) @ local
        local_b = d.xmat[body_b].reshape(3, 3).T @ (world - d.xpos[body_b])
        out.append(Stick(body_a, local, body_b, local_b))
    return tuple(out)


class _Forces:
    """``Q(q) + J(q)^T lambda`` on scratch data, O(nv) per call (no mass matrix, no contact)."""

    def __init__(self, model, sticks, applied=None):
        self.m = model
        self.d = mujoco.MjData(model)
        self.sticks = sticks
        self.applied = np.zeros(model.nv) if applied is None else np.asarray(applied, dtype=float)

    def positions(self, q):
        m, d = self.m, self.d
        d.qpos[:] = q
        d.qvel[:] = 0.0
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)

    def world(self, body, local):
        d = self.d
        return d.xpos[body] + d.xmat[body].reshape(3, 3) @ local

    def __call__(self, q, lam=None) -> np.ndarray:
        m, d = self.m, self.d
        self.positions(q)
        mujoco.mj_comVel(m, d)
        mujoco.mj_passive(m, d)
        bias = np.zeros(m.nv)
        mujoco.mj_rne(m, d, 0, bias)
        out = np.array(d.qfrc_passive) - bias + self.applied
        if lam is not None:
            zero = np.zeros(3)
            at = 0
            for st in self.sticks:
                F = np.zeros(3)
                for axis in st.rows:
                    F["xyz".index(axis)] = lam[at]
                    at += 1
                mujoco.mj_applyFT(m, d, F, zero, self.world(st.body_a, st.point_a), st.body_a, out)
                if st.body_b > 0:
                    mujoco.mj_applyFT(m, d, -F, zero, self.world(st.body_b, st.point_b), st.body_b, out)
        return out

    def jacobian(self, q) -> np.ndarray:
        m, d = self.m, self.d
        self.positions(q)
        rows = []
        for st in self.sticks:
            jp = np.zeros((3, m.nv))
            mujoco.mj_jac(m, d, jp, None, self.world(st.body_a, st.point_a), st.body_a)
            if st.body_b > 0:
                jb = np.zeros((3, m.nv))
                mujoco.mj_jac(m, d, jb, None, self.world(st.body_b, st.point_b), st.body_b)
                jp -= jb
            rows += [jp["xyz".index(axis)] for axis in st.rows]
        return np.array(rows).reshape(len(rows), m.nv)


def _force_scales(model, length: float, force_scale: float) -> np.ndarray:
    """Per-dof force scale: ``rho g l^2`` for hinges and rotations, ``rho g l`` for slides and translations."""
    out = np.full(model.nv, force_scale * length)
    for j in range(model.njnt):
        if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE:
            out[model.jnt_dofadr[j]] = force_scale
        elif model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            out[model.jnt_dofadr[j]:model.jnt_dofadr[j] + 3] = force_scale
    return out


def linearise(scene, data=None, *, sticks=(), step: float = FD_STEP, applied=None) -> Linearisation:
    """Linearise ``scene`` (a built :class:`~simgrip.sim.scene.Scene`) about the configuration in ``data``.

    Parameters
    ----------
    scene : Scene
        Its ``model`` is used (contacts are ignored: a held workpiece enters as ``sticks``).
    data : mujoco.MjData, optional
        Holds the equilibrium ``qpos`` (default ``scene.data``); not modified.
    sticks : sequence of Stick
        Sticking contacts (:func:`sticks_of`); empty for the free rod.
    step : float
        Central-difference step (rad for hinges and rotations, times ``l`` for slides and translations;
        ball and free joints are stepped along their tangent space, ``mj_integratePos``).
    applied : array (nv,), optional
        A constant generalised force [model units] acting at the equilibrium (e.g. a K-finger gripper's
        workpiece weight relief, ``qfrc_applied`` of its settle); it enters the multipliers only.

    Returns
    -------
    Linearisation
        In the model's units (``omega^2`` of :func:`eigen` in 1/s^2).
    """
    m = scene.model
    d0 = scene.data if data is None else data
    step = float(step)
    if not (math.isfinite(step) and step > 0):
        raise ValueError(f"step must be positive and finite, got {step!r}")
    sticks = tuple(sticks)
    q0 = np.array(d0.qpos, dtype=float)
    F = _Forces(m, sticks, applied)
    Q0 = F(q0)
    J = F.jacobian(q0) if sticks else np.zeros((0, m.nv))
    if sticks:
        lam = np.linalg.lstsq(J.T, -Q0, rcond=None)[0]
    else:
        lam = np.zeros(0)
    scale = _force_scales(m, scene.length, scene.force_scale)
    misfit = float(np.max(np.abs(Q0 + J.T @ lam) / scale)) if m.nv else 0.0
    h = np.full(m.nv, step)
    for j in range(m.njnt):
        if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE:
            h[m.jnt_dofadr[j]] = step * scene.length
        elif m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            h[m.jnt_dofadr[j]:m.jnt_dofadr[j] + 3] = step * scene.length
    K = np.zeros((m.nv, m.nv))
    for i in range(m.nv):
        qp, qm = q0.copy(), q0.copy()
        e = np.zeros(m.nv)
        e[i] = h[i]
        mujoco.mj_integratePos(m, qp, e, 1.0)
        mujoco.mj_integratePos(m, qm, -e, 1.0)
        K[:, i] = -(F(qp, lam) - F(qm, lam)) / (2.0 * h[i])
    kmax = float(np.max(np.abs(K))) or 1.0
    asym = float(np.max(np.abs(K - K.T))) / kmax
    K = 0.5 * (K + K.T)
    dm = mujoco.MjData(m)
    dm.qpos[:] = q0
    mujoco.mj_fwdPosition(m, dm)  # kinematics, composite inertia, qM (with armature)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, dm, M)
    if sticks:
        N = sla.null_space(J)
    else:
        N = np.eye(m.nv)
    return Linearisation(M=M, K=K, jacobian=J, basis=N, multipliers=lam, misfit=misfit, asymmetry=asym,
                         qpos=q0, sticks=sticks)


def eigen(M, K, basis=None, count: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Natural frequencies squared and mode shapes of ``M ddq + K q = 0``, lowest first.

    Parameters
    ----------
    M, K : ndarray (nv, nv)
        Symmetric; ``M`` positive definite (on ``basis``).
    basis : ndarray (nv, r), optional
        Restrict to ``q = basis @ eta`` (the constraints' null space, :attr:`Linearisation.basis`).
    count : int, optional
        How many of the lowest modes (default all).

    Returns
    -------
    omega2 : ndarray (count,)
        Eigenvalues ``omega^2`` [1/s^2 of the model]; negative means unstable (no oscillation).
    shapes : ndarray (nv, count)
        Mode shapes in the full coordinates ``q``, mass-normalised (``shape^T M shape = 1``).
    """
    M = np.asarray(M, dtype=float)
    K = np.asarray(K, dtype=float)
    if M.ndim != 2 or M.shape[0] != M.shape[1] or K.shape != M.shape:
        raise ValueError(f"M and K must be square matrices of one shape, got {M.shape} and {K.shape}")
    N = np.eye(M.shape[0]) if basis is None else np.asarray(basis, dtype=float)
    if N.ndim != 2 or N.shape[0] != M.shape[0]:
        raise ValueError(f"basis must have {M.shape[0]} rows, got shape {N.shape}")
    r = N.shape[1]
    if count is None:
        count = r
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or not 1 <= count <= r:
        raise ValueError(f"count must be an integer in [1, {r}] (the degrees of freedom), got {count!r}")
    Mr, Kr = N.T @ M @ N, N.T @ K @ N
    w, v = sla.eigh(0.5 * (Kr + Kr.T), 0.5 * (Mr + Mr.T), subset_by_index=[0, int(count) - 1])
    return w, N @ v

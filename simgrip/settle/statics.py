"""MuJoCo's static force balance of a scene, the sticking constraints, the solve's contact settings.

At rest (``qvel = qacc = 0``) ``mj_inverse`` gives the generalised force that
holds a configuration, ``qfrc_inverse = qfrc_bias - qfrc_passive -
qfrc_constraint``; the imbalance ``r(q) = qfrc_applied - qfrc_inverse`` holds the
springs (``qpos_spring``), gravity and MuJoCo's contact forces.  It is scaled per
dof by :func:`dof_scales` (``rho g l^2`` for hinges, ``rho g l`` for slides): that
is the residual every settle reports.  :class:`RestResidual` is the same
balance from ``mj_forward`` (``qfrc_smooth + qfrc_constraint`` at ``qvel = 0``),
used by the dynamic settles.

MuJoCo's soft contact is invertible at rest: a contact with penetration ``p``
pushes with ``K_c p``; :func:`configure_statics` picks ``solref`` so that
``K_c ~`` :data:`CONTACT_STIFFNESS` ``rho g`` (``p ~ 1e-6 l``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from simgrip.sim.checks import active_warnings
from simgrip.sim.scene import Scene
from simgrip.settle.state import SettleError

__all__ = ["ANGLE_FLOOR_ULPS", "CONTACT_IMPEDANCE", "CONTACT_STIFFNESS", "RestResidual", "Statics", "Stick",
           "angle_floor", "dof_scales", "static_residual", "sync_scene", "centreline_point"]

#: Contact impedance during settle (MuJoCo's maximum is 0.9999).
CONTACT_IMPEDANCE = 0.9999
#: Target contact stiffness over rho g (force per length, dimensionless).
CONTACT_STIFFNESS = 1e6
#: Round-off of a joint angle in ulps of the largest link angle (:func:`angle_floor`).
ANGLE_FLOOR_ULPS = 2.5
_EPS = float(np.finfo(float).eps)  # (looked up once: the floor is evaluated every Newton iteration)


# ---------------------------------------------------------------------------
# statics


def dof_scales(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Per-dof force scale (rho g l^2 hinges, rho g l slides) and length scale (1, l)."""
    m = scene.model
    force = np.full(m.nv, scene.moment_scale)
    length = np.ones(m.nv)
    slide = m.jnt_dofadr[m.jnt_type == int(mujoco.mjtJoint.mjJNT_SLIDE)]  # (one array op: a settle's fixed cost)
    force[slide] = scene.force_scale
    length[slide] = scene.length
    return force, length


def _shared_dof_scales(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """:func:`dof_scales` of ``scene``, read only, computed again only when the model or a scale changed.

    The arrays depend on the model's joint types and addresses (its structure) and the scene's three
    scales: a one-entry memo on the scene, keyed on the model object and the scales, holds the values a
    fresh :func:`dof_scales` gives.  :class:`Statics` (built by every settle) reads them, never writes.
    """
    key = (scene.moment_scale, scene.force_scale, scene.length)
    memo = scene.__dict__.get("_dof_scales")
    if memo is not None and memo[0] is scene.model and memo[1] == key:
        return memo[2]
    out = dof_scales(scene)
    for a in out:
        a.setflags(write=False)
    scene.__dict__["_dof_scales"] = (scene.model, key, out)
    return out


def angle_floor(scene: Scene, qpos=None) -> float:
    """Round-off floor of the hinge rows of the static residual at ``qpos`` (over ``rho g l^2``).

    The chain is solved in link angles ``phi`` (running sums of the joint angles,
    up to ``Phi = max |phi|``) and MuJoCo is handed the joint angles ``q_a =
    phi_a - phi_(a-1)``: each ``phi`` is rounded to half an ulp, their difference
    to another half, so a joint angle carries up to ``1.5 eps Phi_a`` (``Phi_a =
    max(|phi_a|, |phi_(a-1)|)``), and the last Newton update its own rounding
    (``eps Phi_a``): the spring moment ``k_a (q_a - q0_a)`` of the nearest
    representable state can be off by ``2.5 eps k_a Phi_a``
    (:data:`ANGLE_FLOOR_ULPS`); the floor is the largest over the hinges.  A
    stiff fine chain (``k = D n`` over ``rho g l^2``) reaches the default
    tolerance ``1e-10`` near ``D n Phi ~ 2e5``; no residual test below this floor
    can pass.
    """
    m = scene.model
    q = np.asarray(scene.data.qpos if qpos is None else qpos)
    jq = np.asarray(scene.joint_qpos, dtype=int)
    if jq.size == 0:
        return 0.0
    phi = np.abs(q[jq].reshape(-1, jq.shape[-1]).cumsum(axis=-1))
    big = phi.copy()  # max |phi| at each hinge (the first's: |phi_0|, as max(|phi_0|, 0))
    np.maximum(phi[:, 1:], phi[:, :-1], out=big[:, 1:])
    k = m.jnt_stiffness[m.dof_jntid[np.asarray(scene.joint_dof, dtype=int).reshape(big.shape)]]
    return float(ANGLE_FLOOR_ULPS * _EPS * (k * big).max() / scene.moment_scale)


@dataclass
class Stick:
    """Sticking friction: a finger point and a workpiece point that may not slide along ``t``."""

    finger: int  # finger index
    body_f: int
    local_f: np.ndarray
    body_w: int
    local_w: np.ndarray
    t_body: int  # body whose frame carries the tangent
    t_local: np.ndarray
    geoms: tuple  # (finger geom, workpiece geom) of the contact pair
    offset: float = 0.0  # over l: keeps g continuous when the anchors move

    def reanchor(self, d, point) -> None:
        """Move both anchors to ``point`` (the current contact), keeping ``g`` unchanged.

        Round geoms roll: friction acts at the current contact point, not at a
        material point; re-anchoring every Newton iteration integrates the
        no-slip condition of the contact point along the path.
        """
        xmat, xpos = d.xmat, d.xpos  # (one view each: every ``d.xmat`` builds a new one)
        t = xmat[self.t_body].reshape(3, 3) @ self.t_local  # (tangent)
        pf = xpos[self.body_f] + xmat[self.body_f].reshape(3, 3) @ self.local_f  # (points)
        pw = xpos[self.body_w] + xmat[self.body_w].reshape(3, 3) @ self.local_w
        g_old = float(t @ (pf - pw))
        self.local_f = xmat[self.body_f].reshape(3, 3).T @ (point - xpos[self.body_f])
        self.local_w = xmat[self.body_w].reshape(3, 3).T @ (point - xpos[self.body_w])
        self.offset += g_old  # new anchors coincide: t . (pf - pw) = 0

    def tangent(self, d) -> np.ndarray:
        return d.xmat[self.t_body].reshape(3, 3) @ self.t_local

    def points(self, d) -> tuple[np.ndarray, np.ndarray]:
        xmat, xpos = d.xmat, d.xpos
        pf = xpos[self.body_f] + xmat[self.body_f].reshape(3, 3) @ self.local_f
        pw = xpos[self.body_w] + xmat[self.body_w].reshape(3, 3) @ self.local_w
        return pf, pw


class Statics:
    """Static residual of the model plus sticking constraints, on a scratch MjData.

    ``data``: the MjData to evaluate on (default: a new one; the chain-coordinate solve
    passes the scene's own, whose state it owns during the settle, rather than allocate another MjData).
    """

    def __init__(self, scene: Scene, data=None):
        self.scene = scene
        self.m = scene.model
        self.d = mujoco.MjData(self.m) if data is None else data
        self.fscale, self.lscale = _shared_dof_scales(scene)
        self.calls = 0

    def forces(self, q) -> np.ndarray:
        """``r(q) = qfrc_applied - qfrc_inverse`` at rest, dimensional."""
        m, d = self.m, self.d
        d.qpos[:] = q
        d.qvel[:] = 0.0
        d.qacc[:] = 0.0
        d.qfrc_applied[:] = self.scene.data.qfrc_applied
        mujoco.mj_inverse(m, d)
        self.calls += 1
        return d.qfrc_applied - d.qfrc_inverse

    def stick_rows(self, sticks) -> tuple[np.ndarray, np.ndarray]:
        """Constraint values ``g`` (over l) and gradients ``G`` (n_stick x nv) at the scratch state."""
        m, d = self.m, self.d
        g = np.zeros(len(sticks))
        G = np.zeros((len(sticks), m.nv))
        jf = np.zeros((3, m.nv))
        jw = np.zeros((3, m.nv))
        for i, s in enumerate(sticks):
            t = s.tangent(d)
            pf, pw = s.points(d)
            g[i] = (float(t @ (pf - pw)) + s.offset) / self.scene.length
            mujoco.mj_jac(m, d, jf, None, pf, s.body_f)
            mujoco.mj_jac(m, d, jw, None, pw, s.body_w)
            G[i] = t @ (jf - jw)
        return g, G


def static_residual(scene: Scene, qpos=None) -> np.ndarray:
    """Dimensionless static generalised-force imbalance at ``qpos`` (default: the scene's).

    ``mj_inverse`` at rest with the scene's ``qfrc_applied`` and contact
    settings; MuJoCo's (velocity-based) friction is zero at rest, so sticking
    friction is not in it.  Hinge rows over ``rho g l^2``, slide rows over ``rho g l``.
    """
    st = Statics(scene)
    q = scene.data.qpos if qpos is None else qpos
    return st.forces(q) / st.fscale


class RestResidual:
    """``max |qfrc_smooth + qfrc_constraint|`` at ``qvel = 0`` (scaled as :func:`static_residual`), on scratch data.

    ``mj_forward``'s balance (the dynamic settles' stop test).  ``dofs``
    restricts the max; ``applied`` is the ``qfrc_applied`` to use (default 0).
    ``data``: evaluate on this MjData (default a new one); it is left at rest.
    """

    def __init__(self, scene: Scene, dofs=None, data=None):
        self.m = scene.model
        self.d = mujoco.MjData(self.m) if data is None else data
        self.scale = dof_scales(scene)[0]
        self.dofs = None if dofs is None else np.asarray(dofs, int)
        self.calls = 0

    def vector(self, qpos, applied=None) -> np.ndarray:
        """The scaled balance per dof."""
        d = self.d
        d.qpos[:] = qpos
        d.qvel[:] = 0.0
        d.qfrc_applied[:] = 0.0 if applied is None else applied
        mujoco.mj_forward(self.m, d)
        self.calls += 1
        return (d.qfrc_smooth + d.qfrc_constraint) / self.scale

    def __call__(self, qpos, applied=None) -> float:
        r = self.vector(qpos, applied)
        return float(np.max(np.abs(r if self.dofs is None else r[self.dofs])))


# ---------------------------------------------------------------------------
# solver options (set for the solve, restored afterwards)


@dataclass
class SavedOptions:
    """A model's solver and contact options as :func:`save_options` found them (``dynamics``: integrator,
    time step [s], cone, impratio, dof damping, pair dims and frictions; ``ls_iterations``: the constraint
    solver's line-search cap, which the dynamics raises)."""

    solref: np.ndarray
    solimp: np.ndarray
    noslip: int
    disableflags: int
    ccd: tuple
    dynamics: tuple = ()
    ls_iterations: int = 50


def save_options(m) -> SavedOptions:
    """The options a settle changes on model ``m``, to put back with :func:`restore_options`."""
    opt = m.opt  # (one view: each ``m.opt`` builds a new one)
    dyn = (int(opt.integrator), float(opt.timestep), int(opt.cone), float(opt.impratio),
           m.dof_damping.copy(), m.pair_dim.copy(), m.pair_friction.copy())
    return SavedOptions(m.pair_solref.copy(), m.pair_solimp.copy(), int(opt.noslip_iterations), int(opt.disableflags),
                  (float(opt.ccd_tolerance), int(opt.ccd_iterations)), dyn, int(opt.ls_iterations))


def restore_options(m, s: SavedOptions) -> None:
    """Put model ``m``'s options back as :func:`save_options` saved them in ``s``."""
    opt = m.opt
    if s.solref.size:  # (a scene without contact pairs has none to put back)
        m.pair_solref[:] = s.solref
        m.pair_solimp[:] = s.solimp
    opt.noslip_iterations = s.noslip
    opt.disableflags = s.disableflags
    opt.ccd_tolerance, opt.ccd_iterations = s.ccd
    opt.ls_iterations = s.ls_iterations
    if s.dynamics:
        opt.integrator, opt.timestep, opt.cone, opt.impratio = s.dynamics[:4]
        m.dof_damping[:] = s.dynamics[4]
        if s.solref.size:
            m.pair_dim[:], m.pair_friction[:] = s.dynamics[5:]


def configure_statics(scene: Scene) -> None:
    """Contact settings of the static solve (see the module docstring)."""
    m = scene.model
    opt = m.opt
    opt.noslip_iterations = 0  # a dynamics post-process, not part of the force balance at rest
    opt.ccd_tolerance = 1e-14  # distances exact to round-off (Newton differentiates them)
    opt.ccd_iterations = 200
    if m.npair == 0:
        return
    # at rest K_c = 1 / (d (1 - d) timeconst^2 A), A ~ 3 / (link mass): pick timeconst for K_c
    imp = CONTACT_IMPEDANCE
    m_eff = scene.physical.rho * scene.length / scene.n / 3.0
    k_c = CONTACT_STIFFNESS * scene.physical.rho * scene.physical.g
    m.pair_solref[:] = [math.sqrt(m_eff / (imp * (1.0 - imp) * k_c)), 1.0]
    m.pair_solimp[:, 0] = imp
    m.pair_solimp[:, 1] = imp
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_REFSAFE)


def check_warnings(d) -> None:
    """Raise :class:`SettleError` when MuJoCo counted a warning in ``d`` (see :mod:`simgrip.sim.checks`)."""
    warn = active_warnings(d)
    if warn:
        raise SettleError(f"settle diverged (MuJoCo warnings {', '.join(warn)})")


def sync_scene(scene: Scene) -> None:
    """Bring the scene's data to its qpos: ``mj_forward``, or positions only without contact pairs.

    A contact-free chain needs only kinematics (``mj_kinematics``, ``mj_comPos``);
    ``mj_forward`` would factor the dense mass matrix of the serial chain, ``O(n^3)``.
    """
    m, d = scene.model, scene.data
    if m.npair == 0 or (int(m.opt.disableflags) & int(mujoco.mjtDisableBit.mjDSBL_CONTACT)):
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
    else:
        mujoco.mj_forward(m, d)


def centreline_point(m, d, geom: int, point) -> np.ndarray:
    """The point of a finger geom's centreline nearest ``point``: a sphere's centre, a capsule's axis."""
    c = np.array(d.geom_xpos[geom])
    if int(m.geom_type[geom]) == int(mujoco.mjtGeom.mjGEOM_CAPSULE):
        axis = np.asarray(d.geom_xmat[geom]).reshape(3, 3)[:, 2]
        half = float(m.geom_size[geom][1])
        c = c + min(max(float(axis @ (np.asarray(point) - c)), -half), half) * axis
    return c


"""The settle of a K-finger gripper (:mod:`simgrip.sim.gripper`): the symmetry skip where exact, else dynamics.

:func:`settle_gripper` by default (``method="auto"``) settles an exactly
symmetric scene (:func:`simgrip.sim.symmetry.symmetry`) by the symmetry skip
(:mod:`simgrip.settle.gripper_symmetry`: one finger's planar Newton settle,
the paper's point contact by default, replicated to K fingers), and any other
scene by the over-damped dynamics of this module, as the planar settle's
default is the fast point-contact Newton and its dynamics the surface
contact.  The state's ``method`` and ``contact`` say which ran.

The dynamics is the planar ``settle(method="dynamics")``'s
(:mod:`simgrip.settle.dynamics`, whose constants it uses): ``mjINT_DISCRETE``,
time step ``h = 1/omega_min`` of the straight hinge chains
(:func:`straight_frequency`, as the planar settle's from its built, straight
scene), hinge damping ``h max(K, R)`` with ``R`` the loads' geometric
stiffness bound (each finger carrying ``M``, its share of the weight ``K M``),
elliptic cone with ``impratio`` :data:`~simgrip.settle.dynamics.DYN_IMPRATIO`,
contact time constant :data:`~simgrip.settle.dynamics.DYN_TIMECONST` ``h``,
MuJoCo's dense constraint Jacobian up to :data:`GRIPPER_DENSE_NV` dofs.
The workpiece's free joint is damped ``3 m / h`` in translation and ``3 I / h``
in rotation (its principal inertia; the rotational dofs are in its body frame).

* **Start** (:mod:`simgrip.settle.gripper_start`): every finger at the hinge chain's grip equilibrium
  (:func:`simgrip.reference.solve_chain`, the tip a hair inside ``X = b/2``),
  the workpiece centred on the palm axis, level with the tips; an off-centre
  or turned workpiece, or unequal fingers, start with each finger at its own
  reach and a share of the weight that balances the workpiece.  Each finger of a box
  (``K`` = 2, 4) or cylinder is then exactly the planar problem; a sphere's
  tips start at ``X = (b/2) cos beta`` (``beta`` the scene's
  ``contact_angle``, the contact normal's elevation), which is the planar
  problem at width ``b cos beta`` (:mod:`simgrip.reference.inclined`), and
  friction keeps them there.  A finger that cannot reach ``X = b/2`` at
  full curvature, or whose loaded equilibrium would pull on the surface
  (``N1 <= 0``), leaves the workpiece unheld; a chain equilibrium that does
  not exist or is unstable raises
  :class:`SettleError` (the planar settle's staged closing is not provided here).
* **Indeterminate forces** (``K >= 4``): statics fixes each finger's ``N1``,
  the tips and the workpiece's pose, but not how the fingers share the
  weight (``N2``) and the out-of-plane forces (``N3``); the settle keeps
  the start's least-norm split (sticking contacts hold what they start
  with).  Per-finger ``N2``/``N3`` are then the start's choice, not physics.
* **Release**: the chains' start shape already carries the weight by
  friction, so the workpiece is let go at once; the dynamics then
  runs until the static residual at rest is below ``tol`` (default
  :func:`gripper_tolerance`, scaled by the weight ``K M``) and the velocities
  below :data:`~simgrip.settle.dynamics.DYN_VTOL` (tested between batches of
  :data:`~simgrip.settle.dynamics.DYN_BATCH` steps).  A tip that slides
  :data:`~simgrip.settle.dynamics.DYN_DROP_SLIP` over the workpiece's surface
  (in the workpiece's frame) or a workpiece that falls
  :data:`~simgrip.settle.dynamics.DYN_DROP_FALL` is dropped: it is parked
  (held, contact off) and the fingers settle alone from the chain's free shape.
* **Drop retry**: a workpiece dropped from a start that touched it is settled
  once more from the start at half the step (as the planar dynamic settle:
  a growing two-step oscillation of the contacts at ``h`` can throw it off);
  it is dropped when it drops at both steps.
* **Penetration**: a settled state penetrating
  :data:`~simgrip.settle.dynamics.DYN_PEN_LIMIT` or more is settled again with
  half the step (at most three times).

The static residual is ``qfrc_smooth + qfrc_constraint`` at ``qvel = 0``
over ``rho g l^2`` (hinges, workpiece rotation) and ``rho g l`` (workpiece
translation): the workpiece's translation rows are its force balance
(contact forces plus weight) and its rotation rows its moment balance.
:class:`GripperState` reports one :class:`FingerRecord` per finger, read in
the finger's own frame like the planar finger.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import mujoco
import numpy as np

from simgrip.chain import link_positions
from simgrip.settle import check_tol_steps
from simgrip.settle.dynamics import (DYN_DAMPING, DYN_DROP_FALL, DYN_DROP_SLIP, DYN_IMPRATIO,
                                     DYN_PEN_LIMIT, DYN_STEP, DYN_TIMECONST, DYN_TOL, DYN_TOL_PER_WEIGHT, DYN_VTOL,
                                     DYN_WORKPIECE_DAMPING, geometric_stiffness_bound, lowest_frequency,
                                     run_to_rest)
from simgrip.settle.gripper_start import finger_chain, is_symmetric, start_qpos
from simgrip.settle.state import SettleError
from simgrip.settle.statics import CONTACT_IMPEDANCE, check_warnings, restore_options, save_options
from simgrip.sim.checks import clear_warnings
from simgrip.sim.gripper import GripperScene
from simgrip.validity import check_grip_shape

__all__ = ["FingerRecord", "GripperState", "contact_rest_depth", "gripper_tolerance", "settle_gripper",
           "straight_frequency"]

#: Default physics-step budget of one settle.
GRIPPER_MAX_STEPS = 20_000
#: Largest number of dofs for which the dynamics uses MuJoCo's dense constraint Jacobian (sparse above).
#: A gripper has few contact rows (one per finger), and the dense path's step is 10-25 % cheaper up to
#: ``nv`` ~ 200 and dearer from ~260 on (measured, II, K = 2 and 4, n = 16 to 96); MuJoCo's own default
#: switches at 60.  The settled state is the same to round-off either way.
GRIPPER_DENSE_NV = 200


@dataclass
class FingerRecord:
    """The workpiece's contact on one finger, in the finger's frame (over ``l`` and ``rho g l``).

    ``N1`` (along ``E1``, away from the palm axis), ``N2`` (up) and ``N3``
    (out of the finger's plane) are the force on the rod.  ``normal`` is its
    component along the contact normal (pointing from the workpiece into the
    tip, so ``> 0`` pushes), ``friction`` its component along the in-plane
    tangent ``t = n x E3`` (for a vertical face ``t = E2``: ``friction =
    N2``); ``contact_angle`` is the normal's elevation ``atan2(n_2, n_1)``
    (0 on a vertical face).  ``tip`` is the rod's end ``(X, Y)`` from the
    hinge angles, ``point`` MuJoCo's contact point ``(X, Y, out of plane)``;
    ``moment`` the couple (about ``E3``, over ``rho g l^2``) the force exerts
    about the tip because it acts on the tip sphere's surface (pass it as
    ``contact_moment`` to the references); ``required_mu`` is ``|tangential|
    / normal``; ``finger`` the finger's index.
    """

    finger: int
    N1: float
    N2: float
    N3: float
    normal: float
    friction: float
    contact_angle: float
    tip: np.ndarray
    point: np.ndarray
    moment: float
    penetration: float
    required_mu: float


@dataclass
class GripperState:
    """A settled K-finger gripper, dimensionless (lengths over ``l``, forces over ``rho g l``).

    ``records`` holds one :class:`FingerRecord` per finger touching the
    workpiece (empty when it was dropped); ``force_balance`` is the workpiece's net force
    (contacts plus weight, world frame, over ``rho g l``) and
    ``moment_balance`` its net moment about its centre (over ``rho g l^2``),
    both zero at equilibrium; ``workpiece_position`` its centre over ``l``
    and ``workpiece_quat`` its orientation.  A held state with a tip on the
    other grip's side of the palm is reported not held, as the planar settle
    does (:func:`simgrip.validity.check_grip_shape`: ``grip_matched``, ``warnings``).
    """

    grip: str
    workpiece: str
    fingers: int
    links: int
    joint_angles: np.ndarray
    link_angles: np.ndarray
    tip: np.ndarray
    records: list
    held: bool
    converged: bool
    residual: float
    tolerance: float
    velocity: float
    penetration: float
    force_balance: np.ndarray
    moment_balance: np.ndarray
    workpiece_position: np.ndarray
    workpiece_quat: np.ndarray
    steps: int
    timestep: float
    wall_time_s: float
    qpos: np.ndarray = field(repr=False)
    #: Every finger's tip on its grip's side of the palm (:func:`simgrip.validity.check_grip_shape`).
    grip_matched: bool = True
    #: Conditions the state violates that the settle does not enforce (e.g. the other grip's shape).
    warnings: list = field(default_factory=list)
    #: The scene's workpiece offset (over l, scene frame) and turn about its axis [rad] (:func:`build_gripper`).
    offset: np.ndarray = field(default_factory=lambda: np.zeros(2))
    workpiece_yaw: float = 0.0
    #: How it was settled: ``"dynamics"`` or ``"symmetric"`` (:mod:`simgrip.settle.gripper_symmetry`).
    method: str = "dynamics"
    #: Where the sticking friction acts: ``"surface"`` (MuJoCo's contact point on the tip sphere; the
    #: dynamics) or ``"point"`` (the finger's centreline, the paper's point contact; the skip's default).
    contact: str = "surface"


# ---------------------------------------------------------------------------
# the dynamics


class _Dyn:
    """Over-damped MuJoCo dynamics of a gripper scene (options set here, restored by the caller)."""

    def __init__(self, scene: GripperScene, step_factor: float):
        m, d = scene.model, scene.data
        self.scene, self.m, self.d = scene, m, d
        self.steps = 0
        wdof = scene.workpiece_dof
        self.fscale = np.full(m.nv, scene.moment_scale)
        self.fscale[wdof[:3]] = scene.force_scale
        self.vscale = np.ones(m.nv)
        self.vscale[wdof[:3]] = scene.length
        self.vscale /= math.sqrt(scene.length / scene.physical.g)
        k = m.jnt_stiffness[m.dof_jntid].copy()
        self.scratch = mujoco.MjData(m)
        self.h = h = step_factor * DYN_STEP / straight_frequency(scene, self.scratch, k)
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_DISCRETE
        m.opt.timestep = h
        m.opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
        m.opt.impratio = DYN_IMPRATIO
        m.opt.noslip_iterations = 0
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_REFSAFE)
        m.dof_damping[:] = DYN_DAMPING * h * k
        wb = scene.workpiece_body
        m.dof_damping[wdof[:3]] = DYN_WORKPIECE_DAMPING * float(m.body_mass[wb]) / h
        m.dof_damping[wdof[3:]] = DYN_WORKPIECE_DAMPING * np.asarray(m.body_inertia[wb]) / h
        m.pair_solref[:] = [DYN_TIMECONST * h, 1.0]
        m.pair_solimp[:, 0] = CONTACT_IMPEDANCE
        m.pair_solimp[:, 1] = CONTACT_IMPEDANCE
        self.held_q: np.ndarray | None = None
        self.k = np.where(k > 0, k, 0.0)
        self.hinge = scene.joint_dof.ravel()
        self.update_damping()

    def update_damping(self) -> None:
        """Hinge damping ``h max(K, R)``, ``R`` the loads' geometric stiffness bound at the current state.

        As the planar dynamics' (:func:`simgrip.settle.dynamics.geometric_stiffness_bound`: MuJoCo's step
        is explicit in gravity and the contact loads, which a soft finger's springs do not dominate; ``R``
        keeps every step a contraction).  While the workpiece hangs on the fingers (not held, contact
        on), each finger carries its per-finger share of the weight, ``M`` (``K M`` over ``K``), as the
        planar problem's finger does.
        """
        m, sc = self.m, self.scene
        hanging = self.held_q is None and not int(m.opt.disableflags) & int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        load = sc.workpiece_mass * sc.physical.g / sc.fingers if hanging else 0.0
        R = geometric_stiffness_bound(sc, self.d, load)
        m.dof_damping[self.hinge] = DYN_DAMPING * self.h * np.maximum(self.k[self.hinge], R[self.hinge])

    def residual_vector(self) -> np.ndarray:
        """Static balance at rest per dof, scaled (``qfrc_smooth + qfrc_constraint`` at ``qvel = 0``)."""
        s = self.scratch
        s.qpos[:] = self.d.qpos
        s.qvel[:] = 0.0
        s.qfrc_applied[:] = self.d.qfrc_applied
        mujoco.mj_forward(self.m, s)
        r = (s.qfrc_smooth + s.qfrc_constraint) / self.fscale
        if self.held_q is not None:
            r[self.scene.workpiece_dof] = 0.0
        return r

    def residual(self) -> float:
        """Largest scaled static residual (:meth:`residual_vector`)."""
        return float(np.max(np.abs(self.residual_vector())))

    def velocity(self) -> float:
        v = np.abs(np.array(self.d.qvel)) / self.vscale
        if self.held_q is not None:
            v[self.scene.workpiece_dof] = 0.0
        return float(np.max(v))

    def hold(self, on: bool) -> None:
        """Hold the workpiece where it is (pose reset after each step, weight cancelled) or let go."""
        sc, d = self.scene, self.d
        d.qfrc_applied[:] = 0.0
        if on:
            d.qfrc_applied[sc.workpiece_dof[2]] = sc.workpiece_mass * sc.physical.g
        self.held_q = np.array(d.qpos[sc.workpiece_qpos]) if on else None

    def step(self, k: int = 1) -> None:
        sc, d = self.scene, self.d
        self.update_damping()  # the loads' geometric stiffness at the current state
        mujoco.mj_step(self.m, d, k)
        self.steps += k
        if self.held_q is not None:
            d.qpos[sc.workpiece_qpos] = self.held_q
            d.qvel[sc.workpiece_dof] = 0.0
        if not (np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel))):
            raise SettleError("gripper settle diverged (non-finite state)")
        check_warnings(d)

    def run(self, tol: float, budget: int, watch=None) -> tuple[bool, str]:
        """Step until the residual is below ``tol`` and the velocity below DYN_VTOL; ``watch()`` may stop it."""
        return run_to_rest(self, tol, DYN_VTOL, budget, watch, "gripper settle")


def straight_frequency(scene: GripperScene, scratch, k: np.ndarray) -> float:
    """Lowest natural frequency [rad/s] of the hinge chains, straight (every hinge angle 0), with their inertia.

    The configuration is fixed, not the start's: a curled start has less inertia about the base and a higher
    ``omega_min``, hence a shorter step ``h = 1/omega_min`` and more steps to the same rest (Grip II's loaded
    start: ``h`` 0.77 times the straight chain's).  The planar dynamic settle takes ``omega_min`` at the built
    scene, straight for Grips I/II, so the K-finger and the planar settle of the same per-finger problem
    step alike.  ``scratch`` (an ``MjData`` of the scene's model) is overwritten; ``k`` the dofs' stiffness.
    """
    m = scene.model
    scratch.qpos[:] = m.qpos0
    scratch.qpos[scene.joint_qpos.ravel()] = 0.0
    mujoco.mj_kinematics(m, scratch)
    mujoco.mj_comPos(m, scratch)
    mujoco.mj_crb(m, scratch)
    return lowest_frequency(m, scratch, k, scene.joint_dof.ravel())


def contact_rest_depth(scene: GripperScene, N1, timestep: float) -> np.ndarray:
    """How deep (over l) MuJoCo's soft contact rests under normal forces ``N1`` (over rho g l) in the dynamics.

    MuJoCo's contact is a constraint with reference acceleration ``-k r`` (``k = 1/(d tc)^2``, ``tc =
    DYN_TIMECONST h``, impedance ``d`` -> 1) acting through the inverse of the step's metric
    ``M + h D + h^2 K`` (``mjINT_DISCRETE``): at rest a normal force ``N`` sinks the contact by
    ``r = N tc^2 A_nn``, ``A_nn = n J (M + h D + h^2 K)^{-1} J^T n`` the contact's mobility along its
    normal (MuJoCo's ``efc_diagA``), the tip's and the workpiece's.  Evaluated at the scene's current
    state (its contacts' normals; a finger out of contact: its ``E1``) with the damping the dynamics
    sets there (:class:`_Dyn`: hinges ``h max(K, R)`` with each finger carrying ``M``, the workpiece
    ``3 m / h`` and ``3 I / h``), at the step ``timestep`` [s].  Returns one depth per finger.
    """
    m = scene.model
    h = float(timestep)
    s = mujoco.MjData(m)
    s.qpos[:] = scene.data.qpos
    mujoco.mj_forward(m, s)
    k = m.jnt_stiffness[m.dof_jntid].copy()
    hinge = scene.joint_dof.ravel()
    R = geometric_stiffness_bound(scene, s, scene.workpiece_mass * scene.physical.g / scene.fingers)
    damp = np.zeros(m.nv)
    damp[hinge] = DYN_DAMPING * h * np.maximum(k[hinge], R[hinge])
    wb, wdof = scene.workpiece_body, scene.workpiece_dof
    damp[wdof[:3]] = DYN_WORKPIECE_DAMPING * float(m.body_mass[wb]) / h
    damp[wdof[3:]] = DYN_WORKPIECE_DAMPING * np.asarray(m.body_inertia[wb]) / h
    metric = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, s, metric)
    metric += np.diag(h * damp + h * h * np.where(k > 0, k, 0.0))
    tc = DYN_TIMECONST * h
    depth = np.zeros(scene.fingers)
    jt, jw = np.zeros((3, m.nv)), np.zeros((3, m.nv))
    for f in range(scene.fingers):
        g = int(scene.tip_geom[f])
        cons = [i for i in range(s.ncon)
                if int(s.contact.geom1[i]) == g and int(s.contact.geom2[i]) == scene.workpiece_geom]
        if cons:
            i = cons[0]
            p, n = np.array(s.contact.pos[i]), np.array(s.contact.frame[i][:3])
        else:
            p, n = np.array(s.geom_xpos[g]), scene.frame(f)[0]
        mujoco.mj_jac(m, s, jt, None, p, int(m.geom_bodyid[g]))
        mujoco.mj_jac(m, s, jw, None, p, wb)
        j = n @ (jw - jt)
        depth[f] = float(j @ np.linalg.solve(metric, j))
    return np.asarray(N1, dtype=float) * scene.force_scale * tc * tc * depth / scene.length


def _tips_on_workpiece(scene: GripperScene) -> np.ndarray:
    """Every tip's centre in the workpiece's body frame [m], (K, 3)."""
    d = scene.data
    wb = scene.workpiece_body
    rot = np.asarray(d.xmat[wb]).reshape(3, 3)
    return (np.asarray(d.geom_xpos[scene.tip_geom]) - np.asarray(d.xpos[wb])) @ rot


def _touching(scene: GripperScene) -> bool:
    d = scene.data
    tips = set(int(g) for g in scene.tip_geom)
    return any(int(d.contact.geom1[i]) in tips and int(d.contact.geom2[i]) == scene.workpiece_geom
               for i in range(d.ncon))


def gripper_tolerance(scene: GripperScene) -> float:
    """Default static residual tolerance: ``max(DYN_TOL, DYN_TOL_PER_WEIGHT * K * M)``.

    As the planar dynamic settle's (:func:`simgrip.settle.dynamics.dynamics_tolerance`): MuJoCo's
    sticking friction creeps and leaves a fixed fraction of the force it carries unbalanced at
    rest; here the friction carries the whole workpiece, ``K M`` (over rho g l).
    """
    return max(DYN_TOL, DYN_TOL_PER_WEIGHT * scene.fingers * float(scene.params.M))


def settle_gripper(scene: GripperScene, *, tol: float | None = None, max_steps: int | None = None,
                   allow_unconverged: bool = False, method: str | None = None,
                   contact: str | None = None) -> GripperState:
    """Settle a K-finger gripper: the symmetry skip where the scene is exactly symmetric, else the dynamics.

    The default (``method=None``, ``"auto"``) is as the planar settle's: the
    fast static solve of the paper's point-contact problem where it is exact
    (one finger's planar Newton settle replicated to K,
    :mod:`simgrip.settle.gripper_symmetry`), the over-damped dynamics with
    MuJoCo's surface contact (see the module docstring) where it is not.  The
    state's ``method`` says which ran.

    Parameters
    ----------
    scene : GripperScene
    tol : float, optional
        Static residual tolerance (over ``rho g l^2`` / ``rho g l``); default
        :func:`gripper_tolerance` for the dynamics (MuJoCo's sticking friction
        creeps below it), the planar Newton's for the skip.
    max_steps : int, optional
        Dynamics: physics steps allowed to the whole settle (restarts
        included; default :data:`GRIPPER_MAX_STEPS`).  Skip: the planar
        Newton's iteration budget (default its own).
    allow_unconverged : bool
        Return ``converged=False`` instead of raising :class:`SettleError`.
    method : {None, "auto", "symmetric", "dynamics"}
        None is ``"auto"``: ``"symmetric"`` where the scene is exactly
        symmetric (:func:`simgrip.sim.symmetry.symmetry`), else
        ``"dynamics"``.  ``"symmetric"``: one finger's planar static settle
        replicated to K (ValueError naming ``method`` where the scene is not
        exactly symmetric); ``"dynamics"``: the over-damped dynamics of all K
        fingers and the workpiece (Grips I/II only: the K = 4 cradle, Grip
        III, is settled by the skip).
    contact : {None, "point", "surface"}
        Where the sticking friction acts.  The skip: ``"point"`` (default, the
        paper's point contact, on the centreline) or ``"surface"`` (box and
        cylinder: at MuJoCo's contact point, the tip sphere's couple, as the
        dynamics).  The dynamics has MuJoCo's surface contact only:
        ``"point"`` raises ValueError naming ``contact`` where it runs.

    Returns
    -------
    GripperState
    """
    if not isinstance(scene, GripperScene):
        raise ValueError(f"scene must be a simgrip.sim.gripper.GripperScene, got {type(scene).__name__}")
    from simgrip.settle.gripper_symmetry import symmetric_or_none

    state = symmetric_or_none(scene, method, contact=contact, tol=tol, max_steps=max_steps,
                              allow_unconverged=allow_unconverged)
    if state is not None:
        return state
    if tol is None:
        tol = gripper_tolerance(scene)
    if max_steps is None:
        max_steps = GRIPPER_MAX_STEPS
    tol, max_steps = check_tol_steps(tol, max_steps)
    t0 = time.perf_counter()
    m, d = scene.model, scene.data
    saved, jacobian = save_options(m), int(m.opt.jacobian)
    dense = m.nv <= GRIPPER_DENSE_NV
    m.opt.jacobian = int(mujoco.mjtJacobian.mjJAC_DENSE if dense else mujoco.mjtJacobian.mjJAC_SPARSE)
    clear_warnings(d)
    q_start = start_qpos(scene)
    reach = q_start is not None
    if not reach:
        q_start = np.array(d.qpos)
    steps, factor = 0, 1.0
    retried_drop = False
    try:
        for attempt in range(5):
            restore_options(m, saved)  # a dropped attempt left contact off
            d.qpos[:] = q_start
            d.qvel[:] = 0.0
            d.qfrc_applied[:] = 0.0
            mujoco.mj_forward(m, d)
            dyn = _Dyn(scene, factor)
            if reach and not is_symmetric(scene) and scene.workpiece != "sphere":
                seated = start_qpos(scene, timestep=dyn.h)  # every tip at MuJoCo's rest depth (gripper_start)
                if seated is not None:
                    d.qpos[:] = seated
                    mujoco.mj_forward(m, d)
            held, converged, why = _settle_once(scene, dyn, tol, int(max_steps) - steps, reach)
            steps += dyn.steps
            state = _read(scene, dyn, held, converged, steps, t0, tol)
            check_grip_shape(scene, state)
            if reach and not held and not retried_drop and state.converged and steps < max_steps:
                # dropped from a start that touched: once more at half the step, as the planar dynamic settle
                # does (a growing two-step oscillation of the contacts at h can throw the workpiece off)
                retried_drop = True
                factor *= 0.5
                continue
            if (state.penetration < DYN_PEN_LIMIT or attempt >= 3 or steps >= max_steps
                    or not state.converged):
                break
            factor *= 0.5
        if not state.converged and not allow_unconverged:
            raise SettleError(f"gripper settle did not converge ({why} after {steps} steps, residual "
                              f"{state.residual:.3g}, tolerance {tol:.3g})")
    finally:
        restore_options(m, saved)
        m.opt.jacobian = jacobian
        d.qfrc_applied[:] = 0.0
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
    return state


def _settle_once(scene: GripperScene, dyn: _Dyn, tol: float, budget: int, reach: bool) -> tuple[bool, bool, str]:
    """Release the held workpiece and settle; ``(held, converged, reason)``.

    ``reach``: the fingers start on the workpiece (else they settle alone).
    """
    m, d = scene.model, scene.data
    converged, why = True, "ok"
    held = reach and _touching(scene)
    if held:
        wb = scene.workpiece_body
        z0 = float(d.xpos[wb][2])
        # loaded start: the chains' shape already carries the weight by friction, so the workpiece is
        # let go at once (fading a holding force out on top would push it up off the tips; the planar
        # dynamic settle found the same)
        dyn.hold(False)
        on = _tips_on_workpiece(scene)

        def watch():
            fall = (z0 - float(d.xpos[wb][2])) / scene.length
            if fall > DYN_DROP_FALL or (fall > DYN_DROP_SLIP and not _touching(scene)):
                return "lost contact"
            slip = np.max(np.linalg.norm(_tips_on_workpiece(scene) - on, axis=1)) / scene.length
            return "slipped" if slip > DYN_DROP_SLIP else None

        converged, why = dyn.run(tol, budget, watch)
        if why in ("lost contact", "slipped"):
            held, converged = False, True
    if not held and converged:
        # park the workpiece (held, contact off) and settle the fingers alone from the chain's free shape
        dyn.hold(True)
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        for k in range(scene.fingers):
            free = finger_chain(scene, "free", finger=k)
            if free is not None:
                d.qpos[scene.joint_qpos[k]] = free.joint_angles
        d.qvel[:] = 0.0
        converged, why = dyn.run(tol, budget)
    return held, converged, why


def _read(scene: GripperScene, dyn: _Dyn, held: bool, converged: bool, steps: int, t0: float,
          tol: float) -> GripperState:
    """The settled state at rest (``qvel = 0``) from MuJoCo's contact forces."""
    m, d = scene.model, scene.data
    L, W = scene.length, scene.force_scale
    r = dyn.residual_vector()
    residual = float(np.max(np.abs(r)))
    velocity = dyn.velocity()
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    q = np.array(d.qpos[scene.joint_qpos])
    phi = np.cumsum(q, axis=1)
    tips = np.stack([link_positions(p, 1.0 / scene.n)[-1] for p in phi])
    wb = scene.workpiece_body
    centre = np.array(d.xpos[wb])
    records, pen_max = [], 0.0
    total_f = np.zeros(3)
    total_m = np.zeros(3)
    for k in range(scene.fingers if held else 0):
        cons = [i for i in range(d.ncon)
                if int(d.contact.geom1[i]) == scene.tip_geom[k] and int(d.contact.geom2[i]) == scene.workpiece_geom]
        if not cons:
            continue
        F, Fn, point, nvec, pen, wsum = np.zeros(3), 0.0, np.zeros(3), np.zeros(3), 0.0, 0.0
        for i in cons:
            fc = np.zeros(6)
            mujoco.mj_contactForce(m, d, i, fc)
            frame = np.asarray(d.contact.frame[i]).reshape(3, 3)
            fw = -(frame.T @ fc[:3])  # on the tip (geom1); the frame's normal points from geom1 to geom2
            pos = np.asarray(d.contact.pos[i])
            F += fw
            Fn += fc[0]
            w = max(float(np.linalg.norm(fw)), 1e-300)
            point += w * pos
            nvec += w * (-frame[0])  # from the workpiece into the tip
            wsum += w
            pen = max(pen, -float(d.contact.dist[i]) / L)
            total_f -= fw
            total_m += np.cross(pos - centre, -fw)
        point /= wsum
        R = scene.frame(k)
        Fk = R @ F / W
        nk = R @ (nvec / np.linalg.norm(nvec))
        # in-plane unit normal (E1, E2) and tangent t = n x E3 = (-n2, n1)
        n2d = np.array([nk[0], nk[2]]) / math.hypot(nk[0], nk[2])
        t2d = np.array([-n2d[1], n2d[0]])
        F2d = np.array([Fk[0], Fk[2]])
        normal, friction = float(F2d @ n2d), float(F2d @ t2d)
        pk = R @ point / L
        arm = np.array([pk[0], pk[2]]) - tips[k]
        tangential = math.sqrt(max(float(Fk @ Fk) - normal**2, 0.0))
        records.append(FingerRecord(
            finger=k, N1=float(Fk[0]), N2=float(Fk[2]), N3=float(Fk[1]), normal=normal, friction=friction,
            contact_angle=float(math.atan2(n2d[1], n2d[0])), tip=tips[k].copy(),
            point=np.array([pk[0], pk[2], pk[1]]), moment=float(arm[0] * F2d[1] - arm[1] * F2d[0]),
            penetration=pen, required_mu=tangential / normal if normal > 0 else math.inf))
        pen_max = max(pen_max, pen)
    weight = scene.workpiece_mass * scene.physical.g
    total_f[2] -= weight
    return GripperState(
        grip=scene.grip, workpiece=scene.workpiece, fingers=scene.fingers, links=scene.n, joint_angles=q,
        link_angles=phi, tip=tips, records=records, held=held, converged=bool(converged and residual <= tol),
        residual=residual, tolerance=tol, velocity=velocity, penetration=pen_max,
        force_balance=total_f / W if held else np.zeros(3),
        moment_balance=total_m / (W * L) if held else np.zeros(3),
        workpiece_position=centre / L, workpiece_quat=np.array(d.xquat[wb]), steps=steps, timestep=dyn.h,
        wall_time_s=time.perf_counter() - t0, qpos=np.array(d.qpos), offset=np.array(scene.offset),
        workpiece_yaw=float(scene.workpiece_yaw))

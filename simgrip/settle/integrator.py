"""The over-damped MuJoCo integrator of the dynamic settle (:class:`Dyn`, :func:`run_to_rest`).

:class:`Dyn` configures a scene's model for an over-damped flow to rest,
everything chosen from the model:

* **Integrator** ``mjINT_DISCRETE``: the constraint solve and the implicit
  velocity update share the metric ``M + h D + h^2 K``, so hinge stiffness is
  implicit and contacts with a time constant far below the step
  (:data:`DYN_TIMECONST` ``h``, refsafe off) stay stable.
* **Damping and step**: hinge damping ``D = h max(K, R)`` (stiffness-proportional: the
  over-damped flow is preconditioned by the spring matrix, so the number of
  steps does not grow with ``n``); ``h = 1 / omega_min`` of the hinge chain with
  its physical inertia (power iteration on ``K^{-1} M``: ``K`` is diagonal in
  hinge coordinates, one ``mj_mulM`` per iteration).  MuJoCo integrates the
  springs and the damping implicitly but gravity and the contact forces
  explicitly: their geometric stiffness ``H`` (:func:`geometric_stiffness_bound`)
  is stable in the over-damped step only while ``|H| <~ K``, which a soft finger
  (``D`` small: gravity and the workpiece's weight far above the springs) breaks
  by orders of magnitude; ``R``, the Gershgorin row sums of ``H``, keeps every
  step a contraction (updated from the configuration before every ``mj_step``
  call: gravity, and the workpiece's weight while it hangs on the finger).
  The workpiece has no stiffness: damping ``3 m / h``
  (Grip III raises it, and the finger's with it, so a falling workpiece moves
  at most :data:`DYN_FALL_STEP` contact radii per step).  This fall guard is a
  factor ``1 <= s <= slow`` on all the damping: over-damped, the flow only runs
  ``s`` times slower along the same path, and the step the plain flow would take,
  ``s v h`` (``v`` the velocity under the guard), tells how much of it is
  needed: ``s`` is set at each stop test so that this step stays below
  :data:`DYN_FALL_STEP` contact radii (one step per test while ``s < slow``);
  near rest ``s = 1`` and the plain over-damped flow converges in a fixed
  number of steps.
* **Contacts**: elliptic cone, ``impratio =`` :data:`DYN_IMPRATIO` (MuJoCo's
  sticking friction creeps at a speed ~ 1/impratio and leaves ~1e-5 of the
  weight unbalanced, hence :data:`simgrip.settle.dynamics.DYN_TOL`); the
  constraint solve's line search runs to its own tolerance
  (:data:`DYN_LS_ITERATIONS`): cut at MuJoCo's default it returned
  unconverged friction that kicked a light workpiece off the tip.

:func:`run_to_rest` steps such an integrator until the velocity and the
static residual are below their tolerances, :data:`DYN_BATCH` steps per
``mj_step`` call between tests.  The K-finger settle
(:mod:`simgrip.gripper.dynamics`) uses the same constants, bound
and stop loop.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from simgrip.settle.closing import hold_workpiece
from simgrip.settle.state import SettleError
from simgrip.settle.statics import CONTACT_IMPEDANCE, RestResidual, check_warnings, dof_scales
from simgrip.sim.scene import Scene

__all__ = ["DYN_BATCH", "DYN_DAMPING", "DYN_FALL_STEP", "DYN_IMPRATIO", "DYN_LS_ITERATIONS", "DYN_STEP",
           "DYN_TIMECONST", "DYN_WORKPIECE_DAMPING", "Dyn", "geometric_stiffness_bound", "lowest_frequency",
           "run_to_rest"]

#: Time step over ``1 / omega_min`` (lowest hinge mode with the physical inertia).
DYN_STEP = 1.0
#: Hinge damping time over the time step: ``D = DYN_DAMPING h K`` (over-damped, n-independent).
DYN_DAMPING = 1.0
#: Workpiece damping: ``D_w = DYN_WORKPIECE_DAMPING m_w / h`` (over-damped, no stiffness to scale by).
DYN_WORKPIECE_DAMPING = 3.0
#: Grip III: largest step of the workpiece (and of the finger, per unit length) per physics step, over
#: the contact radii ``r_link + r_corner``: a corner that moves less than that between two steps is seen in
#: contact before its centre crosses the rod's axis (the depth at which the run counts it tunnelled).
DYN_FALL_STEP = 1.0
#: Contact time constant over the time step (refsafe off: mjINT_DISCRETE solves contacts implicitly).
DYN_TIMECONST = 1e-2
#: Friction-to-normal impedance ratio: MuJoCo's sticking friction creeps at a speed ~ 1/impratio.
DYN_IMPRATIO = 1e4
#: Physics steps per ``mj_step`` call between two stop tests (velocity, drop watch) once nothing is held.
DYN_BATCH = 16
#: Cap on the line-search evaluations of one Newton iteration of MuJoCo's constraint solve (MuJoCo's default
#: is 50).  The elliptic friction cone with ``impratio =`` :data:`DYN_IMPRATIO` makes the line search's cost
#: piecewise with very unequal pieces; on a light workpiece (M = 1e-3, D = 1e-2, Grip I) one solve needs 59
#: evaluations (measured), and a line search cut at 50 returns an unconverged force (friction at the cone's
#: edge, the normal force 40 % off) that kicks the flow: the kicks grow chaotically and threw the workpiece
#: off (a verdict that flipped with 1e-16 of the start).  The line search stops at its own tolerance, so the
#: cap costs nothing where it is not reached (tests/test_dynamics_solver.py checks the solves converge).
DYN_LS_ITERATIONS = 1000


def lowest_frequency(m, d, k, sprung, iters: int = 50, rtol: float = 1e-12) -> float:
    """Lowest natural frequency [rad/s] of the sprung dofs: ``K v = omega^2 M v`` by power iteration.

    In hinge coordinates the stiffness ``K`` is diagonal, so ``K^{-1} M v`` costs one
    ``mj_mulM`` (``O(n^2)`` on a serial chain, no dense eigen-solve); its largest
    eigenvalue is ``1/omega_min^2``.  The Rayleigh quotient converges with the square of
    the ratio of the two lowest modes (a cantilever's ``omega_2/omega_1 ~ 6``): a few
    iterations.  The mass matrix in ``d`` must be current (``mj_crb``).
    """
    ks = k[sprung]
    v = 1.0 / ks  # start: the deflection under unit hinge moments
    full, out = np.zeros(m.nv), np.zeros(m.nv)
    lam_old = 0.0
    for _ in range(iters):
        full[:] = 0.0
        full[sprung] = v
        mujoco.mj_mulM(m, d, out, full)
        mv = out[sprung]
        lam = float(v @ mv) / float(v @ (ks * v))  # Rayleigh quotient 1/omega^2
        w = mv / ks
        v = w / np.linalg.norm(w)
        if abs(lam - lam_old) <= rtol * lam:
            break
        lam_old = lam
    return math.sqrt(1.0 / lam)


def geometric_stiffness_bound(scene: Scene, d, load: float = 0.0) -> np.ndarray:
    """Gershgorin row sums ``R`` [N m/rad] of the loads' geometric stiffness at the finger hinges (0 elsewhere).

    A force ``F`` held fixed at a point ``p`` beyond two hinges ``a <= b`` of a
    planar serial chain adds ``d^2 V / dq_a dq_b = F . (p - o_b)`` to the Hessian
    (``o_b`` the later hinge's anchor: ``d^2 p / dq_a dq_b = -(p - o_b)`` in the
    plane), so the Hessian of the loads is ``H_ab = g_max(a,b)`` with ``g_c`` the
    sum over the loads beyond hinge ``c``: for gravity ``m_c g . (com_c - o_c)``
    (``m_c``, ``com_c`` the subtree's mass and centre of mass); for the
    workpiece's weight ``load`` [N] hanging on a finger through its contacts at
    ``p_i``, at most ``load max_i |p_i - o_c|`` (however the contacts share it: a
    bound that does not jump when a second contact appears).  A row of
    ``|H|`` sums to ``R_a = a |g_a| + sum_{b > a} |g_b|`` (``a`` counted from 1
    at the base).

    MuJoCo's step is implicit in the springs ``K`` and the damping ``D`` but
    explicit in these loads.  In the over-damped limit a step maps the error
    ``e -> (I - B^{-1}(K + H)) e`` with ``B = K + D/h``; with ``D = h max(K, R)``,
    ``B >= K + R`` row by row, so every eigenvalue of ``B^{-1}(K + H)`` lies in
    ``(0, 1]`` for a stable equilibrium (Gershgorin): each step contracts.  The
    springs' own contact force (a finger squeezing the workpiece) scales with
    ``K`` and is left out: the bound is smooth in the configuration (no
    measured contact force, which chatters), and it matters where gravity and the
    workpiece's weight dominate the springs (``D`` small).
    ``d`` must be current (kinematics, ``subtree_com``, contacts).
    """
    m = scene.model
    R = np.zeros(m.nv)
    gvec = np.asarray(m.opt.gravity, dtype=float)
    idx = scene.index
    # the contacts on each finger: (link index, point)
    on = [[] for _ in range(scene.fingers)]
    if load > 0.0:
        for i in range(d.ncon):
            c = d.contact[i]
            for g in (int(c.geom[0]), int(c.geom[1])):
                f = int(idx.finger_of_geom[g]) if g < len(idx.finger_of_geom) else -1
                k = np.flatnonzero(idx.link_body[f] == m.geom_bodyid[g]) if f >= 0 else ()
                if len(k):
                    on[f].append((int(k[0]), np.array(c.pos)))
    for f in range(scene.fingers):
        bodies = idx.link_body[f]
        dofs = idx.joint_dof[f]
        o = d.xanchor[m.dof_jntid[dofs]]
        g = np.abs(m.body_subtreemass[bodies] * ((d.subtree_com[bodies] - o) @ gvec))
        arm = np.zeros(len(bodies))  # the weight's largest lever over the finger's contacts beyond each hinge
        for k, p in on[f]:
            arm[:k + 1] = np.maximum(arm[:k + 1], np.linalg.norm(p[None, :] - o[:k + 1], axis=1))
        g += load * arm
        after = np.concatenate([np.cumsum(g[::-1])[::-1][1:], [0.0]])
        R[dofs] = (np.arange(len(g)) + 1.0) * g + after
    return R


class Dyn:
    """Over-damped MuJoCo dynamics (``mjINT_DISCRETE``) configured from the model's scales."""

    def __init__(self, scene: Scene, step_factor: float = 1.0):
        self.scene = scene
        m, d = scene.model, scene.data
        self.m, self.d = m, d
        self.fscale, self.lscale = dof_scales(scene)
        self.vscale = self.lscale / math.sqrt(scene.length / scene.physical.g)
        self.rest_residual = RestResidual(scene, data=d)  # on the scene's data, velocities restored
        self.steps = 0
        self.calls = 0
        k = m.jnt_stiffness[m.dof_jntid].copy()
        sprung = np.flatnonzero(k > 0)
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        mujoco.mj_crb(m, d)  # the mass matrix qM, O(n^2) (no factorisation)
        self.omega_min = lowest_frequency(m, d, k, sprung)
        h = step_factor * DYN_STEP / self.omega_min
        self.h = h
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_DISCRETE
        m.opt.timestep = h
        m.opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
        m.opt.impratio = DYN_IMPRATIO
        m.opt.noslip_iterations = 0  # no effect on pair contacts with mjINT_DISCRETE (measured)
        m.opt.ls_iterations = max(int(m.opt.ls_iterations), DYN_LS_ITERATIONS)
        m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_REFSAFE)
        self.k = np.where(k > 0, k, 0.0)
        wd = np.asarray(scene.workpiece_dof, dtype=int)
        #: damping factor of the Grip III fall guard (1: none); :meth:`run` lifts it near rest (:meth:`_guard`)
        self.slow = 1.0
        #: the workpiece's own damping without the guard, and the dofs the guard scales (its translations)
        self.wp_damping = np.zeros(m.nv)
        self.wp_guarded = np.zeros(m.nv, dtype=bool)
        if wd.size:
            dw = DYN_WORKPIECE_DAMPING / h
            if scene.grip == "III":
                # the corner meets thin capsules: falling freely, the workpiece may move at most
                # DYN_FALL_STEP contact radii per step (else it tunnels through the rod); the
                # finger is slowed alike: a sliding corner must not see the rod spring away
                r = (scene.r_link + scene.r_corner) * scene.length
                self.slow = max(1.0, scene.physical.g * h / (DYN_FALL_STEP * r) / dw)
            for j, name in zip(wd, scene.workpiece_joints):
                if name == "ry":  # rotation: inertia about y instead of mass
                    e, col = np.zeros(m.nv), np.zeros(m.nv)
                    e[j] = 1.0
                    mujoco.mj_mulM(m, d, col, e)  # the rotation's inertia M[j, j]
                    self.wp_damping[j] = DYN_WORKPIECE_DAMPING * float(col[j]) / h
                else:
                    self.wp_damping[j] = dw * scene.workpiece_inertial_mass  # over-damps its inertia
                    self.wp_guarded[j] = True
        #: the fall guard's current factor on the damping, in [1, slow] (:meth:`_guard`)
        self.factor = self.slow
        self.R = np.zeros(m.nv)
        self.held_q = None
        self.update_damping()
        if m.npair:
            m.pair_solref[:] = [DYN_TIMECONST * h, 1.0]
            m.pair_solimp[:, 0] = CONTACT_IMPEDANCE
            m.pair_solimp[:, 1] = CONTACT_IMPEDANCE

    def update_damping(self) -> None:
        """Hinge damping ``h max(K, R)`` (:func:`geometric_stiffness_bound` at the current state) times the
        fall guard's factor; the workpiece's ``3 m / h`` (its translations times the guard's factor)."""
        m, sc = self.m, self.scene
        hanging = (sc.has_workpiece and sc.free_workpiece and self.held_q is None
                   and not int(m.opt.disableflags) & int(mujoco.mjtDisableBit.mjDSBL_CONTACT))
        load = sc.workpiece_mass * sc.physical.g if hanging else 0.0
        self.R = geometric_stiffness_bound(sc, self.d, load)
        factor = self.factor
        h = self.h
        damp = np.where(self.k > 0, DYN_DAMPING * h * np.maximum(self.k, self.R) * factor, 0.0)
        damp += np.where(self.wp_guarded, self.wp_damping * factor, self.wp_damping)
        m.dof_damping[:] = damp

    def residual(self) -> float:
        """Static residual at rest: ``qfrc_smooth + qfrc_constraint`` at ``qvel = 0`` (MuJoCo's friction included)."""
        qvel = self.d.qvel.copy()
        r = self.rest_residual.vector(self.d.qpos, self.d.qfrc_applied)
        self.d.qvel[:] = qvel
        self.calls += 1
        if self.held_q is not None:
            r[np.asarray(self.scene.workpiece_dof, dtype=int)] = 0.0
        return float(np.max(np.abs(r)))

    def velocity(self) -> float:
        """Largest scaled speed: rad or ``l`` per ``sqrt(l/g)`` (the workpiece's left out while it is held)."""
        v = np.array(self.d.qvel) / self.vscale
        if self.held_q is not None:
            v[np.asarray(self.scene.workpiece_dof, dtype=int)] = 0.0
        return float(np.max(np.abs(v))) if v.size else 0.0

    def step(self, k: int = 1) -> None:
        """``k`` physics steps (``k > 1`` only while the workpiece is not held in place)."""
        m, d = self.m, self.d
        self.update_damping()  # the loads' geometric stiffness at the current state
        mujoco.mj_step(m, d, k)
        self.steps += k
        self.calls += k
        if self.held_q is not None:
            d.qpos[self.scene.workpiece_qpos] = self.held_q
            d.qvel[self.scene.workpiece_dof] = 0.0
        if not np.all(np.isfinite(d.qpos)) or not np.all(np.isfinite(d.qvel)):
            raise SettleError("dynamic settle diverged (non-finite state)")
        check_warnings(d)

    def _guard(self, v: float) -> None:
        """Grip III fall guard: the factor ``s`` on the damping that keeps the plain flow's step below
        :data:`DYN_FALL_STEP` contact radii.  Over-damped, the velocity goes as ``1 / s``: under the factor
        ``s`` the plain flow's step is ``s v h`` (``v`` over ``l / sqrt(l/g)``), an upper bound
        (inertia and the implicit springs add to the damping's metric), so ``s`` never lets the
        workpiece move more than :data:`DYN_FALL_STEP` contact radii in one step, and a slow
        velocity under heavy damping (a force far from balance) does not lift it."""
        sc = self.scene
        step = v * self.factor * self.h / math.sqrt(sc.length / sc.physical.g)
        allowed = DYN_FALL_STEP * (sc.r_link + sc.r_corner)
        factor = min(self.slow, max(1.0, step / allowed))
        if factor != self.factor:
            self.factor = factor
            self.update_damping()

    def hold(self, on: bool) -> None:
        """Hold the workpiece where it is (:func:`~simgrip.settle.closing.hold_workpiece`) or let it go."""
        hold_workpiece(self.scene, on)
        self.held_q = np.array(self.d.qpos[self.scene.workpiece_qpos]) if on else None

    def run(self, tol, vtol, budget, watch=None) -> tuple[bool, str]:
        """Step until residual < tol and velocity < vtol; ``watch()`` returning a reason stops early."""
        start = self.steps

        def guard(v):
            if self.slow > 1.0 and self.held_q is None and self.steps > start:  # after a first batch
                self._guard(v)

        # one step per test while the fall guard is below its full factor: a workpiece that starts
        # to fall gets it back before it moves a contact radius
        def one_step():
            return self.held_q is not None or self.factor < self.slow

        return run_to_rest(self, tol, vtol, budget, watch, "dynamic settle", before=guard, one_step=one_step)


def run_to_rest(dyn, tol, vtol, budget, watch=None, what="dynamic settle", *, before=None, one_step=None):
    """Step ``dyn`` until its velocity is below ``vtol`` and its residual below ``tol``: ``(converged, why)``.

    ``dyn`` has ``velocity()``, ``residual()`` (scaled, max over dofs), ``step(k)``,
    ``steps`` and ``held_q``.  ``watch()`` returning a reason stops early; ``before(v)``
    runs at each test; between tests ``DYN_BATCH`` steps go in one call (the stop test
    costs nothing in between), one step while ``one_step()`` (default: the workpiece is
    held in place).  A non-finite residual raises :class:`SettleError` naming ``what``.
    """
    while True:
        v = dyn.velocity()
        if before is not None:
            before(v)
        # the residual (one more forward pass) only once at rest: halves the cost of a step
        if v < vtol:
            r = dyn.residual()
            if not math.isfinite(r):
                raise SettleError(f"{what} diverged (non-finite residual)")
            if r < tol:
                return True, "ok"
        if watch is not None:
            why = watch()
            if why:
                return False, why
        if dyn.steps >= budget:
            return False, "max_steps"
        one = one_step() if one_step is not None else dyn.held_q is not None
        dyn.step(1 if one else min(DYN_BATCH, budget - dyn.steps))

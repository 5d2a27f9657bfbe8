"""``method="dynamics"``: a settle that really simulates, with MuJoCo's own contact and friction.

Everything is chosen from the model:

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
  weight unbalanced, hence :data:`DYN_TOL`); a state penetrating more than
  :data:`DYN_PEN_LIMIT` restarts with half the step.
* **Start** (I/II): the hinge chain's grip equilibrium, the workpiece held at
  the tip (as the static solve); where that start is not valid, a closing
  with contact on, frictionless, rest angles ramped at <=
  :data:`DYN_CLOSE_RATE` rad of total rotation per step.  The holding force
  then fades out over :data:`DYN_RELEASE_STEPS` steps.
* **Stop**: the static residual at rest below ``tol`` and velocities below
  :data:`DYN_VTOL`, tested every :data:`DYN_BATCH` steps (one ``mj_step`` call
  between tests; the residual only once the velocity is small).  Drop: the tip slips :data:`DYN_DROP_SLIP` along the face
  (I/II) or the workpiece falls out of contact; then the finger settles alone.
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from simgrip.settle import closing
from simgrip.settle.closing import hold_workpiece, start_free, start_on_chain
from simgrip.settle.state import SettledState, SettleError, read_state
from simgrip.settle.statics import CONTACT_IMPEDANCE, RestResidual, check_warnings, dof_scales
from simgrip.sim.scene import Scene, set_curvature
from simgrip.sim.workpiece import lower_onto_fingers, slip_coordinate

__all__ = ["DYN_TOL", "DYN_TOL_PER_WEIGHT", "Dyn", "dynamics_tolerance", "settle_dynamics"]

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
#: Default static residual tolerance of the dynamic settle (the creep floor is ~2e-6 at the
#: standard workpiece weight M = 5).
DYN_TOL = 1e-5
#: The creep floor is a fixed fraction of the force the friction carries, i.e. of the workpiece's
#: weight ``M`` (over rho g l): measured 4e-7 M (standard case) to 9e-7 M (M = 33, D = 70); the
#: default tolerance is ``max(DYN_TOL, DYN_TOL_PER_WEIGHT M)`` (:func:`dynamics_tolerance`).
DYN_TOL_PER_WEIGHT = 2e-6
#: Velocity tolerance (rad or l per sqrt(l/g)).
DYN_VTOL = 1e-6
#: Closing ramp: largest change of the total rest rotation per physics step [rad] (one step moves
#: the finger most of the way to the new equilibrium, and a tip jumping deeper than ~0.05 l
#: into the face in one step is not pushed back: measured).
DYN_CLOSE_RATE = 0.05
#: Penetration (over l) above which the dynamic settle restarts with half the time step.
DYN_PEN_LIMIT = 1e-4
#: Physics steps over which the workpiece's holding force fades out at release.
DYN_RELEASE_STEPS = 20
#: Fall (over l) of the workpiece after release that counts as a drop even while it still brushes the
#: rod (a soft Grip III finger lets the corner slide down slowly: measured 0.015 l per 1000 steps).
DYN_DROP_FALL = 0.2
#: Physics steps per ``mj_step`` call between two stop tests (velocity, drop watch) once nothing is held.
DYN_BATCH = 16
#: Physics steps allowed to the h/2 rerun that confirms a drop (a state that does not come to rest
#: in them keeps the drop found at h).
DYN_DROP_RETRY_STEPS = 2000
#: Tangential slip (over l) of the tip on the workpiece after release that counts as a drop.
DYN_DROP_SLIP = 0.02


def dynamics_tolerance(scene: Scene) -> float:
    """Default static residual tolerance of the dynamic settle of ``scene`` with a workpiece.

    MuJoCo's sticking friction creeps and leaves a fraction of the friction force
    unbalanced at rest, so the floor scales with the weight it carries:
    ``max(DYN_TOL, DYN_TOL_PER_WEIGHT * M)`` (``M`` the workpiece's weight over ``rho g l``).
    """
    return max(DYN_TOL, DYN_TOL_PER_WEIGHT * float(scene.params.M))


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
                    self.wp_damping[j] = dw * scene.workpiece_mass
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


def _finger_pairs_touching(scene: Scene) -> bool:
    d = scene.data
    mine = set(int(g) for f in range(scene.fingers) for g in scene.contact_geoms[f])
    wg = set(int(g) for g in scene.workpiece_geoms)
    return any((int(d.contact.geom1[i]) in mine and int(d.contact.geom2[i]) in wg) for i in range(d.ncon))


def _deepest_contact(scene: Scene) -> float:
    """Deepest penetration [m] of the contacts in the scene's data (0 without contacts)."""
    d = scene.data
    return max((-float(d.contact.dist[i]) for i in range(d.ncon)), default=0.0)


def _put_back(scene: Scene, state: SettledState) -> None:
    """Put the scene's data back at a settled state (at rest)."""
    d = scene.data
    d.qpos[:] = state.qpos
    d.qvel[:] = 0.0
    mujoco.mj_forward(scene.model, d)


def settle_dynamics(scene: Scene, tol: float, max_steps: int, warm_start, close: bool,
                     allow_unconverged: bool, t0: float) -> SettledState:
    """Over-damped settle; the time step halves (from the start) while penetration >= DYN_PEN_LIMIT,
    or a contact tunnels (the tip sphere wholly inside the face, the corner across the rod's axis:
    the run stops there),
    and once when the workpiece drops: a drop counts when it happens at two time steps ``h`` and
    ``h/2`` (a heavy workpiece on a soft finger can start a growing two-step oscillation of the contact
    at ``h = 1/omega_min`` that throws it off the tip; at ``h/2`` it holds)."""
    d = scene.data
    q0 = d.qpos.copy()
    flags0 = int(scene.model.opt.disableflags)  # a drop leaves contact off (the finger settles alone)
    steps = calls = 0
    factor = 1.0
    retried_drop = tunnelled = False
    first_drop = None
    for _attempt in range(4):
        # max_steps is the budget of the whole settle: a restart gets what the earlier attempts left
        budget = max_steps - steps
        if first_drop is not None:
            budget = min(budget, DYN_DROP_RETRY_STEPS)
        try:
            state, dropped, tunnelled = _settle_dynamics_once(scene, tol, budget, warm_start, close,
                                                              allow_unconverged or first_drop is not None, t0,
                                                              factor)
        except SettleError:
            if first_drop is None:
                raise
            state, dropped = first_drop, True  # diverged at h/2: the drop at h stands
            _put_back(scene, state)
            break
        steps += state.steps
        calls += state.forward_calls
        if first_drop is not None and not state.converged:  # no rest at h/2 within its budget: the drop stands
            state, dropped = first_drop, True
            _put_back(scene, state)
            break
        retry_drop = dropped and not retried_drop
        if retry_drop:
            first_drop = state
        retried_drop = retried_drop or dropped
        if _attempt == 3 or steps >= max_steps or (not tunnelled and (
                (state.penetration < DYN_PEN_LIMIT and not retry_drop) or not state.converged)):
            break
        d.qpos[:] = q0
        d.qvel[:] = 0.0
        d.qfrc_applied[:] = 0.0
        scene.model.opt.disableflags = flags0
        mujoco.mj_forward(scene.model, d)
        factor *= 0.5
    if tunnelled and first_drop is None and not allow_unconverged:
        raise SettleError(f"dynamic settle tunnelled (a contact deeper than the finger geom) at every "
                          f"step down to h/{round(1 / factor)}")
    state.steps, state.forward_calls = steps, calls
    return state


def _settle_dynamics_once(scene: Scene, tol: float, max_steps: int, warm_start, close: bool,
                          allow_unconverged: bool, t0: float,
                          step_factor: float) -> tuple[SettledState, bool, bool]:
    """One dynamic settle at ``step_factor`` h: ``(state, dropped, tunnelled)``."""
    m, d = scene.model, scene.data
    dyn = Dyn(scene, step_factor)
    vtol = DYN_VTOL
    held = scene.has_workpiece
    converged, why = True, "ok"
    if warm_start is not None:
        held = warm_start.held and scene.has_workpiece
    contact_off = int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    flags = int(m.opt.disableflags)
    dim = m.pair_dim.copy()
    closed = dropped = False
    if scene.has_workpiece and held:
        started = start_on_chain(scene, None) if (scene.grip in ("I", "II") and warm_start is None and close
                                                   and closing.CHAIN_START) else None
        if started is not None:
            # the hinge chain's grip equilibrium, workpiece at the tip (as the static settle): the
            # dynamics releases it from there (a finger that cannot reach the face settles alone)
            mujoco.mj_forward(m, d)
            dyn.hold(True)
            held = bool(started) and _finger_pairs_touching(scene)
            # loaded start: the chain's friction already carries the weight, so the workpiece is
            # let go at once (fading a holding force out would push it off the tip: up to twice
            # its weight upwards in the first step)
            closed = False
        elif scene.grip in ("I", "II") and warm_start is None and close:
            # ramp the curvature with contact on, the workpiece held and frictionless
            target = scene.profile
            dyn.hold(True)
            m.pair_dim[:] = 1
            try:
                rest = scene.springs.rest.copy()  # rest angles are linear in the curvature's scale
                stages = max(1, math.ceil(float(np.sum(np.abs(rest))) / DYN_CLOSE_RATE))
                for i in range(1, stages + 1):
                    if dyn.steps >= max_steps:
                        break
                    m.qpos_spring[scene.joint_qpos] = (rest * (i / stages))[None, :]
                    dyn.step()
                conv, why = dyn.run(max(tol, 1e-8), vtol, max_steps)
            finally:
                set_curvature(scene, target)
                m.pair_dim[:] = dim
            if not conv:
                converged = False
            held = _finger_pairs_touching(scene)
            closed = True
        if held and converged and not scene.free_workpiece:  # fixed workpiece: settle against it
            dyn.hold(False)
            converged, why = dyn.run(tol, vtol, max_steps)
        elif held and converged:
            s0 = slip_coordinate(scene)
            z0 = float(d.xpos[scene.workpiece_body][2])
            # let go gently: the holding force fades out over DYN_RELEASE_STEPS steps, so the
            # workpiece never moves more than a contact radius in one step (no tunnelling)
            # (after closing: the finger carries no load yet).  A loaded start (Grip III,
            # warm start) is released at once, the workpiece lowered onto the rod first so
            # that MuJoCo sees the contact in the first step.
            if closed:
                dyn.hold(True)
                dyn.held_q = None
                wz = [dof for name, dof in zip(scene.workpiece_joints, scene.workpiece_dof) if name == "z"]
                weight = scene.workpiece_mass * scene.physical.g
                for i in range(1, DYN_RELEASE_STEPS + 1):
                    if dyn.steps >= max_steps:
                        break
                    d.qfrc_applied[wz] = weight * (1.0 - i / DYN_RELEASE_STEPS)
                    dyn.step()
            else:
                lower_onto_fingers(scene)
            dyn.hold(False)
            if warm_start is not None and warm_start.rest is not None and warm_start.rest.shape == (scene.n,):
                # warm start: ramp the rest angles from the previous state's (loaded, friction on)
                target = scene.springs.rest.copy()
                stages = max(1, math.ceil(float(np.sum(np.abs(target - warm_start.rest))) / DYN_CLOSE_RATE))
                for i in range(1, stages + 1):
                    if dyn.steps >= max_steps:
                        break
                    m.qpos_spring[scene.joint_qpos] = (warm_start.rest + (target - warm_start.rest) * i / stages)[None, :]
                    dyn.step()
                m.qpos_spring[scene.joint_qpos] = target[None, :]

            def watch():
                drop = (z0 - float(d.xpos[scene.workpiece_body][2])) / scene.length
                if drop > DYN_DROP_FALL or (drop > DYN_DROP_SLIP and not _finger_pairs_touching(scene)):
                    return "lost contact"  # out of contact, or sliding down the rod far past any hold
                if scene.grip in ("I", "II") and abs(slip_coordinate(scene) - s0) > DYN_DROP_SLIP:
                    return "slipped"
                if _deepest_contact(scene) > tunnel:
                    return "tunnelled"
                return None

            # tunnelled: the tip sphere wholly inside the face (I/II), the corner across the rod's axis (III)
            tunnel = scene.length * (2.0 * scene.r_tip if scene.grip in ("I", "II")
                                     else scene.r_link + scene.r_corner)
            converged, why = dyn.run(tol, vtol, max_steps, watch)
            if why in ("lost contact", "slipped"):
                held, converged, dropped = False, True, True
            elif why == "tunnelled":
                return read_dynamics(scene, dyn, t0, held, False), False, True
    if not (scene.has_workpiece and held) and converged:
        if scene.has_workpiece:  # park the workpiece, settle the finger alone (from the chain's free state)
            dyn.hold(True)
            m.opt.disableflags = flags | contact_off
            if start_free(scene):
                mujoco.mj_forward(m, d)
        converged, why = dyn.run(tol, vtol, max_steps)
    if not converged and not allow_unconverged:
        raise SettleError(f"dynamic settle did not converge ({why} after {dyn.steps} steps)")
    return read_dynamics(scene, dyn, t0, held, converged), dropped, False


def read_dynamics(scene: Scene, dyn: Dyn, t0: float, held: bool, converged: bool) -> SettledState:
    """The settled state from MuJoCo's own contact forces (friction included), at rest."""
    m, d = scene.model, scene.data
    residual = dyn.residual()
    vmax = dyn.velocity()
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    return read_state(scene, d, held=held, method="dynamics", residual=residual, converged=converged,
                      steps=dyn.steps, newton_iterations=0, forward_calls=dyn.calls,
                      wall_time_s=time.perf_counter() - t0, velocity=vmax, timestep=dyn.h)

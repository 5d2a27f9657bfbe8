"""The settle of a full-contact scene (``contact="full"``, :mod:`simgrip.sim.full_contact`): every link touches.

First the static route (:mod:`~simgrip.settle.full_routes` on :mod:`~simgrip.settle.full_newton`: Newton on
MuJoCo's own rest balance, from the point-contact chain where only the tip touches, by continuation past the
onset for Grips I/II at ``box_depth``), judged as the dynamics' answer is (:func:`_by_newton`: MuJoCo's rest
residual with the friction on below ``tol``, no contact deeper than :data:`FULL_NEWTON_PEN`).  Where it does not
apply, or fails (a warning then says so), the guarded dynamics below settles.

Over-damped MuJoCo dynamics (:class:`~simgrip.settle.integrator.Dyn`: ``mjINT_DISCRETE`` at ``h =
1/omega_min``, stiffness-proportional damping) with MuJoCo's own contact and friction on every contact the
broad phase finds, in three phases:

1. **Closing** (frictionless): from the built start (the straight finger; the box held where it was
   built, Grips I/II), the rest angles are ramped at most ``r_link`` rad of total rotation per step
   (:data:`FULL_CLOSE_RATE_PER_RADIUS`: no link moves through another between two steps) with every
   contact on and ``condim = 1``, then run to rest: the finger
   curls onto the workpiece and onto itself without a sticking history.
1b. **Grasp at a depth** (``scene.box_depth``, :func:`~simgrip.sim.full_contact.check_grasp`), during the
   closing: once the tip has passed ``depth`` below the box's built top, the held box follows it (moved at most
   :data:`FULL_GRASP_RATE` ``r_link`` per step toward ``top - Y_tip = depth``; Grip II ``Y_tip - bottom``:
   :func:`grasp_depth`), and each tip is pulled down by the force its friction will carry once the box hangs
   on it, ``-W/F - (the vertical forces of the finger's other contacts with the box)`` (the box's vertical
   balance; low-passed, :data:`FULL_LOAD_BLEND`).  Without that stand-in a frictionless tip slides up the face
   and off its top edge (past the onset there is no frictionless rest on the face); the held box cannot be
   brought to rest at the depth by this explicit force alone (it feeds back through the corner's contact: a
   limit cycle of ~1e-3 l, measured at n = 16), so the release starts as soon as the ramp ends, the stand-in
   fading as the box's support does, and the box then hangs on the sticking tip: the over-damped flow of the
   rod and the free box with the tip bonded by friction, which converges.  The depth the state ends at (the
   tip sticks; MuJoCo's soft friction slips ~5e-4 l while the load comes on) is checked against the asked one
   within :data:`FULL_DEPTH_TOL`: past it the box is grasped again from the rested state and released again
   (:data:`FULL_REGRASPS`), then a warning says so; :func:`grasp_depth` reads it.  Grip I at kappa -10
   (:mod:`tests.test_full_grasp`): N 0.92, 0.46, 0.30, 0.07 % above the free-boundary BVP at n = 16 ... 128.
   Grip II at kappa 10 does not settle this way (the tip leaves the face: SettleError); the static route does
   (:mod:`tests.test_full_newton`).
2. **Release** (friction ``mu_s`` on, ``condim = 3``; without ``scene.extra_friction`` only the tip's contacts
   carry friction, every other contact stays ``condim = 1``: :func:`_friction`): the box's holding force fades out over
   :data:`~simgrip.settle.dynamics.DYN_RELEASE_STEPS` steps and the scene runs to rest.  The box is
   dropped when it falls :data:`~simgrip.settle.dynamics.DYN_DROP_FALL` (or
   :data:`~simgrip.settle.dynamics.DYN_DROP_SLIP` out of contact); the finger then settles alone,
   still touching itself.
3. **Judge**: MuJoCo's static balance at rest (:class:`~simgrip.settle.statics.RestResidual`, as every
   settle) below ``tol``, velocities below :data:`~simgrip.settle.dynamics.DYN_VTOL`.

Contact softness: every colliding geom takes :func:`contact_solref` (MuJoCo's direct stiffness sized for
the static settle's contact stiffness, ``F / 1e6 l`` deep under a force ``F``; damping that closes half a
penetration per step).  A state deeper than :data:`FULL_PEN_LIMIT` (1e-4 l, ten times inside the issue's
1e-3 l) restarts with half the step; a contact deeper than the capsule's radius has tunnelled: restart too.
Every step is guarded (:class:`~simgrip.settle.full_guard.GuardedSteps`): no point moves through a capsule.
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from simgrip.settle.full_guard import GuardedSteps
from simgrip.settle.dynamics import (DYN_CLOSE_RATE, DYN_DROP_FALL, DYN_DROP_SLIP, DYN_RELEASE_STEPS,
                                     DYN_VTOL, Dyn)
from simgrip.settle.state import SettledState, SettleError, read_state
from simgrip.settle.statics import CONTACT_IMPEDANCE, CONTACT_STIFFNESS
from simgrip.sim.full_contact import colliding_geoms, grasp_depth  # grasp_depth re-exported (__all__)
from simgrip.sim.scene import Scene, set_curvature

__all__ = ["FULL_DEPTH_TOL", "FULL_GRASP_RATE", "FULL_LOAD_BLEND", "FULL_PEN_LIMIT", "contact_set", "contact_solref", "grasp_depth",
           "ramp_rate", "settle_full"]

#: Deepest contact (over l) a full-contact state may keep; deeper restarts at half the step.
FULL_PEN_LIMIT = 1e-4
#: Deepest contact (over l) of a static (Newton) state: the issue's bound.  The depth at rest is MuJoCo's contact
#: law's, not the step's (:func:`contact_solref`'s stiffness is independent of h), so :data:`FULL_PEN_LIMIT`'s
#: restart at half the step would end at the same depth: measured 1.08e-4 l at the tip of Grip I kappa -10, n =
#: 32 (N = 2 x 9.97), where the dynamics stops 8.99e-5 deep short of rest.
FULL_NEWTON_PEN = 1e-3
#: Step halvings tried before the settle gives up on penetration.
FULL_RESTARTS = 3
#: Damping factor on a held workpiece's dofs (:class:`FullDyn`).
FULL_HELD_DAMPING = 1e8
#: Fraction of a contact's penetration closed per step (the contact's damping, :func:`_once`).
FULL_CONTACT_RELAX = 0.5
#: Closing ramp: largest change of the total rest rotation per physics step, over the capsule radius
#: ``r_link / l`` [rad].  A change ``delta`` of the rest angles moves no point of the over-damped finger by more
#: than ``delta l`` in one step (each hinge's change turns the rest of the finger, arm <= l; the step follows its
#: rest shape at most: :class:`Dyn` is over-damped at ``h = 1/omega_min``), so a link moves at most ``r_link``
#: per step: half the capsules' contact distance ``2 r_link``, never through another link between two steps.
FULL_CLOSE_RATE_PER_RADIUS = 1.0
#: Closing ramp: its rate never halves below this (over ``r_link``, rad per step): a contact held deep by a
#: load would otherwise halve it to zero and stall the closing.
FULL_CLOSE_RATE_FLOOR = 0.01
#: Grasp at a depth: largest move of the held box per step, over ``r_link`` (half the guard's bound
#: :data:`~simgrip.settle.full_guard.FULL_STEP_RADII`: the finger keeps the other half).
FULL_GRASP_RATE = 0.25
#: Grasp at a depth: weight of the new value in the tip's stand-in force per closing step (a low-pass: the
#: contact forces it is summed from answer the force itself one step late).
FULL_LOAD_BLEND = 0.5
#: Grasp at a depth: the settled depth must be within this of the asked one (over l): the contact radius
#: ``r_link`` (2e-3); measured 5e-4 of slip at Grip I kappa -10, n = 16 ... 64.  It moves N by
#: ``|dN/d depth|`` times it at most.
FULL_DEPTH_TOL = 2e-3
#: Grasp at a depth: a release that slipped farther grasps again from its rested state (the box back to the
#: depth, the stand-in for the tip's friction, :data:`FULL_REGRASP_STEPS` steps) and releases again, at most this
#: often.  A release far from rest slips (n = 128 at kappa -10: the ramp ends in 3000 steps, the tip slipped
#: 5.8e-3 l); from a rested state the load it takes on is the one it carried.
FULL_REGRASPS = 2
FULL_REGRASP_STEPS = 200


def settle_full(scene: Scene, tol: float, max_steps: int, allow_unconverged: bool, t0: float,
                static: bool = True) -> SettledState:
    """Settle a full-contact scene from its built start.  First the static route (``static``,
    :mod:`~simgrip.settle.full_routes`: Newton on MuJoCo's rest balance, judged as the dynamics is: method
    ``"newton"``, or ``"newton+dynamics"`` where the box dropped past the onset and the finger alone flowed to
    rest); where it does not apply or fails (a warning says so), the guarded dynamics (the module docstring),
    which restarts at ``h/2`` while the deepest contact exceeds :data:`FULL_PEN_LIMIT` or one tunnels.
    ``max_steps`` bounds the Newton iterations and the physics steps of all attempts together; raises
    :class:`SettleError` when the budget is spent (unless ``allow_unconverged``)."""
    m, d = scene.model, scene.data
    if scene.contact != "full":
        raise ValueError("contact: settle_full needs a scene built with contact='full'")
    q0 = d.qpos.copy()
    saved = _save_geoms(m)
    steps = calls = 0
    factor = 1.0
    state = None
    try:
        state, why = _by_newton(scene, tol, max_steps, t0) if static else (None, None)
        if state is not None:
            state.contact_set = contact_set(scene)
            return state
        d.qpos[:] = q0
        d.qvel[:] = 0.0
        d.qfrc_applied[:] = 0.0
        _restore_geoms(m, saved)
        for attempt in range(FULL_RESTARTS + 1):
            d.qpos[:] = q0
            d.qvel[:] = 0.0
            d.qfrc_applied[:] = 0.0
            _restore_geoms(m, saved)
            mujoco.mj_forward(m, d)
            state, deep = _once(scene, tol, max_steps - steps, factor, t0)
            steps += state.steps
            calls += state.forward_calls
            if not deep or steps >= max_steps or attempt == FULL_RESTARTS:
                break
            factor *= 0.5
        state.steps, state.forward_calls = steps, calls
        if deep:
            state.converged = False
            state.warnings.append(f"full contact: a contact stayed deeper than {FULL_PEN_LIMIT:g} l down to the "
                                  f"step h/{round(1 / factor)}")
        if not state.converged and not allow_unconverged:
            raise SettleError(f"full-contact settle did not converge (residual {state.residual:.3g}, "
                              f"{steps} steps)")
        if why:
            state.warnings.append(f"full contact: the static Newton failed ({why}); settled by the dynamics")
        state.contact_set = contact_set(scene)
    finally:
        _restore_geoms(m, saved)
    return state


def _by_newton(scene: Scene, tol: float, max_steps: int, t0: float) -> tuple[SettledState | None, str | None]:
    """The static route (:mod:`~simgrip.settle.full_newton`), judged as the dynamics' answer is: MuJoCo's rest
    balance (:meth:`~simgrip.settle.integrator.Dyn.residual`, the friction of :func:`_friction` on) below ``tol``
    and no contact deeper than :data:`FULL_PEN_LIMIT`.  ``(state, None)``; ``(None, why)`` where it failed;
    ``(None, None)`` where it does not apply.  The caller restores the geoms."""
    from simgrip.settle.full_routes import newton_full

    m, d = scene.model, scene.data
    dyn = FullDyn(scene, 1.0)
    gs = colliding_geoms(m)
    m.geom_solref[gs] = contact_solref(scene, dyn.h)
    m.geom_solimp[gs, 0] = CONTACT_IMPEDANCE
    m.geom_solimp[gs, 1] = CONTACT_IMPEDANCE
    _friction(scene, gs, "none")
    res, why = newton_full(scene, tol, max_steps)
    if res is None:
        return None, why
    _friction(scene, gs, "all" if scene.extra_friction else "tip")
    d.qpos[:] = res.qpos
    d.qvel[:] = 0.0
    d.qfrc_applied[:] = 0.0
    if scene.has_workpiece and not res.held:
        dyn.hold(True)  # parked: its geoms stay out of contact (newton_full), its weight held
    mujoco.mj_forward(m, d)
    method = "newton"
    if not res.settled:  # dropped past the onset: the finger alone flows to rest from the held shape
        for g in scene.workpiece_geoms:
            m.geom_contype[g] = m.geom_conaffinity[g] = 0
        converged, why = GuardedSteps(scene, dyn).run(tol, max_steps)
        if not converged:
            return None, f"the finger alone did not settle after the drop ({why})"
        method = "newton+dynamics"
    residual = dyn.residual()
    if not residual < tol:
        return None, f"MuJoCo's rest residual {residual:.3g} above {tol:.3g} at its state"
    state = _read(scene, dyn, t0, res.held, True)
    if state.penetration > FULL_NEWTON_PEN:
        return None, f"a contact {state.penetration:.3g} l deep"
    state.method = method
    state.steps = dyn.steps
    state.newton_iterations = res.iterations
    state.forward_calls = dyn.calls + res.evaluations
    return state, None


class FullDyn(Dyn):
    """:class:`Dyn` whose held workpiece is damped :data:`FULL_HELD_DAMPING` times: its pose is put back after each
    step, so a contact that MuJoCo's solve resolved by moving it instead of the finger would undo nothing."""

    def update_damping(self) -> None:
        super().update_damping()
        if self.held_q is not None:
            self.m.dof_damping[np.asarray(self.scene.workpiece_dof, dtype=int)] *= FULL_HELD_DAMPING


def _once(scene: Scene, tol: float, budget: int, factor: float, t0: float) -> tuple[SettledState, bool]:
    """One settle at ``factor`` h: ``(state, too_deep)``."""
    m, d = scene.model, scene.data
    dyn = FullDyn(scene, factor)
    gs = colliding_geoms(m)
    m.geom_solref[gs] = contact_solref(scene, dyn.h)
    m.geom_solimp[gs, 0] = CONTACT_IMPEDANCE
    m.geom_solimp[gs, 1] = CONTACT_IMPEDANCE
    limit = FULL_PEN_LIMIT * scene.length
    tunnel = scene.r_link * scene.length
    guard = GuardedSteps(scene, dyn)
    held = scene.has_workpiece
    if held:
        dyn.hold(True)
    # 1. closing, frictionless
    target = scene.profile
    rest = scene.springs.rest.copy()
    grasp = _Follow(scene, dyn) if held and scene.box_depth is not None else None
    _friction(scene, gs, "none")
    try:
        # adaptive ramp: the rest rotation per step grows while a step moves less than half the guard's bound
        # and shrinks when it moves more (the guard itself still rejects any step above it)
        total = float(np.sum(np.abs(rest)))
        rate = min(DYN_CLOSE_RATE, FULL_CLOSE_RATE_PER_RADIUS * scene.r_link)
        frac = 0.0
        while frac < 1.0:
            if dyn.steps >= budget:
                break
            frac = min(1.0, frac + rate / max(total, 1e-300))
            m.qpos_spring[scene.joint_qpos] = (rest * frac)[None, :]
            if grasp is not None:
                grasp.move(force=False)
                grasp.load(FULL_LOAD_BLEND)
            guard.step()
            if _deepest(d) > tunnel:
                return _read(scene, dyn, t0, held, False), True
            rate = max(ramp_rate(rate, guard, _deepest(d), tunnel), FULL_CLOSE_RATE_FLOOR * scene.r_link)
        if grasp is not None:  # 1b. the box at the asked depth (followed on if the tip never got there)
            converged = _follow(grasp, guard, budget, 0)
        else:
            converged, why = guard.run(max(tol, 1e-8), budget)
    finally:
        set_curvature(scene, target)
        _friction(scene, gs, "all" if scene.extra_friction else "tip")
    if not converged:
        return _read(scene, dyn, t0, held, False), _deepest(d) > limit
    # 2. release with friction
    if held and not _touching(scene):
        held = False
    for attempt in range(FULL_REGRASPS + 1 if grasp is not None else 1):
        if not held:
            break
        if attempt:  # 1b again from the rested state: the box to the depth, the stand-in for the tip's friction
            dyn.hold(True)
            _friction(scene, gs, "none")
            converged = _follow(grasp, guard, budget, FULL_REGRASP_STEPS)
            _friction(scene, gs, "all" if scene.extra_friction else "tip")
            if not converged:
                return _read(scene, dyn, t0, held, False), _deepest(d) > limit
        wz = [dof for name, dof in zip(scene.workpiece_joints, scene.workpiece_dof) if name == "z"]
        weight = scene.workpiece_mass * scene.physical.g
        z0 = float(d.xpos[scene.workpiece_body][2])
        dyn.held_q = None
        for i in range(1, DYN_RELEASE_STEPS + 1):
            if dyn.steps >= budget:
                break
            d.qfrc_applied[wz] = weight * (1.0 - i / DYN_RELEASE_STEPS)
            if grasp is not None:  # the tip's stand-in for friction fades as the box's support does
                grasp.fade(1.0 - i / DYN_RELEASE_STEPS)
            guard.step()
        dyn.hold(False)
        if grasp is not None:
            grasp.fade(0.0)

        def watch():
            drop = (z0 - float(d.xpos[scene.workpiece_body][2])) / scene.length
            if drop > DYN_DROP_FALL or (drop > DYN_DROP_SLIP and not _touching(scene)):
                return "lost contact"
            if _deepest(d) > tunnel:
                return "tunnelled"
            return None

        converged, why = guard.run(tol, budget, watch)
        if why == "tunnelled":
            return _read(scene, dyn, t0, held, False), True
        if why == "lost contact" or (converged and not _touching(scene)):
            held, converged = False, True
        if not (held and converged and grasp is not None) or abs(grasp_depth(scene) - scene.box_depth) <= \
                FULL_DEPTH_TOL:
            break
    if not held and scene.has_workpiece:
        # park the workpiece (held, out of contact): the finger settles alone, touching itself
        dyn.hold(True)
        for g in scene.workpiece_geoms:
            m.geom_contype[g] = m.geom_conaffinity[g] = 0
        converged, why = guard.run(tol, budget)
    elif not scene.has_workpiece:
        converged, why = guard.run(tol, budget)
    state = _read(scene, dyn, t0, held, converged)
    if grasp is not None and held:
        got = grasp_depth(scene)
        if abs(got - scene.box_depth) > FULL_DEPTH_TOL:
            state.warnings.append(f"grasp depth: the tip slipped to {got:.4g} l below the box's edge (asked "
                                  f"{scene.box_depth:.4g} l)")
    return state, state.penetration > FULL_PEN_LIMIT or _deepest(d) > limit


class _Follow:
    """Phase 1b (module docstring): the held box's ``z`` toward ``top - Y_tip = depth`` and the tips' stand-in
    for the friction that will carry the box.  While closing it follows once the tip has passed the asked depth
    below the box's built top (before, the box waits where it was built, clear of the finger's root)."""

    def __init__(self, scene: Scene, dyn: Dyn):
        if "z" not in scene.workpiece_joints:
            raise ValueError("box_depth: the box must be free to move vertically (free_workpiece=True)")
        self.scene, self.dyn = scene, dyn
        self.iz = list(scene.workpiece_joints).index("z")
        self.up = 1.0 if scene.grip == "I" else -1.0  # raising the box deepens Grip I's grasp, lowers Grip II's
        self.on = False
        self.tip_qfrc = np.zeros(dyn.m.nv)
        self.fz = None

    def move(self, force: bool) -> float:
        """Move the held box toward the depth by at most :data:`FULL_GRASP_RATE` ``r_link``; returns the box's
        remaining move [m] (before this one)."""
        sc = self.scene
        err = (sc.box_depth - grasp_depth(sc)) * sc.length
        self.on = self.on or force or err <= 0.0
        if self.on:
            rate = FULL_GRASP_RATE * sc.r_link * sc.length
            self.dyn.held_q[self.iz] += self.up * float(np.clip(err, -rate, rate))
        return err

    def load(self, blend: float) -> float:
        """While following: each finger's tip pulled vertically by ``fz = -W/F - sum`` (``W`` the workpiece's
        weight over the ``F`` fingers; ``sum`` the vertical forces of the finger's other contacts with the
        workpiece, MuJoCo's, frictionless): what the tip's friction carries once the box hangs on it (the box's
        vertical balance), applied as ``J^T fz`` at the tip sphere's centre; ``blend`` of the new value mixed
        into the old.  Returns the largest change of ``fz`` over ``W/F``."""
        sc, d, m = self.scene, self.dyn.d, self.dyn.m
        if not self.on:
            return math.inf
        wg = set(int(g) for g in sc.workpiece_geoms)
        idx = sc.index
        weight = sc.workpiece_mass * sc.physical.g / sc.fingers
        fz = np.full(sc.fingers, -weight)
        owner = {int(g): f for f in range(sc.fingers) for g in idx.link_geom[f]}
        fc = np.zeros(6)
        for c in range(d.ncon):
            g1, g2 = int(d.contact.geom1[c]), int(d.contact.geom2[c])
            if g1 in wg and g2 in owner:
                f, sign = owner[g2], 1.0  # the frame's force acts on geom2
            elif g2 in wg and g1 in owner:
                f, sign = owner[g1], -1.0
            else:
                continue
            mujoco.mj_contactForce(m, d, c, fc)
            world = np.asarray(d.contact.frame[c]).reshape(3, 3).T @ fc[:3]
            fz[f] -= sign * float(world[2])
        old = self.fz
        self.fz = fz if old is None else blend * fz + (1.0 - blend) * old
        self.tip_qfrc[:] = 0.0
        jacp = np.zeros((3, m.nv))
        for f in range(sc.fingers):
            g = int(idx.tip_geom[f])
            mujoco.mj_jac(m, d, jacp, None, d.geom_xpos[g], int(m.geom_bodyid[g]))
            self.tip_qfrc += jacp[2] * self.fz[f]
        self.tip_qfrc[np.asarray(sc.workpiece_dof, dtype=int)] = 0.0
        self.fade(1.0)
        return math.inf if old is None else float(np.max(np.abs(self.fz - old))) / weight

    def fade(self, share: float) -> None:
        """Apply ``share`` of the tips' stand-in force (the finger dofs of ``qfrc_applied``)."""
        dofs = np.asarray(self.scene.joint_dof, dtype=int).ravel()
        self.dyn.d.qfrc_applied[dofs] = share * self.tip_qfrc[dofs]


def _follow(grasp: _Follow, guard: GuardedSteps, budget: int, steps: int) -> bool:
    """Phase 1b's steps (the box following, the stand-in load) for at least ``steps`` and until the box is within
    one move of the depth; False when the step budget ran out."""
    dyn, sc = grasp.dyn, grasp.scene
    k = 0
    while abs(grasp.move(force=True)) > FULL_GRASP_RATE * sc.r_link * sc.length or k < steps:
        if dyn.steps >= budget:
            return False
        grasp.load(FULL_LOAD_BLEND)
        guard.step()
        k += 1
    return True


def contact_solref(scene, h: float) -> list[float]:
    """The colliding geoms' ``solref`` in MuJoCo's direct form ``[-k, -b]`` [1/s^2, 1/s] for the step ``h`` [s].

    Stiffness: at rest a contact of MuJoCo's soft law sits ``F / K_c`` deep with ``K_c = k d^2 / A`` (force per
    length; ``d`` the impedance, ``A`` the contact's inverse effective mass, at most ``~3 / m_link`` at a light
    end link: :func:`~simgrip.settle.statics.configure_statics`' estimate).  ``k = K_c A / d^2`` with ``K_c =
    CONTACT_STIFFNESS rho g`` (the static settle's) puts a contact carrying ``F`` (over ``rho g l``) ``F / 1e6 l``
    deep at most: ten times under :data:`FULL_PEN_LIMIT` for ``F <= 100``.  Damping: ``b = k h /``
    :data:`FULL_CONTACT_RELAX`, so that a penetration ``r`` closes at the speed ``(k / b) r``: that fraction of
    it per step, never the whole of it and past (a critically damped ``2 / tau`` with ``tau << h`` closes it
    many times over in one step: a contact that opens in one step and closes in the next, forever).
    """
    phys = scene.physical
    a = 3.0 * scene.n / (phys.rho * phys.length)  # 3 / m_link
    k = CONTACT_STIFFNESS * phys.rho * phys.g * a / CONTACT_IMPEDANCE ** 2
    return [-k, -k * h / FULL_CONTACT_RELAX]


def ramp_rate(rate: float, guard, deepest: float, radius: float) -> float:
    """The closing ramp's next rate [rad of total rest rotation per step]: half when the last step moved near
    the guard's bound or a contact is deeper than a quarter of the capsule's ``radius`` [m] (the contact closes
    only :data:`FULL_CONTACT_RELAX` of a depth per step, so a ramp that keeps pressing a blocked link in deepens
    it by up to the guard's bound per step), 1.5 times (at most :data:`DYN_CLOSE_RATE`) when it moved less than
    half the bound, else unchanged."""
    if guard.last > 0.9 * guard.limit or deepest > 0.25 * radius:
        return 0.5 * rate
    if guard.last < 0.5 * guard.limit:
        return min(DYN_CLOSE_RATE, 1.5 * rate)
    return rate


def _read(scene: Scene, dyn: Dyn, t0: float, held: bool, converged: bool) -> SettledState:
    """The settled state at rest, MuJoCo's own contact forces (as :func:`~simgrip.settle.dynamics.read_dynamics`)."""
    m, d = scene.model, scene.data
    residual = dyn.residual()
    vmax = dyn.velocity()
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    state = read_state(scene, d, held=held, method="dynamics", residual=residual, converged=converged,
                       steps=dyn.steps, newton_iterations=0, forward_calls=dyn.calls,
                       wall_time_s=time.perf_counter() - t0, velocity=vmax, timestep=dyn.h)
    state.penetration = max(state.penetration, _deepest(d) / scene.length)
    return state


def _touching(scene: Scene) -> bool:
    """Whether any finger geom touches a workpiece geom."""
    d = scene.data
    wg = set(int(g) for g in scene.workpiece_geoms)
    return any(int(d.contact.geom1[i]) in wg or int(d.contact.geom2[i]) in wg for i in range(d.ncon))


def _deepest(d) -> float:
    """Deepest penetration [m] among the active contacts (0 without)."""
    return max((-float(d.contact.dist[i]) for i in range(d.ncon)), default=0.0)


def _friction(scene: Scene, gs, where: str) -> None:
    """Which contacts carry friction: ``"none"`` (every colliding geom ``condim = 1``), ``"all"`` (``condim =
    3``) or ``"tip"``: the tip spheres and the last links ``condim = 3``, every other colliding geom ``condim = 1``, the links with
    priority 1 (MuJoCo takes the higher-priority geom's condim, the larger one between equals: a link's
    contact with anything is frictionless, the tip's with the workpiece has friction)."""
    m = scene.model
    m.geom_priority[gs] = 0
    m.geom_condim[gs] = 3 if where == "all" else 1
    if where == "tip":
        # the last link's capsule ends in the tip sphere (same radius by default): its contact with the face is
        # the tip's, and frictionless it would take a share of N without friction
        tips = np.asarray([int(g) for g in scene.index.tip_geom if g >= 0] +
                          [int(g[-1]) for g in scene.index.link_geom], dtype=int)
        links = np.asarray(scene.index.link_geom, dtype=int).ravel()
        m.geom_priority[links] = 1
        m.geom_priority[tips] = 0
        m.geom_condim[tips] = 3


def _save_geoms(m):
    return (m.geom_solref.copy(), m.geom_solimp.copy(), m.geom_condim.copy(), m.geom_contype.copy(),
            m.geom_conaffinity.copy(), m.geom_priority.copy())


def _restore_geoms(m, saved) -> None:
    (m.geom_solref[:], m.geom_solimp[:], m.geom_condim[:], m.geom_contype[:], m.geom_conaffinity[:],
     m.geom_priority[:]) = saved


def contact_set(scene) -> list[dict]:
    """Every active contact of a finger in ``scene.data`` (dimensionless, each finger in its own frame).

    One record per MuJoCo contact that involves a finger geom: ``finger``, ``link`` (0-based; ``n - 1`` for
    the tip sphere, whose ``geom`` is ``"tip"``), ``arc_length`` (over ``l``: where the contact's point
    projects onto that link's centreline), ``with`` (``"workpiece"``, ``"self"`` or ``"finger K"``; a
    self contact also gives ``other_link`` and ``other_arc_length``), ``point`` (the contact point, ``[x,
    z]`` over ``l``), ``normal`` (unit, the direction of the force on this finger), ``normal_force`` (>= 0)
    and ``friction_force`` (signed along the tangent ``(-normal_z, normal_x)`` in the plane; over
    ``rho g l``), ``force`` (the whole force on this finger, ``[x, z]``) and ``depth`` (penetration over ``l``).  A self contact is one record (the first link's).
    """
    m, d = scene.model, scene.data
    L, W, n = scene.length, scene.force_scale, scene.n
    idx = scene.index
    link_of = {}
    for f in range(scene.fingers):
        for i, g in enumerate(idx.link_geom[f]):
            link_of[int(g)] = (f, i, "link")
        if idx.tip_geom[f] >= 0:
            link_of[int(idx.tip_geom[f])] = (f, n - 1, "tip")
    out = []
    fc = np.zeros(6)
    for c in range(d.ncon):
        g1, g2 = int(d.contact.geom1[c]), int(d.contact.geom2[c])
        a, b = link_of.get(g1), link_of.get(g2)
        if a is None and b is None:
            continue
        mujoco.mj_contactForce(m, d, c, fc)
        frame = np.asarray(d.contact.frame[c]).reshape(3, 3)
        world = frame.T @ fc[:3]  # force on geom2 (the frame's normal points from geom1 to geom2)
        mine, other, force = (a, b, -world) if a is not None else (b, a, world)
        f, i, kind = mine
        mir = scene.mirror[f]
        p = np.asarray(d.contact.pos[c])
        normal_w = frame[0] * (-1.0 if a is not None else 1.0)  # pushes this finger's geom away
        nv = np.array([mir * normal_w[0], normal_w[2]])
        nv /= max(float(np.linalg.norm(nv)), 1e-300)
        F2 = np.array([mir * force[0], force[2]]) / W
        tang = np.array([-nv[1], nv[0]])
        rec = {
            "finger": int(f), "link": int(i), "geom": kind,
            "arc_length": _arc(d, idx, f, i, p, L, n),
            "with": "workpiece" if other is None else ("self" if other[0] == f else f"finger {other[0]}"),
            "point": [float(mir * p[0] / L), float(p[2] / L)],
            "normal": [float(nv[0]), float(nv[1])],
            "normal_force": float(fc[0] / W),
            "friction_force": float(F2 @ tang),
            "force": [float(F2[0]), float(F2[1])],
            "depth": float(max(0.0, -float(d.contact.dist[c])) / L),
        }
        if other is not None and other[0] == f:
            rec["other_link"] = int(other[1])
            rec["other_arc_length"] = _arc(d, idx, f, other[1], p, L, n)
        out.append(rec)
    return out


def _arc(d, idx, f: int, i: int, p, L: float, n: int) -> float:
    """Arc length over ``l`` of the point of link ``i`` of finger ``f`` nearest the world point ``p``."""
    b = int(idx.link_body[f][i])
    o = np.asarray(d.xpos[b])
    t = np.asarray(d.xmat[b]).reshape(3, 3)[:, 0]
    u = float(np.clip(np.dot(np.asarray(p) - o, t) / L, 0.0, 1.0 / n))
    return float(i / n + u)

"""``method="dynamics"``: a settle that really simulates, with MuJoCo's own contact and friction.

The settle drives the over-damped integrator from a start to rest:

* **Integrator** (:mod:`simgrip.settle.integrator`, re-exported here):
  ``mjINT_DISCRETE`` at ``h = 1/omega_min``, stiffness-proportional hinge
  damping bounded below by the loads' geometric stiffness, a Grip III fall
  guard, elliptic cone with a high ``impratio``; a state penetrating more than
  :data:`DYN_PEN_LIMIT` restarts with half the step.
* **Start** (I/II): the hinge chain's grip equilibrium, the workpiece held at
  the tip (as the static solve); where that start is not valid, a closing
  with contact on, frictionless, rest angles ramped at <=
  :data:`DYN_CLOSE_RATE` rad of total rotation per step.  The holding force
  then fades out over :data:`DYN_RELEASE_STEPS` steps.
* **Stop**: the static residual at rest below ``tol`` and velocities below
  :data:`DYN_VTOL`, tested every :data:`~simgrip.settle.integrator.DYN_BATCH` steps (one ``mj_step`` call
  between tests; the residual only once the velocity is small).  Drop: the tip slips :data:`DYN_DROP_SLIP` along the face
  or the workpiece falls out of contact (I/II); Grip III: the workpiece falls away (out of contact, moving
  down, a corner with no link it is paired with beneath it:
  :func:`~simgrip.sim.workpiece_motion.corners_over_fingers`), however far it sank while a corner carried it.
  Then the finger settles alone.  A drop the static settle from the same start does not share carries a
  warning that says why (:func:`drop_warning`: MuJoCo's surface contact couple, or the flow's path).
"""

from __future__ import annotations

import copy
import dataclasses
import math
import time

import mujoco
import numpy as np

from simgrip.settle import closing
from simgrip.settle.closing import start_free, start_on_chain
# the integrator's names are importable from here too (simgrip.settle.dynamics.Dyn, DYN_STEP, ...)
from simgrip.settle.integrator import (DYN_BATCH, DYN_DAMPING, DYN_FALL_STEP, DYN_IMPRATIO, DYN_STEP,  # noqa: F401
                                       DYN_TIMECONST, DYN_WORKPIECE_DAMPING, Dyn, geometric_stiffness_bound,
                                       lowest_frequency, run_to_rest)
from simgrip.settle.state import SettledState, SettleError, read_state
from simgrip.settle.statics import restore_options, save_options
from simgrip.sim.scene import Scene, set_curvature
from simgrip.sim.workpiece_motion import corners_over_fingers, lower_onto_fingers, slip_coordinate

__all__ = ["DYN_TOL", "DYN_TOL_PER_WEIGHT", "Dyn", "drop_warning", "dynamics_tolerance", "settle_dynamics"]

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
#: Grips I/II (and the K-finger dynamics): fall (over l) of the workpiece after release that counts as a drop
#: even while the tip still brushes it.  Grip III has no such threshold: a corner that carries the workpiece
#: may sink with a soft, loaded finger; it is dropped when it falls away (corners_over_fingers).
DYN_DROP_FALL = 0.2
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



def _finger_pairs_touching(scene: Scene) -> bool:
    d = scene.data
    mine = set(int(g) for f in range(scene.fingers) for g in scene.contact_geoms[f])
    wg = set(int(g) for g in scene.workpiece_geoms)
    return any((int(d.contact.geom1[i]) in mine and int(d.contact.geom2[i]) in wg) for i in range(d.ncon))


def _descending(scene: Scene, wz_dof) -> bool:
    """Whether the workpiece moves down faster than the settle's rest tolerance :data:`DYN_VTOL` (l per
    sqrt(l/g)) along its ``z`` slide (``wz_dof``: that dof, or none when it has no such joint)."""
    if not wz_dof:
        return False
    v = float(scene.data.qvel[wz_dof[0]]) / math.sqrt(scene.length * scene.physical.g)
    return v < -DYN_VTOL


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


def _static_verdicts(scene: Scene, q_start, saved, settle, ls_iterations: int) -> dict:
    """Whether the static settle ``settle`` (:func:`simgrip.settle.settle`) holds the workpiece from the dynamics'
    start ``q_start``: ``{"point": held, "surface": held}`` (``None``: that settle raised :class:`SettleError`;
    ``"surface"`` only where the point contact holds).  Each settle runs on a copy of the model with the options
    ``saved`` before the dynamics changed them, ``ls_iterations`` the line-search cap among them (the scene's own
    model and data are left as the dynamics leaves them)."""
    out = {}
    for contact in ("point", "surface"):
        m = copy.copy(scene.model)
        restore_options(m, saved)
        m.opt.ls_iterations = ls_iterations
        chk = dataclasses.replace(scene, model=m, data=mujoco.MjData(m))
        chk.data.qpos[:] = q_start
        mujoco.mj_forward(m, chk.data)
        try:
            out[contact] = bool(settle(chk, contact=contact).held)
        except SettleError:
            out[contact] = None
        if not out["point"]:
            break
    return out


def drop_warning(scene: Scene, verdicts: dict) -> str | None:
    """The warning of a dynamics drop given the static settle's :func:`_static_verdicts` (None: they drop too).

    The dynamics has MuJoCo's surface contact: the friction acts on the geoms' surface, ``r`` off the
    centreline (``r_tip``, Grips I/II; ``r_link``, III), and adds a couple ``r f`` that the point contact
    (the default settle's and the BVP's) leaves out; under a heavy load that couple alone can decide the
    verdict.  Where the static settle with ``contact="surface"`` holds too, the workpiece was lost on the
    over-damped flow's way from the start (a path whose damping is chosen for speed), not at an equilibrium.
    """
    if not verdicts.get("point"):
        return None
    r = scene.r_tip if scene.grip in ("I", "II") else scene.r_link
    head = "dropped by the dynamics where the static settle (point contact) holds: "
    if verdicts.get("surface") is False:
        return head + (f"the static settle with MuJoCo's surface contact (contact='surface', --contact surface) "
                       f"drops it too: the friction acting r = {r:g} l off the centreline adds a couple that the "
                       f"point contact (the BVP's) leaves out, and it decides this verdict")
    if verdicts.get("surface"):
        return head + ("the static settle with MuJoCo's surface contact holds it too: the workpiece was lost on "
                       "the over-damped flow's way to rest from the start (a path, not an equilibrium)")
    return head + "the static settle with MuJoCo's surface contact did not converge"


def settle_dynamics(scene: Scene, tol: float, max_steps: int, warm_start, close: bool,
                     allow_unconverged: bool, t0: float, *, static_settle) -> SettledState:
    """Over-damped settle of ``scene`` (:func:`_settle_dynamics`); the constraint solver's line-search cap, which
    :class:`Dyn` raises to :data:`~simgrip.settle.integrator.DYN_LS_ITERATIONS`, is put back on the way out (the
    settle's own option restore does not know it)."""
    ls_iterations = int(scene.model.opt.ls_iterations)
    try:
        return _settle_dynamics(scene, tol, max_steps, warm_start, close, allow_unconverged, t0,
                                static_settle=static_settle, ls_iterations=ls_iterations)
    finally:
        scene.model.opt.ls_iterations = ls_iterations


def _settle_dynamics(scene: Scene, tol: float, max_steps: int, warm_start, close: bool,
                     allow_unconverged: bool, t0: float, *, static_settle, ls_iterations: int) -> SettledState:
    """Over-damped settle (``static_settle``: the static settle that judges a drop, :func:`simgrip.settle.settle`,
    handed down by it: the package imports this module, so this module does not import it back); the time step halves (from the start) while penetration >= DYN_PEN_LIMIT,
    or a contact tunnels (the tip sphere wholly inside the face, the corner across the rod's axis:
    the run stops there),
    and once when the workpiece drops: a drop counts when it happens at two time steps ``h`` and
    ``h/2`` (a heavy workpiece on a soft finger can start a growing two-step oscillation of the contact
    at ``h = 1/omega_min`` that throws it off the tip; at ``h/2`` it holds)."""
    d = scene.data
    q0 = d.qpos.copy()
    saved = save_options(scene.model)  # for the static settles that check a drop (_static_verdicts)
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
    if not state.held and (dropped or first_drop is not None):
        # a drop is checked against the static settle from the same start: a disagreement says why
        why = drop_warning(scene, _static_verdicts(scene, q0, saved, static_settle, ls_iterations))
        if why:
            state.warnings.append(why)
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

            wz_dof = [dof for name, dof in zip(scene.workpiece_joints, scene.workpiece_dof) if name == "z"]

            def watch():
                if scene.grip == "III":
                    # carried while a corner touches the rod (however far the workpiece has come down: a
                    # heavy one sinks with the finger it loads); out of contact it is caught again while
                    # each corner has its finger beneath it, and falls away once one has none and it
                    # moves down (a weightless workpiece left hovering has not fallen)
                    if (not _finger_pairs_touching(scene) and _descending(scene, wz_dof)
                            and not corners_over_fingers(scene)):
                        return "lost contact"
                else:
                    drop = (z0 - float(d.xpos[scene.workpiece_body][2])) / scene.length
                    if drop > DYN_DROP_FALL or (drop > DYN_DROP_SLIP and not _finger_pairs_touching(scene)):
                        return "lost contact"  # out of contact
                    if abs(slip_coordinate(scene) - s0) > DYN_DROP_SLIP:
                        return "slipped"
                if _deepest_contact(scene) > tunnel:
                    return "tunnelled"
                return None

            # tunnelled: the tip sphere wholly inside the face (I/II), the corner across the rod's axis (III)
            tunnel = scene.length * (2.0 * scene.r_tip if scene.grip in ("I", "II")
                                     else scene.r_link + scene.r_corner)
            converged, why = dyn.run(tol, vtol, max_steps, watch)
            if converged and not _finger_pairs_touching(scene):
                # at rest and touching no finger (a weightless workpiece left where it was): nothing holds it
                why = "lost contact"
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

"""The settle of a full-contact K-finger gripper (``build_gripper(..., contact="full")``): every link touches.

The planar full-contact settle's three phases (:mod:`simgrip.settle.full_contact`) on the K-finger dynamics
(:class:`~simgrip.gripper.dynamics.GripperDynamics`, with a damping ``factor`` for the guard:
:class:`FullGripperDynamics`): a frictionless closing ramp of every finger's rest angles from the straight
start with the workpiece held where it was built (below the palm), a release with friction, the workpiece
dropped when it falls :data:`~simgrip.settle.dynamics.DYN_DROP_FALL` (or
:data:`~simgrip.settle.dynamics.DYN_DROP_SLIP` out of contact), and MuJoCo's static balance as the judge.
Every step is guarded (:class:`~simgrip.settle.full_guard.GuardedSteps`): no link passes through another,
through another finger or through the workpiece between two steps.
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from simgrip.settle.dynamics import DYN_CLOSE_RATE, DYN_DROP_FALL, DYN_DROP_SLIP, DYN_RELEASE_STEPS
from simgrip.settle.full_contact import FULL_CLOSE_RATE_PER_RADIUS, FULL_PEN_LIMIT, contact_solref, ramp_rate
from simgrip.settle.full_guard import GuardedSteps
from simgrip.gripper.dynamics import GripperDynamics
from simgrip.gripper.state import GripperState, read_gripper_state
from simgrip.settle.state import SettleError
from simgrip.settle.statics import CONTACT_IMPEDANCE, restore_options, save_options
from simgrip.sim.full_contact import colliding_geoms

__all__ = ["FullGripperDynamics", "settle_gripper_full"]

#: Static residual at which the frictionless closing hands over to the release (over rho g l^2 / rho g l).
FULL_CLOSE_TOL = 1e-2
#: Damping factor on a held workpiece's dofs (:meth:`FullGripperDynamics.update_damping`).
FULL_HELD_DAMPING = 1e8
#: Physics steps allowed to a full-contact gripper settle by default.
FULL_GRIPPER_STEPS = 40_000


class FullGripperDynamics(GripperDynamics):
    """:class:`GripperDynamics` whose hinge and workpiece-translation damping carry a guard ``factor`` (>= 1)."""

    def __init__(self, scene, step_factor: float = 1.0):
        self.factor = 1.0
        super().__init__(scene, step_factor)
        self.wt = np.asarray(scene.workpiece_dof[:3])
        self.wt_damping = self.m.dof_damping[self.wt].copy()
        self.wr = np.asarray(scene.workpiece_dof[3:])
        self.wr_damping = self.m.dof_damping[self.wr].copy()

    def update_damping(self) -> None:
        super().update_damping()
        if getattr(self, "wt", None) is not None:
            self.m.dof_damping[self.hinge] *= self.factor
            # held: the pose is put back after each step, so a contact that pushed the workpiece instead of the
            # finger would undo nothing (a fingertip under a held sphere sank on); damping far above the fingers'
            # (their hinges' h D ~ h^2 K factor) makes MuJoCo's contact solve move the finger
            held = FULL_HELD_DAMPING if self.held_q is not None else 1.0
            self.m.dof_damping[self.wt] = self.wt_damping * self.factor * held
            self.m.dof_damping[self.wr] = self.wr_damping * held


def settle_gripper_full(scene, *, tol: float, max_steps: int | None = None,
                        allow_unconverged: bool = False) -> GripperState:
    """Settle a full-contact gripper (see the module docstring); ``tol`` over ``rho g l^2`` / ``rho g l``;
    ``max_steps`` physics steps (default :data:`FULL_GRIPPER_STEPS`).  Raises :class:`SettleError` when it does
    not converge unless ``allow_unconverged``.  The state's ``contact_set`` lists every contact
    (:func:`gripper_contact_set`) and its ``records`` are each finger's resultant (:func:`whole_finger_records`)."""
    if getattr(scene, "contact", "pairs") != "full":
        raise ValueError("contact: settle_gripper_full needs a gripper built with contact='full'")
    budget = FULL_GRIPPER_STEPS if max_steps is None else int(max_steps)
    t0 = time.perf_counter()
    m, d = scene.model, scene.data
    saved = save_options(m)
    geoms = (m.geom_solref.copy(), m.geom_solimp.copy(), m.geom_condim.copy(), m.geom_contype.copy(),
             m.geom_conaffinity.copy())
    gs = colliding_geoms(m)
    try:
        d.qvel[:] = 0.0
        d.qfrc_applied[:] = 0.0
        mujoco.mj_forward(m, d)
        dyn = FullGripperDynamics(scene)
        m.geom_solref[gs] = contact_solref(scene, dyn.h)
        m.geom_solimp[gs, 0] = CONTACT_IMPEDANCE
        m.geom_solimp[gs, 1] = CONTACT_IMPEDANCE
        guard = GuardedSteps(scene, dyn)
        wb = scene.workpiece_body
        tunnel = scene.r_link * scene.length
        # 1. closing, frictionless, the workpiece held
        dyn.hold(True)
        rest = np.stack([sp.rest for sp in scene.finger_springs]) if scene.finger_springs else \
            np.broadcast_to(scene.springs.rest, (scene.fingers, scene.n))
        m.geom_condim[gs] = 1
        converged, why = True, "ok"
        try:
            total = float(np.max(np.sum(np.abs(rest), axis=1)))
            rate = min(DYN_CLOSE_RATE, FULL_CLOSE_RATE_PER_RADIUS * scene.r_link)
            frac = 0.0
            while frac < 1.0 and dyn.steps < budget:
                frac = min(1.0, frac + rate / max(total, 1e-300))
                m.qpos_spring[scene.joint_qpos] = rest * frac
                guard.step()
                if _deepest(d) > tunnel:
                    raise SettleError("full-contact gripper settle tunnelled while closing")
                rate = ramp_rate(rate, guard, _deepest(d), tunnel)
            # the frictionless closing only brings the fingers onto the workpiece: near rest is enough (a finger
            # on a round workpiece creeps along it frictionless), the release with friction settles to tol
            converged, why = guard.run(max(tol, FULL_CLOSE_TOL), budget, vtol=math.inf)
        finally:
            m.qpos_spring[scene.joint_qpos] = rest
            m.geom_condim[gs] = 3
        # 2. release with friction
        held = converged and _touching(scene)
        if held:
            z0 = float(d.xpos[wb][2])
            dyn.held_q = None
            weight = scene.workpiece_mass * scene.physical.g
            for i in range(1, DYN_RELEASE_STEPS + 1):
                d.qfrc_applied[scene.workpiece_dof[2]] = scene.weight_relief + weight * (1.0 - i / DYN_RELEASE_STEPS)
                guard.step()
            dyn.hold(False)

            def watch():
                fall = (z0 - float(d.xpos[wb][2])) / scene.length
                if fall > DYN_DROP_FALL or (fall > DYN_DROP_SLIP and not _touching(scene)):
                    return "lost contact"
                return "tunnelled" if _deepest(d) > tunnel else None

            converged, why = guard.run(tol, budget, watch)
            if why == "tunnelled":
                raise SettleError("full-contact gripper settle tunnelled (a contact deeper than a link's radius)")
            if why == "lost contact":
                held, converged = False, True
        if not held and converged:
            dyn.hold(True)  # park the workpiece, out of contact; the fingers settle alone, still touching
            m.geom_contype[scene.workpiece_geom] = m.geom_conaffinity[scene.workpiece_geom] = 0
            converged, why = guard.run(tol, budget)
        state = read_gripper_state(scene, dyn, held, converged, dyn.steps, t0, tol)
        state.penetration = max(state.penetration, _deepest(d) / scene.length)
        state.method = "dynamics"
        state.contact = "full"
        state.contact_set = gripper_contact_set(scene)
        if held:  # every contact, not the tips' alone: each finger's resultant and the workpiece's balance
            state.records = whole_finger_records(scene, state)
            on_wp = [c for c in state.contact_set if c["with"] == "workpiece"]
            centre = np.asarray(state.workpiece_position, dtype=float)
            f = -np.sum([c["force"] for c in on_wp], axis=0) if on_wp else np.zeros(3)
            mom = sum((np.cross(np.asarray(c["point"]) - centre, -np.asarray(c["force"])) for c in on_wp),
                      np.zeros(3))
            state.force_balance = f - np.array([0.0, 0.0, scene.workpiece_mass * scene.physical.g / scene.force_scale])
            state.moment_balance = mom
        if state.penetration > FULL_PEN_LIMIT:
            state.warnings.append(f"full contact: a contact {state.penetration:.3g} l deep (above {FULL_PEN_LIMIT:g} l)")
        if not state.converged and not allow_unconverged:
            raise SettleError(f"full-contact gripper settle did not converge ({why} after {dyn.steps} steps, "
                              f"residual {state.residual:.3g}, tolerance {tol:.3g})")
    finally:
        restore_options(m, saved)
        (m.geom_solref[:], m.geom_solimp[:], m.geom_condim[:], m.geom_contype[:], m.geom_conaffinity[:]) = geoms
        d.qfrc_applied[:] = 0.0
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
    return state


def whole_finger_records(scene, state) -> list:
    """Each touching finger's :class:`~simgrip.gripper.state.FingerRecord` as the resultant of all its
    contacts with the workpiece (``state.contact_set``), not the tip's alone: ``N1, N2, N3`` the summed force in
    the finger's frame, ``normal = N1`` and ``friction = N2`` (the Grip I/II reading: ``E1`` is the normal of a
    side face), ``contact_angle`` 0, ``point`` the force-weighted mean contact point ``(X, Y, out of plane)``,
    ``moment`` 0 (several contact points have no one couple about the tip), ``required_mu`` ``sqrt(N2^2 +
    N3^2) / N1``."""
    from simgrip.gripper.state import FingerRecord

    out = []
    for k in range(scene.fingers):
        mine = [c for c in state.contact_set if c["finger"] == k and c["with"] == "workpiece"]
        if not mine:
            continue
        R = scene.frame(k)
        F = R @ np.sum([c["force"] for c in mine], axis=0)
        w = np.array([max(float(np.linalg.norm(c["force"])), 1e-300) for c in mine])
        pt = R @ (np.asarray([c["point"] for c in mine]).T @ w / w.sum())
        N1, N3, N2 = (float(v) for v in F)
        out.append(FingerRecord(
            finger=k, N1=N1, N2=N2, N3=N3, normal=N1, friction=N2, contact_angle=0.0,
            tip=np.asarray(state.tip[k]).copy(), point=np.array([pt[0], pt[2], pt[1]]), moment=0.0,
            penetration=max(c["depth"] for c in mine),
            required_mu=math.hypot(N2, N3) / N1 if N1 > 0 else math.inf))
    return out


def gripper_contact_set(scene) -> list[dict]:
    """Every contact on a finger of a gripper scene (over ``l`` and ``rho g l``, the scene's frame): ``finger``,
    ``link``, ``arc_length``, ``with`` (``"workpiece"``, ``"self"``, ``"finger K"``), ``point`` ``[x, y, z]``,
    ``normal`` (unit, pushing this finger), ``normal_force``, ``friction_force`` (the tangential force's
    magnitude), ``force`` ``[x, y, z]`` on this finger and ``depth``."""
    m, d = scene.model, scene.data
    L, W, n = scene.length, scene.force_scale, scene.n
    idx = scene.index
    where = {}
    for f in range(scene.fingers):
        for i, g in enumerate(idx.link_geom[f]):
            where[int(g)] = (f, i)
        if idx.tip_geom[f] >= 0:
            where[int(idx.tip_geom[f])] = (f, n - 1)
    out, fc = [], np.zeros(6)
    for c in range(d.ncon):
        a, b = where.get(int(d.contact.geom1[c])), where.get(int(d.contact.geom2[c]))
        if a is None and b is None:
            continue
        mujoco.mj_contactForce(m, d, c, fc)
        frame = np.asarray(d.contact.frame[c]).reshape(3, 3)
        on2 = frame.T @ fc[:3]  # on geom2
        mine, other, force, normal = (a, b, -on2, -frame[0]) if a is not None else (b, a, on2, frame[0])
        f, i = mine
        p = np.asarray(d.contact.pos[c])
        body = int(idx.link_body[f][i])
        u = float(np.clip(np.dot(p - d.xpos[body], np.asarray(d.xmat[body]).reshape(3, 3)[:, 0]) / L, 0.0, 1.0 / n))
        out.append({
            "finger": int(f), "link": int(i), "arc_length": i / n + u,
            "with": "workpiece" if other is None else ("self" if other[0] == f else f"finger {other[0]}"),
            "point": [float(v / L) for v in p], "normal": [float(v) for v in normal],
            "normal_force": float(fc[0] / W), "friction_force": float(math.hypot(fc[1], fc[2]) / W),
            "force": [float(v / W) for v in force], "depth": float(max(0.0, -float(d.contact.dist[c])) / L),
        })
    return out


def _touching(scene) -> bool:
    d, w = scene.data, scene.workpiece_geom
    return any(int(d.contact.geom1[i]) == w or int(d.contact.geom2[i]) == w for i in range(d.ncon))


def _deepest(d) -> float:
    return max((-float(d.contact.dist[i]) for i in range(d.ncon)), default=0.0)

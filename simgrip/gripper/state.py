"""The K-finger gripper's settled state (:class:`GripperState`, one :class:`FingerRecord` per finger) and its reading.

:func:`read_gripper_state` reads a state at rest from MuJoCo: the hinge
angles and the tips from the joint angles (:func:`simgrip.chain.link_positions`),
each finger's contact force (``mj_contactForce``, summed over the tip's
contacts with the workpiece) in the finger's own frame like the planar
finger, and the workpiece's force and moment balance from the same forces
and its weight.  The static residual and the velocity are the dynamics'
(:class:`simgrip.gripper.dynamics.GripperDynamics`).  Lengths are over
``l``, forces over ``rho g l``, moments over ``rho g l^2``.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import mujoco
import numpy as np

from simgrip.chain import link_positions
from simgrip.gripper.scene import GripperScene

__all__ = ["FRICTION_MARGIN", "warn_friction_boundary", "FingerRecord", "GripperState", "read_gripper_state"]


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


#: A hold this close to the friction cone (relative: ``required_mu >= (1 - FRICTION_MARGIN) mu_s``) is the
#: threshold, where the methods' friction models may differ (:func:`warn_friction_boundary`; the same margin
#: as the planar agreement check, :data:`simgrip.harness.agreement.MARGIN`).
FRICTION_MARGIN = 0.02


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
    #: Seconds to build and compile the model (:func:`simgrip.gripper.simulate_gripper`);
    #: ``wall_time_s`` is the settle alone.  None when the state was settled from a scene built elsewhere.
    build_time_s: float | None = None
    #: Every finger's tip on its grip's side of the palm (:func:`simgrip.validity.check_grip_shape`).
    grip_matched: bool = True
    #: Grip III: the rod beyond the contact stays below the workpiece (condition (23),
    #: :func:`simgrip.validity.check_condition_23`, read from the planar state the cradle replicates); a held
    #: state with ``tip_clear`` False is not feasible (:func:`simgrip.gripper.gripper_record`), as the planar one.
    tip_clear: bool = True
    #: A physical state: no finger through itself, another finger or the workpiece
    #: (:func:`simgrip.validity_shapes.check_gripper_valid`); False: ``held`` is False and ``warnings`` says why.
    valid: bool = True
    #: Conditions the state violates that the settle does not enforce (e.g. the other grip's shape).
    warnings: list = field(default_factory=list)
    #: The scene's workpiece offset (over l, scene frame) and turn about its axis [rad] (:func:`build_gripper`).
    offset: np.ndarray = field(default_factory=lambda: np.zeros(2))
    workpiece_yaw: float = 0.0
    #: How it was settled: ``"dynamics"`` or ``"symmetric"`` (:mod:`simgrip.gripper.symmetry`).
    method: str = "dynamics"
    #: Where the sticking friction acts: ``"surface"`` (MuJoCo's contact point on the tip sphere; the
    #: dynamics) or ``"point"`` (the finger's centreline, the paper's point contact; the skip's default).
    contact: str = "surface"
    #: Each finger's centreline in the scene's frame, (K, n + 1, 3) over ``l`` (:func:`simgrip.gripper.simulate_gripper`
    #: fills it from the scene; None when the state was settled from a scene elsewhere).
    nodes: np.ndarray | None = field(default=None, repr=False)
    #: Every contact on a finger (:func:`simgrip.gripper.full.gripper_contact_set`): filled by the
    #: full-contact settle (``contact="full"``); None otherwise (the tips' contacts are ``records``).
    contact_set: list | None = None


def read_gripper_state(scene: GripperScene, dyn, held: bool, converged: bool, steps: int, t0: float,
                       tol: float) -> GripperState:
    """The settled state at rest (``qvel = 0``) from MuJoCo's contact forces.

    ``dyn`` is the settle's :class:`~simgrip.gripper.dynamics.GripperDynamics` (its residual,
    velocity and step ``h`` [s]); ``held`` whether the workpiece is held (no records when not);
    ``converged`` the run's verdict, further required ``residual <= tol`` (``tol`` over ``rho g l^2`` /
    ``rho g l``); ``steps`` the physics steps taken; ``t0`` the ``time.perf_counter()`` [s] at the
    settle's start (for ``wall_time_s``).  Sets ``qvel = 0`` on the scene's data.
    """
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


def warn_friction_boundary(scene, state: GripperState) -> None:
    """Warnings where the hold is at the friction cone's boundary, where the methods may disagree.

    A held state whose largest ``required_mu`` (the paper's frame at the contact) is within
    :data:`FRICTION_MARGIN` of ``mu_s`` or beyond (a sticking contact saturated in
    MuJoCo's contact frame, whose normal at a Grip III corner is not the rod's), and ``M = 0`` with
    ``mu_s = 0``:

    A weightless workpiece needs no friction and a frictionless contact has none: ``|F_f| = mu_s N = 0``.
    The paper's criterion ``|F_f| <= mu_s N`` counts it feasible (the BVP's verdict), the point-contact
    Newton settle drops it, and the dynamics holds or loses it on round-off (nothing resists a sideways
    or vertical drift): the methods may answer differently, and the state says why.
    """
    p = scene.params
    mu = float(p.mu_s)
    if state.held and mu > 0.0:
        need = max((r.required_mu for r in state.records), default=0.0)
        if need >= (1.0 - FRICTION_MARGIN) * mu:
            state.warnings.append(
                f"held at the friction cone's edge: a contact needs mu = {need:.4g} of mu_s = {mu:g} (within "
                f"{FRICTION_MARGIN:.0%} or beyond; the record's frame: the rod's at a Grip III corner, else the "
                f"contact's); there the settles' friction models "
                f"(a sticking contact saturated in MuJoCo's contact frame, MuJoCo's soft cone that creeps) and "
                f"the BVP's |f| <= mu_s n may give different verdicts")
    if float(p.M) == 0.0 and mu == 0.0:
        state.warnings.append("M = 0 with mu_s = 0: the workpiece needs no friction and has none (|F_f| = mu_s N = 0, "
                              "the friction cone's boundary); the hold is neutral, so the settles and the BVP "
                              "(which counts the boundary as feasible) may give different verdicts")

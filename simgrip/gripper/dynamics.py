"""The over-damped MuJoCo dynamics of a K-finger gripper scene (:mod:`simgrip.gripper.scene`).

:class:`GripperDynamics` sets the planar ``settle(method="dynamics")``'s
integrator (:mod:`simgrip.settle.integrator`, whose constants it uses) on the
gripper's model: ``mjINT_DISCRETE``, time step ``h = 1/omega_min`` of the
straight hinge chains (:func:`straight_frequency`, as the planar settle's
from its built, straight scene), hinge damping ``h max(K, R)`` with ``R``
the loads' geometric stiffness bound (each finger carrying ``M``, its share
of the weight ``K M``), elliptic cone with ``impratio``
:data:`~simgrip.settle.integrator.DYN_IMPRATIO`, contact time constant
:data:`~simgrip.settle.integrator.DYN_TIMECONST` ``h``.  The workpiece's free
joint is damped ``3 m / h`` in translation and ``3 I / h`` in rotation (its
principal inertia; the rotational dofs are in its body frame).  The caller
saves and restores the model's options.

:func:`settle_once` releases the workpiece from the start and runs to rest,
dropping it (parked, contact off, the fingers settling alone from the
chain's free shape) when a tip slides
:data:`~simgrip.settle.dynamics.DYN_DROP_SLIP` over its surface or it falls
:data:`~simgrip.settle.dynamics.DYN_DROP_FALL`.
:func:`contact_rest_depth` is how deep MuJoCo's soft contact rests under a
normal force at this integrator's step (the start seats the tips there,
:mod:`simgrip.gripper.start`).

The static residual is ``qfrc_smooth + qfrc_constraint`` at ``qvel = 0``
over ``rho g l^2`` (hinges, workpiece rotation) and ``rho g l`` (workpiece
translation): the workpiece's translation rows are its force balance
(contact forces plus weight) and its rotation rows its moment balance.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from simgrip.settle.dynamics import DYN_DROP_FALL, DYN_DROP_SLIP, DYN_VTOL
from simgrip.settle.integrator import (DYN_DAMPING, DYN_IMPRATIO, DYN_LS_ITERATIONS, DYN_STEP, DYN_TIMECONST,
                                       DYN_WORKPIECE_DAMPING, geometric_stiffness_bound, lowest_frequency, run_to_rest)
from simgrip.gripper.rest_depth import contact_rest_depth  # re-exported (__all__)
from simgrip.gripper.start import finger_chain
from simgrip.params import Grip
from simgrip.settle.state import SettleError
from simgrip.settle.statics import CONTACT_IMPEDANCE, check_warnings
from simgrip.gripper.scene import GripperScene

__all__ = ["GripperDynamics", "contact_rest_depth", "settle_once", "straight_frequency"]


class GripperDynamics:
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
        m.opt.ls_iterations = max(int(m.opt.ls_iterations), DYN_LS_ITERATIONS)  # as the planar Dyn (integrator.py)
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

        As the planar dynamics' (:func:`simgrip.settle.integrator.geometric_stiffness_bound`: MuJoCo's step
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
        """Largest scaled speed: hinges in rad, the workpiece in ``l``, per ``sqrt(l/g)`` (0 on a held workpiece)."""
        v = np.abs(np.array(self.d.qvel)) / self.vscale
        if self.held_q is not None:
            v[self.scene.workpiece_dof] = 0.0
        return float(np.max(v))

    def hold(self, on: bool) -> None:
        """Hold the workpiece where it is (pose reset after each step, weight cancelled) or let go (its true weight,
    ``K M``, on the fingers)."""
        sc, d = self.scene, self.d
        d.qfrc_applied[:] = 0.0
        # the model's workpiece may be heavier than its weight (an inertia floor, GripperScene.weight_relief)
        d.qfrc_applied[sc.workpiece_dof[2]] = sc.weight_relief
        if on:
            d.qfrc_applied[sc.workpiece_dof[2]] += sc.workpiece_mass * sc.physical.g
        self.held_q = np.array(d.qpos[sc.workpiece_qpos]) if on else None

    def step(self, k: int = 1) -> None:
        """``k`` physics steps; a held workpiece is put back; a non-finite state raises :class:`SettleError`."""
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


def _frictionless_faces(scene: GripperScene) -> bool:
    """A weight on vertical faces without friction: nothing can carry it (dropped without stepping).

    Box and cylinder faces are vertical, so the contact normals are horizontal; with ``mu_s = 0`` no
    contact force has a vertical component and a workpiece of weight ``M > 0`` falls.  Stepping it there
    took longer than the step budget for a stiff finger (D = 1e4: the over-damped slide at the stiff
    chain's short step), so it is decided here, as statics decides it.
    """
    p = scene.params
    return scene.workpiece in ("box", "cylinder") and float(p.mu_s) == 0.0 and float(p.M) > 0.0


def _tips_on_workpiece(scene: GripperScene) -> np.ndarray:
    """Every tip's centre in the workpiece's body frame [m], (K, 3)."""
    d = scene.data
    wb = scene.workpiece_body
    rot = np.asarray(d.xmat[wb]).reshape(3, 3)
    return (np.asarray(d.geom_xpos[scene.tip_geom]) - np.asarray(d.xpos[wb])) @ rot


def _touching(scene: GripperScene) -> bool:
    """Whether any tip touches the workpiece (a MuJoCo contact between them)."""
    d = scene.data
    tips = set(int(g) for g in scene.tip_geom)
    return any(int(d.contact.geom1[i]) in tips and int(d.contact.geom2[i]) == scene.workpiece_geom
               for i in range(d.ncon))


def settle_once(scene: GripperScene, dyn: GripperDynamics, tol: float, budget: int, reach: bool) -> tuple[bool, bool, str]:
    """Release the held workpiece and settle; ``(held, converged, reason)``.

    ``reach``: the fingers start on the workpiece (else they settle alone).
    """
    m, d = scene.model, scene.data
    converged, why = True, "ok"
    held = reach and _touching(scene) and not _frictionless_faces(scene)
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
            free = finger_chain(scene, Grip.FREE, finger=k)
            if free is not None:
                d.qpos[scene.joint_qpos[k]] = free.joint_angles
        d.qvel[:] = 0.0
        converged, why = dyn.run(tol, budget)
    return held, converged, why

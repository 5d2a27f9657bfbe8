"""How deep MuJoCo's soft contact rests under a normal force in the K-finger dynamics (one law, two users).

:func:`contact_rest_depth` evaluates the law with the damping and step of
:class:`simgrip.gripper.dynamics.GripperDynamics`; the start
(:mod:`simgrip.gripper.start`) seats the tips at that depth and the dynamics
re-exports it.  It sits here, below both, so that neither imports the other
back.
"""

from __future__ import annotations

import mujoco
import numpy as np

from simgrip.gripper.scene import GripperScene
from simgrip.settle.integrator import DYN_DAMPING, DYN_TIMECONST, DYN_WORKPIECE_DAMPING, geometric_stiffness_bound

__all__ = ["contact_rest_depth"]


def contact_rest_depth(scene: GripperScene, N1, timestep: float) -> np.ndarray:
    """How deep (over l) MuJoCo's soft contact rests under normal forces ``N1`` (over rho g l) in the dynamics.

    MuJoCo's contact is a constraint with reference acceleration ``-k r`` (``k = 1/(d tc)^2``, ``tc =
    DYN_TIMECONST h``, impedance ``d`` -> 1) acting through the inverse of the step's metric
    ``M + h D + h^2 K`` (``mjINT_DISCRETE``): at rest a normal force ``N`` sinks the contact by
    ``r = N tc^2 A_nn``, ``A_nn = n J (M + h D + h^2 K)^{-1} J^T n`` the contact's mobility along its
    normal (MuJoCo's ``efc_diagA``), the tip's and the workpiece's.  Evaluated at the scene's current
    state (its contacts' normals; a finger out of contact: its ``E1``) with the damping the dynamics
    sets there (:class:`GripperDynamics`: hinges ``h max(K, R)`` with each finger carrying ``M``, the workpiece
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

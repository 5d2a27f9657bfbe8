"""The MuJoCo models of the K-finger pick environment, built on simgrip's fingers, gripper pieces and pairs.

:func:`build_pick_multi_model` loads ``models/pick_scene.xml`` (options,
table, palm, light, cameras) with :class:`mujoco.MjSpec`, removes its box and
adds, in code:

* the palm's vertical slide and position servo, as the two-finger pick model
  does (:mod:`simgrip.envs.pick_model`);
* ``K`` fingers under the palm, built by
  :func:`simgrip.sim.fingers.add_fingers` (the hinge chain of every simgrip
  scene) and turned to the azimuths ``2 pi k / K`` by
  :func:`simgrip.gripper.scene.orient_fingers`, exactly as
  :func:`simgrip.gripper.scene.build_gripper` places them: finger ``k`` bends
  in its own vertical plane;
* the workpiece on a free joint: a box (faces normal to the fingers' planes
  at zero yaw), a cylinder with a vertical axis, or a sphere; its inertia is
  :func:`simgrip.sim.workpiece.workpiece_inertia`;
* a camera ``gripper`` looking down at the grip from the front right;
* the explicit contact pairs: each finger's tip and links (but the last,
  whose end is the tip sphere) with the workpiece (condim 4), the palm slab
  with the workpiece, the workpiece with the table.

A geom's type cannot change in a compiled model, so the environment holds one
model per workpiece shape (all with the same fingers, palm and addresses of
the fingers) and resizes the workpiece per episode (:func:`set_workpiece`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from simgrip.chain import chain_springs
from simgrip.envs.pick_model import FINGER_PREFIX, PICK_SOLIMP, PICK_SOLREF, hand_spec, resize_workpiece
from simgrip.profiles import Uniform
from simgrip.sim.contacts import add_pair
from simgrip.sim.fingers import FingerIndex, check_finger_links, index_fingers
from simgrip.gripper.scene import finger_azimuths, orient_fingers
from simgrip.sim.workpiece import workpiece_inertia

__all__ = ["GEOM_TYPES", "PickMultiModel", "build_pick_multi_model", "half_height", "set_workpiece", "workpiece_size"]

#: MuJoCo geom type of each workpiece shape.
GEOM_TYPES = {"box": mujoco.mjtGeom.mjGEOM_BOX, "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
              "sphere": mujoco.mjtGeom.mjGEOM_SPHERE}


@dataclass
class PickMultiModel:
    """One compiled K-finger pick model and the addresses the environment reads.

    Attributes
    ----------
    shape : {"box", "cylinder", "sphere"}
    spec, model
    fingers : FingerIndex
        The ``K`` fingers (``n`` links each).
    azimuths : ndarray (K,)
        Azimuth of each finger's plane [rad], ``2 pi k / K``.
    palm_qpos, palm_dof : int
    work_qpos, work_dof, work_body, work_geom : int
        The workpiece's free joint (7 qpos, 6 dofs), body and geom.
    finger_pairs : ndarray
        Ids of the finger-workpiece pairs (their friction is the episode's).
    unit_rest : ndarray (n,)
        Rest angles of a finger per unit of uniform curvature.
    """

    shape: str
    spec: mujoco.MjSpec
    model: mujoco.MjModel
    fingers: FingerIndex
    azimuths: np.ndarray
    palm_qpos: int
    palm_dof: int
    work_qpos: int
    work_dof: int
    work_body: int
    work_geom: int
    finger_pairs: np.ndarray
    unit_rest: np.ndarray


def workpiece_size(shape: str, width: float, height: float) -> np.ndarray:
    """MuJoCo geom size [m] of a workpiece ``width`` across (box side, cylinder or sphere diameter) and
    ``height`` tall (box, cylinder; a sphere is ``width`` tall)."""
    r = 0.5 * width
    if shape == "box":
        return np.array([r, r, 0.5 * height])
    if shape == "cylinder":
        return np.array([r, 0.5 * height, 0.0])
    return np.array([r, 0.0, 0.0])


def half_height(shape: str, size) -> float:
    """Half the height [m] of a workpiece of geom ``size`` (its centre's height when it stands on the table)."""
    return float(size[2] if shape == "box" else size[1] if shape == "cylinder" else size[0])


def build_pick_multi_model(shape: str, *, fingers: int, n_links: int, length: float, EI: float, rho: float,
                           g: float, r_tip: float, width: float, height: float, mass_max: float, friction: float,
                           spin_friction: float, timestep: float, impratio: float, damping_time: float,
                           armature: float, palm_ramp: bool = False, palm_range=(-math.inf, math.inf)
                           ) -> PickMultiModel:
    """Build and compile the K-finger pick scene with a workpiece of ``shape`` (SI units).

    ``width``, ``height`` [m] size the workpiece initially (the environment
    resizes it per episode); ``mass_max`` [kg] sizes the palm servo's damping
    (critical with the heaviest workpiece); ``friction`` is the initial
    finger-workpiece friction; ``damping_time`` [s] and ``armature`` [kg m^2]
    go to every finger hinge; ``palm_ramp``, ``palm_range``: :func:`~simgrip.envs.pick_model.hand_spec`'s.
    """
    n = check_finger_links(n_links, parent_depth=1, name="n_links")
    K = int(fingers)
    spec = hand_spec(fingers=K, n=n, length=length, EI=EI, rho=rho, g=g, r_tip=r_tip, mass_max=mass_max,
                     timestep=timestep, impratio=impratio, damping_time=damping_time, armature=armature,
                     keep_box=False, palm_ramp=palm_ramp, palm_range=palm_range)
    azimuths = finger_azimuths(K)
    orient_fingers(spec, azimuths, FINGER_PREFIX)
    size = workpiece_size(shape, width, height)
    body = spec.worldbody.add_body(name="workpiece", pos=[0.0, 0.0, half_height(shape, size)])
    body.add_freejoint(name="workpiece_free")
    body.explicitinertial = True
    body.mass = mass_max
    body.inertia = workpiece_inertia(shape, size, mass_max)
    body.add_geom(spec.find_default("pick"), name="workpiece", type=GEOM_TYPES[shape], size=list(size),
                  material="box")
    _add_camera(spec, "gripper", pos=(0.17, -0.24, 0.19), target=(0.0, 0.0, 0.08))
    soft = dict(solref=PICK_SOLREF, solimp=PICK_SOLIMP)
    pairs = []
    for f in range(K):
        geoms = [f"{FINGER_PREFIX}f{f}_tip"] + [f"{FINGER_PREFIX}f{f}_geom{i}" for i in range(n - 1)]
        for i, geom in enumerate(geoms):
            name = f"pair_f{f}_{i}"
            add_pair(spec, name, geom, "workpiece", friction, condim=4, spin=spin_friction * friction, **soft)
            pairs.append(name)
    add_pair(spec, "pair_palm_workpiece", "palm_slab", "workpiece", 0.5, spin=spin_friction * 0.5, **soft)
    add_pair(spec, "pair_workpiece_table", "workpiece", "table", 0.6, spin=spin_friction * 0.6, **soft)
    model = spec.compile()

    def ident(kind, name):
        return mujoco.mj_name2id(model, kind, name)

    palm_z = ident(mujoco.mjtObj.mjOBJ_JOINT, "palm_z")
    free = ident(mujoco.mjtObj.mjOBJ_JOINT, "workpiece_free")
    return PickMultiModel(
        shape=shape, spec=spec, model=model, fingers=index_fingers(model, K, n, FINGER_PREFIX), azimuths=azimuths,
        palm_qpos=int(model.jnt_qposadr[palm_z]), palm_dof=int(model.jnt_dofadr[palm_z]),
        work_qpos=int(model.jnt_qposadr[free]), work_dof=int(model.jnt_dofadr[free]),
        work_body=ident(mujoco.mjtObj.mjOBJ_BODY, "workpiece"), work_geom=ident(mujoco.mjtObj.mjOBJ_GEOM, "workpiece"),
        finger_pairs=np.array([ident(mujoco.mjtObj.mjOBJ_PAIR, p) for p in pairs]),
        unit_rest=chain_springs(Uniform(1.0), n).rest,
    )


def _add_camera(spec, name: str, pos, target) -> None:
    """A fixed camera at ``pos`` looking at ``target`` (world, [m]), its image's up towards ``+z``."""
    fwd = np.subtract(target, pos, dtype=float)
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    quat = np.empty(4)
    mujoco.mju_mat2Quat(quat, np.column_stack([right, up, -fwd]).ravel())  # a camera looks along its -z
    spec.worldbody.add_camera(name=name, pos=list(pos), quat=list(quat), fovy=45.0)


def set_workpiece(pm: PickMultiModel, data: mujoco.MjData, *, width: float, height: float, mass: float,
                  friction: float, spin_friction: float) -> np.ndarray:
    """Resize the workpiece of ``pm`` in place to ``width`` x ``height`` [m] (:func:`workpiece_size`), ``mass``
    [kg] and the finger pairs' friction (:func:`simgrip.envs.pick_model.resize_workpiece`: no recompilation).
    Returns the geom size [m]."""
    size = workpiece_size(pm.shape, width, height)
    resize_workpiece(pm.model, data, shape=pm.shape, geom=pm.work_geom, body=pm.work_body, pairs=pm.finger_pairs,
                     size=size, mass=mass, friction=friction, spin_friction=spin_friction)
    return size

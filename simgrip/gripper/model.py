"""The compiled K-finger model: :class:`GripperScene`, :func:`compile_gripper`, azimuths, the workpiece's mass.

What both builders share -- :func:`simgrip.gripper.scene.build_gripper`
(Grips I, II) and :func:`simgrip.gripper.cradle.build_cradle` (Grip III) --
sits here, below both, so that neither imports the other back; ``scene``
re-exports every name.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from simgrip.chain import ChainSprings
from simgrip.params import DimensionlessParams, PhysicalParams
from simgrip.profiles import CurvatureProfile
from simgrip.sim import workpiece as _workpiece
from simgrip.sim.fingers import FingerIndex, index_fingers
from simgrip.sim.scene import FingerScene

__all__ = ["GripperScene", "compile_gripper", "finger_azimuths", "orient_fingers", "workpiece_body_mass"]

_WORKPIECE_GEOM = "workpiece_geom"


@dataclass
class GripperScene(FingerScene):
    """A compiled K-finger scene and the addresses needed to read it.

    ``joint_qpos``, ``joint_dof`` (K, n) and the scales ``length``,
    ``force_scale``, ``moment_scale`` read as in the planar scene (:class:`FingerScene`).

    Attributes
    ----------
    spec, model, data : MuJoCo objects
    grip : {"I", "II"}
    workpiece : {"box", "cylinder", "sphere"}
    params : DimensionlessParams
    physical : PhysicalParams
        SI parameters the model is built in (dimensionless ones with ``l = rho = g = 1``).
    profile : CurvatureProfile
        Finger 0's profile (every finger's unless ``profiles`` differ).
    n : int
        Links per finger.
    fingers : int
        ``K``.
    springs : ChainSprings
        Dimensionless springs of finger 0 (every finger's unless ``profiles`` differ).
    index : FingerIndex
        The fingers' joint, body and geom addresses, shape (K, n).
    azimuths : ndarray (K,)
        Azimuth of each finger's plane [rad] (``yaw + 2 pi k / K``).
    yaw : float
        Rotation of the whole scene about the palm axis [rad].
    workpiece_body, workpiece_geom : int
    workpiece_qpos : ndarray (7,)
        qpos addresses of the free joint (position, then quaternion).
    workpiece_dof : ndarray (6,)
        dof addresses (translation in the world frame, then rotation in the body frame).
    size : ndarray (3,)
        Box half sizes; cylinder ``(radius, half height, 0)``; sphere ``(radius, 0, 0)`` [m].
    r_tip, r_link : float
        Radii over ``l``.
    contact_angle : float
        Sphere: elevation of the start's contact normal [rad] (0 for box and cylinder).
    offset : ndarray (2,)
        The workpiece's centre off the palm axis over ``l``, scene frame (turned by ``yaw`` in the world).
    workpiece_yaw : float
        The workpiece's turn about its vertical axis relative to the fingers [rad].
    profiles : tuple of CurvatureProfile
        Every finger's profile, (K,).
    finger_springs : tuple of ChainSprings
        Every finger's springs, (K,).
    reach : ndarray (K,)
        ``X`` over ``l`` where each finger's tip centre meets the workpiece
        (:func:`~simgrip.gripper.placement.place_fingers`; ``b/2`` when centred).
    normals : ndarray (K, 2)
        The workpiece's outward horizontal normal there, ``(along E1, along E3)`` of the finger.
    """

    spec: mujoco.MjSpec
    model: mujoco.MjModel
    data: mujoco.MjData
    grip: str
    workpiece: str
    params: DimensionlessParams
    physical: PhysicalParams
    profile: CurvatureProfile
    n: int
    fingers: int
    springs: ChainSprings
    index: FingerIndex
    azimuths: np.ndarray
    yaw: float
    workpiece_body: int
    workpiece_geom: int
    workpiece_qpos: np.ndarray
    workpiece_dof: np.ndarray
    size: np.ndarray
    r_tip: float
    r_link: float
    contact_angle: float = 0.0
    offset: np.ndarray = field(default_factory=lambda: np.zeros(2))
    workpiece_yaw: float = 0.0
    profiles: tuple = ()
    finger_springs: tuple = ()
    reach: np.ndarray | None = None
    normals: np.ndarray | None = None
    #: ``"pairs"`` (one explicit pair per tip) or ``"full"`` (every link may touch: :mod:`simgrip.sim.full_contact`).
    contact: str = "pairs"

    @property
    def tip_geom(self) -> np.ndarray:
        """Tip sphere geom ids, (K,)."""
        return self.index.tip_geom

    @property
    def workpiece_mass(self) -> float:
        """Mass of the workpiece [kg]: ``K m`` (its weight; the model's inertial mass may be larger)."""
        return self.physical.m * self.fingers

    @property
    def weight_relief(self) -> float:
        """Upward force [N] that makes the model's gravity on the workpiece its true weight ``K m g``.

        The model's workpiece has the inertial mass :func:`workpiece_body_mass` (floored for light
        workpieces); the settles apply this force to its vertical dof, so only ``K m g`` is carried.
        """
        return (float(self.model.body_mass[self.workpiece_body]) - self.workpiece_mass) * self.physical.g

    def frame(self, k: int) -> np.ndarray:
        """Finger ``k``'s frame as rows ``(E1, E3, E2)`` in world coordinates.

        ``E1`` horizontal, away from the palm axis in the finger's plane; ``E3``
        horizontal, normal to the plane (the hinge axis is ``-E3``); ``E2 = z`` up.
        A world vector ``v`` reads ``frame(k) @ v = (along E1, out of plane, up)``.
        """
        a = float(self.azimuths[k])
        return np.array([[math.cos(a), math.sin(a), 0.0], [-math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]])


# ---------------------------------------------------------------------------
# input checks


def compile_gripper(spec: mujoco.MjSpec, *, fingers: int, n: int, **fields) -> GripperScene:
    """Compile ``spec`` (``fingers`` fingers of ``n`` links named as :func:`~simgrip.sim.fingers.add_fingers`
    names them, the workpiece body ``workpiece_body`` on a free joint with its geom) into a
    :class:`GripperScene`: the finger and workpiece addresses are looked up in the compiled model, ``fields``
    are the scene's other attributes."""
    model = spec.compile()
    index = index_fingers(model, fingers, n)
    wb = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "workpiece_body")
    wj = int(model.body_jntadr[wb])
    return GripperScene(
        spec=spec, model=model, data=mujoco.MjData(model), n=n, fingers=fingers, index=index, workpiece_body=wb,
        workpiece_geom=mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, _WORKPIECE_GEOM),
        workpiece_qpos=np.arange(model.jnt_qposadr[wj], model.jnt_qposadr[wj] + 7),
        workpiece_dof=np.arange(model.jnt_dofadr[wj], model.jnt_dofadr[wj] + 6), **fields)


def finger_azimuths(fingers: int, yaw: float = 0.0) -> np.ndarray:
    """Azimuth of each finger's plane [rad]: ``yaw + 2 pi k / K``, ``k = 0 .. K-1``."""
    return yaw + 2.0 * math.pi * np.arange(int(fingers)) / int(fingers)


def orient_fingers(spec: mujoco.MjSpec, azimuths, prefix: str = "") -> None:
    """Turn the root of finger ``k`` (built by :func:`~simgrip.sim.fingers.add_fingers`, which mirrors
    finger 1) to point along ``azimuths[k]`` [rad] about the vertical; each finger then bends in its own plane."""
    for k, a in enumerate(azimuths):
        spec.body(f"{prefix}f{k}_link0").quat = _yaw_quat(float(a))


def _yaw_quat(a: float) -> list[float]:
    return [math.cos(0.5 * a), 0.0, 0.0, math.sin(0.5 * a)]


def workpiece_body_mass(phys, K: int) -> float:
    """The workpiece body's inertial mass [kg]: ``K m``, at least ``K`` :data:`MIN_WORKPIECE_MASS` ``rho l``.

    Only the inertia is floored, not the weight: the settles apply the difference of the model's gravity
    and the true weight ``K m g`` as an upward force on the workpiece (:attr:`GripperScene.weight_relief`),
    so every static balance is the true ``M``'s (``M = 0`` included).  Why a floor: MuJoCo refuses a free
    body without mass, and its soft contact rests at a depth proportional to the contact's mobility
    (:func:`simgrip.gripper.dynamics.contact_rest_depth`), which a nearly massless workpiece makes
    unbounded: the tips sank through it and the dynamics dropped every workpiece with ``M < ~1e-3``.
    """
    return _workpiece.inertial_mass(K * phys.m, K, phys.rho, phys.length)

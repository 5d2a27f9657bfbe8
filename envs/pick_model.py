"""The MuJoCo model of the pick environment, built on simgrip's own fingers and contact pairs.

``models/pick_scene.xml`` holds the world around the fingers (options, table,
box on a free joint, palm, light, cameras).  :func:`build_pick_model` loads it
with :class:`mujoco.MjSpec` and adds, in code:

* the palm's vertical slide joint and its position servo (a stiff, critically
  damped spring: a mocap body has no velocity, so fingers carried by one could
  not drag the box up by friction);
* the two mirrored fingers under the palm, built by
  :func:`simgrip.sim.fingers.add_fingers` (the same hinge chain as every
  simgrip scene: stiffness ``EI/ds``, rest angles from
  :func:`simgrip.chain.chain_springs`), with hinge damping and armature, link
  capsules and tip spheres of radius ``r_tip``;
* for the cradle grip (III), a narrow pedestal under the box;
* the explicit contact pairs (:func:`simgrip.sim.contacts.add_pair`): each
  finger's tip and links (but the last, whose end is the tip sphere) with the
  box (condim 4: torsional friction ``spin_friction * mu``), the palm slab
  with the box, the box with the table (and pedestal).

Addresses are looked up once (:class:`PickModel`); the fingers' through
:func:`simgrip.sim.fingers.index_fingers`.  Each episode resizes the
workpiece in place (:func:`resize_workpiece`, also the K-finger models').
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from simgrip.chain import chain_springs
from simgrip.envs.palm_servo import PALM_KP, add_palm_servo  # noqa: F401  (PALM_KP re-exported)
from simgrip.models import model_path
from simgrip.profiles import Uniform
from simgrip.sim.contacts import add_pair
from simgrip.sim.fingers import FingerIndex, add_fingers, check_finger_links, index_fingers
from simgrip.sim.workpiece import workpiece_inertia

__all__ = ["FINGER_PREFIX", "PEDESTAL_HEIGHT", "PickModel", "build_pick_model", "hand_spec", "resize_workpiece"]

#: Prefix of the fingers' names in the pick model.
FINGER_PREFIX = "hand_"
#: Height of the cradle grip's pedestal [m] (its half width is 6 mm).
PEDESTAL_HEIGHT = 0.04
#: Palm mass [kg] (its servos' stiffness: PALM_KP, simgrip.envs.palm_servo).
PALM_MASS = 0.2
#: Contact softness of every pair of the pick scene.
PICK_SOLREF = (0.005, 1.0)
PICK_SOLIMP = (0.95, 0.99, 0.001, 0.5, 2.0)


@dataclass
class PickModel:
    """The compiled pick model and the addresses the environment reads.

    Attributes
    ----------
    spec : mujoco.MjSpec
    model : mujoco.MjModel
    fingers : FingerIndex
        The two fingers (``n`` links each).
    palm_qpos, palm_dof : int
        The palm's slide joint.
    box_qpos, box_dof, box_body, box_geom : int
        The box's free joint (7 qpos, 6 dofs), body and geom.
    finger_pairs : ndarray
        Ids of the finger-box pairs (their friction is the episode's box friction).
    pedestal_height : float
        Height of the box's support above the table [m] (0 for Grip I).
    unit_rest : ndarray (n,)
        Rest angles of a finger per unit of uniform curvature (rest angles are linear in ``kappa_bar``).
    """

    spec: mujoco.MjSpec
    model: mujoco.MjModel
    fingers: FingerIndex
    palm_qpos: int
    palm_dof: int
    box_qpos: int
    box_dof: int
    box_body: int
    box_geom: int
    finger_pairs: np.ndarray
    pedestal_height: float
    unit_rest: np.ndarray


def build_pick_model(grip: str, *, n_links: int, length: float, EI: float, rho: float, g: float, r_tip: float,
                     box_size, box_mass_max: float, friction: float, spin_friction: float, timestep: float,
                     impratio: float, damping_time: float, armature: float, palm_ramp: bool = False,
                     palm_range=(-math.inf, math.inf)) -> PickModel:
    """Build and compile the pick scene of ``grip`` (``"I"`` or ``"III"``); SI units.

    ``box_size`` is the box's initial full size ``(x, y, z)`` [m] (the
    environment resizes it per episode); ``box_mass_max`` [kg] sizes the palm
    servo's damping (critical with the heaviest box); ``friction`` is the
    initial finger-box friction.  ``damping_time`` [s] and ``armature``
    [kg m^2] go to every finger hinge; ``palm_ramp``, ``palm_range``: :func:`hand_spec`'s.
    """
    n = check_finger_links(n_links, parent_depth=1, name="n_links")
    spec = hand_spec(fingers=2, n=n, length=length, EI=EI, rho=rho, g=g, r_tip=r_tip, mass_max=box_mass_max,
                     timestep=timestep, impratio=impratio, damping_time=damping_time, armature=armature,
                     palm_ramp=palm_ramp, palm_range=palm_range)
    hx, hy, hz = (0.5 * float(v) for v in box_size)
    spec.geom("box").size = [hx, hy, hz]
    pedestal = PEDESTAL_HEIGHT if grip == "III" else 0.0
    if pedestal:
        spec.worldbody.add_geom(name="pedestal", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.006, hy, 0.5 * pedestal],
                                pos=[0, 0, 0.5 * pedestal], contype=0, conaffinity=0, rgba=[0.45, 0.4, 0.35, 1])
    finger_pairs = _add_pairs(spec, n, friction, spin_friction, pedestal > 0.0)
    model = spec.compile()

    def joint(name):
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)

    palm_z, box_free = joint("palm_z"), joint("box_free")
    return PickModel(
        spec=spec, model=model, fingers=index_fingers(model, 2, n, FINGER_PREFIX),
        palm_qpos=int(model.jnt_qposadr[palm_z]), palm_dof=int(model.jnt_dofadr[palm_z]),
        box_qpos=int(model.jnt_qposadr[box_free]), box_dof=int(model.jnt_dofadr[box_free]),
        box_body=mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "box"),
        box_geom=mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "box"),
        finger_pairs=np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_PAIR, p) for p in finger_pairs]),
        pedestal_height=pedestal, unit_rest=chain_springs(Uniform(1.0), n).rest,
    )


def hand_spec(*, fingers: int, n: int, length: float, EI: float, rho: float, g: float, r_tip: float,
              mass_max: float, timestep: float, impratio: float, damping_time: float, armature: float,
              keep_box: bool = True, palm_ramp: bool = False, palm_range=(-math.inf, math.inf)) -> mujoco.MjSpec:
    """``models/pick_scene.xml`` with its options (``timestep`` [s], ``impratio``, gravity ``g`` [m/s^2]), the
    palm's slide and servo (critically damped for the palm, the fingers and a workpiece of ``mass_max`` [kg]) and
    ``fingers`` straight fingers of ``n`` links under the palm (:func:`simgrip.sim.fingers.add_fingers`: link
    and tip radius ``r_tip`` [m], hinge ``damping_time`` [s] and ``armature`` [kg m^2]); without the scene's
    box unless ``keep_box``; ``palm_ramp``: the palm's target ramped within a control step, kept in ``palm_range``
    [m] (:mod:`simgrip.envs.palm_servo`)."""
    spec = mujoco.MjSpec.from_file(str(model_path("pick_scene.xml")))
    spec.option.timestep = timestep
    spec.option.impratio = impratio
    spec.option.gravity = [0.0, 0.0, -g]
    if not keep_box:
        spec.delete(spec.body("box"))
    palm = spec.body("palm")
    _add_palm_slide(spec, palm, PALM_MASS + fingers * rho * length + mass_max, palm_ramp, palm_range)
    add_fingers(spec, palm, chain_springs(Uniform(0.0), n), fingers=fingers, length=length, EI=EI, rho=rho,
                r_link=r_tip, r_tip=r_tip, damping_time=damping_time, armature=armature, prefix=FINGER_PREFIX)
    return spec


def resize_workpiece(model: mujoco.MjModel, data: mujoco.MjData, *, shape: str, geom: int, body: int, pairs,
                     size, mass: float, friction: float, spin_friction: float) -> None:
    """Resize the workpiece ``geom`` of ``body`` in place (no recompilation), then :func:`mujoco.mj_setConst`.

    Sets the geom's ``size`` [m] (MuJoCo's: box half sizes; cylinder radius, half height; sphere radius), its
    bounding sphere and box, the body's ``mass`` [kg] and the solid's inertia
    (:func:`~simgrip.sim.workpiece.workpiece_inertia`), and the friction of the finger ``pairs`` (pair ids):
    sliding ``friction``, torsional ``spin_friction * friction`` [m].
    """
    if shape == "box":
        hx, hy, hz = size[0], size[1], size[2]
        rbound = math.sqrt(hx * hx + hy * hy + hz * hz)
    elif shape == "cylinder":
        hx = hy = size[0]
        hz = size[1]
        rbound = math.hypot(hx, hz)
    else:  # sphere
        hx = hy = hz = rbound = size[0]
    model.geom_size[geom] = size
    model.geom_rbound[geom] = rbound
    model.geom_aabb[geom] = [0.0, 0.0, 0.0, hx, hy, hz]
    model.body_mass[body] = mass
    model.body_inertia[body] = workpiece_inertia(shape, size, mass)
    model.pair_friction[pairs, 0:2] = friction
    model.pair_friction[pairs, 2] = spin_friction * friction
    mujoco.mj_setConst(model, data)


def _add_palm_slide(spec, palm, moving_mass: float, ramp: bool, z_range) -> None:
    """The palm's vertical slide ``palm_z`` and the servo ``palm_servo`` (critically damped for ``moving_mass`` [kg];
    ``ramp``: its target ramped within a control step, kept in ``z_range`` [m], :mod:`simgrip.envs.palm_servo`)."""
    palm.gravcomp = 1.0
    palm.add_joint(name="palm_z", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1])
    palm.explicitinertial = True
    palm.mass = PALM_MASS
    palm.inertia = [1e-4, 1e-4, 1e-4]
    add_palm_servo(spec, "palm_servo", "palm_z", moving_mass, ramp=ramp, lo=z_range[0], hi=z_range[1])


def _add_pairs(spec, n: int, mu: float, spin: float, pedestal: bool) -> list[str]:
    """Every contact pair of the pick scene; returns the names of the finger-box pairs."""
    soft = dict(solref=PICK_SOLREF, solimp=PICK_SOLIMP)
    names = []
    for f in range(2):
        geoms = [f"{FINGER_PREFIX}f{f}_tip"] + [f"{FINGER_PREFIX}f{f}_geom{i}" for i in range(n - 1)]
        pairs = [f"pair_f{f}_tip"] + [f"pair_f{f}_link{i}" for i in range(n - 1)]
        for geom, name in zip(geoms, pairs):
            add_pair(spec, name, geom, "box", mu, condim=4, spin=spin * mu, **soft)
        names += pairs
    add_pair(spec, "pair_palm_box", "palm_slab", "box", 0.5, spin=spin * 0.5, **soft)
    add_pair(spec, "pair_box_table", "box", "table", 0.6, spin=spin * 0.6, **soft)
    if pedestal:
        add_pair(spec, "pair_box_pedestal", "box", "pedestal", 0.6, spin=spin * 0.6, **soft)
    return names

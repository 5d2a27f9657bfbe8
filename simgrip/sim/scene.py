"""Scenes of soft fingers and a workpiece, built with :class:`mujoco.MjSpec` (never XML strings).

:func:`build_scene` composes a scene from its parts: the root options and
default classes (``models/defaults.xml``), the fingers
(:mod:`simgrip.sim.fingers`), the workpiece placed against them
(:mod:`simgrip.sim.workpiece`), the explicit contact pairs
(:mod:`simgrip.sim.contacts`) and, for pictures, the palm and the rendering
dressing.  It runs no solver: the start shape is passed in
(``initial_angles``) or is a plain geometric one.  :func:`set_curvature`
changes the intrinsic curvature of a built scene without recompiling.

Scenes (``grip``):

=========  ==================================================================
``free``   one or two fingers, no workpiece, contact disabled (Fig. 6)
``I``      palm down; the tip sphere presses the outer face of the box
``II``     palm up; same contact, the box above the palm
``III``    cradle; a capsule along ``y`` on the box's lower corner touches
           the links around ``gamma``
=========  ==================================================================

With ``fingers=2`` the workpiece (weight ``2 m g``) is free in the plane; with
``fingers=1`` and a workpiece (the *symmetric reduction*) it has half the mass
and slides in ``z`` only; with ``free_workpiece=False`` it is fixed.  The
contact geoms have small radii (2e-3 l): a force acting on a geom's surface
acts that far off the centreline (how the settle reads it: :mod:`simgrip.settle`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from simgrip.chain import ChainSprings, chain_springs, link_positions
from simgrip.models import model_path
from simgrip.params import DimensionlessParams, PhysicalParams, check_grip, check_grip_iii_reach
from simgrip.profiles import CurvatureProfile, as_profile
from simgrip.sim.contacts import add_pair
from simgrip.sim.fingers import FingerIndex, add_fingers, check_finger_links, index_fingers
from simgrip.sim.workpiece import (BOX_DEPTH, BOX_HEIGHT, add_workpiece, contact_links, corner_placement, cradle_start,
                                   inertial_mass)

__all__ = [
    "BOX_DEPTH",
    "BOX_HEIGHT",
    "DEFAULT_R_CORNER",
    "DEFAULT_R_LINK",
    "DEFAULT_R_TIP",
    "FingerScene",
    "Scene",
    "build_scene",
    "finger_state",
    "set_curvature",
    "set_joint_angles",
]

#: Default tip sphere radius over ``l`` (Grips I/II contact).
DEFAULT_R_TIP = 2e-3
#: Default link capsule radius over ``l`` (Grip III contact and visuals).
DEFAULT_R_LINK = 2e-3
#: Default corner capsule radius over ``l`` (Grip III).
DEFAULT_R_CORNER = 1e-3


class FingerScene:
    """What every compiled scene of fingers reads the same way: hinge addresses and the scales.

    A base of :class:`Scene` and :class:`simgrip.gripper.scene.GripperScene`; it
    reads their ``index`` (:class:`FingerIndex`) and ``physical``
    (:class:`PhysicalParams`) fields.
    """

    index: FingerIndex
    physical: PhysicalParams

    @property
    def joint_qpos(self) -> np.ndarray:
        """qpos addresses of the hinges, (fingers, n)."""
        return self.index.joint_qpos

    @property
    def joint_dof(self) -> np.ndarray:
        """dof addresses of the hinges, (fingers, n)."""
        return self.index.joint_dof

    @property
    def length(self) -> float:
        """``l`` [m]."""
        return self.physical.length

    @property
    def force_scale(self) -> float:
        """``rho g l`` [N]."""
        return self.physical.force_scale

    @property
    def moment_scale(self) -> float:
        """``rho g l^2`` [N m]."""
        return self.physical.force_scale * self.physical.length


@dataclass
class Scene(FingerScene):
    """A compiled simgrip scene and everything needed to read it.

    Attributes
    ----------
    spec : mujoco.MjSpec
    model : mujoco.MjModel
    data : mujoco.MjData
    grip : str
    params : DimensionlessParams
    physical : PhysicalParams
        The SI parameters the model is built in (``DimensionlessParams`` are
        built with ``l = rho = g = 1``).
    profile : CurvatureProfile
    n : int
        Links per finger.
    fingers : int
    free_workpiece : bool
    render : bool
        Whether the rendering dressing (palm, floor, light, camera) is attached.
    springs : ChainSprings
        Dimensionless springs (stiffness over ``EI/l``, rest angles).
    index : FingerIndex
        The fingers' addresses; ``joint_qpos``, ``joint_dof`` (fingers, n),
        ``link_body`` (fingers, n) and ``tip_geom`` (fingers,; -1 without tip
        contact) read them.
    contact_geoms : list of ndarray
        Per finger: the geom ids that take part in contact pairs.
    workpiece_body : int
        -1 when there is no workpiece.
    workpiece_qpos, workpiece_dof : ndarray
        Addresses of the workpiece's joints (empty when fixed or absent), in the
        order of ``workpiece_joints``.
    workpiece_joints : tuple of str
        ``("z",)``, ``("x", "z", "ry")`` or ``()``.
    workpiece_geoms : ndarray
        Geom ids on the workpiece that take part in pairs.
    box_half : ndarray (3,)
        Half sizes of the box [m].
    r_tip, r_link, r_corner : float
        Radii over ``l``.
    mirror : ndarray (fingers,)
        ``+1`` for the finger along ``+x``, ``-1`` for its mirror.
    contact : str
        ``"pairs"`` (explicit contact pairs) or ``"full"`` (every link may touch:
        :mod:`simgrip.sim.full_contact`; ``contact_geoms`` then holds every link and the tip).
    """

    spec: mujoco.MjSpec
    model: mujoco.MjModel
    data: mujoco.MjData
    grip: str
    params: DimensionlessParams
    physical: PhysicalParams
    profile: CurvatureProfile
    n: int
    fingers: int
    free_workpiece: bool
    render: bool
    springs: ChainSprings
    index: FingerIndex
    contact_geoms: list
    workpiece_body: int
    workpiece_qpos: np.ndarray
    workpiece_dof: np.ndarray
    workpiece_joints: tuple
    workpiece_geoms: np.ndarray
    box_half: np.ndarray
    r_tip: float
    r_link: float
    r_corner: float
    mirror: np.ndarray
    contact: str = "pairs"
    #: ``contact="full"``, Grips I/II: the grasp depth over ``l`` (the tip's centre below the box's top edge, Grip
    #: II above its bottom edge, in the centreline convention; :mod:`simgrip.settle.full_contact`) or None (the
    #: box stays where ``box_gap`` put it); whether contacts other than the tip's carry friction.
    box_depth: float | None = None
    extra_friction: bool = True

    @property
    def link_body(self) -> np.ndarray:
        """Body ids of the links, (fingers, n)."""
        return self.index.link_body

    @property
    def tip_geom(self) -> np.ndarray:
        """Tip sphere geom ids, (fingers,); -1 where the scene has no tip contact."""
        return self.index.tip_geom if self.grip in ("I", "II") else np.full(self.fingers, -1)

    @property
    def hinge_stiffness(self) -> np.ndarray:
        """Hinge stiffness [N m/rad], shape (n,)."""
        return self.physical.EI / self.physical.length * self.springs.stiffness

    @property
    def has_workpiece(self) -> bool:
        """Whether the scene has a workpiece (every grip but ``free``)."""
        return self.workpiece_body >= 0

    @property
    def workpiece_mass(self) -> float:
        """Mass of the workpiece in this scene [kg] (``m`` or ``2 m``): its weight over ``g``.

        The model's inertial mass (``model.body_mass``, :attr:`workpiece_inertial_mass`) may be larger: a
        light workpiece's inertia is floored (:func:`simgrip.sim.workpiece.inertial_mass`) and the extra
        weight relieved by gravity compensation; read the weight from here, never from ``body_mass``.
        """
        return self.physical.m * (1 if self.fingers == 1 else 2)

    @property
    def workpiece_inertial_mass(self) -> float:
        """The workpiece body's inertial mass in the model [kg] (>= :attr:`workpiece_mass`; 0 without one)."""
        return float(self.model.body_mass[self.workpiece_body]) if self.has_workpiece else 0.0


# ---------------------------------------------------------------------------
# input checks


def check_params(params) -> tuple[DimensionlessParams, PhysicalParams]:
    """``(dimensionless, physical)`` of ``params``; ``DimensionlessParams`` are realised with ``l = rho = g = 1``.

    Both dataclasses are checked when they are built; nothing is checked again here
    (:meth:`~simgrip.params.PhysicalParams.dimensionless` returns the groups computed on construction,
    :meth:`~simgrip.params.DimensionlessParams.unit_physical` copies checked groups).
    """
    if isinstance(params, PhysicalParams):
        return params.dimensionless(), params
    if isinstance(params, DimensionlessParams):
        return params, params.unit_physical()
    raise ValueError(f"params must be PhysicalParams or DimensionlessParams, got {type(params).__name__}")


def check_positive(name, value, upper) -> float:
    """``value`` as a float in ``(0, upper]`` (over ``l``); ValueError naming ``name`` otherwise."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not (math.isfinite(v) and 0.0 < v <= upper):
        raise ValueError(f"{name} must lie in (0, {upper}] (over l), got {value!r}")
    return v


def _start_angles(grip, params: DimensionlessParams, profile, n, initial_angles) -> np.ndarray:
    """The start's joint angles: ``initial_angles``, else straight (I, II, free) or :func:`cradle_start` (III)."""
    if initial_angles is not None:
        q0 = np.asarray(initial_angles, dtype=float)
        if q0.shape != (n,) or not np.all(np.isfinite(q0)):
            raise ValueError(f"initial_angles must be {n} finite joint angles, got shape {q0.shape}")
        return q0
    if grip == "III":
        return cradle_start(params.b, params.gamma, profile, n)
    return np.zeros(n)


# ---------------------------------------------------------------------------
# builder


@dataclass(frozen=True)
class _Placement:
    """Where the workpiece goes: box half sizes [m], centre height [m], links paired with it (Grip III)."""

    half: np.ndarray
    center_z: float
    links: np.ndarray


def build_scene(
    grip: str,
    params: PhysicalParams | DimensionlessParams,
    profile,
    n_links: int,
    *,
    fingers: int = 1,
    free_workpiece: bool = True,
    render: bool = False,
    r_tip: float = DEFAULT_R_TIP,
    r_link: float = DEFAULT_R_LINK,
    r_corner: float = DEFAULT_R_CORNER,
    initial_angles=None,
    contact_window: float = 0.35,
    contact: str | None = None,
    box_gap: float | None = None,
    box_depth: float | None = None,
    extra_friction: bool | None = None,
) -> Scene:
    """Build and compile a scene, its fingers at the start shape.

    Parameters
    ----------
    grip : {"free", "I", "II", "III"}
    params : PhysicalParams or DimensionlessParams
        ``DimensionlessParams`` are realised with ``l = rho = g = 1``.
    profile : CurvatureProfile, float or callable
        Intrinsic curvature ``kappa_bar(s_bar)``.
    n_links : int
        Links per finger, ``2 <= n_links <= max_links()`` (MuJoCo's body depth).
    fingers : {1, 2}
        One finger (with a workpiece: the symmetric reduction) or two mirrored.
    free_workpiece : bool
        Give the workpiece its joints; ``False`` fixes it.
    render : bool
        Attach the rendering dressing (floor, light, camera, palm).
    r_tip, r_link, r_corner : float
        Contact radii over ``l`` (see :mod:`simgrip.sim.workpiece`).
    initial_angles : array (n,), optional
        Joint angles of the start shape [rad].  Default: straight for
        ``free``, I and II; for III the geometric start
        :func:`simgrip.sim.workpiece.cradle_start` (pass
        :func:`simgrip.scenes.start_angles` to start from the hinge chain's
        equilibrium at ``params.gamma``).  The workpiece is placed against it.
    contact_window : float
        Grip III: links within this arc length (over ``l``) of the start's
        contact get a contact pair with the corner.
    contact : {None, "point", "surface", "full"}
        ``"full"``: every link and the tip may touch the workpiece and every
        non-adjacent link (:mod:`simgrip.sim.full_contact`; free rod, Grips I and
        II); the others build the explicit pairs above (which settle then runs is
        the settle's ``contact``).
    box_gap : float, optional
        With ``contact="full"`` (Grips I/II): the gap over ``l`` between the palm
        plane and the box's near face (default
        :data:`~simgrip.sim.full_contact.DEFAULT_BOX_GAP`).
    box_depth, extra_friction : optional
        With ``contact="full"`` (Grips I/II): the grasp protocol of
        :func:`~simgrip.sim.full_contact.check_grasp` (the box grasped with the
        tip ``box_depth`` below its top edge; friction on the non-tip contacts).

    Returns
    -------
    Scene
    """
    grip = check_grip(grip)
    from simgrip.sim.full_contact import DEFAULT_BOX_GAP, check_contact_mode, enable_full_contact, full_box_centre

    mode = check_contact_mode(contact)
    if mode == "full" and grip == "III":
        raise ValueError("contact: 'full' is built for the free rod and Grips I/II (Grip III's box would need a "
                         "top below the palm: not built yet)")
    if box_gap is not None and mode != "full":
        raise ValueError("box_gap: only a full-contact scene (contact='full') has a box with a near face")
    gap = DEFAULT_BOX_GAP if box_gap is None else check_positive("box_gap", box_gap, 1.0)
    from simgrip.sim.full_contact import check_grasp

    box_depth, extra_friction = check_grasp(grip, mode, box_depth, extra_friction)
    dimless, phys = check_params(params)
    prof = as_profile(profile)
    n = check_finger_links(n_links)
    if fingers not in (1, 2) or isinstance(fingers, bool):
        raise ValueError(f"fingers must be 1 or 2, got {fingers!r}")
    for name, flag in (("free_workpiece", free_workpiece), ("render", render)):
        if not isinstance(flag, (bool, np.bool_)):  # "no" is truthy: free_workpiece="no" built a free one
            raise ValueError(f"{name} must be True or False, got {flag!r}")
    r_tip = check_positive("r_tip", r_tip, 0.05)
    r_link = check_positive("r_link", r_link, 0.05)
    r_corner = check_positive("r_corner", r_corner, 0.05)
    contact_window = check_positive("contact_window", contact_window, 1.0)
    if grip == "III":
        check_grip_iii_reach(dimless.gamma, dimless.b)
    springs = chain_springs(prof, n)
    q0 = _start_angles(grip, dimless, prof, n, initial_angles)
    place = _placement(grip, q0, springs, dimless, phys, r_tip, r_link, r_corner, contact_window,
                       initial_angles is not None)

    spec = _root(grip, n, phys, full=mode == "full")
    L = phys.length
    if mode == "full" and place is not None:  # a real box: its near face box_gap from the palm
        place = _Placement(place.half, full_box_centre(grip, gap * L, float(place.half[2])), place.links)
    add_fingers(spec, spec.worldbody, springs, fingers=fingers, length=L, EI=phys.EI, rho=phys.rho,
                r_link=r_link * L, r_tip=r_tip * L if (grip in ("I", "II") or render or mode == "full") else None)
    joints: tuple = ()
    if place is not None:
        joints = (("z",) if fingers == 1 else ("x", "z", "ry")) if free_workpiece else ()
        mass = phys.m * fingers
        # a light workpiece's inertia is floored (MuJoCo's soft contact sinks without bound under a nearly
        # massless body), its weight stays m g per finger (gravity compensation: Scene.workpiece_mass)
        body = add_workpiece(spec, half_size=place.half, center_z=place.center_z,
                             mass=inertial_mass(mass, fingers, phys.rho, L), joints=joints, weight_mass=mass)
        if grip == "III":
            _add_corners(spec, body, place.half, fingers, r_corner * L)
        if mode == "pairs":
            _add_pairs(spec, grip, fingers, place.links, phys.mu_s)
    if mode == "full":
        enable_full_contact(spec, [f"f{f}_{g}" for f in range(fingers) for g in [f"geom{i}" for i in range(n)] + ["tip"]],
                            ["workpiece_box"] if place is not None else [], phys.mu_s,
                            root_bodies=[f"f{f}_link0" for f in range(fingers)])
    if render:
        _dress(spec, grip, L)

    model = spec.compile()
    scene = _scene(spec, model, grip, dimless, phys, prof, springs, fingers, free_workpiece, render,
                   joints, place, r_tip, r_link, r_corner, mode)
    scene.box_depth, scene.extra_friction = box_depth, extra_friction
    set_joint_angles(scene, q0)
    return scene


def root_spec(name: str, g: float) -> mujoco.MjSpec:
    """A new spec named ``name``: options and default classes of ``models/defaults.xml``, gravity ``g`` [m/s^2] down ``z``."""
    spec = mujoco.MjSpec.from_file(str(model_path("defaults.xml")))
    spec.modelname = name
    spec.option.gravity = [0.0, 0.0, -g]
    return spec


def _root(grip: str, n: int, phys: PhysicalParams, full: bool = False) -> mujoco.MjSpec:
    """The scene's root spec: options and default classes of ``models/defaults.xml``, gravity, contact switch
    (off for the free rod unless ``full``: its links touch each other)."""
    spec = root_spec(f"simgrip_{grip}_{n}", phys.g)
    if grip == "free" and not full:
        spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    return spec


def _placement(grip, q0, springs, params, phys, r_tip, r_link, r_corner, window, given) -> _Placement | None:
    """Where the workpiece touches the start shape ``q0`` (None for the free rod); ValueError naming ``b``."""
    if grip == "free":
        return None
    L = phys.length
    hy, hz = 0.5 * BOX_DEPTH * L, 0.5 * BOX_HEIGHT * L
    if grip in ("I", "II"):
        hx = 0.5 * phys.b - r_tip * L
        if not hx > 0.0:
            raise ValueError(f"b must exceed 2 r_tip = {2 * r_tip:g} (the tip sphere's centre touches the box at "
                             f"X = b/2), got b = {params.b:g}")
        z0 = link_positions(np.cumsum(q0), springs.ds)[-1, 1] * L
        return _Placement(np.array([hx, hy, hz]), float(z0), np.zeros(0, dtype=int))
    hx, zc, s = corner_placement(q0, springs, params.b, params.gamma, r_link, r_corner, L)
    if not hx > 0.0:
        shape = "initial_angles" if given else f"the start shape of gamma = {params.gamma:g}"
        raise ValueError(f"b = {params.b:g} is too narrow for Grip III: on {shape} the box's corner would sit at "
                         f"x = {hx / L:.3g} l <= 0")
    return _Placement(np.array([hx, hy, hz]), zc + hz, contact_links(s, springs, window))


def _add_corners(spec, body, half, fingers: int, radius: float) -> None:
    """Grip III: a capsule along ``y`` on each lower edge of the box that a finger carries."""
    hx, hy, hz = half
    corner_cls = spec.find_default("corner")
    for f in range(fingers):
        x = hx if f == 0 else -hx
        body.add_geom(corner_cls, name=f"corner{f}", fromto=[x, -hy, -hz, x, hy, -hz], size=[radius, 0, 0])


def _add_pairs(spec, grip: str, fingers: int, links, mu: float) -> None:
    """Contact pairs: tip sphere with the box face (I, II); links around the contact with the corner (III)."""
    for f in range(fingers):
        if grip in ("I", "II"):
            add_pair(spec, f"pair_f{f}_tip", f"f{f}_tip", "workpiece_box", mu)
        else:
            for i in links:
                add_pair(spec, f"pair_f{f}_link{i}", f"f{f}_geom{i}", f"corner{f}", mu)


def _dress(spec, grip: str, L: float) -> None:
    """Rendering only: the palm slab above (I, III) or below (II) the roots, floor, light, camera."""
    palm_spec = mujoco.MjSpec.from_file(str(model_path("palm.xml")))
    up = -1.0 if grip == "II" else 1.0
    palm = spec.worldbody.add_frame(pos=[0.0, 0.0, up * 0.012 * L]).attach_body(palm_spec.body("body"), "palm_", "")
    palm.first_geom().size = [0.15 * L, 0.1 * L, 0.01 * L]
    spec.attach(mujoco.MjSpec.from_file(str(model_path("dressing.xml"))), prefix="dress_",
                frame=spec.worldbody.add_frame())
    spec.visual.global_.offwidth = 1280
    spec.visual.global_.offheight = 960
    spec.stat.center = [0.0, 0.0, -0.3 * L]
    spec.stat.extent = 2.0 * L


def _scene(spec, model, grip, params, phys, profile, springs, fingers, free_workpiece, render, joints, place,
           r_tip, r_link, r_corner, mode="pairs") -> Scene:
    """The :class:`Scene` of a compiled model: addresses looked up once."""
    n = springs.n
    index = index_fingers(model, fingers, n)

    def gid(name):
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)

    wj = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, f"workpiece_{name}") for name in joints]
    if grip in ("I", "II"):
        contact_geoms = [index.tip_geom[f:f + 1].copy() for f in range(fingers)]
        wgeoms = np.array([gid("workpiece_box")])
    elif grip == "III":
        contact_geoms = [index.link_geom[f, place.links] for f in range(fingers)]
        wgeoms = np.array([gid(f"corner{f}") for f in range(fingers)])
    else:
        contact_geoms = [np.zeros(0, int) for _ in range(fingers)]
        wgeoms = np.zeros(0, int)
    if mode == "full":  # every link and the tip touch
        contact_geoms = [np.append(index.link_geom[f], index.tip_geom[f]) for f in range(fingers)]
    return Scene(
        spec=spec, model=model, data=mujoco.MjData(model), grip=grip, params=params, physical=phys,
        profile=profile, n=n, fingers=fingers, free_workpiece=bool(free_workpiece), render=bool(render),
        springs=springs, index=index, contact_geoms=contact_geoms,
        workpiece_body=mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "workpiece_body") if place else -1,
        workpiece_qpos=np.array(model.jnt_qposadr[wj], dtype=int), workpiece_dof=np.array(model.jnt_dofadr[wj], dtype=int),
        workpiece_joints=joints, workpiece_geoms=wgeoms,
        box_half=place.half if place else np.zeros(3), r_tip=r_tip, r_link=r_link, r_corner=r_corner,
        mirror=np.array([1.0, -1.0][:fingers]), contact=mode,
    )


# ---------------------------------------------------------------------------
# runtime edits and reading


def set_curvature(scene: Scene, profile) -> ChainSprings:
    """Change the intrinsic curvature at run time (``model.qpos_spring``), no recompile.

    The hinge stiffnesses do not depend on the profile; only the rest angles
    change.  Returns the new springs and stores them (and the profile) in ``scene``.
    """
    prof = as_profile(profile)
    springs = chain_springs(prof, scene.n)
    scene.model.qpos_spring[scene.joint_qpos] = springs.rest[None, :]
    scene.springs = springs
    scene.profile = prof
    return springs


def set_joint_angles(scene: Scene, angles, *, forward: bool = True) -> None:
    """Set every finger's hinge angles [rad] (shape (n,) or (fingers, n)), zero velocities, forward
    (``forward=False``: MuJoCo's derived quantities are left for the caller to compute)."""
    q = np.asarray(angles, dtype=float)
    q = np.broadcast_to(q, (scene.fingers, scene.n))
    scene.data.qpos[scene.joint_qpos] = q
    scene.data.qvel[:] = 0.0
    if forward:
        mujoco.mj_forward(scene.model, scene.data)


def finger_state(scene: Scene, data: mujoco.MjData | None = None, finger: int = 0):
    """Joint angles, link angles [rad] and centreline nodes ``(n+1, 2)`` over ``l`` of one finger.

    Nodes are in the finger's own frame (``x`` away from the palm centre), so the
    mirrored finger reads exactly like finger 0.
    """
    d = scene.data if data is None else data
    q = np.array(d.qpos[scene.joint_qpos[finger]])
    phi = np.cumsum(q)
    return q, phi, link_positions(phi, 1.0 / scene.n)

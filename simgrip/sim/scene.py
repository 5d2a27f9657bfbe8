"""MuJoCo scenes of soft fingers built with :class:`mujoco.MjSpec` (never XML strings).

A finger of ``n`` links is the hinge chain of :mod:`simgrip.chain`: link ``i``
is a rigid body of mass ``rho ds`` centred at its midpoint, hinge ``j`` has
stiffness ``(EI/l) * springs.stiffness[j]`` and spring reference
(``springref`` / ``model.qpos_spring``) ``springs.rest[j]``.  Hinges turn about
``-y`` so that a positive joint angle is a counter-clockwise ``theta`` in the
``x-z`` plane (``x = E1``, ``z = E2``); finger 0 points along ``+x`` from the
world origin, finger 1 (two-finger scenes) is its mirror image along ``-x``.

Scenes (``grip``):

=========  ==================================================================
``free``   one or two fingers, no workpiece, contact disabled (Fig. 6)
``I``      palm down; the tip sphere presses the outer face of the box
``II``     palm up; same contact, the box above the palm
``III``    cradle; a capsule along ``y`` on the box's lower corner touches
           the links around ``gamma``
=========  ==================================================================

With ``fingers=2`` the workpiece (weight ``2 m g``) is free in the plane (slide
x, slide z, hinge y).  With ``fingers=1`` and a workpiece (the *symmetric
reduction*) it has half the mass and slides in ``z`` only: its ``x`` is held by
the missing joint, which stands in for the mirrored finger.  With
``free_workpiece=False`` it has no joint at all (fixed in the world).

Contact geometry (centreline where the theory puts it):

* Grips I/II: tip sphere of radius ``r_tip`` centred at ``s = l``, box face at
  ``x = b/2 - r_tip``, so a touching tip has its centreline at ``X(l) = b/2``.
  The friction force then acts ``r_tip`` off the centreline: the workpiece
  applies the tip couple ``C = -r_tip F_f`` (``= +r_tip m g`` at equilibrium),
  see :func:`contact_moment`.  The settled state measures it from MuJoCo's
  contact point (``FingerContact.moment``); pass it to the references as
  ``contact_moment`` (radii are kept small, 2e-3 l, so it is a 0.3 % effect on
  ``N``, but it is resolved exactly rather than neglected).
* Grip III: links are capsules of radius ``r_link``; the corner capsule (radius
  ``r_corner``, along ``y`` at the box's lower corner) is placed
  ``r_link + r_corner`` from the centreline along the normal, so the
  centreline passes ``X(gamma) = b/2`` for the initial shape (by default the
  hinge chain's equilibrium at ``params.gamma`` from
  :func:`simgrip.reference.discrete.solve_chain`); a settled state reports its own
  ``gamma`` and ``X(gamma)``.  The friction force acts ``r_link`` off the
  centreline: couple ``C = r_link f`` at ``gamma``.

Only geoms that can meet the workpiece collide, through explicit ``<pair>``
elements (every geom has ``contype = conaffinity = 0``): no finger
self-collision, no broad phase.  Rendering dressing (floor, light, camera) is
attached only with ``render=True``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mujoco
import numpy as np

from simgrip.chain import ChainSprings, chain_springs, check_links, link_positions
from simgrip.models import model_path
from simgrip.params import DimensionlessParams, PhysicalParams, check_grip
from simgrip.profiles import CurvatureProfile, as_profile

__all__ = [
    "Scene",
    "build_scene",
    "set_curvature",
    "set_joint_angles",
    "finger_state",
    "contact_moment",
    "DEFAULT_R_TIP",
    "DEFAULT_R_LINK",
]

#: Default tip sphere radius over ``l`` (Grips I/II contact).
DEFAULT_R_TIP = 2e-3
#: Default link capsule radius over ``l`` (Grip III contact and visuals).
DEFAULT_R_LINK = 2e-3
#: Default corner capsule radius over ``l`` (Grip III).
DEFAULT_R_CORNER = 1e-3
#: Box height and depth over ``l``.
BOX_HEIGHT = 2.0  # tall: a frictionless tip slides along the face while closing
BOX_DEPTH = 0.2

_MIRROR_QUAT = (0.0, 0.0, 0.0, 1.0)  # rotation by pi about z


@dataclass
class Scene:
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
    springs : ChainSprings
        Dimensionless springs (stiffness over ``EI/l``, rest angles).
    joint_qpos, joint_dof : ndarray (fingers, n)
        qpos / dof addresses of the hinges.
    link_body : ndarray (fingers, n)
        Body ids of the links.
    tip_geom : ndarray (fingers,)
        Tip sphere geom ids (-1 when there is no tip contact).
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
    ids : dict
        name -> id for bodies, joints and geoms (``{"body": {...}, ...}``).
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
    joint_qpos: np.ndarray
    joint_dof: np.ndarray
    link_body: np.ndarray
    tip_geom: np.ndarray
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
    ids: dict = field(default_factory=dict)

    # -- scales -------------------------------------------------------------
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

    @property
    def hinge_stiffness(self) -> np.ndarray:
        """Hinge stiffness [N m/rad], shape (n,)."""
        return self.physical.EI / self.physical.length * self.springs.stiffness

    @property
    def has_workpiece(self) -> bool:
        return self.workpiece_body >= 0

    @property
    def symmetric(self) -> bool:
        """One finger and a workpiece of half the weight on the symmetry line."""
        return self.fingers == 1 and self.has_workpiece

    @property
    def workpiece_mass(self) -> float:
        """Mass of the workpiece in this scene [kg] (``m`` or ``2 m``)."""
        return self.physical.m * (1 if self.fingers == 1 else 2)


# ---------------------------------------------------------------------------
# input checks


def _check_params(params) -> tuple[DimensionlessParams, PhysicalParams]:
    if isinstance(params, PhysicalParams):
        return params.dimensionless(), params
    if isinstance(params, DimensionlessParams):
        return params, params.to_physical(length=1.0, rho=1.0, g=1.0)
    raise ValueError(f"params must be PhysicalParams or DimensionlessParams, got {type(params).__name__}")


def _check_radius(name, value, upper) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not (math.isfinite(v) and 0.0 < v <= upper):
        raise ValueError(f"{name} must lie in (0, {upper}] (over l), got {value!r}")
    return v


# ---------------------------------------------------------------------------
# builder


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
) -> Scene:
    """Build and compile a scene.

    Parameters
    ----------
    grip : {"free", "I", "II", "III"}
    params : PhysicalParams or DimensionlessParams
        ``DimensionlessParams`` are realised with ``l = rho = g = 1``.
    profile : CurvatureProfile, float or callable
        Intrinsic curvature ``kappa_bar(s_bar)``.
    n_links : int
        Links per finger (>= 2).
    fingers : {1, 2}
        One finger (with a workpiece: the symmetric reduction) or two mirrored.
    free_workpiece : bool
        Give the workpiece its joints (see module docstring); ``False`` fixes it.
    render : bool
        Attach the rendering dressing (floor, light, camera, palm).
    r_tip, r_link, r_corner : float
        Contact radii over ``l`` (see module docstring).
    initial_angles : array (n,), optional
        Joint angles to build the initial ``qpos`` (default: the rest angles
        scaled to zero, i.e. the straight finger).  For Grip III the corner is
        placed on this shape (default: the rest shape, ``springs.rest``).
    contact_window : float
        Grip III: links whose arc-length span is within this distance (over
        ``l``) of the initial contact get a contact pair with the corner.

    Returns
    -------
    Scene
    """
    grip = check_grip(grip)
    dimless, phys = _check_params(params)
    prof = as_profile(profile)
    n = check_links(n_links)
    if fingers not in (1, 2) or isinstance(fingers, bool):
        raise ValueError(f"fingers must be 1 or 2, got {fingers!r}")
    r_tip = _check_radius("r_tip", r_tip, 0.05)
    r_link = _check_radius("r_link", r_link, 0.05)
    r_corner = _check_radius("r_corner", r_corner, 0.05)
    springs = chain_springs(prof, n)
    if initial_angles is None:
        q0 = _cradle_angles(dimless, prof, n) if grip == "III" else np.zeros(n)
    else:
        q0 = np.asarray(initial_angles, dtype=float)
        if q0.shape != (n,) or not np.all(np.isfinite(q0)):
            raise ValueError(f"initial_angles must be {n} finite joint angles, got shape {q0.shape}")

    L = phys.length
    ds = L / n
    spec = mujoco.MjSpec.from_file(str(model_path("defaults.xml")))
    spec.modelname = f"simgrip_{grip}_{n}"
    spec.option.gravity = [0.0, 0.0, -phys.g]
    if grip == "free":
        spec.option.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    finger_cls = spec.find_default("finger")
    tip_cls = spec.find_default("tip")

    # -- fingers -------------------------------------------------------------
    k = phys.EI / L * springs.stiffness
    link_mass = phys.rho * ds
    r_vis = r_link * L
    inertia_perp = link_mass * (ds**2 / 12.0 + r_vis**2 / 4.0)
    inertia_axis = 0.5 * link_mass * r_vis**2
    has_tip_contact = grip in ("I", "II")
    mirror = np.array([1.0, -1.0][:fingers])
    for f in range(fingers):
        parent = spec.worldbody
        for i in range(n):
            body = parent.add_body(name=f"f{f}_link{i}", pos=[ds if i else 0.0, 0.0, 0.0])
            if i == 0 and f == 1:
                body.quat = list(_MIRROR_QUAT)
            body.explicitinertial = True
            body.mass = link_mass
            body.ipos = [0.5 * ds, 0.0, 0.0]
            body.inertia = [inertia_axis, inertia_perp, inertia_perp]
            body.add_joint(
                finger_cls,
                name=f"f{f}_joint{i}",
                stiffness=float(k[i]),
                springref=float(springs.rest[i]),
            )
            body.add_geom(finger_cls, name=f"f{f}_geom{i}", fromto=[0, 0, 0, ds, 0, 0], size=[r_vis, 0, 0])
            parent = body
        if has_tip_contact or render:
            parent.add_geom(tip_cls, name=f"f{f}_tip", pos=[ds, 0, 0], size=[r_tip * L, 0, 0])

    # -- workpiece -----------------------------------------------------------
    box_half = np.zeros(3)
    wp_joints: tuple = ()
    if grip != "free":
        wp_spec = mujoco.MjSpec.from_file(str(model_path("workpiece.xml")))
        frame = spec.worldbody.add_frame()
        wp = frame.attach_body(wp_spec.body("body"), "workpiece_", "")
        mass = phys.m * (1 if fingers == 1 else 2)
        hz = 0.5 * BOX_HEIGHT * L
        hy = 0.5 * BOX_DEPTH * L
        if grip in ("I", "II"):
            hx = 0.5 * phys.b - r_tip * L
            nodes = link_positions(np.cumsum(q0), 1.0 / n) * L
            z0 = nodes[-1, 1]
        else:
            hx, z0, _ = _corner_placement(q0, springs, dimless, phys, r_link, r_corner)
        if not hx > 0.0:
            raise ValueError(f"initial_angles: the Grip III corner would sit at x = {hx:g} m <= 0")
        box_half = np.array([hx, hy, hz])
        wp.pos = [0.0, 0.0, z0]
        wp.explicitinertial = True
        wp.mass = max(mass, 1e-12 * phys.rho * L)
        wp.ipos = [0.0, 0.0, 0.0]
        wp.inertia = [
            wp.mass / 3.0 * (hy**2 + hz**2),
            wp.mass / 3.0 * (hx**2 + hz**2),
            wp.mass / 3.0 * (hx**2 + hy**2),
        ]
        box = wp.first_geom()
        box.size = list(box_half)
        if free_workpiece:
            wp_joints = ("z",) if fingers == 1 else ("x", "z", "ry")
            axes = {"x": [1, 0, 0], "z": [0, 0, 1], "ry": [0, -1, 0]}
            for name in wp_joints:
                jtype = mujoco.mjtJoint.mjJNT_HINGE if name == "ry" else mujoco.mjtJoint.mjJNT_SLIDE
                wp.add_joint(name=f"workpiece_{name}", type=jtype, axis=axes[name])
        if grip == "III":
            for f in range(fingers):
                wp.add_geom(
                    spec.find_default("corner"),
                    name=f"corner{f}",
                    fromto=[mirror[f] * hx, -hy, -hz, mirror[f] * hx, hy, -hz],
                    size=[r_corner * L, 0, 0],
                )

    # -- palm and dressing ---------------------------------------------------
    if render:
        palm_spec = mujoco.MjSpec.from_file(str(model_path("palm.xml")))
        up = -1.0 if grip == "II" else 1.0
        pf = spec.worldbody.add_frame(pos=[0.0, 0.0, up * 0.012 * L])
        palm = pf.attach_body(palm_spec.body("body"), "palm_", "")
        palm.first_geom().size = [0.15 * L, 0.1 * L, 0.01 * L]
        dress = mujoco.MjSpec.from_file(str(model_path("dressing.xml")))
        spec.attach(dress, prefix="dress_", frame=spec.worldbody.add_frame())
        spec.visual.global_.offwidth = 1280
        spec.visual.global_.offheight = 960
        spec.stat.center = [0.0, 0.0, -0.3 * L]
        spec.stat.extent = 2.0 * L

    # -- contact pairs -------------------------------------------------------
    if grip in ("I", "II"):
        for f in range(fingers):
            _add_pair(spec, f"pair_f{f}_tip", f"f{f}_tip", "workpiece_box", phys.mu_s)
    elif grip == "III":
        window = _contact_links(q0, springs, dimless, contact_window)
        for f in range(fingers):
            for i in window:
                _add_pair(spec, f"pair_f{f}_link{i}", f"f{f}_geom{i}", f"corner{f}", phys.mu_s)

    model = spec.compile()
    data = mujoco.MjData(model)

    # -- addresses -----------------------------------------------------------
    def jid(name):
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)

    def gid(name):
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)

    def bid(name):
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)

    j = np.array([[jid(f"f{f}_joint{i}") for i in range(n)] for f in range(fingers)])
    joint_qpos = model.jnt_qposadr[j]
    joint_dof = model.jnt_dofadr[j]
    link_body = np.array([[bid(f"f{f}_link{i}") for i in range(n)] for f in range(fingers)])
    tip_geom = np.array([gid(f"f{f}_tip") if has_tip_contact else -1 for f in range(fingers)])
    wb = bid("workpiece_body") if grip != "free" else -1
    wj = [jid(f"workpiece_{name}") for name in wp_joints]
    wq = np.array(model.jnt_qposadr[wj], dtype=int) if wj else np.zeros(0, int)
    wd = np.array(model.jnt_dofadr[wj], dtype=int) if wj else np.zeros(0, int)
    if grip in ("I", "II"):
        contact_geoms = [np.array([tip_geom[f]]) for f in range(fingers)]
        wgeoms = np.array([gid("workpiece_box")])
    elif grip == "III":
        contact_geoms = [np.array([gid(f"f{f}_geom{i}") for i in window]) for f in range(fingers)]
        wgeoms = np.array([gid(f"corner{f}") for f in range(fingers)])
    else:
        contact_geoms = [np.zeros(0, int) for _ in range(fingers)]
        wgeoms = np.zeros(0, int)

    ids = {
        "body": {model.body(i).name: i for i in range(model.nbody)},
        "joint": {model.joint(i).name: i for i in range(model.njnt)},
        "geom": {model.geom(i).name: i for i in range(model.ngeom)},
        "pair": {model.pair(i).name: i for i in range(model.npair)},
    }
    scene = Scene(
        spec=spec,
        model=model,
        data=data,
        grip=grip,
        params=dimless,
        physical=phys,
        profile=prof,
        n=n,
        fingers=fingers,
        free_workpiece=bool(free_workpiece),
        render=bool(render),
        springs=springs,
        joint_qpos=joint_qpos,
        joint_dof=joint_dof,
        link_body=link_body,
        tip_geom=tip_geom,
        contact_geoms=contact_geoms,
        workpiece_body=wb,
        workpiece_qpos=wq,
        workpiece_dof=wd,
        workpiece_joints=wp_joints,
        workpiece_geoms=wgeoms,
        box_half=box_half,
        r_tip=r_tip,
        r_link=r_link,
        r_corner=r_corner,
        mirror=mirror,
        ids=ids,
    )
    set_joint_angles(scene, q0)
    return scene


def _add_pair(spec, name, g1, g2, mu):
    p = spec.add_pair()
    p.name = name
    p.geomname1 = g1
    p.geomname2 = g2
    p.condim = 3
    # sliding friction in both tangent directions; torsion/rolling unused (condim 3)
    p.friction = [mu, mu, 0.0, 0.0, 0.0]
    p.solref = [0.002, 1.0]
    p.solimp = [0.9999, 0.9999, 0.001, 0.5, 2.0]


def _cradle_angles(params, profile, n) -> np.ndarray:
    """Default Grip III start: the hinge chain's equilibrium with the contact at ``params.gamma``."""
    from simgrip.reference.discrete import DiscreteError, solve_chain

    try:
        return solve_chain("III", params, profile, n).joint_angles
    except DiscreteError as exc:
        raise ValueError(
            f"profile: no Grip III starting shape with gamma = {params.gamma:g} ({exc}); pass initial_angles"
        ) from exc


def _shape(q0, springs):
    phi = np.cumsum(q0)
    return phi, link_positions(phi, springs.ds)


def _contact_s(q0, springs, params) -> tuple[float, float, np.ndarray]:
    """Arc length (over l), tangent angle and point of the initial Grip III contact.

    The contact is where the centreline crosses ``X = b/2`` heading inwards
    (``cos theta < 0``); among those crossings, the one nearest ``params.gamma``.
    Without such a crossing, the material point at ``params.gamma``.
    """
    phi, nodes = _shape(q0, springs)
    ds = springs.ds
    half = 0.5 * params.b
    best = None
    for i in range(springs.n):
        x0, x1 = nodes[i, 0], nodes[i + 1, 0]
        if (x0 - half) * (x1 - half) <= 0.0 and x0 != x1 and math.cos(phi[i]) < 0.0:
            t = (x0 - half) / (x0 - x1)
            s = (i + t) * ds
            if best is None or abs(s - params.gamma) < abs(best[0] - params.gamma):
                best = (s, phi[i], nodes[i] + t * (nodes[i + 1] - nodes[i]))
    if best is None:
        s = params.gamma
        i = min(int(s / ds), springs.n - 1)
        t = s / ds - i
        best = (s, phi[i], nodes[i] + t * (nodes[i + 1] - nodes[i]))
    return best


def _corner_placement(q0, springs, params, phys, r_link, r_corner):
    """Box half width and centre height so the corner capsule touches the initial shape."""
    s, th, point = _contact_s(q0, springs, params)
    L = phys.length
    e2 = np.array([-math.sin(th), math.cos(th)])
    sign = 1.0 if e2[1] <= 0.0 else -1.0  # the box sits above the rod
    corner = point * L - sign * (r_link + r_corner) * L * e2
    hz = 0.5 * BOX_HEIGHT * L
    return float(corner[0]), float(corner[1] + hz), s


def _contact_links(q0, springs, params, window) -> list[int]:
    s, _, _ = _contact_s(q0, springs, params)
    ds = springs.ds
    return [i for i in range(springs.n) if (i + 1) * ds >= s - window and i * ds <= s + window]


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


def set_joint_angles(scene: Scene, angles) -> None:
    """Set every finger's hinge angles (shape (n,) or (fingers, n)), zero velocities, forward."""
    q = np.asarray(angles, dtype=float)
    q = np.broadcast_to(q, (scene.fingers, scene.n))
    scene.data.qpos[scene.joint_qpos] = q
    scene.data.qvel[:] = 0.0
    mujoco.mj_forward(scene.model, scene.data)


def finger_state(scene: Scene, data: mujoco.MjData | None = None, finger: int = 0):
    """Joint angles, link angles and centreline nodes ``(n+1, 2)`` over ``l`` of one finger.

    Nodes are in the finger's own frame (``x`` away from the palm centre), so the
    mirrored finger reads exactly like finger 0.
    """
    d = scene.data if data is None else data
    q = np.array(d.qpos[scene.joint_qpos[finger]])
    phi = np.cumsum(q)
    return q, phi, link_positions(phi, 1.0 / scene.n)


def contact_moment(scene: Scene, friction_force: float) -> float:
    """Couple (E3, over ``rho g l^2``) the finite contact radius adds at the contact.

    Grips I/II: the friction ``F_f E2`` acts at the sphere's surface, ``r_tip``
    inside the centreline tip: ``C = -r_tip F_f``.  Grip III: the friction ``f e1``
    acts ``r_link`` from the centreline on the ``-e2`` side: ``C = r_link f``.
    """
    if scene.grip in ("I", "II"):
        return -scene.r_tip * friction_force
    if scene.grip == "III":
        return scene.r_link * friction_force
    return 0.0

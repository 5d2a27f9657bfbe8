"""Grip III (the cradle) for a K = 4 gripper around a box: each finger carries the bottom edge of one face.

:func:`simgrip.gripper.scene.build_gripper` builds ``grip="III"`` here.

Which edges carry the fingers, and why.  Each finger bends in its own
vertical plane through the palm axis; with four fingers at azimuths ``2 pi
k / 4`` and the box's faces turned to them, finger ``k``'s plane is the box's
mid-plane normal to face ``k``, and cuts the box in the planar Grip III
section: a rectangle whose lower outer corner is the midpoint of face
``k``'s bottom edge.  So every finger carries the bottom edge of its own
face, at that edge's midpoint, the edge running out of the finger's plane
(``E3``): exactly the paper's corner at ``s = gamma``, seen edge on.  By the
four-fold symmetry every finger carries ``M``, each pair of opposite fingers
balances the box horizontally and in tilt, and the edges' friction along
``E3`` (the fingers are rigid out of their planes) holds its turn about the
palm axis: the problem is the planar Grip III problem per finger.  A box
held at its corners instead (fingers on the diagonals) would rest on the
bottom vertices, a point contact on two edges that no planar problem
describes; a cylinder's bottom rim is curved along ``E3`` (MuJoCo has no
torus to model it); both are not built.

Geometry, as the planar cradle (:func:`simgrip.sim.scene.build_scene` with
``grip="III"``; lengths over ``l``): the fingers start at ``initial_angles``
(default the geometric cradle shape
:func:`~simgrip.sim.workpiece.cradle_start` crossing ``X = b/2`` at ``s =
gamma``; :func:`simgrip.scenes.start_angles` gives the hinge chain's own
equilibrium there, the start the theory compares with); the box is square,
half width ``hx`` and half height ``BOX_HEIGHT/2``, placed so that a corner
capsule (radius ``r_corner``) along each bottom edge touches the start shape
(:func:`~simgrip.sim.workpiece.corner_placement`: the same ``hx`` and height
as the planar box; the start is kept in the model, :func:`cradle_start_angles`,
the shape every settle of the scene starts from); every link within ``contact_window`` of the contact's
arc length gets a contact pair with its finger's edge, no other pair.  The
box weighs ``4 M``.  The fingers carry no tip sphere (as the planar cradle).

Well-posedness of a settled state (checked by the settle): the planar
condition (23) (the rod beyond the contact stays below the box), and the
fingers beyond the contact stay off the palm axis (``X > sqrt(2) r_link``),
where the four fingers' planes meet.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from simgrip.chain import chain_springs
from simgrip.params import DimensionlessParams, Grip, PhysicalParams
from simgrip.profiles import as_profile
from simgrip.sim.contacts import add_pair
from simgrip.sim.fingers import add_fingers, check_finger_links
from simgrip.sim.scene import DEFAULT_R_CORNER, check_params, check_positive, root_spec, set_joint_angles
from simgrip.sim.workpiece import BOX_HEIGHT, contact_links, corner_placement, cradle_start, workpiece_inertia
from simgrip.gripper.model import compile_gripper, finger_azimuths, orient_fingers, workpiece_body_mass

__all__ = ["CRADLE_FINGERS", "DEFAULT_CONTACT_WINDOW", "START_NUMERIC", "build_cradle", "corner_name", "cradle_start_angles"]

#: Fingers of a K-finger cradle (one per face of the box).
CRADLE_FINGERS = (4,)
#: Links within this arc length (over l) of the start's contact get a pair with their edge (as the planar scene).
DEFAULT_CONTACT_WINDOW = 0.35

#: Name of the model's custom numeric field holding the start's joint angles (every finger's).
START_NUMERIC = "cradle_start"

_WORKPIECE_GEOM = "workpiece_geom"


def corner_name(k: int) -> str:
    """Name of the capsule along the bottom edge finger ``k`` carries."""
    return f"corner{k}"


def cradle_start_angles(model) -> np.ndarray:
    """The joint angles [rad] a cradle was built with (the box placed on them), from the compiled model."""
    i = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_NUMERIC, START_NUMERIC)
    if i < 0:
        raise ValueError(f"model has no '{START_NUMERIC}' field: not a cradle built by build_cradle")
    a = int(model.numeric_adr[i])
    return np.array(model.numeric_data[a:a + int(model.numeric_size[i])])


def build_cradle(params: PhysicalParams | DimensionlessParams, profile, n_links: int, *, fingers: int = 4,
                 yaw: float = 0.0, r_tip: float, r_link: float, r_corner: float = DEFAULT_R_CORNER,
                 initial_angles=None, contact_window: float = DEFAULT_CONTACT_WINDOW):
    """Build and compile the K = 4 cradle (see the module docstring); a :class:`~simgrip.gripper.scene.GripperScene`.

    ``params``: ``M`` per finger, ``gamma`` the contact's arc length the
    default start crosses ``X = b/2`` at; ``profile`` one profile (every
    finger's); ``initial_angles`` (n,) or (K, n) with equal rows;
    ``r_tip`` is recorded only (no tip sphere); ``r_link``, ``r_corner`` over
    ``l``.  ValueError naming the bad argument (``b`` when the box's corner
    would not sit at ``x > 0`` on the start shape).
    """

    if isinstance(fingers, bool) or fingers not in CRADLE_FINGERS:
        raise ValueError(f"fingers must be one of {CRADLE_FINGERS} for Grip III (one finger per face of the box), "
                         f"got {fingers!r}")
    K = int(fingers)
    dimless, phys = check_params(params)
    if isinstance(profile, (list, tuple, np.ndarray)):
        raise ValueError("profile must be one profile for Grip III (every finger carries its edge alike)")
    prof = as_profile(profile)
    n = check_finger_links(n_links)
    r_link = check_positive("r_link", r_link, 0.05)
    r_corner = check_positive("r_corner", r_corner, 0.05)
    contact_window = check_positive("contact_window", contact_window, 1.0)
    springs = chain_springs(prof, n)
    if initial_angles is None:
        q0 = cradle_start(dimless.b, dimless.gamma, prof, n)
    else:
        q = np.asarray(initial_angles, dtype=float)
        if q.shape not in ((n,), (K, n)) or not np.all(np.isfinite(q)) or (q.ndim == 2 and np.any(q != q[:1])):
            raise ValueError(f"initial_angles must be {n} finite joint angles (or {K}x{n} equal rows) for Grip III, "
                             f"got shape {q.shape}")
        q0 = np.array(q if q.ndim == 1 else q[0])
    L = phys.length
    hx, zc, s = corner_placement(q0, springs, dimless.b, dimless.gamma, r_link, r_corner, L)
    if not hx > 0.0:
        raise ValueError(f"b = {dimless.b:g} is too narrow for Grip III: on the start shape the box's edge would sit "
                         f"at x = {hx / L:.3g} l <= 0")
    links = contact_links(s, springs, contact_window)
    hz = 0.5 * BOX_HEIGHT * L
    size = np.array([hx, hx, hz])

    spec = root_spec(f"simgrip_gripper_III_{K}box_{n}", phys.g)
    spec.add_numeric(name=START_NUMERIC, data=[float(v) for v in q0], size=n)  # the settle starts from it
    add_fingers(spec, spec.worldbody, springs, fingers=K, length=L, EI=phys.EI, rho=phys.rho, r_link=r_link * L)
    azimuths = finger_azimuths(K, yaw)
    orient_fingers(spec, azimuths)
    body = spec.worldbody.add_body(name="workpiece_body", pos=[0.0, 0.0, zc + hz],
                                   quat=[math.cos(0.5 * yaw), 0.0, 0.0, math.sin(0.5 * yaw)])
    body.add_freejoint(name="workpiece_free")
    body.explicitinertial = True
    mass = workpiece_body_mass(phys, K)  # M = 0: MuJoCo needs a massive free body (the floor)
    body.mass = mass
    body.ipos = [0.0, 0.0, 0.0]
    body.inertia = [max(v, 10.0 * mujoco.mjMINVAL) for v in workpiece_inertia("box", size, mass)]
    body.add_geom(spec.find_default("workpiece"), name=_WORKPIECE_GEOM, type=mujoco.mjtGeom.mjGEOM_BOX,
                  size=list(size))
    corner_cls = spec.find_default("corner")
    for k in range(K):  # in the box's frame: finger k's face normal e, the edge along t = perp(e)
        a = float(azimuths[k]) - yaw
        e, t = np.array([math.cos(a), math.sin(a)]), np.array([-math.sin(a), math.cos(a)])
        p0, p1 = hx * e - hx * t, hx * e + hx * t
        body.add_geom(corner_cls, name=corner_name(k), fromto=[p0[0], p0[1], -hz, p1[0], p1[1], -hz],
                      size=[r_corner * L, 0.0, 0.0])
        for i in links:
            add_pair(spec, f"pair_f{k}_link{i}", f"f{k}_geom{i}", corner_name(k), phys.mu_s)

    scene = compile_gripper(
        spec, fingers=K, n=n, grip=Grip.III, workpiece="box", params=dimless, physical=phys, profile=prof,
        springs=springs, azimuths=azimuths, yaw=float(yaw), size=size, r_tip=float(r_tip), r_link=r_link,
        contact_angle=0.0, profiles=(prof,) * K, finger_springs=(springs,) * K, reach=np.full(K, 0.5 * dimless.b),
        normals=np.tile([1.0, 0.0], (K, 1)))
    set_joint_angles(scene, np.tile(q0, (K, 1)))
    return scene

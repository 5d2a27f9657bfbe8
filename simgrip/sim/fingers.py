"""The soft fingers as MuJoCo bodies: :func:`add_fingers` builds them, :class:`FingerIndex` finds them.

A finger of ``n`` links is the hinge chain of :mod:`simgrip.chain`: link ``i``
is a rigid body of mass ``rho ds`` centred at its midpoint, nested in link
``i - 1`` one link length further along its ``x`` axis; hinge ``i`` at the
link's root has stiffness ``(EI/l) * springs.stiffness[i]`` and spring
reference (``springref`` / ``model.qpos_spring``) ``springs.rest[i]``.  Hinges
turn about ``-y`` so that a positive joint angle is a counter-clockwise
``theta`` in the ``x-z`` plane.  Finger 0 points along ``+x`` from its
parent's origin, finger 1 is its mirror image along ``-x``.  Each link carries
a capsule along its centreline (radius ``r_link``), and the last link may
carry a tip sphere (radius ``r_tip``) centred on the finger's end.  The joint
and geom attributes shared by every finger are the default classes ``finger``
and ``tip`` of ``models/finger.xml``, which the scene's root MJCF includes.

Names: ``{prefix}f{f}_link{i}`` (bodies), ``{prefix}f{f}_joint{i}``,
``{prefix}f{f}_geom{i}`` and ``{prefix}f{f}_tip``.  :class:`FingerIndex` turns
them into the qpos / dof / body / geom addresses once, after compiling; the
scene builder and the pick environment both read their fingers through it.

MuJoCo limits how deep bodies may nest (:data:`MAX_BODY_DEPTH`), so a finger
has at most :func:`max_links` links; :func:`check_finger_links` refuses more
before anything is built.  Building the chain costs ``O(n)``; MuJoCo's compile
of a serial chain grows much faster (its constants need the dense
``n x n`` joint-space inertia of the chain).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np

from simgrip.chain import ChainSprings, check_links

__all__ = [
    "MAX_BODY_DEPTH",
    "FingerIndex",
    "add_fingers",
    "check_finger_links",
    "finger_names",
    "index_fingers",
    "max_links",
]

#: Deepest body MuJoCo compiles, counted from the world body (depth 0).
MAX_BODY_DEPTH = 1023

_MIRROR_QUAT = (0.0, 0.0, 0.0, 1.0)  # rotation by pi about z


def max_links(parent_depth: int = 0) -> int:
    """Most links a finger can have when its root body hangs from a body at ``parent_depth``."""
    return MAX_BODY_DEPTH - int(parent_depth)


def check_finger_links(n_links, parent_depth: int = 0, name: str = "links") -> int:
    """``n_links`` as an int within ``[2, max_links(parent_depth)]``; ValueError naming ``name`` otherwise."""
    try:
        n = check_links(n_links)
    except ValueError as exc:
        raise ValueError(str(exc).replace("links must", f"{name} must", 1)) from None
    top = max_links(parent_depth)
    if n > top:
        raise ValueError(f"{name} must be at most {top} (MuJoCo nests bodies at most {MAX_BODY_DEPTH} deep), got {n}")
    return n


def finger_names(f: int, i: int, prefix: str = "") -> tuple[str, str, str]:
    """``(body, joint, geom)`` names of link ``i`` of finger ``f``."""
    return f"{prefix}f{f}_link{i}", f"{prefix}f{f}_joint{i}", f"{prefix}f{f}_geom{i}"


def add_fingers(
    spec: mujoco.MjSpec,
    parent,
    springs: ChainSprings,
    *,
    fingers: int,
    length: float,
    EI: float,
    rho: float,
    r_link: float,
    r_tip: float | None = None,
    damping_time: float = 0.0,
    armature: float = 0.0,
    prefix: str = "",
) -> None:
    """Add ``fingers`` (1 or 2) mirrored hinge chains under the body ``parent`` of ``spec``.

    Parameters
    ----------
    spec : mujoco.MjSpec
        Must hold the default classes ``finger`` and ``tip`` (``models/finger.xml``).
    parent : mujoco.MjsBody
        The fingers' roots sit at its origin (the clamp).
    springs : ChainSprings
        Dimensionless springs of one finger (``springs.n`` links).
    fingers : int
    length, EI, rho : float
        Finger length [m], bending stiffness [N m^2], mass per length [kg/m].
    r_link : float
        Link capsule radius [m] (contact geometry of Grip III; the mechanics is the centreline).
    r_tip : float or None
        Tip sphere radius [m]; ``None`` adds no tip.
    damping_time : float
        Hinge damping over hinge stiffness [s] (``damping = damping_time * stiffness``).
    armature : float
        Hinge armature [kg m^2].
    prefix : str
        Prepended to every name.
    """
    n = springs.n
    ds = length / n
    finger_cls = spec.find_default("finger")
    tip_cls = spec.find_default("tip")
    if finger_cls is None or tip_cls is None:
        raise ValueError("spec must include models/finger.xml (default classes 'finger' and 'tip')")
    stiffness = (EI / length) * springs.stiffness
    mass = rho * ds
    inertia_perp = mass * (ds**2 / 12.0 + r_link**2 / 4.0)
    inertia_axis = 0.5 * mass * r_link**2
    fromto = [0.0, 0.0, 0.0, ds, 0.0, 0.0]
    for f in range(fingers):
        body = parent
        for i in range(n):
            body_name, joint_name, geom_name = finger_names(f, i, prefix)
            body = body.add_body(name=body_name, pos=[ds if i else 0.0, 0.0, 0.0])
            if i == 0 and f == 1:
                body.quat = list(_MIRROR_QUAT)
            body.explicitinertial = True
            body.mass = mass
            body.ipos = [0.5 * ds, 0.0, 0.0]
            body.inertia = [inertia_axis, inertia_perp, inertia_perp]
            joint = body.add_joint(finger_cls, name=joint_name, stiffness=float(stiffness[i]),
                                   springref=float(springs.rest[i]))
            if damping_time:
                joint.damping = [float(damping_time * stiffness[i]), 0.0, 0.0]
            if armature:
                joint.armature = float(armature)
            body.add_geom(finger_cls, name=geom_name, fromto=fromto, size=[r_link, 0.0, 0.0])
        if r_tip is not None:
            body.add_geom(tip_cls, name=f"{prefix}f{f}_tip", pos=[ds, 0.0, 0.0], size=[r_tip, 0.0, 0.0])


@dataclass(frozen=True)
class FingerIndex:
    """Addresses of the fingers in a compiled model (arrays are read-only).

    Attributes
    ----------
    fingers, n : int
        Fingers and links per finger.
    joint_qpos, joint_dof : ndarray (fingers, n)
        qpos / dof addresses of the hinges.
    link_body, link_geom : ndarray (fingers, n)
        Body and capsule geom ids of the links.
    tip_geom : ndarray (fingers,)
        Tip sphere geom ids (-1 where there is no tip).
    finger_of_geom : ndarray (ngeom,)
        The finger a geom belongs to (link capsule or tip), -1 for every other geom.
    """

    fingers: int
    n: int
    joint_qpos: np.ndarray
    joint_dof: np.ndarray
    link_body: np.ndarray
    link_geom: np.ndarray
    tip_geom: np.ndarray
    finger_of_geom: np.ndarray

    @property
    def hinge_qpos(self) -> slice | None:
        """The slice of ``qpos`` holding every hinge (finger 0 then 1), or None when not contiguous."""
        flat = self.joint_qpos.ravel()
        if np.array_equal(flat, np.arange(flat[0], flat[0] + flat.size)):
            return slice(int(flat[0]), int(flat[0]) + flat.size)
        return None


def index_fingers(model: mujoco.MjModel, fingers: int, n: int, prefix: str = "") -> FingerIndex:
    """Find the fingers :func:`add_fingers` built (same ``fingers``, ``n``, ``prefix``) in ``model``."""

    def ids(kind, names):
        out = np.array([mujoco.mj_name2id(model, kind, name) for name in names], dtype=int)
        if np.any(out < 0):
            raise ValueError(f"model has no finger element named {names[int(np.argmin(out))]!r}")
        return out

    grid = [(f, i) for f in range(fingers) for i in range(n)]
    joints = ids(mujoco.mjtObj.mjOBJ_JOINT, [finger_names(f, i, prefix)[1] for f, i in grid]).reshape(fingers, n)
    bodies = ids(mujoco.mjtObj.mjOBJ_BODY, [finger_names(f, i, prefix)[0] for f, i in grid]).reshape(fingers, n)
    geoms = ids(mujoco.mjtObj.mjOBJ_GEOM, [finger_names(f, i, prefix)[2] for f, i in grid]).reshape(fingers, n)
    tips = np.array([mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, f"{prefix}f{f}_tip") for f in range(fingers)],
                    dtype=int)
    owner = np.full(model.ngeom, -1, dtype=int)
    for f in range(fingers):
        owner[geoms[f]] = f
        if tips[f] >= 0:
            owner[tips[f]] = f
    arrays = dict(joint_qpos=np.array(model.jnt_qposadr[joints]), joint_dof=np.array(model.jnt_dofadr[joints]),
                  link_body=bodies, link_geom=geoms, tip_geom=tips, finger_of_geom=owner)
    for a in arrays.values():
        a.setflags(write=False)
    return FingerIndex(fingers=fingers, n=n, **arrays)

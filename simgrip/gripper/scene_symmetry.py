"""Whether a K-finger scene (:mod:`simgrip.gripper.scene`) is exactly symmetric, read from its compiled model.

Where it is, every finger is the same planar problem and the K-finger
settle may be one finger's (:mod:`simgrip.gripper.symmetry`).
:func:`symmetry` reads the compiled model, not the builder's arguments, so
that whatever the builder learns to do (offsets, turns, per-finger
curvature) is seen.  Exact means:

* the fingers are identical (hinge stiffness and rest angles, link masses,
  inertias and frames, geom sizes, every contact pair's friction), their
  roots at the palm's origin, evenly spaced in azimuth (``2 pi / K``), with
  gravity along the palm axis, and their springs those of the scene's
  ``profile``;
* the workpiece starts on the palm axis (its free joint's ``qpos0``; any
  scene attribute named ``*offset*`` is zero), upright, and every finger's
  plane meets the same surface head on at ``b/2 - r_tip`` from the axis: a
  box face whose normal is the finger's ``E1`` (box ``K`` = 2, 4), a
  vertical cylinder (any turn about its axis), a sphere (one contact angle);
* Grips I/II: one tip--workpiece contact pair per finger and no other;
  Grip III (the K = 4 cradle, :mod:`simgrip.gripper.cradle`): every
  finger's links in the same window paired with one edge, the edges alike in
  the fingers' frames (along ``E3`` at the same place).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from simgrip.chain import chain_springs
from simgrip.gripper.scene import GripperScene

__all__ = ["EQUAL_RTOL", "SYMMETRIC_GRIPS", "Symmetry", "cradle_edges", "symmetry"]

#: Grips the skip covers (III: the K = 4 cradle, :mod:`simgrip.gripper.cradle`).
SYMMETRIC_GRIPS = ("I", "II", "III")
#: Relative round-off within which two model arrays count as equal (the builder computes every
#: finger's from the same numbers; trigonometry of the azimuths leaves a few ulps).
EQUAL_RTOL = 1e-9


@dataclass(frozen=True)
class Symmetry:
    """Whether the K-finger scene is exactly symmetric; ``reason`` says why not (empty when it is)."""

    exact: bool
    reason: str = ""


def _same(a) -> bool:
    """All rows of ``a`` (leading axis: the fingers) equal to the first, to round-off of its largest entry."""
    a = np.asarray(a, dtype=float)
    return bool(np.all(np.abs(a - a[:1]) <= EQUAL_RTOL * float(np.max(np.abs(a), initial=0.0))))


def _yaw_of(quat) -> tuple[float, float]:
    """``(yaw about z, tilt)`` of a unit quaternion ``(w, x, y, z)``: tilt is ``|(x, y)|``."""
    w, x, y, z = (float(v) for v in quat)
    return 2.0 * math.atan2(z, w), math.hypot(x, y)


def _wrap(a):
    return (np.asarray(a, dtype=float) + math.pi) % (2.0 * math.pi) - math.pi


def symmetry(scene: GripperScene) -> Symmetry:
    """Whether every finger of ``scene`` is the same planar problem (see the module docstring)."""
    if not isinstance(scene, GripperScene):
        raise ValueError(f"scene must be a simgrip.gripper.scene.GripperScene, got {type(scene).__name__}")
    m, K, n, L = scene.model, scene.fingers, scene.n, scene.length
    if scene.grip not in SYMMETRIC_GRIPS:
        return Symmetry(False, f"grip {scene.grip} (the skip covers {SYMMETRIC_GRIPS})")
    if np.any(np.asarray(m.opt.gravity[:2]) != 0.0):
        return Symmetry(False, "gravity is not along the palm axis")
    jnt = m.dof_jntid[scene.joint_dof]
    bodies = scene.index.link_body
    link_geoms = scene.index.link_geom
    checks = {
        "hinge stiffness": m.jnt_stiffness[jnt],
        "hinge rest angles": m.qpos_spring[scene.joint_qpos],
        "link masses": m.body_mass[bodies],
        "link inertias": m.body_inertia[bodies],
        "link frames": np.concatenate([m.body_pos[bodies[:, 1:]], m.body_quat[bodies[:, 1:]]], axis=2),
        "link geoms": m.geom_size[link_geoms],
    }
    if np.all(scene.tip_geom >= 0):
        checks["tip spheres"] = m.geom_size[scene.tip_geom][:, :1]
    elif np.any(scene.tip_geom >= 0):
        return Symmetry(False, "some fingers have tip spheres and some not")
    for what, arr in checks.items():
        if not _same(arr):
            return Symmetry(False, f"the fingers differ in their {what}")
    for name, value in vars(scene).items():
        if "offset" in name and value is not None and np.any(np.asarray(value, dtype=float) != 0.0):
            return Symmetry(False, f"the workpiece is off the palm axis ({name} = {value!r})")
    sp = chain_springs(scene.profile, n)
    if not (np.allclose(m.qpos_spring[scene.joint_qpos[0]], sp.rest, rtol=0.0, atol=EQUAL_RTOL)
            and np.allclose(m.jnt_stiffness[jnt[0]], scene.physical.EI / L * sp.stiffness, rtol=EQUAL_RTOL, atol=0)):
        return Symmetry(False, "the scene's profile does not give its fingers' springs")
    # roots at the palm's origin, evenly spaced in azimuth, turned about z only
    roots = bodies[:, 0]
    if np.max(np.abs(m.body_pos[roots])) > EQUAL_RTOL * L:
        return Symmetry(False, "a finger's root is off the palm's origin")
    yaws, tilts = zip(*(_yaw_of(q) for q in m.body_quat[roots]))
    if max(tilts) > EQUAL_RTOL:
        return Symmetry(False, "a finger's root is tilted")
    spacing = np.sort((np.asarray(yaws) - yaws[0]) % (2.0 * math.pi))
    if np.max(np.abs(_wrap(spacing - 2.0 * math.pi * np.arange(K) / K))) > 1e-9:
        return Symmetry(False, "the fingers are not evenly spaced about the palm axis")
    # the contact pairs: one per finger, tip with the workpiece (III: its links with its edge), the same friction
    pairs = sorted((int(m.pair_geom1[i]), int(m.pair_geom2[i])) for i in range(m.npair))
    if scene.grip == "III":
        why = _cradle_pairs(scene, pairs, np.asarray(yaws))
        if why:
            return Symmetry(False, why)
    elif pairs != sorted((int(g), int(scene.workpiece_geom)) for g in scene.tip_geom):
        return Symmetry(False, "the contact pairs are not one tip--workpiece pair per finger")
    if not _same(m.pair_friction):
        return Symmetry(False, "the contact pairs' friction differs")
    # the workpiece: on the axis, upright, every finger meeting the same surface head on
    q0 = np.asarray(m.qpos0[scene.workpiece_qpos])
    if np.max(np.abs(q0[:2])) > EQUAL_RTOL * L:
        return Symmetry(False, "the workpiece starts off the palm axis")
    wg = scene.workpiece_geom
    if np.max(np.abs(m.geom_pos[wg])) > EQUAL_RTOL * L:
        return Symmetry(False, "the workpiece's geom is off its body's centre")
    rot = np.zeros(9)
    quat = np.zeros(4)
    mujoco.mju_mulQuat(quat, q0[3:], m.geom_quat[wg])
    mujoco.mju_quat2Mat(rot, quat)
    rot = rot.reshape(3, 3)
    size = np.asarray(m.geom_size[wg])
    face = (0.5 * scene.params.b - scene.r_tip) * L
    if scene.grip == "III":  # the cradle's box: any half width, the same along every finger
        face = float(size[0])
    gtype = int(m.geom_type[wg])
    if gtype == int(mujoco.mjtGeom.mjGEOM_SPHERE):
        ok = abs(size[0] - face) <= EQUAL_RTOL * L
        angles = np.atleast_1d(np.asarray(scene.contact_angle, dtype=float))
        if ok and not np.all(angles == angles[0]):
            return Symmetry(False, "the fingers' contact angles differ")
    elif gtype == int(mujoco.mjtGeom.mjGEOM_CYLINDER):
        ok = abs(size[0] - face) <= EQUAL_RTOL * L and abs(rot[2, 2] - 1.0) <= EQUAL_RTOL
    elif gtype == int(mujoco.mjtGeom.mjGEOM_BOX):
        ok = abs(rot[2, 2] - 1.0) <= EQUAL_RTOL
        for a in yaws:
            e = rot.T @ np.array([math.cos(a), math.sin(a), 0.0])  # the finger's E1 in the box's frame
            axis = int(np.argmax(np.abs(e[:2])))
            ok = ok and abs(abs(e[axis]) - 1.0) <= 1e-9 and abs(size[axis] - face) <= EQUAL_RTOL * L
    else:
        ok = False
    if not ok:
        return Symmetry(False, "the fingers do not all meet the workpiece's surface head on at b/2 - r_tip")
    return Symmetry(True)


def _cradle_pairs(scene: GripperScene, pairs, yaws) -> str:
    """Grip III: every finger's links in the same window paired with one edge, the same in its frame; else why not."""
    m, K, L = scene.model, scene.fingers, scene.length
    owner = np.asarray(scene.index.finger_of_geom)
    links, edges = [set() for _ in range(K)], [set() for _ in range(K)]
    for g1, g2 in pairs:
        k = int(owner[g1]) if g1 < owner.size else -1
        if k < 0 or int(m.geom_bodyid[g2]) != scene.workpiece_body:
            return "a contact pair is not a finger's link with the workpiece"
        links[k].add(int(np.nonzero(scene.index.link_geom[k] == g1)[0][0]))
        edges[k].add(g2)
    if any(len(e) != 1 for e in edges) or any(lk != links[0] for lk in links):
        return "the fingers' links are not paired alike, each with one edge"
    q0 = np.asarray(m.qpos0[scene.workpiece_qpos])
    rot = np.zeros(9)
    mujoco.mju_quat2Mat(rot, q0[3:])
    rot = rot.reshape(3, 3)
    seen = []
    for k, (edge,) in enumerate(edges):
        a = float(yaws[k])
        R = np.array([[math.cos(a), math.sin(a), 0.0], [-math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]])
        axis = np.zeros(9)
        mujoco.mju_quat2Mat(axis, m.geom_quat[edge])
        axis = R @ rot @ axis.reshape(3, 3)[:, 2]
        seen.append(np.concatenate([R @ rot @ m.geom_pos[edge] / L, np.abs(axis), m.geom_size[edge] / L,
                                    [int(m.geom_type[edge])]]))
    if not _same(seen) or abs(abs(seen[0][4]) - 1.0) > 1e-9:
        return "the fingers' edges are not alike in their frames (each along E3 at the same place)"
    return ""


def cradle_edges(scene: GripperScene) -> list:
    """Grip III: the edge geom each finger's links are paired with (finger order)."""
    m = scene.model
    owner = np.asarray(scene.index.finger_of_geom)
    edges = {}
    for i in range(m.npair):
        edges.setdefault(int(owner[int(m.pair_geom1[i])]), int(m.pair_geom2[i]))
    return [edges[k] for k in range(scene.fingers)]

"""Holding, moving and reading the workpiece of a built scene (:class:`simgrip.sim.scene.Scene`).

:mod:`simgrip.sim.workpiece` builds the workpiece and places it against the
fingers, below the scene; these functions act on the compiled scene, above
it: the weight held or released, the centre put at a height, a hovering
workpiece lowered onto the fingers, and its pose and slip read back.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from simgrip.sim.scene import Scene

__all__ = ["corners_over_fingers", "hold_workpiece", "lower_onto_fingers", "place_workpiece", "slip_coordinate",
           "workpiece_pose"]


def hold_workpiece(scene: Scene, on: bool) -> None:
    """Hold the workpiece: its weight cancelled by ``qfrc_applied`` on its ``z`` slide (or released)."""
    d = scene.data
    weight = scene.workpiece_mass * scene.physical.g
    for name, dof in zip(scene.workpiece_joints, scene.workpiece_dof):
        d.qfrc_applied[dof] = weight if (on and name == "z") else 0.0


def place_workpiece(scene: Scene, z: float, *, forward: bool = True) -> None:
    """Put the workpiece's centre at height ``z`` [m] (joint or, when fixed, body position), forward.

    ``forward=False`` skips the ``mj_forward`` (``O(n^3)`` in the serial chain's dense mass matrix: ~2 ms at
    ``n = 256``) for a caller whose every reader evaluates MuJoCo at the state itself: the static settle's
    closing (:mod:`simgrip.settle.closing`), whose Newton computes positions, contacts and forces at each
    state it reads and ends with :func:`~simgrip.settle.statics.sync_scene` (``mj_forward`` leaves
    ``qacc_warmstart`` as it finds it, so the settled data are the same bit for bit).
    """
    m, d = scene.model, scene.data
    body_z = float(m.body_pos[scene.workpiece_body][2])
    for name, qa in zip(scene.workpiece_joints, scene.workpiece_qpos):
        d.qpos[qa] = z - body_z if name == "z" else 0.0
    if not scene.free_workpiece:
        m.body_pos[scene.workpiece_body][2] = z
    d.qvel[:] = 0.0
    if forward:
        mujoco.mj_forward(m, d)


def lower_onto_fingers(scene: Scene) -> None:
    """Lower a hovering workpiece (placement round-off) until its nearest pair touches (1e-9 l deep)."""
    m, d = scene.model, scene.data
    wz = [qa for name, qa in zip(scene.workpiece_joints, scene.workpiece_qpos) if name == "z"]
    if not wz or m.npair == 0:
        return
    L = scene.length
    for _ in range(3):
        mujoco.mj_kinematics(m, d)
        gap = min(mujoco.mj_geomDistance(m, d, int(m.pair_geom1[i]), int(m.pair_geom2[i]), L, None)
                  for i in range(m.npair))
        if gap < 0.0:
            break
        d.qpos[wz[0]] -= gap + 1e-9 * L
    mujoco.mj_forward(m, d)


def _ray_segment_distance(c, a, b) -> float:
    """Distance in the ``x``-``z`` plane from the downward vertical ray from ``c`` to the segment ``ab``."""
    cx, cz = c
    (ax, az), (bx, bz) = a, b
    if (ax - cx) * (bx - cx) <= 0.0 and ax != bx:  # the segment spans the ray's line: crossing below c?
        z = az + (bz - az) * (cx - ax) / (bx - ax)
        if z <= cz:
            return 0.0

    def to_ray(px, pz):
        return abs(px - cx) if pz <= cz else math.hypot(px - cx, pz - cz)

    ab = np.array([bx - ax, bz - az])
    t = float(np.clip(np.dot([cx - ax, cz - az], ab) / max(float(ab @ ab), 1e-300), 0.0, 1.0))
    return min(to_ray(ax, az), to_ray(bx, bz), math.hypot(ax + t * ab[0] - cx, az + t * ab[1] - cz))


def corners_over_fingers(scene: Scene, data: mujoco.MjData | None = None) -> bool:
    """Grip III: whether each corner of the workpiece would land on its finger if it fell straight down.

    True when, for every finger ``f``, some link capsule paired with corner ``f``
    (``scene.contact_geoms[f]``: only those collide with it) comes within ``r_link + r_corner`` of the
    vertical ray down from the corner's axis, in the ``x``-``z`` plane of the fingers.  A workpiece out of
    contact with a finger beneath each corner is caught again (a momentary separation: the loaded finger
    moving faster than the damped workpiece); one with a corner over nothing falls away (past the finger's
    tip, or past the links it is paired with).  Positions from ``data`` (default the scene's), current
    kinematics; True for grips other than III.
    """
    if scene.grip != "III" or not scene.has_workpiece:
        return True
    m, d = scene.model, scene.data if data is None else data
    reach = (scene.r_link + scene.r_corner) * scene.length
    for f in range(scene.fingers):
        cg = int(scene.workpiece_geoms[f])
        c = (float(d.geom_xpos[cg][0]), float(d.geom_xpos[cg][2]))
        near = False
        for g in scene.contact_geoms[f]:
            g = int(g)
            axis = d.geom_xmat[g].reshape(3, 3)[:, 2] * float(m.geom_size[g][1])  # capsule half segment
            p = d.geom_xpos[g]
            a, b = (float(p[0] - axis[0]), float(p[2] - axis[2])), (float(p[0] + axis[0]), float(p[2] + axis[2]))
            if _ray_segment_distance(c, a, b) < reach:
                near = True
                break
        if not near:
            return False
    return True


def workpiece_pose(scene: Scene):
    """Workpiece ``(x, z, angle)`` (over l, rad) from the scene's data, or None without one."""
    if not scene.has_workpiece:
        return None
    d, L = scene.data, scene.length
    x = d.xpos[scene.workpiece_body]
    rot = d.xmat[scene.workpiece_body].reshape(3, 3)
    return np.array([x[0] / L, x[2] / L, math.atan2(rot[0, 2], rot[0, 0])])


def slip_coordinate(scene: Scene) -> float:
    """Tangential position (over l) of a Grip I/II contact on the workpiece: tip height minus workpiece height."""
    d = scene.data
    if scene.grip in ("I", "II"):
        return float(d.geom_xpos[scene.tip_geom[0]][2] - d.xpos[scene.workpiece_body][2]) / scene.length
    return 0.0

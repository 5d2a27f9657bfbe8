"""The K-finger gripper's and the elastica reference's states checked as :mod:`simgrip.validity` checks the planar ones.

* :func:`check_gripper_valid` -- a K-finger :class:`~simgrip.gripper.state.GripperState`: every finger
  against itself, every pair of fingers (their common base on the palm axis excepted), every link and tip
  against the held workpiece's 3-D solid (:func:`gripper_solid`: box, cylinder, sphere);
* :func:`reference_violations` -- an :class:`~simgrip.reference.elastica.ElasticaSolution`: the BVP allows
  the rod to pass through itself and the workpiece; its sampled centreline gets the same checks.

Both reuse :func:`simgrip.validity.chain_violations` and :class:`simgrip.validity.Solid` (one implementation).
"""

from __future__ import annotations

import math

import numpy as np

from simgrip.validity import Solid, mark_invalid, chain_violations
from simgrip.validity_hinges import folded_hinges

__all__ = ["REFERENCE_SAMPLES", "check_gripper_valid", "gripper_solid", "gripper_violations", "reference_violations"]


#: Points at which a reference (BVP) centreline is sampled for :func:`reference_violations`: the polyline's
#: chords miss the curve by ``|kappa| h^2 / 8``, ``2.7e-5 l`` at ``|kappa| = 14``, far below the
#: ``DEPTH_FRACTION r_link = 1e-3 l`` the checks resolve.
REFERENCE_SAMPLES = 256


def reference_violations(sol, *, r_link: float | None = None, r_tip: float | None = None,
                         r_corner: float | None = None) -> list[str]:
    """What makes an elastica solution (:class:`~simgrip.reference.elastica.ElasticaSolution`) impossible.

    The BVP solves the idealised problem, which lets the rod pass through itself and the workpiece; its
    centreline (sampled at :data:`REFERENCE_SAMPLES` + 1 points) gets the simulation's checks
    (:func:`chain_violations`) with the simulation's default radii (a rod of radius ``r_link``; Grips I/II
    a tip sphere ``r_tip`` on the face ``X = b/2``; Grip III the corner, radius ``r_corner``, touching the
    rod at ``gamma`` from above), the workpiece's solid built as :func:`planar_solid` builds the
    simulation's; a reference that is not feasible by its own verdict holds no workpiece, and only its
    self-crossing is checked (as a dropped simulated state).  Empty for a valid solution.
    """
    from simgrip.sim.scene import BOX_HEIGHT, DEFAULT_R_CORNER, DEFAULT_R_LINK, DEFAULT_R_TIP

    r_link = DEFAULT_R_LINK if r_link is None else float(r_link)
    r_tip = DEFAULT_R_TIP if r_tip is None else float(r_tip)
    r_corner = DEFAULT_R_CORNER if r_corner is None else float(r_corner)
    s = np.linspace(0.0, 1.0, REFERENCE_SAMPLES + 1)
    P = np.asarray(sol.position_at(s), dtype=float)
    if not np.all(np.isfinite(P)):
        return []
    b = float(sol.params.b)
    solid, tip = None, None
    if not bool(getattr(sol, "feasible", True)):  # it holds nothing (its own verdict): only its self-crossing
        return [m for _, m in chain_violations([P], [P], r_link=r_link, r_tip=None, solid=None,
                                               who="the reference's rod, finger")]
    hz = 0.5 * BOX_HEIGHT
    if sol.grip in ("I", "II"):
        tip = r_tip
        full = Solid("box", np.array([0.0, float(P[-1, 1])]), np.eye(2), np.array([0.5 * b - r_tip, hz]))
        solid = full.clipped(hi=r_tip) if sol.grip == "I" else full.clipped(lo=-r_tip)
    elif sol.grip == "III":
        g = float(sol.gamma)
        th = float(sol.theta_at(np.array([g]))[0])
        c = np.asarray(sol.position_at(np.array([g])), dtype=float).reshape(2)
        nu = np.array([-math.sin(th), math.cos(th)])
        c = c + (r_link + r_corner) * (nu if nu[1] >= 0.0 else -nu)  # the corner on the rod's upper side
        hx = abs(float(c[0]))
        full = Solid("box", np.array([0.0, float(c[1]) + hz]), np.eye(2), np.array([hx, hz]),
                     np.array([[hx, -hz], [-hx, -hz]]), r_corner)
        solid = full.clipped(hi=-hz + 2.0 * r_link)
    found = chain_violations([P], [P], r_link=r_link, r_tip=tip, solid=solid, who="the reference's rod, finger")
    return [m for _, m in found]


def _quat_matrix(q) -> np.ndarray:
    """Rotation matrix (local -> world) of a unit quaternion ``(w, x, y, z)``."""
    w, x, y, z = (float(v) for v in np.asarray(q, dtype=float) / max(float(np.linalg.norm(q)), 1e-300))
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def gripper_solid(scene, state) -> Solid | None:
    """The K-finger workpiece's solid in the world frame over ``l`` (:func:`planar_solid`'s least solid, in 3-D).

    Box and cylinder are :data:`~simgrip.sim.workpiece.BOX_HEIGHT` tall (their part on the palm's side of the
    tips is not the workpiece's: cut at the highest tip plus ``r_tip``, Grip I, the lowest less ``r_tip``,
    Grip II); the sphere is the workpiece itself.  The cradle (Grip III): the box's bottom band ``2 r_link``
    high (its edge capsules left out: a lenient, never a false, verdict).
    """
    L = float(scene.length)
    R = _quat_matrix(state.workpiece_quat)
    centre = np.asarray(state.workpiece_position, dtype=float)
    size = np.asarray(scene.size, dtype=float) / L
    shape = getattr(scene, "workpiece", "box")
    if shape == "sphere":
        return Solid("sphere", centre, R.T, np.array([size[0]]))
    full = (Solid("box", centre, R.T, size[:3]) if shape == "box"
            else Solid("cylinder", centre, R.T, np.array([size[0], size[1]])))
    if scene.grip == "III":
        return full.clipped(hi=-float(full.half[-1]) + 2.0 * float(scene.r_link))
    tips = full.local(np.stack([_world_nodes(scene, state, k)[-1] for k in range(state.fingers)]))[:, 2]
    r = float(scene.r_tip)
    return full.clipped(hi=float(np.max(tips)) + r) if scene.grip == "I" else full.clipped(lo=float(np.min(tips)) - r)


def _world_nodes(scene, state, k: int) -> np.ndarray:
    from simgrip.chain import link_positions

    P = link_positions(np.asarray(state.link_angles[k], dtype=float), 1.0 / int(state.links))
    a = float(scene.azimuths[k])
    return P[:, :1] * np.array([math.cos(a), math.sin(a), 0.0]) + P[:, 1:2] * np.array([0.0, 0.0, 1.0])


def gripper_violations(scene, state) -> list[tuple[str, str]]:
    """``(kind, message)`` of every violation of a K-finger settled state (pure; see :func:`check_gripper_valid`)."""
    from simgrip.chain import link_positions

    K, n = int(state.fingers), int(state.links)
    planar = [link_positions(np.asarray(state.link_angles[k], dtype=float), 1.0 / n) for k in range(K)]
    world = [_world_nodes(scene, state, k) for k in range(K)]
    az = np.asarray(scene.azimuths, dtype=float)
    sines = np.abs(np.sin(0.5 * (az[:, None] - az[None, :])))
    solid = gripper_solid(scene, state) if state.held else None
    r_tip = float(scene.r_tip) if scene.grip in ("I", "II") else None
    found = chain_violations(planar, world, r_link=float(scene.r_link), r_tip=r_tip, solid=solid,
                             base_sines=sines, contact_links=_contact_links_of_pairs(scene))
    return found + folded_hinges(state.joint_angles)  # what the nodes cannot show (simgrip.validity_hinges)


def check_gripper_valid(scene, state):
    """:func:`check_valid` for a K-finger :class:`~simgrip.gripper.state.GripperState`; returns ``state``.

    Each finger against itself, every pair of fingers (from the common base on the palm axis: pairs whose
    near ends are so close to it that straight fingers would touch are the palm's joint, not compared),
    and every link and tip against the held workpiece's solid (:func:`gripper_solid`).
    """
    mark_invalid(state, [m for _, m in gripper_violations(scene, state)])
    return state


def _contact_links_of_pairs(scene) -> list:
    """Per finger: the links whose geoms are in a contact pair of the model (the cradle's corner links)."""
    m = scene.model
    paired = set(int(g) for g in np.asarray(m.pair_geom1)) | set(int(g) for g in np.asarray(m.pair_geom2))
    geoms = np.asarray(scene.index.link_geom)
    return [np.nonzero([int(g) in paired for g in geoms[f]])[0] for f in range(geoms.shape[0])]

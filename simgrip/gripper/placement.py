"""Where each finger of a K-finger gripper meets an off-centre, yawed workpiece (:mod:`simgrip.gripper.scene`).

The workpiece of :func:`simgrip.gripper.scene.build_gripper` may sit off the
palm axis (``offset = (dx, dy)`` over ``l``) and turned about its vertical
axis by ``workpiece_yaw`` relative to the fingers; both are given in the
scene's frame, the frame that the scene's ``yaw`` turns with everything
else.  Every finger still bends in its own vertical plane through the palm
axis, so its tip centre meets the workpiece where the finger's half-line
``X E1`` (``X > 0``) leaves the *tip-centre surface*: the workpiece grown by
``r_tip`` (a cylinder of radius ``b/2`` about the workpiece's axis; a box
grown by ``r_tip`` on every face).  :func:`place_fingers` finds, per finger,
that ``X`` (the *reach*, where the settle starts the finger's tip) and the
surface's outward horizontal normal there, in the finger's frame ``(E1, E3)``:
a normal with an ``E3`` part pushes the tip out of the finger's plane, which
the hinges (rigid out of plane) carry.

Box and cylinder have vertical faces, so a tip at any height meets the
surface at the same ``X``.  Geometry the gripper cannot hold is refused
(ValueError naming ``offset`` or ``workpiece_yaw``): the palm axis outside the
workpiece's footprint (a finger would start inside it), a finger meeting
the box on an edge's rounded strip instead of a flat face, or two fingers
with the workpiece off their common plane (it would hang from the line
through the two contacts and swing about it).  A sphere is held
centred only (its tips start on a circle of latitude, :func:`simgrip.gripper.settle`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from simgrip.params import _finite

__all__ = ["Placement", "check_offset", "check_workpiece_yaw", "place_fingers"]


@dataclass(frozen=True)
class Placement:
    """Per finger: the tip centre's ``reach`` ``X`` over ``l`` and the surface's horizontal ``normal`` there.

    ``normal[k] = (along E1, along E3)`` of finger ``k``'s frame (unit, outward
    from the workpiece); ``(1, 0)`` for a centred, unturned workpiece.
    ``face[k]``: which face a box finger touches (``0 +x, 1 +y, 2 -x, 3 -y`` of
    the box's own frame), ``-1`` for a cylinder or sphere.
    """

    reach: np.ndarray
    normal: np.ndarray
    face: np.ndarray


def check_offset(value) -> np.ndarray:
    """``offset`` as a finite ``(dx, dy)`` over ``l``; ValueError naming ``offset`` otherwise."""
    try:
        if isinstance(value, (str, bytes)) or any(isinstance(c, (str, bytes, bool, np.bool_)) for c in value):
            raise TypeError  # ('0.01', '0') was read as numbers; a bool is not one
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"offset must be two real numbers (dx, dy) over l, got {value!r}") from None
    if v.shape != (2,) or not np.all(np.isfinite(v)):
        raise ValueError(f"offset must be two finite numbers (dx, dy) over l, got {value!r}")
    return v + 0.0  # no negative zeros


def check_workpiece_yaw(value) -> float:
    """``workpiece_yaw`` [rad] as a finite float; ValueError naming ``workpiece_yaw`` otherwise.

    Whether a box's fingers still meet flat faces at that turn is checked by :func:`place_fingers`.
    """
    return _finite("workpiece_yaw", value, unit="radians")


def place_fingers(shape: str, azimuths, size_l, r_tip: float, offset, workpiece_yaw: float) -> Placement:
    """Where every finger's tip centre meets the workpiece (see the module docstring).

    Parameters
    ----------
    shape : {"box", "cylinder", "sphere"}
    azimuths : array (K,)
        The fingers' azimuths in the scene's frame [rad] (without the scene's ``yaw``).
    size_l : array (3,)
        The workpiece geom's size over ``l`` (box half sizes; cylinder, sphere: radius first).
    r_tip : float
        Tip sphere radius over ``l``.
    offset : array (2,)
        The workpiece's centre over ``l``, scene frame.
    workpiece_yaw : float
        The workpiece's turn about its vertical axis [rad], scene frame.

    Raises
    ------
    ValueError
        Naming ``offset`` (the palm axis outside the footprint, a sphere off the
        axis) or ``workpiece_yaw`` (a box finger on an edge).
    """
    c = np.asarray(offset, dtype=float)
    az = np.asarray(azimuths, dtype=float)
    K = len(az)
    reach, normal, face = np.zeros(K), np.zeros((K, 2)), np.full(K, -1)
    if shape == "sphere":
        if np.any(c != 0.0):
            raise ValueError(f"offset must be (0, 0) for workpiece 'sphere' (held centred only), got ({float(c[0]):g}, {float(c[1]):g})")
        reach[:] = size_l[0] + r_tip
        normal[:, 0] = 1.0
        return Placement(reach, normal, face)
    if K == 2 and abs(float(c @ np.array([-math.sin(az[0]), math.cos(az[0])]))) > 0.0:
        raise ValueError(f"offset must lie along the fingers' plane for fingers = 2 (across it the workpiece hangs "
                         f"from the line through the two contacts and swings about it), got ({float(c[0]):g}, {float(c[1]):g})")
    if shape == "cylinder":
        R = size_l[0] + r_tip
        if not math.hypot(*c) < size_l[0]:
            raise ValueError(f"offset must keep the palm axis inside the cylinder (|offset| < {size_l[0]:g} l), "
                             f"got ({float(c[0]):g}, {float(c[1]):g})")
        for k, a in enumerate(az):
            e1, e3 = np.array([math.cos(a), math.sin(a)]), np.array([-math.sin(a), math.cos(a)])
            along, across = float(c @ e1), float(c @ e3)
            reach[k] = along + math.sqrt(R * R - across * across)
            nw = (reach[k] * e1 - c) / R
            normal[k] = [nw @ e1, nw @ e3]
        return Placement(reach, normal, face)
    # box: leave the grown box (half sizes h + r_tip) along the finger's half-line, in the box's frame
    ca, sa = math.cos(workpiece_yaw), math.sin(workpiece_yaw)
    rot = np.array([[ca, -sa], [sa, ca]])  # box frame -> scene frame
    half = np.asarray(size_l[:2], dtype=float)
    o = rot.T @ (-c)  # the palm axis in the box's frame
    if not np.all(np.abs(o) < half):
        raise ValueError(f"offset must keep the palm axis inside the box's footprint (|dx|, |dy| within its half "
                         f"sizes ({half[0]:g}, {half[1]:g}) l, turned by workpiece_yaw), got ({float(c[0]):g}, {float(c[1]):g})")
    for k, a in enumerate(az):
        e1, e3 = np.array([math.cos(a), math.sin(a)]), np.array([-math.sin(a), math.cos(a)])
        u = rot.T @ e1
        best, axis = math.inf, -1
        for i in range(2):
            if abs(u[i]) > 1e-15:
                t = (math.copysign(half[i] + r_tip, u[i]) - o[i]) / u[i]
                if 0.0 < t < best:
                    best, axis = t, i
        hit = o + best * u
        other = 1 - axis
        if not abs(hit[other]) < half[other]:
            raise ValueError(f"offset / workpiece_yaw: finger {k}'s plane meets the box on an edge (the tip would "
                             f"touch its rounded strip, not a flat face); offset {tuple(float(v) for v in c)}, "
                             f"workpiece_yaw {workpiece_yaw:g} rad")
        n_box = np.zeros(2)
        n_box[axis] = math.copysign(1.0, u[axis])
        nw = rot @ n_box
        reach[k] = best
        normal[k] = [nw @ e1, nw @ e3]
        face[k] = axis + (0 if u[axis] > 0 else 2)
    return Placement(reach, normal, face)

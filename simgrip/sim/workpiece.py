"""The workpiece: a rigid box and where it is placed against the fingers (how a built one is held, moved and
read: :mod:`simgrip.sim.workpiece_motion`).

Geometry (the contact centreline where the theory puts it):

* Grips I/II: the finger's tip sphere (radius ``r_tip``) is centred at
  ``s = l``; the box face is at ``x = b/2 - r_tip``, so a touching tip has its
  centreline at ``X(l) = b/2``.  The box's centre starts level with the tip of
  the start shape.
* Grip III: a capsule (radius ``r_corner``) along ``y`` on each lower edge of
  the box touches the link capsules (radius ``r_link``).  It is placed
  ``r_link + r_corner`` from the start shape's centreline along the normal, at
  the point where the centreline crosses ``X = b/2`` heading inwards (the
  crossing nearest ``gamma``; :func:`cradle_contact`).  Only links within
  ``contact_window`` of that point get a contact pair.

The box is free in the plane between two fingers (slide ``x``, slide ``z``,
hinge ``y``), slides in ``z`` only in the symmetric reduction (one finger:
half the weight, its ``x`` held by the missing mirror finger), or is fixed.

:func:`cradle_start` is a Grip III start shape made of a straight piece and a
circular arc that crosses ``X = b/2`` at ``s = gamma`` heading inwards: pure
geometry, no mechanics.  Friction keeps the contact where it first touches, so
a settle from this start ends near, not at, ``gamma``; the hinge chain's
equilibrium (:func:`simgrip.scenes.start_angles`) is the start that settles at
``gamma`` itself.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from simgrip.chain import ChainSprings, chain_springs, link_positions
from simgrip.models import model_path

__all__ = [
    "BOX_DEPTH",
    "BOX_HEIGHT",
    "add_workpiece",
    "contact_links",
    "corner_placement",
    "cradle_contact",
    "cradle_start",
    "MIN_WORKPIECE_MASS",
    "inertial_mass",
    "workpiece_inertia",
]

#: Box height and depth over ``l``.
BOX_HEIGHT = 2.0  # tall: a frictionless tip slides along the face while closing
BOX_DEPTH = 0.2

#: Least inertial mass of the workpiece per finger over ``rho l`` (:func:`inertial_mass`; its weight stays
#: ``M``).  The K-finger gripper's floor (:data:`simgrip.gripper.scene.MIN_WORKPIECE_MASS`, one value for both):
#: MuJoCo's soft contact rests at a depth proportional to the contact's mobility, i.e. to the workpiece's
#: inverse mass, so a nearly massless workpiece sinks into the finger without bound (the planar dynamics
#: dropped every weightless Grip III workpiece: the corner passed the rod).  Measured on the planar Grip III
#: at M = 0, mu_s = 100 (kappa = -2, -4, -7 at D = 1e-2; -4 at D = 1): from a floor of 1e-3 every one is held in
#: contact where the Newton settle puts it; at 1e-4 one is dropped, below 1e-6 the corner leaves the rod.
MIN_WORKPIECE_MASS = 1e-2

_TURN = 0.75 * math.pi  # turn of the arc of cradle_start (heading 45 degrees inwards at gamma)
_SINC_TURN = math.sin(_TURN) / _TURN


# ---------------------------------------------------------------------------
# placement


def cradle_start(b: float, gamma: float, profile, n: int) -> np.ndarray:
    """Joint angles of a Grip III start shape crossing ``X = b/2`` at ``s = gamma`` heading inwards.

    On ``[0, gamma]`` the centreline is straight for a length ``a`` and then a
    circular arc turning clockwise by ``3 pi / 4`` (``a = 0`` and a larger turn
    when ``b/2 < 0.3 gamma``); beyond ``gamma`` it bends as the rest shape of
    ``profile``.  Link ``i`` takes the centreline's angle at its midpoint.
    Lengths over ``l``.
    """
    h = 0.5 * float(b)
    g = float(gamma)
    if not 0.0 < h < g:
        raise ValueError(f"b/2 must be below gamma for the cradle (Grip III), got b = {b:g}, gamma = {g:g}")
    if h >= _SINC_TURN * g:
        turn = _TURN
        a = (h - _SINC_TURN * g) / (1.0 - _SINC_TURN)
    else:  # sin(turn)/turn = h/g on (3 pi/4, pi), decreasing: bisection
        lo, hi = _TURN, math.pi
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if math.sin(mid) / mid > h / g else (lo, mid)
        turn, a = 0.5 * (lo + hi), 0.0
    c = turn / (g - a)
    s = (np.arange(n) + 0.5) / n
    theta = -c * np.clip(s - a, 0.0, g - a)
    rest = np.cumsum(chain_springs(profile, n).rest)
    beyond = s > g
    theta[beyond] += rest[beyond] - np.interp(g, s, rest)
    return np.diff(np.concatenate(([0.0], theta)))


def cradle_contact(q0, springs: ChainSprings, b: float, gamma: float) -> tuple[float, float, np.ndarray]:
    """Arc length (over l), tangent angle and point of the Grip III contact on the shape ``q0``.

    The contact is where the centreline crosses ``X = b/2`` heading inwards
    (``cos theta < 0``); among those crossings, the one nearest ``gamma``.
    Without such a crossing, the material point at ``gamma``.
    """
    phi = np.cumsum(q0)
    nodes = link_positions(phi, springs.ds)
    x = nodes[:, 0] - 0.5 * b
    cross = np.flatnonzero((x[:-1] * x[1:] <= 0.0) & (x[:-1] != x[1:]) & (np.cos(phi) < 0.0))
    if cross.size:
        t = x[cross] / (x[cross] - x[cross + 1])
        s = (cross + t) * springs.ds
        k = int(np.argmin(np.abs(s - gamma)))
        i, t, s = int(cross[k]), float(t[k]), float(s[k])
    else:
        s = float(gamma)
        i = min(int(s / springs.ds), springs.n - 1)
        t = s / springs.ds - i
    return s, float(phi[i]), nodes[i] + t * (nodes[i + 1] - nodes[i])


def corner_placement(q0, springs: ChainSprings, b: float, gamma: float, r_link: float, r_corner: float,
                     length: float) -> tuple[float, float, float]:
    """``(x, z, s)``: corner capsule centre [m] touching the shape ``q0`` and the contact's arc length (over l)."""
    s, th, point = cradle_contact(q0, springs, b, gamma)
    e2 = np.array([-math.sin(th), math.cos(th)])
    sign = 1.0 if e2[1] <= 0.0 else -1.0  # the box sits above the rod
    corner = (point - sign * (r_link + r_corner) * e2) * length
    return float(corner[0]), float(corner[1]), s


def contact_links(s: float, springs: ChainSprings, window: float) -> np.ndarray:
    """Links whose span lies within ``window`` (over l) of the arc length ``s``."""
    i = np.arange(springs.n)
    ds = springs.ds
    return i[((i + 1) * ds >= s - window) & (i * ds <= s + window)]


# ---------------------------------------------------------------------------
# building


def workpiece_inertia(shape: str, size, mass: float) -> list[float]:
    """Principal inertia [kg m^2] of a solid ``shape`` ("box", "cylinder" with a vertical axis, "sphere") of
    mass ``mass`` [kg] and MuJoCo geom ``size`` [m] (box: half sizes; cylinder: radius, half height; sphere:
    radius), about its centre, in the geom's axes."""
    if shape == "box":
        hx, hy, hz = size
        return [mass / 3.0 * (hy**2 + hz**2), mass / 3.0 * (hx**2 + hz**2), mass / 3.0 * (hx**2 + hy**2)]
    if shape == "cylinder":
        r, h = size[0], size[1]
        side = mass * (3.0 * r**2 + 4.0 * h**2) / 12.0
        return [side, side, 0.5 * mass * r**2]
    r = size[0]
    return [0.4 * mass * r**2] * 3


def inertial_mass(mass: float, fingers: int, rho: float, length: float) -> float:
    """The workpiece body's inertial mass [kg]: ``mass``, at least ``fingers`` :data:`MIN_WORKPIECE_MASS` ``rho l``.

    ``mass`` [kg] is the workpiece's true mass (its weight over ``g``); ``rho`` [kg/m] and ``length`` [m] the
    finger's.  Only the inertia is floored: :func:`add_workpiece` relieves the extra weight by MuJoCo's
    gravity compensation, so every balance sees the weight of ``mass`` (``0`` included).
    """
    return max(float(mass), fingers * MIN_WORKPIECE_MASS * rho * length)


def add_workpiece(spec: mujoco.MjSpec, *, half_size, center_z: float, mass: float, joints: tuple,
                  weight_mass: float | None = None) -> mujoco.MjsBody:
    """Attach ``models/workpiece.xml`` as ``workpiece_body`` with box ``half_size`` [m] centred at ``(0, 0, center_z)``.

    ``mass`` [kg] with the solid box's inertia; ``joints`` any of ``"x"``,
    ``"z"`` (slides) and ``"ry"`` (hinge about ``-y``), named ``workpiece_{name}``.
    ``weight_mass`` [kg] (default ``mass``, at most ``mass``): the mass whose weight gravity puts on the body;
    below ``mass`` the difference is relieved by MuJoCo's gravity compensation (``gravcomp = 1 -
    weight_mass / mass``, a passive force: in ``qfrc_passive``, hence in every ``mj_forward``/``mj_inverse``
    balance and ``mj_step``), so that a floored inertia (:func:`inertial_mass`) keeps the true weight.
    ``weight_mass = 0`` gives ``gravcomp = 1``: exactly weightless.
    """
    part = mujoco.MjSpec.from_file(str(model_path("workpiece.xml")))
    body = spec.worldbody.add_frame().attach_body(part.body("body"), "workpiece_", "")
    hx, hy, hz = (float(v) for v in half_size)
    body.pos = [0.0, 0.0, float(center_z)]
    body.explicitinertial = True
    body.mass = mass
    body.ipos = [0.0, 0.0, 0.0]
    body.inertia = workpiece_inertia("box", (hx, hy, hz), mass)
    if weight_mass is not None:
        if not 0.0 <= weight_mass <= mass:
            raise ValueError(f"weight_mass must lie in [0, mass = {mass:g}] kg, got {weight_mass!r}")
        if weight_mass < mass:
            body.gravcomp = 1.0 - weight_mass / mass
    body.first_geom().size = [hx, hy, hz]
    axes = {"x": [1, 0, 0], "z": [0, 0, 1], "ry": [0, -1, 0]}
    for name in joints:
        kind = mujoco.mjtJoint.mjJNT_HINGE if name == "ry" else mujoco.mjtJoint.mjJNT_SLIDE
        body.add_joint(name=f"workpiece_{name}", type=kind, axis=axes[name])
    return body

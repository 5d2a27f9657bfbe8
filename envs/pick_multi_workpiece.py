"""The workpiece of one episode of the K-finger pick: its parameters, drawn from the ranges or given.

:func:`draw_workpiece` makes every draw from the episode's generator in a
fixed order whatever the ``reset`` options say (so that a seed gives the same
episode otherwise), then lets the options override them, each checked
(``ValueError`` naming it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from simgrip.envs.arguments import check_positive

__all__ = ["WORKPIECE_OPTIONS", "WorkpieceParams", "check_draw_ranges", "draw_workpiece"]

#: The ``reset`` options that fix a workpiece parameter.
WORKPIECE_OPTIONS = ("shape", "width", "mass", "friction", "offset", "yaw")


@dataclass(frozen=True)
class WorkpieceParams:
    """The workpiece of one episode (SI): shape, width [m] (box side, cylinder or sphere diameter), mass [kg],
    finger-workpiece friction, horizontal offset ``(x, y)`` of its centre from the palm axis [m], yaw [rad]."""

    shape: str
    width: float
    mass: float
    friction: float
    offset: tuple
    yaw: float


def draw_workpiece(rng, options: dict, *, shapes, fingers: int, size_range, mass_range, friction_range,
                   offset_max: float, yaw_range, length: float) -> WorkpieceParams:
    """Draw a workpiece with ``rng`` (a :class:`numpy.random.Generator`), then apply ``options``.

    Shape uniform over ``shapes``; width, mass, friction and yaw uniform over their ranges; the offset uniform
    over the disc of radius ``offset_max`` [m] (``fingers = 2``: on the fingers' line ``x``, the radius drawn
    alike: off it, a pinch's two contacts let the workpiece turn about the line through them).  Options (keys of
    :data:`WORKPIECE_OPTIONS`) must be valid: a shape of ``shapes``, positive width (at most ``1.9 length``),
    mass and friction, a finite offset within the fingers' reach ``length``, a finite yaw.
    """
    shape = shapes[int(rng.integers(len(shapes)))]
    width = float(rng.uniform(*size_range))
    mass = float(rng.uniform(*mass_range))
    mu = float(rng.uniform(*friction_range))
    radius = offset_max * math.sqrt(float(rng.uniform()))
    angle = float(rng.uniform(-math.pi, math.pi))
    yaw = float(rng.uniform(*yaw_range))
    if fingers == 2:
        angle = 0.0 if angle >= 0.0 else math.pi
    shape = options.get("shape", shape)
    if shape not in shapes:
        raise ValueError(f"shape must be one of {tuple(shapes)}, got {shape!r}")
    width = check_positive("width", options.get("width", width))
    if width > 1.9 * length:
        raise ValueError(f"width = {width} m is wider than the fingers reach (1.9 length = {1.9 * length} m)")
    mass = check_positive("mass", options.get("mass", mass))
    mu = check_positive("friction", options.get("friction", mu))
    offset = options.get("offset", (radius * math.cos(angle), radius * math.sin(angle)))
    try:
        offset = tuple(float(v) for v in offset)
    except (TypeError, ValueError):
        raise ValueError(f"offset must be an (x, y) pair in metres, got {offset!r}") from None
    if len(offset) != 2 or not all(math.isfinite(v) for v in offset) or math.hypot(*offset) >= length:
        raise ValueError(f"offset must be a finite (x, y) pair within the fingers' reach, got {offset!r}")
    yaw = options.get("yaw", yaw)
    if not isinstance(yaw, (int, float)) or isinstance(yaw, bool) or not math.isfinite(yaw):
        raise ValueError(f"yaw must be a finite number (radians), got {yaw!r}")
    return WorkpieceParams(shape, width, mass, mu, offset, float(yaw))


def check_draw_ranges(*, fingers: int, length: float, EI: float, rho: float, g: float, size_range, mass_range,
                      friction_range, offset_max: float) -> None:
    """Every workpiece the ranges can draw is one the model takes, checked at construction: ValueError naming the
    range otherwise (before, a training run met it at the reset whose draw left the model's range, hours in).

    ``offset_max`` below the fingers' reach ``length`` (what :func:`draw_workpiece` requires of each offset); each
    end of ``size_range``, ``mass_range`` and ``friction_range`` within the paper's parameter space per finger
    (:meth:`simgrip.params.PhysicalParams.dimensionless`: ``m`` = mass / K, ``b`` the width).  Each group is one
    quantity's (``b/l`` the size's, ``M`` the mass's, ``mu_s`` the friction's) and monotonic in it, so each end is
    checked with the other two at values every model takes (no mass, no friction, half a finger wide), and the
    ends bound every draw.  SI units.
    """
    from simgrip.params import PhysicalParams

    if not offset_max < length:
        raise ValueError(f"offset_max must be below the fingers' reach (length = {length} m), got {offset_max!r}")
    neutral = {"size_range": 0.5 * length, "mass_range": 0.0, "friction_range": 0.0}
    for name, ends in (("size_range", size_range), ("mass_range", mass_range), ("friction_range", friction_range)):
        for end in ends:
            v = dict(neutral, **{name: float(end)})
            try:
                PhysicalParams(length=length, EI=EI, rho=rho, g=g, m=v["mass_range"] / fingers, b=v["size_range"],
                               mu_s=v["friction_range"], gamma=0.8 * length).dimensionless()
            except ValueError as exc:
                raise ValueError(f"{name} = {tuple(ends)!r} draws workpieces the model cannot take: {exc}") from None

"""Rod, workpiece and grip parameters: physical (SI) and dimensionless.

Conventions (see ``README.md``): ``E1`` horizontal from the palm centre towards
the finger, ``E2`` vertically up, gravity ``-rho*g*E2``.  Each finger is an
inextensible planar elastica of length ``length`` clamped horizontally at its
base; two identical fingers grip a workpiece of width ``b`` and weight ``2*m*g``
symmetrically, so one finger carries ``m*g``.

Dimensionless groups (paper eq. 24)::

    D = EI / (rho g l^3),  M = m / (rho l),  kappa_bar = l * kappa0,  s_bar = s / l

lengths are scaled by ``l`` and forces by ``rho g l``.  The solvers in this
package all work in dimensionless units (``l = 1``, ``rho g = 1``, so
``EI = D`` and the per-finger workpiece weight is ``M``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

__all__ = ["PhysicalParams", "DimensionlessParams", "GRIPS", "check_grip", "STANDARD"]

#: Grip names understood everywhere in simgrip.
GRIPS = ("free", "I", "II", "III")


def check_grip(grip: str) -> str:
    """Return ``grip`` normalised (``"i"`` -> ``"I"``), or raise ``ValueError`` naming ``grip``."""
    if not isinstance(grip, str):
        raise ValueError(f"grip must be one of {GRIPS}, got {grip!r}")
    g = grip.strip()
    g = g if g == "free" else g.upper()
    if g not in GRIPS:
        raise ValueError(f"grip must be one of {GRIPS}, got {grip!r}")
    return g


def _finite(name: str, value) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return v


def _positive(name: str, value) -> float:
    v = _finite(name, value)
    if v <= 0.0:
        raise ValueError(f"{name} must be positive, got {v!r}")
    return v


def _nonnegative(name: str, value) -> float:
    v = _finite(name, value)
    if v < 0.0:
        raise ValueError(f"{name} must be non-negative, got {v!r}")
    return v


@dataclass(frozen=True)
class DimensionlessParams:
    """The paper's dimensionless groups for one finger and its share of the workpiece.

    Parameters
    ----------
    D : float
        Bending stiffness ``EI / (rho g l^3)``; must be > 0.
    M : float
        Workpiece mass per finger ``m / (rho l)``; must be >= 0.
    b : float
        Workpiece width over rod length ``b / l``; ``0 < b < 2`` (the tip of a
        straight finger reaches ``X = l``, so ``b/2 >= l`` is out of reach).
    mu_s : float
        Coefficient of static friction; must be >= 0.
    gamma : float
        Grip III contact arc length ``gamma / l`` in ``(0, 1)``.
    """

    D: float = 1.0
    M: float = 5.0
    b: float = 0.6
    mu_s: float = 1.0
    gamma: float = 0.8

    def __post_init__(self):
        object.__setattr__(self, "D", _positive("D", self.D))
        object.__setattr__(self, "M", _nonnegative("M", self.M))
        b = _positive("b", self.b)
        if b / 2.0 >= 1.0:
            raise ValueError(
                f"b (workpiece width over finger length) = {b!r}: the workpiece is wider than "
                "the fingers can reach (need b/2 < l)"
            )
        object.__setattr__(self, "b", b)
        object.__setattr__(self, "mu_s", _nonnegative("mu_s", self.mu_s))
        gamma = _finite("gamma", self.gamma)
        if not 0.0 < gamma < 1.0:
            raise ValueError(f"gamma (contact arc length over l) must lie in (0, 1), got {gamma!r}")
        object.__setattr__(self, "gamma", gamma)

    def replace(self, **changes) -> "DimensionlessParams":
        """A copy with some fields changed (validated again)."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        values.update(changes)
        return DimensionlessParams(**values)

    def to_physical(self, length: float = 1.0, rho: float = 1.0, g: float = 9.81) -> "PhysicalParams":
        """Physical parameters with the given length [m], mass per length [kg/m] and gravity [m/s^2]."""
        length = _positive("length", length)
        rho = _positive("rho", rho)
        g = _positive("g", g)
        return PhysicalParams(
            length=length,
            EI=self.D * rho * g * length**3,
            rho=rho,
            g=g,
            m=self.M * rho * length,
            b=self.b * length,
            mu_s=self.mu_s,
            gamma=self.gamma * length,
        )


@dataclass(frozen=True)
class PhysicalParams:
    """Physical parameters in SI units.

    Parameters
    ----------
    length : float
        Finger length ``l`` [m], > 0.
    EI : float
        Bending stiffness [N m^2], > 0.
    rho : float
        Mass per unit length [kg/m], > 0.
    g : float
        Gravitational acceleration [m/s^2], > 0.
    m : float
        Workpiece mass carried by one finger [kg] (half the workpiece), >= 0.
    b : float
        Workpiece width [m]; ``0 < b < 2 l``.
    mu_s : float
        Coefficient of static friction, >= 0.
    gamma : float
        Grip III contact arc length [m], ``0 < gamma < l``.
    """

    length: float = 0.1
    EI: float = 9.81e-4
    rho: float = 0.1
    g: float = 9.81
    m: float = 0.05
    b: float = 0.06
    mu_s: float = 1.0
    gamma: float = 0.08

    def __post_init__(self):
        for name in ("length", "EI", "rho", "g"):
            object.__setattr__(self, name, _positive(name, getattr(self, name)))
        object.__setattr__(self, "m", _nonnegative("m", self.m))
        object.__setattr__(self, "mu_s", _nonnegative("mu_s", self.mu_s))
        b = _positive("b", self.b)
        if b / 2.0 >= self.length:
            raise ValueError(
                f"b = {b!r} m: the workpiece is wider than the fingers can reach (need b/2 < length = {self.length!r} m)"
            )
        object.__setattr__(self, "b", b)
        gamma = _finite("gamma", self.gamma)
        if not 0.0 < gamma < self.length:
            raise ValueError(f"gamma must lie in (0, length) = (0, {self.length!r}) m, got {gamma!r}")
        object.__setattr__(self, "gamma", gamma)

    def dimensionless(self) -> DimensionlessParams:
        """The paper's dimensionless groups ``D, M, b/l, mu_s, gamma/l``."""
        w = self.rho * self.g * self.length  # weight of the rod [N], the force scale
        return DimensionlessParams(
            D=self.EI / (w * self.length**2),
            M=self.m / (self.rho * self.length),
            b=self.b / self.length,
            mu_s=self.mu_s,
            gamma=self.gamma / self.length,
        )

    @property
    def force_scale(self) -> float:
        """``rho g l`` [N]: divide a force by this to make it dimensionless."""
        return self.rho * self.g * self.length


#: The paper's standard case: D = 1, M = 5, mu_s = 1, b/l = 0.6, gamma/l = 0.8.
STANDARD = DimensionlessParams()

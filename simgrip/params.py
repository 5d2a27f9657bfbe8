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

Where the parameter space ends
------------------------------
Every group is validated on construction; a value outside its range raises
``ValueError`` naming the parameter.  The bounds are where the model or its
double-precision numerics stop meaning anything, not where the paper's
figures stop:

* ``D`` in ``[D_MIN, D_MAX] = [1e-2, 1e4]``.  Below: the heavy rod's bending
  boundary layer at the clamp, of length ``~ sqrt(D) l``, is 0.1 l at
  ``D = 1e-2``, three links of the default 32-link chain; a softer finger is
  a hanging string that needs ``n >> 1/sqrt(D)`` links, and the elastica
  BVP, started from the straight rod, converges to a spurious branch near
  ``D = 2e-3`` (free rod, ``kappa = 0``).  Above: the rod's own weight moves
  its tip by ``l/(8 D) = 1.25e-5 l`` at ``D = 1e4``, a tenth of the contact
  tolerance (1e-4 l): a stiffer finger is rigid to the model's resolution
  (the small-deflection limit is tested against linear beam theory there).
  Inside the range, the Newton settle's absolute force residual (1e-10, in
  ``rho g l``) meets the round-off of the spring forces, ``D n pi 2.2e-16``,
  at ``D n ~ 1.4e5``: stiff, finely resolved chains (``D = 1e3`` above ~140
  links, ``D = 1e4`` at 32) stall with a loud ``SettleError`` today.
* ``M`` in ``[0, M_MAX] = [0, 1e4]``.  Forces of size ``M`` carry round-off
  ``M * 2.2e-16``; the settle's force residual is 1e-10 (forces over
  ``rho g l``), which must stay above it with margin: ``M <= 1e4`` keeps two
  orders.  (``M = 1e300`` overflowed in the reference's stability test.)
* ``b`` in ``(0, 2)`` (``b/2 < l``: a straight finger reaches ``X = l``).
* ``mu_s`` in ``[0, MU_MAX] = [0, 100]``.  Real material pairs have
  ``mu_s <~ 4``; at 100 no grip is ever friction-limited, and MuJoCo's
  elliptic friction cone (``impratio`` 1e4) is ill-conditioned beyond.
* ``gamma`` in ``(0, 1)``: the Grip III contact lies on the finger.
* ``|kappa_bar|`` at most ``KAPPA_LIMIT = 100`` (uniform curvature, the peak
  of the concentrated profile; in :mod:`simgrip.profiles`).  A uniform rest
  shape closes on itself at ``2 pi`` (self-contact is not modelled, so beyond
  that the rod passes through itself); 100 (a curl radius of ``l/100``, 16
  turns) is kept as the numerical limit: the chain's rest angle per hinge,
  ``kappa_bar / n``, stays at 0.1 rad at ``n = MAX_LINKS``.
* ``alpha`` (concentrated profile, eq. 34) in ``[0, ALPHA_MAX] = [0, 100]``:
  ``(4 s (1 - s))^alpha ~ exp(-4 alpha (s - 1/2)^2)`` has width
  ``1/sqrt(8 alpha) = 0.035 l`` at 100, about one link of the default chain;
  sharper is a kink the chain and the BVP mesh cannot resolve.
* links per finger in ``[2, MAX_LINKS] = [2, 1000]``.  MuJoCo nests bodies
  at most 1023 deep (:data:`simgrip.sim.fingers.MAX_BODY_DEPTH`), which caps
  a serial chain just above; and the chain is second order, so its error at
  1000 links is ``(32/1000)^2 = 1e-3`` of that at 32 (normal force ~5e-6
  relative, tip ~1e-6 l), below the contact tolerance: more links would buy
  nothing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from enum import Enum

import numpy as np

__all__ = [
    "PhysicalParams",
    "DimensionlessParams",
    "GRIPS",
    "Grip",
    "check_grip",
    "check_grip_iii_reach",
    "STANDARD",
    "D_MIN",
    "D_MAX",
    "M_MAX",
    "MU_MAX",
    "KAPPA_LIMIT",
    "ALPHA_MAX",
    "MAX_LINKS",
    "as_dimensionless",
]

#: Grip names understood everywhere in simgrip.
GRIPS = ("free", "I", "II", "III")

# Bounds of the parameter space; the module docstring says why each is where it is.
#: Softest rod: its clamp boundary layer (~ sqrt(D) l = 0.1 l) spans three links of the default chain.
D_MIN = 1e-2
#: Stiffest rod: self-weight deflection l/(8 D) a tenth of the contact tolerance (rigid to the model's resolution).
D_MAX = 1e4
#: Heaviest workpiece per finger (in rod weights): round-off M * 2.2e-16 stays 1e4 below the settle residual.
M_MAX = 1e4
#: Largest static friction coefficient.
MU_MAX = 100.0
#: Largest ``|kappa_bar|`` (uniform curvature, peak of the concentrated profile).
KAPPA_LIMIT = 100.0
#: Largest concentration exponent of eq. (34): peak width 1/sqrt(8 alpha) = 0.035 l.
ALPHA_MAX = 100.0
#: Most links per finger: under MuJoCo's body depth (1023); error (32/n)^2 of n = 32's, below the contact tolerance.
MAX_LINKS = 1000



class Grip(str, Enum):
    """A grip name that has been checked: what :func:`check_grip` returns.

    A ``str`` equal (and hashing equal) to its name (``Grip.I == "I"``), which
    prints, formats, ``repr``-s and serialises (JSON) as the plain name, so a
    layer that reads a grip reads it as before; a layer handed a ``Grip`` knows
    it is one of :data:`GRIPS` and :func:`check_grip` returns it unchanged
    (parameters are checked once where they enter, issue 21).
    """

    FREE = "free"
    I = "I"  # noqa: E741 (the paper's name)
    II = "II"
    III = "III"

    __hash__ = str.__hash__
    __str__ = str.__str__
    __format__ = str.__format__

    def __repr__(self) -> str:
        return repr(self.value)

    def __reduce_ex__(self, protocol):
        return Grip, (self.value,)


def check_grip(grip) -> Grip:
    """Return ``grip`` checked and normalised (``"i"`` -> ``Grip.I``), or raise ``ValueError`` naming ``grip``.

    A :class:`Grip` is returned as it is (it was checked where it entered).
    """
    if isinstance(grip, Grip):
        return grip
    return _parse_grip(grip)


def _parse_grip(grip) -> Grip:
    """The check itself: ``grip`` as a :class:`Grip` (``"i"``, ``" III "`` accepted), ValueError naming it."""
    if not isinstance(grip, str):
        raise ValueError(f"grip must be one of {GRIPS}, got {grip!r}")
    g = grip.strip()
    g = g if g == "free" else g.upper()
    if g not in GRIPS:
        raise ValueError(f"grip must be one of {GRIPS}, got {grip!r}")
    return Grip(g)


def check_grip_iii_reach(gamma: float, b: float) -> None:
    """Grip III needs ``gamma > b/2`` (both over ``l``): the contact point at arc length ``gamma`` must reach
    the box's corner at ``X = b/2``, and an arc of length ``gamma`` reaches at most ``X = gamma`` (straight).

    Raises ``ValueError`` naming ``gamma`` (the BVP, the scenes and the settle share this one message).
    """
    if not gamma > b / 2.0:
        raise ValueError(f"gamma = {gamma!r} must exceed b/2 = {b / 2.0!r} for Grip III "
                         "(the contact at arc length gamma cannot reach X = b/2)")


def _finite(name: str, value, unit: str | None = None) -> float:
    """``value`` as a finite float; ValueError naming ``name`` (and its ``unit``, e.g. "radians") otherwise.
    A string or a bool is refused, not converted (``D="1"`` was 1.0, ``b=True`` 1.0): docs/limits.md."""
    what = f"a real number ({unit})" if unit else "a real number"
    if isinstance(value, (str, bytes, bool, np.bool_)):
        raise ValueError(f"{name} must be {what}, got {value!r}")
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be {what}, got {value!r}") from None
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


def _ratio(num: float, den: float) -> float:
    """``num / den`` for ``num >= 0``, ``den >= 0``; ``inf`` when ``den`` underflowed to 0 (validation names it)."""
    return num / den if den > 0.0 else (math.inf if num > 0.0 else 0.0)


def _within(name: str, value, lo: float, hi: float, why: str = "") -> float:
    """``value`` as a float in ``[lo, hi]``, or ``ValueError`` naming ``name`` (and why the bound exists)."""
    v = _finite(name, value)
    if not lo <= v <= hi:
        reason = f" ({why})" if why else ""
        raise ValueError(f"{name} must lie in [{lo:g}, {hi:g}], got {v!r}{reason}")
    return v


def _within_reach(b, gamma, length: float, si: bool) -> tuple[float, float]:
    """``(b, gamma)`` as floats with ``0 < b/2 < length`` and ``0 < gamma < length``, or ``ValueError`` naming one.

    ``si``: the values are in metres and ``length`` is ``l`` [m]; else they are over ``l`` (``length = 1``).
    """
    reach, unit = (f"length = {length!r} m", " m") if si else ("l", " (over l)")
    b = _positive("b", b)
    if b / 2.0 >= length:
        raise ValueError(f"b (workpiece width) = {b!r}{unit}: the workpiece is wider than the fingers can reach "
                         f"(need b/2 < {reach})")
    gamma = _finite("gamma", gamma)
    if not 0.0 < gamma < length:
        raise ValueError(f"gamma (contact arc length) must lie in (0, {reach}), got {gamma!r}{unit}")
    return b, gamma


@dataclass(frozen=True)
class DimensionlessParams:
    """The paper's dimensionless groups for one finger and its share of the workpiece.

    Parameters
    ----------
    D : float
        Bending stiffness ``EI / (rho g l^3)``, in ``[D_MIN, D_MAX] = [1e-2, 1e4]``.
    M : float
        Workpiece mass per finger ``m / (rho l)``, in ``[0, M_MAX] = [0, 1e4]``.
    b : float
        Workpiece width over rod length ``b / l``; ``0 < b < 2`` (the tip of a
        straight finger reaches ``X = l``, so ``b/2 >= l`` is out of reach).
    mu_s : float
        Coefficient of static friction, in ``[0, MU_MAX] = [0, 100]``.
    gamma : float
        Grip III contact arc length ``gamma / l`` in ``(0, 1)``.

    The bounds are explained in the module docstring.
    """

    D: float = 1.0
    M: float = 5.0
    b: float = 0.6
    mu_s: float = 1.0
    gamma: float = 0.8

    def __post_init__(self):
        object.__setattr__(self, "D", _within("D", _positive("D", self.D), D_MIN, D_MAX,
                                              "softer hangs like a string, stiffer is rigid to the contact "
                                              "tolerance; see simgrip.params"))
        object.__setattr__(self, "M", _within("M", _nonnegative("M", self.M), 0.0, M_MAX,
                                              "heavier drowns the rod's weight in round-off; see simgrip.params"))
        object.__setattr__(self, "mu_s", _within("mu_s", _nonnegative("mu_s", self.mu_s), 0.0, MU_MAX,
                                                 "no real material pair; never friction-limited"))
        b, gamma = _within_reach(self.b, self.gamma, 1.0, si=False)
        object.__setattr__(self, "b", b)
        object.__setattr__(self, "gamma", gamma)

    def replace(self, **changes) -> "DimensionlessParams":
        """A copy with some fields changed (validated again)."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        values.update(changes)
        return DimensionlessParams(**values)

    def unit_physical(self) -> "PhysicalParams":
        """These groups realised with ``l = rho = g = 1`` (``EI = D``, ``m = M``), as the scenes build them.

        Equal, bit for bit, to ``to_physical(length=1.0, rho=1.0, g=1.0)``, whose products by 1 are exact,
        but not checked again: every field is one of these groups, checked when they were built, and the
        result's :meth:`PhysicalParams.dimensionless` is ``self``.
        """
        p = object.__new__(PhysicalParams)
        for name, value in (("length", 1.0), ("EI", self.D), ("rho", 1.0), ("g", 1.0), ("m", self.M),
                            ("b", self.b), ("mu_s", self.mu_s), ("gamma", self.gamma)):
            object.__setattr__(p, name, value)
        object.__setattr__(p, "_dimensionless", self)
        return p

    def to_physical(self, length: float = 1.0, rho: float = 1.0, g: float = 9.81) -> "PhysicalParams":
        """Physical parameters with the given length [m], mass per length [kg/m] and gravity [m/s^2]."""
        length = _positive("length", length)
        rho = _positive("rho", rho)
        g = _positive("g", g)
        return PhysicalParams(
            length=length,
            EI=self.D * rho * g * (length * length * length),  # products overflow to inf (named below), ** raises
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
        b, gamma = _within_reach(self.b, self.gamma, self.length, si=True)
        object.__setattr__(self, "b", b)
        object.__setattr__(self, "gamma", gamma)
        try:  # the model's range is stated in dimensionless groups; kept: dimensionless() returns them
            object.__setattr__(self, "_dimensionless", self._groups())
        except ValueError as exc:
            raise ValueError(
                f"these physical parameters leave the model's range: {exc} "
                "(D = EI/(rho g length^3), M = m/(rho length), b/length, gamma/length)"
            ) from None

    def dimensionless(self) -> DimensionlessParams:
        """The paper's dimensionless groups ``D, M, b/l, mu_s, gamma/l`` (computed and checked once, on
        construction)."""
        return self._dimensionless

    def _groups(self) -> DimensionlessParams:
        """The groups computed from the fields (a ``DimensionlessParams``, which checks their range)."""
        w = self.rho * self.g * self.length  # weight of the rod [N], the force scale
        return DimensionlessParams(
            D=_ratio(self.EI, w * self.length * self.length),
            M=_ratio(self.m, self.rho * self.length),
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


def as_dimensionless(params, name: str = "params") -> "DimensionlessParams":
    """``params`` as its dimensionless groups: a :class:`DimensionlessParams` as it is, a :class:`PhysicalParams`
    through :meth:`PhysicalParams.dimensionless` (what :func:`simgrip.compare.simulate` settles either way);
    ``ValueError`` naming ``name`` for anything else.  For the functions that report in groups (the compare and
    the records), so that both kinds are taken where ``simulate`` takes both."""
    if isinstance(params, PhysicalParams):
        return params.dimensionless()
    if isinstance(params, DimensionlessParams):
        return params
    raise ValueError(f"{name} must be DimensionlessParams or PhysicalParams, got {type(params).__name__}")

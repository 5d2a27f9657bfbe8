"""Intrinsic curvature profiles ``kappa_bar(s_bar) = l * kappa0(s)``.

All profiles are dimensionless functions of ``s_bar = s / l`` in ``[0, 1]``.
Sign convention: ``theta`` (the tangent's angle from ``E1``) is counter-clockwise
positive, so ``kappa_bar < 0`` curls the finger downwards (Grips I and III) and
``kappa_bar > 0`` curls it upwards (Grip II).

A profile knows its values and its integral over any interval; the integral is
what a hinge chain uses for its rest angles.

Parameters are validated on construction (``ValueError`` naming them):
``|kappa|`` and ``kappa_max`` at most :data:`~simgrip.params.KAPPA_LIMIT`,
``alpha`` in ``[0, ALPHA_MAX]`` (the reasons are in :mod:`simgrip.params`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from simgrip.params import ALPHA_MAX, KAPPA_LIMIT, _finite, _within

__all__ = ["CurvatureProfile", "Uniform", "Concentrated", "UserProfile", "as_profile"]

_KAPPA_WHY = "a curl radius under l/100; see simgrip.params"
_ALPHA_WHY = "a sharper peak than 0.035 l is a kink the chain cannot resolve; see simgrip.params"

# 16-point Gauss-Legendre rule on [-1, 1], used for integrals without a closed form.
_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)


class CurvatureProfile:
    """Base class: a dimensionless intrinsic curvature ``kappa_bar(s_bar)`` on ``[0, 1]``."""

    def __call__(self, s_bar) -> np.ndarray:
        s = np.asarray(s_bar, dtype=float)
        return self._eval(s)

    def _eval(self, s: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def integral(self, a, b) -> np.ndarray:
        """``int_a^b kappa_bar(s) ds`` (dimensionless angle), elementwise over arrays ``a``, ``b``.

        The default uses a composite 16-point Gauss-Legendre rule on each interval,
        exact for polynomials up to degree 31.
        """
        a = np.asarray(a, dtype=float)
        b = np.asarray(b, dtype=float)
        mid = 0.5 * (a + b)
        half = 0.5 * (b - a)
        nodes = mid[..., None] + half[..., None] * _GL_X
        return half * np.sum(_GL_W * self(nodes), axis=-1)

    def scaled(self, factor: float) -> "CurvatureProfile":
        """The profile multiplied by ``factor`` (for ramping curvature)."""
        f = _finite("factor", factor)
        return UserProfile(lambda s, f=f, p=self: f * p(s), name=f"{f:g}*{self!r}")


@dataclass(frozen=True)
class Uniform(CurvatureProfile):
    """Constant curvature ``kappa_bar`` along the whole finger."""

    kappa: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "kappa", _within("kappa", self.kappa, -KAPPA_LIMIT, KAPPA_LIMIT, _KAPPA_WHY))

    def _eval(self, s):
        return np.full(np.shape(s), self.kappa)

    def integral(self, a, b):
        return self.kappa * (np.asarray(b, dtype=float) - np.asarray(a, dtype=float))

    def scaled(self, factor):
        return Uniform(self.kappa * _finite("factor", factor))


@dataclass(frozen=True)
class Concentrated(CurvatureProfile):
    """The concentrated profile of the paper's eq. (34).

    ``kappa_bar(s) = p * kappa_max * (4 s (1 - s))**alpha``: peak ``p*kappa_max``
    at mid-length, vanishing at both ends; ``alpha`` concentrates it (``alpha = 0``
    is uniform).  ``p = -1`` curls downwards (palm down), ``p = +1`` upwards.
    Defined on ``[0, 1]`` (values outside are clipped to zero).
    """

    kappa_max: float = 6.0
    alpha: float = 1.0
    p: int = -1

    def __post_init__(self):
        km = _finite("kappa_max", self.kappa_max)
        if km < 0:
            raise ValueError(f"kappa_max must be non-negative (the sign is p), got {km!r}")
        object.__setattr__(self, "kappa_max", _within("kappa_max", km, 0.0, KAPPA_LIMIT, _KAPPA_WHY))
        a = _finite("alpha", self.alpha)
        if a < 0:
            raise ValueError(f"alpha must be non-negative, got {a!r}")
        object.__setattr__(self, "alpha", _within("alpha", a, 0.0, ALPHA_MAX, _ALPHA_WHY))
        if isinstance(self.p, bool) or self.p not in (-1, 1):
            raise ValueError(f"p must be -1 or +1, got {self.p!r}")
        object.__setattr__(self, "p", int(self.p))

    def _eval(self, s):
        base = np.clip(4.0 * s * (1.0 - s), 0.0, None)
        return self.p * self.kappa_max * base**self.alpha

    def integral(self, a, b):
        """Exact: ``int (4s(1-s))^alpha ds = 4^alpha B(alpha+1, alpha+1) [I_b - I_a]`` (regularised incomplete beta)."""
        from scipy import special as _special  # lazily: scipy.special costs ~0.3 s at start-up

        a = np.clip(np.asarray(a, dtype=float), 0.0, 1.0)
        b = np.clip(np.asarray(b, dtype=float), 0.0, 1.0)
        k = self.alpha + 1.0
        # 4^alpha B(k, k) in log space: each factor alone overflows/underflows for large alpha
        scale = self.p * self.kappa_max * np.exp(self.alpha * np.log(4.0) + _special.betaln(k, k))
        return scale * (_special.betainc(k, k, b) - _special.betainc(k, k, a))

    def scaled(self, factor):
        f = _finite("factor", factor)
        if f >= 0:
            return Concentrated(self.kappa_max * f, self.alpha, self.p)
        return Concentrated(-self.kappa_max * f, self.alpha, -self.p)


class UserProfile(CurvatureProfile):
    """Any user callable ``f(s_bar) -> kappa_bar``, vectorised over NumPy arrays.

    The callable is checked on a probe grid: it must return finite values of the
    same shape as its input (a scalar result is broadcast).  Its values are not bounded pointwise: a narrow
    spike may peak far above ``KAPPA_LIMIT`` with a modest total turn (the stress box's spikes peak at ~240).
    """

    def __init__(self, func: Callable[[np.ndarray], np.ndarray], name: str | None = None):
        if not callable(func):
            raise ValueError(f"profile must be callable, got {func!r}")
        self._func = func
        self._name = name or getattr(func, "__name__", "user")
        probe = np.linspace(0.0, 1.0, 17)
        self(probe)  # validates

    def _eval(self, s):
        try:
            out = np.asarray(self._func(s), dtype=float)
        except (TypeError, ValueError, ArithmeticError) as exc:  # ArithmeticError: 1/0 in the user's callable
            raise ValueError(f"profile {self._name!r} failed on an array of s_bar: {exc}") from exc
        if out.shape != np.shape(s):
            if out.ndim == 0:
                out = np.full(np.shape(s), float(out))
            else:
                raise ValueError(
                    f"profile {self._name!r} must return an array of shape {np.shape(s)}, got {out.shape}"
                )
        if not np.all(np.isfinite(out)):
            raise ValueError(f"profile {self._name!r} returned non-finite curvature values")
        return out

    def __repr__(self):
        return f"UserProfile({self._name})"


def as_profile(profile) -> CurvatureProfile:
    """Coerce a number (uniform curvature), a profile or a callable into a :class:`CurvatureProfile`."""
    if isinstance(profile, CurvatureProfile):
        return profile
    if callable(profile):
        return UserProfile(profile)
    return Uniform(_finite("kappa", profile))

"""Checks of the arguments of the reference solvers' public entry points.

Each public function of :mod:`simgrip.reference` checks and converts its inputs
once, with these helpers, and hands plain floats, ints and
:class:`~simgrip.profiles.CurvatureProfile` objects to the internal functions,
which do not check them again.  Every failure is a ``ValueError`` naming the
parameter.  Values already checked where they entered simgrip (a
:class:`~simgrip.params.Grip`, a :class:`~simgrip.chain.Count`, a
``DimensionlessParams``, checked when it was built) pass through unchanged, so
a solver called by the settle or a scene builder does not re-check them.
"""

from __future__ import annotations

import math

import numpy as np

from simgrip.chain import check_links
from simgrip.params import DimensionlessParams, _finite, check_grip, check_grip_iii_reach
from simgrip.profiles import CurvatureProfile, as_profile

__all__ = ["MAX_COUNT", "check_count", "check_discrete", "check_failures", "check_gamma", "check_gravity", "check_params", "check_tip_load", "check_tol"]


def check_params(params) -> DimensionlessParams:
    """``params`` itself if it is a :class:`~simgrip.params.DimensionlessParams`."""
    if not isinstance(params, DimensionlessParams):
        raise ValueError(f"params must be a DimensionlessParams, got {type(params).__name__}")
    return params


#: Most elements (nodal scheme) or links (hinge chain) a discrete solver takes.
#: Both schemes are second order, so at 16384 the discretisation error
#: (~(1/16384)^2 = 4e-9 of the leading term) is already near the round-off of the
#: Newton solve: more buys nothing, and the work grows with the count (seconds at
#: the bound, a minute at 2^17).  The CLI's ``--K`` has the same bound.
MAX_COUNT = 16384


def check_count(name: str, value) -> int:
    """An element or link count named ``name``: an integer in ``[2, MAX_COUNT]``
    (``inf``, ``nan``, floats with a fraction, bools and strings are refused)."""
    n = check_links(value, name)
    if n > MAX_COUNT:
        raise ValueError(f"{name} must be at most {MAX_COUNT}, got {value!r} (the scheme's error there is ~4e-9; "
                         "more elements buy nothing)")
    return n


def check_gamma(gamma, params: DimensionlessParams) -> float:
    """The Grip III contact arc length: ``params.gamma`` when ``None``, else a float in (0, 1)."""
    if gamma is None:
        return params.gamma
    g = _finite("gamma", gamma)
    if not 0.0 < g < 1.0:
        raise ValueError(f"gamma must lie in (0, 1), got {gamma!r}")
    return g


def check_gravity(gravity) -> float:
    """A factor >= 0 on the rod's own weight (``True``/``False`` read as 1/0)."""
    try:
        g = float(gravity)
    except (TypeError, ValueError):
        raise ValueError(f"gravity must be a real factor >= 0, got {gravity!r}") from None
    if not (math.isfinite(g) and g >= 0):
        raise ValueError(f"gravity must be a finite factor >= 0, got {gravity!r}")
    return g


def check_tip_load(tip_load) -> tuple[float, float]:
    """An extra tip force ``(E1, E2)``: a pair of finite floats."""
    try:
        t = np.asarray(tip_load, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"tip_load must be a pair of real numbers, got {tip_load!r}") from None
    if t.shape != (2,) or not np.all(np.isfinite(t)):
        raise ValueError(f"tip_load must be a pair of finite numbers, got {tip_load!r}")
    return float(t[0]), float(t[1])


def check_tol(tol) -> float:
    """A ``solve_bvp`` tolerance in ``[1e-13, 1e-2]``."""
    tol = _finite("tol", tol)
    if not 1e-13 <= tol <= 1e-2:
        raise ValueError(f"tol must lie in [1e-13, 1e-2], got {tol!r}")
    return tol


def check_failures(failures) -> str:
    """What a sweep does with a point that fails: ``"raise"`` or ``"skip"``."""
    if failures not in ("raise", "skip"):
        raise ValueError(f"failures must be 'raise' or 'skip', got {failures!r}")
    return failures


def check_discrete(grip, params, profile, count_name: str, count, gamma, gravity
                   ) -> tuple[str, DimensionlessParams, CurvatureProfile, int, float, float]:
    """The common arguments of the discrete solvers: ``(grip, params, profile, count, gamma, gravity)``."""
    grip, params = check_grip(grip), check_params(params)
    gam = check_gamma(gamma, params)
    if grip == "III":
        check_grip_iii_reach(gam, params.b)
    return (grip, params, as_profile(profile), check_count(count_name, count), gam, check_gravity(gravity))

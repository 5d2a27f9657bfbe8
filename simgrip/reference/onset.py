"""The onset of full contact: the largest ``|kappa0|`` at which the point-contact elastica stays valid.

The paper's BVPs (:func:`simgrip.reference.elastica.solve`) let the rod pass through itself, the
workpiece and the mirror finger.  :func:`point_contact_violations` says what a point-contact solution does
wrong; :func:`onset` continues a grip in the curvature's scale from a valid start and bisects the first
loss of validity.

What counts as a violation (centreline terms, as in :mod:`simgrip.reference.constrained`):

* the centreline crossing itself;
* any point of the rod inside the workpiece: Grips I/II the box ``{X < b/2}`` beyond its top face
  ``Y(1) + depth`` (I) / bottom face ``Y(1) - depth`` (II), the box hanging on the tip; Grip III the rod
  beyond the contact rising into the box above the corner, ``{X < b/2, Y > Y(gamma)}`` (the part before
  the contact: the paper's Grip III knows the box only as its corner, and the rod leaving the palm
  necessarily runs over the box's width there);
* a point with ``X < 0`` (the mirror finger, which crosses there too);
* Grip III: the paper's condition (23), the tip not below the contact (``feasibility["tip_clear"]``).

Not a violation: the friction and contact-force verdicts (``feasible``), which the paper already reports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from simgrip.params import _finite
from simgrip.profiles import Uniform
from simgrip.reference.arguments import check_params
from simgrip.reference.contact_geometry import self_crossing
from simgrip.reference.elastica import ElasticaError, ElasticaSolution, solve

__all__ = ["Onset", "onset", "point_contact_violations"]

#: Default box depth: the tip's distance below the top face (Grip I) / above the bottom face (Grip II), as
#: :data:`simgrip.reference.constrained.DEFAULT_DEPTH` (unused by Grip III).
DEPTH = 0.4


def point_contact_violations(sol: ElasticaSolution, depth: float = DEPTH) -> tuple:
    """What the point-contact solution ``sol`` (Grips I-III) does that no real finger can (see the
    module docstring); an empty tuple when it is valid."""
    x, y = np.asarray(sol.x, float), np.asarray(sol.y, float)
    xb = 0.5 * sol.params.b
    bad = []
    if self_crossing(np.stack([x, y], axis=1), 0.0):
        bad.append("the centreline crosses itself")
    if sol.grip in ("I", "II"):
        sd = 1.0 if sol.grip == "I" else -1.0
        face = y[-1] + sd * depth
        inside = (x < xb - 1e-9) & (sd * (y - face) < -1e-9)
    elif sol.grip == "III":
        yc = sol.contact[1]
        beyond = np.asarray(sol.s) > sol.gamma + 1e-9
        inside = beyond & (x < xb - 1e-9) & (y > yc + 1e-9)
    else:
        inside = np.zeros(x.shape, bool)
    if np.any(inside):
        bad.append(f"the rod enters the workpiece at s = {float(np.asarray(sol.s)[np.argmax(inside)]):.4g}")
    if np.min(x[1:]) < -1e-9:
        bad.append(f"the rod crosses the mirror plane X = 0 (min X = {float(np.min(x)):.4g})")
    if sol.grip == "III" and not sol.feasibility.get("tip_clear", True):
        bad.append("condition (23): the tip is not below the contact")
    return tuple(bad)


@dataclass(frozen=True)
class Onset:
    """``kappa``: the last valid ``kappa0`` scale (to ``tol``); ``first_invalid``: the first invalid one;
    ``violations``: what goes wrong there; ``solution``: the valid solution at ``kappa``; ``reached_end``:
    True when no violation occurred up to ``kappa_end`` (``kappa`` is then ``kappa_end``)."""

    grip: str
    kappa: float
    first_invalid: float | None
    violations: tuple
    solution: ElasticaSolution
    reached_end: bool


def onset(grip, params, *, profile_of=Uniform, depth: float = DEPTH, kappa_start=None, kappa_end=None,
          step: float = 0.25, tol: float = 1e-4) -> Onset:
    """Largest ``|kappa|`` (profile ``profile_of(kappa)``) up to which the point-contact solution stays valid.

    Parameters
    ----------
    grip : {"I", "II", "III"}
    params : DimensionlessParams
    profile_of : callable
        ``kappa -> profile`` (default :class:`~simgrip.profiles.Uniform`).
    depth : float
        Grips I/II's box depth (see :func:`point_contact_violations`).
    kappa_start, kappa_end : float, optional
        The continuation's range; defaults ``-2 .. -20`` (I, III), ``2 .. 20`` (II).  The start must be valid.
    step, tol : float
        Continuation step and the bisection's final bracket width.

    Raises
    ------
    ValueError
        Bad arguments, or an invalid start.
    ElasticaError
        The continuation failed before any violation (the branch ends: reported, not guessed).
    """
    if grip not in ("I", "II", "III"):
        raise ValueError(f"grip must be 'I', 'II' or 'III', got {grip!r}")
    params = check_params(params)
    sign = 1.0 if grip == "II" else -1.0
    k0 = sign * 2.0 if kappa_start is None else _finite("kappa_start", kappa_start)
    k1 = sign * 20.0 if kappa_end is None else _finite("kappa_end", kappa_end)
    if k0 * sign <= 0 or (k1 - k0) * sign <= 0:
        raise ValueError(f"kappa_start/kappa_end must run away from 0 in the grip's direction "
                         f"({'+' if sign > 0 else '-'}), got {k0:g} .. {k1:g}")
    step, tol = _finite("step", step), _finite("tol", tol)
    if not (step > 0 and tol > 0 and tol < step):
        raise ValueError(f"step and tol must be > 0 with tol < step, got step={step!r}, tol={tol!r}")
    depth = _finite("depth", depth)
    if not 0.0 < depth < 2.0:
        raise ValueError(f"depth must lie in (0, 2), got {depth!r}")

    def at(k, guess):
        return solve(grip, params, profile_of(k), guess=guess)

    sol = at(k0, None)
    bad = point_contact_violations(sol, depth)
    if bad:
        raise ValueError(f"kappa_start = {k0:g} is already invalid: {'; '.join(bad)}")
    good_k, good = k0, sol
    nsteps = int(math.ceil(abs(k1 - k0) / step))
    for i in range(1, nsteps + 1):
        k = k0 + sign * min(i * step, abs(k1 - k0))
        sol = at(k, good)
        bad = point_contact_violations(sol, depth)
        if bad:
            break
        good_k, good = k, sol
    else:
        return Onset(grip, good_k, None, (), good, True)
    lo, hi, bad_hi = good_k, k, bad
    while abs(hi - lo) > tol:
        mid = 0.5 * (lo + hi)
        try:
            s_mid = at(mid, good)
        except ElasticaError:
            hi = mid
            continue
        b = point_contact_violations(s_mid, depth)
        if b:
            hi, bad_hi = mid, b
        else:
            lo, good = mid, s_mid
    return Onset(grip, lo, hi, bad_hi, good, False)

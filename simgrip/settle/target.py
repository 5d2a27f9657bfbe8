"""Settle to an error target: three resolutions, Richardson extrapolation, an error estimate.

The hinge chain is a symmetric second-order discretisation (midpoint rules,
central differences, the half-cell clamp; :mod:`simgrip.chain`), so for a
smooth problem a settled quantity ``Q`` (tip position, contact forces) at link
length ``h = l/n`` expands in even powers of ``h``::

    Q(h) = Q* + a h^2 + b h^4 + O(h^6).

Two resolutions cancel the ``h^2`` term (Richardson)::

    R(h) = (4 Q(h/2) - Q(h)) / 3 = Q* - b h^4 / 4 + O(h^6),

and a third, coarser one estimates what is left: ``R(h/2) - R(h) = 15 b h^4 /
64``, so the error of ``R(h/2)`` is ``-(R(h/2) - R(h)) / 15`` (Romberg).  The
settle runs MuJoCo at ``2 n0`` and ``4 n0`` links and reports the extrapolated
``R(h/2)`` of these two; the coarsest level ``n0``, used only for the estimate,
is the hinge chain's exact equilibrium (the MuJoCo finger is that chain, see
:mod:`simgrip.settle.chain_model`; a scene build and settle would cost more);
``error_estimate = |R(h/2) - R(h)| / 15`` -- tip over ``l``, forces relative to
the largest contact force component.  If the estimate exceeds the target,
``n0`` grows by the factor the ``h^4`` law asks for.

Contact compliance.  MuJoCo's contact is soft: a held tip sits at ``X(l) =
b/2 - p`` with ``p = N/K_c`` (~1e-7..1e-5 l, nearly independent of ``h``),
i.e. the settled chain is the point-contact chain of width ``b - 2p``.  That
error does not extrapolate away, so each level is corrected to width ``b``
first: ``Q += (dQ/db) 2 p`` with ``p = b/2 - X(l)`` read from the state and
``dQ/db`` from the hinge chain's equilibrium at the finest level and width
``b`` (the MuJoCo finger is that chain: the finest level's corrected value is
that equilibrium; the sensitivity's own ``O(h^2)`` error costs ``O(p h^2)``
at the coarser level).

Scope: the free rod and Grips I/II.  Grip III's contact point moves along the
links as ``n`` changes (the carrying link and the offset in it jump), so its
error is not a smooth expansion in ``h``.  Below :data:`MIN_TARGET_ERROR` the
contact's compliance (penetration ``~1e-7 l``, independent of ``h``) and the
contact-force round-off dominate.
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from simgrip.reference import DiscreteError, solve_chain
from simgrip.settle.chain_model import gravity_factor
from simgrip.settle.state import SettledState, SettleError

__all__ = ["MIN_TARGET_ERROR", "check_target_error", "settle_to_error"]

#: Links of the coarsest level of the first try.
TARGET_N0 = 8
#: Finest level allowed (the target is refused when it would need more).
TARGET_MAX_LINKS = 2048
#: Smallest target accepted (relative error floor of the contact's compliance and round-off).
MIN_TARGET_ERROR = 1e-7


def check_target_error(target_error, grip: str) -> float:
    """``target_error`` as a float, or ``ValueError`` naming it."""
    try:
        e = float(target_error)
    except (TypeError, ValueError):
        raise ValueError(f"target_error must be a real number, got {target_error!r}") from None
    if not (math.isfinite(e) and MIN_TARGET_ERROR <= e < 1.0):
        raise ValueError(f"target_error must lie in [{MIN_TARGET_ERROR:g}, 1), got {target_error!r}")
    if grip == "III":
        raise ValueError("target_error: Grip III is not supported (its contact moves along the links with n: "
                         "no smooth expansion of the error in the link length)")
    return e


def _chain_quantities(scene, n, held: bool, guess=None):
    """Tip, (N1, N2) and link angles of the hinge chain at ``n`` links (the grip's, or free when not held)."""
    grip = scene.grip if held else "free"
    try:
        ch = solve_chain(grip, scene.params, scene.profile, n, guess=guess, gravity=gravity_factor(scene))
    except (DiscreteError, ValueError):
        return None
    if not ch.success:
        return None
    return np.array(ch.tip, dtype=float), np.array([ch.N1, ch.N2], dtype=float)


def _quantities(st: SettledState) -> tuple[np.ndarray, np.ndarray]:
    """Tip (over l) and contact forces (over rho g l) of finger 0."""
    return np.array(st.tip[0], dtype=float), np.array([st.N1, st.N2], dtype=float)


def settle_to_error(scene, target_error: float, settle_one, **kw) -> SettledState:
    """Settle rebuilt copies of ``scene`` at ``n0, 2 n0, 4 n0`` links until the estimate meets the target.

    ``settle_one(scene, **kw)`` settles one scene.  Returns the finest state
    with ``tip`` and the contact forces replaced by their extrapolated values,
    ``extrapolated=True``, ``error_estimate`` (``{"tip": .., "force": ..}``) and
    ``wall_time_s`` of all the settles.  Resolutions that disagree on hold/drop
    (a state at the friction threshold) give the finest state unextrapolated,
    with a warning.
    """
    from simgrip.scenes import build_scene

    t0 = time.perf_counter()
    cache: dict[int, SettledState] = {}

    def level(n):
        if n not in cache:
            sc = build_scene(scene.grip, scene.physical, scene.profile, n, fingers=scene.fingers,
                             free_workpiece=scene.free_workpiece, r_tip=scene.r_tip, r_link=scene.r_link,
                             r_corner=scene.r_corner)
            # the scene's gravity as the caller set it (a zeroed vector or the disable flag)
            sc.model.opt.gravity[:] = scene.model.opt.gravity
            bit = int(mujoco.mjtDisableBit.mjDSBL_GRAVITY)
            sc.model.opt.disableflags = (int(sc.model.opt.disableflags) & ~bit) | (int(scene.model.opt.disableflags) & bit)
            cache[n] = settle_one(sc, **kw)
        return cache[n]

    n0 = TARGET_N0
    for _round in range(6):
        if 4 * n0 > TARGET_MAX_LINKS:
            raise SettleError(f"target_error {target_error:g} needs more than {TARGET_MAX_LINKS} links")
        s2, s4 = level(2 * n0), level(4 * n0)
        fine = s4
        if s2.held != s4.held:
            fine.warnings.append("target_error: the resolutions disagree on hold/drop (friction threshold): "
                                 "the finest state is reported unextrapolated")
            fine.wall_time_s = time.perf_counter() - t0
            return fine
        (t2, f2), (t4, f4) = _quantities(s2), _quantities(s4)
        if scene.grip in ("I", "II") and s4.held:  # contact compliance: correct both levels to X(l) = b/2
            ref = _chain_quantities(scene, 4 * n0, True, guess=s4.link_angles[0])
            shift4, shift2 = (2.0 * (0.5 * scene.params.b - t[0]) for t in (t4, t2))
            if ref is not None and abs(shift4) > 1e-12:
                st_, sf_ = (ref[0] - t4) / shift4, (ref[1] - f4) / shift4
                t4, f4 = ref
                t2, f2 = t2 + st_ * shift2, f2 + sf_ * shift2
        coarse = _chain_quantities(scene, n0, s4.held)
        if coarse is None:  # the chain cannot say: the MuJoCo settle at n0 (compliance left in)
            coarse = _quantities(level(n0))
        t1, f1 = coarse
        rt_c, rt_f = (4 * t2 - t1) / 3, (4 * t4 - t2) / 3
        rf_c, rf_f = (4 * f2 - f1) / 3, (4 * f4 - f2) / 3
        scale = max(float(np.max(np.abs(rf_f))), 1e-300)
        est_tip = float(np.max(np.abs(rt_f - rt_c))) / 15.0
        est_force = float(np.max(np.abs(rf_f - rf_c))) / 15.0 / scale if s4.contacts else 0.0
        est = max(est_tip, est_force)
        if est <= target_error:
            fine.tip = fine.tip.copy()
            fine.tip[0] = rt_f
            if fine.contacts:
                c = fine.contacts[0]
                c.N1, c.N2 = float(rf_f[0]), float(rf_f[1])
                if scene.grip in ("I", "II"):
                    c.normal, c.friction = c.N1, c.N2
                    c.required_mu = abs(c.friction) / c.normal if c.normal > 0 else math.inf
            fine.extrapolated = True
            fine.error_estimate = {"tip": est_tip, "force": est_force}
            fine.wall_time_s = time.perf_counter() - t0
            return fine
        # the h^4 law: est scales as n0^-4; aim at half the target
        grow = (est / (0.5 * target_error)) ** 0.25
        n0 *= 2 ** max(1, math.ceil(math.log2(grow)))
    raise SettleError(f"target_error {target_error:g} not met (estimate {est:.3g} at {4 * n0} links)")

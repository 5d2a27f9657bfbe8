"""Drive a scene to static equilibrium, fast, and read the settled state.

:func:`settle` is the entry point.  The default is a static solve of MuJoCo's
own force balance by Newton in the chains' own coordinates
(:mod:`.chain_newton` on :mod:`.chain_model`: exact forces and Jacobian,
tridiagonal in the link angles of one or both fingers and bordered by the
workpiece's dofs and the contact and stick rows, ``O(n)`` per iteration,
:mod:`.banded`).  Grips I/II start from the hinge
chain's grip equilibrium and a free finger from its free one (:mod:`.closing`),
so Newton only polishes.  ``method="dynamics"`` is an over-damped MuJoCo
simulation (:mod:`.dynamics`); ``target_error`` settles at several resolutions
and extrapolates (:mod:`.target`).  Both methods return a
:class:`SettledState` (:mod:`.state`) whose ``residual`` is MuJoCo's static
residual (:mod:`.statics`) and whose ``converged`` means ``residual <=
tolerance``; :func:`naive_settle` (:mod:`.naive`) is the plain-dynamics baseline.

Contact: by default the sticking friction acts on the finger's centreline
(``contact="point"``, the paper's point contact: the settled state converges at
second order to the point-contact BVP); ``contact="surface"`` puts it at
MuJoCo's contact point (the finite-radius couple), as the dynamics does.

Grips: I/II release the workpiece under friction (dropped when the friction
cone is violated; a state in the other grip's shape is reported not held,
:mod:`simgrip.validity`); III starts from the shape the scene was built with
(corner on the rod) and settles at the simulation's own ``gamma``; a warm start
(:func:`settle_sweep`) releases from the previous equilibrium.

Budgets: ``max_steps`` bounds the Newton iterations of the whole settle
(default :data:`NEWTON_BUDGET`) or the physics steps of the dynamic settle; a
spent budget raises :class:`SettleError` naming it.
"""

from __future__ import annotations

import functools
import math
import time

import mujoco
import numpy as np

from simgrip.settle.chain_newton import ChainNewton
from simgrip.settle.closing import close_grip, finger_alone, place_on_chain, release, start_free
from simgrip.settle.dynamics import DYN_TOL, dynamics_tolerance, settle_dynamics
from simgrip.settle.naive import naive_relax, naive_settle
from simgrip.settle.newton import SOLVE_ITERS, read_newton
from simgrip.settle.state import FingerContact, SettledState, SettleError, finger_tip
from simgrip.settle.target import check_target_error, settle_to_error
from simgrip.settle.statics import (RestResidual, angle_floor, configure_statics, dof_scales, restore_options,
                                    save_options, static_residual, sync_scene)
from simgrip.sim.checks import clear_warnings
from simgrip.sim.scene import Scene, set_curvature
from simgrip.threads import blas_threads
from simgrip.validity import (check_valid, check_condition_23, check_contact_depth, check_friction_cone, check_grip_shape,
                              check_reach, check_tip_contact)

__all__ = [
    "DEFAULT_TOL",
    "DYN_TOL",
    "FingerContact",
    "RestResidual",
    "SettleError",
    "SettledState",
    "dof_scales",
    "finger_tip",
    "naive_relax",
    "naive_settle",
    "settle",
    "settle_sweep",
    "static_residual",
]

#: Default static residual tolerance (over rho g l^2 and rho g l).
DEFAULT_TOL = 1e-10
#: The contact floor raises the effective tolerance at most to this (a bogus ``K_c`` read back
#: from a deep contact must not make every residual "converged").
RESIDUAL_FLOOR_MAX = 1e-6
#: Default total Newton iteration budget of one settle (``max_steps``): closing, release and
#: the finger-alone settle together.
NEWTON_BUDGET = 2000


def _check_settle_args(scene, tol, max_steps):
    if not isinstance(scene, Scene):
        raise ValueError(f"scene must be a simgrip.sim.scene.Scene, got {type(scene).__name__}")
    return check_tol_steps(tol, max_steps)


def check_tol_steps(tol, max_steps) -> tuple[float, int]:
    """``(tol, max_steps)`` of a settle as a positive finite float and a positive int; ValueError naming the bad one."""
    try:
        tol = float(tol)
    except (TypeError, ValueError):
        raise ValueError(f"tol must be a real number, got {tol!r}") from None
    if not (math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol must be positive and finite, got {tol!r}")
    if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or max_steps < 1:
        raise ValueError(f"max_steps must be a positive integer, got {max_steps!r}")
    return tol, int(max_steps)


def settle(scene: Scene, *, target_error=None, **kw) -> SettledState:  # docstring: _settle's (functools.wraps)
    with blas_threads(1):  # small dense Newton systems: multithreaded OpenBLAS only spins (simgrip.threads)
        if target_error is None:
            return _settle(scene, **kw)
        if not isinstance(scene, Scene):
            raise ValueError(f"scene must be a simgrip.sim.scene.Scene, got {type(scene).__name__}")
        e = check_target_error(target_error, scene.grip)
        if kw.get("method") == "dynamics":
            raise ValueError("method: target_error extrapolates the static settle (method='newton'); the dynamic "
                             "settle's error is floored by MuJoCo's friction creep, not by ds")
        if kw.get("contact") == "full" or getattr(scene, "contact", "pairs") == "full":
            raise ValueError("contact: target_error extrapolates the point-contact settle over resolutions; the "
                             "full-contact settle (contact='full') has no derived error expansion in ds")
        if kw.get("contact") == "surface":
            raise ValueError("contact: target_error extrapolates the point-contact settle (method='newton', "
                             "contact='point'), whose error expansion in ds is derived; the finite-radius "
                             "surface contact adds a couple that does not vanish with ds")
        if kw.get("warm_start") is not None:
            raise ValueError("target_error: warm_start is not supported (each resolution settles from scratch)")
        return settle_to_error(scene, e, _settle, **kw)


def _finish(scene: Scene, state: SettledState, tolerance: float, allow_unconverged: bool, what: str,
            effort: str) -> SettledState:
    """Both methods' last word: converged means residual <= ``tolerance``; then the checks the solve does not
    enforce (condition (23), the grip's shape) and the rest angles the state was settled with."""
    state.tolerance = tolerance
    if state.converged and not state.residual <= tolerance:
        state.converged = False
        if not allow_unconverged:
            raise SettleError(f"{what} did not converge (static residual {state.residual:.3g} above the "
                              f"tolerance {tolerance:.3g} after {effort})")
    check_condition_23(scene, state)
    check_contact_depth(scene, state)
    check_grip_shape(scene, state)
    check_reach(scene, state)
    check_tip_contact(scene, state)
    check_friction_cone(scene, state)
    check_valid(scene, state)  # last: the others read the solve's own verdict (simgrip.validity, issue 17)
    if not state.converged:  # allow_unconverged: the state the caller asked for, said to be one (never silent)
        state.warnings.append(f"not converged: {what} stopped at static residual {state.residual:.3g} (tolerance "
                              f"{tolerance:.3g}) after {effort}; held, feasible and the forces are those of an "
                              f"unfinished settle (allow_unconverged)")
    state.rest = scene.springs.rest.copy()
    return state


def _settle(
    scene: Scene,
    *,
    tol: float | None = None,
    max_steps: int | None = None,
    warm_start: SettledState | None = None,
    close: bool = True,
    allow_unconverged: bool = False,
    method: str = "newton",
    contact: str | None = None,
    sync: bool = True,
) -> SettledState:
    """Drive ``scene`` to static equilibrium (see the module docstring).

    Parameters
    ----------
    scene : Scene
    tol : float, optional
        Static residual tolerance (generalised forces over ``rho g l^2`` / ``rho g l``);
        default :data:`DEFAULT_TOL` (Newton) or, with a workpiece, ``max(DYN_TOL, 2e-6 M)``
        (dynamics: MuJoCo's friction creep floor, :func:`.dynamics.dynamics_tolerance`).
    max_steps : int, optional
        Newton iterations (default :data:`NEWTON_BUDGET`, one solve at most
        :data:`SOLVE_ITERS`) or physics steps (dynamics, default 20000)
        allowed to the whole settle; a spent budget raises :class:`SettleError`.
    warm_start : SettledState, optional
        Start from this state (same scene layout); skips the closing phase and
        sticks the workpiece where it touches.
    close : bool
        Grips I/II: run the closing procedure (curl, place and hold the
        workpiece, ramp, release).  ``False`` releases from the current state.
    allow_unconverged : bool
        Return ``converged=False`` instead of raising when the solve does not
        converge or the final residual is above :attr:`SettledState.tolerance`.
    method : {"newton", "dynamics"}
        ``"newton"`` (default): the static Newton-KKT solve with simgrip's
        sticking constraints.  ``"dynamics"``: over-damped MuJoCo dynamics
        with MuJoCo's own contact and friction (see :class:`Dyn` and the
        module docstring); ``steps`` counts physics steps.
    target_error : float, optional
        Settle to this error instead of at the scene's ``n``: three resolutions,
        Richardson extrapolation and an error estimate (:mod:`.target`; free rod
        and Grips I/II; ``links`` of the result is the finest used).
    contact : {"point", "surface"}, optional
        Where the sticking friction acts.  ``"point"`` (default for
        ``"newton"``): on the finger's centreline, the paper's point contact, so
        the settled state converges at second order to the point-contact BVP
        (``contact_moment`` ~ 0).  ``"surface"``: at MuJoCo's contact point on
        the geoms' surface, which adds the finite-radius couple (``-r_tip F_f``
        for Grips I/II, ``~r_link f`` for III; compare against the
        couple-aware reference with ``contact_moment``).  ``"dynamics"`` is
        always ``"surface"`` (MuJoCo's own friction).
    sync : bool
        Leave the scene's data at the settled state (``mj_forward``, or the positions of a
        contact-free chain: :func:`.statics.sync_scene`; ~0.1 ms at ``n = 32``), as the default does.
        ``False`` leaves it where the solve's last evaluation left it, for a caller that discards the
        scene (:func:`simgrip.compare.simulate`'s cached scene, reset before its next use): the returned
        state is read before and is the same either way.

    Returns
    -------
    SettledState

    Raises
    ------
    ValueError
        Bad arguments.
    SettleError
        Divergence (non-finite residual, MuJoCo warning), or no convergence
        unless ``allow_unconverged``.
    """
    if method not in ("newton", "dynamics"):
        raise ValueError(f"method must be 'newton' or 'dynamics', got {method!r}")
    for name, flag in (("close", close), ("allow_unconverged", allow_unconverged), ("sync", sync)):
        if not isinstance(flag, (bool, np.bool_)):  # "no" is truthy: allow_unconverged="no" allowed it
            raise ValueError(f"{name} must be True or False, got {flag!r}")
    if isinstance(scene, Scene) and (scene.contact == "full" or contact == "full"):
        return _settle_full(scene, tol, max_steps, warm_start, close, allow_unconverged, contact, sync)
    if contact is None:
        contact = "point" if method == "newton" else "surface"
    if contact not in ("point", "surface") or (method == "dynamics" and contact != "surface"):
        raise ValueError(f"contact must be 'point' or 'surface' ('surface' for method='dynamics'), got {contact!r}")
    if tol is None:
        # dynamics: MuJoCo's sticking friction creeps (~1e-5 of the weight), so a
        # scene with a workpiece stops at its creep floor (dynamics_tolerance: DYN_TOL, more for a heavy
        # workpiece); without contact it goes as far as Newton.
        tol = DEFAULT_TOL if method == "newton" or not scene.has_workpiece else dynamics_tolerance(scene)
    if max_steps is None:
        max_steps = NEWTON_BUDGET if method == "newton" else 20_000
    tol, max_steps = _check_settle_args(scene, tol, max_steps)
    if warm_start is not None and not isinstance(warm_start, SettledState):
        raise ValueError(f"warm_start must be a SettledState or None, got {type(warm_start).__name__}")
    t0 = time.perf_counter()
    m, d = scene.model, scene.data
    saved = save_options(m)
    clear_warnings(d)
    per = min(SOLVE_ITERS, max_steps)  # one solve's share
    held = scene.has_workpiece
    converged, why = True, "ok"
    run = None
    try:
        if warm_start is not None:
            if warm_start.qpos.shape != d.qpos.shape:
                raise ValueError("warm_start does not match the scene's layout (qpos size)")
            d.qpos[:] = warm_start.qpos
            d.qvel[:] = 0.0
            mujoco.mj_forward(m, d)
            held = warm_start.held and scene.has_workpiece
        if method == "dynamics":
            if not scene.has_workpiece and warm_start is None:
                start_free(scene)  # a free finger from its chain equilibrium: the dynamics checks it is at rest
                mujoco.mj_forward(m, d)
            state = settle_dynamics(scene, tol, max_steps, warm_start, close, allow_unconverged, t0,
                                    static_settle=settle)
            return _finish(scene, state, tol, allow_unconverged, "dynamic settle", f"{state.steps} steps")
        run = ChainNewton(scene)
        run.budget = max_steps  # every Newton iteration of this settle counts against max_steps
        run.friction_at = "centreline" if contact == "point" else "surface"
        configure_statics(scene)
        wdofs = tuple(int(x) for x in scene.workpiece_dof)
        if scene.has_workpiece and held:
            if scene.grip in ("I", "II") and warm_start is None and close:
                target = scene.profile
                try:
                    held = close_grip(scene, run, tol, per)
                except SettleError:
                    set_curvature(scene, target)
                    # the frictionless closing path can fold (large |kappa|): start
                    # instead from the hinge chain's grip equilibrium, tip on the face
                    held = place_on_chain(scene, run)
            if held:
                held, converged, why = release(scene, run, tol, per)
        else:
            started = False
            if not scene.has_workpiece and warm_start is None:
                # a free finger starts from the hinge chain's free (energy-minimising) equilibrium, the
                # MuJoCo finger's own: Newton only polishes, a soft rod (gravity far above the springs)
                # settles like any other, and a bistable rod takes the same branch with both methods
                started = start_free(scene)
            converged, why = run.solve(tol, per, frozen=wdofs, at_rest=started)  # (judged at once if at rest)
        if scene.has_workpiece and not held and (converged or why == "stalled") and not run.spent():
            # dropped: a release without an equilibrium (Newton stalls as the workpiece falls) is a
            # drop too; a spent budget or a solve that ran out of iterations is not (issue 16: a Grip I
            # release at D = 1e4 that hit max_iter was reported dropped, the finger through the box)
            converged, why = finger_alone(scene, run, tol, per)
        if not converged and not allow_unconverged:
            raise SettleError(f"settle did not converge ({why} after {run.iterations} Newton iterations)")
        state = read_newton(scene, run, t0, held, converged)
        # the reported (MuJoCo) residual is checked, not only Newton's own KKT rows; a grip's
        # tolerance is raised to its contact round-off floor
        tolerance = max(tol, angle_floor(scene))  # the joint angles' round-off (stiff fine chains)
        if held:
            # (the cap scales with the stiffness the solve chose for a hard-pressed contact: Newton.stiffen)
            tolerance = max(tolerance, min(run.noise_floor(), RESIDUAL_FLOOR_MAX * run.stiffening))
        state = _finish(scene, state, tolerance, allow_unconverged, "settle", f"{run.iterations} Newton iterations")
    finally:
        restore_options(m, saved)
        d.qfrc_applied[:] = 0.0
        d.qvel[:] = 0.0
        if sync and (run is None or not run.positions_current()):  # (a contact-free state's are there already)
            sync_scene(scene)
    return state


def _settle_full(scene, tol, max_steps, warm_start, close, allow_unconverged, contact, sync=True) -> SettledState:
    """``contact="full"`` (:mod:`.full_contact`): the over-damped dynamics with every contact on, whatever
    ``method`` (the full-contact Newton is not built); ``tol`` defaults to the dynamics' creep floor."""
    from simgrip.settle.full_contact import settle_full

    if scene.contact != "full":
        raise ValueError("contact: 'full' needs a scene built with contact='full' (build_scene(..., contact='full'))")
    if contact not in (None, "full"):
        raise ValueError(f"contact: a full-contact scene settles with contact='full', got {contact!r}")
    if warm_start is not None:
        raise ValueError("warm_start: not supported with contact='full' (each settle closes from the built start)")
    if not close:
        raise ValueError("close: a full-contact settle always closes from the built start")
    if tol is None:
        tol = dynamics_tolerance(scene) if scene.has_workpiece else DYN_TOL
    tol, max_steps = _check_settle_args(scene, tol, 20_000 if max_steps is None else max_steps)
    t0 = time.perf_counter()
    m, d = scene.model, scene.data
    saved = save_options(m)
    clear_warnings(d)
    try:
        state = settle_full(scene, tol, max_steps, allow_unconverged, t0)
        state = _finish(scene, state, tol, allow_unconverged, "full-contact settle", f"{state.steps} steps")
    finally:
        restore_options(m, saved)
        d.qfrc_applied[:] = 0.0
        d.qvel[:] = 0.0
        if sync:
            sync_scene(scene)
    return state


settle = functools.wraps(_settle)(settle)
settle.__name__ = settle.__qualname__ = "settle"


def settle_sweep(scene: Scene, profiles, **kw) -> list[SettledState]:
    """Settle ``scene`` for each profile in turn, warm-starting from the previous state.

    The first profile is settled from the scene's current state (with the
    closing procedure for Grips I/II); the following ones change only
    ``qpos_spring`` (:func:`simgrip.sim.scene.set_curvature`) and start from the
    previous equilibrium.  A dropped workpiece stays dropped.
    """
    out = []
    prev = None
    for p in profiles:
        set_curvature(scene, p)
        st = settle(scene, warm_start=prev, **kw)
        out.append(st)
        prev = st
    return out

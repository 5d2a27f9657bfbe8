"""The settle of a K-finger gripper (:mod:`simgrip.gripper.scene`): the symmetry skip where exact, else dynamics.

:func:`settle_gripper` by default (``method="auto"``) settles an exactly
symmetric scene (:func:`simgrip.gripper.scene_symmetry.symmetry`) by the symmetry skip
(:mod:`simgrip.gripper.symmetry`: one finger's planar Newton settle,
the paper's point contact by default, replicated to K fingers), and any other
scene by the over-damped dynamics (below), as the planar settle's
default is the fast point-contact Newton and its dynamics the surface
contact.  The state's ``method`` and ``contact`` say which ran.

The dynamics (:mod:`simgrip.gripper.dynamics`) is the planar
``settle(method="dynamics")``'s integrator (:mod:`simgrip.settle.integrator`)
on all K fingers and the workpiece, with MuJoCo's dense constraint Jacobian
up to :data:`GRIPPER_DENSE_NV` dofs.  This module drives it:

* **Start** (:mod:`simgrip.gripper.start`): every finger at the hinge chain's grip equilibrium
  (:func:`simgrip.reference.solve_chain`, the tip a hair inside ``X = b/2``),
  the workpiece centred on the palm axis, level with the tips; an off-centre
  or turned workpiece, or unequal fingers, start with each finger at its own
  reach and a share of the weight that balances the workpiece.  Each finger of a box
  (``K`` = 2, 4) or cylinder is then exactly the planar problem; a sphere's
  tips start at ``X = (b/2) cos beta`` (``beta`` the scene's
  ``contact_angle``, the contact normal's elevation), which is the planar
  problem at width ``b cos beta`` (:mod:`simgrip.reference.inclined`), and
  friction keeps them there.  A finger that cannot reach ``X = b/2`` at
  full curvature, or whose loaded equilibrium would pull on the surface
  (``N1 <= 0``), leaves the workpiece unheld; a chain equilibrium that does
  not exist or is unstable raises
  :class:`SettleError` (the planar settle's staged closing is not provided here).
* **Indeterminate forces** (``K >= 4``): statics fixes each finger's ``N1``,
  the tips and the workpiece's pose, but not how the fingers share the
  weight (``N2``) and the out-of-plane forces (``N3``); the settle keeps
  the start's least-norm split (sticking contacts hold what they start
  with).  Per-finger ``N2``/``N3`` are then the start's choice, not physics.
* **Release**: the chains' start shape already carries the weight by
  friction, so the workpiece is let go at once; the dynamics then
  runs until the static residual at rest is below ``tol`` (default
  :func:`gripper_tolerance`, scaled by the weight ``K M``) and the velocities
  below :data:`~simgrip.settle.dynamics.DYN_VTOL` (tested between batches of
  :data:`~simgrip.settle.integrator.DYN_BATCH` steps).  A tip that slides
  :data:`~simgrip.settle.dynamics.DYN_DROP_SLIP` over the workpiece's surface
  (in the workpiece's frame) or a workpiece that falls
  :data:`~simgrip.settle.dynamics.DYN_DROP_FALL` is dropped: it is parked
  (held, contact off) and the fingers settle alone from the chain's free shape.
* **Drop retry**: a workpiece dropped from a start that touched it is settled
  once more from the start at half the step (as the planar dynamic settle:
  a growing two-step oscillation of the contacts at ``h`` can throw it off);
  it is dropped when it drops at both steps.
* **Penetration**: a settled state penetrating
  :data:`~simgrip.settle.dynamics.DYN_PEN_LIMIT` or more is settled again with
  half the step (at most three times).

The static residual is the dynamics' (``qfrc_smooth + qfrc_constraint`` at
``qvel = 0``, :mod:`simgrip.gripper.dynamics`).
:class:`GripperState` (:mod:`simgrip.gripper.state`, re-exported here)
reports one :class:`FingerRecord` per finger, read in the finger's own frame
like the planar finger.
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

from simgrip.settle import check_tol_steps
from simgrip.settle.dynamics import DYN_PEN_LIMIT, DYN_TOL, DYN_TOL_PER_WEIGHT
# FingerRecord, GripperState, contact_rest_depth and straight_frequency are re-exported (__all__)
from simgrip.gripper.dynamics import GripperDynamics, contact_rest_depth, settle_once, straight_frequency
from simgrip.gripper.start import is_symmetric, start_qpos, warn_unreached
from simgrip.gripper.state import FingerRecord, GripperState, read_gripper_state, warn_friction_boundary
from simgrip.settle.state import SettleError
from simgrip.settle.statics import restore_options, save_options
from simgrip.sim.checks import clear_warnings
from simgrip.gripper.scene import GripperScene
from simgrip.validity import check_grip_shape
from simgrip.validity_shapes import check_gripper_valid

__all__ = ["FingerRecord", "GripperState", "contact_rest_depth", "gripper_tolerance", "settle_gripper",
           "straight_frequency"]

#: Default physics-step budget of one settle.
GRIPPER_MAX_STEPS = 20_000
#: Largest number of dofs for which the dynamics uses MuJoCo's dense constraint Jacobian (sparse above).
#: A gripper has few contact rows (one per finger), so the dense path's step stays the cheaper one up to
#: ``nv`` ~ 200 (Grip II, K = 2 and 4, n = 16 to 96), well above MuJoCo's own switch at 60.  The settled
#: state is the same to round-off either way.
GRIPPER_DENSE_NV = 200


def gripper_tolerance(scene: GripperScene) -> float:
    """Default static residual tolerance: ``max(DYN_TOL, DYN_TOL_PER_WEIGHT * K * M)``.

    As the planar dynamic settle's (:func:`simgrip.settle.dynamics.dynamics_tolerance`): MuJoCo's
    sticking friction creeps and leaves a fixed fraction of the force it carries unbalanced at
    rest; here the friction carries the whole workpiece, ``K M`` (over rho g l).
    """
    return max(DYN_TOL, DYN_TOL_PER_WEIGHT * scene.fingers * float(scene.params.M))


def settle_gripper(scene: GripperScene, *, tol: float | None = None, max_steps: int | None = None,
                   allow_unconverged: bool = False, method: str | None = None,
                   contact: str | None = None) -> GripperState:
    """Settle a K-finger gripper: the symmetry skip where the scene is exactly symmetric, else the dynamics.

    The default (``method=None``, ``"auto"``) is as the planar settle's: the
    fast static solve of the paper's point-contact problem where it is exact
    (one finger's planar Newton settle replicated to K,
    :mod:`simgrip.gripper.symmetry`), the over-damped dynamics with
    MuJoCo's surface contact (see the module docstring) where it is not.  The
    state's ``method`` says which ran.  Where the skip fails (:class:`SettleError`,
    or an unconverged state) under ``"auto"``, the dynamics
    settles the scene instead and the state's ``warnings`` say so (the default
    must not fail where another method answers; the Grip III cradle: one
    finger's planar dynamics, replicated); an explicit ``"symmetric"`` or
    ``contact="point"`` (the skip's only) raise as before.

    Parameters
    ----------
    scene : GripperScene
    tol : float, optional
        Static residual tolerance (over ``rho g l^2`` / ``rho g l``); default
        :func:`gripper_tolerance` for the dynamics (MuJoCo's sticking friction
        creeps below it), the planar Newton's for the skip.
    max_steps : int, optional
        Dynamics: physics steps allowed to the whole settle (restarts
        included; default :data:`GRIPPER_MAX_STEPS`).  Skip: the planar
        Newton's iteration budget (default its own).
    allow_unconverged : bool
        Return ``converged=False`` instead of raising :class:`SettleError`.
    method : {None, "auto", "symmetric", "dynamics"}
        None is ``"auto"``: ``"symmetric"`` where the scene is exactly
        symmetric (:func:`simgrip.gripper.scene_symmetry.symmetry`), else
        ``"dynamics"``.  ``"symmetric"``: one finger's planar static settle
        replicated to K (ValueError naming ``method`` where the scene is not
        exactly symmetric); ``"dynamics"``: the over-damped dynamics of all K
        fingers and the workpiece (Grips I/II only: the K = 4 cradle, Grip
        III, is settled by the skip).
    contact : {None, "point", "surface"}
        Where the sticking friction acts.  The skip: ``"point"`` (default, the
        paper's point contact, on the centreline) or ``"surface"`` (box and
        cylinder: at MuJoCo's contact point, the tip sphere's couple, as the
        dynamics).  The dynamics has MuJoCo's surface contact only:
        ``"point"`` raises ValueError naming ``contact`` where it runs.

    Returns
    -------
    GripperState
    """
    if not isinstance(scene, GripperScene):
        raise ValueError(f"scene must be a simgrip.gripper.scene.GripperScene, got {type(scene).__name__}")
    if scene.contact == "full" or contact == "full":  # every link touches (issue 17): the guarded dynamics
        from simgrip.gripper.full import settle_gripper_full

        if scene.contact != "full" or contact not in (None, "full"):
            raise ValueError("contact: 'full' needs a gripper built with contact='full' and settles with it only")
        if method not in (None, "auto", "dynamics"):
            raise ValueError(f"method: a full-contact gripper settles by the dynamics, got {method!r}")
        tol, _ = check_tol_steps(gripper_tolerance(scene) if tol is None else tol,
                                 1 if max_steps is None else max_steps)
        return check_gripper_valid(scene, settle_gripper_full(scene, tol=tol, max_steps=max_steps,
                                                              allow_unconverged=allow_unconverged))
    from simgrip.gripper.symmetry import symmetric_or_none

    t0 = time.perf_counter()
    try:
        skip = symmetric_or_none(scene, method, contact=contact, tol=tol, max_steps=max_steps,
                                 allow_unconverged=allow_unconverged)
    except SettleError as exc:
        if not _may_fall_back(scene, method, contact):
            raise
        skip, why = None, str(exc)
    else:
        if skip is None:
            return check_gripper_valid(scene, _settle_dynamics(scene, tol, max_steps, allow_unconverged))
        if skip.converged or not _may_fall_back(scene, method, contact):
            return check_gripper_valid(scene, skip)
        why = f"symmetric settle did not converge (residual {skip.residual:.3g}, tolerance {skip.tolerance:.3g})"
    # method "auto": the default must not fail where another method answers; the dynamics settles the same
    # scene (MuJoCo's surface contact), and the state says why it, not the skip, answered
    try:
        if scene.grip == "III":  # the cradle: one finger's planar dynamics, replicated
            from simgrip.gripper.symmetry import settle_cradle_dynamics

            state = settle_cradle_dynamics(scene, tol=tol, max_steps=max_steps, allow_unconverged=allow_unconverged)
        else:
            state = _settle_dynamics(scene, tol, max_steps, allow_unconverged)
    except SettleError as exc:
        raise SettleError(f"{why}; the fallback to the dynamics failed too: {exc}") from exc
    if skip is not None and not state.converged:
        return check_gripper_valid(scene, skip)  # allow_unconverged: neither converged; the skip's (the default's)
    which = "one finger's planar dynamics, replicated" if scene.grip == "III" else "the over-damped dynamics"
    state.warnings.insert(0, f"the symmetry skip failed ({why}): settled by {which} instead "
                             f"(method 'dynamics', MuJoCo's surface contact)")
    state.wall_time_s = time.perf_counter() - t0
    return check_gripper_valid(scene, state)


def _may_fall_back(scene: GripperScene, method: str | None, contact: str | None) -> bool:
    """Whether a failed symmetry skip falls back to the dynamics: ``method`` auto (None) and a contact the dynamics
    has (None or ``"surface"``; the point contact is the skip's only).  The cradle (Grip III) falls back to one
    finger's planar dynamics, replicated (:func:`~simgrip.gripper.symmetry.settle_cradle_dynamics`)."""
    return method in (None, "auto") and contact in (None, "surface")


def _settle_dynamics(scene: GripperScene, tol: float | None, max_steps: int | None,
                     allow_unconverged: bool) -> GripperState:
    """The over-damped dynamics of all K fingers and the workpiece (see the module docstring)."""
    if tol is None:
        tol = gripper_tolerance(scene)
    if max_steps is None:
        max_steps = GRIPPER_MAX_STEPS
    tol, max_steps = check_tol_steps(tol, max_steps)
    t0 = time.perf_counter()
    m, d = scene.model, scene.data
    saved, jacobian = save_options(m), int(m.opt.jacobian)
    dense = m.nv <= GRIPPER_DENSE_NV
    m.opt.jacobian = int(mujoco.mjtJacobian.mjJAC_DENSE if dense else mujoco.mjtJacobian.mjJAC_SPARSE)
    clear_warnings(d)
    q_start = start_qpos(scene)
    reach = q_start is not None
    if not reach:
        q_start = np.array(d.qpos)
    steps, factor = 0, 1.0
    retried_drop = False
    try:
        for attempt in range(5):
            restore_options(m, saved)  # a dropped attempt left contact off
            d.qpos[:] = q_start
            d.qvel[:] = 0.0
            d.qfrc_applied[:] = 0.0
            mujoco.mj_forward(m, d)
            dyn = GripperDynamics(scene, factor)
            if reach and not is_symmetric(scene) and scene.workpiece != "sphere":
                seated = start_qpos(scene, timestep=dyn.h)  # every tip at MuJoCo's rest depth (gripper_start)
                if seated is not None:
                    d.qpos[:] = seated
                    mujoco.mj_forward(m, d)
            held, converged, why = settle_once(scene, dyn, tol, int(max_steps) - steps, reach)
            steps += dyn.steps
            state = read_gripper_state(scene, dyn, held, converged, steps, t0, tol)
            check_grip_shape(scene, state)
            warn_friction_boundary(scene, state)
            warn_unreached(scene, state)
            if reach and not held and not retried_drop and state.converged and steps < max_steps:
                # dropped from a start that touched: once more at half the step, as the planar dynamic settle
                # does (a growing two-step oscillation of the contacts at h can throw the workpiece off)
                retried_drop = True
                factor *= 0.5
                continue
            if (state.penetration < DYN_PEN_LIMIT or attempt >= 3 or steps >= max_steps
                    or not state.converged):
                break
            factor *= 0.5
        if not state.converged and not allow_unconverged:
            raise SettleError(f"gripper settle did not converge ({why} after {steps} steps, residual "
                              f"{state.residual:.3g}, tolerance {tol:.3g})")
    finally:
        restore_options(m, saved)
        m.opt.jacobian = jacobian
        d.qfrc_applied[:] = 0.0
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
    return state

"""Grips I/II: close the finger on the workpiece, then release it under friction.

Start (:func:`start_on_chain`): the hinge chain's grip equilibrium with the
workpiece at the tip, wherever it is valid (the free finger reaches the face,
the equilibrium exists, is stable and pushes on the face); a free finger starts
from the chain's free equilibrium (:func:`start_free`).  The MuJoCo finger is
that chain, so the static solve only polishes.

Staged closing (where the chain start is not valid): the finger curls with contact off until its tip reaches ``X = b/2``
(secant on the curvature factor); the workpiece is placed there and held
(weight cancelled, frictionless) while the curvature goes to its final value by
continuation, halving failed increments (:func:`close_grip`).  The stages up to
the penultimate one run on the hinge chain (:func:`_close_predicted`) and the
static solve takes over for the last stage; a fold of the path or a failing
stage hands the whole closing to the MuJoCo ramp.  If the frictionless path
folds (large ``|kappa|``), the start is the hinge chain's grip equilibrium
(:func:`place_on_chain`).

Release (:func:`release`): a sticking constraint at each contact, the
workpiece free under its full weight; a violated friction cone drops the
workpiece (I/II) or lets the contact slide with friction ``mu N`` until it
holds (III).
"""

from __future__ import annotations

import mujoco
import numpy as np

from simgrip.reference import DiscreteError, chain_start, hinge_chain
from simgrip.settle.chain_model import gravity_factor
from simgrip.settle.newton import Newton
from simgrip.settle.state import SettleError, finger_tip
from simgrip.sim.scene import BOX_HEIGHT, Scene, set_curvature
from simgrip.sim.workpiece_motion import hold_workpiece, place_workpiece

__all__ = ["close_grip", "finger_alone", "hold_workpiece", "place_on_chain", "place_workpiece", "release",
           "start_free", "start_on_chain"]

#: Grips I/II start from the hinge chain's equilibrium (:func:`start_on_chain`) where it is valid;
#: False: always the staged closing.
CHAIN_START = True
#: Curvature ramp stages while closing on the held workpiece.
CLOSE_STAGES = 8
#: Newton iterations allowed to one continuation stage while closing (a failing stage is halved).
CLOSE_STAGE_ITERS = 40
#: The closing predictor (:func:`_close_predicted`) hands over to the staged ramp when a chain
#: stage's stability margin (smallest projected Hessian eigenvalue) falls below this fraction of
#: the first stage's, or when a stage's change of the link angles differs from the previous
#: stage's by more than :data:`FOLD_KINK` times the latter (a fold or branch jump of the path).
FOLD_MARGIN = 0.5
FOLD_KINK = 0.5


def start_free(scene: Scene) -> bool:
    """Put every finger at the hinge chain's free equilibrium (the MuJoCo finger alone is that chain).

    The static solve then only polishes (one or two iterations) and a soft rod
    (small ``D``: gravity far above the springs, where Newton from the straight
    finger stalls) settles like any other.  False (state unchanged) when the
    chain solver fails.
    """
    try:
        # the angles alone (chain_angles' equilibrium by its own Newton steps on LAPACK, chain_start): the free
        # start needs no fields, nodes or stability eigenvalue
        phi = chain_start.free_start_angles(scene.params, scene.profile, scene.n, gravity=gravity_factor(scene))
    except (DiscreteError, ValueError):
        return False
    q = phi.copy()  # solve_chain's joint_angles, np.diff(phi, prepend=0) without its concatenation: phi_0 - 0 is phi_0
    q[1:] -= phi[:-1]
    scene.data.qpos[scene.joint_qpos] = q[None, :]
    scene.data.qvel[:] = 0.0
    return True


def finger_alone(scene, run, tol, max_steps):
    """The workpiece is gone: park it (held, no contact) and settle the finger (from the chain's free state)."""
    m = scene.model
    started = start_free(scene)
    hold_workpiece(scene, True)
    run.sticks, run.sliding, run.lam = [], {}, np.zeros(0)
    run.normal_active, run.N = [], np.zeros(0)
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    frozen = tuple(int(x) for x in scene.workpiece_dof)
    if started and hasattr(run, "_at_rest"):  # the chain Newton judges a start at rest by MuJoCo first
        return run.solve(tol, max_steps, frozen=frozen, at_rest=True)
    return run.solve(tol, max_steps, frozen=frozen)


def release(scene: Scene, run: Newton, tol: float, max_steps: int) -> tuple[bool, bool, str]:
    """Let go of the workpiece: stick it where it touches, settle, check the friction cone.

    Returns ``(held, converged, reason)``.  Grips I/II: a violated cone drops the
    workpiece.  Grip III: violated sticks slide with friction ``mu N`` until the
    settled state holds, then stick again.
    """
    hold_workpiece(scene, False)
    if not scene.free_workpiece:
        conv, why = run.solve(tol, max_steps, frozen=tuple(int(x) for x in scene.workpiece_dof))
        return True, conv, why
    touch(scene, run)
    if run.stick_now() == 0:
        return False, True, "no contact"
    for _ in range(6):
        conv, why = run.solve(tol, max_steps)
        if not conv:
            if scene.grip == "III" or why != "stalled" or run.spent():
                return False, conv, why
            return False, True, "dropped"
        bad = run.cone_violations()
        if not bad:
            return True, True, "ok"
        if scene.grip in ("I", "II"):
            return False, True, "dropped"
        for i, sign in bad:
            run.sliding[i] = sign
        conv, why = run.solve(tol, max_steps)
        if not conv:
            if run.spent():
                return False, False, why
            return False, True, "dropped"
        run.stick_now()  # stopped sliding: stick at the new contact
    return False, False, "friction did not settle"


def place_on_chain(scene: Scene, run: Newton) -> bool:
    """Fallback start for Grips I/II: the hinge chain's equilibrium, workpiece at the tip."""
    try:
        # the tip a hair inside the face so that MuJoCo reports the contact
        ch = hinge_chain.solve_chain(scene.grip, scene.params.replace(b=scene.params.b - 2e-6), scene.profile, scene.n,
                                     gravity=gravity_factor(scene), stability="none")
    except DiscreteError as exc:
        raise SettleError(f"no starting shape for grip {scene.grip}: {exc}") from exc
    d = scene.data
    d.qpos[scene.joint_qpos] = ch.joint_angles[None, :]
    run.N, run.normal_active = np.zeros(0), []
    scene.model.opt.disableflags = run._flags if hasattr(run, "_flags") else scene.model.opt.disableflags
    place_workpiece(scene, float(ch.tip[1]) * scene.length, forward=False)
    return True


def touch(scene: Scene, run: Newton) -> None:
    """Lower the workpiece onto the finger(s) if it hovers (placement round-off)."""
    d = scene.data
    wz = [qa for name, qa in zip(scene.workpiece_joints, scene.workpiece_qpos) if name == "z"]
    if not wz or not run.pairs:
        return
    for _ in range(3):
        gap = float(np.min(run._dists(d.qpos)))
        if gap <= 0.0:
            break
        d.qpos[wz[0]] -= gap + 1e-9 * scene.length
    # nothing more: the release's next step (Newton.stick_now, touch's only caller's) evaluates MuJoCo's balance at
    # this state itself (mj_inverse: positions, contacts and forces), before anything reads the data; positions
    # computed here (mj_kinematics, mj_comPos) would be overwritten unread


def _inside(scene: Scene, p):
    """``p`` with the face a hair nearer (``b - 2e-6``), so that MuJoCo reports the tip's contact: kept on the scene
    with the parameters object it was made from (frozen: the same object is the same values)."""
    memo = scene.__dict__.get("_chain_start_inside")
    if memo is not None and memo[0] is p:
        return memo[1]
    out = p.replace(b=p.b - 2e-6)
    scene.__dict__["_chain_start_inside"] = (p, out)
    return out


def start_on_chain(scene: Scene, run: Newton | None) -> bool | None:
    """Grips I/II: start from the hinge chain's grip equilibrium, the workpiece at the tip.

    The MuJoCo finger is the hinge chain (:mod:`simgrip.settle.chain_model`), so
    the chain's equilibrium with the tip on the face and the workpiece's weight
    as friction (:func:`simgrip.reference.solve_chain`) is the held state up to
    MuJoCo's contact (penetration, the tip radius's couple), which the release
    then polishes.  Valid when the free finger at full curvature reaches the
    face (else False: no contact, as :func:`close_grip` decides) and the
    chain's equilibrium exists, is stable (positive projected Hessian) and
    pushes on the face (``N1 > 0``); otherwise None and the staged closing runs.
    """
    p = scene.params
    try:
        # the tip a hair inside the face so that MuJoCo reports the contact
        # only the angles, tip, N1 and the stability's sign are read (solve_chain's, by chain_start)
        ch = chain_start.grip_start(scene.grip, _inside(scene, p), scene.profile, scene.n,
                                    gravity=gravity_factor(scene))
        # the free finger's equilibrium next to the grip's: Newton in link angles when the solve has the
        # chain model (O(n), from the grip shape), else the chain solver (free_equilibrium copies its start:
        # one finger's angles are passed as they are)
        model = getattr(run, "model", None)
        if model is not None:
            start = ch.link_angles if model.fingers == 1 else np.tile(ch.link_angles, model.fingers)
            phi = model.free_equilibrium(start)
        else:
            phi = None
        phi = phi[:scene.n] if phi is not None else None  # the fingers are mirror images
        if phi is None:
            phi = hinge_chain.chain_angles("free", p, scene.profile, scene.n, guess=ch.link_angles,
                                           gravity=gravity_factor(scene))
        if float(np.add.reduce(np.cos(phi))) / scene.n > 0.5 * p.b:  # (np.sum's reduction, without its wrapper)
            return False
    except (DiscreteError, ValueError):
        return None
    if not (ch.N1 > 0.0 and ch.stable):
        return None
    scene.data.qpos[scene.joint_qpos] = ch.joint_angles[None, :]
    if run is not None:
        run.N, run.normal_active = np.zeros(0), []
    place_workpiece(scene, float(ch.tip[1]) * scene.length, forward=False)
    return True


def close_grip(scene: Scene, run: Newton, tol: float, max_steps: int) -> bool:
    """Grips I/II closing: the chain start where valid, else curl (contact off) to first touch,
    place and hold the box, ramp.

    Returns False when the finger cannot reach the workpiece (its free tip never
    comes back to ``X = b/2``).
    """
    if CHAIN_START:
        started = start_on_chain(scene, run)
        if started is not None:
            return started
    m = scene.model
    target = scene.profile
    half = 0.5 * scene.params.b
    wdofs = tuple(int(x) for x in scene.workpiece_dof)
    loose = max(tol, 1e-8)
    flags = int(m.opt.disableflags)

    def free_tip(t):
        set_curvature(scene, target.scaled(t))
        conv, why = run.solve(loose, max_steps, frozen=wdofs)
        if not conv:
            raise SettleError(f"free finger did not settle while closing ({why})")
        return finger_tip(scene)[0]

    hold_workpiece(scene, True)
    m.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    x1 = free_tip(1.0)
    if x1 > half:
        set_curvature(scene, target)
        m.opt.disableflags = flags
        return False
    x0 = free_tip(0.0)
    lo, hi, xlo, xhi = 0.0, 1.0, x0, x1
    t, x = 1.0, x1
    for _ in range(60):
        t = lo + (hi - lo) * (xlo - half) / (xlo - xhi)
        t = min(max(t, lo + 0.02 * (hi - lo)), hi - 0.02 * (hi - lo))
        x = free_tip(t)
        if x > half:
            lo, xlo = t, x
        else:
            hi, xhi = t, x
        if abs(x - half) < 1e-7 or hi - lo < 1e-10:
            break
    if x < half:  # start just outside the face
        t = lo
        free_tip(t)
    z0 = finger_tip(scene)[1]
    place_workpiece(scene, z0 * scene.length, forward=False)
    m.opt.disableflags = flags
    if _close_predicted(scene, run, target, t, z0, loose, min(max_steps, CLOSE_STAGE_ITERS), wdofs):
        return True
    # continuation in the curvature factor, halving the increment when a stage fails
    s, h = t, (1.0 - t) / CLOSE_STAGES
    while s < 1.0:
        s_next = min(1.0, s + h)
        q_prev, contact_prev = scene.data.qpos.copy(), run.contact_snapshot()
        set_curvature(scene, target.scaled(s_next))
        conv, why = run.solve(loose, min(max_steps, CLOSE_STAGE_ITERS), frozen=wdofs)
        if conv:
            s = s_next
            continue
        if h < (1.0 - t) / CLOSE_STAGES / 8:
            raise SettleError(f"closing on the held workpiece did not converge ({why}, curvature factor {s_next:g})")
        scene.data.qpos[:] = q_prev
        run.restore_contact(contact_prev)
        h *= 0.5
    set_curvature(scene, target)
    return True


def _close_predicted(scene: Scene, run: Newton, target, t: float, z0: float, tol: float, max_steps: int,
                     wdofs) -> bool:
    """Closing in two MuJoCo stages: the ramp's first stages on the hinge chain, its last in MuJoCo.

    The held, frictionless state along the closing (workpiece frozen at its
    placement height ``z0``, tip on the face ``X = b/2``, purely normal tip
    load) is the hinge chain's equilibrium of ``solve_chain`` with ``M = 0``
    (~1 ms), the exact state of the same chain with an ideal contact.  The chain
    runs the continuation's stages from the first-touch shape (each warm-started
    from the previous one, so it follows the ramp's branch) up to the
    penultimate one; MuJoCo's Newton corrects that state to MuJoCo's contact and
    then takes the ramp's last stage exactly as :func:`close_grip` would.  The last
    stage is the hardest (the normal force grows along the ramp): where it
    fails, the ramp would halve it and might fall back to the chain's grip
    equilibrium, so the full ramp runs instead and the answer stays the ramp's.
    Used only when the prediction is valid -- every chain stage converges to a
    stable state (positive projected Hessian) with the tip pushing on the face
    (``N1 > 0``) within the box's height, and both Newton solves converge with
    every tip pair carrying a positive normal force; otherwise the scene and the
    Newton state are restored and False returned (the MuJoCo ramp then runs).
    """
    m, d = scene.model, scene.data
    margin = 0.5 * BOX_HEIGHT - 0.1
    # the tip a hair inside the face so that MuJoCo reports the contact (as place_on_chain)
    params = scene.params.replace(b=scene.params.b - 2e-6, M=0.0)
    stages = []
    s, h = t, (1.0 - t) / CLOSE_STAGES
    while s < 1.0:  # the stages of close_grip's continuation, same arithmetic
        s = min(1.0, s + h)
        stages.append(s)
    # the ramp's last real stage starts at the last stage a good step below 1 (the cumulative sum
    # can leave a last stage of round-off size: that one stays in MuJoCo too)
    k = max((i for i, si in enumerate(stages) if 1.0 - si > 0.5 * h), default=-1)
    if k < 0:
        return False
    phi = np.cumsum(np.array(d.qpos[scene.joint_qpos[0]]))
    ch, step, lam0 = None, None, None
    for s in stages[:k + 1]:
        try:
            ch = hinge_chain.solve_chain(scene.grip, params, target.scaled(s), scene.n, guess=phi,
                                         gravity=gravity_factor(scene))
        except (DiscreteError, ValueError):
            return False
        if not (ch.success and ch.N1 > 0.0 and ch.min_eigenvalue > 0.0 and abs(float(ch.tip[1]) - z0) < margin):
            return False
        # a fold of the frictionless path (where the ramp's Newton fails and the closing falls
        # back to the chain's grip equilibrium) shows as a softening stability margin or a kink
        # in the path; the coarse chain stages would jump it to another branch: leave it to the ramp
        lam0 = ch.min_eigenvalue if lam0 is None else lam0
        new_step = ch.link_angles - phi
        if ch.min_eigenvalue < FOLD_MARGIN * lam0 or (
                step is not None and np.max(np.abs(new_step - step)) > FOLD_KINK * np.max(np.abs(step))):
            return False
        phi, step = ch.link_angles, new_step
    q_prev, contact_prev = d.qpos.copy(), run.contact_snapshot()  # stiffness and solref too (Newton.stiffen)
    profile = scene.profile
    d.qpos[scene.joint_qpos] = ch.joint_angles[None, :]
    mujoco.mj_forward(m, d)
    ok = True
    try:
        for s in stages[k:]:  # MuJoCo at the penultimate stage, then the ramp's last stage(s)
            set_curvature(scene, target.scaled(s))
            conv, _ = run.solve(tol, max_steps, frozen=wdofs)
            ok = (conv and bool(run.pairs) and sorted(run.normal_active) == list(range(len(run.pairs)))
                  and bool(np.all(run.N > 0.0)) and abs(finger_tip(scene)[1] - z0) < margin)
            if not ok:
                break
    except SettleError:
        if run.spent():
            raise
        ok = False
    if ok:
        return True
    d.qpos[:] = q_prev
    run.restore_contact(contact_prev)
    set_curvature(scene, profile)
    mujoco.mj_forward(m, d)
    return False

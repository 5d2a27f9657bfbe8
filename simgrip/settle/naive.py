"""Baselines: settling with plain MuJoCo dynamics (physical inertia, light damping).

:func:`naive_settle` steps until the link angles are within ``tol`` of a
settled state; :func:`naive_relax` relaxes from the current state and records
when the static residual (:class:`~simgrip.settle.statics.RestResidual`) falls
below ``tol`` and when the tip enters a band around a target tip, extrapolating
a criterion not met from the exponential decay of its envelope.  They are what
the static settle is measured against (``simgrip bench``).
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from simgrip.settle.state import SettledState, SettleError, finger_tip
from simgrip.settle.statics import RestResidual
from simgrip.sim.checks import clear_warnings, invalid_state
from simgrip.sim.scene import Scene

__all__ = ["HOLD_TOL", "NAIVE_DAMPING_RATIO", "naive_relax", "naive_settle"]

#: Damping ratio of the lowest hinge mode in the naive relaxation.
NAIVE_DAMPING_RATIO = 0.05
#: The naive relaxation holds the workpiece until the finger's residual is below this.
HOLD_TOL = 1e-3


def naive_settle(scene: Scene, reference: SettledState, *, tol: float = 1e-6, max_steps: int = 1_000_000,
                 damping_ratio: float = 0.05, check_every: int = 500, start_qpos=None) -> dict:
    """Baseline: plain MuJoCo dynamics with physical inertia, light damping, largest stable step.

    Damping proportional to stiffness gives the lowest hinge mode
    ``damping_ratio`` of critical; the time step is ``1.8 / omega_max`` of the
    undamped chain (semi-implicit Euler's limit is ``2 / omega_max``; the
    ``implicitfast`` damping does not move it), contacts use MuJoCo's safe
    minimum time constant ``2 dt`` and the model's friction settings (elliptic
    cone, no-slip).  Steps from ``start_qpos`` (default: the scene's state)
    until every link angle is within ``tol`` of ``reference`` (the state
    :func:`settle` found), i.e. the time a plain simulation needs to reach the
    same rest state.  Returns a dict: steps, wall_time_s, error (final max angle
    error), converged, dt, workpiece_drift (over l).
    """
    m, d = scene.model, scene.data
    dt0, damp0, solref0 = float(m.opt.timestep), m.dof_damping.copy(), m.pair_solref.copy()
    t0 = time.perf_counter()
    try:
        if start_qpos is not None:
            d.qpos[:] = start_qpos
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
        M = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M)
        kd = np.where(m.jnt_stiffness[m.dof_jntid] > 0, m.jnt_stiffness[m.dof_jntid], 0.0)
        sub = np.flatnonzero(kd > 0)
        w2 = np.linalg.eigvals(np.linalg.solve(M[np.ix_(sub, sub)], np.diag(kd[sub]))).real
        wmax, wmin = math.sqrt(w2.max()), math.sqrt(w2.min())
        dt = 1.8 / wmax
        m.opt.timestep = dt
        m.dof_damping[:] = 2 * damping_ratio / wmin * kd
        m.pair_solref[:, 0] = 2 * dt
        wz0 = d.xpos[scene.workpiece_body].copy() if scene.has_workpiece else None
        steps, err = 0, math.inf
        while steps < max_steps:
            mujoco.mj_step(m, d, check_every)
            steps += check_every
            if not np.all(np.isfinite(d.qpos)):
                raise SettleError("naive settle diverged")
            phi = np.cumsum(np.array(d.qpos[scene.joint_qpos]), axis=1)
            err = float(np.max(np.abs(phi - reference.link_angles)))
            if err < tol:
                break
        drift = float(np.linalg.norm(d.xpos[scene.workpiece_body] - wz0)) / scene.length if wz0 is not None else 0.0
        return {"steps": steps, "wall_time_s": time.perf_counter() - t0, "error": err, "converged": err < tol,
                "dt": dt, "workpiece_drift": drift}
    finally:
        m.opt.timestep, m.dof_damping[:], m.pair_solref[:] = dt0, damp0, solref0


def naive_relax(
    scene,
    *,
    tol: float = 1e-10,
    target_tip=None,
    tip_tol: float | None = None,
    damping_ratio: float = NAIVE_DAMPING_RATIO,
    max_steps: int = 50_000_000,
    time_budget_s: float = 10.0,
    check_every: int = 200,
    trial_steps: int = 400,
) -> dict:
    """Relax ``scene`` from its current state with physical dynamics (the naive baseline).

    Physical link masses, no armature; stiffness-proportional joint damping
    with ratio ``damping_ratio`` at the lowest undamped mode (MuJoCo's
    ``implicitfast`` integrates it implicitly); contacts with ``solref`` time
    constant ``2 dt``; time step: the largest for which ``trial_steps`` steps
    stay finite and warning-free, by bisection between ``0.25/omega_max`` and
    ``2/omega_max`` (the explicit limit: larger steps lose the contacts) (``setup_s``, not counted in the times).

    Two stopping criteria are tracked:

    * the static residual (``qfrc_smooth + qfrc_constraint`` at rest, over
      ``rho g l^2`` / ``rho g l``, as :func:`simgrip.settle.static_residual`)
      below ``tol``: ``converged``, ``steps_to_tol``, ``time_to_tol_s``;
    * matched error: finger 0's tip within ``tip_tol`` of ``target_tip`` (the
      chain's exact equilibrium) and still there 25 % later:
      ``matched``, ``steps_to_match``, ``time_to_match_s``.

    The run stops when both are met (or the residual criterion alone when no
    target is given), after ``max_steps`` steps or ``time_budget_s`` seconds.
    A criterion not met is **extrapolated** from the exponential decay of its
    quantity's envelope over the second half of the run (``*_extrapolated``;
    ``inf`` when there is no useful decay, e.g. MuJoCo's soft friction creeping).

    The model's options are restored afterwards; the scene's data is left at
    the relaxed state.
    """
    m, d = scene.model, scene.data
    saved = (m.opt.timestep, m.dof_damping.copy(), m.dof_armature.copy(), m.pair_solref.copy())
    q0 = d.qpos.copy()
    t_setup = time.perf_counter()
    want_match = target_tip is not None and tip_tol is not None
    if want_match:
        target_tip = np.asarray(target_tip, float)
    try:
        stiff = m.jnt_stiffness[m.dof_jntid]
        sprung = stiff > 0
        mujoco.mj_forward(m, d)
        m.dof_armature[:] = 0.0
        M = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M)
        idx = np.flatnonzero(sprung)
        w2 = np.linalg.eigvals(np.linalg.solve(M[np.ix_(idx, idx)], np.diag(stiff[idx]))).real
        w2 = w2[w2 > 1e-12]
        wmax, wmin = math.sqrt(w2.max()), math.sqrt(w2.min())
        m.dof_damping[:] = 2.0 * damping_ratio / wmin * np.where(sprung, stiff, 0.0)
        res_fn = RestResidual(scene)

        def reset(dt):
            m.opt.timestep = dt
            m.pair_solref[:] = [2.0 * dt, 1.0]
            d.qpos[:] = q0
            d.qvel[:] = 0.0
            d.qfrc_applied[:] = 0.0
            clear_warnings(d)
            mujoco.mj_forward(m, d)

        def stable(dt) -> bool:
            reset(dt)
            r0 = res_fn(d.qpos)
            for _ in range(max(1, trial_steps // 50)):
                mujoco.mj_step(m, d, 50)
                if invalid_state(d) is not None:
                    return False
            return res_fn(d.qpos) < 10.0 * max(r0, 1e-3) and np.max(np.abs(d.qvel)) < 1e6

        lo, hi = 0.25 / wmax, 2.0 / wmax
        while not stable(lo) and lo > 1e-6 / wmax:
            lo *= 0.25
        for _ in range(8):
            mid = math.sqrt(lo * hi)
            if stable(mid):
                lo = mid
            else:
                hi = mid
        dt = lo
        setup_s = time.perf_counter() - t_setup

        wdofs = [int(x) for x in getattr(scene, "workpiece_dof", [])]
        free_dofs = np.setdiff1d(np.arange(m.nv), wdofs)
        res_free = RestResidual(scene, free_dofs)
        for _attempt in range(4):  # restarted with a smaller step if it diverges later on
            reset(dt)
            hs, hres, htip, hwall = [], [], [], []
            steps = 0
            t0 = time.perf_counter()
            if wdofs:  # hold the workpiece (weight carried, heavily damped) until the finger presses on it
                c0 = m.dof_damping[wdofs].copy()
                for name, dof in zip(scene.workpiece_joints, scene.workpiece_dof):
                    if name == "z":
                        d.qfrc_applied[dof] = scene.workpiece_mass * scene.physical.g
                m.dof_damping[wdofs] = 1e9 * max(1.0, float(np.max(M)))
                while steps < max_steps // 2 and time.perf_counter() - t0 < 0.5 * time_budget_s:
                    mujoco.mj_step(m, d, check_every)
                    steps += check_every
                    if invalid_state(d) is not None or res_free(d.qpos) < HOLD_TOL:
                        break
                m.dof_damping[wdofs] = c0
                d.qfrc_applied[:] = 0.0
                d.qvel[wdofs] = 0.0
            res = res_fn(d.qpos)
            hit = None  # (steps, wall) of the first entry into the tip band
            s_tol = None
            diverged = False
            while steps < max_steps and time.perf_counter() - t0 < time_budget_s:
                mujoco.mj_step(m, d, check_every)
                steps += check_every
                if invalid_state(d) is not None:
                    diverged = True
                    break
                wall = time.perf_counter() - t0
                res = res_fn(d.qpos)
                hs.append(steps)
                hres.append(res)
                hwall.append(wall)
                if res < tol and s_tol is None:
                    s_tol = (steps, wall)
                done_match = True
                if want_match:
                    dtip = float(np.linalg.norm(finger_tip(scene) - target_tip))
                    htip.append(dtip)
                    if dtip <= tip_tol:
                        if hit is None:
                            hit = (steps, wall)
                    else:
                        hit = None
                    done_match = hit is not None and steps >= 1.25 * hit[0]
                if s_tol is not None and done_match:
                    break
            wall = time.perf_counter() - t0
            if not diverged:
                break
            dt *= 0.7
        else:
            return {"steps": steps, "dt": dt, "setup_s": setup_s, "omega_max": wmax, "omega_min": wmin,
                    "converged": False, "matched": False, "steps_to_tol": None, "time_to_tol_s": math.inf,
                    "tol_extrapolated": False, "steps_to_match": None, "time_to_match_s": math.inf,
                    "match_extrapolated": False, "residual": math.nan, "measured_s": wall, "note": "diverged",
                    "diverged": True}
        rate = wall / max(steps, 1)
        lost = False
        if wdofs:
            d2 = res_fn.d
            res_fn(d.qpos)
            wr = np.abs((d2.qfrc_smooth + d2.qfrc_constraint) / res_fn.scale)[wdofs]
            lost = bool(np.max(wr) > 0.5 * scene.workpiece_mass * scene.physical.g / scene.force_scale)
        if lost:
            return {"steps": steps, "dt": dt, "setup_s": setup_s, "omega_max": wmax, "omega_min": wmin,
                    "converged": False, "matched": False, "steps_to_tol": None, "time_to_tol_s": math.inf,
                    "tol_extrapolated": False, "steps_to_match": None, "time_to_match_s": math.inf,
                    "match_extrapolated": False, "residual": res, "measured_s": wall,
                    "note": f"workpiece slid off after {steps} steps (MuJoCo's soft friction): no static state",
                    "workpiece_lost": True}
        out = {"steps": steps, "dt": dt, "setup_s": setup_s, "omega_max": wmax, "omega_min": wmin,
               "residual": res, "measured_s": wall, "note": ""}
        notes = []
        ok, n_at, t_at, est = _reached(s_tol, hs, hres, tol, rate)
        out.update(converged=ok, steps_to_tol=n_at, time_to_tol_s=t_at, tol_extrapolated=est)
        if not ok:
            notes.append(f"residual {res:.1e} after {steps} steps" + (": extrapolated" if n_at else ": no useful decay"))
        if want_match:
            ok, n_at, t_at, est = _reached(hit, hs, htip, tip_tol, rate)
            out.update(matched=ok, steps_to_match=n_at, time_to_match_s=t_at, match_extrapolated=est)
            if not ok:
                notes.append(f"tip {htip[-1] if htip else math.nan:.1e} from the chain's"
                             + (": extrapolated" if n_at else ": no useful decay"))
        else:
            out.update(matched=None, steps_to_match=None, time_to_match_s=None, match_extrapolated=False)
        out["note"] = "; ".join(notes)
        return out
    finally:
        m.opt.timestep, m.dof_damping[:], m.dof_armature[:], m.pair_solref[:] = (
            saved[0], saved[1], saved[2], saved[3])


def _reached(hit, steps, values, tol, rate) -> tuple[bool, float | None, float, bool]:
    """``(reached, steps, time [s], extrapolated)`` of a quantity's first fall below ``tol``.

    ``hit`` is ``(steps, time)`` where the run saw it, else None: then the steps
    are extrapolated from the history ``(steps, values)`` (None when it does not
    decay usefully) and the time is ``rate`` [s/step] times them (inf without).
    """
    if hit is not None:
        return True, hit[0], hit[1], False
    est = _extrapolate(steps, values, tol)
    return False, est, (rate * est if est else math.inf), est is not None


def _extrapolate(steps, res, tol) -> float | None:
    """Steps to reach ``tol`` from an exponential fit of the residual's envelope (second half)."""
    if len(steps) < 8:
        return None
    s = np.asarray(steps, float)
    r = np.log(np.maximum(np.asarray(res, float), 1e-300))
    half = len(s) // 2
    # envelope: running maximum from the right smooths the oscillation of light damping
    env = np.maximum.accumulate(r[half:][::-1])[::-1]
    slope, icpt = np.polyfit(s[half:], env, 1)
    if not slope < 0:
        return None
    est = max(float(s[-1]), (math.log(tol) - icpt) / slope)
    return est if est < min(1e12, 1e4 * s[-1]) else None

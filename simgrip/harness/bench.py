"""``simgrip bench``: run time against error, what skipping buys, and the sweep timing.

What is measured
----------------
For the free rod and Grips I, II and III at the paper's standard parameters
(``D = 1, M = 5, mu_s = 1, b/l = 0.6, gamma/l = 0.8``) and the curvatures of
:data:`STANDARD_CASES`, over ``n`` links (:data:`N_FULL`, or :data:`N_QUICK`
with ``quick=True``), four methods side by side:

``settle``
    :func:`simgrip.settle.settle` on a freshly built scene (the time includes
    :func:`simgrip.sim.scene.build_scene`; ``build_s`` gives that part alone).
``naive``
    A plain MuJoCo relaxation of the *same* chain (:func:`naive_relax`):
    physical inertia, light stiffness-proportional damping (ratio
    :data:`NAIVE_DAMPING_RATIO` at the lowest mode), the largest stable time
    step found by bisection, the same static-residual tolerance as ``settle``.
    It is given a head start (:func:`_start_state`: Grips I/II from the chain's
    equilibrium at 80 % of the curvature with the workpiece at the tip, Grip
    III from the built state; the workpiece is held until the finger presses
    on it, then released).  Its time is the time to **matched error**: the tip
    within :data:`MATCH_FRACTION` of the discretisation error of the chain's
    exact equilibrium.  It is compared with the settle's own time (settle only,
    closing included, ``settle_same_start_s``).  When the budget (a
    deterministic step count) runs out first, the decay of the tip distance is
    fitted and the time is **extrapolated** (flagged); when the workpiece slides
    off (MuJoCo's soft friction creeps) there is no static state: ``inf``.
``minimiser``
    :func:`simgrip.reference.discrete.solve_chain`, Newton on the hinge chain's energy:
    the exact limit of this discretisation.
``bvp``
    :func:`simgrip.reference.elastica.solve` of the same state (same contact couple and,
    for Grip III, the simulation's own contact arc length), cold start.  Per
    grip it is also timed at the tolerances :data:`BVP_TOLS` (rows with
    ``n = 0``), which gives its own error-vs-time curve.

Errors are against the converged BVP (``tol = 1e-10``) of the same state:
``tip_err = |r_tip - r_tip,BVP|`` and ``force_err = |F - F_BVP|`` (contact
force on the rod over ``rho g l``; none for the free rod).  ``settle_vs_min_*``
are the differences between the settle and the minimiser at the same ``n``
(how well MuJoCo reaches the chain's equilibrium).

Ratios "at matched error": settle and naive and minimiser at the same ``n``
converge to the same chain state (checked: ``settle_vs_min`` is tiny), so
their ratio is taken at equal ``n``; for the BVP, the cheapest tolerance whose
error is at most the settle's error at that ``n``.

Every task (one grip and one ``n``) is independent and deterministic, so the
errors written do not depend on ``jobs``; wall times do (concurrent processes
share cores), and ``jobs`` is written next to them.

Files written (atomically) to ``out_dir``: ``bench.csv``, ``bench.json``,
``pareto.png``, ``summary.md``, ``skips.md``, ``sweep.json``.

Command line (to be wired in :mod:`simgrip.cli`)::

    simgrip bench [--quick] [--out DIR] [--jobs N] [--repeats R]

see :func:`add_arguments` and :func:`cli_bench`.
"""

from __future__ import annotations

import csv
import io as _io
import math
import os
import statistics
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from simgrip.io import atomic_write, write_json
from simgrip.params import STANDARD, DimensionlessParams
from simgrip.profiles import Uniform
from simgrip.threads import _openblas_libs, blas_threads  # noqa: F401 - re-exported

__all__ = [
    "STANDARD_CASES",
    "N_FULL",
    "N_QUICK",
    "BVP_TOLS",
    "BenchResult",
    "run_bench",
    "naive_relax",
    "add_arguments",
    "cli_bench",
]

#: Curvature of each grip's standard case (feasible at the standard parameters).
STANDARD_CASES = {"free": -4.0, "I": -6.0, "II": 6.0, "III": -4.0}
#: Links per finger in the full and the quick bench.
N_FULL = (8, 16, 32, 64, 128, 256)
N_QUICK = (8, 16, 32)
#: Tolerances of the BVP's own error-vs-time curve; the last one is the reference.
BVP_TOLS = (1e-3, 1e-4, 1e-6, 1e-8, 1e-10)
REF_TOL = 1e-10
#: Damping ratio of the naive relaxation at its lowest mode.
NAIVE_DAMPING_RATIO = 0.05
#: Matched error: the naive run counts as done when its tip is within this
#: fraction of the discretisation error of the chain's exact equilibrium.
MATCH_FRACTION = 0.01
#: The naive run holds the workpiece until the finger's residual is below this.
HOLD_TOL = 1e-3
#: Columns of ``bench.csv``.
COLUMNS = (
    "grip", "kappa", "n", "method", "tol", "time_s", "time_min_s", "repeats", "steps", "converged",
    "matched", "extrapolated", "tip_err", "force_err", "settle_vs_min_tip", "settle_vs_min_force", "gamma",
    "contact_moment", "residual", "build_s", "settle_same_start_s", "dt", "time_to_tol_s", "steps_to_tol", "note",
)


# ---------------------------------------------------------------------------
# helpers


def _median_time(fn, repeats: int):
    """Run ``fn`` ``repeats`` times; return (last result, median seconds, min seconds)."""
    times = []
    out = None
    for _ in range(max(1, repeats)):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times), min(times)


def _force(obj) -> np.ndarray:
    return np.array([float(obj.N1), float(obj.N2)])


def _errors(grip, tip, force, ref) -> tuple[float, float | None]:
    tip_err = float(np.linalg.norm(np.asarray(tip, float) - ref.tip))
    if grip == "free":
        return tip_err, None
    return tip_err, float(np.linalg.norm(np.asarray(force, float) - _force(ref)))


def _full_mass(m, d) -> np.ndarray:
    import mujoco

    M = np.zeros((m.nv, m.nv))
    if hasattr(d, "qM"):
        mujoco.mj_fullM(m, M, d.qM)
    else:  # MuJoCo >= 4
        mujoco.mj_fullM(m, d, M)
    return M


def _dof_scales(scene) -> np.ndarray:
    """Per-dof scale of :func:`simgrip.settle.static_residual`: rho g l^2 (hinges), rho g l (slides)."""
    import mujoco

    m = scene.model
    sc = np.full(m.nv, scene.moment_scale)
    for j in range(m.njnt):
        if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE:
            sc[m.jnt_dofadr[j]] = scene.force_scale
    return sc


class _Residual:
    """The static residual (``qfrc_smooth + qfrc_constraint`` at rest), on scratch data.

    Same scaling as :func:`simgrip.settle.static_residual`; ``dofs`` restricts the max.
    """

    def __init__(self, scene, dofs=None):
        import mujoco

        self.m = scene.model
        self.d = mujoco.MjData(self.m)
        self.scale = _dof_scales(scene)
        self.dofs = None if dofs is None else np.asarray(dofs, int)

    def __call__(self, qpos) -> float:
        import mujoco

        d = self.d
        d.qpos[:] = qpos
        d.qvel[:] = 0.0
        d.qfrc_applied[:] = 0.0
        mujoco.mj_forward(self.m, d)
        r = (d.qfrc_smooth + d.qfrc_constraint) / self.scale
        return float(np.max(np.abs(r if self.dofs is None else r[self.dofs])))


# ---------------------------------------------------------------------------
# the naive relaxation


def _diverged(d) -> bool:
    if not (np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.qvel))):
        return True
    return any(d.warning[i].number > 0 for i in range(len(d.warning)))


def _clear_warnings(d) -> None:
    for i in range(len(d.warning)):
        d.warning[i].number = 0


def _tip_of(scene) -> np.ndarray:
    """Finger 0's tip (over l) from its joint angles."""
    q = np.asarray(scene.data.qpos[scene.joint_qpos[0]], float)
    phi = np.cumsum(q)
    return np.array([np.sum(np.cos(phi)), np.sum(np.sin(phi))]) / scene.n


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
    import mujoco

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
        M = _full_mass(m, d)
        idx = np.flatnonzero(sprung)
        w2 = np.linalg.eigvals(np.linalg.solve(M[np.ix_(idx, idx)], np.diag(stiff[idx]))).real
        w2 = w2[w2 > 1e-12]
        wmax, wmin = math.sqrt(w2.max()), math.sqrt(w2.min())
        m.dof_damping[:] = 2.0 * damping_ratio / wmin * np.where(sprung, stiff, 0.0)
        res_fn = _Residual(scene)

        def reset(dt):
            m.opt.timestep = dt
            m.pair_solref[:] = [2.0 * dt, 1.0]
            d.qpos[:] = q0
            d.qvel[:] = 0.0
            d.qfrc_applied[:] = 0.0
            _clear_warnings(d)
            mujoco.mj_forward(m, d)

        def stable(dt) -> bool:
            reset(dt)
            r0 = res_fn(d.qpos)
            for _ in range(max(1, trial_steps // 50)):
                mujoco.mj_step(m, d, 50)
                if _diverged(d):
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
        res_free = _Residual(scene, free_dofs)
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
                    if _diverged(d) or res_free(d.qpos) < HOLD_TOL:
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
                if _diverged(d):
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
                    dtip = float(np.linalg.norm(_tip_of(scene) - target_tip))
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
                    "match_extrapolated": False, "residual": math.nan, "measured_s": wall, "note": "diverged"}
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
                    "note": f"workpiece slid off after {steps} steps (MuJoCo's soft friction): no static state"}
        out = {"steps": steps, "dt": dt, "setup_s": setup_s, "omega_max": wmax, "omega_min": wmin,
               "residual": res, "measured_s": wall, "note": ""}
        notes = []
        if s_tol is not None:
            out.update(converged=True, steps_to_tol=s_tol[0], time_to_tol_s=s_tol[1], tol_extrapolated=False)
        else:
            est = _extrapolate(hs, hres, tol)
            out.update(converged=False, steps_to_tol=est, time_to_tol_s=(rate * est if est else math.inf),
                       tol_extrapolated=est is not None)
            notes.append(f"residual {res:.1e} after {steps} steps" + (": extrapolated" if est else ": no useful decay"))
        if want_match:
            if hit is not None:
                out.update(matched=True, steps_to_match=hit[0], time_to_match_s=hit[1], match_extrapolated=False)
            else:
                est = _extrapolate(hs, htip, tip_tol)
                out.update(matched=False, steps_to_match=est, time_to_match_s=(rate * est if est else math.inf),
                           match_extrapolated=est is not None)
                notes.append(f"tip {htip[-1] if htip else math.nan:.1e} from the chain's"
                             + (": extrapolated" if est else ": no useful decay"))
        else:
            out.update(matched=None, steps_to_match=None, time_to_match_s=None, match_extrapolated=False)
        out["note"] = "; ".join(notes)
        return out
    finally:
        m.opt.timestep, m.dof_damping[:], m.dof_armature[:], m.pair_solref[:] = (
            saved[0], saved[1], saved[2], saved[3])


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


# ---------------------------------------------------------------------------
# one task: a grip at one n


def _reference(grip, params, prof, *, gamma=None, contact_moment=0.0, tol=REF_TOL, guess=None):
    from simgrip.reference import elastica

    kw = {"contact_moment": contact_moment, "tol": tol}
    if grip == "III":
        kw["gamma"] = gamma
    return elastica.solve(grip, params, prof, guess=guess, **kw)


def _chain(grip, params, prof, n, *, gamma=None, contact_moment=0.0, guess=None):
    """The hinge chain's exact equilibrium with the same contact couple as the simulation.

    :func:`simgrip.reference.discrete.solve_chain` takes the couple only for Grip III; for
    Grips I/II a tip couple ``C`` adds ``-C phi_last = -C sum q_j`` to the
    energy, which is the same as shifting every rest angle by ``C / (D k_j)``.
    """
    from simgrip.chain import ChainSprings, chain_springs
    from simgrip.reference.discrete import solve_chain

    if grip in ("I", "II") and contact_moment:
        sp = chain_springs(prof, n)
        sp = ChainSprings(n=sp.n, ds=sp.ds, stiffness=sp.stiffness,
                          rest=sp.rest + contact_moment / (params.D * sp.stiffness), nodes=sp.nodes)
        return solve_chain(grip, params, prof, n, springs=sp, guess=guess)
    return solve_chain(grip, params, prof, n, gamma=gamma, contact_moment=contact_moment, guess=guess)


def _naive_budget(budget: float, n: int) -> dict:
    """Deterministic step budget of a naive run: ``budget * 2e5 / n`` steps (about ``budget``
    seconds of MuJoCo stepping), with a wall-clock guard at 5x (only a pathological run hits it)."""
    return {"max_steps": max(2000, int(budget * 2e5 / n)), "time_budget_s": 5.0 * budget + 5.0}


def _start_state(scene, grip, params, prof, n, C):
    """Common start of ``naive`` and ``settle(close=False)``.

    Grips I/II: the chain's equilibrium at 80 % of the curvature (tip on the
    face), the workpiece centred at the tip height; III: the built state (the
    chain's equilibrium with the corner at ``gamma``); free: straight.
    """
    import mujoco

    from simgrip.reference.discrete import solve_chain
    from simgrip.sim.scene import set_joint_angles

    if grip in ("I", "II"):
        q = _chain(grip, params, prof.scaled(0.8), n, contact_moment=C).joint_angles
        set_joint_angles(scene, q)
        m, d = scene.model, scene.data
        tipz = float(np.cumsum(np.sin(np.cumsum(q)))[-1] / n) * scene.length
        body_z = float(m.body_pos[scene.workpiece_body][2])
        for name, qa in zip(scene.workpiece_joints, scene.workpiece_qpos):
            d.qpos[qa] = tipz - body_z if name == "z" else 0.0
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
    return scene.data.qpos.copy()


def _bench_task(grip: str, n: int, repeats: int, naive_budget_s: float, params: DimensionlessParams) -> list[dict]:
    from simgrip.reference.discrete import solve_chain
    from simgrip.sim.scene import DEFAULT_R_TIP, build_scene
    from simgrip.settle import DEFAULT_TOL, SettleError, settle

    kappa = STANDARD_CASES[grip]
    prof = Uniform(kappa)
    tol = DEFAULT_TOL
    rows = []
    base = {"grip": grip, "kappa": kappa, "n": n, "tol": tol}

    if n == 0:  # the BVP's own error-vs-time curve at the nominal state
        C = DEFAULT_R_TIP * params.M if grip in ("I", "II") else 0.0
        ref = _reference(grip, params, prof, gamma=params.gamma, contact_moment=C)
        for btol in BVP_TOLS:
            sol, tmed, tmin = _median_time(
                lambda: _reference(grip, params, prof, gamma=params.gamma, contact_moment=C, tol=btol), repeats)
            te, fe = _errors(grip, sol.tip, _force(sol), ref)
            rows.append({**base, "method": "bvp", "tol": btol, "time_s": tmed, "time_min_s": tmin,
                         "repeats": repeats, "steps": sol.mesh_size, "converged": True, "tip_err": te,
                         "force_err": fe, "gamma": sol.gamma, "contact_moment": C,
                         "residual": sol.residual, "note": "reference" if btol == REF_TOL else ""})
        return rows

    # -- settle (end to end: build + settle) --------------------------------
    settle_only = []

    def run_settle():
        t0 = time.perf_counter()
        sc = build_scene(grip, params, prof, n)
        tb = time.perf_counter() - t0
        t1 = time.perf_counter()
        out = settle(sc, tol=tol)
        settle_only.append(time.perf_counter() - t1)
        return sc, out, tb

    st = None
    try:
        (scene, st, build_s), t_settle, t_settle_min = _median_time(run_settle, repeats)
    except (SettleError, ValueError) as exc:
        rows.append({**base, "method": "settle", "converged": False, "note": f"{type(exc).__name__}: {exc}"})
    if grip == "free":
        gam, C = None, 0.0
    elif st is not None and st.contact is not None:
        gam, C = (st.gamma_sim if grip == "III" else None), st.contact_moment
    else:
        gam, C = (params.gamma if grip == "III" else None), (DEFAULT_R_TIP * params.M if grip != "III" else 0.0)
    ref, t_bvp, t_bvp_min = _median_time(
        lambda: _reference(grip, params, prof, gamma=gam, contact_moment=C), repeats)
    chain, t_min, t_min_min = _median_time(
        lambda: _chain(grip, params, prof, n, gamma=gam, contact_moment=C), repeats)
    min_te, min_fe = _errors(grip, chain.tip, _force(chain), ref)
    extra = {"gamma": gam, "contact_moment": C}
    if st is not None:
        te, fe = _errors(grip, st.tip[0], _force(st), ref)
        dmt, dmf = _errors(grip, st.tip[0], _force(st), chain)
        rows.append({**base, **extra, "method": "settle", "time_s": t_settle, "time_min_s": t_settle_min,
                     "repeats": repeats, "steps": int(st.steps), "converged": bool(st.converged),
                     "tip_err": te, "force_err": fe, "settle_vs_min_tip": dmt, "settle_vs_min_force": dmf,
                     "residual": st.residual, "build_s": build_s,
                     "note": "" if (st.held or grip == "free") else "workpiece dropped"})
    # -- settle, method="dynamics" (over-damped MuJoCo dynamics, MuJoCo's own friction) --
    def run_dyn():
        return settle(build_scene(grip, params, prof, n), method="dynamics")

    try:
        sd, t_dyn, t_dyn_min = _median_time(run_dyn, repeats)
        te, fe = _errors(grip, sd.tip[0], _force(sd), ref)
        dmt, dmf = _errors(grip, sd.tip[0], _force(sd), chain)
        rows.append({**base, **extra, "method": "settle_dynamics", "tol": None, "time_s": t_dyn,
                     "time_min_s": t_dyn_min, "repeats": repeats, "steps": int(sd.steps),
                     "converged": bool(sd.converged), "tip_err": te, "force_err": fe,
                     "settle_vs_min_tip": dmt, "settle_vs_min_force": dmf, "residual": sd.residual,
                     "note": "" if (sd.held or grip == "free") else "workpiece dropped"})
    except (SettleError, ValueError) as exc:
        rows.append({**base, **extra, "method": "settle_dynamics", "converged": False,
                     "note": f"{type(exc).__name__}: {exc}"})
    rows.append({**base, **extra, "method": "minimiser", "tol": None, "time_s": t_min, "time_min_s": t_min_min,
                 "repeats": repeats, "steps": int(chain.iterations), "converged": bool(chain.success),
                 "tip_err": min_te, "force_err": min_fe, "residual": chain.gradient_norm})
    rows.append({**base, **extra, "method": "bvp", "tol": REF_TOL, "time_s": t_bvp, "time_min_s": t_bvp_min,
                 "repeats": repeats, "steps": ref.mesh_size, "converged": True, "tip_err": 0.0,
                 "force_err": None if grip == "free" else 0.0, "residual": ref.residual, "note": "reference"})

    # -- naive (head start: see _start_state) vs the settle's own time --------
    try:
        scene = build_scene(grip, params, prof, n)
        q0 = _start_state(scene, grip, params, prof, n, C)

        t_same = statistics.median(settle_only) if settle_only else None
        scene.data.qpos[:] = q0
        band = MATCH_FRACTION * min_te
        nv = naive_relax(scene, tol=tol, target_tip=chain.tip, tip_tol=band, **_naive_budget(naive_budget_s, n))
        # the naive answer at the end of its run (within the band when matched)
        nte, _ = _errors(grip, _tip_of(scene), np.zeros(2), ref)
        rows.append({**base, **extra, "method": "naive", "time_s": nv["time_to_match_s"],
                     "time_min_s": nv["measured_s"], "repeats": 1, "steps": nv["steps_to_match"],
                     "converged": bool(nv["converged"]), "matched": bool(nv["matched"]),
                     "extrapolated": bool(nv["match_extrapolated"]),
                     "tip_err": nte if nv["matched"] else min_te, "force_err": None if grip == "free" else min_fe,
                     "residual": nv["residual"], "settle_same_start_s": t_same, "dt": nv["dt"],
                     "time_to_tol_s": nv["time_to_tol_s"], "steps_to_tol": nv["steps_to_tol"],
                     "note": nv["note"]})
    except (SettleError, ValueError) as exc:
        rows.append({**base, **extra, "method": "naive", "converged": False, "note": f"{type(exc).__name__}: {exc}"})
    return rows


# ---------------------------------------------------------------------------
# the Fig. 7 sweep and the skipping table


def _sweep_task(n: int, kappas: tuple, params: DimensionlessParams) -> dict:
    """Fig. 7 (Grip I) by simulation with warm starts, cold, and by the BVP."""
    from simgrip.reference import elastica
    from simgrip.sim.scene import build_scene
    from simgrip.settle import settle, settle_sweep

    profs = [Uniform(k) for k in kappas]
    t0 = time.perf_counter()
    scene = build_scene("I", params, profs[0], n)
    warm = settle_sweep(scene, profs)
    t_warm = time.perf_counter() - t0
    t0 = time.perf_counter()
    cold = []
    for p in profs:
        cold.append(settle(build_scene("I", params, p, n)))
    t_cold = time.perf_counter() - t0
    t0 = time.perf_counter()
    bvp = elastica.kappa_sweep("I", params, list(kappas))
    t_bvp = time.perf_counter() - t0
    held = [bool(w.held) for w in warm]
    dN_warm_cold = max((abs(w.N1 - c.N1) for w, c in zip(warm, cold) if w.held and c.held), default=0.0)
    dtip_warm_cold = max(float(np.linalg.norm(w.tip[0] - c.tip[0])) for w, c in zip(warm, cold))
    dN_bvp = max((abs(w.N1 - b.N1) for w, b in zip(warm, bvp) if w.held), default=None)
    chains = [_chain("I", params, p, n, contact_moment=w.contact_moment) for p, w in zip(profs, warm)]
    dN_chain = max((abs(w.N1 - c.N1) for w, c in zip(warm, chains) if w.held), default=None)
    return {
        "grip": "I", "n": n, "kappas": list(kappas), "time_warm_s": t_warm, "time_cold_s": t_cold,
        "time_bvp_s": t_bvp, "held": held, "held_bvp_feasible": [bool(b.feasible) for b in bvp],
        "N_sim": [w.N1 if w.held else None for w in warm], "N_bvp": [b.N1 for b in bvp],
        "max_dN_warm_vs_cold": dN_warm_cold, "max_dtip_warm_vs_cold": dtip_warm_cold,
        "max_dN_sim_vs_bvp": dN_bvp, "max_dN_sim_vs_chain": dN_chain,
        "steps_warm": int(sum(w.steps for w in warm)), "steps_cold": int(sum(c.steps for c in cold)),
    }


def _broad_collision(scene) -> None:
    """Undo collision filtering: every geom collides with every geom (MuJoCo's default)."""
    m = scene.model
    m.geom_contype[:] = 1
    m.geom_conaffinity[:] = 1


def _contact_on(scene) -> None:
    import mujoco

    scene.model.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_CONTACT)


def _timed_settle(make, repeats, **kw):
    from simgrip.settle import settle

    def go():
        sc = make()
        return sc, settle(sc, **kw)

    (sc, st), t, _ = _median_time(go, repeats)
    return sc, st, t


def _answer(st) -> np.ndarray:
    return np.concatenate([np.asarray(st.tip[0], float), _force(st)])


def _skip_task(which: str, n: int, repeats: int, params: DimensionlessParams, naive_budget_s: float) -> dict:
    """One row of the skipping table: time with the skip (simgrip's default) and without it."""
    from simgrip.sim.scene import build_scene

    k = STANDARD_CASES
    row = {"skip": which, "n": n}
    b = b_tip = None
    if which == "contact off (free rod)":
        mk = lambda: build_scene("free", params, Uniform(k["free"]), n)  # noqa: E731

        def mk_off():
            sc = mk()
            _contact_on(sc)
            _broad_collision(sc)
            return sc

        _, a, ta = _timed_settle(mk, repeats)
        _, b, tb = _timed_settle(mk_off, repeats)
        row.update(case=f"free, kappa={k['free']:g}", note="without: contact enabled, all geoms collide")
    elif which.startswith("collision filtering"):
        g = "III" if "III" in which else "I"
        mk = lambda: build_scene(g, params, Uniform(k[g]), n)  # noqa: E731

        def mk_off():
            sc = mk()
            _broad_collision(sc)
            return sc

        _, a, ta = _timed_settle(mk, repeats)
        _, b, tb = _timed_settle(mk_off, repeats)
        row.update(case=f"{g}, kappa={k[g]:g}", note="without: all geoms collide (contype = conaffinity = 1)")
    elif which.startswith("symmetric reduction"):
        g = "III" if "III" in which else "I"
        _, a, ta = _timed_settle(lambda: build_scene(g, params, Uniform(k[g]), n), repeats)
        _, b, tb = _timed_settle(lambda: build_scene(g, params, Uniform(k[g]), n, fingers=2), repeats)
        row.update(case=f"{g}, kappa={k[g]:g}", note="without: two fingers, workpiece free in x, z, rotation")
    elif which.startswith("inertia and damping") or which.startswith("all together"):
        from simgrip.reference.discrete import solve_chain
        from simgrip.sim.scene import DEFAULT_R_TIP
        from simgrip.settle import settle

        allt = which.startswith("all together")
        g = "free" if "free" in which else "I"
        prof = Uniform(k[g])
        C = DEFAULT_R_TIP * params.M if g != "free" else 0.0
        times = []

        def full():
            sc = build_scene(g, params, prof, n)
            t1 = time.perf_counter()
            out = settle(sc)
            times.append(time.perf_counter() - t1)
            return out

        a, _, _ = _median_time(full, repeats)
        ta = statistics.median(times)
        scene2 = build_scene(g, params, prof, n, fingers=2 if allt else 1)
        q2 = _start_state(scene2, g, params, prof, n, C)
        if allt:
            _broad_collision(scene2)
        scene2.data.qpos[:] = q2
        chain = _chain(g, params, prof, n, contact_moment=C)
        ref = _reference(g, params, prof, contact_moment=C)
        band = MATCH_FRACTION * float(np.linalg.norm(chain.tip - ref.tip))
        nv = naive_relax(scene2, tol=1e-10, target_tip=chain.tip, tip_tol=band, **_naive_budget(naive_budget_s, n))
        tb = nv["time_to_match_s"]
        b_tip = _tip_of(scene2) if nv["matched"] else None
        row.update(case=f"{g}, kappa={k[g]:g}, to matched error (naive: head start)", extrapolated=bool(nv["match_extrapolated"]),
                   note=("without: physical inertia, light damping, largest stable dt"
                         + (", two fingers, all geoms collide (warm starts: see the sweep row)" if allt else "")))
        row["diff_vs_minimiser_with"] = float(np.linalg.norm(a.tip[0] - chain.tip))
    elif which == "warm starts (Fig. 7 sweep)":
        raise ValueError("the warm-start row comes from the sweep task")
    else:
        raise ValueError(f"unknown skip {which!r}")
    row.update(time_with_s=ta, time_without_s=tb, speedup=(tb / ta if ta > 0 and tb is not None else None))
    if b_tip is not None:
        row.update(answer_change_tip=float(np.linalg.norm(np.asarray(a.tip[0]) - b_tip)), answer_change_force=None)
    elif b is not None:
        da = _answer(a) - _answer(b)
        row.update(answer_change_tip=float(np.linalg.norm(da[:2])), answer_change_force=float(np.linalg.norm(da[2:])))
    else:
        row.update(answer_change_tip=None, answer_change_force=None)
    return row


SKIPS = (
    "contact off (free rod)",
    "collision filtering (Grip I)",
    "collision filtering (Grip III)",
    "symmetric reduction (Grip I)",
    "symmetric reduction (Grip III)",
    "inertia and damping (free rod)",
    "inertia and damping (Grip I)",
    "all together (Grip I)",
)


# ---------------------------------------------------------------------------
# driver


@dataclass
class BenchResult:
    """What :func:`run_bench` measured.

    Attributes
    ----------
    rows : list of dict
        One row per (grip, n, method) (and per BVP tolerance, ``n = 0``); see :data:`COLUMNS`.
    ratios : list of dict
        Per grip and ``n``: settle / naive, settle / minimiser, settle / BVP at matched error.
    skips : list of dict
        The skipping table.
    sweep : dict
        The Fig. 7 sweep timing (simulation warm, cold, BVP).
    env : dict
        Gymnasium env throughput per grip (:func:`simgrip.envs.throughput.measure_throughput`).
    files : dict
        name -> path of every file written.
    jobs, quick, elapsed_s
    """

    rows: list
    ratios: list
    skips: list
    sweep: dict
    env: dict = field(default_factory=dict)
    files: dict = field(default_factory=dict)
    jobs: int = 1
    quick: bool = False
    elapsed_s: float = 0.0

    def select(self, **match) -> list[dict]:
        """Rows whose fields equal ``match`` (e.g. ``grip="I", method="settle"``)."""
        return [r for r in self.rows if all(r.get(k) == v for k, v in match.items())]


def _call(spec):
    """Run one task (single-threaded BLAS); an unexpected error becomes a recorded row."""
    with blas_threads(1):
        return _call_inner(spec)


def _call_inner(spec):
    kind, args = spec
    try:
        if kind == "case":
            return kind, args, _bench_task(*args)
        if kind == "sweep":
            return kind, args, _sweep_task(*args)
        return kind, args, _skip_task(*args)
    except Exception as exc:  # noqa: BLE001 - reported in the outputs
        err = f"{type(exc).__name__}: {exc}"
        if kind == "case":
            return kind, args, [{"grip": args[0], "kappa": STANDARD_CASES[args[0]], "n": args[1], "method": "settle",
                                 "converged": False, "note": err}]
        if kind == "sweep":
            return kind, args, {"error": err, "n": args[0], "kappas": list(args[1])}
        return kind, args, {"skip": args[0], "n": args[1], "error": err, "note": err}


def _ratios(rows) -> list[dict]:
    out = []
    by = {}
    for r in rows:
        by.setdefault((r["grip"], r["n"], r["method"]), []).append(r)
    order = ("free", "I", "II", "III")
    for (grip, n, method), rs in sorted(by.items(), key=lambda kv: (order.index(kv[0][0]), kv[0][1])):
        if method != "settle" or n == 0 or not rs[0].get("time_s"):
            continue
        s = rs[0]
        rec = {"grip": grip, "n": n, "settle_s": s["time_s"], "settle_tip_err": s.get("tip_err")}
        nv = by.get((grip, n, "naive"), [{}])[0]
        if nv.get("time_s") and nv.get("settle_same_start_s"):
            rec["settle_over_naive"] = nv["settle_same_start_s"] / nv["time_s"]
            rec["naive_extrapolated"] = bool(nv.get("extrapolated"))
            rec["naive_s"] = nv["time_s"]
            rec["settle_same_start_s"] = nv["settle_same_start_s"]
        mn = by.get((grip, n, "minimiser"), [{}])[0]
        if mn.get("time_s"):
            rec["settle_over_minimiser"] = s["time_s"] / mn["time_s"]
        curve = sorted((b for b in by.get((grip, 0, "bvp"), []) if b.get("tip_err") is not None),
                       key=lambda b: b["time_s"])
        target = s.get("tip_err")
        match = next((b for b in curve if b["tip_err"] <= target), None) if target is not None else None
        if match is None and curve:
            match = min(curve, key=lambda b: b["tip_err"])
        if match is not None:
            rec["settle_over_bvp"] = s["time_s"] / match["time_s"]
            rec["bvp_tol_matched"] = match["tol"]
        dy = by.get((grip, n, "settle_dynamics"), [{}])[0]
        if dy.get("time_s"):
            rec["dynamics_s"] = dy["time_s"]
            rec["dynamics_tip_err"] = dy.get("tip_err")
            if mn.get("time_s"):
                rec["dynamics_over_minimiser"] = dy["time_s"] / mn["time_s"]
            dmatch = next((b for b in curve if b["tip_err"] <= (dy.get("tip_err") or 0.0)), None)
            if dmatch is None and curve:
                dmatch = min(curve, key=lambda b: b["tip_err"])
            if dmatch is not None:
                rec["dynamics_over_bvp"] = dy["time_s"] / dmatch["time_s"]
            if nv.get("time_s"):
                rec["dynamics_over_naive"] = dy["time_s"] / nv["time_s"]
        out.append(rec)
    return out


def run_bench(
    out_dir,
    *,
    quick: bool = False,
    jobs: int | None = None,
    repeats: int | None = None,
    progress: bool = True,
    params: DimensionlessParams = STANDARD,
    naive_budget_s: float | None = None,
    grips=("free", "I", "II", "III"),
    skips: bool = True,
    sweep: bool = True,
) -> BenchResult:
    """Measure run time against error and write the bench files (see the module docstring).

    Parameters
    ----------
    out_dir : path
        Destination folder (created).
    quick : bool
        ``n`` in :data:`N_QUICK`, one repeat, short naive budgets, a 5-point
        sweep: under a minute.
    jobs : int, optional
        Worker processes (default ``os.cpu_count()``); 1 runs in this process.
    repeats : int, optional
        Timing repeats (median); default 1 quick, 3 full.
    progress : bool
        tqdm progress bar.
    naive_budget_s : float, optional
        Budget of each naive relaxation before extrapolation, as about that
        many seconds of stepping: a deterministic step count ``2e5 * budget / n``
        (default 0.5 quick, 10 full), so the results do not depend on ``jobs``.
    grips, skips, sweep
        What to run (all by default).
    """
    from tqdm import tqdm

    if jobs is not None and (isinstance(jobs, bool) or int(jobs) != jobs or int(jobs) < 1):
        raise ValueError(f"jobs must be a positive integer, got {jobs!r}")
    if repeats is not None and (isinstance(repeats, bool) or int(repeats) != repeats or int(repeats) < 1):
        raise ValueError(f"repeats must be a positive integer, got {repeats!r}")
    t_start = time.perf_counter()
    ns = N_QUICK if quick else N_FULL
    reps = int(repeats or (1 if quick else 3))
    budget = float(naive_budget_s if naive_budget_s is not None else (0.5 if quick else 10.0))
    n_skip = 16 if quick else 32
    kappas = tuple(float(x) for x in (np.linspace(-6.0, -4.8, 4) if quick else np.linspace(-6.0, 0.0, 13)))
    specs = [("case", (g, 0, reps, budget, params)) for g in grips]
    specs += [("case", (g, n, reps, budget, params)) for n in reversed(ns) for g in grips]
    if sweep:
        specs.append(("sweep", (n_skip, kappas, params)))
    if skips:
        specs += [("skip", (w, n_skip, reps, params, budget)) for w in SKIPS]
    workers = min(int(jobs or os.cpu_count() or 1), len(specs))
    results = {}
    with tqdm(total=len(specs), desc="bench", unit="task", disable=not progress) as bar:
        if workers <= 1:
            for i, sp in enumerate(specs):
                bar.set_postfix_str(f"{sp[0]} {sp[1][0]} {sp[1][1]}")
                results[i] = _call(sp)
                bar.update()
        else:
            with ProcessPoolExecutor(max_workers=workers) as pool:
                futs = {pool.submit(_call, sp): i for i, sp in enumerate(specs)}
                for fut in as_completed(futs):
                    results[futs[fut]] = fut.result()
                    sp = specs[futs[fut]]
                    bar.set_postfix_str(f"{sp[0]} {sp[1][0]} {sp[1][1]}")
                    bar.update()
    rows, skip_rows, sweep_rec = [], [], {}
    for i in range(len(specs)):  # the order of ``specs``: independent of jobs
        kind, _, res = results[i]
        if kind == "case":
            rows.extend(res)
        elif kind == "sweep":
            sweep_rec = res
        else:
            skip_rows.append(res)
    rows.sort(key=lambda r: (("free", "I", "II", "III").index(r["grip"]), r["n"], r["method"], -(r.get("tol") or 0)))
    for r in rows:
        for c in COLUMNS:
            r.setdefault(c, None)
    if sweep_rec and "error" not in sweep_rec:
        skip_rows.append({
            "skip": "warm starts (Fig. 7 sweep)", "n": sweep_rec["n"], "case": f"I, {len(kappas)} curvatures",
            "time_with_s": sweep_rec["time_warm_s"], "time_without_s": sweep_rec["time_cold_s"],
            "speedup": sweep_rec["time_cold_s"] / sweep_rec["time_warm_s"],
            "answer_change_tip": sweep_rec["max_dtip_warm_vs_cold"],
            "answer_change_force": sweep_rec["max_dN_warm_vs_cold"], "note": "without: each curvature settled from scratch",
        })
    from simgrip.envs.throughput import measure_throughput  # issue 4: env overhead over raw mj_step

    env = {grip: measure_throughput(steps=300 if quick else 2000, grip=grip, repeats=1 if quick else 3)
           for grip in ("I", "III")}
    result = BenchResult(rows=rows, ratios=_ratios(rows), skips=skip_rows, sweep=sweep_rec, env=env,
                         jobs=workers, quick=bool(quick), elapsed_s=time.perf_counter() - t_start)
    result.files = _write(Path(out_dir), result)
    return result


# ---------------------------------------------------------------------------
# output


def _fmt(v, spec=".3g"):
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        if math.isinf(v):
            return "∞"
        return format(v, spec)
    return str(v)


def _write(out: Path, res: BenchResult) -> dict:
    out.mkdir(parents=True, exist_ok=True)
    files = {}
    buf = _io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(COLUMNS), extrasaction="ignore", lineterminator="\n")
    w.writeheader()
    for r in res.rows:
        w.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in COLUMNS})
    with atomic_write(out / "bench.csv") as fh:
        fh.write(buf.getvalue())
    files["bench.csv"] = out / "bench.csv"
    meta = {"quick": res.quick, "jobs": res.jobs, "elapsed_s": res.elapsed_s, "params": vars(STANDARD),
            "standard_cases": STANDARD_CASES, "cpu_count": os.cpu_count(), "load_avg": _loadavg()}
    write_json(out / "bench.json", {"meta": meta, "rows": res.rows, "ratios": res.ratios, "env": res.env})
    files["bench.json"] = out / "bench.json"
    write_json(out / "sweep.json", res.sweep)
    files["sweep.json"] = out / "sweep.json"
    with atomic_write(out / "skips.md") as fh:
        fh.write(_skips_md(res))
    files["skips.md"] = out / "skips.md"
    with atomic_write(out / "summary.md") as fh:
        fh.write(_summary_md(res))
    files["summary.md"] = out / "summary.md"
    _pareto(res, out / "pareto.png")
    files["pareto.png"] = out / "pareto.png"
    return files


def _loadavg():
    try:
        return list(os.getloadavg())
    except OSError:  # pragma: no cover
        return None


def _skips_md(res: BenchResult) -> str:
    lines = [
        "| skip | case | n | with (s) | without (s) | speedup | answer change: tip | force | without means |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for s in res.skips:
        if s.get("error"):
            lines.append(f"| {s['skip']} | – | {s['n']} | – | – | – | – | – | failed: {s['error']} |")
            continue
        sp = s.get("speedup")
        lines.append(
            f"| {s['skip']} | {s.get('case', '')} | {s['n']} | {_fmt(s.get('time_with_s'))} | "
            f"{_fmt(s.get('time_without_s'))}{' (extrap.)' if s.get('extrapolated') else ''} | "
            f"{_fmt(sp, '.3g') + '×' if sp is not None else '–'} | {_fmt(s.get('answer_change_tip'), '.1e')} | "
            f"{_fmt(s.get('answer_change_force'), '.1e')} | {s.get('note', '')} |"
        )
    return "\n".join(lines) + "\n"


def _summary_md(res: BenchResult) -> str:
    L = [f"# simgrip bench{' (quick)' if res.quick else ''}", ""]
    L.append(f"jobs = {res.jobs}, {os.cpu_count()} cores, load average {_loadavg()}, {res.elapsed_s:.0f} s in all. "
             "Timings are medians; errors are against the converged BVP (tol 1e-10) of the same state.")
    L.append("")
    L.append("## Ratios at matched error (time of settle / time of the other method; < 1: settle is faster)")
    L.append("")
    L.append("| grip | n | settle (s) | tip error | settle / naive | settle / minimiser | settle / BVP (tol) |")
    L.append("|---|---|---|---|---|---|---|")
    for r in res.ratios:
        nv = _fmt(r.get("settle_over_naive"))
        if r.get("naive_s") is not None and math.isinf(r["naive_s"]):
            nv = "0 (naive: no static state)"
        elif r.get("naive_extrapolated"):
            nv += " (naive extrap.)"
        bv = _fmt(r.get("settle_over_bvp"))
        if r.get("bvp_tol_matched") is not None:
            bv += f" ({r['bvp_tol_matched']:.0e})"
        L.append(f"| {r['grip']} | {r['n']} | {_fmt(r['settle_s'])} | {_fmt(r.get('settle_tip_err'), '.2e')} | {nv} | "
                 f"{_fmt(r.get('settle_over_minimiser'))} | {bv} |")
    L.append("")
    L.append("## settle(method=\"dynamics\"): over-damped MuJoCo dynamics with MuJoCo's own friction")
    L.append("")
    L.append("| grip | n | dynamics (s) | tip error | dynamics / naive | dynamics / minimiser | dynamics / BVP |")
    L.append("|---|---|---|---|---|---|---|")
    for r in res.ratios:
        if r.get("dynamics_s") is None:
            continue
        L.append(f"| {r['grip']} | {r['n']} | {_fmt(r['dynamics_s'])} | {_fmt(r.get('dynamics_tip_err'), '.2e')} | "
                 f"{_fmt(r.get('dynamics_over_naive'))} | {_fmt(r.get('dynamics_over_minimiser'))} | "
                 f"{_fmt(r.get('dynamics_over_bvp'))} |")
    L.append("")
    L.append("## Errors and times")
    L.append("")
    L.append("| grip | n | method | time (s) | steps | tip error | force error | note |")
    L.append("|---|---|---|---|---|---|---|---|")
    for r in res.rows:
        L.append(f"| {r['grip']} | {r['n'] or '–'} | {r['method']}{'' if r['n'] else ' tol ' + format(r['tol'], '.0e')} | "
                 f"{_fmt(r.get('time_s'))} | {_fmt(r.get('steps'))} | {_fmt(r.get('tip_err'), '.2e')} | "
                 f"{_fmt(r.get('force_err'), '.2e')} | {r.get('note') or ''} |")
    if res.sweep and "error" in res.sweep:
        L += ["", f"## Fig. 7 sweep: failed ({res.sweep['error']})"]
    elif res.sweep:
        s = res.sweep
        L += ["", f"## Fig. 7 sweep (Grip I, {len(s['kappas'])} curvatures, n = {s['n']})", "",
              f"simulation with warm starts {s['time_warm_s']:.3g} s, cold {s['time_cold_s']:.3g} s, "
              f"BVP sweep {s['time_bvp_s']:.3g} s; held where the BVP is feasible: "
              f"{sum(s['held'])}/{len(s['held'])} held, {sum(s['held_bvp_feasible'])} feasible; "
              f"max |N_sim − N_BVP| over held points {_fmt(s['max_dN_sim_vs_bvp'], '.2e')} (BVP without the contact couple; "
              f"discretisation error at this n), max |N_sim − N_chain| {_fmt(s.get('max_dN_sim_vs_chain'), '.2e')}."]
    if res.env:
        L += ["", "## Gymnasium pick environment throughput", "",
              "| env | env steps/s | physics steps/s (env) | raw mj_step steps/s | overhead |", "|---|---|---|---|---|"]
        for grip, e in res.env.items():
            L.append(f"| {'Pick-v0' if grip == 'I' else 'PickCradle-v0'} | {_fmt(e['env_steps_per_s'])} | "
                     f"{_fmt(e['env_physics_steps_per_s'])} | {_fmt(e['raw_physics_steps_per_s'])} | "
                     f"{e['overhead_percent']:.1f} % |")
    L += ["", "## What skipping buys", "", _skips_md(res)]
    L += ["Reproduce: `simgrip bench" + (" --quick" if res.quick else "") + f" --jobs {res.jobs}` "
          "(or `python -c \"from simgrip.harness.bench import run_bench; run_bench('bench_out')\"`).", ""]
    return "\n".join(L)


def _pareto(res: BenchResult, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    grips = [g for g in ("free", "I", "II", "III") if any(r["grip"] == g for r in res.rows)]
    fig = Figure(figsize=(4.0 * len(grips), 3.8), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, len(grips), squeeze=False)[0]
    style = {"settle": ("o-", "C0"), "naive": ("s--", "C3"), "minimiser": ("^-", "C2"), "bvp": ("d:", "C1")}
    floor = 1e-13
    for ax, g in zip(axes, grips):
        for meth, (ls, col) in style.items():
            if meth == "bvp":
                rs = sorted((r for r in res.rows if r["grip"] == g and r["method"] == "bvp" and r["n"] == 0),
                            key=lambda r: -r["tol"])
                lab = "BVP, tol 1e-3 … 1e-10 (reference at the floor)"
            else:
                rs = sorted((r for r in res.rows if r["grip"] == g and r["method"] == meth and r.get("time_s")),
                            key=lambda r: r["n"])
                lab = meth
            xs = [r["time_s"] for r in rs if r.get("tip_err") is not None and math.isfinite(r["time_s"])]
            ys = [max(r["tip_err"], floor) for r in rs if r.get("tip_err") is not None and math.isfinite(r["time_s"])]
            if xs:
                ax.loglog(xs, ys, ls, color=col, label=lab, ms=4)
            if meth == "naive":
                ex = [r for r in rs if r.get("extrapolated") and math.isfinite(r["time_s"])]
                if ex:
                    ax.loglog([r["time_s"] for r in ex], [max(r["tip_err"], floor) for r in ex], "s", ms=9,
                              mfc="none", color=col, label="naive, extrapolated")
            if meth != "bvp":
                for r in rs:
                    if r.get("tip_err") is not None and math.isfinite(r["time_s"]) and meth == "settle":
                        ax.annotate(str(r["n"]), (r["time_s"], max(r["tip_err"], floor)), fontsize=6,
                                    textcoords="offset points", xytext=(3, 3))
        ax.set_title(f"{'free rod' if g == 'free' else 'Grip ' + g}, κ̄0 = {STANDARD_CASES[g]:g}")
        ax.set_xlabel("wall time [s]")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("tip error |r − r_BVP| / ℓ")
    axes[-1].legend(fontsize=7)
    buf = _io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    with atomic_write(path, "wb") as fh:
        fh.write(buf.getvalue())


# ---------------------------------------------------------------------------
# command line


def add_arguments(p) -> None:
    """Add ``--quick --out --jobs --repeats --no-progress`` to an argparse parser."""
    p.add_argument("--quick", action="store_true", help="n in {8, 16, 32}, one repeat: under a minute")
    p.add_argument("--out", default="bench_out", help="output folder [default bench_out]")
    p.add_argument("--jobs", type=int, default=None, help="worker processes [default: all cores]")
    p.add_argument("--repeats", type=int, default=None, help="timing repeats (median) [default 1 quick, 3 full]")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def cli_bench(args) -> dict:
    """Run the bench from parsed arguments; returns a small record for the CLI to print."""
    res = run_bench(args.out, quick=args.quick, jobs=args.jobs, repeats=args.repeats,
                    progress=not getattr(args, "no_progress", False))
    return {"out": str(args.out), "files": sorted(str(p) for p in res.files.values()),
            "elapsed_s": res.elapsed_s, "ratios": res.ratios}

"""One bench task: every method's run time and error for one grip at one number of links.

The methods (see :mod:`simgrip.harness.bench` for what is compared how):

``settle`` / ``settle_dynamics``
    :func:`simgrip.settle.settle` (Newton, or ``method="dynamics"``) on a
    freshly built scene (build included; ``build_s`` alone);
``minimiser``
    :func:`simgrip.reference.solve_chain`: the exact equilibrium of
    the same hinge chain with the same contact couple;
``bvp``
    :func:`simgrip.reference.elastica.solve` of the same state (the error
    reference, at :data:`REF_TOL`); with ``n = 0`` the BVP alone at each
    tolerance of :data:`BVP_TOLS`, its own error-vs-time curve;
``naive``
    :func:`simgrip.settle.naive_relax` (plain MuJoCo dynamics) from a head
    start (:func:`start_state`), timed to matched error: the tip within
    :data:`MATCH_FRACTION` of the chain's discretisation error.  A run that
    does not get there within its step budget is extrapolated from the decay
    of the tip distance; where it does not decay, or the extrapolation is more
    than :data:`MAX_EXTRAPOLATION` times the measured run, only a lower bound
    is known: the run needs more than the measured time (``lower_bound``).
    A run that loses the workpiece (MuJoCo's soft friction creeps) has no
    static state to reach: ``inf``.

Every row carries the errors against the converged BVP of the same state
(``tip_err``, ``force_err``); ``settle_vs_min_*`` compare the settle with the
minimiser (how well MuJoCo reaches the chain's own equilibrium).
"""

from __future__ import annotations

import math
import statistics
import time

import numpy as np

from simgrip.harness.timing import contact_force, errors, median_time
from simgrip.params import DimensionlessParams
from simgrip.profiles import Uniform

__all__ = ["STANDARD_CASES", "BVP_TOLS", "TARGET_ERRORS", "REF_TOL", "MATCH_FRACTION", "MAX_EXTRAPOLATION", "bench_task",
           "reference", "chain", "start_state", "naive_to_matched_error"]

#: Curvature of each grip's standard case (feasible at the standard parameters).
STANDARD_CASES = {"free": -4.0, "I": -6.0, "II": 6.0, "III": -4.0}
#: Tolerances of the BVP's own error-vs-time curve; the last one is the reference.
BVP_TOLS = (1e-3, 1e-4, 1e-6, 1e-8, 1e-10)
REF_TOL = 1e-10
#: Error targets of the error-targeted settle's curve (``settle(target_error=...)``).
TARGET_ERRORS = (1e-3, 1e-4, 1e-5, 1e-6)
#: Matched error: the naive run is done when its tip is within this fraction of
#: the discretisation error of the chain's exact equilibrium.
MATCH_FRACTION = 0.01
#: An extrapolated naive time is trusted up to this many times the measured run:
#: the exponential fit covers the run's second half, and nothing measured says
#: the rate holds for more than an order of magnitude longer.
MAX_EXTRAPOLATION = 10.0


def reference(grip, params, prof, *, gamma=None, contact_moment=0.0, tol=REF_TOL):
    """The elastica BVP of the simulated state (same contact couple; Grip III: the simulation's ``gamma``)."""
    from simgrip.reference import elastica

    kw = {"contact_moment": contact_moment, "tol": tol}
    if grip == "III":
        kw["gamma"] = gamma
    return elastica.solve(grip, params, prof, **kw)


def chain(grip, params, prof, n, *, gamma=None, contact_moment=0.0):
    """The hinge chain's exact equilibrium with the simulation's contact couple (and Grip III ``gamma``)."""
    from simgrip.reference import solve_chain

    return solve_chain(grip, params, prof, n, gamma=gamma, contact_moment=contact_moment)


def naive_budget(budget_s: float, n: int) -> dict:
    """Deterministic step budget of a naive run: ``budget_s * 2e5 / n`` steps (about ``budget_s``
    seconds of MuJoCo stepping), with a wall-clock guard at 5x (only a pathological run hits it)."""
    return {"max_steps": max(2000, int(budget_s * 2e5 / n)), "time_budget_s": 5.0 * budget_s + 5.0}


def start_state(scene, grip, params, prof, C) -> np.ndarray:
    """Common start of ``naive`` (and of the skipping table's runs); returns the scene's ``qpos``.

    Grips I/II: the chain's equilibrium at 80 % of the curvature (tip on the
    face), the workpiece centred at the tip height; III: the built state (the
    chain's equilibrium with the corner at ``gamma``); free: straight.
    """
    import mujoco

    from simgrip.settle import finger_tip
    from simgrip.sim.scene import set_joint_angles

    if grip in ("I", "II"):
        set_joint_angles(scene, chain(grip, params, prof.scaled(0.8), scene.n, contact_moment=C).joint_angles)
        m, d = scene.model, scene.data
        tip_z = float(finger_tip(scene)[1]) * scene.length
        body_z = float(m.body_pos[scene.workpiece_body][2])
        for name, qa in zip(scene.workpiece_joints, scene.workpiece_qpos):
            d.qpos[qa] = tip_z - body_z if name == "z" else 0.0
        d.qvel[:] = 0.0
        mujoco.mj_forward(m, d)
    return scene.data.qpos.copy()


def naive_to_matched_error(scene, target_tip, tip_tol: float, budget_s: float, tol: float) -> dict:
    """:func:`simgrip.settle.naive_relax` from the scene's state until the tip is within ``tip_tol`` of ``target_tip``.

    Adds ``lower_bound``: the tip did not get there, and its distance either did
    not decay usefully or extrapolates beyond :data:`MAX_EXTRAPOLATION` times
    the measured run, so only "more than ``measured_s``" is known (a run that
    diverged or lost the workpiece has no static state: ``time_to_match_s`` is
    ``inf``); and ``tip``, finger 0's tip at the end.
    """
    from simgrip.settle import finger_tip, naive_relax

    nv = naive_relax(scene, tol=tol, target_tip=target_tip, tip_tol=tip_tol, **naive_budget(budget_s, scene.n))
    t, measured = nv["time_to_match_s"], nv["measured_s"]
    stopped = nv.get("diverged", False) or nv.get("workpiece_lost", False)  # no static state to reach: inf
    nv["lower_bound"] = bool(not nv["matched"] and not stopped and t > MAX_EXTRAPOLATION * measured)
    if nv["lower_bound"]:
        far = f"; extrapolation to {t:.3g} s is beyond {MAX_EXTRAPOLATION:g}x the run" if math.isfinite(t) else ""
        nv["note"] += f"{far}; needs more than {measured:.3g} s"
    nv["tip"] = finger_tip(scene)
    return nv


def _bvp_curve(grip, params, prof, repeats, base) -> list[dict]:
    """The BVP alone at each tolerance of :data:`BVP_TOLS`, errors against the last (rows with ``n = 0``)."""
    from simgrip.sim.scene import DEFAULT_R_TIP

    C = DEFAULT_R_TIP * params.M if grip in ("I", "II") else 0.0
    ref = reference(grip, params, prof, gamma=params.gamma, contact_moment=C)
    rows = []
    for btol in BVP_TOLS:
        sol, tmed, tmin = median_time(
            lambda: reference(grip, params, prof, gamma=params.gamma, contact_moment=C, tol=btol), repeats)
        te, fe = errors(grip, sol.tip, contact_force(sol), ref)
        rows.append({**base, "method": "bvp", "tol": btol, "time_s": tmed, "time_min_s": tmin,
                     "repeats": repeats, "steps": sol.mesh_size, "converged": True, "tip_err": te,
                     "force_err": fe, "gamma": sol.gamma, "contact_moment": C,
                     "residual": sol.residual, "note": "reference" if btol == REF_TOL else ""})
    return rows


def _target_curve(grip, params, prof, repeats, base) -> list[dict]:
    """``settle(target_error=E)`` at each of :data:`TARGET_ERRORS`, errors against the converged BVP (``n = 0`` rows).

    The reference is the point-contact BVP (the settle's default contact); Grip III has no error target.
    """
    from simgrip.scenes import build_scene
    from simgrip.settle import SettleError, settle

    if grip == "III":
        return []
    ref = reference(grip, params, prof)
    rows = []
    for target in TARGET_ERRORS:
        try:
            st, tmed, tmin = median_time(lambda: settle(build_scene(grip, params, prof, 8), target_error=target),
                                         repeats)
        except (SettleError, ValueError) as exc:
            rows.append({**base, "method": "settle_target", "target_error": target, "tol": target, "converged": False,
                         "note": f"{type(exc).__name__}: {exc}"})
            continue
        te, fe = errors(grip, st.tip[0], contact_force(st), ref)
        rows.append({**base, "method": "settle_target", "target_error": target, "tol": target, "time_s": tmed,
                     "time_min_s": tmin, "repeats": repeats, "steps": int(st.steps), "links": int(st.links),
                     "converged": bool(st.converged), "tip_err": te, "force_err": fe, "residual": st.residual,
                     "error_estimate": st.error_estimate, "extrapolated": bool(st.extrapolated),
                     "note": "" if (st.held or grip == "free") else "workpiece dropped"})
    return rows


def _settle_row(st, method, ref, chn, grip, extra, timing) -> dict:
    te, fe = errors(grip, st.tip[0], contact_force(st), ref)
    dmt, dmf = errors(grip, st.tip[0], contact_force(st), chn)
    return {**extra, **timing, "method": method, "steps": int(st.steps), "converged": bool(st.converged),
            "tip_err": te, "force_err": fe, "settle_vs_min_tip": dmt, "settle_vs_min_force": dmf,
            "residual": st.residual, "note": "" if (st.held or grip == "free") else "workpiece dropped"}


def bench_task(grip: str, n: int, repeats: int, naive_budget_s: float, params: DimensionlessParams) -> list[dict]:
    """Rows of every method for ``grip`` (its :data:`STANDARD_CASES` curvature) at ``n`` links (``n = 0``: BVP curve)."""
    from simgrip.settle import DEFAULT_TOL, SettleError, settle
    from simgrip.scenes import build_scene
    from simgrip.sim.scene import DEFAULT_R_TIP

    kappa = STANDARD_CASES[grip]
    prof = Uniform(kappa)
    tol = DEFAULT_TOL
    base = {"grip": grip, "kappa": kappa, "n": n, "tol": tol}
    if n == 0:
        return _bvp_curve(grip, params, prof, repeats, base) + _target_curve(grip, params, prof, repeats, base)
    rows = []

    settle_only = []  # the settle alone (build excluded): compared with the naive run from its head start

    def run_settle():
        t0 = time.perf_counter()
        sc = build_scene(grip, params, prof, n)
        tb = time.perf_counter() - t0
        t1 = time.perf_counter()
        out = settle(sc, tol=tol)
        settle_only.append(time.perf_counter() - t1)
        return out, tb

    st = None
    try:
        (st, build_s), t_settle, t_settle_min = median_time(run_settle, repeats)
    except (SettleError, ValueError) as exc:
        rows.append({**base, "method": "settle", "converged": False, "note": f"{type(exc).__name__}: {exc}"})
    if grip == "free":
        gam, C = None, 0.0
    elif st is not None and st.contact is not None:
        gam, C = (st.gamma_sim if grip == "III" else None), st.contact_moment
    else:
        gam, C = (params.gamma if grip == "III" else None), (DEFAULT_R_TIP * params.M if grip != "III" else 0.0)
    ref, t_bvp, t_bvp_min = median_time(lambda: reference(grip, params, prof, gamma=gam, contact_moment=C), repeats)
    chn, t_min, t_min_min = median_time(lambda: chain(grip, params, prof, n, gamma=gam, contact_moment=C), repeats)
    min_te, min_fe = errors(grip, chn.tip, contact_force(chn), ref)
    extra = {**base, "gamma": gam, "contact_moment": C}
    if st is not None:
        rows.append(_settle_row(st, "settle", ref, chn, grip, extra,
                                {"time_s": t_settle, "time_min_s": t_settle_min, "repeats": repeats, "build_s": build_s}))
    try:
        sd, t_dyn, t_dyn_min = median_time(lambda: settle(build_scene(grip, params, prof, n), method="dynamics"), repeats)
        rows.append(_settle_row(sd, "settle_dynamics", ref, chn, grip, extra,
                                {"tol": None, "time_s": t_dyn, "time_min_s": t_dyn_min, "repeats": repeats}))
    except (SettleError, ValueError) as exc:
        rows.append({**extra, "method": "settle_dynamics", "converged": False, "note": f"{type(exc).__name__}: {exc}"})
    rows.append({**extra, "method": "minimiser", "tol": None, "time_s": t_min, "time_min_s": t_min_min,
                 "repeats": repeats, "steps": int(chn.iterations), "converged": bool(chn.success),
                 "tip_err": min_te, "force_err": min_fe, "residual": chn.gradient_norm})
    rows.append({**extra, "method": "bvp", "tol": REF_TOL, "time_s": t_bvp, "time_min_s": t_bvp_min,
                 "repeats": repeats, "steps": ref.mesh_size, "converged": True, "tip_err": 0.0,
                 "force_err": None if grip == "free" else 0.0, "residual": ref.residual, "note": "reference"})
    try:
        scene = build_scene(grip, params, prof, n)
        start_state(scene, grip, params, prof, C)
        nv = naive_to_matched_error(scene, chn.tip, MATCH_FRACTION * min_te, naive_budget_s, tol)
        nte, _ = errors(grip, nv["tip"], np.zeros(2), ref)  # the naive answer at the end of its run
        rows.append({**extra, "method": "naive", "time_s": nv["time_to_match_s"], "time_min_s": nv["measured_s"],
                     "repeats": 1, "steps": nv["steps_to_match"], "converged": bool(nv["converged"]),
                     "matched": bool(nv["matched"]), "extrapolated": bool(nv["match_extrapolated"]),
                     "lower_bound": nv["lower_bound"],
                     "tip_err": nte if nv["matched"] else min_te, "force_err": None if grip == "free" else min_fe,
                     "residual": nv["residual"], "dt": nv["dt"],
                     "settle_same_start_s": statistics.median(settle_only) if settle_only else None,
                     "time_to_tol_s": nv["time_to_tol_s"], "steps_to_tol": nv["steps_to_tol"], "note": nv["note"]})
    except (SettleError, ValueError) as exc:
        rows.append({**extra, "method": "naive", "converged": False, "note": f"{type(exc).__name__}: {exc}"})
    return rows

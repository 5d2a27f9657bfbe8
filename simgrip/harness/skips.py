"""What skipping buys: the settle with and without each shortcut simgrip takes, and the Fig. 7 sweep.

Each row of the skipping table times the settle with a shortcut (simgrip's
default) and without it, on the same case, and says how much the answer changes
(a shortcut that changes the answer would be a bug):

* contact off for the free rod, collision filtering, the symmetric reduction:
  the scene rebuilt without the shortcut, settled the same way;
* inertia and damping (and all of them together): the static settle against
  the naive relaxation (plain MuJoCo dynamics, :mod:`simgrip.harness.methods`),
  timed to matched error;
* warm starts: the Fig. 7 sweep (Grip I over several curvatures) settled with
  :func:`simgrip.settle.settle_sweep` and cold at every curvature, beside the
  BVP's own sweep (:func:`sweep_task`).
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from simgrip.harness.methods import MATCH_FRACTION, STANDARD_CASES, chain, naive_to_matched_error, reference, start_state
from simgrip.harness.timing import contact_force, median_time
from simgrip.params import DimensionlessParams
from simgrip.profiles import Uniform

__all__ = ["SKIPS", "skip_task", "sweep_task", "WARM_STARTS"]

#: The rows of the skipping table, in order (the warm-start row comes from :func:`sweep_task`).
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
WARM_STARTS = "warm starts (Fig. 7 sweep)"


def sweep_task(n: int, kappas: tuple, params: DimensionlessParams) -> dict:
    """Fig. 7 (Grip I) by simulation with warm starts, cold, and by the BVP; times and answer changes."""
    from simgrip.reference import elastica
    from simgrip.settle import settle, settle_sweep
    from simgrip.scenes import build_scene

    profs = [Uniform(k) for k in kappas]
    t0 = time.perf_counter()
    warm = settle_sweep(build_scene("I", params, profs[0], n), profs)
    t_warm = time.perf_counter() - t0
    t0 = time.perf_counter()
    cold = [settle(build_scene("I", params, p, n)) for p in profs]
    t_cold = time.perf_counter() - t0
    t0 = time.perf_counter()
    bvp = elastica.kappa_sweep("I", params, list(kappas))
    t_bvp = time.perf_counter() - t0
    held = [bool(w.held) for w in warm]
    dN_warm_cold = max((abs(w.N1 - c.N1) for w, c in zip(warm, cold) if w.held and c.held), default=0.0)
    dtip_warm_cold = max(float(np.linalg.norm(w.tip[0] - c.tip[0])) for w, c in zip(warm, cold))
    dN_bvp = max((abs(w.N1 - b.N1) for w, b in zip(warm, bvp) if w.held), default=None)
    chains = [chain("I", params, p, n, contact_moment=w.contact_moment) for p, w in zip(profs, warm)]
    dN_chain = max((abs(w.N1 - c.N1) for w, c in zip(warm, chains) if w.held), default=None)
    return {
        "grip": "I", "n": n, "kappas": list(kappas), "time_warm_s": t_warm, "time_cold_s": t_cold,
        "time_bvp_s": t_bvp, "held": held, "held_bvp_feasible": [bool(b.feasible) for b in bvp],
        "N_sim": [w.N1 if w.held else None for w in warm], "N_bvp": [b.N1 for b in bvp],
        "max_dN_warm_vs_cold": dN_warm_cold, "max_dtip_warm_vs_cold": dtip_warm_cold,
        "max_dN_sim_vs_bvp": dN_bvp, "max_dN_sim_vs_chain": dN_chain,
        "steps_warm": int(sum(w.steps for w in warm)), "steps_cold": int(sum(c.steps for c in cold)),
    }


def warm_start_row(sweep: dict) -> dict:
    """The skipping table's warm-start row, from :func:`sweep_task`'s record."""
    return {
        "skip": WARM_STARTS, "n": sweep["n"], "case": f"I, {len(sweep['kappas'])} curvatures",
        "time_with_s": sweep["time_warm_s"], "time_without_s": sweep["time_cold_s"],
        "speedup": sweep["time_cold_s"] / sweep["time_warm_s"],
        "answer_change_tip": sweep["max_dtip_warm_vs_cold"],
        "answer_change_force": sweep["max_dN_warm_vs_cold"], "note": "without: each curvature settled from scratch",
    }


def _broad_collision(scene) -> None:
    """Undo collision filtering: every geom collides with every geom (MuJoCo's default)."""
    scene.model.geom_contype[:] = 1
    scene.model.geom_conaffinity[:] = 1


def _contact_on(scene) -> None:
    import mujoco

    scene.model.opt.disableflags &= ~int(mujoco.mjtDisableBit.mjDSBL_CONTACT)


def _timed_settle(make, repeats):
    """``(state, median s)`` of building with ``make()`` and settling."""
    from simgrip.settle import settle

    st, t, _ = median_time(lambda: settle(make()), repeats)
    return st, t


def _answer(st) -> np.ndarray:
    return np.concatenate([np.asarray(st.tip[0], float), contact_force(st)])


def _without(make, undo):
    """A scene factory: ``make()`` with the shortcut undone by ``undo(scene)`` (each in turn)."""
    def mk():
        sc = make()
        for u in undo:
            u(sc)
        return sc
    return mk


def _versus_naive(which, g, params, n, repeats, budget_s):
    """Static settle (build excluded) vs the naive relaxation to matched error, from a head start."""
    from simgrip.settle import settle
    from simgrip.scenes import build_scene
    from simgrip.sim.scene import DEFAULT_R_TIP

    allt = which.startswith("all together")
    prof = Uniform(STANDARD_CASES[g])
    C = DEFAULT_R_TIP * params.M if g != "free" else 0.0
    times = []

    def full():
        sc = build_scene(g, params, prof, n)
        t1 = time.perf_counter()
        out = settle(sc)
        times.append(time.perf_counter() - t1)
        return out

    a, _, _ = median_time(full, repeats)
    scene = build_scene(g, params, prof, n, fingers=2 if allt else 1)
    start_state(scene, g, params, prof, C)
    if allt:
        _broad_collision(scene)
    chn = chain(g, params, prof, n, contact_moment=C)
    band = MATCH_FRACTION * float(np.linalg.norm(chn.tip - reference(g, params, prof, contact_moment=C).tip))
    nv = naive_to_matched_error(scene, chn.tip, band, budget_s, 1e-10)
    row = {
        "case": f"{g}, kappa={STANDARD_CASES[g]:g}, to matched error (naive: head start)",
        "extrapolated": bool(nv["match_extrapolated"]), "lower_bound": nv["lower_bound"],
        "note": ("without: physical inertia, light damping, largest stable dt"
                 + (", two fingers, all geoms collide (warm starts: see the sweep row)" if allt else "")),
        "diff_vs_minimiser_with": float(np.linalg.norm(a.tip[0] - chn.tip)),
        "time_with_s": statistics.median(times),
        "time_without_s": nv["measured_s"] if nv["lower_bound"] else nv["time_to_match_s"],
    }
    if nv["matched"]:
        row["answer_change_tip"] = float(np.linalg.norm(np.asarray(a.tip[0]) - nv["tip"]))
    return row


def skip_task(which: str, n: int, repeats: int, params: DimensionlessParams, naive_budget_s: float) -> dict:
    """One row of the skipping table (``which`` in :data:`SKIPS`): time with the skip and without it."""
    from simgrip.scenes import build_scene

    k = STANDARD_CASES
    row = {"skip": which, "n": n, "answer_change_tip": None, "answer_change_force": None}
    if which.startswith(("inertia and damping", "all together")):
        row.update(_versus_naive(which, "free" if "free" in which else "I", params, n, repeats, naive_budget_s))
    else:
        if which == "contact off (free rod)":
            g, note = "free", "without: contact enabled, all geoms collide"
            mk = lambda: build_scene(g, params, Uniform(k[g]), n)  # noqa: E731
            mk_off = _without(mk, (_contact_on, _broad_collision))
        elif which.startswith("collision filtering"):
            g, note = ("III" if "III" in which else "I"), "without: all geoms collide (contype = conaffinity = 1)"
            mk = lambda: build_scene(g, params, Uniform(k[g]), n)  # noqa: E731
            mk_off = _without(mk, (_broad_collision,))
        elif which.startswith("symmetric reduction"):
            g, note = ("III" if "III" in which else "I"), "without: two fingers, workpiece free in x, z, rotation"
            mk = lambda: build_scene(g, params, Uniform(k[g]), n)  # noqa: E731
            mk_off = lambda: build_scene(g, params, Uniform(k[g]), n, fingers=2)  # noqa: E731
        else:
            raise ValueError(f"skip must be one of {SKIPS}, got {which!r}")
        a, ta = _timed_settle(mk, repeats)
        b, tb = _timed_settle(mk_off, repeats)
        da = _answer(a) - _answer(b)
        row.update(case=f"{g}, kappa={k[g]:g}", note=note, time_with_s=ta, time_without_s=tb,
                   answer_change_tip=float(np.linalg.norm(da[:2])), answer_change_force=float(np.linalg.norm(da[2:])))
    ta, tb = row["time_with_s"], row["time_without_s"]
    row["speedup"] = tb / ta if ta > 0 and tb is not None else None
    return row

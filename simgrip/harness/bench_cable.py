"""MuJoCo's own cable as a peer of the free-rod settle: its error against the BVP and its time to a matched error.

The peer is MuJoCo's discrete elastic rod, a 1-D flex with bending elasticity (MuJoCo >= 3.17; the
``composite``/``mujoco.elasticity.cable`` plugin of older versions is gone from 4.0): ``n + 2``
vertices, each a body with two slide joints in the plane of the rod, joined by edges held at their
length by MuJoCo's flex edge equality (near-hard: ``solimp`` 0.9999), bending stiffness
``EI = D rho g l^3`` from the Young modulus of a circular section (``E = 4 EI / (pi r^4)``).

* **Rest curvature.** The flex's bending is measured from its compiled configuration, so the
  rod is compiled in its discrete rest shape: edge angles ``phi_j = phi_(j-1) + kappa0(s_j) (l_(j-1) + l_j)/2``
  (the turning at vertex ``j`` over its Voronoi length is ``kappa0(s_j)``).  With gravity off the
  rest shape is an equilibrium, and with gravity the settled tip converges at second order to
  :func:`simgrip.reference.elastica.solve` (``tests/test_bench_cable.py``), so the cable does
  represent ``kappa0(s)``.
* **Clamp.** The first edge, from ``s = -h/2`` to ``s = h/2``, has both ends pinned and lies on the
  clamp's tangent: the discrete rod's bending at ``h/2`` then refers to a tangent whose midpoint is
  the clamp, which is second order (a ghost edge ending at ``s = 0`` puts the clamp at ``-h/2``:
  first order, the tip sag ``1 + 2 h`` times too large).  Free vertices at ``s = (k + 1/2) h``,
  ``k = 1 .. n-1``, and the tip at ``s = l`` (last edge ``h/2``); lumped masses ``rho h`` inside,
  ``3/4 rho h`` and ``rho h/4`` at the last two vertices (their Voronoi lengths).
* **Its own settle.** Damped dynamics with MuJoCo's ``discrete`` integrator (the one that integrates
  flex bending implicitly), stiffness-proportional flex damping ``beta = 2 zeta / omega_1`` with
  ``omega_1 = 3.516 sqrt(D)`` (the cantilever's first mode in ``sqrt(g/l)``), ``zeta =`` :data:`ZETA`;
  at rest when ``max |qvel| <`` :data:`VTOL` ``sqrt(g l)``.
* **Matched error.** For each ``n`` the target is simgrip's own free-rod settle error at that ``n``
  (``|tip - tip_BVP| / l``): the cable at the same ``n`` is matched once its tip error is below the
  target and stays below it for the rest of the run.  Time steps are tried from the largest of
  :data:`DTS` down (a larger step's fixed point moves with its softer edge constraint); the first that
  matches is timed.  Times are CPU seconds (``time.process_time``) of the cable's ``k`` steps from its
  start and of simgrip's settle from its start (:func:`simgrip.harness.timing.settle_from_start`),
  interleaved over ``repeats`` rounds, median and fastest; one BLAS thread.

Files: ``cable.json`` and ``cable.md`` (:func:`write_cable_bench`, a part of ``simgrip bench``).
"""

from __future__ import annotations

import math
import statistics
import time
from dataclasses import dataclass

import numpy as np

from simgrip.params import STANDARD, DimensionlessParams

__all__ = ["ZETA", "VTOL", "DTS", "CABLE_RADIUS", "KAPPA", "N_FULL", "N_QUICK", "Cable", "build_cable", "cable_run",
           "steps_to_error", "cable_row", "cable_bench", "cable_bench_md", "write_cable_bench"]

#: Damping ratio of the first mode (stiffness-proportional damping: higher modes over-damped).
ZETA = 0.7
#: At rest: ``max |qvel| <`` VTOL, in ``sqrt(g l)``.
VTOL = 1e-6
#: Time steps tried, in ``sqrt(l/g)``, largest first (the first that matches is timed: the peer gets every
#: advantage, an error under the target by a cancellation of its step's edge stretch and its discretisation counts).
DTS = (0.1, 0.03, 0.01, 0.003, 0.001)
#: Section radius over ``l`` (only ``EI`` enters the bending; the radius sets ``E``).
CABLE_RADIUS = 0.01
#: The first mode of a clamped uniform cantilever, ``omega_1 = 3.516 sqrt(EI / (rho l^4))`` (Euler-Bernoulli).
OMEGA1_COEFF = 3.516
#: The run's length, in ``sqrt(l/g)``: ``exp(-zeta omega_1 T) < 1e-10`` for ``D >= 1``.
T_MAX = 15.0
#: Curvature of the free rod (bench_settle's and bench_overhead's standard case).
KAPPA = -3.0
N_FULL = (16, 32, 64, 128, 256)
N_QUICK = (16, 32)


@dataclass
class Cable:
    """A compiled cable: ``model``, ``data`` (at its start after :func:`build_cable`), vertex arc lengths ``s``
    (over ``l``; the first two pinned), time step ``dt`` (``sqrt(l/g)``), ``n`` edges of the free rod."""

    model: object
    data: object
    s: np.ndarray
    dt: float
    n: int

    def reset(self) -> None:
        """Back to the start: the rest shape at rest (positions computed)."""
        import mujoco

        mujoco.mj_resetData(self.model, self.data)
        mujoco.mj_kinematics(self.model, self.data)

    def tip(self) -> np.ndarray:
        """The tip ``(X, Y)`` over ``l`` from the clamp, ``Y`` up (the BVP's axes)."""
        p = self.data.xpos[-1]
        return np.array([p[0], p[2]])


def _check(n, dt, zeta, D):
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 2:
        raise ValueError(f"n must be an integer >= 2, got {n!r}")
    for name, v in (("dt", dt), ("zeta", zeta), ("D", D)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise ValueError(f"{name} must be a positive finite number, got {v!r}")


def build_cable(n: int, profile=KAPPA, *, params: DimensionlessParams = STANDARD, dt: float = 0.003,
                zeta: float = ZETA, gravity: bool = True) -> Cable:
    """MuJoCo's cable for the free clamped rod of ``n`` edges with intrinsic curvature ``profile`` (a number:
    uniform ``kappa_bar``; a profile or callable of ``s_bar``) and ``D = params.D``, in units ``l = rho = g = 1``
    (see the module docstring).  ``gravity=False``: no weight (the rest shape is then the equilibrium)."""
    import mujoco

    from simgrip.profiles import as_profile

    _check(n, dt, zeta, params.D)
    kap = as_profile(profile)
    h = 1.0 / n
    s = np.concatenate([[-h / 2, h / 2], (np.arange(1, n) + 0.5) * h, [1.0]])
    le = np.diff(s)
    k = np.asarray(kap(np.clip(s, 0.0, 1.0)), float)
    phi = np.zeros(le.size)
    for j in range(1, le.size):
        phi[j] = phi[j - 1] + k[j] * (le[j - 1] + le[j]) / 2
    pts = np.vstack([[-h / 2, 0.0], np.array([-h / 2, 0.0]) + np.cumsum(np.c_[le * np.cos(phi), le * np.sin(phi)], 0)])
    mass = np.concatenate([[1.0, 1.0], np.full(n - 2, h), [0.75 * h, 0.25 * h]])  # the pinned two: any mass
    sp = mujoco.MjSpec()
    sp.option.gravity = [0.0, 0.0, -1.0 if gravity else 0.0]
    sp.option.timestep = float(dt)
    sp.option.integrator = mujoco.mjtIntegrator.mjINT_DISCRETE
    names = []
    for i, (x, y) in enumerate(pts):
        b = sp.worldbody.add_body(name=f"v{i}", pos=[x, 0.0, y])
        b.mass, b.inertia, b.explicitinertial = float(mass[i]), [1e-8] * 3, True  # point mass (slides only)
        if i >= 2:
            for axis in ([1, 0, 0], [0, 0, 1]):
                b.add_joint(type=mujoco.mjtJoint.mjJNT_SLIDE, axis=axis)
        names.append(b.name)
    f = sp.add_flex(name="rod")
    f.dim, f.radius, f.vertbody, f.vert = 1, CABLE_RADIUS, names, [0.0] * (3 * len(names))
    f.elem = [v for i in range(len(names) - 1) for v in (i, i + 1)]
    f.young = 4.0 * params.D / (math.pi * CABLE_RADIUS ** 4)
    f.damping = 2.0 * zeta / (OMEGA1_COEFF * math.sqrt(params.D))
    f.contype = f.conaffinity = 0
    eq = sp.add_equality(type=mujoco.mjtEq.mjEQ_FLEX, name1="rod")
    eq.solref = [2.0 * dt, 1.0]  # the stiffest MuJoCo allows at this step
    eq.solimp = [0.9999, 0.9999, 0.001, 0.5, 2.0]
    model = sp.compile()
    cable = Cable(model, mujoco.MjData(model), s, float(dt), int(n))
    cable.reset()
    return cable


def cable_run(cable: Cable, steps: int):
    """Step ``cable`` from its start ``steps`` times; returns ``(tips (steps, 2), max |qvel| per step, warnings)``."""
    import mujoco

    from simgrip.sim.checks import active_warnings

    cable.reset()
    m, d = cable.model, cable.data
    tips = np.empty((steps, 2))
    vmax = np.empty(steps)
    with _quiet():
        for k in range(steps):
            mujoco.mj_step(m, d)
            tips[k] = d.xpos[-1][0], d.xpos[-1][2]
            vmax[k] = np.abs(d.qvel).max()
    return tips, vmax, active_warnings(d)


def _quiet():
    """MuJoCo's warning printer off for a block (the warnings are still counted in ``data.warning`` and
    recorded); the previous handler restored after."""
    from simgrip.sim.checks import warnings_to

    return warnings_to(lambda msg: None)


def steps_to_error(err: np.ndarray, target: float) -> int | None:
    """The fewest steps after which ``err`` stays ``<= target`` to the end of the run (None: never)."""
    bad = np.nonzero(~(np.asarray(err) <= target))[0]
    if bad.size == 0:
        return 1
    return None if bad[-1] + 1 >= len(err) else int(bad[-1] + 2)


def _timed(fns: dict, repeats: int) -> dict:
    """CPU times of ``fns`` interleaved over ``repeats`` rounds: ``{key: (median, fastest)}``."""
    t = {k: [] for k in fns}
    for _ in range(max(1, repeats)):
        for k, fn in fns.items():
            t0 = time.process_time()
            fn()
            t[k].append(time.process_time() - t0)
    return {k: (statistics.median(v), min(v)) for k, v in t.items()}


def cable_row(n: int, kappa: float = KAPPA, *, repeats: int = 3, ref=None) -> dict:
    """One ``n``: simgrip's free-rod settle and the cable, errors against the converged BVP, times to matched
    error (see the module docstring).  ``ref``: the BVP solution (solved here if None)."""
    import mujoco

    from simgrip.harness.timing import settle_from_start
    from simgrip.profiles import Uniform
    from simgrip.reference import elastica
    from simgrip.threads import blas_threads

    ref = ref if ref is not None else elastica.solve("free", STANDARD, Uniform(kappa), tol=1e-10)
    settle = settle_from_start("free", kappa, n)
    row = {"n": n, "kappa": kappa}
    with blas_threads(1):
        st = settle()
        target = float(np.linalg.norm(np.asarray(st.tip, float).ravel() - ref.tip))
        row["settle_tip_err"] = target
        tried = []
        for dt in DTS:
            cable = build_cable(n, kappa, dt=dt)
            steps = int(round(T_MAX / dt))
            tips, vmax, warns = cable_run(cable, steps)
            err = np.linalg.norm(tips - ref.tip, axis=1)
            k = steps_to_error(err, target)
            rest = np.nonzero(vmax < VTOL)[0]
            kr = int(rest[0] + 1) if rest.size else None
            tried.append({"dt": dt, "steps_to_match": k, "final_err": float(err[-1]), "steps_to_rest": kr,
                          "err_at_rest": None if kr is None else float(err[kr - 1]), "warnings": warns})
            if k is not None:  # (MuJoCo's warnings, e.g. its M+K solve under-converged at n >= 64, are recorded)
                break
        row["cable_tried"] = tried
        best = tried[-1]
        row.update({"cable_dt": best["dt"], "cable_floor_err": best["final_err"],
                    "steps_to_match": best["steps_to_match"],
                    "steps_to_rest": best["steps_to_rest"], "cable_err_at_rest": best["err_at_rest"],
                    "cable_warnings": best["warnings"]})
        if best["steps_to_match"] is None:
            row.update({"cable_s": None, "cable_min_s": None, "note": "the cable never reached simgrip's error"})
            row.update(dict(zip(("settle_s", "settle_min_s"), _timed({"s": settle}, repeats)["s"])))
        else:
            k = best["steps_to_match"]
            m, d = cable.model, cable.data

            def run_cable():
                mujoco.mj_resetData(m, d)
                for _ in range(k):
                    mujoco.mj_step(m, d)

            with _quiet():
                t = _timed({"settle": settle, "cable": run_cable}, repeats)
            row.update({"settle_s": t["settle"][0], "settle_min_s": t["settle"][1], "cable_s": t["cable"][0],
                        "cable_min_s": t["cable"][1], "cable_over_settle": t["cable"][0] / t["settle"][0],
                        "cable_over_settle_fastest": t["cable"][1] / t["settle"][1]})
            if best["steps_to_rest"] is not None:  # its own stop, at the per-step cost just measured
                row["cable_rest_s"] = t["cable"][0] * best["steps_to_rest"] / k
    return row


def cable_bench(*, quick: bool = False, repeats: int | None = None, kappa: float = KAPPA) -> dict:
    """The rows of :func:`cable_row` over :data:`N_QUICK` (``quick``) or :data:`N_FULL`, and the verdict
    ``ahead_at_every_n`` (simgrip's settle faster, in median CPU time, than the cable at matched error)."""
    import mujoco

    from simgrip.profiles import Uniform
    from simgrip.reference import elastica

    reps = int(repeats or (1 if quick else 5))
    ref = elastica.solve("free", STANDARD, Uniform(kappa), tol=1e-10)
    rows = [cable_row(n, kappa, repeats=reps, ref=ref) for n in (N_QUICK if quick else N_FULL)]
    ahead = all(r.get("cable_s") is None or r["cable_s"] > r["settle_s"] for r in rows)
    return {"mujoco": mujoco.__version__, "kappa": kappa, "D": STANDARD.D, "zeta": ZETA, "vtol": VTOL,
            "repeats": reps, "rows": rows, "ahead_at_every_n": ahead}


def cable_bench_md(rec: dict) -> str:
    """``cable.md``: one row per ``n``."""
    from simgrip.harness.tables import fmt

    lines = [f"# simgrip's free-rod settle against MuJoCo {rec['mujoco']}'s cable (1-D flex, discrete elastic rod)",
             "",
             f"Free clamped rod, kappa_bar = {rec['kappa']:g}, D = {rec['D']:g}; errors |tip - tip_BVP| / l against "
             "the "
             "converged BVP; CPU ms, median (fastest) of interleaved rounds; the cable timed to simgrip's error at the "
             f"same n (module simgrip.harness.bench_cable). simgrip ahead at every n: **{rec['ahead_at_every_n']}**.",
             "",
             "| n | simgrip err | settle ms | cable floor err | cable dt | steps to match | cable ms | cable / settle "
             "| cable at rest: steps, err | MuJoCo warnings |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rec["rows"]:
        cab = "never" if r.get("cable_s") is None else f"{r['cable_s'] * 1e3:.3g} ({r['cable_min_s'] * 1e3:.3g})"
        lines.append(
            f"| {r['n']} | {fmt(r['settle_tip_err'])} | {r['settle_s'] * 1e3:.3g} ({r['settle_min_s'] * 1e3:.3g}) | "
            f"{fmt(r['cable_floor_err'])} | {r['cable_dt']:g} | {fmt(r['steps_to_match'], 'd')} | {cab} | "
            f"{fmt(r.get('cable_over_settle'), '.3g', '-')} | {fmt(r['steps_to_rest'], 'd')}, "
            f"{fmt(r['cable_err_at_rest'])} | {', '.join(r['cable_warnings']) or 'none'} |")
    return "\n".join(lines) + "\n"


def write_cable_bench(out_dir, *, quick: bool = False, repeats: int | None = None) -> dict:
    """Measure and write ``cable.json`` and ``cable.md`` into ``out_dir``; returns the record."""
    from simgrip.harness.tables import write_record

    rec = cable_bench(quick=quick, repeats=repeats)
    write_record(out_dir, "cable", rec, cable_bench_md(rec))
    return rec


if __name__ == "__main__":  # pragma: no cover - manual run: python -m simgrip.harness.bench_cable [--quick]
    import sys

    print(cable_bench_md(cable_bench(quick="--quick" in sys.argv)))

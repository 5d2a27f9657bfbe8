"""Numerical stress tests of the MuJoCo settle: every run ends settled or with a named error.

:func:`run_stress` builds and settles many scenes over the whole parameter box
of the issue

=============  ==========================================================
``D``          ``[1e-2, 1e2]`` (log-uniform)
``kappa``      ``[-12, 12]`` (uniform; the profile's peak curvature)
``M``          ``[0, 50]``
``mu_s``       ``[0.05, 5]`` (log-uniform)
``b``          ``(0, 1)`` (``b/l``)
``n``          ``[4, 256]`` links (log-uniform integer)
profile        uniform, concentrated (eq. 34, ``alpha`` up to 8) and extreme
               ones: a step that reverses the curvature at mid-length, a
               narrow spike, a fast oscillation
grip           ``free``, ``I``, ``II``, ``III``
=============  ==========================================================

plus a grid over the corners and centre of the box.  Cases are drawn up front
from ``numpy.random.default_rng(seed)``, and each case is self-contained, so
the outcome of every case is independent of ``jobs``.

Each case ends as exactly one of

``settled``
    a finite state with ``converged = True`` and a static residual at most
    :data:`RESIDUAL_CAP` (``residual_above_tol`` records whether it is above
    settle's own tolerance, i.e. stopped at its noise floor);
``rejected``
    a ``ValueError`` whose message names the offending input (one of
    :data:`INPUT_NAMES`; e.g. a Grip III curvature that gives no starting
    shape); a ``ValueError`` that names no input is a failure;
``unsettled``
    a :class:`simgrip.settle.SettleError`: non-convergence reported loudly
    within the step budget (a named error, listed with its inputs);
``failed``
    anything else: another exception (NumPy's RuntimeWarnings are raised), a
    ValueError naming no input, a non-finite state, a returned state that is
    not converged (silent non-convergence), or a time-out (:data:`CASE_TIMEOUT_S`,
    a hang).

A settled state is also checked for physically invalid configurations, which
are reported as flags rather than returned quietly:

``self_intersection``
    the centreline crosses itself (a rod curled beyond a full turn passes
    through itself: the chain has no self-collision), :func:`self_intersects`;
``tip_touches_workpiece``
    Grip III: the tip (with the link radius) touches the box,
    :func:`tip_touches_workpiece`; also ``tip_above_contact`` (the paper's
    condition 23 violated);
``beyond_full_turn``
    some link has turned through a full turn or more (``|phi| >= 2 pi``);
``penetration``
    contact penetration above :data:`PENETRATION_TOL` (over ``l``).

Outputs: ``stress.json`` (counts, every case with inputs and outcome, the
failures listed) and ``stability_map.png`` (per grip, ``kappa`` against
``log10 D``: easy, slow, dropped, rejected, unsettled, failed).
"""

from __future__ import annotations

import io as _io
import math
import os
import signal
import time
import traceback
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from simgrip.io import write_json, atomic_write

__all__ = [
    "StressResult",
    "run_stress",
    "make_cases",
    "run_case",
    "self_intersects",
    "tip_touches_workpiece",
    "invalid_state_flags",
    "PENETRATION_TOL",
    "CASE_TIMEOUT_S",
    "MAX_STEPS",
    "RESIDUAL_CAP",
    "names_an_input",
]

#: Contact penetration (over l) above which a settled state is flagged.
PENETRATION_TOL = 1e-3
#: Wall-clock guard of one case (s); a case that runs longer is a failure (hang).
CASE_TIMEOUT_S = 60.0
#: Step budget handed to settle (``None``: settle's own default budget).
MAX_STEPS = None
#: A "converged" state whose static residual exceeds this is a silent non-convergence (failure).
RESIDUAL_CAP = 1e-6
#: A settled case that needed more steps (settle's own count) than this is "slow".
SLOW_STEPS = 5000
#: Parameter box.
BOX = {"D": (1e-2, 1e2), "kappa": (-12.0, 12.0), "M": (0.0, 50.0), "mu_s": (0.05, 5.0), "b": (0.0, 1.0), "n": (4, 256)}
GRIPS = ("free", "I", "II", "III")
PROFILES = ("uniform", "concentrated", "step", "spike", "wiggle")
OUTCOMES = ("settled", "rejected", "unsettled", "failed")
#: Input names a rejection must mention to count as "rejected" (else it is a failure).
INPUT_NAMES = ("grip", "D", "M", "b", "mu_s", "gamma", "kappa", "profile", "links", "n_links", "initial_angles",
               "alpha", "params", "fingers", "r_tip", "r_link", "r_corner", "tol", "max_steps")


def names_an_input(message: str) -> bool:
    """Whether an error message names one of :data:`INPUT_NAMES` as a word."""
    import re

    return any(re.search(rf"(?<![A-Za-z_]){re.escape(k)}(?![A-Za-z_])", message) for k in INPUT_NAMES)


# ---------------------------------------------------------------------------
# profiles and cases


def _profile(kind: str, kappa: float, alpha: float):
    from simgrip.profiles import Concentrated, Uniform, UserProfile

    if kind == "uniform":
        return Uniform(kappa)
    if kind == "concentrated":
        return Concentrated(kappa_max=abs(kappa), alpha=alpha, p=-1 if kappa < 0 else 1)
    if kind == "step":  # the curvature reverses at mid-length
        return UserProfile(lambda s, k=kappa: np.where(np.asarray(s) < 0.5, k, -k), name=f"step({kappa:g})")
    if kind == "spike":  # a narrow Gaussian spike carrying the same total turn as the uniform profile
        w = 0.02
        return UserProfile(
            lambda s, k=kappa: k * np.exp(-0.5 * ((np.asarray(s) - 0.5) / w) ** 2) / (w * math.sqrt(2 * math.pi)),
            name=f"spike({kappa:g})",
        )
    if kind == "wiggle":  # fast oscillation around the uniform profile
        return UserProfile(lambda s, k=kappa: k * (1.0 + 2.0 * np.sin(40.0 * np.pi * np.asarray(s))), name=f"wiggle({kappa:g})")
    raise ValueError(f"profile kind must be one of {PROFILES}, got {kind!r}")


def _grip_sign(grip: str) -> float:
    return 1.0 if grip == "II" else -1.0


def make_cases(cases: int = 500, seed: int = 0, grid_cases: int | None = None, max_links: int = 256) -> list[dict]:
    """The stress cases: a grid (corners and centre of the box) then random draws, ``cases`` in all.

    ``grid_cases`` limits the grid part (evenly spaced through the grid, which
    is interleaved across grips); by default the whole grid comes first.
    ``max_links`` caps ``n`` (random draws in ``[4, max_links]``, grid values clipped).

    Random draws use ``numpy.random.default_rng(seed)``; the curvature's sign
    is drawn freely (wrong-way curls are part of the test).
    """
    if isinstance(cases, bool) or int(cases) != cases or cases < 1:
        raise ValueError(f"cases must be a positive integer, got {cases!r}")
    out: list[dict] = []
    # grid: for each grip, D x kappa at the standard case, plus the extremes of M, mu_s, b, n
    grid = []
    for g in GRIPS:
        s = _grip_sign(g)
        for D in (1e-2, 1.0, 1e2):
            for k in (-12.0, -6.0, 0.0, 6.0, 12.0):
                grid.append(dict(grip=g, D=D, kappa=k, M=5.0, mu_s=1.0, b=0.6, n=16, profile="uniform", alpha=0.0))
        for M in (0.0, 50.0):
            grid.append(dict(grip=g, D=1.0, kappa=6.0 * s, M=M, mu_s=1.0, b=0.6, n=16, profile="uniform", alpha=0.0))
        for mu in (0.05, 5.0):
            grid.append(dict(grip=g, D=1.0, kappa=6.0 * s, M=5.0, mu_s=mu, b=0.6, n=16, profile="uniform", alpha=0.0))
        for b in (0.02, 0.98):
            grid.append(dict(grip=g, D=1.0, kappa=6.0 * s, M=5.0, mu_s=1.0, b=b, n=16, profile="uniform", alpha=0.0))
        for n in (4, 256):
            grid.append(dict(grip=g, D=1.0, kappa=6.0 * s, M=5.0, mu_s=1.0, b=0.6, n=n, profile="uniform", alpha=0.0))
        for kind in PROFILES[1:]:
            grid.append(dict(grip=g, D=1.0, kappa=6.0 * s, M=5.0, mu_s=1.0, b=0.6, n=32, profile=kind, alpha=8.0))
    # interleave the grid across grips so that any prefix covers all four
    per = {g: [c for c in grid if c["grip"] == g] for g in GRIPS}
    grid = [c for row in zip(*per.values()) for c in row]
    if grid_cases is not None:
        k = max(0, min(int(grid_cases), len(grid), int(cases)))
        grid = [grid[int(i)] for i in np.linspace(0, len(grid) - 1, k).round()] if k else []
    rng = np.random.default_rng(seed)
    n_rand = max(0, int(cases) - len(grid))
    for _ in range(n_rand):
        g = GRIPS[int(rng.integers(len(GRIPS)))]
        rec = dict(
            grip=g,
            D=float(10 ** rng.uniform(-2, 2)),
            kappa=float(rng.uniform(*BOX["kappa"])),
            M=float(rng.uniform(*BOX["M"])),
            mu_s=float(10 ** rng.uniform(math.log10(0.05), math.log10(5.0))),
            b=float(rng.uniform(0.01, 0.99)),
            n=int(round(10 ** rng.uniform(math.log10(4), math.log10(max(4, int(max_links)))))),
            profile=PROFILES[int(rng.choice(len(PROFILES), p=[0.5, 0.2, 0.1, 0.1, 0.1]))],
            alpha=float(rng.uniform(0.0, 8.0)),
        )
        out.append(rec)
    allc = grid + out
    allc = allc[: int(cases)] if len(allc) > cases else allc
    for i, c in enumerate(allc):
        c["n"] = min(int(c["n"]), max(4, int(max_links)))
        c["id"] = i
        c["source"] = "grid" if i < len(grid) else "random"
    return allc


# ---------------------------------------------------------------------------
# invalid-state checks


def self_intersects(nodes) -> bool:
    """Whether the centreline polyline ``nodes`` ``(n+1, 2)`` crosses itself (non-adjacent links).

    Vectorised over all pairs of links ``i < j - 1``; touching end points do
    not count (a proper crossing is required).
    """
    P = np.asarray(nodes, dtype=float)
    a, b = P[:-1], P[1:]
    nseg = len(a)
    if nseg < 3:
        return False
    i, j = np.triu_indices(nseg, k=2)

    def orient(u, v, w):
        return (v[:, 0] - u[:, 0]) * (w[:, 1] - u[:, 1]) - (v[:, 1] - u[:, 1]) * (w[:, 0] - u[:, 0])

    d1 = orient(a[j], b[j], a[i])
    d2 = orient(a[j], b[j], b[i])
    d3 = orient(a[i], b[i], a[j])
    d4 = orient(a[i], b[i], b[j])
    return bool(np.any((d1 * d2 < 0) & (d3 * d4 < 0)))


def _point_box_distance(p, centre, half, angle) -> float:
    """Signed distance from a point (x, z) to a rectangle (negative inside)."""
    c, s = math.cos(angle), math.sin(angle)
    d = np.asarray(p, float) - np.asarray(centre, float)
    local = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])
    q = np.abs(local) - np.asarray(half, float)
    outside = float(np.linalg.norm(np.maximum(q, 0.0)))
    inside = float(min(max(q[0], q[1]), 0.0))
    return outside + inside


def tip_touches_workpiece(scene, state, finger: int = 0) -> bool:
    """Grip III: does the finger's tip (a ball of the link radius) touch the workpiece's box?

    Uses the box's half sizes and the settled workpiece pose (in the finger's
    frame, dimensionless).  Always ``False`` for other grips.
    """
    if scene.grip != "III" or state.workpiece_pose is None:
        return False
    L = scene.length
    half = np.array([scene.box_half[0], scene.box_half[2]]) / L
    x, z, ang = state.workpiece_pose
    centre = np.array([scene.mirror[finger] * x, z])
    tip = np.asarray(state.tip[finger], float)
    return _point_box_distance(tip, centre, half, scene.mirror[finger] * ang) <= scene.r_link


def invalid_state_flags(scene, state, *, penetration_tol: float = PENETRATION_TOL) -> dict:
    """Physically invalid features of a settled state: name -> bool (see the module docstring)."""
    flags = {
        "self_intersection": any(self_intersects(state.nodes[f]) for f in range(state.fingers)),
        "penetration": bool(state.penetration > penetration_tol),
        "tip_touches_workpiece": False,
        "tip_above_contact": False,
        "beyond_full_turn": bool(np.max(np.abs(state.link_angles)) >= 2 * math.pi),
    }
    if scene.grip == "III" and state.held:
        flags["tip_touches_workpiece"] = any(tip_touches_workpiece(scene, state, f) for f in range(state.fingers))
        c = state.contact
        if c is not None:
            flags["tip_above_contact"] = bool(state.tip[0][1] >= c.point[1])
    return flags


# ---------------------------------------------------------------------------
# one case


class _Timeout(Exception):
    pass


def _alarm(signum, frame):  # pragma: no cover - only on a hang
    raise _Timeout()


def run_case(case: dict, *, timeout_s: float = CASE_TIMEOUT_S, max_steps: int | None = MAX_STEPS) -> dict:
    """Build and settle one case; return the case with ``outcome``, ``error``, ``steps``, flags..."""
    from simgrip.params import DimensionlessParams
    from simgrip.sim.scene import build_scene
    from simgrip.settle import DEFAULT_TOL, SettleError, settle

    rec = dict(case)
    rec.update(outcome=None, error=None, error_type=None, steps=None, newton=None, time_s=None,
               residual=None, held=None, penetration=None, flags={})
    use_alarm = hasattr(signal, "SIGALRM") and _main_thread()
    old = None
    if use_alarm:
        old = signal.signal(signal.SIGALRM, _alarm)
        signal.setitimer(signal.ITIMER_REAL, timeout_s)
    t0 = time.perf_counter()
    wctx = warnings.catch_warnings()
    wctx.__enter__()
    # a NaN/overflow inside the solvers is a failure with a name, whatever the caller's warning filters
    warnings.simplefilter("error", RuntimeWarning)
    try:
        params = DimensionlessParams(D=case["D"], M=case["M"], b=case["b"], mu_s=case["mu_s"])
        prof = _profile(case["profile"], case["kappa"], case.get("alpha", 0.0))
        scene = build_scene(case["grip"], params, prof, case["n"])
        st = settle(scene) if max_steps is None else settle(scene, max_steps=max_steps)
        rec.update(steps=int(st.steps), newton=int(st.newton_iterations), residual=float(st.residual),
                   held=bool(st.held), penetration=float(st.penetration))
        finite = (np.all(np.isfinite(st.qpos)) and np.all(np.isfinite(st.tip)) and math.isfinite(st.residual)
                  and all(math.isfinite(c.N1) and math.isfinite(c.N2) for c in st.contacts))
        if not finite:
            rec.update(outcome="failed", error="non-finite settled state returned", error_type="NaN")
        elif not st.converged:
            rec.update(outcome="failed", error="state returned with converged=False", error_type="silent")
        elif not st.residual <= RESIDUAL_CAP:
            rec.update(outcome="failed", error=f"converged=True with static residual {st.residual:.3g} > {RESIDUAL_CAP:g}",
                       error_type="silent")
        else:
            rec["outcome"] = "settled"
            rec["flags"] = invalid_state_flags(scene, st)
            rec["residual_above_tol"] = bool(st.residual > DEFAULT_TOL)
    except _Timeout:
        rec.update(outcome="failed", error=f"no answer within {timeout_s:g} s (hang)", error_type="Timeout")
    except ValueError as exc:
        if names_an_input(str(exc)):
            rec.update(outcome="rejected", error=str(exc), error_type=type(exc).__name__)
        else:  # a ValueError from inside the solver, not a rejected input
            rec.update(outcome="failed", error=f"unnamed ValueError: {exc}\n{traceback.format_exc(limit=4)}",
                       error_type=type(exc).__name__)
    except SettleError as exc:
        rec.update(outcome="unsettled", error=str(exc), error_type=type(exc).__name__)
    except Exception as exc:  # noqa: BLE001 - every other error (RuntimeWarning: NaN) is a failure, recorded
        rec.update(outcome="failed", error=f"{exc}\n{traceback.format_exc(limit=4)}", error_type=type(exc).__name__)
    finally:
        wctx.__exit__(None, None, None)
        if use_alarm:
            signal.setitimer(signal.ITIMER_REAL, 0.0)
            signal.signal(signal.SIGALRM, old)
    rec["time_s"] = time.perf_counter() - t0
    return rec


def _main_thread() -> bool:
    import threading

    return threading.current_thread() is threading.main_thread()


def _run_chunk(chunk, timeout_s, max_steps):
    from simgrip.harness.bench import blas_threads

    with blas_threads(1):
        return [run_case(c, timeout_s=timeout_s, max_steps=max_steps) for c in chunk]


# ---------------------------------------------------------------------------
# driver


@dataclass
class StressResult:
    """What :func:`run_stress` found.

    Attributes
    ----------
    cases : list of dict
        Every case with its inputs, ``outcome`` (one of :data:`OUTCOMES`),
        ``error``, ``steps``, ``held``, ``penetration`` and ``flags``.
    counts : dict
        outcome -> number of cases, plus ``flagged`` (settled with any flag)
        and one count per flag.
    failures : list of dict
        The ``failed`` cases (inputs and error).
    files : dict
    """

    cases: list
    counts: dict
    failures: list
    files: dict = field(default_factory=dict)
    elapsed_s: float = 0.0
    jobs: int = 1

    @property
    def unsettled(self) -> list:
        return [c for c in self.cases if c["outcome"] == "unsettled"]

    @property
    def rejected(self) -> list:
        return [c for c in self.cases if c["outcome"] == "rejected"]


def _counts(cases) -> dict:
    counts = {k: 0 for k in OUTCOMES}
    flag_counts: dict = {}
    flagged = 0
    dropped = 0
    for c in cases:
        counts[c["outcome"]] += 1
        if c["outcome"] == "settled":
            if any(c["flags"].values()):
                flagged += 1
            for k, v in c["flags"].items():
                flag_counts[k] = flag_counts.get(k, 0) + int(bool(v))
            if c["grip"] != "free" and c["held"] is False:
                dropped += 1
    counts["total"] = len(cases)
    counts["flagged"] = flagged
    counts["dropped"] = dropped
    counts["flags"] = flag_counts
    counts["residual_above_tol"] = sum(1 for c in cases if c.get("residual_above_tol"))
    return counts


def run_stress(
    out_dir,
    *,
    cases: int = 500,
    seed: int = 0,
    jobs: int | None = None,
    progress: bool = True,
    timeout_s: float = CASE_TIMEOUT_S,
    max_steps: int | None = MAX_STEPS,
    grid_cases: int | None = None,
    max_links: int = 256,
) -> StressResult:
    """Run the stress cases of :func:`make_cases` and write ``stress.json`` and ``stability_map.png``.

    Parameters
    ----------
    out_dir : path
    cases : int
        Number of cases (the grid comes first, then random draws).
    seed : int
        Seed of the random draws.
    jobs : int, optional
        Worker processes (default ``os.cpu_count()``); 1 runs in this process.
        The outcome of every case does not depend on ``jobs``.
    progress : bool
        tqdm progress bar.
    timeout_s, max_steps
        Per-case guards: wall clock (a hang is a failure) and settle's step budget.
    grid_cases : int, optional
        Use only this many (evenly spaced) grid cases; default: the whole grid.
    max_links : int
        Largest ``n`` (256 by default; smaller for quick runs).
    """
    from tqdm import tqdm

    if jobs is not None and (isinstance(jobs, bool) or int(jobs) != jobs or int(jobs) < 1):
        raise ValueError(f"jobs must be a positive integer, got {jobs!r}")
    t0 = time.perf_counter()
    todo = make_cases(cases, seed, grid_cases, max_links)
    workers = min(int(jobs or os.cpu_count() or 1), len(todo))
    done: dict[int, dict] = {}
    with tqdm(total=len(todo), desc="stress", unit="case", disable=not progress) as bar:
        if workers <= 1:
            for c in todo:
                done[c["id"]] = _run_chunk([c], timeout_s, max_steps)[0]
                bar.update()
        else:
            # chunks of a few cases keep the pool's overhead small; heavy cases (large n) first
            order = sorted(todo, key=lambda c: -c["n"])
            chunks = [order[i:i + 4] for i in range(0, len(order), 4)]
            with ProcessPoolExecutor(max_workers=workers) as pool:
                futs = [pool.submit(_run_chunk, ch, timeout_s, max_steps) for ch in chunks]
                for fut in as_completed(futs):
                    for rec in fut.result():
                        done[rec["id"]] = rec
                        bar.update()
    recs = [done[c["id"]] for c in todo]
    counts = _counts(recs)
    failures = [c for c in recs if c["outcome"] == "failed"]
    res = StressResult(cases=recs, counts=counts, failures=failures, elapsed_s=time.perf_counter() - t0, jobs=workers)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "stress.json", {
        "meta": {"cases": len(recs), "seed": seed, "jobs": workers, "elapsed_s": res.elapsed_s,
                 "timeout_s": timeout_s, "max_steps": max_steps, "penetration_tol": PENETRATION_TOL,
                 "residual_cap": RESIDUAL_CAP, "max_links": max_links, "grid_cases": grid_cases,
                 "slow_steps": SLOW_STEPS, "box": BOX},
        "counts": counts,
        "failures": failures,
        "unsettled": res.unsettled,
        "flagged": [c for c in recs if c["outcome"] == "settled" and any(c["flags"].values())],
        "cases": recs,
    })
    _stability_map(recs, out / "stability_map.png")
    res.files = {"stress.json": out / "stress.json", "stability_map.png": out / "stability_map.png"}
    return res


def _category(c) -> str:
    if c["outcome"] != "settled":
        return c["outcome"]
    if c["grip"] != "free" and c["held"] is False:
        return "dropped"
    if any(c["flags"].values()):
        return "flagged"
    return "slow" if (c["steps"] or 0) > SLOW_STEPS else "easy"


_COLORS = {"easy": "tab:green", "slow": "gold", "dropped": "tab:blue", "flagged": "tab:purple",
           "rejected": "0.6", "unsettled": "tab:orange", "failed": "tab:red"}


def _stability_map(recs, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(14, 4.0), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 4, sharey=True)
    for ax, g in zip(axes, GRIPS):
        for cat, col in _COLORS.items():
            pts = [c for c in recs if c["grip"] == g and _category(c) == cat]
            if pts:
                ax.scatter([c["kappa"] for c in pts], [math.log10(c["D"]) for c in pts], s=12,
                           c=col, label=f"{cat} ({len(pts)})", edgecolors="none", alpha=0.8)
        ax.axvline(2 * math.pi, color="k", lw=0.5, ls=":")
        ax.axvline(-2 * math.pi, color="k", lw=0.5, ls=":")
        ax.set_title("free rod" if g == "free" else f"Grip {g}")
        ax.set_xlabel("κ̄0 (peak)")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=6, loc="upper left")
    axes[0].set_ylabel("log10 D")
    fig.suptitle(f"settle stability map: easy (≤ {SLOW_STEPS} steps), slow, dropped workpiece, flagged invalid, "
                 "rejected (ValueError), unsettled (SettleError), failed; dotted: a full turn")
    buf = _io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    with atomic_write(path, "wb") as fh:
        fh.write(buf.getvalue())


def add_arguments(p) -> None:
    """Add ``--cases --seed --out --jobs --no-progress`` to an argparse parser."""
    p.add_argument("--cases", type=int, default=500, help="number of cases [default 500]")
    p.add_argument("--seed", type=int, default=0, help="seed of the random cases [default 0]")
    p.add_argument("--out", default="stress_out", help="output folder [default stress_out]")
    p.add_argument("--jobs", type=int, default=None, help="worker processes [default: all cores]")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def cli_stress(args) -> dict:
    """Run the stress test from parsed arguments; returns the counts and the failures."""
    res = run_stress(args.out, cases=args.cases, seed=args.seed, jobs=args.jobs,
                     progress=not getattr(args, "no_progress", False))
    return {"out": str(args.out), "counts": res.counts,
            "failures": [{k: c[k] for k in ("id", "grip", "D", "kappa", "M", "mu_s", "b", "n", "profile", "error")}
                         for c in res.failures]}

"""The paper's figures 6-9 and 11-16, recomputed from the elastica reference.

Computation and plotting are separate:

* :func:`figure_data` returns the numbers a figure shows (a ``dict`` of NumPy
  arrays and floats, no matplotlib involved), so tests and other tools can
  check them without rendering;
* :func:`plot_figure` turns those numbers into a :class:`matplotlib.figure.Figure`
  (figures 6-9 optionally with simulated points, see ``overlay`` below);
* :func:`simulation_overlay` settles the MuJoCo hinge chain (``links`` links,
  symmetric reduction) at a few ``kappa_bar0`` of figures 6-9, warm-started
  along the sweep, and returns the simulated points in the overlay format;
* :func:`make_figures` computes, plots and writes PNG files, in parallel over
  figures, each figure computed independently (so the files do not depend on
  ``jobs``); figures 6-9 carry the simulation overlay unless ``simulate=False``.

matplotlib is imported lazily inside the plotting functions (``import simgrip``
does not import it) and only its object-oriented API is used (Agg canvas, no
pyplot state).

Conventions: dimensionless units (lengths over ``l``, forces on the rod over
``rho g l``), the finger's base at the origin, ``x`` horizontal along ``E1``,
``z`` vertically **up** (heights ``h`` are positive up, unlike the paper's
Fig. 9, which measures them downwards).  Shape panels draw the pair of fingers
(the computed finger and its mirror image ``x -> -x``).

=====  ===================================================================
name   content
=====  ===================================================================
fig06  free clamped rod, uniform ``kappa_bar0``: (a) no gravity, (b) gravity; D = 1
fig07  Grip I, ``kappa_bar0`` in [0, -6]: shapes (feasible marked ``f``),
       required friction ``M`` vs available ``mu_s N``, tip height ``h``;
       feasible region shaded
fig08  Grip II, ``kappa_bar0`` in [0, 6]: the same three panels
fig09  Grip III, ``kappa_bar0`` in [0, -10], ``gamma = 0.8``: shapes, friction
       ``|f|`` needed vs ``mu_s n`` available, heights ``h`` (tip) and
       ``h_gamma`` (contact); feasible region shaded
fig11  smallest eigenvalue of ``E^T L E`` along the sweeps of Figs. 7-9
fig12  concentrated profile (34), ``kappa_max = 6``, ``p = -1``, alpha in [1, 3]:
       the profile and the free heavy rod's shape
fig13  Grip I with profile (34), alpha in [1, 3]: shapes, load capacity
       ``mu_s N``, smallest eigenvalue
fig14  Grip II with profile (34) (``p = +1``): the same three panels
fig15  Grip III with profile (34): shapes, load capacity (largest ``|N2| = M``
       held, see the caption of the paper's Fig. 15), smallest eigenvalue
fig16  (a) least ``mu_s = |f|/n`` to hold ``M = 5`` (gaps: no normal force, or
       Grip III's tip above the contact), (b) largest ``M`` held at
       ``mu_s = 1`` (``N`` depends on ``M``: continuation in ``M`` from 0 up to
       the first loss of feasibility, or to the fold where the palm-up finger
       snaps through -- hollow markers); the three grips vs ``|kappa_bar0|``
=====  ===================================================================

Overlay (figures 6-9)
---------------------
``plot_figure(name, data, overlay=...)`` draws simulated points (e.g. from the
MuJoCo model) over the reference curves; :func:`simulation_overlay` computes
one from the MuJoCo hinge chain (what ``make_figures(simulate=True)`` and
``simgrip figures`` draw).  ``overlay`` is a ``dict``; every key but
``"kappa"`` is optional and skipped when absent:

=========================  ===================================================
key                        meaning
=========================  ===================================================
``"kappa"``                ``kappa_bar0`` of each simulated point, shape (n,)
``"label"``                legend label (default ``"simulation"``)
``"shapes"``               list of ``(x, z)`` array pairs (finger centrelines),
                           drawn as markers on the shape panel
``"tip_x"``, ``"tip_z"``   fig06: tip positions (panel (b), or (a) when
                           ``overlay["gravity"]`` is False)
``"a"``, ``"b"``           fig06: per-panel dicts with ``"tip_x"``, ``"tip_z"``,
                           ``"shapes"`` (instead of the keys above): (a) without,
                           (b) with gravity
``"muN"``, ``"h"``         fig07/fig08: available friction ``mu_s N`` and tip height
``"f"``, ``"mu_n"``,       fig09: ``|f|``, ``mu_s n``, tip height and contact
``"h"``, ``"h_gamma"``     height
``"held"``                 fig07-09: bool (n,), the simulation holds the
                           workpiece.  Values are drawn (filled markers) only
                           where held; panel (b) gets a row of verdict markers
                           along its bottom: filled triangle held, hollow
                           circle dropped, cross (with ``"feasible"`` False)
                           held but infeasible -- compare with the shading
``"feasible"``             fig07-09: bool (n,), the simulation's verdict in the
                           caption's terms (default ``"held"``)
``"failed"``               bool (n,): points whose settle failed (NaN values);
                           listed in the legend, never dropped silently
=========================  ===================================================
"""

from __future__ import annotations

import math
import os
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

from simgrip.params import STANDARD, DimensionlessParams
from simgrip.profiles import Concentrated, Uniform

__all__ = ["FIGURES", "figure_data", "plot_figure", "make_figures", "save_figure", "simulation_overlay"]

#: Figure names, in the paper's order, with a one-line description.
FIGURES = {
    "fig06": "free clamped rod with uniform intrinsic curvature, without and with gravity",
    "fig07": "Grip I (palm down) vs kappa_bar0 in [0, -6]",
    "fig08": "Grip II (palm up) vs kappa_bar0 in [0, 6]",
    "fig09": "Grip III (cradle, gamma = 0.8) vs kappa_bar0 in [0, -10]",
    "fig11": "smallest eigenvalue of E^T L E along the sweeps of Figs. 7-9",
    "fig12": "concentrated profile (34), kappa_max = 6: profile and free heavy rod",
    "fig13": "Grip I with profile (34), alpha in [1, 3]",
    "fig14": "Grip II with profile (34), alpha in [1, 3]",
    "fig15": "Grip III with profile (34), alpha in [1, 3]",
    "fig16": "least mu_s for M = 5 and largest M at mu_s = 1, three grips",
}

# Rough relative cost, used to submit the slow figures first.
_COST = {"fig16": 10, "fig11": 8, "fig15": 6, "fig13": 4, "fig14": 4, "fig09": 3,
         "fig07": 2, "fig08": 2, "fig06": 2, "fig12": 1}

# Resolution of the sweeps (points per curve).
_N_KAPPA = {"I": 49, "II": 49, "III": 41}  # Figs. 7-9, 16 (steps of 1/8 and 1/4)
_N_SHAPES = {"I": 7, "II": 7, "III": 6}      # shapes drawn (at integer / even kappa_bar0)
_N_KAPPA_STAB = 25     # Fig. 11 (each point also solves the discrete problem)
_LOAD_EVERY = 2        # Fig. 16 (b): every 2nd point of the sweep (each is a continuation in M)
_N_ALPHA = 21          # Figs. 13-15 capacity curves
_N_ALPHA_STAB = 11     # Figs. 13-15 eigenvalue curves
_N_RAMP = 13           # continuation steps in kappa_max before an alpha sweep
_K_DISCRETE = 60       # elements of the discrete stability problem (gamma K integer for gamma = 0.8)
_N_SHAPE = 101         # points per stored centreline
_TOL = 1e-8            # solve_bvp tolerance (8 digits; the 1e-10 default is ~10x slower)
_TOL_LOAD = 1e-6       # tolerance of the load search's many probe solves (plot accuracy)
_M_MAX = 200.0         # largest load tried by the load-capacity search
_JUMP = 0.2            # tip displacement between continuation steps taken as a branch jump

_KAPPA_RANGE = {"I": (0.0, -6.0), "II": (0.0, 6.0), "III": (0.0, -10.0)}
_ALPHAS_SHAPES = (1.0, 1.5, 2.0, 2.5, 3.0)
_GRIP_SIGN = {"I": -1, "II": 1, "III": -1}
_GRIP_TITLE = {"I": "Grip I (palm down)", "II": "Grip II (palm up)", "III": "Grip III (cradle)"}


def _name(name) -> str:
    """Normalise ``6``, ``"6"``, ``"fig6"``, ``"fig06"`` to ``"fig06"``."""
    s = str(name).strip().lower()
    if s.startswith("fig"):
        s = s[3:]
    try:
        key = f"fig{int(s):02d}"
    except ValueError:
        key = None
    if key not in FIGURES:
        raise ValueError(f"unknown figure {name!r}; known: {', '.join(FIGURES)}")
    return key


# ---------------------------------------------------------------------------
# computation
# ---------------------------------------------------------------------------

def _field(sol, name, default=np.nan) -> float:
    v = getattr(sol, name, default)
    try:
        return float(v)
    except (TypeError, ValueError):
        return default


def _ok(sol) -> bool:
    return sol is not None and bool(getattr(sol, "success", True))


def _resample(sol, n=_N_SHAPE):
    """Centreline ``(x, z)`` of a solution on ``n`` equally spaced arc lengths."""
    if not _ok(sol):
        return np.full(n, np.nan), np.full(n, np.nan)
    s = np.asarray(sol.s, dtype=float)
    x = np.asarray(sol.x, dtype=float)
    z = np.asarray(sol.y, dtype=float)
    # drop repeated nodes (a two-segment solution may repeat s = gamma)
    keep = np.concatenate([[True], np.diff(s) > 0])
    sg = np.linspace(s[0], s[-1], n)
    return np.interp(sg, s[keep], x[keep]), np.interp(sg, s[keep], z[keep])


def _sweep_arrays(sols, grip: str, params: DimensionlessParams) -> dict:
    """Forces, heights, feasibility and shapes of a list of solutions (failed ones become NaN)."""
    n = len(sols)
    ok = np.array([_ok(s) for s in sols], dtype=bool)
    get = lambda f: np.array([_field(s, f) if o else np.nan for s, o in zip(sols, ok)])  # noqa: E731
    out = {"success": ok, "N1": get("N1"), "N2": get("N2"), "n": get("n"), "f": get("f")}
    out["h"] = np.array([float(np.asarray(s.tip)[1]) if o else np.nan for s, o in zip(sols, ok)])
    if grip == "III":
        out["h_gamma"] = np.array([float(np.asarray(s.contact)[1]) if o else np.nan for s, o in zip(sols, ok)])
        out["x_gamma"] = np.array([float(np.asarray(s.contact)[0]) if o else np.nan for s, o in zip(sols, ok)])
    shapes = [_resample(s) for s in sols]
    out["shape_x"] = np.array([p[0] for p in shapes]).reshape(n, _N_SHAPE)
    out["shape_z"] = np.array([p[1] for p in shapes]).reshape(n, _N_SHAPE)
    out["solver_feasible"] = np.array([bool(getattr(s, "feasible", False)) and o for s, o in zip(sols, ok)])
    mu = params.mu_s
    with np.errstate(invalid="ignore"):
        if grip in ("I", "II"):
            out["N"] = out["N1"]
            out["required"] = np.abs(out["N2"])          # |F_f| = M
            out["available"] = mu * out["N1"]            # mu_s N
            out["feasible"] = ok & (out["N1"] > 0) & (out["required"] <= out["available"])
            out["least_mu"] = np.where(out["N1"] > 0, out["required"] / out["N1"], np.nan)
        elif grip == "III":
            out["required"] = np.abs(out["f"])           # |f|
            out["available"] = mu * out["n"]             # mu_s n
            out["tip_below_contact"] = ok & (out["h"] < out["h_gamma"])
            out["friction_ok"] = ok & (out["n"] > 0) & (out["required"] <= out["available"])
            out["feasible"] = out["friction_ok"] & out["tip_below_contact"]
            out["least_mu"] = np.where(out["n"] > 0, out["required"] / out["n"], np.nan)
    return out


def _solve(grip, params, profile, guess=None, *, gravity=True, tol=_TOL, fallback=True):
    """:func:`simgrip.reference.elastica.solve` at ``tol``; ``None`` when it fails."""
    from simgrip.reference import elastica

    try:
        return elastica.solve(grip, params, profile, gravity=gravity, guess=guess, tol=tol, fallback=fallback)
    except (elastica.ElasticaError, ArithmeticError, np.linalg.LinAlgError):
        return None


def _warm_solve(grip, params, profile, guess):
    """One Newton run of ``solve_bvp`` from ``guess``, without the solver's fallback strategies.

    Deterministic and fast; ``None`` when it does not converge (e.g. past a fold,
    where a full solve would search for a distant branch).
    """
    return _solve(grip, params, profile, guess, tol=_TOL_LOAD, fallback=False)


def _sweep(grip, params, profiles, *, gravity=True, start=None):
    """Continuation along ``profiles`` (each solve warm-started from the last success);
    failed points are ``None`` instead of aborting the whole sweep."""
    out, prev = [], start
    for prof in profiles:
        sol = _solve(grip, params, prof, prev, gravity=gravity)
        out.append(sol)
        if sol is not None:
            prev = sol
    return out


def _kappa_sweep(grip, params, kappas):
    return _sweep(grip, params, [Uniform(float(k)) for k in kappas])


def _alpha_profiles(grip, alphas, kappa_max=6.0, n_ramp=_N_RAMP):
    """Continuation path: ramp kappa_max at alpha = alphas[0], then sweep alpha."""
    p = _GRIP_SIGN.get(grip, -1)
    ramp = [Concentrated(kappa_max * t, float(alphas[0]), p) for t in np.linspace(0.0, 1.0, n_ramp)[:-1]]
    return ramp, [Concentrated(kappa_max, float(a), p) for a in alphas]


def _alpha_sweep(grip, params, alphas, kappa_max=6.0, gravity=True):
    ramp, profiles = _alpha_profiles(grip, alphas, kappa_max)
    sols = _sweep(grip, params, ramp + profiles, gravity=gravity)
    return sols[len(ramp):], profiles


def _margin(sol, grip, mu) -> float:
    """Feasibility margin, >= 0 iff the grip holds (the captions' criteria):
    ``min(mu_s n - |f|, n)``, and for Grip III also ``h_gamma - h`` (tip below contact)."""
    terms = [mu * sol.normal_force - abs(sol.friction_force), sol.normal_force]
    if grip == "III":
        terms.append(float(sol.contact[1]) - float(sol.tip[1]))
    return float(min(terms))


def _largest_load(grip, params, profile, base, *, start=None, M_max=_M_MAX, iterations=10):
    """Largest load ``M`` held at ``params.mu_s`` (the contact force depends on ``M``).

    Continuation in ``M`` upwards from 0, starting from ``base`` (a solution of the
    same grip and profile), until the first feasible -> infeasible transition, the
    end of the solution branch (a fold: no nearby solution, or a jump of the tip
    to another branch, i.e. the finger snaps through) or ``M_max``; the transition
    is then located by bisection.  Returns ``(M, reason)``: ``M`` is 0.0 when no
    load is held, ``inf`` when ``M_max`` is still held, NaN when even ``M = 0``
    cannot be solved; ``reason`` is ``"friction"`` (the margin crosses zero),
    ``"fold"`` (the branch ends: the finger snaps through), ``"limit"`` or ``"none"``.

    ``start = (M, solution)`` (the last feasible point of a neighbouring profile,
    as returned in the third item) starts the march there instead of at 0 when
    that load is still held: one search per point of a sweep then takes a few
    probes instead of a march from 0.  Returns ``(M, reason, (M_ok, sol_ok))``.
    """
    mu = params.mu_s

    def probe(M, guess):
        s = _warm_solve(grip, params.replace(M=M), profile, guess)
        if s is not None and np.hypot(*(np.asarray(s.tip) - np.asarray(guess.tip))) > _JUMP:
            return None
        return s

    s0 = None
    if start is not None and start[1] is not None and start[0] > 0:
        s0 = _warm_solve(grip, params.replace(M=start[0]), profile, start[1])
        if s0 is not None and _margin(s0, grip, mu) >= 0:
            M, sol = float(start[0]), s0
        else:
            s0 = None
    if s0 is None:
        s0 = _solve(grip, params.replace(M=0.0), profile, base, tol=_TOL_LOAD)
        if s0 is None:
            return math.nan, "none", None
        M, sol = 0.0, s0
    ok_M, ok_sol = (M, s0) if _margin(s0, grip, mu) >= 0 else (None, None)
    bad_M = reason = None
    while M < M_max:
        Mn = min(M_max, M + max(0.5, 0.25 * M))
        sn = probe(Mn, sol)
        if sn is not None and _margin(sn, grip, mu) >= 0:
            ok_M, ok_sol = Mn, sn
        elif ok_M is not None:
            bad_M, reason = Mn, "fold" if sn is None else "friction"
            break
        if sn is None:  # branch ends before any feasible load
            return 0.0, "none", None
        M, sol = Mn, sn
    if ok_M is None:
        return 0.0, "none", None
    if bad_M is None:
        return math.inf, "limit", (ok_M, ok_sol)
    lo, hi, g = ok_M, bad_M, ok_sol
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        sm = probe(mid, g)
        if sm is not None and _margin(sm, grip, mu) >= 0:
            lo, g = mid, sm
        else:
            hi, reason = mid, "fold" if sm is None else "friction"
    return lo, reason, (lo, g)


def _track_loads(grip, params, profiles, bases):
    """:func:`_largest_load` along a sweep, each search started from the previous one's result."""
    out, start = [], None
    for prof, base in zip(profiles, bases):
        if base is None:
            out.append((math.nan, "none"))
            continue
        M, reason, start = _largest_load(grip, params, prof, base, start=start)
        out.append((M, reason))
    return out


def _min_eigenvalues(grip, params, profiles, guesses, K=_K_DISCRETE, gravity=True) -> np.ndarray:
    """Smallest eigenvalue of ``E^T L E`` (paper Section 4) of the discrete problem with
    ``K`` elements, started from the continuous solutions ``guesses`` (NaN where a solve fails)."""
    from simgrip.reference import discrete

    out = np.full(len(profiles), np.nan)
    for i, (prof, g) in enumerate(zip(profiles, guesses)):
        if g is None:
            continue
        try:
            d = discrete.discrete_from_continuous(g, grip, params, prof, K)
        except (discrete.DiscreteError, ArithmeticError, np.linalg.LinAlgError):
            continue
        if d.success:
            out[i] = float(d.min_eigenvalue)
    return out


def _data_fig06(params):
    kappas = np.array([-6.0, -4.0, -2.0, 0.0, 2.0, 4.0, 6.0])
    data = {"kappa": kappas, "D": params.D}
    for panel, gravity in (("a", False), ("b", True)):
        # continue outwards from the straight rod in both directions
        sols = {}
        for end in (kappas[0], kappas[-1]):
            ks = np.linspace(0.0, end, 13)
            for k, s in zip(ks, _sweep("free", params, [Uniform(float(k)) for k in ks], gravity=gravity)):
                sols[round(float(k), 9)] = s
        xs, zs = zip(*(_resample(sols[round(float(k), 9)]) for k in kappas))
        data[f"x_{panel}"] = np.array(xs)
        data[f"z_{panel}"] = np.array(zs)
    return data


def _data_grip_sweep(grip, params):
    lo, hi = _KAPPA_RANGE[grip]
    kappas = np.linspace(lo, hi, _N_KAPPA[grip])
    data = {"grip": grip, "kappa": kappas, "M": params.M, "mu_s": params.mu_s, "b": params.b,
            "D": params.D, "gamma": params.gamma}
    data.update(_sweep_arrays(_kappa_sweep(grip, params, kappas), grip, params))
    return data


def _data_fig11(params):
    data = {"M": params.M, "mu_s": params.mu_s, "b": params.b, "D": params.D, "gamma": params.gamma,
            "K": _K_DISCRETE}
    for grip in ("I", "II", "III"):
        lo, hi = _KAPPA_RANGE[grip]
        kappas = np.linspace(lo, hi, _N_KAPPA_STAB)
        sols = _kappa_sweep(grip, params, kappas)
        arr = _sweep_arrays(sols, grip, params)
        data[f"kappa_{grip}"] = kappas
        data[f"lambda_min_{grip}"] = _min_eigenvalues(grip, params, [Uniform(k) for k in kappas], sols)
        data[f"feasible_{grip}"] = arr["feasible"]
    return data


def _data_fig12(params):
    alphas = np.array(_ALPHAS_SHAPES)
    s = np.linspace(0.0, 1.0, _N_SHAPE)
    sols, profiles = _alpha_sweep("free", params, alphas, gravity=True)
    xs, zs = zip(*(_resample(sol) for sol in sols))
    return {"alpha": alphas, "kappa_max": 6.0, "p": -1, "D": params.D, "s": s,
            "profile": np.array([prof(s) for prof in profiles]), "x": np.array(xs), "z": np.array(zs)}


def _data_alpha(grip, params):
    alphas = np.linspace(1.0, 3.0, _N_ALPHA)
    sols, profiles = _alpha_sweep(grip, params, alphas)
    arr = _sweep_arrays(sols, grip, params)
    data = {"grip": grip, "alpha": alphas, "M": params.M, "mu_s": params.mu_s, "b": params.b,
            "D": params.D, "gamma": params.gamma, "kappa_max": 6.0, "p": _GRIP_SIGN[grip],
            "K": _K_DISCRETE}
    data.update(arr)
    # shapes at a few alphas
    idx = [int(np.argmin(np.abs(alphas - a))) for a in _ALPHAS_SHAPES]
    data["shape_index"] = np.array(idx)
    # stability on a coarser set of alphas
    stab = np.linspace(0, _N_ALPHA - 1, _N_ALPHA_STAB).round().astype(int)
    data["alpha_stab"] = alphas[stab]
    data["lambda_min"] = _min_eigenvalues(grip, params, [profiles[i] for i in stab], [sols[i] for i in stab])
    if grip == "III":
        # load capacity: the largest |N2| = M the grip holds at mu_s (caption of Fig. 15)
        data["alpha_capacity"] = alphas
        res = _track_loads(grip, params, profiles, sols)
        data["capacity"] = np.array([r[0] for r in res])
        data["capacity_reason"] = np.array([r[1] for r in res])
    else:
        # load capacity: the largest friction force mu_s N at the standard load M
        data["alpha_capacity"] = alphas
        data["capacity"] = arr["available"]
    # reference: the uniform profile with the same peak curvature (alpha = 0)
    kap = _GRIP_SIGN[grip] * data["kappa_max"]
    uni = _kappa_sweep(grip, params, np.linspace(0.0, kap, 13))[-1]
    if uni is None:
        data["uniform_capacity"] = math.nan
    elif grip == "III":
        data["uniform_capacity"] = _largest_load(grip, params, Uniform(kap), uni)[0]
    else:
        data["uniform_capacity"] = params.mu_s * uni.normal_force
    return data


def _data_fig16(params):
    data = {"M": params.M, "mu_s": params.mu_s, "b": params.b, "D": params.D, "gamma": params.gamma,
            "M_max": _M_MAX}
    p1 = params.replace(mu_s=1.0)
    for grip in ("I", "II", "III"):
        lo, hi = _KAPPA_RANGE[grip]
        kappas = np.linspace(lo, hi, _N_KAPPA[grip])
        sols = _kappa_sweep(grip, params, kappas)
        arr = _sweep_arrays(sols, grip, params)
        lm = arr["least_mu"]
        if grip == "III":  # the grip only holds where the tip stays below the contact
            lm = np.where(arr["tip_below_contact"], lm, np.nan)
        data[f"kappa_{grip}"] = kappas
        data[f"least_mu_{grip}"] = lm
        sel = np.arange(0, len(kappas), _LOAD_EVERY)
        data[f"kappa_load_{grip}"] = kappas[sel]
        res = _track_loads(grip, p1, [Uniform(float(kappas[i])) for i in sel], [sols[i] for i in sel])
        data[f"max_load_{grip}"] = np.array([r[0] for r in res])
        data[f"max_load_reason_{grip}"] = np.array([r[1] for r in res])
    return data


def figure_data(name, *, params: DimensionlessParams | None = None) -> dict:
    """Compute the numbers shown by figure ``name`` (``"fig06"`` ... ``"fig16"``, or ``6``).

    Parameters
    ----------
    name : str or int
        One of :data:`FIGURES`.
    params : DimensionlessParams, optional
        Defaults to the paper's standard case :data:`simgrip.params.STANDARD`
        (D = 1, M = 5, mu_s = 1, b = 0.6, gamma = 0.8).

    Returns
    -------
    dict
        NumPy arrays and floats; ``"name"`` is the normalised figure name.
        Sweep figures (7-9) hold ``kappa``, ``N1``, ``N2``, ``n``, ``f``, ``h``
        (tip height, z up), ``required`` / ``available`` friction,
        ``feasible`` (the shaded region), ``shape_x``/``shape_z`` (n_kappa x 101)
        and, for Grip III, ``h_gamma`` and ``tip_below_contact``.
    """
    key = _name(name)
    params = STANDARD if params is None else params
    if key == "fig06":
        data = _data_fig06(params)
    elif key in ("fig07", "fig08", "fig09"):
        data = _data_grip_sweep({"fig07": "I", "fig08": "II", "fig09": "III"}[key], params)
    elif key == "fig11":
        data = _data_fig11(params)
    elif key == "fig12":
        data = _data_fig12(params)
    elif key in ("fig13", "fig14", "fig15"):
        data = _data_alpha({"fig13": "I", "fig14": "II", "fig15": "III"}[key], params)
    else:
        data = _data_fig16(params)
    data["name"] = key
    return data


# ---------------------------------------------------------------------------
# simulation overlay (MuJoCo hinge chain on Figs. 6-9)
# ---------------------------------------------------------------------------

#: kappa_bar0 of the simulated points.  Integer values coincide with the
#: reference shapes the figures draw; Grips I/II add half steps where the grip
#: holds (the feasible interval is only ~1.25 wide), Grip III adds -3 and -5.
_SIM_KAPPA = {
    "free": (-6.0, -4.0, -2.0, 0.0, 2.0, 4.0, 6.0),
    "I": (0.0, -1.0, -2.0, -3.0, -4.0, -5.0, -5.5, -6.0),
    "II": (0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 5.5, 6.0),
    "III": (0.0, -2.0, -3.0, -4.0, -5.0, -6.0, -8.0, -10.0),
}
_SIM_LABEL = "MuJoCo chain, n = {links}"
_FIG_GRIP = {"fig07": "I", "fig08": "II", "fig09": "III"}
_OVERLAY_FIGURES = ("fig06", "fig07", "fig08", "fig09")


def _sim_scene(grip, params, kappa, links, gravity):
    import mujoco

    from simgrip.sim.scene import build_scene

    scene = build_scene(grip, params, Uniform(float(kappa)), links)
    if not gravity:
        scene.model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_GRAVITY)
    return scene


def _sim_sweep(grip, params, kappas, links, *, gravity=True):
    """Settled states along ``kappas`` (in that order), warm-started.

    Each point starts from the previous equilibrium (the continuation of
    :func:`simgrip.settle.settle_sweep`) while that one holds the workpiece (a
    free rod always continues); after a drop -- where ``settle_sweep`` would
    keep the workpiece dropped -- and whenever a warm start fails, the point is
    settled cold in a freshly built scene (Grips I/II: the closing procedure;
    Grip III: the corner placed at ``params.gamma``), so that hold/drop is
    decided at every point.  Returns ``(states, errors)``: ``states[i]`` is
    ``None`` where even the cold settle failed, ``errors[i]`` the message(s).
    """
    from simgrip.sim.scene import set_curvature
    from simgrip.settle import SettleError, settle

    states, errors = [], []
    scene = prev = None
    for k in kappas:
        st, msg = None, []
        if prev is not None and (grip == "free" or prev.held):
            try:
                set_curvature(scene, Uniform(float(k)))
                st = settle(scene, warm_start=prev)
            except (SettleError, ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                msg.append(f"warm start: {type(exc).__name__}: {exc}")
                st = None
        if st is None:
            try:
                scene = _sim_scene(grip, params, k, links, gravity)
                st = settle(scene)
            except (SettleError, ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                msg.append(f"cold start: {type(exc).__name__}: {exc}")
                st = None
        states.append(st)
        errors.append("; ".join(msg))
        prev = st
    return states, errors


def _nodes(st):
    nodes = np.asarray(st.nodes[0], dtype=float)
    return nodes[:, 0].copy(), nodes[:, 1].copy()


def _overlay_free(params, links, kappas):
    kappas = np.asarray(sorted(kappas), dtype=float)
    out = {"kappa": kappas, "links": int(links), "label": _SIM_LABEL.format(links=links)}
    failed = np.zeros(len(kappas), dtype=bool)
    errors = [""] * len(kappas)
    for panel, gravity in (("a", False), ("b", True)):
        # continue outwards from the straight rod in both directions (as the reference does)
        neg = [i for i, k in enumerate(kappas) if k <= 0][::-1]
        pos = [i for i, k in enumerate(kappas) if k >= 0]
        states = [None] * len(kappas)
        for order in (neg, pos):
            if not order:
                continue
            sts, errs = _sim_sweep("free", params, kappas[order], links, gravity=gravity)
            for i, s, e in zip(order, sts, errs):
                if order is pos and kappas[i] == 0 and neg:
                    continue  # already settled by the sweep towards negative kappa
                states[i] = s
                if e:
                    errors[i] = (errors[i] + f"; ({panel}) " if errors[i] else f"({panel}) ") + e
        tip = np.array([s.tip[0] if s is not None else (np.nan, np.nan) for s in states], dtype=float)
        failed |= np.array([s is None for s in states])
        out[panel] = {
            "tip_x": tip[:, 0], "tip_z": tip[:, 1],
            "shapes": [_nodes(s) for s in states if s is not None],
            "gravity": gravity,
        }
    out["failed"] = failed
    out["errors"] = errors
    return out


def _overlay_grip(grip, params, links, kappas):
    kappas = np.asarray(kappas, dtype=float)
    states, errors = _sim_sweep(grip, params, kappas, links)
    n = len(kappas)
    nan = np.full(n, np.nan)
    failed = np.array([s is None for s in states])
    held = np.array([s is not None and bool(s.held) and s.contact is not None for s in states])
    tip = np.array([s.tip[0] if s is not None else (np.nan, np.nan) for s in states], dtype=float)
    out = {"kappa": kappas, "grip": grip, "links": int(links), "label": _SIM_LABEL.format(links=links),
           "held": held, "failed": failed, "errors": errors, "tip_x": tip[:, 0], "tip_z": tip[:, 1],
           "residual": np.array([s.residual if s is not None else np.nan for s in states])}
    c = [s.contact if h else None for s, h in zip(states, held)]
    pick = lambda f: np.array([f(ci) if ci is not None else np.nan for ci in c], dtype=float)  # noqa: E731
    out["N1"], out["N2"] = pick(lambda ci: ci.N1), pick(lambda ci: ci.N2)
    out["n"], out["f_signed"] = pick(lambda ci: ci.normal), pick(lambda ci: ci.friction)
    out["gamma"] = pick(lambda ci: ci.gamma)
    out["contact_moment"] = pick(lambda ci: ci.moment)
    out["h"] = np.where(held, tip[:, 1], nan)
    mu = params.mu_s
    if grip in ("I", "II"):
        out["muN"] = mu * out["N1"]
        out["feasible"] = held  # the simulation's verdict: the workpiece is held
    else:
        out["f"] = np.abs(out["f_signed"])
        out["mu_n"] = mu * out["n"]
        out["x_gamma"] = pick(lambda ci: float(ci.point[0]))
        out["h_gamma"] = pick(lambda ci: float(ci.point[1]))
        with np.errstate(invalid="ignore"):
            out["tip_below_contact"] = held & (out["h"] < out["h_gamma"])
        # the sim's box is not a collider for the tip: condition (23) is checked on its geometry
        out["feasible"] = out["tip_below_contact"]
    # shapes: held states at the kappas the reference panel draws (integers; even for Grip III)
    step = 2.0 if grip == "III" else 1.0
    out["shape_kappa"] = np.array([k for k, h in zip(kappas, held) if h and float(k / step).is_integer()])
    out["shapes"] = [_nodes(s) for k, s, h in zip(kappas, states, held) if h and float(k / step).is_integer()]
    return out


def simulation_overlay(name, *, links: int = 16, params: DimensionlessParams | None = None,
                       kappas=None) -> dict:
    """Simulated points (MuJoCo hinge chain, symmetric reduction) for figure ``name`` (6-9).

    Settles the chain of ``links`` links per finger at a few ``kappa_bar0``
    (default :data:`_SIM_KAPPA`, 7-8 values across the figure's range),
    warm-started along the sweep (see :func:`_sim_sweep`), and returns the
    ``overlay`` :func:`plot_figure` draws (see the module docstring), plus:

    * ``"failed"`` (bool per point): the settle failed even from a cold start;
      its numbers are NaN and ``"errors"[i]`` says why (drawn as a note in
      the figure: never silent);
    * Figs. 7-9: ``"held"`` -- the simulation holds the workpiece.  Force and
      height values are NaN where it dropped it (the state is then the free
      finger, not a grip); ``"tip_x"``/``"tip_z"`` are the tips of every state.
      ``"feasible"`` is the simulation's verdict in the caption's terms (Grip
      III: held *and* the tip below the contact, condition (23), measured on
      the simulated shape: the box is not a collider for the finger's tip);
      ``"N1"``, ``"N2"``, ``"n"``, ``"f_signed"``, ``"gamma"``,
      ``"contact_moment"`` (and ``"x_gamma"`` for Grip III) the raw contact;
    * Fig. 6: ``"a"`` (gravity off, ``mjDSBL_GRAVITY``) and ``"b"`` (gravity
      on), each with ``"tip_x"``, ``"tip_z"``, ``"shapes"``.

    Shapes are the chain's ``links + 1`` nodes, finger 0's frame (``x`` along
    ``E1``, ``z`` up, base at the origin).
    """
    from simgrip.chain import check_links

    key = _name(name)
    if key not in _OVERLAY_FIGURES:
        raise ValueError(f"simulation overlays exist for fig06-fig09 only, not {key}")
    links = check_links(links)
    params = STANDARD if params is None else params
    if key == "fig06":
        return _overlay_free(params, links, _SIM_KAPPA["free"] if kappas is None else kappas)
    grip = _FIG_GRIP[key]
    return _overlay_grip(grip, params, links, _SIM_KAPPA[grip] if kappas is None else kappas)


# ---------------------------------------------------------------------------
# plotting
# ---------------------------------------------------------------------------

_KBAR = r"\bar{\kappa}_0"


def _new_figure(ncols, width=4.3, height=3.9):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width * ncols, height), layout="constrained")
    FigureCanvasAgg(fig)
    axes = [fig.add_subplot(1, ncols, i + 1) for i in range(ncols)]
    return fig, axes


def _cmap(n, name="viridis", lo=0.0, hi=0.9):
    import matplotlib

    cm = matplotlib.colormaps[name]
    return [cm(v) for v in np.linspace(lo, hi, max(n, 1))]


def _shade(ax, x, mask, label="feasible"):
    """Shade the x-intervals where ``mask`` holds (full height of the axes)."""
    mask = np.asarray(mask, dtype=bool)
    if not mask.any():
        return
    ax.fill_between(x, 0, 1, where=mask, transform=ax.get_xaxis_transform(), color="tab:green",
                    alpha=0.18, linewidth=0, label=label, step=None, interpolate=False)


def _hatch(ax, x, mask, label="friction suffices, tip above contact"):
    """Hatch the x-intervals where ``mask`` holds (Grip III: |f| <= mu_s n, but (23) fails)."""
    mask = np.asarray(mask, dtype=bool)
    if not mask.any():
        return
    ax.fill_between(x, 0, 1, where=mask, transform=ax.get_xaxis_transform(), facecolor="none",
                    edgecolor="tab:red", alpha=0.35, hatch="///", linewidth=0, label=label)


def _shape_axes(ax, title):
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(r"$x/\ell$ (along $\mathbf{E}_1$)")
    ax.set_ylabel(r"$z/\ell$ (up)")
    ax.set_title(title, fontsize=10)
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.plot([0.0], [0.0], "ks", ms=4, zorder=7)  # the palm (the fingers' base)


def _draw_pair(ax, x, z, color, label=None, lw=1.4):
    ax.plot(x, z, color=color, lw=lw, label=label)
    ax.plot(-np.asarray(x), z, color=color, lw=lw, alpha=0.55)


def _shape_indices(n, count=7):
    return np.unique(np.linspace(0, n - 1, count).round().astype(int))


def _param_text(data, keys=("D", "M", "mu_s", "b")):
    names = {"D": "D", "M": "M", "mu_s": r"\mu_s", "b": r"b/\ell", "gamma": r"\gamma/\ell"}
    return ", ".join(f"${names[k]} = {data[k]:g}$" for k in keys if k in data)


def _overlay_shapes(ax, overlay, label):
    for i, pair in enumerate(overlay.get("shapes") or []):
        x, z = (np.asarray(v, dtype=float) for v in pair)
        ax.plot(x, z, "o", ms=2.5, mfc="none", mew=0.8, color="tab:red", linestyle="none",
                label=label if i == 0 else None)


def _overlay_points(ax, overlay, key, xfun, label, marker="o", color="tab:red"):
    """Simulated values ``overlay[key]`` against ``kappa``; filled markers (NaN: not drawn).

    With ``overlay["held"]`` only the held states are drawn (a dropped state is
    the free finger, not a point of the grip's curves)."""
    if overlay is None or key not in overlay:
        return
    x = xfun(np.asarray(overlay["kappa"], dtype=float))
    y = np.asarray(overlay[key], dtype=float)
    if "held" in overlay:
        y = np.where(np.asarray(overlay["held"], dtype=bool), y, np.nan)
    ax.plot(x, y, marker, color=color, ms=5.5, mec="k", mew=0.7, linestyle="none", label=label, zorder=5)


def _overlay_verdict(ax, overlay, xfun, grip):
    """The simulation's hold/drop verdict as a row of markers along the bottom of ``ax``.

    Filled triangle: the workpiece is held (Grip III: and the tip stays below the
    contact); hollow circle: dropped; cross (Grip III): held, but the tip is above
    the contact (condition (23) fails on the simulated shape); red X: the settle
    failed (also listed in the legend).  Compare with the shaded feasible region.
    """
    if overlay is None or "held" not in overlay:
        return
    import matplotlib.transforms as mtransforms

    tr = mtransforms.blended_transform_factory(ax.transData, ax.transAxes)
    k = np.asarray(overlay["kappa"], dtype=float)
    x = xfun(k)
    held = np.asarray(overlay["held"], dtype=bool)
    failed = np.asarray(overlay.get("failed", np.zeros(len(k), dtype=bool)), dtype=bool)
    feas = np.asarray(overlay.get("feasible", held), dtype=bool) & held
    y = 0.045
    rows = (
        (feas, dict(marker="^", color="k", mfc="k", ms=6), "MuJoCo holds the box"),
        (held & ~feas, dict(marker="x", color="k", ms=6, mew=1.2), "MuJoCo holds, tip above contact"),
        (~held & ~failed, dict(marker="o", color="k", mfc="white", ms=6, mew=1.0), "MuJoCo drops the box"),
        (failed, dict(marker="X", color="tab:red", ms=7), None),
    )
    for mask, style, lab in rows:
        if mask.any():
            ax.plot(x[mask], np.full(mask.sum(), y), linestyle="none", transform=tr, clip_on=False,
                    zorder=6, label=lab, **style)
    if failed.any():
        ks = ", ".join(f"{v:g}" for v in k[failed])
        ax.plot([], [], "X", color="tab:red", ms=7, label=rf"settle failed at ${_KBAR} = {ks}$")


def _overlay_failed_note(ax, overlay, label):
    failed = np.asarray(overlay.get("failed", []), dtype=bool)
    if failed.any():
        ks = ", ".join(f"{v:g}" for v in np.asarray(overlay["kappa"], dtype=float)[failed])
        ax.plot([], [], "X", color="tab:red", ms=7, label=rf"{label}: failed at ${_KBAR} = {ks}$")


def _plot_fig06(data, overlay=None):
    fig, (a, b) = _new_figure(2, width=4.8, height=4.4)
    colors = _cmap(len(data["kappa"]), "coolwarm", 0.0, 1.0)
    for ax, panel, title in ((a, "a", "(a) without gravity"), (b, "b", "(b) with gravity")):
        _shape_axes(ax, title)
        for i, k in enumerate(data["kappa"]):
            ax.plot(data[f"x_{panel}"][i], data[f"z_{panel}"][i], color=colors[i], lw=1.6,
                    label=rf"${_KBAR} = {k:g}$")
        ax.legend(fontsize=7, loc="best")
    if overlay is not None:
        label = overlay.get("label", "simulation")
        if "a" in overlay or "b" in overlay:  # both panels (simulation_overlay("fig06"))
            panels = [(ax, overlay[p]) for ax, p in ((a, "a"), (b, "b")) if p in overlay]
        else:  # one panel, chosen by overlay["gravity"]
            panels = [(a if overlay.get("gravity", True) is False else b, overlay)]
        for ax, sub in panels:
            _overlay_shapes(ax, sub, f"{label} (nodes)")
            if "tip_x" in sub and "tip_z" in sub:
                ax.plot(sub["tip_x"], sub["tip_z"], "o", color="tab:red", mec="k", mew=0.7, ms=6,
                        linestyle="none", label=f"{label} (tips)", zorder=5)
            _overlay_failed_note(ax, overlay, label)
            ax.legend(fontsize=7, loc="lower right")
    fig.suptitle(f"Fig. 6 - free clamped rod, uniform ${_KBAR}$, $D = {data['D']:g}$")
    return fig


def _plot_grip_sweep(data, overlay=None):
    grip = data["grip"]
    num = {"I": 7, "II": 8, "III": 9}[grip]
    sign = _GRIP_SIGN[grip]
    k = np.asarray(data["kappa"])
    xk = sign * k  # plot against |kappa| with the paper's orientation (-kappa for I/III)
    xlabel = rf"$-{_KBAR}$" if sign < 0 else rf"${_KBAR}$"
    xfun = lambda kk: sign * kk  # noqa: E731
    label = (overlay or {}).get("label", "simulation")
    fig, (a, b, c) = _new_figure(3)

    # (a) shapes
    _shape_axes(a, "(a) deformed shapes (thick, f: feasible)")
    idx = _shape_indices(len(k), _N_SHAPES[grip])
    colors = _cmap(len(idx))
    for j, i in enumerate(idx):
        if not data["success"][i]:
            continue
        x, z = data["shape_x"][i], data["shape_z"][i]
        feas = bool(data["feasible"][i])
        _draw_pair(a, x, z, colors[j], label=rf"${_KBAR} = {k[i]:.3g}$" + (" (f)" if feas else ""),
                   lw=2.4 if feas else 1.2)
        if grip == "III":
            a.plot([data["x_gamma"][i], -data["x_gamma"][i]], [data["h_gamma"][i]] * 2, "v",
                   color=colors[j], ms=4)
    half = data["b"] / 2.0
    for xv in (half, -half):
        a.axvline(xv, color="0.5", lw=0.8, ls="--")
    if overlay is not None:
        _overlay_shapes(a, overlay, label)
    # room for the legend on the side away from the palm (below for I/III, above for II)
    zs = np.asarray(data["shape_z"])[np.asarray(data["success"], dtype=bool)]
    lo, hi = (float(np.nanmin(zs)), float(np.nanmax(zs))) if zs.size else (-1.0, 0.0)
    lo, hi = min(lo, 0.0) - 0.05, max(hi, 0.0) + 0.05
    rows = 0.075 * math.ceil((len(idx) + (overlay is not None)) / 2) + 0.06
    # (extend the data limits, not the view limits: the equal aspect adjusts the data limits)
    a.update_datalim([(0.0, lo - rows if sign < 0 else hi + rows)])
    a.autoscale_view()
    if sign < 0:
        a.legend(fontsize=6.5, loc="lower center", ncol=2, columnspacing=0.8, handlelength=1.6)
    else:
        a.legend(fontsize=6.5, loc="upper center", ncol=2, columnspacing=0.8, handlelength=1.6)

    # (b) friction needed vs available
    _shade(b, xk, data["feasible"])
    if grip == "III":  # friction suffices but condition (23) fails: the tip is above the contact
        _hatch(b, xk, np.asarray(data["friction_ok"]) & ~np.asarray(data["tip_below_contact"]))
    if grip == "III":
        b.plot(xk, data["required"], color="tab:blue", label=r"$|f|/\rho g\ell$ needed")
        b.plot(xk, data["available"], color="tab:orange", label=r"$\mu_s n/\rho g\ell$ available")
        b.set_title(r"(b) friction $|f|$ needed vs $\mu_s n$ available", fontsize=10)
        if overlay is not None:
            _overlay_points(b, overlay, "f", xfun, f"{label}: $|f|$", "o", "tab:blue")
            _overlay_points(b, overlay, "mu_n", xfun, rf"{label}: $\mu_s n$", "s", "tab:orange")
    else:
        b.plot(xk, data["required"], color="tab:blue", label=r"$|F_f|/\rho g\ell = M$ needed")
        b.plot(xk, data["available"], color="tab:orange", label=r"$\mu_s N/\rho g\ell$ available")
        b.set_title(r"(b) friction $|F_f|$ needed vs $\mu_s N$ available", fontsize=10)
        if overlay is not None:
            _overlay_points(b, overlay, "muN", xfun, rf"{label}: $\mu_s N$", "s", "tab:orange")
    if overlay is not None:
        _overlay_verdict(b, overlay, xfun, grip)
    b.axhline(0.0, color="0.6", lw=0.6)
    b.set_xlabel(xlabel)
    b.set_ylabel(r"force on the rod $/\rho g\ell$")
    # legend in the upper left, above the curves (room made for Grips I/II, whose M line crosses it)
    if grip != "III":
        y0, y1 = b.get_ylim()
        b.set_ylim(y0, y1 + 0.6 * (y1 - y0))
    b.legend(fontsize=7, loc="upper left")

    # (c) heights
    _shade(c, xk, data["feasible"])
    if grip == "III":
        _hatch(c, xk, np.asarray(data["friction_ok"]) & ~np.asarray(data["tip_below_contact"]))
    c.plot(xk, data["h"], color="tab:purple", label=r"$h$ (tip)")
    if grip == "III":
        c.plot(xk, data["h_gamma"], color="tab:brown", label=r"$h_\gamma$ (contact $s=\gamma$)")
        c.set_title(r"(c) heights $h$ and $h_\gamma$", fontsize=10)
        if overlay is not None:
            _overlay_points(c, overlay, "h", xfun, f"{label}: $h$", "o", "tab:purple")
            _overlay_points(c, overlay, "h_gamma", xfun, rf"{label}: $h_\gamma$", "s", "tab:brown")
    else:
        c.set_title(r"(c) tip height $h$", fontsize=10)
        if overlay is not None:
            _overlay_points(c, overlay, "h", xfun, f"{label}: $h$", "o", "tab:purple")
    c.set_xlabel(xlabel)
    c.set_ylabel(r"height $/\ell$ ($z$ up)")
    c.legend(fontsize=7, loc="lower right" if grip == "III" else "best")

    keys = ("D", "M", "mu_s", "b", "gamma") if grip == "III" else ("D", "M", "mu_s", "b")
    fig.suptitle(f"Fig. {num} - {_GRIP_TITLE[grip]} vs ${_KBAR}$; {_param_text(data, keys)}")
    return fig


def _plot_fig11(data, overlay=None):
    fig, (a, b) = _new_figure(2, width=4.8)
    for grip, color, sign in (("I", "tab:blue", -1), ("II", "tab:orange", 1)):
        kk = np.abs(data[f"kappa_{grip}"])
        a.plot(kk, data[f"lambda_min_{grip}"], "o-", ms=3, color=color,
               label=f"Grip I (${_KBAR} \\leq 0$)" if grip == "I" else f"Grip II (${_KBAR} \\geq 0$)")
    a.set_xlabel(rf"$|{_KBAR}|$")
    a.set_title("(a) Grips I and II (Figs. 7, 8)", fontsize=10)
    _shade(b, -data["kappa_III"], data["feasible_III"])
    b.plot(-data["kappa_III"], data["lambda_min_III"], "o-", ms=3, color="tab:green", label="Grip III")
    b.set_xlabel(rf"$-{_KBAR}$")
    b.set_title(r"(b) Grip III (Fig. 9), $\gamma/\ell = %g$" % data["gamma"], fontsize=10)
    for ax in (a, b):
        ax.axhline(0.0, color="k", lw=0.7, ls=":")
        ax.set_ylabel(r"$\lambda_{\min}(E^T L E)$")
        ax.legend(fontsize=8, loc="best")
    fig.suptitle(f"Fig. 11 - stability along the sweeps of Figs. 7-9 ($K = {data['K']}$); "
                 f"{_param_text(data)}")
    return fig


def _plot_fig12(data, overlay=None):
    fig, (a, b) = _new_figure(2, width=4.8, height=4.2)
    colors = _cmap(len(data["alpha"]))
    for i, al in enumerate(data["alpha"]):
        a.plot(data["s"], data["profile"][i], color=colors[i], label=rf"$\alpha = {al:g}$")
        b.plot(data["x"][i], data["z"][i], color=colors[i], label=rf"$\alpha = {al:g}$")
    a.set_xlabel(r"$\bar{s} = s/\ell$")
    a.set_ylabel(rf"${_KBAR}(\bar{{s}})$")
    a.set_title("(a) intrinsic curvature, eq. (34)", fontsize=10)
    a.legend(fontsize=8)
    _shape_axes(b, "(b) free heavy rod")
    b.legend(fontsize=8)
    fig.suptitle(rf"Fig. 12 - concentrated profile (34): $\bar{{\kappa}}_{{\max}} = {data['kappa_max']:g}$, "
                 rf"$p = {data['p']:d}$, $D = {data['D']:g}$")
    return fig


def _plot_alpha(data, overlay=None):
    grip = data["grip"]
    num = {"I": 13, "II": 14, "III": 15}[grip]
    fig, (a, b, c) = _new_figure(3)
    _shape_axes(a, r"(a) deformed shapes vs $\alpha$")
    colors = _cmap(len(data["shape_index"]))
    for j, i in enumerate(data["shape_index"]):
        if data["success"][i]:
            _draw_pair(a, data["shape_x"][i], data["shape_z"][i], colors[j],
                       label=rf"$\alpha = {data['alpha'][i]:g}$")
            if grip == "III":
                a.plot([data["x_gamma"][i], -data["x_gamma"][i]], [data["h_gamma"][i]] * 2, "v",
                       color=colors[j], ms=4)
    for xv in (data["b"] / 2, -data["b"] / 2):
        a.axvline(xv, color="0.5", lw=0.8, ls="--")
    a.legend(fontsize=7)
    if grip == "III":
        b.plot(data["alpha_capacity"], data["capacity"], "o-", ms=3, color="tab:orange",
               label=r"largest $|N_2|/\rho g\ell = M$ held")
        b.set_title(r"(b) load capacity $|N_2|$ at $\mu_s = %g$" % data["mu_s"], fontsize=10)
        b.set_ylabel(r"$|N_2|/\rho g\ell$")
    else:
        b.plot(data["alpha_capacity"], data["capacity"], "o-", ms=3, color="tab:orange",
               label=r"$\mu_s N/\rho g\ell$ at $M = %g$" % data["M"])
        b.set_title(r"(b) load capacity $\mu_s N$", fontsize=10)
        b.set_ylabel(r"$\mu_s N/\rho g\ell$")
    b.axhline(data["M"], color="tab:blue", ls="--", lw=1, label=f"$M = {data['M']:g}$ (weight per finger)")
    if np.isfinite(data.get("uniform_capacity", np.nan)):
        b.axhline(data["uniform_capacity"], color="0.35", ls=":", lw=1.2,
                  label=rf"uniform ${_KBAR} = {data['p'] * data['kappa_max']:+g}$")
    b.set_xlabel(r"$\alpha$")
    b.legend(fontsize=7)
    c.plot(data["alpha_stab"], data["lambda_min"], "o-", ms=3, color="tab:green")
    c.axhline(0.0, color="k", lw=0.7, ls=":")
    c.set_xlabel(r"$\alpha$")
    c.set_ylabel(r"$\lambda_{\min}(E^T L E)$")
    c.set_title("(c) stability: smallest eigenvalue", fontsize=10)
    keys = ("D", "M", "mu_s", "b", "gamma") if grip == "III" else ("D", "M", "mu_s", "b")
    fig.suptitle(rf"Fig. {num} - {_GRIP_TITLE[grip]}, profile (34) with $\bar{{\kappa}}_{{\max}} = "
                 rf"{data['kappa_max']:g}$, $p = {data['p']:+d}$; {_param_text(data, keys)}")
    return fig


def _plot_fig16(data, overlay=None):
    fig, (a, b) = _new_figure(2, width=5.0, height=4.2)
    colors = {"I": "tab:blue", "II": "tab:orange", "III": "tab:green"}
    inset = b.inset_axes([0.09, 0.47, 0.42, 0.4])
    for grip in ("I", "II", "III"):
        a.plot(np.abs(data[f"kappa_{grip}"]), data[f"least_mu_{grip}"], color=colors[grip], label=f"Grip {grip}")
        load = np.asarray(data[f"max_load_{grip}"], dtype=float)
        shown = np.where(np.isinf(load), data["M_max"], load)
        kl = np.abs(data[f"kappa_load_{grip}"])
        fold = np.asarray(data.get(f"max_load_reason_{grip}", np.array([""] * len(kl)))) == "fold"
        for ax in (b, inset):
            ax.plot(kl, shown, "-", color=colors[grip], label=f"Grip {grip}" if ax is b else None)
            ax.plot(kl[~fold], shown[~fold], "o", ms=3, color=colors[grip])
            ax.plot(kl[fold], shown[fold], "o", ms=5, mfc="white", color=colors[grip])
        if np.isinf(load).any():
            b.plot(kl[np.isinf(load)], np.full(np.isinf(load).sum(), data["M_max"]), "^", ms=7,
                   color=colors[grip], label=rf"Grip {grip}: $M \geq {data['M_max']:g}$ (search limit)")
    if any((np.asarray(data.get(f"max_load_reason_{g}", [])) == "fold").any() for g in ("I", "II", "III")):
        b.plot([], [], "o", ms=5, mfc="white", color="0.3", label="limited by snap-through (fold)")
    a.axhline(1.0, color="0.5", ls="--", lw=0.8, label=r"$\mu_s = 1$")
    finite = np.concatenate([data[f"least_mu_{g}"][np.isfinite(data[f"least_mu_{g}"])] for g in ("I", "II", "III")])
    top = min(3.0, float(finite.max())) if finite.size else 3.0
    a.set_ylim(0.0, max(top, 1.2) * 1.05)
    a.set_xlim(0.0, None)
    a.set_xlabel(rf"$|{_KBAR}|$")
    a.set_ylabel(r"least $\mu_s = |f|/n$")
    a.set_title(f"(a) least $\\mu_s$ to hold $M = {data['M']:g}$ (gaps: cannot hold)", fontsize=10)
    b.set_xlabel(rf"$|{_KBAR}|$")
    b.set_ylabel(r"largest $M = m/\rho\ell$")
    b.set_title(r"(b) largest $M$ held at $\mu_s = 1$", fontsize=10)
    for ax in (b, inset):
        ax.axhline(data["M"], color="0.5", ls="--", lw=0.8, label=f"$M = {data['M']:g}$" if ax is b else None)
    kmax = max(np.abs(data["kappa_load_I"]).max(), np.abs(data["kappa_load_II"]).max())
    small = np.concatenate([data["max_load_I"], data["max_load_II"]])
    small = small[np.isfinite(small)]
    inset.set_xlim(0.0, kmax * 1.02)
    inset.set_ylim(0.0, (small.max() if small.size else 10.0) * 1.15)
    inset.set_title("Grips I, II (zoom)", fontsize=7)
    inset.tick_params(labelsize=7)
    a.legend(fontsize=8)
    b.legend(fontsize=7, loc="lower right")
    fig.suptitle(rf"Fig. 16 - load capability of the three grips; $D = {data['D']:g}$, "
                 rf"$b/\ell = {data['b']:g}$, $\gamma/\ell = {data['gamma']:g}$ (Grip III)")
    return fig


_PLOTTERS = {"fig06": _plot_fig06, "fig07": _plot_grip_sweep, "fig08": _plot_grip_sweep,
             "fig09": _plot_grip_sweep, "fig11": _plot_fig11, "fig12": _plot_fig12,
             "fig13": _plot_alpha, "fig14": _plot_alpha, "fig15": _plot_alpha, "fig16": _plot_fig16}


def plot_figure(name, data: dict, *, overlay: dict | None = None):
    """Draw figure ``name`` from :func:`figure_data`'s ``data``; returns a :class:`matplotlib.figure.Figure`.

    ``overlay`` (figures 6-9 only) adds simulated points; see the module docstring
    for its keys.  The figure has an Agg canvas attached and is not registered
    with pyplot.
    """
    key = _name(name)
    if overlay is not None:
        if key not in ("fig06", "fig07", "fig08", "fig09"):
            raise ValueError(f"overlay is supported for fig06-fig09 only, not {key}")
        if "kappa" not in overlay and key != "fig06":
            raise ValueError("overlay needs a 'kappa' array (kappa_bar0 of each simulated point)")
    return _PLOTTERS[key](data, overlay)


def save_figure(fig, path, *, dpi: int = 110) -> Path:
    """Write ``fig`` as a PNG atomically (see :func:`simgrip.io.atomic_write`)."""
    from simgrip.io import atomic_write

    path = Path(path)
    with atomic_write(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=dpi)
    return path


def _render(name: str, out_dir: str, simulate: bool = False, links: int = 16) -> str:
    """Compute, plot and write one figure (runs in a worker process).

    With ``simulate``, figures 6-9 get :func:`simulation_overlay` (``links`` links).
    """
    key = _name(name)
    data = figure_data(key)
    overlay = simulation_overlay(key, links=links) if simulate and key in _OVERLAY_FIGURES else None
    fig = plot_figure(key, data, overlay=overlay)
    path = save_figure(fig, Path(out_dir) / f"{key}.png")
    return str(path)


def make_figures(out_dir, *, which=None, jobs: int | None = None, progress: bool = True,
                 simulate: bool = True, links: int = 16) -> list[Path]:
    """Write the paper's figures as PNG files ``out_dir/figNN.png``.

    Parameters
    ----------
    out_dir : path
        Destination folder (created if missing).
    which : iterable of str or int, optional
        Figures to make (``"fig07"``, ``7``...); all of :data:`FIGURES` by default.
    jobs : int, optional
        Worker processes (default ``os.cpu_count()``); ``1`` runs in this process.
        Each figure is computed independently, so the results do not depend on ``jobs``.
    progress : bool
        Show a tqdm progress bar.
    simulate : bool
        Overlay the MuJoCo hinge chain's settled states on figures 6-9
        (:func:`simulation_overlay`, label ``"MuJoCo chain, n = <links>"``).
    links : int
        Links per finger of the simulated chain (default 16).

    Returns
    -------
    list of Path
        The files written, in the order of ``which``.
    """
    from tqdm import tqdm

    from simgrip.chain import check_links

    names = list(FIGURES) if which is None else [_name(w) for w in ([which] if isinstance(which, (str, int)) else which)]
    names = list(dict.fromkeys(names))
    if jobs is not None and int(jobs) < 1:
        raise ValueError(f"jobs must be a positive integer, got {jobs!r}")
    links = check_links(links)
    simulate = bool(simulate)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    workers = min(int(jobs or os.cpu_count() or 1), len(names)) if names else 1
    done: dict[str, Path] = {}
    with tqdm(total=len(names), desc="figures", unit="fig", disable=not progress) as bar:
        if workers <= 1:
            for key in names:
                bar.set_postfix_str(key)
                done[key] = Path(_render(key, str(out), simulate, links))
                bar.update()
        else:
            order = sorted(names, key=lambda k: -_COST.get(k, 1))
            with ProcessPoolExecutor(max_workers=workers) as pool:
                futures = {pool.submit(_render, key, str(out), simulate, links): key for key in order}
                for fut in as_completed(futures):
                    key = futures[fut]
                    done[key] = Path(fut.result())
                    bar.set_postfix_str(key)
                    bar.update()
    return [done[k] for k in names]

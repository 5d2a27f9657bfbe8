"""The numbers behind the paper's figures 6-9 and 11-16, computed from the elastica reference.

:func:`figure_data` returns a ``dict`` of NumPy arrays and floats per figure
(no matplotlib here), so that tests and other tools check what a figure shows
without rendering it.  Sweeps are continuations (each solve warm-started from
the last success; a failed point becomes NaN instead of aborting the sweep);
load capacities come from :mod:`simgrip.reference.capacity`; stability from the
discrete problem's projected Hessian (:func:`simgrip.reference.discrete_from_continuous`).

Conventions: dimensionless units (lengths over ``l``, forces on the rod over
``rho g l``), the finger's base at the origin, ``x`` along ``E1``, ``z`` up.
"""

from __future__ import annotations

import math

import numpy as np

from simgrip.figures.catalog import GRIP_SIGN, figure_key
from simgrip.params import STANDARD, DimensionlessParams
from simgrip.profiles import Concentrated, Uniform

__all__ = ["figure_data"]

# Resolution of the sweeps (points per curve).
_N_KAPPA = {"I": 49, "II": 49, "III": 41}  # Figs. 7-9, 16 (steps of 1/8 and 1/4)
_N_KAPPA_STAB = 25     # Fig. 11 (each point also solves the discrete problem)
_LOAD_EVERY = 2        # Fig. 16 (b): every 2nd point of the sweep (each is a continuation in M)
_N_ALPHA = 21          # Figs. 13-15 capacity curves
_N_ALPHA_STAB = 11     # Figs. 13-15 eigenvalue curves
_N_RAMP = 13           # continuation steps in kappa_max before an alpha sweep
_K_DISCRETE = 60       # elements of the discrete stability problem (gamma K integer for gamma = 0.8)
_N_SHAPE = 101         # points per stored centreline
_TOL = 1e-8            # solve_bvp tolerance (8 digits: far below what a plot resolves)
_TOL_LOAD = 1e-6       # tolerance of the load search's many probe solves (plot accuracy)
_XTOL_LOAD = 1e-4      # the largest load M to this (a plot resolves 1e-3 of M_max at best)
_M_MAX = 200.0         # largest load tried by the load-capacity search
_KAPPA_RANGE = {"I": (0.0, -6.0), "II": (0.0, 6.0), "III": (0.0, -10.0)}
_ALPHAS_SHAPES = (1.0, 1.5, 2.0, 2.5, 3.0)


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
    # the verdicts are the solver's (ElasticaSolution.feasibility): the criteria live in one place
    verdict = lambda key: np.array([o and bool(s.feasibility.get(key, True)) for s, o in zip(sols, ok)])  # noqa: E731
    out["feasible"] = out["solver_feasible"] = np.array([o and bool(s.feasible) for s, o in zip(sols, ok)])
    least_mu = np.array([s.required_mu if o else np.nan for s, o in zip(sols, ok)])
    out["least_mu"] = np.where(verdict("contact"), least_mu, np.nan)  # gaps: no normal force
    if grip in ("I", "II"):
        out["N"] = out["N1"]
        out["required"] = np.abs(out["N2"])          # |F_f| = M
        out["available"] = params.mu_s * out["N1"]   # mu_s N
    elif grip == "III":
        out["required"] = np.abs(out["f"])           # |f|
        out["available"] = params.mu_s * out["n"]    # mu_s n
        out["tip_below_contact"] = verdict("tip_clear")
        out["friction_ok"] = verdict("contact") & verdict("friction")
    return out


def _sweep(grip, params, profiles, *, gravity=True):
    """:func:`simgrip.reference.elastica.sweep` at :data:`_TOL`; failed points are ``None``."""
    from simgrip.reference import elastica

    return elastica.sweep(grip, params, profiles, gravity=gravity, tol=_TOL, failures="skip")


def _kappa_sweep(grip, params, kappas):
    return _sweep(grip, params, [Uniform(float(k)) for k in kappas])


def _alpha_profiles(grip, alphas, kappa_max=6.0, n_ramp=_N_RAMP):
    """Continuation path: ramp kappa_max at alpha = alphas[0], then sweep alpha."""
    p = GRIP_SIGN.get(grip, -1)
    ramp = [Concentrated(kappa_max * t, float(alphas[0]), p) for t in np.linspace(0.0, 1.0, n_ramp)[:-1]]
    return ramp, [Concentrated(kappa_max, float(a), p) for a in alphas]


def _alpha_sweep(grip, params, alphas, kappa_max=6.0, gravity=True):
    ramp, profiles = _alpha_profiles(grip, alphas, kappa_max)
    sols = _sweep(grip, params, ramp + profiles, gravity=gravity)
    return sols[len(ramp):], profiles


def _loads(grip, params, profiles, guesses):
    """Largest load held at ``params.mu_s`` along ``profiles`` (:func:`simgrip.reference.capacity.track_largest_load`).

    Returns ``(M, reason)`` arrays; a failed point is NaN with reason ``"failed"``.
    """
    from simgrip.reference.capacity import track_largest_load

    caps = track_largest_load(grip, params, profiles, guesses, failures="skip", M_max=_M_MAX, xtol=_XTOL_LOAD,
                              tol=_TOL_LOAD)
    return np.array([c.M for c in caps]), np.array([c.reason for c in caps])


def _min_eigenvalues(grip, params, profiles, guesses, K=_K_DISCRETE, gravity=True) -> np.ndarray:
    """Smallest eigenvalue of ``E^T L E`` (paper Section 4) of the discrete problem with
    ``K`` elements, started from the continuous solutions ``guesses`` (NaN where a solve fails)."""
    from simgrip.reference import DiscreteError, discrete_from_continuous

    out = np.full(len(profiles), np.nan)
    for i, (prof, g) in enumerate(zip(profiles, guesses)):
        if g is None:
            continue
        try:
            d = discrete_from_continuous(g, grip, params, prof, K)
        except (DiscreteError, ArithmeticError, np.linalg.LinAlgError):
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
            "D": params.D, "gamma": params.gamma, "kappa_max": 6.0, "p": GRIP_SIGN[grip],
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
        data["capacity"], data["capacity_reason"] = _loads(grip, params, profiles, sols)
    else:
        # load capacity: the largest friction force mu_s N at the standard load M
        data["alpha_capacity"] = alphas
        data["capacity"] = arr["available"]
    # reference: the uniform profile with the same peak curvature (alpha = 0)
    kap = GRIP_SIGN[grip] * data["kappa_max"]
    uni = _kappa_sweep(grip, params, np.linspace(0.0, kap, 13))[-1]
    if uni is None:
        data["uniform_capacity"] = math.nan
    elif grip == "III":
        data["uniform_capacity"] = float(_loads(grip, params, [Uniform(kap)], [uni])[0][0])
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
        data[f"max_load_{grip}"], data[f"max_load_reason_{grip}"] = _loads(
            grip, p1, [Uniform(float(kappas[i])) for i in sel], [sols[i] for i in sel])
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
    key = figure_key(name)
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
    elif key == "fig16":
        data = _data_fig16(params)
    else:
        raise ValueError(f"{key} is not one of the paper's figures: simgrip.figures.gripper makes it")
    data["name"] = key
    return data


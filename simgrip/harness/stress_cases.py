"""The cases of the numerical stress run: a grid, then low-discrepancy draws, so that any prefix spreads.

The parameter box:

=============  ==========================================================
``D``          ``[1e-2, 1e2]`` (log scale)
``kappa``      ``[-12, 12]`` (the profile's peak curvature; both signs for
               every grip: wrong-way curls are part of the test)
``M``          ``[0, 50]``
``mu_s``       ``[0.05, 5]`` (log scale)
``b``          ``(0, 1)`` (``b/l``)
``n``          ``[4, 256]`` links (log scale, integer)
profile        uniform, concentrated (eq. 34, ``alpha`` up to 8) and extreme
               ones: a step that reverses the curvature at mid-length, a
               narrow spike, a fast oscillation
grip           ``free``, ``I``, ``II``, ``III``
=============  ==========================================================

:func:`make_cases` mixes two kinds of cases, alternating (grid, draw, grid,
draw, ...) so that any prefix of the list spreads over the whole box:

* the **grid**: per grip, ``D`` x ``kappa`` at the standard case, the extremes
  of ``M``, ``mu_s``, ``b`` and ``n``, and each extreme profile.  Its order is
  a greedy maximin (farthest-point) order in the box scaled to the unit cube:
  each next case is the one farthest from all cases already listed, starting
  from the one nearest the centre; the grips take turns.  The first ``k`` grid
  cases thus spread as evenly as ``k`` grid points can, instead of filling one
  row of the grid;
* **draws** from a scrambled Sobol sequence (:class:`scipy.stats.qmc.Sobol`,
  seeded by ``seed``): low-discrepancy in all nine dimensions (grip and
  profile included), so a few dozen already cover each dimension evenly.

A run of ``cases`` takes the first ``min(grid size, ceil(cases / 2))`` grid
cases (the whole grid from 216 cases on) and fills up with draws.

Each case is a plain ``dict`` (``grip, D, kappa, M, mu_s, b, n, profile,
alpha, id, source``), self-contained, so its outcome does not depend on how
the run is spread over processes.

**Full-contact cases** (:func:`make_full_cases`, ``contact="full"``: every link touches the workpiece and
itself) are drawn apart, from their own box :data:`FULL_BOX`: grips I, II and the free rod, uniform profile,
``|kappa|`` past the point-contact onset (standard case: I -8.27, II 5.50, :mod:`tests.test_free_boundary`;
I at ``D = 0.5``: -9.38; the free rod touches itself past ``2 pi``), ``n <= 16`` (each settle is the
over-damped dynamics, ~0.5-4 s at these ``n``).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["BOX", "FULL_BOX", "FULL_GRIPS", "GRIPS", "PROFILES", "make_cases", "make_full_cases", "stress_profile"]

#: Parameter box (``n``: links).
BOX = {"D": (1e-2, 1e2), "kappa": (-12.0, 12.0), "M": (0.0, 50.0), "mu_s": (0.05, 5.0), "b": (0.0, 1.0), "n": (4, 256)}
GRIPS = ("free", "I", "II", "III")
PROFILES = ("uniform", "concentrated", "step", "spike", "wiggle")
#: How often each profile is drawn (the uniform profile is the common case).
PROFILE_WEIGHTS = (0.5, 0.2, 0.1, 0.1, 0.1)
#: Grips of the full-contact cases (Grip III's full contact is not settled by contact="full").
FULL_GRIPS = ("I", "II", "free")
#: Box of the full-contact cases.  ``abs_kappa`` per grip: from past the onset over ``D`` and ``b`` here (Grip I's
#: onset is -8.27 at the standard case, -9.38 at D = 0.5, -7.51 at b = 0.4; Grip II's 5.50; the free uniform rod
#: closes on itself at 2 pi) to the stress box's 12, curled onto the workpiece (I: kappa < 0, II: > 0; free: either).
FULL_BOX = {"D": (0.5, 2.0), "abs_kappa": {"I": (9.5, 12.0), "II": (6.5, 12.0), "free": (6.5, 12.0)},
            "M": (0.0, 10.0), "mu_s": (0.3, 2.0), "b": (0.4, 0.8), "n": (8, 16)}


def stress_profile(kind: str, kappa: float, alpha: float):
    """The curvature profile ``kind`` (one of :data:`PROFILES`) with peak curvature ``kappa``."""
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


def _log_unit(x, lo, hi) -> float:
    return (math.log10(x) - math.log10(lo)) / (math.log10(hi) - math.log10(lo))


def _unit(c: dict) -> np.ndarray:
    """A grid case as a point of the unit cube (log scales as in the box; profile: 0 uniform, 1 other)."""
    return np.array([
        _log_unit(c["D"], *BOX["D"]),
        (c["kappa"] - BOX["kappa"][0]) / (BOX["kappa"][1] - BOX["kappa"][0]),
        c["M"] / BOX["M"][1],
        _log_unit(c["mu_s"], *BOX["mu_s"]),
        c["b"],
        _log_unit(c["n"], *BOX["n"]),
        float(c["profile"] != "uniform"),
    ])


def _maximin_order(cases: list[dict]) -> list[dict]:
    """Greedy farthest-point order: start nearest the centre, then always the case farthest from those chosen."""
    P = np.array([_unit(c) for c in cases])
    dist = np.linalg.norm(P - 0.5, axis=1)
    order = [int(np.argmin(dist))]
    dist = np.linalg.norm(P - P[order[0]], axis=1)
    while len(order) < len(cases):
        nxt = int(np.argmax(dist))  # ties: the first in the grid's listing order
        order.append(nxt)
        dist = np.minimum(dist, np.linalg.norm(P - P[nxt], axis=1))
    return [cases[i] for i in order]


def _grid() -> list[dict]:
    """The grid, grips taking turns, each grip's cases in maximin order."""
    per = {}
    for g in GRIPS:
        s = 1.0 if g == "II" else -1.0  # the curvature that curls the finger onto the workpiece
        std = dict(grip=g, D=1.0, kappa=6.0 * s, M=5.0, mu_s=1.0, b=0.6, n=16, profile="uniform", alpha=0.0)
        cases = [{**std, "D": D, "kappa": k} for D in (1e-2, 1.0, 1e2) for k in (-12.0, -6.0, 0.0, 6.0, 12.0)]
        cases += [{**std, "M": M} for M in (0.0, 50.0)]
        cases += [{**std, "mu_s": mu} for mu in (0.05, 5.0)]
        cases += [{**std, "b": b} for b in (0.02, 0.98)]
        cases += [{**std, "n": n} for n in (4, 256)]
        cases += [{**std, "n": 32, "profile": kind, "alpha": 8.0} for kind in PROFILES[1:]]
        per[g] = _maximin_order(cases)
    return [c for row in zip(*per.values()) for c in row]


def _draws(count: int, seed: int, max_links: int) -> list[dict]:
    """``count`` cases from a scrambled Sobol sequence over the box (grip and profile included)."""
    if count <= 0:
        return []
    from scipy.stats import qmc

    U = qmc.Sobol(d=9, scramble=True, seed=seed).random_base2(max(0, math.ceil(math.log2(count))))[:count]
    cum = np.cumsum(PROFILE_WEIGHTS)
    out = []
    for u in U:
        out.append(dict(
            grip=GRIPS[min(int(u[0] * len(GRIPS)), len(GRIPS) - 1)],
            D=float(10 ** (-2.0 + 4.0 * u[1])),
            kappa=float(BOX["kappa"][0] + (BOX["kappa"][1] - BOX["kappa"][0]) * u[2]),
            M=float(BOX["M"][1] * u[3]),
            mu_s=float(10 ** (math.log10(0.05) + 2.0 * u[4])),
            b=float(0.01 + 0.98 * u[5]),
            n=int(round(10 ** (math.log10(4) + (math.log10(max(4, max_links)) - math.log10(4)) * u[6]))),
            profile=PROFILES[min(int(np.searchsorted(cum, u[7] * cum[-1], side="right")), len(PROFILES) - 1)],
            alpha=float(8.0 * u[8]),
        ))
    return out


def _check_count(name: str, value, lowest: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < lowest:
        raise ValueError(f"{name} must be an integer >= {lowest}, got {value!r}")
    return int(value)


def make_cases(cases: int = 500, seed: int = 0, grid_cases: int | None = None, max_links: int = 256) -> list[dict]:
    """The stress cases: grid cases and Sobol draws alternating, ``cases`` in all (see the module docstring).

    ``grid_cases`` sets how many grid cases (the first in maximin order) are
    used instead of the default ``min(grid size, ceil(cases / 2))``.
    ``max_links`` caps ``n`` (draws in ``[4, max_links]``, grid values clipped).
    Raises ``ValueError`` naming ``cases``, ``seed``, ``grid_cases`` or ``max_links``.
    """
    cases = _check_count("cases", cases, 1)
    seed = _check_count("seed", seed, 0)
    max_links = _check_count("max_links", max_links, 4)
    grid = _grid()
    n_grid = min(len(grid), cases - cases // 2)
    if grid_cases is not None:
        n_grid = min(_check_count("grid_cases", grid_cases, 0), len(grid), cases)
    grid = [{**c, "source": "grid"} for c in grid[:n_grid]]
    draws = [{**c, "source": "random"} for c in _draws(cases - n_grid, seed, max_links)]
    allc = [c for pair in zip(grid, draws) for c in pair]
    k = min(len(grid), len(draws))
    allc += grid[k:] + draws[k:]
    for i, c in enumerate(allc):
        c["n"] = min(int(c["n"]), max_links)
        c["id"] = i
    return allc


def make_full_cases(count: int, seed: int = 0, max_links: int = 16) -> list[dict]:
    """``count`` full-contact cases (``contact="full"``) from a scrambled Sobol sequence over :data:`FULL_BOX`.

    Grip, ``D`` (log), ``|kappa|``, ``M``, ``mu_s`` (log), ``b``, ``n`` (integer, capped at ``max_links``) and,
    for the free rod, the sign of ``kappa``.  Each case is a dict like :func:`make_cases`' with ``contact =
    "full"``, ``profile = "uniform"``, ``source = "full"`` and ``id`` counted from 0.  Raises ``ValueError``
    naming ``full_cases`` (``count``), ``seed`` or ``max_links``.
    """
    count = _check_count("full_cases", count, 0)
    seed = _check_count("seed", seed, 0)
    max_links = _check_count("max_links", max_links, 4)
    if count == 0:
        return []
    from scipy.stats import qmc

    U = qmc.Sobol(d=8, scramble=True, seed=seed + 1).random_base2(max(0, math.ceil(math.log2(count))))[:count]
    b = FULL_BOX
    out = []
    for i, u in enumerate(U):
        grip = FULL_GRIPS[min(int(u[0] * len(FULL_GRIPS)), len(FULL_GRIPS) - 1)]
        lo, hi = b["abs_kappa"][grip]
        sign = {"I": -1.0, "II": 1.0}.get(grip, -1.0 if u[7] < 0.5 else 1.0)
        lg = (math.log10(b["D"][0]), math.log10(b["D"][1]))
        lm = (math.log10(b["mu_s"][0]), math.log10(b["mu_s"][1]))
        n = int(round(b["n"][0] + (b["n"][1] - b["n"][0]) * u[6]))
        out.append(dict(
            grip=grip, contact="full", profile="uniform", alpha=0.0, source="full", id=i,
            D=float(10 ** (lg[0] + (lg[1] - lg[0]) * u[1])),
            kappa=float(sign * (lo + (hi - lo) * u[2])),
            M=float(b["M"][0] + (b["M"][1] - b["M"][0]) * u[3]),
            mu_s=float(10 ** (lm[0] + (lm[1] - lm[0]) * u[4])),
            b=float(b["b"][0] + (b["b"][1] - b["b"][0]) * u[5]),
            n=min(n, max_links),
        ))
    return out

"""The continuous reference: :func:`solve` one elastica equilibrium, :func:`sweep` along profiles.

Everything is dimensionless (``l = 1``, ``rho g = 1``, so ``EI = D`` and the
per-finger workpiece weight is ``M``); conventions are those of ``README.md``:
``E1`` horizontal from the palm centre towards the finger, ``E2`` up, gravity
``-E2`` per unit length, ``theta`` counter-clockwise from ``E1``, forces named in
results are forces the workpiece exerts **on the rod**.

The equations (free rod, Grips I-III, the Grip III erratum of eq. 21) are in
:mod:`simgrip.reference.bvp`; how ``solve_bvp`` is brought to converge (warm
starts, continuation, cold starts) is in :mod:`simgrip.reference.continuation`.
A warm start (``guess=``) is tried directly, then by continuation from the
guess's problem to the requested one, then cold.

Default ``tol = 1e-8`` (``solve_bvp``'s relative residual): the tip then agrees
with a ``tol = 1e-11`` solution to ~1e-12.

The load-capacity functions (:func:`~simgrip.reference.capacity.least_mu`,
:func:`~simgrip.reference.capacity.max_load`, ...) live in
:mod:`simgrip.reference.capacity` (also :mod:`simgrip.reference`'s: ``discrete.max_load``); capacity
builds on this module, so this module does not import it back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Sequence

import numpy as np

from simgrip.params import DimensionlessParams, _finite, check_grip
from simgrip.profiles import CurvatureProfile, Uniform, as_profile
from simgrip.reference.arguments import check_failures, check_gamma, check_params, check_tip_load, check_tol
from simgrip.reference.bvp import BvpProblem, BvpSolution, ElasticaError, grip_problem
from simgrip.reference.continuation import Budget, cold_start, continue_along, linear_path, solve_from

__all__ = [
    "ElasticaError",
    "ElasticaSolution",
    "solve",
    "sweep",
    "kappa_sweep",
    "FINE_POINTS",
]

#: Number of points of the fine output grid of every solution.
FINE_POINTS = 201

@dataclass(frozen=True, eq=False)
class ElasticaSolution:
    """An equilibrium of the free rod or of one grip, dimensionless.

    Attributes
    ----------
    grip : str
        ``"free"``, ``"I"``, ``"II"`` or ``"III"``.
    params, profile
        The inputs (``params.M`` is ignored by the free rod).
    s, theta, x, y, moment : ndarray
        Fine grid (:data:`FINE_POINTS` points, ``s`` in ``[0, 1]``, Grip III has a
        node at ``gamma``) with the tangent angle, position and bending moment
        ``m = D (theta' - kappa0)``.  At ``gamma`` (Grip III) ``moment`` is the
        clamp-side value ``m(gamma-)``.
    tip : ndarray
        ``[X(1), Y(1)]``.
    contact : ndarray or None
        ``[x, y]`` of the contact point: the tip for Grips I/II, ``r(gamma)`` for
        Grip III, ``None`` for the free rod.
    gamma : float or None
        Contact arc length: 1.0 for Grips I/II, the one used for III, ``None`` free.
    N1, N2 : float
        Contact force on the rod, ``E1`` and ``E2`` components (I/II: ``N1 = N``,
        ``N2 = F_f = -M``).  0 for the free rod.
    n, f : float
        Normal and tangential (friction) components of the contact force in the
        workpiece's frame: Grip III along ``e2`` and ``e1`` at ``gamma``; Grips I/II
        the face is vertical, so ``n = N1``, ``f = N2``.  0 for the free rod.
    normal_force, friction_force : float
        ``n`` and ``f`` again, by role (I/II: ``N`` and ``F_f``).
    required_mu : float
        ``|friction_force| / normal_force``, the least friction coefficient that
        holds this configuration; ``inf`` when ``normal_force <= 0``; 0 for the
        free rod (nothing to hold).
    feasible : bool
        All of ``feasibility``'s entries (``True`` for the free rod).
    feasibility : dict
        ``"contact"``: normal force > 0; ``"friction"``: ``|f| <= mu_s n``; Grip III
        also ``"tip_clear"``: ``Y(1) < Y(gamma)`` (paper's condition 23); Grips I/II
        also ``"grip_shape"``: the tip on the grip's side of the palm (I: ``Y(1) <
        0``, II: ``Y(1) > 0``, :func:`grip_side`; a solution in the other grip's
        shape is not the grip asked for).  Empty for the free rod.
    residual : float
        Largest relative rms collocation residual of ``solve_bvp``.
    success, message
        Convergence flag (always ``True`` for a returned solution) and solver message.
    gravity, tip_load, contact_moment
        The loading options the solution was computed with.
    """

    grip: str
    params: DimensionlessParams
    profile: CurvatureProfile
    s: np.ndarray
    theta: np.ndarray
    x: np.ndarray
    y: np.ndarray
    moment: np.ndarray
    tip: np.ndarray
    contact: np.ndarray | None
    gamma: float | None
    N1: float
    N2: float
    n: float
    f: float
    normal_force: float
    friction_force: float
    required_mu: float
    feasible: bool
    feasibility: dict
    residual: float
    success: bool
    message: str
    gravity: bool = True
    tip_load: tuple = (0.0, 0.0)
    contact_moment: float = 0.0
    _raw: BvpSolution | None = field(default=None, repr=False)

    def theta_at(self, s) -> np.ndarray:
        """Tangent angle at arc lengths ``s`` (array of ``s``'s shape), from the
        solver's C1 cubic interpolant."""
        return self._raw.states(s)[0]

    def moment_at(self, s) -> np.ndarray:
        """Bending moment at arc lengths ``s`` (Grip III: ``m(gamma-)`` at ``gamma``)."""
        return self._raw.states(s)[1]

    def position_at(self, s) -> np.ndarray:
        """Centreline position at arc lengths ``s``: shape ``s.shape + (2,)``, ``[..., 0] = X``."""
        st = self._raw.states(s)
        return np.moveaxis(st[2:4], 0, -1)

    @property
    def mesh_size(self) -> int:
        """Number of collocation nodes ``solve_bvp`` ended with."""
        return int(self._raw.x.size)

    @classmethod
    def from_bvp(cls, grip: str, params: DimensionlessParams, raw: BvpSolution) -> "ElasticaSolution":
        """Package a converged BVP of ``grip`` (the loads and profile are read from ``raw.prob``)."""
        P = raw.prob
        s = _fine_grid(P.gamma if grip == "III" else None)
        th, m, X, Y = raw.states(s)
        tip = np.array([X[-1], Y[-1]])
        contact, gamma = None, None
        N1 = N2 = n = f = req = 0.0
        feas: dict = {}
        if grip != "free":
            cs = raw.contact_state()
            contact = cs[2:4].copy()
            N1, N2 = raw.N1, P.N2
            if grip == "III":
                gamma, thg = P.gamma, cs[0]
                f = N1 * math.cos(thg) + N2 * math.sin(thg)
                n = -N1 * math.sin(thg) + N2 * math.cos(thg)
            else:
                gamma, n, f = 1.0, N1, N2
            req = abs(f) / n if n > 0 else math.inf
            feas = {"contact": bool(n > 0), "friction": bool(n > 0 and abs(f) <= params.mu_s * n)}
            if grip == "III":
                feas["tip_clear"] = bool(tip[1] < contact[1])
            else:
                feas["grip_shape"] = bool(grip_side(grip) * tip[1] > 0.0)
        return cls(
            grip=grip, params=params, profile=P.profile, s=s, theta=th, x=X, y=Y, moment=m, tip=tip,
            contact=contact, gamma=gamma, N1=float(N1), N2=float(N2), n=float(n), f=float(f),
            normal_force=float(n), friction_force=float(f), required_mu=float(req),
            feasible=all(feas.values()), feasibility=feas, residual=raw.rms, success=True,
            message=raw.message, gravity=P.g > 0, tip_load=(P.t1, P.t2), contact_moment=P.C, _raw=raw,
        )


def grip_side(grip: str) -> float:
    """The side of the palm a Grip I/II tip lies on: ``-1`` (Grip I hangs the workpiece below, ``Y(1) < 0``),
    ``+1`` (Grip II carries it above, ``Y(1) > 0``; Fig. 2 of the paper).  Both grips are the same equations;
    a solution on the other side is the other grip's shape, which the simulation reports as not held
    (:func:`simgrip.validity.check_grip_shape`), so its ``feasibility["grip_shape"]`` is False."""
    return -1.0 if grip == "I" else 1.0


def _fine_grid(gamma: float | None) -> np.ndarray:
    """The arc lengths a solution is sampled on (a fresh array: the solution owns it)."""
    return _fine_grid_of(gamma).copy()


@lru_cache(maxsize=64)
def _fine_grid_of(gamma: float | None) -> np.ndarray:
    k = FINE_POINTS - 1
    if gamma is None or gamma >= 1.0:
        return np.linspace(0.0, 1.0, FINE_POINTS)
    ka = min(max(1, int(round(k * gamma))), k - 1)
    return np.concatenate((np.linspace(0.0, gamma, ka + 1), np.linspace(gamma, 1.0, k - ka + 1)[1:]))


def checked_problem(grip, params, profile, *, gravity=True, tip_load=(0.0, 0.0), contact_moment=0.0,
                    gamma=None) -> tuple[str, DimensionlessParams, BvpProblem]:
    """Check the arguments of :func:`solve` once: ``(grip, params, problem)``.

    The entry points of this package (``solve``, ``least_mu``, ``max_load``, ...)
    call it; everything below them takes the checked problem.
    """
    grip = check_grip(grip)
    params = check_params(params)
    prof = as_profile(profile)
    t = check_tip_load(tip_load)
    C = _finite("contact_moment", contact_moment)
    gam = check_gamma(gamma, params) if grip == "III" else 1.0
    if not isinstance(gravity, (bool, np.bool_)):  # 0.5 or NaN read as True (solve_chain takes a factor: not here)
        raise ValueError(f"gravity must be True or False (the rod's weight on or off), got {gravity!r}")
    return grip, params, grip_problem(grip, params, prof, gravity=bool(gravity), tip_load=t, C=C, gamma=gam)


def check_guess(guess) -> BvpSolution | None:
    """The BVP inside a warm start ``guess``: an :class:`ElasticaSolution`, a settled hinge chain's shape
    (:func:`simgrip.reference.chain_guess.chain_guess`) or ``None``."""
    from simgrip.reference.chain_guess import ChainGuess

    if isinstance(guess, ChainGuess):
        return guess
    if guess is not None and not isinstance(guess, ElasticaSolution):
        raise ValueError(f"guess must be an ElasticaSolution, a ChainGuess or None, got {type(guess).__name__}")
    return None if guess is None else guess._raw


def solve_problem(P: BvpProblem, guess: BvpSolution | None, tol: float, fallback: bool = True) -> BvpSolution | None:
    """Warm start from ``guess`` (direct, then continuation), then cold; ``None`` if all fail.

    With ``fallback=False`` and a guess, only the direct warm start is tried.  The
    whole search spends at most :data:`~simgrip.reference.continuation.MAX_BVP_RUNS`
    ``solve_bvp`` runs: past that it raises :class:`ElasticaError`.
    """
    budget = Budget()
    raw = None
    if guess is not None:
        raw = solve_from(guess, P, tol, budget)
        if raw is None and not fallback:
            return None
        if raw is None:
            path = linear_path(guess.prob, P)
            if path is not None:
                raw = continue_along(path, guess, tol, h=0.5, budget=budget)
    if raw is None:
        raw = cold_start(P, tol, budget)
    return raw


def solve(
    grip: str,
    params: DimensionlessParams,
    profile,
    *,
    gravity: bool = True,
    tip_load=(0.0, 0.0),
    contact_moment: float = 0.0,
    gamma: float | None = None,
    guess: ElasticaSolution | None = None,
    tol: float = 1e-8,
    fallback: bool = True,
) -> ElasticaSolution:
    """Solve the free rod or one grip for ``params`` and curvature ``profile``.

    Parameters
    ----------
    grip : {"free", "I", "II", "III"}
    params : DimensionlessParams
        ``D, M, b, mu_s, gamma`` (``M, b, mu_s, gamma`` unused by the free rod).
    profile : CurvatureProfile, float or callable
        Intrinsic curvature ``kappa_bar(s_bar)`` (see :func:`~simgrip.profiles.as_profile`).
    gravity : bool
        Include the rod's own weight (``-E2`` per unit length).
    tip_load : (float, float)
        Extra force ``(E1, E2)`` on the tip (over ``rho g l``), e.g. for the
        Bisshopp-Drucker cantilever; in addition to any contact force.
    contact_moment : float
        Couple (``E3``, over ``rho g l^2``) the workpiece applies to the rod at the
        contact: the tip couple ``m(1)`` for the free rod and Grips I/II, the jump
        ``m(gamma+) - m(gamma-) = -contact_moment`` for Grip III.
    gamma : float, optional
        Grip III contact arc length; ``params.gamma`` when ``None``.
    guess : ElasticaSolution or ChainGuess, optional
        A solution to start from (any grip), or a settled hinge chain's shape
        (:func:`simgrip.reference.chain_guess.chain_guess`, built for this problem:
        the branch the chain settled on); continuation from its problem to this
        one is used if the direct start fails.
    tol : float
        ``solve_bvp`` tolerance (relative collocation residual and boundary residual).
    fallback : bool
        With ``False`` and a ``guess``, try only the direct warm start (one Newton
        run of ``solve_bvp``): fast and deterministic, for tracking a branch up to
        its fold, where the fallbacks would search for a distant branch.

    Returns
    -------
    ElasticaSolution

    Raises
    ------
    ValueError
        Unknown ``grip`` or invalid inputs.
    ElasticaError
        When neither the warm start nor the continuation strategies converge, or
        when they have spent :data:`~simgrip.reference.continuation.MAX_BVP_RUNS`
        ``solve_bvp`` runs (the bound on one solve's work).

    Examples
    --------
    >>> from simgrip import STANDARD, Uniform
    >>> sol = solve("I", STANDARD, Uniform(-5.5))
    >>> bool(abs(sol.tip[0] - 0.3) < 1e-9), sol.feasible, round(sol.N1, 3)
    (True, True, 6.656)
    """
    grip, params, P = checked_problem(grip, params, profile, gravity=gravity, tip_load=tip_load,
                                      contact_moment=contact_moment, gamma=gamma)
    tol = check_tol(tol)
    g_raw = check_guess(guess)
    raw = solve_problem(P, g_raw, tol, fallback)
    if raw is None and g_raw is not None and not fallback:
        raise ElasticaError(f"warm start of grip {grip!r} from the guess did not converge (fallback=False)")
    if raw is None:
        raise ElasticaError(
            f"elastica BVP failed for grip {grip!r}: D={params.D:g}, M={params.M:g}, b={params.b:g}, "
            f"gamma={P.gamma:g}, profile={P.profile!r}, gravity={gravity}, tip_load={tip_load}, "
            f"contact_moment={P.C:g}"
        )
    return ElasticaSolution.from_bvp(grip, params, raw)


def sweep(
    grip: str,
    params: DimensionlessParams,
    profiles: Sequence,
    *,
    start: ElasticaSolution | None = None,
    failures: str = "raise",
    **kw,
) -> list:
    """Solve along a sequence of profiles, each warm-started from the previous solution.

    A failed step is subdivided (continuation along the blend of the two
    profiles) before falling back to a cold start; ``start`` warm-starts the first.
    With ``failures="raise"`` (default) a point that still fails raises
    :class:`ElasticaError`; with ``failures="skip"`` it is ``None`` in the
    returned list and the next point is warm-started from the last success.
    Keyword arguments go to :func:`solve`.
    """
    check_failures(failures)
    return march(profiles, lambda i, prof, prev: solve(grip, params, prof, guess=prev, **kw), failures, start=start)


def march(items, solve_one, failures: str, *, start=None, failed=None, ok=lambda r: r is not None) -> list:
    """``[solve_one(i, item, last) for each item]``, ``last`` the latest result that is ``ok`` (``start`` before one).

    A step that raises :class:`ElasticaError` raises again (``failures="raise"``)
    or gives ``failed`` (``"skip"``); the next step then starts from the last success.
    """
    out: list = []
    last = start
    for i, item in enumerate(items):
        try:
            r = solve_one(i, item, last)
        except ElasticaError:
            if failures == "raise":
                raise
            r = failed
        out.append(r)
        if ok(r):
            last = r
    return out


def kappa_sweep(grip: str, params: DimensionlessParams, kappas, profile_of=Uniform, **kw) -> list:
    """:func:`sweep` over ``profile_of(kappa)`` for each ``kappa`` in ``kappas``."""
    return sweep(grip, params, [profile_of(float(k)) for k in np.atleast_1d(kappas)], **kw)

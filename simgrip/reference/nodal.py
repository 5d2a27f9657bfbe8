"""The paper's nodal scheme (Section 4, eqs. 25-33): :func:`solve_discrete` and its energy.

The dimensionless potential energy (``l = 1``, ``rho g = 1``, ``EI = D``,
per-finger workpiece weight ``M``)::

    V = int_0^1 D/2 (theta' - kappa0)^2 ds + int_0^1 (1 - s) sin(theta) ds - F . r(s_c)

(the gravity term is ``int Y ds`` after the change of order of integration of
eq. 12; ``F`` is the force the workpiece exerts on the rod at the contact point
``s_c``) is minimised subject to the width constraint ``X(s_c) = b/2``:

=========  ======================  =====================  ===================
grip       contact ``s_c``         known load             multiplier
=========  ======================  =====================  ===================
``free``   none                    none                   none
``I/II``   tip, ``s_c = 1``        ``F_f = N2 = -M``      ``N = N1``
``III``    ``s_c = gamma``         ``N2 = -M``            ``N1``
=========  ======================  =====================  ===================

Grips I and II are the same equations (II simply has ``kappa0 > 0``).  For Grip
III the load acts on the part ``(0, gamma)`` of the rod (the paper's eq. 21
swaps the segments; eq. 32 is right and is what is implemented).

Nodes ``s_i = i ds``, ``ds = 1/K``, angles ``theta_0 .. theta_K`` with
``theta_0 = 0`` imposed; unknowns ``theta_1 .. theta_K``.  Strain energy
``D/2 sum_i ((theta_i - theta_{i-1})/ds - kbar_i)^2 ds`` with ``kbar_i`` the
*element average* ``int_{s_{i-1}}^{s_i} kappa0 / ds`` (so the curvature term
``int kappa0 theta'`` is exact for piecewise-linear ``theta`` and non-uniform
profiles stay second order); every other integral is the trapezoid rule on the
nodes (gravity ``(1 - s_i) sin(theta_i)``, the loads and the constraint ``X``).
The moment-free tip condition is natural: the half-weight of node ``K`` makes
its equation a second-order one-sided approximation of
``theta'(1) = kappa0(1)``, so the paper's ghost node of eq. (26)_3 is not
needed.  Checked against eq. (11)/(19): eq. (25) is right (its ``theta_0``
terms are constants once ``theta_0 = 0``); eq. (32) writes ``sin(theta_n)`` for
``sin(theta_K)``.  Grip III contact node: ``I = round(gamma/ds)``; the scheme is
second order only when ``gamma`` is a node (choose ``K`` with ``gamma*K`` an
integer, e.g. ``K`` a multiple of 5 for ``gamma = 0.8``); otherwise the contact
sits at ``I ds`` (reported as ``solution.gamma``), an ``O(ds)`` shift.

The scheme is the standard symmetric three-point scheme with a half-cell
Neumann end: ``O(ds^2)`` in the tip/contact position, the angles and the
contact force (measured in ``tests/test_discrete.py``).  The stability eigenvalue
is normalised with the trapezoid weights (see :mod:`simgrip.reference.stability`);
:func:`stability_eigenvalue` evaluates it at an elastica solution.

Examples
--------
>>> from simgrip import STANDARD, Uniform
>>> sol = solve_discrete("I", STANDARD, Uniform(-4.0), 64)
>>> bool(sol.success and sol.min_eigenvalue > 0 and abs(sol.tip[0] - 0.3) < 1e-12)
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from simgrip.params import DimensionlessParams, check_grip
from simgrip.reference.arguments import check_count, check_discrete
from simgrip.reference.minimiser import (
    DiscreteEnergy,
    DiscreteEquilibrium,
    EnergyTerms,
    NewtonResult,
    angles_from_guess,
    energy_terms,
    equilibrium_fields,
    grip_sign,
    minimise,
)

__all__ = ["DiscreteSolution", "discrete_energy", "discrete_from_continuous", "solve_discrete", "stability_eigenvalue"]


@dataclass(frozen=True)
class DiscreteSolution(DiscreteEquilibrium):
    """Equilibrium of the paper's nodal scheme (eqs. 25-33).

    Attributes
    ----------
    grip : str
        ``"free"``, ``"I"``, ``"II"`` or ``"III"``.
    K : int
        Number of elements; ``ds = 1/K``.
    params : DimensionlessParams
    s, theta, x, y : ndarray, shape (K+1,)
        Nodes, nodal angles (``theta[0] = 0``) and trapezoid-rule positions.
    tip : ndarray (2,)
        ``(x[K], y[K])``.
    contact : ndarray (2,) or None
        Contact point (the tip for I/II, node ``I`` for III, None for free).
    N1, N2, energy, min_eigenvalue, gradient_norm, iterations, success
        See :class:`~simgrip.reference.minimiser.DiscreteEquilibrium`; the
        eigenvalue's metric is the trapezoid rule on the nodes.
    gamma : float or None
        Grip III: the contact arc length actually used, ``I ds``.
    gravity : float
        Factor on the rod's weight the solution was computed with.
    """

    grip: str
    K: int
    params: DimensionlessParams
    s: np.ndarray
    theta: np.ndarray
    x: np.ndarray
    y: np.ndarray
    tip: np.ndarray
    contact: np.ndarray | None
    gamma: float | None = None
    gravity: float = 1.0

    @property
    def ds(self) -> float:
        return 1.0 / self.K

    def theta_at(self, s) -> np.ndarray:
        """Piecewise-linear interpolation of the nodal angles."""
        return np.interp(s, self.s, self.theta)


def _nodal_problem(grip, params, prof, K, gamma, gravity=1.0):
    ds = 1.0 / K
    s = np.arange(K + 1) * ds
    wt = np.full(K + 1, ds)
    wt[0] = wt[-1] = 0.5 * ds
    rest = np.asarray(prof.integral(s[:-1], s[1:]), dtype=float)  # = kbar_i ds
    k = np.full(K, 1.0 / ds)
    a = gravity * wt[1:] * (1.0 - s[1:])
    lin = np.zeros(K)
    w = None
    c0 = 0.0
    I = None
    if grip in ("I", "II"):
        a = a + params.M * wt[1:]
        w = wt[1:].copy()
        c0 = wt[0] - 0.5 * params.b
    elif grip == "III":
        I = int(round(gamma * K))
        if I * ds <= 0.5 * params.b:
            raise ValueError(
                f"K = {K} is too coarse for gamma = {gamma!r}: the contact node round(gamma K) = {I} sits at "
                f"s = {I * ds:g}, which cannot reach X = b/2 = {0.5 * params.b:g}"
            )
        wc = np.zeros(K + 1)
        wc[:I] = ds
        wc[0] = wc[I] = 0.5 * ds
        a = a + params.M * wc[1:]
        w = wc[1:].copy()
        c0 = wc[0] - 0.5 * params.b
    prob = DiscreteEnergy(params.D, k, rest, a, lin, w, c0, 0.5 * params.b, metric=wt[1:].copy())
    unit_rest = np.full(K, ds)
    return prob, unit_rest, s, I


def discrete_energy(grip, params, profile, K, theta, N1=0.0, *, gamma=None, gravity=1.0, hessian=True) -> EnergyTerms:
    """The paper's ``V_dis`` (eq. 27/32) in ``theta_1 .. theta_K`` with the multiplier fixed at ``N1``.

    ``theta`` may hold ``K`` values (``theta_1..theta_K``) or ``K+1`` (``theta_0`` is
    then dropped; it must be 0).  Returns :class:`EnergyTerms` (value, gradient
    and, if ``hessian``, the Hessian ``L``).
    """
    grip, params, prof, K, gam, grav = check_discrete(grip, params, profile, "K", K, gamma, gravity)
    th = np.asarray(theta, dtype=float)
    if th.shape == (K + 1,):
        th = th[1:]
    prob, _, _, _ = _nodal_problem(grip, params, prof, K, gam, grav)
    return energy_terms(prob, th, N1, hessian)


def solve_discrete(grip, params, profile, K, *, guess=None, gamma=None, gravity=1.0) -> DiscreteSolution:
    """Minimise the paper's discrete energy for one grip.

    Parameters
    ----------
    grip : {"free", "I", "II", "III"}
    params : DimensionlessParams
    profile : CurvatureProfile, float or callable
        Intrinsic curvature ``kappa_bar(s_bar)``.
    K : int
        Number of elements (>= 2).  For Grip III pick ``K`` so that ``gamma K`` is
        an integer (the contact node is ``round(gamma K)``).
    guess : optional
        Start for Newton: ``theta_1..theta_K`` (or ``theta_0..theta_K``), any object
        with ``theta_at(s)`` (e.g. an elastica solution), a solution of another
        resolution, or None (a uniform-curvature shape meeting the constraint,
        with a homotopy fallback).
    gamma : float, optional
        Grip III contact arc length; default ``params.gamma``.
    gravity : float
        Factor on the rod's own weight (1 physical, 0 gravity free).

    Raises
    ------
    ValueError
        Bad ``grip``, ``K``, ``gamma`` or ``guess``.
    DiscreteError
        Newton failed to converge.
    """
    grip, params, prof, K, gam, grav = check_discrete(grip, params, profile, "K", K, gamma, gravity)
    prob, unit_rest, s, I = _nodal_problem(grip, params, prof, K, gam, grav)
    g0 = angles_from_guess(guess, s, K + 1, "K or K+1 nodal angles")
    if g0 is not None:
        g0 = g0[1:] if g0.size == K + 1 else g0
    res = minimise(prob, unit_rest, grip_sign(grip, prof), g0)
    return _nodal_solution(grip, params, K, prob, s, I, res, grav)


def _nodal_solution(grip, params, K, prob, s, I, res: NewtonResult, gravity: float) -> DiscreteSolution:
    ds = 1.0 / K
    theta = np.concatenate([[0.0], res.x])
    wseg = 0.5 * ds
    x = np.concatenate([[0.0], np.cumsum(wseg * (np.cos(theta[1:]) + np.cos(theta[:-1])))])
    y = np.concatenate([[0.0], np.cumsum(wseg * (np.sin(theta[1:]) + np.sin(theta[:-1])))])
    tip = np.array([x[-1], y[-1]])
    contact, gam = None, None
    if grip == "III":
        contact, gam = np.array([x[I], y[I]]), I * ds
    elif grip != "free":
        contact = tip.copy()
    return DiscreteSolution(
        grip=grip, K=K, params=params, s=s, theta=theta, x=x, y=y, tip=tip, contact=contact, gamma=gam,
        gravity=gravity, **equilibrium_fields(prob, res, params.M),
    )


def discrete_from_continuous(continuous, grip, params, profile, K, *, gamma=None) -> DiscreteSolution:
    """:func:`solve_discrete` started from a continuous solution (anything with ``theta_at(s)``).

    Useful to get the paper's stability eigenvalue at a BVP solution: Newton
    then converges in a few steps to the discrete equilibrium nearest to it.
    For Grip III, ``gamma`` defaults to ``continuous.gamma`` when it has one;
    the contact node is ``round(gamma K)``, so pick ``K`` with ``gamma K`` an
    integer (e.g. a multiple of 5 for 0.8) to keep the contact where the BVP has it.
    """
    if not hasattr(continuous, "theta_at"):
        raise ValueError("continuous must have a theta_at(s) method")
    if gamma is None and check_grip(grip) == "III":
        g = getattr(continuous, "gamma", None)
        gamma = g if g is not None and 0.0 < g < 1.0 else None
    return solve_discrete(grip, params, profile, K, guess=continuous, gamma=gamma)


def stability_eigenvalue(solution, K: int = 128) -> float:
    """Stability eigenvalue of the paper's nodal scheme at an elastica solution (over ``rho g l``).

    :attr:`DiscreteSolution.min_eigenvalue` of :func:`discrete_from_continuous`
    with ``K`` elements (Grip III: the first ``K' in [K, 2K]`` that puts ``gamma``
    closest to a node), the smallest eigenvalue of the projected Hessian in the
    ``L^2`` metric; it approximates the continuous one to ``O(1/K^2)`` (see
    :mod:`simgrip.reference.stability`).  ``solution`` is an
    :class:`~simgrip.reference.elastica.ElasticaSolution` without tip load or
    contact couple (the nodal scheme has neither).

    Raises
    ------
    ValueError
        Bad ``solution`` or ``K``.
    DiscreteError
        Newton failed to converge.
    """
    for name in ("grip", "params", "profile", "theta_at", "tip_load", "contact_moment", "gravity"):
        if not hasattr(solution, name):
            raise ValueError(f"solution must be an ElasticaSolution, got {type(solution).__name__}")
    if any(solution.tip_load) or solution.contact_moment:
        raise ValueError("solution: the nodal scheme has no tip load or contact couple; use solve_chain")
    K = check_count("K", K)
    grip, params, gamma = solution.grip, solution.params, None
    if grip == "III":  # the contact sits on node round(gamma K): pick K with gamma on a node
        gamma = solution.gamma
        K = min(range(K, 2 * K + 1), key=lambda k: (abs(gamma * k - round(gamma * k)), k))
    prof = solution.profile
    prob, unit_rest, s, I = _nodal_problem(grip, params, prof, K, params.gamma if gamma is None else gamma,
                                           1.0 if solution.gravity else 0.0)
    g0 = angles_from_guess(solution, s, K + 1, "K or K+1 nodal angles")[1:]
    res = minimise(prob, unit_rest, grip_sign(grip, prof), g0)
    return equilibrium_fields(prob, res, params.M)["min_eigenvalue"]

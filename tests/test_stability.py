"""Tests of simgrip.reference.stability: the projected-Hessian eigenvalue and its normalisation.

The solvers report the smallest eigenvalue of the projected Hessian in the ``L^2``
metric of each scheme's quadrature (trapezoid weights on the paper's nodes, ``ds``
per link of the chain).  Derived in the module docstring: it converges at second
order in ``ds`` to the smallest eigenvalue of the continuous second variation, the
same limit for both schemes.  Checked here against a closed form (the unloaded
cantilever, ``D pi^2 / 4``) and, for the grips, between the two independent
schemes.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sla

from simgrip import STANDARD, Uniform
from simgrip.reference import min_eigenvalue, solve, solve_chain, solve_discrete, stability_eigenvalue
from simgrip.reference.stability import tridiagonal_min_eigenvalue


def _fitted_order(levels, errors) -> float:
    return float(np.polyfit(np.log(1.0 / np.asarray(levels, float)), np.log(np.abs(errors)), 1)[0])


# ---------------------------------------------------------------------------- algebra


def test_min_eigenvalue_projects_on_the_constraint_tangent():
    L = np.diag([1.0, -1.0, 3.0])
    assert min_eigenvalue(L) == pytest.approx(-1.0)
    assert min_eigenvalue(L, np.array([0.0, 2.0, 0.0])) == pytest.approx(1.0)
    assert min_eigenvalue(L, np.array([5.0, 0.0, 0.0])) == pytest.approx(-1.0)
    rng = np.random.default_rng(1)
    A = rng.normal(size=(6, 6))
    L = A + A.T
    a = rng.normal(size=6)
    E = sla.null_space(a[None, :])
    assert min_eigenvalue(L, a) == pytest.approx(np.linalg.eigvalsh(E.T @ L @ E)[0], rel=1e-12)


def test_weighted_eigenvalue_is_the_pencil_eigenvalue():
    """With ``weights`` the eigenvalue is that of ``(E^T L E, E^T W E)`` for any basis ``E``."""
    rng = np.random.default_rng(2)
    A = rng.normal(size=(7, 7))
    L = A + A.T
    a, w = rng.normal(size=7), rng.uniform(0.1, 2.0, 7)
    E = sla.null_space(a[None, :]) @ rng.normal(size=(6, 6))  # a non-orthonormal basis
    expected = sla.eigh(E.T @ L @ E, E.T @ np.diag(w) @ E, eigvals_only=True)[0]
    assert min_eigenvalue(L, a, weights=w) == pytest.approx(expected, rel=1e-10)
    assert min_eigenvalue(L, weights=w) == pytest.approx(sla.eigh(L, np.diag(w), eigvals_only=True)[0], rel=1e-10)
    with pytest.raises(ValueError, match="weights"):
        min_eigenvalue(L, a, weights=-w)


@pytest.mark.parametrize("constrained", [False, True])
def test_tridiagonal_bisection_matches_the_dense_eigenvalue(constrained):
    rng = np.random.default_rng(5)
    m = 30
    diag, off = rng.normal(size=m) + 2.0, rng.normal(size=m - 1)
    w = rng.uniform(0.2, 1.5, m)
    a = rng.normal(size=m) if constrained else None
    L = np.diag(diag) + np.diag(off, 1) + np.diag(off, -1)
    assert tridiagonal_min_eigenvalue(diag, off, a, w) == pytest.approx(min_eigenvalue(L, a, weights=w),
                                                                        abs=1e-13 * np.max(np.abs(L)) / w.min())


# ---------------------------------------------------------------------------- normalisation


@pytest.mark.parametrize("solver", [solve_discrete, solve_chain])
@pytest.mark.parametrize("D, kappa", [(1.0, 0.0), (0.3, -3.0), (7.0, 5.0)])
def test_unloaded_cantilever_eigenvalue_is_the_euler_load(solver, D, kappa):
    """No gravity, no load: ``d2V = D int dtheta'^2``, ``theta(0) = 0``, ``theta'(1)`` free.

    Continuous: ``lambda = D pi^2 / 4`` (mode ``sin(pi s / 2)``; in newtons the cantilever's
    Euler load ``pi^2 EI / (4 l^2)``).  Both schemes have the exact discrete eigenvalue
    ``4 D n^2 sin^2(pi / (4 n))`` (the mode sampled at their unknowns; the Hessian does not
    depend on the rest angles), whose error is ``D pi^4 / (192 n^2)``: second order.
    """
    params = STANDARD.replace(D=D)
    for n in (2, 5, 16, 64, 256):
        lam = solver("free", params, Uniform(kappa), n, gravity=0.0).min_eigenvalue
        assert lam == pytest.approx(4 * D * n**2 * math.sin(math.pi / (4 * n)) ** 2, rel=1e-10)
        assert abs(lam - D * math.pi**2 / 4) <= 1.01 * D * math.pi**4 / (192 * n**2)


# grip, kappa, gamma (0.75: the chain's contact at a link end and the nodal contact on a node
# for every level below), nodal levels, chain levels
GRIP_CASES = {
    "free": (-3.0, None),
    "I": (-5.5, None),
    "II": (5.0, None),
    "III": (-5.0, 0.75),
}
NODAL_LEVELS = (20, 40, 80, 160)
CHAIN_LEVELS = (16, 32, 64, 128)


def _limit(grip, kappa, gamma) -> float:
    """Richardson extrapolation of the nodal scheme at K = 400, 800 (error ~1e-6, far below those tested)."""
    a, b = (solve_discrete(grip, STANDARD, Uniform(kappa), K, gamma=gamma).min_eigenvalue for K in (400, 800))
    return (4 * b - a) / 3


@pytest.mark.parametrize("grip", sorted(GRIP_CASES))
def test_both_schemes_converge_to_one_eigenvalue_at_second_order(grip):
    kappa, gamma = GRIP_CASES[grip]
    lam = _limit(grip, kappa, gamma)
    assert lam > 0
    for solver, levels in ((solve_discrete, NODAL_LEVELS), (solve_chain, CHAIN_LEVELS)):
        err = [solver(grip, STANDARD, Uniform(kappa), n, gamma=gamma).min_eigenvalue - lam for n in levels]
        assert 1.9 <= _fitted_order(levels, err) <= 2.1, (solver.__name__, err)
        # the error itself vanishes (both converge to lam, no leftover factor of ds) under C ds^2
        C = max(abs(e) * n**2 for e, n in zip(err[:-1], levels[:-1]))
        assert abs(err[-1]) <= 1.1 * C / levels[-1] ** 2


@pytest.mark.parametrize("grip", ["I", "II", "III"])
def test_bvp_side_and_chain_report_the_same_eigenvalue(grip):
    """``simgrip solve`` (the nodal scheme at K = 128 started from the BVP) and ``simgrip simulate``
    (the chain at the settled state, n = 32) report one number, equal to discretisation order:
    the difference is bounded by ``C_chain / 32^2 + C_nodal / 128^2``, with the constants taken
    from the coarse levels (n, K = 8, 16) of the same state."""
    kappa, gamma = GRIP_CASES[grip]
    prof = Uniform(kappa)
    lam = _limit(grip, kappa, gamma)
    bvp = stability_eigenvalue(solve(grip, STANDARD, prof, gamma=gamma), 128)
    chain = solve_chain(grip, STANDARD, prof, 32, gamma=gamma).min_eigenvalue
    c_chain = max(abs(solve_chain(grip, STANDARD, prof, n, gamma=gamma).min_eigenvalue - lam) * n**2 for n in (8, 16))
    c_nodal = max(abs(solve_discrete(grip, STANDARD, prof, K, gamma=gamma).min_eigenvalue - lam) * K**2
                  for K in (8, 16))
    assert abs(bvp - chain) <= 1.1 * (c_chain / 32**2 + c_nodal / 128**2), (bvp, chain)
    assert abs(bvp - chain) < 5e-3 * lam


def test_stability_eigenvalue_rejects_what_the_nodal_scheme_cannot_model():
    sol = solve("I", STANDARD, Uniform(-5.5), contact_moment=0.01)
    with pytest.raises(ValueError, match="contact couple"):
        stability_eigenvalue(sol)
    with pytest.raises(ValueError, match="solution"):
        stability_eigenvalue(np.zeros(3))
    with pytest.raises(ValueError, match="K"):
        stability_eigenvalue(solve("I", STANDARD, Uniform(-5.5)), 1)

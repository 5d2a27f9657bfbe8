"""The linearised elastica's eigenproblem (simgrip.modes.rod) against closed forms, and its two solvers.

Closed forms (dimensionless: l = rho = g = 1, EI = D, omega over sqrt(g/l)):

* Euler-Bernoulli cantilever, weightless: 1 + cos x cosh x = 0, omega = x^2 sqrt(D) (omega^2 = EI beta^4 / rho);
* the same with a point mass mu (over rho l) on the tip, moment free:
  1 + cos x cosh x + mu x (cos x sinh x - sin x cosh x) = 0 (the tip of a straight horizontal rod moves only
  transversely);
  (a straight rod with a pinned or sticking tip is degenerate, its axial force decouples: the sticking tip
  is checked on the curled Grip I, against the chain in tests/test_modes.py and solve_bvp here);
* Greenhill's standing heavy column (gravity's geometric stiffness): omega_1 = 0 at rho g l^3 / EI =
  (3/2 j)^2, j the first zero of J_{-1/3} (7.8373...).

The collocation is spectral for these smooth coefficients: its two resolutions agree to ~1e-12, so the
tolerances below (1e-8 relative) only leave room for the root finding of the closed forms (brentq, xtol 1e-14).
"""

import math

import numpy as np
import pytest
from scipy.integrate import simpson
from scipy.optimize import brentq
from scipy.special import jv

from simgrip import DimensionlessParams, STANDARD, Uniform
from simgrip.modes.rod import RodProblem, problem_of, refine, rod_modes
from simgrip.reference import elastica

EB = (3.5160, 22.0345, 61.6972)  # the (beta l)^2, 4 decimals


def roots(f, brackets):
    return np.array([brentq(f, a, b, xtol=1e-14) for a, b in brackets])


CANTILEVER = roots(lambda x: 1 + math.cos(x) * math.cosh(x), [(1, 2.5), (4, 5.5), (7, 8.5)])


def straight(D, tip="free", tip_mass=0.0):
    return RodProblem(theta0=lambda s: 0.0 * s, D=D, gravity=0.0, tip=tip, tip_mass=tip_mass)


@pytest.mark.parametrize("D", [1.0, 1e4])
def test_euler_bernoulli_cantilever(D):
    r = rod_modes(straight(D), 3)
    assert np.allclose(r.omega / math.sqrt(D), CANTILEVER ** 2, rtol=1e-8, atol=0)
    assert np.allclose(CANTILEVER ** 2, EB, atol=5e-5)  # the numbers, to their 4 decimals


def test_tip_mass():
    mu = 5.0
    eq = roots(lambda x: 1 + math.cos(x) * math.cosh(x) + mu * x * (math.cos(x) * math.sinh(x)
                                                                    - math.sin(x) * math.cosh(x)),
               [(0.1, 1.5), (3.5, 5.0), (6.5, 8.0)])
    assert np.allclose(rod_modes(straight(1.0, "mass", mu), 3).omega, eq ** 2, rtol=1e-8, atol=0)


def test_greenhill_column_loses_its_first_frequency():
    j = brentq(lambda x: jv(-1.0 / 3.0, x), 1.0, 3.0, xtol=1e-15)
    q = (1.5 * j) ** 2  # 7.8373...
    up = lambda D: RodProblem(theta0=lambda s: 0.0 * s + math.pi / 2, D=D)  # noqa: E731 - clamped pointing up
    # omega_1^2 changes sign within 1e-6 of Greenhill's load: stable above D = 1/q, buckled below
    assert rod_modes(up(1.0 / (q * (1 - 1e-6))), 1).lam[0] > 0 > rod_modes(up(1.0 / (q * (1 + 1e-6))), 1).lam[0]


@pytest.mark.parametrize("grip, kappa, params", [("free", -3.0, DimensionlessParams(D=1.0)),
                                                 ("I", -6.0, STANDARD)])
def test_collocation_agrees_with_solve_bvp(grip, kappa, params):
    """Two solvers of one eigenproblem: Chebyshev collocation and solve_bvp (omega^2 a parameter, int |u|^2 = 1).
    solve_bvp's tolerance 1e-6 is relative to the residual, so the eigenvalues agree to ~1e-7."""
    P = problem_of(elastica.solve(grip, params, Uniform(kappa)))
    r = rod_modes(P, 3)
    assert r.error_estimate < 1e-8
    lam = np.array([refine(P, r, k, 1e-6)[0] for k in range(3)])
    assert np.allclose(lam, r.lam, rtol=1e-6, atol=0)


def test_mode_shapes_are_normalised_and_resolution_independent():
    P = problem_of(elastica.solve("free", DimensionlessParams(D=1.0), Uniform(-3.0)))
    a, b = rod_modes(P, 3, 32), rod_modes(P, 3, 48)
    s = np.linspace(0, 1, 41)
    for k in range(3):
        ua, ub = a.displacement(k, s), b.displacement(k, s)
        assert np.max(np.abs(ua - ub)) < 1e-8
        # Simpson on 40 steps: error ~ (1/40)^4 max|(u^2)^(4)| / 180, below 1e-5 for these three shapes
        assert math.isclose(simpson(np.sum(ua ** 2, axis=1), x=s), 1.0, rel_tol=1e-5)


def test_bad_arguments_are_named():
    with pytest.raises(ValueError, match="D must"):
        rod_modes(straight(-1.0))
    with pytest.raises(ValueError, match="tip must"):
        rod_modes(RodProblem(theta0=np.zeros_like, D=1.0, tip="glued"))
    with pytest.raises(ValueError, match="count must"):
        rod_modes(straight(1.0), 0)
    with pytest.raises(ValueError, match="nodes must"):
        rod_modes(straight(1.0), 3, 1000)
    with pytest.raises(ValueError, match="solution"):
        problem_of(elastica.solve("free", STANDARD, Uniform(-1.0), tip_load=(0.0, -1.0)))


@pytest.mark.parametrize("tip", ["stick", "fixed"])
def test_interior_contact_tends_to_the_tip_contact(tip):
    """Grip III's two-segment problem (contact at gamma < 1, free tip beyond) tends to the tip contact as
    gamma -> 1, at first order in 1 - gamma (the eigenvalues are smooth in gamma): the change shrinks tenfold
    from 1 - gamma = 1e-4 to 1e-5."""
    def lam(gamma):
        P = RodProblem(theta0=lambda s: -3.0 * s, D=1.0, tip_force=(5.0, -5.0), tip=tip, tip_mass=5.0,
                       contact=gamma)
        return rod_modes(P, 3, 24).lam  # smooth coefficients: 24 intervals per segment resolve these to ~1e-12

    tip_lam = lam(1.0)
    d4, d5 = lam(1 - 1e-4) / tip_lam - 1, lam(1 - 1e-5) / tip_lam - 1
    assert np.all(np.abs(d4 / d5 - 10.0) < 0.5), (d4, d5)
    with pytest.raises(ValueError, match="contact"):
        rod_modes(RodProblem(theta0=np.zeros_like, D=1.0, contact=0.5))

"""Curvature profiles: values, exact integrals, and validation of user callables."""

import numpy as np
import pytest
from scipy.special import beta as beta_fn

from simgrip.profiles import Concentrated, CurvatureProfile, Uniform, UserProfile, as_profile


def test_uniform_values_and_integral():
    p = Uniform(-3.0)
    s = np.linspace(0, 1, 5)
    assert np.all(p(s) == -3.0)
    assert np.isclose(p.integral(0.2, 0.7), -1.5, rtol=0, atol=1e-15)


def test_concentrated_matches_eq34():
    p = Concentrated(kappa_max=6.0, alpha=2.0, p=-1)
    s = np.array([0.0, 0.25, 0.5, 1.0])
    np.testing.assert_allclose(p(s), -6.0 * (4 * s * (1 - s)) ** 2)
    assert p(0.5) == -6.0  # the peak is p*kappa_max


@pytest.mark.parametrize("alpha", [1.0, 2.0, 3.0])
def test_concentrated_integral_exact_for_polynomial_profiles(alpha):
    # int_0^1 (4 s (1-s))^alpha ds = 4^alpha B(alpha+1, alpha+1); Gauss-Legendre-16 is exact for degree <= 31.
    p = Concentrated(kappa_max=1.0, alpha=alpha, p=1)
    exact = 4.0**alpha * beta_fn(alpha + 1, alpha + 1)
    assert np.isclose(p.integral(0.0, 1.0), exact, rtol=1e-14)


def test_integral_is_additive_and_vectorised():
    p = Concentrated(kappa_max=4.0, alpha=1.5, p=1)
    edges = np.linspace(0, 1, 33)
    parts = p.integral(edges[:-1], edges[1:])
    assert parts.shape == (32,)
    assert np.isclose(parts.sum(), p.integral(0.0, 1.0), rtol=1e-12)


def test_scaled_profiles():
    assert Uniform(2.0).scaled(-0.5) == Uniform(-1.0)
    c = Concentrated(6.0, 2.0, -1).scaled(-0.5)
    assert (c.kappa_max, c.alpha, c.p) == (3.0, 2.0, 1)
    u = UserProfile(lambda s: np.sin(s)).scaled(2.0)
    assert np.isclose(u(0.3), 2 * np.sin(0.3))


def test_user_profile_scalar_result_is_broadcast():
    u = UserProfile(lambda s: 1.5)
    assert u(np.zeros(4)).shape == (4,)


@pytest.mark.parametrize(
    "func, match",
    [
        (lambda s: np.full_like(s, np.nan), "non-finite"),
        (lambda s: np.zeros(3), "shape"),
        (lambda s: 1 / (s - s), "non-finite"),
    ],
)
def test_user_profile_rejects_bad_callables(func, match):
    with np.errstate(all="ignore"), pytest.raises(ValueError, match=match):
        UserProfile(func)


@pytest.mark.parametrize(
    "kwargs, name",
    [({"kappa_max": -1.0}, "kappa_max"), ({"alpha": float("nan")}, "alpha"), ({"p": 0}, r"\bp\b")],
)
def test_concentrated_rejects_bad_values(kwargs, name):
    with pytest.raises(ValueError, match=name):
        Concentrated(**kwargs)


def test_as_profile():
    assert as_profile(2) == Uniform(2.0)
    with pytest.raises(ValueError, match="kappa"):
        as_profile(float("nan"))
    with pytest.raises(ValueError, match="profile"):
        UserProfile("not callable")


@pytest.mark.parametrize("alpha", [0.5, 1.5, 2.7])
def test_concentrated_integral_exact_for_fractional_alpha(alpha):
    # compare with adaptive quadrature on a fine split (the profile ~ s^alpha near the ends)
    from scipy.integrate import quad

    p = Concentrated(kappa_max=3.0, alpha=alpha, p=-1)
    for a, b in [(0.0, 1e-3), (0.0, 0.5), (0.3, 0.9), (0.999, 1.0)]:
        ref, _ = quad(lambda s: float(p(s)), a, b, epsabs=1e-15, epsrel=1e-13, limit=200)
        assert np.isclose(p.integral(a, b), ref, rtol=1e-11, atol=1e-16)


@pytest.mark.parametrize(
    "make, name",
    [
        (lambda: Uniform(101.0), "kappa"),
        (lambda: Uniform(-1e6), "kappa"),
        (lambda: Concentrated(kappa_max=1e3), "kappa_max"),
        (lambda: Concentrated(alpha=520.0), "alpha"),
        (lambda: Concentrated(p=True), "p"),
    ],
)
def test_profile_bounds_are_named(make, name):
    with pytest.raises(ValueError, match=rf"^{name} must"):
        make()


@pytest.mark.parametrize("alpha", [0.0, 3.0, 100.0])
def test_concentrated_integral_in_log_space_matches_quadrature(alpha):
    """4^alpha B(a+1, a+1) is evaluated in log space; compare with Gauss-Legendre on fine panels."""
    prof = Concentrated(kappa_max=6.0, alpha=alpha, p=-1)
    edges = np.linspace(0.0, 1.0, 401)
    quad = float(np.sum(CurvatureProfile.integral(prof, edges[:-1], edges[1:])))
    assert float(prof.integral(0.0, 1.0)) == pytest.approx(quad, rel=1e-12)
    assert np.isfinite(prof.integral(np.array([0.0, 0.3]), np.array([0.5, 1.0]))).all()

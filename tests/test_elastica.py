"""Tests of the continuous elastica reference (simgrip.reference.elastica).

Tolerances come from the method: ``solve`` runs ``solve_bvp`` at ``tol = 1e-8``
(relative collocation residual of a 4th-order method); measured tip errors
against ``tol = 1e-11`` are ~1e-12, so agreement to 1e-8 is a check with
margin, not a tuned number.  Checks against other theories use their own
neglected order (stated where used).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from simgrip import STANDARD, Concentrated, DimensionlessParams, Uniform
from simgrip.reference.capacity import least_mu, max_load
from simgrip.reference.elastica import (
    FINE_POINTS,
    ElasticaError,
    ElasticaSolution,
    kappa_sweep,
    solve,
    sweep,
)

_GL_X, _GL_W = np.polynomial.legendre.leggauss(40)


def _quad(f, a, b):
    """Gauss-Legendre integral of a vectorised ``f`` on ``[a, b]`` (40 points)."""
    if b <= a:
        return 0.0
    x = 0.5 * (a + b) + 0.5 * (b - a) * _GL_X
    return 0.5 * (b - a) * float(np.sum(_GL_W * f(x)))


def _balance_moment(sol: ElasticaSolution, s0: float, contact_on_clamp_side: bool = True) -> float:
    """Moment (E3) that the rod beyond ``s0`` exerts on the part before it, from the
    global balance of the piece ``[s0, 1]`` computed by quadrature of the shape:
    weight, contact force (and couple) and tip load.  Independent of the ODEs.

    ``contact_on_clamp_side=False`` evaluates the moment with the contact force
    acting only on ``(gamma, 1)``, as the paper's printed eq. (21) would have it.
    """
    g = 1.0 if sol.gravity else 0.0
    r0 = sol.position_at(np.array([s0]))[0]

    def xs(s):
        return sol.position_at(s)[:, 0] - r0[0]

    m = 0.0
    # Weight -g E2 per length on [s0, 1]: moment (r - r0) x (-g E2) = -g (X - X0).
    if sol.grip == "III":
        m += -g * (_quad(xs, s0, sol.gamma) + _quad(xs, max(s0, sol.gamma), 1.0))
    else:
        m += -g * _quad(xs, s0, 1.0)
    # Tip load.
    d = sol.tip - r0
    t1, t2 = sol.tip_load
    m += d[0] * t2 - d[1] * t1
    # Contact force N1 E1 + N2 E2 at the contact point, with its couple.
    if sol.contact is not None:
        beyond = s0 < sol.gamma if contact_on_clamp_side else s0 >= sol.gamma
        if beyond:
            d = sol.contact - r0
            m += d[0] * sol.N2 - d[1] * sol.N1 + sol.contact_moment
    return m


# --------------------------------------------------------------------------- fixtures


@pytest.fixture(scope="module")
def grip_sweeps():
    """The paper's standard sweeps (Figs. 7-9) at a 0.25 step in kappa_bar."""
    ks = {
        "I": np.linspace(0.0, -6.0, 25),
        "II": np.linspace(0.0, 6.0, 25),
        "III": np.linspace(0.0, -10.0, 41),
    }
    return {g: (k, kappa_sweep(g, STANDARD, k)) for g, k in ks.items()}


@pytest.fixture(scope="module")
def concentrated_sweeps():
    """Eq. (34) with kappa_max = 6, alpha in [1, 3] (Figs. 13-15)."""
    alphas = np.linspace(1.0, 3.0, 9)
    out = {}
    for grip, p in (("I", -1), ("II", 1), ("III", -1)):
        out[grip] = (alphas, sweep(grip, STANDARD, [Concentrated(6.0, a, p) for a in alphas]))
    return out


# --------------------------------------------------------------------------- free rod


@pytest.mark.parametrize("kappa", [-6.0, -1.0, 0.0, 2.5, 10.0])
def test_free_rod_without_gravity_is_a_circular_arc(kappa):
    sol = solve("free", STANDARD, Uniform(kappa), gravity=False)
    if kappa == 0.0:
        expected = np.array([1.0, 0.0])
    else:
        expected = np.array([math.sin(kappa) / kappa, (1.0 - math.cos(kappa)) / kappa])
    np.testing.assert_allclose(sol.tip, expected, rtol=0, atol=1e-8)
    np.testing.assert_allclose(sol.theta, kappa * sol.s, rtol=0, atol=1e-8)
    np.testing.assert_allclose(sol.moment, 0.0, atol=1e-8)
    assert sol.success and sol.residual < 1e-8
    assert sol.s.size >= 201 and sol.s.size == FINE_POINTS
    assert sol.contact is None and sol.gamma is None
    assert sol.feasible and sol.feasibility == {} and sol.required_mu == 0.0
    assert sol.N1 == sol.N2 == sol.n == sol.f == 0.0


@pytest.mark.parametrize("D", [1e3, 1e4])
def test_self_weight_small_deflection_matches_linear_beam_theory(D):
    # Linear theory: w(1) = -1/(8D).  The neglected terms are O(theta^2) relative,
    # theta ~ 1/(6D) the tip rotation; the bound below is that order.
    sol = solve("free", STANDARD.replace(D=D), 0.0)
    w_lin = -1.0 / (8.0 * D)
    theta_tip = 1.0 / (6.0 * D)
    assert abs(sol.tip[1] - w_lin) <= abs(w_lin) * theta_tip**2
    assert sol.theta[-1] == pytest.approx(-theta_tip, rel=theta_tip)


@pytest.mark.parametrize("P", [1e-3, -2e-3])
def test_tip_load_small_deflection_matches_linear_beam_theory(P):
    D = 1.0
    sol = solve("free", STANDARD.replace(D=D), 0.0, gravity=False, tip_load=(0.0, P))
    w_lin = P / (3.0 * D)
    theta_tip = abs(P) / (2.0 * D)
    assert abs(sol.tip[1] - w_lin) <= abs(w_lin) * theta_tip**2
    # The shortening is second order: 1 - X(1) = (1/2) int w'^2 = P^2 / (15 D^2).
    assert 1.0 - sol.tip[0] == pytest.approx(P**2 / (15.0 * D**2), rel=4 * theta_tip**2)


def test_bisshopp_drucker_cantilever():
    # PL^2/EI = 1: w/L = 0.30172, u/L = 0.05643 (Bisshopp & Drucker 1945, 5 decimals).
    sol = solve("free", STANDARD.replace(D=1.0), 0.0, gravity=False, tip_load=(0.0, -1.0))
    assert abs(-sol.tip[1] - 0.30172) < 5e-6
    assert abs((1.0 - sol.tip[0]) - 0.05643) < 5e-6


@pytest.mark.parametrize(
    "grip, kappa", [("free", -4.0), ("I", -5.0), ("II", 5.0), ("III", -4.0)]
)
def test_self_convergence(grip, kappa):
    loose = solve(grip, STANDARD, Uniform(kappa), tol=1e-6)
    tight = solve(grip, STANDARD, Uniform(kappa), tol=1e-10)
    assert tight.mesh_size > loose.mesh_size
    assert np.max(np.abs(loose.tip - tight.tip)) < 1e-6
    assert abs(loose.N1 - tight.N1) < 1e-6 * max(1.0, abs(tight.N1))


def test_interpolants_agree_with_grid():
    sol = solve("III", STANDARD, Uniform(-4.0))
    np.testing.assert_allclose(sol.theta_at(sol.s), sol.theta, atol=1e-14)
    pos = sol.position_at(sol.s)
    assert pos.shape == (sol.s.size, 2)
    np.testing.assert_allclose(pos[:, 0], sol.x, atol=1e-14)
    np.testing.assert_allclose(pos[:, 1], sol.y, atol=1e-14)
    assert sol.position_at(0.5).shape == (2,)
    assert np.isclose(sol.s, sol.gamma).sum() == 1


# --------------------------------------------------------------------------- grips: balance


@pytest.mark.parametrize("grip, kappa", [("I", -5.0), ("I", -1.0), ("II", 5.5), ("III", -4.0), ("III", -7.0)])
def test_grip_constraint_and_global_balance(grip, kappa):
    sol = solve(grip, STANDARD, Uniform(kappa))
    assert sol.success and sol.residual < 1e-8
    assert sol.contact[0] == pytest.approx(STANDARD.b / 2, abs=1e-10)
    assert sol.N2 == -STANDARD.M
    # Moment balance of every piece [s0, 1], from quadrature of the shape; the
    # ODE's moment must match it.  Interpolant error ~1e-10, so 1e-7 has margin.
    s_checks = [0.0, 0.13, 0.37, 0.61, 0.79, 0.81, 0.95]
    for s0 in s_checks:
        expected = _balance_moment(sol, s0)
        assert sol.moment_at(s0) == pytest.approx(expected, abs=1e-7), s0
    # m = D (theta' - kappa0), theta' by central differences (error O(h^2) ~ 1e-5).
    h = 1e-3
    for s0 in (0.2, 0.5, 0.9):
        if sol.gamma is not None and abs(s0 - sol.gamma) < 2 * h:
            continue
        dth = (sol.theta_at(s0 + h) - sol.theta_at(s0 - h)) / (2 * h)
        assert STANDARD.D * (dth - kappa) == pytest.approx(sol.moment_at(s0), abs=1e-4)
    # Clamp reaction: the force the clamp exerts equals minus the total of the
    # other external forces (weight -1 E2, contact force).
    clamp = -np.array([sol.N1, sol.N2 - 1.0])
    assert np.all(np.isfinite(clamp))
    assert sol.moment[0] == pytest.approx(_balance_moment(sol, 0.0), abs=1e-7)


def test_grip_III_contact_force_acts_between_clamp_and_contact():
    """The erratum of eq. (21): the contact terms belong on (0, gamma)."""
    sol = solve("III", STANDARD, Uniform(-5.0))
    gam = sol.gamma
    # Beyond the contact the rod carries only its own weight.
    for s0 in (gam + 1e-9, 0.85, 0.9):
        assert sol.moment_at(s0) == pytest.approx(_balance_moment(sol, s0), abs=1e-7)
    # Before it, the balance includes the contact force ...
    for s0 in (0.1, 0.4, 0.7):
        right = _balance_moment(sol, s0, contact_on_clamp_side=True)
        printed = _balance_moment(sol, s0, contact_on_clamp_side=False)
        assert sol.moment_at(s0) == pytest.approx(right, abs=1e-7)
        # ... and the printed placement misses it by O(1): the test can tell them apart.
        assert abs(sol.moment_at(s0) - printed) > 0.1
    # Frame of the contact force: F = f e1 + n e2.
    thg = sol.theta_at(gam)
    e1 = np.array([math.cos(thg), math.sin(thg)])
    e2 = np.array([-math.sin(thg), math.cos(thg)])
    F = np.array([sol.N1, sol.N2])
    assert sol.f == pytest.approx(F @ e1, abs=1e-12)
    assert sol.n == pytest.approx(F @ e2, abs=1e-12)
    assert sol.contact == pytest.approx(sol.position_at(gam), abs=1e-12)


@pytest.mark.parametrize("grip, kappa", [("I", -5.0), ("II", 5.0), ("III", -4.0), ("free", -3.0)])
def test_contact_moment(grip, kappa):
    C = 0.3
    sol = solve(grip, STANDARD, Uniform(kappa), contact_moment=C)
    base = solve(grip, STANDARD, Uniform(kappa))
    assert sol.contact_moment == C
    if grip == "III":
        gam = sol.gamma
        jump = sol.moment_at(gam + 1e-12) - sol.moment_at(gam)
        assert jump == pytest.approx(-C, abs=1e-7)
        for s0 in (0.3, 0.9):
            assert sol.moment_at(s0) == pytest.approx(_balance_moment(sol, s0), abs=1e-7)
    else:
        assert sol.moment[-1] == pytest.approx(C, abs=1e-9)
        for s0 in (0.0, 0.5):
            if grip == "free":
                # the couple at the tip enters every piece's balance
                m_free = _balance_moment(sol, s0) + C
                assert sol.moment_at(s0) == pytest.approx(m_free, abs=1e-7)
            else:
                assert sol.moment_at(s0) == pytest.approx(_balance_moment(sol, s0), abs=1e-7)
    # A couple bending the finger against its curl changes the equilibrium.
    assert np.max(np.abs(sol.theta - base.theta)) > 1e-3


def test_gamma_override():
    sol = solve("III", STANDARD, Uniform(-5.0), gamma=0.7)
    assert sol.gamma == 0.7
    assert sol.position_at(0.7)[0] == pytest.approx(STANDARD.b / 2, abs=1e-10)
    with pytest.raises(ValueError, match="gamma"):
        solve("III", STANDARD, Uniform(-5.0), gamma=1.2)


# --------------------------------------------------------------------------- standard sweeps


def _window(ks, sols):
    feas = np.array([s.feasible for s in sols])
    return ks[feas]


# Window edges at the standard case, measured with this module (tol 1e-8,
# edges by Brent's method to 1e-10): a regression guard, and what the figures shade.
STANDARD_WINDOWS = {"I": (-6.0, -4.741539), "II": (4.519007, 6.0), "III": (-5.716817, -2.838146)}


def test_feasible_windows_at_the_standard_case(grip_sweeps):
    """Each grip has one feasible window; flags agree with the raw numbers, and at
    each refined edge one condition is exactly marginal."""
    from scipy.optimize import brentq

    from simgrip.reference.capacity import margin as _margin

    mu = STANDARD.mu_s
    for grip, (ks, sols) in grip_sweeps.items():
        for s in sols:
            assert s.success and s.residual < 1e-8
            assert s.contact[0] == pytest.approx(STANDARD.b / 2, abs=1e-10)
            ok = s.normal_force > 0 and abs(s.friction_force) <= mu * s.normal_force
            if grip == "III":
                assert s.feasibility["tip_clear"] == bool(s.tip[1] < s.contact[1])
                ok = ok and s.tip[1] < s.contact[1]
            assert s.feasible == ok
            assert s.feasible == (_margin(s) >= 0)
            if s.normal_force > 0:
                assert s.required_mu == pytest.approx(abs(s.friction_force) / s.normal_force)
            else:
                assert s.required_mu == math.inf
        flags = np.array([s.feasible for s in sols])
        idx = np.flatnonzero(flags)
        assert idx.size > 0 and np.all(np.diff(idx) == 1), grip  # one contiguous window
        edges = []
        for i in np.flatnonzero(flags[:-1] != flags[1:]):
            k = brentq(
                lambda k: _margin(solve(grip, STANDARD, Uniform(k), guess=sols[i])), ks[i], ks[i + 1], xtol=1e-10
            )
            edge = solve(grip, STANDARD, Uniform(k), guess=sols[i])
            marginal = [edge.required_mu - mu]
            if grip == "III":
                marginal.append(edge.tip[1] - edge.contact[1])
            assert min(abs(v) for v in marginal) < 1e-8
            edges.append(k)
        lo, hi = STANDARD_WINDOWS[grip]
        full = sorted(edges + [ks[idx[0]], ks[idx[-1]]])
        assert full[0] == pytest.approx(lo, abs=1e-5) and full[-1] == pytest.approx(hi, abs=1e-5), (grip, edges)


def test_small_curvature_grip_I_pulls(grip_sweeps):
    ks, sols = grip_sweeps["I"]
    assert sols[0].N1 < 0 and not sols[0].feasibility["contact"]
    assert sols[0].tip[0] == pytest.approx(0.3, abs=1e-10)


def test_normal_force_grows_with_curvature_in_feasible_part(grip_sweeps):
    for grip, (ks, sols) in grip_sweeps.items():
        n = np.array([s.normal_force for s in sols if s.feasible])
        assert n.size >= 3
        assert np.all(np.diff(n) > 0), grip


def test_grip_I_tip_height_nearly_linear_in_feasible_range(grip_sweeps):
    ks, sols = grip_sweeps["I"]
    k = np.array([kk for kk, s in zip(ks, sols) if s.feasible])
    h = np.array([s.tip[1] for s in sols if s.feasible])
    coef = np.polyfit(k, h, 1)
    resid = h - np.polyval(coef, k)
    r2 = 1.0 - np.sum(resid**2) / np.sum((h - h.mean()) ** 2)
    assert r2 > 0.99


def test_palm_up_pinches_harder_than_palm_down(grip_sweeps):
    """Same |kappa|: N(II) > N(I) over the feasible windows.

    (Below |kappa| ~ 4.1 it is the other way round on these branches; the
    paper's statement is about the gripping regime.)"""
    k1, s1 = grip_sweeps["I"]
    k2, s2 = grip_sweeps["II"]
    np.testing.assert_allclose(-k1, k2)
    either = [a.feasible or b.feasible for a, b in zip(s1, s2)]
    assert sum(either) >= 3
    for a, b, e in zip(s1, s2, either):
        if e:
            assert b.N1 > a.N1


def test_grip_III_friction_changes_sign(grip_sweeps):
    ks, sols = grip_sweeps["III"]
    f = np.array([s.f for s in sols])
    feas = np.array([s.feasible for s in sols])
    changes = np.flatnonzero(np.sign(f[:-1]) != np.sign(f[1:]))
    assert changes.size >= 1
    i = changes[0]
    assert feas[i] and feas[i + 1]  # the friction-free grip lies inside the window
    # Somewhere between, least_mu reaches 0: it is below 0.05 on a fine step.
    from scipy.optimize import brentq

    k0 = brentq(lambda k: solve("III", STANDARD, Uniform(k), guess=sols[i]).f, ks[i], ks[i + 1], xtol=1e-10)
    assert least_mu("III", STANDARD, Uniform(k0)) < 1e-8


def test_concentrating_curvature_does_not_improve_the_grip(concentrated_sweeps):
    uniform = {"I": Uniform(-6.0), "II": Uniform(6.0), "III": Uniform(-6.0)}
    for grip, (alphas, sols) in concentrated_sweeps.items():
        cap = np.array([STANDARD.mu_s * s.normal_force for s in sols])
        assert np.all(np.diff(cap) < 0), grip
        assert cap[0] < STANDARD.mu_s * solve(grip, STANDARD, uniform[grip]).normal_force


@pytest.mark.slow
# --------------------------------------------------------------------------- warm starts, errors


def test_warm_start_matches_cold_start():
    cold = solve("III", STANDARD, Uniform(-5.0))
    guess = solve("III", STANDARD, Uniform(-4.5))
    warm = solve("III", STANDARD, Uniform(-5.0), guess=guess)
    assert np.max(np.abs(warm.tip - cold.tip)) < 1e-9
    assert warm.N1 == pytest.approx(cold.N1, abs=1e-8)
    # A guess of another grip is also usable.
    other = solve("I", STANDARD, Uniform(-5.0), guess=cold)
    assert other.tip[0] == pytest.approx(0.3, abs=1e-10)


def test_invalid_inputs_raise_value_error_naming_the_parameter():
    with pytest.raises(ValueError, match="grip"):
        solve("IV", STANDARD, Uniform(-1.0))
    with pytest.raises(ValueError, match="D"):
        solve("I", STANDARD.replace(D=-1.0), Uniform(-1.0))
    with pytest.raises(ValueError, match="tip_load"):
        solve("free", STANDARD, 0.0, tip_load=(1.0,))
    with pytest.raises(ValueError, match="contact_moment"):
        solve("I", STANDARD, -1.0, contact_moment=float("nan"))
    with pytest.raises(ValueError, match="tol"):
        solve("I", STANDARD, -1.0, tol=0.0)
    with pytest.raises(ValueError, match="kappa"):
        solve("I", STANDARD, "abc")
    with pytest.raises(ValueError, match="gamma"):
        # the contact cannot sit at X = b/2 with gamma <= b/2
        solve("III", DimensionlessParams(b=0.9, gamma=0.4), Uniform(-3.0))
    with pytest.raises(ValueError, match="grip"):
        max_load("free", STANDARD, -1.0)
    assert issubclass(ElasticaError, RuntimeError)


@pytest.mark.parametrize(
    "grip, D, M, kappa",
    [
        ("I", 0.01, 5.0, -6.0),  # very soft: hangs, curvature barely matters
        ("III", 100.0, 5.0, -5.0),  # very stiff: N ~ D
        ("I", 1.0, 5.0, -12.0),  # nearly two turns of intrinsic curl
        ("II", 1.0, 5.0, 12.0),
        ("I", 1.0, 0.0, -5.0),  # no load: no friction needed
        ("III", 1.0, 50.0, -6.0),  # heavy workpiece
        ("free", 0.01, 5.0, 12.0),
    ],
)
def test_edge_cases_converge_and_balance(grip, D, M, kappa):
    p = STANDARD.replace(D=D, M=M)
    sol = solve(grip, p, Uniform(kappa))
    assert sol.success and sol.residual < 1e-8
    assert np.all(np.isfinite(sol.theta)) and np.all(np.isfinite(sol.moment))
    scale = max(1.0, float(np.max(np.abs(sol.moment))))
    for s0 in (0.0, 0.3, 0.9):
        assert sol.moment_at(s0) == pytest.approx(_balance_moment(sol, s0), abs=1e-7 * scale)
    if grip != "free":
        assert sol.contact[0] == pytest.approx(p.b / 2, abs=1e-10)
    if M == 0.0 and grip in ("I", "II") and sol.N1 > 0:
        assert sol.required_mu == 0.0 and sol.feasible


def test_fallback_false_only_tries_the_warm_start(monkeypatch):
    from simgrip.reference import elastica
    from simgrip.reference.elastica import ElasticaError

    near = solve("I", STANDARD, Uniform(-5.0))
    assert solve("I", STANDARD, Uniform(-5.1), guess=near, fallback=False).success
    monkeypatch.setattr(elastica, "solve_from", lambda *a, **k: None)  # the warm start fails
    with pytest.raises(ElasticaError, match="fallback=False"):
        solve("I", STANDARD, Uniform(-5.1), guess=near, fallback=False)

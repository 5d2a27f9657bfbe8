"""Tests of the two discrete schemes (simgrip.reference.nodal, .hinge_chain) and their shared minimiser.

Orders of accuracy (derived in the module docstring, measured here): both schemes
are O(ds^2) in tip/contact position and contact force.  The reference is the
continuous BVP (:mod:`simgrip.reference.elastica`, tol 1e-10, whose error is far below the
discretisation errors tested).  The stability eigenvalue is tested in ``test_stability.py``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from simgrip import STANDARD, Concentrated, Uniform
from simgrip.chain import chain_springs
from simgrip.reference import (
    GRADIENT_TOL,
    ChainEquilibrium,
    DiscreteError,
    DiscreteSolution,
    chain_energy,
    discrete_energy,
    discrete_from_continuous,
    min_eigenvalue,
    solve_chain,
    solve_discrete,
)

from simgrip.reference import elastica as _elastica
from simgrip.reference.arguments import MAX_COUNT

LEVELS = (16, 32, 64, 128)
ORDER_BAND = (1.8, 2.2)
SOLVERS = {"nodal": solve_discrete, "chain": solve_chain}

# (grip, profile, gamma): free rod with gravity, Grip I and Grip III; uniform and concentrated.
CASES = {
    "free-uniform": ("free", Uniform(-3.0), None),
    "free-concentrated": ("free", Concentrated(6.0, 2.0, -1), None),
    "I-uniform": ("I", Uniform(-4.0), None),
    "I-concentrated": ("I", Concentrated(6.0, 2.0, -1), None),
    "II-uniform": ("II", Uniform(4.0), None),
    "III-uniform": ("III", Uniform(-6.0), 0.75),
    "III-concentrated": ("III", Concentrated(6.0, 2.0, -1), 0.75),
}


class _Ref:
    def __init__(self, tip, N1, contact=None):
        self.tip, self.N1, self.contact = np.asarray(tip), float(N1), contact


_REF_CACHE: dict = {}


def reference(grip, profile, gamma, params=STANDARD, contact_moment=0.0):
    key = (grip, repr(profile), gamma, params, contact_moment)
    if key not in _REF_CACHE:
        sol = _elastica.solve(grip, params, profile, gamma=gamma, contact_moment=contact_moment, tol=1e-10)
        _REF_CACHE[key] = _Ref(sol.tip, sol.N1, sol.contact)
    return _REF_CACHE[key]


def observed_orders(levels, errors):
    """Pairwise orders and the least-squares order of ``errors ~ C ds^p``."""
    ds = 1.0 / np.asarray(levels, float)
    e = np.asarray(errors, float)
    pairs = np.log(e[:-1] / e[1:]) / np.log(ds[:-1] / ds[1:])
    fit = np.polyfit(np.log(ds), np.log(e), 1)[0]
    return pairs, fit


def assert_second_order(levels, errors, what):
    pairs, fit = observed_orders(levels, errors)
    lo, hi = ORDER_BAND
    assert lo <= fit <= hi, f"{what}: fitted order {fit:.3f}, pairwise {pairs}"
    assert lo <= pairs[-1] <= hi, f"{what}: finest pairwise order {pairs[-1]:.3f}, all {pairs}"
    # C from the coarser levels; the finest error must sit under C ds^2
    C = max(e * n**2 for e, n in zip(errors[:-1], levels[:-1]))
    assert errors[-1] <= 1.1 * C / levels[-1] ** 2, f"{what}: {errors[-1]:.3e} > C ds^2 = {C / levels[-1] ** 2:.3e}"


# ---------------------------------------------------------------------------- arguments


@pytest.mark.parametrize("solver, name", [(solve_discrete, "K"), (solve_chain, "n")])
@pytest.mark.parametrize("bad", [1, 0, -3, 2.5, "8", None, True, float("inf"), float("-inf"), float("nan"), 1e300,
                                 MAX_COUNT + 1])
def test_bad_counts_name_the_parameter(solver, name, bad):
    with pytest.raises(ValueError, match=rf"\b{name}\b"):
        solver("I", STANDARD, -3.0, bad)


@pytest.mark.parametrize("solver", [solve_discrete, solve_chain])
def test_bad_grip_gamma_and_params(solver):
    with pytest.raises(ValueError, match="grip"):
        solver("IV", STANDARD, -3.0, 16)
    with pytest.raises(ValueError, match="gamma"):
        solver("III", STANDARD, -3.0, 16, gamma=1.2)
    with pytest.raises(ValueError, match="params"):
        solver("I", {"D": 1.0}, -3.0, 16)
    with pytest.raises(ValueError, match="gravity"):
        solver("I", STANDARD, -3.0, 16, gravity=-1.0)
    with pytest.raises(ValueError, match="guess"):
        solver("I", STANDARD, -3.0, 16, guess=np.zeros(5))


def test_grip_names_are_normalised_and_results_typed():
    sol = solve_discrete("ii", STANDARD, 3.0, 16)
    eq = solve_chain(" iii", STANDARD, -5.0, 16)
    assert isinstance(sol, DiscreteSolution) and sol.grip == "II"
    assert isinstance(eq, ChainEquilibrium) and eq.grip == "III"
    assert sol.theta.shape == sol.s.shape == sol.x.shape == (17,) and sol.theta[0] == 0.0
    assert eq.nodes.shape == (17, 2) and eq.link_angles.shape == eq.joint_angles.shape == (16,)
    np.testing.assert_allclose(np.cumsum(eq.joint_angles), eq.link_angles, atol=1e-15)
    assert sol.N2 == eq.N2 == -STANDARD.M


def test_newton_failure_raises(monkeypatch):
    import simgrip.reference.minimiser as d

    def never(prob, x0, **kw):
        return d.NewtonResult(np.asarray(x0, float), 0.0, 1.0, 1, False, "forced failure")

    monkeypatch.setattr(d, "newton", never)
    with pytest.raises(DiscreteError, match="did not converge"):
        solve_chain("I", STANDARD, -4.0, 16)
    with pytest.raises(DiscreteError):
        solve_discrete("free", STANDARD, -4.0, 16)


def test_homotopy_fallback_reaches_the_same_state(monkeypatch):
    """If Newton fails from the constrained arc, the arc-to-target homotopy takes over."""
    import simgrip.reference.minimiser as d

    direct = solve_chain("III", STANDARD, Uniform(-8.0), 32)
    real, calls = d.newton, []

    def flaky(prob, x0, **kw):
        calls.append(kw)
        if len(calls) == 1:
            return d.NewtonResult(np.asarray(x0, float), 0.0, 1.0, 1, False, "forced failure")
        return real(prob, x0, **kw)

    monkeypatch.setattr(d, "newton", flaky)
    via = solve_chain("III", STANDARD, Uniform(-8.0), 32)
    assert len(calls) > 3 and via.success
    np.testing.assert_allclose(via.link_angles, direct.link_angles, atol=1e-11)
    assert via.N1 == pytest.approx(direct.N1, rel=1e-11)


# ---------------------------------------------------------------------------- derivatives


def _fd_check(func, x, h=1e-6):
    """Central differences of value -> gradient and gradient -> Hessian."""
    t = func(x)
    g_fd = np.empty_like(x)
    h_fd = np.empty((x.size, x.size))
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = h
        tp, tm = func(x + e), func(x - e)
        g_fd[i] = (tp.value - tm.value) / (2 * h)
        h_fd[:, i] = (tp.gradient - tm.gradient) / (2 * h)
    scale = np.max(np.abs(t.hessian))
    np.testing.assert_allclose(t.gradient, g_fd, atol=1e-7 * scale)
    np.testing.assert_allclose(t.hessian, h_fd, atol=1e-7 * scale)
    np.testing.assert_array_equal(t.hessian, t.hessian.T)


@pytest.mark.parametrize("grip", ["free", "I", "II", "III"])
def test_energy_derivatives_match_finite_differences(grip):
    rng = np.random.default_rng(7)
    prof = Concentrated(5.0, 1.5, -1)
    params = STANDARD.replace(D=0.7, M=3.0)
    K = 10
    th = rng.uniform(-2.5, 1.0, K)
    _fd_check(lambda x: discrete_energy(grip, params, prof, K, x, N1=2.3, gamma=0.6), th)
    phi = rng.uniform(-2.5, 1.0, K)
    _fd_check(
        lambda x: chain_energy(grip, params, prof, K, x, N1=-1.7, gamma=0.63, contact_moment=0.4), phi
    )


def test_energy_values_match_the_paper_sums():
    """``V_dis`` of eq. (27)/(32) written out term by term (independent of the implementation)."""
    rng = np.random.default_rng(3)
    K, N = 8, 1.9
    p = STANDARD.replace(D=1.3, M=2.0)
    prof = Concentrated(4.0, 1.0, -1)
    ds = 1.0 / K
    s = np.arange(K + 1) * ds
    th = np.concatenate([[0.0], rng.uniform(-2, 1, K)])
    kbar = np.array([prof.integral(s[i - 1], s[i]) / ds for i in range(1, K + 1)])
    strain = p.D / 2 * np.sum(((th[1:] - th[:-1]) / ds - kbar) ** 2 * ds)
    w = np.full(K + 1, ds)
    w[0] = w[-1] = ds / 2
    grav = np.sum(w * (1 - s) * np.sin(th))
    v_I = strain + grav + p.M * np.sum(w * np.sin(th)) - N * np.sum(w * np.cos(th))
    assert discrete_energy("I", p, prof, K, th, N1=N).value == pytest.approx(v_I, rel=1e-13)
    I = 5  # gamma = 5/8
    wc = np.where(np.arange(K + 1) <= I, ds, 0.0)
    wc[0] = wc[I] = ds / 2
    v_III = strain + grav + p.M * np.sum(wc * np.sin(th)) - N * np.sum(wc * np.cos(th))
    assert discrete_energy("III", p, prof, K, th, N1=N, gamma=I / K).value == pytest.approx(v_III, rel=1e-13)
    assert discrete_energy("free", p, prof, K, th[1:]).value == pytest.approx(strain + grav, rel=1e-13)


@pytest.mark.parametrize("grip", ["free", "I", "III"])
def test_solutions_are_stationary_with_their_multiplier(grip):
    prof = Concentrated(6.0, 2.0, -1)
    sol = solve_discrete(grip, STANDARD, prof, 40)
    t = discrete_energy(grip, STANDARD, prof, 40, sol.theta, N1=sol.N1)
    assert np.max(np.abs(t.gradient)) < 1e-11 * np.max(np.abs(t.hessian))
    assert t.value == pytest.approx(sol.energy, rel=1e-14, abs=1e-14)
    eq = solve_chain(grip, STANDARD, prof, 40, contact_moment=0.3)
    t = chain_energy(grip, STANDARD, prof, 40, eq.link_angles, N1=eq.N1, contact_moment=0.3)
    assert np.max(np.abs(t.gradient)) < 1e-11 * np.max(np.abs(t.hessian))
    for r in (sol, eq):
        assert r.success and r.gradient_norm <= GRADIENT_TOL
    # the O(K) inertia-bisection eigenvalue equals the dense projected one (eqs. 29-31) in the
    # L^2 metric of each scheme's quadrature: trapezoid weights on the nodes, ds per link;
    # grad X = dE/d(-N1), so the constraint gradient comes from two energy evaluations
    trapezoid = np.full(40, 1 / 40)
    trapezoid[-1] = 1 / 80
    for r, f, args, w in ((sol, discrete_energy, (sol.theta,), trapezoid),
                          (eq, chain_energy, (eq.link_angles,), np.full(40, 1 / 40))):
        kw = {"contact_moment": 0.3} if f is chain_energy else {}
        L = f(grip, STANDARD, prof, 40, *args, N1=r.N1, **kw).hessian
        a = None
        if grip != "free":
            a = f(grip, STANDARD, prof, 40, *args, N1=0.0, **kw).gradient - f(grip, STANDARD, prof, 40, *args, N1=1.0, **kw).gradient
        assert r.min_eigenvalue == pytest.approx(min_eigenvalue(L, a, weights=w), abs=1e-13 * np.max(np.abs(L)) / w.min())
    if grip != "free":
        np.testing.assert_allclose(sol.contact[0], STANDARD.b / 2, atol=1e-14)
        np.testing.assert_allclose(eq.contact[0], STANDARD.b / 2, atol=1e-14)


# ---------------------------------------------------------------------------- convergence


@pytest.mark.parametrize("scheme", sorted(SOLVERS))
@pytest.mark.parametrize("case", sorted(CASES))
def test_second_order_convergence_to_the_bvp(scheme, case):
    grip, prof, gamma = CASES[case]
    ref = reference(grip, prof, gamma)
    levels = LEVELS if not (scheme == "chain" and case == "I-concentrated") else (32, 64, 128, 256)
    sols = [SOLVERS[scheme](grip, STANDARD, prof, k, gamma=gamma) for k in levels]
    tip_err = [np.linalg.norm(s.tip - ref.tip) for s in sols]
    assert_second_order(levels, tip_err, f"{scheme} {case} tip")
    if grip != "free":
        n_err = [abs(s.N1 - ref.N1) for s in sols]
        assert_second_order(levels, n_err, f"{scheme} {case} N1")
        assert n_err[-1] < 2e-3 * abs(ref.N1)


def test_grip_III_at_the_papers_gamma():
    """gamma = 0.8: nodal scheme on K = 20 * 2^k (gamma a node) is second order; the
    chain with gamma strictly inside links keeps its error under C ds^2 (the
    constant depends on where gamma falls in its link, so no clean pairwise order)."""
    prof = Uniform(-6.0)
    ref = reference("III", prof, 0.8)
    levels = (20, 40, 80, 160)
    sols = [solve_discrete("III", STANDARD, prof, k) for k in levels]
    assert all(s.gamma == pytest.approx(0.8, abs=1e-15) for s in sols)
    assert_second_order(levels, [np.linalg.norm(s.tip - ref.tip) for s in sols], "nodal III tip")
    assert_second_order(levels, [abs(s.N1 - ref.N1) for s in sols], "nodal III N1")
    scaled_tip, scaled_n = [], []
    for n in (16, 32, 64, 128, 256):
        eq = solve_chain("III", STANDARD, prof, n)
        assert eq.gamma == 0.8 and 0 < 0.8 * n - eq.contact_link < 1
        scaled_tip.append(np.linalg.norm(eq.tip - ref.tip) * n**2)
        scaled_n.append(abs(eq.N1 - ref.N1) * n**2)
        np.testing.assert_allclose(eq.contact, ref.contact, atol=0.5 / n**2)
    # bounded, not decaying or growing: second order with a constant set by the link fraction
    assert max(scaled_tip) < 3 * min(scaled_tip) and max(scaled_tip) < 1.0
    assert max(scaled_n) < 4 * min(scaled_n) and max(scaled_n) < 15.0


def test_off_node_gamma_is_rounded_in_the_nodal_scheme():
    sol = solve_discrete("III", STANDARD, -6.0, 16)  # 0.8 * 16 = 12.8 -> node 13
    assert sol.gamma == pytest.approx(13 / 16)
    np.testing.assert_allclose(sol.contact, [sol.x[13], sol.y[13]])
    assert sol.contact[0] == pytest.approx(0.3, abs=1e-14)


def test_contact_moment_matches_the_bvp():
    """A point couple at the Grip III contact: same sign convention as elastica.

    The couple loads link ``m`` as a whole, so it is second order when the contact
    sits at the link's midpoint (the BVP is solved at each level's own gamma)."""
    prof, mc = Uniform(-6.0), 0.8
    assert abs(reference("III", prof, 0.75, contact_moment=mc).N1 - reference("III", prof, 0.75).N1) > 0.05
    tip_err, n_err = [], []
    for n in LEVELS:
        gam = (math.floor(0.75 * n) + 0.5) / n
        ref = reference("III", prof, gam, contact_moment=mc)
        eq = solve_chain("III", STANDARD, prof, n, gamma=gam, contact_moment=mc)
        assert eq.contact_moment == mc
        tip_err.append(np.linalg.norm(eq.tip - ref.tip))
        n_err.append(abs(eq.N1 - ref.N1))
    assert_second_order(LEVELS, tip_err, "chain III couple tip")
    assert_second_order(LEVELS, n_err, "chain III couple N1")


@pytest.mark.parametrize("grip", ["free", "I"])
def test_chain_is_second_order_because_of_the_clamp_hinge(grip):
    """With 1/ds and the full rest angle at the clamp the chain is only first order."""
    prof = Uniform(-4.0)
    ref = reference(grip, prof, None)
    good, bad = [], []
    for n in LEVELS:
        sp = chain_springs(prof, n)
        assert sp.stiffness[0] == pytest.approx(2 * n) and sp.rest[0] == pytest.approx(prof.integral(0, 0.5 / n))
        stiff = sp.stiffness.copy()
        stiff[0] = 1.0 / sp.ds
        rest = sp.rest.copy()
        rest[0] = prof.integral(0.0, sp.ds)
        naive = dataclasses.replace(sp, stiffness=stiff, rest=rest)
        good.append(np.linalg.norm(solve_chain(grip, STANDARD, prof, n).tip - ref.tip))
        bad.append(np.linalg.norm(solve_chain(grip, STANDARD, prof, n, springs=naive).tip - ref.tip))
    assert_second_order(LEVELS, good, f"chain {grip}")
    pairs, fit = observed_orders(LEVELS, bad)
    assert 0.85 <= fit <= 1.15 and np.all((pairs > 0.85) & (pairs < 1.15)), (pairs, fit)
    assert bad[-1] > 50 * good[-1]


def test_nodal_and_chain_share_the_limit():
    """Two independent discretisations extrapolate (Richardson) to the same state."""
    prof = Concentrated(6.0, 1.0, -1)
    ext = []
    for solver in (solve_discrete, solve_chain):
        a, b = solver("I", STANDARD, prof, 128), solver("I", STANDARD, prof, 256)
        ext.append(((4 * b.tip - a.tip) / 3, (4 * b.N1 - a.N1) / 3))
    np.testing.assert_allclose(ext[0][0], ext[1][0], atol=2e-8)
    assert ext[0][1] == pytest.approx(ext[1][1], rel=1e-7)


# ---------------------------------------------------------------------------- exact states


@pytest.mark.parametrize("kappa", [-12.0, -3.0, 0.7, 5.0])
@pytest.mark.parametrize("n", [2, 7, 64])
def test_gravity_free_uniform_chain_is_an_inscribed_regular_polygon(kappa, n):
    """Without gravity and load the springs are at rest: q_0 = kappa ds/2, q_j = kappa ds.

    So phi_i = kappa (i + 1/2) ds is the exact arc's tangent at each link's midpoint,
    and the nodes are the vertices of a regular polygon (side ds, turning angle
    kappa ds) inscribed in the circle tangent to E1 at the base with radius
    rho = ds / (2 sin(kappa ds / 2)) (slightly larger than 1/|kappa|), node j at
    central angle j kappa ds.  All exact, to roundoff.
    """
    eq = solve_chain("free", STANDARD, Uniform(kappa), n, gravity=0.0)
    ds = 1.0 / n
    np.testing.assert_allclose(eq.link_angles, kappa * (np.arange(n) + 0.5) * ds, rtol=0, atol=1e-12)
    rho = ds / (2 * math.sin(kappa * ds / 2))
    centre = np.array([0.0, rho])
    np.testing.assert_allclose(np.linalg.norm(eq.nodes - centre, axis=1), abs(rho), rtol=0, atol=1e-12)
    a = kappa * ds * np.arange(n + 1)
    np.testing.assert_allclose(eq.nodes, rho * np.stack([np.sin(a), 1 - np.cos(a)], axis=1), rtol=0, atol=1e-12)
    sol = solve_discrete("free", STANDARD, Uniform(kappa), n, gravity=0.0)
    np.testing.assert_allclose(sol.theta, kappa * sol.s, rtol=0, atol=1e-12)  # nodal tangents exact


# ---------------------------------------------------------------------------- stability


def test_free_rod_eigenvalue_is_the_hessian_eigenvalue():
    sol = solve_discrete("free", STANDARD, -3.0, 32)
    H = discrete_energy("free", STANDARD, -3.0, 32, sol.theta).hessian
    w = np.full(32, 1 / 32)
    w[-1] = 1 / 64
    r = 1 / np.sqrt(w)
    assert sol.min_eigenvalue == pytest.approx(np.linalg.eigvalsh(r[:, None] * H * r[None, :])[0], rel=1e-12)
    # the paper's (Euclidean) eigenvalue scales like ds; the reported one does not
    fine = solve_discrete("free", STANDARD, -3.0, 64)
    assert fine.min_eigenvalue == pytest.approx(sol.min_eigenvalue, rel=0.02)
    H64 = discrete_energy("free", STANDARD, -3.0, 64, fine.theta).hessian
    assert min_eigenvalue(H64) == pytest.approx(min_eigenvalue(H) / 2, rel=0.02)


SWEEPS = {
    "I": (np.linspace(0.0, -6.0, 13), None, 64),
    "II": (np.linspace(0.0, 6.0, 13), None, 64),
    "III": (np.linspace(0.0, -10.0, 21), 0.8, 80),
}


@pytest.mark.parametrize("scheme", sorted(SOLVERS))
@pytest.mark.parametrize("grip", sorted(SWEEPS))
def test_paper_branches_are_stable(scheme, grip):
    """Fig. 11: lambda_min(E^T L E) > 0 along the sweeps (D=1, M=5, mu_s=1, b=0.6), with continuation."""
    kappas, gamma, K = SWEEPS[grip]
    prev, lams = None, []
    for k in kappas:
        sol = SOLVERS[scheme](grip, STANDARD, Uniform(k), K, guess=prev, gamma=gamma)
        assert sol.success
        lams.append(sol.min_eigenvalue)
        prev = sol
    assert min(lams) > 5.0, lams
    if grip != "III":
        assert prev.N1 > STANDARD.M  # the end of each sweep holds the workpiece (mu_s = 1)


def test_newton_from_a_continuous_solution():
    cont = _elastica.solve("I", STANDARD, Uniform(-5.0), tol=1e-8)
    warm = discrete_from_continuous(cont, "I", STANDARD, Uniform(-5.0), 64)
    cold = solve_discrete("I", STANDARD, Uniform(-5.0), 64)
    assert warm.iterations <= 4
    np.testing.assert_allclose(warm.theta, cold.theta, atol=1e-11)
    assert warm.min_eigenvalue == pytest.approx(cold.min_eigenvalue, rel=1e-9)
    eq = solve_chain("I", STANDARD, Uniform(-5.0), 64, guess=warm)  # a solution of the other scheme
    assert eq.iterations <= 5 and eq.success
    with pytest.raises(ValueError, match="theta_at"):
        discrete_from_continuous(np.zeros(3), "I", STANDARD, -5.0, 16)
    # Grip III takes the contact arc length of the continuous solution
    c3 = _elastica.solve("III", STANDARD, Uniform(-6.0), gamma=0.75, tol=1e-8)
    d3 = discrete_from_continuous(c3, "III", STANDARD, Uniform(-6.0), 64)
    assert d3.gamma == 0.75 and d3.iterations <= 5
    assert d3.N1 == pytest.approx(c3.N1, rel=1e-3)


# ---------------------------------------------------------------------------- hardening


@pytest.mark.parametrize("solver", [solve_discrete, solve_chain])
@pytest.mark.parametrize("grip", ["free", "I", "II", "III"])
@pytest.mark.parametrize("D, M, kappa", [(0.01, 50.0, 12.0), (0.01, 0.0, -12.0), (100.0, 50.0, -12.0), (100.0, 0.0, 12.0), (1.0, 5.0, 0.0)])
def test_extreme_parameters_converge(solver, grip, D, M, kappa):
    params = STANDARD.replace(D=D, M=M)
    for n in (2, 3, 24):
        r = solver(grip, params, Uniform(kappa), n)
        assert r.success and r.gradient_norm <= GRADIENT_TOL and np.all(np.isfinite(r.tip))
        if grip != "free":
            assert r.contact[0] == pytest.approx(params.b / 2, abs=1e-13)
            assert r.N2 == -M


def test_fine_chains_are_cheap(monkeypatch):
    """Each Newton step and the stability eigenvalue are O(n): tridiagonal (no dense n x n solve or eigenproblem),
    and the Newton iterations do not grow with n.  Work, not seconds (issue 22, item 8: speed is simgrip bench's;
    the clock below only guards a hang, ~0.02 s alone)."""
    import time

    import scipy.linalg

    def dense(*a, **k):
        raise AssertionError("a dense O(n^3) linear-algebra call")

    for mod, names in ((np.linalg, ("solve", "inv", "eig", "eigh", "eigvalsh", "lstsq")),
                       (scipy.linalg, ("solve", "inv", "eig", "eigh", "eigvalsh", "lstsq", "lu_factor"))):
        for name in names:
            monkeypatch.setattr(mod, name, dense)
    t0 = time.perf_counter()
    its = {}
    for n in (64, 1024):
        eq = solve_chain("I", STANDARD, Uniform(-4.0), n)
        assert eq.success and eq.min_eigenvalue > 0
        its[n] = eq.iterations
    assert its[1024] <= its[64] + 1 <= 7  # measured 3 and 3
    assert time.perf_counter() - t0 < 120.0


@settings(max_examples=40, deadline=None)
@given(
    grip=st.sampled_from(["free", "I", "II", "III"]),
    D=st.floats(0.05, 20.0),
    M=st.floats(0.0, 20.0),
    kappa=st.floats(-10.0, 10.0),
    alpha=st.floats(0.0, 3.0),
    n=st.integers(2, 40),
    gamma=st.floats(0.35, 0.95),
    chain=st.booleans(),
)
def test_random_problems_reach_a_stationary_state(grip, D, M, kappa, alpha, n, gamma, chain):
    params = STANDARD.replace(D=D, M=M)
    prof = Concentrated(abs(kappa), alpha, -1 if kappa < 0 else 1)
    if grip == "III" and not chain and round(gamma * n) / n <= params.b / 2:
        with pytest.raises(ValueError, match="too coarse"):  # the contact node cannot reach X = b/2
            solve_discrete(grip, params, prof, n, gamma=gamma)
        assume(False)
    if chain:
        r = solve_chain(grip, params, prof, n, gamma=gamma)
        t = chain_energy(grip, params, prof, n, r.link_angles, N1=r.N1, gamma=gamma)
    else:
        r = solve_discrete(grip, params, prof, n, gamma=gamma)
        t = discrete_energy(grip, params, prof, n, r.theta, N1=r.N1, gamma=gamma)
    assert r.success and r.gradient_norm <= GRADIENT_TOL
    assert np.max(np.abs(t.gradient)) <= 1e-10 * max(1.0, np.max(np.abs(t.hessian)))
    assert t.value == pytest.approx(r.energy, rel=1e-12, abs=1e-12)
    if grip != "free":
        assert r.contact[0] == pytest.approx(params.b / 2, abs=1e-13)


@pytest.mark.parametrize("grip, kappa", [("free", -3.0), ("I", -5.5), ("II", 5.0)])
def test_tip_couple_equals_shifted_rest_angles(grip, kappa):
    """A tip couple C on the last link is exactly a shift of every rest angle by C/(D k_j):
    sum_j k_j/2 (q_j - r_j)^2 - C sum_j q_j = sum_j k_j/2 (q_j - r_j - C/k_j)^2 + const."""
    from simgrip.chain import ChainSprings, chain_springs
    from simgrip.reference import solve_chain
    from simgrip.params import STANDARD
    from simgrip.profiles import Uniform

    params, n, C = STANDARD.replace(D=1.3), 24, 0.07
    sp = chain_springs(Uniform(kappa), n)
    shifted = ChainSprings(n=n, ds=sp.ds, stiffness=sp.stiffness, rest=sp.rest + C / (params.D * sp.stiffness),
                           nodes=sp.nodes)
    a = solve_chain(grip, params, Uniform(kappa), n, contact_moment=C)
    b = solve_chain(grip, params, Uniform(kappa), n, springs=shifted)
    np.testing.assert_allclose(a.link_angles, b.link_angles, rtol=0, atol=1e-11)
    assert a.N1 == pytest.approx(b.N1, abs=1e-10)

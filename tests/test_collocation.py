"""simgrip.reference.collocation against SciPy's solve_bvp: the same algorithm, another linear solver.

Every case starts both solvers from the same mesh, states and parameters and
asks for the same status, iteration count, mesh and solution.  The solution may
differ only by the rounding of two LU factorisations of the same Newton systems
carried through a few iterations: 1e-12 relative to the states' scale is
~1e4 machine epsilons (the systems' condition numbers at these meshes are
~1e3-1e4), far below any Newton tolerance that could change the iteration count.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.integrate import solve_bvp

from simgrip import STANDARD, Uniform
from simgrip.reference import bvp
from simgrip.reference.collocation import solve_collocation
from simgrip.reference.elastica import checked_problem, solve

_RTOL = 1e-12  # see the module docstring


def _both(P, x, y, p, tol, max_nodes=6000):
    fun, bc, fj, bj = bvp.system(P)
    f2, fj2, A, B, c = bvp.linear_system(P)
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        warnings.simplefilter("ignore")
        ref = solve_bvp(fun, bc, x, y, p=p, fun_jac=fj, bc_jac=bj, tol=tol, max_nodes=max_nodes)
        new = solve_collocation(f2, fj2, A, B, c, x, y, p, tol=tol, max_nodes=max_nodes)
    return ref, new


def _same(ref, new, tol):
    assert (new.status, new.niter, new.message) == (ref.status, ref.niter, ref.message)
    np.testing.assert_array_equal(new.x, ref.x)
    scale = max(1.0, float(np.max(np.abs(ref.y))))
    np.testing.assert_allclose(new.y, ref.y, rtol=0, atol=_RTOL * scale)
    # the rms residuals difference the spline's nodes over intervals of ~1e-3: the states' rounding shows there
    # amplified ~1/h, up to ~1e-13 where the residual is ~1e-11; they are only ever compared with tol
    np.testing.assert_allclose(new.rms_residuals, ref.rms_residuals, rtol=0, atol=1e-3 * tol)
    if ref.p is None:
        assert new.p is None
    else:
        np.testing.assert_allclose(new.p, ref.p, rtol=_RTOL, atol=_RTOL)
    s = np.linspace(0.0, 1.0, 37)
    np.testing.assert_allclose(new.sol(s), ref.sol(s), rtol=0, atol=_RTOL * scale)


# (grip, params changes, kappa of the guess, kappa of the problem): tip contact with the parameter N1 (I, II),
# the free rod (no parameter), Grip III (two segments: boundary rows coupling both ends)
CASES = [
    ("I", {}, -5.5, -5.4),
    ("I", {}, -5.5, -4.0),  # a far guess: damped steps, several Jacobians, mesh refinement
    ("II", {}, 3.0, 3.2),
    ("III", {}, -4.0, -3.8),
    ("free", {}, -3.0, -2.5),
]


@pytest.mark.parametrize("grip, changes, k0, k1", CASES)
def test_same_as_solve_bvp_from_a_neighbour(grip, changes, k0, k1):
    params = STANDARD.replace(**changes)
    guess = solve(grip, params, Uniform(k0))._raw
    _, _, P = checked_problem(grip, params, Uniform(k1))
    p = guess.p if P.constrained else None
    for tol, x, y in ((1e-8, guess.x, guess.y), (1e-6, guess.x[::4], guess.y[:, ::4])):
        if x[-1] != 1.0:
            x, y = np.append(x, 1.0), np.hstack((y, guess.y[:, -1:]))
        _same(*_both(P, x, y, p, tol), tol)


def test_same_failure_when_nodes_run_out():
    """A coarse guess with too few nodes allowed: both stop with status 1 (nodes exceeded) at the same point."""
    guess = solve("I", STANDARD, Uniform(-5.5))._raw
    _, _, P = checked_problem("I", STANDARD, Uniform(-5.0))
    x = np.linspace(0.0, 1.0, 11)
    ref, new = _both(P, x, guess.sol(x), guess.p, 1e-8, max_nodes=50)
    assert ref.status == 1
    _same(ref, new, 1e-8)


def test_bad_input_raises_value_error():
    _, _, P = checked_problem("I", STANDARD, Uniform(-5.0))
    f, fj, A, B, c = bvp.linear_system(P)
    x = np.linspace(0.0, 1.0, 5)
    with pytest.raises(ValueError, match="strictly increasing"):
        solve_collocation(f, fj, A, B, c, x[::-1], np.zeros((4, 5)), [0.0])
    with pytest.raises(ValueError, match="shape"):
        solve_collocation(f, fj, A, B, c, x, np.zeros((4, 4)), [0.0])
    with pytest.raises(ValueError, match="boundary conditions"):
        solve_collocation(f, fj, A, B, c, x, np.zeros((4, 5)), None)


def test_singular_system_reported_as_solve_bvp_does():
    """The free rod with ``X(0) = 0`` replaced by a second ``theta(0) = 0``: ``X`` enters no other equation, so
    it is fixed only up to a constant and every Newton system is singular; both solvers report status 2."""
    _, _, P = checked_problem("free", STANDARD, Uniform(-1.0))
    f, fj, A, B, c = bvp.linear_system(P)
    A2, B2 = A.copy(), B.copy()
    A2[1], B2[1] = A2[0], B2[0]  # X(0) = 0 replaced by a second theta(0) = 0: X is free, the system singular
    x = np.linspace(0.0, 1.0, 9)
    y = np.zeros((4, 9))
    ref = solve_bvp(f, lambda ya, yb: A2 @ ya + B2 @ yb - c, x, y, fun_jac=fj,
                    bc_jac=lambda ya, yb: (A2, B2), tol=1e-6)
    new = solve_collocation(f, fj, A2, B2, c, x, y, None, tol=1e-6)
    assert ref.status == 2 and new.status == 2 and new.message == ref.message


# continue_collocation: a continuation's chord Newton ------------------------------------------------------------

def _line(grip, kappas, params=STANDARD):
    """Converged solutions of a grid line's first points and the problems of the next ones."""
    sols = [solve(grip, params, Uniform(k))._raw for k in kappas[:2]]
    probs = [checked_problem(grip, params, Uniform(k))[2] for k in kappas[2:]]
    return sols, probs


@pytest.mark.parametrize("grip, kappas", [("I", np.linspace(-7, -3, 300)[:6]), ("III", np.linspace(-6, -1, 60)[:6])])
def test_chord_steps_from_a_neighbour_equal_a_solve(grip, kappas, monkeypatch):
    """Along a grid line (the 300-point Grip I sweep's spacing; Grip III's two segments), each point from the
    secant predictor of the two before it with the previous point's factorisation: accepted without a new
    Jacobian, and equal to solve_collocation from the same start to the solver's tolerance (both stop by the
    same Newton test, residuals 1.5 decades below tol; the states of two such iterates differ by the discrete
    problem's conditioning times that, measured ~1e-10)."""
    from simgrip.reference import collocation as C

    (a, b), probs = _line(grip, kappas)
    factors = []
    real = C._Factor
    monkeypatch.setattr(C, "_Factor", lambda *args: factors.append(1) or real(*args))
    factor = None
    for P in probs:
        f, fj, A, B, c = bvp.linear_system(P)
        y, p = 2 * b.y - (a.y if np.array_equal(a.x, b.x) else a.sol(b.x)), 2 * b.p - a.p  # the secant predictor
        got = solve_collocation(f, fj, A, B, c, b.x, y, p, tol=1e-8) if factor is None else None
        if factor is None:  # the first point: a full solve, whose factorisation the next ones take
            factor = got.factor
            a, b = b, bvp.BvpSolution(P, got.x, got.y, got.p, got.sol, 0.0, "")
            continue
        factors.clear()
        new = C.continue_collocation(f, fj, A, B, c, b.x, y, p, tol=1e-8, factor=factor)
        assert new is not None and new.success and factors == []
        assert np.max(new.rms_residuals) <= 1e-8
        ref = solve_collocation(f, fj, A, B, c, b.x, y, p, tol=1e-8)
        np.testing.assert_array_equal(new.x, ref.x)
        np.testing.assert_allclose(new.y, ref.y, rtol=0, atol=1e-8 * max(1.0, float(np.max(np.abs(ref.y)))))
        np.testing.assert_allclose(new.p, ref.p, rtol=1e-8)
        a, b = b, bvp.BvpSolution(P, new.x, new.y, new.p, new.sol, 0.0, "")


def test_chord_on_a_coarse_mesh_refines_as_solve_bvp_and_refuses_a_far_start():
    """On a mesh too coarse for tol the converged chord steps go on as solve_bvp goes on (nodes inserted where
    the rms residual asks, the result equal to solve_collocation's from the same start to the tolerance); from
    a start its steps cannot reach it returns None (the caller then runs the full solver)."""
    from simgrip.reference.collocation import continue_collocation

    g = solve("I", STANDARD, Uniform(-5.5))._raw
    _, _, P = checked_problem("I", STANDARD, Uniform(-5.45))
    f, fj, A, B, c = bvp.linear_system(P)
    x = g.x[::8] if g.x[::8][-1] == 1.0 else np.append(g.x[::8], 1.0)
    new = continue_collocation(f, fj, A, B, c, x, g.sol(x), g.p, tol=1e-8, max_nodes=6000)
    ref = solve_collocation(f, fj, A, B, c, x, g.sol(x), g.p, tol=1e-8, max_nodes=6000)
    assert ref.success and new.success and new.x.size > x.size and np.max(new.rms_residuals) <= 1e-8
    s = np.linspace(0.0, 1.0, 41)
    np.testing.assert_allclose(new.sol(s), ref.sol(s), rtol=0, atol=1e-8 * max(1.0, float(np.max(np.abs(ref.y)))))
    _, _, far = checked_problem("I", STANDARD, Uniform(-2.0))
    f, fj, A, B, c = bvp.linear_system(far)
    assert continue_collocation(f, fj, A, B, c, g.x, g.y, g.p, tol=1e-8, max_steps=1) is None


# Spline: solve_bvp's PPoly without scipy.interpolate ------------------------------------------------------------

def test_spline_equals_ppoly_bit_for_bit():
    """Random cubics on random increasing breakpoints, evaluated inside, at every breakpoint (the half-open
    intervals, the closed last one), outside (extrapolation) and at scalars and 2-d arrays: the values, shapes
    and signs of zero of scipy's PPoly (the spline solve_bvp returns), exactly."""
    from scipy.interpolate import PPoly

    from simgrip.reference.collocation import _spline

    rng = np.random.default_rng(3)
    for _ in range(100):
        x = np.unique(np.concatenate(([0.0, 1.0], rng.random(int(rng.integers(0, 300))))))
        n = int(rng.integers(1, 9))
        c = rng.normal(size=(4, n, x.size - 1)) * 10.0 ** float(rng.integers(-5, 5))
        ref = PPoly(np.moveaxis(c, 1, 0), x, extrapolate=True, axis=1)
        new = _spline(c, x)
        t = np.concatenate((rng.random(200) * 1.4 - 0.2, x, [-0.0, np.nextafter(1.0, 2.0), -1e-300]))
        for tt in (t, t[:200].reshape(20, 10), 0.5, np.float64(x[-1])):
            a, b = ref(tt), new(tt)
            assert a.shape == b.shape
            assert np.array_equal(a, b) and np.array_equal(np.signbit(a), np.signbit(b))

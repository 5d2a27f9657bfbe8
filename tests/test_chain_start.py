"""The settle's chain starts by the minimiser's own Newton steps on LAPACK (simgrip.reference.chain_start, issue 19).

Each answer is compared with the chain solver's (``chain_angles``, ``solve_chain``) to the bound the two
Newton stopping tests allow (derived in ``_angle_bound``), its stability sign decision for decision, and
the fast path is checked to be taken on the standard cases (else the test would compare the fallback,
the minimiser itself, with itself).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from simgrip.params import STANDARD
from simgrip.profiles import Uniform
from simgrip.reference import chain_start, solve_chain
from simgrip.reference.hinge_chain import chain_angles
from simgrip.reference.minimiser import GRADIENT_TOL
from simgrip.reference.stability import tridiagonal_min_eigenvalue


def _angle_bound(eq) -> float:
    """Largest distance (max norm, rad) between two states that both pass the stopping test
    ``|r|_inf <= GRADIENT_TOL * scale`` near ``eq``: ``|dx|_2 <= (|r_a|_2 + |r_b|_2) / mu`` with ``mu`` the
    smallest eigenvalue of the (reduced) Hessian in Euclidean units, ``min_eigenvalue * ds`` (its metric is
    ``ds`` per link), and ``|r|_2 <= sqrt(n) |r|_inf``; the scale is that of the spring moments ``D k (|q| +
    |r|)`` (``k = 2n`` at the clamp) plus the loads, bounded by ``D 4 n (|q|_max + |rest|_max) + 2 + |N1|``."""
    n = eq.n
    q = np.abs(eq.joint_angles).max()
    scale = eq.params.D * 4.0 * n * (q + 10.0 / n) + 2.0 + abs(eq.N1) + eq.params.M
    mu = eq.min_eigenvalue / n
    return 2.0 * math.sqrt(n) * GRADIENT_TOL * scale / mu


@pytest.fixture
def fast_calls(monkeypatch):
    """Counts of :func:`chain_start.fast_newton` answering (``fast``) or handing over (``fallback``)."""
    calls = {"fast": 0, "fallback": 0}
    orig = chain_start.fast_newton

    def counted(*a, **k):
        res = orig(*a, **k)
        calls["fast" if res is not None else "fallback"] += 1
        return res

    monkeypatch.setattr(chain_start, "fast_newton", counted)
    return calls


@pytest.mark.parametrize("D", [0.3, 1.0, 20.0])
def test_free_start_is_chain_angles(D, fast_calls):
    """The free start is ``chain_angles("free")``'s equilibrium within the stopping tests' bound, by the fast path."""
    p = STANDARD.replace(D=D)
    for n in (2, 9, 16, 32, 128):
        for kappa in (-8.0, -3.0, 0.0, 5.0):
            eq = solve_chain("free", p, Uniform(kappa), n, gravity=0.7)
            got = chain_start.free_start_angles(p, Uniform(kappa), n, gravity=0.7)
            assert np.max(np.abs(got - chain_angles("free", p, Uniform(kappa), n, gravity=0.7))) <= _angle_bound(eq)
    assert fast_calls == {"fast": 20, "fallback": 0}


@pytest.mark.parametrize("grip,kappas", [("I", (-9.0, -6.0, -4.0, -2.0)), ("II", (2.0, 5.0, 8.0))])
def test_grip_start_is_solve_chain(grip, kappas, fast_calls):
    """Angles, tip and ``N1`` within the bound, stability as ``min_eigenvalue > 0``; the standard cases take the
    fast path, the hard ones (|kappa| >= 8: the minimiser shifts its steps) hand over and agree too."""
    for D in (0.5, 1.0, 5.0):
        p = STANDARD.replace(D=D, b=STANDARD.b - 2e-6)
        for n in (8, 16, 32):
            for kappa in kappas:
                eq = solve_chain(grip, p, Uniform(kappa), n)
                got = chain_start.grip_start(grip, p, Uniform(kappa), n)
                bound = _angle_bound(eq) if eq.min_eigenvalue > 0 else 1e-9  # (an unstable one: its own scale)
                assert np.max(np.abs(got.link_angles - eq.link_angles)) <= bound, (D, n, kappa)
                assert np.array_equal(got.joint_angles[1:], np.diff(got.link_angles))
                assert np.max(np.abs(got.tip - eq.tip)) <= bound
                assert abs(got.N1 - eq.N1) <= 1e-9 * max(1.0, abs(eq.N1))
                assert got.stable == (eq.min_eigenvalue > 0.0)
    assert fast_calls["fast"] > 0 and fast_calls["fallback"] > 0  # (both paths compared)


def test_grip_start_standard_case_is_fast(fast_calls):
    """The bench's Grip I case (kappa -6, n = 32) is solved by the fast path alone."""
    chain_start.grip_start("I", STANDARD.replace(b=STANDARD.b - 2e-6), Uniform(-6.0), 32)
    assert fast_calls == {"fast": 1, "fallback": 0}


def test_reduced_definite_decides_as_the_eigenvalue():
    """On random constrained tridiagonal problems (eigenvalues away from round-off), the definiteness test
    says what the sign of the smallest reduced eigenvalue says."""
    rng = np.random.default_rng(19)
    seen = set()
    for m in (2, 3, 8, 33):
        for _ in range(60):
            diag = rng.normal(size=m) * 3.0 + rng.uniform(-4.0, 6.0)
            off, a = rng.normal(size=m - 1), rng.normal(size=m)
            lam = tridiagonal_min_eigenvalue(diag, off, a)
            if abs(lam) < 1e-9:
                continue
            assert chain_start.reduced_definite(diag, off, a) == (lam > 0.0), (m, lam)
            seen.add(lam > 0.0)
    assert seen == {True, False}


def test_bad_input():
    with pytest.raises(ValueError, match="grip"):
        chain_start.grip_start("III", STANDARD, Uniform(-4.0), 16)
    with pytest.raises(ValueError, match="n"):
        chain_start.free_start_angles(STANDARD, Uniform(-3.0), 1)
    with pytest.raises(ValueError, match="gravity"):
        chain_start.free_start_angles(STANDARD, Uniform(-3.0), 8, gravity=-1.0)
    with pytest.raises(ValueError, match="b"):  # the straight finger already inside the face, as solve_chain says
        chain_start.grip_start("I", STANDARD.replace(b=2.5), Uniform(-3.0), 8)

"""The settle's fixed cost cut without changing an answer (issue 19).

The start shapes ask the chain solver for only what they use (``solve_chain(stability=...)``);
the stability test of a start needs only the sign of the smallest eigenvalue, so its
bisection stops once zero has left the bracket.  Each shortcut must give exactly what
the full computation gives: these tests compare them bit for bit, or decision for decision.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from simgrip.params import STANDARD
from simgrip.profiles import Uniform
from simgrip.reference import solve_chain
from simgrip.reference.stability import tridiagonal_min_eigenvalue


def _random_bordered(rng, m, shift):
    diag = rng.normal(size=m) * 3.0 + shift
    off = rng.normal(size=m - 1)
    a = rng.normal(size=m)
    w = rng.uniform(0.5, 2.0, size=m)
    return diag, off, a, w


def test_sign_only_bisection_decides_as_the_full_one():
    """``sign_only`` returns a value of the same sign (``> 0`` or not) as the full bisection, on random
    constrained tridiagonal problems spread around zero and on ones whose eigenvalue is zero to
    round-off (the shift that zeroes it, found by the full bisection itself)."""
    rng = np.random.default_rng(19)
    checked = 0
    for m in (2, 3, 8, 33):
        for _ in range(40):
            diag, off, a, w = _random_bordered(rng, m, rng.uniform(-4.0, 6.0))
            full = tridiagonal_min_eigenvalue(diag, off, a, w)
            fast = tridiagonal_min_eigenvalue(diag, off, a, w, sign_only=True)
            assert (fast > 0.0) == (full > 0.0), (m, full, fast)
            # the same matrix shifted so that its eigenvalue sits at zero (to the bisection's accuracy)
            zd = diag - full * w  # the metric scales the diagonal by 1 / w: this shifts the eigenvalue by -full
            full0 = tridiagonal_min_eigenvalue(zd, off, a, w)
            fast0 = tridiagonal_min_eigenvalue(zd, off, a, w, sign_only=True)
            assert (fast0 > 0.0) == (full0 > 0.0), (m, full0, fast0)
            checked += 2
    assert checked == 320


def test_sign_only_leaves_the_unconstrained_value():
    """Without a constraint the eigenvalue is LAPACK's either way (``sign_only`` only shortens the bisection)."""
    rng = np.random.default_rng(3)
    diag, off, _, w = _random_bordered(rng, 12, 1.0)
    assert tridiagonal_min_eigenvalue(diag, off, None, w, sign_only=True) == tridiagonal_min_eigenvalue(diag, off, None, w)


@pytest.mark.parametrize("grip,kappa", [("free", -3.0), ("I", -6.0), ("II", 5.0), ("III", -4.0)])
def test_solve_chain_stability_modes(grip, kappa):
    """``stability="sign"`` / ``"none"`` change ``min_eigenvalue`` alone: same angles, forces, energy."""
    full = solve_chain(grip, STANDARD, Uniform(kappa), 24)
    sign = solve_chain(grip, STANDARD, Uniform(kappa), 24, stability="sign")
    none = solve_chain(grip, STANDARD, Uniform(kappa), 24, stability="none")
    for other in (sign, none):
        assert np.array_equal(other.link_angles, full.link_angles)
        assert (other.N1, other.N2, other.energy, other.iterations) == (full.N1, full.N2, full.energy, full.iterations)
    assert (sign.min_eigenvalue > 0.0) == (full.min_eigenvalue > 0.0)
    assert math.isnan(none.min_eigenvalue)


def test_solve_chain_bad_stability():
    with pytest.raises(ValueError, match="stability"):
        solve_chain("I", STANDARD, Uniform(-6.0), 8, stability="fast")


def test_solve_tridiagonal_is_solve_banded():
    """The direct LAPACK ``gtsv`` call gives scipy's ``solve_banded((1, 1))`` answer bit for bit (the same
    routine on the same numbers), one or several right-hand sides, down to the 1 x 1 case; a singular
    matrix raises as there."""
    from scipy.linalg import solve_banded

    from simgrip.settle.banded import solve_tridiagonal

    rng = np.random.default_rng(7)
    for n in (1, 2, 5, 40):
        for shape in ((n,), (n, 3)):
            diag, off, rhs = rng.normal(size=n) * 3.0, rng.normal(size=n - 1), rng.normal(size=shape)
            ab = np.zeros((3, n))
            ab[0, 1:], ab[1], ab[2, :-1] = off, diag, off
            assert np.array_equal(solve_tridiagonal(diag, off, rhs), solve_banded((1, 1), ab, rhs))
    with pytest.raises(np.linalg.LinAlgError):
        solve_tridiagonal(np.zeros(3), np.zeros(2), np.ones(3))


@pytest.mark.parametrize("grip,kappa", [("free", -3.0), ("free", 4.0), ("I", -6.0), ("III", -4.0)])
def test_chain_angles_are_solve_chains(grip, kappa):
    """``chain_angles`` (the free start's solve) returns ``solve_chain``'s link angles bit for bit, cold and
    from a guess, and rejects what it rejects."""
    from simgrip.reference.hinge_chain import chain_angles

    full = solve_chain(grip, STANDARD, Uniform(kappa), 20, gravity=0.5)
    assert np.array_equal(chain_angles(grip, STANDARD, Uniform(kappa), 20, gravity=0.5), full.link_angles)
    guess = full.link_angles * 0.9
    assert np.array_equal(chain_angles(grip, STANDARD, Uniform(kappa), 20, gravity=0.5, guess=guess),
                          solve_chain(grip, STANDARD, Uniform(kappa), 20, gravity=0.5, guess=guess).link_angles)
    with pytest.raises(ValueError, match="n"):
        chain_angles(grip, STANDARD, Uniform(kappa), 1)

"""Issue 19: the Grip I/II settle's cheaper arithmetic.

* :func:`simgrip.settle.banded.solve_small` (the bordered Newton's Schur solve) is the exact solution up to
  round-off, and ``lstsq``'s least-squares answer where the matrix is singular or nearly so;
* the MuJoCo evaluations the settle reuses (the judge's ``mj_inverse`` at the solve's last ``K_c`` read, the
  release's first ``K_c`` read at ``stick_now``'s evaluation) give the very bits a fresh evaluation gives:
  a settle with the reuse switched off returns the same state, residual and contact forces bit for bit, and
  makes more ``mj_inverse`` calls.
"""

from __future__ import annotations

import numpy as np
import pytest

from simgrip.params import STANDARD
from simgrip.profiles import Uniform
from simgrip.scenes import build_scene
from simgrip.settle import settle
from simgrip.settle import chain_newton
from simgrip.settle.banded import SMALL_K, solve_small


@pytest.mark.parametrize("k", [1, 2, 3, SMALL_K, SMALL_K + 2])
def test_small_solve_is_the_solution(k):
    rng = np.random.default_rng(k)
    for _ in range(50):
        S = rng.normal(size=(k, k)) + 3.0 * np.eye(k)
        b = rng.normal(size=k)
        y = solve_small(S, b)
        np.testing.assert_allclose(S @ y, b, rtol=0, atol=1e-12 * (1.0 + np.abs(b).max()))
        np.testing.assert_allclose(y, np.linalg.solve(S, b), rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("k", [2, 3, SMALL_K + 1])
def test_singular_small_system_takes_the_least_squares_answer(k):
    rng = np.random.default_rng(10 + k)
    A = rng.normal(size=(k, k - 1))
    S = A @ A.T  # rank k - 1
    b = S @ rng.normal(size=k)  # consistent
    want = np.linalg.lstsq(S, b, rcond=1e-14)[0]
    y = solve_small(S, b)
    np.testing.assert_allclose(S @ y, b, atol=1e-10)
    assert np.abs(y).max() < 1e3 * (np.abs(want).max() + 1.0)  # not the elimination's huge round-off answer
    assert solve_small(np.zeros((k, k)), np.ones(k), least_squares=False) is None
    np.testing.assert_array_equal(solve_small(np.zeros((k, k)), np.ones(k)),
                                  np.linalg.lstsq(np.zeros((k, k)), np.ones(k), rcond=1e-14)[0])


def _record(st):
    return (st.qpos.tobytes(), st.tip.tobytes(), float(st.residual).hex(),
            [(float(c.N1).hex(), float(c.N2).hex()) for c in st.contacts], st.held, st.valid, st.converged)


@pytest.mark.parametrize("grip,kappa,contact", [("I", -6.0, "point"), ("I", -7.5, "surface"), ("II", 5.0, "point"),
                                                ("I", -3.0, "point")])
def test_reused_evaluations_are_bit_identical_to_fresh_ones(monkeypatch, grip, kappa, contact):
    def run():
        sc = build_scene(grip, STANDARD, Uniform(kappa), 16)
        return settle(sc, contact=contact)

    reused = run()
    monkeypatch.setattr(chain_newton.ChainNewton, "_inverse_current", lambda self, q: False)
    monkeypatch.setattr(chain_newton.ChainNewton, "_stick_mark_holds", lambda self, mark, q: False)
    fresh = run()
    assert _record(reused) == _record(fresh)
    assert reused.forward_calls <= fresh.forward_calls
    if reused.held:
        assert reused.forward_calls < fresh.forward_calls  # the reuse did happen

"""simgrip.reference.chain_guess: a settled chain's shape as the BVP's warm start (issue 16 section 6)."""

from __future__ import annotations

import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.reference import elastica, solve_chain
from simgrip.reference.capacity import margin
from simgrip.reference.chain_guess import chain_guess


@pytest.mark.parametrize("grip,kappa,gamma", [("I", -6.0, None), ("II", 5.0, None), ("III", -4.0, 0.8)])
def test_a_chain_guess_converges_to_the_cold_solution(grip, kappa, gamma):
    kw = {} if gamma is None else {"gamma": gamma}
    cold = elastica.solve(grip, STANDARD, Uniform(kappa), **kw)
    ch = solve_chain(grip, STANDARD, Uniform(kappa), 32, **kw)
    _, _, prob = elastica.checked_problem(grip, STANDARD, Uniform(kappa), **kw)
    g = chain_guess(prob, ch.link_angles, None, ch.N1)
    assert g.states(np.array([0.0]))[0, 0] == 0.0  # the clamp
    warm = elastica.solve(grip, STANDARD, Uniform(kappa), guess=g, fallback=False, **kw)
    assert np.allclose(warm.tip, cold.tip, atol=1e-7) and warm.N1 == pytest.approx(cold.N1, rel=1e-6)


def test_a_chain_guess_checks_its_arrays():
    _, _, prob = elastica.checked_problem("I", STANDARD, Uniform(-6.0))
    with pytest.raises(ValueError, match="chain_guess"):
        chain_guess(prob, [0.1, 0.2, 0.3], np.zeros((3, 2)))
    with pytest.raises(ValueError, match="chain_guess"):
        chain_guess(prob, [0.1, np.nan])
    with pytest.raises(ValueError, match="guess must be"):
        elastica.solve("I", STANDARD, Uniform(-6.0), guess=[0.1, 0.2])


def test_a_solution_in_the_other_grips_shape_has_no_positive_margin():
    sol = elastica.solve("II", STANDARD.replace(D=1e-2, mu_s=100.0), Uniform(3.5))
    assert not sol.feasibility["grip_shape"] and margin(sol) < 0
    ok = elastica.solve("I", STANDARD, Uniform(-6.0))
    assert ok.feasibility["grip_shape"] and ok.feasible

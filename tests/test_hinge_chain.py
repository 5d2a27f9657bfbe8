"""Tests of simgrip.reference.hinge_chain beyond the convergence studies of ``test_discrete.py``:
what a chain equilibrium reports about its loads, and the Grip III start shape."""

from __future__ import annotations

import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.reference import chain_energy, cradle_start_angles, solve_chain


@pytest.mark.parametrize("grip, kappa", [("free", -3.0), ("I", -5.5), ("II", 5.0), ("III", -5.0)])
def test_reported_contact_moment_reproduces_the_equilibrium(grip, kappa):
    """The result names the couple it was solved with: the chain energy built from the
    reported fields (``contact_moment``, ``N1``, ``gamma``) is stationary at the reported
    angles and has the reported value.  (Grips I/II and the free rod once reported 0 for
    a tip couple.)"""
    C = 0.05
    eq = solve_chain(grip, STANDARD, Uniform(kappa), 24, contact_moment=C)
    assert eq.contact_moment == C
    t = chain_energy(grip, STANDARD, Uniform(kappa), 24, eq.link_angles, N1=eq.N1, gamma=eq.gamma,
                     contact_moment=eq.contact_moment)
    assert np.max(np.abs(t.gradient)) < 1e-10 * np.max(np.abs(t.hessian))
    assert t.value == pytest.approx(eq.energy, rel=1e-13, abs=1e-13)
    # and the couple matters: without it the same angles are not an equilibrium
    t0 = chain_energy(grip, STANDARD, Uniform(kappa), 24, eq.link_angles, N1=eq.N1, gamma=eq.gamma)
    assert np.max(np.abs(t0.gradient)) > 0.5 * C


def test_cradle_start_angles_put_the_contact_at_gamma():
    q = cradle_start_angles(STANDARD, Uniform(-5.0), 20)
    eq = solve_chain("III", STANDARD, Uniform(-5.0), 20)
    np.testing.assert_array_equal(q, eq.joint_angles)
    assert eq.contact[0] == pytest.approx(STANDARD.b / 2, abs=1e-13)
    with pytest.raises(ValueError, match="links"):
        cradle_start_angles(STANDARD, Uniform(-5.0), 1)

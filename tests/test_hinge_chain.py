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


# ---------------------------------------------------------------------------- a signed load
# The load enters the chain's energy only through ``load * Y(s_c)`` (N2 = -load at the contact), so
# a negative load (the contact pushed up: a finger whose friction pulls the workpiece down) is the
# same discrete problem with the opposite vertical contact force.  Its independent reference is the
# elastica BVP with that force: for Grips I/II the contact is the tip, so M = 0 plus the BVP's
# extra tip force tip_load = (0, -load) is exactly N2 = -load there.  The chain is second order
# in ds (module docstring), so N1 and the tip converge to it at order 2.

LEVELS = (16, 32, 64, 128)


def _orders(errors):
    e = np.asarray(errors, float)
    return np.log2(e[:-1] / e[1:])


@pytest.mark.parametrize("grip, kappa, load", [("I", -5.5, -2.0), ("II", 5.0, -1.5), ("I", -5.5, 3.0)])
def test_signed_load_converges_at_second_order_to_the_bvp(grip, kappa, load):
    from simgrip.reference import elastica

    ref = elastica.solve(grip, STANDARD.replace(M=0.0), Uniform(kappa), tip_load=(0.0, -load), tol=1e-10)
    sols = [solve_chain(grip, STANDARD, Uniform(kappa), n, load=load) for n in LEVELS]
    for s in sols:
        assert s.N2 == -load and s.min_eigenvalue > 0.0
        assert s.tip[0] == pytest.approx(STANDARD.b / 2, abs=1e-13)
    n_err = [abs(s.N1 - ref.N1) for s in sols]
    y_err = [abs(s.tip[1] - ref.tip[1]) for s in sols]
    for what, err in (("N1", n_err), ("tip Y", y_err)):
        orders = _orders(err)
        assert np.all(np.abs(orders - 2.0) <= 0.2), (what, orders)
    assert n_err[-1] < 1e-3 * abs(ref.N1)


def test_the_load_changes_the_state_its_sign_matters():
    # the opposite load is a different equilibrium (the test above would pass for an ignored sign only by
    # accident): N1 and the tip move with the load, monotonically
    N1 = [solve_chain("I", STANDARD, Uniform(-5.5), 32, load=v).N1 for v in (-2.0, 0.0, 2.0)]
    assert N1[0] != N1[1] != N1[2] and (N1[0] - N1[1]) * (N1[1] - N1[2]) > 0


@pytest.mark.parametrize("grip, kappa", [("I", -5.5), ("II", 5.0), ("III", -5.0)])
def test_signed_load_is_stationary_in_the_chain_energy(grip, kappa):
    eq = solve_chain(grip, STANDARD, Uniform(kappa), 24, load=-1.0, contact_moment=0.02)
    t = chain_energy(grip, STANDARD, Uniform(kappa), 24, eq.link_angles, N1=eq.N1, gamma=eq.gamma,
                     contact_moment=0.02, load=-1.0)
    assert np.max(np.abs(t.gradient)) < 1e-10 * np.max(np.abs(t.hessian))
    assert t.value == pytest.approx(eq.energy, rel=1e-13, abs=1e-13)
    # the default load (params.M) is not the equilibrium of these angles
    t_m = chain_energy(grip, STANDARD, Uniform(kappa), 24, eq.link_angles, N1=eq.N1, gamma=eq.gamma,
                       contact_moment=0.02)
    assert np.max(np.abs(t_m.gradient)) > 0.1


@pytest.mark.parametrize("grip, kappa", [("I", -5.5), ("II", 5.0), ("III", -5.0)])
def test_a_nonnegative_load_is_bit_identical_to_params_M(grip, kappa):
    a = solve_chain(grip, STANDARD, Uniform(kappa), 24)
    b = solve_chain(grip, STANDARD, Uniform(kappa), 24, load=STANDARD.M)
    c = solve_chain(grip, STANDARD.replace(M=0.0), Uniform(kappa), 24, load=STANDARD.M)
    for other in (b, c):
        for f in ("link_angles", "joint_angles", "nodes", "tip"):
            assert np.array_equal(getattr(a, f), getattr(other, f)), f
        assert (a.N1, a.N2, a.energy, a.min_eigenvalue, a.iterations) == (other.N1, other.N2, other.energy,
                                                                           other.min_eigenvalue, other.iterations)


@pytest.mark.parametrize("bad", [float("nan"), float("inf"), "heavy", 2e4, -2e4, [1.0]])
def test_bad_load_names_the_parameter(bad):
    with pytest.raises(ValueError, match="load"):
        solve_chain("I", STANDARD, -5.5, 16, load=bad)
    with pytest.raises(ValueError, match="load"):
        chain_energy("I", STANDARD, -5.5, 16, np.zeros(16), load=bad)


def test_the_free_rod_takes_no_load():
    with pytest.raises(ValueError, match="load"):
        solve_chain("free", STANDARD, -3.0, 16, load=1.0)
    assert solve_chain("free", STANDARD, -3.0, 16, load=None).N2 == 0.0

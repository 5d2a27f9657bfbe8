"""The K-finger settle's start (simgrip.gripper.start): the balance of shares, the rest depth, the diagnosis."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simgrip import STANDARD
from simgrip.settle import SettleError
from simgrip.gripper.settle import contact_rest_depth, settle_gripper
from simgrip.gripper import start as gripper_start
from simgrip.gripper.start import balance_shares, is_symmetric, rest_depth, start_forces, start_qpos
from simgrip.harness.stress_gripper import _scene, make_gripper_cases
from simgrip.gripper.scene import build_gripper


def _equations(az, X, Y, N1, centre, s, n3):
    """Net force (with the weight) and moment about the centre of the forces balance_shares describes."""
    c = np.array([centre[0], centre[1], np.mean(Y)])
    force, moment = np.array([0.0, 0.0, -float(np.sum(s))]), np.zeros(3)
    for k, a in enumerate(az):
        e1, e3 = np.array([math.cos(a), math.sin(a), 0.0]), np.array([-math.sin(a), math.cos(a), 0.0])
        f = -(N1[k] * e1 + n3[k] * e3 - s[k] * np.array([0.0, 0.0, 1.0]))
        force += f
        moment += np.cross(X[k] * e1 + np.array([0.0, 0.0, Y[k]]) - c, f)
    return force, moment


@pytest.mark.parametrize("K", [3, 4, 5])
def test_balance_shares_balances_the_workpiece_with_the_least_change(K):
    rng = np.random.default_rng(K)
    az = 2 * math.pi * np.arange(K) / K + 0.3
    X, Y, N1 = rng.uniform(0.25, 0.35, K), rng.uniform(-0.7, -0.6, K), rng.uniform(6.0, 9.0, K)
    centre, M = rng.uniform(-0.03, 0.03, 2), 5.0
    s, n3, residual = balance_shares(az, X, Y, N1, centre, M)
    force, moment = _equations(az, X, Y, N1, centre, s, n3)
    assert np.sum(s) == pytest.approx(K * M, rel=1e-12)  # the weight
    assert np.max(np.abs(force[:2])) < 1e-12 and np.max(np.abs(moment)) < 1e-12 and residual < 1e-12
    # least change from (M, 0): orthogonal to every self-balanced change (the null space of the equations)
    A = np.zeros((6, 2 * K))
    for j in range(2 * K):
        u = np.zeros(2 * K)
        u[j] = 1.0
        f1, m1 = _equations(az, X, Y, np.zeros(K), centre, u[:K], u[K:])
        A[:, j] = np.concatenate([f1 + np.array([0.0, 0.0, np.sum(u[:K])]), m1])
    null = np.linalg.svd(A)[2][np.linalg.matrix_rank(A):]
    assert null.shape[0] == 2 * K - 6  # K = 3 is determinate; every further finger adds two internal modes
    change = np.concatenate([s - M, n3])
    assert null.size == 0 or np.max(np.abs(null @ change)) < 1e-10


def test_balance_shares_of_a_symmetric_grasp_is_equal_shares():
    az = 2 * math.pi * np.arange(4) / 4
    s, n3, residual = balance_shares(az, [0.3] * 4, [-0.65] * 4, [7.8] * 4, (0.0, 0.0), 5.0)
    np.testing.assert_allclose(s, 5.0, atol=1e-13)
    np.testing.assert_allclose(n3, 0.0, atol=1e-13)
    # two fingers pushing unequally cannot be balanced by shares: said, not hidden
    _s, _n, residual = balance_shares([0.0, math.pi], [0.3, 0.3], [-0.65, -0.65], [7.8, 8.0], (0.0, 0.0), 5.0)
    assert residual == pytest.approx(0.2, rel=1e-9)


def test_is_symmetric():
    def sc(**kw):
        return build_gripper("I", STANDARD, kw.pop("profile", -6.0), 8, fingers=3, workpiece="cylinder", **kw)

    assert is_symmetric(sc()) and is_symmetric(sc(profile=[-6.0] * 3)) and is_symmetric(sc(yaw=0.4))
    assert not is_symmetric(sc(offset=(0.01, 0.0)))
    assert not is_symmetric(sc(workpiece_yaw=0.1))
    assert not is_symmetric(sc(profile=[-6.0, -6.0, -5.9]))


@pytest.mark.parametrize("grip, kappa, n", [("I", -6.0, 16), ("II", 5.0, 32), ("I", -6.0, 32)])
def test_rest_depth_is_where_the_contact_rests(grip, kappa, n):
    # the start seats each tip at the settled penetration: the dynamics' law N tc^2 A_nn, measured 1.02 times
    scene = build_gripper(grip, STANDARD, kappa, n, fingers=3, workpiece="cylinder")
    st = settle_gripper(scene, method="dynamics")
    depth = rest_depth([r.normal for r in st.records], st.timestep, scene)  # at the settled state
    assert np.array_equal(depth, np.maximum(gripper_start.START_INSIDE,
                                            contact_rest_depth(scene, [r.normal for r in st.records], st.timestep)))
    for r, dep in zip(st.records, depth):
        assert 1.0 <= r.penetration / dep <= 1.03


def test_the_balanced_start_is_what_lets_the_settle_finish(monkeypatch):
    """The diagnosis: from equal shares the workpiece's moments do not balance, settling loads internal
    friction modes that relax only by creep; the default budget (20 000 steps) runs out."""
    def build():
        return build_gripper("I", STANDARD, -6.0, 16, fingers=4, workpiece="box", offset=(0.02, 0.01),
                             workpiece_yaw=0.1)

    st = settle_gripper(build(), method="dynamics")
    assert st.held and st.converged and st.steps <= 100
    q = start_qpos(build(), timestep=st.timestep)
    assert q is not None and np.all(np.isfinite(q))
    monkeypatch.setattr(gripper_start, "is_symmetric", lambda scene: True)  # equal shares at each reach
    import simgrip.gripper.settle as settle_module

    monkeypatch.setattr(settle_module, "is_symmetric", lambda scene: True)
    with pytest.raises(SettleError, match="did not converge"):
        settle_gripper(build(), method="dynamics")


def test_a_start_that_needs_a_pulling_finger_is_balanced_with_a_negative_share():
    """Stress case 16 (two-finger box, Grip I, off-centre): its balance needs finger 1's friction to pull
    the box down.  The start now carries that (solve_chain's signed load) and balances the box exactly."""
    scene = _scene(make_gripper_cases(17)[16])
    f = start_forces(scene)
    assert f.balanced and f.residual < 1e-10
    assert min(-f.N2) < -0.5  # a negative share: the finger pushes its tip's friction downwards on the box
    assert np.sum(-f.N2) == pytest.approx(scene.fingers * scene.params.M, rel=1e-12)  # the weight
    # the required mu is |force - normal part| / normal part, from the same forces
    assert np.all(f.normal > 0) and np.all(f.required_mu == f.tangential / f.normal)


def test_start_forces_of_a_symmetric_grasp_are_the_planar_problem():
    scene = build_gripper("I", STANDARD, -6.0, 16, fingers=3, workpiece="cylinder")
    f = start_forces(scene)
    np.testing.assert_array_equal(f.N2, -STANDARD.M)
    np.testing.assert_allclose(f.N3, 0.0)
    np.testing.assert_allclose(f.required_mu, STANDARD.M / f.N1, rtol=1e-12)
    assert f.balanced and f.residual < 1e-12


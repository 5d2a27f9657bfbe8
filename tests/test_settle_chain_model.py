"""The chain-coordinate statics equal MuJoCo's, and their derivatives are exact.

* forces: MuJoCo's static balance (``mj_inverse``, contacts off) in hinge rows is the
  suffix sum of the link-angle forces -- equal to round-off;
* contact distances: MuJoCo's ``mj_geomDistance`` -- equal to round-off;
* gradients and Hessians (tridiagonal + diagonal + low rank) against central
  differences with step ``h = 1e-6``: error ``O(h^2)`` times third derivatives of
  order ``k ~ n`` (springs) -> 1e-8 absolute, relative to the entries' size.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.scenes import build_scene
from simgrip.settle.chain_model import ChainModel
from simgrip.settle.newton import Newton
from simgrip.settle.statics import configure_statics

H = 1e-6


def _perturbed(grip, kappa, n, seed=0, fingers=1):
    """A scene off equilibrium: link angles and (two fingers) the workpiece's x, z and turn moved."""
    sc = build_scene(grip, STANDARD, Uniform(kappa), n, fingers=fingers)
    configure_statics(sc)
    cm = ChainModel(sc)
    q = sc.data.qpos.copy()
    rng = np.random.default_rng(seed)
    q[cm.jq] += 0.05 * rng.standard_normal(cm.n)
    if cm.nw == 3:
        q[cm.wq] += 0.02 * rng.standard_normal(3) * cm.wscale
    return sc, cm, q


def _x(cm, phi, w):
    return np.append(phi, w)


def _fd_check(cm, term_at, x0):
    """Central differences of value -> gradient and of gradient -> Hessian."""
    t = term_at(x0)
    g = np.zeros(x0.size)
    Hfd = np.zeros((x0.size, x0.size))
    for k in range(x0.size):
        e = np.zeros(x0.size)
        e[k] = H
        tp, tm = term_at(x0 + e), term_at(x0 - e)
        g[k] = (tp.value - tm.value) / (2 * H)
        Hfd[:, k] = (tp.grad - tm.grad) / (2 * H)
    Ha = t.U @ t.S @ t.U.T
    Ha[:cm.n, :cm.n] += np.diag(t.diag)
    np.testing.assert_allclose(t.grad, g, atol=1e-8)
    np.testing.assert_allclose(Ha, Hfd, atol=1e-7 * max(1.0, np.max(np.abs(Hfd))))


@pytest.mark.parametrize("fingers", [1, 2])
@pytest.mark.parametrize("grip,kappa", [("free", -3.0), ("I", -6.0), ("III", -6.0)])
def test_forces_equal_mujocos_and_their_jacobian_is_exact(grip, kappa, fingers):
    sc, cm, q = _perturbed(grip, kappa, 12, fingers=fingers)
    run = Newton(sc)
    m = sc.model
    flags = int(m.opt.disableflags)
    m.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    r = run.st.forces(q) / run.st.fscale
    m.opt.disableflags = flags
    phi, w = cm.split(q)
    F, diag, off = cm.internal(phi)
    np.testing.assert_allclose(cm.to_q(F), r[cm.jd], atol=1e-13)
    np.testing.assert_allclose(cm.workpiece_force(), r[cm.wd], atol=1e-13)
    J = np.zeros((cm.n, cm.n))
    for k in range(cm.n):
        e = np.zeros(cm.n)
        e[k] = H
        J[:, k] = (cm.internal(phi + e)[0] - cm.internal(phi - e)[0]) / (2 * H)
    T = np.diag(diag) + np.diag(off, 1) + np.diag(off, -1)
    np.testing.assert_allclose(T, J, atol=1e-7 * np.max(np.abs(T)))


@pytest.mark.parametrize("fingers", [1, 2])
@pytest.mark.parametrize("grip,kappa", [("I", -6.0), ("III", -6.0), ("III", -4.0)])
def test_contact_distances_and_their_derivatives(grip, kappa, fingers):
    """Two fingers: the workpiece turned, so the face normals and corners turn (workpiece rows exact too)."""
    sc, cm, q = _perturbed(grip, kappa, 12, seed=1, fingers=fingers)
    phi, w = cm.split(q)
    run = Newton(sc)
    np.testing.assert_allclose(cm.pair_distances(phi, cm.nodes(phi), w), run._dists(q) / sc.length, atol=1e-14)
    for p in range(len(cm.pairs)):  # interior contacts and end caps alike
        def term_at(x, p=p):
            ph, ww = x[:cm.n], x[cm.n:]
            return cm.pair_term(p, ph, cm.nodes(ph), ww)

        _fd_check(cm, term_at, _x(cm, phi, w))


@pytest.mark.parametrize("fingers", [1, 2])
@pytest.mark.parametrize("grip,kappa", [("I", -6.0), ("III", -6.0)])
def test_stick_constraints_and_their_derivatives(grip, kappa, fingers):
    """Sticks (tangent turning with the workpiece for I/II, with the link for III) from a settled grip."""
    from simgrip.settle import settle

    sc = build_scene(grip, STANDARD, Uniform(kappa), 12, fingers=fingers)
    settle(sc)
    configure_statics(sc)
    run = Newton(sc)
    run.stick_now()
    assert run.sticks
    cm = ChainModel(sc)
    q = sc.data.qpos.copy()
    q[cm.jq] += 0.01
    if cm.nw == 3:
        q[cm.wq] += np.array([0.01, -0.01, 0.03]) * cm.wscale
    phi, w = cm.split(q)
    for s in run.sticks:
        def term_at(x, s=s):
            ph, ww = x[:cm.n], x[cm.n:]
            return cm.stick_term(s, ph, cm.nodes(ph), ww)

        _fd_check(cm, term_at, _x(cm, phi, w))
        # its value is MuJoCo's stick row
        run.st.d.qpos[:] = q
        mujoco.mj_kinematics(sc.model, run.st.d)
        g, _ = run.st.stick_rows([s])
        assert term_at(_x(cm, phi, w)).value == pytest.approx(g[0], abs=1e-14)

"""settle.dynamics on soft fingers: the loads' geometric stiffness in the damping, the Grip III fall guard.

MuJoCo's step is implicit in the hinge springs and the damping but explicit in
gravity and the contact forces.  Where those dominate the springs (``D`` small)
the over-damped step with ``D = h K`` was unstable and threw held workpieces off
(stress cases 245 and 403 of ``simgrip stress --cases 500``); the fall guard was
lifted on a velocity its own damping had slowed (case 38).  Each test is the
smallest stress case that showed it.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.harness.agreement import MARGIN
from simgrip.scenes import build_scene
from simgrip.settle import settle
from simgrip.settle.dynamics import Dyn, geometric_stiffness_bound
from settle_cases import stress_scene

# stress ids 245 (Grip I) and 38 (Grip III) of `simgrip stress --cases 500`
SOFT_HEAVY_I = dict(D=0.01108243183173168, kappa=-2.15166637301445, M=28.167713852599263, mu_s=2.239939991373532,
                    b=0.8584589946642518, n=18)
SOFT_CURLED_III = dict(D=0.01, kappa=-12.0, M=5.0, mu_s=1.0, b=0.6, n=16)


def _margin(st, mu_s):
    return 1.0 - max(c.required_mu_contact for c in st.contacts) / mu_s


def _gravity_hessian(scene, q, eps=1e-6):
    """-d(generalised gravity force)/dq by central differences of MuJoCo's bias force at rest."""
    m, d = scene.model, mujoco.MjData(scene.model)
    H = np.zeros((m.nv, m.nv))
    for j in range(m.nv):
        cols = []
        for s in (1.0, -1.0):
            d.qpos[:] = q
            d.qpos[j] += s * eps
            d.qvel[:] = 0.0
            mujoco.mj_forward(m, d)
            cols.append(d.qfrc_bias.copy())  # at rest: minus the generalised gravity force
        H[:, j] = (cols[0] - cols[1]) / (2 * eps)
    return H


@pytest.mark.parametrize("grip,kappa", [("free", -3.0), ("I", -6.0)])
def test_geometric_bound_is_the_row_sum_of_gravitys_hessian(grip, kappa):
    # gravity alone (no load): R_a = sum_b |H_ab| exactly, H the Hessian of the links' weight
    sc = build_scene(grip, STANDARD.replace(D=0.05), Uniform(kappa), 12)
    q = sc.data.qpos.copy()
    q[sc.joint_qpos] = np.linspace(-0.3, 0.5, sc.n)[None, :]
    H = _gravity_hessian(sc, q)
    d = mujoco.MjData(sc.model)
    d.qpos[:] = q
    mujoco.mj_forward(sc.model, d)
    R = geometric_stiffness_bound(sc, d, 0.0)
    dofs = sc.index.joint_dof[0]
    # central differences at eps = 1e-6: truncation ~eps^2 (1e-12) relative, round-off ~1e-16/eps (1e-10)
    # of the bias force; rtol 1e-6 leaves room for both, atol covers the rows near zero
    np.testing.assert_allclose(R[dofs], np.abs(H[np.ix_(dofs, dofs)]).sum(axis=1), rtol=1e-6, atol=1e-9)


def test_soft_finger_damping_covers_the_loads():
    # the held state of stress case 245: gravity and the 28-weight workpiece hanging on the tip give a
    # geometric stiffness ~1e3 times the springs'; the damping takes the larger of the two
    sc = stress_scene("I", **SOFT_HEAVY_I)
    nw = settle(sc, contact="surface")
    sc2 = stress_scene("I", **SOFT_HEAVY_I)
    sc2.data.qpos[:] = nw.qpos
    mujoco.mj_forward(sc2.model, sc2.data)
    dyn = Dyn(sc2)
    dyn.hold(False)
    dyn.update_damping()
    k = dyn.k[dyn.k > 0]
    assert np.max(dyn.R[dyn.k > 0] / k) > 100.0
    np.testing.assert_allclose(sc2.model.dof_damping[dyn.k > 0], dyn.h * np.maximum(k, dyn.R[dyn.k > 0]))


def test_soft_heavy_grip_i_holds_as_the_static_settle_says():
    # stress case 245: held 5 % inside the cone by the static settle, the chain and the BVP; the
    # dynamics with D = h K dropped it at h, h/2 and h/4 (the explicit weight's stiffness is ~1e3 K)
    p = SOFT_HEAVY_I
    nw = settle(stress_scene("I", **p), contact="surface")
    st = settle(stress_scene("I", **p), method="dynamics")
    assert nw.held and st.held and st.converged
    assert _margin(st, p["mu_s"]) == pytest.approx(_margin(nw, p["mu_s"]), abs=0.01)
    assert _margin(st, p["mu_s"]) > MARGIN


def test_soft_curled_grip_iii_comes_to_rest_at_the_cone():
    # stress case 38: in the surface-contact problem the workpiece slides until the friction cone
    # holds it (Newton's margin 0); the fall guard lifted on a velocity its own damping had slowed
    # let the workpiece tunnel through the rod. The dynamics now ends at the cone too.
    p = SOFT_CURLED_III
    nw = settle(stress_scene("III", **p), contact="surface")
    st = settle(stress_scene("III", **p), method="dynamics")
    assert nw.held and abs(_margin(nw, p["mu_s"])) < 1e-6
    assert st.held and st.converged and 0.0 <= _margin(st, p["mu_s"]) < MARGIN

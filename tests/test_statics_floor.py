"""settle.statics.angle_floor: the static residual's round-off floor on stiff fine chains."""

from __future__ import annotations

import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.reference import solve_chain
from simgrip.scenes import build_scene
from simgrip.settle import DEFAULT_TOL, settle
from simgrip.settle.statics import angle_floor, static_residual


def _at_chain(D, n, kappa=-6.0):
    p = STANDARD.replace(D=D)
    sc = build_scene("free", p, Uniform(kappa), n)
    ch = solve_chain("free", p, Uniform(kappa), n)
    sc.data.qpos[sc.joint_qpos] = ch.joint_angles[None, :]
    return sc, ch


@pytest.mark.parametrize("D,n", [(1.0, 64), (400.0, 256), (4000.0, 256)])
def test_floor_bounds_the_settled_residual_and_grows_like_D_n(D, n):
    # the settled free rod is MuJoCo's equilibrium to round-off: its residual is within the floor
    # 2.5 eps k_a Phi_a, largest at the tip hinge (k = D n, Phi = |phi(1)| ~ 6 for kappa = -6)
    sc, _ = _at_chain(D, n)
    st = settle(build_scene("free", STANDARD.replace(D=D), Uniform(-6.0), n))
    floor = angle_floor(sc, st.qpos)
    assert st.converged and float(np.max(np.abs(static_residual(sc, st.qpos)))) <= max(floor, DEFAULT_TOL)
    phi_tip = abs(float(np.sum(st.joint_angles[0])))
    # |phi| grows along the curled rod, so k_a Phi_a is largest at the tip hinge (k = D n, Phi = |phi(1)|;
    # the base hinge's k = 2 D n multiplies a small |phi|): the floor is that product, to round-off
    assert floor == pytest.approx(2.5 * np.finfo(float).eps * D * n * phi_tip, rel=1e-12)


def test_stiff_fine_free_rod_settles_at_its_floor():
    # D n = 2.6e5: the round-off of the joint angles alone (~2.4e-10) is above the default
    # tolerance 1e-10, and the settle stalled ("did not converge (stalled)")
    sc, ch = _at_chain(1000.0, 256)
    st = settle(build_scene("free", STANDARD.replace(D=1000.0), Uniform(-6.0), 256))
    assert st.converged and st.tolerance == pytest.approx(angle_floor(sc), rel=1e-6)
    assert DEFAULT_TOL < st.residual <= st.tolerance
    np.testing.assert_allclose(st.link_angles[0], ch.link_angles, rtol=0, atol=1e-12)


def test_floor_is_far_below_the_tolerance_for_ordinary_chains():
    sc, _ = _at_chain(1.0, 32)
    assert angle_floor(sc) < 1e-2 * DEFAULT_TOL

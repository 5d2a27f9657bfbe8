"""Stability of the K-finger settle's balanced start (simgrip.gripper.stability): the statics' second
variation and MuJoCo's linearised dynamics, two independent answers, agree."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simgrip import STANDARD
from simgrip.harness.stress_gripper import _scene, make_gripper_cases
from simgrip.gripper.stability import (UNSTABLE_GROWTH, _cross_matrix, start_growth, start_stiffness)
from simgrip.gripper.start import start_forces
from simgrip.gripper.scene import build_gripper

CASES = make_gripper_cases(23)


def test_the_geometric_term_is_the_second_order_work_of_the_preload():
    # F . 1/2 w x (w x r) = 1/2 w^T (sym(F r^T) - (F.r) I) w, for any F, r, w
    rng = np.random.default_rng(1)
    for _ in range(5):
        F, r, w = rng.normal(size=(3, 3))
        G = 0.5 * (np.outer(F, r) + np.outer(r, F)) - float(F @ r) * np.eye(3)
        assert F @ (0.5 * np.cross(w, np.cross(w, r))) == pytest.approx(0.5 * w @ G @ w, rel=1e-12, abs=1e-14)
        np.testing.assert_allclose(_cross_matrix(r) @ w, np.cross(r, w), rtol=1e-14, atol=1e-15)


def test_stress_case_22_starts_at_an_unstable_equilibrium():
    """Stress case 22 (four-finger box, Grip I, n = 8): a balanced start whose friction suffices (need 1.42 <
    mu_s 1.84), which the settle leaves exponentially until the box tips out.  The statics' second variation
    has a negative eigenvalue on the workpiece's admissible motions, and MuJoCo's one-step map linearised about
    the start a real eigenvalue ~1.0135 per step (the growth of the box's turn measured in the run: 1.0133 to
    1.0139 per step over steps 200 to 600); the unstable mode is mostly the box's rotation."""
    scene = _scene(CASES[22])
    f = start_forces(scene)
    assert f.balanced and f.max_required_mu < scene.params.mu_s
    st = start_stiffness(scene)
    assert st.dims == 2 and not st.stable and st.min_eigenvalue < -100 * st.tolerance
    assert start_growth(scene) > 1.0 + 10 * UNSTABLE_GROWTH
    assert start_growth(scene, 0.5) > 1.0 + UNSTABLE_GROWTH  # at half the step too (the settle's drop retry)


@pytest.mark.parametrize("case", [2, 12, 13])
def test_stable_four_finger_starts_are_stable_both_ways(case):
    scene = _scene(CASES[case])
    st = start_stiffness(scene)
    assert st.dims == 2 and st.stable and st.min_eigenvalue > 100 * st.tolerance
    q = np.array(scene.data.qpos)
    g = start_growth(scene)
    assert abs(g - 1.0) < 0.2 * UNSTABLE_GROWTH  # the neutral drift of sticking friction only
    assert np.array_equal(scene.data.qpos, q) and start_growth(scene) == g  # state restored, deterministic


def test_two_fingers_have_the_pinch_axis_as_a_zero_mode():
    """Two point contacts do not resist a turn about the line through them: one zero eigenvalue (to the
    finite differences), whatever the rest.  Stress case 16 (two-finger box, off-centre, a pulling finger)
    is unstable besides, both ways."""
    sym = start_stiffness(build_gripper("I", STANDARD, -6.0, 16, fingers=2, workpiece="box"))
    assert sym.dims == 4
    ev = sym.eigenvalues
    assert np.min(np.abs(ev)) < 1e-6 * np.max(np.abs(ev))
    st = start_stiffness(_scene(CASES[16]))
    assert st.dims == 4 and not st.stable and np.min(np.abs(st.eigenvalues)) < 1e-6 * np.max(np.abs(st.eigenvalues))
    assert start_growth(_scene(CASES[16])) > 1.0 + 10 * UNSTABLE_GROWTH


def test_a_symmetric_three_finger_grasp_is_stable_and_bad_scenes_are_refused():
    st = start_stiffness(build_gripper("I", STANDARD, -6.0, 16, fingers=3, workpiece="cylinder"))
    assert st.dims == 3 and st.stable
    with pytest.raises(ValueError, match="scene"):
        start_stiffness("not a scene")
    with pytest.raises(ValueError, match="scene"):
        start_stiffness(build_gripper("I", STANDARD, -6.0, 16, fingers=3, workpiece="sphere", contact_angle=-0.2))
    assert math.isfinite(st.min_eigenvalue)

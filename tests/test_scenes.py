"""The paper's scenes: Grip III starts from the hinge chain's equilibrium; other grips as the model layer builds them."""

from __future__ import annotations

import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.reference import solve_chain
from simgrip.scenes import build_scene, start_angles
from simgrip.sim import scene as model_layer
from simgrip.sim.scene import finger_state


def test_grip_iii_starts_from_the_hinge_chain_at_gamma():
    q = solve_chain("III", STANDARD, Uniform(-6.0), 16).joint_angles
    np.testing.assert_array_equal(start_angles("III", STANDARD, Uniform(-6.0), 16), q)
    sc = build_scene("III", STANDARD, Uniform(-6.0), 16)
    np.testing.assert_array_equal(finger_state(sc)[0], q)
    same = model_layer.build_scene("III", STANDARD, Uniform(-6.0), 16, initial_angles=q)
    assert sc.spec.to_xml() == same.spec.to_xml()


@pytest.mark.parametrize("grip", ["free", "I", "II"])
def test_other_grips_are_the_model_layers_scenes(grip):
    assert start_angles(grip, STANDARD, Uniform(-6.0), 8) is None
    k = 5.0 if grip == "II" else -6.0
    a = build_scene(grip, STANDARD, Uniform(k), 8, fingers=2)
    b = model_layer.build_scene(grip, STANDARD, Uniform(k), 8, fingers=2)
    assert a.spec.to_xml() == b.spec.to_xml()


def test_bad_input_is_named_before_solving():
    with pytest.raises(ValueError, match="links"):
        build_scene("III", STANDARD, Uniform(-6.0), 5000)
    with pytest.raises(ValueError, match="params"):
        build_scene("III", "standard", Uniform(-6.0), 8)
    with pytest.raises(ValueError, match="grip"):
        build_scene("IV", STANDARD, Uniform(-6.0), 8)

"""Whether a K-finger scene is exactly symmetric (simgrip.gripper.scene_symmetry), read from its compiled model.

Every check must see a change of the model itself (not only of the builder's arguments), and keep
what maps the scene into itself (a quarter turn of a K = 4 box, any turn of a cylinder).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.gripper.scene import build_gripper
from simgrip.gripper.scene_symmetry import symmetry

N = 16
CASES = [(2, "box"), (3, "cylinder"), (4, "box"), (5, "cylinder")]


def _gripper(grip, K, shape, n=N, params=STANDARD, kappa=-6.0, **kw):
    return build_gripper(grip, params, Uniform(kappa), n, fingers=K, workpiece=shape, **kw)


@pytest.mark.parametrize("K, shape", CASES + [(3, "sphere"), (6, "sphere")])
def test_centred_scenes_are_symmetric(K, shape):
    for yaw in (0.0, 0.7):
        assert symmetry(_gripper("I", K, shape, yaw=yaw)).exact


def _mutated(change):
    sc = _gripper("I", 4, "box")
    change(sc)
    return symmetry(sc)


def test_broken_symmetry_is_seen_in_the_model():
    def rest(sc):  # one finger's rest angles (per-finger curvature)
        sc.model.qpos_spring[sc.joint_qpos[2, 3]] += 1e-3

    def stiff(sc):
        sc.model.jnt_stiffness[sc.model.dof_jntid[sc.joint_dof[1, 0]]] *= 1.01

    def moved(sc):  # the workpiece off the palm axis
        sc.model.qpos0[sc.workpiece_qpos[0]] += 1e-3 * sc.length

    def turned(sc):  # the box turned about the palm axis relative to the fingers
        q = np.zeros(4)
        mujoco.mju_axisAngle2Quat(q, np.array([0.0, 0.0, 1.0]), 0.1)
        sc.model.qpos0[sc.workpiece_qpos[3:]] = q

    def friction(sc):
        sc.model.pair_friction[1, 0] *= 0.9

    def gravity(sc):
        sc.model.opt.gravity[0] = 0.1

    def mass(sc):
        sc.model.body_mass[sc.index.link_body[0, 5]] *= 1.1

    for change, words in [(rest, "rest angles"), (stiff, "stiffness"), (moved, "off the palm axis"),
                          (turned, "head on"), (friction, "friction"), (gravity, "gravity"), (mass, "masses")]:
        s = _mutated(change)
        assert not s.exact and words in s.reason, (change.__name__, s)
    # a quarter turn of a K = 4 box, or any turn of a cylinder, keeps every face head on
    sc = _gripper("I", 4, "box")
    q = np.zeros(4)
    mujoco.mju_axisAngle2Quat(q, np.array([0.0, 0.0, 1.0]), 0.5 * math.pi)
    sc.model.qpos0[sc.workpiece_qpos[3:]] = q
    assert symmetry(sc).exact
    sc = _gripper("I", 3, "cylinder")
    mujoco.mju_axisAngle2Quat(q, np.array([0.0, 0.0, 1.0]), 0.3)
    sc.model.qpos0[sc.workpiece_qpos[3:]] = q
    assert symmetry(sc).exact


def test_builder_asymmetries_are_not_exact():
    assert not symmetry(_gripper("I", 3, "cylinder", offset=(0.02, 0.0))).exact
    assert not symmetry(_gripper("I", 4, "box", workpiece_yaw=0.05)).exact
    assert symmetry(_gripper("I", 3, "cylinder", workpiece_yaw=0.4)).exact  # a cylinder turns into itself
    sc = build_gripper("I", STANDARD, [Uniform(-6.0), Uniform(-6.0), Uniform(-5.0)], N, fingers=3,
                       workpiece="cylinder")
    assert not symmetry(sc).exact

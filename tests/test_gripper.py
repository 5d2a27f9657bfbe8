"""K-finger gripper scenes (simgrip.gripper.scene): structure, geometry, input checks."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.gripper.scene import GripperScene, build_gripper, check_gripper
from simgrip.sim.workpiece import BOX_DEPTH

N = 8


@pytest.mark.parametrize("K, shape", [(2, "box"), (4, "box"), (2, "cylinder"), (3, "cylinder"), (5, "cylinder"),
                                      (2, "sphere"), (3, "sphere"), (6, "sphere")])
def test_gripper_holds_what_the_builder_made(K, shape):
    sc = build_gripper("I", STANDARD, Uniform(-6), N, fingers=K, workpiece=shape)
    m = sc.model
    assert isinstance(sc, GripperScene) and sc.fingers == K and sc.workpiece == shape
    assert sc.joint_qpos.shape == (K, N) and m.nq == K * N + 7 and m.nv == K * N + 6
    # one free joint for the workpiece, K * n hinges, nothing else
    assert list(m.jnt_type).count(mujoco.mjtJoint.mjJNT_FREE) == 1
    assert m.body_jntnum[sc.workpiece_body] == 1
    # mass: M per finger (l = rho = g = 1)
    assert m.body_mass[sc.workpiece_body] == pytest.approx(K * STANDARD.M, rel=1e-12)
    # explicit pairs: exactly one per finger, its tip with the workpiece; no broad-phase collision
    assert m.npair == K
    assert sorted(m.pair_geom1) == sorted(sc.tip_geom) and set(m.pair_geom2) == {sc.workpiece_geom}
    assert not np.any(m.geom_contype) and not np.any(m.geom_conaffinity)
    assert np.allclose(m.pair_friction[:, :2], STANDARD.mu_s)
    # the same springs and rest angles as the planar finger, on every finger
    k = m.jnt_stiffness[m.dof_jntid]
    for f in range(K):
        np.testing.assert_allclose(k[sc.joint_dof[f]], STANDARD.D * sc.springs.stiffness, rtol=1e-12)
        np.testing.assert_allclose(m.qpos_spring[sc.joint_qpos[f]], sc.springs.rest, rtol=0, atol=1e-15)


@pytest.mark.parametrize("K, shape", [(4, "box"), (3, "cylinder"), (3, "sphere")])
def test_fingers_are_evenly_spaced_and_bend_in_their_own_planes(K, shape):
    yaw = 0.4
    sc = build_gripper("II", STANDARD, Uniform(5), N, fingers=K, workpiece=shape, yaw=yaw,
                       initial_angles=np.linspace(0.1, 0.3, N))
    d = sc.data
    np.testing.assert_allclose(sc.azimuths, yaw + 2 * math.pi * np.arange(K) / K)
    tips = np.asarray(d.geom_xpos[sc.tip_geom])
    for f in range(K):
        e3 = sc.frame(f)[1]
        local = sc.frame(f) @ tips[f]
        assert abs(local[1]) < 1e-12  # in the finger's own vertical plane
        # every finger's tip is where the planar finger's is in its frame
        np.testing.assert_allclose(local, tips[0] @ sc.frame(0).T, atol=1e-12)
        # the hinge axes are normal to the finger's plane (-E3)
        for j in sc.index.joint_qpos[f]:
            jid = int(np.flatnonzero(sc.model.jnt_qposadr == j)[0])
            axis = np.asarray(d.xaxis[jid])
            np.testing.assert_allclose(axis, -e3, atol=1e-12)


@pytest.mark.parametrize("K, shape", [(4, "box"), (2, "box"), (4, "cylinder"), (3, "sphere")])
def test_workpiece_surface_is_b_over_2_minus_r_tip_from_the_axis(K, shape):
    sc = build_gripper("I", STANDARD, Uniform(-6), N, fingers=K, workpiece=shape, yaw=0.3)
    m, d = sc.model, sc.data
    # the workpiece's centre is on the palm axis, level with the start's tips
    assert np.allclose(d.xpos[sc.workpiece_body][:2], 0.0)
    assert d.xpos[sc.workpiece_body][2] == pytest.approx(d.geom_xpos[sc.tip_geom[0]][2], abs=1e-12)
    # a tip centre at X = b/2 along each finger's E1 touches the surface (distance r_tip)
    for f in range(K):
        e1 = sc.frame(f)[0]
        point = 0.5 * STANDARD.b * e1 + d.xpos[sc.workpiece_body]
        wid = sc.workpiece_geom
        size = m.geom_size[wid]
        R = d.geom_xmat[wid].reshape(3, 3)
        local = R.T @ (point - d.geom_xpos[wid])
        if shape == "box":
            dist = np.max(np.abs(local) - size)  # outside a face: distance along its normal
        elif shape == "cylinder":
            dist = math.hypot(local[0], local[1]) - size[0]
        else:
            dist = np.linalg.norm(local) - size[0]
        assert dist == pytest.approx(sc.r_tip, abs=1e-12)
    if shape == "box" and K == 2:
        assert m.geom_size[sc.workpiece_geom][1] == pytest.approx(0.5 * BOX_DEPTH)


def test_check_gripper_normalises_and_names_what_is_wrong():
    assert check_gripper("i", 3, " Cylinder ") == ("I", 3, "cylinder")
    bad = [
        (("I", 3, "box"), "fingers"),  # a box takes 2 or 4
        (("I", 5, "box"), "fingers"),
        (("I", 1, "cylinder"), "fingers"),
        (("I", True, "cylinder"), "fingers"),
        (("I", 2.0, "cylinder"), "fingers"),
        (("I", 3, "cone"), "workpiece"),
        (("I", 3, None), "workpiece"),
        (("III", 3, "box"), "fingers"),  # the cradle (Grip III) is a box with K = 4
        (("free", 3, "cylinder"), "grip"),
        (("V", 3, "cylinder"), "grip"),
    ]
    for args, name in bad:
        with pytest.raises(ValueError, match=name):
            check_gripper(*args)
    with pytest.raises(ValueError, match="fingers.*workpiece 'box'"):
        build_gripper("I", STANDARD, -6, N, fingers=3, workpiece="box")


def test_build_gripper_input_checks():
    def build(**kw):
        args = dict(fingers=3, workpiece="cylinder")
        args.update(kw)
        return build_gripper("I", STANDARD, Uniform(-6), args.pop("n", N), **args)

    cases = [
        (dict(yaw=math.nan), "yaw"), (dict(yaw="x"), "yaw"), (dict(r_tip=0.0), "r_tip"), (dict(r_link=1.0), "r_link"),
        (dict(n=1), "links"), (dict(initial_angles=np.zeros(3)), "initial_angles"),
        (dict(fingers=1000), "fingers"),  # 1000 tip spheres do not fit around b/2 = 0.3
        (dict(contact_angle=0.1), "contact_angle"),  # a cylinder's surface is vertical
        (dict(workpiece="sphere", contact_angle=math.pi / 2), "contact_angle"),
        (dict(workpiece="sphere", contact_angle=math.nan), "contact_angle"),
    ]
    for kw, name in cases:
        with pytest.raises(ValueError, match=name):
            build(**kw)
    with pytest.raises(ValueError, match="params"):
        build_gripper("I", {"D": 1}, -6, N)
    assert build(workpiece="sphere", contact_angle=-0.3).contact_angle == -0.3

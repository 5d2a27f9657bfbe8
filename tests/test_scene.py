"""Scene builder: structure, what is skipped, runtime edits, input checks."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.chain import chain_springs
from simgrip.params import DimensionlessParams
from simgrip.sim.fingers import MAX_BODY_DEPTH
from simgrip.sim.scene import Scene, build_scene, finger_state, set_curvature, set_joint_angles
from simgrip.sim.workpiece import cradle_contact

KAPPA = {"free": -4.0, "I": -6.0, "II": 5.0, "III": -6.0}
N = 12


# Every scene compiling and running without MuJoCo warnings: tests/test_models.py.


@pytest.mark.parametrize("grip", ["free", "I", "II", "III"])
def test_scene_holds_what_the_builder_made(grip):
    sc = build_scene(grip, STANDARD, Uniform(KAPPA[grip]), N, fingers=2)
    assert isinstance(sc, Scene) and sc.grip == grip and sc.n == N and sc.fingers == 2
    assert sc.joint_qpos.shape == (2, N) and sc.link_body.shape == (2, N)
    assert sc.has_workpiece == (grip != "free")
    if grip in ("I", "II"):
        assert np.all(sc.tip_geom >= 0)
    else:
        assert np.all(sc.tip_geom == -1)


def test_chain_springs_masses_and_hinge_axis():
    sc = build_scene("free", STANDARD, Uniform(-3.0), N)
    m = sc.model
    sp = chain_springs(Uniform(-3.0), N)
    j = sc.joint_qpos[0]
    jid = [m.joint(f"f0_joint{i}").id for i in range(N)]
    np.testing.assert_allclose(m.jnt_stiffness[jid], STANDARD.D * sp.stiffness, rtol=1e-15)
    np.testing.assert_allclose(m.qpos_spring[j], sp.rest, rtol=1e-15)
    np.testing.assert_allclose(m.body_mass[sc.link_body[0]], 1.0 / N, rtol=1e-15)
    np.testing.assert_allclose(m.body_ipos[sc.link_body[0]][:, 0], 0.5 / N, rtol=1e-15)
    # a positive hinge angle is a counter-clockwise theta: the tip rises
    set_joint_angles(sc, np.r_[0.1, np.zeros(N - 1)])
    tip = sc.data.xpos[sc.link_body[0, -1]] + sc.data.xmat[sc.link_body[0, -1]].reshape(3, 3) @ [1.0 / N, 0, 0]
    np.testing.assert_allclose(tip[[0, 2]], [math.cos(0.1), math.sin(0.1)], atol=1e-14)
    _, _, nodes = finger_state(sc)
    np.testing.assert_allclose(nodes[-1], tip[[0, 2]], atol=1e-14)


def test_free_rod_has_no_contact_at_all():
    sc = build_scene("free", STANDARD, Uniform(-4.0), N, fingers=2)
    m = sc.model
    assert m.opt.disableflags & int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    assert m.npair == 0
    assert not np.any(m.geom_contype) and not np.any(m.geom_conaffinity)
    assert sc.workpiece_body == -1 and m.nv == 2 * N


@pytest.mark.parametrize("grip", ["I", "II", "III"])
def test_only_geoms_that_can_touch_the_workpiece_collide(grip):
    sc = build_scene(grip, STANDARD, Uniform(KAPPA[grip]), N, fingers=2)
    m = sc.model
    assert not np.any(m.geom_contype) and not np.any(m.geom_conaffinity)  # no broad phase, no self-collision
    pair_geoms = {int(g) for g in m.pair_geom1} | {int(g) for g in m.pair_geom2}
    allowed = set(int(g) for g in sc.workpiece_geoms) | set(int(g) for gs in sc.contact_geoms for g in gs)
    assert pair_geoms <= allowed
    if grip in ("I", "II"):
        assert m.npair == 2  # one tip sphere per finger
        assert set(int(g) for g in m.pair_geom1) == set(int(g) for g in sc.tip_geom)
    else:
        assert 0 < m.npair < 2 * N  # only the links around gamma
    assert np.all(m.pair_dim == 3)


def test_contact_geometry_places_the_centreline_where_theory_says():
    p = STANDARD
    sc = build_scene("I", p, Uniform(-6.0), N)
    hx = sc.box_half[0]
    assert hx == pytest.approx(p.b / 2 - sc.r_tip, rel=1e-15)  # tip sphere centred at s = l touches at X = b/2
    sc3 = build_scene("III", p, Uniform(-6.0), N)
    assert sc3.model.ngeom > 0
    # the corner capsule touches the rod at the start (within round-off)
    m, d = sc3.model, sc3.data
    dists = [mujoco.mj_geomDistance(m, d, int(a), int(b), 1.0, None) for a, b in zip(m.pair_geom1, m.pair_geom2)]
    assert min(dists) == pytest.approx(0.0, abs=1e-12)


def test_render_dressing_only_when_asked():
    plain = build_scene("I", STANDARD, Uniform(-6.0), N)
    dressed = build_scene("I", STANDARD, Uniform(-6.0), N, render=True)
    assert plain.model.nlight == 0 and plain.model.ncam == 0 and plain.model.ntex == 0
    assert dressed.model.nlight > 0 and dressed.model.ncam > 0
    assert plain.model.nsensor == 0 and dressed.model.nsensor == 0


def test_symmetric_reduction_and_two_finger_workpieces():
    one = build_scene("I", STANDARD, Uniform(-6.0), N)
    two = build_scene("I", STANDARD, Uniform(-6.0), N, fingers=2)
    fixed = build_scene("I", STANDARD, Uniform(-6.0), N, free_workpiece=False)
    assert one.workpiece_joints == ("z",)
    assert two.workpiece_joints == ("x", "z", "ry")
    assert fixed.workpiece_joints == ()
    assert one.model.body_mass[one.workpiece_body] == pytest.approx(STANDARD.M)
    assert two.model.body_mass[two.workpiece_body] == pytest.approx(2 * STANDARD.M)


def test_mirrored_finger_reads_like_finger_zero():
    sc = build_scene("free", STANDARD, Uniform(-4.0), N, fingers=2)
    q = np.linspace(-0.3, 0.2, N)
    set_joint_angles(sc, q)
    d = sc.data
    x0 = d.xpos[sc.link_body[0, -1]]
    x1 = d.xpos[sc.link_body[1, -1]]
    np.testing.assert_allclose(x1, [-x0[0], x0[1], x0[2]], atol=1e-14)
    np.testing.assert_allclose(finger_state(sc, finger=1)[2], finger_state(sc, finger=0)[2], atol=1e-15)


def test_set_curvature_writes_qpos_spring_like_a_rebuild():
    sc = build_scene("II", STANDARD, Uniform(2.0), N)
    set_curvature(sc, Uniform(5.0))
    fresh = build_scene("II", STANDARD, Uniform(5.0), N)
    np.testing.assert_array_equal(sc.model.qpos_spring, fresh.model.qpos_spring)
    np.testing.assert_array_equal(sc.model.jnt_stiffness, fresh.model.jnt_stiffness)


def test_build_is_deterministic():
    a = build_scene("III", STANDARD, Uniform(-6.0), N, fingers=2)
    b = build_scene("III", STANDARD, Uniform(-6.0), N, fingers=2)
    for name in ("qpos0", "qpos_spring", "body_pos", "geom_size", "jnt_stiffness", "pair_geom1", "body_mass"):
        np.testing.assert_array_equal(getattr(a.model, name), getattr(b.model, name))
    np.testing.assert_array_equal(a.data.qpos, b.data.qpos)


def test_physical_params_build_in_si_units():
    phys = STANDARD.to_physical(length=0.1, rho=0.2, g=9.81)
    sc = build_scene("free", phys, Uniform(-4.0), N)
    assert sc.model.opt.gravity[2] == pytest.approx(-9.81)
    assert sc.model.body_mass[sc.link_body[0, 0]] == pytest.approx(0.2 * 0.1 / N)
    assert sc.hinge_stiffness[1] == pytest.approx(phys.EI / phys.length * N)
    assert sc.params.D == pytest.approx(STANDARD.D)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        (dict(grip="IV"), "grip"),
        (dict(n_links=1), "links"),
        (dict(n_links=2.5), "links"),
        (dict(fingers=3), "fingers"),
        (dict(r_tip=float("nan")), "r_tip"),
        (dict(r_link=-1.0), "r_link"),
        (dict(profile=float("nan")), "kappa"),
        (dict(params="standard"), "params"),
        (dict(initial_angles=np.zeros(3)), "initial_angles"),
    ],
)
def test_invalid_input_names_the_parameter(kwargs, name):
    args = dict(grip="I", params=STANDARD, profile=Uniform(-6.0), n_links=N)
    args.update(kwargs)
    with pytest.raises(ValueError, match=name):
        build_scene(**args)


def test_invalid_params_are_rejected_before_building():
    with pytest.raises(ValueError, match="D"):
        build_scene("free", DimensionlessParams(D=float("nan")), Uniform(0.0), N)


def test_links_beyond_mujocos_body_depth_are_refused_before_building():
    with pytest.raises(ValueError, match=f"links must be at most {MAX_BODY_DEPTH}"):
        build_scene("I", STANDARD, Uniform(-5.5), 100_000)


def test_a_grip_i_box_too_narrow_for_the_tip_names_b():
    with pytest.raises(ValueError, match=r"^b must exceed 2 r_tip") as info:
        build_scene("I", STANDARD.replace(b=0.001), Uniform(-4.0), N)
    assert "III" not in str(info.value) and "initial_angles" not in str(info.value)


def test_grip_iii_needs_gamma_beyond_half_the_box():
    with pytest.raises(ValueError, match=r"gamma = 0.8 must exceed b/2 = 0.85 for Grip III"):
        build_scene("III", STANDARD.replace(b=1.7, gamma=0.8), Uniform(-6.0), N)


def test_grip_iii_default_start_puts_the_corner_at_gamma():
    """Without initial_angles the start is geometric (no solver) and the contact is at gamma, X = b/2."""
    sc = build_scene("III", STANDARD, Uniform(-6.0), 64)
    s, _, point = cradle_contact(finger_state(sc)[0], sc.springs, STANDARD.b, STANDARD.gamma)
    assert s == pytest.approx(STANDARD.gamma, abs=1.0 / 64)  # the polyline crosses within a link of gamma
    assert point[0] == pytest.approx(STANDARD.b / 2, abs=1e-12)

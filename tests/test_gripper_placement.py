"""Off-centre, turned workpieces and a profile per finger (simgrip.gripper.placement, build_gripper, the CLI).

The reach is checked against MuJoCo's own geometry: a tip centre at ``X =
reach`` along the finger's ``E1`` lies ``r_tip`` from the compiled workpiece
geom's surface, and the surface's outward normal there is the reported one.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.chain import chain_springs
from simgrip.cli import main
from simgrip.gripper.scene import build_gripper, uniform_profiles
from simgrip.gripper.placement import check_offset, check_workpiece_yaw, place_fingers

N = 8


def _surface(scene, point):
    """Distance of a world point from the workpiece geom's surface and the outward normal there (world)."""
    m, d = scene.model, scene.data
    g = scene.workpiece_geom
    R = d.geom_xmat[g].reshape(3, 3)
    local = R.T @ (point - d.geom_xpos[g])
    size = m.geom_size[g]
    if scene.workpiece == "box":
        over = np.abs(local) - size
        i = int(np.argmax(over))
        n = np.zeros(3)
        n[i] = math.copysign(1.0, local[i])
        return float(over[i]), R @ n
    radial = np.array([local[0], local[1], 0.0])
    return float(np.linalg.norm(radial) - size[0]), R @ (radial / np.linalg.norm(radial))


@pytest.mark.parametrize("K, shape, offset, psi, yaw", [
    (3, "cylinder", (0.03, -0.02), 0.0, 0.0), (5, "cylinder", (-0.1, 0.07), 1.0, 0.4),
    (4, "box", (0.02, 0.01), 0.1, 0.0), (4, "box", (-0.05, 0.04), -0.3, 2.0), (2, "box", (0.05, 0.0), 0.2, -0.7),
    (2, "cylinder", (-0.04, 0.0), 0.0, 0.3), (4, "cylinder", (0.0, 0.0), 0.0, 0.0),
])
def test_reach_is_where_the_tip_centre_touches(K, shape, offset, psi, yaw):
    sc = build_gripper("I", STANDARD, -6.0, N, fingers=K, workpiece=shape, offset=offset, workpiece_yaw=psi, yaw=yaw)
    d = sc.data
    # the workpiece sits at the offset turned with the scene, turned by yaw + psi about its axis
    c, s = math.cos(yaw), math.sin(yaw)
    np.testing.assert_allclose(d.xpos[sc.workpiece_body][:2] / sc.length,
                               [c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]], atol=1e-12)
    turn = 2 * math.atan2(d.xquat[sc.workpiece_body][3], d.xquat[sc.workpiece_body][0])
    assert math.remainder(turn - yaw - psi, 2 * math.pi) == pytest.approx(0.0, abs=1e-12)
    z = d.xpos[sc.workpiece_body][2]
    for k in range(K):
        e1, e3 = sc.frame(k)[0], sc.frame(k)[1]
        dist, normal = _surface(sc, sc.reach[k] * sc.length * e1 + np.array([0.0, 0.0, z]))
        assert dist == pytest.approx(sc.r_tip * sc.length, abs=1e-12)
        np.testing.assert_allclose(sc.normals[k], [normal @ e1, normal @ e3], atol=1e-12)
    if not any(offset) and psi == 0.0:
        np.testing.assert_allclose(sc.reach, 0.5 * STANDARD.b, atol=1e-15)


def test_reach_turns_with_the_scene():
    a = build_gripper("I", STANDARD, -6.0, N, fingers=4, workpiece="box", offset=(0.03, -0.01), workpiece_yaw=0.1)
    b = build_gripper("I", STANDARD, -6.0, N, fingers=4, workpiece="box", offset=(0.03, -0.01), workpiece_yaw=0.1,
                      yaw=1.3)
    np.testing.assert_allclose(a.reach, b.reach, atol=1e-14)
    np.testing.assert_allclose(a.normals, b.normals, atol=1e-14)


def test_a_profile_per_finger():
    profs = [Uniform(-6.0), Uniform(-5.5), Uniform(-7.0)]
    sc = build_gripper("I", STANDARD, profs, N, fingers=3, workpiece="cylinder")
    k = sc.model.jnt_stiffness[sc.model.dof_jntid]
    for f, p in enumerate(profs):
        sp = chain_springs(p, N)
        np.testing.assert_allclose(sc.model.qpos_spring[sc.joint_qpos[f]], sp.rest, rtol=0, atol=1e-15)
        np.testing.assert_allclose(k[sc.joint_dof[f]], STANDARD.D * sp.stiffness, rtol=1e-12)  # same stiffness
        assert sc.profiles[f] is p and np.array_equal(sc.finger_springs[f].rest, sp.rest)
    assert sc.profile is profs[0]
    assert uniform_profiles([-6, -5.5, -7], 3) == tuple(profs)


@pytest.mark.parametrize("kw, name", [
    (dict(offset=(0.3, 0.0)), "offset"),  # the palm axis outside the cylinder
    (dict(offset=(0.1, math.nan)), "offset"), (dict(offset=(0.1,)), "offset"), (dict(offset="x"), "offset"),
    (dict(workpiece="box", fingers=4, offset=(0.0, 0.3)), "offset"),
    (dict(workpiece="box", fingers=2, offset=(0.0, 0.05)), "offset"),  # the box is 0.2 deep across K = 2
    (dict(workpiece="cylinder", fingers=2, offset=(0.0, 0.01)), "offset"),  # off the fingers' plane
    (dict(workpiece="sphere", offset=(0.01, 0.0)), "offset"),
    (dict(workpiece="box", fingers=4, workpiece_yaw=math.pi / 4), "workpiece_yaw"),  # finger on an edge
    (dict(workpiece_yaw=math.inf), "workpiece_yaw"), (dict(workpiece_yaw="a"), "workpiece_yaw"),
    (dict(profile=[-6.0, -6.0]), "profile"),  # two profiles for three fingers
    (dict(workpiece="sphere", profile=[-6.0, -6.0, -5.0]), "profile"),
])
def test_bad_placement_names_the_parameter(kw, name):
    args = dict(fingers=3, workpiece="cylinder")
    args.update(kw)
    profile = args.pop("profile", -6.0)
    with pytest.raises(ValueError, match=name):
        build_gripper("I", STANDARD, profile, N, **args)


def test_checks_and_placement_directly():
    assert check_offset((1, 2)).tolist() == [1.0, 2.0] and check_workpiece_yaw(0.5) == 0.5
    p = place_fingers("cylinder", [0.0, math.pi], [0.25, 1.0, 0.0], 0.05, (0.1, 0.0), 0.0)
    np.testing.assert_allclose(p.reach, [0.4, 0.2])
    np.testing.assert_allclose(p.normal, [[1, 0], [1, 0]], atol=1e-15)
    p = place_fingers("box", [0.0], [0.25, 0.25, 1.0], 0.05, (0.0, 0.0), 0.2)
    assert p.reach[0] == pytest.approx(0.3 / math.cos(0.2)) and p.face[0] == 0
    np.testing.assert_allclose(p.normal[0], [math.cos(0.2), math.sin(0.2)], atol=1e-15)  # the +x face, turned
    for bad in ((1, 2, 3), None, [[1, 2]]):
        with pytest.raises(ValueError, match="offset"):
            check_offset(bad)
    for bad in ([-6.0], [-6.0, math.nan, 1.0], [-6.0, 200.0, 1.0], "abc"):
        with pytest.raises(ValueError, match="kappa_per_finger"):
            uniform_profiles(bad, 3)


def test_cli_offset_yaw_and_a_curvature_per_finger(capsys):
    assert main(["simulate", "I", "--links", "12", "--json", "--fingers", "3", "--workpiece", "cylinder",
                 "--kappa-per-finger", "-6", "-5.8", "-6.3", "--offset", "0.03", "-0.02", "--workpiece-yaw", "10"]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert rec["held"] and len(rec["fingers"]) == 3
    assert rec["offset"] == [0.03, -0.02] and rec["workpiece_yaw"] == pytest.approx(math.radians(10))
    assert len({round(f["N1"], 6) for f in rec["fingers"]}) == 3  # unequal fingers push unequally
    assert any(abs(f["N3"]) > 1e-3 for f in rec["fingers"])  # and friction carries the difference out of plane
    assert rec["min_eigenvalue"] > 0


@pytest.mark.parametrize("args, name", [
    (["--fingers", "3", "--kappa-per-finger", "-6", "-6"], "kappa_per_finger"),
    (["--fingers", "3", "--kappa-per-finger", "-6", "-6", "nan"], "kappa_per_finger"),
    (["--fingers", "3", "--offset", "0.5", "0"], "offset"),
    (["--fingers", "3", "--offset", "0.1"], "offset"),
    (["--fingers", "3", "--workpiece-yaw", "inf"], "workpiece_yaw"),
    (["--fingers", "4", "--workpiece", "box", "--workpiece-yaw", "45"], "workpiece_yaw"),
    (["--offset", "0.01", "0"], "fingers"),
    (["--kappa-per-finger", "-6", "-6", "-6"], "fingers"),
])
def test_bad_options_exit_2_naming_them(capsys, args, name):
    base = ["simulate", "I", "--links", "8"] + ([] if "--kappa-per-finger" in args else ["--kappa", "-6"])
    assert main(base + args) == 2
    err = capsys.readouterr().err
    assert name in err and "Traceback" not in err


def test_kappa_and_kappa_per_finger_together_is_refused(capsys):
    assert main(["simulate", "I", "--links", "8", "--kappa", "-6", "--fingers", "3",
                 "--kappa-per-finger", "-6", "-6", "-6"]) == 2
    assert "kappa_per_finger" in capsys.readouterr().err

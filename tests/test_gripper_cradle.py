"""The K = 4 cradle's scene (simgrip.gripper.cradle): every finger's section is the planar Grip III scene."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.scenes import build_scene, start_angles
from simgrip.gripper.scene import build_gripper, check_gripper
from simgrip.gripper.cradle import corner_name, cradle_start_angles

N = 16


def _cradle(yaw=0.0, **kw):
    q = start_angles("III", STANDARD, Uniform(-4.0), N)
    return build_gripper("III", STANDARD, Uniform(-4.0), N, fingers=4, workpiece="box", initial_angles=q, yaw=yaw,
                         **kw)


@pytest.mark.parametrize("yaw", [0.0, 0.7])
def test_each_finger_meets_the_planar_cradle_section(yaw):
    sc = _cradle(yaw)
    pl = build_scene("III", STANDARD, Uniform(-4.0), N)
    m, d, L = sc.model, sc.data, sc.length
    np.testing.assert_allclose(sc.size, [pl.box_half[0], pl.box_half[0], pl.box_half[2]], rtol=1e-14)
    np.testing.assert_array_equal(cradle_start_angles(m), pl.data.qpos[pl.joint_qpos[0]])
    assert m.body_mass[sc.workpiece_body] == pytest.approx(4 * STANDARD.M * L * sc.physical.rho, rel=1e-14)
    mujoco.mj_forward(m, d)
    pz = float(pl.data.xpos[pl.workpiece_body][2])
    assert float(d.xpos[sc.workpiece_body][2]) == pytest.approx(pz, abs=1e-14)
    # the planar corner, seen in each finger's frame: the edge of its own face, along E3, at the same place
    pc = pl.data.geom_xpos[mujoco.mj_name2id(pl.model, mujoco.mjtObj.mjOBJ_GEOM, "corner0")]
    plinks = sorted(int(pl.model.pair_geom1[i]) - int(pl.index.link_geom[0, 0]) for i in range(pl.model.npair))
    for k in range(4):
        g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, corner_name(k))
        R = sc.frame(k)
        np.testing.assert_allclose(R @ d.geom_xpos[g], [pc[0], 0.0, pc[2]], atol=1e-14)
        axis = R @ np.asarray(d.geom_xmat[g]).reshape(3, 3)[:, 2]
        assert abs(abs(axis[1]) - 1.0) <= 1e-12  # along E3, out of the finger's plane
        assert m.geom_size[g][1] == pytest.approx(sc.size[0], rel=1e-14)  # the whole face's width
        links = sorted(int(m.pair_geom1[i]) - int(sc.index.link_geom[k, 0]) for i in range(m.npair)
                       if int(m.pair_geom2[i]) == g)
        assert links == plinks
    # the start touches every edge as the planar start touches its corner
    touching = {int(d.contact.geom2[i]) for i in range(d.ncon)}
    assert touching == {mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, corner_name(k)) for k in range(4)}
    assert np.all(sc.tip_geom < 0)  # no tip sphere (as the planar cradle)


def test_default_start_is_the_geometric_cradle():
    from simgrip.sim.workpiece import cradle_start

    sc = build_gripper("III", STANDARD, Uniform(-4.0), N, fingers=4, workpiece="box")
    np.testing.assert_allclose(cradle_start_angles(sc.model), cradle_start(STANDARD.b, STANDARD.gamma, Uniform(-4.0), N))


def test_bad_cradles_are_refused():
    for kw, name in [(dict(fingers=3, workpiece="box"), "workpiece"), (dict(fingers=4, workpiece="cylinder"), "workpiece"),
                     (dict(fingers=2, workpiece="box"), "fingers = 2")]:
        with pytest.raises(ValueError, match=name):
            check_gripper("III", kw["fingers"], kw["workpiece"])
    with pytest.raises(ValueError, match="offset"):
        build_gripper("III", STANDARD, Uniform(-4.0), N, fingers=4, workpiece="box", offset=(0.01, 0.0))
    with pytest.raises(ValueError, match="profile"):
        build_gripper("III", STANDARD, [Uniform(-4.0)] * 4, N, fingers=4, workpiece="box")
    q = np.tile(start_angles("III", STANDARD, Uniform(-4.0), N), (4, 1))
    q[1, 3] += 0.01
    with pytest.raises(ValueError, match="initial_angles"):
        build_gripper("III", STANDARD, Uniform(-4.0), N, fingers=4, workpiece="box", initial_angles=q)
    with pytest.raises(ValueError, match="r_link"):
        build_gripper("III", STANDARD, Uniform(-4.0), N, fingers=4, workpiece="box", r_link=-1.0)


def test_simulate_the_cradle_from_the_command_line(capsys):
    """``simulate III --fingers 4 --workpiece box``: every finger is the planar ``simulate III`` (same start)."""
    import json

    from simgrip.cli import main

    args = ["simulate", "III", "--kappa", "-4", "--links", "12", "--json"]
    assert main(args) == 0
    planar = json.loads(capsys.readouterr().out)
    assert main(args + ["--fingers", "4", "--workpiece", "box"]) == 0
    rec = json.loads(capsys.readouterr().out)
    assert rec["held"] and rec["method"] == "symmetric" and len(rec["fingers"]) == 4
    for f in rec["fingers"]:
        for key in ("normal_force", "friction_force", "N1", "N2"):
            assert f[key] == pytest.approx(planar[key], abs=1e-12)
        np.testing.assert_allclose(f["tip"], planar["tip"], atol=1e-12)

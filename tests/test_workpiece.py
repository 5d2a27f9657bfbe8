"""Workpiece placement: the geometric Grip III start, the cradle contact, holding and placing."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simgrip import STANDARD, Uniform
from simgrip.chain import chain_springs, link_positions
from simgrip.sim.scene import build_scene
from simgrip.sim.workpiece import contact_links, cradle_contact, cradle_start
from simgrip.sim.workpiece_motion import hold_workpiece, place_workpiece, workpiece_pose


@pytest.mark.parametrize("b, gamma", [(0.6, 0.8), (0.2, 0.8), (1.2, 0.8), (0.6, 0.5)])
def test_cradle_start_crosses_half_the_box_at_gamma_heading_inwards(b, gamma):
    n = 400
    q = cradle_start(b, gamma, Uniform(-6.0), n)
    phi = np.cumsum(q)
    nodes = link_positions(phi, 1.0 / n)
    # link angles are the centreline's at the link midpoints: nodes lie on the arc to O(ds^2)
    s, theta, point = cradle_contact(q, chain_springs(Uniform(-6.0), n), b, gamma)
    assert s == pytest.approx(gamma, abs=2.0 / n)
    assert point[0] == pytest.approx(b / 2, abs=1e-12)
    assert math.cos(theta) < 0.0
    assert np.all(nodes[: int(gamma * n), 0] >= -1e-12)  # the finger never crosses the symmetry line first


def test_cradle_start_refuses_a_box_wider_than_twice_gamma():
    with pytest.raises(ValueError, match="b/2 must be below gamma"):
        cradle_start(1.7, 0.8, Uniform(-6.0), 16)


def test_cradle_contact_falls_back_to_gamma_without_an_inward_crossing():
    sp = chain_springs(Uniform(0.0), 10)
    s, theta, point = cradle_contact(np.zeros(10), sp, 0.6, 0.8)  # straight finger: crosses b/2 heading out
    assert s == pytest.approx(0.8) and theta == 0.0
    np.testing.assert_allclose(point, [0.8, 0.0])


def test_contact_links_are_the_window_around_the_contact():
    sp = chain_springs(Uniform(0.0), 10)
    assert list(contact_links(0.5, sp, 0.15)) == [3, 4, 5, 6]


def test_hold_and_place_move_the_workpiece_as_asked():
    sc = build_scene("I", STANDARD, Uniform(-6.0), 8)
    place_workpiece(sc, -0.3)
    assert workpiece_pose(sc)[1] == pytest.approx(-0.3)
    hold_workpiece(sc, True)
    assert sc.data.qfrc_applied[sc.workpiece_dof[0]] == pytest.approx(sc.workpiece_mass * sc.physical.g)
    hold_workpiece(sc, False)
    assert sc.data.qfrc_applied[sc.workpiece_dof[0]] == 0.0
    fixed = build_scene("I", STANDARD, Uniform(-6.0), 8, free_workpiece=False)
    place_workpiece(fixed, -0.25)
    assert workpiece_pose(fixed)[1] == pytest.approx(-0.25)
    assert workpiece_pose(build_scene("free", STANDARD, Uniform(-6.0), 8)) is None


@pytest.mark.parametrize("shape, size", [("box", (0.03, 0.02, 0.05)), ("cylinder", (0.025, 0.04, 0.0)),
                                         ("sphere", (0.03, 0.0, 0.0))])
def test_workpiece_inertia_is_mujocos_inertia_of_the_solid_geom(shape, size):
    """The one inertia formula (PickEnv's box, the K-finger scenes, add_workpiece) against MuJoCo's own
    inertia of the same solid geom (inertiafromgeom), to round-off."""
    import mujoco

    from simgrip.sim.workpiece import workpiece_inertia

    mass = 0.047
    spec = mujoco.MjSpec()
    body = spec.worldbody.add_body(name="w")
    body.add_freejoint()
    types = {"box": mujoco.mjtGeom.mjGEOM_BOX, "cylinder": mujoco.mjtGeom.mjGEOM_CYLINDER,
             "sphere": mujoco.mjtGeom.mjGEOM_SPHERE}
    body.add_geom(type=types[shape], size=list(size), mass=mass)
    model = spec.compile()
    b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "w")
    assert model.body_mass[b] == pytest.approx(mass, rel=1e-12)
    np.testing.assert_allclose(workpiece_inertia(shape, size, mass), model.body_inertia[b], rtol=1e-9)

"""Finger builder and index: names, addresses, hinge springs, damping, the depth limit."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from simgrip import Uniform
from simgrip.chain import chain_springs
from simgrip.models import model_path
from simgrip.sim.fingers import (MAX_BODY_DEPTH, add_fingers, check_finger_links, finger_names, index_fingers,
                                 max_links)

N = 7


def _build(prefix="", **kw):
    spec = mujoco.MjSpec.from_file(str(model_path("defaults.xml")))
    parent = spec.worldbody.add_body(name="palm")
    args = dict(fingers=2, length=0.1, EI=3e-3, rho=0.15, r_link=0.004, r_tip=0.004, prefix=prefix)
    args.update(kw)
    add_fingers(spec, parent, chain_springs(Uniform(-3.0), N), **args)
    return spec.compile()


def test_index_finds_every_finger_element_by_name():
    m = _build(prefix="hand_")
    idx = index_fingers(m, 2, N, "hand_")
    for f in range(2):
        for i in range(N):
            body, joint, geom = finger_names(f, i, "hand_")
            assert m.body(idx.link_body[f, i]).name == body
            assert m.geom(idx.link_geom[f, i]).name == geom
            assert idx.joint_qpos[f, i] == m.jnt_qposadr[m.joint(joint).id]
        assert m.geom(idx.tip_geom[f]).name == f"hand_f{f}_tip"
    owner = idx.finger_of_geom
    assert set(np.flatnonzero(owner == 0)) == set(idx.link_geom[0]) | {idx.tip_geom[0]}
    assert set(np.flatnonzero(owner == 1)) == set(idx.link_geom[1]) | {idx.tip_geom[1]}
    assert idx.hinge_qpos == slice(0, 2 * N)
    with pytest.raises(ValueError):
        idx.joint_qpos[0, 0] = 5  # read-only


def test_hinges_carry_the_chain_springs_damping_and_armature():
    m = _build(damping_time=0.02, armature=1e-5)
    idx = index_fingers(m, 2, N)
    k = 3e-3 / 0.1 * chain_springs(Uniform(-3.0), N).stiffness
    jid = [m.joint(finger_names(1, i)[1]).id for i in range(N)]
    np.testing.assert_allclose(m.jnt_stiffness[jid], k, rtol=1e-15)
    np.testing.assert_allclose(m.dof_damping[idx.joint_dof[1]], 0.02 * k, rtol=1e-15)
    np.testing.assert_allclose(m.dof_armature[idx.joint_dof[1]], 1e-5)
    np.testing.assert_allclose(m.qpos_spring[idx.joint_qpos[0]], chain_springs(Uniform(-3.0), N).rest, rtol=1e-15)
    np.testing.assert_allclose(m.body_mass[idx.link_body], 0.15 * 0.1 / N)


def test_without_a_tip_radius_there_is_no_tip():
    m = _build(r_tip=None)
    assert np.all(index_fingers(m, 2, N).tip_geom == -1)


def test_a_spec_without_the_finger_classes_is_refused():
    spec = mujoco.MjSpec()
    with pytest.raises(ValueError, match="finger.xml"):
        add_fingers(spec, spec.worldbody, chain_springs(Uniform(0.0), N), fingers=1, length=1.0, EI=1.0, rho=1.0,
                    r_link=0.01)


def test_link_count_is_bounded_by_mujocos_body_depth():
    assert max_links() == MAX_BODY_DEPTH and max_links(1) == MAX_BODY_DEPTH - 1
    assert check_finger_links(MAX_BODY_DEPTH) == MAX_BODY_DEPTH
    with pytest.raises(ValueError, match="n_links must be at most"):
        check_finger_links(MAX_BODY_DEPTH, parent_depth=1, name="n_links")
    with pytest.raises(ValueError, match="^links must be an integer"):
        check_finger_links(1)


@pytest.mark.slow
def test_the_deepest_finger_compiles_and_one_more_link_would_not():
    """MAX_BODY_DEPTH is MuJoCo's limit: a chain of that many links compiles (one more fails in MuJoCo)."""
    for n in (MAX_BODY_DEPTH, MAX_BODY_DEPTH + 1):
        spec = mujoco.MjSpec.from_file(str(model_path("defaults.xml")))
        add_fingers(spec, spec.worldbody, chain_springs(Uniform(0.0), n), fingers=1, length=1.0, EI=1.0, rho=1.0,
                    r_link=1e-3)
        if n == MAX_BODY_DEPTH:
            assert spec.compile().nbody == MAX_BODY_DEPTH + 1
        else:
            with pytest.raises(ValueError, match="depth"):
                spec.compile()

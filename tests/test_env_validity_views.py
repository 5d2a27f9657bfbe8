"""The validity probe's bound views (issue 18 item 5): ``FingerValidity`` keeps views of the last ``MjData``'s node rows
and binds them again for another ``data`` (a K-finger env switches models per shape; tests probe their own data), and a
pickled or copied probe reads the data it is given, never a stale copy of the views."""

from __future__ import annotations

import copy
import pickle

import mujoco
import numpy as np

from simgrip.envs.pick import PickEnv


def _curled(env, hinge: float) -> mujoco.MjData:
    """A fresh data of ``env``'s model with every hinge at ``hinge`` [rad], kinematics computed."""
    d = mujoco.MjData(env.model)
    mujoco.mj_resetData(env.model, d)
    d.qpos[env.joint_qpos.ravel()] = hinge
    mujoco.mj_forward(env.model, d)
    return d


def test_views_follow_the_data_they_are_given():
    env = PickEnv()
    v = env._validity
    bad = _curled(env, -1.2)  # 12 links x -1.2 rad: each finger rolls through itself
    good = _curled(env, -0.1)  # curled (past the pure-Python screen) but clear
    q_bad, q_good = bad.qpos.tolist(), good.qpos.tolist()
    assert not v._mild(q_good) and v._bound(q_good, good) == 1  # decided by the bound: the views are read
    assert v(q_good, good) == []
    found = v(q_bad, bad)
    assert found and v._views[0] is bad
    assert v(q_good, good) == [] and v._views[0] is good
    assert v(q_bad, bad) == found  # bound again to the first data: the same verdict and messages
    env.close()


def test_pickled_and_copied_probes_read_the_given_data():
    env = PickEnv()
    v = env._validity
    bad, good = _curled(env, -1.2), _curled(env, -0.1)
    found = v(bad.qpos.tolist(), bad)
    for other in (pickle.loads(pickle.dumps(v)), copy.deepcopy(v)):
        assert other._views == (None, None, None)
        assert other(good.qpos.tolist(), good) == []
        assert other(bad.qpos.tolist(), bad) == found
    # the coarse rows' nodes are copied from the data's own rows: a changed state is read, not a stale copy
    mujoco.mj_resetData(env.model, bad)
    bad.qpos[env.joint_qpos.ravel()] = -0.1
    mujoco.mj_forward(env.model, bad)
    assert v(bad.qpos.tolist(), bad) == []
    assert np.array_equal(v._P[:v._nb], bad.xpos[v._body_cols[0]:v._body_cols[1]])
    env.close()

"""The pick envs' validity probe (envs/pick_validity.py): its screens never change the exact check's verdict.

``FingerValidity`` returns ``[]`` early on three proofs (every link within the screen's cap of its start
direction; every compared pair's midpoint bound above the limit; every pair the bound left open farther than
the limit by its exact segment distance) and otherwise the messages of
:func:`simgrip.validity_hinges.folded_hinges` (a hinge turned by half a turn or more) and
:func:`simgrip.validity.chain_violations`.  The reference here is ``chain_violations`` on the same nodes with no
screen at all: over random finger shapes (uniform curvature plus noise, from straight to 1.7 turns, both signs,
so that crossings, overlaps and fingers through each other all occur) the probe's messages must equal the
reference's exactly, and every path must have been taken (else the test proves nothing about it).
"""

from __future__ import annotations

import math
from collections import Counter

import mujoco
import numpy as np
import pytest

from simgrip.envs.pick import PickEnv
from simgrip.envs.pick_multi import PickMultiEnv
from simgrip.validity import chain_violations


def _reference(v, data):
    """``chain_violations`` on every node, no screen, after :func:`simgrip.validity_hinges.folded_hinges` on every
    hinge (what the probe must agree with: the settle's verdict, :func:`simgrip.validity.state_violations`)."""
    from simgrip.validity_hinges import folded_hinges

    folded = [m for _, m in folded_hinges([[data.qpos[a] for a in row] for row in v._jq])]
    world = v.nodes(data)
    planar = []
    for f, w in enumerate(world):
        rel = w - w[0]
        planar.append(np.stack([rel @ v._dirs[f], rel[:, 2]], axis=1))
    L = v._length
    found = chain_violations([p / L for p in planar], [w / L for w in world], r_link=v._r / L, r_tip=None,
                             solid=None, base_sines=v._sines)
    return folded + [m for _, m in found]


@pytest.mark.parametrize("make", [lambda: PickEnv(), lambda: PickMultiEnv(fingers=3)], ids=["pick", "multi3"])
def test_probe_equals_the_unscreened_exact_check(make, monkeypatch):
    env = make()
    env.reset(seed=0)
    v, m, d = env._validity, env.model, env.data
    paths = Counter()
    for name in ("_mild", "_near_clear"):
        orig = getattr(type(v), name)

        def counted(self, *a, _orig=orig, _name=name):
            r = _orig(self, *a)
            paths[_name, bool(r)] += 1
            return r
        monkeypatch.setattr(type(v), name, counted)
    jq = np.asarray(env.fingers.joint_qpos)
    K, n = jq.shape
    rng = np.random.default_rng(1)
    for trial in range(400):
        # per finger: a uniform curvature (total turning kappa_bar rad) plus noise per hinge
        for f in range(K):
            kappa = rng.uniform(-11.0, 2.0) if trial % 4 else rng.uniform(-1.4, 1.4)
            d.qpos[jq[f]] = kappa / n + rng.normal(0.0, 0.15 if trial % 3 else 0.02, n)
        mujoco.mj_kinematics(m, d)
        got = v(d.qpos.tolist(), d)
        assert got == _reference(v, d), trial
        paths["invalid", bool(got)] += 1
    env.close()
    # every proof was used and passed at least once, the exact check ran (its proof failed), states of both kinds
    for key in (("_mild", True), ("_mild", False), ("_near_clear", True), ("_near_clear", False),
                ("invalid", True), ("invalid", False)):
        assert paths[key] > 0, (key, dict(paths))


def test_near_clear_refuses_a_folded_hinge():
    """A hinge turned by pi/2 or more could fold two adjacent links onto each other, a crossing the exact
    check's pair tests skip: the exact-distance proof then refuses and leaves the verdict to chain_violations."""
    env = PickEnv()
    env.reset(seed=0)
    v, d = env._validity, env.data
    q = d.qpos.tolist()
    a = int(np.asarray(env.fingers.joint_qpos)[0, 3])
    q[a] = 0.5 * math.pi
    W = v._world(d)
    assert v._near_clear(q, W, np.array([0]), np.array([5])) is False
    q[a] = 0.1
    assert v._near_clear(q, W, np.array([0]), np.array([5])) is True  # links 0 and 5 of a near-straight finger
    env.close()

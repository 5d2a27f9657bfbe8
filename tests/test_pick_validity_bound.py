"""The validity probe's matrix-product screen (``FingerValidity._bound``, issue 18) changes no verdict.

For random finger shapes (a curvature from straight to beyond a full curl, varied per finger, plus per-hinge
noise, some hinges past ``pi/2``) of the two-finger and the three-finger pick models, the probe's answer with the screen
equals the exact path's answer without it (messages included), and the screen proves valid only states the
exact path finds valid.  Each of its outcomes occurs (proved valid, sent straight to the exact messages,
undecided), so the comparison is not vacuous.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from simgrip.envs.pick import PickEnv
from simgrip.envs.pick_multi import PickMultiEnv
from simgrip.envs.pick_validity import FingerValidity


def _exact(probe: FingerValidity, q: list, data) -> list:
    """The probe's answer with the screen switched off (the path every verdict came from before issue 18)."""
    probe._bound = lambda q, data: 0  # an instance attribute hides the method: "undecided"
    try:
        return probe._check(q, data)
    finally:
        del probe._bound


@pytest.mark.parametrize("make", [lambda: PickEnv(), lambda: PickMultiEnv(fingers=3)], ids=["pick", "multi"])
def test_screen_gives_the_exact_verdict(make):
    env = make()
    m, d = env.model, mujoco.MjData(env.model)
    probe = env._validity
    rng = np.random.default_rng(18)
    joints = env.joint_qpos
    K, n = joints.shape
    counts = {"screened": 0, "doomed": 0, "passed_over": 0, "invalid": 0}
    for _ in range(300):
        mujoco.mj_resetData(m, d)
        kappa = rng.uniform(-13.0, 2.0) + rng.normal(0.0, 0.5, K)  # total turning per finger [rad], alike
        q = kappa[:, None] / n + rng.normal(0.0, 0.12, (K, n))
        q[rng.random((K, n)) < 0.02] += rng.choice((-1.0, 1.0)) * 1.7  # a few hinges past pi/2
        d.qpos[joints.ravel()] = q.ravel()
        d.qpos[env.palm_qpos] = rng.uniform(0.08, 0.2)
        mujoco.mj_kinematics(m, d)
        ql = d.qpos.tolist()
        exact = _exact(probe, ql, d)
        bound = 0 if probe._cap > 0.0 and probe._mild(ql) else probe._bound(ql, d)
        assert probe._check(ql, d) == exact
        if bound > 0:
            assert exact == [], "the screen proved valid a state the exact path finds invalid"
        counts[{1: "screened", -1: "doomed", 0: "passed_over"}[bound]] += 1
        counts["invalid"] += bool(exact)
    assert counts["screened"] > 30 and counts["doomed"] > 30 and counts["passed_over"] > 10 and counts["invalid"] > 10, counts
    assert math.isfinite(float(d.qpos.sum()))
    env.close()


def test_a_model_too_large_for_the_screen_goes_to_the_exact_path(monkeypatch):
    """A model whose pair rows would pass ``BOUND_MAX_ENTRIES`` builds none (two fingers of 1000 links would need
    ~60 GiB and raised MemoryError at construction) and answers every state by the exact path: the same verdicts
    and messages as the screened probe of the same model."""
    import simgrip.envs.pick_validity as pv

    env = PickEnv()
    screened = env._validity
    monkeypatch.setattr(pv, "BOUND_MAX_ENTRIES", 100)  # below this model's 233 rows x 26 nodes
    large = FingerValidity(env.model, env.fingers)
    assert large._QT is None and screened._QT is not None
    m, d = env.model, mujoco.MjData(env.model)
    rng = np.random.default_rng(7)
    K, n = env.joint_qpos.shape
    invalid = 0
    for _ in range(100):
        mujoco.mj_resetData(m, d)
        q = rng.uniform(-13.0, 2.0) / n + rng.normal(0.0, 0.15, (K, n))
        d.qpos[env.joint_qpos.ravel()] = q.ravel()
        mujoco.mj_kinematics(m, d)
        ql = d.qpos.tolist()
        assert large._bound(ql, d) == 0
        got = large._check(ql, d)
        assert got == screened._check(ql, d)
        invalid += bool(got)
    assert 10 < invalid < 90  # both verdicts occur
    env.close()

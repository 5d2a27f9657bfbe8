"""The fragile suite's ramped-palm, peak-rule versions (simgrip.envs.pick_fragile_v7).

Each is its older version made with ``palm_ramp=True, crush_at="peak"``, step for step and info for info (the
baselines and learning runs made as the older id with ``--env-kwargs '{"palm_ramp": true, "crush_at":
"peak"}'`` are these envs' runs), and made with the older defaults back it is the older version; the peak rule
ends episodes the end-of-step rule let go on.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  registers the environments
from simgrip.envs import FRAGILE_ENV_IDS, retired_spec
from simgrip.envs.pick_fragile_v7 import RAMP_PEAK
from env_checks import spoiled_controller

#: each new id -> the id it is made from (retired by it)
OLDER = {"simgrip/PickFragile-v7": "simgrip/PickFragile-v6",
         "simgrip/PickMultiFragile-v7": "simgrip/PickMultiFragile-v6",
         "simgrip/PlaceFragile-v8": "simgrip/PlaceFragile-v7",
         "simgrip/PickCradleFragile-v6": "simgrip/PickCradleFragile-v5",
         "simgrip/PickSphereFragile-v6": "simgrip/PickSphereFragile-v5"}


def test_the_new_versions_are_registered_and_the_older_retired():
    assert sorted(FRAGILE_ENV_IDS) == sorted(OLDER)
    for new, old in OLDER.items():
        spec, was = gym.spec(new), retired_spec(old)
        assert spec.max_episode_steps == was.max_episode_steps
        u = gym.make(new).unwrapped
        assert (u.palm_ramp, u.crush_at) == (True, "peak")
        assert type(u).__mro__[2].__name__ == was.entry_point.split(":")[1]  # the older class, under the mixin
        u.close()


def _episodes_beside(a, b, seeds, steps=400):
    """Step ``a`` and ``b`` beside each other under the spoiled observation-only controller (successes, drops,
    crushes); assert the same observations, rewards, flags and infos.  Returns the outcomes seen."""
    from simgrip.envs.outcome import outcome

    ends = []
    for seed in seeds:
        oa, ia = a.reset(seed=seed)
        ob, ib = b.reset(seed=seed)
        np.testing.assert_array_equal(oa, ob)
        start, act = spoiled_controller(a, seed)
        start(ia)
        for t in range(steps):
            x = act(oa, t, ia)
            oa, ra, ta, tra, ia = a.step(x)
            ob, rb, tb, trb, ib = b.step(x)
            np.testing.assert_array_equal(oa, ob)
            assert (ra, ta, tra) == (rb, tb, trb)
            assert list(ia) == list(ib)
            for k in ia:
                assert np.array_equal(ia[k], ib[k]), k
            if ta or tra:
                break
        ends.append(outcome(ia))
    return ends


@pytest.mark.parametrize("env_id", sorted(OLDER))
def test_it_is_the_older_version_made_with_the_ramp_and_the_peak(env_id):
    new, old = gym.make(env_id), gym.make(retired_spec(OLDER[env_id]), **RAMP_PEAK)
    try:
        ends = _episodes_beside(new, old, range(8240, 8243))
    finally:
        new.close()
        old.close()
    assert "crushed" in ends  # (seed 8242: the valve closed hard)


@pytest.mark.parametrize("env_id", ["simgrip/PickFragile-v7", "simgrip/PickSphereFragile-v6"])
def test_with_the_older_defaults_back_it_is_the_older_version(env_id):
    new = gym.make(env_id, palm_ramp=False, crush_at="end")
    old = gym.make(retired_spec(OLDER[env_id]))
    try:
        _episodes_beside(new, old, range(8250, 8252))
    finally:
        new.close()
        old.close()


def test_the_peak_rule_crushes_where_the_end_rule_let_the_episode_go_on():
    """The pinch closed at full valve rate onto a piece whose limit lies between the end-of-step force and the
    first touch's impact: v7 ends the episode crushed on that step, the end-of-step rule does not."""
    env_id = "simgrip/PickFragile-v7"
    probe = gym.make(env_id)
    probe.reset(seed=8260, options={"crush_limit": 1e9})
    a = np.array([-1.0, 0.0], np.float32)
    for t in range(100):
        *_, info = probe.step(a)
        end, peak = max(info["normal_force"]), max(info["peak_normal_force"])
        if end > 0.0 and peak > 1.2 * end:
            break
    else:
        pytest.fail("no step whose peak stood above its end value")
    probe.close()
    limit = 0.5 * (end + peak)
    for kwargs, crushed in (({}, True), ({"crush_at": "end"}, False)):
        env = gym.make(env_id, **kwargs)
        env.reset(seed=8260, options={"crush_limit": limit})
        for _ in range(t + 1):
            *_, term, _, info = env.step(a)
        assert (info["crushed"], term) == (crushed, crushed), kwargs
        env.close()

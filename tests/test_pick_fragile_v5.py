"""The pinch's and the K fingers' v5 (simgrip.envs.pick_fragile_v5, retired by v6): v4 without the per-step touch
pay.

Checked against v4 itself, stepped with the same seed and actions beside it: the same observations, events
and info; the reward differs by exactly v4's ``reward_touch``; v5's ``reward_touch`` is 0 on every step.
And the ordering the module states: no unsuccessful episode returns more than ``w_contact + w_lift``.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  registers the environments
from simgrip.envs import RETIRED, retired_spec
from simgrip.envs.pick_fragile_v4 import FragilePickEnvV4, FragilePickMultiEnvV4
from simgrip.envs.pick_fragile_v5 import FragilePickEnvV5, FragilePickMultiEnvV5

# v4 built from its class (gym.make of an id with a newer version warns)
V4_OF = {"simgrip/PickFragile-v5": FragilePickEnvV4, "simgrip/PickMultiFragile-v5": FragilePickMultiEnvV4}


def test_both_are_retired():
    assert set(V4_OF) <= set(RETIRED)
    assert retired_spec("simgrip/PickFragile-v5").entry_point.endswith(FragilePickEnvV5.__name__)


def _actions(n, seed):
    """A closing that touches, squeezes and lifts, with noise: touch steps, lift steps and some crushes."""
    rng = np.random.default_rng(seed)
    a = np.empty((n, 2), np.float32)
    a[:, 0] = np.clip(-0.25 + 0.3 * rng.standard_normal(n), -1, 1)
    a[:, 1] = np.clip(np.where(np.arange(n) > 25, 0.6, 0.0) + 0.3 * rng.standard_normal(n), -1, 1)
    return a


#: the info keys v5 leaves as v4 has them (the events and every reward term but the touch pay)
SAME_KEYS = ("is_success", "crushed", "dropped", "knocked_over", "workpiece_lift", "reward_lift", "reward_contact",
             "reward_crush", "reward_drop", "reward_success")


def episode_return(env, seed, act) -> tuple[float, bool]:
    """``(return, success)`` of one episode of ``env`` from ``reset(seed)``, ``act(t)`` the action of step ``t``."""
    env.reset(seed=seed)
    total, success = 0.0, False
    for t in range(300):
        _, r, term, trunc, info = env.step(act(t))
        total += r
        success |= info["is_success"]
        if term or trunc:
            break
    return total, success


@pytest.mark.parametrize("env_id", sorted(V4_OF))
def test_v5_is_v4_less_the_touch_pay(env_id):
    new, old = gym.make(retired_spec(env_id)).unwrapped, V4_OF[env_id]()
    touch_steps = 0
    try:
        for seed in (8100, 8101, 8102):
            o5, i5 = new.reset(seed=seed)
            o4, i4 = old.reset(seed=seed)
            np.testing.assert_array_equal(o5, o4)
            assert i5["start_gap"] == i4["start_gap"]
            for a in _actions(120, seed):
                o5, r5, t5, tr5, i5 = new.step(a)
                o4, r4, t4, tr4, i4 = old.step(a)
                np.testing.assert_array_equal(o5, o4)
                assert (t5, tr5) == (t4, tr4)
                assert i5["reward_touch"] == 0.0
                touch_steps += i4["reward_touch"] > 0.0
                assert r5 == pytest.approx(r4 - i4["reward_touch"], abs=1e-12)
                for k in SAME_KEYS:
                    assert i5[k] == i4[k], k
                if t5 or tr5:
                    break
    finally:
        new.close()
        old.close()
    assert touch_steps > 20  # the check saw v4 paying the touch


@pytest.mark.parametrize("env_id", sorted(V4_OF))
def test_an_unsuccessful_episode_returns_at_most_contact_plus_lift(env_id):
    env = gym.make(retired_spec(env_id))
    u = env.unwrapped
    bound = u.w_contact + u.w_lift
    try:
        for seed in (8110, 8111, 8112, 8113):
            total, success = episode_return(env, seed, _actions(300, seed).__getitem__)
            if not success:
                assert total <= bound + 1e-9
    finally:
        env.close()


def test_w_touch_is_still_an_argument():
    a = FragilePickMultiEnvV5(w_touch=0.02)
    b = FragilePickMultiEnvV4()
    try:
        a.reset(seed=8120)
        b.reset(seed=8120)
        for act in _actions(60, 8120):
            ra, rb = a.step(act)[1], b.step(act)[1]
            assert ra == rb
    finally:
        a.close()
        b.close()

"""PlaceFragile-v5 (simgrip.envs.pick_place_v5): PlaceFragile-v4 without the drop penalty.

Checked against v4 itself, stepped with the same seed and actions beside it: the same observations, events and
info; the reward differs by exactly v4's ``reward_drop``; v5's is 0 on every step.  The actions are the
observation-only place controller's, its valve opened once the workpiece is lifted a few millimetres on some
seeds (drops) and closed hard on others (crushes).  And the ordering the module states.
"""

from __future__ import annotations

from collections import Counter

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  registers the environments
from simgrip.envs import FRAGILE_ENV_IDS, retired_spec
from simgrip.envs.baselines import policy_maker
from simgrip.envs.outcome import outcome
from simgrip.envs.pick_place_v4 import FragilePlaceEnvV4
from simgrip.envs.pick_place_v5 import FragilePlaceEnvV5

ID, V4 = "simgrip/PlaceFragile-v5", "simgrip/PlaceFragile-v4"
SAME_KEYS = ("is_success", "crushed", "dropped", "knocked_over", "workpiece_lift", "place_error", "carried",
             "target_x", "reward_lift", "reward_contact", "reward_crush", "reward_touch", "reward_success",
             "reward_place", "crush_limit", "start_gap")


def test_v5_is_registered_and_v4_is_retired():
    assert ID in FRAGILE_ENV_IDS and V4 not in FRAGILE_ENV_IDS
    assert gym.spec(ID).entry_point.endswith(FragilePlaceEnvV5.__name__) and gym.spec(ID).max_episode_steps == 400
    assert retired_spec(V4).entry_point.endswith(FragilePlaceEnvV4.__name__)


def _spoiled(env, seed):
    """The observation-only place controller, spoiled by ``seed % 3``: 0 as it is, 1 its valve opened at full
    rate once the workpiece is 4 mm up (a drop), 2 its valve closed at full rate from step 5 (a crush)."""
    make = policy_maker(env, "observation")
    mode, state = seed % 3, {}

    def start(info):
        state["act"] = make(env, info, seed)

    def act(obs, t, info):
        a = np.array(state["act"](obs, t), dtype=np.float32)
        if mode == 1 and info.get("workpiece_lift", 0.0) > 0.004:
            a[0] = 1.0
        elif mode == 2 and t >= 5:
            a[0] = -1.0
        return a
    return start, act


def test_v5_is_v4_less_the_drop_penalty():
    new, old = gym.make(ID), gym.make(retired_spec(V4))
    ends, drop_charged = Counter(), 0
    try:
        for seed in range(8200, 8206):
            o5, i5 = new.reset(seed=seed)
            o4, i4 = old.reset(seed=seed)
            np.testing.assert_array_equal(o5, o4)
            start, act = _spoiled(new, seed)
            start(i5)
            for t in range(400):
                a = act(o5, t, i5)
                o5, r5, t5, tr5, i5 = new.step(a)
                o4, r4, t4, tr4, i4 = old.step(a)
                np.testing.assert_array_equal(o5, o4)
                assert (t5, tr5) == (t4, tr4)
                assert i5["reward_drop"] == 0.0
                drop_charged += i4["reward_drop"] < 0.0
                assert r5 == pytest.approx(r4 - i4["reward_drop"], abs=1e-12)
                for k in SAME_KEYS:
                    if k in i4:
                        assert np.array_equal(i5[k], i4[k]), k
                if t5 or tr5:
                    break
            ends[outcome(i5)] += 1
    finally:
        new.close()
        old.close()
    assert ends["success"] >= 1 and ends["crushed"] >= 1 and ends["dropped"] >= 1, ends
    assert drop_charged == ends["dropped"] + ends["knocked_over"]


def test_v5_is_v4_made_with_w_drop_0():
    # the runs of docs/baselines/rl_place_v4_scripted* trained on v4 with --env-kwargs '{"w_drop": 0.0}': the
    # same env as v5, reward for reward
    new, old = gym.make(ID), gym.make(retired_spec(V4), w_drop=0.0)
    rng = np.random.default_rng(3)
    try:
        for seed in (8210, 8211):
            new.reset(seed=seed)
            old.reset(seed=seed)
            for _ in range(150):
                a = rng.uniform(-1, 1, new.action_space.shape).astype(np.float32)
                o5, r5, t5, tr5, _ = new.step(a)
                o4, r4, t4, tr4, _ = old.step(a)
                np.testing.assert_array_equal(o5, o4)
                assert (r5, t5, tr5) == (r4, t4, tr4)
                if t5 or tr5:
                    break
    finally:
        new.close()
        old.close()


def test_a_failure_returns_at_most_the_contact_and_carry_pay():
    env = gym.make(ID)
    u = env.unwrapped
    ends = Counter()
    try:
        for seed in range(8220, 8226):
            obs, info = env.reset(seed=seed)
            start, act = _spoiled(env, seed)
            start(info)
            total = 0.0
            for t in range(400):
                obs, r, term, trunc, info = env.step(act(obs, t, info))
                total += r
                if term or trunc:
                    break
            end = outcome(info)
            ends[end] += 1
            if end == "success":
                assert total >= u.w_place + u.w_success - 1e-9
            else:
                assert total <= u.w_contact + u.w_lift + u.w_place + 1e-9, (seed, end, total)
    finally:
        env.close()
    assert ends["crushed"] >= 1 and ends["dropped"] >= 1, ends


def test_w_drop_is_still_an_argument():
    assert (FragilePlaceEnvV5().w_drop, FragilePlaceEnvV5(w_drop=5.0).w_drop) == (0.0, 5.0)
    with pytest.raises(ValueError, match="w_drop"):
        FragilePlaceEnvV5(w_drop=-1.0)

"""The pinch's and the K fingers' v6 (simgrip.envs.pick_fragile_v6): v5 without the drop penalty.

Checked against v5 itself, stepped with the same seed and actions beside it: the same observations, events and
info; the reward differs by exactly v5's ``reward_drop``; v6's is 0 on every step.  The actions are the
observation-only controller's, its valve opened once the workpiece is lifted a few millimetres on some seeds
(drops) and closed hard on others (crushes).  And the ordering the module states: an episode that ends in a
failure returns at most ``w_contact``, one that does not succeed at most ``w_contact + w_lift``.
"""

from __future__ import annotations

from collections import Counter

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  registers the environments
from simgrip.envs import FRAGILE_ENV_IDS, retired_spec
from simgrip.envs.baselines import policy_maker
from simgrip.envs.evaluation import outcome
from simgrip.envs.pick_fragile_v5 import FragilePickEnvV5, FragilePickMultiEnvV5
from simgrip.envs.pick_fragile_v6 import FragilePickEnvV6, FragilePickMultiEnvV6

V5_OF = {"simgrip/PickFragile-v6": FragilePickEnvV5, "simgrip/PickMultiFragile-v6": FragilePickMultiEnvV5}

#: the info keys v6 leaves as v5 has them (the events and every reward term but the drop penalty)
SAME_KEYS = ("is_success", "crushed", "dropped", "knocked_over", "workpiece_lift", "reward_lift", "reward_contact",
             "reward_crush", "reward_touch", "reward_success", "crush_limit", "start_gap")


def test_both_are_registered_and_v5_is_retired():
    assert set(V5_OF) <= set(FRAGILE_ENV_IDS)
    assert gym.spec("simgrip/PickFragile-v6").entry_point.endswith(FragilePickEnvV6.__name__)
    assert gym.spec("simgrip/PickMultiFragile-v6").entry_point.endswith(FragilePickMultiEnvV6.__name__)
    assert retired_spec("simgrip/PickFragile-v5").entry_point.endswith(FragilePickEnvV5.__name__)


def _spoiled(env, seed):
    """The observation-only controller of ``env``, spoiled by ``seed % 3``: 0 as it is, 1 its valve opened at
    full rate once the workpiece is 4 mm up (a drop), 2 its valve closed at full rate from step 5 (a crush)."""
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


@pytest.mark.parametrize("env_id", sorted(V5_OF))
def test_v6_is_v5_less_the_drop_penalty(env_id):
    new, old = gym.make(env_id), gym.make(retired_spec(env_id.replace("-v6", "-v5")))
    ends, drop_charged = Counter(), 0
    try:
        for seed in range(8200, 8206):
            o6, i6 = new.reset(seed=seed)
            o5, i5 = old.reset(seed=seed)
            np.testing.assert_array_equal(o6, o5)
            start, act = _spoiled(new, seed)
            start(i6)
            for t in range(300):
                a = act(o6, t, i6)
                o6, r6, t6, tr6, i6 = new.step(a)
                o5, r5, t5, tr5, i5 = old.step(a)
                np.testing.assert_array_equal(o6, o5)
                assert (t6, tr6) == (t5, tr5)
                assert i6["reward_drop"] == 0.0
                drop_charged += i5["reward_drop"] < 0.0
                assert r6 == pytest.approx(r5 - i5["reward_drop"], abs=1e-12)
                for k in SAME_KEYS:
                    if k in i5:
                        assert np.array_equal(i6[k], i5[k]), k
                if t6 or tr6:
                    break
            ends[outcome(i6)] += 1
    finally:
        new.close()
        old.close()
    # the check saw each ending, and v5 charging its drops
    assert ends["success"] >= 1 and ends["crushed"] >= 1 and ends["dropped"] >= 1, ends
    assert drop_charged == ends["dropped"]


@pytest.mark.parametrize("env_id", sorted(V5_OF))
def test_v6_is_v5_made_with_w_drop_0(env_id):
    # the runs of docs/baselines/rl_*_v5_wdrop0 and rl_*_v5_wd0_probe* trained on v5 with --env-kwargs
    # '{"w_drop": 0.0}': the same env as v6, reward for reward
    new, old = gym.make(env_id), gym.make(retired_spec(env_id.replace("-v6", "-v5")), w_drop=0.0)
    rng = np.random.default_rng(3)
    try:
        for seed in (8210, 8211):
            new.reset(seed=seed)
            old.reset(seed=seed)
            for _ in range(120):
                a = rng.uniform(-1, 1, new.action_space.shape).astype(np.float32)
                o6, r6, t6, tr6, _ = new.step(a)
                o5, r5, t5, tr5, _ = old.step(a)
                np.testing.assert_array_equal(o6, o5)
                assert (r6, t6, tr6) == (r5, t5, tr5)
                if t6 or tr6:
                    break
    finally:
        new.close()
        old.close()


@pytest.mark.parametrize("env_id", sorted(V5_OF))
def test_a_failure_returns_at_most_the_contact_pay(env_id):
    env = gym.make(env_id)
    u = env.unwrapped
    ends = Counter()
    try:
        for seed in range(8220, 8226):
            obs, info = env.reset(seed=seed)
            start, act = _spoiled(env, seed)
            start(info)
            total = 0.0
            for t in range(300):
                obs, r, term, trunc, info = env.step(act(obs, t, info))
                total += r
                if term or trunc:
                    break
            end = outcome(info)
            ends[end] += 1
            if end in ("crushed", "dropped", "knocked_over"):
                assert total <= u.w_contact + 1e-9, (seed, end, total)
            elif end != "success":
                assert total <= u.w_contact + u.w_lift + 1e-9
            else:
                assert total >= u.w_lift + u.w_success - 1e-9
    finally:
        env.close()
    assert ends["crushed"] >= 1 and ends["dropped"] >= 1, ends


def test_w_drop_is_still_an_argument():
    a, b = FragilePickEnvV6(w_drop=5.0), FragilePickEnvV5()
    try:
        assert (a.w_drop, FragilePickEnvV6().w_drop, FragilePickMultiEnvV6().w_drop) == (5.0, 0.0, 0.0)
        a.reset(seed=8230)
        b.reset(seed=8230)
        rng = np.random.default_rng(0)
        for _ in range(60):
            act = rng.uniform(-1, 1, 2).astype(np.float32)
            assert a.step(act)[1] == b.step(act)[1]
    finally:
        a.close()
        b.close()
    with pytest.raises(ValueError, match="w_drop"):
        FragilePickMultiEnvV6(w_drop=-1.0)

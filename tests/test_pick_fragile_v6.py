"""The pinch's and the K fingers' v6 (simgrip.envs.pick_fragile_v6): v5 without the drop penalty.

Checked against v5 itself, stepped with the same seed and actions beside it: the same observations, events and
info; the reward differs by exactly v5's ``reward_drop``; v6's is 0 on every step.  The actions are the
observation-only controller's, its valve opened once the workpiece is lifted a few millimetres on some seeds
(drops) and closed hard on others (crushes).  And the ordering the module states: an episode that ends in a
failure returns at most ``w_contact``, one that does not succeed at most ``w_contact + w_lift``.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  registers the environments
from simgrip.envs import FRAGILE_ENV_IDS, retired_spec
from simgrip.envs.pick_fragile_v5 import FragilePickEnvV5, FragilePickMultiEnvV5
from simgrip.envs.pick_fragile_v6 import FragilePickEnvV6, FragilePickMultiEnvV6
from env_checks import assert_step_for_step_equal, assert_the_same_less_the_drop_penalty, spoiled_returns

V5_OF = {"simgrip/PickFragile-v6": FragilePickEnvV5, "simgrip/PickMultiFragile-v6": FragilePickMultiEnvV5}

#: the info keys v6 leaves as v5 has them (the events and every reward term but the drop penalty)
SAME_KEYS = ("is_success", "crushed", "dropped", "knocked_over", "workpiece_lift", "reward_lift", "reward_contact",
             "reward_crush", "reward_touch", "reward_success", "crush_limit", "start_gap")


def test_both_are_retired_with_v5():
    # (retired by v7, simgrip.envs.pick_fragile_v7; retired_spec builds them exactly)
    assert not set(V5_OF) & set(FRAGILE_ENV_IDS)
    assert retired_spec("simgrip/PickFragile-v6").entry_point.endswith(FragilePickEnvV6.__name__)
    assert retired_spec("simgrip/PickMultiFragile-v6").entry_point.endswith(FragilePickMultiEnvV6.__name__)
    assert retired_spec("simgrip/PickFragile-v5").entry_point.endswith(FragilePickEnvV5.__name__)


@pytest.mark.parametrize("env_id", sorted(V5_OF))
def test_v6_is_v5_less_the_drop_penalty(env_id):
    new, old = gym.make(retired_spec(env_id)), gym.make(retired_spec(env_id.replace("-v6", "-v5")))
    try:
        ends, drop_charged = assert_the_same_less_the_drop_penalty(new, old, range(8200, 8206), 300, SAME_KEYS)
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
    new, old = gym.make(retired_spec(env_id)), gym.make(retired_spec(env_id.replace("-v6", "-v5")), w_drop=0.0)
    try:
        assert_step_for_step_equal(new, old, (8210, 8211), 120)
    finally:
        new.close()
        old.close()


@pytest.mark.parametrize("env_id", sorted(V5_OF))
def test_a_failure_returns_at_most_the_contact_pay(env_id):
    rows, ends, u = spoiled_returns(env_id, range(8220, 8226), 300)
    for seed, end, total in rows:
        if end in ("crushed", "dropped", "knocked_over"):
            assert total <= u.w_contact + 1e-9, (seed, end, total)
        elif end != "success":
            assert total <= u.w_contact + u.w_lift + 1e-9
        else:
            assert total >= u.w_lift + u.w_success - 1e-9
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

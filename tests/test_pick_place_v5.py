"""PlaceFragile-v5 (simgrip.envs.pick_place_v5): PlaceFragile-v4 without the drop penalty.

Checked against v4 itself, stepped with the same seed and actions beside it: the same observations, events and
info; the reward differs by exactly v4's ``reward_drop``; v5's is 0 on every step.  The actions are the
observation-only place controller's, its valve opened once the workpiece is lifted a few millimetres on some
seeds (drops) and closed hard on others (crushes).  And the ordering the module states.
"""

from __future__ import annotations

import gymnasium as gym
import pytest

import simgrip.envs  # noqa: F401  registers the environments
from simgrip.envs import FRAGILE_ENV_IDS, retired_spec
from simgrip.envs.pick_place_v4 import FragilePlaceEnvV4
from simgrip.envs.pick_place_v5 import FragilePlaceEnvV5
from env_checks import assert_step_for_step_equal, assert_the_same_less_the_drop_penalty, spoiled_returns

ID, V4 = "simgrip/PlaceFragile-v5", "simgrip/PlaceFragile-v4"
SAME_KEYS = ("is_success", "crushed", "dropped", "knocked_over", "workpiece_lift", "place_error", "carried",
             "target_x", "reward_lift", "reward_contact", "reward_crush", "reward_touch", "reward_success",
             "reward_place", "crush_limit", "start_gap")


def test_v5_and_v4_are_retired():
    # v5 retired by v6 (simgrip.envs.pick_place_v6: the grip's pay), which subclasses it
    assert ID not in FRAGILE_ENV_IDS and V4 not in FRAGILE_ENV_IDS
    assert retired_spec(ID).entry_point.endswith(FragilePlaceEnvV5.__name__)
    assert retired_spec(ID).max_episode_steps == 400
    assert retired_spec(V4).entry_point.endswith(FragilePlaceEnvV4.__name__)


def test_v5_is_v4_less_the_drop_penalty():
    new, old = gym.make(retired_spec(ID)), gym.make(retired_spec(V4))
    try:
        ends, drop_charged = assert_the_same_less_the_drop_penalty(new, old, range(8200, 8206), 400, SAME_KEYS)
    finally:
        new.close()
        old.close()
    # the check saw each ending, and v4 charging its drops and knock-overs
    assert ends["success"] >= 1 and ends["crushed"] >= 1 and ends["dropped"] >= 1, ends
    assert drop_charged == ends["dropped"] + ends["knocked_over"]


def test_v5_is_v4_made_with_w_drop_0():
    # the runs of docs/baselines/rl_place_v4_scripted* trained on v4 with --env-kwargs '{"w_drop": 0.0}': the
    # same env as v5, reward for reward
    new, old = gym.make(retired_spec(ID)), gym.make(retired_spec(V4), w_drop=0.0)
    try:
        assert_step_for_step_equal(new, old, (8210, 8211), 150)
    finally:
        new.close()
        old.close()


def test_a_failure_returns_at_most_the_contact_and_carry_pay():
    rows, ends, u = spoiled_returns(ID, range(8220, 8226), 400)
    for seed, end, total in rows:
        if end == "success":
            assert total >= u.w_place + u.w_success - 1e-9
        else:
            assert total <= u.w_contact + u.w_lift + u.w_place + 1e-9, (seed, end, total)
    assert ends["crushed"] >= 1 and ends["dropped"] >= 1, ends


def test_w_drop_is_still_an_argument():
    assert (FragilePlaceEnvV5().w_drop, FragilePlaceEnvV5(w_drop=5.0).w_drop) == (0.0, 5.0)
    with pytest.raises(ValueError, match="w_drop"):
        FragilePlaceEnvV5(w_drop=-1.0)

"""PlaceFragile-v6 (simgrip.envs.pick_place_v6): PlaceFragile-v5 paying a grip that holds.

Checked against v5 itself, stepped with the same seed and actions beside it: the same observations, events and
info; the reward differs by exactly ``reward_hold``, which is ``+w_hold`` on the one step v5's own ``hold_time``
first reaches ``grip_time``, and kept through a later crush or drop.  The actions are the
observation-only place controller's with the palm held still sideways (so that the grip holds the workpiece at
the carry height), spoiled once the grip has held: its valve opened at full rate (a drop) or closed at full rate
(a crush).  And the ordering the module states.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  registers the environments
from simgrip.envs import FRAGILE_ENV_IDS, retired_spec
from simgrip.envs.baselines import policy_maker
from simgrip.envs.outcome import outcome
from simgrip.envs.pick_place_v5 import FragilePlaceEnvV5
from simgrip.envs.pick_place_v6 import V6_GRIP_TIME, V6_W_HOLD, FragilePlaceEnvV6
from env_checks import make, spoiled_returns, step_beside

ID, V5 = "simgrip/PlaceFragile-v6", "simgrip/PlaceFragile-v5"
SAME_KEYS = ("is_success", "crushed", "dropped", "knocked_over", "workpiece_lift", "place_error", "carried",
             "target_x", "hold_time", "reward_lift", "reward_contact", "reward_crush", "reward_touch",
             "reward_drop", "reward_success", "reward_place", "crush_limit", "normal_force")


def test_v6_and_v5_are_retired():
    # v6 retired by v7 (simgrip.envs.pick_place_v7: the set-down's pay), which subclasses it
    assert ID not in FRAGILE_ENV_IDS and V5 not in FRAGILE_ENV_IDS
    assert retired_spec(ID).entry_point.endswith(FragilePlaceEnvV6.__name__)
    assert retired_spec(ID).max_episode_steps == 400
    assert retired_spec(V5).entry_point.endswith(FragilePlaceEnvV5.__name__)


def _held_then_spoiled(env, seed: int):
    """The observation-only controller with the palm held still sideways and raised at half speed from 2 cm of
    lift until ``info["gripped"]`` (v6's; the controller itself stops at the carry height, where the workpiece
    creeps down in the grip); once gripped the valve is opened (``spoil = "drop"``) or closed (``"crush"``) at
    full rate, or the controller goes on (``None``)."""
    make_act = policy_maker(env, "observation")
    state = {}

    def start(info):
        state["act"] = make_act(env, info, seed)

    def act(obs, t, info, spoil):
        a = np.array(state["act"](obs, t), dtype=np.float32)
        a[1] = 0.0
        if info.get("workpiece_lift", 0.0) > 0.02 and not info.get("gripped"):
            a[2] = 0.5
        if spoil and info.get("gripped"):
            a[0] = 1.0 if spoil == "drop" else -1.0
        return a
    return start, act


@pytest.mark.parametrize("seed, spoil", [(8300, "drop"), (8301, "crush"), (8302, None), (8303, "crush")])
def test_v6_is_v5_plus_the_hold_pay(seed, spoil):
    new, old = make(ID), gym.make(retired_spec(V5))
    w = new.unwrapped.w_hold
    try:
        o_new, i_new = new.reset(seed=seed)
        o_old, i_old = old.reset(seed=seed)
        np.testing.assert_array_equal(o_new, o_old)
        start, act = _held_then_spoiled(new, seed)
        start(i_new)
        paid, paid_at, total_hold, held_before, total = 0, None, 0.0, 0.0, 0.0
        for t in range(400):
            o_new, r_new, r_old, done, i_new, i_old = step_beside(new, old, act(o_new, t, i_new, spoil), SAME_KEYS)
            r_hold = i_new["reward_hold"]
            assert r_new == pytest.approx(r_old + r_hold, abs=1e-12)
            # paid on the step v5's own hold clock first reaches grip_time, and only then
            first = held_before < V6_GRIP_TIME - 1e-9 <= i_old["hold_time"] and not paid
            lost = i_old["crushed"] or i_old["dropped"] or i_old["knocked_over"]
            if first and not lost:
                assert r_hold == w
                paid, paid_at = 1, t
            else:
                assert r_hold == 0.0, t
            assert i_new["gripped"] == bool(paid)
            total_hold += r_hold
            total += r_new
            held_before = i_old["hold_time"]
            if done:
                break
    finally:
        new.close()
        old.close()
    assert paid_at is not None, "the grip never held: the check saw no hold pay"
    end = outcome(i_new)
    if spoil:  # the spoiled grip is lost; the hold pay is kept
        assert end == ("dropped" if spoil == "drop" else "crushed"), end
    assert total_hold == w, end
    if end in ("dropped", "crushed"):  # the lift taken back, the contact and hold pay kept
        assert total <= new.unwrapped.w_contact + w + 1e-9, total


@pytest.mark.parametrize("seed", [8004, 8008])
def test_the_controller_that_holds_before_the_carry_is_paid_once(seed):
    # the observation-only controller as it is: on these seeds its grip holds the carry height 0.5 s before the
    # carry, is paid w_hold once and keeps it through the set-down
    env = make(ID)
    u = env.unwrapped
    try:
        obs, info = env.reset(seed=seed)
        act = policy_maker(env, "observation")(env, info, seed)
        pays, total = [], 0.0
        for t in range(400):
            obs, r, te, tr, info = env.step(act(obs, t))
            pays.append(info["reward_hold"])
            total += r
            if te or tr:
                break
    finally:
        env.close()
    assert info["is_success"] and info["gripped"]
    assert pays.count(V6_W_HOLD) == 1 and sum(pays) == V6_W_HOLD
    assert total >= u.w_place + u.w_success + u.w_hold - 1e-9


def test_a_failure_returns_at_most_the_contact_lift_hold_and_carry_pay():
    # spoiled_returns' drops come before the hold pay; the held-then-spoiled ones above return their hold pay
    rows, ends, u = spoiled_returns(ID, range(8220, 8226), 400)
    for seed, end, total in rows:
        if end == "success":
            assert total >= u.w_place + u.w_success - 1e-9
        elif end in ("crushed", "dropped", "knocked_over"):
            assert total <= u.w_contact + u.w_hold + 1e-9, (seed, end, total)
        else:
            assert total <= u.w_contact + u.w_lift + u.w_hold + u.w_place + 1e-9, (seed, end, total)
    assert ends["crushed"] >= 1 and ends["dropped"] >= 1 and ends["success"] >= 1, ends


def test_the_arguments():
    env = FragilePlaceEnvV6()
    assert (env.w_hold, env.grip_time, env.w_drop) == (V6_W_HOLD, V6_GRIP_TIME, 0.0)
    assert FragilePlaceEnvV6(w_hold=0.0).w_hold == 0.0
    for name, bad in (("w_hold", -1.0), ("w_hold", float("nan")), ("grip_time", 0.0), ("grip_time", "x")):
        with pytest.raises(ValueError, match=name):
            FragilePlaceEnvV6(**{name: bad})


def test_a_grip_in_an_impossible_state_is_not_paid_until_a_valid_step():
    # the validity probe made to report a finger through itself from 0.4 s of hold until 4 steps after the hold
    # clock has passed grip_time: v6 checks the state afresh on the steps the grip would be paid (between the
    # every-25-steps checks too), pays nothing there, and pays w_hold on the first valid step
    env = make(ID)
    u = env.unwrapped
    probe, check = u._validity, u._validity._check
    state = {"bad": False}
    probe._check = lambda q, data: ["finger 0 through itself (test)"] if state["bad"] else check(q, data)
    try:
        obs, info = env.reset(seed=8302)
        start, act = _held_then_spoiled(env, 8302)
        start(info)
        late, paid_at, calls = 0, None, []
        for t in range(400):
            obs, r, te, tr, info = env.step(act(obs, t, info, None))
            calls.append(probe._calls)
            hold = info["hold_time"]
            if hold >= V6_GRIP_TIME - 1e-9 and state["bad"]:
                assert info["reward_hold"] == 0.0 and not info["gripped"], t
                assert info["valid"] is False and info["invalid"] == ["finger 0 through itself (test)"], t
                late += 1
                if late == 4:
                    state["bad"] = False
            elif info["reward_hold"]:
                paid_at = t
                break
            state["bad"] = state["bad"] or (hold >= 0.4 and late == 0)
            if te or tr:
                break
    finally:
        env.close()
    assert late == 4 and paid_at is not None and info["valid"] and info["gripped"]
    assert info["hold_time"] > V6_GRIP_TIME
    assert calls == list(range(1, len(calls) + 1))  # the fresh checks did not move the every-25 schedule

"""PlaceFragile-v7 (simgrip.envs.pick_place_v7): PlaceFragile-v6 paying the set-down.

Checked against v6 itself, stepped with the same seed and actions beside it: the same observations, events and
info; the reward differs by exactly ``reward_set_down``, which is recomputed here from v6's own info on every
step as the difference of ``Psi = (1 - clip(lift / carry_height, 0, 1)) (w_lift + w_down [place_error <=
place_tolerance])`` once carried and not lost (0 otherwise).  The actions are the observation-only place
controller's, as it is (it carries and sets down) and spoiled once carried (its valve opened or closed at full
rate: a drop or a crush).  And the ordering the module states, on those episodes and on the shared spoiled ones.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  registers the environments
from simgrip.envs import FRAGILE_ENV_IDS, retired_spec
from simgrip.envs.baselines import policy_maker
from simgrip.envs.outcome import outcome
from simgrip.envs.pick_place_v6 import FragilePlaceEnvV6
from simgrip.envs.pick_place_v7 import V7_W_DOWN, FragilePlaceEnvV7, set_down_potential
from env_checks import spoiled_returns, step_beside

ID, V6 = "simgrip/PlaceFragile-v7", "simgrip/PlaceFragile-v6"
SAME_KEYS = ("is_success", "crushed", "dropped", "knocked_over", "workpiece_lift", "place_error", "carried",
             "gripped", "target_x", "hold_time", "reward_hold", "reward_lift", "reward_contact", "reward_crush",
             "reward_touch", "reward_drop", "reward_success", "reward_place", "crush_limit", "normal_force",
             "valid")


def test_v7_and_v6_are_retired():
    # (v7 retired by v8, simgrip.envs.pick_fragile_v7; retired_spec builds it exactly)
    assert ID not in FRAGILE_ENV_IDS and V6 not in FRAGILE_ENV_IDS
    spec = retired_spec(ID)
    assert spec.entry_point.endswith(FragilePlaceEnvV7.__name__) and spec.max_episode_steps == 400
    assert retired_spec(V6).entry_point.endswith(FragilePlaceEnvV6.__name__)


def test_the_potential():
    # phi = clip(lift / h): the lift pay's progress; once carried the two pay w_lift at any height
    h, wl, wd = 0.03, 10.0, 10.0
    assert set_down_potential(0.03, h, True, wl, wd) == 0.0
    assert set_down_potential(0.05, h, False, wl, wd) == 0.0  # above the carry height: nothing yet
    assert set_down_potential(0.0, h, False, wl, wd) == pytest.approx(wl)
    assert set_down_potential(0.0, h, True, wl, wd) == pytest.approx(wl + wd)
    assert set_down_potential(-0.001, h, True, wl, wd) == pytest.approx(wl + wd)  # clipped below
    assert set_down_potential(0.015, h, True, wl, wd) == pytest.approx(0.5 * (wl + wd))
    for lift in np.linspace(-0.01, 0.05, 13):  # with the lift pay w_lift phi: w_lift, plus the set-down
        phi = min(max(lift / h, 0.0), 1.0)
        assert wl * phi + set_down_potential(lift, h, False, wl, wd) == pytest.approx(wl)


def _controller(env, seed: int, spoil):
    """The observation-only place controller, its valve opened (``spoil = "drop"``) or closed (``"crush"``) at
    full rate once ``info["carried"]``, or as it is (``None``)."""
    make_act = policy_maker(env, "observation")
    state = {}

    def start(info):
        state["act"] = make_act(env, info, seed)

    def act(obs, t, info):
        a = np.array(state["act"](obs, t), dtype=np.float32)
        if spoil and info.get("carried"):
            a[0] = 1.0 if spoil == "drop" else -1.0
        return a
    return start, act


@pytest.mark.parametrize("seed, spoil", [(8004, None), (8008, None), (8300, "drop"), (8301, "crush")])
def test_v7_is_v6_plus_the_set_down_pay(seed, spoil):
    new, old = gym.make(retired_spec(ID)), gym.make(retired_spec(V6))
    u = new.unwrapped
    try:
        o_new, i_new = new.reset(seed=seed)
        o_old, i_old = old.reset(seed=seed)
        np.testing.assert_array_equal(o_new, o_old)
        start, act = _controller(new, seed, spoil)
        start(i_new)
        psi_prev, total, down_steps, total_down = 0.0, 0.0, 0, 0.0
        for t in range(400):
            o_new, r_new, r_old, done, i_new, i_old = step_beside(new, old, act(o_new, t, i_new), SAME_KEYS)
            lost = i_old["crushed"] or i_old["dropped"] or i_old["knocked_over"]
            psi = 0.0
            if i_old["carried"] and not lost:
                phi = min(max(i_old["workpiece_lift"] / u.carry_height, 0.0), 1.0)
                over = i_old["place_error"] <= u.place_tolerance
                psi = (1.0 - phi) * (u.w_lift + (u.w_down if over else 0.0))
            assert i_new["reward_set_down"] == pytest.approx(psi - psi_prev, abs=1e-12), t
            assert r_new == pytest.approx(r_old + psi - psi_prev, abs=1e-12), t
            down_steps += i_new["reward_set_down"] > 0
            total_down += i_new["reward_set_down"]
            psi_prev = psi
            total += r_new
            if done:
                break
    finally:
        new.close()
        old.close()
    end = outcome(i_new)
    if spoil is None:  # the controller places: paid its way down, and at least the stated floor
        assert end == "success", end
        assert down_steps > 0 and total_down >= 0.9 * (u.w_lift + u.w_down) - 1e-9
        assert total >= u.w_success + u.w_lift + 0.9 * u.w_down - 1e-9, total
    else:  # the spoiled carry is lost: the set-down pay taken back whole, with the lift
        assert end == ("dropped" if spoil == "drop" else "crushed"), end
        assert total_down == pytest.approx(0.0, abs=1e-9)
        assert total <= u.w_contact + u.w_hold + 1e-9, total


def test_the_ordering_on_the_shared_spoiled_episodes():
    rows, ends, u = spoiled_returns(ID, range(8220, 8226), 400)
    for seed, end, total in rows:
        if end == "success":
            assert total >= u.w_success + u.w_lift + 0.9 * u.w_down - 1e-9
        elif end in ("crushed", "dropped", "knocked_over"):
            assert total <= u.w_contact + u.w_hold + 1e-9, (seed, end, total)
        else:
            assert total <= u.w_contact + u.w_lift + u.w_hold + u.w_place + u.w_down + 1e-9, (seed, end, total)
    assert ends["crushed"] >= 1 and ends["dropped"] >= 1 and ends["success"] >= 1, ends


def test_the_arguments():
    env = FragilePlaceEnvV7()
    assert (env.w_down, env.w_hold, env.w_drop) == (V7_W_DOWN, 10.0, 0.0)
    assert FragilePlaceEnvV7(w_down=0.0).w_down == 0.0
    for bad in (-1.0, float("nan"), "x", None):
        with pytest.raises(ValueError, match="w_down"):
            FragilePlaceEnvV7(w_down=bad)


@pytest.mark.parametrize("seed", [8004, 8300])
def test_sideways_after_carry_is_v7_given_no_sideways_command_before_the_carry(seed):
    # random sideways commands on top of the observation-only controller: with the option, the palm ignores
    # them until info["carried"] (step for step v7 given action[1] = 0 there), and follows them after
    gated, plain = gym.make(retired_spec(ID), sideways_after_carry=True), gym.make(retired_spec(ID))
    rng = np.random.default_rng(seed)
    try:
        o_g, i_g = gated.reset(seed=seed)
        plain.reset(seed=seed)
        start, act = _controller(gated, seed, None)
        start(i_g)
        carried_at, moved_after = None, False
        for t in range(400):
            a = act(o_g, t, i_g)
            a[1] = rng.uniform(-1.0, 1.0)
            b = a.copy()
            if not i_g.get("carried"):
                b[1] = 0.0
            o_g, r_g, te_g, tr_g, i_g = gated.step(a)
            o_p, r_p, te_p, tr_p, i_p = plain.step(b)
            np.testing.assert_array_equal(o_g, o_p)
            assert (r_g, te_g, tr_g) == (r_p, te_p, tr_p)
            if i_g["carried"] and carried_at is None:
                carried_at = t
            moved_after = moved_after or (carried_at is not None and t > carried_at and b[1] != 0.0)
            if te_g or tr_g:
                break
    finally:
        gated.close()
        plain.close()
    assert carried_at is not None and moved_after


def test_sideways_after_carry_must_be_a_bool():
    assert FragilePlaceEnvV7().sideways_after_carry is False
    for bad in (1, "yes", None):
        with pytest.raises(ValueError, match="sideways_after_carry"):
            FragilePlaceEnvV7(sideways_after_carry=bad)

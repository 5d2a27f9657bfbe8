"""PlaceFragile-v4 (simgrip.envs.pick_place_v4): PlaceFragile-v3 started from a pre-grasp, without the touch pay.

Checked against independent computations: the start shape's clearance is measured afresh with MuJoCo's distance
query on a copy of the data (the bisection's bracket brackets the drawn gap), no finger touches the workpiece after
the reset's settle, the per-seed draw (width, friction, palm height, crush ratio) is the retired v3's, and the
reward differs from the same env paying ``w_touch`` by exactly that pay.
"""

from __future__ import annotations

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  registers the environments
from simgrip.envs import FRAGILE_ENV_IDS, RETIRED, retired_spec
from simgrip.envs.pick_fragile_v4 import _BISECTIONS, _SCAN, GAP_RANGE, V4_MASS, pre_grasp_curvature
from simgrip.envs.pick_place_v4 import FragilePlaceEnvV4

ID, V3 = "simgrip/PlaceFragile-v4", "simgrip/PlaceFragile-v3"


def _clearance(model, data, pairs, hinges, unit, k):
    """Least finger-workpiece distance [m] of the rest shape at ``k`` on a copy of the data (one mj_forward)."""
    d = mujoco.MjData(model)
    d.qpos[:] = data.qpos
    d.qpos[hinges] = unit * k
    mujoco.mj_forward(model, d)
    return min(mujoco.mj_geomDistance(model, d, int(model.pair_geom1[p]), int(model.pair_geom2[p]), 1.0, None)
               for p in pairs)


def test_v4_is_registered_and_v3_retired():
    assert ID in FRAGILE_ENV_IDS and V3 in RETIRED and V3 not in FRAGILE_ENV_IDS
    assert gym.spec(ID).entry_point.endswith(FragilePlaceEnvV4.__name__) and gym.spec(ID).max_episode_steps == 400


def test_the_start_shape_clears_the_workpiece_by_the_drawn_gap():
    env = FragilePlaceEnvV4()
    try:
        for seed in range(5):
            env.reset(seed=seed)
            gap = env.start_gap
            assert GAP_RANGE[0] <= gap <= GAP_RANGE[1]
            pairs, hinges, unit = env._pre_grasp_handles()
            # the hinge addresses are the place model's (its palm x slide shifts them from the pick's)
            assert np.array_equal(hinges, env.fingers.joint_qpos.ravel())
            m, d = env.model, env.data
            k = pre_grasp_curvature(m, d, pairs, hinges, unit, gap, float(env.kappa_range[0]))
            assert env.kappa_range[0] < k < 0.0
            step = _SCAN / 2 ** _BISECTIONS
            assert _clearance(m, d, pairs, hinges, unit, k) > gap >= _clearance(m, d, pairs, hinges, unit, k - step)
    finally:
        env.close()


def test_an_episode_starts_near_the_workpiece_and_not_touching_it():
    env = gym.make(ID)
    u = env.unwrapped
    sl = u.obs_slices
    try:
        for seed in range(12):
            obs, info = env.reset(seed=seed)
            assert info["start_gap"] == u.start_gap and info["target_x"] == u.target_x
            assert obs[sl["kappa_command"]][0] == pytest.approx(u.valve_command, abs=1e-6)
            assert 0.0 < u.valve_command < 0.9
            assert np.all(obs[sl["contact_force"]] == 0.0)
            a = np.array([-1.0, 0.0, 0.0], np.float32)  # closing at the valve's full rate touches within 40 steps
            for _ in range(40):
                _, _, term, _, i = env.step(a)
                if max(i["normal_force"]) > 0.0 or term:
                    break
            assert max(i["normal_force"]) > 0.0, seed
    finally:
        env.close()


def test_the_draw_is_v3s_but_for_the_mass_and_the_target():
    new, old = gym.make(ID), gym.make(retired_spec(V3))
    try:
        masses = []
        for seed in range(25):
            _, fn = new.reset(seed=seed)
            _, fo = old.reset(seed=seed)
            for key in fn:  # the gap is drawn before the target: the target's draw moves on
                if key in ("box_mass", "hold_force", "crush_limit", "dimensionless", "start_gap", "target_x"):
                    continue
                assert fn[key] == fo[key], key
            masses.append(fn["box_mass"])
            un, uo = new.unwrapped, old.unwrapped
            assert un.crush_limit / un.hold_force == pytest.approx(uo.crush_limit / uo.hold_force, rel=1e-12)
            assert un.target_range == uo.target_range and abs(un.target_x) >= un.target_range[0]
        assert V4_MASS[0] <= min(masses) and max(masses) <= V4_MASS[1]
    finally:
        new.close()
        old.close()


def _actions(n, seed):
    """Close with noise, lift after 30 steps, carry sideways after 60: touches, lifts, carries, some losses."""
    rng = np.random.default_rng(seed)
    a = np.empty((n, 3), np.float32)
    t = np.arange(n)
    a[:, 0] = np.clip(-0.25 + 0.3 * rng.standard_normal(n), -1, 1)
    a[:, 1] = np.clip(np.where(t > 60, 0.5, 0.0) + 0.3 * rng.standard_normal(n), -1, 1)
    a[:, 2] = np.clip(np.where(t > 30, 0.6, 0.0) + 0.3 * rng.standard_normal(n), -1, 1)
    return a


def test_the_reward_is_the_touch_paying_envs_less_that_pay():
    new, paid = FragilePlaceEnvV4(), FragilePlaceEnvV4(w_touch=0.02)
    touch_steps = 0
    try:
        for seed in (8100, 8101):
            on, _ = new.reset(seed=seed)
            op, _ = paid.reset(seed=seed)
            np.testing.assert_array_equal(on, op)
            for a in _actions(150, seed):
                on, rn, tn, trn, i_n = new.step(a)
                op, rp, tp, trp, i_p = paid.step(a)
                np.testing.assert_array_equal(on, op)
                assert (tn, trn) == (tp, trp) and i_n["reward_touch"] == 0.0
                touch_steps += i_p["reward_touch"] > 0.0
                assert rn == pytest.approx(rp - i_p["reward_touch"], abs=1e-12)
                if tn or trn:
                    break
    finally:
        new.close()
        paid.close()
    assert touch_steps > 20


def test_an_unsuccessful_episode_returns_at_most_contact_lift_and_place():
    env = gym.make(ID)
    u = env.unwrapped
    bound = u.w_contact + u.w_lift + u.w_place
    try:
        for seed in (8110, 8111, 8112):
            env.reset(seed=seed)
            total, success = 0.0, False
            for a in _actions(400, seed):
                _, r, term, trunc, info = env.step(a)
                total, success = total + r, success or info["is_success"]
                if term or trunc:
                    break
            if not success:
                assert total <= bound + 1e-9
    finally:
        env.close()


def test_the_observation_only_controller_places_from_the_pre_grasp():
    """The valve's pick-and-place controller (as ``simgrip.envs.baselines`` drives it) on the 10 first seeds
    it was tuned on for v3 (6100-6109): at least 8 (the issue's 80 %)."""
    from simgrip.envs.scripted_fragile import PlacePolicy
    from simgrip.envs.valve import absolute_to_valve

    env = gym.make(ID)
    u, done = env.unwrapped, 0
    try:
        for seed in range(6100, 6110):
            obs, info = env.reset(seed=seed)
            pol = PlacePolicy()
            pol.reset(env, info)
            while True:
                a = np.array(pol(obs), dtype=np.float32)
                a[0] = absolute_to_valve(a[0], u.valve_command, u.kappa_rate)
                obs, _, term, trunc, info = env.step(a)
                if term or trunc:
                    break
            done += info["is_success"]
    finally:
        env.close()
    assert done >= 8


@pytest.mark.parametrize("bad", [(0.0, 0.01), (0.01, 0.003), "near"])
def test_bad_gap_range_names_it(bad):
    with pytest.raises(ValueError, match="gap_range"):
        gym.make(ID, gap_range=bad)

"""The claws' v5 (simgrip.envs.pick_claw_v5): v4's cradle and sphere paid for approaching the grasp height.

Checked against v4 itself, stepped with the same seed and actions beside it (the same observations, events and
info; the reward differs by exactly v4's touch pay and v5's approach term), against the observation-only
controllers (the potential's grasp height is theirs: where they stop descending it is ~0), and against the
potential computed afresh from the simulation's bodies, not from the observation.
"""

from __future__ import annotations

import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  registers the environments
from simgrip.envs import FRAGILE_ENV_IDS, retired_spec
from simgrip.envs.pick_claw_v5 import APPROACH_SCALE, FragileCradleEnvV5, FragileSphereEnvV5
from simgrip.envs.pick_fragile_v3 import FragileCradleEnvV4, FragileSphereEnvV4
from simgrip.envs.scripted_fragile import CLAW_POLICIES
from simgrip.envs.scripted_policies import scripted, through_valve

sys.path.insert(0, str(Path(__file__).parent))
from test_pick_fragile_v5 import SAME_KEYS, episode_return  # noqa: E402  (the shared checks of v5's reward)

CASES = {"simgrip/PickCradleFragile-v5": (FragileCradleEnvV5, FragileCradleEnvV4, "cradle"),
         "simgrip/PickSphereFragile-v5": (FragileSphereEnvV5, FragileSphereEnvV4, "sphere")}


def test_both_are_retired():
    # (retired by v6, simgrip.envs.pick_fragile_v7; retired_spec builds them exactly)
    assert not set(CASES) & set(FRAGILE_ENV_IDS)
    assert all(retired_spec(i).entry_point.endswith(c[0].__name__) for i, c in CASES.items())


def _observation_policy(env, info, seed, kind):
    return through_valve(scripted(CLAW_POLICIES[kind][1]))(env, info, seed)


def _noisy(act, seed):
    rng = np.random.default_rng(seed)
    return lambda obs, t: np.clip(act(obs, t) + 0.15 * rng.standard_normal(2), -1, 1).astype(np.float32)


@pytest.mark.parametrize("env_id", sorted(CASES))
def test_v5_is_v4_less_the_touch_pay_plus_the_approach(env_id):
    cls5, cls4, kind = CASES[env_id]
    new, old = cls5(), cls4()
    touch_steps = approach_steps = 0
    try:
        for seed in (8200, 8201):
            o5, i5 = new.reset(seed=seed)
            o4, i4 = old.reset(seed=seed)
            np.testing.assert_array_equal(o5, o4)
            act = _noisy(_observation_policy(new, i5, seed, kind), seed)
            for t in range(300):
                a = act(o5, t)
                o5, r5, t5, tr5, i5 = new.step(a)
                o4, r4, t4, tr4, i4 = old.step(a)
                np.testing.assert_array_equal(o5, o4)
                assert (t5, tr5) == (t4, tr4)
                assert i5["reward_touch"] == 0.0
                touch_steps += i4["reward_touch"] > 0.0
                approach_steps += i5["reward_approach"] != 0.0
                assert r5 == pytest.approx(r4 - i4["reward_touch"] + i5["reward_approach"], abs=1e-12)
                for k in SAME_KEYS:
                    assert i5[k] == i4[k], k
                if t5 or tr5:
                    break
    finally:
        new.close()
        old.close()
    assert touch_steps > 10 and approach_steps > 10


def _potential_from_bodies(u) -> float:
    """psi from the simulation's bodies at the current ``qpos`` (kinematics run afresh on a copy of the data): the
    workpiece body's centre height minus the palm body's [m]."""
    import mujoco

    model, data = u.model, mujoco.MjData(u.model)
    data.qpos[:] = u.data.qpos
    mujoco.mj_kinematics(model, data)
    wp = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, n) for n in ("box", "workpiece")]
    wp = next(i for i in wp if i >= 0)
    palm = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, "palm")
    z = float(data.xpos[wp][2] - data.xpos[palm][2])
    return -min(abs(z - u._grasp_offset()) / APPROACH_SCALE, 1.0)


@pytest.mark.parametrize("env_id", sorted(CASES))
def test_the_approach_term_is_a_potential_difference_and_zero_at_the_controllers_grasp_height(env_id):
    cls5, _, kind = CASES[env_id]
    env = gym.make(retired_spec(env_id))
    u = env.unwrapped
    assert isinstance(u, cls5)
    try:
        for seed in (8210, 8211, 8212):
            obs, info = env.reset(seed=seed)
            psi0 = _potential_from_bodies(u)
            assert psi0 < -0.2  # the hand starts well above the grasp height
            act = _observation_policy(env, info, seed, kind)
            total, at_grasp, t = 0.0, None, 0
            for t in range(300):
                a = act(obs, t)
                obs, r, term, trunc, info = env.step(a)
                total += info["reward_approach"]
                # the controller's descent ends (its palm speed action drops from descending to closing)
                if at_grasp is None and a[1] > -0.5 and t > 5:
                    at_grasp = _potential_from_bodies(u)
                if term or trunc:
                    break
            assert total == pytest.approx(u.w_approach * (_potential_from_bodies(u) - psi0), abs=1e-6)
            assert at_grasp is not None and at_grasp > -0.05  # within 1 cm of the controller's grasp height
    finally:
        env.close()


@pytest.mark.parametrize("env_id", sorted(CASES))
def test_an_unsuccessful_episode_returns_at_most_contact_lift_and_approach(env_id):
    env = gym.make(retired_spec(env_id))
    u = env.unwrapped
    bound = u.w_contact + u.w_lift + u.w_approach
    rng = np.random.default_rng(8220)
    try:
        for seed in (8220, 8221, 8222):
            total, success = episode_return(
                env, seed, lambda t: np.clip(np.array([0.3, -0.6]) + 0.5 * rng.standard_normal(2), -1, 1).astype(
                    np.float32))
            if not success:
                assert total <= bound + 1e-9
    finally:
        env.close()


def test_bad_w_approach_names_it():
    with pytest.raises(ValueError, match="w_approach"):
        FragileCradleEnvV5(w_approach=float("nan"))

"""envs.evaluation: seeded episodes and the shared options of the baseline scripts."""

import argparse

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401
from simgrip.envs.env_options import EnvOptions, make_env
from simgrip.envs.evaluation import (GAMMA, add_episode_arguments, check_env_id, outcomes, run_episodes,
                                     summary)


def test_episodes_are_seeded_and_summarised():
    env = gym.make("simgrip/Pick-v1")
    act = lambda obs: env.action_space.sample()  # noqa: E731
    seed_space = lambda env_, info, seed: env.action_space.seed(seed)  # noqa: E731
    a = run_episodes(env, act, 2, 5, on_reset=seed_space)
    b = run_episodes(env, act, 2, 5, on_reset=seed_space)
    env.close()
    assert [r.seed for r in a] == [5, 6]
    assert [(r.ret, r.length) for r in a] == [(r.ret, r.length) for r in b]
    s = summary(a)
    assert s["episodes"] == 2 and 0.0 <= s["success_rate"] <= 1.0
    assert s["mean_length"] == sum(r.length for r in a) / 2


@pytest.mark.parametrize("argv", [["--episodes", "0"], ["--seed", "-1"], ["--episodes", "x"]])
def test_bad_episode_options_exit_2(argv):
    p = argparse.ArgumentParser()
    add_episode_arguments(p)
    with pytest.raises(SystemExit) as info:
        p.parse_args(argv)
    assert info.value.code == 2


def test_unknown_env_id_exits_2():
    p = argparse.ArgumentParser()
    with pytest.raises(SystemExit) as info:
        check_env_id(p, "simgrip/Nope-v9")
    assert info.value.code == 2


def test_retired_ids_pass_only_where_asked(capsys):
    p = argparse.ArgumentParser()
    check_env_id(p, "simgrip/PickFragile-v2", retired=True)  # make_env builds it through its spec
    check_env_id(p, "simgrip/Pick-v1", retired=True)
    for env_id, retired in (("simgrip/PickFragile-v2", False), ("simgrip/Nope-v9", True)):
        with pytest.raises(SystemExit) as info:
            check_env_id(p, env_id, retired=retired)
        assert info.value.code == 2
        assert f"--env: unknown id {env_id!r}" in capsys.readouterr().err


class _Counting(gym.Env):
    """Reward ``t + 1`` on step ``t``; ends after ``seed % 4 + 1`` steps, in the outcome ``ENDS[seed % 4]``."""

    ENDS = ({"is_success": True}, {"crushed": True}, {"dropped": True}, {})
    observation_space = gym.spaces.Box(-1.0, 1.0, (1,))
    action_space = gym.spaces.Box(-1.0, 1.0, (1,))

    def reset(self, *, seed=None, options=None):
        self.n, self.t = seed % 4 + 1, 0
        self.end = self.ENDS[seed % 4]
        return self.observation_space.low, {}

    def step(self, action):
        self.t += 1
        done = self.t == self.n
        info = dict(self.end) if done else {}
        return self.observation_space.low, float(self.t), done and bool(self.end), done and not self.end, info


def test_discounted_return_and_outcomes():
    gamma = 0.9
    res = run_episodes(_Counting(), lambda obs: [0.0], 4, 0, gamma=gamma)
    # seed s: rewards 1..n, n = s % 4 + 1; discounted sum_t gamma^t (t + 1)
    for r in res:
        assert r.length == r.seed % 4 + 1
        assert r.ret == sum(range(1, r.length + 1))
        assert r.discounted == pytest.approx(sum(gamma ** t * (t + 1) for t in range(r.length)), abs=1e-12)
    o = outcomes(res, gamma)
    assert o["outcomes"] == {"success": 1, "crushed": 1, "dropped": 1, "timeout": 1}
    assert o["mean_success_length"] == 1  # seed 0
    assert o["mean_discounted_return"] == pytest.approx(sum(r.discounted for r in res) / 4, abs=1e-12)
    assert o["gamma"] == gamma
    assert outcomes(res[1:])["mean_success_length"] is None  # no success: None, which JSON can write


def test_default_discount_is_sb3s():
    res = run_episodes(_Counting(), lambda obs: [0.0], 1, 1)  # two steps: 1 + 0.99 * 2
    assert res[0].discounted == pytest.approx(1.0 + GAMMA * 2.0, abs=1e-12) and GAMMA == 0.99


def test_make_env_names_the_option_it_refuses():
    from simgrip.envs.action_offset import ActionOffset

    env = make_env("simgrip/PickFragile-v2", EnvOptions({"w_touch": 0.0}, (-0.4, 0.2)))  # a retired id (its spec)
    assert isinstance(env, ActionOffset) and env.spec.id == "simgrip/PickFragile-v2" and env.unwrapped.w_touch == 0.0
    env.close()
    with pytest.raises(ValueError, match="^--env-kwargs: simgrip/PickFragile-v7 does not take"):
        make_env("simgrip/PickFragile-v7", EnvOptions({"w_nope": 1}))
    with pytest.raises(ValueError, match="^--action-offset: offset must be 2 finite numbers"):
        make_env("simgrip/PickFragile-v7", EnvOptions(action_offset=(0.1,)))
    for bad in (0, -1, 2.0, True, "3"):
        with pytest.raises(ValueError, match="^--frame-stack: a whole number >= 1"):
            make_env("simgrip/PickFragile-v7", EnvOptions(frame_stack=bad))


def test_make_env_stacks_the_last_observations():
    plain = make_env("simgrip/PickFragile-v7")
    one = make_env("simgrip/PickFragile-v7", EnvOptions(frame_stack=1))  # 1: the env's own observation, no wrapper
    stacked = make_env("simgrip/PickFragile-v7", EnvOptions(action_offset=(-0.4, 0.2), frame_stack=3))
    try:
        assert type(one) is type(plain) and one.observation_space == plain.observation_space
        n = plain.observation_space.shape[0]
        assert stacked.observation_space.shape == (3, n)
        o, _ = stacked.reset(seed=8400)
        p, _ = plain.reset(seed=8400)
        assert o.shape == (3, n) and all(np.array_equal(o[k], p) for k in range(3))  # the reset repeated
        history = [p]
        for t in range(4):
            a = np.array([0.3 * (-1) ** t, 0.5], np.float32)
            o, *_ = stacked.step(a)
            p, *_ = plain.step(np.clip(a + np.array([-0.4, 0.2], np.float32), -1, 1))
            history.append(p)
            want = [history[max(0, len(history) - 3 + k)] for k in range(3)]  # oldest first
            assert all(np.array_equal(o[k], want[k]) for k in range(3)), t
    finally:
        for e in (plain, one, stacked):
            e.close()

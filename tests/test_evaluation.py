"""envs.evaluation: seeded episodes and the shared options of the baseline scripts."""

import argparse

import gymnasium as gym
import pytest

import simgrip.envs  # noqa: F401
from simgrip.envs.evaluation import add_episode_arguments, check_env_id, run_episodes, summary


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

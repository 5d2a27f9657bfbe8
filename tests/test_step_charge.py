"""A charge on every training step (issue 18's training aids): :class:`simgrip.envs.step_charge.StepCharge`, and
``--step-charge C`` of ``examples/train_sb3.py`` and ``examples/rl_baselines.py``.

The wrapper is checked step for step against the same env unwrapped (same seed, same actions: the same
observations, terminations and infos, each reward lower by exactly ``C``); the scripts on what they pass and
record."""

from __future__ import annotations

import json
import math

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs.env_options import EnvOptions, make_env
from simgrip.envs.step_charge import StepCharge
from helpers import load_example as _example, rl_baselines_args


def test_every_step_costs_the_charge_and_nothing_else_changes():
    plain, charged = gym.make("simgrip/PickFragile-v7"), StepCharge(gym.make("simgrip/PickFragile-v7"), 0.005)
    rng = np.random.default_rng(3)
    o1, _ = plain.reset(seed=8123)
    o2, _ = charged.reset(seed=8123)
    assert np.array_equal(o1, o2)
    for _ in range(60):
        a = rng.uniform(-1, 1, plain.action_space.shape).astype(np.float32)
        o1, r1, t1, u1, i1 = plain.step(a)
        o2, r2, t2, u2, i2 = charged.step(a)
        assert np.array_equal(o1, o2) and (t1, u1) == (t2, u2)
        assert r2 == r1 - 0.005 and i2.pop("reward_step_charge") == -0.005
        assert i1.keys() == i2.keys() and i1["is_success"] == i2["is_success"]
        if t1 or u1:
            o1, _ = plain.reset(seed=8124)
            o2, _ = charged.reset(seed=8124)
    plain.close(), charged.close()


@pytest.mark.parametrize("bad", [-0.1, math.nan, math.inf, True, "0.1"])
def test_a_bad_charge_is_refused_by_name(bad):
    env = gym.make("simgrip/PickFragile-v7")
    with pytest.raises(ValueError, match="charge"):
        StepCharge(env, bad)
    env.close()


def test_make_env_puts_it_on_the_training_env_only_where_asked():
    env = make_env("simgrip/PickMultiFragile-v7", EnvOptions(light_bias=0.5, step_charge=0.005))
    assert isinstance(env, StepCharge) and env.charge == 0.005
    env.close()
    env = make_env("simgrip/PickMultiFragile-v7")
    assert not isinstance(env, StepCharge)
    env.close()


def test_rl_baselines_passes_it_to_every_run(tmp_path):
    mod = _example("rl_baselines")
    args = rl_baselines_args(mod, step_charge=0.005)
    cmd = mod.run_command("ppo", 0, args, tmp_path)
    assert cmd[cmd.index("--step-charge") + 1] == "0.005"
    args.step_charge = None
    assert "--step-charge" not in mod.run_command("ppo", 0, args, tmp_path)


def test_train_sb3_records_it_and_evaluates_the_task(tmp_path):
    """One rollout and one update with the charge: the JSON records it and its wrapper as a training one; the
    held-out evaluation is the task's (an episode's return there carries no charge: it equals the evaluation's
    own return of the same policy without the wrapper, which ``evaluate`` builds from the task)."""
    pytest.importorskip("stable_baselines3")
    _example("train_sb3").main(["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--steps", "64",
                                "--step-charge", "0.5", "--eval-episodes", "1", "--eval-seed", "8310",
                                "--out", str(tmp_path)])
    trained = json.loads((tmp_path / "ppo_eval.json").read_text())
    assert trained["step_charge"] == 0.5
    assert "StepCharge(0.5) in training" in trained["wrapper"]
    # 0.5 a step would take the return of an episode of mean_length steps down by 0.5 * length: not there
    assert trained["mean_return"] > -0.5 * trained["mean_length"] + 5.0

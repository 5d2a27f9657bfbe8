"""A charge for a grip near the crush (issue 18's training aids): :class:`simgrip.envs.crush_margin.CrushMargin`,
and ``--crush-margin C`` of ``examples/train_sb3.py`` and ``examples/rl_baselines.py``.

The wrapper is checked step for step against the same env unwrapped (same seed, same actions): the same
observations, terminations and infos, each reward lower by exactly ``C clip((F / F_c - 0.8) / 0.2, 0, 1)`` with
``F`` the step's largest finger force and ``F_c`` the hidden limit, computed here from the unwrapped env's own info;
the actions close the fingers hard so that the steps cover no charge, part of it and all of it (a crush)."""

from __future__ import annotations

import json
import math

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs.crush_margin import MARGIN_ONSET, CrushMargin
from simgrip.envs.env_options import EnvOptions, make_env
from helpers import load_example as _example, rl_baselines_args


@pytest.mark.parametrize("env_id", ["simgrip/PickMultiFragile-v7", "simgrip/PickFragile-v7"])
def test_each_step_costs_the_charge_of_its_force_and_nothing_else_changes(env_id):
    plain, charged = gym.make(env_id), CrushMargin(gym.make(env_id), 0.2)
    shares, costs = [], []
    for seed in (8200, 8201, 8202, 8203):
        o1, _ = plain.reset(seed=seed)
        o2, _ = charged.reset(seed=seed)
        assert np.array_equal(o1, o2)
        for t in range(300):
            a = np.array([-0.6 if t < 40 else -0.05, 0.0], dtype=np.float32)  # close fast, then creep
            o1, r1, t1, u1, i1 = plain.step(a)
            o2, r2, t2, u2, i2 = charged.step(a)
            assert np.array_equal(o1, o2) and (t1, u1) == (t2, u2)
            share = max(i1["peak_normal_force"]) / plain.unwrapped.crush_limit
            want = 0.2 * min(max((share - 0.8) / 0.2, 0.0), 1.0)
            got = i2.pop("reward_crush_margin")  # the same sum, rounded in another order: to the last bits
            assert math.isclose(got, -want, rel_tol=1e-12, abs_tol=1e-15) and math.isclose(r2, r1 + got, abs_tol=1e-12)
            assert i1.keys() == i2.keys() and i1["crushed"] == i2["crushed"]
            shares.append(share), costs.append(want)
            if t1 or u1:
                break
    costs = np.array(costs)
    # the runs met every case: no charge below the onset, part of it between, all of it past the limit
    assert (costs == 0).any() and ((costs > 0) & (costs < 0.2)).any() and (costs == 0.2).any(), shares
    assert MARGIN_ONSET == 0.8
    plain.close(), charged.close()


@pytest.mark.parametrize("bad", [-0.1, math.nan, math.inf, True, "0.1"])
def test_a_bad_charge_is_refused_by_name(bad):
    env = gym.make("simgrip/PickFragile-v7")
    with pytest.raises(ValueError, match="charge"):
        CrushMargin(env, bad)
    env.close()


def test_a_task_without_a_crush_limit_is_refused():
    env = gym.make("simgrip/Pick-v1")
    with pytest.raises(ValueError, match="fragile"):
        CrushMargin(env, 0.2)
    env.close()
    with pytest.raises(ValueError, match="--crush-margin"):
        make_env("simgrip/Pick-v1", EnvOptions(crush_margin=0.2))


def test_make_env_puts_it_on_the_training_env_only_where_asked():
    env = make_env("simgrip/PickMultiFragile-v7", EnvOptions(light_bias=0.5, step_charge=0.005, crush_margin=0.2))
    assert isinstance(env, CrushMargin) and env.charge == 0.2
    env.close()
    env = make_env("simgrip/PickMultiFragile-v7", EnvOptions(step_charge=0.005))
    assert not isinstance(env, CrushMargin)
    env.close()


def test_rl_baselines_passes_it_to_every_run(tmp_path):
    mod = _example("rl_baselines")
    args = rl_baselines_args(mod, crush_margin=0.2)
    cmd = mod.run_command("ppo", 0, args, tmp_path)
    assert cmd[cmd.index("--crush-margin") + 1] == "0.2"
    args.crush_margin = None
    assert "--crush-margin" not in mod.run_command("ppo", 0, args, tmp_path)


@pytest.mark.parametrize("script", ["train_sb3", "rl_baselines"])
@pytest.mark.parametrize("env_id, value", [("simgrip/PickFragile-v7", "-1"), ("simgrip/PickFragile-v7", "nan"),
                                           ("simgrip/Pick-v1", "0.2")])
def test_a_bad_margin_exits_2_naming_it(script, env_id, value, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        _example(script).main(["--env", env_id, "--out", str(tmp_path / "o"), "--crush-margin", value])
    assert e.value.code == 2 and "--crush-margin" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_train_sb3_records_it_and_evaluates_the_task(tmp_path):
    pytest.importorskip("stable_baselines3")
    _example("train_sb3").main(["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--steps", "64",
                                "--crush-margin", "0.2", "--eval-episodes", "1", "--eval-seed", "8310",
                                "--out", str(tmp_path)])
    trained = json.loads((tmp_path / "ppo_eval.json").read_text())
    assert trained["crush_margin"] == 0.2 and "CrushMargin(0.2) in training" in trained["wrapper"]

"""``--n-envs N`` of ``examples/train_sb3.py`` and ``examples/rl_baselines.py``: the training steps ``N`` copies of
the env in its own process (Stable-Baselines3's ``DummyVecEnv``); and ``--n-steps S``, PPO's steps a rollout
collects from each env; and ``--batch-size B``, the transitions of each gradient step.

Checked on what they change and record: PPO's rollout becomes ``S * N`` steps (one rollout under ``--steps 64``),
the JSON names the copies and the rollout's length, the same command gives the same numbers twice, bad values exit
2 naming the option, and the driver passes both to every run and names them in ``aggregate.json``."""

from __future__ import annotations

import json

import pytest

from helpers import load_example as _example, rl_baselines_args


def _train(out, n_envs: int, *extra: str) -> dict:
    _example("train_sb3").main(["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--steps", "64", "--seed", "5",
                                "--n-envs", str(n_envs), "--eval-episodes", "2", "--eval-seed", "8320",
                                "--out", str(out), *extra])
    return json.loads((out / "ppo_eval.json").read_text())


def test_two_copies_fill_one_rollout_of_twice_the_steps_and_repeat_bit_for_bit(tmp_path):
    pytest.importorskip("stable_baselines3")
    first, again = _train(tmp_path / "a", 2), _train(tmp_path / "b", 2)
    assert first["timesteps"] == 2 * 2048 and first["n_envs"] == 2
    assert "DummyVecEnv of 2 copies in training" in first["wrapper"]
    assert first["episodes"] == 2 and first["eval_seeds"] == [8320, 8321]  # the evaluation: one env, as always
    # the training episodes of both copies are on the curve: their lengths fill the rollout but for the two
    # episodes still running at its end
    curve = (tmp_path / "a" / "ppo_curve.csv").read_text().splitlines()[1:]
    assert len(curve) == first["train_episodes"] > 0
    assert sum(int(r.split(",")[5]) for r in curve) <= 2 * 2048
    for key in ("timesteps", "train_episodes", "success_rate", "mean_return", "outcomes"):
        assert first[key] == again[key], key
    strip = (lambda text: [r.split(",")[:2] + r.split(",")[4:] for r in text.splitlines()])  # not the times
    assert strip((tmp_path / "a" / "ppo_curve.csv").read_text()) == strip((tmp_path / "b" / "ppo_curve.csv")
                                                                          .read_text())


def test_n_steps_sets_each_envs_share_of_the_rollout(tmp_path):
    pytest.importorskip("stable_baselines3")
    four = _train(tmp_path, 4, "--n-steps", "512")
    assert four["timesteps"] == 2048 and four["n_envs"] == 4
    assert four["hyperparameters"] == "Stable-Baselines3 defaults but n_steps = 512"
    policy = (tmp_path / "ppo_policy.csv").read_text().splitlines()
    assert [r.split(",")[0] for r in policy[1:]] == ["2048"]  # one window: the one rollout


def test_batch_size_sets_the_minibatch_and_is_named(tmp_path, monkeypatch):
    sb3 = pytest.importorskip("stable_baselines3")
    seen = []
    train = sb3.PPO.train
    monkeypatch.setattr(sb3.PPO, "train", lambda self: seen.append(self.batch_size) or train(self))
    four = _train(tmp_path, 4, "--n-steps", "512", "--batch-size", "128")
    assert seen == [128] and four["timesteps"] == 2048
    assert four["hyperparameters"] == "Stable-Baselines3 defaults but n_steps = 512, batch_size = 128"


def test_one_env_is_recorded_as_one(tmp_path):
    pytest.importorskip("stable_baselines3")
    one = _train(tmp_path, 1)
    assert one["timesteps"] == 2048 and one["n_envs"] == 1 and "DummyVecEnv" not in one.get("wrapper", "")


@pytest.mark.parametrize("script", ["train_sb3", "rl_baselines"])
@pytest.mark.parametrize("option, value", [("--n-envs", "0"), ("--n-envs", "-1"), ("--n-envs", "65"),
                                           ("--n-envs", "2.5"), ("--n-envs", "x"), ("--n-steps", "1"),
                                           ("--n-steps", "1048577"), ("--n-steps", "nan"),
                                           ("--batch-size", "1"), ("--batch-size", "1048577"),
                                           ("--batch-size", "64.0")])
def test_a_bad_count_exits_2_naming_it(script, option, value, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        _example(script).main(["--env", "simgrip/PickFragile-v7", "--out", str(tmp_path / "o"), option, value])
    assert e.value.code == 2 and option in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("script", ["train_sb3", "rl_baselines"])
def test_n_steps_is_ppos_alone(script, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        _example(script).main(["--env", "simgrip/PickFragile-v7", "--algo", "sac", "--out", str(tmp_path / "o"),
                               "--n-steps", "512"])
    assert e.value.code == 2 and "--n-steps: PPO only" in capsys.readouterr().err


@pytest.mark.parametrize("script", ["train_sb3", "rl_baselines"])
@pytest.mark.parametrize("extra, rollout", [(["--batch-size", "100"], 2048),
                                            (["--n-envs", "3", "--n-steps", "512", "--batch-size", "1024"], 1536)])
def test_a_batch_size_that_does_not_divide_the_rollout_exits_2(script, extra, rollout, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        _example(script).main(["--env", "simgrip/PickFragile-v7", "--algo", "ppo", "--out", str(tmp_path / "o"),
                               *extra])
    err = capsys.readouterr().err
    assert e.value.code == 2 and f"does not divide PPO's rollout of {rollout} steps" in err and "--batch-size" in err
    assert not (tmp_path / "o").exists()


def test_rl_baselines_passes_it_to_every_run_and_names_it(tmp_path):
    mod = _example("rl_baselines")
    args = rl_baselines_args(mod, n_envs=4)
    cmd = mod.run_command("ppo", 0, args, tmp_path)
    assert cmd[cmd.index("--n-envs") + 1] == "4" and cmd[cmd.index("--threads") + 1] == "1"
    assert mod.hyperparameters(args) == "Stable-Baselines3 defaults, 4 envs (DummyVecEnv), one torch thread"
    args.n_steps = 512
    assert mod.run_command("ppo", 0, args, tmp_path)[-2:] == ["--n-steps", "512"]
    assert mod.hyperparameters(args).endswith("one torch thread; but n_steps = 512")
    args.batch_size = 128
    assert mod.run_command("ppo", 0, args, tmp_path)[-4:] == ["--n-steps", "512", "--batch-size", "128"]
    assert mod.hyperparameters(args).endswith("one torch thread; but n_steps = 512; but batch_size = 128")
    args.batch_size = None
    args.n_envs, args.n_steps, args.gamma, args.lr_decay = 1, None, 0.995, True
    assert "--n-envs" not in mod.run_command("ppo", 0, args, tmp_path)
    assert "--n-steps" not in mod.run_command("ppo", 0, args, tmp_path)
    assert mod.hyperparameters(args) == ("Stable-Baselines3 defaults, one env, one torch thread; but gamma = 0.995; "
                                         "but the learning rate falls linearly to 0 over the budget")

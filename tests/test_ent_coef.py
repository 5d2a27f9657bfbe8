"""PPO's entropy bonus as a training aid (issue 18): ``--ent-coef C`` of ``examples/train_sb3.py`` and
``examples/rl_baselines.py`` (:func:`simgrip.envs.evaluation.add_training_aid_arguments`).

SB3's PPO adds ``-ent_coef * entropy`` to its loss (default 0).  A Gaussian policy's entropy grows by 1 per unit of
each action's log standard deviation, so with ``C = 1`` that term's gradient on each log standard deviation is -1,
against a policy-gradient term of about the advantages' spread over a minibatch's square root (advantages
normalised to unit spread, 64 per minibatch: about 0.1).  Adam then moves each one upwards by about the learning
rate (3e-4) per step, each step at least (1 - 0.1) / (1 + 0.1) of it where the gradient stays within 0.1 of -1 and at
most Adam's largest step, 3e-4 (1 - beta1) / sqrt(1 - beta2) = 3.2 times it: after one update (10 epochs of 32
minibatches) every log standard deviation, 0 at the start, lies in (0.8 * 320 * 3e-4, 3.2 * 320 * 3e-4) =
(0.077, 0.30); without the bonus it moves either way by up to about 0.096 (``test_examples.py``).
"""

from __future__ import annotations

import json

import pytest

from helpers import load_example as _example, rl_baselines_args


def test_train_sb3_ent_coef_raises_the_entropy_and_says_so(tmp_path):
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO

    _example("train_sb3").main(["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--steps", "64",
                                "--ent-coef", "1", "--eval-episodes", "1", "--eval-seed", "8310",
                                "--out", str(tmp_path)])
    trained = json.loads((tmp_path / "ppo_eval.json").read_text())
    assert trained["hyperparameters"] == "Stable-Baselines3 defaults but ent_coef = 1.0"
    model = PPO.load(tmp_path / "ppo_model.zip", device="cpu")
    log_std = model.policy.log_std.detach().numpy()
    assert model.ent_coef == 1.0 and trained["timesteps"] == 2048
    assert (log_std > 0.077).all() and (log_std < 0.30).all(), log_std


@pytest.mark.parametrize("extra, word", [(["--algo", "sac", "--ent-coef", "0.01"], "--ent-coef: PPO only"),
                                         (["--ent-coef", "-0.01"], "--ent-coef"), (["--ent-coef", "nan"], "--ent-coef"),
                                         (["--ent-coef", "2"], "--ent-coef")])
def test_train_sb3_ent_coef_refusals_exit_2(extra, word, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        _example("train_sb3").main(["--env", "simgrip/PickFragile-v7", *extra, "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and word in capsys.readouterr().err.strip().splitlines()[-1]
    assert not (tmp_path / "o").exists()


def test_rl_baselines_passes_ent_coef_to_every_run_and_refuses_it_for_sac(tmp_path, capsys):
    mod = _example("rl_baselines")
    args = rl_baselines_args(mod, ent_coef=0.01)
    cmd = mod.run_command("ppo", 0, args, tmp_path)
    assert cmd[cmd.index("--ent-coef") + 1] == "0.01"
    args.ent_coef = None
    assert "--ent-coef" not in mod.run_command("ppo", 0, args, tmp_path)  # the library's 0
    with pytest.raises(SystemExit) as e:
        mod.main(["--env", "simgrip/PickFragile-v7", "--algo", "sac", "--ent-coef", "0.01", "--minutes", "1",
                  "--eval-seeds", "8000-8001", "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "--ent-coef: PPO only" in capsys.readouterr().err

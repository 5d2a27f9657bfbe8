"""``--sde``: PPO explores by SB3's generalised state-dependent exploration (``use_sde=True``), a named
hyperparameter (simgrip.envs.hyperparameters; train_sb3.py, rl_baselines.py).

What is ours is the plumbing: the keyword argument reaches the library, the records name it (so a replay without it
is refused), the policy CSV leaves gSDE's per-feature log standard deviation out, and SAC is refused.
"""

import csv
import json

import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs.hyperparameters import hyperparameters, model_kwargs
from helpers import load_example, rl_baselines_args

CRADLE = "simgrip/PickCradleFragile-v6"


def test_the_keyword_and_the_sentence():
    assert model_kwargs("ppo", None, -1.0, use_sde=True) == {"use_sde": True, "policy_kwargs": {"log_std_init": -1.0}}
    assert model_kwargs("ppo", None, None, use_sde=False) == {} == model_kwargs("sac", None, None)
    with pytest.raises(ValueError, match="use_sde: PPO only"):
        model_kwargs("sac", None, None, use_sde=True)
    assert hyperparameters(None, -1.0, use_sde=True) == \
        "Stable-Baselines3 defaults but log_std_init = -1.0, use_sde = True"
    assert hyperparameters(None, -1.0, use_sde=False) == hyperparameters(None, -1.0)  # the records before it read alike


def test_train_sb3_trains_with_it_and_records_it(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO

    train = load_example("train_sb3", "_sde")
    common = ["--algo", "ppo", "--env", CRADLE, "--steps", "256", "--n-steps", "128", "--action-offset", "-0.4", "0",
              "--residual", "palm_z", "--eval-episodes", "1", "--eval-seed", "8040"]
    train.main(common + ["--sde", "--out", str(tmp_path / "a")])
    rec = json.loads((tmp_path / "a" / "ppo_eval.json").read_text())
    assert rec["hyperparameters"] == "Stable-Baselines3 defaults but n_steps = 128, use_sde = True"
    model = PPO.load(tmp_path / "a" / "ppo_model.zip", device="cpu")
    assert model.use_sde and model.policy.use_sde
    with (tmp_path / "a" / "ppo_policy.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 1 and rows[0]["log_std_0"] == "" and len(rows[0]) == 2 + 3 * 2
    capsys.readouterr()
    with pytest.raises(SystemExit) as e:  # the record names use_sde: a replay without it is another command
        train.main(common + ["--replay", str(tmp_path / "a" / "ppo_eval.json"), "--out", str(tmp_path / "b")])
    assert e.value.code == 2 and "hyperparameters" in capsys.readouterr().err
    for argv, why in ((["--algo", "sac", "--sde"], "--sde: PPO only"),
                      (["--algo", "ppo", "--sde", "--init-from", str(tmp_path / "a" / "ppo_model.zip")],
                       "--sde: not with --init-from")):
        with pytest.raises(SystemExit) as e:
            train.main(["--env", CRADLE, *argv, "--out", str(tmp_path / "c")])
        assert e.value.code == 2 and why in capsys.readouterr().err
    assert not (tmp_path / "c").exists()


def test_rl_baselines_passes_it_and_names_it(tmp_path):
    mod = load_example("rl_baselines", "_sde")
    args = rl_baselines_args(mod, CRADLE, sde=True)
    assert "--sde" in mod.run_command("ppo", 0, args, tmp_path / "run")
    assert mod.hyperparameters(args).endswith("one torch thread; but use_sde = True")
    args.sde = False
    assert "--sde" not in mod.run_command("ppo", 0, args, tmp_path / "run")
    assert "use_sde" not in mod.hyperparameters(args)

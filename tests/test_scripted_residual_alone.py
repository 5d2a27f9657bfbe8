"""``ScriptedResidual(env, channels, alone=True)`` and ``--residual-alone`` (simgrip.envs.scripted_residual): the
scripted controller drives the named actions alone and the learner acts on the others only.

The reference is the residual itself: alone, the env must run exactly as behind the plain residual driven with the
learner's action 0 on the scripted channels (``clip(b + 0) = b``), step for step and bit for bit.
"""

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs.env_options import EnvOptions, make_env
from simgrip.envs.scripted_residual import PALM_CHANNELS, ScriptedResidual
from helpers import load_example, rl_baselines_args, train_and_evaluate_again

PLACE, SPHERE = "simgrip/PlaceFragile-v8", "simgrip/PickSphereFragile-v6"


@pytest.mark.parametrize("env_id, channels, seed", [(SPHERE, ("palm_z",), 8012), (PLACE, PALM_CHANNELS, 8010)])
def test_alone_is_the_residual_with_the_learners_action_0_on_the_scripted_channels(env_id, channels, seed):
    alone = ScriptedResidual(gym.make(env_id), channels, alone=True)
    plain = ScriptedResidual(gym.make(env_id), channels)
    names = plain.unwrapped.action_names
    assert alone.action_space.shape == (len(names) - len(channels),) and alone.alone and not plain.alone
    assert alone.observation_space == plain.observation_space and alone.obs_layout == plain.obs_layout
    obs_a, _ = alone.reset(seed=seed)
    obs_p, _ = plain.reset(seed=seed)
    # the valve held while the script lowers the palm, then closing and opening (contact, the script's phases)
    assert names[0] == "curvature" and "curvature" not in channels
    for t, c in enumerate(np.r_[np.zeros(40), np.linspace(-0.6, 0.3, 110)].astype(np.float32)):
        assert np.array_equal(obs_a, obs_p)
        full = np.zeros(len(names), np.float32)
        full[0] = c
        obs_a, r_a, term_a, trunc_a, info_a = alone.step(np.array([c], np.float32))
        obs_p, r_p, term_p, trunc_p, info_p = plain.step(full)
        assert (r_a, term_a, trunc_a) == (r_p, term_p, trunc_p)
        assert np.array_equal(info_a["normal_force"], info_p["normal_force"])
        if term_a or trunc_a:
            break
    assert np.array_equal(obs_a, obs_p) and t > 100  # past the first touch (steps 100 and 44), into a crush or carry
    alone.close(), plain.close()


def test_alone_refuses_every_action_scripted_and_a_non_boolean():
    with pytest.raises(ValueError, match="channels: with alone, not every action"):
        ScriptedResidual(gym.make(PLACE), ("curvature", "palm_x", "palm_z"), alone=True)
    with pytest.raises(ValueError, match="alone must be True or False"):
        ScriptedResidual(gym.make(PLACE), PALM_CHANNELS, alone=1)


def test_make_env_builds_records_and_checks_the_option():
    options = EnvOptions(action_offset=(-0.8,), residual=("palm_z",), residual_alone=True)
    env = make_env(SPHERE, options)
    assert env.action_space.shape == (1,) and env.env.alone
    env.close()
    keys, wrappers = options.record()
    assert keys["residual"] == ["palm_z"] and keys["residual_alone"] is True
    assert "ScriptedResidual(['palm_z'], alone)" in wrappers
    assert "residual_alone" not in EnvOptions(residual=("palm_z",)).record()[0]
    with pytest.raises(ValueError, match="--residual-alone: needs --residual"):
        make_env(SPHERE, EnvOptions(residual_alone=True))
    with pytest.raises(ValueError, match="--action-offset"):  # two numbers for a one-action policy
        make_env(SPHERE, EnvOptions(action_offset=(-0.8, 0.0), residual=("palm_z",), residual_alone=True))
    with pytest.raises(ValueError, match="--residual-alone: channels"):
        make_env(PLACE, EnvOptions(residual=("curvature", "palm_x", "palm_z"), residual_alone=True))


def test_train_sb3_records_it_and_evaluate_policy_gives_its_figures_again(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    train, ev, rec, again = train_and_evaluate_again(
        SPHERE, ["--action-offset", "-0.8", "--residual", "palm_z", "--residual-alone"], tmp_path, "_alone")
    capsys.readouterr()
    assert rec["residual"] == ["palm_z"] and rec["residual_alone"] is True
    assert "ScriptedResidual(['palm_z'], alone)" in rec["wrapper"]
    assert again["residual_alone"] is True
    for key in ("success_rate", "mean_return", "mean_length", "outcomes"):
        assert again[key] == rec[key], key
    with pytest.raises(SystemExit) as e:  # the model's one action against the residual's two
        ev.main(["--env", SPHERE, "--model", str(tmp_path / "ppo_model.zip"), "--action-offset", "-0.8", "0",
                 "--residual", "palm_z"])
    assert e.value.code == 2 and "--residual" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        train.main(["--algo", "ppo", "--env", SPHERE, "--residual-alone", "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "--residual-alone" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_rl_baselines_passes_it_to_every_run(tmp_path):
    mod = load_example("rl_baselines", "_alone")
    args = rl_baselines_args(mod, SPHERE, residual=["palm_z"], residual_alone=True)
    cmd = mod.run_command("ppo", 0, args, tmp_path / "run")
    i = cmd.index("--residual")
    assert cmd[i + 1:i + 3] == ["palm_z", "--residual-alone"]
    args.residual_alone = False
    assert "--residual-alone" not in mod.run_command("ppo", 0, args, tmp_path / "run")

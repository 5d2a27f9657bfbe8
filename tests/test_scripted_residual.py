"""ScriptedResidual (simgrip.envs.scripted_residual): the env performs the scripted controller's action on the
chosen channels plus the learner's; the learner sees the controller's action."""

import json

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs.scripted_policies import policy_maker
from simgrip.envs.env_options import EnvOptions, make_env
from simgrip.envs.scripted_residual import PALM_CHANNELS, ScriptedResidual
from helpers import load_example, rl_baselines_args, train_and_evaluate_again

PLACE, PINCH = "simgrip/PlaceFragile-v8", "simgrip/PickFragile-v7"


def _beside(env_id, channels, actions, seed):
    """Step the wrapped env with ``actions`` and a plain env beside it with what the wrapper should pass on,
    ``clip(b + a)``, ``b`` the controller's action (on its own plain env's observations) masked to ``channels``;
    assert the same observations and infos every step.  Returns the wrapped env's last info and step count."""
    wrapped, plain = ScriptedResidual(gym.make(env_id), channels), gym.make(env_id)
    names = plain.unwrapped.action_names
    mask = np.array([n in channels for n in names], dtype=np.float32)
    obs_w, info_w = wrapped.reset(seed=seed)
    obs_p, info_p = plain.reset(seed=seed)
    act = policy_maker(plain, "observation")(plain, info_p, seed)
    n = len(names)
    for t, a in enumerate(actions):
        b = np.clip(np.asarray(act(obs_p, t), dtype=np.float32) * mask, -1, 1)
        assert np.array_equal(obs_w[:-n], obs_p) and np.array_equal(obs_w[-n:], b)  # the controller's next action
        obs_w, r_w, term_w, trunc_w, info_w = wrapped.step(a)
        obs_p, r_p, term_p, trunc_p, info_p = plain.step(np.clip(b + a, -1, 1))
        assert r_w == r_p and term_w == term_p and trunc_w == trunc_p
        assert info_w.keys() == info_p.keys() and info_w["crush_limit"] == info_p["crush_limit"]
        if term_w or trunc_w:
            break
    assert np.array_equal(obs_w[:-n], obs_p)
    wrapped.close(), plain.close()
    return info_w, t + 1


def test_every_channel_scripted_and_a_zero_action_is_the_controller():
    # the place's observation-only controller places the piece of seed 8004 (tests/test_examples.py)
    info, steps = _beside(PLACE, ("curvature", "palm_x", "palm_z"), np.zeros((400, 3), np.float32), 8004)
    assert info["is_success"] and steps < 400


def test_the_palm_scripted_the_curvature_the_learners():
    rng = np.random.default_rng(3)
    actions = rng.uniform(-1, 1, size=(60, 3)).astype(np.float32)
    actions[:, 0] = np.linspace(-0.5, 0.3, 60)  # a curvature closing then opening: contact, the script's phases
    _beside(PLACE, PALM_CHANNELS, actions, 8010)
    _beside(PINCH, ("palm_z",), actions[:, [0, 2]], 8011)  # the pinch's palm: its one palm action


def test_spaces_layout_and_determinism():
    env = ScriptedResidual(gym.make(PLACE), PALM_CHANNELS)
    inner = env.env.observation_space
    assert env.observation_space.shape == (inner.shape[0] + 3,) and env.observation_space.dtype == inner.dtype
    assert sum(size for _, size in env.obs_layout) == env.observation_space.shape[0]
    assert [name for name, _ in env.obs_layout[-3:]] == ["base_curvature", "base_palm_x", "base_palm_z"]
    assert env.mask.tolist() == [0.0, 1.0, 1.0] and env.channels == PALM_CHANNELS
    runs = []
    for _ in range(2):
        obs, _ = env.reset(seed=8020)
        seq = [obs]
        for t in range(30):
            seq.append(env.step(np.array([-0.4, 0.0, 0.1], np.float32))[0])
        runs.append(np.array(seq))
    assert np.array_equal(runs[0], runs[1])
    assert env.observation_space.contains(runs[0][-1])
    env.close()


@pytest.mark.parametrize("channels, word", [(["palm_y"], "palm_y"), ("palm_x", "one or more"), ([], "one or more"),
                                            (["palm_x", "palm_x"], "distinct"), ([0], "one or more")])
def test_bad_channels_are_refused_naming_them(channels, word):
    with pytest.raises(ValueError, match="channels") as e:
        ScriptedResidual(gym.make(PLACE), channels)
    assert word in str(e.value)


def test_an_env_without_a_scripted_controller_and_a_scripted_start_are_refused():
    with pytest.raises(ValueError, match="--residual: env"):
        make_env("simgrip/Pick-v1", EnvOptions(residual=("palm_z",)))
    with pytest.raises(ValueError, match="--residual: not with --scripted-start"):
        make_env(PLACE, EnvOptions(residual=tuple(PALM_CHANNELS), scripted_start=0.5))
    with pytest.raises(RuntimeError, match="reset"):
        ScriptedResidual(gym.make(PLACE), PALM_CHANNELS).step(np.zeros(3, np.float32))


def test_make_env_puts_the_offset_outside_the_residual():
    """``make_env(offset, residual)``: the env performs ``clip(b + clip(a + offset))``; PPO's zero start then
    closes through the valve at 0.4 of its rate while the script moves the palm."""
    wrapped = make_env(PLACE, EnvOptions(action_offset=(-0.4, 0.0, 0.0), residual=tuple(PALM_CHANNELS)))
    assert isinstance(wrapped.env, ScriptedResidual)
    obs_w, _ = wrapped.reset(seed=8030)
    ref = ScriptedResidual(gym.make(PLACE), PALM_CHANNELS)
    obs_r, _ = ref.reset(seed=8030)
    for a in np.random.default_rng(5).uniform(-1, 1, size=(100, 3)).astype(np.float32):
        assert np.array_equal(obs_w, obs_r)
        obs_w, _, term, trunc, _ = wrapped.step(a)
        obs_r, _, term_r, trunc_r, _ = ref.step(np.clip(a + np.array([-0.4, 0.0, 0.0], np.float32), -1, 1))
        assert (term, trunc) == (term_r, trunc_r)
        if term or trunc:
            break
    assert np.array_equal(obs_w, obs_r)
    wrapped.close(), ref.close()


def test_evaluate_policy_and_the_trainers_refuse_a_bad_residual(tmp_path, capsys):
    ev = load_example("evaluate_policy", "_res")
    with pytest.raises(SystemExit) as e:  # the controller alone is --policy observation
        ev.main(["--env", PLACE, "--policy", "observation", "--residual", "palm_x"])
    assert e.value.code == 2 and "--residual" in capsys.readouterr().err
    model = tmp_path / "m.zip"
    model.write_bytes(b"")
    with pytest.raises(SystemExit) as e:
        ev.main(["--env", PLACE, "--model", str(model), "--residual", "palm_y"])
    assert e.value.code == 2 and "--residual" in capsys.readouterr().err


def test_train_sb3_trains_and_evaluates_behind_the_residual(tmp_path, capsys):
    """Recorded in the JSON, and the saved model evaluated again behind the same wrapper (evaluate_policy) gives
    train_sb3's held-out figures; without it the spaces differ (exit 2); bad names and --init-from refused."""
    pytest.importorskip("stable_baselines3")
    train, ev, rec, again = train_and_evaluate_again(
        PLACE, ["--action-offset", "-0.4", "0", "0", "--residual", "palm_x", "palm_z"], tmp_path, "_res")
    capsys.readouterr()
    assert rec["residual"] == ["palm_x", "palm_z"] and "ScriptedResidual(['palm_x', 'palm_z'])" in rec["wrapper"]
    assert again["residual"] == ["palm_x", "palm_z"]
    for key in ("success_rate", "mean_return", "mean_length", "outcomes"):
        assert again[key] == rec[key], key
    with pytest.raises(SystemExit) as e:
        ev.main(["--env", PLACE, "--model", str(tmp_path / "ppo_model.zip"), "--action-offset", "-0.4", "0", "0"])
    assert e.value.code == 2 and "--residual" in capsys.readouterr().err
    for extra, word in ((["--residual", "palm_y"], "--residual"),
                        (["--residual", "palm_x", "--init-from", str(tmp_path / "ppo_model.zip")], "--init-from")):
        with pytest.raises(SystemExit) as e:
            train.main(["--algo", "ppo", "--env", PLACE, "--out", str(tmp_path / "o"), *extra])
        assert e.value.code == 2 and word in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_rl_baselines_passes_the_residual_to_every_run(tmp_path, capsys):
    mod = load_example("rl_baselines", "_res")
    args = rl_baselines_args(mod, PLACE, residual=["palm_x", "palm_z"])
    cmd = mod.run_command("ppo", 0, args, tmp_path / "run")
    i = cmd.index("--residual")
    assert cmd[i + 1:i + 3] == ["palm_x", "palm_z"]
    args.residual = None
    assert "--residual" not in mod.run_command("ppo", 0, args, tmp_path / "run")
    pytest.importorskip("stable_baselines3")  # main checks the rl extra before the options
    with pytest.raises(SystemExit) as e:
        mod.main(["--env", PLACE, "--residual", "palm_y", "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "--residual" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_the_baselines_behind_the_scripted_palm_vary_the_curvature_alone(tmp_path, capsys):
    """``python -m simgrip.envs.baselines --residual``: the grids' members command the curvature, the script the
    palm.  A valve held (rate 0) keeps the pre-grasp: the palm probes and waits for a grip that never comes, so
    the piece is never lifted and every episode times out; closing at the full rate crushes every piece."""
    from simgrip.envs import baselines

    out = tmp_path / "c.json"
    assert baselines.main(["--env", PLACE, "--policy", "constant", "--residual", "palm_x", "palm_z",
                           "--seeds", "8000-8001", "--out", str(out)]) == 0
    rec = json.loads(out.read_text())
    assert rec["residual"] == ["palm_x", "palm_z"]
    members = {m["kappa_rate_action"]: m["outcomes"] for m in rec["members"]}
    assert list(members) == list(baselines.VALVE_GRID)
    assert members[0.0] == {"timeout": 2} and members[-1.0] == {"crushed": 2}
    rec = baselines.evaluate(PLACE, "openloop", [8000], "coarse", ["palm_z", "palm_x"])
    assert [m["kappa"] for m in rec["members"]] == list(baselines.KAPPA_GRID[::2])
    for argv, word in ((["--policy", "observation", "--residual", "palm_x", "palm_z"], "constant and openloop"),
                       (["--policy", "constant", "--residual", "palm_x"], "every palm action"),
                       (["--policy", "constant", "--residual", "palm_x", "palm_z", "curvature"], "every palm")):
        with pytest.raises(SystemExit) as e:
            baselines.main(["--env", PLACE, *argv, "--out", str(tmp_path / "o.json")])
        assert e.value.code == 2 and word in capsys.readouterr().err
    assert not (tmp_path / "o.json").exists()

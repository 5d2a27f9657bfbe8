"""The examples: scripted and random baselines print JSON summaries; train_sb3 runs (when SB3 is installed)."""

import csv
import json
import tempfile

import gymnasium as gym
import pytest


from helpers import load_example as _example


@pytest.mark.parametrize("name, argv", [
    ("scripted_pick", ["--policy", "oracle"]), ("scripted_pick", ["--policy", "observation"]), ("random_policy", []),
    ("scripted_pick", ["--env", "simgrip/PickMulti-v0", "--fingers", "4"]),
    ("scripted_pick", ["--env", "simgrip/PickMulti-v0", "--fingers", "3", "--policy", "observation"]),
    ("random_policy", ["--env", "simgrip/PickMulti-v0", "--fingers", "4"]),
])
def test_examples_print_a_json_summary(name, argv, capsys):
    summary = _example(name).main(["--episodes", "2", "--seed", "7", "--json", *argv])
    out = json.loads(capsys.readouterr().out.strip())
    assert out == summary
    assert set(out) == {"episodes", "success_rate", "mean_return"} and out["episodes"] == 2
    if name == "scripted_pick":
        assert out["success_rate"] == 1.0


def test_random_policy_documents_only_its_options():
    module = _example("random_policy")
    doc = module.__doc__
    options = {"--episodes", "--seed", "--env", "--fingers", "--json"}
    import re

    assert set(re.findall(r"--[a-z][a-z-]*", doc)) == options
    with pytest.raises(SystemExit):
        module.main(["--vector", "4"])


@pytest.mark.parametrize("argv", [["--fingers", "4"], ["--env", "simgrip/PickMulti-v0", "--fingers", "1"],
                                  ["--env", "simgrip/PickMulti-v0", "--fingers", "x"]])
def test_fingers_option_is_checked(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        _example("random_policy").main(["--episodes", "1", *argv])
    assert exc.value.code == 2 and "--fingers" in capsys.readouterr().err


def test_train_sb3_evaluates_with_the_env_kwargs_it_was_given():
    import numpy as np

    class Closing:  # a policy: close through the valve, palm still (touches from the pre-grasp)
        def predict(self, obs, deterministic=True):
            return np.array([-0.3, 0.0], np.float32), None

    from simgrip.envs.env_options import EnvOptions

    evaluate = _example("train_sb3").evaluate
    plain = evaluate(Closing(), "simgrip/PickFragile-v7", 1, 8000)
    paid = evaluate(Closing(), "simgrip/PickFragile-v7", 1, 8000, EnvOptions({"w_touch": 0.5}))
    assert paid["mean_return"] > plain["mean_return"] + 0.5  # touch steps paid: the kwargs reached the env


def test_train_sb3_evaluates_behind_the_action_offset_it_was_given():
    import numpy as np

    from simgrip.envs.action_offset import ActionOffset
    from simgrip.envs.env_options import EnvOptions

    class Zero:  # PPO's start: the mean action 0
        def predict(self, obs, deterministic=True):
            return np.zeros(2, np.float32), None

    evaluate = _example("train_sb3").evaluate
    held = evaluate(Zero(), "simgrip/PickFragile-v7", 2, 8000)
    probed = evaluate(Zero(), "simgrip/PickFragile-v7", 2, 8000, EnvOptions(action_offset=(-0.4, 0.2)))
    # the same episodes run by hand behind the wrapper: the evaluation went through it
    env = ActionOffset(gym.make("simgrip/PickFragile-v7"), [-0.4, 0.2])
    returns = []
    for seed in (8000, 8001):
        env.reset(seed=seed)
        total, done = 0.0, False
        while not done:
            _, r, terminated, truncated, _ = env.step(np.zeros(2, np.float32))
            total += r
            done = terminated or truncated
        returns.append(total)
    env.close()
    assert probed["mean_return"] == pytest.approx(np.mean(returns), abs=1e-9)
    assert held["mean_return"] != pytest.approx(probed["mean_return"], abs=1e-6)


def test_train_sb3_smoke(tmp_path, capsys, monkeypatch):
    pytest.importorskip("stable_baselines3")
    module = _example("train_sb3")
    scratch = tmp_path.parent / (tmp_path.name + "_tmpdir")
    scratch.mkdir()
    monkeypatch.delenv("SB3_LOGDIR", raising=False)
    monkeypatch.setattr(tempfile, "tempdir", str(scratch))  # where SB3's own logger makes its SB3-<time> folder
    module.main(["--algo", "sac", "--steps", "120", "--eval-episodes", "1", "--out", str(tmp_path)])
    assert list(scratch.glob("SB3-*")) == []  # no empty log folder left per run (torch's own caches may be)
    res = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert res["algo"] == "SAC" and res["timesteps"] >= 120 and res["episodes"] == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["curves.png", "sac_curve.csv", "sac_eval.json",
                                                           "sac_model.zip", "sac_policy.csv"]
    with open(tmp_path / "sac_policy.csv") as fh:
        (row,) = list(csv.DictReader(fh))  # 120 steps: one partial window
    assert int(row["timesteps"]) == res["timesteps"] and row["log_std_0"] == ""  # SAC: no state-free std
    assert all(-1.0 <= float(row[f"action_mean_{i}"]) <= 1.0 for i in range(2))  # squashed into the bounds


def test_train_sb3_policy_log_starts_at_ppo_initial_gaussian(tmp_path, capsys):
    # SB3's PPO starts with log_std = 0 (std 1) and a near-zero mean (last layer initialised with gain 0.01):
    # the first window's 2048 samples must show exactly that; the second, after one update, a changed log_std
    pytest.importorskip("stable_baselines3")
    module = _example("train_sb3")
    module.main(["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--steps", "4096", "--eval-episodes", "1",
                 "--out", str(tmp_path)])
    capsys.readouterr()
    with open(tmp_path / "ppo_policy.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert [int(r["timesteps"]) for r in rows] == [2048, 4096]
    first, second = rows
    for i in range(2):
        assert float(first[f"log_std_{i}"]) == 0.0
        assert abs(float(first[f"action_mean_{i}"])) < 0.1  # 2048 draws of std 1: the mean's error ~0.02
        assert 0.93 < float(first[f"action_std_{i}"]) < 1.07  # unclipped samples (clipped ones: std ~0.8)
        assert float(second[f"log_std_{i}"]) != 0.0


def test_train_sb3_evaluates_through_the_frozen_normalizer():
    import numpy as np

    class Shift:  # a stand-in for VecNormalize: what the policy must see instead of the raw observation
        def normalize_obs(self, obs):
            return obs - 1000.0

    seen = []

    class Recorder:
        def predict(self, obs, deterministic=True):
            seen.append(np.array(obs))
            return np.zeros(2, np.float32), None

    evaluate = _example("train_sb3").evaluate
    evaluate(Recorder(), "simgrip/PickFragile-v7", 1, 8000, None, Shift())
    assert seen and all(np.all(o < -500.0) for o in seen)  # the env's observations are bounded by 100
    seen.clear()
    evaluate(Recorder(), "simgrip/PickFragile-v7", 1, 8000)
    assert seen and all(np.all(o > -500.0) for o in seen)


def test_train_sb3_normalize_saves_the_statistics_with_every_model(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    module = _example("train_sb3")
    module.main(["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--minutes", "0.06", "--checkpoint-minutes",
                 "0.03", "--eval-episodes", "1", "--normalize", "--out", str(tmp_path)])
    res = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert "VecNormalize" in res["wrapper"] and res["episodes"] == 1
    names = {p.name for p in tmp_path.iterdir()}
    assert {"ppo_vecnormalize.pkl", "ppo_vecnormalize_0.03min.pkl"} <= names
    final = module._load_normalizer(tmp_path / "ppo_vecnormalize.pkl")
    first = module._load_normalizer(tmp_path / "ppo_vecnormalize_0.03min.pkl")
    # statistics of the observations seen so far: the checkpoint's froze earlier than the final one's
    assert 0 < first.obs_rms.count < final.obs_rms.count and getattr(final, "venv", None) is None


def test_evaluate_policy_scripted_matches_the_baselines_harness(capsys):
    """The scripted controller through evaluate_policy ends its episodes as simgrip.envs.baselines runs it."""
    from simgrip.envs.baselines import evaluate

    out = _example("evaluate_policy").main(["--env", "simgrip/PickFragile-v7", "--policy", "observation",
                                            "--episodes", "3", "--seed", "8300", "--json"])
    assert json.loads(capsys.readouterr().out.strip()) == out
    ref = evaluate("simgrip/PickFragile-v7", "observation", list(range(8300, 8303)))
    assert out["outcomes"] == ref["outcomes"] and out["success_rate"] == ref["success_rate"]
    assert out["gamma"] == 0.99 and out["eval_seeds"] == [8300, 8302]
    assert out["mean_discounted_return"] < out["mean_return"]  # rewards are paid late in an episode


@pytest.mark.parametrize("argv, word", [
    (["--policy", "observation", "--gamma", "0"], "--gamma"),
    (["--policy", "observation", "--gamma", "x"], "--gamma"),
    (["--policy", "observation", "--action-offset", "-0.4", "0.2"], "--action-offset"),
    (["--policy", "observation", "--frame-stack", "2"], "--frame-stack"),
    (["--policy", "observation", "--frame-stack", "0"], "--frame-stack"),
    (["--policy", "psychic"], "--policy"),
    (["--model", "no/such/model.zip"], "--model"),
    ([], "--model"),
    (["--policy", "observation", "--episodes", "0"], "--episodes"),
    (["--policy", "observation", "--env-kwargs", "{\"w_nope\": 1}"], "--env-kwargs"),
])
def test_evaluate_policy_bad_options_exit_2_naming_them(argv, word, capsys):
    with pytest.raises(SystemExit) as e:
        _example("evaluate_policy").main(["--env", "simgrip/PickFragile-v7", *argv])
    assert e.value.code == 2
    assert word in capsys.readouterr().err


def test_evaluate_policy_runs_a_retired_id_as_it_was_registered(capsys):
    # the stored runs of docs/baselines/ were trained on ids retired since (v5: w_drop 5)
    from simgrip.envs.baselines import evaluate

    out = _example("evaluate_policy").main(["--env", "simgrip/PickFragile-v5", "--policy", "observation",
                                            "--episodes", "2", "--seed", "8300", "--json"])
    ref = evaluate("simgrip/PickFragile-v5", "observation", [8300, 8301])
    assert out["env"] == "simgrip/PickFragile-v5" and out["outcomes"] == ref["outcomes"]


@pytest.mark.parametrize("env_id, word", [("simgrip/Nope-v9", "--env"), ("simgrip/Pick-v1", "--policy")])
def test_evaluate_policy_refuses_an_env_without_that_controller(env_id, word, capsys):
    with pytest.raises(SystemExit) as e:
        _example("evaluate_policy").main(["--env", env_id, "--policy", "observation"])
    assert e.value.code == 2
    assert word in capsys.readouterr().err


def test_train_sb3_log_std_init_sets_ppos_start_and_says_so(tmp_path):
    """``--log-std-init -1``: the saved PPO policy's log standard deviations started at -1, and the JSON names the
    changed hyperparameter beside the discount's.  The run is one rollout (2048 steps) and one update: 10 epochs of
    32 minibatches, each an Adam step of at most about the learning rate 3e-4 per parameter, so the log standard
    deviations lie within 320 * 3e-4 = 0.096 of their start (the default start, 0, does not)."""
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO

    _example("train_sb3").main(["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--steps", "64",
                                "--log-std-init", "-1", "--gamma", "0.95", "--eval-episodes", "1",
                                "--eval-seed", "8310", "--out", str(tmp_path)])
    trained = json.loads((tmp_path / "ppo_eval.json").read_text())
    assert trained["hyperparameters"] == "Stable-Baselines3 defaults but gamma = 0.95, log_std_init = -1.0"
    log_std = PPO.load(tmp_path / "ppo_model.zip", device="cpu").policy.log_std.detach().numpy()
    assert trained["timesteps"] == 2048 and abs(log_std + 1.0).max() < 0.096, log_std


def test_train_sb3_eval_start_is_the_untrained_policy_and_leaves_the_training_alone(tmp_path):
    """``--eval-start``: ``start`` is the held-out evaluation of the policy PPO builds for this seed before any update
    (built again here, evaluated by the script's own ``evaluate``), and the training after it is the one a run
    without the option makes (same steps, same final evaluation: the deterministic evaluation draws no random
    numbers of the training's).  Behind ``--residual`` on every action the fresh policy is the scripted
    controller plus SB3's initial mean (near 0)."""
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    from simgrip.envs.env_options import EnvOptions, make_env

    mod = _example("train_sb3")
    common = ["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--steps", "64", "--seed", "3",
              "--residual", "curvature", "palm_z", "--log-std-init", "-1", "--eval-episodes", "2",
              "--eval-seed", "8320"]
    mod.main(common + ["--eval-start", "--out", str(tmp_path / "a")])
    mod.main(common + ["--out", str(tmp_path / "b")])
    a, b = (json.loads((tmp_path / k / "ppo_eval.json").read_text()) for k in "ab")
    res = ["curvature", "palm_z"]
    env = make_vec_env(lambda: make_env("simgrip/PickFragile-v7", EnvOptions(residual=res)), n_envs=1, seed=3)
    fresh = PPO("MlpPolicy", env, seed=3, verbose=0, **mod.model_kwargs("ppo", None, -1.0))
    ref = mod.evaluate(fresh, "simgrip/PickFragile-v7", 2, 8320, EnvOptions(residual=res))
    assert a["start"] == {k: ref[k] for k in ("success_rate", "mean_return", "mean_discounted_return", "outcomes")}
    assert "start" not in b
    assert {k: a[k] for k in ("timesteps", "success_rate", "mean_return")} == \
        {k: b[k] for k in ("timesteps", "success_rate", "mean_return")}


@pytest.mark.parametrize("budget_s", [30, 31])
def test_train_sb3_keeps_the_checkpoint_at_the_budgets_end(budget_s, tmp_path, monkeypatch, capsys):
    """A CPU clock that moves 1 s at each reading: whichever reading ends the budget, the checkpoint due at that
    moment is written, since the checkpoints and the stop read the clock once per step (two readings, one second
    apart, once let the stop pass the budget while the checkpoint had not: a run's last checkpoint was lost)."""
    pytest.importorskip("stable_baselines3")
    import itertools

    mod = _example("train_sb3")
    ticks = itertools.count()
    monkeypatch.setattr(mod.time, "process_time", lambda: float(next(ticks)))
    minutes = budget_s / 60.0
    mod.main(["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--minutes", f"{minutes!r}",
              "--checkpoint-minutes", f"{minutes / 2!r}", "--eval-episodes", "1", "--out", str(tmp_path)])
    res = json.loads((tmp_path / "ppo_eval.json").read_text())
    capsys.readouterr()
    assert [c["minutes"] for c in res["checkpoints"]] == [round(minutes / 2, 6), round(minutes, 6)]
    assert all((tmp_path / c["file"]).is_file() for c in res["checkpoints"])
    assert res["timesteps"] < 64  # the fake clock, not the steps, ended the run


@pytest.mark.parametrize("extra", [["--algo", "sac"], ["--algo", "ppo", "--init-from", "x.zip"],
                                   ["--algo", "ppo", "--log-std-init", "inf"]])
def test_train_sb3_log_std_init_refusals_exit_2(extra, tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        _example("train_sb3").main(["--env", "simgrip/PickFragile-v7", "--log-std-init", "-1", *extra,
                                    "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "--log-std-init" in capsys.readouterr().err.strip().splitlines()[-1]


def test_train_sb3_critic_warmup_holds_the_policy_then_trains_it(tmp_path):
    """``--critic-warmup 2048``: PPO's first rollout (2048 steps) with the actor frozen.  Stopped there
    (``--steps 2048``), the saved policy's actor is the fresh PPO's of that seed bit for bit and its value function
    is not; run on to 4096 steps the actor moves.  The JSON records the warm-up's steps and the update's fit."""
    pytest.importorskip("stable_baselines3")
    import torch
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    from simgrip.envs.critic_warmup import actor_parameters
    from simgrip.envs.env_options import make_env

    mod = _example("train_sb3")
    common = ["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--seed", "4", "--critic-warmup", "2048",
              "--eval-episodes", "1", "--eval-seed", "8330"]
    mod.main(common + ["--steps", "2048", "--out", str(tmp_path / "a")])
    mod.main(common + ["--steps", "4096", "--out", str(tmp_path / "b")])
    env = make_vec_env(lambda: make_env("simgrip/PickFragile-v7"), n_envs=1, seed=4)
    policy = PPO("MlpPolicy", env, seed=4, verbose=0).policy
    fresh = policy.state_dict()
    ids = {id(p) for p in actor_parameters(policy)}
    names = [n for n, p in policy.named_parameters() if id(p) in ids]
    for key, changed in (("a", False), ("b", True)):
        res = json.loads((tmp_path / key / "ppo_eval.json").read_text())
        warm = res["critic_warmup"]
        assert warm["timesteps"] == 2048 and len(warm["explained_variance"]) == len(warm["value_loss"]) == 1
        assert res["timesteps"] == (4096 if changed else 2048) and "critic warm-up" in res["wrapper"]
        saved = PPO.load(tmp_path / key / "ppo_model.zip").policy.state_dict()
        assert any(not torch.equal(saved[n], fresh[n]) for n in fresh if n.startswith("value_net."))
        assert all(torch.equal(saved[n], fresh[n]) for n in names) != changed


def test_train_sb3_critic_warmup_refusals_exit_2(tmp_path, capsys):
    with pytest.raises(SystemExit) as e:
        _example("train_sb3").main(["--env", "simgrip/PickFragile-v7", "--algo", "sac", "--critic-warmup", "2048",
                                    "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "--critic-warmup" in capsys.readouterr().err.strip().splitlines()[-1]
    with pytest.raises(SystemExit) as e:
        _example("train_sb3").main(["--algo", "ppo", "--critic-warmup", "-1", "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "--critic-warmup" in capsys.readouterr().err.strip().splitlines()[-1]


def test_evaluate_policy_model_reproduces_train_sb3s_evaluation(tmp_path, capsys):
    """A model evaluated again by evaluate_policy: the held-out figures train_sb3 wrote, digit for digit, at
    the discount it was trained with."""
    pytest.importorskip("stable_baselines3")
    _example("train_sb3").main(["--algo", "sac", "--env", "simgrip/PickFragile-v7", "--steps", "150",
                                "--action-offset", "-0.4", "0.2", "--gamma", "0.95", "--eval-episodes", "2",
                                "--frame-stack", "2", "--eval-seed", "8310", "--out", str(tmp_path)])
    trained = json.loads((tmp_path / "sac_eval.json").read_text())
    assert trained["hyperparameters"] == "Stable-Baselines3 defaults but gamma = 0.95" and trained["gamma"] == 0.95
    assert trained["frame_stack"] == 2 and "FrameStackObservation(2)" in trained["wrapper"]
    capsys.readouterr()
    again = _example("evaluate_policy").main([
        "--env", "simgrip/PickFragile-v7", "--model", str(tmp_path / "sac_model.zip"), "--algo", "sac",
        "--action-offset", "-0.4", "0.2", "--frame-stack", "2", "--episodes", "2", "--seed", "8310",
        "--gamma", "0.95", "--json"])
    for key in ("success_rate", "mean_return", "mean_length", "outcomes", "mean_success_length",
                "mean_discounted_return", "gamma", "eval_seeds"):
        assert again[key] == trained[key], key
    with pytest.raises(SystemExit) as e:  # without the stack it was trained on, the spaces differ
        _example("evaluate_policy").main(["--env", "simgrip/PickFragile-v7", "--model",
                                          str(tmp_path / "sac_model.zip"), "--algo", "sac",
                                          "--action-offset", "-0.4", "0.2"])
    assert e.value.code == 2 and "--frame-stack" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:  # the model's spaces against another env's
        _example("evaluate_policy").main(["--env", "simgrip/PlaceFragile-v4", "--model",
                                          str(tmp_path / "sac_model.zip"), "--algo", "sac"])
    assert e.value.code == 2 and "--model" in capsys.readouterr().err


def _trained_with_a_training_aid(module, tmp_path, env_id: str, steps: int, eval_seed: int, option: str,
                                 wrapper: str) -> dict:
    """Train SAC a few ``steps`` with the training-only ``option`` at 1 and check that its JSON records it and
    that its held-out evaluation is the plain task's (the saved model re-evaluated without the aid gives the
    same figures); returns the training's JSON."""
    from stable_baselines3 import SAC

    module.main(["--algo", "sac", "--env", env_id, "--steps", str(steps), option, "1", "--eval-episodes", "2",
                 "--eval-seed", str(eval_seed), "--out", str(tmp_path)])
    trained = json.loads((tmp_path / "sac_eval.json").read_text())
    assert trained[option[2:].replace("-", "_")] == 1.0 and trained["wrapper"] == f"{wrapper}(1.0) in training"
    again = module.evaluate(SAC.load(tmp_path / "sac_model.zip"), env_id, 2, eval_seed)
    for key in ("success_rate", "mean_return", "mean_length", "outcomes"):  # the held-out episodes: the plain task
        assert again[key] == trained[key], key
    return trained


def test_train_sb3_scripted_start_trains_from_scripted_states_and_evaluates_plainly(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    module = _example("train_sb3")
    _trained_with_a_training_aid(module, tmp_path, "simgrip/PlaceFragile-v8", 800, 8320, "--scripted-start",
                                 "ScriptedStart")
    with open(tmp_path / "sac_curve.csv") as fh:
        lengths = [int(row["length"]) for row in csv.DictReader(fh)]
    assert lengths and max(lengths) < 400  # every training episode started part-way (its limit: 400 steps)
    with pytest.raises(SystemExit) as e:
        module.main(["--algo", "sac", "--env", "simgrip/PlaceFragile-v8", "--scripted-start", "-0.1",
                     "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "--scripted-start" in capsys.readouterr().err
    capsys.readouterr()
    # where it has got to: evaluated from scripted starts, the outcomes per handover bin
    ev = _example("evaluate_policy")
    out = ev.main(["--env", "simgrip/PlaceFragile-v8", "--model", str(tmp_path / "sac_model.zip"), "--algo", "sac",
                   "--scripted-start", "1", "--episodes", "3", "--seed", "8320", "--json"])
    assert out["scripted_start"] == 1.0
    assert sum(sum(c.values()) for c in out["by_handover"].values()) == 3
    assert all(int(k.split("-")[1]) - int(k.split("-")[0]) == 49 for k in out["by_handover"])
    with pytest.raises(SystemExit) as e:
        ev.main(["--env", "simgrip/PlaceFragile-v8", "--policy", "observation", "--scripted-start", "1"])
    assert e.value.code == 2 and "--scripted-start" in capsys.readouterr().err


def test_by_handover_counts_outcomes_per_50_steps():
    from simgrip.envs.evaluation import EpisodeResult

    infos = [{"is_success": True}, {"crushed": True}, {"is_success": True}, {}]
    results = [EpisodeResult(i, i, 0.0, 1, info) for i, info in enumerate(infos)]
    assert _example("evaluate_policy").by_handover(results, [0, 49, 50, 120]) == {
        "0-49": {"crushed": 1, "success": 1}, "50-99": {"success": 1}, "100-149": {"timeout": 1}}


def test_by_mass_counts_outcomes_per_mass_bin():
    from simgrip.envs.evaluation import EpisodeResult

    infos = [{"is_success": True}, {"crushed": True}, {"is_success": True}, {}]
    results = [EpisodeResult(i, i, 0.0, 1, info) for i, info in enumerate(infos)]
    edges = [0.005, 0.02, 0.1, 0.25]
    assert _example("evaluate_policy").by_mass(results, [0.005, 0.0199, 0.02, 0.25], edges) == {
        "5-20 g": {"crushed": 1, "success": 1}, "20-100 g": {"success": 1}, "100-250 g": {"timeout": 1}}


def test_crushed_after_touch_bins_the_steps_from_first_touch_to_the_crush():
    from simgrip.envs.evaluation import EpisodeResult

    # (length, first touch step, info): crushed 0, 1, 4, 5, 24, 25 steps after the touch; a success and a
    # timeout are not counted
    eps = [(10, 10, {"crushed": True}), (10, 9, {"crushed": True}), (30, 26, {"crushed": True}),
           (30, 25, {"crushed": True}), (40, 16, {"crushed": True}), (40, 15, {"crushed": True}),
           (50, 3, {"is_success": True}), (300, None, {})]
    results = [EpisodeResult(i, i, 0.0, n, info) for i, (n, _, info) in enumerate(eps)]
    assert _example("evaluate_policy").crushed_after_touch(results, [touch for _, touch, _ in eps]) == {
        "0": 1, "1-4": 2, "5-24": 2, "25+": 1}


def test_crush_overrun_is_the_crushing_steps_relative_overrun_of_the_limit():
    from simgrip.envs.evaluation import EpisodeResult

    # crushed at 1.1 and 3 times the limit (the largest finger's force counts), a success and a timeout not
    infos = [{"crushed": True, "normal_force": [0.2, 1.1], "crush_limit": 1.0},
             {"crushed": True, "normal_force": [6.0, 1.0], "crush_limit": 2.0},
             {"is_success": True, "normal_force": [9.0, 9.0], "crush_limit": 1.0}, {}]
    results = [EpisodeResult(i, i, 0.0, 10, info) for i, info in enumerate(infos)]
    module = _example("evaluate_policy")
    got = module.crush_overrun(results)
    assert got["crushes"] == 2 and got["median"] == pytest.approx(1.05) and got["max"] == pytest.approx(2.0)
    assert module.crush_overrun(results[2:]) is None


def test_evaluate_policy_times_a_crush_from_the_first_touch(capsys):
    import gymnasium as gym

    module = _example("evaluate_policy")
    # the cradle controller crushes seed 8011's piece (and holds 8010's): counted once, in the bin of the steps
    # between the first step with a finger force within it and the crush, counted here by stepping the same
    # controller (v6 reads the peak: info["peak_normal_force"], the force that crushed it)
    out = module.main(["--env", "simgrip/PickCradleFragile-v6", "--policy", "observation", "--episodes", "2",
                       "--seed", "8010", "--json"])
    assert out["outcomes"] == {"crushed": 1, "success": 1}
    env = gym.make("simgrip/PickCradleFragile-v6")
    act, on_reset = module._scripted(env, "observation")
    obs, info = env.reset(seed=8011)
    on_reset(env, info, 8011)
    step, touch, done = 0, None, False
    while not done:
        obs, _, terminated, truncated, info = env.step(act(obs))
        step += 1
        if touch is None and max(info["peak_normal_force"]) > 0.0:
            touch = step
        done = terminated or truncated
    env.close()
    assert info["crushed"] and touch is not None
    gap = step - touch
    expected = {"0": gap == 0, "1-4": 1 <= gap <= 4, "5-24": 5 <= gap <= 24, "25+": gap >= 25}
    assert out["crushed_after_touch"] == {k: int(v) for k, v in expected.items()}
    limit = info["crush_limit"]  # the one crush's overrun, from the same crushing step
    x = (max(info["peak_normal_force"]) - limit) / limit
    assert x > 0.0 and out["crush_overrun"] == {"crushes": 1, "median": x, "max": x}
    assert out["crush_overrun"]["max"] > 0.0


def test_place_timeouts_count_the_carried_pieces_never_set_down():
    from simgrip.envs.evaluation import EpisodeResult

    up, tol = 0.03, 0.01
    infos = [{"carried": True, "workpiece_lift": up, "place_error": 0.004},  # hovering over the target
             {"carried": True, "workpiece_lift": up, "place_error": 0.02},  # hovering short of it
             {"carried": True, "workpiece_lift": 0.002, "place_error": 0.004},  # down on it, timed out placing
             {"carried": False, "workpiece_lift": up, "place_error": 0.004},  # lifted, never carried
             {"carried": True, "workpiece_lift": up, "place_error": 0.004, "crushed": True},  # lost
             {"carried": True, "workpiece_lift": 0.001, "place_error": 0.0, "is_success": True}]
    results = [EpisodeResult(i, i, 0.0, 1, info) for i, info in enumerate(infos)]
    assert _example("evaluate_policy").place_timeouts(results, tol, 0.003) == {"held_up": 2, "over_target": 1}
    # carried at some step, and how each of those ended (the fourth never was)
    assert _example("evaluate_policy").carried(results) == {
        "episodes": 5, "outcomes": {"crushed": 1, "success": 1, "timeout": 3}}
    assert _example("evaluate_policy").carried(results[3:4]) == {"episodes": 0, "outcomes": {}}


def test_evaluate_policy_counts_the_places_hovering_timeouts(capsys):
    # the observation-only controller sets every piece of these seeds down: none held up at the end
    out = _example("evaluate_policy").main(["--env", "simgrip/PlaceFragile-v8", "--policy", "observation",
                                            "--episodes", "2", "--seed", "8004", "--json"])
    assert out["place_timeouts"] == {"held_up": 0, "over_target": 0} and out["success_rate"] == 1.0
    assert out["carried"] == {"episodes": 2, "outcomes": {"success": 2}}  # a place is carried first
    pinch = _example("evaluate_policy").main(["--env", "simgrip/PickFragile-v7", "--policy", "observation",
                                              "--episodes", "1", "--seed", "8004", "--json"])
    assert "place_timeouts" not in pinch and "carried" not in pinch


def test_evaluate_policy_counts_a_fragile_tasks_outcomes_by_hidden_mass(capsys):
    import gymnasium as gym

    from simgrip.envs.light_bias import episode_mass, mass_bins

    out = _example("evaluate_policy").main(["--env", "simgrip/PickMultiFragile-v7", "--policy", "observation",
                                            "--episodes", "3", "--seed", "8330", "--json"])
    env = gym.make("simgrip/PickMultiFragile-v7")
    edges = mass_bins(env)
    masses = []
    for seed in (8330, 8331, 8332):
        env.reset(seed=seed)
        masses.append(episode_mass(env))
    env.close()
    assert edges[0] == 0.005 and edges[-1] == 0.25 and len(out["by_mass"]) == 3
    expected = [sum(lo <= m < hi or (i == 2 and m == hi) for m in masses)
                for i, (lo, hi) in enumerate(zip(edges[:-1], edges[1:]))]
    assert [sum(c.values()) for c in out["by_mass"].values()] == expected


def test_train_sb3_light_bias_trains_on_light_pieces_and_evaluates_on_the_task(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")

    module = _example("train_sb3")
    _trained_with_a_training_aid(module, tmp_path, "simgrip/PickMultiFragile-v7", 300, 8340, "--light-bias",
                                 "LightBias")
    with pytest.raises(SystemExit) as e:
        module.main(["--algo", "sac", "--env", "simgrip/PickMultiFragile-v7", "--light-bias", "1.5",
                     "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "--light-bias" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()

"""``PrivilegedObservation``, ``AsymmetricActorCriticPolicy`` and ``--privileged-critic``
(simgrip.envs.privileged_critic): PPO's value function reads the hidden workpiece, its policy does not.

References: the task itself (the wrapped observation's first entries are the task's, bit for bit, over whole
episodes), the module's table computed here from the task's hidden attributes and the step's ``info``, and the
optimiser's arithmetic (Adam moves a weight only where its gradient is nonzero, so the policy's first-layer weights
on the hidden entries must end PPO's updates exactly where they started, and the critic's must not).
"""

import math

import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs.budget_replay import OPTION_KEYS
from simgrip.envs.env_options import EnvOptions, make_env
from simgrip.envs.privileged_critic import N_PRIVILEGED, NEAR_MAX, PrivilegedObservation, policy_for
from helpers import assert_passes_flag, load_example, train_and_evaluate_again

CRADLE, SPHERE, PLACE = "simgrip/PickCradleFragile-v6", "simgrip/PickSphereFragile-v6", "simgrip/PlaceFragile-v8"
AIDS = dict(action_offset=(-0.4, 0.0), residual=("palm_z",))


def _expected(task, info) -> list:
    """The module's table from the task's hidden hold force and crush limit and the step's largest read force."""
    hold, crush = task.hold_force, task.crush_limit
    force = 0.0 if info is None else max(np.asarray(info.get("peak_normal_force", info["normal_force"])).tolist())
    return [math.log(crush / hold), math.log1p(hold / task._force_unit), min(force / crush, NEAR_MAX),
            math.log1p(force / hold)]


@pytest.mark.parametrize("env_id, options", [
    (CRADLE, AIDS), (SPHERE, dict(action_offset=(-0.4,), residual=("palm_z",), residual_alone=True)),
    (PLACE, dict(action_offset=(-0.4, 0.0, 0.0), residual=("palm_x", "palm_z")))])
def test_the_task_is_unchanged_and_the_entries_follow_the_table(env_id, options):
    wrapped = make_env(env_id, EnvOptions(privileged_critic=True, **options))
    plain = make_env(env_id, EnvOptions(**options))
    n = plain.observation_space.shape[0]
    assert wrapped.observation_space.shape == (n + N_PRIVILEGED,)
    task = wrapped.unwrapped
    touched = crushed_or_near = 0
    for seed in (8003, 8011, 8017):
        rng = np.random.default_rng(seed)
        (ow, _), (op, _) = wrapped.reset(seed=seed), plain.reset(seed=seed)
        assert np.array_equal(ow[:n], op) and ow.dtype == op.dtype
        assert np.allclose(ow[n:], _expected(task, None), rtol=1e-6)
        while True:
            a = np.clip(rng.normal(0.0, 0.5, wrapped.action_space.shape), -1, 1).astype(np.float32)
            (ow, rw, tw, uw, iw), (op, rp, tp, up, ip) = wrapped.step(a), plain.step(a)
            assert np.array_equal(ow[:n], op) and (rw, tw, uw) == (rp, tp, up)
            assert np.allclose(ow[n:], _expected(task, iw), rtol=1e-6, atol=0)
            assert wrapped.observation_space.contains(ow)
            touched += ow[n + 2] > 0
            crushed_or_near += ow[n + 2] > 0.5
            if tw or uw:
                break
    assert touched > 10 and crushed_or_near > 0  # the force entries were exercised, not only the zeros
    wrapped.close(), plain.close()


def _model(env, **kwargs):
    from stable_baselines3 import PPO

    return PPO(policy_for(EnvOptions(privileged_critic=True)), env, seed=3, n_steps=128, batch_size=64,
               policy_kwargs={"log_std_init": -1.0}, **kwargs)


def test_the_policy_ignores_the_hidden_entries_and_the_critic_reads_them():
    pytest.importorskip("stable_baselines3")
    import torch as th

    env = make_env(CRADLE, EnvOptions(privileged_critic=True, **AIDS))
    model = _model(env)
    pi0 = model.policy.mlp_extractor.policy_net[0].weight.detach().clone()
    vf0 = model.policy.mlp_extractor.value_net[0].weight.detach().clone()
    model.learn(256)  # two updates of 10 epochs
    pi1 = model.policy.mlp_extractor.policy_net[0].weight.detach()
    vf1 = model.policy.mlp_extractor.value_net[0].weight.detach()
    k = N_PRIVILEGED
    assert th.equal(pi1[:, -k:], pi0[:, -k:])  # no gradient reached them: Adam leaves them where they began
    assert not th.equal(pi1[:, :-k], pi0[:, :-k])  # the policy did learn, on the task's own entries
    assert not th.equal(vf1[:, -k:], vf0[:, -k:])  # the critic learned from the hidden ones
    rng = np.random.default_rng(0)
    obs = np.stack([env.observation_space.sample() for _ in range(8)]).clip(-3, 3).astype(np.float32)
    other = obs.copy()
    other[:, -k:] = rng.uniform(0, 5, (8, k))
    assert np.array_equal(model.predict(obs, deterministic=True)[0], model.predict(other, deterministic=True)[0])
    with th.no_grad():
        d0 = model.policy.get_distribution(th.as_tensor(obs)).distribution
        d1 = model.policy.get_distribution(th.as_tensor(other)).distribution
        assert th.equal(d0.mean, d1.mean) and th.equal(d0.stddev, d1.stddev)
        v0, v1 = model.policy.predict_values(th.as_tensor(obs)), model.policy.predict_values(th.as_tensor(other))
    assert not th.equal(v0, v1)
    env.close()


def test_a_saved_model_loads_as_the_same_asymmetric_policy(tmp_path):
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO

    env = make_env(CRADLE, EnvOptions(privileged_critic=True, **AIDS))
    model = _model(env)
    model.learn(128)
    model.save(tmp_path / "m.zip")
    again = PPO.load(tmp_path / "m.zip", device="cpu")
    assert type(again.policy).__name__ == "AsymmetricActorCriticPolicy" and not again.policy.share_features_extractor
    obs = np.stack([env.observation_space.sample() for _ in range(4)]).clip(-3, 3).astype(np.float32)
    assert np.array_equal(model.predict(obs, deterministic=True)[0], again.predict(obs, deterministic=True)[0])
    env.close()


def test_make_env_records_it_and_refuses_what_it_cannot_give():
    keys, wrappers = EnvOptions(privileged_critic=True).record()
    assert keys == {"privileged_critic": True} and wrappers == ["PrivilegedObservation (the critic's)"]
    assert "privileged_critic" not in EnvOptions().record()[0] and "privileged_critic" in OPTION_KEYS
    assert policy_for(EnvOptions()) == "MlpPolicy" and policy_for(None) == "MlpPolicy"
    with pytest.raises(ValueError, match="--privileged-critic: env: PickEnv is not a fragile task"):
        make_env("simgrip/Pick-v1", EnvOptions(privileged_critic=True))
    with pytest.raises(ValueError, match="--privileged-critic: not with --frame-stack"):
        make_env(CRADLE, EnvOptions(privileged_critic=True, frame_stack=2))
    env = make_env(CRADLE, EnvOptions(privileged_critic=True, frame_stack=1))  # 1: no stack
    assert isinstance(env, PrivilegedObservation)
    env.close()


def test_train_sb3_records_it_and_evaluate_policy_gives_its_figures_again(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    options = ["--action-offset", "-0.4", "0", "--residual", "palm_z", "--privileged-critic"]
    train, ev, rec, again = train_and_evaluate_again(CRADLE, options, tmp_path, "_privileged")
    capsys.readouterr()
    assert rec["privileged_critic"] is True and "PrivilegedObservation (the critic's)" in rec["wrapper"]
    assert again["privileged_critic"] is True
    for key in ("success_rate", "mean_return", "mean_length", "outcomes"):
        assert again[key] == rec[key], key
    with pytest.raises(SystemExit) as e:  # without the wrapper the model's observation does not fit
        ev.main(["--env", CRADLE, "--model", str(tmp_path / "ppo_model.zip"), *options[:-1], "--episodes", "1"])
    assert e.value.code == 2 and "--privileged-critic?" in capsys.readouterr().err
    for argv, why in ((["--algo", "sac", "--privileged-critic"], "--privileged-critic: PPO only"),
                      (["--algo", "ppo", "--privileged-critic", "--init-from", str(tmp_path / "ppo_model.zip")],
                       "--privileged-critic: not with --init-from"),
                      (["--algo", "ppo", "--privileged-critic", "--frame-stack", "2"], "not with --frame-stack")):
        with pytest.raises(SystemExit) as e:
            train.main(["--env", CRADLE, *argv, "--out", str(tmp_path / "o")])
        assert e.value.code == 2 and why in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        train.main(["--algo", "ppo", "--env", "simgrip/Pick-v1", "--privileged-critic", "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "not a fragile task" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        ev.main(["--env", CRADLE, "--policy", "observation", "--privileged-critic"])
    assert e.value.code == 2 and "--privileged-critic: only with --model" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_rl_baselines_passes_it_to_every_run_and_refuses_sac(tmp_path):
    mod = load_example("rl_baselines", "_privileged")
    assert_passes_flag(mod, CRADLE, "privileged_critic", tmp_path / "run")
    with pytest.raises(SystemExit) as e:
        mod.main(["--env", CRADLE, "--algo", "sac", "--privileged-critic", "--seeds", "0", "--minutes", "1",
                  "--eval-seeds", "8000-8001", "--out", str(tmp_path / "o")])
    assert e.value.code == 2


def test_rl_baselines_aggregate_names_the_options_as_each_run_records_them(tmp_path):
    pytest.importorskip("stable_baselines3")
    import json
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    out = tmp_path / "runs"
    cmd = [sys.executable, str(root / "examples" / "rl_baselines.py"), "--env", CRADLE, "--algo", "ppo", "--seeds",
           "0", "--steps", "64", "--minutes", "1", "--eval-seeds", "8000-8000", "--jobs", "1",
           "--action-offset", "-0.4", "0", "--residual", "palm_z", "--light-bias", "0.5", "--privileged-critic",
           "--out", str(out)]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300, cwd=root)
    assert r.returncode == 0, r.stderr[-2000:]
    agg = json.loads((out / "aggregate.json").read_text())
    run = json.loads((out / "ppo_seed0" / "ppo_eval.json").read_text())
    keys = ("action_offset", "residual", "light_bias", "privileged_critic")
    assert {k: agg[k] for k in keys} == {k: run[k] for k in keys} == {
        "action_offset": [-0.4, 0.0], "residual": ["palm_z"], "light_bias": 0.5, "privileged_critic": True}
    assert not {"env_kwargs", "valve_share", "residual_alone", "frame_stack"} & set(agg)

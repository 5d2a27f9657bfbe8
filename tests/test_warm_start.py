"""simgrip.envs.warm_start: a PPO policy copied into another task's PPO by observation and action names.

The reference is the source policy itself: on a target observation, the copied policy's mean of each shared
action and its value equal the source's on the same named entries, and a new action's mean is 0 with PPO's
initial standard deviation 1. Equal up to float32 rounding: the first layer's sums gain terms that are exactly 0
but may be added in another order (a 64-wide float32 layer; 1e-5 is ~100 ulp of the O(1) activations).
"""

from __future__ import annotations

import json

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from helpers import load_example, rl_baselines_args
from simgrip.envs.warm_start import action_names, check_source, plan_transfer, source_record, transfer_ppo

try:  # the plan and the checks need neither; the copies need the rl extra
    import stable_baselines3 as sb3
    import torch
except ImportError:
    sb3 = torch = None
needs_sb3 = pytest.mark.skipif(sb3 is None, reason='needs the rl extra: pip install ".[rl]"')

PINCH, PLACE = "simgrip/PickFragile-v7", "simgrip/PlaceFragile-v8"
TOL = 1e-5


def _ppo(env, seed, jitter=0.0):
    model = sb3.PPO("MlpPolicy", env, seed=seed, device="cpu")
    if jitter:  # a policy unlike PPO's initial one: every weight and the log std moved
        gen = torch.Generator().manual_seed(seed)
        with torch.no_grad():
            for p in model.policy.parameters():
                p.add_(jitter * torch.randn(p.shape, generator=gen))
    return model


def _mean_std_value(model, obs):
    t = model.policy.obs_to_tensor(np.asarray(obs, dtype=np.float32))[0]
    with torch.no_grad():
        dist = model.policy.get_distribution(t).distribution
        return dist.mean.numpy(), dist.stddev.numpy(), model.policy.predict_values(t).numpy()[:, 0]


def _place_obs(n=32, seed=0):
    """Observations of the place's 21 entries, O(1) each."""
    return np.random.default_rng(seed).normal(size=(n, 21))


@needs_sb3
def test_the_pinch_policy_acts_in_the_place_as_on_the_pinch():
    pinch, place = gym.make(PINCH), gym.make(PLACE)
    src, dst = _ppo(pinch, 0, jitter=0.3), _ppo(place, 1)
    plan = plan_transfer(pinch, place)
    assert plan.new_obs == ("workpiece_x", "target_x") and plan.new_actions == ("palm_x",)
    assert action_names(pinch) == ("curvature", "palm_z") and action_names(place) == ("curvature", "palm_x", "palm_z")
    transfer_ppo(src, dst, plan)
    obs = _place_obs()
    m_src, s_src, v_src = _mean_std_value(src, obs[:, :19])  # the place's first 19 entries are the pinch's
    m_dst, s_dst, v_dst = _mean_std_value(dst, obs)
    assert np.max(np.abs(m_dst[:, [0, 2]] - m_src)) < TOL and np.max(np.abs(v_dst - v_src)) < TOL
    assert np.all(m_dst[:, 1] == 0.0) and np.all(s_dst[:, 1] == 1.0)
    assert np.array_equal(s_dst[:, [0, 2]], s_src)
    # the new entries do nothing yet: moving the workpiece and the target changes no action
    moved = obs.copy()
    moved[:, 19:] += 3.0
    assert np.max(np.abs(_mean_std_value(dst, moved)[0] - m_dst)) == 0.0


@needs_sb3
def test_a_task_to_itself_copies_every_weight():
    pinch = gym.make(PINCH)
    src, dst = _ppo(pinch, 0, jitter=0.3), _ppo(pinch, 1)
    plan = plan_transfer(pinch, pinch)
    assert plan.new_obs == () and plan.new_actions == () and len(plan.obs_pairs) == 19
    transfer_ppo(src, dst, plan)
    for (k, a), (_, b) in zip(src.policy.state_dict().items(), dst.policy.state_dict().items()):
        assert torch.equal(a, b), k


@needs_sb3
def test_what_cannot_be_transferred_is_refused():
    pinch, place = gym.make(PINCH), gym.make(PLACE)
    stacked = gym.wrappers.FrameStackObservation(gym.make(PINCH), 2)
    with pytest.raises(ValueError, match="frame stack"):
        plan_transfer(stacked, pinch)
    nameless = gym.make("CartPole-v1")
    with pytest.raises(ValueError, match="action_names"):
        action_names(nameless)
    with pytest.raises(ValueError, match="PPO"):
        transfer_ppo(sb3.SAC("MlpPolicy", pinch, device="cpu"), _ppo(place, 0), plan_transfer(pinch, place))
    with pytest.raises(ValueError, match="spaces"):
        transfer_ppo(_ppo(pinch, 0), _ppo(pinch, 1), plan_transfer(pinch, place))


def test_the_plan_matches_entries_and_actions_by_name():
    pinch, place = gym.make(PINCH), gym.make(PLACE)
    plan = plan_transfer(pinch, place, [-0.4, 0.2], [0.0, 0.0, 0.1])
    slices = place.unwrapped.obs_slices
    assert plan.obs_pairs == tuple((k, k) for k in range(19)) and slices["target_x"].start == 20
    assert plan.act_pairs == ((0, 0), (2, 1)) and plan.bias_shift == (-0.4, 0.0, 0.1)
    assert plan.new_obs == ("workpiece_x", "target_x") and plan.new_actions == ("palm_x",)
    assert (plan.n_obs, plan.n_actions, plan.source_shape) == (21, 3, (19, 2))
    back = plan_transfer(place, pinch)  # the other way: the place's extra entries and action dropped
    assert back.new_obs == () and back.act_pairs == ((0, 0), (1, 2)) and back.n_obs == 19
    with pytest.raises(ValueError, match="frame stack"):
        plan_transfer(gym.wrappers.FrameStackObservation(gym.make(PINCH), 2), pinch)
    with pytest.raises(ValueError, match="obs_layout"):
        plan_transfer(gym.make("CartPole-v1"), pinch)
    with pytest.raises(ValueError, match="--action-offset"):
        plan_transfer(pinch, place, [-0.4], None)


def test_check_source_names_the_option():
    rec = {"algo": "PPO", "env": PINCH, "action_offset": [-0.4, 0.2]}
    check_source(rec)
    with pytest.raises(ValueError, match="--normalize"):
        check_source(rec, normalize=True)
    with pytest.raises(ValueError, match="--normalize"):
        check_source({**rec, "wrapper": "VecNormalize (SB3 defaults: observation and return)"})
    with pytest.raises(ValueError, match="--frame-stack"):
        check_source({**rec, "frame_stack": 2})
    with pytest.raises(ValueError, match="--frame-stack"):
        check_source(rec, frame_stack=3)


@needs_sb3
def test_a_different_action_offset_is_absorbed_into_the_bias():
    """The pinch trained behind the probe offset, the place behind none or another: the env performs the same
    motion, ``clip(mean + offset)``, wherever both runs' means lie within the bounds (SB3 clips there first)."""
    pinch, place = gym.make(PINCH), gym.make(PLACE)
    src = _ppo(pinch, 0, jitter=0.05)
    obs = _place_obs(seed=2)
    m_src = _mean_std_value(src, obs[:, :19])[0]
    inside = np.all(np.abs(m_src) <= 1.0, axis=1)
    assert inside.sum() >= 16  # the comparison covers most of the sample
    for src_off, dst_off in (([-0.4, 0.2], None), ([-0.4, 0.2], [0.3, 0.5, -0.1]), (None, [-0.4, 0.0, 0.2])):
        dst = _ppo(place, 1)
        plan = plan_transfer(pinch, place, src_off, dst_off)
        transfer_ppo(src, dst, plan)
        m_dst = _mean_std_value(dst, obs)[0]
        so = np.zeros(2) if src_off is None else np.asarray(src_off)
        do = np.zeros(3) if dst_off is None else np.asarray(dst_off)
        env_src = np.clip(np.clip(m_src, -1, 1) + so, -1, 1)
        env_dst = np.clip(np.clip(m_dst, -1, 1) + do, -1, 1)
        both = inside & np.all(np.abs(m_dst) <= 1.0, axis=1)
        assert both.sum() >= 8
        assert np.max(np.abs(env_dst[both][:, [0, 2]] - env_src[both])) < TOL
        assert np.all(m_dst[:, 1] == 0.0)  # the new action: the target's own offset's motion
    with pytest.raises(ValueError, match="--action-offset"):
        plan_transfer(pinch, place, [-0.4], None)


def test_source_record_needs_the_model_and_its_record(tmp_path):
    with pytest.raises(ValueError, match="--init-from: no model file"):
        source_record(tmp_path / "ppo_model.zip")
    (tmp_path / "ppo_model.zip").write_bytes(b"")
    with pytest.raises(ValueError, match="ppo_eval.json"):
        source_record(tmp_path / "ppo_model.zip")
    (tmp_path / "ppo_eval.json").write_text(json.dumps({"algo": "SAC", "env": PINCH}))
    with pytest.raises(ValueError, match="not a PPO run"):
        source_record(tmp_path / "ppo_model.zip")


@needs_sb3
def test_train_sb3_starts_the_place_from_the_pinch(tmp_path, capsys):
    """End to end: a budget too small for one PPO update, so the saved place model is the copy itself."""
    train = load_example("train_sb3", "_ws")
    src_dir, dst_dir = tmp_path / "pinch", tmp_path / "place"
    common = ["--algo", "ppo", "--minutes", "0.001", "--eval-episodes", "1"]
    train.main([*common, "--env", PINCH, "--action-offset", "-0.4", "0.2", "--out", str(src_dir)])
    train.main([*common, "--env", PLACE, "--action-offset", "-0.4", "0", "0.2", "--init-from",
                str(src_dir / "ppo_model.zip"), "--out", str(dst_dir)])
    rec = json.loads((dst_dir / "ppo_eval.json").read_text())
    src_rec = json.loads((src_dir / "ppo_eval.json").read_text())
    assert rec["init_from"]["env"] == PINCH and rec["init_from"]["new_actions"] == ["palm_x"]
    # the copy before any update, on the same held-out episode as the trained policy: here the same policy
    assert rec["init_from"]["eval"] == {k: rec[k] for k in ("success_rate", "mean_return", "outcomes")}
    assert rec["cpu_s_with_init"] == pytest.approx(rec["cpu_s"] + src_rec["cpu_s"], abs=0.11)
    assert "warm start" in rec["wrapper"]
    src, dst = sb3.PPO.load(src_dir / "ppo_model.zip"), sb3.PPO.load(dst_dir / "ppo_model.zip")
    assert dst.num_timesteps < dst.n_steps  # no update happened
    obs = _place_obs(seed=1)
    m_src, _, v_src = _mean_std_value(src, obs[:, :19])
    m_dst, _, v_dst = _mean_std_value(dst, obs)
    assert np.max(np.abs(m_dst[:, [0, 2]] - m_src)) < TOL and np.max(np.abs(v_dst - v_src)) < TOL
    capsys.readouterr()


@needs_sb3
@pytest.mark.parametrize("extra, word", [
    (["--algo", "sac"], "PPO only"),
    (["--action-offset", "-0.4", "0", "0.2", "--frame-stack", "2"], "--frame-stack"),
    (["--normalize"], "--normalize"),
])
def test_train_sb3_refuses_a_source_it_cannot_start_from(extra, word, tmp_path, capsys):
    train = load_example("train_sb3", "_ws2")
    src_dir = tmp_path / "pinch"
    src_dir.mkdir()
    (src_dir / "ppo_model.zip").write_bytes(b"")
    (src_dir / "ppo_eval.json").write_text(json.dumps({"algo": "PPO", "env": PINCH, "action_offset": [-0.4, 0.2]}))
    argv = ["--env", PLACE, "--init-from", str(src_dir / "ppo_model.zip"), "--out", str(tmp_path / "o"), *extra]
    if "--algo" not in extra:
        argv = ["--algo", "ppo", *argv]
    with pytest.raises(SystemExit) as e:
        train.main(argv)
    err = capsys.readouterr().err
    assert e.value.code == 2 and word in err and len(err.strip().splitlines()[-1]) > 0
    assert not (tmp_path / "o").exists()


@needs_sb3
def test_a_model_that_is_not_its_records_is_refused(tmp_path, capsys):
    """A file that is no PPO model, and a PPO model of another env than its record names: exit 2, no training."""
    train = load_example("train_sb3", "_ws3")
    src_dir = tmp_path / "pinch"
    src_dir.mkdir()
    (src_dir / "ppo_eval.json").write_text(json.dumps({"algo": "PPO", "env": PINCH}))
    argv = ["--algo", "ppo", "--env", PLACE, "--init-from", str(src_dir / "ppo_model.zip"),
            "--out", str(tmp_path / "o")]
    (src_dir / "ppo_model.zip").write_bytes(b"PK not a model")
    with pytest.raises(SystemExit) as e:
        train.main(argv)
    assert e.value.code == 2 and "cannot load" in capsys.readouterr().err
    _ppo(gym.make(PLACE), 0).save(src_dir / "ppo_model.zip")  # the place's own model under the pinch's record
    with pytest.raises(SystemExit) as e:
        train.main(argv)
    assert e.value.code == 2 and "not of the env its record names" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


@needs_sb3
def test_rl_baselines_starts_each_seed_from_its_own_source(tmp_path, capsys):
    mod = load_example("rl_baselines", "_ws")
    src = tmp_path / "pinch"
    for seed in (0, 1):
        (src / f"ppo_seed{seed}").mkdir(parents=True)
        _ppo(gym.make(PINCH), seed).save(src / f"ppo_seed{seed}" / "ppo_model.zip")
        (src / f"ppo_seed{seed}" / "ppo_eval.json").write_text(
            json.dumps({"algo": "PPO", "env": PINCH, "action_offset": [-0.4, 0.2], "seed": seed}))
    args = rl_baselines_args(mod, PLACE, action_offset=[-0.4, 0.0, 0.2], init_from=str(src))
    cmd = mod.run_command("ppo", 1, args, tmp_path / "run")
    assert cmd[cmd.index("--init-from") + 1] == str(src / "ppo_seed1" / "ppo_model.zip")
    base = ["--env", PLACE, "--algo", "ppo", "--action-offset", "-0.4", "0", "0.2", "--init-from", str(src),
            "--out", str(tmp_path / "o")]
    with pytest.raises(SystemExit) as e:  # seed 2 has no source run
        mod.main([*base, "--seeds", "0", "1", "2"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and "--init-from" in err and "seed 2" in err
    with pytest.raises(SystemExit) as e:
        mod.main([*base[:-2], "--algo", "ppo", "sac", "--seeds", "0", "--out", str(tmp_path / "o")])
    assert e.value.code == 2 and "PPO only" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()

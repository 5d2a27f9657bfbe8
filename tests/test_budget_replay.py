"""A recorded run replayed in steps (simgrip.envs.budget_replay; train_sb3.py and rl_baselines.py --replay)."""

from __future__ import annotations

import json
import math

import pytest

from helpers import load_example as _example, rl_baselines_args
from simgrip.envs.budget_replay import IDENTITY_KEYS, ReplaySchedule, compare, load_schedule, policy_digest, versions

IDENTITY = {"algo": "ppo", "env": "simgrip/PickFragile-v7", "seed": 0, "clock": "cpu", "budget_minutes": 15.0,
            "hyperparameters": "Stable-Baselines3 defaults but gamma = 0.995", "eval_seeds": [8000, 8049],
            "n_envs": 1, "action_offset": [-0.2, 0.2]}


def _record(**changes) -> dict:
    rec = {**{k: v for k, v in IDENTITY.items() if k != "n_envs"}, "algo": "PPO", "timesteps": 9000,
           "cpu_s": 900.0, "wall_s": 950.0, "success_rate": 0.8, "mean_return": 20.5, "outcomes": {"success": 40},
           "checkpoints": [{"minutes": 5.0, "timesteps": 3000, "success_rate": 0.5, "mean_return": 10.0},
                           {"minutes": 10.0, "timesteps": 6100, "success_rate": 0.7, "mean_return": 15.0},
                           {"minutes": 15.0, "timesteps": 9000, "success_rate": 0.8, "mean_return": 20.5}],
           "returncode": 0}
    rec.update(changes)
    return {k: v for k, v in rec.items() if v is not None}


def _write(tmp_path, rec, name="ppo_seed0.json"):
    path = tmp_path / name
    path.write_text(json.dumps(rec))
    return path


def test_the_clock_reads_each_decision_s_time_at_its_step_and_less_before_it():
    s = ReplaySchedule(((0, 0.0), (3000, 300.0), (6100, 600.0), (9000, 900.0), (9000, 900.0)), 900.0, "r", {})
    assert s.timesteps == 9000
    assert [s.seconds(n) for n in (0, 3000, 6100, 9000, 12000)] == [0.0, 300.0, 600.0, 900.0, 900.0]
    # one step short of a decision: below its threshold, so the run decides exactly where the record did
    assert s.seconds(2999) < 300.0 and s.seconds(6099) < 600.0 and s.seconds(8999) < 900.0
    assert s.seconds(1500) == 150.0 and s.seconds(4550) == 450.0  # linear in between
    times = [s.seconds(n) for n in range(0, 9001, 7)]
    assert times == sorted(times)
    # two checkpoints at one step (a long pause in the record): the later one's time there, less one step before
    s2 = ReplaySchedule(((0, 0.0), (10, 60.0), (10, 120.0), (20, 180.0)), 180.0, "r", {})
    assert s2.seconds(10) == 120.0 and s2.seconds(9) < 60.0 and 120.0 < s2.seconds(15) < 180.0
    # a steep segment: the time just short of the next decision stays below it (never rounded up onto it)
    s3 = ReplaySchedule(((0, 0.0), (2**60, 900.0)), 900.0, "r", {})  # (2**60 - 1) / 2**60 rounds to 1.0
    assert s3.seconds(2**60 - 1) == math.nextafter(900.0, -math.inf)


def test_a_matching_record_gives_its_steps_as_anchors(tmp_path):
    s = load_schedule(_write(tmp_path, _record()), IDENTITY, checkpoint_minutes=5.0)
    assert s.anchors == ((0, 0.0), (3000, 300.0), (6100, 600.0), (9000, 900.0), (9000, 900.0))
    assert s.budget_s == 900.0 and s.record["success_rate"] == 0.8
    # a wall-clock record is stopped by its wall time
    rec = _record(clock="wall", cpu_s=100.0, wall_s=900.1)
    assert load_schedule(_write(tmp_path, rec), {**IDENTITY, "clock": "wall"}, checkpoint_minutes=5.0).timesteps == 9000


@pytest.mark.parametrize("key,value", [
    ("algo", "SAC"), ("env", "simgrip/PickMultiFragile-v7"), ("seed", 1), ("clock", "wall"), ("budget_minutes", 30.0),
    ("hyperparameters", "Stable-Baselines3 defaults"), ("eval_seeds", [1000, 1049]), ("action_offset", [-0.4, 0.2]),
    ("action_offset", None), ("light_bias", 0.5), ("n_envs", 4),
])
def test_a_record_of_another_experiment_is_refused_naming_the_field(tmp_path, key, value):
    path = _write(tmp_path, _record(**{key: value}))
    with pytest.raises(ValueError, match=f"--replay: the record's {key} is"):
        load_schedule(path, IDENTITY, checkpoint_minutes=5.0)
    assert set(IDENTITY_KEYS) <= set(IDENTITY)


@pytest.mark.parametrize("rec,kw,why", [
    (_record(), {"lr_decay": True}, "--lr-decay cannot be replayed from .*: it does not keep"),
    (_record(lr_fractions=[]), {"lr_decay": True}, "--lr-decay cannot be replayed"),
    (_record(lr_fractions=[1.0, 0.5, 1.5]), {"lr_decay": True}, "--lr-decay cannot be replayed"),
    (_record(lr_fractions=[1.0, True]), {"lr_decay": True}, "--lr-decay cannot be replayed"),
    (_record(), {"selection": True}, "--select-every cannot be replayed"),
    (_record(selection={"every_minutes": 1.0}), {}, "validated within its budget"),
    (_record(returncode=1), {}, "records no finished run"),
    (_record(success_rate=None), {}, "records no finished run"),
    (_record(cpu_s=400.0), {}, "stopped by its step cap at 9000 steps"),
    (_record(), {"checkpoint_minutes": 3.0}, "checkpoints are at [5.0, 10.0, 15.0] minutes"),
    (_record(), {"checkpoint_minutes": None}, "checkpoints are at"),
    (_record(checkpoints=None), {"checkpoint_minutes": 5.0}, "the record has no checkpoints"),
    (_record(checkpoints=[{"minutes": 5.0, "timesteps": 7000}, {"minutes": 10.0, "timesteps": 6000}]),
     {"checkpoint_minutes": 5.0}, "out of order"),
])
def test_what_cannot_be_replayed_is_refused_saying_why(tmp_path, rec, kw, why):
    kw = {"checkpoint_minutes": 5.0, **kw}
    with pytest.raises(ValueError, match="--replay: .*" + why.replace("[", r"\[").replace("]", r"\]")):
        load_schedule(_write(tmp_path, rec), IDENTITY, **kw)


def test_a_decaying_rate_is_replayed_from_the_readings_its_record_kept(tmp_path):
    s = load_schedule(_write(tmp_path, _record(lr_fractions=[1.0, 0.75, 0.75, 0])), IDENTITY, checkpoint_minutes=5.0,
                      lr_decay=True)
    assert s.lr_fractions == (1.0, 0.75, 0.75, 0.0)
    assert load_schedule(_write(tmp_path, _record()), IDENTITY, checkpoint_minutes=5.0).lr_fractions is None
    rec = _record(lr_fractions=[1.0, 0.75, 0.75])
    same = compare(rec, rec)
    assert same["identical"] and same["lr_readings"] == [3, 3]
    fewer = compare({**rec, "lr_fractions": [1.0, 0.75]}, rec)  # a replay that stopped reading early
    assert not fewer["identical"] and fewer["lr_readings"] == [2, 3]
    assert not compare({**rec, "lr_fractions": [1.0, 0.75, 0.5]}, rec)["identical"]


def test_an_unreadable_record_is_named(tmp_path):
    with pytest.raises(ValueError, match="--replay: cannot read the record"):
        load_schedule(tmp_path / "missing.json", IDENTITY, checkpoint_minutes=None)
    (tmp_path / "list.json").write_text("[1, 2]")
    with pytest.raises(ValueError, match="is not a run's record"):
        load_schedule(tmp_path / "list.json", IDENTITY, checkpoint_minutes=None)


def test_compare_sets_each_result_beside_the_record_s():
    rec = _record()
    same = compare(rec, rec)
    assert same["identical"] and same["success_rate"] == [0.8, 0.8] and len(same["checkpoints"]) == 3
    other = compare({**rec, "checkpoints": [{**rec["checkpoints"][0], "mean_return": 9.0}, *rec["checkpoints"][1:]]},
                    rec)
    assert not other["identical"] and other["checkpoints"][0]["mean_return"] == [9.0, 10.0]
    assert not compare({**rec, "checkpoints": rec["checkpoints"][:2]}, rec)["identical"]
    assert not compare({**rec, "outcomes": {"success": 39, "crushed": 1}}, rec)["identical"]


def test_the_policy_digest_is_the_network_to_the_last_bit():
    pytest.importorskip("stable_baselines3")
    import gymnasium as gym
    import numpy as np
    import torch
    from stable_baselines3 import PPO

    env = gym.make("Pendulum-v1")
    a, b = (PPO("MlpPolicy", env, seed=3, device="cpu") for _ in range(2))
    assert policy_digest(a) == policy_digest(b) and len(policy_digest(a)) == 16
    with torch.no_grad():  # one parameter one unit in the last place away
        p = next(b.policy.parameters())
        p.view(-1)[0] = float(np.nextafter(np.float32(p.view(-1)[0].item()), np.float32(np.inf)))
    assert policy_digest(a) != policy_digest(b)
    rec = {**_record(), "policy_digest": policy_digest(a)}
    assert compare({**rec}, rec)["identical"]
    other = compare({**rec, "policy_digest": policy_digest(b)}, rec)
    assert not other["identical"] and other["policy_digest"] == [policy_digest(b), policy_digest(a)]
    assert compare(_record(), _record())["identical"] and "policy_digest" not in compare(_record(), _record())
    env.close()


def test_versions_name_what_the_numbers_depend_on():
    import platform

    v = versions()
    assert v["python"] == platform.python_version()
    assert set(v) == {"python", "mujoco", "numpy", "gymnasium", "stable-baselines3", "torch"}
    import mujoco
    import numpy

    assert v["mujoco"] == mujoco.__version__ and v["numpy"] == numpy.__version__


def test_rl_baselines_passes_each_seed_its_record(tmp_path):
    mod = _example("rl_baselines")
    cmd = mod.run_command("ppo", 2, rl_baselines_args(mod, replay=str(tmp_path)), tmp_path / "o")
    assert cmd[-2:] == ["--replay", str(tmp_path / "ppo_seed2.json")]
    assert "--replay" not in mod.run_command("ppo", 2, rl_baselines_args(mod), tmp_path / "o")


@pytest.mark.parametrize("script", ["train_sb3", "rl_baselines"])
def test_a_record_that_is_not_the_command_s_exits_2_before_any_training(script, tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    _write(tmp_path, _record(env="simgrip/PickMultiFragile-v7"), "ppo_seed0.json")
    held_out = ["--eval-seed", "8000", "--eval-episodes", "50", "--seed", "0"] if script == "train_sb3" else \
        ["--eval-seeds", "8000-8049", "--seeds", "0"]
    replay = str(tmp_path / "ppo_seed0.json") if script == "train_sb3" else str(tmp_path)
    common = ["--env", "simgrip/PickFragile-v7", "--algo", "ppo", "--minutes", "15", "--checkpoint-minutes", "5",
              "--action-offset", "-0.2", "0.2", "--gamma", "0.995", *held_out, "--out", str(tmp_path / "o")]
    with pytest.raises(SystemExit) as e:
        _example(script).main([*common, "--replay", replay])
    err = capsys.readouterr().err
    assert e.value.code == 2 and "--replay: the record's env is 'simgrip/PickMultiFragile-v7'" in err
    assert not (tmp_path / "o" / "ppo_seed0" / "ppo_eval.json").exists()
    if script == "rl_baselines":  # a seed without a record
        with pytest.raises(SystemExit) as e:
            _example(script).main([*common[:-2], "--seeds", "1", "--out", str(tmp_path / "o"), "--replay", replay])
        assert e.value.code == 2 and "--replay: no record of ppo seed 1" in capsys.readouterr().err


def test_a_replay_trains_the_record_s_policy_step_for_step(tmp_path):
    """A budgeted run, then its replay: the same steps, checkpoints and held-out results; and a record whose steps
    were others (a machine of another speed) makes the replay checkpoint and stop at those."""
    pytest.importorskip("stable_baselines3")
    train = _example("train_sb3")
    common = ["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--seed", "5", "--minutes", "0.15",
              "--checkpoint-minutes", "0.05", "--eval-episodes", "2", "--eval-seed", "8360"]
    train.main([*common, "--out", str(tmp_path / "a")])
    rec = json.loads((tmp_path / "a" / "ppo_eval.json").read_text())
    assert rec["timesteps"] > 2048  # one update at least: the replay must repeat it
    assert rec["versions"] == versions()
    train.main([*common, "--replay", str(tmp_path / "a" / "ppo_eval.json"), "--out", str(tmp_path / "b")])
    rep = json.loads((tmp_path / "b" / "ppo_eval.json").read_text())
    assert rep["replay"]["identical"], rep["replay"]
    assert rep["policy_digest"] == rec["policy_digest"] and rep["replay"]["policy_digest"] == [rec["policy_digest"]] * 2
    assert rep["timesteps"] == rec["timesteps"]
    assert [c["timesteps"] for c in rep["checkpoints"]] == [c["timesteps"] for c in rec["checkpoints"]]
    assert (tmp_path / "b" / "ppo_model.zip").stat().st_size > 0

    def rows(run):  # the training curve without its time columns
        lines = (tmp_path / run / "ppo_curve.csv").read_text().splitlines()
        return [[c for i, c in enumerate(line.split(",")) if i not in (2, 3)] for line in lines]

    assert rows("a") == rows("b")
    # the same record with other steps: the replay follows them, not the clock
    moved = {**rec, "timesteps": 1500, "checkpoints": [{**c, "timesteps": n} for c, n in
                                                       zip(rec["checkpoints"], (500, 1000, 1500))]}
    _write(tmp_path, moved, "moved.json")
    train.main([*common, "--replay", str(tmp_path / "moved.json"), "--out", str(tmp_path / "c")])
    out = json.loads((tmp_path / "c" / "ppo_eval.json").read_text())
    assert out["timesteps"] == 1500 and [c["timesteps"] for c in out["checkpoints"]] == [500, 1000, 1500]
    assert out["replay"]["timesteps"] == [1500, 1500] and out["replay"]["from"] == str(tmp_path / "moved.json")
    assert out["policy_digest"] != rec["policy_digest"] and not out["replay"]["identical"]  # fewer updates


def test_a_replay_of_a_decaying_rate_trains_the_record_s_policy(tmp_path):
    """``--lr-decay``: the record keeps each reading of the clock its rate made, and the replay, given them instead of
    the clock, trains the same policy (updates at rates below SB3's, none repeated: the clock moved between them);
    a record whose readings were others (another machine's clock) gives the replay its rates."""
    pytest.importorskip("stable_baselines3")
    train = _example("train_sb3")
    common = ["--algo", "ppo", "--env", "simgrip/PickFragile-v7", "--seed", "6", "--minutes", "0.15",
              "--checkpoint-minutes", "0.05", "--eval-episodes", "2", "--eval-seed", "8370", "--lr-decay"]
    train.main([*common, "--out", str(tmp_path / "a")])
    rec = json.loads((tmp_path / "a" / "ppo_eval.json").read_text())
    updates = rec["timesteps"] // 2048
    assert updates >= 2, rec["timesteps"]  # two updates at least: the second one's rate read later than the first
    shares = rec["lr_fractions"]
    assert len(shares) == 1 + 2 * updates  # one as the model is built, two an update (the log's and the set's)
    assert shares == sorted(shares, reverse=True) and 0.0 <= shares[-1] < shares[2] < shares[0] <= 1.0
    train.main([*common, "--replay", str(tmp_path / "a" / "ppo_eval.json"), "--out", str(tmp_path / "b")])
    rep = json.loads((tmp_path / "b" / "ppo_eval.json").read_text())
    assert rep["replay"]["identical"], rep["replay"]
    assert rep["lr_fractions"] == shares and rep["replay"]["lr_readings"] == [len(shares)] * 2
    # other readings (another machine's clock), stopped after the first update: the replay's rates are the record's,
    # not its own clock's, and it says it read fewer than the record kept
    other = [x * 0.5 for x in shares]
    short = {**rec, "lr_fractions": other, "timesteps": 2100,
             "checkpoints": [{**c, "timesteps": n} for c, n in zip(rec["checkpoints"], (700, 1400, 2100))]}
    _write(tmp_path, short, "other.json")
    train.main([*common, "--replay", str(tmp_path / "other.json"), "--out", str(tmp_path / "c")])
    out = json.loads((tmp_path / "c" / "ppo_eval.json").read_text())
    assert out["timesteps"] == 2100 and out["lr_fractions"] == other[:3]
    assert not out["replay"]["identical"] and out["replay"]["lr_readings"] == [3, len(other)]
    from stable_baselines3 import PPO

    model = PPO.load(tmp_path / "c" / "ppo_model.zip", device="cpu")
    assert model.policy.optimizer.param_groups[0]["lr"] == 3e-4 * other[2]

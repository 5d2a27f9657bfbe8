"""``ValveShare(env, share)`` and ``--valve-share`` (simgrip.envs.valve_share): a restrictor between the policy
and the valve, so the policy closes at most ``share`` of the valve's rate.

The reference is the valve itself: behind the wrapper the registered task must step exactly as the task made with
the valve's rate ``kappa_rate = share * 0.02`` (``gym.make``'s keyword argument), for a power-of-two share, where
the curvature is the policy's.  ``0.02 * (share * a)`` and ``(share * 0.02) * a`` are then the same double: a
product by a power of two only moves the exponent, so both round the same real number.
"""

import json

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs.env_options import EnvOptions, make_env
from simgrip.envs.valve import KAPPA_RATE
from simgrip.envs.valve_share import ValveShare
from helpers import load_example, rl_baselines_args, train_and_evaluate_again

PLACE, SPHERE, CRADLE = "simgrip/PlaceFragile-v8", "simgrip/PickSphereFragile-v6", "simgrip/PickCradleFragile-v6"


def _episodes(env, seeds, rng):
    """Every step's (obs, reward, terminated, truncated, info) of ``env`` over ``seeds``, driven by clipped Gaussian
    actions (a PPO policy's early noise about a slow close) from ``rng``."""
    out = []
    for seed in seeds:
        obs, _ = env.reset(seed=seed)
        steps = [obs]
        while True:
            a = np.clip(rng.normal(0.0, 0.4, env.action_space.shape), -1, 1).astype(np.float32)
            obs, r, term, trunc, info = env.step(a)
            steps.append((obs, r, term, trunc, {k: np.asarray(v).tolist() for k, v in info.items()}))
            if term or trunc:
                break
        out.append(steps)
    return out


def _same(a, b):
    assert len(a) == len(b)
    for ea, eb in zip(a, b):
        assert len(ea) == len(eb)
        assert np.array_equal(ea[0], eb[0])
        for (oa, ra, ta, ua, ia), (ob, rb, tb, ub, ib) in zip(ea[1:], eb[1:]):
            assert np.array_equal(oa, ob) and (ra, ta, ua) == (rb, tb, ub) and ia == ib


@pytest.mark.parametrize("env_id, share, options", [
    (SPHERE, 0.25, dict(action_offset=(-0.8,), residual=("palm_z",), residual_alone=True)),
    (PLACE, 0.5, dict(action_offset=(-0.4, 0.0, 0.0), residual=("palm_x", "palm_z"))),
    (CRADLE, 0.25, dict(action_offset=(-0.8, 0.0))),
])
def test_the_restrictor_is_the_valve_at_that_share_of_its_rate(env_id, share, options):
    wrapped = make_env(env_id, EnvOptions(valve_share=share, **options))
    valve = make_env(env_id, EnvOptions(env_kwargs={"kappa_rate": share * KAPPA_RATE}, **options))
    a = _episodes(wrapped, (8003, 8017), np.random.default_rng(5))
    b = _episodes(valve, (8003, 8017), np.random.default_rng(5))
    _same(a, b)
    ends = [ep[-1][4] for ep in a]
    assert sum(len(ep) for ep in a) > 150 and any(max(e["normal_force"]) > 0 for e in ends)  # past a touch
    wrapped.close(), valve.close()


def test_the_registered_rate_differs_so_the_comparison_can_fail():
    wrapped = make_env(SPHERE, EnvOptions(valve_share=0.25, action_offset=(-0.8, 0.0)))
    plain = make_env(SPHERE, EnvOptions(action_offset=(-0.8, 0.0)))
    a, b = (_episodes(e, (8003,), np.random.default_rng(5)) for e in (wrapped, plain))
    with pytest.raises(AssertionError):
        _same(a, b)
    wrapped.close(), plain.close()


def test_the_wrapper_leaves_the_callers_action_and_the_palm_alone():
    env = ValveShare(gym.make(PLACE), 0.25)
    a = np.array([-0.8, 0.5, -1.0], np.float32)
    out = env.action(a)
    assert out.tolist() == np.array([-0.2, 0.5, -1.0], np.float32).tolist()  # -0.8 / 4 exactly, in float32
    assert a.tolist() == np.array([-0.8, 0.5, -1.0], np.float32).tolist()
    assert out.dtype == np.float32 and env.share == 0.25
    env.close()


@pytest.mark.parametrize("bad", [0, 0.0, -0.5, 1.5, float("nan"), float("inf"), True, "half", None])
def test_a_share_outside_0_1_is_refused_naming_it(bad):
    with pytest.raises(ValueError, match="share must be a number in \\(0, 1\\]"):
        ValveShare(gym.make(SPHERE), bad)


def test_make_env_records_it_and_refuses_what_it_cannot_restrict():
    options = EnvOptions(valve_share=0.25, residual=("palm_z",), residual_alone=True)
    keys, wrappers = options.record()
    assert keys["valve_share"] == 0.25 and "ValveShare(0.25)" in wrappers and "env_kwargs" not in keys
    env = make_env(SPHERE, options)
    assert isinstance(env.env, ValveShare)  # under the residual: the script's palm is not cut
    env.close()
    with pytest.raises(ValueError, match="--valve-share: env: .* has no valve"):
        make_env("simgrip/Pick-v1", EnvOptions(valve_share=0.5))
    with pytest.raises(ValueError, match="--valve-share: not with a residual on the curvature"):
        make_env(PLACE, EnvOptions(valve_share=0.5, residual=("curvature", "palm_x")))
    with pytest.raises(ValueError, match="--valve-share: share must be"):
        make_env(SPHERE, EnvOptions(valve_share=2.0))


def test_train_sb3_records_it_and_evaluate_policy_gives_its_figures_again(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    train, ev, rec, again = train_and_evaluate_again(
        SPHERE, ["--action-offset", "-0.8", "--residual", "palm_z", "--residual-alone", "--valve-share", "0.25"],
        tmp_path, "_share")
    capsys.readouterr()
    assert rec["valve_share"] == 0.25 and "ValveShare(0.25)" in rec["wrapper"] and "env_kwargs" not in rec
    assert again["valve_share"] == 0.25
    for key in ("success_rate", "mean_return", "mean_length", "outcomes"):
        assert again[key] == rec[key], key
    for argv, option in ((["--valve-share", "0"], "--valve-share"), (["--valve-share", "nan"], "--valve-share")):
        with pytest.raises(SystemExit) as e:
            train.main(["--algo", "ppo", "--env", SPHERE, *argv, "--out", str(tmp_path / "o")])
        assert e.value.code == 2 and option in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        ev.main(["--env", SPHERE, "--policy", "observation", "--valve-share", "0.5"])
    assert e.value.code == 2 and "--valve-share: only with --model" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_rl_baselines_passes_it_to_every_run(tmp_path):
    mod = load_example("rl_baselines", "_share")
    args = rl_baselines_args(mod, SPHERE, residual=["palm_z"], residual_alone=True, valve_share=0.25)
    cmd = mod.run_command("ppo", 0, args, tmp_path / "run")
    i = cmd.index("--valve-share")
    assert cmd[i + 1] == "0.25"
    args.valve_share = None
    assert "--valve-share" not in mod.run_command("ppo", 0, args, tmp_path / "run")


def test_a_training_behind_the_restrictor_is_the_training_on_that_valve(tmp_path):
    """The same observations and rewards give the same learner: PPO trained for two updates behind
    ``--valve-share 0.25`` and on the task made with ``kappa_rate = 0.005`` ends with the same policy to the last
    bit (``policy_digest``), and on the registered valve alone with another."""
    pytest.importorskip("stable_baselines3")
    train = load_example("train_sb3", "_share_digest")
    common = ["--algo", "ppo", "--env", SPHERE, "--steps", "512", "--n-steps", "256", "--batch-size", "64",
              "--action-offset", "-0.8", "--residual", "palm_z", "--residual-alone", "--eval-episodes", "1",
              "--eval-seed", "8040"]
    digests = {}
    for name, extra in (("share", ["--valve-share", "0.25"]), ("kwarg", ["--env-kwargs", '{"kappa_rate": 0.005}']),
                        ("plain", [])):
        train.main(common + extra + ["--out", str(tmp_path / name)])
        digests[name] = json.loads((tmp_path / name / "ppo_eval.json").read_text())["policy_digest"]
    assert digests["share"] == digests["kwarg"] != digests["plain"]

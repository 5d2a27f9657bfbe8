"""``TouchMemory`` and ``--touch-memory`` (simgrip.envs.touch_memory): the first touch remembered in the observation.

References: the task itself (the wrapped observation's first entries are the task's, bit for bit, over whole
episodes), and the module's table computed here from each step's ``info`` (the first touch is the first step whose
``normal_force`` has an entry above 0; the rise is ``workpiece_lift`` in metres over a millimetre) and the task's
own curvature (``_kact``, mapped to action units by the task's ``kappa_range``).
"""

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs.budget_replay import OPTION_KEYS
from simgrip.envs.env_options import EnvOptions, make_env
from simgrip.envs.touch_memory import CLOSE_UNIT, RISE_UNIT, TouchMemory
from helpers import assert_passes_flag, load_example, train_and_evaluate_again

PLACE, SPHERE, PINCH = "simgrip/PlaceFragile-v8", "simgrip/PickSphereFragile-v6", "simgrip/PickFragile-v7"
PALM_ALONE = dict(action_offset=(-0.2,), residual=("palm_x", "palm_z"), residual_alone=True)
# float32 observations: the curvature in action units (|k| <= 1) and the lift (in target heights, <= ~2) carry
# relative errors of 2^-24, so the entries, differences of two of them over units of 0.05 and 1 mm, to ~1e-5
TOL = 1e-4


def _action_units(task, k: float) -> float:
    lo, hi = task.kappa_range
    return 2.0 * (k - lo) / (hi - lo) - 1.0


@pytest.mark.parametrize("env_id, options, action", [
    (PLACE, PALM_ALONE, [-0.05]), (SPHERE, dict(residual=("palm_z",), residual_alone=True), [-0.15]),
    (PINCH, {}, [-0.3, 0.2])])
def test_the_task_is_unchanged_and_the_entries_follow_the_table(env_id, options, action):
    wrapped = make_env(env_id, EnvOptions(touch_memory=True, **options))
    plain = make_env(env_id, EnvOptions(**options))
    n = plain.observation_space.shape[0]
    assert wrapped.observation_space.shape == (n + 3,)
    assert wrapped.get_wrapper_attr("obs_layout")[-3:] == [("touched", 1), ("closed_since_touch", 1),
                                                           ("risen_since_touch", 1)]
    task = wrapped.unwrapped
    a = np.array(action, dtype=np.float32)
    touched_steps = 0
    for seed in (8000, 8001):
        obs, _ = wrapped.reset(seed=seed)
        ref, _ = plain.reset(seed=seed)
        assert np.array_equal(obs[:n], ref) and np.array_equal(obs[n:], [0.0, 0.0, 0.0])  # a reset forgets
        touch = None  # (curvature in action units, lift [m]) at the first touch
        for _ in range(400):
            obs, r, term, trunc, info = wrapped.step(a)
            ref, r_ref, term_ref, trunc_ref, _ = plain.step(a)
            assert np.array_equal(obs[:n], ref) and (r, term, trunc) == (r_ref, term_ref, trunc_ref)
            assert obs in wrapped.observation_space
            k = _action_units(task, task._kact[0])
            if touch is None and max(np.asarray(info["normal_force"]).tolist()) > 0.0:
                touch = (k, info["workpiece_lift"])
            if touch is None:
                assert np.array_equal(obs[n:], [0.0, 0.0, 0.0])
            else:
                touched_steps += 1
                expected = [1.0, (touch[0] - k) / CLOSE_UNIT, (info["workpiece_lift"] - touch[1]) / RISE_UNIT]
                assert np.allclose(obs[n:], expected, rtol=0.0, atol=TOL), (obs[n:], expected)
            if term or trunc:
                break
    assert touched_steps > 10  # the fingers touched in these episodes: the table was checked after a touch
    wrapped.close()
    plain.close()


def test_it_passes_gymnasiums_checker_and_refuses_an_env_without_the_entries():
    from gymnasium.utils.env_checker import check_env

    env = make_env(PLACE, EnvOptions(touch_memory=True, **PALM_ALONE))
    check_env(env.unwrapped)  # the task; the wrapper's space holds every observation (the test above)
    assert isinstance(env.env, TouchMemory)
    env.close()
    with pytest.raises(ValueError, match="env: CartPoleEnv does not observe the actual curvature"):
        TouchMemory(gym.make("CartPole-v1"))


def test_make_env_records_it_and_init_from_refuses_it():
    from simgrip.envs.warm_start import check_init_from

    keys, wrappers = EnvOptions(touch_memory=True).record()
    assert keys == {"touch_memory": True} and wrappers == ["TouchMemory"]
    assert "touch_memory" not in EnvOptions().record()[0] and "touch_memory" in OPTION_KEYS
    assert EnvOptions(touch_memory=True).evaluation().touch_memory  # part of the policy, not a training aid
    with pytest.raises(ValueError, match="--init-from: not with --touch-memory"):
        check_init_from("unused.zip", PINCH, touch_memory=True)


def test_train_sb3_records_it_and_evaluate_policy_gives_its_figures_again(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    options = ["--action-offset", "-0.2", "--residual", "palm_x", "palm_z", "--residual-alone", "--touch-memory"]
    train, ev, rec, again = train_and_evaluate_again(PLACE, options, tmp_path, "_touch_memory")
    capsys.readouterr()
    assert rec["touch_memory"] is True and "TouchMemory" in rec["wrapper"] and again["touch_memory"] is True
    for key in ("success_rate", "mean_return", "mean_length", "outcomes"):
        assert again[key] == rec[key], key
    with pytest.raises(SystemExit) as e:  # without the wrapper the model's observation does not fit
        ev.main(["--env", PLACE, "--model", str(tmp_path / "ppo_model.zip"), *options[:-1], "--episodes", "1"])
    assert e.value.code == 2 and "--touch-memory" in capsys.readouterr().err
    with pytest.raises(SystemExit) as e:
        ev.main(["--env", PLACE, "--policy", "observation", "--touch-memory"])
    assert e.value.code == 2 and "--touch-memory: only with --model" in capsys.readouterr().err


def test_rl_baselines_passes_it_to_every_run(tmp_path):
    assert_passes_flag(load_example("rl_baselines", "_touch_memory"), PLACE, "touch_memory", tmp_path / "run")

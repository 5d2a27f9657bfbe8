"""``crush_at="peak"`` (``simgrip.envs.touch_history``): the crush rule reads each finger's largest normal force
within the control step, summed in C by MuJoCo's contact sensors.

* the sensors' peaks are the physics-step-by-physics-step replay's (``simgrip.envs.substep_forces``), to rounding
  (a finger's contacts summed pairwise against one by one), on every fragile task, held palm and ramped, under
  the scripted controller and under actions that press several contacts at once;
* the rule crushes at the first step whose peak passes the limit, where the end-of-step rule crushes at the
  first step whose end value does: an episode replayed with a limit between a step's end value and its peak;
* the default stays ``"end"`` (every registered id, bit for bit: ``tests/test_env_rollout_reference.py``), and a bad
  value is refused by name.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs import FRAGILE_ENV_IDS, retired_spec
from simgrip.envs.scripted_policies import policy_maker
from simgrip.envs.substep_forces import step_with_peaks


@pytest.mark.parametrize("ramp", [False, True], ids=["held", "ramped"])
@pytest.mark.parametrize("env_id", FRAGILE_ENV_IDS)
def test_the_sensors_peak_is_the_replays(env_id, ramp):
    """Two episodes of the task's scripted controller (random actions never reach the claws' workpieces)."""
    env = gym.make(env_id, crush_at="peak", palm_ramp=ramp)
    make = policy_maker(env, "observation")
    touched = 0
    for seed in (8000, 8001):
        obs, info = env.reset(seed=seed)
        act = make(env, info, seed)
        for t in range(400):
            obs, _, term, trunc, info, peaks = step_with_peaks(env, act(obs, t))
            np.testing.assert_allclose(info["peak_normal_force"], peaks, rtol=1e-13, atol=1e-15)
            assert np.all(info["peak_normal_force"] >= info["normal_force"] * (1 - 1e-13))
            touched += max(peaks) > 0.0
            if term or trunc:
                break
    assert touched > 10  # (forces to compare)
    env.close()


def _run(env, seed, limit, actions=None):
    """Per step (end value, peak) of the largest finger under the scripted controller, or under ``actions``;
    and the step that crushed (None)."""
    obs, info = env.reset(seed=seed, options={"crush_limit": limit})
    act = policy_maker(env, "observation")(env, info, seed)
    rows, taken, crushed_at = [], [], None
    for t in range(len(actions) if actions is not None else 400):
        a = actions[t] if actions is not None else np.asarray(act(obs, t), dtype=np.float32)
        taken.append(a)
        obs, _, term, trunc, info = env.step(a)
        rows.append((max(info["normal_force"]), max(info.get("peak_normal_force", info["normal_force"]))))
        if info["crushed"]:
            crushed_at = t
        if term or trunc:
            break
    return rows, taken, crushed_at


def test_the_rule_crushes_on_the_peak():
    sphere = "simgrip/PickSphereFragile-v6"
    peak_env, end_env = gym.make(sphere), gym.make(sphere, crush_at="end")
    rows, actions, _ = _run(peak_env, 8000, 1e9)
    k = next(t for t, (e, p) in enumerate(rows) if e > 0.0 and p > 1.2 * e)  # a step whose peak is well above
    limit = 0.5 * (rows[k][0] + rows[k][1])
    first_peak = next(t for t, (_, p) in enumerate(rows) if p > limit)
    first_end = next((t for t, (e, _) in enumerate(rows) if e > limit), None)
    assert first_end is None or first_end > first_peak
    _, _, crushed_peak = _run(peak_env, 8000, limit, actions)
    _, _, crushed_end = _run(end_env, 8000, limit, actions)
    assert crushed_peak == first_peak
    assert crushed_end == first_end
    peak_env.close()
    end_env.close()


def test_the_default_reads_the_end_before_v7_and_a_bad_value_is_named():
    env = gym.make(retired_spec("simgrip/PickFragile-v6"))
    env.reset(seed=0)
    _, _, _, _, info = env.step(env.action_space.sample())
    assert env.unwrapped.crush_at == "end" and "peak_normal_force" not in info
    env.close()
    env = gym.make("simgrip/PickFragile-v7", crush_at="end")
    env.reset(seed=0)
    _, _, _, _, info = env.step(env.action_space.sample())
    assert "peak_normal_force" not in info
    env.close()
    with pytest.raises(ValueError, match="crush_at must be 'end'"):
        gym.make("simgrip/PickFragile-v7", crush_at="max")


def test_a_peak_env_pickles_and_continues_alike():
    import pickle

    env = gym.make("simgrip/PickFragile-v7").unwrapped
    env.reset(seed=4)
    for _ in range(20):
        env.step(np.array([-0.3, 0.2], np.float32))
    copy = pickle.loads(pickle.dumps(env))
    for _ in range(20):
        a = np.array([-0.3, 0.5], np.float32)
        one, other = env.step(a)[4], copy.step(a)[4]
        assert one["peak_normal_force"].tolist() == other["peak_normal_force"].tolist()


def test_baselines_take_env_kwargs_and_name_a_bad_one(capsys):
    """``python -m simgrip.envs.baselines --env-kwargs`` (the docs' table of the controllers under the ramp and
    the peak rule): recorded in the JSON; a keyword the env refuses is one line naming --env-kwargs."""
    import json

    from simgrip.envs.baselines import main

    assert main(["--env", "simgrip/PickFragile-v7", "--policy", "observation", "--seeds", "8000-8001",
                 "--env-kwargs", '{"palm_ramp": false, "crush_at": "end"}']) == 0
    assert json.loads(capsys.readouterr().out)["env_kwargs"] == {"palm_ramp": False, "crush_at": "end"}
    for bad in ('{"crush_at": "max"}', '{"bogus": 1}', '{"per_finger": true}'):
        with pytest.raises(SystemExit) as exc:
            main(["--env", "simgrip/PickFragile-v7", "--policy", "observation", "--seeds", "8000-8001",
                  "--env-kwargs", bad])
        err = capsys.readouterr().err
        assert exc.value.code == 2 and len(err.strip().splitlines()) == 1 and "--env-kwargs" in err, err


def test_the_controllers_close_gentler_where_the_peak_is_read():
    """On a ``crush_at="peak"`` env the scripted controllers close at PEAK_CLOSING_RATE before first contact (a
    faster first touch's impact crushes light pieces there); elsewhere at CLOSING_RATE, as every stored baseline
    was run; a rate given explicitly is kept."""
    from simgrip.envs.scripted_fragile import (CLOSING_RATE, PEAK_CLOSING_RATE, ObservationFragilePolicy,
                                               SphereFragilePolicy)

    for env_id, cls in (("simgrip/PickFragile-v7", ObservationFragilePolicy),
                        ("simgrip/PickSphereFragile-v6", SphereFragilePolicy)):
        for kwargs, want in (({"crush_at": "end"}, CLOSING_RATE), ({}, PEAK_CLOSING_RATE)):
            env = gym.make(env_id, **kwargs)
            _, info = env.reset(seed=0)
            for pol, rate in ((cls(), want), (cls(rate=0.01), 0.01)):
                pol.reset(env, info)
                assert pol.rate == rate
            env.close()


def test_the_peak_with_several_contacts_per_finger():
    """Full closing and a palm jerked up and down on a finger of 40 links presses several contacts per finger at
    once (an audit found the pairwise sum 1-2 ulp off the one-by-one sum there; the scripted controller keeps one)."""
    env = gym.make("simgrip/PickFragile-v7", n_links=40)
    env.reset(seed=0, options={"crush_limit": 1e9})
    rng = np.random.default_rng(0)
    several = 0
    for _ in range(200):
        a = np.array([-1.0, rng.choice([-1.0, 1.0, 0.3])], np.float32)
        _, _, term, trunc, info, peaks = step_with_peaks(env, a)
        np.testing.assert_allclose(info["peak_normal_force"], peaks, rtol=1e-13, atol=1e-15)
        several += env.unwrapped.data.ncon > 4
        if term or trunc:
            break
    assert several > 10
    env.close()

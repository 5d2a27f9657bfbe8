"""ActionOffset: the env performs clip(action + offset); bad offsets are named."""

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs.action_offset import PEAK_PROBE_OFFSET, PROBE_OFFSET, ActionOffset

ENV = "simgrip/PickFragile-v7"


def _rollout(env, actions, seed=8000):
    obs, _ = env.reset(seed=seed)
    out = [obs]
    for a in actions:
        obs, _, terminated, truncated, _ = env.step(np.asarray(a, np.float32))
        out.append(obs)
        if terminated or truncated:
            break
    env.close()
    return np.array(out)


@pytest.mark.parametrize("action, performed", [((0.0, 0.0), PROBE_OFFSET), ((1.0, 1.0), (0.6, 1.0)),
                                               ((-1.0, -1.0), (-1.0, -0.8))])
def test_the_env_performs_the_clipped_sum(action, performed):
    # the wrapped env stepped with `action` and the bare env stepped with the sum clipped by hand: same states
    wrapped = _rollout(ActionOffset(gym.make(ENV), PROBE_OFFSET), [action] * 20)
    bare = _rollout(gym.make(ENV), [performed] * 20)
    assert np.array_equal(wrapped, bare)


def test_a_zero_action_is_not_the_bare_envs_hold():
    held = _rollout(gym.make(ENV), [(0.0, 0.0)] * 20)
    probed = _rollout(ActionOffset(gym.make(ENV), PROBE_OFFSET), [(0.0, 0.0)] * 20)
    assert held.shape != probed.shape or not np.array_equal(held, probed)


def test_the_action_space_is_the_envs():
    env = ActionOffset(gym.make(ENV), PROBE_OFFSET)
    assert env.action_space == env.unwrapped.action_space
    env.close()


@pytest.mark.parametrize("offset, words", [((0.1,), "2 finite numbers"), ((0.0, float("nan")), "2 finite"),
                                           ((-1.5, 0.0), "within the action bounds"), ("ab", "2 numbers"),
                                           ((0.0, 0.0, 0.0), "2 finite numbers")])
def test_a_bad_offset_is_named(offset, words):
    with pytest.raises(ValueError, match="offset") as exc:
        ActionOffset(gym.make(ENV), offset)
    assert words in str(exc.value)


def test_a_discrete_action_space_is_refused():
    with pytest.raises(ValueError, match="Box"):
        ActionOffset(gym.make("CartPole-v1"), (0.0,))


def test_the_peak_probe_closes_at_the_scripted_controllers_peak_rate():
    from simgrip.envs.scripted_fragile import PEAK_CLOSING_RATE
    from simgrip.envs.valve import KAPPA_RATE

    assert PEAK_PROBE_OFFSET == pytest.approx((-PEAK_CLOSING_RATE / KAPPA_RATE, PROBE_OFFSET[1]), abs=1e-15)


@pytest.mark.parametrize("offset", [PROBE_OFFSET, PEAK_PROBE_OFFSET], ids=["probe", "peak_probe"])
@pytest.mark.parametrize("env_id", ["simgrip/PickFragile-v7", "simgrip/PickMultiFragile-v7"])
def test_the_probe_alone_is_no_solution(env_id, offset):
    # the zero action behind either probe is a constant schedule: it must not pick the workpieces up by itself
    env = ActionOffset(gym.make(env_id), offset)
    successes = 0
    for seed in range(6200, 6210):
        env.reset(seed=seed)
        done = False
        while not done:
            _, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
            done = terminated or truncated
        successes += bool(info["is_success"])
    env.close()
    assert successes == 0

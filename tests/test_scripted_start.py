"""ScriptedStart (simgrip.envs.scripted_start): the learner starts where the scripted controller's episode was."""

import math

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs import FRAGILE_ENV_IDS
from simgrip.envs.baselines import policy_maker
from simgrip.envs.env_options import EnvOptions, make_env
from simgrip.envs.scripted_start import ScriptedStart

PLACE = "simgrip/PlaceFragile-v8"


def _scripted_prefix(env_id, seed, k, **make_kwargs):
    """The observation and elapsed steps after the observation-only controller's first ``k`` steps on a plain env."""
    env = gym.make(env_id, **make_kwargs)
    obs, info = env.reset(seed=seed)
    act = policy_maker(env, "observation")(env, info, seed)
    for t in range(k):
        obs, _, terminated, truncated, _ = env.step(act(obs, t))
        assert not (terminated or truncated)
    elapsed = env._elapsed_steps
    env.close()
    return obs, elapsed


@pytest.mark.parametrize("env_id", FRAGILE_ENV_IDS)
def test_a_scripted_start_is_the_controllers_state_after_k_steps(env_id):
    env = ScriptedStart(gym.make(env_id), probability=1.0, max_steps=60)
    seen = set()
    for seed in (6300, 6301, 6302):
        obs, info = env.reset(seed=seed)
        k = info["scripted_steps"]
        seen.add(k)
        ref, elapsed = _scripted_prefix(env_id, seed, k)
        assert np.array_equal(obs, ref)
        assert env.env._elapsed_steps == elapsed == k  # the scripted steps count against the time limit
    assert len(seen) > 1 and max(seen) > 0
    env.close()


def test_probability_zero_is_the_plain_env():
    plain, wrapped = gym.make(PLACE), ScriptedStart(gym.make(PLACE), probability=0.0)
    for seed in (6310, 6311):
        o1, i1 = plain.reset(seed=seed)
        o2, i2 = wrapped.reset(seed=seed)
        assert np.array_equal(o1, o2) and i2["scripted_steps"] == 0 and i1["target_x"] == i2["target_x"]
        for _ in range(5):
            a = np.array([-0.3, 0.1, 0.2], dtype=np.float32)
            assert np.array_equal(plain.step(a)[0], wrapped.step(a)[0])
    plain.close(), wrapped.close()


def test_the_same_seeds_give_the_same_starts():
    def starts():
        env = ScriptedStart(gym.make(PLACE), probability=0.5, max_steps=40)
        out = [env.reset(seed=6320)]
        out += [env.reset() for _ in range(5)]  # unseeded resets continue both generators
        env.close()
        return [(o.tobytes(), i["scripted_steps"]) for o, i in out]

    a, b = starts(), starts()
    assert a == b
    ks = [k for _, k in a]
    assert 0 in ks and any(k > 0 for k in ks)  # both kinds of start drawn at probability 0.5


def test_a_draw_past_the_scripted_episode_is_redrawn_within_it():
    # a 5-step limit: every draw of 5 steps or more ends the scripted episode first; the same episode is then
    # run again and handed over within its 5 steps
    env = ScriptedStart(gym.make(PLACE, max_episode_steps=5), probability=1.0, max_steps=200)
    for seed in (6330, 6331, 6332):
        obs, info = env.reset(seed=seed)
        k = info["scripted_steps"]
        assert 0 <= k < 5
        ref, elapsed = _scripted_prefix(PLACE, seed, k, max_episode_steps=5)
        assert np.array_equal(obs, ref) and env.env._elapsed_steps == elapsed == k
    env.close()


def test_unseeded_scripted_starts_are_whole_episodes_of_drawn_seeds():
    env = ScriptedStart(gym.make(PLACE), probability=1.0, max_steps=30)
    env.reset(seed=6340)
    obs, info = env.reset()  # no seed: the wrapper draws the episode's seed, the workpiece is drawn anew
    assert 0 <= info["scripted_steps"] < 30 and env.env._elapsed_steps == info["scripted_steps"]
    assert np.all(np.isfinite(obs))
    env.close()


@pytest.mark.parametrize("bad", [-0.1, 1.5, math.nan, math.inf, True, "0.5", None])
def test_a_bad_probability_is_refused_naming_it(bad):
    with pytest.raises(ValueError, match="^probability must be a number in"):
        ScriptedStart(gym.make(PLACE), probability=bad)


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, "10"])
def test_bad_max_steps_is_refused_naming_it(bad):
    with pytest.raises(ValueError, match="^max_steps must be a whole number"):
        ScriptedStart(gym.make(PLACE), max_steps=bad)


def test_an_env_without_a_scripted_controller_is_refused():
    with pytest.raises(ValueError, match="^env: "):
        ScriptedStart(gym.make("simgrip/Pick-v1"))


def test_make_env_puts_it_next_to_the_env_and_names_the_option():
    env = make_env(PLACE, EnvOptions(action_offset=(-0.4, 0.0, 0.2), frame_stack=2, scripted_start=0.25))
    inner = env.env.env  # FrameStackObservation(ActionOffset(ScriptedStart(...)))
    assert isinstance(inner, ScriptedStart) and inner.probability == 0.25
    env.close()
    with pytest.raises(ValueError, match="^--scripted-start: probability must be"):
        make_env(PLACE, EnvOptions(scripted_start=2.0))
    with pytest.raises(ValueError, match="^--scripted-start: env: "):
        make_env("simgrip/Pick-v1", EnvOptions(scripted_start=0.5))

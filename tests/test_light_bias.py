"""LightBias (simgrip.envs.light_bias): training workpieces drawn from the light end of the mass range."""

import math

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs import FRAGILE_ENV_IDS
from simgrip.envs.env_options import EnvOptions, make_env
from simgrip.envs.light_bias import LIGHT_SHARE, LightBias
from simgrip.envs.scripted_start import ScriptedStart

MULTI = "simgrip/PickMultiFragile-v7"


def _mass(env) -> float:
    """The episode's drawn mass [kg], from the hidden hold force it sets (``m = N_hold K mu / g``)."""
    u = env.unwrapped
    mass, _, _ = u._episode()
    return float(mass)


@pytest.mark.parametrize("env_id", FRAGILE_ENV_IDS)
def test_a_biased_episode_is_the_plain_episode_with_a_light_mass(env_id):
    biased, plain = LightBias(gym.make(env_id), probability=1.0), gym.make(env_id)
    lo, hi = (float(m) for m in plain.unwrapped._mass_range)
    assert biased.light_range == pytest.approx((lo, lo * (hi / lo) ** LIGHT_SHARE), rel=1e-15)
    for seed in (6400, 6401, 6402):
        _, info = biased.reset(seed=seed)
        _, ref = plain.reset(seed=seed)
        assert info["light_bias"] is True
        m = _mass(biased)
        assert biased.light_range[0] <= m <= biased.light_range[1]
        # the same mass handed to the plain env as its reset option gives the same episode: the env's own draws
        # (size, friction, crush ratio, gap, placement) are untouched by the wrapper
        obs2, ref2 = plain.reset(seed=seed, options={plain.unwrapped._MASS_KEY: m})
        assert info["crush_limit"] / info["hold_force"] == pytest.approx(ref["crush_limit"] / ref["hold_force"],
                                                                         rel=1e-12)
        assert info["crush_limit"] == ref2["crush_limit"] and info["hold_force"] == ref2["hold_force"]
        assert info.get("start_gap") == ref2.get("start_gap")  # the pre-grasp tasks; None on the claws
    biased.close(), plain.close()


def test_probability_zero_is_the_plain_env():
    plain, wrapped = gym.make(MULTI), LightBias(gym.make(MULTI), probability=0.0)
    for seed in (6410, 6411):
        o1, i1 = plain.reset(seed=seed)
        o2, i2 = wrapped.reset(seed=seed)
        assert np.array_equal(o1, o2) and i2["light_bias"] is False and i1["crush_limit"] == i2["crush_limit"]
        for _ in range(5):
            a = np.array([-0.3, 0.2], dtype=np.float32)
            assert np.array_equal(plain.step(a)[0], wrapped.step(a)[0])
    plain.close(), wrapped.close()


def test_the_share_of_light_pieces_follows_the_probability():
    # the task's own draw puts LIGHT_SHARE of the pieces in the light range (log-uniform); at probability p the
    # share is p + (1 - p) LIGHT_SHARE.  200 resets: a binomial spread of ~0.035, the bound 4 sigma
    env = LightBias(gym.make(MULTI), probability=0.5)
    env.reset(seed=6420)
    light = 0
    n = 200
    for _ in range(n):
        env.reset()
        light += _mass(env) <= env.light_range[1]
    expected = 0.5 + 0.5 * LIGHT_SHARE
    sigma = math.sqrt(expected * (1 - expected) / n)
    assert abs(light / n - expected) < 4 * sigma
    env.close()


def test_the_same_seeds_give_the_same_draws():
    def draws():
        env = LightBias(gym.make(MULTI), probability=0.5)
        out = [env.reset(seed=6430)[1]]
        out += [env.reset()[1] for _ in range(6)]  # unseeded resets continue both generators
        env.close()
        return [(i["light_bias"], i["crush_limit"]) for i in out]

    a, b = draws(), draws()
    assert a == b
    assert {f for f, _ in a} == {True, False}


@pytest.mark.parametrize("bad", [-0.1, 1.5, math.nan, math.inf, True, "0.5", None])
def test_a_bad_probability_is_refused_naming_it(bad):
    with pytest.raises(ValueError, match=r"^probability must be a number in \[0, 1\]"):
        LightBias(gym.make(MULTI), probability=bad)


@pytest.mark.parametrize("bad", [0.0, -0.5, 1.01, math.nan, False, "1"])
def test_a_bad_share_is_refused_naming_it(bad):
    with pytest.raises(ValueError, match=r"^share must be a number in \(0, 1\]"):
        LightBias(gym.make(MULTI), share=bad)


def test_an_env_that_is_not_fragile_is_refused():
    with pytest.raises(ValueError, match="^env: "):
        LightBias(gym.make("simgrip/Pick-v1"))


def test_make_env_puts_it_innermost_and_names_the_option():
    env = make_env(MULTI, EnvOptions(action_offset=(-0.4, 0.2), frame_stack=2, scripted_start=0.25, light_bias=0.5))
    scripted = env.env.env  # FrameStackObservation(ActionOffset(ScriptedStart(LightBias(...))))
    assert isinstance(scripted, ScriptedStart) and isinstance(scripted.env, LightBias)
    assert scripted.env.probability == 0.5
    env.close()
    with pytest.raises(ValueError, match="^--light-bias: probability must be"):
        make_env(MULTI, EnvOptions(light_bias=2.0))
    with pytest.raises(ValueError, match="^--light-bias: env: "):
        make_env("simgrip/Pick-v1", EnvOptions(light_bias=0.5))

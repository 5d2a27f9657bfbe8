"""Checks several environment test modules make the same way (imported by them; not a test module)."""

import warnings

import gymnasium as gym
import numpy as np
import pytest


def make(env_id: str, **kwargs) -> gym.Env:
    """``gym.make`` of a registered id, or of a retired simgrip id through ``simgrip.envs.retired_spec`` (its
    class, keyword arguments and time limit as they were registered)."""
    from simgrip.envs import RETIRED, retired_spec

    return gym.make(retired_spec(env_id) if env_id in RETIRED else env_id, **kwargs)


def assert_sb3_check_env_clean(env_ids) -> None:
    """Stable-Baselines3's ``check_env`` passes every id (registered or retired) without a warning (skips without
    SB3)."""
    sb3_checker = pytest.importorskip("stable_baselines3.common.env_checker")
    for env_id in env_ids:
        env = make(env_id)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            sb3_checker.check_env(env.unwrapped)
        env.close()
        assert not [str(w.message) for w in caught]


def assert_headless_frame(env_id) -> None:
    """A 96 x 72 ``rgb_array`` frame of ``env_id`` after a reset is an image, not a blank (callers request the
    ``render_backend`` fixture, tests/conftest.py: it skips only where the machine has no GL library at all)."""
    env = make(env_id, render_mode="rgb_array", width=96, height=72)
    try:
        env.reset(seed=0)
        frame = env.render()
    finally:
        env.close()
    assert frame.shape == (72, 96, 3) and frame.dtype == np.uint8 and frame.std() > 0

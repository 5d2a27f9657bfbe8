"""The interface's least Python step (simgrip.envs.step_floor): the env's physics, its tuple's shape and keys."""

from __future__ import annotations

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import simgrip.envs  # noqa: F401  (registers the ids)
from simgrip.envs.step_floor import floor_step


@pytest.mark.parametrize("env_id", ["simgrip/PickFragile-v7", "simgrip/PickSphereFragile-v6"])
def test_floor_steps_the_envs_physics_and_returns_its_interface(env_id):
    """From the same state, with the rest angles and controls the env wrote, the floor's step ends where the env's
    step ended, bit for bit, and returns an observation of the env's size and an info with the env's keys (arrays
    where the env's are arrays, of their lengths)."""
    env = gym.make(env_id).unwrapped
    env.reset(seed=3)
    m, d = env.model, env.data
    kind = mujoco.mjtState.mjSTATE_INTEGRATION
    idx = env.joint_qpos.ravel()
    rng = np.random.default_rng(0)
    for _ in range(5):
        start = np.empty(mujoco.mj_stateSize(m, kind))
        mujoco.mj_getState(m, d, start, kind)
        obs, _, term, trunc, info = env.step(rng.uniform(-1, 1, env.action_space.shape).astype(np.float32))
        assert not (term or trunc)
        end = np.empty_like(start)
        mujoco.mj_getState(m, d, end, kind)
        spring, ctrl = m.qpos_spring[idx].copy(), d.ctrl.copy()
        mujoco.mj_setState(m, d, start, kind)
        step = floor_step(m, d, frame_skip=env.frame_skip, obs_size=obs.size, info=info, spring_index=idx)
        f_obs, reward, f_term, f_trunc, f_info = step(spring, ctrl)
        replayed = np.empty_like(start)
        mujoco.mj_getState(m, d, replayed, kind)
        np.testing.assert_array_equal(replayed, end)
        assert f_obs.shape == obs.shape and (reward, f_term, f_trunc) == (0.0, False, False)
        assert list(f_info) == list(info)
        for key, value in info.items():
            if isinstance(value, np.ndarray):
                assert isinstance(f_info[key], np.ndarray) and f_info[key].shape == value.shape, key
    env.close()


def test_bad_sizes_and_keys_are_named():
    env = gym.make("simgrip/PickFragile-v7").unwrapped
    env.reset(seed=0)
    m, d = env.model, env.data
    with pytest.raises(ValueError, match="obs_size"):
        floor_step(m, d, frame_skip=10, obs_size=0, info={}, spring_index=env.joint_qpos.ravel())
    with pytest.raises(ValueError, match="info keys"):
        floor_step(m, d, frame_skip=10, obs_size=4, info={1: 1.0}, spring_index=env.joint_qpos.ravel())
    env.close()

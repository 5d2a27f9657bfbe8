"""Every registered pick env, and every retired one (``simgrip.envs.RETIRED``, built through ``retired_spec``), is
deterministic: same seed, same actions -> identical observations, rewards, ends and info (every key, arrays
included), in a fresh env and in one reused after another episode.

Actions mix a curl-and-lift schedule (the fingers meet the workpiece, the validity probe's exact paths run) with
seeded noise, some outside [-1, 1] (clipped by the env).
"""

from __future__ import annotations

import numpy as np
import pytest

import simgrip.envs  # noqa: F401
from simgrip.envs import ENV_IDS, FRAGILE_ENV_IDS, MULTI_ENV_IDS, RETIRED
from env_checks import make


def _same(a, b) -> bool:
    if type(a) is not type(b):
        return False
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and np.array_equal(a, b)
    if isinstance(a, dict):
        return list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    return a == b


def _actions(space, steps: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.arange(steps)[:, None]
    base = np.zeros((steps,) + space.shape)
    base[:, :1] = np.maximum(1.0 - 0.08 * t, -0.8)  # curvature: straight to curled
    base[:, -1:] = np.where(t < 15, 0.0, 0.7)  # palm: wait, then lift
    return (base + rng.normal(0.0, 0.4, base.shape)).astype(np.float32)


def _episode(env, actions, seed: int) -> list:
    obs, info = env.reset(seed=seed)
    out = [obs, info]
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        out.append((obs, r, term, trunc, info))
        if term or trunc:
            break
    return out


@pytest.mark.parametrize("env_id", sorted(set(ENV_IDS) | set(MULTI_ENV_IDS) | set(FRAGILE_ENV_IDS) | set(RETIRED)))
def test_same_seed_same_actions_identical_everything(env_id):
    env = make(env_id).unwrapped
    actions = _actions(env.action_space, 40, seed=3)
    first = _episode(env, actions, seed=21)
    _episode(env, _actions(env.action_space, 25, seed=4), seed=5)  # another episode in between
    second = _episode(env, actions, seed=21)
    env.close()
    fresh = make(env_id).unwrapped
    third = _episode(fresh, actions, seed=21)
    fresh.close()
    assert len(first) > 5  # the episode ran some steps
    assert _same(first, second) and _same(first, third)

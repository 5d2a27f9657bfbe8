"""The crush charge of a training run (issue 18): :class:`simgrip.envs.crush_charge.CrushCharge`.

The wrapped env runs the same episode as the task, step for step; only a crushing step's reward differs, by exactly the
charge, and only from the ``start``-th wrapped step on (counted over episodes).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import simgrip.envs  # noqa: F401
from simgrip.envs.crush_charge import CrushCharge


def _closing_episode(env, seed: int) -> list:
    """``(obs, reward, crushed, info)`` per step of an episode that closes the valve at full rate on a limit every
    grasp overruns (the K-finger pinch: a crush within a few steps)."""
    env.reset(seed=seed, options={"crush_limit": 0.05})
    rows = []
    for _ in range(400):
        a = np.zeros(env.action_space.shape, dtype=np.float32)
        a[0] = -1.0
        obs, r, term, trunc, info = env.step(a)
        rows.append((obs, r, info["crushed"], info))
        if term or trunc:
            break
    return rows


def test_the_charge_lowers_the_crushing_steps_reward_and_nothing_else():
    plain = _closing_episode(gym.make("simgrip/PickMultiFragile-v6"), 3)
    charged = _closing_episode(CrushCharge(gym.make("simgrip/PickMultiFragile-v6"), 7.5), 3)
    assert len(plain) == len(charged) and plain[-1][2] and charged[-1][2]  # both end in the crush
    for (o0, r0, c0, _), (o1, r1, c1, i1) in zip(plain, charged):
        assert np.array_equal(o0, o1) and c0 == c1
        assert r1 == (r0 - 7.5 if c1 else r0) and i1["reward_crush_charge"] == (-7.5 if c1 else 0.0)


def test_the_charge_starts_at_its_step_counted_over_episodes():
    env = CrushCharge(gym.make("simgrip/PickMultiFragile-v6"), 7.5, start=1)
    first = _closing_episode(env, 3)
    n = len(first)
    env.start = n + len(first)  # the second episode (the same seed: as long) crushes on its last step, step 2n - 1
    assert first[-1][2] and first[-1][3]["reward_crush_charge"] == -7.5 and env.steps == n  # crushed at n - 1 >= 1
    second = _closing_episode(env, 3)
    assert len(second) == n and second[-1][2] and second[-1][3]["reward_crush_charge"] == 0.0  # before its start
    env.start = 2 * n + n - 1  # the third episode's crush is its start: charged
    third = _closing_episode(env, 3)
    assert third[-1][3]["reward_crush_charge"] == -7.5 and third[-1][1] == second[-1][1] - 7.5 and env.steps == 3 * n


@pytest.mark.parametrize("kwargs, word", [
    ({"charge": -1.0}, "charge"), ({"charge": float("nan")}, "charge"), ({"charge": float("inf")}, "charge"),
    ({"charge": True}, "charge"), ({"charge": "1"}, "charge"),
    ({"charge": 1.0, "start": -1}, "start"), ({"charge": 1.0, "start": 1.5}, "start"),
    ({"charge": 1.0, "start": True}, "start"),
])
def test_bad_arguments_name_themselves(kwargs, word):
    with pytest.raises(ValueError, match=word):
        CrushCharge(gym.make("simgrip/PickFragile-v6"), **kwargs)


def test_a_task_without_a_crush_is_refused():
    with pytest.raises(ValueError, match="env"):
        CrushCharge(gym.make("simgrip/Pick-v1"), 1.0)

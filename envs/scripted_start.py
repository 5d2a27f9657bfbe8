r"""Training starts part-way through the scripted controller's episode (issue 18, the pick-and-place).

``ScriptedStart(env, probability, max_steps)`` wraps a fragile task (:mod:`simgrip.envs.scripted_fragile`).
On each ``reset``, with probability ``probability``, it draws ``k`` uniform in ``0 .. max_steps - 1`` and steps
the task's scripted **observation-only** controller (:func:`simgrip.envs.scripted_policies.policy_maker`: it reads only
what the agent reads) for ``k`` steps; the learner starts from the state reached, with the time left of the
episode's limit (the wrapper sits outside ``gym.make``'s ``TimeLimit``, so the scripted steps count).  Where the
scripted episode ends first, at its step ``j <= k`` (a success, a crush, a drop), the same episode (the same
seed) is run again and handed over after ``k'`` steps, ``k'`` uniform in ``0 .. j - 1``: with ``max_steps``
past the controller's episodes, the handover is uniform over each scripted episode's own steps, its last
ones (the set-down, a few steps from a success) included.  The other episodes start plainly.  The scripted
steps' rewards are not the learner's: ``reset`` returns the observation and ``reset``'s info with
``scripted_steps`` (``k``; 0 for a plain start) added.

This is reference-state initialisation (Peng et al. 2018, "DeepMimic"; "start from demonstration states",
Salimans & Chen 2018), a training aid only: the learner's actions are its own from the handover on, and it is
evaluated on the plain task from the pre-grasp (:func:`simgrip.envs.env_options.make_env` builds evaluation envs
without it).

Why (measured on the pick-and-place, ``PlaceFragile-v5``; the Gymnasium environments page, "Pick-and-place
from scripted starts"): the place's first success needs a grip that survives, a lift of 3 cm, a carry of 4-10
cm and 0.3 s set down on the target.  PPO with SB3 defaults never saw one: 0 successes in 12,854 training
episodes, 0 in 19,959 behind the probe offset, 0 in 2,909 without the drop penalty (screens), so its return had
nothing to climb past the lift.
Started at random points of the scripted controller's episodes, some of its episodes begin mid-carry or over
the target, where a success is a few steps away.  Measured with ``probability = 0.5`` (3 training seeds):
156-501 training successes per 15 CPU-minute run where there had been none, and learners that finish carries
and set-downs handed over to them late, but not yet the grip before them: 0 % held-out success at 15 and at 30
CPU-minutes.

The draws use the wrapper's own generator, seeded from ``reset``'s ``seed`` (the same seeds give the same
starts).  A plain start is the env's own ``reset``; a scripted one resets the env with ``reset``'s ``seed``, or
when none is given with a seed the wrapper draws (so that its episode can be run again).
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

__all__ = ["ScriptedStart", "SCRIPTED_START_STEPS"]

#: default ``max_steps``: past the scripted controller's episodes on PlaceFragile-v4/-v5 (93-222 steps on seeds
#: 6000-6019, its time limit 400), so that the handover is about uniform over each of them
SCRIPTED_START_STEPS = 300


class ScriptedStart(gym.Wrapper):
    """Start a share of the episodes part-way through the scripted observation-only controller's episode
    (see :mod:`simgrip.envs.scripted_start`).

    Parameters
    ----------
    env : gymnasium.Env
        A fragile task as ``gym.make`` builds it (its raw action space: wrap before any action wrapper).
    probability : float
        The share of resets that start from a scripted state, in [0, 1].
    max_steps : int
        The scripted part is ``k`` steps, ``k`` uniform in ``0 .. max_steps - 1``; at least 1.

    Raises ValueError naming ``probability`` or ``max_steps`` when out of range, ``env`` when it is not a
    fragile task with a scripted controller.
    """

    def __init__(self, env: gym.Env, probability: float = 0.5, max_steps: int = SCRIPTED_START_STEPS):
        if isinstance(probability, bool) or not isinstance(probability, (int, float)) \
                or not math.isfinite(probability) or not 0.0 <= probability <= 1.0:
            raise ValueError(f"probability must be a number in [0, 1], got {probability!r}")
        if isinstance(max_steps, bool) or not isinstance(max_steps, (int, np.integer)) or max_steps < 1:
            raise ValueError(f"max_steps must be a whole number >= 1, got {max_steps!r}")
        super().__init__(env)
        from simgrip.envs.scripted_policies import policy_maker

        try:
            self._make = policy_maker(env, "observation")
        except ValueError as e:
            raise ValueError(f"env: {e}") from None
        self.probability, self.max_steps = float(probability), int(max_steps)
        self._rng = np.random.default_rng(0)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        if seed is not None:
            self._rng = np.random.default_rng([int(seed), 0x5C5])
        if not self._rng.random() < self.probability:
            obs, info = self.env.reset(seed=seed, options=options)
            return obs, {**info, "scripted_steps": 0}
        k = int(self._rng.integers(self.max_steps))
        episode_seed = int(seed) if seed is not None else int(self._rng.integers(2**31))
        obs, info, ended_at = self._scripted(episode_seed, options, k)
        if ended_at is not None:  # past its end: the same episode again, handed over within it
            k = int(self._rng.integers(ended_at))
            obs, info, _ = self._scripted(episode_seed, options, k)
        return obs, {**info, "scripted_steps": k}

    def _scripted(self, episode_seed: int, options, k: int):
        """Reset with ``episode_seed`` and step the scripted controller ``k`` steps: ``(obs, reset's info, None)``,
        or ``(.., .., j)`` when its step ``j`` (1-based) ended the episode first."""
        obs, info = self.env.reset(seed=episode_seed, options=options)
        act = self._make(self.env, info, episode_seed)
        for t in range(k):
            obs, _, terminated, truncated, _ = self.env.step(act(obs, t))
            if terminated or truncated:
                return obs, info, t + 1
        return obs, info, None

r"""A charge on every training step: a cost of time (issue 18's training aids).

``StepCharge(env, charge)`` lowers the reward of every step through it by ``charge`` and adds
``info["reward_step_charge"]`` (``-charge``).  A training aid only: the task's success, observation and own reward
are unchanged, and the held-out evaluation runs the task itself.

Why (measured; the learning page, ``docs/learning.md``, "Where the seeds that never grip end"): every seed of the
pinch and the K fingers that never grips ends holding its valve and its palm still.  Such a policy touches the
workpiece once (the one-off contact reward, 1) and then times out, a return of about 1.0 an episode, while the
near-random episodes of a learner's first minutes return 0.46-0.92 (their crushes take back what they earned), so a
learner that meets too few successes early climbs to the hold and stays there.  A charge ``c`` a step costs the hold
``300 c`` (the episode's length) and a short attempt far less: with ``c = 0.005`` the hold returns about -0.5 and an
attempt ended by a crush after 100 steps about 0.5 less than before, while a success (at least 30) keeps nearly all
of its worth.  It also makes a quicker end worth a little more, a crush included: the price of the aid.
"""

from __future__ import annotations

import gymnasium as gym

from simgrip.envs.arguments import check_charge

__all__ = ["StepCharge"]


class StepCharge(gym.Wrapper):
    """Lower every step's reward by ``charge`` (module docstring).

    Parameters
    ----------
    env : gymnasium.Env
        Any environment, possibly wrapped.
    charge : float
        The charge a step, in reward units, finite and >= 0.

    Raises ValueError naming ``charge`` when it is out of range.
    """

    def __init__(self, env, charge: float):
        charge = check_charge("charge", charge)
        super().__init__(env)
        self.charge = charge

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        info["reward_step_charge"] = 0.0 - self.charge
        return obs, reward - self.charge, terminated, truncated, info

r"""A charge for a grip close to the crush: a dense, privileged reward shaping (issue 18's training aids).

``CrushMargin(env, charge)`` wraps a fragile task (every ``simgrip/*Fragile-*`` id: the hidden ``crush_limit`` on its
unwrapped env, each finger's force in ``info``).  On every step it lowers the reward by

.. math::  c \, \mathrm{clip}\!\left(\frac{F/F_c - \rho}{1 - \rho},\ 0,\ 1\right),

with ``F`` the largest finger force of the step (``info["peak_normal_force"]`` where the task reads the peak within
the control step, else ``info["normal_force"]``: the force the crush rule reads), ``F_c`` the episode's crush limit
and ``rho = MARGIN_ONSET = 0.8``: nothing while every finger presses less than 80 % of the limit, rising linearly to
``c`` at the limit, and ``c`` on the crushing step itself.  ``info`` gains ``reward_crush_margin`` (the step's
charge, <= 0).  A training aid only: it reads the hidden limit, which the policy never sees, and the held-out
evaluation runs the task's own reward.

Why (measured; the learning page, ``docs/learning.md``, "The step charge with PPO's discount at 0.995"): the K
fingers' learners crush 5-17 of 50 held-out pieces, mostly the light ones, 1-24 steps after the first touch and by a
median overrun of 3 %: the task tells them so once, at the crush, and the credit for it is spread over every step
of the closing.  The charge tells them on each step that comes near it.  Why 0.8: a task's crush limit is 1.6-2.6
times the least force that holds its piece (:mod:`simgrip.envs.pick_fragile_v4`), so a grip at 1.25 times that
least force, the margin of the tasks' scripted controllers, is at most ``1.25 / 1.6 = 0.78`` of the limit and is
never charged.
"""

from __future__ import annotations

import gymnasium as gym

from simgrip.envs.arguments import check_charge
from simgrip.envs.touch_history import read_forces

__all__ = ["CrushMargin", "MARGIN_ONSET"]

#: the share of the crush limit from which a finger's force is charged
MARGIN_ONSET = 0.8


class CrushMargin(gym.Wrapper):
    """Lower each step's reward by ``charge`` times how far its largest finger force has gone from
    :data:`MARGIN_ONSET` of the crush limit towards the limit (module docstring).

    Parameters
    ----------
    env : gymnasium.Env
        A fragile task (its unwrapped env has a ``crush_limit``; its ``info`` a ``normal_force``), possibly wrapped.
    charge : float
        The charge at the limit, in reward units a step, finite and >= 0.

    Raises ValueError naming ``charge`` when it is out of range, ``env`` when it is not a fragile task.
    """

    def __init__(self, env, charge: float):
        charge = check_charge("charge", charge)
        if not hasattr(env.unwrapped, "crush_limit"):
            raise ValueError("env must be a fragile task (one with a crush limit), "
                             f"got {env.unwrapped.__class__.__name__}")
        super().__init__(env)
        self.charge = charge
        self._task = env.unwrapped  # its crush_limit, drawn anew at each reset

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        share = max(read_forces(info)) / self._task.crush_limit
        cost = self.charge * min(max((share - MARGIN_ONSET) / (1.0 - MARGIN_ONSET), 0.0), 1.0)
        info["reward_crush_margin"] = 0.0 - cost
        return obs, reward - cost, terminated, truncated, info

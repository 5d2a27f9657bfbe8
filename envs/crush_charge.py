r"""A flat charge on every crush, from a chosen training step on: a reward curriculum (issue 18).

``CrushCharge(env, charge, start)`` wraps a fragile task (every ``simgrip/*Fragile-*`` id: its ``info["crushed"]``
marks the step a finger's force passed the hidden crush limit).  From the ``start``-th step through the wrapper on
(counted over every episode since it was made: a training run's environment steps), the reward of a crushing step
is lowered by ``charge``; every other step, and every step before ``start``, is the env's own.  ``info`` gains
``reward_crush_charge`` (``-charge`` on a charged step, else 0).  A training aid only: the task's success, its
observation and its own reward are unchanged, and the held-out evaluation runs the task itself.

Why (measured; the Gymnasium environments page, "A flat charge for a crush"): the fragile tasks charge a crush by
its overrun of the limit, ``w_crush x / (1 + x)``, and the usual crush of a fast closing overruns it by a few per
cent, so it costs about nothing beyond the success it loses.  Under SB3's discount (0.99) the learners' fast
grasps, with their crushes, are then worth more than the careful scripted controller's (the sphere's two best
learners 9.37 and 9.67 against 9.17; ``examples/evaluate_policy.py --crush-charge``), and a flat charge of about
6-10 per crush would turn that round.  Charged from the first step, the learners stop closing instead (no
success in the first 81,920 steps of two sphere seeds charged 10 from the start, against 77 and 76 without):
early on every closing crushes, and a charged crush is worth less than never touching.  ``start`` lets the
learner find the grasp first under the task's own reward and meet the charge once it grips.
"""

from __future__ import annotations

import gymnasium as gym

from simgrip.envs.arguments import check_charge

__all__ = ["CrushCharge"]


class CrushCharge(gym.Wrapper):
    """Lower a crushing step's reward by ``charge`` from the ``start``-th wrapped step on (module docstring).

    Parameters
    ----------
    env : gymnasium.Env
        A fragile task (its unwrapped env has a ``crush_limit``; its ``info`` a ``crushed`` key), possibly wrapped.
    charge : float
        The flat charge, in reward units, finite and >= 0.
    start : int
        The first step (0-based, counted over every episode through this wrapper) whose crush is charged, >= 0.

    Attributes
    ----------
    steps : int
        The steps taken through the wrapper so far.

    Raises ValueError naming ``charge`` or ``start`` when out of range, ``env`` when it is not a fragile task.
    """

    def __init__(self, env, charge: float, start: int = 0):
        charge = check_charge("charge", charge)
        if isinstance(start, bool) or not isinstance(start, int) or start < 0:
            raise ValueError(f"start must be a whole number >= 0, got {start!r}")
        if not hasattr(env.unwrapped, "crush_limit"):
            raise ValueError("env must be a fragile task (one with a crush limit), "
                             f"got {env.unwrapped.__class__.__name__}")
        super().__init__(env)
        self.charge, self.start, self.steps = float(charge), int(start), 0

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        charged = 0.0 - self.charge if info.get("crushed") and self.steps >= self.start else 0.0
        self.steps += 1
        info["reward_crush_charge"] = charged
        return obs, reward + charged, terminated, truncated, info

r"""A valve-commanded curvature: the action sets how fast the curvature command moves, not where it is.

A pneumatic finger is driven through a valve: opening it one way fills the chamber and the finger curls, the
other way vents it, and closed it holds the pressure (and so the curvature) where it is.  :class:`ValveCommand`
gives an env that reading of its curvature action: ``action[0]`` in ``[-1, 1]`` moves the curvature command
``c`` (in action units, ``+1`` straight/open, ``-1`` fully curled, as the parent env's absolute command) by

    ``c_{t+1} = clip(c_t + kappa_rate * action[0], -1, 1)``

per control step (``kappa_rate`` action units per step, default 0.02: the whole range in 100 steps, 2 s at
50 Hz), and passes ``c_{t+1}`` to the parent env as its absolute command; the parent's first-order pneumatic
lag then acts on it as before.  The other actions (palm speeds) are unchanged.  The command starts where the
parent starts it (``+1``, straight) and is observed as before (``kappa_command``, in action units).

Why (issue 18, measured on ``PickFragile-v1`` with Stable-Baselines3 PPO defaults): with an absolute command a
memoryless policy must output its own last command to keep a grip, and the learner's exploration noise
(``sigma = 1`` at the start) moves the grip force by the whole range every step; the narrow force window of a
fragile workpiece is then crushed within a few steps of any contact.  Through the valve the same noise is
integrated (a random walk of ``kappa_rate`` per step), holding is the action 0 at which the policy starts, and
the same physical trajectories of the curvature stay reachable (any ramp of at most ``kappa_rate`` per step).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["KAPPA_RATE", "ValveCommand", "absolute_to_valve"]

#: default valve rate: the curvature command's largest change per control step [action units]
KAPPA_RATE = 0.02


def _check_rate(kappa_rate) -> float:
    if isinstance(kappa_rate, (bool, np.bool_)):  # True is not a rate (it was 1.0)
        raise ValueError(f"kappa_rate must be a number in (0, 2], got {kappa_rate!r}")
    try:
        rate = float(kappa_rate)
    except (TypeError, ValueError):
        raise ValueError(f"kappa_rate must be a number in (0, 2], got {kappa_rate!r}") from None
    if not (math.isfinite(rate) and 0.0 < rate <= 2.0):
        raise ValueError(f"kappa_rate must be a number in (0, 2] (action units per step), got {kappa_rate!r}")
    return rate


class ValveCommand:
    """Valve-commanded curvature (a mixin placed before an env whose ``action[0]`` is an absolute curvature
    command in ``[-1, 1]``): ``action[0]`` is the command's rate, ``kappa_rate`` action units per step at
    ``|action[0]| = 1``.  See :mod:`simgrip.envs.valve`."""

    def __init__(self, *, kappa_rate: float = KAPPA_RATE, **kwargs):
        self.kappa_rate = _check_rate(kappa_rate)
        self._valve = 1.0
        super().__init__(**kwargs)

    @property
    def valve_command(self) -> float:
        """The curvature command the valve has reached, in action units (``+1`` straight, ``-1`` curled)."""
        return self._valve

    def reset(self, *, seed=None, options=None):
        obs, info = super().reset(seed=seed, options=options)
        self._valve = float(obs[self.obs_slices["kappa_command"]][0])
        return obs, info

    def _step_checked(self, a: list):
        # the first layer of the step's chain (simgrip.envs.pick_step.CheckedStep: step checked the episode and
        # the action once): the rate becomes the absolute command the layers below read
        c = self._valve + self.kappa_rate * a[0]
        self._valve = c = -1.0 if c < -1.0 else (1.0 if c > 1.0 else c)
        a[0] = c
        return super()._step_checked(a)


def absolute_to_valve(target: float, command: float, kappa_rate: float) -> float:
    """The valve action that moves the curvature command from ``command`` towards ``target`` (both in action
    units) as fast as ``kappa_rate`` allows: ``clip((target - command) / kappa_rate, -1, 1)``.  Used to run the
    absolute-command scripted controllers and open-loop schedules on a valve env."""
    a = (float(target) - float(command)) / kappa_rate
    return -1.0 if a < -1.0 else (1.0 if a > 1.0 else a)

r"""A fixed offset on an env's action: the learner's zero becomes a chosen motion (issue 18).

``ActionOffset(env, offset)`` passes ``clip(a + offset, low, high)`` to ``env`` for the action ``a`` in the
same box (``low``, ``high``: the env's action bounds).  A policy that outputs 0 then performs ``offset``; its
corrections are residuals on that fixed motion (residual policy learning).  Every action the env takes stays
reachable on the side towards which ``offset`` leans; on the other side the range shrinks by ``|offset|``.

Why (measured on ``PickFragile-v5``; the Gymnasium environments page, "When is a seed's fate decided?"):
Stable-Baselines3's PPO starts with a mean action of 0, which on the valve tasks holds the curvature and the
palm. From there the valve's random walk touches and sometimes crushes, the palm's seldom lifts a gripped
piece, and in three of six seeds both means stayed within 0.1 of 0 until the noise shrank, with no success
ever found. The seeds that learned had, within their first ten updates, moved the means to about ``(-0.4,
+0.2)``: close through the valve at 0.4 of its rate while raising the palm at 0.2 of its speed, a slow
close-and-lift probe like the scripted observation-only controller's. :data:`PROBE_OFFSET` starts there;
:data:`PEAK_PROBE_OFFSET` closes at half that rate, as the scripted controllers do where the crush rule reads the
peak force within the control step.
Held as a constant action it is a fixed schedule inside the constant-action grid of
:mod:`simgrip.envs.baselines`, whose every member scores 0 % on the pinch's and the K fingers' held-out seeds
(``tests/test_action_offset.py`` checks the probe itself on seeds 6200-6209: no success): when to stop
closing and when to lift faster, the feedback, is still the learner's.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np

__all__ = ["ActionOffset", "PEAK_PROBE_OFFSET", "PROBE_OFFSET"]

#: the valve tasks' probe: the valve closing at 0.4 of its rate, the palm rising at 0.2 of its speed
PROBE_OFFSET = (-0.4, 0.2)
#: the probe where the crush rule reads the peak within a control step (``crush_at="peak"``,
#: :mod:`simgrip.envs.pick_fragile_v7`): the valve closing at the scripted controllers' rate there,
#: :data:`~simgrip.envs.scripted_fragile.PEAK_CLOSING_RATE` / :data:`~simgrip.envs.valve.KAPPA_RATE` = 0.2 of its
#: rate (a faster first touch's impact crushes light pieces), the palm as :data:`PROBE_OFFSET`
PEAK_PROBE_OFFSET = (-0.2, 0.2)


class ActionOffset(gym.ActionWrapper):
    """The env's action is ``clip(a + offset, low, high)`` (see :mod:`simgrip.envs.action_offset`).

    Parameters
    ----------
    env : gymnasium.Env
        An env with a ``Box`` action space.
    offset : sequence of float
        One finite number per action, within the action bounds (the motion a zero action performs).
    """

    def __init__(self, env: gym.Env, offset):
        super().__init__(env)
        space = env.action_space
        if not isinstance(space, gym.spaces.Box):
            raise ValueError(f"offset: ActionOffset needs a Box action space, got {space!r}")
        try:
            off = np.asarray(offset, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"offset must be {space.shape[0]} numbers, got {offset!r}") from None
        if off.shape != space.shape or not all(math.isfinite(x) for x in off.ravel()):
            raise ValueError(f"offset must be {space.shape[0]} finite numbers, got {offset!r}")
        if np.any(off < space.low) or np.any(off > space.high):
            raise ValueError(f"offset must lie within the action bounds [{space.low}, {space.high}], got {offset!r}")
        self.offset = off.astype(space.dtype)

    def action(self, action):
        space = self.action_space
        return np.clip(np.asarray(action, dtype=space.dtype) + self.offset, space.low, space.high)

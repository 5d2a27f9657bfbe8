r"""The first touch remembered in the observation (issue 18, the pick-and-place's grip).

``TouchMemory(env)`` wraps a fragile task and appends three entries to its observation, each computed from the
observations of the episode so far (nothing hidden: the policy could hold them itself, if it had a memory):

| entry | meaning | bounds |
|---|---|---|
| ``touched`` | 1 from the first observation with a finger force (any ``contact_force`` entry above 0) on, else 0 | [0, 1] |
| ``closed_since_touch`` | ``(k_touch - k) / 0.05``: how far the actual curvature ``k`` (``kappa_actual``, action units) has closed since the first touch's ``k_touch``, in twentieths of an action unit; 0 before the touch | [-40, 40] |
| ``risen_since_touch`` | how far the workpiece has risen since the first touch [mm] (the ``box_lift`` or ``workpiece_lift`` entry times the task's ``target_height``); 0 before the touch | [-100, 100] |

Why: the scripted observation-only controllers (:mod:`simgrip.envs.scripted_fragile`) are stateful.  After the
first touch they close by a share of the curvature closed since it (the force grows about linearly with it, so
this is a relative force increase per step) and freeze a margin past the curvature where the workpiece is seen to
rise, 0.1 mm being their trigger.  A feed-forward policy (SB3's MLP) sees neither the curvature at the touch nor a
rise of 0.1 mm, which is a three-hundredth of the lift entry's unit on the place.  This wrapper gives it both, as
named inputs of a useful size.  It is part of the policy, like a frame stack (training and evaluation alike:
``--touch-memory`` of ``train_sb3.py``, ``rl_baselines.py`` and ``evaluate_policy.py``).

The memory restarts with every ``reset``.  Raises ValueError naming ``env`` when the task does not observe the
actual curvature, the finger forces and the workpiece's lift (the fragile tasks all do).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

__all__ = ["TouchMemory", "CLOSE_UNIT", "RISE_UNIT"]

#: ``closed_since_touch``'s unit [action units of curvature]
CLOSE_UNIT = 0.05
#: ``risen_since_touch``'s unit [m]
RISE_UNIT = 0.001
_BOUNDS = ((0.0, 1.0), (-40.0, 40.0), (-100.0, 100.0))


class TouchMemory(gym.Wrapper):
    """The observation with ``touched``, ``closed_since_touch`` and ``risen_since_touch`` appended (see
    :mod:`simgrip.envs.touch_memory`).

    Parameters
    ----------
    env : gymnasium.Env
        A fragile task, possibly behind wrappers that only append to its observation (``ScriptedResidual``).

    Attributes
    ----------
    obs_layout : list of (str, int)
        The wrapped env's layout and the three entries.
    """

    def __init__(self, env: gym.Env):
        super().__init__(env)
        u = env.unwrapped
        sl = getattr(u, "obs_slices", {})
        lift = sl.get("box_lift", sl.get("workpiece_lift"))
        height = getattr(u, "target_height", None)
        if "kappa_actual" not in sl or "contact_force" not in sl or lift is None or not height:
            raise ValueError(f"env: {u.__class__.__name__} does not observe the actual curvature, the finger forces "
                             "and the workpiece's lift (a fragile task does)")
        self._k = sl["kappa_actual"].start
        self._forces = sl["contact_force"]
        self._lift = lift.start
        self._rise = float(height) / RISE_UNIT  # the lift entry's unit in RISE_UNITs
        obs = env.observation_space
        lo, hi = np.array(_BOUNDS, dtype=obs.dtype).T
        self.observation_space = gym.spaces.Box(np.concatenate([obs.low, lo]), np.concatenate([obs.high, hi]),
                                                dtype=obs.dtype)
        try:
            layout = list(env.get_wrapper_attr("obs_layout"))
        except AttributeError:
            layout = []
        self.obs_layout = layout + [("touched", 1), ("closed_since_touch", 1), ("risen_since_touch", 1)]
        self._touch = None  # (k, lift) at the first touch; None before it

    def _observe(self, obs) -> np.ndarray:
        k, lift = float(obs[self._k]), float(obs[self._lift])
        if self._touch is None and float(np.max(obs[self._forces])) > 0.0:
            self._touch = (k, lift)
        if self._touch is None:
            extra = (0.0, 0.0, 0.0)
        else:
            k0, lift0 = self._touch
            extra = (1.0, (k0 - k) / CLOSE_UNIT, (lift - lift0) * self._rise)
        extra = [min(max(x, lo), hi) for x, (lo, hi) in zip(extra, _BOUNDS)]
        return np.concatenate([obs, np.array(extra, dtype=self.observation_space.dtype)])

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        obs, info = self.env.reset(seed=seed, options=options)
        self._touch = None
        return self._observe(obs), info

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        return self._observe(obs), reward, terminated, truncated, info

r"""The learner's action added to the scripted controller's on chosen channels (issue 18, the pick-and-place).

``ScriptedResidual(env, channels)`` wraps a fragile task (:mod:`simgrip.envs.scripted_fragile`).  Each step it
runs the task's scripted **observation-only** controller (:func:`simgrip.envs.scripted_policies.policy_maker`: it
reads only what the agent reads) on the env's observation and passes ``clip(b + a, low, high)`` to the env, ``a`` the
learner's action and ``b`` the controller's action on the named ``channels`` (names of the env's
``action_names``; 0 on the others).  The observation is the env's with ``b`` appended (the entries
``base_<name>`` of :attr:`ScriptedResidual.obs_layout`, every action's, 0 where not scripted): the learner sees
what the script is about to do.  This is residual policy learning (Silver et al. 2018, "Residual Policy
Learning"; Johannink et al. 2019, "Residual Reinforcement Learning for Robot Control").

The controller restarts with every ``reset`` (its state is the episode's) and follows the episode as it is
played: it reads each observation, whatever was done before it, so its phases (grip, carry, lower) follow the
workpiece, not the clock.  On the pick-and-place with ``channels = ("palm_x", "palm_z")`` the palm's path is
the script's (up when the workpiece is lifted by the grip, over the observed target, down) and the curvature
is the learner's alone: the grip, which no learner that also had to move the palm has found, and PPO learns
behind it (the Gymnasium environments page, "The palm scripted, the grip learned").  Unlike
:class:`~simgrip.envs.scripted_start.ScriptedStart` (a training aid) the wrapper is part of the policy: it is
trained and evaluated behind it, and ``train_sb3.py --residual`` records it.

With ``alone=True`` the named actions are the controller's alone: the learner's action space loses them (it acts
on the other actions only, in the env's order) and the env performs ``b`` there, as it would behind the residual
with the learner's action 0 on them.  On the sphere the learners' own palm correction kept lowering the palm as
the fingers touched it, part of an impact the crush rule reads (the learning page, "The first touch on the
sphere"); alone, the palm's path is the script's and only the curvature is learned.

Raises ValueError naming ``channels`` when a name is not one of the env's actions or names one twice, or (with
``alone``) names every action, ``env`` when the task has no scripted controller.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

__all__ = ["ScriptedResidual", "PALM_CHANNELS"]

#: the palm's channels of the pick tasks' ``action_names`` (the place's; the pinch's is ``palm_z`` alone)
PALM_CHANNELS = ("palm_x", "palm_z")


class ScriptedResidual(gym.Wrapper):
    """The env performs ``clip(b + a)``, ``b`` the scripted observation-only controller's action on ``channels``
    (0 elsewhere), and observes its observation with ``b`` appended (see :mod:`simgrip.envs.scripted_residual`).

    Parameters
    ----------
    env : gymnasium.Env
        A fragile task as ``gym.make`` builds it (its raw action space: wrap before any action wrapper).
    channels : sequence of str
        The actions the controller drives, names of ``env.unwrapped.action_names`` (at least one).
    alone : bool
        The controller drives ``channels`` alone and the learner's action space holds only the other actions
        (default False: the learner's action, over every action, is added to the controller's).

    Attributes
    ----------
    channels : tuple of str
    mask : numpy.ndarray
        1.0 on the scripted channels, 0.0 elsewhere (float32, the env's action's shape).
    alone : bool
    obs_layout : list of (str, int)
        The env's ``obs_layout`` and one ``("base_<name>", 1)`` per action.
    """

    def __init__(self, env: gym.Env, channels, alone: bool = False):
        super().__init__(env)
        u = env.unwrapped
        names = tuple(getattr(u, "action_names", ()))
        if isinstance(channels, str) or not all(isinstance(c, str) for c in channels) or not len(channels):
            raise ValueError(f"channels must be one or more action names of {names}, got {channels!r}")
        channels = tuple(channels)
        unknown = [c for c in channels if c not in names]
        if unknown or len(set(channels)) != len(channels):
            raise ValueError(f"channels must be distinct action names of {u.__class__.__name__} {names}, "
                             f"got {list(channels)}")
        from simgrip.envs.scripted_policies import policy_maker

        try:
            self._make = policy_maker(env, "observation")
        except ValueError as e:
            raise ValueError(f"env: {e}") from None
        if not isinstance(alone, (bool, np.bool_)):
            raise ValueError(f"alone must be True or False, got {alone!r}")
        if alone and len(channels) == len(names):
            raise ValueError(f"channels: with alone, not every action of {names} (the learner would have none)")
        self.channels, self.alone = channels, bool(alone)
        space = env.action_space
        self.mask = np.array([1.0 if n in channels else 0.0 for n in names], dtype=np.float32)
        self._free = np.flatnonzero(self.mask == 0.0)  # the learner's actions where alone
        if self.alone:
            self.action_space = gym.spaces.Box(space.low[self._free], space.high[self._free], dtype=space.dtype)
        n = len(names)
        obs = env.observation_space
        self.observation_space = gym.spaces.Box(np.concatenate([obs.low, space.low]).astype(obs.dtype),
                                                np.concatenate([obs.high, space.high]).astype(obs.dtype),
                                                dtype=obs.dtype)
        self.obs_layout = list(getattr(u, "obs_layout", [])) + [(f"base_{name}", 1) for name in names]
        self._low, self._high = space.low, space.high
        self._act, self._t, self._base = None, 0, np.zeros(n, dtype=np.float32)

    def _observe(self, obs) -> np.ndarray:
        """The controller's next action on the scripted channels, kept for ``step``; ``obs`` with it appended."""
        b = np.asarray(self._act(obs, self._t), dtype=np.float32) * self.mask
        self._base = np.clip(b, self._low, self._high)
        return np.concatenate([obs, self._base]).astype(self.observation_space.dtype, copy=False)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        obs, info = self.env.reset(seed=seed, options=options)
        self._act, self._t = self._make(self.env, info, seed), 0
        return self._observe(obs), info

    def step(self, action):
        if self._act is None:
            raise RuntimeError("ScriptedResidual: call reset() before step()")
        learner = np.asarray(action, dtype=np.float32)
        if self.alone:  # the learner's actions in their places, 0 on the scripted channels
            learner = np.zeros_like(self._base)
            learner[self._free] = action
        a = np.clip(self._base + learner, self._low, self._high)
        obs, reward, terminated, truncated, info = self.env.step(a)
        self._t += 1
        return self._observe(obs), reward, terminated, truncated, info
